//! Injection: read each log, compute the change the effects make to the true tyre at every
//! sample, and write the log again with only FX, FYW, MZW and DSTWOWHC of its RigSamples
//! changed — every other topic, message, time stamp and metadata record copied as it is.

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use mcaplog::records::{LogRecord, Records};
use mcaplog::{McapLog, McapLogOptions};
use rigsim::{NoiseParams, VirtualTyre};
use tyre_msgs::RigSample;

use crate::InjectError;
use crate::effect::HiddenEffect;
use crate::factors::{Factors, TrueTyre};
use crate::report::{ChangeSize, EffectReport, InjectionReport, LogReport, PerChannel, RADIUS_STEP_M, SampleChange};
use crate::resolve::Resolved;
use crate::series::{LogSeries, SampleKey};

/// One log's change at every sample: ΔFX, ΔFYW, ΔMZW [N, N, N·m] and Δ loaded radius [m].
type Deltas = Vec<[f64; 4]>;

/// Injects `effects` into one log (see [`inject_logs`]), sizes measured in the default rig's
/// noise.
pub fn inject(
    log_in: &Path,
    log_out: &Path,
    tyre: &VirtualTyre,
    effects: &[HiddenEffect],
) -> Result<InjectionReport, InjectError> {
    inject_logs(&[(log_in.to_owned(), log_out.to_owned())], tyre, &NoiseParams::default(), effects)
}

/// Injects `effects` into the logs of one tyre compound (input, output pairs), all at once: the
/// effects' relative parameters are anchored to the logs together, their states (wear,
/// break-in energy) start again in each log. `noise` is the rig's, the unit the report measures
/// the changes in.
pub fn inject_logs(
    pairs: &[(PathBuf, PathBuf)],
    tyre: &VirtualTyre,
    noise: &NoiseParams,
    effects: &[HiddenEffect],
) -> Result<InjectionReport, InjectError> {
    for (input, output) in pairs {
        let same = input.canonicalize().ok().zip(output.canonicalize().ok()).is_some_and(|(i, o)| i == o);
        if same || input == output {
            return Err(InjectError::SamePath { path: input.clone() });
        }
    }
    let mut series = Vec::with_capacity(pairs.len());
    for (input, _) in pairs {
        let bytes = read(input)?;
        series.push(LogSeries::read(input, &bytes)?);
    }
    let resolved: Vec<Resolved> = effects.iter().map(|e| Resolved::new(e, &series)).collect();
    let truth = TrueTyre::new(tyre);
    let sigma = PerChannel::noise_sigma(noise);

    let mut logs = Vec::with_capacity(pairs.len());
    let mut alone: Vec<Vec<SampleChange>> = vec![Vec::new(); effects.len()];
    let mut combined_changes = Vec::new();
    for (li, ((input, output), s)) in pairs.iter().zip(&series).enumerate() {
        let per_effect: Vec<Vec<Factors>> = resolved.iter().map(|r| r.factors(s)).collect();
        let combined: Vec<Factors> =
            (0..s.len()).map(|k| per_effect.iter().fold(Factors::NEUTRAL, |acc, f| acc.and(f[k]))).collect();
        let deltas = deltas(&truth, s, &combined);
        combined_changes.extend(in_sweep_changes(li, s, &deltas));
        for (ei, f) in per_effect.iter().enumerate() {
            // One effect alone changes what all of them do together: no second evaluation.
            let own = if effects.len() == 1 { deltas.clone() } else { self::deltas(&truth, s, f) };
            alone[ei].extend(in_sweep_changes(li, s, &own));
        }
        let mut log = write(input, output, s, &deltas)?;
        log.sweep_samples = s.in_sweep.iter().filter(|v| **v).count();
        logs.push(log);
    }
    let effects = resolved
        .into_iter()
        .zip(alone)
        .map(|(r, changes)| EffectReport {
            kind: r.effect.kind(),
            strength: r.effect.strength(),
            size: ChangeSize::measure(&changes, &sigma),
            effect: r.effect,
            resolved: r.values,
            changes,
        })
        .collect();
    Ok(InjectionReport {
        format_version: 1,
        tyre: tyre.name(),
        noise_sigma: sigma,
        logs,
        effects,
        combined: ChangeSize::measure(&combined_changes, &sigma),
    })
}

fn read(path: &Path) -> Result<Vec<u8>, InjectError> {
    std::fs::read(path).map_err(|source| InjectError::Read { path: path.to_owned(), source })
}

/// The change `factors` make at every sample: the true tyre with them minus the true tyre
/// without, at the measured inputs (forces only where they may change), and the radius change:
/// the effect's own plus what the tyre's loaded radius does with the changed forces.
fn deltas(truth: &TrueTyre<'_>, s: &LogSeries, factors: &[Factors]) -> Deltas {
    let one = |k: usize| -> [f64; 4] {
        let f = &factors[k];
        let radius = if s.radius_ok[k] { f.radius_m } else { 0.0 };
        if !s.forces_ok[k] || !f.changes_forces() {
            return [0.0, 0.0, 0.0, radius];
        }
        let with = truth.forces(f, &s.input[k]);
        let without = truth.forces(&Factors::NEUTRAL, &s.input[k]);
        let d: [f64; 4] = std::array::from_fn(|i| with[i] - without[i]);
        let radius = if s.radius_ok[k] { radius + d[3] } else { 0.0 };
        // A model evaluation that fails (NaN at some odd input) changes nothing.
        if d.iter().all(|v| v.is_finite()) { [d[0], d[1], d[2], radius] } else { [0.0, 0.0, 0.0, radius] }
    };
    parallel_map(s.len(), one)
}

/// `f(0..n)` on every core the machine has (the model evaluations are the costly part).
fn parallel_map<T: Send + Copy + Default>(n: usize, f: impl Fn(usize) -> T + Sync) -> Vec<T> {
    let threads = std::thread::available_parallelism().map_or(1, |p| p.get()).clamp(1, 8);
    let mut out = vec![T::default(); n];
    let chunk = n.div_ceil(threads).max(1);
    std::thread::scope(|scope| {
        for (c, part) in out.chunks_mut(chunk).enumerate() {
            let f = &f;
            scope.spawn(move || {
                for (i, v) in part.iter_mut().enumerate() {
                    *v = f(c * chunk + i);
                }
            });
        }
    });
    out
}

fn in_sweep_changes<'a>(log: usize, s: &'a LogSeries, d: &'a Deltas) -> impl Iterator<Item = SampleChange> + 'a {
    (0..s.len()).filter(move |&k| s.in_sweep[k]).map(move |k| SampleChange {
        log,
        seq: s.key[k].1,
        t_s: s.t_s[k],
        delta: d[k].map(|v| v as f32),
    })
}

/// Copies `input` to `output`, changing the RigSamples by `deltas`.
fn write(input: &Path, output: &Path, s: &LogSeries, deltas: &Deltas) -> Result<LogReport, InjectError> {
    let bytes = read(input)?;
    let index: HashMap<SampleKey, usize> = s.key.iter().enumerate().map(|(k, key)| (*key, k)).collect();
    let mut out = McapLog::create(output, McapLogOptions::default())?;
    let mut schemas: HashMap<u16, (String, String)> = HashMap::new();
    let mut channels: HashMap<u16, (u16, String, String)> = HashMap::new(); // old id → (new id, topic, type)
    let mut report = LogReport {
        input: input.display().to_string(),
        output: output.display().to_string(),
        topic: s.topic.clone(),
        samples: s.len(),
        sweep_samples: 0,
        forces_changed: 0,
        radius_changed: 0,
        messages: 0,
    };
    let mut sample_index = 0usize;
    for rec in Records::new(&bytes) {
        let rec = rec.map_err(|detail| InjectError::Log { path: input.to_owned(), detail })?;
        match rec {
            LogRecord::Schema { id, name, data, .. } => {
                schemas.insert(id, (name, String::from_utf8_lossy(&data).into_owned()));
            }
            LogRecord::Channel { id, schema_id, topic, .. } => {
                if channels.contains_key(&id) {
                    continue;
                }
                let (ty, text) = schemas.get(&schema_id).cloned().unwrap_or_default();
                let new_id = out.ensure_channel(&topic, &ty, &text)?;
                channels.insert(id, (new_id, topic, ty));
            }
            LogRecord::Message { channel_id, log_time, publish_time, data, .. } => {
                let Some((id, topic, ty)) = channels.get(&channel_id) else {
                    return Err(InjectError::Log {
                        path: input.to_owned(),
                        detail: format!("a message on channel {channel_id}, which was never defined"),
                    });
                };
                if *topic == s.topic {
                    let mut m: RigSample = mcaplog::codec::decode(&data, ty).map_err(|source| InjectError::Decode {
                        path: input.to_owned(),
                        topic: topic.clone(),
                        index: sample_index,
                        source: Box::new(source),
                    })?;
                    if let Some(&k) = index.get(&(log_time, m.seq)) {
                        apply(&mut m, &deltas[k], &mut report);
                    }
                    let encoded = mcaplog::codec::encode(&m, ty).map_err(|source| InjectError::Encode {
                        path: output.to_owned(),
                        topic: topic.clone(),
                        index: sample_index,
                        source: Box::new(source),
                    })?;
                    out.write(*id, log_time, publish_time, &encoded)?;
                    sample_index += 1;
                } else {
                    out.write(*id, log_time, publish_time, &data)?;
                }
                report.messages += 1;
            }
            LogRecord::Metadata { name, entries } => out.write_metadata(&name, &entries)?,
            // Indexes, statistics and the footer are rebuilt by the writer.
            LogRecord::Other => {}
        }
    }
    out.finish()?;
    Ok(report)
}

/// Adds one sample's change: forces as they are (the deltas are zero where forces may not
/// change), the radius re-quantised to the rig's 0.1 mm with a dither so that sub-step changes
/// come out right on average.
fn apply(m: &mut RigSample, d: &[f64; 4], report: &mut LogReport) {
    if d[0] != 0.0 || d[1] != 0.0 || d[2] != 0.0 {
        m.fx_n += d[0];
        m.fyw_n += d[1];
        m.mzw_nm += d[2];
        report.forces_changed += 1;
    }
    if d[3] != 0.0 {
        // The recorded value is a multiple of the step; where in its step the true value was is
        // unknown, so draw it (deterministically from seq), add the change and round again.
        let within = (unit_hash(m.seq) - 0.5) * 0.999 * RADIUS_STEP_M;
        let steps = ((m.dstwowhc_m + within + d[3]) / RADIUS_STEP_M).round();
        let old_steps = (m.dstwowhc_m / RADIUS_STEP_M).round();
        if steps != old_steps {
            m.dstwowhc_m = steps * RADIUS_STEP_M;
            report.radius_changed += 1;
        }
    }
}

/// A uniform number in [0, 1) from `x` (SplitMix64's finaliser).
fn unit_hash(x: u64) -> f64 {
    let mut z = x.wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^= z >> 31;
    (z >> 11) as f64 / (1u64 << 53) as f64
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn radius_stays_on_its_steps_and_small_changes_average_out() {
        let mut report = LogReport {
            input: String::new(),
            output: String::new(),
            topic: String::new(),
            samples: 0,
            sweep_samples: 0,
            forces_changed: 0,
            radius_changed: 0,
            messages: 0,
        };
        let base = (0.3456 / RADIUS_STEP_M).round() * RADIUS_STEP_M;
        let mut sum = 0.0;
        let n = 20_000;
        for seq in 0..n {
            let mut m = RigSample { seq, dstwowhc_m: base, ..RigSample::default() };
            apply(&mut m, &[0.0, 0.0, 0.0, -0.03e-3], &mut report);
            let steps = m.dstwowhc_m / RADIUS_STEP_M;
            assert!((steps - steps.round()).abs() < 1e-6, "off the 0.1 mm grid: {}", m.dstwowhc_m);
            sum += m.dstwowhc_m - base;
        }
        let mean = sum / n as f64;
        assert!((mean + 0.03e-3).abs() < 0.002e-3, "mean change {mean}");
        // No change leaves the value's bits alone.
        let mut m = RigSample { seq: 5, dstwowhc_m: base, ..RigSample::default() };
        apply(&mut m, &[0.0; 4], &mut report);
        assert_eq!(m.dstwowhc_m.to_bits(), base.to_bits());
    }
}

//! One log's RigSamples as the generator needs them: the measured inputs of the true tyre, the
//! validity of each channel, whether the sample is inside a sweep, and the generator's own
//! state variables (sliding power and energy, the measured mean tread temperature).
//!
//! Everything is computed from the log's measured samples, never from the rig's truth: the
//! generator sees what a rig engineer injecting an effect into a real file would see.

use mcaplog::records::{LogRecord, Records};
use mftyre::MfInput;
use std::collections::BTreeMap;
use std::path::Path;
use tyre_msgs::{ProcedureState, RigSample, RigSetpoint, RosMessage};

use crate::InjectError;

/// Below this belt speed the wheel is not rolling: slips mean nothing and forces are left alone.
pub const MIN_ROLLING_SPEED_MPS: f64 = 0.5;
/// Longest step counted in an integral or a lag: a gap in the log is not sliding time [s].
const MAX_STEP_S: f64 = 0.1;

/// Identifies one RigSample message in the log (log time, seq): the same key in both passes.
pub type SampleKey = (u64, u64);

/// One log's samples, in rig-time order.
#[derive(Debug, Clone, Default)]
pub struct LogSeries {
    /// The RigSample topic.
    pub topic: String,
    /// (log time, seq) of each sample.
    pub key: Vec<SampleKey>,
    /// RUNTIME [s].
    pub t_s: Vec<f64>,
    /// The true tyre's inputs at the measured SLIPANGL, LONGSLIP, FZW, INCLANGL, INFLPRES,
    /// TRAJVELW and wheel speed.
    pub input: Vec<MfInput>,
    /// Forces may be changed here: rolling, loaded, not static, force channels valid, inputs finite.
    pub forces_ok: Vec<bool>,
    /// DSTWOWHC is valid (finite, positive, no FAULT_RADIUS).
    pub radius_ok: Vec<bool>,
    /// Inside a sweep (`PHASE_SWEEP` of the procedure state).
    pub in_sweep: Vec<bool>,
    /// A fresh tyre is on the rig from this sample: the log's first, and the first after each
    /// later tyre change (`PHASE_TYRE_CHANGE`; the change a log opens with mounts its first
    /// tyre). Wear and break-in start again on it, as the rig's own tyre does.
    pub new_tyre: Vec<bool>,
    /// Mean of the finite TRDTEMPI/C/O [°C] (NaN when FAULT_TEMPERATURE or none is finite).
    pub temp_c: Vec<f64>,
    /// Sliding power √((FX·κ·V)² + (FYW·V·sin α)²) from the measured samples [W] (0 when not rolling).
    pub sliding_power_w: Vec<f64>,
}

impl LogSeries {
    /// Number of samples.
    pub fn len(&self) -> usize {
        self.t_s.len()
    }

    /// No samples.
    pub fn is_empty(&self) -> bool {
        self.t_s.is_empty()
    }

    /// Reads the RigSamples and procedure states of the MCAP file held in `bytes`.
    pub fn read(path: &Path, bytes: &[u8]) -> Result<LogSeries, InjectError> {
        let sample_type = RigSample::ros_type_name();
        let state_type = ProcedureState::ros_type_name();
        let mut schemas: BTreeMap<u16, String> = BTreeMap::new();
        let mut channels: BTreeMap<u16, (String, String)> = BTreeMap::new();
        let mut samples: Vec<(u64, RigSample)> = Vec::new();
        let mut states: Vec<ProcedureState> = Vec::new();
        let mut sample_topic: Option<String> = None;
        for rec in Records::new(bytes) {
            let rec = rec.map_err(|detail| InjectError::Log { path: path.to_owned(), detail })?;
            match rec {
                LogRecord::Schema { id, name, .. } => {
                    schemas.insert(id, name);
                }
                LogRecord::Channel { id, schema_id, topic, .. } => {
                    let ty = schemas.get(&schema_id).cloned().unwrap_or_default();
                    channels.insert(id, (topic, ty));
                }
                LogRecord::Message { channel_id, log_time, data, .. } => {
                    let Some((topic, ty)) = channels.get(&channel_id) else { continue };
                    if *ty == sample_type {
                        check_single_topic(path, &mut sample_topic, topic)?;
                        let s: RigSample = decode(path, topic, samples.len(), &data, ty)?;
                        samples.push((log_time, s));
                    } else if *ty == state_type {
                        states.push(decode(path, topic, states.len(), &data, ty)?);
                    }
                }
                LogRecord::Metadata { .. } | LogRecord::Other => {}
            }
        }
        let topic = sample_topic
            .ok_or_else(|| InjectError::Log { path: path.to_owned(), detail: "no RigSample messages".into() })?;
        // Chunks need not be in time order; the state filters need one timeline.
        samples.sort_by(|a, b| a.1.runtime_s.total_cmp(&b.1.runtime_s).then(a.1.seq.cmp(&b.1.seq)));
        states.sort_by(|a, b| stamp_s(a).total_cmp(&stamp_s(b)));
        Ok(build(topic, &samples, &states))
    }

    /// Sliding energy on the tyre above `threshold_w` of sliding power, ∫max(P − threshold,
    /// 0) dt [J] since the tyre was mounted, per sample.
    pub fn energy_j(&self, threshold_w: f64) -> Vec<f64> {
        let mut e = 0.0;
        let mut out = Vec::with_capacity(self.len());
        for k in 0..self.len() {
            if self.mounted_at(k) {
                e = 0.0;
            } else {
                e += (self.sliding_power_w[k] - threshold_w).max(0.0) * self.step_s(k);
            }
            out.push(e);
        }
        out
    }

    /// Largest sliding energy any tyre of the log reached above `threshold_w` [J].
    pub fn largest_tyre_energy_j(&self, threshold_w: f64) -> f64 {
        self.energy_j(threshold_w).into_iter().fold(0.0, f64::max)
    }

    /// A fresh tyre from sample `k` (a series built without tyre changes has one, from 0).
    fn mounted_at(&self, k: usize) -> bool {
        self.new_tyre.get(k).copied().unwrap_or(k == 0)
    }

    /// The grip temperature: `surface_weight` × the measured mean tread temperature +
    /// (1 − weight) × its first-order lag with time constant `lag_s` (0: the reading itself).
    /// Invalid readings hold the last value; before the first valid reading it is NaN.
    pub fn grip_temperature_c(&self, lag_s: f64, surface_weight: f64) -> Vec<f64> {
        let mut lagged = f64::NAN;
        let mut last = f64::NAN;
        // Time since the last valid reading: the bulk keeps following through invalid ones.
        let mut pending_s = 0.0;
        let mut out = Vec::with_capacity(self.len());
        for k in 0..self.len() {
            let t = self.temp_c[k];
            if self.mounted_at(k) {
                // A fresh tyre's bulk is at its surface's temperature.
                lagged = f64::NAN;
                last = f64::NAN;
            }
            pending_s += self.step_s(k);
            if t.is_finite() {
                last = t;
                if !lagged.is_finite() || lag_s <= 0.0 {
                    lagged = t;
                } else {
                    lagged += (1.0 - (-pending_s / lag_s).exp()) * (t - lagged);
                }
                pending_s = 0.0;
            }
            out.push(surface_weight * last + (1.0 - surface_weight) * lagged);
        }
        out
    }

    /// Time since the previous sample, bounded so gaps do not count [s].
    fn step_s(&self, k: usize) -> f64 {
        if k == 0 { 0.0 } else { (self.t_s[k] - self.t_s[k - 1]).clamp(0.0, MAX_STEP_S) }
    }
}

fn check_single_topic(path: &Path, seen: &mut Option<String>, topic: &str) -> Result<(), InjectError> {
    match seen {
        None => {
            *seen = Some(topic.to_owned());
            Ok(())
        }
        Some(t) if t == topic => Ok(()),
        Some(t) => Err(InjectError::Log {
            path: path.to_owned(),
            detail: format!("RigSamples on two topics ({t} and {topic}): which tyre to change is ambiguous"),
        }),
    }
}

fn decode<M: serde::de::DeserializeOwned>(
    path: &Path,
    topic: &str,
    index: usize,
    data: &[u8],
    ty: &str,
) -> Result<M, InjectError> {
    mcaplog::codec::decode(data, ty).map_err(|source| InjectError::Decode {
        path: path.to_owned(),
        topic: topic.to_owned(),
        index,
        source: Box::new(source),
    })
}

fn stamp_s(st: &ProcedureState) -> f64 {
    f64::from(st.header.stamp.sec) + f64::from(st.header.stamp.nanosec) * 1e-9
}

fn build(topic: String, samples: &[(u64, RigSample)], states: &[ProcedureState]) -> LogSeries {
    let mut s = LogSeries { topic, ..LogSeries::default() };
    let mut st_i = 0;
    let mut phase: Option<u8> = None;
    // As the doctor reads a log: a tyre change mounts its tyre where it ends.
    let (mut change_pending, mut outside_change_seen) = (false, false);
    for (log_time, m) in samples {
        // The sweep phase in force at this sample, as the doctor reads it.
        while st_i < states.len() && stamp_s(&states[st_i]) <= m.runtime_s + 1e-9 {
            phase = Some(states[st_i].phase);
            st_i += 1;
        }
        let input = MfInput {
            fz_n: m.fzw_n.max(0.0),
            kappa: m.longslip,
            alpha_rad: m.slipangl_deg.to_radians(),
            gamma_rad: m.inclangl_deg.to_radians(),
            phit_per_m: 0.0,
            vx_mps: m.trajvelw_mps,
            p_pa: m.inflpres_pa,
            omega_radps: m.wheel_speed_radps.max(0.0),
        };
        let inputs_finite = [m.fzw_n, m.longslip, m.slipangl_deg, m.inclangl_deg, m.inflpres_pa, m.trajvelw_mps]
            .iter()
            .chain(&[m.wheel_speed_radps, m.fx_n, m.fyw_n, m.mzw_nm])
            .all(|v| v.is_finite());
        let rolling = m.trajvelw_mps >= MIN_ROLLING_SPEED_MPS && m.rig_mode != RigSetpoint::MODE_STATIC;
        let forces_ok = rolling
            && inputs_finite
            && m.fzw_n > 0.0
            && m.fault_flags & (RigSample::FAULT_FORCE | RigSample::FAULT_ESTOP) == 0;
        let radius_ok = m.dstwowhc_m.is_finite() && m.dstwowhc_m > 0.0 && m.fault_flags & RigSample::FAULT_RADIUS == 0;
        let temp_c = if m.fault_flags & RigSample::FAULT_TEMPERATURE != 0 {
            f64::NAN
        } else {
            let (sum, n) = [m.trdtempi_c, m.trdtempc_c, m.trdtempo_c]
                .iter()
                .filter(|t| t.is_finite())
                .fold((0.0, 0usize), |(s, n), t| (s + t, n + 1));
            if n == 0 { f64::NAN } else { sum / n as f64 }
        };
        let v = m.trajvelw_mps;
        let power = if forces_ok {
            let px = m.fx_n * m.longslip * v;
            let py = m.fyw_n * v * m.slipangl_deg.to_radians().sin();
            (px * px + py * py).sqrt()
        } else {
            0.0
        };
        s.key.push((*log_time, m.seq));
        s.t_s.push(m.runtime_s);
        s.input.push(input);
        s.forces_ok.push(forces_ok);
        s.radius_ok.push(radius_ok);
        s.in_sweep.push(phase == Some(ProcedureState::PHASE_SWEEP));
        let in_change = phase == Some(ProcedureState::PHASE_TYRE_CHANGE);
        change_pending |= in_change && outside_change_seen;
        s.new_tyre.push(s.new_tyre.is_empty() || (change_pending && !in_change));
        if !in_change {
            change_pending = false;
            outside_change_seen = true;
        }
        s.temp_c.push(temp_c);
        s.sliding_power_w.push(power);
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    fn series(t: &[f64], temp: &[f64], power: &[f64]) -> LogSeries {
        LogSeries { t_s: t.to_vec(), temp_c: temp.to_vec(), sliding_power_w: power.to_vec(), ..LogSeries::default() }
    }

    #[test]
    fn energy_integrates_above_the_threshold() {
        let s = series(&[0.0, 0.01, 0.02, 0.03], &[0.0; 4], &[1000.0, 1000.0, 3000.0, 0.0]);
        let e = s.energy_j(0.0);
        assert!((e[3] - (10.0 + 30.0)).abs() < 1e-9, "{e:?}");
        let e = s.energy_j(2000.0);
        assert!((e[3] - 10.0).abs() < 1e-9, "{e:?}");
    }

    /// A fresh tyre has slid nothing: the energy starts again where a tyre is mounted.
    #[test]
    fn energy_starts_again_on_a_new_tyre() {
        let mut s = series(&[0.0, 0.01, 0.02, 0.03, 0.04], &[0.0; 5], &[1000.0; 5]);
        s.new_tyre = vec![true, false, false, true, false];
        let e = s.energy_j(0.0);
        assert!((e[2] - 20.0).abs() < 1e-9 && e[3] == 0.0 && (e[4] - 10.0).abs() < 1e-9, "{e:?}");
        assert!((s.largest_tyre_energy_j(0.0) - 20.0).abs() < 1e-9);
    }

    /// The generator reads tyre changes as the doctor does: the change a log opens with mounts
    /// its first tyre, a later one mounts the next where it ends.
    #[test]
    fn a_tyre_change_mounts_a_new_tyre_where_it_ends() {
        let samples: Vec<(u64, RigSample)> = (0..60)
            .map(|k| (k, RigSample { seq: k, runtime_s: k as f64 * 0.1, trajvelw_mps: 10.0, ..Default::default() }))
            .collect();
        let state = |t_s: f64, phase: u8| ProcedureState {
            header: tyre_msgs::std_msgs::Header::iso_w(t_s),
            phase,
            ..Default::default()
        };
        let states = [
            state(0.0, ProcedureState::PHASE_TYRE_CHANGE),
            state(1.0, ProcedureState::PHASE_SWEEP),
            state(3.0, ProcedureState::PHASE_TYRE_CHANGE),
            state(4.0, ProcedureState::PHASE_SWEEP),
        ];
        let s = build("/rig/sample".into(), &samples, &states);
        let mounted: Vec<usize> = (0..s.len()).filter(|&k| s.new_tyre[k]).collect();
        assert_eq!(mounted, vec![0, 40]);
    }

    #[test]
    fn lagged_temperature_approaches_a_step_and_holds_through_invalid_readings() {
        let t: Vec<f64> = (0..=1000).map(|k| k as f64 * 0.1).collect();
        let mut temp = vec![20.0; t.len()];
        for v in temp.iter_mut().skip(1) {
            *v = 60.0;
        }
        temp[500] = f64::NAN;
        let s = series(&t, &temp, &vec![0.0; t.len()]);
        let g = s.grip_temperature_c(10.0, 0.0);
        // After one time constant (10 s = 100 steps) 63 % of the step.
        assert!((g[100] - (20.0 + 40.0 * (1.0 - (-1.0_f64).exp()))).abs() < 0.01, "{}", g[100]);
        assert!((g[1000] - 60.0).abs() < 0.01);
        assert_eq!(s.grip_temperature_c(0.0, 1.0)[500], 60.0, "an invalid reading holds the last value");
    }
}

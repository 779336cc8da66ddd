//! What was injected and how big it is: per effect its drawn form, its absolute parameters,
//! the change it made at every in-sweep sample, and that change's size in the rig's noise.

use rigsim::NoiseParams;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

use crate::effect::{EffectKind, HiddenEffect};

/// The changed channels, in the order of every `[f64; 4]` here.
pub const CHANNELS: [&str; 4] = ["FX", "FYW", "MZW", "DSTWOWHC"];

/// DSTWOWHC's resolution [m]: the rig writes the loaded radius in 0.1 mm steps.
pub const RADIUS_STEP_M: f64 = 1e-4;

/// One value per changed channel.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct PerChannel {
    /// FX [N].
    pub fx_n: f64,
    /// FYW [N].
    pub fyw_n: f64,
    /// MZW [N·m].
    pub mzw_nm: f64,
    /// DSTWOWHC [m].
    pub dstwowhc_m: f64,
}

impl PerChannel {
    /// From FX, FYW, MZW, DSTWOWHC.
    pub fn from_array(v: [f64; 4]) -> Self {
        Self { fx_n: v[0], fyw_n: v[1], mzw_nm: v[2], dstwowhc_m: v[3] }
    }

    /// FX, FYW, MZW, DSTWOWHC.
    pub fn to_array(self) -> [f64; 4] {
        [self.fx_n, self.fyw_n, self.mzw_nm, self.dstwowhc_m]
    }

    /// The rig's noise σ per channel. DSTWOWHC's counts its quantisation too (a uniform error
    /// of one step: step/√12), as the measured channel carries both.
    pub fn noise_sigma(noise: &NoiseParams) -> Self {
        Self {
            fx_n: noise.fx_n,
            fyw_n: noise.fy_n,
            mzw_nm: noise.mz_nm,
            dstwowhc_m: (noise.radius_m.powi(2) + RADIUS_STEP_M.powi(2) / 12.0).sqrt(),
        }
    }
}

/// The change at one in-sweep sample.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SampleChange {
    /// Which log (index into [`InjectionReport::logs`]).
    pub log: usize,
    /// RigSample.seq.
    pub seq: u64,
    /// RUNTIME [s].
    pub t_s: f64,
    /// ΔFX, ΔFYW, ΔMZW [N, N, N·m] and the loaded radius change before quantisation [m].
    pub delta: [f32; 4],
}

/// How big a change is, over the samples inside sweeps.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct ChangeSize {
    /// Samples inside sweeps.
    pub sweep_samples: usize,
    /// RMS of the change per channel.
    pub rms_in_sweeps: PerChannel,
    /// Largest |change| per channel.
    pub max_abs_in_sweeps: PerChannel,
    /// The channel it moves most, in noise units (FX, FYW, MZW or DSTWOWHC).
    pub main_channel: String,
    /// RMS of the main channel's change over the samples where it exceeds the noise σ, divided
    /// by σ (the overall RMS/σ, below 1, when it never does): the effect's strength in its
    /// region, the measure the bench's recall is counted on.
    pub strength_noise_units: f64,
    /// Share of the in-sweep samples where the main channel's change exceeds σ.
    pub region_share: f64,
}

impl ChangeSize {
    /// Measures `changes` against the noise σ per channel.
    pub fn measure(changes: &[SampleChange], sigma: &PerChannel) -> ChangeSize {
        let n = changes.len();
        let sigma = sigma.to_array();
        let mut sq = [0.0; 4];
        let mut max = [0.0_f64; 4];
        for c in changes {
            for ch in 0..4 {
                let d = f64::from(c.delta[ch]);
                sq[ch] += d * d;
                max[ch] = max[ch].max(d.abs());
            }
        }
        let rms = sq.map(|s| if n > 0 { (s / n as f64).sqrt() } else { 0.0 });
        let main = (0..4).max_by(|&a, &b| (rms[a] / sigma[a]).total_cmp(&(rms[b] / sigma[b]))).unwrap_or(1);
        let (mut region_sq, mut region_n) = (0.0, 0usize);
        for c in changes {
            let d = f64::from(c.delta[main]);
            if d.abs() > sigma[main] {
                region_sq += d * d;
                region_n += 1;
            }
        }
        let strength = if region_n > 0 { (region_sq / region_n as f64).sqrt() } else { rms[main] } / sigma[main];
        ChangeSize {
            sweep_samples: n,
            rms_in_sweeps: PerChannel::from_array(rms),
            max_abs_in_sweeps: PerChannel::from_array(max),
            main_channel: CHANNELS[main].to_owned(),
            strength_noise_units: if strength.is_finite() { strength } else { 0.0 },
            region_share: if n > 0 { region_n as f64 / n as f64 } else { 0.0 },
        }
    }
}

/// One injected effect.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct EffectReport {
    /// Its kind.
    pub kind: EffectKind,
    /// Its strength as drawn.
    pub strength: f64,
    /// Its drawn form.
    pub effect: HiddenEffect,
    /// Its parameters made absolute for these logs (temperatures °C, rates, W, J).
    pub resolved: BTreeMap<String, f64>,
    /// The size of the change it makes alone.
    pub size: ChangeSize,
    /// Its change at every in-sweep sample (not serialised: large).
    #[serde(skip)]
    pub changes: Vec<SampleChange>,
}

/// One log written.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct LogReport {
    /// The recorded log read.
    pub input: String,
    /// The injected log written.
    pub output: String,
    /// The RigSample topic changed.
    pub topic: String,
    /// RigSamples.
    pub samples: usize,
    /// RigSamples inside sweeps.
    pub sweep_samples: usize,
    /// RigSamples whose forces changed.
    pub forces_changed: usize,
    /// RigSamples whose DSTWOWHC changed (by at least one 0.1 mm step).
    pub radius_changed: usize,
    /// Messages copied (all topics, this one included).
    pub messages: u64,
}

/// What [`crate::inject_logs`] did.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct InjectionReport {
    /// Format of this record.
    pub format_version: u32,
    /// The true tyre's name.
    pub tyre: String,
    /// The rig's noise σ per channel the sizes are measured in.
    pub noise_sigma: PerChannel,
    /// Every log written.
    pub logs: Vec<LogReport>,
    /// Every effect, alone.
    pub effects: Vec<EffectReport>,
    /// All effects together (what was added to the logs).
    pub combined: ChangeSize,
}

impl InjectionReport {
    /// The kinds injected, in order.
    pub fn kinds(&self) -> Vec<EffectKind> {
        self.effects.iter().map(|e| e.kind).collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn change(delta: [f32; 4]) -> SampleChange {
        SampleChange { log: 0, seq: 0, t_s: 0.0, delta }
    }

    #[test]
    fn strength_is_the_rms_where_the_change_exceeds_the_noise() {
        let sigma = PerChannel { fx_n: 30.0, fyw_n: 40.0, mzw_nm: 3.0, dstwowhc_m: 1e-4 };
        // FYW: 120 N on half the samples, 0 elsewhere → 3 σ in its region, half the samples.
        let cs: Vec<_> = (0..10).map(|k| change([0.0, if k % 2 == 0 { 120.0 } else { 0.0 }, 1.0, 0.0])).collect();
        let s = ChangeSize::measure(&cs, &sigma);
        assert_eq!(s.main_channel, "FYW");
        assert!((s.strength_noise_units - 3.0).abs() < 1e-9);
        assert!((s.region_share - 0.5).abs() < 1e-12);
        assert!((s.rms_in_sweeps.fyw_n - (120.0_f64 * 120.0 / 2.0).sqrt()).abs() < 1e-6);
        let none = ChangeSize::measure(&[change([0.0; 4])], &sigma);
        assert_eq!(none.strength_noise_units, 0.0);
    }
}

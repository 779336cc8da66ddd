//! Anchoring an effect's relative parameters to the logs it is injected into, and its factors
//! at every sample.
//!
//! The logs injected together are one tyre compound: a temperature optimum is a quantile of
//! their pooled grip temperatures, the wear rate is set by the most-sliding of them, and so on,
//! so a cornering and a drive/brake run get the same μ(T) law. The states themselves (wear,
//! break-in energy) start again in each log, as each is a fresh specimen, and at every tyre
//! change within a log (a Square Matrix run changes its tyre ten times).

use std::collections::BTreeMap;

use crate::effect::{BreakInEffect, GripCurve, HiddenEffect, Recovery, ThermalEffect, WearEffect};
use crate::factors::Factors;
use crate::series::LogSeries;

/// Smallest temperature range a side of the friction curve is scaled by [K]: a log held at one
/// temperature must not turn a tenth of a kelvin into the full loss.
const MIN_SIDE_RANGE_K: f64 = 2.0;
/// Largest grip loss any curve gives [-].
const MAX_GRIP_LOSS: f64 = 0.5;

/// An effect with its parameters made absolute for a set of logs.
#[derive(Debug, Clone, PartialEq)]
pub struct Resolved {
    /// The effect as drawn.
    pub effect: HiddenEffect,
    /// The absolute values (temperatures °C, rates, thresholds W, energies J), by name.
    pub values: BTreeMap<String, f64>,
}

impl Resolved {
    /// Anchors `effect` to `logs`.
    pub fn new(effect: &HiddenEffect, logs: &[LogSeries]) -> Resolved {
        let values = match effect {
            HiddenEffect::Thermal(t) => resolve_thermal(t, logs),
            HiddenEffect::Wear(w) => resolve_wear(w, logs),
            HiddenEffect::BreakIn(b) => resolve_break_in(b, logs),
        };
        Resolved { effect: effect.clone(), values }
    }

    fn value(&self, key: &str) -> f64 {
        self.values.get(key).copied().unwrap_or(f64::NAN)
    }

    /// The effect's factors at every sample of `log`.
    pub fn factors(&self, log: &LogSeries) -> Vec<Factors> {
        match &self.effect {
            HiddenEffect::Thermal(t) => {
                let temps = log.grip_temperature_c(t.bulk_lag_s, t.surface_weight);
                temps.iter().map(|&c| self.thermal_at(t, c)).collect()
            }
            HiddenEffect::Wear(w) => {
                let rate = self.value("rate_mm_per_mj") * 1e-6;
                log.energy_j(0.0).iter().map(|&e| wear_at(w, rate * e)).collect()
            }
            HiddenEffect::BreakIn(b) => {
                let e0 = self.value("energy_scale_j");
                log.energy_j(self.value("threshold_w")).iter().map(|&e| break_in_at(b, e / e0)).collect()
            }
        }
    }

    fn thermal_at(&self, t: &ThermalEffect, temp_c: f64) -> Factors {
        if !temp_c.is_finite() {
            return Factors::NEUTRAL;
        }
        let (lo, hi) = (self.value("coldest_c"), self.value("hottest_c"));
        let opt = self.value("grip_optimum_c");
        let (x, side_loss) = if temp_c < opt {
            ((opt - temp_c) / (opt - lo).max(MIN_SIDE_RANGE_K), t.grip_loss_cold)
        } else {
            ((temp_c - opt) / (hi - opt).max(MIN_SIDE_RANGE_K), t.grip_loss_hot)
        };
        let shape = match t.grip_curve {
            GripCurve::AsymmetricQuadratic => x * x,
            GripCurve::AsymmetricGaussian { width } => {
                let w2 = 2.0 * width * width;
                (1.0 - (-x * x / w2).exp()) / (1.0 - (-1.0 / w2).exp())
            }
        };
        let loss = (side_loss * shape).min(MAX_GRIP_LOSS);
        let y = (temp_c - self.value("stiffness_reference_c")) / (hi - lo).max(2.0 * MIN_SIDE_RANGE_K);
        let k = (1.0 + t.strength * (-t.stiffness_slope * y - t.stiffness_curvature * y * y)).clamp(0.6, 1.4);
        Factors {
            mux: 1.0 - t.strength * loss * t.grip_x_ratio,
            muy: 1.0 - t.strength * loss,
            kx: k,
            ky: k,
            radius_m: t.strength * t.radius_mm_per_k * (temp_c - self.value("radius_reference_c")) * 1e-3,
            ..Factors::NEUTRAL
        }
    }
}

/// Wear at `depth_mm` of tread lost.
fn wear_at(w: &WearEffect, depth_mm: f64) -> Factors {
    let d = depth_mm.max(0.0);
    let grip = 1.0 + w.grip_per_mm * d.powf(w.grip_exponent);
    Factors {
        mux: grip,
        muy: grip,
        kx: 1.0 + w.stiffness_per_mm * d,
        ky: 1.0 + w.stiffness_per_mm * d,
        cx: 1.0 + w.shape_per_mm * d,
        cy: 1.0 + w.shape_per_mm * d,
        trail: 1.0 + w.trail_per_mm * d,
        radius_m: -d * 1e-3,
    }
}

/// Break-in after `e` severe energy scales (E/E0).
fn break_in_at(b: &BreakInEffect, e: f64) -> Factors {
    let e = if e.is_finite() { e.max(0.0) } else { 0.0 };
    let r = match b.recovery {
        Recovery::PowerLaw { exponent } => (1.0 + e).powf(-exponent),
        Recovery::TwoStage { fast_share, slow_ratio } => {
            fast_share * (-e).exp() + (1.0 - fast_share) * (-e / slow_ratio).exp()
        }
    };
    let grip = 1.0 - b.strength * b.grip_deficit * r;
    let k = 1.0 - b.strength * b.stiffness_deficit * r;
    let c = 1.0 - b.strength * b.shape_deficit * r;
    Factors { mux: grip, muy: grip, kx: k, ky: k, cx: c, cy: c, ..Factors::NEUTRAL }
}

fn resolve_thermal(t: &ThermalEffect, logs: &[LogSeries]) -> BTreeMap<String, f64> {
    let mut temps = pooled(logs, |log| log.grip_temperature_c(t.bulk_lag_s, t.surface_weight));
    temps.retain(|v| v.is_finite());
    temps.sort_by(f64::total_cmp);
    let q = |p: f64| quantile(&temps, p);
    BTreeMap::from([
        ("coldest_c".into(), q(0.02)),
        ("hottest_c".into(), q(0.98)),
        ("grip_optimum_c".into(), q(t.grip_optimum_quantile)),
        ("stiffness_reference_c".into(), q(t.stiffness_reference_quantile)),
        // The radius grows from the cold tyre's (the pressure rises with temperature).
        ("radius_reference_c".into(), q(0.05)),
    ])
}

fn resolve_wear(w: &WearEffect, logs: &[LogSeries]) -> BTreeMap<String, f64> {
    let e_max_j = logs.iter().map(|l| l.largest_tyre_energy_j(0.0)).fold(0.0, f64::max);
    let rate = if e_max_j > 0.0 { w.strength * w.depth_at_end_mm / (e_max_j * 1e-6) } else { 0.0 };
    BTreeMap::from([("rate_mm_per_mj".into(), rate), ("largest_log_energy_j".into(), e_max_j)])
}

fn resolve_break_in(b: &BreakInEffect, logs: &[LogSeries]) -> BTreeMap<String, f64> {
    let mut powers = pooled(logs, |log| log.sliding_power_w.clone());
    powers.retain(|p| *p > 0.0);
    powers.sort_by(f64::total_cmp);
    let threshold_w = if powers.is_empty() { 0.0 } else { quantile(&powers, b.threshold_quantile) };
    let e_max_j = logs.iter().map(|l| l.largest_tyre_energy_j(threshold_w)).fold(0.0, f64::max);
    // A log with no severe sliding keeps the whole deficit (E/E0 = 0 everywhere).
    let energy_scale_j = (b.energy_scale_share * e_max_j).max(1.0);
    BTreeMap::from([
        ("threshold_w".into(), threshold_w),
        ("energy_scale_j".into(), energy_scale_j),
        ("largest_log_severe_energy_j".into(), e_max_j),
    ])
}

/// The in-sweep values of `f` over every log (all values when no log has a sweep).
fn pooled(logs: &[LogSeries], f: impl Fn(&LogSeries) -> Vec<f64>) -> Vec<f64> {
    let mut all = Vec::new();
    let mut in_sweeps = Vec::new();
    for log in logs {
        let v = f(log);
        in_sweeps.extend(v.iter().zip(&log.in_sweep).filter(|(_, s)| **s).map(|(x, _)| *x));
        all.extend(v);
    }
    if in_sweeps.is_empty() { all } else { in_sweeps }
}

/// Linear-interpolated quantile of sorted values (NaN when empty).
fn quantile(sorted: &[f64], p: f64) -> f64 {
    match sorted.len() {
        0 => f64::NAN,
        1 => sorted[0],
        n => {
            let x = p.clamp(0.0, 1.0) * (n - 1) as f64;
            let i = (x.floor() as usize).min(n - 2);
            sorted[i] + (x - i as f64) * (sorted[i + 1] - sorted[i])
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::effect::EffectKind;

    fn log_at(temps: &[f64]) -> LogSeries {
        LogSeries {
            t_s: (0..temps.len()).map(|k| k as f64 * 0.01).collect(),
            temp_c: temps.to_vec(),
            sliding_power_w: vec![1000.0; temps.len()],
            in_sweep: vec![true; temps.len()],
            ..LogSeries::default()
        }
    }

    #[test]
    fn quantiles_interpolate() {
        assert_eq!(quantile(&[1.0, 2.0, 3.0], 0.5), 2.0);
        assert_eq!(quantile(&[1.0, 3.0], 0.25), 1.5);
        assert!(quantile(&[], 0.5).is_nan());
    }

    #[test]
    fn thermal_grip_is_lowest_away_from_its_optimum() {
        let HiddenEffect::Thermal(mut t) = HiddenEffect::draw(EffectKind::Thermal, 1, 1.0) else { unreachable!() };
        t.bulk_lag_s = 0.0;
        t.surface_weight = 1.0;
        t.grip_curve = GripCurve::AsymmetricQuadratic;
        t.grip_optimum_quantile = 0.5;
        t.grip_loss_cold = 0.05;
        t.grip_loss_hot = 0.10;
        let temps: Vec<f64> = (0..=100).map(|k| 40.0 + 0.4 * k as f64).collect();
        let log = log_at(&temps);
        let r = Resolved::new(&HiddenEffect::Thermal(t.clone()), std::slice::from_ref(&log));
        let f = r.factors(&log);
        assert!((r.value("grip_optimum_c") - 60.0).abs() < 1e-9);
        assert!((f[50].muy - 1.0).abs() < 1e-12, "no loss at the optimum");
        // The hottest 2 % quantile is at 79.2 °C: the full hot-side loss there.
        let hot = f[98].muy;
        assert!((hot - 0.90).abs() < 1e-3, "hot loss {hot}");
        let cold = f[2].muy;
        assert!((cold - 0.95).abs() < 1e-3, "cold loss {cold}");
        assert!(f[100].radius_m > f[0].radius_m, "a hot tyre's radius grows");
    }

    #[test]
    fn wear_radius_falls_by_the_depth_and_break_in_recovers() {
        let HiddenEffect::Wear(w) = HiddenEffect::draw(EffectKind::Wear, 2, 1.0) else { unreachable!() };
        let f = wear_at(&w, 0.7);
        assert!((f.radius_m + 0.7e-3).abs() < 1e-15);
        assert!(f.kx > 1.0 && f.cx > 1.0);
        let HiddenEffect::BreakIn(b) = HiddenEffect::draw(EffectKind::BreakIn, 2, 1.0) else { unreachable!() };
        let new = break_in_at(&b, 0.0);
        let run_in = break_in_at(&b, 100.0);
        assert!((new.muy - (1.0 - b.grip_deficit)).abs() < 1e-12);
        assert!(run_in.muy > new.muy && run_in.muy <= 1.0);
    }

    #[test]
    fn zero_strength_is_neutral_everywhere() {
        let temps: Vec<f64> = (0..200).map(|k| 30.0 + 0.2 * k as f64).collect();
        let log = log_at(&temps);
        for kind in EffectKind::ALL {
            let e = HiddenEffect::draw(kind, 7, 0.0);
            let r = Resolved::new(&e, std::slice::from_ref(&log));
            for f in r.factors(&log) {
                assert_eq!(f, Factors::NEUTRAL, "{kind}");
            }
        }
    }
}

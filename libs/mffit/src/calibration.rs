//! Is the band of the mean honest? Scores a channel's prediction map (value ± 1.96·σ over the
//! envelope grid, [`crate::prediction`]) against a known true tyre (the virtual rig's), on the
//! grid points inside the tested envelope and on those outside it.
//!
//! A calibrated σ holds 95 % of the true values in ±1.96·σ and has a median |error|/σ of
//! 0.674 (the median of |z| for a standard normal variate z); a σ too small holds fewer and has
//! a larger ratio, a σ too wide holds all and a ratio near zero.

use serde::Serialize;

use crate::accuracy::{ReferenceTyre, Support};
use crate::prediction::{EnvelopeGrid, MapChannel, PredictionMap};

/// The median |z| of a standard normal variate: what a calibrated median |error|/σ is.
pub const CALIBRATED_MEDIAN_RATIO: f64 = 0.674_489_75;

/// How one channel's band of the mean holds the true tyre over part of the grid.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct BandScore {
    /// Grid points scored (finite value, σ and truth).
    pub points: usize,
    /// % of the true values inside value ± 1.96·σ.
    pub in_band_pct: f64,
    /// Median of |true − value| / σ.
    pub median_error_over_std: f64,
    /// Median σ, channel units.
    pub median_std: f64,
    /// Median |true − value|, channel units.
    pub median_abs_error: f64,
}

/// One channel's calibration.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Calibration {
    /// `FYW`, `FX` or `MZW`.
    pub channel: String,
    /// Grid points inside the tested envelope ([`Support`]: a data point of the channel's stage
    /// within the box around it).
    pub tested: BandScore,
    /// Grid points outside it (extrapolation).
    pub outside: BandScore,
}

/// Scores every map of `maps` (over `grid`, model inputs at unloaded radius `r0_m`) against
/// `truth`; `support` decides which grid points lie inside the tested envelope (lateral data
/// for FYW and MZW, longitudinal data for FX).
pub fn calibrate(
    maps: &[PredictionMap],
    grid: &EnvelopeGrid,
    r0_m: f64,
    truth: &ReferenceTyre<'_>,
    support: &Support,
) -> Vec<Calibration> {
    maps.iter()
        .map(|map| {
            let inputs = grid.inputs(map.channel, r0_m);
            let set = match map.channel {
                MapChannel::FxPure => &support.longitudinal,
                MapChannel::FyPure | MapChannel::MzPure => &support.lateral,
            };
            let (mut tested, mut outside) = (Vec::new(), Vec::new());
            for ((x, &value), &std) in inputs.iter().zip(&map.value).zip(&map.std) {
                let t = map.channel.channel().eval_reference(truth, x);
                let e = (t - value).abs();
                if !(e.is_finite() && std.is_finite()) {
                    continue;
                }
                if support.near(set, x) { &mut tested } else { &mut outside }.push((e, std));
            }
            Calibration { channel: map.channel.tydex_name().into(), tested: score(&tested), outside: score(&outside) }
        })
        .collect()
}

/// [`BandScore`] of `(|error|, σ)` pairs.
fn score(pairs: &[(f64, f64)]) -> BandScore {
    let n = pairs.len();
    let inside = pairs.iter().filter(|(e, s)| *e <= 1.96 * s).count();
    let median = |v: Vec<f64>| crate::starts::median(v).unwrap_or(f64::NAN);
    BandScore {
        points: n,
        in_band_pct: if n == 0 { f64::NAN } else { 100.0 * inside as f64 / n as f64 },
        median_error_over_std: median(
            pairs.iter().map(|(e, s)| if *s > 0.0 { e / s } else { f64::INFINITY }).collect(),
        ),
        median_std: median(pairs.iter().map(|p| p.1).collect()),
        median_abs_error: median(pairs.iter().map(|p| p.0).collect()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_score_counts_the_band_and_the_ratio() {
        // Errors 0, 1, 2, 3 against σ = 1: 0, 1 inside ±1.96; ratios 0, 1, 2, 3 (median of four: the third).
        let s = score(&[(0.0, 1.0), (1.0, 1.0), (2.0, 1.0), (3.0, 1.0)]);
        assert_eq!(s.points, 4);
        assert_eq!(s.in_band_pct, 50.0);
        assert_eq!(s.median_error_over_std, 2.0);
        assert!(score(&[]).in_band_pct.is_nan());
    }
}

//! Starting values from the data: peak friction, slope at zero and curve shape, so the optimiser
//! starts near the right basin instead of from a generic `.tir`.

use std::f64::consts::{FRAC_PI_2, PI};

use crate::engine::Point;

/// Least-squares line `y = a + b·x`; `None` with fewer than two distinct x.
pub fn line_fit(xy: &[(f64, f64)]) -> Option<(f64, f64)> {
    let n = xy.len() as f64;
    if xy.len() < 2 {
        return None;
    }
    let mx = xy.iter().map(|p| p.0).sum::<f64>() / n;
    let my = xy.iter().map(|p| p.1).sum::<f64>() / n;
    let sxx: f64 = xy.iter().map(|p| (p.0 - mx) * (p.0 - mx)).sum();
    let sxy: f64 = xy.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
    if sxx.is_nan() || sxx <= 1e-300 {
        return None;
    }
    let b = sxy / sxx;
    Some((my - b * mx, b))
}

/// Peaks of one slip curve: for each side of zero slip, `(Fz at the peak, |F|/Fz at the peak,
/// |slip| at the peak, |F| at the largest |slip| / peak)`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Peak {
    /// Load at the peak, N.
    pub fz_n: f64,
    /// Friction coefficient at the peak.
    pub mu: f64,
    /// |slip| at the peak (rad or slip ratio).
    pub slip_at_peak: f64,
    /// Force at the largest slip as a fraction of the peak (≤ 1).
    pub tail_ratio: f64,
    /// Largest |slip| reached.
    pub slip_max: f64,
}

/// Finds the peaks of a segment's curve; `slip` picks the slip variable (α or κ).
pub fn peaks(points: &[Point], slip: impl Fn(&Point) -> f64) -> Vec<Peak> {
    let mut out = Vec::new();
    for side in [1.0_f64, -1.0] {
        let mut best: Option<(f64, &Point)> = None;
        let mut far: Option<(f64, &Point)> = None;
        for p in points.iter().filter(|p| slip(p) * side > 0.0 && p.input.fz_n > 100.0) {
            let mu = p.measured.abs() / p.input.fz_n;
            if best.is_none_or(|b| mu > b.0) {
                best = Some((mu, p));
            }
            let s = slip(p).abs();
            if far.is_none_or(|f| s > f.0) {
                far = Some((s, p));
            }
        }
        if let (Some((mu, bp)), Some((smax, fp))) = (best, far) {
            let tail = (fp.measured.abs() / fp.input.fz_n) / mu;
            out.push(Peak { fz_n: bp.input.fz_n, mu, slip_at_peak: slip(bp).abs(), tail_ratio: tail, slip_max: smax });
        }
    }
    out
}

/// The peaks that are maxima of their curve: the force fell past them (the largest slip is
/// clearly beyond the peak, and the force there is below it). A sweep that stops short of its
/// peak (small-slip sweeps, run for stiffness and drift) reports its end as its "peak": a
/// friction read from those is far too low (brush tyre, GS2MF: μ 0.6 at 2.5° against 1.1 at
/// 8.5°) and starts the optimiser in the wrong basin. All of `peaks` when none qualifies.
pub fn past_peak(peaks: &[Peak]) -> Vec<Peak> {
    let real: Vec<Peak> =
        peaks.iter().copied().filter(|p| p.slip_at_peak < 0.9 * p.slip_max && p.tail_ratio < 0.99).collect();
    if real.is_empty() { peaks.to_vec() } else { real }
}

/// Shape factor C from how far the force falls beyond the peak: for a curve reaching well past
/// its peak, `y∞/D = sin(C·π/2)`, so `C = 2 − (2/π)·asin(y∞/D)` (clamped to a sane range).
pub fn shape_factor(peaks: &[Peak], default: f64) -> f64 {
    // Only curves that go at least twice as far as their peak say anything about the tail.
    let cs: Vec<f64> = peaks
        .iter()
        .filter(|p| p.slip_max > 2.0 * p.slip_at_peak && p.tail_ratio < 0.999)
        .map(|p| 2.0 - (2.0 / PI) * p.tail_ratio.clamp(0.0, 1.0).asin())
        .collect();
    if cs.is_empty() { default } else { (cs.iter().sum::<f64>() / cs.len() as f64).clamp(1.05, 2.0) }
}

/// Curvature E from the peak position: with `y = D·sin(C·atan(B·x − E(B·x − atan(B·x))))` the
/// peak is where the inner argument is `π/(2C)`, so
/// `E = (B·xₘ − tan(π/(2C))) / (B·xₘ − atan(B·xₘ))`.
pub fn curvature(b: f64, c: f64, x_peak: f64) -> f64 {
    let bx = b * x_peak;
    let den = bx - bx.atan();
    if den.abs() < 1e-9 {
        return 0.0;
    }
    ((bx - (FRAC_PI_2 / c).tan()) / den).clamp(-3.0, 0.9)
}

/// Friction at nominal load and its load sensitivity from peaks: `μ = a + b·dfz`.
pub fn friction(peaks: &[Peak], fz0: f64) -> Option<(f64, f64)> {
    let xy: Vec<(f64, f64)> = peaks.iter().map(|p| ((p.fz_n - fz0) / fz0, p.mu)).collect();
    match line_fit(&xy) {
        Some((a, b)) if a > 0.1 => Some((a, b.clamp(-0.5 * a, 0.2 * a))),
        _ if !xy.is_empty() => Some((xy.iter().map(|p| p.1).sum::<f64>() / xy.len() as f64, 0.0)),
        _ => None,
    }
}

/// Slope at zero slip normalised by load: least squares of `F/Fz` against slip over the points
/// with `|slip| < limit`, with an offset.
pub fn slope_at_zero(points: &[Point], slip: impl Fn(&Point) -> f64, limit: f64) -> Option<f64> {
    let xy: Vec<(f64, f64)> = points
        .iter()
        .filter(|p| slip(p).abs() < limit && p.input.fz_n > 100.0)
        .map(|p| (slip(p), p.measured / p.input.fz_n))
        .collect();
    line_fit(&xy).map(|(_, b)| b)
}

/// Median of the finite values (`None` when there are none).
pub fn median(mut v: Vec<f64>) -> Option<f64> {
    v.retain(|x| x.is_finite());
    if v.is_empty() {
        return None;
    }
    v.sort_by(f64::total_cmp);
    Some(v[v.len() / 2])
}

#[cfg(test)]
mod tests {
    use super::*;

    fn peak(mu: f64, at_deg: f64, max_deg: f64, tail: f64) -> Peak {
        Peak { fz_n: 4000.0, mu, slip_at_peak: at_deg.to_radians(), tail_ratio: tail, slip_max: max_deg.to_radians() }
    }

    /// A sweep that stops at its largest force has no peak in it; friction is read from the
    /// curves that pass theirs, or from all when none does.
    #[test]
    fn only_curves_past_their_peak_give_friction() {
        let stopped_short = peak(0.6, 2.5, 2.5, 1.0);
        let passed = peak(1.1, 8.5, 16.0, 0.95);
        let nearly_at_end = peak(0.9, 11.0, 12.0, 0.999);
        assert_eq!(past_peak(&[stopped_short, passed, nearly_at_end]), vec![passed]);
        assert_eq!(past_peak(&[stopped_short]), vec![stopped_short]);
        assert!(past_peak(&[]).is_empty());
    }
}

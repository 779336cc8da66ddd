//! Detection of the known failure modes of MF fits (thesis §5): non-physical coefficients
//! (C ≤ 0, D ≤ 0, E > 1 somewhere in the tested range), a "square" friction ellipse (the
//! combined-slip local minimum) and extrapolation instability just outside the tested range.

use mftyre::{MfInput, TyreParams, UseMode};

use crate::data::ValidRange;
use crate::physics::{self, MarginSet};

/// Squareness above which a friction ellipse counts as square (see [`ellipse_squareness`]).
/// A round ellipse gives 1.0; a square one approaches 2.0; the project's default tyre gives 1.6
/// (its ellipse bulges where Fx peaks before Fy falls).
pub const SQUARE_LIMIT: f64 = 1.8;

fn input(fz: f64, kappa: f64, alpha: f64, gamma: f64, p: f64, v: f64) -> MfInput {
    MfInput {
        fz_n: fz,
        kappa,
        alpha_rad: alpha,
        gamma_rad: gamma,
        phit_per_m: 0.0,
        vx_mps: v,
        p_pa: p,
        omega_radps: 0.0,
    }
}

/// How square the friction ellipse is at nominal load and pressure: the largest
/// `(Fx/Fx,max)² + (Fy/Fy,max)²` along slip-ratio sweeps at slip angles 2°, 4° and 8°. A
/// round ellipse gives ≈ 1; a fit that keeps the full lateral force while the longitudinal
/// force saturates (the square ellipse) gives ≈ 2.
pub fn ellipse_squareness(params: &TyreParams, fz0: f64, p0: f64) -> f64 {
    let v = params.longvl_mps();
    let mut worst: f64 = 0.0;
    for a_deg in [2.0_f64, 4.0, 8.0] {
        let a = a_deg.to_radians();
        let pts: Vec<(f64, f64)> = (0..=100)
            .map(|i| {
                let k = -0.4 + 0.8 * i as f64 / 100.0;
                let o = mftyre::evaluate(params, UseMode::M211, &input(fz0, k, a, 0.0, p0, v));
                (o.fx_n, o.fy_n)
            })
            .collect();
        let fxp = pts.iter().map(|p| p.0).fold(0.0, f64::max).max(1e-9);
        let fxn = pts.iter().map(|p| -p.0).fold(0.0, f64::max).max(1e-9);
        let fym = pts.iter().map(|p| p.1.abs()).fold(0.0, f64::max).max(1e-9);
        for (fx, fy) in pts {
            let nx = if fx >= 0.0 { fx / fxp } else { fx / fxn };
            worst = worst.max(nx * nx + (fy / fym) * (fy / fym));
        }
    }
    worst
}

/// Every failure-mode finding for a fitted model over its tested range: Cy/Cx ≤ 0, the physical
/// margins of [`crate::physics`] (one line per failing set, naming the stage that owns it), a
/// square friction ellipse, and extrapolation instability.
pub fn check_all(params: &TyreParams, range: &ValidRange) -> Vec<String> {
    let mut out = Vec::new();
    let g = |k: &str| params.get(k).unwrap_or(0.0);
    if g("PCY1") <= 0.0 {
        out.push(format!("non-physical: PCY1 = {} (Cy ≤ 0)", g("PCY1")));
    }
    if g("PCX1") <= 0.0 {
        out.push(format!("non-physical: PCX1 = {} (Cx ≤ 0)", g("PCX1")));
    }
    let grid = physics::Grid::of_range(params, range);
    for set in [MarginSet::FyPure, MarginSet::MzPure, MarginSet::FxPure, MarginSet::FxCombined, MarginSet::FyCombined] {
        let failing: Vec<physics::Margin> =
            physics::margins(params, set, &grid).into_iter().filter(physics::fails).collect();
        if let Some(first) = failing.first() {
            let more = if failing.len() > 1 { format!(" (and {} more)", failing.len() - 1) } else { String::new() };
            out.push(format!("non-physical (stage {}): {}{more}", set.stage(), first.what));
        }
    }
    let sq = ellipse_squareness(params, params.fnomin_n(), params.nominal_pressure_pa());
    if sq > SQUARE_LIMIT {
        out.push(format!("square friction ellipse: squareness {sq:.2} > {SQUARE_LIMIT}"));
    }
    out.extend(extrapolation(params, range));
    out
}

/// Extrapolation instability: beyond the tested loads and slip angles (to 1.3× the range) the
/// lateral force must stay finite, below 3·Fz, and keep its sign past the peak.
pub fn extrapolation(params: &TyreParams, range: &ValidRange) -> Vec<String> {
    let fz0 = params.fnomin_n();
    let p0 = params.nominal_pressure_pa();
    let v = params.longvl_mps();
    let fz_max = if range.fz_n.is_empty() { 2.0 * fz0 } else { range.fz_n.max } * 1.3;
    let a_max = if range.alpha_rad.is_empty() { 0.3 } else { range.alpha_rad.max.max(-range.alpha_rad.min) } * 1.3;
    let mut out = Vec::new();
    for fz in [0.1 * fz0, 0.5 * fz0, fz0, fz_max] {
        for side in [-1.0, 1.0] {
            let mut peak: f64 = 0.0;
            for i in 1..=60 {
                let a = side * a_max * i as f64 / 60.0;
                let fy = mftyre::pure_fy(params, UseMode::M211, &input(fz, 0.0, a, 0.0, p0, v));
                if !fy.is_finite() || fy.abs() > 3.0 * fz {
                    out.push(format!(
                        "extrapolation unstable: FY {fy:.0} N at Fz {fz:.0} N, SA {:.1} deg",
                        a.to_degrees()
                    ));
                    return out;
                }
                if peak.abs() > 0.2 * fz && fy * peak < 0.0 {
                    out.push(format!(
                        "extrapolation unstable: FY changes sign past its peak at Fz {fz:.0} N, SA {:.1} deg",
                        a.to_degrees()
                    ));
                    return out;
                }
                if fy.abs() > peak.abs() {
                    peak = fy;
                }
            }
        }
    }
    out
}

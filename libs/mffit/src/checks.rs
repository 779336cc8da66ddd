//! Detection of the known failure modes of MF fits (thesis §5): non-physical coefficients
//! (C ≤ 0, D ≤ 0, E > 1 somewhere in the tested range), a "square" friction ellipse (the
//! combined-slip local minimum) and extrapolation instability just outside the tested range.

use mftyre::{MfInput, TyreParams, UseMode};

use crate::data::ValidRange;

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

/// Combined-slip weights outside [0, 1] (|combined| > |pure| by more than 2 %), as findings.
pub fn nonphysical_combined(params: &TyreParams) -> Vec<String> {
    let fz0 = params.fnomin_n();
    let p0 = params.nominal_pressure_pa();
    let v = params.longvl_mps();
    let mut out = Vec::new();
    for fz in [0.5 * fz0, fz0, 1.5 * fz0] {
        for a_deg in [-8.0_f64, -3.0, 3.0, 8.0] {
            for k in [-0.2, -0.05, 0.05, 0.2] {
                let i = input(fz, k, a_deg.to_radians(), 0.0, p0, v);
                let fx = mftyre::evaluate(params, UseMode::M211, &i).fx_n;
                let fx0 = mftyre::pure_fx(params, UseMode::M211, &i);
                if !fx.is_finite() || fx.abs() > 1.02 * fx0.abs() + 0.01 * fz {
                    out.push(format!(
                        "combined FX {fx:.0} N exceeds pure {fx0:.0} N at Fz {fz:.0} N, SA {a_deg} deg, SR {k}"
                    ));
                    return out;
                }
            }
        }
    }
    out
}

/// Every failure-mode finding for a fitted model over its tested range.
pub fn check_all(params: &TyreParams, range: &ValidRange) -> Vec<String> {
    let mut out = Vec::new();
    let fz0 = params.fnomin_n();
    let p0 = params.nominal_pressure_pa();
    let lfz = |fz: f64| (fz - fz0) / fz0;
    let dpi = |p: f64| (p - p0) / p0;
    let g = |k: &str| params.get(k).unwrap_or(0.0);
    let fz_r = if range.fz_n.is_empty() { (0.4 * fz0, 2.0 * fz0) } else { (range.fz_n.min.max(1.0), range.fz_n.max) };
    let g_r = if range.gamma_rad.is_empty() { (0.0, 0.0) } else { (range.gamma_rad.min, range.gamma_rad.max) };
    let p_r = if range.p_pa.is_empty() { (p0, p0) } else { (range.p_pa.min, range.p_pa.max) };
    if g("PCY1") <= 0.0 {
        out.push(format!("non-physical: PCY1 = {} (Cy ≤ 0)", g("PCY1")));
    }
    if g("PCX1") <= 0.0 {
        out.push(format!("non-physical: PCX1 = {} (Cx ≤ 0)", g("PCX1")));
    }
    let mut worst_dy = f64::INFINITY;
    let mut worst_dx = f64::INFINITY;
    let mut worst_ey = f64::NEG_INFINITY;
    let mut worst_ex = f64::NEG_INFINITY;
    for i in 0..=6 {
        let fz = fz_r.0 + (fz_r.1 - fz_r.0) * i as f64 / 6.0;
        let df = lfz(fz);
        for j in 0..=4 {
            let gam = g_r.0 + (g_r.1 - g_r.0) * j as f64 / 4.0;
            for l in 0..=2 {
                let p = p_r.0 + (p_r.1 - p_r.0) * l as f64 / 2.0;
                let dp = dpi(p);
                let muy = (g("PDY1") + g("PDY2") * df)
                    * (1.0 + g("PPY3") * dp + g("PPY4") * dp * dp)
                    * (1.0 - g("PDY3") * gam * gam);
                let mux = (g("PDX1") + g("PDX2") * df)
                    * (1.0 + g("PPX3") * dp + g("PPX4") * dp * dp)
                    * (1.0 - g("PDX3") * gam * gam);
                worst_dy = worst_dy.min(muy);
                worst_dx = worst_dx.min(mux);
                for sgn in [-1.0, 1.0] {
                    let ey = (g("PEY1") + g("PEY2") * df)
                        * (1.0 + g("PEY5") * gam * gam - (g("PEY3") + g("PEY4") * gam) * sgn);
                    let ex = (g("PEX1") + g("PEX2") * df + g("PEX3") * df * df) * (1.0 - g("PEX4") * sgn);
                    worst_ey = worst_ey.max(ey);
                    worst_ex = worst_ex.max(ex);
                }
            }
        }
    }
    // The model clamps E at 1 itself; still, E > 1 means the fit leaned on the clamp.
    if worst_dy <= 0.0 {
        out.push(format!("non-physical: lateral friction Dy/Fz reaches {worst_dy:.3} ≤ 0 in the tested range"));
    }
    if worst_dx <= 0.0 {
        out.push(format!("non-physical: longitudinal friction Dx/Fz reaches {worst_dx:.3} ≤ 0 in the tested range"));
    }
    if worst_ey > 1.0 {
        out.push(format!("non-physical: Ey reaches {worst_ey:.3} > 1 in the tested range (clamped by the model)"));
    }
    if worst_ex > 1.0 {
        out.push(format!("non-physical: Ex reaches {worst_ex:.3} > 1 in the tested range (clamped by the model)"));
    }
    let sq = ellipse_squareness(params, fz0, p0);
    if sq > SQUARE_LIMIT {
        out.push(format!("square friction ellipse: squareness {sq:.2} > {SQUARE_LIMIT}"));
    }
    out.extend(nonphysical_combined(params));
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

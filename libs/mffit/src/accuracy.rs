//! Model-against-model accuracy on a held-out grid of operating points inside the tested range:
//! how close a fitted tyre is to a reference ("true") tyre, as RMS difference in % of the
//! reference's peak, per channel.

use mftyre::{MfInput, TyreParams, UseMode};
use serde::Serialize;

use crate::data::ValidRange;
use crate::stages::FitResult;

/// The operating points the data cover, per kind of grid; a grid point counts as "inside the
/// tested range" when a data point lies within a box around it (load ±15 % of Fz0, slip angle
/// ±1°, slip ratio ±0.02, camber ±0.75°, pressure ±20 kPa). Empty = the whole box.
#[derive(Debug, Clone, Default)]
pub struct Support {
    /// Free-rolling force & moment data (FY, MZ, MX pure grids).
    pub lateral: Vec<MfInput>,
    /// Pure longitudinal data (FX pure grid).
    pub longitudinal: Vec<MfInput>,
    /// Combined-slip data (combined grids).
    pub combined: Vec<MfInput>,
    /// Nominal load for the load scale, N.
    pub fz0_n: f64,
}

impl Support {
    /// The support of a fit's own stage data.
    pub fn of_fit(result: &FitResult) -> Self {
        let take = |stage: &str| -> Vec<MfInput> {
            result.data.iter().filter(|d| d.stage == stage).flat_map(|d| d.points.iter().map(|p| p.input)).collect()
        };
        Support {
            lateral: take("fy_pure"),
            longitudinal: take("fx_pure"),
            combined: take("fx_combined"),
            fz0_n: result.nominal.fz0_n,
        }
    }

    /// True when a point of `set` (one of this support's sets) lies within the box around `x`;
    /// always for an empty set.
    pub fn near(&self, set: &[MfInput], x: &MfInput) -> bool {
        if set.is_empty() {
            return true;
        }
        let sf = 0.15 * self.fz0_n.max(1.0);
        let sa = 1.0f64.to_radians();
        let sg = 0.75f64.to_radians();
        set.iter().any(|d| {
            (d.fz_n - x.fz_n).abs() <= sf
                && (d.alpha_rad - x.alpha_rad).abs() <= sa
                && (d.kappa - x.kappa).abs() <= 0.02
                && (d.gamma_rad - x.gamma_rad).abs() <= sg
                && (d.p_pa - x.p_pa).abs() <= 20e3
        })
    }
}

/// One row of the accuracy table.
#[derive(Debug, Clone, Serialize)]
pub struct AccuracyRow {
    /// Channel and condition, e.g. `FY pure`.
    pub channel: String,
    /// RMS difference, channel units.
    pub rms: f64,
    /// RMS difference in % of the reference's peak |value| over the grid.
    pub rms_pct_of_peak: f64,
    /// Largest difference in % of the peak.
    pub max_pct_of_peak: f64,
    /// Grid points.
    pub points: usize,
}

fn lin(lo: f64, hi: f64, n: usize, i: usize) -> f64 {
    if n <= 1 { 0.5 * (lo + hi) } else { lo + (hi - lo) * i as f64 / (n - 1) as f64 }
}

/// Compares `fitted` with `truth` on grids inside `range` (shrunk by 5 % at each end), keeping
/// the grid points `support` covers (pass `Support::default()` for the whole box, which
/// includes combinations never tested, e.g. high camber at high slip). The grid points lie
/// between the tested conditions, not on them, hence "held out".
pub fn compare(truth: &TyreParams, fitted: &TyreParams, range: &ValidRange, support: &Support) -> Vec<AccuracyRow> {
    compare_with(&|mode, x| mftyre::evaluate(truth, mode, x), fitted, range, support)
}

/// A reference tyre as a function of use mode and operating point (a virtual rig's true tyre,
/// MF or brush; a measured map).
pub type ReferenceTyre<'a> = dyn Fn(UseMode, &MfInput) -> mftyre::MfOutput + 'a;

/// [`compare`] against any reference tyre given as a function (a brush tyre, a measured map).
pub fn compare_with(
    truth: &ReferenceTyre<'_>,
    fitted: &TyreParams,
    range: &ValidRange,
    support: &Support,
) -> Vec<AccuracyRow> {
    let shrink = |r: crate::data::Range| {
        let w = r.max - r.min;
        (r.min + 0.05 * w, r.max - 0.05 * w)
    };
    let fz = shrink(range.fz_n);
    let al = shrink(range.alpha_rad);
    let ka = shrink(range.kappa);
    let ga = shrink(range.gamma_rad);
    let pr = shrink(range.p_pa);
    let v = fitted.longvl_mps();
    let mut out = Vec::new();
    type Get = fn(&mftyre::MfOutput) -> f64;
    // Pure lateral: FY, MZ, MX over load × slip angle × camber × pressure, κ = 0.
    let mut pure_lat = Vec::new();
    for i in 0..7 {
        for j in 0..41 {
            for k in 0..5 {
                for l in 0..3 {
                    pure_lat.push(MfInput {
                        fz_n: lin(fz.0, fz.1, 7, i),
                        kappa: 0.0,
                        alpha_rad: lin(al.0, al.1, 41, j),
                        gamma_rad: lin(ga.0, ga.1, 5, k),
                        phit_per_m: 0.0,
                        vx_mps: v,
                        p_pa: lin(pr.0, pr.1, 3, l),
                        omega_radps: 0.0,
                    });
                }
            }
        }
    }
    // Pure longitudinal: FX over load × slip ratio × pressure at α = 0, small camber.
    let mut pure_long = Vec::new();
    for i in 0..7 {
        for j in 0..41 {
            for l in 0..3 {
                pure_long.push(MfInput {
                    fz_n: lin(fz.0, fz.1, 7, i),
                    kappa: lin(ka.0, ka.1, 41, j),
                    alpha_rad: 0.0,
                    gamma_rad: 0.0,
                    phit_per_m: 0.0,
                    vx_mps: v,
                    p_pa: lin(pr.0, pr.1, 3, l),
                    omega_radps: 0.0,
                });
            }
        }
    }
    // Combined: slip angle up to the combined data's ±8.5°-ish, slip ratio ±0.2, nominal pressure.
    let mut combined = Vec::new();
    let amax = 8.0f64.to_radians().min(al.1);
    let kmax = 0.2f64.min(ka.1);
    for i in 0..9 {
        for j in 0..17 {
            for k in 0..21 {
                combined.push(MfInput {
                    fz_n: lin(fz.0, fz.1, 9, i),
                    kappa: lin(-kmax, kmax, 21, k),
                    alpha_rad: lin(-amax, amax, 17, j),
                    gamma_rad: 0.0,
                    phit_per_m: 0.0,
                    vx_mps: v,
                    p_pa: fitted.nominal_pressure_pa(),
                    omega_radps: 0.0,
                });
            }
        }
    }
    pure_lat.retain(|x| support.near(&support.lateral, x));
    pure_long.retain(|x| support.near(&support.longitudinal, x));
    combined.retain(|x| support.near(&support.combined, x));
    let rows: [(&str, &Vec<MfInput>, UseMode, Get); 7] = [
        ("FY pure", &pure_lat, UseMode::M111, |o| o.fy_n),
        ("MZ pure", &pure_lat, UseMode::M111, |o| o.mz_nm),
        ("MX pure", &pure_lat, UseMode::M111, |o| o.mx_nm),
        ("FX pure", &pure_long, UseMode::M111, |o| o.fx_n),
        ("FX combined", &combined, UseMode::M111, |o| o.fx_n),
        ("FY combined", &combined, UseMode::M111, |o| o.fy_n),
        ("MZ combined", &combined, UseMode::M111, |o| o.mz_nm),
    ];
    for (name, grid, mode, get) in rows {
        let mut se = 0.0;
        let mut peak: f64 = 0.0;
        let mut maxe: f64 = 0.0;
        for inp in grid.iter() {
            let a = get(&truth(mode, inp));
            let b = get(&mftyre::evaluate(fitted, mode, inp));
            let e = b - a;
            se += e * e;
            peak = peak.max(a.abs());
            maxe = maxe.max(e.abs());
        }
        let rms = (se / grid.len().max(1) as f64).sqrt();
        out.push(AccuracyRow {
            channel: name.into(),
            rms,
            rms_pct_of_peak: 100.0 * rms / peak.max(1e-9),
            max_pct_of_peak: 100.0 * maxe / peak.max(1e-9),
            points: grid.len(),
        });
    }
    out
}

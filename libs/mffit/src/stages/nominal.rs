//! Stage 0: the nominal values every MF coefficient is relative to — speed V0 (LONGVL),
//! pressure P0 (NOMPRES), load Fz0 (FNOMIN) and the unloaded radius R0 — all from the data.

use serde::Serialize;

use crate::data::{DataKind, Dataset, Procedure, Sample};
use crate::error::FitError;
use crate::stages::FitOptions;
use crate::starts;

/// The nominal values of stage 0.
#[derive(Debug, Clone, Serialize)]
pub struct Nominal {
    /// LONGVL, m/s.
    pub v0_mps: f64,
    /// NOMPRES, Pa.
    pub p0_pa: f64,
    /// FNOMIN, N.
    pub fz0_n: f64,
    /// UNLOADED_RADIUS, m.
    pub r0_m: f64,
    /// How each was found.
    pub notes: Vec<String>,
}

fn median(mut v: Vec<f64>) -> Option<f64> {
    v.retain(|x| x.is_finite());
    if v.is_empty() {
        return None;
    }
    // The middle element without sorting all of them (a live fit takes this every update).
    let mid = v.len() / 2;
    Some(*v.select_nth_unstable_by(mid, f64::total_cmp).1)
}

/// Distinct pressure levels (clustered to 5 kPa), ascending; rare levels (pressure changes pass
/// through intermediate pressures) are ignored.
pub fn pressure_levels(data: &Dataset) -> Vec<f64> {
    let mut levels: Vec<(f64, usize)> = Vec::new();
    for seg in data.segments.iter().filter(|s| s.kind == DataKind::Sweep || s.kind == DataKind::RollingRadius) {
        for s in seg.samples.iter().step_by(10).filter(|s| s.p_pa.is_finite()) {
            match levels.iter_mut().find(|(p, _)| (p - s.p_pa).abs() < 5e3) {
                Some(l) => l.1 += 1,
                None => levels.push((s.p_pa, 1)),
            }
        }
    }
    let total: usize = levels.iter().map(|l| l.1).sum();
    // A level must hold at least ~1 % of the samples.
    let guard = if total < 100 { 1 } else { 5 };
    let mut v: Vec<f64> = levels.into_iter().filter(|l| l.1 * 20 >= total / guard).map(|l| l.0).collect();
    v.sort_by(f64::total_cmp);
    v
}

/// Samples near free rolling inside force & moment sweeps: |α| < 1°, |κ| < 1 %, rolling at
/// speed. Their loaded radius is the tyre's radius under load alone (no big forces).
pub fn near_free_rolling(data: &Dataset) -> Vec<&Sample> {
    data.segments
        .iter()
        .filter(|s| s.kind == DataKind::Sweep || s.kind == DataKind::OnCentre)
        .flat_map(|seg| {
            let free = seg.procedure == Procedure::FreeRolling;
            seg.samples.iter().filter(move |s| {
                s.alpha_rad.abs() < 1f64.to_radians()
                    && (free || s.kappa.abs() < 0.01)
                    && s.vx_mps > 2.0
                    && s.rl_m > 0.0
                    && s.fz_n > 0.0
            })
        })
        .collect()
}

/// R0 per pressure: loaded radius against load, straight line through the samples at the
/// lowest speed tested, extrapolated to zero load; the mean over pressures (thesis §3.11).
fn r0_from(samples: &[&Sample], levels: &[f64]) -> Option<f64> {
    if samples.len() < 10 {
        return None;
    }
    let vmin = samples.iter().map(|s| s.vx_mps).fold(f64::INFINITY, f64::min);
    // One pass over the samples for all levels (a live fit takes this every update).
    let mut per_level: Vec<Vec<(f64, f64)>> = vec![Vec::new(); levels.len()];
    for s in samples.iter().filter(|s| s.vx_mps < vmin + 2.0) {
        for (xy, &p) in per_level.iter_mut().zip(levels) {
            if (s.p_pa - p).abs() < 5e3 {
                xy.push((s.fz_n, s.rl_m));
            }
        }
    }
    let mut r0s = Vec::new();
    for xy in &per_level {
        if let Some((a, b)) = starts::line_fit(xy)
            && a.is_finite()
            && a > 0.0
            && b < 0.0
        {
            r0s.push(a);
        }
    }
    (!r0s.is_empty()).then(|| r0s.iter().sum::<f64>() / r0s.len() as f64)
}

/// Stage 0: nominal values V0, P0, Fz0 and R0.
pub fn nominal_values(data: &Dataset, opts: &FitOptions) -> Result<Nominal, FitError> {
    let fm = || data.select(|s| s.kind == DataKind::Sweep).map(|(_, s)| s);
    if fm().next().is_none() {
        return Err(FitError::NoData("no force & moment sweeps in the data".into()));
    }
    let mut notes = Vec::new();
    let v0 = median(fm().filter(|s| s.vx_mps > 2.0).map(|s| s.vx_mps).collect()).unwrap_or(16.6);
    let v0 = (v0 * 10.0).round() / 10.0;
    let levels = pressure_levels(data);
    let p0 = if levels.is_empty() {
        median(fm().map(|s| s.p_pa).collect()).unwrap_or(2.6e5)
    } else {
        levels[levels.len() / 2]
    };
    let p0 = (p0 / 1e3).round() * 1e3;
    notes.push(format!(
        "V0 {v0:.1} m/s (median sweep speed); P0 {:.0} kPa (middle of {} pressure level(s))",
        p0 / 1e3,
        levels.len().max(1)
    ));
    let (fz0, how) = match (opts.fnomin_n, data.fnomin_n) {
        (Some(f), _) => (f, "given (--fnomin)"),
        (None, Some(f)) => (f, "from the log's metadata"),
        (None, None) => {
            // The median load of the sweeps, to 10 N: the middle of the tested loads, where the
            // dfz terms are best determined.
            let m = median(fm().map(|s| s.fz_n).collect()).unwrap_or(5000.0);
            ((m / 10.0).round() * 10.0, "median sweep load")
        }
    };
    notes.push(format!("Fz0 {fz0:.0} N ({how})"));
    let plevels = if levels.is_empty() { vec![p0] } else { levels.clone() };
    // R0: rolling-radius holds when the test has them (GS2MF), else the near-free-rolling
    // samples inside the sweeps (any real test has those).
    let rr: Vec<&Sample> =
        data.select(|s| s.kind == DataKind::RollingRadius).map(|(_, s)| s).filter(|s| s.rl_m > 0.0).collect();
    let (r0, how) = if let Some(r) = r0_from(&rr, &plevels) {
        (r, "rolling-radius holds extrapolated to zero load".to_owned())
    } else {
        let nf = near_free_rolling(data);
        match r0_from(&nf, &plevels) {
            Some(r) => (
                r,
                format!(
                    "{} near-free-rolling sweep samples (|SA| < 1 deg, |SR| < 1 %) extrapolated to zero load",
                    nf.len()
                ),
            ),
            None => {
                let r = fm().map(|s| s.rl_m).filter(|r| r.is_finite()).fold(0.0, f64::max) + 0.01;
                (r, "no usable loaded radius against load: the largest loaded radius seen + 10 mm".to_owned())
            }
        }
    };
    notes.push(format!("R0 {r0:.4} m ({how})"));
    Ok(Nominal { v0_mps: v0, p0_pa: p0, fz0_n: fz0, r0_m: r0, notes })
}

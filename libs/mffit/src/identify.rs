//! Which coefficients a stage's data can identify, and how well the fit determines them.
//!
//! A real test seldom covers everything MF-Tyre 6.1 can describe: a cornering run at camber 0
//! says nothing about camber thrust, a drive/brake run at one pressure nothing about pressure.
//! Fitting such a coefficient anyway fits noise (or another effect) into it, and the model then
//! extrapolates that noise. So before a stage fits, its candidate keys are judged in two ways,
//! and only those that pass are freed; the others keep their template values and the report
//! says why:
//!
//! 1. **Structure** — what the coefficient multiplies must vary in the data: a load term needs
//!    two load levels (a quadratic one three), a camber term two cambers, a pressure term two
//!    pressures (quadratic: three), a speed term two speeds ([`need`], [`Levels`]).
//! 2. **The Jacobian** — at the stage's start, the residuals' sensitivity to each key, columns
//!    normalised, taken in the stage's priority order (nominal terms first): a key whose column
//!    is (numerically) a combination of the keys already accepted cannot be told apart from them
//!    by this data (variance inflation above [`MAX_VIF`]), and is held ([`by_jacobian`]).
//!
//! After the fit, [`uncertainty`] gives each fitted coefficient a standard deviation from the
//! Jacobian at the solution and the residual variance: cov = s²·(JᵀJ)⁻¹, with s² the residual
//! variance and an inflation for serially correlated residuals (the data are time series: the
//! residual of a 10 Hz point is much like its neighbour's, so there are fewer independent
//! points than rows). The figures describe the spread over repeats of the same test; model-form
//! error is visible in the k-fold held-out error, not here.

use std::collections::BTreeMap;

use mftyre::TyreParams;
use nalgebra::{DMatrix, DVector};
use serde::Serialize;

use crate::engine::{Channel, ChannelProblem, Point, bounds_for, values_of};

/// A key whose variance inflation (1/(1 − R²) against the keys accepted before it) exceeds this
/// is held: at 10⁶ the data determine it a thousand times worse than an orthogonal one.
pub const MAX_VIF: f64 = 1.0e6;

/// Fewest points a level needs to count: a term fitted from fewer is fitted to their noise (the
/// brush road tyre's MZ camber terms, from 46 points at the zero crossings of slip-ratio sweeps,
/// held out at 19 % and 34 % on the repeat run).
pub const MIN_LEVEL_POINTS: usize = 20;

/// Distinct operating levels present in a stage's points.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Levels {
    /// Load levels (clustered to 8 % of Fz0), N.
    pub loads_n: Vec<f64>,
    /// Pressure levels (clustered to 5 kPa), Pa.
    pub pressures_pa: Vec<f64>,
    /// Camber levels (clustered to 0.5°), rad.
    pub cambers_rad: Vec<f64>,
    /// The camber levels at which a slip is swept ([`SWEPT_SLIP_ANGLE_RAD`],
    /// [`SWEPT_SLIP_RATIO`]), rad: a camber sweep at one held slip angle (camber stepped 0–4° at
    /// 1.8°, as some rounds' cornering runs end) adds camber levels, but at one point of each
    /// level's slip curve only.
    pub swept_cambers_rad: Vec<f64>,
    /// Speed levels (clustered to 2 m/s), m/s.
    pub speeds_mps: Vec<f64>,
}

/// Levels of `values` with tolerance `tol`, from a histogram of bins `tol/2` wide: a bin is
/// occupied when it holds at least [`MIN_LEVEL_POINTS`] values and 0.2 % of them, so ramps,
/// stray samples between levels and a level touched by a handful of points (the zero crossings
/// of slip-ratio sweeps at other cambers, in a cornering run at one camber) do not count; runs of occupied bins are groups, and a group
/// counts one level per `tol` it spans (a held level with sensor noise spans one; a load that
/// varies continuously within every sweep spans many).
fn clusters(values: impl Iterator<Item = f64>, tol: f64) -> Vec<f64> {
    let v: Vec<f64> = values.filter(|x| x.is_finite()).collect();
    if v.is_empty() || tol.is_nan() || tol <= 0.0 {
        return Vec::new();
    }
    let lo = v.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = v.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let w = tol / 2.0;
    // Bound the histogram: a range of more than 10,000 bins is no levelled test.
    let nbins = (((hi - lo) / w).floor() as usize + 1).min(10_000);
    let w = if nbins == 10_000 { (hi - lo) / 9_999.0 } else { w };
    let mut count = vec![0usize; nbins];
    for x in &v {
        let b = (((x - lo) / w.max(1e-300)).floor() as usize).min(nbins - 1);
        count[b] += 1;
    }
    let min_count = (v.len() / 500).max(MIN_LEVEL_POINTS);
    let mut out = Vec::new();
    let mut b = 0;
    while b < nbins {
        if count[b] < min_count {
            b += 1;
            continue;
        }
        let first = b;
        while b < nbins && count[b] >= min_count {
            b += 1;
        }
        let (a, z) = (lo + first as f64 * w, lo + b as f64 * w);
        let n = (((z - a) - w) / tol).floor().max(0.0) as usize + 1;
        for k in 0..n {
            out.push(a + (z - a) * (k as f64 + 0.5) / n as f64);
        }
    }
    out
}

/// Spread (5–95 % range) of the slip angle over a camber level's points above which the slip
/// angle counts as swept there: a TTC cornering sweep reaches ±6–13°, the held slip angles of
/// combined runs are 0, 3 and 6°; a camber sweep holds one.
pub const SWEPT_SLIP_ANGLE_RAD: f64 = 3.0 * std::f64::consts::PI / 180.0;

/// Spread of the slip ratio over a camber level's points above which it counts as swept there.
pub const SWEPT_SLIP_RATIO: f64 = 0.05;

/// Camber tolerance of a level, rad.
const CAMBER_TOL_RAD: f64 = 0.5 * std::f64::consts::PI / 180.0;

/// True when the slip angle or the slip ratio is swept among `points` at camber `gamma_rad`
/// (within half the camber tolerance).
fn slip_swept_at(points: &[Point], gamma_rad: f64) -> bool {
    let at: Vec<&Point> =
        points.iter().filter(|p| (p.input.gamma_rad - gamma_rad).abs() <= CAMBER_TOL_RAD / 2.0).collect();
    let spread = |v: Vec<f64>| {
        let mut v: Vec<f64> = v.into_iter().filter(|x| x.is_finite()).collect();
        if v.len() < MIN_LEVEL_POINTS {
            return 0.0;
        }
        v.sort_by(f64::total_cmp);
        let q = |f: f64| v[((v.len() - 1) as f64 * f).round() as usize];
        q(0.95) - q(0.05)
    };
    spread(at.iter().map(|p| p.input.alpha_rad).collect()) >= SWEPT_SLIP_ANGLE_RAD
        || spread(at.iter().map(|p| p.input.kappa).collect()) >= SWEPT_SLIP_RATIO
}

impl Levels {
    /// The levels of `points`, with the nominal load `fz0_n` setting the load tolerance.
    pub fn of(points: &[Point], fz0_n: f64) -> Self {
        let cambers_rad = clusters(points.iter().map(|p| p.input.gamma_rad), CAMBER_TOL_RAD);
        let swept_cambers_rad = cambers_rad.iter().copied().filter(|&c| slip_swept_at(points, c)).collect();
        Levels {
            loads_n: clusters(points.iter().map(|p| p.input.fz_n), 0.08 * fz0_n.max(1.0)),
            pressures_pa: clusters(points.iter().map(|p| p.input.p_pa), 5e3),
            cambers_rad,
            swept_cambers_rad,
            speeds_mps: clusters(points.iter().map(|p| p.input.vx_mps), 2.0),
        }
    }

    fn describe(&self, what: Dim) -> String {
        let list = |v: &[f64], f: &dyn Fn(f64) -> String| v.iter().map(|x| f(*x)).collect::<Vec<_>>().join(", ");
        match what {
            Dim::Load => {
                format!("{} load level(s) ({})", self.loads_n.len(), list(&self.loads_n, &|x| format!("{x:.0} N")))
            }
            Dim::Pressure => format!(
                "{} pressure level(s) ({})",
                self.pressures_pa.len(),
                list(&self.pressures_pa, &|x| format!("{:.0} kPa", x / 1e3))
            ),
            Dim::Camber => format!(
                "{} camber level(s) ({})",
                self.cambers_rad.len(),
                list(&self.cambers_rad, &|x| format!("{:.1} deg", x.to_degrees()))
            ),
            Dim::SweptCamber => format!(
                "{} camber level(s) with the slip swept ({}; camber sweeps at one slip angle do not count)",
                self.swept_cambers_rad.len(),
                list(&self.swept_cambers_rad, &|x| format!("{:.1} deg", x.to_degrees()))
            ),
            Dim::Speed => format!(
                "{} speed level(s) ({})",
                self.speeds_mps.len(),
                list(&self.speeds_mps, &|x| format!("{x:.1} m/s"))
            ),
        }
    }

    fn count(&self, what: Dim) -> usize {
        match what {
            Dim::Load => self.loads_n.len(),
            Dim::Pressure => self.pressures_pa.len(),
            Dim::Camber => self.cambers_rad.len(),
            Dim::SweptCamber => self.swept_cambers_rad.len(),
            Dim::Speed => self.speeds_mps.len(),
        }
    }
}

/// An operating variable a coefficient's effect depends on.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Dim {
    /// Vertical load (dfz terms).
    Load,
    /// Inflation pressure (dpi terms).
    Pressure,
    /// Inclination angle (γ terms), any level: terms a held slip angle shows (camber thrust
    /// at small slip, the residual moment per camber).
    Camber,
    /// Inclination angle at which the slip is swept: γ terms that shape the slip curve (its
    /// peak, curvature, stiffness and shifts), which one point of the curve per camber cannot
    /// tell from each other.
    SweptCamber,
    /// Speed (Ω, V terms).
    Speed,
}

/// The most levels of one variable any coefficient [`need`]s: beyond it, more levels free no
/// further coefficient.
pub const MOST_LEVELS_NEEDED: usize = 3;

/// How many distinct levels of which variables a coefficient needs to be identifiable, from the
/// MF-Tyre 6.1 equations: e.g. PDY2 multiplies dfz (2 loads), PEX3 multiplies dfz² (3 loads),
/// PKY4 shapes Kyα(Fz) beyond its slope (3 loads), PPY4 multiplies dpi² (3 pressures).
pub fn need(key: &str) -> &'static [(Dim, usize)] {
    use Dim::*;
    match key {
        // Lateral, pure.
        "PDY2" | "PEY2" | "PHY2" | "PVY2" | "PKY2" => &[(Load, 2)],
        "PKY4" => &[(Load, 3)],
        "PKY6" => &[(Camber, 2)],
        "PKY7" => &[(Camber, 2), (Load, 2)],
        "PDY3" | "PEY4" | "PEY5" | "PKY3" | "PKY5" | "PVY3" => &[(SweptCamber, 2)],
        "PVY4" => &[(SweptCamber, 2), (Load, 2)],
        "PPY1" | "PPY3" => &[(Pressure, 2)],
        "PPY2" => &[(Pressure, 2), (Load, 2)],
        "PPY4" => &[(Pressure, 3)],
        "PPY5" => &[(Pressure, 2), (SweptCamber, 2)],
        // Longitudinal, pure.
        "PDX2" | "PEX2" | "PKX2" | "PHX2" | "PVX2" => &[(Load, 2)],
        "PEX3" | "PKX3" => &[(Load, 3)],
        "PDX3" => &[(SweptCamber, 2)],
        "PPX1" | "PPX3" => &[(Pressure, 2)],
        "PPX2" | "PPX4" => &[(Pressure, 3)],
        // Aligning, pure.
        "QBZ2" | "QDZ2" | "QDZ7" | "QEZ2" | "QHZ2" => &[(Load, 2)],
        "QBZ3" | "QEZ3" => &[(Load, 3)],
        "QDZ8" => &[(Camber, 2)],
        "QDZ9" => &[(Camber, 2), (Load, 2)],
        "QBZ4" | "QBZ5" | "QDZ3" | "QDZ4" | "QDZ10" | "QEZ5" | "QHZ3" => &[(SweptCamber, 2)],
        "QDZ11" | "QHZ4" => &[(SweptCamber, 2), (Load, 2)],
        "PPZ1" | "PPZ2" => &[(Pressure, 2)],
        // Combined.
        "REX2" | "REY2" | "RHY2" | "RVY2" => &[(Load, 2)],
        "RBX3" | "RBY4" | "RVY3" | "SSZ3" => &[(Camber, 2)],
        "SSZ4" => &[(Camber, 2), (Load, 2)],
        // Overturning.
        "QSX2" | "QSX7" | "QSX10" | "QSX12" | "QSX14" => &[(Camber, 2)],
        "PPMX1" => &[(Camber, 2), (Pressure, 2)],
        // Vertical.
        "Q_FZ2" => &[(Load, 3)],
        "PFZ1" => &[(Pressure, 2)],
        "Q_V1" | "Q_V2" => &[(Speed, 2)],
        "Q_CAM" => &[(Camber, 2)],
        "BREFF" | "DREFF" | "FREFF" => &[(Load, 3)],
        "PCFX1" | "PCFX2" | "PCFY1" | "PCFY2" => &[(Load, 2)],
        "PCFX3" | "PCFY3" => &[(Pressure, 2)],
        _ => &[],
    }
}

/// A coefficient a stage did not fit, with the reason.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Held {
    /// `.tir` key.
    pub key: String,
    /// Value it keeps (the template's, or what an earlier stage set).
    pub value: f64,
    /// Why, in words a tyre engineer can act on.
    pub reason: String,
}

/// The verdict on a stage's candidate keys.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Identification {
    /// Keys the data identify, in priority order.
    pub free: Vec<&'static str>,
    /// Keys held, with reasons.
    pub held: Vec<Held>,
}

/// True when `held` was held because the data lack levels of what it multiplies (a region of
/// the operating envelope not tested, e.g. one camber), as [`structural`] words it; false for
/// keys the Jacobian found without effect or not separable.
pub fn is_structural(held: &Held) -> bool {
    held.reason.contains(STRUCTURAL_REASON)
}

const STRUCTURAL_REASON: &str = "levels, the data have";

/// Keys the structure of the data rules out (too few levels of what they multiply).
pub fn structural(params: &TyreParams, keys: &[&'static str], levels: &Levels) -> Identification {
    let mut out = Identification::default();
    for &k in keys {
        let missing: Vec<String> = need(k)
            .iter()
            .filter(|(d, n)| levels.count(*d) < *n)
            .map(|(d, n)| format!("needs {n} {STRUCTURAL_REASON} {}", levels.describe(*d)))
            .collect();
        if missing.is_empty() {
            out.free.push(k);
        } else {
            out.held.push(Held { key: k.into(), value: params.get(k).unwrap_or(0.0), reason: missing.join("; ") });
        }
    }
    out
}

/// The Jacobian (data residuals only, in channel units per unit coefficient) of `channel` over
/// `points` with respect to `keys`, at `params` (values clamped into their fitting bounds).
pub fn jacobian(
    params: &TyreParams,
    keys: &[&'static str],
    points: &[Point],
    channel: Channel,
    threads: usize,
) -> DMatrix<f64> {
    let mut problem = ChannelProblem::new(params, keys, points, channel, 1.0);
    problem.threads = threads.max(1);
    let p: Vec<f64> = values_of(params, keys)
        .iter()
        .zip(keys)
        .map(|(v, k)| {
            let (lo, hi) = bounds_for(k);
            v.clamp(lo, hi)
        })
        .collect();
    let mut j = DMatrix::zeros(points.len(), keys.len());
    lsq::Problem::jacobian(&problem, &DVector::from_vec(p), &mut j);
    j
}

/// Judges `keys` (already structurally possible) by the Jacobian: in priority order, a key is
/// accepted unless its normalised column is (within 1/[`MAX_VIF`]) in the span of the columns
/// accepted before it, or has no effect at all on these points.
pub fn by_jacobian(
    params: &TyreParams,
    keys: &[&'static str],
    points: &[Point],
    channel: Channel,
    threads: usize,
) -> Identification {
    if keys.is_empty() || points.is_empty() {
        return Identification::default();
    }
    judge_jacobian(params, keys, &jacobian(params, keys, points, channel, threads))
}

/// [`by_jacobian`] on a Jacobian already in hand (columns in the order of `keys`).
pub fn judge_jacobian(params: &TyreParams, keys: &[&'static str], j: &DMatrix<f64>) -> Identification {
    let mut out = Identification::default();
    if keys.is_empty() || j.nrows() == 0 {
        return out;
    }
    let norms: Vec<f64> = (0..keys.len()).map(|c| j.column(c).norm()).collect();
    let biggest = norms.iter().copied().filter(|x| x.is_finite()).fold(0.0, f64::max);
    // Orthonormal basis of the accepted columns (modified Gram–Schmidt, twice for accuracy).
    let mut basis: Vec<DVector<f64>> = Vec::new();
    let mut basis_keys: Vec<&'static str> = Vec::new();
    let min_fraction = 1.0 / MAX_VIF.sqrt();
    for (c, &k) in keys.iter().enumerate() {
        let value = params.get(k).unwrap_or(0.0);
        if !norms[c].is_finite() {
            out.held.push(Held { key: k.into(), value, reason: "the model is not finite around its start".into() });
            continue;
        }
        if norms[c] <= 1e-12 * biggest.max(1e-300) {
            out.held.push(Held { key: k.into(), value, reason: "no effect on this data (zero sensitivity)".into() });
            continue;
        }
        let col = j.column(c) / norms[c];
        let mut r = col.clone();
        for _ in 0..2 {
            for q in &basis {
                let d = q.dot(&r);
                r -= q * d;
            }
        }
        let fraction = r.norm();
        if fraction < min_fraction {
            // Name the accepted keys it is most alike.
            let mut alike: Vec<(f64, &str)> = basis_keys
                .iter()
                .enumerate()
                .map(|(i, bk)| {
                    let ci = keys.iter().position(|x| x == bk).unwrap_or(i);
                    ((j.column(ci) / norms[ci]).dot(&col).abs(), *bk)
                })
                .collect();
            alike.sort_by(|a, b| b.0.total_cmp(&a.0));
            let names: Vec<&str> = alike.iter().take(3).map(|a| a.1).collect();
            out.held.push(Held {
                key: k.into(),
                value,
                reason: format!(
                    "cannot be told apart from {} in this data (variance inflation {:.1e})",
                    names.join(", "),
                    1.0 / (fraction * fraction).max(1e-300)
                ),
            });
            continue;
        }
        basis.push(r / fraction);
        basis_keys.push(k);
        out.free.push(k);
    }
    out
}

/// One fitted coefficient's estimate.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Estimate {
    /// `.tir` key.
    pub key: String,
    /// Fitted value.
    pub value: f64,
    /// Standard deviation (1σ), same units; NaN when the covariance is singular.
    pub std: f64,
    /// 1σ from refits that each leave out a fold of the sweeps (grouped jackknife over the
    /// cross-validation's folds, [`crate::stages::crossval`]): it counts how much the value
    /// depends on which sweeps were tested, form error and correlated noise included, which
    /// `std` (repeatability under a correct model) does not. `None` without cross-validation.
    pub std_sweeps: Option<f64>,
}

/// Standard deviations of the fitted `keys` at the solution `params`.
///
/// `groups[i]` is the segment (sweep) of `points[i]`; consecutive points of one group are a time
/// series, whose lag-1 autocorrelation ρ of the residuals inflates the variance by (1+ρ)/(1−ρ)
/// (the effective number of independent points, clamped to at most 50×).
pub fn uncertainty(
    params: &TyreParams,
    keys: &[&'static str],
    points: &[Point],
    groups: &[usize],
    channel: Channel,
    threads: usize,
) -> (Vec<Estimate>, f64) {
    let (est, inflation, _) = uncertainty_with_covariance(params, keys, points, groups, channel, threads);
    (est, inflation)
}

/// [`uncertainty`] with the whole covariance matrix of `keys` (row-major n×n; empty when it
/// cannot be computed, infinite entries where a direction is unidentified): the delta method
/// turns it into the uncertainty of the model's predictions.
pub fn uncertainty_with_covariance(
    params: &TyreParams,
    keys: &[&'static str],
    points: &[Point],
    groups: &[usize],
    channel: Channel,
    threads: usize,
) -> (Vec<Estimate>, f64, Vec<f64>) {
    uncertainty_from(params, keys, points, groups, channel, || jacobian(params, keys, points, channel, threads))
}

/// [`uncertainty_with_covariance`] with the Jacobian at `params` from `jacobian_at_params`
/// (called only when there is something to estimate): a fit that judged its keys on that
/// Jacobian hands it over instead of differencing the model again.
pub fn uncertainty_from(
    params: &TyreParams,
    keys: &[&'static str],
    points: &[Point],
    groups: &[usize],
    channel: Channel,
    jacobian_at_params: impl FnOnce() -> DMatrix<f64>,
) -> (Vec<Estimate>, f64, Vec<f64>) {
    let n = keys.len();
    let m = points.len();
    let nan = |k: &&str| Estimate {
        key: (*k).into(),
        value: params.get(k).unwrap_or(f64::NAN),
        std: f64::NAN,
        std_sweeps: None,
    };
    if n == 0 || m <= n {
        return (keys.iter().map(nan).collect(), 1.0, Vec::new());
    }
    let res: Vec<f64> = channel.values_at(params, points).iter().zip(points).map(|(v, p)| v - p.measured).collect();
    let ssr: f64 = res.iter().map(|r| r * r).sum();
    let s2 = ssr / (m - n) as f64;
    let inflation = serial_inflation(&res, groups);
    let j = jacobian_at_params();
    let svd = j.svd(false, true);
    let (Some(vt), sv) = (svd.v_t.as_ref(), &svd.singular_values) else {
        return (keys.iter().map(nan).collect(), inflation, Vec::new());
    };
    let smax = sv.iter().copied().fold(0.0, f64::max);
    // Cov = s²·inflation·V·Σ⁻²·Vᵀ; a (numerically) zero σ_k makes the directions it spans unbounded.
    let scale = s2 * inflation;
    let mut cov = vec![0.0; n * n];
    for a in 0..n {
        for b in 0..n {
            let mut c = 0.0;
            for k in 0..sv.len() {
                let (va, vb) = (vt[(k, a)], vt[(k, b)]);
                if sv[k] <= 1e-13 * smax {
                    if va.abs() > 1e-9 && vb.abs() > 1e-9 {
                        c = f64::INFINITY;
                        break;
                    }
                    continue;
                }
                c += va * vb / (sv[k] * sv[k]);
            }
            cov[a * n + b] = scale * c;
        }
    }
    let estimates = (0..n)
        .map(|c| Estimate {
            key: keys[c].into(),
            value: params.get(keys[c]).unwrap_or(f64::NAN),
            std: cov[c * n + c].sqrt(),
            std_sweeps: None,
        })
        .collect();
    (estimates, inflation, cov)
}

/// (1+ρ)/(1−ρ) from the lag-1 autocorrelation of residuals within groups, in [1, 50].
fn serial_inflation(res: &[f64], groups: &[usize]) -> f64 {
    let mut by_group: BTreeMap<usize, Vec<f64>> = BTreeMap::new();
    for (r, g) in res.iter().zip(groups) {
        by_group.entry(*g).or_default().push(*r);
    }
    let (mut num, mut den) = (0.0, 0.0);
    for v in by_group.values() {
        if v.len() < 3 {
            continue;
        }
        let mean = v.iter().sum::<f64>() / v.len() as f64;
        for w in v.windows(2) {
            num += (w[0] - mean) * (w[1] - mean);
        }
        den += v.iter().map(|x| (x - mean) * (x - mean)).sum::<f64>();
    }
    if den <= 0.0 {
        return 1.0;
    }
    let rho = (num / den).clamp(0.0, 0.96);
    ((1.0 + rho) / (1.0 - rho)).clamp(1.0, 50.0)
}

#[cfg(test)]
mod tests {

    #[test]
    fn no_coefficient_needs_more_than_the_most_levels_needed() {
        for group in mftyre::CoefGroup::ALL {
            for key in group.keys() {
                for (_, n) in need(key) {
                    assert!(*n <= MOST_LEVELS_NEEDED, "{key} needs {n} levels");
                }
            }
        }
    }

    use super::*;

    #[test]
    fn clusters_find_levels_and_ignore_ramps() {
        let mut v: Vec<f64> = Vec::new();
        for level in [220.0, 660.0, 1100.0] {
            v.extend(std::iter::repeat_n(level, 200));
        }
        // A ramp between levels: a few samples each.
        v.extend((0..40).map(|i| 660.0 + i as f64 * 11.0));
        let c = clusters(v.into_iter(), 80.0);
        assert_eq!(c.len(), 3, "{c:?}");
    }

    #[test]
    fn serial_inflation_is_one_for_white_and_large_for_smooth_residuals() {
        let white: Vec<f64> = (0..400).map(|i| if i % 2 == 0 { 1.0 } else { -1.0 }).collect();
        assert!((serial_inflation(&white, &vec![0; 400]) - 1.0).abs() < 1e-9);
        let smooth: Vec<f64> = (0..400).map(|i| (i as f64 / 40.0).sin()).collect();
        assert!(serial_inflation(&smooth, &vec![0; 400]) > 20.0);
    }
}

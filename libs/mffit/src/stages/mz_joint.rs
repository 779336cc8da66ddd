//! The combined aligning moment's trail and residual torque, refined on the combined sweeps
//! together with `mz_pure`'s points.
//!
//! MF 6.1's combined Mz (MFeval A54–A56) is `−t(αt,eq)·F′y + Mzr(αr,eq) + s·Fx`: the pneumatic
//! trail and the residual torque are the pure ones evaluated at the equivalent slip angles
//! (αt,eq = atan√(tan²αt + (Kxκ/K′yα)²κ²), likewise αr,eq), F′y = Gyκ·Fy0(γ = 0) and Fx come
//! from the combined force stages, and only the arm s (SSZ1–4) is the moment's own. So the
//! combined sweeps say as much about the trail and residual-torque coefficients as about SSZ:
//! at the held slip angles they show the trail at the loads and cambers of the drive/brake run
//! (often cambers the cornering run never had), and along the slip ratio how it decays. Fitting
//! SSZ alone leaves every difference there to the arm (brush tyres: MZ combined 6.2–6.4 %
//! against 3.1–4.3 % pure).
//!
//! Here those coefficients are refitted on both sets at once, each point's residual in % of its
//! own set's peak and the pure set weighted as much as the combined one, so the pure fit is
//! moved only where the combined sweeps gain more than it loses. Only keys the joint data
//! identify are freed (levels, then the weighted Jacobian at the solution); the refinement is
//! kept only when MZ combined improves and MZ pure stays within [`PURE_TOLERANCE`] of its fit,
//! physical. Otherwise the SSZ-only fit stands and the report says why.

use mftyre::TyreParams;
use nalgebra::{DMatrix, DVector};

use crate::engine::{Channel, ChannelProblem, Differences, Penalty, Point, apply, bounds_for, values_of};
use crate::error::FitError;
use crate::fit::{fit_step_weighted, rms};
use crate::identify::{self, Held, Levels};
use crate::physics::MarginSet;
use crate::stages::context::{Ctx, StagePoints, peak_abs};
use crate::stages::{Stage, StageReport};

/// Pure-MZ keys the combined sweeps inform, in priority order: the trail's size, load terms,
/// stiffness, shape and offset; the residual torque and its decay (Br = QBZ10·By·Cy); the
/// camber terms of both (the drive/brake run usually holds the cambers). Pressure terms stay
/// with `mz_pure` (a drive/brake run is at one pressure).
pub const JOINT: [&str; 12] =
    ["QDZ1", "QDZ2", "QBZ1", "QCZ1", "QEZ1", "QHZ1", "QDZ6", "QDZ7", "QBZ10", "QDZ3", "QDZ8", "QHZ3"];
/// The arm's keys (`mz_combined`'s own).
const ARM: [&str; 4] = crate::stages::mz_combined::KEYS;
/// Largest MZ pure NRMSE after the refinement, as a multiple of before it: the pure points are
/// `mz_pure`'s least-squares optimum, so a small move costs them little; more than this and
/// the two runs disagree (temperature, wear), which the pure fit should not pay for.
pub const PURE_TOLERANCE: f64 = 1.03;
/// Smallest relative gain in MZ combined RMSE worth moving `mz_pure`'s coefficients for.
const MIN_GAIN: f64 = 0.02;
/// Weights of the pure set against the combined set (1: both NRMSEs count alike), tried in
/// turn until MZ pure stays within [`PURE_TOLERANCE`]: where the two runs agree the first
/// gains most; where they disagree (the drive/brake run hotter or more worn) the pure points
/// must pull harder. Measured on the brush race tyre's TTC-style runs: weight 1 took MZ
/// combined 6.17 → 4.99 % but MZ pure 3.12 → 3.47 %; weight 10 gave 5.38 % and 3.15 %.
const PURE_WEIGHTS: [f64; 6] = [1.0, 2.0, 3.0, 5.0, 10.0, 30.0];
/// Points `mz_pure` needs (its own minimum): below it there are no pure points to protect and
/// `mz_combined` fits the pure trail itself.
const MZ_PURE_MIN_POINTS: usize = 50;

/// The joint problem: combined points then pure points, one weight each.
struct Joint {
    points: Vec<Point>,
    groups: Vec<usize>,
    weights: Vec<f64>,
    /// Residual scale: 1 % of the combined set's peak.
    scale: f64,
}

impl Joint {
    fn of(combined: &StagePoints, pure: &StagePoints, pure_weight: f64) -> Self {
        let (pc, pp) = (peak_abs(&combined.points), peak_abs(&pure.points));
        let (nc, np) = (combined.len() as f64, pure.len() as f64);
        // Each residual in % of its own set's peak; the pure set scaled to count as much in
        // total as the combined one (times `pure_weight`).
        let w_pure = (pure_weight * nc / np).sqrt() * pc / pp;
        let mut points = combined.points.clone();
        points.extend_from_slice(&pure.points);
        let mut groups = combined.groups.clone();
        groups.extend_from_slice(&pure.groups);
        let weights = std::iter::repeat_n(1.0, combined.len()).chain(std::iter::repeat_n(w_pure, pure.len())).collect();
        Joint { points, groups, weights, scale: pc / 100.0 }
    }

    /// The weighted Jacobian (central differences) at `params`.
    fn jacobian(&self, params: &TyreParams, keys: &[&'static str], threads: usize) -> DMatrix<f64> {
        let mut problem =
            ChannelProblem::new(params, keys, &self.points, Channel::Mz, self.scale).with_weights(&self.weights);
        problem.threads = threads.max(1);
        problem.differences = Differences::Central;
        let p: Vec<f64> = values_of(params, keys)
            .iter()
            .zip(keys)
            .map(|(v, k)| {
                let (lo, hi) = bounds_for(k);
                v.clamp(lo, hi)
            })
            .collect();
        let mut j = DMatrix::zeros(self.points.len(), keys.len());
        lsq::Problem::jacobian(&problem, &DVector::from_vec(p), &mut j);
        j
    }
}

/// NRMSE (%) of `channel` over `points` for `params`.
fn nrmse_pct(params: &TyreParams, points: &[Point], channel: Channel) -> f64 {
    100.0 * rms(params, points, channel) / peak_abs(points)
}

/// One weighted joint fit: its parameters, freed keys, held keys and NRMSEs.
struct Attempt {
    params: TyreParams,
    free: Vec<&'static str>,
    held: Vec<Held>,
    combined_pct: f64,
    pure_pct: f64,
    physical: bool,
    iterations: usize,
}

/// Fits `free` (and holds what the weighted Jacobian at the solution cannot tell apart, then
/// refits) on `joint` from `start`.
fn attempt(
    ctx: &Ctx,
    stage: &str,
    start: &TyreParams,
    mut free: Vec<&'static str>,
    joint: &Joint,
    sets: (&StagePoints, &StagePoints),
) -> Result<Attempt, FitError> {
    let mut trial = start.clone();
    let mut held = Vec::new();
    let mut iterations = 0;
    let penalty = Penalty { set: MarginSet::MzPure, grid: &ctx.grid, weight: Penalty::weight_for(joint.points.len()) };
    for _round in 0..3 {
        let o = fit_step_weighted(
            stage,
            &mut trial,
            &free,
            &joint.points,
            Some(&joint.weights),
            Channel::Mz,
            joint.scale,
            &ctx.settings,
            Some(penalty),
        )?;
        iterations += o.iterations;
        let verdict = identify::judge_jacobian(&trial, &free, &joint.jacobian(&trial, &free, ctx.settings.threads));
        if verdict.held.is_empty() {
            break;
        }
        for mut h in verdict.held {
            let v = start.get(&h.key).unwrap_or(h.value);
            apply(&mut trial, &[h.key.as_str()], &[v]);
            h.value = v;
            h.reason = format!("kept at its earlier value: {} {}", h.reason, crate::stages::steps::JACOBIAN_HELD);
            free.retain(|k| *k != h.key);
            held.push(h);
        }
    }
    Ok(Attempt {
        combined_pct: nrmse_pct(&trial, &sets.0.points, Channel::Mz),
        pure_pct: nrmse_pct(&trial, &sets.1.points, Channel::Mz0),
        physical: crate::physics::worst(&trial, MarginSet::MzPure, &ctx.grid).is_none(),
        params: trial,
        free,
        held,
        iterations,
    })
}

/// Refines the trail and residual-torque keys of [`JOINT`] with the arm on `combined` and
/// `mz_pure`'s points; `params` and `rep` (already holding the SSZ-only fit) change only when
/// the refinement is kept.
pub fn refine(
    ctx: &Ctx,
    params: &mut TyreParams,
    rep: &mut StageReport,
    combined: &StagePoints,
) -> Result<(), FitError> {
    if ctx.opts.skip_stages.iter().any(|s| s == "mz_pure") {
        return Ok(());
    }
    let pure = crate::stages::mz_pure::MzPure.select(ctx).unwrap_or_default();
    if pure.len() < MZ_PURE_MIN_POINTS || combined.is_empty() {
        return Ok(());
    }
    let before_c = nrmse_pct(params, &combined.points, Channel::Mz);
    let before_p = nrmse_pct(params, &pure.points, Channel::Mz0);
    if !(before_c.is_finite() && before_p.is_finite()) {
        return Ok(());
    }
    let mut joint = Joint::of(combined, &pure, PURE_WEIGHTS[0]);
    let levels = Levels::of(&joint.points, ctx.nominal.fz0_n);
    let structural = identify::structural(params, &JOINT, &levels);
    let arm = ARM.iter().copied().filter(|k| rep.free.contains(k));
    let free: Vec<&'static str> = structural.free.iter().copied().chain(arm).collect();
    let structurally_held = structural.held.into_iter().map(|mut h| {
        h.reason = format!("kept at mz_pure's value: {}", h.reason);
        h
    });
    let mut tried = Vec::new();
    let mut kept = None;
    for (i, &w) in PURE_WEIGHTS.iter().enumerate() {
        if i > 0 {
            joint = Joint::of(combined, &pure, w);
        }
        let a = attempt(ctx, &rep.stage, params, free.clone(), &joint, (combined, &pure))?;
        rep.iterations += a.iterations;
        tried.push(format!(
            "pure weight {w}: MZ combined {:.2} %, MZ pure {:.2} %{}",
            a.combined_pct,
            a.pure_pct,
            if a.physical { "" } else { " (non-physical)" }
        ));
        if !(a.physical && a.pure_pct <= PURE_TOLERANCE * before_p) {
            continue;
        }
        if a.combined_pct < (1.0 - MIN_GAIN) * before_c {
            kept = Some((w, a));
        }
        // The pure fit is protected from here on: more weight only gives less to the combined.
        break;
    }
    let Some((w, a)) = kept else {
        rep.notes.push(format!(
            "trail and residual torque refined with mz_pure's points: not kept (before: MZ combined {before_c:.2} %, \
             MZ pure {before_p:.2} %; {}): the arm alone stands",
            tried.join("; ")
        ));
        return Ok(());
    };
    *params = a.params;
    let moved: Vec<&'static str> = a.free.iter().copied().filter(|k| !ARM.contains(k)).collect();
    rep.notes.push(format!(
        "trail and residual torque ({}) refined with the arm on the combined sweeps and mz_pure's {} points \
         (each in % of its own peak, the pure set weighted {w}×): MZ combined {before_c:.2} → {:.2} %, MZ pure \
         {before_p:.2} → {:.2} % (kept: pure within {PURE_TOLERANCE}× of its fit; tried {})",
        moved.join(", "),
        pure.len(),
        a.combined_pct,
        a.pure_pct,
        tried.join("; ")
    ));
    for k in &a.free {
        if !rep.keys.iter().any(|x| x == k) {
            rep.keys.push((*k).to_owned());
        }
        if !rep.free.contains(k) {
            rep.free.push(k);
        }
    }
    for h in structurally_held.chain(a.held) {
        rep.held.retain(|x| x.key != h.key);
        rep.held.push(h);
    }
    rep.rmse = rms(params, &combined.points, Channel::Mz);
    // Uncertainties over both sets (unweighted residual variance, serial correlation per sweep).
    let free = a.free;
    let (est, inflation, covariance) =
        identify::uncertainty_from(params, &free, &joint.points, &joint.groups, Channel::Mz, || {
            identify::jacobian(params, &free, &joint.points, Channel::Mz, ctx.settings.threads)
        });
    rep.estimates = est;
    rep.serial_inflation = inflation;
    rep.covariance = covariance;
    rep.primary_keys = free;
    rep.anchor_weight = Some(w);
    Ok(())
}

/// Cross-validation's refit of a fold (`crossval::kfold`): the stage's `keys` refitted as the
/// stage fitted them, on the fold's training sweeps `train` together with `mz_pure`'s points at
/// the pure weight the stage chose. Refitting them on the combined sweeps alone would judge
/// another procedure (the pure trail keys free of the pure data they were anchored to).
pub fn refit_fold(
    ctx: &Ctx,
    params: &mut TyreParams,
    keys: &[&'static str],
    train: &StagePoints,
    pure_weight: f64,
    settings: &crate::fit::StepSettings,
) -> Result<(), FitError> {
    let pure = crate::stages::mz_pure::MzPure.select(ctx).unwrap_or_default();
    let joint = Joint::of(train, &pure, pure_weight);
    let penalty = Penalty { set: MarginSet::MzPure, grid: &ctx.grid, weight: Penalty::weight_for(joint.points.len()) };
    fit_step_weighted(
        "mz_combined",
        params,
        keys,
        &joint.points,
        Some(&joint.weights),
        Channel::Mz,
        joint.scale,
        settings,
        Some(penalty),
    )?;
    Ok(())
}

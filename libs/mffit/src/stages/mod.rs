//! The staged fit in the thesis's order (§5, reference §12). Each stage is one module behind the
//! small [`Stage`] interface: it selects its data from the [`Dataset`], estimates starting values
//! from it, decides which of its coefficients the data identify ([`crate::identify`]), fits
//! those in steps (nominal conditions first, then camber, then pressure, then all together, so
//! the optimiser never has to find 30 coefficients from nowhere) with its physical margins as
//! penalties ([`crate::physics`]), and hands the parameter set to the next stage. Afterwards
//! every point-based stage is cross-validated over sweeps ([`crossval`]).
//!
//! Adding or changing a stage happens in its module and in [`STAGES`].

use std::time::Instant;

use mftyre::TyreParams;
use serde::Serialize;

use crate::checks;
use crate::data::{Dataset, ValidRange};
use crate::engine::{Channel, Point, values_of};
use crate::error::FitError;
use crate::fit::StepSettings;
use crate::identify::{Estimate, Held, Levels};
use crate::physics::{Grid, MarginSet};

pub mod context;
pub mod crossval;
mod fx_combined;
mod fx_pure;
mod fy_combined;
mod fy_pure;
mod mx;
mod mz_combined;
mod mz_joint;
mod mz_pure;
pub mod nominal;
mod radius;
mod relaxation;
pub mod states;
pub mod steps;

pub use context::{Ctx, Resampled, StagePoints};
pub use crossval::{HeldOut, ValidationRow, validate};
pub use nominal::{Nominal, nominal_values};
pub use relaxation::{static_stiffness, step_steer_length};

/// The neutral MF-Tyre 6.1 template every fit starts from (generic inertia, contact patch,
/// structural frequencies; secondary coefficients zero, i.e. "no such effect").
pub const TEMPLATE_TIR: &str = include_str!("../template.tir");

/// Options of a staged fit.
#[derive(Debug, Clone)]
pub struct FitOptions {
    /// Resampling period for free-rolling data, s (the thesis fits at 10 Hz).
    pub resample_period_s: f64,
    /// Resampling period for BrkDrv data, s. Finer than 10 Hz: a slip-ratio sweep crosses 6 %
    /// slip per 0.1 s at its high rate, and averaging across the peak would flatten it.
    pub brkdrv_period_s: f64,
    /// Also fit the graph sweeps (drift/wear checks; off by default, as in the thesis).
    pub include_graph_sweeps: bool,
    /// Robust (soft-L1) loss threshold in % of the channel's peak; `None` = least squares.
    pub robust_pct: Option<f64>,
    /// Largest number of points a stage fits (evenly decimated beyond it).
    pub max_points: usize,
    /// Nominal load if known (else from the data's metadata, else estimated), N.
    pub fnomin_n: Option<f64>,
    /// Template for the coefficients no stage fits; default [`TEMPLATE_TIR`].
    pub template: Option<TyreParams>,
    /// Worker threads.
    pub threads: usize,
    /// Iteration limit per optimiser step.
    pub max_iterations: usize,
    /// Folds of the k-fold cross-validation over sweeps (0 or 1: none).
    pub folds: usize,
    /// Stages not to run (their coefficients keep template values), by name.
    pub skip_stages: Vec<String>,
    /// Try other starting values when a stage ends above its noise floor (as a fresh fit does);
    /// a live update after a sweep turns it off and continues from the previous solution.
    pub restarts: bool,
    /// How the optimiser's Jacobians are differenced: forward by default (the Jacobians that
    /// decide which keys are identified, and the covariances, are always central).
    pub differences: crate::engine::Differences,
    /// A previous solution to start from (the live fit's update after a new sweep): stages it
    /// fitted start from its coefficients and run only their final, all-keys step.
    pub warm_start: Option<WarmStart>,
}

/// How the note of a stage a warm-started fit refitted from the data's start ends.
pub const COLD_START_NOTE: &str = "fitted from the data's start, not warm";

/// How the note of a stage ends that stayed above [`WARM_WORSENING`] × its last fresh NRMSE even
/// after its own refit from the data's start: the stages before it moved, and a live update
/// then fits the whole model fresh as well ([`FitResult::wants_fresh_fit`]).
pub const UPSTREAM_NOTE: &str = "still worse after its own fresh refit: the stages before it moved";

/// A warm-started stage ending above this multiple of its previous NRMSE (plus
/// [`WARM_WORSENING_PCT`]) is fitted afresh: a new sweep moves a converged NRMSE by a few
/// percent of itself, a warm start stuck in a poor region by several times.
const WARM_WORSENING: f64 = 1.5;
/// The NRMSE (percentage points) a warm-started stage may gain besides [`WARM_WORSENING`].
const WARM_WORSENING_PCT: f64 = 0.25;

/// A previous solution a fit starts from ([`FitOptions::warm_start`]).
///
/// A stage starts warm when the previous fit fitted it and its data still hold the same
/// operating levels (loads, pressures, cambers, speeds): a new level frees coefficients the
/// previous solution never had, and the stage is then fitted from the data in its steps, as in
/// a fresh fit (a warm start would put them in at "no such effect" and could stay in a local
/// minimum of the others).
#[derive(Debug, Clone)]
pub struct WarmStart {
    /// The previous fit's parameters.
    pub params: TyreParams,
    /// The stages that previous fit fitted, with the number of load, pressure, camber, speed
    /// and swept-camber levels in their points.
    pub stages: Vec<(String, [usize; 5])>,
    /// Per stage, the previous report, the signature of its points and the values it set:
    /// a stage whose points are unchanged, after stages that were all unchanged too, is taken
    /// over as it was instead of being refitted.
    reuse: Vec<Reusable>,
    /// The previous fit's nominal values (LONGVL, NOMPRES, FNOMIN, UNLOADED_RADIUS): reuse needs
    /// them unchanged.
    nominal: [f64; 4],
    /// Per stage, the keys the previous solution's Jacobian could not identify.
    jacobian_held: Vec<(String, Vec<Held>)>,
    /// Per stage, the NRMSE (%) of its latest fit from the data's start.
    fresh_nrmse_pct: Vec<(String, f64)>,
    /// The previous fit's resampled segments (the next fit's data begin with the same ones).
    resampled: Resampled,
}

impl WarmStart {
    /// The warm start a finished fit gives the next one.
    pub fn of(result: &FitResult) -> Self {
        let stages = result
            .stages
            .iter()
            .filter(|r| result.fitted(&r.stage))
            .filter_map(|r| Some((r.stage.clone(), level_counts(r.levels.as_ref()?))))
            .collect();
        let reuse = result
            .stages
            .iter()
            .filter_map(|r| {
                let d = result.data.iter().find(|d| d.stage == r.stage)?;
                let keys = r.keys.iter().cloned().chain(r.held.iter().map(|h| h.key.clone()));
                let values = keys.filter_map(|k| result.params.get(&k).map(|v| (k, v))).collect();
                let model = model_signature(d.channel, &result.params, &d.points);
                Some((r.clone(), signature(&d.points), values, model))
            })
            .collect();
        let jacobian_held = result
            .stages
            .iter()
            .map(|r| {
                let held = r.held.iter().filter(|h| h.reason.ends_with(steps::JACOBIAN_HELD)).cloned().collect();
                (r.stage.clone(), held)
            })
            .collect();
        let fresh_nrmse_pct = result
            .stages
            .iter()
            .filter(|r| r.started_fresh && result.fitted(&r.stage))
            .map(|r| (r.stage.clone(), r.nrmse_pct()))
            .collect();
        let n = &result.nominal;
        WarmStart {
            params: result.params.clone(),
            stages,
            reuse,
            nominal: [n.v0_mps, n.p0_pa, n.fz0_n, n.r0_m],
            jacobian_held,
            fresh_nrmse_pct,
            resampled: result.resampled.clone(),
        }
    }

    /// The keys the previous solution's Jacobian held in `stage`.
    fn jacobian_held(&self, stage: &str) -> &[Held] {
        self.jacobian_held.iter().find(|(s, _)| s == stage).map_or(&[], |(_, h)| h.as_slice())
    }

    /// The previous report and values of `stage` when its points had `sig`.
    fn reusable(&self, stage: &str, sig: u64) -> Option<&Reusable> {
        self.reuse.iter().find(|(r, s, _, _)| r.stage == stage && *s == sig)
    }

    /// This warm start, remembering the most levels of each stage that `older` (the warm start
    /// of the update before) had seen: a level count that flickers as data accumulate (a level
    /// near the point threshold of [`Levels`], decimation choosing other points) then frees
    /// nothing new and does not send the stage back to a fresh fit at every update.
    pub fn remembering(mut self, older: Option<&WarmStart>) -> Self {
        for (stage, v) in older.map_or(&[][..], |o| o.fresh_nrmse_pct.as_slice()) {
            if !self.fresh_nrmse_pct.iter().any(|(s, _)| s == stage) {
                self.fresh_nrmse_pct.push((stage.clone(), *v));
            }
        }
        for (stage, seen) in older.map_or(&[][..], |o| o.stages.as_slice()) {
            if let Some((_, now)) = self.stages.iter_mut().find(|(s, _)| s == stage) {
                for (n, o) in now.iter_mut().zip(seen) {
                    *n = (*n).max(*o);
                }
            }
        }
        self
    }

    /// True when `stage` may start warm on points with `levels`: the previous solutions fitted
    /// it and had seen at least as many levels of each kind, counted up to the most any
    /// coefficient needs (a load that varies within sweeps counts more levels as points
    /// accumulate, and a fourth or a sixteenth level frees nothing).
    fn admits(&self, stage: &str, levels: &Levels) -> bool {
        let now = level_counts(levels).map(|n| n.min(crate::identify::MOST_LEVELS_NEEDED));
        self.stages.iter().any(|(s, seen)| s == stage && now.iter().zip(seen).all(|(n, m)| n <= m))
    }

    /// The NRMSE (%) a warm start of `stage` is held to: what its latest fit from the data's
    /// start reached (warm updates that each lose a little add up to a stuck solution that no
    /// single update shows), else the previous solution's.
    fn reference_nrmse_pct(&self, stage: &str) -> Option<f64> {
        self.fresh_nrmse_pct
            .iter()
            .find(|(s, _)| s == stage)
            .map(|(_, v)| *v)
            .or_else(|| self.reuse.iter().find(|(r, _, _, _)| r.stage == stage).map(|(r, _, _, _)| r.nrmse_pct()))
            .filter(|v| v.is_finite())
    }

    /// The most levels (loads, pressures, cambers, speeds, swept cambers) the previous solutions
    /// of `stage` saw.
    fn levels_seen(&self, stage: &str) -> Option<[usize; 5]> {
        self.stages.iter().find(|(s, _)| s == stage).map(|(_, n)| *n)
    }
}

/// A stage's previous report, the signature of its points, the values it set, and the
/// signature of the model's values at its points.
type Reusable = (StageReport, u64, Vec<(String, f64)>, u64);

/// Stages that fit one model channel on the points they select and nothing else (the radius
/// stage fits Re on other points too, the relaxation stage Cx): for them, unchanged points and
/// unchanged model values there mean an unchanged problem.
/// Not `mz_combined`: it may refine `mz_pure`'s trail keys ([`mz_joint`]), and restoring its
/// old values after a refitted `mz_pure` would undo that stage.
const ONE_CHANNEL_STAGES: [&str; 6] = ["fy_pure", "mz_pure", "fx_pure", "fx_combined", "fy_combined", "mx"];

/// A fingerprint of `channel`'s model values at `points` (bit for bit): a stage whose points
/// and model values are unchanged after an upstream stage was refitted depends on nothing that
/// refit moved (Mx on free-rolling data does not see the Fx stages), so its previous solution
/// stands.
fn model_signature(channel: Channel, params: &TyreParams, points: &[Point]) -> u64 {
    use std::hash::{Hash, Hasher};
    let values = channel.values_at(params, points);
    let mut h = std::collections::hash_map::DefaultHasher::new();
    values.len().hash(&mut h);
    for v in values {
        v.to_bits().hash(&mut h);
    }
    h.finish()
}

/// A fingerprint of a stage's points (every input and measured value, bit for bit).
fn signature(points: &[crate::engine::Point]) -> u64 {
    use std::hash::{Hash, Hasher};
    let mut h = std::collections::hash_map::DefaultHasher::new();
    points.len().hash(&mut h);
    for p in points {
        let x = &p.input;
        for v in [x.fz_n, x.kappa, x.alpha_rad, x.gamma_rad, x.vx_mps, x.p_pa, x.omega_radps, p.measured] {
            v.to_bits().hash(&mut h);
        }
    }
    h.finish()
}

fn level_counts(l: &Levels) -> [usize; 5] {
    [l.loads_n.len(), l.pressures_pa.len(), l.cambers_rad.len(), l.speeds_mps.len(), l.swept_cambers_rad.len()]
}

impl Default for FitOptions {
    fn default() -> Self {
        Self {
            resample_period_s: 0.1,
            brkdrv_period_s: 0.02,
            include_graph_sweeps: false,
            robust_pct: None,
            max_points: 3000,
            fnomin_n: None,
            template: None,
            threads: std::thread::available_parallelism().map(|n| n.get()).unwrap_or(1),
            max_iterations: 60,
            folds: 5,
            skip_stages: Vec::new(),
            restarts: true,
            differences: crate::engine::Differences::Forward,
            warm_start: None,
        }
    }
}

/// What one stage did.
#[derive(Debug, Clone, Serialize)]
pub struct StageReport {
    /// Stage name (`fy_pure`, …).
    pub stage: String,
    /// Channel fitted.
    pub channel: String,
    /// Keys fitted.
    pub keys: Vec<String>,
    /// Points used.
    pub points: usize,
    /// RMS residual before the stage (starting values), channel units.
    pub initial_rmse: f64,
    /// RMS residual after.
    pub rmse: f64,
    /// Largest |measured| of the stage's points (NRMSE = RMSE / peak).
    pub peak: f64,
    /// Optimiser iterations over all steps.
    pub iterations: usize,
    /// Termination of the last step.
    pub termination: String,
    /// Wall time, s.
    pub wall_s: f64,
    /// Findings: skipped steps, restarts, fallbacks.
    pub notes: Vec<String>,
    /// True when the stage was fitted from the data's start (not warm-started).
    #[serde(skip)]
    pub started_fresh: bool,
    /// Why the stage was skipped, if it was.
    pub skipped: Option<String>,
    /// Candidate keys the data identify (fitted by some step).
    #[serde(skip)]
    pub free: Vec<&'static str>,
    /// Keys fitted on the stage's main channel (cross-validated, with uncertainties).
    #[serde(skip)]
    pub primary_keys: Vec<&'static str>,
    /// Candidate keys the data do not identify, with the value they keep and why.
    pub held: Vec<Held>,
    /// Fitted coefficients with their standard deviations.
    pub estimates: Vec<Estimate>,
    /// Variance inflation applied for serially correlated residuals.
    pub serial_inflation: f64,
    /// The operating levels the stage's data hold.
    pub levels: Option<Levels>,
    /// k-fold held-out accuracy over sweeps.
    pub heldout: Option<HeldOut>,
    /// Physical margins of this stage still failing on the final model.
    pub nonphysical: Vec<String>,
    /// Covariance of the fitted `primary_keys` (row-major, n×n, serial inflation included):
    /// what the prediction uncertainty of the stage's channel comes from (delta method).
    #[serde(skip)]
    pub covariance: Vec<f64>,
    /// The weight of an earlier stage's points when this stage's keys were fitted together
    /// with them (`mz_combined` refining `mz_pure`'s trail, [`mz_joint`]); cross-validation
    /// refits the same way.
    #[serde(skip)]
    pub anchor_weight: Option<f64>,
}

impl StageReport {
    /// An empty report for `stage` on `channel`.
    pub fn new(stage: &str, channel: &str) -> Self {
        StageReport {
            stage: stage.into(),
            channel: channel.into(),
            keys: Vec::new(),
            points: 0,
            initial_rmse: f64::NAN,
            rmse: f64::NAN,
            peak: f64::NAN,
            iterations: 0,
            termination: String::new(),
            wall_s: 0.0,
            notes: Vec::new(),
            started_fresh: false,
            skipped: None,
            free: Vec::new(),
            primary_keys: Vec::new(),
            held: Vec::new(),
            estimates: Vec::new(),
            serial_inflation: 1.0,
            levels: None,
            heldout: None,
            nonphysical: Vec::new(),
            covariance: Vec::new(),
            anchor_weight: None,
        }
    }

    /// Takes the fit's outcome (RMSE, keys, iterations, termination) from a trial report, keeping
    /// this report's notes and held keys.
    pub fn adopt_fit(&mut self, trial: &StageReport) {
        self.keys = trial.keys.clone();
        self.points = trial.points;
        self.initial_rmse = trial.initial_rmse;
        self.rmse = trial.rmse;
        self.iterations += trial.iterations;
        self.termination = trial.termination.clone();
    }

    /// RMSE in % of the stage's peak.
    pub fn nrmse_pct(&self) -> f64 {
        100.0 * self.rmse / self.peak
    }
}

/// The data a stage fitted, kept for the report's metrics, plots and cross-validation.
#[derive(Debug, Clone)]
pub struct StageData {
    /// Stage name.
    pub stage: String,
    /// Channel.
    pub channel: Channel,
    /// Points.
    pub points: Vec<Point>,
    /// Segment of each point.
    pub groups: Vec<usize>,
    /// Test time and tread temperature of each point (for the report's residual plots).
    pub states: Vec<states::PointState>,
}

/// The outcome of [`fit`].
#[derive(Debug, Clone)]
pub struct FitResult {
    /// The fitted parameter set (FITTYP 61), limits set to the tested range.
    pub params: TyreParams,
    /// Nominal values.
    pub nominal: Nominal,
    /// Per-stage reports, in order.
    pub stages: Vec<StageReport>,
    /// Per-stage data.
    pub data: Vec<StageData>,
    /// The tested range.
    pub range: ValidRange,
    /// Failure-mode findings on the final model (physical margins name their stage).
    pub warnings: Vec<String>,
    /// Total wall time, s.
    pub wall_s: f64,
    /// Accuracy on other runs ([`validate`]), per source; filled by the caller.
    pub validation: Vec<(String, Vec<ValidationRow>)>,
    /// The data's segments as resampled for this fit (a warm start's next fit reuses them).
    resampled: Resampled,
}

impl FitResult {
    /// Stages whose physical margins still fail on the final model.
    pub fn nonphysical_stages(&self) -> Vec<&str> {
        self.stages.iter().filter(|s| !s.nonphysical.is_empty()).map(|s| s.stage.as_str()).collect()
    }

    /// The first stage a warm start left worse than its last fresh fit even after refitting it
    /// from the data's start ([`UPSTREAM_NOTE`]): the warm stages before it sit in another
    /// minimum, and only a fresh fit of the whole model tells.
    pub fn wants_fresh_fit(&self) -> Option<&str> {
        self.stages.iter().find(|s| s.notes.iter().any(|n| n.ends_with(UPSTREAM_NOTE))).map(|s| s.stage.as_str())
    }

    /// True when `stage` ran and fitted at least one key.
    pub fn fitted(&self, stage: &str) -> bool {
        self.stages.iter().any(|s| s.stage == stage && s.skipped.is_none() && !s.keys.is_empty())
    }
}

/// One stage of the staged fit.
pub trait Stage: Sync {
    /// Name in reports (`fy_pure`).
    fn name(&self) -> &'static str;
    /// The channel it fits.
    fn channel(&self) -> Channel;
    /// The physical margins it owns (penalties while fitting, checks afterwards).
    fn margins(&self) -> Option<MarginSet> {
        None
    }
    /// Its points: `None` for stages that are not a least-squares fit of one channel over
    /// sweeps (relaxation lengths), which are then not cross-validated.
    fn select(&self, ctx: &Ctx) -> Option<StagePoints>;
    /// Fits the stage on `data` (its selection), starting from `params`; fills `rep`. Returns
    /// `Err(FitError::NotEnoughData)` to be skipped with the reason.
    fn fit(
        &self,
        ctx: &Ctx,
        params: &mut TyreParams,
        data: &StagePoints,
        rep: &mut StageReport,
    ) -> Result<(), FitError>;
}

/// The parsed [`TEMPLATE_TIR`] (parsed once: a live fit starts from it every update).
fn template() -> Result<TyreParams, FitError> {
    static PARSED: std::sync::OnceLock<Option<TyreParams>> = std::sync::OnceLock::new();
    match PARSED.get_or_init(|| TyreParams::from_tir_str(TEMPLATE_TIR, "mffit template").ok()) {
        Some(t) => Ok(t.clone()),
        // Parsed again for the error itself.
        None => Ok(TyreParams::from_tir_str(TEMPLATE_TIR, "mffit template")?),
    }
}

/// The stages, in the thesis's order.
pub static STAGES: [&dyn Stage; 9] = [
    &fy_pure::FyPure,
    &mz_pure::MzPure,
    &fx_pure::FxPure,
    &fx_combined::FxCombined,
    &fy_combined::FyCombined,
    &mz_combined::MzCombined,
    &mx::Mx,
    &radius::Radius,
    &relaxation::Relaxation,
];

/// Fits every stage in order, then cross-validates them. Stages without (enough) data are
/// skipped and say so; so are stages named in `opts.skip_stages`.
pub fn fit(data: &Dataset, opts: &FitOptions) -> Result<FitResult, FitError> {
    let t_start = Instant::now();
    let nominal = nominal_values(data, opts)?;
    let mut params = match &opts.template {
        Some(t) => t.clone(),
        None => template()?,
    };
    params.fittyp = 61;
    params.source = "tyrerig fit".into();
    params.set("LONGVL", nominal.v0_mps)?;
    params.set("NOMPRES", nominal.p0_pa)?;
    params.set("INFLPRES", nominal.p0_pa)?;
    params.set("FNOMIN", nominal.fz0_n)?;
    params.set("UNLOADED_RADIUS", nominal.r0_m)?;
    let resampled = match &opts.warm_start {
        Some(w) => Resampled::continuing(&w.resampled, data),
        None => Resampled::of(data),
    };
    let range = resampled.valid_range(data);
    let settings = StepSettings {
        robust: opts.robust_pct,
        max_iterations: opts.max_iterations,
        threads: opts.threads.max(1),
        differences: opts.differences,
    };
    let grid = Grid::of_range(&params, &range);
    let ctx = Ctx { data, opts, nominal: nominal.clone(), settings, grid, resampled };
    let mut stages = Vec::new();
    let mut stage_data = Vec::new();
    let mut nom = StageReport::new("nominal", "-");
    nom.keys = ["LONGVL", "NOMPRES", "FNOMIN", "UNLOADED_RADIUS"].map(String::from).to_vec();
    nom.points = data.len();
    nom.termination = "direct".into();
    nom.notes = nominal.notes.clone();
    nom.wall_s = t_start.elapsed().as_secs_f64();
    stages.push(nom);

    // Stages are reused only while every stage before them was (their inputs are unchanged).
    let mut unchanged_so_far = opts
        .warm_start
        .as_ref()
        .is_some_and(|w| w.nominal == [nominal.v0_mps, nominal.p0_pa, nominal.fz0_n, nominal.r0_m]);
    // The model as each stage left it: a later stage may move an earlier one's prediction.
    let mut after_stage: Vec<(&'static str, TyreParams)> = Vec::new();
    for stage in STAGES {
        let t = Instant::now();
        let mut rep = StageReport::new(stage.name(), stage.channel().name());
        if opts.skip_stages.iter().any(|s| s == stage.name()) {
            rep.skipped = Some("skipped on request (--skip-stage): its coefficients keep the template's values".into());
            stages.push(rep);
            continue;
        }
        let selection = stage.select(&ctx).unwrap_or_default();
        rep.peak = context::peak_abs(&selection.points);
        // Unchanged points after unchanged stages, or unchanged points and unchanged model
        // values there after a refit upstream: the previous result stands.
        let sig = signature(&selection.points);
        let reusable =
            opts.warm_start.as_ref().and_then(|w| w.reusable(stage.name(), sig)).filter(|(_, _, values, model)| {
                unchanged_so_far
                    || ONE_CHANNEL_STAGES.contains(&stage.name()) && {
                        let mut trial = params.clone();
                        for (k, v) in values {
                            let _ = trial.set(k, *v);
                        }
                        model_signature(stage.channel(), &trial, &selection.points) == *model
                    }
            });
        if let Some((prev, _, values, _)) = reusable {
            for (k, v) in values {
                let _ = params.set(k, *v);
            }
            let mut rep = prev.clone();
            rep.wall_s = t.elapsed().as_secs_f64();
            rep.iterations = 0;
            stages.push(rep);
            after_stage.push((stage.name(), params.clone()));
            stage_data.push(StageData {
                stage: stage.name().into(),
                channel: stage.channel(),
                states: states::of(&ctx, &selection),
                points: selection.points,
                groups: selection.groups,
            });
            continue;
        }
        unchanged_so_far = false;
        // Warm only where the previous solutions saw as many levels (else fitted as in a fresh fit).
        let levels = Levels::of(&selection.points, ctx.nominal.fz0_n);
        let warm = opts.warm_start.as_ref().is_some_and(|w| w.admits(stage.name(), &levels));
        let cold_opts = opts.warm_start.as_ref().map(|_| FitOptions { warm_start: None, ..opts.clone() });
        let cold_ctx = cold_opts.as_ref().map(|o| Ctx {
            data,
            opts: o,
            nominal: nominal.clone(),
            settings,
            grid: ctx.grid.clone(),
            resampled: ctx.resampled.clone(),
        });
        let stage_ctx = match (&cold_ctx, warm) {
            (Some(cold), false) => {
                let seen = opts.warm_start.as_ref().and_then(|w| w.levels_seen(stage.name()));
                rep.notes.push(format!(
                    "new operating levels in the data (loads, pressures, cambers, speeds: {:?}, before at most {}): \
                     {COLD_START_NOTE}",
                    level_counts(&levels),
                    seen.map_or("none fitted".into(), |n| format!("{n:?}"))
                ));
                cold
            }
            _ => &ctx,
        };
        let before = params.clone();
        let mut outcome = stage.fit(stage_ctx, &mut params, &selection, &mut rep);
        // A warm start that ends far above where the previous solution was (upstream stages
        // moved, or the new sweep sits where the old solution extrapolates badly and the
        // update's few iterations cannot get out): fitted afresh, as a fresh fit would.
        let previous = opts.warm_start.as_ref().and_then(|w| w.reference_nrmse_pct(stage.name()));
        if let (true, Ok(()), Some(cold), Some(prev)) = (warm, &outcome, &cold_ctx, previous)
            && rep.nrmse_pct() > WARM_WORSENING * prev + WARM_WORSENING_PCT
        {
            let note = format!(
                "the warm start ended at {:.2} % NRMSE, the last fit from the data's start at {prev:.2} %: {COLD_START_NOTE}",
                rep.nrmse_pct()
            );
            params = before;
            rep = StageReport::new(stage.name(), stage.channel().name());
            rep.peak = context::peak_abs(&selection.points);
            rep.notes.push(note);
            outcome = stage.fit(cold, &mut params, &selection, &mut rep);
            if outcome.is_ok() && rep.nrmse_pct() > WARM_WORSENING * prev + WARM_WORSENING_PCT {
                rep.notes.push(format!("{:.2} % NRMSE {UPSTREAM_NOTE}", rep.nrmse_pct()));
            }
        }
        rep.started_fresh = !warm || rep.notes.iter().any(|n| n.ends_with(COLD_START_NOTE));
        match outcome {
            Ok(()) => {
                if !selection.is_empty() {
                    stage_data.push(StageData {
                        stage: stage.name().into(),
                        channel: stage.channel(),
                        states: states::of(&ctx, &selection),
                        points: selection.points.clone(),
                        groups: selection.groups.clone(),
                    });
                }
            }
            Err(FitError::NotEnoughData { points, needed, .. }) => {
                rep.skipped = Some(format!(
                    "not enough data ({points} points for {needed}): its coefficients keep the template's values"
                ));
            }
            Err(e) => return Err(e),
        }
        rep.wall_s = t.elapsed().as_secs_f64();
        stages.push(rep);
        after_stage.push((stage.name(), params.clone()));
    }
    mz_pure::refit_after_arm(&ctx, &mut params, &mut stages, &stage_data, &after_stage);
    note_refined_later(&mut stages, &params);
    let mut my = StageReport::new("my", "MY");
    my.skipped = Some(
        "rolling resistance moment is not measurable on this rig class (thesis §5): QSY* keep the template's generic values"
            .into(),
    );
    stages.push(my);
    set_limits(&mut params, &range, &nominal);

    // Cross-validation over sweeps, stage by stage, with the final model as the base.
    if opts.folds >= 2 {
        for d in &stage_data {
            let Some(stage) = STAGES.iter().find(|s| s.name() == d.stage) else { continue };
            let Some(rep) = stages.iter_mut().find(|r| r.stage == d.stage) else { continue };
            let t = Instant::now();
            let sel = StagePoints { points: d.points.clone(), groups: d.groups.clone() };
            rep.heldout = crossval::kfold(&ctx, &params, *stage, rep, &sel, opts.folds)?;
            if let Some(h) = &rep.heldout {
                for (key, sd) in rep.primary_keys.iter().zip(&h.jackknife_std) {
                    if let Some(e) = rep.estimates.iter_mut().find(|e| e.key == *key) {
                        e.std_sweeps = Some(*sd);
                    }
                }
            }
            rep.wall_s += t.elapsed().as_secs_f64();
        }
    }

    // Physical margins on the final model, owned by their stages.
    for stage in STAGES {
        let Some(set) = stage.margins() else { continue };
        let Some(rep) = stages.iter_mut().find(|r| r.stage == stage.name()) else { continue };
        if rep.skipped.is_none() {
            rep.nonphysical = crate::physics::margins(&params, set, &ctx.grid)
                .into_iter()
                .filter(crate::physics::fails)
                .map(|m| m.what)
                .collect();
        }
    }
    let warnings = checks::check_all(&params, &range);
    Ok(FitResult {
        params,
        nominal,
        stages,
        data: stage_data,
        range,
        warnings,
        wall_s: t_start.elapsed().as_secs_f64(),
        validation: Vec::new(),
        resampled: ctx.resampled.clone(),
    })
}

/// A coefficient a later stage refitted (`mz_combined` refines `mz_pure`'s trail keys) is one
/// value in the `.tir`: the earlier stage's report says so, with the value written.
fn note_refined_later(stages: &mut [StageReport], params: &TyreParams) {
    for i in 0..stages.len() {
        let (head, tail) = stages.split_at_mut(i + 1);
        let rep = &mut head[i];
        let mut later: Vec<String> = Vec::new();
        for e in &rep.estimates {
            if let Some(by) = tail.iter().find(|t| t.keys.contains(&e.key)) {
                let now = params.get(&e.key).unwrap_or(f64::NAN);
                later.push(format!("{} {:.6} → {now:.6} ({})", e.key, e.value, by.stage));
            }
        }
        if !later.is_empty() {
            rep.notes.push(format!("refined by a later stage (the .tir holds the later value): {}", later.join(", ")));
        }
    }
}

/// Writes the tested range into the `.tir` limits (the model is valid where it was tested).
fn set_limits(params: &mut TyreParams, r: &ValidRange, n: &Nominal) {
    let mut set = |k: &str, v: f64| {
        if v.is_finite() {
            let _ = params.set(k, v);
        }
    };
    set("FZMIN", 0.0);
    set("FZMAX", (r.fz_n.max * 1.1).max(2.0 * n.fz0_n));
    set("ALPMIN", r.alpha_rad.min.min(-0.01));
    set("ALPMAX", r.alpha_rad.max.max(0.01));
    set("KPUMIN", r.kappa.min.min(-0.01));
    set("KPUMAX", r.kappa.max.max(0.01));
    set("CAMMIN", r.gamma_rad.min.min(-0.001));
    set("CAMMAX", r.gamma_rad.max.max(0.001));
    set("PRESMIN", (r.p_pa.min * 0.98).min(n.p0_pa));
    set("PRESMAX", (r.p_pa.max * 1.02).max(n.p0_pa));
}

/// Values of `keys` as `(key, value)` pairs (for reports and tests).
pub fn key_values(params: &TyreParams, keys: &[&'static str]) -> Vec<(&'static str, f64)> {
    keys.iter().copied().zip(values_of(params, keys)).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn warm(stages: &[(&str, [usize; 5])], fresh: &[(&str, f64)]) -> WarmStart {
        WarmStart {
            params: TyreParams::from_tir_str(TEMPLATE_TIR, "template").expect("the template parses"),
            stages: stages.iter().map(|(s, n)| (s.to_string(), *n)).collect(),
            reuse: Vec::new(),
            nominal: [0.0; 4],
            jacobian_held: Vec::new(),
            fresh_nrmse_pct: fresh.iter().map(|(s, v)| (s.to_string(), *v)).collect(),
            resampled: Resampled::default(),
        }
    }

    fn levels(n: [usize; 5]) -> Levels {
        let v = |k: usize| (0..k).map(|i| i as f64).collect();
        Levels {
            loads_n: v(n[0]),
            pressures_pa: v(n[1]),
            cambers_rad: v(n[2]),
            speeds_mps: v(n[3]),
            swept_cambers_rad: v(n[4]),
        }
    }

    #[test]
    fn a_warm_start_admits_flickering_levels_but_not_a_level_that_frees_a_coefficient() {
        let older = warm(&[("fy_pure", [7, 2, 1, 1, 1])], &[("fy_pure", 0.8)]);
        // The newer solution saw fewer loads (decimation, a level under the point threshold).
        let w = warm(&[("fy_pure", [5, 2, 1, 1, 1])], &[]).remembering(Some(&older));
        assert!(w.admits("fy_pure", &levels([6, 2, 1, 1, 1])));
        assert!(w.admits("fy_pure", &levels([16, 2, 1, 1, 1])), "a 16th load frees nothing");
        assert!(!w.admits("fy_pure", &levels([5, 3, 1, 1, 1])), "a third pressure frees PPY4");
        assert!(!w.admits("fy_pure", &levels([5, 2, 2, 1, 2])), "a second camber frees the camber terms");
        assert!(!w.admits("mz_pure", &levels([1, 1, 1, 1, 1])), "a stage never fitted starts fresh");
        // The reference a warm start is held to is the latest fresh fit's, remembered.
        assert_eq!(w.reference_nrmse_pct("fy_pure"), Some(0.8));
        assert_eq!(w.reference_nrmse_pct("mz_pure"), None);
    }
}

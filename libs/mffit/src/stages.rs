//! The staged fit in the thesis's order (§5, reference §12). Each stage selects its data from
//! the [`Dataset`], estimates starting values from it, fits its coefficients in steps (nominal
//! conditions first, then camber, then pressure, then all together, so the optimiser never
//! has to find 30 coefficients from nowhere) and hands the parameter set to the next stage.

use std::time::Instant;

use mftyre::{MfInput, TyreParams};
use serde::Serialize;

use crate::checks;
use crate::data::{DataKind, Dataset, Procedure, Sample, Segment, ValidRange, resample};
use crate::engine::{Channel, Point, apply, values_of};
use crate::error::FitError;
use crate::fit::{StepOutcome, StepSettings, fit_step, rms};
use crate::starts;

/// The neutral MF-Tyre 6.1 template every fit starts from (generic inertia, contact patch,
/// structural frequencies; every fitted coefficient is overwritten).
pub const TEMPLATE_TIR: &str = include_str!("template.tir");

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
    /// Optimiser iterations over all steps.
    pub iterations: usize,
    /// Termination of the last step.
    pub termination: String,
    /// Wall time, s.
    pub wall_s: f64,
    /// Findings: skipped steps, restarts, fallbacks.
    pub notes: Vec<String>,
    /// Why the stage was skipped, if it was.
    pub skipped: Option<String>,
}

/// The data a stage fitted, kept for the report's metrics and plots.
#[derive(Debug, Clone)]
pub struct StageData {
    /// Stage name.
    pub stage: String,
    /// Channel.
    pub channel: Channel,
    /// Points.
    pub points: Vec<Point>,
}

/// The nominal values of stage 0.
#[derive(Debug, Clone, Copy, Serialize)]
pub struct Nominal {
    /// LONGVL, m/s.
    pub v0_mps: f64,
    /// NOMPRES, Pa.
    pub p0_pa: f64,
    /// FNOMIN, N.
    pub fz0_n: f64,
    /// UNLOADED_RADIUS from the rolling-radius extrapolation, m.
    pub r0_m: f64,
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
    /// Failure-mode findings on the final model.
    pub warnings: Vec<String>,
    /// Total wall time, s.
    pub wall_s: f64,
}

struct Ctx<'a> {
    data: &'a Dataset,
    opts: &'a FitOptions,
    nominal: Nominal,
    settings: StepSettings,
}

fn is_fm(seg: &Segment, opts: &FitOptions) -> bool {
    matches!(seg.kind, DataKind::Sweep | DataKind::OnCentre)
        || (opts.include_graph_sweeps && seg.kind == DataKind::GraphSweep)
}

fn input_of(s: &Sample, free_rolling: bool) -> MfInput {
    MfInput {
        fz_n: s.fz_n,
        // Free rolling: the wheel is not driven, slip ratio is zero by construction (the rig's
        // reported value is noise around it).
        kappa: if free_rolling { 0.0 } else { s.kappa },
        alpha_rad: s.alpha_rad,
        gamma_rad: s.gamma_rad,
        phit_per_m: 0.0,
        vx_mps: s.vx_mps,
        p_pa: s.p_pa,
        omega_radps: s.omega_radps,
    }
}

/// Selected samples as points, resampled per segment and evenly decimated to `max`.
fn points(
    ctx: &Ctx,
    keep_seg: impl Fn(&Segment) -> bool,
    keep: impl Fn(&Sample) -> bool,
    measured: impl Fn(&Sample) -> f64,
    max: usize,
) -> Vec<Point> {
    let mut out = Vec::new();
    for seg in ctx.data.segments.iter().filter(|s| keep_seg(s)) {
        let free = seg.procedure == Procedure::FreeRolling;
        let rs = resample(&seg.samples, period_of(ctx, seg));
        for s in rs.iter().filter(|s| keep(s) && s.fz_n > 50.0) {
            let m = measured(s);
            if m.is_finite() {
                out.push(Point { input: input_of(s, free), measured: m });
            }
        }
    }
    decimate(out, max)
}

fn period_of(ctx: &Ctx, seg: &Segment) -> f64 {
    if seg.procedure == Procedure::BrkDrv { ctx.opts.brkdrv_period_s } else { ctx.opts.resample_period_s }
}

fn decimate(v: Vec<Point>, max: usize) -> Vec<Point> {
    if v.len() <= max || max == 0 {
        return v;
    }
    let step = v.len() as f64 / max as f64;
    (0..max).map(|i| v[((i as f64 * step) as usize).min(v.len() - 1)]).collect()
}

fn peak_abs(points: &[Point]) -> f64 {
    points.iter().map(|p| p.measured.abs()).fold(0.0, f64::max).max(1e-9)
}

fn median(mut v: Vec<f64>) -> Option<f64> {
    v.retain(|x| x.is_finite());
    if v.is_empty() {
        return None;
    }
    v.sort_by(f64::total_cmp);
    Some(v[v.len() / 2])
}

/// Distinct pressure levels (clustered to 5 kPa), ascending.
fn pressure_levels(data: &Dataset) -> Vec<f64> {
    let mut levels: Vec<(f64, usize)> = Vec::new();
    for seg in data.segments.iter().filter(|s| s.kind == DataKind::Sweep || s.kind == DataKind::RollingRadius) {
        for s in seg.samples.iter().step_by(10) {
            match levels.iter_mut().find(|(p, _)| (p - s.p_pa).abs() < 5e3) {
                Some(l) => l.1 += 1,
                None => levels.push((s.p_pa, 1)),
            }
        }
    }
    let total: usize = levels.iter().map(|l| l.1).sum();
    // Pressure changes leave a few samples at intermediate pressures: ignore rare levels.
    let mut v: Vec<f64> =
        levels.into_iter().filter(|l| l.1 * 20 >= total / levels_len_guard(total)).map(|l| l.0).collect();
    v.sort_by(f64::total_cmp);
    v
}

fn levels_len_guard(total: usize) -> usize {
    // A level must hold at least ~1 % of the samples.
    if total < 100 { 1 } else { 5 }
}

/// Stage 0: nominal values V0, P0, Fz0 and R0 (rolling-radius extrapolation, per pressure,
/// averaged — thesis §3.11).
pub fn nominal_values(data: &Dataset, opts: &FitOptions) -> Result<Nominal, FitError> {
    let fm: Vec<&Sample> = data.select(|s| s.kind == DataKind::Sweep).map(|(_, s)| s).collect();
    if fm.is_empty() {
        return Err(FitError::NoData("no force & moment sweeps in the logs".into()));
    }
    let v0 = median(fm.iter().filter(|s| s.vx_mps > 2.0).map(|s| s.vx_mps).collect()).unwrap_or(16.6);
    let v0 = (v0 * 10.0).round() / 10.0;
    let levels = pressure_levels(data);
    let p0 = if levels.is_empty() {
        median(fm.iter().map(|s| s.p_pa).collect()).unwrap_or(2.6e5)
    } else {
        levels[levels.len() / 2]
    };
    let p0 = (p0 / 1e3).round() * 1e3;
    let fz0 = opts
        .fnomin_n
        .or(data.fnomin_n)
        .or_else(|| median(fm.iter().map(|s| s.fz_n).collect()).map(|f| f.round()))
        .unwrap_or(5000.0);
    // R0: one straight line per pressure of loaded radius against load, at the lowest speed
    // tested (least radius growth), extrapolated to zero load; the mean over pressures.
    let rr: Vec<&Sample> = data.select(|s| s.kind == DataKind::RollingRadius).map(|(_, s)| s).collect();
    let mut r0s = Vec::new();
    if !rr.is_empty() {
        let vmin = rr.iter().map(|s| s.vx_mps).fold(f64::INFINITY, f64::min);
        let plevels = if levels.is_empty() { vec![p0] } else { levels.clone() };
        for p in plevels {
            let xy: Vec<(f64, f64)> = rr
                .iter()
                .filter(|s| (s.p_pa - p).abs() < 5e3 && s.vx_mps < vmin + 2.0 && s.rl_m > 0.0)
                .map(|s| (s.fz_n, s.rl_m))
                .collect();
            if let Some((a, _)) = starts::line_fit(&xy)
                && a.is_finite()
                && a > 0.0
            {
                r0s.push(a);
            }
        }
    }
    let r0 = if r0s.is_empty() {
        // No rolling-radius data: the largest loaded radius seen plus a small deflection.
        fm.iter().map(|s| s.rl_m).fold(0.0, f64::max) + 0.01
    } else {
        r0s.iter().sum::<f64>() / r0s.len() as f64
    };
    Ok(Nominal { v0_mps: v0, p0_pa: p0, fz0_n: fz0, r0_m: r0 })
}

/// Fits every stage in order. Stages without data are skipped and say so.
pub fn fit(data: &Dataset, opts: &FitOptions) -> Result<FitResult, FitError> {
    let t_start = Instant::now();
    let nominal = nominal_values(data, opts)?;
    let mut params = match &opts.template {
        Some(t) => t.clone(),
        None => TyreParams::from_tir_str(TEMPLATE_TIR, "mffit template")?,
    };
    params.fittyp = 61;
    params.source = "tyrerig fit".into();
    params.set("LONGVL", nominal.v0_mps)?;
    params.set("NOMPRES", nominal.p0_pa)?;
    params.set("INFLPRES", nominal.p0_pa)?;
    params.set("FNOMIN", nominal.fz0_n)?;
    params.set("UNLOADED_RADIUS", nominal.r0_m)?;
    let range = ValidRange::of(data);
    let settings =
        StepSettings { robust: opts.robust_pct, max_iterations: opts.max_iterations, threads: opts.threads.max(1) };
    let ctx = Ctx { data, opts, nominal, settings };
    let mut stages = Vec::new();
    let mut stage_data = Vec::new();
    let t0 = t_start.elapsed().as_secs_f64();
    stages.push(StageReport {
        stage: "nominal".into(),
        channel: "-".into(),
        keys: vec!["LONGVL".into(), "NOMPRES".into(), "FNOMIN".into(), "UNLOADED_RADIUS".into()],
        points: data.len(),
        initial_rmse: f64::NAN,
        rmse: f64::NAN,
        iterations: 0,
        termination: "direct".into(),
        wall_s: t0,
        notes: vec![format!(
            "V0 {:.1} m/s, P0 {:.0} Pa, Fz0 {:.0} N, R0 {:.4} m (rolling-radius extrapolation)",
            nominal.v0_mps, nominal.p0_pa, nominal.fz0_n, nominal.r0_m
        )],
        skipped: None,
    });

    type StageFn = fn(&Ctx, &mut TyreParams, &mut StageReport) -> Result<Option<StageData>, FitError>;
    let order: [(&str, &str, StageFn); 9] = [
        ("fy_pure", "FY", stage_fy_pure),
        ("mz_pure", "MZ", stage_mz_pure),
        ("fx_pure", "FX", stage_fx_pure),
        ("fx_combined", "FX", stage_fx_combined),
        ("fy_combined", "FY", stage_fy_combined),
        ("mz_combined", "MZ", stage_mz_combined),
        ("mx", "MX", stage_mx),
        ("radius_stiffness", "RL", stage_vertical),
        ("relaxation", "SIGMA", stage_relaxation),
    ];
    for (name, channel, f) in order {
        let t = Instant::now();
        let mut rep = StageReport {
            stage: name.into(),
            channel: channel.into(),
            keys: Vec::new(),
            points: 0,
            initial_rmse: f64::NAN,
            rmse: f64::NAN,
            iterations: 0,
            termination: String::new(),
            wall_s: 0.0,
            notes: Vec::new(),
            skipped: None,
        };
        match f(&ctx, &mut params, &mut rep) {
            Ok(Some(d)) => stage_data.push(d),
            Ok(None) => {}
            Err(FitError::NotEnoughData { points, needed, .. }) => {
                rep.skipped = Some(format!("not enough data ({points} points for {needed} coefficients)"));
            }
            Err(e) => return Err(e),
        }
        rep.wall_s = t.elapsed().as_secs_f64();
        stages.push(rep);
    }
    stages.push(StageReport {
        stage: "my".into(),
        channel: "MY".into(),
        keys: Vec::new(),
        points: 0,
        initial_rmse: f64::NAN,
        rmse: f64::NAN,
        iterations: 0,
        termination: String::new(),
        wall_s: 0.0,
        notes: Vec::new(),
        skipped: Some(
            "rolling resistance moment is not measurable on this rig class (thesis §5): QSY* keep the template's generic values"
                .into(),
        ),
    });
    set_limits(&mut params, &range, &nominal);
    let warnings = checks::check_all(&params, &range);
    Ok(FitResult {
        params,
        nominal,
        stages,
        data: stage_data,
        range,
        warnings,
        wall_s: t_start.elapsed().as_secs_f64(),
    })
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

/// Runs a sequence of steps (each a key list over a point subset) and fills the report.
fn run_steps(
    ctx: &Ctx,
    params: &mut TyreParams,
    rep: &mut StageReport,
    channel: Channel,
    all: &[Point],
    steps: &[(&str, Vec<&'static str>, Vec<Point>)],
) -> Result<Vec<StepOutcome>, FitError> {
    let scale = peak_abs(all) / 100.0;
    rep.initial_rmse = rms(params, all, channel);
    let mut outs = Vec::new();
    for (label, keys, pts) in steps {
        if keys.is_empty() {
            continue;
        }
        if pts.len() <= keys.len() * 2 {
            rep.notes.push(format!("step `{label}` skipped: {} points", pts.len()));
            continue;
        }
        let o = fit_step(&rep.stage, params, keys, pts, channel, scale, &ctx.settings)?;
        rep.iterations += o.iterations;
        rep.termination = o.termination.clone();
        outs.push(o);
        for k in keys {
            if !rep.keys.iter().any(|x| x == k) {
                rep.keys.push((*k).to_owned());
            }
        }
    }
    rep.points = all.len();
    rep.rmse = rms(params, all, channel);
    Ok(outs)
}

/// Noise floor of a channel: from consecutive resampled samples at (nearly) the same operating
/// point, σ ≈ median|Δ| / (0.6745·√2).
fn noise_floor(ctx: &Ctx, keep_seg: impl Fn(&Segment) -> bool, measured: fn(&Sample) -> f64) -> f64 {
    let mut d = Vec::new();
    for seg in ctx.data.segments.iter().filter(|s| keep_seg(s)) {
        let rs = resample(&seg.samples, period_of(ctx, seg));
        for w in rs.windows(2) {
            if (w[1].alpha_rad - w[0].alpha_rad).abs() < 0.05f64.to_radians()
                && (w[1].kappa - w[0].kappa).abs() < 0.002
                && (w[1].fz_n - w[0].fz_n).abs() < 100.0
            {
                d.push((measured(&w[1]) - measured(&w[0])).abs());
            }
        }
    }
    starts::median(d).map(|m| m / (0.6745 * std::f64::consts::SQRT_2)).unwrap_or(0.0)
}

/// Runs `steps`, then — while the RMSE stays above 1.6× the data's noise floor (estimated from
/// neighbouring samples; a good MZ fit sits at 1.2–1.5× it, a stuck one at 2–10×) — runs them
/// again from each alternative start (`keys` set to `values` on the stage's
/// starting point), keeping the best. MF shape and curvature terms have local minima the
/// data-derived start does not always avoid.
#[allow(clippy::too_many_arguments)] // the stage's whole context, passed through
fn run_with_restarts(
    ctx: &Ctx,
    params: &mut TyreParams,
    rep: &mut StageReport,
    channel: Channel,
    all: &[Point],
    steps: &[(&str, Vec<&'static str>, Vec<Point>)],
    floor: f64,
    alternatives: &[(&[&'static str], Vec<f64>)],
) -> Result<(), FitError> {
    let start = params.clone();
    run_steps(ctx, params, rep, channel, all, steps)?;
    let tiny = 1e-6 * peak_abs(all);
    let good_enough = |rmse: f64| rmse <= 1.6 * floor + tiny;
    if good_enough(rep.rmse) {
        return Ok(());
    }
    rep.notes.push(if floor > 0.0 {
        format!("rmse {:.3} above 1.6x the noise floor {floor:.3}: restarting", rep.rmse)
    } else {
        format!("rmse {:.3} from the data's start; trying other starts", rep.rmse)
    });
    for (i, (keys, values)) in alternatives.iter().enumerate() {
        let mut trial = start.clone();
        apply(&mut trial, keys, values);
        let mut r = rep.clone();
        run_steps(ctx, &mut trial, &mut r, channel, all, steps)?;
        rep.notes.push(format!("restart {}: rmse {:.3}", i + 1, r.rmse));
        rep.iterations += r.iterations;
        if r.rmse < rep.rmse {
            *params = trial;
            rep.rmse = r.rmse;
            rep.termination = r.termination;
        }
        if good_enough(rep.rmse) {
            break;
        }
    }
    Ok(())
}

fn near_nominal_camber(p: &Point) -> bool {
    p.input.gamma_rad.abs() < 0.4f64.to_radians()
}

fn near_p0(p: &Point, p0: f64) -> bool {
    (p.input.p_pa - p0).abs() < 5e3
}

fn alpha(p: &Point) -> f64 {
    p.input.alpha_rad
}

fn kappa(p: &Point) -> f64 {
    p.input.kappa
}

fn split_segments_points(
    ctx: &Ctx,
    keep_seg: impl Fn(&Segment) -> bool,
    measured: fn(&Sample) -> f64,
) -> Vec<Vec<Point>> {
    ctx.data
        .segments
        .iter()
        .filter(|s| keep_seg(s))
        .map(|seg| {
            let free = seg.procedure == Procedure::FreeRolling;
            resample(&seg.samples, period_of(ctx, seg))
                .iter()
                .filter(|s| s.fz_n > 50.0)
                .map(|s| Point { input: input_of(s, free), measured: measured(s) })
                .collect()
        })
        .collect()
}

const FY_NOMINAL: [&str; 12] =
    ["PCY1", "PDY1", "PDY2", "PEY1", "PEY2", "PEY3", "PKY1", "PKY2", "PKY4", "PHY1", "PHY2", "PVY1"];
const FY_CAMBER: [&str; 10] = ["PDY3", "PEY4", "PEY5", "PKY3", "PKY5", "PKY6", "PKY7", "PVY2", "PVY3", "PVY4"];
const FY_PRESSURE: [&str; 5] = ["PPY1", "PPY2", "PPY3", "PPY4", "PPY5"];

fn stage_fy_pure(ctx: &Ctx, params: &mut TyreParams, rep: &mut StageReport) -> Result<Option<StageData>, FitError> {
    let opts = ctx.opts;
    let keep = |s: &Segment| s.procedure == Procedure::FreeRolling && is_fm(s, opts);
    let all = points(ctx, keep, |_| true, |s| s.fy_n, opts.max_points);
    if all.len() < 50 {
        return Err(FitError::NotEnoughData { stage: "fy_pure".into(), points: all.len(), needed: 50 });
    }
    let p0 = ctx.nominal.p0_pa;
    let fz0 = ctx.nominal.fz0_n;
    let nominal: Vec<Point> = all.iter().copied().filter(|p| near_nominal_camber(p) && near_p0(p, p0)).collect();
    let base = if nominal.len() > 100 { &nominal } else { &all };

    // Starting values from the data.
    let sweeps =
        split_segments_points(ctx, |s| s.procedure == Procedure::FreeRolling && s.kind == DataKind::Sweep, |s| s.fy_n);
    let mut pk = Vec::new();
    for sw in &sweeps {
        let nom: Vec<Point> = sw.iter().copied().filter(|p| near_nominal_camber(p) && near_p0(p, p0)).collect();
        pk.extend(starts::peaks(&nom, alpha));
    }
    let (mu0, dmu) = starts::friction(&pk, fz0).unwrap_or((1.0, 0.0));
    let c = starts::shape_factor(&pk, 1.3);
    let k = starts::slope_at_zero(base, alpha, 1.5f64.to_radians()).unwrap_or(-15.0);
    // Kyα/Fz ≈ PKY1·sin(PKY4·atan(1/PKY2)) at Fz0 with PKY4 = 2, PKY2 = 1.8.
    let pky1 = k / (2.0 * (1.0f64 / 1.8).atan()).sin();
    let by = (k / (c * mu0)).abs();
    let x_peak = starts::median(pk.iter().map(|p| p.slip_at_peak).collect()).unwrap_or(0.15);
    let e = starts::curvature(by, c, x_peak);
    let shift = starts::line_fit(
        &base
            .iter()
            .filter(|p| p.input.alpha_rad.abs() < 1.0f64.to_radians())
            .map(|p| (p.input.alpha_rad, p.measured / p.input.fz_n))
            .collect::<Vec<_>>(),
    )
    .map(|(a, _)| a)
    .unwrap_or(0.0);
    let start_keys = ["PCY1", "PDY1", "PDY2", "PEY1", "PKY1", "PKY2", "PKY4", "PVY1"];
    apply(params, &start_keys, &[c, mu0, dmu, e, pky1, 1.8, 2.0, shift]);
    rep.notes.push(format!(
        "start from data: mu {mu0:.3} ({dmu:+.3}/dfz), C {c:.2}, Kya/Fz {k:.2}/rad, E {e:.2}, peak at {:.1} deg",
        x_peak.to_degrees()
    ));

    // Stiffness first on the near-linear part, where the curve says the most about it.
    let lin: Vec<Point> = base.iter().copied().filter(|p| p.input.alpha_rad.abs() < 2.0f64.to_radians()).collect();
    let camber: Vec<Point> = all.iter().copied().filter(|p| near_p0(p, p0)).collect();
    let mut all_keys: Vec<&'static str> = FY_NOMINAL.to_vec();
    all_keys.extend(FY_CAMBER);
    all_keys.extend(FY_PRESSURE);
    let steps = vec![
        ("stiffness", vec!["PKY1", "PKY2", "PVY1", "PHY1"], lin),
        ("nominal", FY_NOMINAL.to_vec(), base.clone()),
        ("camber", [FY_NOMINAL.as_slice(), FY_CAMBER.as_slice()].concat(), camber),
        ("pressure", FY_PRESSURE.to_vec(), all.clone()),
        ("all", all_keys, all.clone()),
    ];
    run_steps(ctx, params, rep, Channel::Fy0, &all, &steps)?;
    Ok(Some(StageData { stage: rep.stage.clone(), channel: Channel::Fy0, points: all }))
}

const MZ_NOMINAL: [&str; 16] = [
    "QBZ1", "QBZ2", "QBZ3", "QBZ9", "QBZ10", "QCZ1", "QDZ1", "QDZ2", "QDZ6", "QDZ7", "QEZ1", "QEZ2", "QEZ3", "QEZ4",
    "QHZ1", "QHZ2",
];
const MZ_CAMBER: [&str; 11] =
    ["QBZ4", "QBZ5", "QDZ3", "QDZ4", "QDZ8", "QDZ9", "QDZ10", "QDZ11", "QEZ5", "QHZ3", "QHZ4"];
const MZ_PRESSURE: [&str; 2] = ["PPZ1", "PPZ2"];

fn stage_mz_pure(ctx: &Ctx, params: &mut TyreParams, rep: &mut StageReport) -> Result<Option<StageData>, FitError> {
    let opts = ctx.opts;
    let keep = |s: &Segment| s.procedure == Procedure::FreeRolling && is_fm(s, opts);
    // Mz is evaluated through the full model: fewer points keep the stage fast; 10 Hz data
    // of a few hundred sweeps still gives thousands.
    let all = points(ctx, keep, |_| true, |s| s.mz_nm, opts.max_points * 2 / 3);
    if all.len() < 50 {
        return Err(FitError::NotEnoughData { stage: "mz_pure".into(), points: all.len(), needed: 50 });
    }
    let p0 = ctx.nominal.p0_pa;
    let fz0 = ctx.nominal.fz0_n;
    let r0 = ctx.nominal.r0_m;
    let nominal: Vec<Point> = all.iter().copied().filter(|p| near_nominal_camber(p) && near_p0(p, p0)).collect();
    let base = if nominal.len() > 100 { nominal.clone() } else { all.clone() };
    // Pneumatic trail at small slip: t = −Mz/Fy (Fy from the fitted model, less noisy).
    let trails: Vec<f64> = base
        .iter()
        .filter(|p| (0.5f64.to_radians()..2.0f64.to_radians()).contains(&p.input.alpha_rad.abs()))
        .filter_map(|p| {
            let fy = Channel::Fy0.eval(params, &p.input);
            (fy.abs() > 200.0).then(|| -p.measured / fy * fz0 / (p.input.fz_n * r0))
        })
        .collect();
    let qdz1 = starts::median(trails).unwrap_or(0.1).clamp(0.01, 0.5);
    // Mz changes sign where the trail vanishes: Ct·atan(Bt·α₀) = π/2 with Ct = 1.2.
    let mut crossings = Vec::new();
    let sweeps =
        split_segments_points(ctx, |s| s.procedure == Procedure::FreeRolling && s.kind == DataKind::Sweep, |s| s.mz_nm);
    for sw in &sweeps {
        for w in sw.windows(2) {
            let (a, b) = (w[0], w[1]);
            if a.input.alpha_rad.abs() > 2.0f64.to_radians()
                && a.measured.signum() != b.measured.signum()
                && a.input.alpha_rad.signum() == b.input.alpha_rad.signum()
            {
                crossings.push(a.input.alpha_rad.abs());
            }
        }
    }
    let qbz1 = match starts::median(crossings) {
        Some(a0) if a0 > 0.02 => ((std::f64::consts::FRAC_PI_2 / 1.2).tan() / a0).clamp(2.0, 40.0),
        _ => 10.0,
    };
    apply(params, &["QBZ1", "QCZ1", "QDZ1", "QEZ1"], &[qbz1, 1.2, qdz1, 0.0]);
    rep.notes.push(format!("start from data: trail/R0 {qdz1:.3}, Bt {qbz1:.1}"));
    let camber: Vec<Point> = all.iter().copied().filter(|p| near_p0(p, p0)).collect();
    let mut all_keys: Vec<&'static str> = MZ_NOMINAL.to_vec();
    all_keys.extend(MZ_CAMBER);
    all_keys.extend(MZ_PRESSURE);
    let steps = vec![
        ("trail", vec!["QBZ1", "QCZ1", "QDZ1", "QDZ2", "QEZ1", "QHZ1"], base.clone()),
        ("nominal", MZ_NOMINAL.to_vec(), base.clone()),
        ("camber", [MZ_NOMINAL.as_slice(), MZ_CAMBER.as_slice()].concat(), camber),
        ("pressure", MZ_PRESSURE.to_vec(), all.clone()),
        ("all", all_keys, all.clone()),
    ];
    // Mz's trail and residual-torque terms have local minima: other trail shapes if needed.
    let floor = noise_floor(ctx, |s| s.procedure == Procedure::FreeRolling && s.kind == DataKind::Sweep, |s| s.mz_nm);
    const TRAIL: &[&str] = &["QBZ1", "QCZ1", "QDZ1", "QEZ1"];
    let alts = [(TRAIL, vec![qbz1 * 0.6, 1.5, qdz1, -1.0]), (TRAIL, vec![qbz1 * 1.5, 1.0, qdz1, 0.5])];
    run_with_restarts(ctx, params, rep, Channel::Mz0, &all, &steps, floor, &alts)?;
    Ok(Some(StageData { stage: rep.stage.clone(), channel: Channel::Mz0, points: all }))
}

const FX_NOMINAL: [&str; 14] =
    ["PCX1", "PDX1", "PDX2", "PEX1", "PEX2", "PEX3", "PEX4", "PKX1", "PKX2", "PKX3", "PHX1", "PHX2", "PVX1", "PVX2"];
const FX_PRESSURE: [&str; 4] = ["PPX1", "PPX2", "PPX3", "PPX4"];

fn is_pure_long(p: &Point) -> bool {
    p.input.alpha_rad.abs() < 0.3f64.to_radians()
}

fn stage_fx_pure(ctx: &Ctx, params: &mut TyreParams, rep: &mut StageReport) -> Result<Option<StageData>, FitError> {
    let opts = ctx.opts;
    let keep = |s: &Segment| s.procedure == Procedure::BrkDrv && is_fm(s, opts);
    let all: Vec<Point> = points(ctx, keep, |s| s.alpha_rad.abs() < 0.3f64.to_radians(), |s| s.fx_n, opts.max_points);
    if all.len() < 50 {
        return Err(FitError::NotEnoughData { stage: "fx_pure".into(), points: all.len(), needed: 50 });
    }
    let p0 = ctx.nominal.p0_pa;
    let fz0 = ctx.nominal.fz0_n;
    let nominal: Vec<Point> = all.iter().copied().filter(|p| near_nominal_camber(p) && near_p0(p, p0)).collect();
    let base = if nominal.len() > 100 { nominal.clone() } else { all.clone() };
    let sweeps =
        split_segments_points(ctx, |s| s.procedure == Procedure::BrkDrv && s.kind == DataKind::Sweep, |s| s.fx_n);
    let mut pk = Vec::new();
    for sw in &sweeps {
        let nom: Vec<Point> =
            sw.iter().copied().filter(|p| is_pure_long(p) && near_nominal_camber(p) && near_p0(p, p0)).collect();
        pk.extend(starts::peaks(&nom, kappa));
    }
    let (mu0, dmu) = starts::friction(&pk, fz0).unwrap_or((1.0, 0.0));
    let c = starts::shape_factor(&pk, 1.6);
    let k = starts::slope_at_zero(&base, kappa, 0.02).unwrap_or(20.0).max(1.0);
    let bx = k / (c * mu0);
    let x_peak = starts::median(pk.iter().map(|p| p.slip_at_peak).collect()).unwrap_or(0.1);
    let e = starts::curvature(bx, c, x_peak);
    apply(params, &["PCX1", "PDX1", "PDX2", "PEX1", "PKX1", "PKX2", "PKX3"], &[c, mu0, dmu, e, k, 0.0, 0.0]);
    rep.notes.push(format!("start from data: mu {mu0:.3} ({dmu:+.3}/dfz), C {c:.2}, Kxk/Fz {k:.1}, E {e:.2}"));
    let lin: Vec<Point> = base.iter().copied().filter(|p| p.input.kappa.abs() < 0.03).collect();
    let mut all_keys: Vec<&'static str> = FX_NOMINAL.to_vec();
    all_keys.push("PDX3");
    all_keys.extend(FX_PRESSURE);
    let camber: Vec<Point> = all.iter().copied().filter(|p| near_p0(p, p0)).collect();
    let steps = vec![
        ("stiffness", vec!["PKX1", "PKX2", "PHX1", "PVX1"], lin),
        ("nominal", FX_NOMINAL.to_vec(), base.clone()),
        ("camber", vec!["PDX3"], camber),
        ("pressure", FX_PRESSURE.to_vec(), all.clone()),
        ("all", all_keys, all.clone()),
    ];
    // Ex's load and sign(κ) terms trade off against each other: always try the other
    // curvatures (the stage takes ~0.1 s, and the slip-ratio noise makes the FX noise-floor
    // estimate too high to tell a local minimum from noise).
    let floor = 0.0;
    const CURV: &[&str] = &["PEX1", "PEX2", "PEX3", "PEX4"];
    let alts = [(CURV, vec![0.3, 0.0, 0.0, 0.3]), (CURV, vec![-0.5, 0.0, 0.0, -0.3])];
    run_with_restarts(ctx, params, rep, Channel::Fx0, &all, &steps, floor, &alts)?;
    Ok(Some(StageData { stage: rep.stage.clone(), channel: Channel::Fx0, points: all }))
}

fn combined_points(ctx: &Ctx, measured: fn(&Sample) -> f64, max: usize) -> Vec<Point> {
    let opts = ctx.opts;
    points(
        ctx,
        |s: &Segment| s.procedure == Procedure::BrkDrv && is_fm(s, opts),
        |s| s.alpha_rad.abs() >= 0.5f64.to_radians(),
        measured,
        max,
    )
}

const FX_COMBINED: [&str; 7] = ["RBX1", "RBX2", "RBX3", "RCX1", "REX1", "REX2", "RHX1"];
const FY_COMBINED: [&str; 15] = [
    "RBY1", "RBY2", "RBY3", "RBY4", "RCY1", "REY1", "REY2", "RHY1", "RHY2", "RVY1", "RVY2", "RVY3", "RVY4", "RVY5",
    "RVY6",
];

fn stage_fx_combined(ctx: &Ctx, params: &mut TyreParams, rep: &mut StageReport) -> Result<Option<StageData>, FitError> {
    let all = combined_points(ctx, |s| s.fx_n, ctx.opts.max_points * 2 / 3);
    if all.len() < 30 {
        return Err(FitError::NotEnoughData { stage: "fx_combined".into(), points: all.len(), needed: 30 });
    }
    // Starts: Gxα falls to ~cos(atan(Bxα·α)) — a typical passenger-car tyre halves its Fx near
    // 10° slip angle, i.e. Bxα ≈ 10.
    let starts_tried: [[f64; 7]; 2] = [[10.0, 8.0, 0.0, 1.0, 0.0, 0.0, 0.0], [20.0, 15.0, 0.0, 1.1, -0.5, 0.0, 0.0]];
    let mut best: Option<(f64, TyreParams)> = None;
    for (i, st) in starts_tried.iter().enumerate() {
        let mut trial = params.clone();
        apply(&mut trial, &FX_COMBINED, st);
        let mut r = rep.clone();
        run_steps(ctx, &mut trial, &mut r, Channel::Fx, &all, &[("all", FX_COMBINED.to_vec(), all.clone())])?;
        let bad = checks::nonphysical_combined(&trial);
        if i > 0 {
            rep.notes.push(format!("restart {i}: rmse {:.1} N", r.rmse));
        }
        if bad.is_empty() && best.as_ref().is_none_or(|b| r.rmse < b.0) {
            best = Some((r.rmse, trial));
            *rep = r;
        }
        if best.is_some() && i == 0 && rep.rmse < 0.03 * peak_abs(&all) {
            break;
        }
    }
    if let Some((_, t)) = best {
        *params = t;
    }
    Ok(Some(StageData { stage: rep.stage.clone(), channel: Channel::Fx, points: all }))
}

fn stage_fy_combined(ctx: &Ctx, params: &mut TyreParams, rep: &mut StageReport) -> Result<Option<StageData>, FitError> {
    let all = combined_points(ctx, |s| s.fy_n, ctx.opts.max_points * 2 / 3);
    if all.len() < 30 {
        return Err(FitError::NotEnoughData { stage: "fy_combined".into(), points: all.len(), needed: 30 });
    }
    let starts_tried: [[f64; 15]; 2] = [
        [10.0, 8.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.9, 10.0],
        [20.0, 15.0, 0.0, 0.0, 1.1, -0.5, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.9, 20.0],
    ];
    let mut best: Option<(f64, TyreParams)> = None;
    for (i, st) in starts_tried.iter().enumerate() {
        let mut trial = params.clone();
        apply(&mut trial, &FY_COMBINED, st);
        let mut r = rep.clone();
        let weighting: Vec<&'static str> = FY_COMBINED[..9].to_vec();
        run_steps(
            ctx,
            &mut trial,
            &mut r,
            Channel::Fy,
            &all,
            &[("weighting", weighting, all.clone()), ("all", FY_COMBINED.to_vec(), all.clone())],
        )?;
        // A "square" friction ellipse is the known local minimum (thesis §5): restart.
        let square = checks::ellipse_squareness(&trial, ctx.nominal.fz0_n, ctx.nominal.p0_pa);
        let bad = checks::nonphysical_combined(&trial);
        if i > 0 {
            rep.notes.push(format!("restart {i}: rmse {:.1} N, ellipse squareness {square:.2}", r.rmse));
        }
        let ok = bad.is_empty() && square < checks::SQUARE_LIMIT;
        if (ok || best.is_none()) && best.as_ref().is_none_or(|b| r.rmse < b.0 || !b.0.is_finite()) {
            best = Some((if ok { r.rmse } else { f64::INFINITY }, trial));
            *rep = r;
        }
        if ok && i == 0 {
            break;
        }
        if i == 0 {
            rep.notes
                .push(format!("friction ellipse squareness {square:.2} (limit {}); restarting", checks::SQUARE_LIMIT));
        }
    }
    if let Some((_, t)) = best {
        *params = t;
    }
    rep.notes.push(format!(
        "friction ellipse squareness {:.2} at Fz0 (1 = round, 2 = square; limit {})",
        checks::ellipse_squareness(params, ctx.nominal.fz0_n, ctx.nominal.p0_pa),
        checks::SQUARE_LIMIT
    ));
    Ok(Some(StageData { stage: rep.stage.clone(), channel: Channel::Fy, points: all }))
}

fn stage_mz_combined(ctx: &Ctx, params: &mut TyreParams, rep: &mut StageReport) -> Result<Option<StageData>, FitError> {
    let all = combined_points(ctx, |s| s.mz_nm, ctx.opts.max_points / 2);
    if all.len() < 30 {
        return Err(FitError::NotEnoughData { stage: "mz_combined".into(), points: all.len(), needed: 30 });
    }
    apply(params, &["SSZ1", "SSZ2", "SSZ3", "SSZ4"], &[0.0, 0.0, 0.0, 0.0]);
    run_steps(ctx, params, rep, Channel::Mz, &all, &[("arm", vec!["SSZ1", "SSZ2", "SSZ3", "SSZ4"], all.clone())])?;
    rep.notes
        .push("coupled-drive MZ is noisy (thesis: ~22 % on a 385 N·m signal); only the s-arm is fitted here".into());
    Ok(Some(StageData { stage: rep.stage.clone(), channel: Channel::Mz, points: all }))
}

const MX_LINEAR: [&str; 7] = ["QSX1", "QSX2", "QSX3", "QSX12", "QSX13", "QSX14", "PPMX1"];
const MX_ALL: [&str; 15] = [
    "QSX1", "QSX2", "QSX3", "QSX4", "QSX5", "QSX6", "QSX7", "QSX8", "QSX9", "QSX10", "QSX11", "QSX12", "QSX13",
    "QSX14", "PPMX1",
];

fn stage_mx(ctx: &Ctx, params: &mut TyreParams, rep: &mut StageReport) -> Result<Option<StageData>, FitError> {
    let opts = ctx.opts;
    // Thesis §5: coupled-drive MX is unusable; free-rolling data carry it.
    let all = points(
        ctx,
        |s| s.procedure == Procedure::FreeRolling && is_fm(s, opts),
        |_| true,
        |s| s.mx_nm,
        opts.max_points / 2,
    );
    if all.len() < 50 {
        return Err(FitError::NotEnoughData { stage: "mx".into(), points: all.len(), needed: 50 });
    }
    rep.notes.push("fitted on free-rolling data (coupled-drive MX too noisy, thesis §5)".into());
    apply(params, &MX_ALL, &[0.0; 15]);
    run_steps(ctx, params, rep, Channel::Mx, &all, &[("linear", MX_LINEAR.to_vec(), all.clone())])?;
    let linear = params.clone();
    let linear_rmse = rep.rmse;
    // The nonlinear terms multiply each other: start them off zero so their derivatives exist.
    apply(params, &MX_ALL[3..11], &[0.05, 0.5, 1.0, 1.0, 0.5, 0.5, 0.1, 1.0]);
    let mut r = rep.clone();
    run_steps(ctx, params, &mut r, Channel::Mx, &all, &[("all", MX_ALL.to_vec(), all.clone())])?;
    if r.rmse.is_finite() && r.rmse < linear_rmse {
        *rep = r;
    } else {
        *params = linear;
        rep.notes.push("nonlinear QSX4–QSX11 did not improve on the linear terms; kept at zero".into());
    }
    Ok(Some(StageData { stage: rep.stage.clone(), channel: Channel::Mx, points: all }))
}

fn stage_vertical(ctx: &Ctx, params: &mut TyreParams, rep: &mut StageReport) -> Result<Option<StageData>, FitError> {
    let rr = points(ctx, |s| s.kind == DataKind::RollingRadius, |s| s.rl_m > 0.0, |s| s.rl_m, ctx.opts.max_points);
    if rr.len() < 20 {
        return Err(FitError::NotEnoughData { stage: "radius_stiffness".into(), points: rr.len(), needed: 20 });
    }
    // Vertical stiffness start: the slope of radius against load at nominal pressure.
    let xy: Vec<(f64, f64)> =
        rr.iter().filter(|p| near_p0(p, ctx.nominal.p0_pa)).map(|p| (p.input.fz_n, p.measured)).collect();
    if let Some((_, b)) = starts::line_fit(&xy)
        && b < 0.0
    {
        let _ = params.set("VERTICAL_STIFFNESS", -1.0 / b);
    }
    let sweeps = points(
        ctx,
        |s| s.procedure == Procedure::FreeRolling && s.kind == DataKind::Sweep,
        |s| s.rl_m > 0.0,
        |s| s.rl_m,
        ctx.opts.max_points / 3,
    );
    let long = points(
        ctx,
        |s| s.procedure == Procedure::BrkDrv && s.kind == DataKind::Sweep,
        |s| s.rl_m > 0.0 && s.alpha_rad.abs() < 0.3f64.to_radians(),
        |s| s.rl_m,
        ctx.opts.max_points / 3,
    );
    let mut steps =
        vec![("loaded radius", vec!["VERTICAL_STIFFNESS", "Q_FZ2", "PFZ1", "Q_V2", "Q_V1", "Q_RE0"], rr.clone())];
    if sweeps.len() > 20 {
        steps.push(("lateral force and camber", vec!["Q_FCY", "Q_CAM"], sweeps));
    }
    if long.len() > 20 {
        steps.push(("longitudinal force", vec!["Q_FCX"], long));
    }
    run_steps(ctx, params, rep, Channel::Rl, &rr, &steps)?;
    // Effective rolling radius from the free-rolling wheel speed: Re = Vx/Ω.
    let re: Vec<Point> = points(
        ctx,
        |s| s.kind == DataKind::RollingRadius,
        |s| s.omega_radps > 1.0 && s.vx_mps > 1.0,
        |s| s.vx_mps / s.omega_radps,
        ctx.opts.max_points,
    );
    if re.len() > 20 {
        let scale = peak_abs(&re) / 100.0;
        let o =
            fit_step("radius_stiffness", params, &["BREFF", "DREFF", "FREFF"], &re, Channel::Re, scale, &ctx.settings)?;
        rep.iterations += o.iterations;
        rep.keys.extend(["BREFF", "DREFF", "FREFF"].map(String::from));
        rep.notes.push(format!(
            "effective rolling radius: rmse {:.2} mm over {} points",
            rms(params, &re, Channel::Re) * 1e3,
            re.len()
        ));
    }
    rep.notes.push(format!("loaded radius rmse {:.2} mm", rep.rmse * 1e3));
    Ok(Some(StageData { stage: rep.stage.clone(), channel: Channel::Rl, points: rr }))
}

/// Relaxation lengths: σy from step-steer (distance to 63.2 % of the saturated force minus the
/// distance where the force crosses zero, ± pairs averaged), then Cx from static longitudinal
/// tests (slope of FX against belt travel). The carcass stiffnesses follow: Cy = Kyα/σy.
fn stage_relaxation(ctx: &Ctx, params: &mut TyreParams, rep: &mut StageReport) -> Result<Option<StageData>, FitError> {
    let mut sigma_pts = Vec::new();
    for seg in ctx.data.segments.iter().filter(|s| s.kind == DataKind::StepSteer) {
        if let Some((sigma, s)) = step_steer_length(&seg.samples) {
            let input = MfInput {
                alpha_rad: 0.0,
                kappa: 0.0,
                vx_mps: ctx.nominal.v0_mps,
                omega_radps: 0.0,
                ..input_of(&s, true)
            };
            sigma_pts.push(Point { input, measured: sigma });
        }
    }
    let mut cx_pts = Vec::new();
    let static_tests = ctx.data.segments.iter().filter(|s| s.kind == DataKind::StaticLong).count();
    for seg in ctx.data.segments.iter().filter(|s| s.kind == DataKind::StaticLong) {
        if let Some((cx, s)) = static_stiffness(&seg.samples) {
            let input = MfInput {
                alpha_rad: 0.0,
                kappa: 0.0,
                gamma_rad: 0.0,
                vx_mps: ctx.nominal.v0_mps,
                omega_radps: 0.0,
                ..input_of(&s, true)
            };
            cx_pts.push(Point { input, measured: cx });
        }
    }
    if sigma_pts.is_empty() && cx_pts.is_empty() {
        rep.skipped = Some(format!(
            "no usable step-steer or static longitudinal tests ({static_tests} static tests without resolved belt travel)"
        ));
        return Ok(None);
    }
    if cx_pts.len() >= 2 {
        let mean = cx_pts.iter().map(|p| p.measured).sum::<f64>() / cx_pts.len() as f64;
        let _ = params.set("LONGITUDINAL_STIFFNESS", mean);
        let keys: Vec<&'static str> = if cx_pts.len() > 6 {
            vec!["LONGITUDINAL_STIFFNESS", "PCFX1", "PCFX2", "PCFX3"]
        } else {
            vec!["LONGITUDINAL_STIFFNESS"]
        };
        let o = fit_step("relaxation", params, &keys, &cx_pts, Channel::Cx, mean / 100.0, &ctx.settings)?;
        rep.iterations += o.iterations;
        rep.keys.extend(keys.iter().map(|k| k.to_string()));
        let sx: Vec<f64> =
            cx_pts.iter().map(|p| mftyre::evaluate(params, mftyre::UseMode::M211, &p.input).sigmax_m).collect();
        rep.notes.push(format!(
            "static longitudinal: {} tests, Cx {:.0} N/m at Fz0; sigma_x = Kxk/Cx {:.3}..{:.3} m",
            cx_pts.len(),
            params.get("LONGITUDINAL_STIFFNESS").unwrap_or(f64::NAN),
            sx.iter().copied().fold(f64::INFINITY, f64::min),
            sx.iter().copied().fold(f64::NEG_INFINITY, f64::max)
        ));
    } else {
        rep.notes.push(if static_tests > 0 {
            format!(
                "{static_tests} static longitudinal tests, but the belt is not seen moving in TRAJVELW during the drag, so LONGDISP is unknown: LONGITUDINAL_STIFFNESS keeps the template value"
            )
        } else {
            "no static longitudinal data: LONGITUDINAL_STIFFNESS keeps the template value".into()
        });
    }
    if sigma_pts.len() >= 2 {
        // Cy = Kyα/σy point by point for the start.
        let cys: Vec<f64> = sigma_pts
            .iter()
            .map(|p| (mftyre::evaluate(params, mftyre::UseMode::M211, &p.input).kya_nprad / p.measured).abs())
            .collect();
        let _ = params.set("LATERAL_STIFFNESS", cys.iter().sum::<f64>() / cys.len() as f64);
        let keys: Vec<&'static str> = if sigma_pts.len() > 6 {
            vec!["LATERAL_STIFFNESS", "PCFY1", "PCFY2", "PCFY3"]
        } else {
            vec!["LATERAL_STIFFNESS"]
        };
        let mean = sigma_pts.iter().map(|p| p.measured).sum::<f64>() / sigma_pts.len() as f64;
        let o = fit_step("relaxation", params, &keys, &sigma_pts, Channel::SigmaY, mean / 100.0, &ctx.settings)?;
        rep.iterations += o.iterations;
        rep.keys.extend(keys.iter().map(|k| k.to_string()));
        rep.rmse = rms(params, &sigma_pts, Channel::SigmaY);
        rep.points = sigma_pts.len();
        rep.notes.push(format!(
            "step-steer: {} tests, sigma_y {:.3} m mean, rmse {:.3} m",
            sigma_pts.len(),
            mean,
            rep.rmse
        ));
    } else {
        rep.notes.push("no step-steer data: LATERAL_STIFFNESS keeps the template value".into());
    }
    rep.termination = "direct".into();
    Ok(Some(StageData { stage: rep.stage.clone(), channel: Channel::SigmaY, points: sigma_pts }))
}

/// Lateral relaxation length of one step-steer test and the mean rolling sample.
///
/// The test rolls at zero slip, stops, steers at standstill and rolls again holding the slip
/// angle; only the roll after the last standstill counts (the segment may begin with the
/// previous test's steer-back).
pub fn step_steer_length(samples: &[Sample]) -> Option<(f64, Sample)> {
    let a_max = samples.iter().map(|s| s.alpha_rad.abs()).fold(0.0, f64::max);
    if a_max < 0.2f64.to_radians() {
        return None;
    }
    // The standstill with the wheel steered: the roll starts after it.
    let stop = samples.iter().rposition(|s| s.vx_mps.abs() < 0.05 && s.alpha_rad.abs() > 0.5 * a_max)?;
    let rolling: Vec<&Sample> = samples[stop..].iter().take_while(|s| s.alpha_rad.abs() > 0.5 * a_max).collect();
    if rolling.len() < 20 {
        return None;
    }
    let d0 = rolling[0].dist_m;
    let n = rolling.len();
    let tail = &rolling[n * 3 / 4..];
    let fy_sat = tail.iter().map(|s| s.fy_n).sum::<f64>() / tail.len() as f64;
    if fy_sat.abs() < 50.0 {
        return None;
    }
    // Smooth lightly: noise near zero would trigger the crossings early.
    let smooth: Vec<f64> = (0..n)
        .map(|i| {
            let lo = i.saturating_sub(2);
            let hi = (i + 3).min(n);
            rolling[lo..hi].iter().map(|s| s.fy_n).sum::<f64>() / (hi - lo) as f64
        })
        .collect();
    let cross = |level: f64| -> Option<f64> {
        if (smooth[0] - level) * fy_sat.signum() >= 0.0 {
            return Some(0.0);
        }
        (1..n).find(|&i| (smooth[i] - level) * fy_sat.signum() >= 0.0).map(|i| {
            let (a, b) = (smooth[i - 1], smooth[i]);
            let f = if (b - a).abs() > 1e-9 { ((level - a) / (b - a)).clamp(0.0, 1.0) } else { 0.0 };
            rolling[i - 1].dist_m + f * (rolling[i].dist_m - rolling[i - 1].dist_m) - d0
        })
    };
    let d63 = cross(0.632 * fy_sat)?;
    let dz = cross(0.0).unwrap_or(0.0).min(d63);
    let mut mean = *rolling[n / 2];
    mean.fz_n = rolling.iter().map(|s| s.fz_n).sum::<f64>() / n as f64;
    mean.p_pa = rolling.iter().map(|s| s.p_pa).sum::<f64>() / n as f64;
    Some((d63 - dz, mean))
}

/// Static longitudinal stiffness of one test: the slope of FX against belt travel (LONGDISP)
/// over the elastic part (below half the largest force, before the patch slides). `None` when
/// the belt is not seen moving over that part (e.g. a rig that reports TRAJVELW = 0 while it
/// drags the belt).
pub fn static_stiffness(samples: &[Sample]) -> Option<(f64, Sample)> {
    let fmax = samples.iter().map(|s| s.fx_n.abs()).fold(0.0, f64::max);
    if fmax < 100.0 {
        return None;
    }
    // The drag itself: from the last rolling sample on.
    let start = samples.iter().rposition(|s| s.vx_mps > 0.05).map(|i| i + 1).unwrap_or(0);
    let drag = &samples[start.min(samples.len())..];
    let xy: Vec<(f64, f64)> = drag.iter().filter(|s| s.fx_n.abs() < 0.5 * fmax).map(|s| (s.dist_m, s.fx_n)).collect();
    // The belt must be seen moving: a mean TRAJVELW clearly above its noise (integrating pure
    // noise gives a random walk, not a displacement).
    let v: Vec<f64> =
        drag.iter().filter(|s| (0.1 * fmax..0.5 * fmax).contains(&s.fx_n.abs())).map(|s| s.vx_mps).collect();
    let n = v.len().max(1) as f64;
    let mean_v = v.iter().sum::<f64>() / n;
    let sd_v = (v.iter().map(|x| (x - mean_v) * (x - mean_v)).sum::<f64>() / n).sqrt();
    if v.len() < 5 || mean_v.abs() < 1e-3 || mean_v.abs() < 3.0 * sd_v / n.sqrt() {
        return None;
    }
    let (_, b) = starts::line_fit(&xy)?;
    let mut mean = drag[drag.len() / 2];
    mean.fz_n = drag.iter().map(|s| s.fz_n).sum::<f64>() / drag.len() as f64;
    mean.p_pa = drag.iter().map(|s| s.p_pa).sum::<f64>() / drag.len() as f64;
    (b.abs() > 0.0).then_some((b.abs(), mean))
}

/// Values of `keys` as `(key, value)` pairs (for reports and tests).
pub fn key_values(params: &TyreParams, keys: &[&'static str]) -> Vec<(&'static str, f64)> {
    keys.iter().copied().zip(values_of(params, keys)).collect()
}

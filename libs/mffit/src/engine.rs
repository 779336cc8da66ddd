//! The least-squares problem every stage solves: "these `.tir` keys, this model channel, these
//! points", on top of [`lsq`]'s bounded Levenberg–Marquardt.
//!
//! Residuals go through `mftyre`'s batch kernel ([`mftyre::evaluate_batch`], four points per
//! SIMD lane group, ≤ 1e-13 relative to the scalar model): a stage's points are sweeps, whose
//! load-dependent terms the kernel computes once per load case.
//!
//! The Jacobian is numeric: forward differences from the residuals in hand while optimising,
//! central ones where a Jacobian is judged or becomes a covariance ([`Differences`]), steps
//! scaled to each coefficient, its columns computed on all cores (each stage has 4–30
//! coefficients, each column a full pass over the points, so columns are the natural unit of
//! parallel work). A test compares it with
//! `lsq`'s own bounds-aware differences through [`lsq::check_jacobian`]. Analytic derivatives
//! of the full MF 6.1 chain (limits, shifts, combined weighting, Mz's equivalent slips) would be
//! a second model to keep in step with `mftyre`; numeric ones are exactly as correct as the
//! model itself.

use mftyre::{BatchColumn, BatchInput, MfInput, TyreParams, UseMode};
use nalgebra::{DMatrix, DVector};
use std::ops::Range;

/// A model output a stage fits.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Channel {
    /// Pure lateral force Fy0 (cheap path, κ ignored).
    Fy0,
    /// Pure longitudinal force Fx0 (cheap path, α ignored).
    Fx0,
    /// Aligning moment at pure side slip: the whole model (combined-slip mode) at κ = 0, as
    /// MFeval and the rig evaluate it. That is Mz0 + s·Fx(κ = 0), not Mz0 alone: a tyre that
    /// carries a force at zero slip ratio (SVx, SHx) has its arm's moment in every free-rolling
    /// sample, and fitting Mz0 alone to those samples let its coefficients absorb the term,
    /// which the written model's evaluation then added again (the virtual rig's MF tyre at
    /// 2·Fz0: −4.8 to −9.8 N·m at α −1…2°).
    Mz0,
    /// Combined-slip Fx.
    Fx,
    /// Combined-slip Fy.
    Fy,
    /// Combined-slip Mz.
    Mz,
    /// Overturning moment Mx (full model with pure slip: free-rolling data).
    Mx,
    /// Loaded radius, m.
    Rl,
    /// Effective rolling radius, m.
    Re,
    /// Overall longitudinal carcass stiffness, N/m.
    Cx,
    /// Lateral relaxation length, m.
    SigmaY,
}

impl Channel {
    /// Name in reports.
    pub fn name(self) -> &'static str {
        match self {
            Channel::Fy0 | Channel::Fy => "FY",
            Channel::Fx0 | Channel::Fx => "FX",
            Channel::Mz0 | Channel::Mz => "MZ",
            Channel::Mx => "MX",
            Channel::Rl => "RL",
            Channel::Re => "RE",
            Channel::Cx => "CX",
            Channel::SigmaY => "SIGMAY",
        }
    }

    /// Evaluates the channel of `params` at `input`. No limit checks: the data define the range.
    pub fn eval(self, params: &TyreParams, input: &MfInput) -> f64 {
        match self {
            Channel::Fy0 => mftyre::pure_fy(params, UseMode::M211, input),
            Channel::Fx0 => mftyre::pure_fx(params, UseMode::M211, input),
            Channel::Mz0 => mftyre::evaluate(params, UseMode::M211, &MfInput { kappa: 0.0, ..*input }).mz_nm,
            Channel::Mx => mftyre::evaluate(params, UseMode::M212, input).mx_nm,
            Channel::Fx => mftyre::evaluate(params, UseMode::M211, input).fx_n,
            Channel::Fy => mftyre::evaluate(params, UseMode::M211, input).fy_n,
            Channel::Mz => mftyre::evaluate(params, UseMode::M211, input).mz_nm,
            Channel::Rl => mftyre::evaluate(params, UseMode::M211, input).rl_m,
            Channel::Re => mftyre::evaluate(params, UseMode::M211, input).re_m,
            Channel::Cx => mftyre::evaluate(params, UseMode::M211, input).cx_npm,
            Channel::SigmaY => mftyre::evaluate(params, UseMode::M211, input).sigmay_m,
        }
    }
}

impl Channel {
    /// [`Channel::eval`] at every point of `inputs`, into `out` (as long as `inputs`), by the
    /// batch kernel; `scratch` holds the kernel's outputs between calls.
    pub fn eval_batch(self, params: &TyreParams, inputs: &BatchInput<'_>, scratch: &mut BatchScratch, out: &mut [f64]) {
        // The columns are built from points, so their lengths always agree.
        let column = |mode: UseMode, column: BatchColumn, values: &mut Vec<f64>| {
            let _ = mftyre::evaluate_column(params, mode, inputs, column, values);
        };
        let values = &mut scratch.values;
        match self {
            Channel::Fy0 => {
                let _ = mftyre::pure_fy_batch(params, UseMode::M211, inputs, values);
            }
            // Pure Fx has no batch path; it is one of the cheapest channels.
            Channel::Fx0 => {
                for (i, o) in out.iter_mut().enumerate() {
                    *o = mftyre::pure_fx(params, UseMode::M211, &inputs.point(i));
                }
                return;
            }
            // The batch kernel computes only the terms each channel's column needs.
            Channel::Mz0 => {
                scratch.zeros.resize(inputs.fz_n.len(), 0.0);
                let at_zero_kappa = BatchInput { kappa: &scratch.zeros, ..*inputs };
                let _ = mftyre::evaluate_column(params, UseMode::M211, &at_zero_kappa, BatchColumn::MzNm, values);
            }
            Channel::Mx => column(UseMode::M212, BatchColumn::MxNm, values),
            Channel::Fx => column(UseMode::M211, BatchColumn::FxN, values),
            Channel::Fy => column(UseMode::M211, BatchColumn::FyN, values),
            Channel::Mz => column(UseMode::M211, BatchColumn::MzNm, values),
            Channel::Rl => column(UseMode::M211, BatchColumn::RlM, values),
            Channel::Re => column(UseMode::M211, BatchColumn::ReM, values),
            Channel::Cx => column(UseMode::M211, BatchColumn::CxNpm, values),
            Channel::SigmaY => column(UseMode::M211, BatchColumn::SigmayM, values),
        }
        out.copy_from_slice(&values[..out.len()]);
    }
}

impl Channel {
    /// [`Channel::eval`] at every point, by the batch kernel (equal to it within the kernel's
    /// 1e-13): for reports' RMSE and covariances, which visit every point of a stage.
    pub fn values_at(self, params: &TyreParams, points: &[Point]) -> Vec<f64> {
        let mut out = vec![0.0; points.len()];
        let cols = InputColumns::of(points);
        self.eval_batch(params, &cols.batch(0..points.len()), &mut BatchScratch::default(), &mut out);
        out
    }
}

/// The batch kernel's output buffers, kept between evaluations (one per worker thread).
#[derive(Debug, Default)]
pub struct BatchScratch {
    values: Vec<f64>,
    /// A column of zeros (κ for [`Channel::Mz0`]).
    zeros: Vec<f64>,
}

/// Points' inputs as columns, the batch kernel's struct-of-arrays layout.
#[derive(Debug, Clone, Default)]
pub struct InputColumns {
    fz_n: Vec<f64>,
    kappa: Vec<f64>,
    alpha_rad: Vec<f64>,
    gamma_rad: Vec<f64>,
    phit_per_m: Vec<f64>,
    vx_mps: Vec<f64>,
    p_pa: Vec<f64>,
    omega_radps: Vec<f64>,
}

impl InputColumns {
    /// The inputs of `points`, in order.
    pub fn of(points: &[Point]) -> Self {
        let inputs: Vec<MfInput> = points.iter().map(|p| p.input).collect();
        Self::of_inputs(&inputs)
    }

    /// The columns of `inputs`, in order.
    pub fn of_inputs(inputs: &[MfInput]) -> Self {
        let col = |f: fn(&MfInput) -> f64| inputs.iter().map(f).collect();
        InputColumns {
            fz_n: col(|i| i.fz_n),
            kappa: col(|i| i.kappa),
            alpha_rad: col(|i| i.alpha_rad),
            gamma_rad: col(|i| i.gamma_rad),
            phit_per_m: col(|i| i.phit_per_m),
            vx_mps: col(|i| i.vx_mps),
            p_pa: col(|i| i.p_pa),
            omega_radps: col(|i| i.omega_radps),
        }
    }

    /// Number of points.
    pub fn len(&self) -> usize {
        self.fz_n.len()
    }

    /// True without points.
    pub fn is_empty(&self) -> bool {
        self.fz_n.is_empty()
    }

    /// Points `range` as a batch.
    pub fn batch(&self, range: Range<usize>) -> BatchInput<'_> {
        BatchInput {
            fz_n: &self.fz_n[range.clone()],
            kappa: &self.kappa[range.clone()],
            alpha_rad: &self.alpha_rad[range.clone()],
            gamma_rad: &self.gamma_rad[range.clone()],
            phit_per_m: &self.phit_per_m[range.clone()],
            vx_mps: &self.vx_mps[range.clone()],
            p_pa: &self.p_pa[range.clone()],
            omega_radps: &self.omega_radps[range],
        }
    }
}

impl Channel {
    /// The channel's value from any tyre given as a function (e.g. a virtual rig's brush tyre as
    /// the reference a fit is scored against), read the way [`Channel::eval`] reads the MF: the
    /// pure channels with the other slip at zero.
    pub fn eval_reference(self, tyre: &crate::accuracy::ReferenceTyre<'_>, input: &MfInput) -> f64 {
        let pure = |kappa: f64, alpha_rad: f64| MfInput { kappa, alpha_rad, ..*input };
        match self {
            Channel::Fy0 => tyre(UseMode::M211, &pure(0.0, input.alpha_rad)).fy_n,
            Channel::Fx0 => tyre(UseMode::M211, &pure(input.kappa, 0.0)).fx_n,
            Channel::Mz0 => tyre(UseMode::M211, &pure(0.0, input.alpha_rad)).mz_nm,
            Channel::Mx => tyre(UseMode::M212, input).mx_nm,
            Channel::Fx => tyre(UseMode::M211, input).fx_n,
            Channel::Fy => tyre(UseMode::M211, input).fy_n,
            Channel::Mz => tyre(UseMode::M211, input).mz_nm,
            Channel::Rl => tyre(UseMode::M211, input).rl_m,
            Channel::Re => tyre(UseMode::M211, input).re_m,
            Channel::Cx => tyre(UseMode::M211, input).cx_npm,
            Channel::SigmaY => tyre(UseMode::M211, input).sigmay_m,
        }
    }
}

/// One data point: operating condition and measured value.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Point {
    /// Model input.
    pub input: MfInput,
    /// Measured channel value.
    pub measured: f64,
}

/// Fits `keys` of `base` to `points` of `channel`; residuals are `(model − measured)/scale`.
#[derive(Debug)]
pub struct ChannelProblem<'a> {
    /// Parameter set holding every coefficient not being fitted.
    pub base: &'a TyreParams,
    /// `.tir` keys being fitted, in parameter-vector order.
    pub keys: &'a [&'static str],
    /// The data.
    pub points: &'a [Point],
    /// Model output fitted.
    pub channel: Channel,
    /// Residual scale (so robust-loss thresholds are in units of it), > 0.
    pub scale: f64,
    /// How the Jacobian is differenced.
    pub differences: Differences,
    /// Worker threads for residuals and Jacobian columns.
    pub threads: usize,
    /// Physical margins added as penalty residuals (see [`crate::physics`]), if any.
    pub penalty: Option<Penalty<'a>>,
    /// A weight per point (residual × weight), when points of different sets share one fit
    /// (a joint fit of two stages' data, each in % of its own peak); `None`: all 1.
    weights: Option<&'a [f64]>,
    /// Number of penalty residuals (fixed for a grid).
    penalty_count: usize,
    /// `points`' inputs as the batch kernel takes them.
    columns: InputColumns,
    /// The last residuals evaluated and where: the solver asks for the Jacobian where it last
    /// accepted a step, so forward differences find their base point here.
    last: std::sync::Mutex<Option<(DVector<f64>, DVector<f64>)>>,
}

/// How a [`ChannelProblem`]'s Jacobian is differenced.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Differences {
    /// Central: two model passes per coefficient, error O(h²). Every Jacobian that is judged
    /// (identifiability) or turned into a covariance is central.
    #[default]
    Central,
    /// Forward from the residuals in hand: one pass per coefficient, error O(h), stepping
    /// inward at an upper bound. The optimiser's default ([`crate::FitOptions::differences`]):
    /// where Levenberg–Marquardt ends depends on the residuals only, and on the MF and brush
    /// GS2MF logs of docs/fitting.md it ends as low as with central differences or lower, in
    /// half the model passes.
    Forward,
}

/// Relative difference step, central and forward alike. ∛ε: a forward step of √ε (the textbook
/// balance of truncation against rounding) sits in the batch kernel's rounding noise for
/// coefficients near zero and sent the Mz fits of the MF tyre to worse minima (MZ combined 4.8 %
/// NRMSE against 2.3 %); at ∛ε the forward error is ~1e-5 of a column, far below what steers
/// the optimiser.
fn relative_step() -> f64 {
    f64::EPSILON.cbrt()
}

/// Penalty residuals: `weight × shortfall` of each margin of `set` on `grid`, appended after the
/// data residuals. They are zero while the model is physical, so they change nothing there;
/// outside, they pull the optimiser back (a fit stays physical by construction).
#[derive(Debug, Clone, Copy)]
pub struct Penalty<'a> {
    /// The margins.
    pub set: crate::physics::MarginSet,
    /// Where they are checked.
    pub grid: &'a crate::physics::Grid,
    /// Residual per unit of shortfall (residual units: % of the channel's peak).
    pub weight: f64,
}

impl Penalty<'_> {
    /// Weight for `points` data residuals: a shortfall of 0.001 (in μ, E or G) costs as much as
    /// raising every data residual by about 0.3 % of the peak, 0.01 as much as 3 % — more than
    /// any fit gains by leaving the physical region.
    pub fn weight_for(points: usize) -> f64 {
        300.0 * (points.max(1) as f64).sqrt()
    }
}

impl<'a> ChannelProblem<'a> {
    /// A problem with default differencing and all available cores.
    pub fn new(
        base: &'a TyreParams,
        keys: &'a [&'static str],
        points: &'a [Point],
        channel: Channel,
        scale: f64,
    ) -> Self {
        let threads = std::thread::available_parallelism().map(|n| n.get()).unwrap_or(1);
        Self {
            base,
            keys,
            points,
            channel,
            scale,
            differences: Differences::Central,
            threads,
            penalty: None,
            weights: None,
            penalty_count: 0,
            columns: InputColumns::of(points),
            last: std::sync::Mutex::new(None),
        }
    }

    /// Adds physical margins as penalty residuals.
    pub fn with_penalty(mut self, penalty: Penalty<'a>) -> Self {
        let mut v = Vec::new();
        crate::physics::shortfalls(self.base, penalty.set, penalty.grid, &mut v);
        self.penalty_count = v.len();
        self.penalty = Some(penalty);
        self
    }

    /// Weights the residuals point by point (`weights` as long as the points; a slice of
    /// another length is ignored).
    pub fn with_weights(mut self, weights: &'a [f64]) -> Self {
        self.weights = (weights.len() == self.points.len()).then_some(weights);
        self
    }

    fn num_penalties(&self) -> usize {
        self.penalty_count
    }

    fn penalties_into(&self, t: &TyreParams, out: &mut [f64]) {
        if let Some(pen) = &self.penalty {
            let mut v = Vec::with_capacity(out.len());
            crate::physics::shortfalls(t, pen.set, pen.grid, &mut v);
            for (o, x) in out.iter_mut().zip(v) {
                *o = pen.weight * x;
            }
        }
    }

    /// `base` with the parameter vector written into `keys`.
    pub fn params_at(&self, p: &DVector<f64>) -> TyreParams {
        let mut t = self.base.clone();
        apply(&mut t, self.keys, p.as_slice());
        t
    }

    /// Residuals of points `range` into `out` (as long as the range).
    fn residuals_into(&self, t: &TyreParams, range: Range<usize>, scratch: &mut BatchScratch, out: &mut [f64]) {
        let pts = &self.points[range.clone()];
        self.channel.eval_batch(t, &self.columns.batch(range.clone()), scratch, out);
        let inv = 1.0 / self.scale;
        for (o, pt) in out.iter_mut().zip(pts) {
            *o = (*o - pt.measured) * inv;
        }
        if let Some(w) = self.weights.and_then(|w| w.get(range)) {
            for (o, w) in out.iter_mut().zip(w) {
                *o *= w;
            }
        }
    }

    fn residuals_parallel(&self, t: &TyreParams, out: &mut [f64]) {
        // Below a few hundred points a thread costs more than it saves.
        if self.threads <= 1 || out.len() < 400 {
            self.residuals_into(t, 0..out.len(), &mut BatchScratch::default(), out);
            return;
        }
        let chunk = out.len().div_ceil(self.threads);
        std::thread::scope(|s| {
            for (ci, o) in out.chunks_mut(chunk).enumerate() {
                let range = ci * chunk..ci * chunk + o.len();
                s.spawn(move || self.residuals_into(t, range, &mut BatchScratch::default(), o));
            }
        });
    }

    fn step(&self, x: f64) -> f64 {
        relative_step() * x.abs().max(1e-3)
    }

    /// The residuals at `p`: the last ones evaluated when they were evaluated there.
    fn residuals_at(&self, p: &DVector<f64>) -> DVector<f64> {
        if let Ok(last) = self.last.lock()
            && let Some((at, r)) = last.as_ref()
            && at == p
        {
            return r.clone();
        }
        let mut r = DVector::zeros(lsq::Problem::num_residuals(self));
        lsq::Problem::residuals(self, p, &mut r);
        r
    }
}

/// Writes `values` into `params` at `keys` (keys are `mftyre` typed coefficients, so `set` can
/// only fail on non-finite values, which the solver never proposes; such a value is skipped).
pub fn apply(params: &mut TyreParams, keys: &[&str], values: &[f64]) {
    for (k, v) in keys.iter().zip(values) {
        let _ = params.set(k, *v);
    }
}

/// The current values of `keys` in `params` (0 for an unknown key).
pub fn values_of(params: &TyreParams, keys: &[&str]) -> Vec<f64> {
    keys.iter().map(|k| params.get(k).unwrap_or(0.0)).collect()
}

impl lsq::Problem for ChannelProblem<'_> {
    fn num_residuals(&self) -> usize {
        self.points.len() + self.num_penalties()
    }

    fn residuals(&self, p: &DVector<f64>, r: &mut DVector<f64>) {
        let t = self.params_at(p);
        let (data, pen) = r.as_mut_slice().split_at_mut(self.points.len());
        self.residuals_parallel(&t, data);
        self.penalties_into(&t, pen);
        if self.differences == Differences::Forward
            && let Ok(mut last) = self.last.lock()
        {
            *last = Some((p.clone(), r.clone()));
        }
    }

    fn jacobian(&self, p: &DVector<f64>, j: &mut DMatrix<f64>) -> bool {
        let n = p.len();
        let m = self.points.len() + self.num_penalties();
        let md = self.points.len();
        let threads = self.threads.max(1).min(n);
        let base = (self.differences == Differences::Forward).then(|| self.residuals_at(p));
        let base = base.as_ref();
        // Columns are contiguous in nalgebra's column-major storage: hand each worker its own.
        let cols: Vec<&mut [f64]> = j.as_mut_slice().chunks_mut(m).collect();
        let mut buckets: Vec<Vec<(usize, &mut [f64])>> = (0..threads).map(|_| Vec::new()).collect();
        for (c, col) in cols.into_iter().enumerate() {
            buckets[c % threads].push((c, col));
        }
        std::thread::scope(|s| {
            for bucket in buckets {
                s.spawn(move || {
                    let mut plus = vec![0.0; m];
                    let mut minus = vec![0.0; m];
                    let mut scratch = BatchScratch::default();
                    for (c, col) in bucket {
                        let mut h = self.step(p[c]);
                        // A one-sided step stays inside the key's bounds (the model beyond them
                        // can be clamped flat, E at 1, and would read as no effect at all).
                        if base.is_some() && p[c] + h > bounds_for(self.keys[c]).1 {
                            h = -h;
                        }
                        let mut pp = p.clone();
                        pp[c] = p[c] + h;
                        let t = self.params_at(&pp);
                        self.residuals_into(&t, 0..md, &mut scratch, &mut plus[..md]);
                        self.penalties_into(&t, &mut plus[md..]);
                        if let Some(base) = base {
                            // The step as represented, so rounding of p + h does not bias it.
                            let inv = 1.0 / (pp[c] - p[c]);
                            for i in 0..m {
                                col[i] = (plus[i] - base[i]) * inv;
                            }
                            continue;
                        }
                        pp[c] = p[c] - h;
                        let t = self.params_at(&pp);
                        self.residuals_into(&t, 0..md, &mut scratch, &mut minus[..md]);
                        self.penalties_into(&t, &mut minus[md..]);
                        let inv = 1.0 / (2.0 * h);
                        for i in 0..m {
                            col[i] = (plus[i] - minus[i]) * inv;
                        }
                    }
                });
            }
        });
        true
    }
}

/// Bounds for one coefficient, [lower, upper].
pub type Bounds = (f64, f64);

/// Physical bounds on a coefficient during fitting. They keep the fit out of the known bad
/// regions (C ≤ 0, D ≤ 0, E > 1 at nominal conditions, radii and stiffnesses ≤ 0) without pinning
/// anything a real tyre could need.
pub fn bounds_for(key: &str) -> Bounds {
    const INF: f64 = f64::INFINITY;
    match key {
        // Shape factors: C > 0; above 2.5 the curve oscillates.
        "PCY1" | "PCX1" => (0.5, 2.5),
        // Friction at nominal load: D > 0.
        "PDY1" | "PDX1" => (0.1, 4.0),
        // Curvature at nominal load: E ≤ 1.
        "PEY1" | "PEX1" => (-10.0, 1.0),
        "PEX4" => (-1.0, 1.0),
        "PEY3" => (-1.0, 1.0),
        // Combined weighting: B > 0, C > 0 (weights between 0 and 1).
        "RBX1" | "RBY1" => (0.1, 100.0),
        "RCX1" | "RCY1" => (0.2, 3.0),
        "REX1" | "REY1" => (-10.0, 1.0),
        // Trail and residual torque shape.
        "QBZ1" => (0.5, 50.0),
        "QCZ1" => (0.5, 3.0),
        "QEZ1" => (-20.0, 1.0),
        // Vertical and structural: positive stiffness and radius.
        "VERTICAL_STIFFNESS" => (1.0e4, 5.0e6),
        "UNLOADED_RADIUS" => (0.05, 2.0),
        "LONGITUDINAL_STIFFNESS" | "LATERAL_STIFFNESS" => (1.0e3, 1.0e8),
        "BREFF" => (0.1, 100.0),
        "DREFF" => (0.0, 2.0),
        "FREFF" => (-1.0, 1.0),
        "Q_RE0" => (0.8, 1.2),
        "Q_FZ2" => (0.0, 200.0),
        // Slip stiffness: Kyα/Fz and Kxκ/Fz of real tyres are a few tens per rad (race tyres up
        // to ~100).
        "PKY1" => (-500.0, 500.0),
        "PKX1" => (0.1, 500.0),
        // Every other force-and-moment coefficient of MF 6.1 is a dimensionless factor of order
        // 0.001–50 in published .tir files. Without a bound, a coefficient the data barely
        // touch (a camber term fitted on a few points) can run off to 10⁵ while its neighbours
        // compensate: the fit stays plausible in the data and is nonsense beside them.
        k if is_force_moment_coefficient(k) => (-100.0, 100.0),
        _ => (-INF, INF),
    }
}

/// True for MF 6.1's force and moment coefficients (`P?X*`, `P?Y*`, `Q?Z*`, `QSX*`, `QSY*`,
/// `R??*`, `SSZ*`, `PP*`): dimensionless factors, as opposed to stiffnesses and radii.
fn is_force_moment_coefficient(key: &str) -> bool {
    let b = key.as_bytes();
    let digit_tail = b.last().is_some_and(u8::is_ascii_digit);
    digit_tail
        && (key.starts_with("PC")
            || key.starts_with("PD")
            || key.starts_with("PE")
            || key.starts_with("PK")
            || key.starts_with("PH")
            || key.starts_with("PV")
            || key.starts_with("PP")
            || key.starts_with("QB")
            || key.starts_with("QC")
            || key.starts_with("QD")
            || key.starts_with("QE")
            || key.starts_with("QH")
            || key.starts_with("QS")
            || key.starts_with("RB")
            || key.starts_with("RC")
            || key.starts_with("RE")
            || key.starts_with("RH")
            || key.starts_with("RV")
            || key.starts_with("SSZ"))
        && !key.starts_with("PCF")
}

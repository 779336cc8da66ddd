//! What the planner needs from the live model, per target channel: the covariance of the
//! coefficients the channel depends on, the mean prediction variance it gives over the envelope
//! grid, the noise of a new measurement, and sensitivities at any planned point.
//!
//! Everything is normalised by the channel's peak |value| over its grid, so variances of FY,
//! MZ and FX add up as (fraction of peak)² and the predicted error reads as % of peak, the unit
//! the held-out accuracy is reported in.

use mffit::FitResult;
use mffit::engine::Channel;
use mffit::identify::is_structural;
use mffit::prediction::{EnvelopeGrid, MapChannel};
use mftyre::{MfInput, TyreParams};
use nalgebra::{DMatrix, DVector};
use procedure::Setpoint;
use procedure::setpoint::PA_PER_BAR;
use serde::{Deserialize, Serialize};

use crate::config::AdaptiveConfig;
use crate::design;

/// A channel the plan tries to make sure of.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Target {
    /// Pure lateral force over slip angle.
    FyPure,
    /// Pure aligning moment over slip angle.
    MzPure,
    /// Pure overturning moment over slip angle (camber and load make it).
    MxPure,
    /// Pure longitudinal force over slip ratio.
    FxPure,
    /// Combined-slip FX (slip ratio at a held slip angle).
    FxCombined,
    /// Combined-slip FY.
    FyCombined,
}

impl Target {
    /// Every target.
    pub const ALL: [Target; 6] =
        [Target::FyPure, Target::MzPure, Target::MxPure, Target::FxPure, Target::FxCombined, Target::FyCombined];

    /// Name in logs and reports.
    pub fn name(self) -> &'static str {
        match self {
            Target::FyPure => "FY pure",
            Target::MzPure => "MZ pure",
            Target::MxPure => "MX pure",
            Target::FxPure => "FX pure",
            Target::FxCombined => "FX combined",
            Target::FyCombined => "FY combined",
        }
    }

    /// The fit stages whose coefficients the channel depends on (block-diagonal covariance, as
    /// `mffit::prediction` takes them: stages are fitted one after another on their own data).
    pub fn stages(self) -> &'static [&'static str] {
        match self {
            Target::FyPure => &["fy_pure"],
            Target::MzPure => &["fy_pure", "mz_pure"],
            Target::MxPure => &["mx"],
            Target::FxPure => &["fx_pure"],
            Target::FxCombined => &["fx_pure", "fx_combined"],
            Target::FyCombined => &["fy_pure", "fy_combined"],
        }
    }

    /// The stage whose residual RMSE stands for a new measurement's noise.
    pub fn residual_stage(self) -> &'static str {
        match self {
            Target::FyPure => "fy_pure",
            Target::MzPure => "mz_pure",
            Target::MxPure => "mx",
            Target::FxPure => "fx_pure",
            Target::FxCombined => "fx_combined",
            Target::FyCombined => "fy_combined",
        }
    }

    fn channel(self) -> Channel {
        match self {
            Target::FyPure => Channel::Fy0,
            Target::MzPure => Channel::Mz0,
            Target::MxPure => Channel::Mx,
            Target::FxPure => Channel::Fx0,
            Target::FxCombined => Channel::Fx,
            Target::FyCombined => Channel::Fy,
        }
    }
}

/// One target's linearised model, normalised by its peak.
#[derive(Debug, Clone)]
pub struct TargetModel {
    /// Coefficient covariance (n×n).
    pub cov: DMatrix<f64>,
    /// Grid weight H = GᵀG/m of the normalised grid gradients ([`design::grid_weight`]).
    pub h: DMatrix<f64>,
    /// Noise of one new measurement, fraction of peak.
    pub sigma: f64,
}

impl TargetModel {
    /// Predicted error over the grid: RMS of the mean's σ, % of peak.
    pub fn error_pct(&self) -> f64 {
        100.0 * design::mean_variance(&self.h, &self.cov).sqrt()
    }
}

/// The model as the planner sees it.
pub trait ModelView {
    /// The target's model; `None` while a stage it depends on is not fitted.
    fn target(&self, t: Target) -> Option<&TargetModel>;
    /// Normalised sensitivities (k×n, the target's coefficient order) at planned setpoints.
    fn sensitivities(&self, t: Target, points: &[Setpoint]) -> DMatrix<f64>;
    /// Friction power the tyre dissipates sliding at a setpoint \[W\] (what wears the tread),
    /// as the model predicts it; `None` without a model.
    fn sliding_power_w(&self, _sp: &Setpoint) -> Option<f64> {
        None
    }
}

/// No model yet (before the first update): every target unknown.
#[derive(Debug, Clone, Copy, Default)]
pub struct NoModel;

impl ModelView for NoModel {
    fn target(&self, _: Target) -> Option<&TargetModel> {
        None
    }
    fn sensitivities(&self, _: Target, points: &[Setpoint]) -> DMatrix<f64> {
        DMatrix::zeros(points.len(), 0)
    }
}

/// The live model as the planner needs it, owned: the whole parameter set, the nominal values
/// the fit found, and per fitted stage the covariance of its coefficients. A fit in-process
/// gives it ([`ModelSnapshot::of`]); over DDS it travels as `tyre_msgs/ModelCovariance` on
/// `model/covariance`, so a sequencer node decides with the same model the headless run has.
#[derive(Debug, Clone, PartialEq)]
pub struct ModelSnapshot {
    /// The fitted parameter set.
    pub params: TyreParams,
    /// FNOMIN the fit found \[N\].
    pub fz0_n: f64,
    /// NOMPRES \[Pa\].
    pub p0_pa: f64,
    /// LONGVL \[m/s\].
    pub v0_mps: f64,
    /// UNLOADED_RADIUS \[m\].
    pub r0_m: f64,
    /// The fitted stages (skipped ones left out), in fit order.
    pub stages: Vec<StageSnapshot>,
}

/// One fitted stage of a [`ModelSnapshot`].
#[derive(Debug, Clone, PartialEq)]
pub struct StageSnapshot {
    /// Stage name (`fy_pure`, ...).
    pub stage: String,
    /// RMS residual, channel units.
    pub rmse: f64,
    /// The coefficients fitted on the stage's main channel, in `covariance` order.
    pub keys: Vec<String>,
    /// Row-major keys × keys; non-finite where a coefficient is not identified.
    pub covariance: Vec<f64>,
    /// Keys held at template values because the data lack levels of what they multiply.
    pub held_for_want_of_data: Vec<String>,
}

impl ModelSnapshot {
    /// The snapshot of a fit.
    pub fn of(result: &FitResult) -> Self {
        let n = &result.nominal;
        ModelSnapshot {
            params: result.params.clone(),
            fz0_n: n.fz0_n,
            p0_pa: n.p0_pa,
            v0_mps: n.v0_mps,
            r0_m: n.r0_m,
            stages: result
                .stages
                .iter()
                .filter(|s| s.skipped.is_none())
                .map(|s| StageSnapshot {
                    stage: s.stage.clone(),
                    rmse: s.rmse,
                    keys: s.primary_keys.iter().map(|k| (*k).to_owned()).collect(),
                    covariance: s.covariance.clone(),
                    held_for_want_of_data: s.held.iter().filter(|h| is_structural(h)).map(|h| h.key.clone()).collect(),
                })
                .collect(),
        }
    }

    fn stage(&self, name: &str) -> Option<&StageSnapshot> {
        self.stages.iter().find(|s| s.stage == name)
    }
}

/// A live model as a [`ModelView`]: per target the stages' covariances plus, for every
/// coefficient held for want of data (a level not tested yet), a prior of
/// [`AdaptiveConfig::held_prior_std`] — the uncertainty the planner should go after.
#[derive(Debug)]
pub struct FitView<'a> {
    model: &'a ModelSnapshot,
    targets: Vec<(Target, Option<Built>)>,
}

#[derive(Debug)]
struct Built {
    keys: Vec<String>,
    scale: f64,
    model: TargetModel,
}

impl<'a> FitView<'a> {
    /// The view of `model`, its grid the live fit's standard envelope grid (pure channels)
    /// and a combined-slip grid at the nominal pressure.
    pub fn new(model: &'a ModelSnapshot, cfg: &AdaptiveConfig) -> Self {
        let grid = EnvelopeGrid::standard(model.fz0_n, model.p0_pa, model.v0_mps);
        let targets = Target::ALL.iter().map(|&t| (t, build(model, t, &grid, cfg))).collect();
        FitView { model, targets }
    }

    fn built(&self, t: Target) -> Option<&Built> {
        self.targets.iter().find(|(x, _)| *x == t).and_then(|(_, b)| b.as_ref())
    }
}

impl ModelView for FitView<'_> {
    fn target(&self, t: Target) -> Option<&TargetModel> {
        self.built(t).map(|b| &b.model)
    }

    fn sensitivities(&self, t: Target, points: &[Setpoint]) -> DMatrix<f64> {
        let Some(b) = self.built(t) else { return DMatrix::zeros(points.len(), 0) };
        let r0 = self.model.r0_m;
        let rows: Vec<DVector<f64>> = points
            .iter()
            .map(|sp| gradient(&self.model.params, t.channel(), &b.keys, &input_of(sp, r0)) / b.scale)
            .collect();
        design::rows(&rows, b.keys.len())
    }

    /// |FX|·|slip velocity x| + |FY|·|slip velocity y|, the slip velocities κ·V and tan α·V of the
    /// contact over the road (ISO-W), with the combined-slip forces (which reduce to the pure
    /// ones at zero slip on the other axis).
    fn sliding_power_w(&self, sp: &Setpoint) -> Option<f64> {
        let x = input_of(sp, self.model.r0_m);
        let fx = Channel::Fx.eval(&self.model.params, &x);
        let fy = Channel::Fy.eval(&self.model.params, &x);
        let v = sp.speed_mps.abs();
        let p = v * (fx.abs() * sp.slip_ratio.abs() + fy.abs() * x.alpha_rad.tan().abs());
        p.is_finite().then_some(p)
    }
}

/// The model input of a planned setpoint (ISO-W, SI).
pub fn input_of(sp: &Setpoint, r0_m: f64) -> MfInput {
    MfInput {
        fz_n: sp.fz_n,
        kappa: sp.slip_ratio,
        alpha_rad: sp.slip_angle_deg.to_radians(),
        gamma_rad: sp.camber_deg.to_radians(),
        phit_per_m: 0.0,
        vx_mps: sp.speed_mps,
        p_pa: sp.pressure_bar * PA_PER_BAR,
        omega_radps: sp.speed_mps * (1.0 + sp.slip_ratio) / r0_m.max(0.1),
    }
}

/// ∂y/∂p by central differences, steps scaled to each coefficient as the fit's Jacobian does.
fn gradient(params: &TyreParams, ch: Channel, keys: &[String], x: &MfInput) -> DVector<f64> {
    let mut p = params.clone();
    DVector::from_iterator(
        keys.len(),
        keys.iter().map(|key| {
            let v = params.get(key).unwrap_or(0.0);
            let h = 1e-6 * v.abs().max(1e-3);
            let _ = p.set(key, v + h);
            let up = ch.eval(&p, x);
            let _ = p.set(key, v - h);
            let down = ch.eval(&p, x);
            let _ = p.set(key, v);
            let g = (up - down) / (2.0 * h);
            if g.is_finite() { g } else { 0.0 }
        }),
    )
}

fn grid_inputs(model: &ModelSnapshot, t: Target, grid: &EnvelopeGrid) -> Vec<MfInput> {
    let r0 = model.r0_m;
    match t {
        Target::FyPure => grid.inputs(MapChannel::FyPure, r0),
        Target::MzPure | Target::MxPure => grid.inputs(MapChannel::MzPure, r0),
        Target::FxPure => grid.inputs(MapChannel::FxPure, r0),
        Target::FxCombined | Target::FyCombined => {
            let p0 = model.p0_pa;
            let mut out = Vec::new();
            for &fz in &grid.fz_n {
                for sa in [-8.0f64, -4.0, -1.0, 1.0, 4.0, 8.0] {
                    for kappa in [-0.2, -0.1, -0.03, 0.03, 0.1, 0.2] {
                        out.push(MfInput {
                            fz_n: fz,
                            kappa,
                            alpha_rad: sa.to_radians(),
                            gamma_rad: 0.0,
                            phit_per_m: 0.0,
                            vx_mps: grid.speed_mps,
                            p_pa: p0,
                            omega_radps: grid.speed_mps * (1.0 + kappa) / r0.max(0.1),
                        });
                    }
                }
            }
            out
        }
    }
}

fn build(model: &ModelSnapshot, t: Target, grid: &EnvelopeGrid, cfg: &AdaptiveConfig) -> Option<Built> {
    let mut keys: Vec<String> = Vec::new();
    let mut blocks: Vec<(usize, Vec<f64>, usize)> = Vec::new(); // (offset, cov, n)
    let mut priors: Vec<usize> = Vec::new();
    for name in t.stages() {
        let rep = model.stage(name)?;
        let n = rep.keys.len();
        if n == 0 || rep.covariance.len() != n * n {
            return None;
        }
        blocks.push((keys.len(), rep.covariance.clone(), n));
        keys.extend(rep.keys.iter().cloned());
        for key in &rep.held_for_want_of_data {
            if !keys.contains(key) && model.params.get(key).is_some() {
                priors.push(keys.len());
                keys.push(key.clone());
            }
        }
    }
    let n = keys.len();
    let mut cov = DMatrix::zeros(n, n);
    for (at, c, k) in &blocks {
        for i in 0..*k {
            for j in 0..*k {
                let v = c[i * k + j];
                cov[(at + i, at + j)] = if v.is_finite() { v } else { 0.0 };
            }
            // A coefficient without a finite variance is as unknown as a held one.
            if !c[i * k + i].is_finite() {
                for j in 0..n {
                    cov[(at + i, j)] = 0.0;
                    cov[(j, at + i)] = 0.0;
                }
                cov[(at + i, at + i)] = cfg.held_prior_std * cfg.held_prior_std;
            }
        }
    }
    for &i in &priors {
        cov[(i, i)] = cfg.held_prior_std * cfg.held_prior_std;
    }
    let inputs = grid_inputs(model, t, grid);
    let ch = t.channel();
    let scale = inputs.iter().map(|x| ch.eval(&model.params, x).abs()).filter(|v| v.is_finite()).fold(0.0, f64::max);
    if scale <= 0.0 {
        return None;
    }
    let rows: Vec<DVector<f64>> = inputs.iter().map(|x| gradient(&model.params, ch, &keys, x) / scale).collect();
    let g = design::rows(&rows, n);
    let rmse = model.stage(t.residual_stage()).map_or(f64::NAN, |s| s.rmse);
    let sigma = if rmse.is_finite() && rmse > 0.0 { rmse / scale } else { 0.01 };
    Some(Built { keys, scale, model: TargetModel { cov, h: design::grid_weight(&g), sigma } })
}

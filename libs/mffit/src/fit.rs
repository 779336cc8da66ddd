//! One least-squares step of a stage: fit some keys of a parameter set to some points.

use lsq::{Loss, Options};
use mftyre::TyreParams;
use nalgebra::DVector;

use crate::engine::{Channel, ChannelProblem, Differences, Penalty, Point, apply, bounds_for, values_of};
use crate::error::FitError;

/// What one step did.
#[derive(Debug, Clone, PartialEq)]
pub struct StepOutcome {
    /// Cost before and after (½·Σ r², residuals in units of the scale).
    pub initial_cost: f64,
    /// Final cost.
    pub cost: f64,
    /// LM iterations.
    pub iterations: usize,
    /// Termination reason, as text.
    pub termination: String,
}

/// Settings shared by every step.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StepSettings {
    /// Robust loss threshold in units of the residual scale (None = plain least squares).
    pub robust: Option<f64>,
    /// Iteration limit per step.
    pub max_iterations: usize,
    /// Worker threads.
    pub threads: usize,
    /// How the optimiser's Jacobians are differenced.
    pub differences: Differences,
}

impl Default for StepSettings {
    fn default() -> Self {
        Self {
            robust: None,
            max_iterations: 60,
            threads: std::thread::available_parallelism().map(|n| n.get()).unwrap_or(1),
            differences: Differences::Forward,
        }
    }
}

/// Fits `keys` of `params` (in place) to `points` of `channel`. Residuals are divided by `scale`.
///
/// Starting values outside a key's bounds are moved inside first. The parameters are only
/// replaced when the fit lowered the cost, so a failed step never makes a stage worse.
pub fn fit_step(
    stage: &str,
    params: &mut TyreParams,
    keys: &[&'static str],
    points: &[Point],
    channel: Channel,
    scale: f64,
    settings: &StepSettings,
) -> Result<StepOutcome, FitError> {
    fit_step_with(stage, params, keys, points, channel, scale, settings, None)
}

/// [`fit_step`] with physical margins as penalty residuals ([`Penalty`]).
#[allow(clippy::too_many_arguments)] // fit_step's arguments plus the penalty
pub fn fit_step_with(
    stage: &str,
    params: &mut TyreParams,
    keys: &[&'static str],
    points: &[Point],
    channel: Channel,
    scale: f64,
    settings: &StepSettings,
    penalty: Option<Penalty<'_>>,
) -> Result<StepOutcome, FitError> {
    fit_step_weighted(stage, params, keys, points, None, channel, scale, settings, penalty)
}

/// [`fit_step_with`] with a weight per point (`weights[i]` multiplies point i's residual): for
/// a fit over two stages' points, each set in units of its own peak.
#[allow(clippy::too_many_arguments)] // fit_step_with's arguments plus the weights
pub fn fit_step_weighted(
    stage: &str,
    params: &mut TyreParams,
    keys: &[&'static str],
    points: &[Point],
    weights: Option<&[f64]>,
    channel: Channel,
    scale: f64,
    settings: &StepSettings,
    penalty: Option<Penalty<'_>>,
) -> Result<StepOutcome, FitError> {
    if points.len() <= keys.len() {
        return Err(FitError::NotEnoughData { stage: stage.to_owned(), points: points.len(), needed: keys.len() + 1 });
    }
    let (lower, upper): (Vec<f64>, Vec<f64>) = keys.iter().map(|k| bounds_for(k)).unzip();
    let mut p0 = values_of(params, keys);
    for (i, v) in p0.iter_mut().enumerate() {
        *v = v.clamp(lower[i], upper[i]);
    }
    let mut problem = ChannelProblem::new(params, keys, points, channel, scale.max(1e-12));
    problem.threads = settings.threads.max(1);
    problem.differences = settings.differences;
    if let Some(pen) = penalty {
        problem = problem.with_penalty(pen);
    }
    if let Some(w) = weights {
        problem = problem.with_weights(w);
    }
    let mut options = Options::default()
        .max_iterations(settings.max_iterations)
        .ftol(1e-8)
        .xtol(1e-8)
        .gtol(1e-8)
        .bounds(DVector::from_vec(lower), DVector::from_vec(upper));
    if let Some(d) = settings.robust {
        options = options.loss(Loss::SoftL1(d));
    }
    let report = lsq::solve(&problem, DVector::from_vec(p0.clone()), &options)
        .map_err(|source| FitError::Solver { stage: stage.to_owned(), source })?;
    let improved = report.cost <= report.initial_cost && report.params.iter().all(|v| v.is_finite());
    if improved {
        apply(params, keys, report.params.as_slice());
    } else {
        apply(params, keys, &p0);
    }
    Ok(StepOutcome {
        initial_cost: report.initial_cost,
        cost: if improved { report.cost } else { report.initial_cost },
        iterations: report.iterations,
        termination: format!("{:?}", report.termination),
    })
}

/// Root-mean-square residual of `channel` over `points` for `params`.
pub fn rms(params: &TyreParams, points: &[Point], channel: Channel) -> f64 {
    if points.is_empty() {
        return f64::NAN;
    }
    let values = channel.values_at(params, points);
    let s: f64 = values
        .iter()
        .zip(points)
        .map(|(v, p)| {
            let e = v - p.measured;
            e * e
        })
        .sum();
    (s / points.len() as f64).sqrt()
}

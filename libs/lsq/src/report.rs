//! What a solve returns.

use nalgebra::DVector;

use crate::jacobian::JacobianCheck;

/// Which convergence test stopped the solver.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Convergence {
    /// The cost is exactly zero.
    ZeroCost,
    /// Actual and predicted relative cost reductions below `ftol`.
    Cost,
    /// Relative step below `xtol`.
    Step,
    /// Projected gradient (cosine) below `gtol`.
    Gradient,
}

/// Why the solver stopped.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Termination {
    /// A convergence test was met.
    Converged {
        /// Which one.
        reason: Convergence,
    },
    /// `max_iterations` outer iterations ran.
    MaxIterations,
    /// `max_evaluations` residual evaluations were spent.
    MaxEvaluations,
    /// The damping grew without bound and no step reduced the cost: the solver is stuck (at a
    /// point where the Jacobian is wrong, or the residuals are non-finite all around).
    NoProgress,
}

impl Termination {
    /// True for [`Termination::Converged`].
    pub fn converged(&self) -> bool {
        matches!(self, Termination::Converged { .. })
    }
}

/// The outcome of [`crate::solve`].
#[derive(Debug, Clone, PartialEq)]
pub struct Report {
    /// The best parameters found (always within the bounds).
    pub params: DVector<f64>,
    /// Cost `½·Σ ρ(rᵢ²)` at `params`.
    pub cost: f64,
    /// Cost at the (projected) starting point.
    pub initial_cost: f64,
    /// Outer iterations (one Jacobian each).
    pub iterations: usize,
    /// Residual evaluations, finite differences included.
    pub evaluations: usize,
    /// Jacobian evaluations (analytic or numeric).
    pub jacobian_evaluations: usize,
    /// Why the solver stopped.
    pub termination: Termination,
    /// Largest scaled projected-gradient component at the last Jacobian (the `gtol` measure).
    pub gradient_norm: f64,
    /// Parameters that ended on a bound.
    pub active_bounds: Vec<usize>,
    /// Analytic-versus-numeric Jacobian comparison at the start, if requested with
    /// [`crate::Options::check_jacobian`] and the problem has an analytic Jacobian.
    pub jacobian_check: Option<JacobianCheck>,
}

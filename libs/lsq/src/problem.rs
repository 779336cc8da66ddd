//! The problem trait.

use nalgebra::{DMatrix, DVector};

/// A nonlinear least-squares problem: minimise `½·Σ ρ(rᵢ(p)²)` over the parameters `p`.
///
/// Implementors give the residuals and, optionally, their Jacobian. Both write into buffers the
/// solver owns and reuses, so a problem with 200k residuals does not allocate per evaluation.
pub trait Problem {
    /// Number of residuals `m` (fixed for the problem's lifetime).
    fn num_residuals(&self) -> usize;

    /// Writes the residuals at `p` into `r` (length `m`). Non-finite residuals are allowed: the
    /// solver treats such a point as unacceptable (it rejects the step) rather than panicking.
    fn residuals(&self, p: &DVector<f64>, r: &mut DVector<f64>);

    /// Writes the Jacobian `∂rᵢ/∂pⱼ` at `p` into `j` (`m × n`, zero-filled on entry) and returns
    /// `true`, or returns `false` to have the solver use bounds-aware central differences.
    fn jacobian(&self, p: &DVector<f64>, j: &mut DMatrix<f64>) -> bool {
        let _ = (p, j);
        false
    }
}

impl<P: Problem + ?Sized> Problem for &P {
    fn num_residuals(&self) -> usize {
        (**self).num_residuals()
    }

    fn residuals(&self, p: &DVector<f64>, r: &mut DVector<f64>) {
        (**self).residuals(p, r);
    }

    fn jacobian(&self, p: &DVector<f64>, j: &mut DMatrix<f64>) -> bool {
        (**self).jacobian(p, j)
    }
}

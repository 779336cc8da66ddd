//! lsq: bounded nonlinear least squares (Levenberg–Marquardt) on nalgebra — the optimiser
//! behind tyrerig's MF-Tyre 6.1 fits.
//!
//! ```
//! use lsq::{Options, Problem, solve};
//! use nalgebra::{DMatrix, DVector};
//!
//! /// y = a·exp(−b·t) through three points.
//! struct Decay;
//! impl Problem for Decay {
//!     fn num_residuals(&self) -> usize { 3 }
//!     fn residuals(&self, p: &DVector<f64>, r: &mut DVector<f64>) {
//!         for (i, (t, y)) in [(0.0, 2.0), (1.0, 1.0), (2.0, 0.5)].into_iter().enumerate() {
//!             r[i] = p[0] * (-p[1] * t).exp() - y;
//!         }
//!     }
//! }
//! let report = solve(&Decay, DVector::from_vec(vec![1.0, 1.0]), &Options::default()).unwrap();
//! assert!(report.termination.converged());
//! assert!((report.params[1] - std::f64::consts::LN_2).abs() < 1e-8);
//! ```
//!
//! # Design
//! - One small trait, [`Problem`]: residuals into a caller-owned buffer, and optionally an
//!   analytic Jacobian (return `false` from [`Problem::jacobian`] for finite differences).
//! - [`Options`] is a builder: iteration and evaluation limits, `ftol`/`xtol`/`gtol`, initial
//!   damping, per-parameter bounds, a robust [`Loss`] and a damping [`Scaling`].
//! - [`solve`] returns a [`Report`] with a [`Termination`] reason; only invalid input is an
//!   [`LsqError`].
//!
//! # Algorithm
//! Levenberg–Marquardt in MINPACK's form: each iteration factors the (reweighted) Jacobian
//! `J = Q·R` in place by Householder reflections, then each damping trial solves
//! `min ‖[R; √λ·D]·h + [Qᵀr; 0]‖` by a second, small `2n × n` QR — never forming `JᵀJ`, whose
//! condition number is the square of `J`'s. `D` is Moré's scaling (largest Jacobian column
//! norms so far) unless overridden; λ follows Nielsen's update.
//!
//! **Bounds** are handled with an active set and step truncation (the scheme of scipy's
//! "dogbox", with LM steps instead of dogleg ones): at each iteration a parameter sitting on a
//! bound with its descent direction pointing outwards is frozen (its Jacobian column is left out,
//! so its step is exactly zero); the others take the damped step, truncated where it first
//! crosses a bound, and the parameter that hits the bound is put exactly on it (frozen next time
//! if the gradient still pushes outwards). A frozen-free parameter already on a bound that the
//! step would push through is frozen for that trial. Truncating rather than projecting each
//! coordinate matters for MF fits: projection lets the long early Gauss–Newton steps pin
//! parameters to their bounds while the rest move on, and strands the fit in false constrained
//! minima (a test shows it). The gradient test uses the projected gradient, so a solution on a
//! bound converges properly. The iterates, and every finite-difference evaluation, stay within
//! the bounds.
//!
//! **Finite differences** are central with `hⱼ = ε^(1/3)·max(|pⱼ|, typicalⱼ)` (typical: the
//! start's magnitude, or `1/Dⱼ` of a fixed scaling), switching to the
//! second-order one-sided formula near a bound. [`check_jacobian`] compares an analytic
//! Jacobian against them.
//!
//! **Robust losses** (Huber, soft-L1, Cauchy) enter by iteratively reweighted least squares: row
//! `i` is weighted by `√ρ'(rᵢ²)` at the present iterate, and steps are accepted on the true
//! robust cost.
//!
//! **Memory**: the `m × n` Jacobian buffer is the only large allocation besides three residual
//! vectors (plus two more for finite differences); nothing is allocated inside the loop, so a
//! fit with 40 parameters and 200k residuals holds about 64 MB.

mod error;
mod jacobian;
mod options;
mod problem;
mod qr;
mod report;
mod solver;

pub use crate::error::LsqError;
pub use crate::jacobian::{JacobianCheck, check_jacobian};
pub use crate::options::{Loss, Options, Scaling};
pub use crate::problem::Problem;
pub use crate::report::{Convergence, Report, Termination};
pub use crate::solver::solve;

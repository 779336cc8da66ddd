//! Finite-difference Jacobians and the analytic-versus-numeric check.

use nalgebra::{DMatrix, DVector};

use crate::error::LsqError;
use crate::problem::Problem;

/// The result of comparing an analytic Jacobian with central differences.
#[derive(Debug, Clone, PartialEq)]
pub struct JacobianCheck {
    /// Largest relative difference over all entries (see [`check_jacobian`]).
    pub max_rel_error: f64,
    /// Row (residual) of the worst entry.
    pub row: usize,
    /// Column (parameter) of the worst entry.
    pub col: usize,
    /// The analytic value there.
    pub analytic: f64,
    /// The finite-difference value there.
    pub numeric: f64,
}

/// Reused buffers for finite differences (two residual vectors and a parameter vector), so a
/// Jacobian of a 200k-residual problem allocates nothing per call.
#[derive(Debug)]
pub(crate) struct DiffWorkspace {
    p: DVector<f64>,
    r_a: DVector<f64>,
    r_b: DVector<f64>,
}

impl DiffWorkspace {
    pub(crate) fn new(m: usize, n: usize) -> Self {
        Self { p: DVector::zeros(n), r_a: DVector::zeros(m), r_b: DVector::zeros(m) }
    }
}

/// Writes the finite-difference Jacobian at `p` into `j`; `r0` are the residuals at `p`.
/// Returns the number of residual evaluations.
///
/// Central differences with `hⱼ = rel_step·max(|pⱼ|, typicalⱼ)` where both `pⱼ ± hⱼ` lie within the
/// bounds; otherwise the second-order one-sided three-point formula into the roomier side (with
/// the step shrunk to fit), so the problem is never evaluated outside its bounds. A parameter
/// fixed by equal bounds gets a zero column.
#[allow(clippy::too_many_arguments)]
pub(crate) fn numeric_jacobian<P: Problem + ?Sized>(
    problem: &P,
    p: &DVector<f64>,
    r0: &DVector<f64>,
    lower: &DVector<f64>,
    upper: &DVector<f64>,
    rel_step: f64,
    typical: &DVector<f64>,
    ws: &mut DiffWorkspace,
    j: &mut DMatrix<f64>,
) -> usize {
    let n = p.len();
    let mut evaluations = 0;
    ws.p.copy_from(p);
    for col in 0..n {
        let x = p[col];
        let h = rel_step * x.abs().max(typical[col]);
        let room_up = upper[col] - x;
        let room_dn = x - lower[col];
        let mut column = j.column_mut(col);
        if room_up >= h && room_dn >= h {
            let (xp, xm) = (x + h, x - h);
            ws.p[col] = xp;
            problem.residuals(&ws.p, &mut ws.r_a);
            ws.p[col] = xm;
            problem.residuals(&ws.p, &mut ws.r_b);
            evaluations += 2;
            // The representable step, not the nominal one, to avoid a rounding bias.
            let inv = 1.0 / (xp - xm);
            for i in 0..column.len() {
                column[i] = (ws.r_a[i] - ws.r_b[i]) * inv;
            }
        } else {
            let (sign, room) = if room_up >= room_dn { (1.0, room_up) } else { (-1.0, room_dn) };
            let h = h.min(0.5 * room);
            if h <= 0.0 || h.is_nan() {
                column.fill(0.0);
                ws.p[col] = x;
                continue;
            }
            let x1 = (x + sign * h).clamp(lower[col], upper[col]);
            let x2 = (x + 2.0 * sign * h).clamp(lower[col], upper[col]);
            ws.p[col] = x1;
            problem.residuals(&ws.p, &mut ws.r_a);
            ws.p[col] = x2;
            problem.residuals(&ws.p, &mut ws.r_b);
            evaluations += 2;
            // f'(x) ≈ (−3f(x) + 4f(x + s) − f(x + 2s)) / 2s, s = ±h.
            let inv = 1.0 / (2.0 * sign * h);
            for i in 0..column.len() {
                column[i] = (-3.0 * r0[i] + 4.0 * ws.r_a[i] - ws.r_b[i]) * inv;
            }
        }
        ws.p[col] = x;
    }
    evaluations
}

/// Typical parameter magnitudes, the floor of the finite-difference steps: `1/Dⱼ` of a fixed
/// scaling if given, else `|p₀ⱼ|` (the start's magnitude; 1 where it is 0). A floor of 1 for
/// every parameter, the common choice, would make the step of a parameter of size 1e-6 six
/// times the parameter itself.
pub(crate) fn typical_magnitudes(p0: &DVector<f64>, fixed_scale: Option<&DVector<f64>>) -> DVector<f64> {
    match fixed_scale {
        Some(d) => d.map(|dj| 1.0 / dj),
        None => p0.map(|x| if x != 0.0 { x.abs() } else { 1.0 }),
    }
}

/// Compares the problem's analytic Jacobian at `p` with central differences.
///
/// The relative error of an entry is `|a − f| / max(|a|, |f|, 1e-6·c + 1e-10)`, where `c` is
/// the largest magnitude in the entry's column: entries that are tiny compared with the rest
/// of their column are judged against the column's scale, since central differences cannot
/// resolve them relatively. An agreeing Jacobian gives about `1e-7`, up to `1e-5` on entries
/// much smaller than their residuals (round-off); a wrong derivative gives order 1. Steps are
/// `ε^(1/3)·|pⱼ|` (`ε^(1/3)` where `pⱼ = 0`).
pub fn check_jacobian<P: Problem + ?Sized>(problem: &P, p: &DVector<f64>) -> Result<JacobianCheck, LsqError> {
    let n = p.len();
    let inf = DVector::from_element(n, f64::INFINITY);
    let typical = typical_magnitudes(p, None);
    check_jacobian_within(problem, p, &(-&inf), &inf, f64::EPSILON.cbrt(), &typical)
}

pub(crate) fn check_jacobian_within<P: Problem + ?Sized>(
    problem: &P,
    p: &DVector<f64>,
    lower: &DVector<f64>,
    upper: &DVector<f64>,
    rel_step: f64,
    typical: &DVector<f64>,
) -> Result<JacobianCheck, LsqError> {
    let n = p.len();
    if n == 0 {
        return Err(LsqError::NoParameters);
    }
    let m = problem.num_residuals();
    let mut analytic = DMatrix::zeros(m, n);
    if !problem.jacobian(p, &mut analytic) {
        return Err(LsqError::NoAnalyticJacobian);
    }
    let mut r0 = DVector::zeros(m);
    problem.residuals(p, &mut r0);
    if r0.len() != m {
        return Err(LsqError::ResidualLength { len: r0.len(), expected: m });
    }
    let mut numeric = DMatrix::zeros(m, n);
    let mut ws = DiffWorkspace::new(m, n);
    numeric_jacobian(problem, p, &r0, lower, upper, rel_step, typical, &mut ws, &mut numeric);
    let mut worst = JacobianCheck {
        max_rel_error: 0.0,
        row: 0,
        col: 0,
        analytic: analytic.get((0, 0)).copied().unwrap_or(0.0),
        numeric: numeric.get((0, 0)).copied().unwrap_or(0.0),
    };
    for col in 0..n {
        let scale =
            analytic.column(col).iter().chain(numeric.column(col).iter()).fold(0.0_f64, |acc, v| acc.max(v.abs()));
        let floor = 1e-6 * scale + 1e-10;
        for row in 0..m {
            let (a, f) = (analytic[(row, col)], numeric[(row, col)]);
            let err = if a.is_finite() && f.is_finite() {
                (a - f).abs() / a.abs().max(f.abs()).max(floor)
            } else {
                f64::INFINITY
            };
            if err > worst.max_rel_error || (err.is_nan() && !worst.max_rel_error.is_nan()) {
                worst = JacobianCheck { max_rel_error: err, row, col, analytic: a, numeric: f };
            }
        }
    }
    Ok(worst)
}

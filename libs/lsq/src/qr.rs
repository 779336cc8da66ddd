//! Dense Householder QR in place, and the damped (Levenberg–Marquardt) subproblem on top of it.
//!
//! Written out rather than taken from nalgebra's `QR` because the solver must factor the same
//! `m × n` buffer every iteration without allocating a new one (nalgebra's decomposition takes
//! the matrix by value), and because it needs only `R` and `Qᵀr`, never `Q` itself.

use nalgebra::{DMatrix, DVector};

/// Householder QR of `a` (`rows × cols`, `rows ≥ cols`) in place, applying `Qᵀ` to `b`.
///
/// Leaves `R` in the upper triangle of `a`'s first `cols` rows; entries below the diagonal are
/// overwritten with scratch. A zero column leaves a zero diagonal.
pub(crate) fn householder_qr(a: &mut DMatrix<f64>, b: &mut DVector<f64>) {
    let (m, n) = a.shape();
    debug_assert!(m >= n && b.len() == m);
    let data = a.as_mut_slice();
    let b = b.as_mut_slice();
    for j in 0..n {
        let (left, right) = data.split_at_mut((j + 1) * m);
        let v = &mut left[j * m + j..j * m + m];
        let norm = v.iter().map(|x| x * x).sum::<f64>().sqrt();
        if norm == 0.0 {
            continue;
        }
        let alpha = if v[0] > 0.0 { -norm } else { norm };
        v[0] -= alpha;
        // vᵀv = −2·α·v₀ (> 0 since α has the opposite sign of x₀); β = 2/vᵀv.
        let beta = -1.0 / (alpha * v[0]);
        for k in 0..n - j - 1 {
            let col = &mut right[k * m + j..k * m + m];
            let s = beta * dot(v, col);
            axpy(-s, v, col);
        }
        let tail = &mut b[j..];
        let s = beta * dot(v, tail);
        axpy(-s, v, tail);
        v[0] = alpha;
    }
}

fn dot(x: &[f64], y: &[f64]) -> f64 {
    x.iter().zip(y).map(|(a, b)| a * b).sum()
}

fn axpy(a: f64, x: &[f64], y: &mut [f64]) {
    for (yi, xi) in y.iter_mut().zip(x) {
        *yi += a * xi;
    }
}

/// Solves `R·x = c` for the upper-triangular `R` in the top `n × n` of `r`; a zero pivot gives
/// a zero component (it belongs to a parameter the residuals do not depend on).
pub(crate) fn back_substitute(r: &DMatrix<f64>, c: &[f64], x: &mut DVector<f64>) {
    let n = x.len();
    for i in (0..n).rev() {
        let mut s = c[i];
        for k in i + 1..n {
            s -= r[(i, k)] * x[k];
        }
        let d = r[(i, i)];
        x[i] = if d == 0.0 { 0.0 } else { s / d };
    }
}

/// Buffers for the damped subproblem `min ‖[R; √λ·D]·h + [Qᵀr; 0]‖`, reused across trials.
#[derive(Debug)]
pub(crate) struct DampedSolver {
    aug: DMatrix<f64>,
    rhs: DVector<f64>,
}

impl DampedSolver {
    pub(crate) fn new(n: usize) -> Self {
        Self { aug: DMatrix::zeros(2 * n, n), rhs: DVector::zeros(2 * n) }
    }

    /// Solves the Levenberg–Marquardt step `(RᵀR + λDᵀD)·h = −Rᵀ·qtr` through a QR of the
    /// augmented `2n × n` system (better conditioned than forming the normal equations).
    /// `r` holds `R` in its top `n × n` upper triangle; `qtr` is the first `n` entries of `Qᵀr`;
    /// parameters marked in `frozen` get a zero step.
    pub(crate) fn solve(
        &mut self,
        r: &DMatrix<f64>,
        qtr: &[f64],
        d: &DVector<f64>,
        lambda: f64,
        frozen: &[bool],
        h: &mut DVector<f64>,
    ) {
        let n = h.len();
        self.aug.fill(0.0);
        self.rhs.fill(0.0);
        let sqrt_lambda = lambda.sqrt();
        for col in 0..n {
            // A frozen parameter's column is left out of R, so only its damping row constrains
            // it: its step is exactly zero and the others solve the reduced problem.
            if !frozen[col] {
                for row in 0..=col {
                    self.aug[(row, col)] = r[(row, col)];
                }
            }
            self.aug[(n + col, col)] = sqrt_lambda * d[col];
            self.rhs[col] = -qtr[col];
        }
        householder_qr(&mut self.aug, &mut self.rhs);
        back_substitute(&self.aug, self.rhs.as_slice(), h);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn qr_solves_least_squares() {
        let a = DMatrix::from_row_slice(4, 2, &[1.0, 1.0, 1.0, 2.0, 1.0, 3.0, 1.0, 4.0]);
        let b = DVector::from_row_slice(&[6.0, 5.0, 7.0, 10.0]);
        let (mut qa, mut qb) = (a.clone(), b.clone());
        householder_qr(&mut qa, &mut qb);
        let mut x = DVector::zeros(2);
        back_substitute(&qa, qb.as_slice(), &mut x);
        let expected = (a.transpose() * &a).cholesky().unwrap().solve(&(a.transpose() * b));
        assert!((x - expected).norm() < 1e-12);
    }

    #[test]
    fn damped_step_matches_normal_equations() {
        let j = DMatrix::from_row_slice(3, 2, &[2.0, -1.0, 0.5, 3.0, 1.0, 1.0]);
        let r = DVector::from_row_slice(&[1.0, -2.0, 0.5]);
        let d = DVector::from_row_slice(&[2.0, 0.5]);
        let lambda = 0.3;
        let (mut qj, mut qr) = (j.clone(), r.clone());
        householder_qr(&mut qj, &mut qr);
        let mut h = DVector::zeros(2);
        DampedSolver::new(2).solve(&qj, &qr.as_slice()[..2], &d, lambda, &[false; 2], &mut h);
        let dd = DMatrix::from_diagonal(&d.component_mul(&d));
        let lhs = j.transpose() * &j + dd * lambda;
        let expected = lhs.cholesky().unwrap().solve(&(-(j.transpose() * r)));
        assert!((h - expected).norm() < 1e-12);
    }
}

//! The linearised I-optimal design criterion.
//!
//! For a model output y(x; p) with parameter covariance Σ, the variance of the predicted mean at
//! an operating point x is gᵀΣg, g = ∂y/∂p. Adding k measurements at points with sensitivities
//! J (k×n) and noise σ gives, to first order, Σ' = (Σ⁻¹ + JᵀJ/σ²)⁻¹, computed here in the
//! Woodbury form Σ' = Σ − ΣJᵀ(σ²I + JΣJᵀ)⁻¹JΣ, which needs no inverse of Σ (a covariance of
//! coefficients the data barely separate is close to singular). The value of the measurements
//! is the reduction of the mean prediction variance over an envelope grid with gradients G
//! (m×n): tr(H Σ) − tr(H Σ'), H = GᵀG / m (I-optimality: integrated prediction variance).

use nalgebra::{DMatrix, DVector};

/// H = GᵀG / m for a grid's gradient rows `g` (m×n): the mean grid variance of any covariance
/// Σ is then tr(H Σ).
pub fn grid_weight(g: &DMatrix<f64>) -> DMatrix<f64> {
    let m = g.nrows().max(1) as f64;
    g.transpose() * g / m
}

/// Mean prediction variance over the grid, tr(H Σ).
pub fn mean_variance(h: &DMatrix<f64>, cov: &DMatrix<f64>) -> f64 {
    // tr(HΣ) = Σ_ij H_ij Σ_ji; both symmetric.
    h.component_mul(cov).sum().max(0.0)
}

/// The covariance after adding measurements with sensitivities `j` (k×n), noise `sigma`:
/// (Σ⁻¹ + JᵀJ/σ²)⁻¹, symmetrised. Never larger than Σ (in the Loewner order).
///
/// In information form whenever Σ is positive definite: the covariance form
/// Σ − ΣJᵀ(σ²I + JΣJᵀ)⁻¹JΣ subtracts terms of Σ's size to leave one of σ²'s, and for a model
/// that knows little yet (variances of 1e20 and more) round-off left garbage larger than Σ
/// itself. The covariance form remains for a Σ that is only semi-definite.
pub fn updated(cov: &DMatrix<f64>, j: &DMatrix<f64>, sigma: f64) -> DMatrix<f64> {
    // Points the output does not depend on teach nothing, exactly.
    if j.nrows() == 0 || j.ncols() != cov.nrows() || j.iter().all(|v| *v == 0.0) {
        return cov.clone();
    }
    let s2 = (sigma * sigma).max(1e-300);
    let out = information_update(cov, j, s2).unwrap_or_else(|| covariance_update(cov, j, s2));
    // Round-off can leave it a hair asymmetric or a diagonal a hair negative.
    let mut out = (&out + out.transpose()) * 0.5;
    for i in 0..out.nrows() {
        if out[(i, i)] < 0.0 {
            out[(i, i)] = 0.0;
        }
    }
    out
}

fn information_update(cov: &DMatrix<f64>, j: &DMatrix<f64>, s2: f64) -> Option<DMatrix<f64>> {
    let info = cov.clone().cholesky()?.inverse() + j.transpose() * j / s2;
    let out = info.cholesky()?.inverse();
    out.iter().all(|v| v.is_finite()).then_some(out)
}

fn covariance_update(cov: &DMatrix<f64>, j: &DMatrix<f64>, s2: f64) -> DMatrix<f64> {
    let a = j * cov; // k×n = JΣ
    let mut s = &a * j.transpose(); // k×k = JΣJᵀ
    for i in 0..s.nrows() {
        s[(i, i)] += s2;
    }
    let solved = match s.clone().cholesky() {
        Some(c) => c.solve(&a),
        None => match s.try_inverse() {
            Some(inv) => inv * &a,
            None => return cov.clone(),
        },
    };
    cov - a.transpose() * solved
}

/// Reduction of the mean grid variance from adding `j` (never negative).
pub fn variance_reduction(h: &DMatrix<f64>, cov: &DMatrix<f64>, j: &DMatrix<f64>, sigma: f64) -> f64 {
    (mean_variance(h, cov) - mean_variance(h, &updated(cov, j, sigma))).max(0.0)
}

/// Rows of sensitivities as a matrix (k×n); rows of the wrong length are skipped.
pub fn rows(rows: &[DVector<f64>], n: usize) -> DMatrix<f64> {
    let ok: Vec<&DVector<f64>> = rows.iter().filter(|r| r.len() == n && r.iter().all(|v| v.is_finite())).collect();
    DMatrix::from_fn(ok.len(), n, |i, c| ok[i][c])
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cov2() -> DMatrix<f64> {
        DMatrix::from_row_slice(2, 2, &[4.0, 1.0, 1.0, 2.0])
    }

    #[test]
    fn woodbury_matches_the_information_form() {
        let c = cov2();
        let j = DMatrix::from_row_slice(3, 2, &[1.0, 0.5, 0.2, 1.0, -1.0, 0.3]);
        let s = 0.7;
        let info = c.clone().try_inverse().unwrap() + j.transpose() * &j / (s * s);
        let direct = info.try_inverse().unwrap();
        let w = updated(&c, &j, s);
        assert!((w - direct).abs().max() < 1e-12);
    }

    #[test]
    fn variance_never_increases_and_uninformative_points_add_nothing() {
        let c = cov2();
        let g = DMatrix::from_row_slice(3, 2, &[1.0, 0.0, 0.0, 1.0, 1.0, 1.0]);
        let h = grid_weight(&g);
        for j in [
            DMatrix::from_row_slice(1, 2, &[3.0, -2.0]),
            DMatrix::from_row_slice(2, 2, &[0.1, 0.0, 0.0, 0.1]),
            DMatrix::from_row_slice(1, 2, &[1e6, 1e6]),
        ] {
            let after = mean_variance(&h, &updated(&c, &j, 0.5));
            assert!(after <= mean_variance(&h, &c) + 1e-12);
        }
        // Points where the output does not depend on the parameters teach nothing.
        let zero = DMatrix::zeros(5, 2);
        assert!(variance_reduction(&h, &c, &zero, 0.5).abs() < 1e-15);
        // Nor does anything when the grid does not depend on what the points inform.
        let g1 = DMatrix::from_row_slice(1, 2, &[1.0, 0.0]);
        let diag = DMatrix::from_row_slice(2, 2, &[1.0, 0.0, 0.0, 1.0]);
        let only_p2 = DMatrix::from_row_slice(1, 2, &[0.0, 5.0]);
        assert!(variance_reduction(&grid_weight(&g1), &diag, &only_p2, 0.1).abs() < 1e-15);
    }

    #[test]
    fn repeating_the_same_points_is_worth_less_each_time() {
        let c = cov2();
        let h = grid_weight(&DMatrix::from_row_slice(2, 2, &[1.0, 0.2, 0.3, 1.0]));
        let j = DMatrix::from_row_slice(2, 2, &[1.0, 0.0, 0.0, 1.0]);
        let first = variance_reduction(&h, &c, &j, 1.0);
        let c1 = updated(&c, &j, 1.0);
        let second = variance_reduction(&h, &c1, &j, 1.0);
        assert!(first > 0.0 && second > 0.0 && second < first, "{first} {second}");
    }
}

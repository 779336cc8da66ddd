//! Solver options (a builder) and robust losses.

use nalgebra::DVector;

use crate::error::LsqError;

/// Robust loss `ρ(s)` applied to each squared residual `s = rᵢ²`; the cost is `½·Σ ρ(rᵢ²)`.
///
/// Each loss is quadratic (`ρ(s) ≈ s`) for `|r| ≪ δ` and grows more slowly beyond `δ`, the
/// residual size where a point starts to count as an outlier, in the residuals' units.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Loss {
    /// Plain least squares, `ρ(s) = s`.
    Linear,
    /// Huber: quadratic up to `δ`, linear beyond, `ρ(s) = 2δ√s − δ²`.
    Huber(f64),
    /// Smooth L1 (pseudo-Huber), `ρ(s) = 2δ²(√(1 + s/δ²) − 1)`.
    SoftL1(f64),
    /// Cauchy (Lorentzian), `ρ(s) = δ²·ln(1 + s/δ²)`: redescending influence, for gross outliers.
    Cauchy(f64),
}

impl Loss {
    /// `[ρ(s), ρ'(s)]` for a squared residual `s ≥ 0`.
    pub fn evaluate(&self, s: f64) -> [f64; 2] {
        match *self {
            Loss::Linear => [s, 1.0],
            Loss::Huber(d) => {
                if s <= d * d {
                    [s, 1.0]
                } else {
                    let r = s.sqrt();
                    [2.0 * d * r - d * d, d / r]
                }
            }
            Loss::SoftL1(d) => {
                let z = (1.0 + s / (d * d)).sqrt();
                // 2δ²(z − 1) rewritten as 2s/(z + 1): no cancellation for s ≪ δ².
                [2.0 * s / (z + 1.0), 1.0 / z]
            }
            Loss::Cauchy(d) => {
                let x = s / (d * d);
                [d * d * x.ln_1p(), 1.0 / (1.0 + x)]
            }
        }
    }

    fn scale(&self) -> Option<f64> {
        match *self {
            Loss::Linear => None,
            Loss::Huber(d) | Loss::SoftL1(d) | Loss::Cauchy(d) => Some(d),
        }
    }
}

/// How the damping term is scaled per parameter (the `D` in `(JᵀJ + λDᵀD)·h = −Jᵀr`).
#[derive(Debug, Clone, PartialEq)]
pub enum Scaling {
    /// `D = I`: damping in the parameters' own units.
    None,
    /// Moré's scaling: `Dⱼ` = the largest column norm of the Jacobian seen so far. Makes the
    /// solver invariant to the parameters' units (the default).
    Jacobian,
    /// Fixed, user-given typical magnitudes' inverses (`Dⱼ > 0`).
    Fixed(DVector<f64>),
}

/// Options for [`crate::solve`], built like `Options::default().max_iterations(50).ftol(1e-12)`.
#[derive(Debug, Clone, PartialEq)]
pub struct Options {
    /// Maximum outer iterations (Jacobian evaluations).
    pub max_iterations: usize,
    /// Maximum residual evaluations, finite differences included.
    pub max_evaluations: usize,
    /// Relative cost tolerance: converged when both the actual and the predicted relative
    /// reduction of the cost are below it.
    pub ftol: f64,
    /// Relative step tolerance: converged when `‖D·h‖ ≤ xtol·(‖D·p‖ + xtol)`.
    pub xtol: f64,
    /// Gradient tolerance: converged when the largest cosine between the residual vector and a
    /// free Jacobian column (the projected gradient) is below it.
    pub gtol: f64,
    /// Initial damping, relative to the largest scaled diagonal of `JᵀJ`.
    pub initial_damping: f64,
    /// Lower bounds per parameter (`-∞` for none).
    pub lower: Option<DVector<f64>>,
    /// Upper bounds per parameter (`+∞` for none).
    pub upper: Option<DVector<f64>>,
    /// Robust loss.
    pub loss: Loss,
    /// Damping scaling.
    pub scaling: Scaling,
    /// Relative step of the central differences, `hⱼ = step·max(|pⱼ|, typicalⱼ)` with the
    /// typical magnitude `1/Dⱼ` of a fixed scaling, else `|p₀ⱼ|` (1 where `p₀ⱼ = 0`); the default
    /// `ε^(1/3)` balances truncation and round-off error for central differences.
    pub diff_step: f64,
    /// Compare an analytic Jacobian with finite differences at the start (see the report).
    pub check_jacobian: bool,
}

impl Default for Options {
    fn default() -> Self {
        Self {
            max_iterations: 100,
            max_evaluations: 100_000,
            ftol: 1e-10,
            xtol: 1e-10,
            gtol: 1e-10,
            initial_damping: 1e-3,
            lower: None,
            upper: None,
            loss: Loss::Linear,
            scaling: Scaling::Jacobian,
            diff_step: f64::EPSILON.cbrt(),
            check_jacobian: false,
        }
    }
}

impl Options {
    /// Sets [`Options::max_iterations`].
    pub fn max_iterations(mut self, n: usize) -> Self {
        self.max_iterations = n;
        self
    }

    /// Sets [`Options::max_evaluations`].
    pub fn max_evaluations(mut self, n: usize) -> Self {
        self.max_evaluations = n;
        self
    }

    /// Sets [`Options::ftol`].
    pub fn ftol(mut self, tol: f64) -> Self {
        self.ftol = tol;
        self
    }

    /// Sets [`Options::xtol`].
    pub fn xtol(mut self, tol: f64) -> Self {
        self.xtol = tol;
        self
    }

    /// Sets [`Options::gtol`].
    pub fn gtol(mut self, tol: f64) -> Self {
        self.gtol = tol;
        self
    }

    /// Sets [`Options::initial_damping`].
    pub fn initial_damping(mut self, factor: f64) -> Self {
        self.initial_damping = factor;
        self
    }

    /// Sets both bound vectors.
    pub fn bounds(mut self, lower: DVector<f64>, upper: DVector<f64>) -> Self {
        self.lower = Some(lower);
        self.upper = Some(upper);
        self
    }

    /// Sets the lower bounds only.
    pub fn lower(mut self, lower: DVector<f64>) -> Self {
        self.lower = Some(lower);
        self
    }

    /// Sets the upper bounds only.
    pub fn upper(mut self, upper: DVector<f64>) -> Self {
        self.upper = Some(upper);
        self
    }

    /// Sets [`Options::loss`].
    pub fn loss(mut self, loss: Loss) -> Self {
        self.loss = loss;
        self
    }

    /// Sets [`Options::scaling`].
    pub fn scaling(mut self, scaling: Scaling) -> Self {
        self.scaling = scaling;
        self
    }

    /// Sets [`Options::diff_step`].
    pub fn diff_step(mut self, step: f64) -> Self {
        self.diff_step = step;
        self
    }

    /// Sets [`Options::check_jacobian`].
    pub fn check_jacobian(mut self, check: bool) -> Self {
        self.check_jacobian = check;
        self
    }

    /// Checks the options against a problem with `n` parameters; returns the bounds, with
    /// infinite defaults filled in.
    pub(crate) fn validate(&self, n: usize) -> Result<(DVector<f64>, DVector<f64>), LsqError> {
        let invalid = |name, value, expected| Err(LsqError::InvalidOption { name, value, expected });
        for (name, value) in [("ftol", self.ftol), ("xtol", self.xtol), ("gtol", self.gtol)] {
            if !(value >= 0.0 && value.is_finite()) {
                return invalid(name, value, "a finite tolerance >= 0");
            }
        }
        if !(self.initial_damping > 0.0 && self.initial_damping.is_finite()) {
            return invalid("initial_damping", self.initial_damping, "a finite value > 0");
        }
        if !(self.diff_step > 0.0 && self.diff_step < 1.0) {
            return invalid("diff_step", self.diff_step, "a relative step in (0, 1)");
        }
        if let Some(d) = self.loss.scale()
            && !(d > 0.0 && d.is_finite())
        {
            return invalid("loss", d, "a finite loss scale > 0");
        }
        if let Scaling::Fixed(d) = &self.scaling {
            if d.len() != n {
                return invalid("scaling", d.len() as f64, "one scale per parameter");
            }
            if let Some(&bad) = d.iter().find(|&&v| !(v > 0.0 && v.is_finite())) {
                return invalid("scaling", bad, "finite scales > 0");
            }
        }
        let lower = match &self.lower {
            Some(l) if l.len() != n => {
                return Err(LsqError::BoundsLength { which: "lower", len: l.len(), params: n });
            }
            Some(l) => l.clone(),
            None => DVector::from_element(n, f64::NEG_INFINITY),
        };
        let upper = match &self.upper {
            Some(u) if u.len() != n => {
                return Err(LsqError::BoundsLength { which: "upper", len: u.len(), params: n });
            }
            Some(u) => u.clone(),
            None => DVector::from_element(n, f64::INFINITY),
        };
        for index in 0..n {
            let (lo, up) = (lower[index], upper[index]);
            if lo.is_nan() || up.is_nan() || lo > up || lo == f64::INFINITY || up == f64::NEG_INFINITY {
                return Err(LsqError::InvalidBounds { index, lower: lo, upper: up });
            }
        }
        Ok((lower, upper))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn loss_derivatives_match_finite_differences() {
        for loss in [Loss::Linear, Loss::Huber(0.7), Loss::SoftL1(0.7), Loss::Cauchy(0.7)] {
            for s in [1e-3, 0.1, 0.45, 0.55, 2.0, 50.0] {
                let h = 1e-6 * s;
                let numeric = (loss.evaluate(s + h)[0] - loss.evaluate(s - h)[0]) / (2.0 * h);
                let [rho, d_rho] = loss.evaluate(s);
                assert!((d_rho - numeric).abs() < 1e-6, "{loss:?} at {s}: {d_rho} vs {numeric}");
                // Every loss is ≈ s near zero and grows no faster than s.
                assert!(rho <= s * (1.0 + 1e-12) && rho > 0.0, "{loss:?} at {s}");
            }
            let [rho, d_rho] = loss.evaluate(1e-12);
            assert!((rho / 1e-12 - 1.0).abs() < 1e-6 && (d_rho - 1.0).abs() < 1e-6);
        }
    }

    #[test]
    fn builder_sets_fields() {
        let o = Options::default().max_iterations(7).ftol(1e-3).loss(Loss::Huber(2.0)).check_jacobian(true);
        assert_eq!(o.max_iterations, 7);
        assert_eq!(o.ftol, 1e-3);
        assert_eq!(o.loss, Loss::Huber(2.0));
        assert!(o.check_jacobian);
        let (lo, up) = o.validate(2).unwrap();
        assert!(lo.iter().all(|v| *v == f64::NEG_INFINITY) && up.iter().all(|v| *v == f64::INFINITY));
    }
}

//! The solver on classic problems, bounds, robust losses, and invalid input.

mod common;

use std::cell::Cell;

use common::{BoxWatch, ExpDecay, Gauss, MagicCurve, Rosenbrock};
use lsq::{Convergence, Loss, LsqError, Options, Problem, Scaling, Termination, check_jacobian, solve};
use nalgebra::{DMatrix, DVector};

fn dv(v: &[f64]) -> DVector<f64> {
    DVector::from_row_slice(v)
}

#[test]
fn analytic_jacobians_agree_with_finite_differences() {
    let p = dv(&[-1.2, 1.0]);
    let check = check_jacobian(&Rosenbrock { analytic: true }, &p).unwrap();
    assert!(check.max_rel_error < 1e-7, "{check:?}");

    let exp = ExpDecay::with_noise([3.0, 0.7, 0.5], 200, 0.01, 1);
    let check = check_jacobian(&exp, &dv(&[2.0, 0.4, 1.0])).unwrap();
    assert!(check.max_rel_error < 1e-7, "{check:?}");

    let mf = MagicCurve::with_noise(500, 20.0, 2);
    for p in [[10.0, 1.6, 5000.0, -0.5], [5.0, 1.3, 4000.0, 0.9], [20.0, 1.9, 3000.0, -3.0]] {
        let check = check_jacobian(&mf, &dv(&p)).unwrap();
        assert!(check.max_rel_error < 1e-5, "{p:?}: {check:?}");
    }
}

/// The MF curve with a deliberately wrong ∂y/∂E (sign flipped).
struct WrongJacobian(MagicCurve);

impl Problem for WrongJacobian {
    fn num_residuals(&self) -> usize {
        self.0.num_residuals()
    }
    fn residuals(&self, p: &DVector<f64>, r: &mut DVector<f64>) {
        self.0.residuals(p, r);
    }
    fn jacobian(&self, p: &DVector<f64>, j: &mut DMatrix<f64>) -> bool {
        self.0.jacobian(p, j);
        j.column_mut(3).neg_mut();
        true
    }
}

#[test]
fn check_jacobian_catches_a_wrong_derivative() {
    let wrong = WrongJacobian(MagicCurve::with_noise(100, 0.0, 3));
    let check = check_jacobian(&wrong, &dv(&MagicCurve::TRUTH)).unwrap();
    assert!(check.max_rel_error > 0.5, "{check:?}");
    assert_eq!(check.col, 3);
    assert_eq!(
        check_jacobian(&Rosenbrock { analytic: false }, &dv(&[0.0, 0.0])).unwrap_err(),
        LsqError::NoAnalyticJacobian
    );
    // The report carries the check when asked for.
    let report =
        solve(&Rosenbrock { analytic: true }, dv(&[-1.2, 1.0]), &Options::default().check_jacobian(true)).unwrap();
    assert!(report.jacobian_check.unwrap().max_rel_error < 1e-7);
}

#[test]
fn rosenbrock_analytic_and_numeric() {
    for analytic in [true, false] {
        let report = solve(&Rosenbrock { analytic }, dv(&[-1.2, 1.0]), &Options::default()).unwrap();
        assert!(report.termination.converged(), "{report:?}");
        assert!((report.params[0] - 1.0).abs() < 1e-8, "{report:?}");
        assert!((report.params[1] - 1.0).abs() < 1e-8, "{report:?}");
        assert!(report.cost < 1e-20);
        assert!(report.initial_cost > 1.0);
        assert!(report.iterations < 100);
    }
}

#[test]
fn exponential_fit_with_noise() {
    let truth = [3.0, 0.7, 0.5];
    for analytic in [true, false] {
        let mut problem = ExpDecay::with_noise(truth, 200, 0.01, 4);
        problem.analytic = analytic;
        let report = solve(&problem, dv(&[1.0, 0.1, 0.0]), &Options::default()).unwrap();
        assert!(report.termination.converged(), "{report:?}");
        for (est, tru) in report.params.iter().zip(truth) {
            assert!((est - tru).abs() < 0.01, "{report:?}");
        }
        // The residual RMS matches the noise.
        let rms = (2.0 * report.cost / 200.0).sqrt();
        assert!((rms - 0.01).abs() < 0.002, "rms {rms}");
    }
}

#[test]
fn magic_formula_curve_with_noise_and_bounds() {
    let problem = MagicCurve::with_noise(1000, 25.0, 5);
    let lower = dv(&[1.0, 1.0, 0.0, -10.0]);
    let upper = dv(&[30.0, 2.0, 1e4, 1.0]);
    let watched = BoxWatch { inner: problem, lower: lower.clone(), upper: upper.clone(), violations: Cell::new(0) };
    let options = Options::default().bounds(lower, upper);
    // Starts far off, on both sides; long early steps hit the C and E bounds on the way.
    for p0 in [[5.0, 1.3, 4000.0, 0.0], [3.0, 1.1, 2000.0, 0.5], [20.0, 1.9, 6000.0, -3.0]] {
        let report = solve(&watched, dv(&p0), &options).unwrap();
        assert!(report.termination.converged(), "{report:?}");
        let truth = MagicCurve::TRUTH;
        let tolerances = [0.2, 0.02, 20.0, 0.1];
        for ((est, tru), tol) in report.params.iter().zip(truth).zip(tolerances) {
            assert!((est - tru).abs() < tol, "from {p0:?}: {report:?}");
        }
        assert!(report.active_bounds.is_empty());
    }
    assert_eq!(watched.violations.get(), 0);
}

#[test]
fn solution_on_a_bound_converges_with_the_bound_active() {
    // True C = 1.6, but C ≤ 1.5: the constrained optimum has C on its bound. (The constrained
    // problem has a second, much worse local minimum with E on its bound 1.0 too; starts from
    // far away can end there, as any local method would.)
    let mut problem = MagicCurve::with_noise(1000, 25.0, 6);
    let lower = dv(&[1.0, 1.0, 0.0, -10.0]);
    let upper = dv(&[30.0, 1.5, 1e4, 1.0]);
    for analytic in [true, false] {
        problem.analytic = analytic;
        let watched = BoxWatch { inner: problem, lower: lower.clone(), upper: upper.clone(), violations: Cell::new(0) };
        let options = Options::default().bounds(lower.clone(), upper.clone());
        let report = solve(&watched, dv(&[8.0, 1.4, 4500.0, -0.2]), &options).unwrap();
        assert!(report.termination.converged(), "{report:?}");
        assert_eq!(report.params[1], 1.5);
        assert_eq!(report.active_bounds, vec![1]);
        assert_eq!(watched.violations.get(), 0, "evaluated outside the box");
        problem = watched.inner;
    }
}

#[test]
fn numeric_jacobian_never_leaves_the_box() {
    /// r = p·tᵢ − yᵢ, undefined (NaN) for p < 0; the data want p = −1, so p ends on 0.
    struct NonNegative;
    impl Problem for NonNegative {
        fn num_residuals(&self) -> usize {
            5
        }
        fn residuals(&self, p: &DVector<f64>, r: &mut DVector<f64>) {
            for i in 0..5 {
                let t = i as f64;
                r[i] = if p[0] < 0.0 { f64::NAN } else { p[0] * t + t };
            }
        }
    }
    let report = solve(&NonNegative, dv(&[3.0]), &Options::default().lower(dv(&[0.0]))).unwrap();
    assert!(report.termination.converged(), "{report:?}");
    assert_eq!(report.params[0], 0.0);
    assert_eq!(report.active_bounds, vec![0]);
}

#[test]
fn robust_losses_win_against_outliers() {
    let truth = [3.0, 0.7, 0.5];
    let mut problem = ExpDecay::with_noise(truth, 200, 0.02, 7);
    let mut g = Gauss::new(8);
    // 10 % gross outliers, all on one side (a typical glitch or a spike), 1–3 units high.
    for i in (0..200).step_by(10) {
        problem.y[i] += 1.0 + 2.0 * g.uniform();
    }
    let p0 = dv(&[1.0, 0.1, 0.0]);
    let error = |p: &DVector<f64>| p.iter().zip(truth).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
    let plain = solve(&problem, p0.clone(), &Options::default()).unwrap();
    let plain_error = error(&plain.params);
    assert!(plain_error > 0.1, "plain least squares is pulled off: {plain:?}");
    for loss in [Loss::Huber(0.05), Loss::SoftL1(0.05), Loss::Cauchy(0.05)] {
        let report = solve(&problem, p0.clone(), &Options::default().loss(loss)).unwrap();
        assert!(report.termination.converged(), "{loss:?}: {report:?}");
        let robust_error = error(&report.params);
        assert!(
            robust_error < 0.05 && robust_error < plain_error / 5.0,
            "{loss:?}: error {robust_error} vs plain {plain_error}: {report:?}"
        );
    }
}

#[test]
fn badly_scaled_parameters() {
    // a ≈ 1e6, b ≈ 2e-6 1/s over a million seconds: seven orders apart.
    let truth = [1.0e6, 2.0e-6, 100.0];
    let t: Vec<f64> = (0..100).map(|i| 1e4 * i as f64).collect();
    let y = t.iter().map(|&t| ExpDecay::model(&truth, t)).collect();
    let problem = ExpDecay { t, y, analytic: false };
    let report = solve(&problem, dv(&[5e5, 1e-6, 0.0]), &Options::default()).unwrap();
    assert!(report.termination.converged(), "{report:?}");
    assert!((report.params[0] / truth[0] - 1.0).abs() < 1e-6, "{report:?}");
    assert!((report.params[1] / truth[1] - 1.0).abs() < 1e-6, "{report:?}");
    // Fixed scaling with the inverse typical magnitudes works as well.
    let options = Options::default().scaling(Scaling::Fixed(dv(&[1e-6, 5e5, 1e-2])));
    let report = solve(&problem, dv(&[5e5, 1e-6, 0.0]), &options).unwrap();
    assert!(report.termination.converged(), "{report:?}");
    assert!((report.params[1] / truth[1] - 1.0).abs() < 1e-6, "{report:?}");
}

#[test]
fn termination_reasons() {
    let report =
        solve(&Rosenbrock { analytic: true }, dv(&[-1.2, 1.0]), &Options::default().max_iterations(2)).unwrap();
    assert_eq!(report.termination, Termination::MaxIterations);
    assert_eq!(report.iterations, 2);

    let report =
        solve(&Rosenbrock { analytic: false }, dv(&[-1.2, 1.0]), &Options::default().max_evaluations(10)).unwrap();
    assert_eq!(report.termination, Termination::MaxEvaluations);

    // An exactly solvable problem started at its solution.
    let report = solve(&Rosenbrock { analytic: true }, dv(&[1.0, 1.0]), &Options::default()).unwrap();
    assert_eq!(report.termination, Termination::Converged { reason: Convergence::ZeroCost });
}

#[test]
fn start_outside_the_box_is_projected_and_fixed_parameters_stay() {
    let problem = ExpDecay::with_noise([3.0, 0.7, 0.5], 50, 0.0, 9);
    let options = Options::default().bounds(dv(&[0.0, 0.0, 0.5]), dv(&[10.0, 5.0, 0.5]));
    let report = solve(&problem, dv(&[20.0, -1.0, 3.0]), &options).unwrap();
    assert!(report.termination.converged(), "{report:?}");
    assert_eq!(report.params[2], 0.5);
    assert!((report.params[0] - 3.0).abs() < 1e-6 && (report.params[1] - 0.7).abs() < 1e-6);
    assert!(report.active_bounds.contains(&2));
}

#[test]
fn invalid_input_is_an_error() {
    let rb = Rosenbrock { analytic: true };
    let opts = Options::default();
    assert_eq!(solve(&rb, DVector::zeros(0), &opts).unwrap_err(), LsqError::NoParameters);
    assert!(matches!(
        solve(&rb, DVector::zeros(3), &opts).unwrap_err(),
        LsqError::Underdetermined { residuals: 2, params: 3 }
    ));
    assert!(matches!(solve(&rb, dv(&[f64::NAN, 0.0]), &opts).unwrap_err(), LsqError::NonFiniteStart { index: 0, .. }));
    let bad = Options::default().bounds(dv(&[0.0, 2.0]), dv(&[1.0, 1.0]));
    assert!(matches!(solve(&rb, dv(&[0.0, 0.0]), &bad).unwrap_err(), LsqError::InvalidBounds { index: 1, .. }));
    let bad = Options::default().lower(dv(&[0.0]));
    assert!(matches!(
        solve(&rb, dv(&[0.0, 0.0]), &bad).unwrap_err(),
        LsqError::BoundsLength { which: "lower", len: 1, params: 2 }
    ));
    let bad = Options::default().loss(Loss::Cauchy(0.0));
    assert!(matches!(solve(&rb, dv(&[0.0, 0.0]), &bad).unwrap_err(), LsqError::InvalidOption { name: "loss", .. }));
    let bad = Options::default().ftol(f64::NAN);
    assert!(matches!(solve(&rb, dv(&[0.0, 0.0]), &bad).unwrap_err(), LsqError::InvalidOption { name: "ftol", .. }));
    let nan_start = ExpDecay { t: vec![0.0, 1.0, 2.0], y: vec![0.0, f64::NAN, 0.0], analytic: true };
    assert!(matches!(
        solve(&nan_start, dv(&[1.0, 1.0, 0.0]), &opts).unwrap_err(),
        LsqError::NonFiniteResiduals { index: 1, .. }
    ));
}

#[test]
fn non_finite_trial_points_are_rejected_not_fatal() {
    /// A decay that returns NaN for b > 2 (an unstable region the solver must avoid).
    struct Fragile(ExpDecay);
    impl Problem for Fragile {
        fn num_residuals(&self) -> usize {
            self.0.num_residuals()
        }
        fn residuals(&self, p: &DVector<f64>, r: &mut DVector<f64>) {
            self.0.residuals(p, r);
            if p[1] > 2.0 {
                r.fill(f64::NAN);
            }
        }
        fn jacobian(&self, p: &DVector<f64>, j: &mut DMatrix<f64>) -> bool {
            self.0.jacobian(p, j)
        }
    }
    let problem = Fragile(ExpDecay::with_noise([3.0, 1.5, 0.5], 100, 0.0, 10));
    let report = solve(&problem, dv(&[0.1, 0.05, 3.0]), &Options::default()).unwrap();
    assert!(report.termination.converged(), "{report:?}");
    assert!((report.params[1] - 1.5).abs() < 1e-6, "{report:?}");
}

/// A dense linear problem with 40 parameters (the MF fits' size) against nalgebra's SVD.
struct Linear {
    a: DMatrix<f64>,
    b: DVector<f64>,
}

impl Problem for Linear {
    fn num_residuals(&self) -> usize {
        self.b.len()
    }
    fn residuals(&self, p: &DVector<f64>, r: &mut DVector<f64>) {
        self.a.mul_to(p, r);
        *r -= &self.b;
    }
    fn jacobian(&self, _p: &DVector<f64>, j: &mut DMatrix<f64>) -> bool {
        j.copy_from(&self.a);
        true
    }
}

#[test]
fn forty_parameters_match_a_direct_solve() {
    let (m, n) = (2000, 40);
    let mut g = Gauss::new(11);
    // Columns of very different scales, as MF coefficients have.
    let a = DMatrix::from_fn(m, n, |_, j| g.sample(1.0) * 10f64.powi((j % 7) as i32 - 3));
    let b = DVector::from_fn(m, |_, _| g.sample(1.0));
    let expected = a.clone().svd(true, true).solve(&b, 1e-14).unwrap();
    let problem = Linear { a, b };
    let report = solve(&problem, DVector::zeros(n), &Options::default()).unwrap();
    assert!(report.termination.converged(), "{report:?}");
    let rel = (&report.params - &expected).norm() / expected.norm();
    assert!(rel < 1e-8, "relative difference {rel}");
}

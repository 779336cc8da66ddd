//! Projected, scaled Levenberg–Marquardt with an active set for the bounds.

use nalgebra::{DMatrix, DVector};

use crate::error::LsqError;
use crate::jacobian::{DiffWorkspace, check_jacobian_within, numeric_jacobian, typical_magnitudes};
use crate::options::{Loss, Options, Scaling};
use crate::problem::Problem;
use crate::qr::{DampedSolver, householder_qr};
use crate::report::{Convergence, Report, Termination};

/// A step is accepted when it achieves at least this fraction of the predicted reduction.
const ACCEPT_RATIO: f64 = 1e-4;
/// Damping beyond this means no step of any length reduces the cost.
const MAX_DAMPING: f64 = 1e300;

/// Minimises `½·Σ ρ(rᵢ(p)²)` from `p0` within the bounds of `options`.
///
/// `p0` is projected onto the bounds first. Errors are returned only for invalid input (empty or
/// underdetermined problem, bad bounds or options, non-finite start); a fit that does not
/// converge returns a [`Report`] whose [`Termination`] says why.
pub fn solve<P: Problem + ?Sized>(problem: &P, p0: DVector<f64>, options: &Options) -> Result<Report, LsqError> {
    let n = p0.len();
    if n == 0 {
        return Err(LsqError::NoParameters);
    }
    let m = problem.num_residuals();
    if m < n {
        return Err(LsqError::Underdetermined { residuals: m, params: n });
    }
    let (lower, upper) = options.validate(n)?;
    if let Some((index, &value)) = p0.iter().enumerate().find(|(_, v)| !v.is_finite()) {
        return Err(LsqError::NonFiniteStart { index, value });
    }
    let typical = typical_magnitudes(
        &p0,
        match &options.scaling {
            Scaling::Fixed(d) => Some(d),
            Scaling::None | Scaling::Jacobian => None,
        },
    );
    let mut p = p0;
    project(&mut p, &lower, &upper);

    let mut r = DVector::zeros(m);
    evaluate(problem, &p, &mut r)?;
    if let Some((index, &value)) = r.iter().enumerate().find(|(_, v)| !v.is_finite()) {
        return Err(LsqError::NonFiniteResiduals { index, value });
    }
    let loss = options.loss;
    let mut cost = robust_cost(&r, loss);
    let initial_cost = cost;

    let jacobian_check = if options.check_jacobian {
        match check_jacobian_within(problem, &p, &lower, &upper, options.diff_step, &typical) {
            Ok(check) => Some(check),
            Err(LsqError::NoAnalyticJacobian) => None,
            Err(e) => return Err(e),
        }
    } else {
        None
    };

    // Every buffer is allocated once here; the loop only overwrites them. The m×n Jacobian is
    // factored in place, so the whole solve holds O(m·n) memory once.
    let mut jac = DMatrix::<f64>::zeros(m, n);
    let mut qtr = DVector::<f64>::zeros(m);
    let mut r_trial = DVector::<f64>::zeros(m);
    let mut p_trial = DVector::<f64>::zeros(n);
    let mut h = DVector::<f64>::zeros(n);
    let mut step = DVector::<f64>::zeros(n);
    let mut grad = DVector::<f64>::zeros(n);
    let mut col_norm = DVector::<f64>::zeros(n);
    let mut d = match &options.scaling {
        Scaling::Fixed(d) => d.clone(),
        Scaling::None | Scaling::Jacobian => DVector::from_element(n, 1.0),
    };
    let mut active = vec![false; n];
    let mut frozen = vec![false; n];
    let mut diff = DiffWorkspace::new(m, n);
    let mut damped = DampedSolver::new(n);

    let mut evaluations = 1;
    let mut iterations = 0;
    let mut jacobian_evaluations = 0;
    let mut use_analytic = true;
    let mut lambda = 0.0;
    let mut nu = 2.0;
    let mut gradient_norm = f64::INFINITY;

    let termination = 'outer: loop {
        if cost == 0.0 {
            gradient_norm = 0.0;
            break Termination::Converged { reason: Convergence::ZeroCost };
        }
        if iterations >= options.max_iterations {
            break Termination::MaxIterations;
        }
        if evaluations >= options.max_evaluations {
            break Termination::MaxEvaluations;
        }
        iterations += 1;

        jac.fill(0.0);
        if use_analytic {
            use_analytic = problem.jacobian(&p, &mut jac);
            if !use_analytic {
                jac.fill(0.0);
            }
        }
        if !use_analytic {
            evaluations +=
                numeric_jacobian(problem, &p, &r, &lower, &upper, options.diff_step, &typical, &mut diff, &mut jac);
        }
        jacobian_evaluations += 1;
        if jac.iter().any(|v| !v.is_finite()) {
            break Termination::NoProgress;
        }

        // Robust loss by iteratively reweighted least squares: row i of the Gauss–Newton model
        // is scaled by √ρ'(rᵢ²). (The Triggs second-order correction is used by Ceres only
        // where ρ'' > 0; none of these losses has that, so it reduces to this reweighting.)
        qtr.copy_from(&r);
        if loss != Loss::Linear {
            for i in 0..m {
                let w = loss.evaluate(r[i] * r[i])[1].sqrt();
                r_trial[i] = w;
                qtr[i] *= w;
            }
            for mut col in jac.column_iter_mut() {
                col.component_mul_assign(&r_trial);
            }
        }

        for (col_idx, col) in jac.column_iter().enumerate() {
            grad[col_idx] = col.dot(&qtr);
            col_norm[col_idx] = col.norm();
        }
        if options.scaling == Scaling::Jacobian {
            for j in 0..n {
                // Moré's rule: the scale only grows, which keeps the trust region from
                // collapsing when a column's norm dips.
                let c = if col_norm[j] > 0.0 { col_norm[j] } else { 1.0 };
                d[j] = if iterations == 1 { c } else { d[j].max(c) };
            }
        }

        // Active set: a parameter on a bound whose descent direction points out of the box is
        // held there for this iteration; the others move freely and are projected afterwards.
        let r_norm = qtr.norm();
        gradient_norm = 0.0;
        for j in 0..n {
            let at_lower = p[j] <= lower[j];
            let at_upper = p[j] >= upper[j];
            active[j] = (at_lower && (at_upper || grad[j] > 0.0)) || (at_upper && grad[j] < 0.0);
            if !active[j] && col_norm[j] > 0.0 && r_norm > 0.0 {
                gradient_norm = gradient_norm.max(grad[j].abs() / (col_norm[j] * r_norm));
            }
        }
        if gradient_norm <= options.gtol {
            break Termination::Converged { reason: Convergence::Gradient };
        }
        for (j, _) in active.iter().enumerate().filter(|(_, is_active)| **is_active) {
            jac.column_mut(j).fill(0.0);
        }

        householder_qr(&mut jac, &mut qtr);
        if iterations == 1 {
            let mut max_diag: f64 = 0.0;
            for j in 0..n {
                if !active[j] {
                    max_diag = max_diag.max((col_norm[j] / d[j]).powi(2));
                }
            }
            lambda = options.initial_damping * if max_diag > 0.0 { max_diag } else { 1.0 };
        }

        loop {
            // Truncate the step at the first bound it crosses (as in dogbox) and put the
            // parameter that hits it exactly on the bound, so it can join the active set.
            // (Projecting every coordinate instead lets the long early Gauss–Newton steps pin
            // parameters to bounds while the others move on, which strands fits in false
            // constrained minima.) A parameter already on a bound that the step would push
            // through is frozen for this trial and the step recomputed without it.
            frozen.copy_from_slice(&active);
            let (alpha, hit) = loop {
                damped.solve(&jac, &qtr.as_slice()[..n], &d, lambda, &frozen, &mut h);
                let mut alpha: f64 = 1.0;
                let mut hit = None;
                for j in 0..n {
                    if frozen[j] || h[j] == 0.0 {
                        continue;
                    }
                    let bound = if h[j] > 0.0 { upper[j] } else { lower[j] };
                    let fraction = (bound - p[j]) / h[j];
                    if fraction < alpha {
                        alpha = fraction.max(0.0);
                        hit = Some((j, bound));
                    }
                }
                match hit {
                    Some((j, _)) if alpha == 0.0 => frozen[j] = true,
                    _ => break (alpha, hit),
                }
            };
            for j in 0..n {
                p_trial[j] = if frozen[j] { p[j] } else { (p[j] + alpha * h[j]).clamp(lower[j], upper[j]) };
            }
            if let Some((j, bound)) = hit {
                p_trial[j] = bound;
            }
            for j in 0..n {
                step[j] = p_trial[j] - p[j];
            }
            // Predicted reduction of the (reweighted) Gauss–Newton model for the actual step:
            // ½‖Qᵀr‖² − ½‖Qᵀr + R·s‖² over the first n rows (the rest does not depend on s).
            let mut predicted = 0.0;
            for i in 0..n {
                let mut rs_i = 0.0;
                for j in i..n {
                    rs_i += jac[(i, j)] * step[j];
                }
                predicted -= qtr[i] * rs_i + 0.5 * rs_i * rs_i;
            }
            let (mut step_norm, mut p_norm) = (0.0_f64, 0.0_f64);
            for j in 0..n {
                step_norm = step_norm.hypot(d[j] * step[j]);
                p_norm = p_norm.hypot(d[j] * p[j]);
            }
            let small_step = step_norm <= options.xtol * (p_norm + options.xtol);

            if predicted > 0.0 && step_norm > 0.0 {
                evaluate(problem, &p_trial, &mut r_trial)?;
                evaluations += 1;
                let trial_cost = robust_cost(&r_trial, loss);
                let ratio = (cost - trial_cost) / predicted;
                let actual_rel = (cost - trial_cost) / cost;
                let predicted_rel = predicted / cost;
                let accepted = ratio > ACCEPT_RATIO;
                if accepted {
                    // Nielsen's damping update: smooth in the gain ratio.
                    lambda *= (1.0 / 3.0_f64).max(1.0 - (2.0 * ratio - 1.0).powi(3));
                    nu = 2.0;
                    std::mem::swap(&mut p, &mut p_trial);
                    std::mem::swap(&mut r, &mut r_trial);
                    cost = trial_cost;
                } else {
                    lambda *= nu;
                    nu *= 2.0;
                }
                if actual_rel.abs() <= options.ftol && predicted_rel <= options.ftol && ratio <= 2.0 {
                    break 'outer Termination::Converged { reason: Convergence::Cost };
                }
                if small_step {
                    break 'outer Termination::Converged { reason: Convergence::Step };
                }
                if accepted {
                    continue 'outer;
                }
            } else {
                if small_step {
                    break 'outer Termination::Converged { reason: Convergence::Step };
                }
                lambda *= nu;
                nu *= 2.0;
            }
            if lambda >= MAX_DAMPING || lambda.is_nan() {
                break 'outer Termination::NoProgress;
            }
            if evaluations >= options.max_evaluations {
                break 'outer Termination::MaxEvaluations;
            }
        }
    };

    let active_bounds = (0..n).filter(|&j| p[j] <= lower[j] || p[j] >= upper[j]).collect();
    Ok(Report {
        params: p,
        cost,
        initial_cost,
        iterations,
        evaluations,
        jacobian_evaluations,
        termination,
        gradient_norm,
        active_bounds,
        jacobian_check,
    })
}

fn project(p: &mut DVector<f64>, lower: &DVector<f64>, upper: &DVector<f64>) {
    for j in 0..p.len() {
        p[j] = p[j].clamp(lower[j], upper[j]);
    }
}

fn evaluate<P: Problem + ?Sized>(problem: &P, p: &DVector<f64>, r: &mut DVector<f64>) -> Result<(), LsqError> {
    let expected = r.len();
    problem.residuals(p, r);
    if r.len() != expected {
        return Err(LsqError::ResidualLength { len: r.len(), expected });
    }
    Ok(())
}

/// `½·Σ ρ(rᵢ²)`; infinite if any residual is not finite, so such a point is never accepted.
pub(crate) fn robust_cost(r: &DVector<f64>, loss: Loss) -> f64 {
    let mut sum = 0.0;
    for &ri in r.iter() {
        if !ri.is_finite() {
            return f64::INFINITY;
        }
        sum += match loss {
            Loss::Linear => ri * ri,
            _ => loss.evaluate(ri * ri)[0],
        };
    }
    0.5 * sum
}

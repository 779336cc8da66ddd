//! Residuals, the noise floor, fitting extensions (bounded Levenberg–Marquardt) and
//! cross-validated scoring on held-out sweeps.

use crate::effects::{CH_FX, CH_FY, CH_MZ, CH_RL, Effect, EffectParams, Evaluator, ParamSpec};
use lsq::{Options, Problem, solve};
use nalgebra::DVector;

/// Measured [FX, FYW, MZW, DSTWOWHC] at every point (NaN where invalid).
pub fn measured(ev: &Evaluator<'_>) -> Vec<[f64; 4]> {
    let s = &ev.ds.series;
    ev.ds.points.iter().map(|&i| [s.fx_n[i], s.fy_n[i], s.mz_nm[i], s.rl_m[i]]).collect()
}

/// Robust noise floor per channel from the data itself: the second difference of the base
/// model's residual along each sweep, d = r_k − (r_{k−1} + r_{k+1})/2, removes everything that
/// varies smoothly over the test (the effects being looked for) and keeps the point-to-point
/// scatter (sensor noise and the noise of the measured inputs propagated through the model);
/// σ = 1.4826·MAD(d)/√1.5. DSTWOWHC is floored at its 0.1 mm quantisation (0.1/√12 mm), where
/// the median difference is often exactly zero.
pub fn noise_floor(ev: &Evaluator<'_>, meas: &[[f64; 4]], pred: &[[f64; 4]]) -> [f64; 4] {
    let n = meas.len();
    let mut out = [0.0; 4];
    for (ch, o) in out.iter_mut().enumerate() {
        let mut d = Vec::new();
        for k in 1..n.saturating_sub(1) {
            let (a, b, c) = (k - 1, k, k + 1);
            if ev.ds.point_sweep(a) != ev.ds.point_sweep(b) || ev.ds.point_sweep(c) != ev.ds.point_sweep(b) {
                continue;
            }
            let r = |j: usize| meas[j][ch] - pred[j][ch];
            let v = r(b) - 0.5 * (r(a) + r(c));
            if v.is_finite() {
                d.push(v.abs());
            }
        }
        let floor = match ch {
            CH_RL => 0.1e-3 / 12f64.sqrt(),
            CH_FX | CH_FY => 1.0,
            CH_MZ => 0.05,
            _ => 1e-9,
        };
        *o = if d.is_empty() {
            floor
        } else {
            d.sort_by(f64::total_cmp);
            (1.4826 * d[d.len() / 2] / 1.5f64.sqrt()).max(floor)
        };
    }
    out
}

/// χ² of predictions against measurements over `which` (points), per channel.
pub fn chi2(meas: &[[f64; 4]], pred: &[[f64; 4]], sigma: &[f64; 4], which: &[usize]) -> [f64; 4] {
    let mut c = [0.0; 4];
    for &k in which {
        for ch in 0..4 {
            let r = (meas[k][ch] - pred[k][ch]) / sigma[ch];
            if r.is_finite() {
                c[ch] += r * r;
            }
        }
    }
    c
}

/// Number of finite residuals over `which`.
pub fn count_valid(meas: &[[f64; 4]], which: &[usize]) -> usize {
    which.iter().map(|&k| meas[k].iter().filter(|v| v.is_finite()).count()).sum()
}

/// One effect of a fit: its parameter specs.
#[derive(Debug, Clone)]
pub struct FitSpec {
    /// The effect.
    pub effect: Effect,
    /// Its parameters.
    pub params: Vec<ParamSpec>,
}

struct FitProblem<'e, 'a> {
    ev: &'e Evaluator<'a>,
    specs: &'e [FitSpec],
    /// Effects held at their values (the state effects fitted through their sensitivities).
    fixed: &'e [EffectParams],
    train: &'e [usize],
    meas: &'e [[f64; 4]],
    sigma: [f64; 4],
}

impl FitProblem<'_, '_> {
    fn unpack(&self, p: &DVector<f64>) -> Vec<EffectParams> {
        let mut at = 0;
        self.specs
            .iter()
            .map(|s| {
                let n = s.params.len();
                let e = EffectParams {
                    effect: s.effect,
                    keys: s.params.iter().map(|p| p.key.clone()).collect(),
                    values: p.as_slice()[at..at + n].to_vec(),
                };
                at += n;
                e
            })
            .collect()
    }
}

impl Problem for FitProblem<'_, '_> {
    fn num_residuals(&self) -> usize {
        4 * self.train.len()
    }

    fn residuals(&self, p: &DVector<f64>, r: &mut DVector<f64>) {
        let mut effects = self.unpack(p);
        effects.extend(self.fixed.iter().cloned());
        let pred = self.ev.predict(&effects, self.train);
        for (j, (&k, pr)) in self.train.iter().zip(&pred).enumerate() {
            for ch in 0..4 {
                let v = (self.meas[k][ch] - pr[ch]) / self.sigma[ch];
                r[4 * j + ch] = if self.meas[k][ch].is_finite() { v } else { 0.0 };
            }
        }
    }
}

/// Fit settings.
#[derive(Debug, Clone, Copy)]
pub struct FitOptions {
    /// Levenberg–Marquardt iterations per fit.
    pub max_iterations: usize,
}

impl Default for FitOptions {
    fn default() -> Self {
        Self { max_iterations: 25 }
    }
}

/// Fits the parameters of `specs` jointly on the points `train`, with the effects `fixed` held
/// at their values. Returns the fitted effects (of `specs`) and the cost ½χ².
pub fn fit_effects(
    ev: &Evaluator<'_>,
    specs: &[FitSpec],
    fixed: &[EffectParams],
    train: &[usize],
    meas: &[[f64; 4]],
    sigma: [f64; 4],
    opt: FitOptions,
) -> (Vec<EffectParams>, f64) {
    let p0 = DVector::from_iterator(
        specs.iter().map(|s| s.params.len()).sum(),
        specs.iter().flat_map(|s| s.params.iter().map(|p| p.init)),
    );
    let lo = DVector::from_iterator(p0.len(), specs.iter().flat_map(|s| s.params.iter().map(|p| p.lower)));
    let up = DVector::from_iterator(p0.len(), specs.iter().flat_map(|s| s.params.iter().map(|p| p.upper)));
    let prob = FitProblem { ev, specs, fixed, train, meas, sigma };
    let options = Options::default().max_iterations(opt.max_iterations).bounds(lo, up);
    let (params, cost) = match solve(&prob, p0.clone(), &options) {
        Ok(rep) => (rep.params, rep.cost),
        // Only invalid input (empty data, no parameters) errors; keep the start, "no change".
        Err(_) => (p0, f64::INFINITY),
    };
    (prob.unpack(&params), cost)
}

/// The points of every fold but `fi`: fold `fi`'s training points.
pub fn training(folds: &[Vec<usize>], fi: usize) -> Vec<usize> {
    folds.iter().enumerate().filter(|(j, _)| *j != fi).flat_map(|(_, v)| v.iter().copied()).collect()
}

/// Held-out folds: the sweeps, in a fixed pseudo-random order, dealt round-robin into `k`
/// folds (balanced: fold sizes differ by at most one sweep).
///
/// Not the sweep ordinal modulo `k`: test plans are periodic (a TTC drive/brake run cycles four
/// loads per slip-angle/camber cell), and with four folds every fold would then hold exactly one
/// load — each held-out fold an extrapolation in load, and an effect that varies with load
/// (heating does) would fail every fold however right it is. The order is a fixed permutation
/// (a hash of the ordinal), so a diagnosis is deterministic. Nor blocks of consecutive sweeps
/// (each log's first sweeps in different folds): more effects found, but states that drift with
/// time then fit each other's drift and false names were added (docs/doctor-benchmark.md, "Fold
/// plans that spread each log's first sweeps").
pub fn folds(ev: &Evaluator<'_>, k: usize) -> Vec<Vec<usize>> {
    let k = k.max(1);
    let fold_of = sweep_folds(ev.ds.sweeps.len(), k);
    let mut f = vec![Vec::new(); k];
    for p in 0..ev.ds.len() {
        let sw = ev.ds.point_sweep(p);
        f[fold_of.get(sw).copied().unwrap_or(sw % k)].push(p);
    }
    f.retain(|v| !v.is_empty());
    f
}

/// Fold of each of `n` sweeps: ordinals sorted by a 64-bit mix of the ordinal (splitmix64's
/// finaliser), then dealt round-robin into `k` folds.
fn sweep_folds(n: usize, k: usize) -> Vec<usize> {
    let mut order: Vec<usize> = (0..n).collect();
    order.sort_by_key(|&i| splitmix64(i as u64));
    let mut fold_of = vec![0; n];
    for (pos, &sw) in order.iter().enumerate() {
        fold_of[sw] = pos % k;
    }
    fold_of
}

/// splitmix64's step and finaliser: a fixed, well-mixed pseudo-random sequence, so that a
/// diagnosis (its folds, its bootstrap) is reproducible.
pub(crate) fn splitmix64(x: u64) -> u64 {
    let mut z = x.wrapping_add(0x9e37_79b9_7f4a_7c15);
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

/// Cross-validated predictions: every point predicted by the fit that did not see its sweep.
pub fn cross_validate(
    ev: &Evaluator<'_>,
    specs: &[FitSpec],
    fixed: &[EffectParams],
    folds: &[Vec<usize>],
    meas: &[[f64; 4]],
    sigma: [f64; 4],
    opt: FitOptions,
) -> Vec<[f64; 4]> {
    cross_validate_with(ev, specs, fixed, folds, meas, sigma, opt, None)
}

/// Cross-validated predictions against the form error ([`crate::form`]): for each held-out
/// fold the effects are fitted to the training points' measurements less their correction
/// (from the other training sweeps), and the held-out points are predicted with theirs added.
#[allow(clippy::too_many_arguments)]
pub fn cross_validate_corrected(
    ev: &Evaluator<'_>,
    specs: &[FitSpec],
    fixed: &[EffectParams],
    folds: &[Vec<usize>],
    meas: &[[f64; 4]],
    sigma: [f64; 4],
    opt: FitOptions,
    correction: &[crate::form::FoldCorrection],
) -> Vec<[f64; 4]> {
    cross_validate_with(ev, specs, fixed, folds, meas, sigma, opt, Some(correction))
}

#[allow(clippy::too_many_arguments)]
fn cross_validate_with(
    ev: &Evaluator<'_>,
    specs: &[FitSpec],
    fixed: &[EffectParams],
    folds: &[Vec<usize>],
    meas: &[[f64; 4]],
    sigma: [f64; 4],
    opt: FitOptions,
    correction: Option<&[crate::form::FoldCorrection]>,
) -> Vec<[f64; 4]> {
    let mut out = vec![[f64::NAN; 4]; ev.ds.len()];
    for (fi, test) in folds.iter().enumerate() {
        let corr = match correction {
            Some(c) => match c.get(fi) {
                Some(f) => Some(f),
                None => continue,
            },
            None => None,
        };
        let train = training(folds, fi);
        let target: Vec<[f64; 4]> = match corr {
            Some(c) => meas.iter().zip(c).map(|(m, c)| std::array::from_fn(|ch| m[ch] - c[ch])).collect(),
            None => meas.to_vec(),
        };
        let (mut fitted, _) = fit_effects(ev, specs, fixed, &train, &target, sigma, opt);
        fitted.extend(fixed.iter().cloned());
        for (k, p) in test.iter().zip(ev.predict(&fitted, test)) {
            out[*k] = match corr {
                Some(c) => std::array::from_fn(|ch| p[ch] + c[*k][ch]),
                None => p,
            };
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::sweep_folds;

    #[test]
    fn folds_are_balanced_and_do_not_alias_a_periodic_plan() {
        // A TTC drive/brake plan: 9 slip-angle/camber cells × 4 loads, loads cycling.
        let f = sweep_folds(36, 4);
        for fold in 0..4 {
            let sweeps: Vec<usize> = (0..36).filter(|&s| f[s] == fold).collect();
            assert_eq!(sweeps.len(), 9, "fold {fold}: {sweeps:?}");
            let loads: std::collections::BTreeSet<usize> = sweeps.iter().map(|s| s % 4).collect();
            assert!(loads.len() >= 3, "fold {fold} holds loads {loads:?} only");
        }
        // Deterministic.
        assert_eq!(f, sweep_folds(36, 4));
    }
}

//! Fitting whole-tyre state effects by linear least squares through the scaling factors'
//! sensitivities.
//!
//! A state effect's coefficients enter the model through the logarithms of the MF scaling
//! factors ([`crate::state`]). At the present model the change of each channel per unit of a
//! factor's logarithm, S_f(k) = ∂pred_k/∂ln λ_f, is one model evaluation per factor (eight in
//! all, whatever the number of coefficients), and to first order
//!
//!   pred_k(c) ≈ pred_k(c₀) + Σ_{f,b} S_f(k)·φ_b(z_k)·(c_{f,b} − c₀_{f,b}),
//!
//! linear in the coefficients (the loaded radius is exactly linear). So every state candidate
//! of a round shares one set of sensitivities; a candidate's fit is a small normal-equation
//! solve, its discrete choices (a temperature lag, break-in's energy scale) cost a solve each,
//! and cross-validation only removes a fold's rows. A Gauss–Newton step re-linearises at the
//! fitted coefficients, so large effects (a quarter of the grip) are fitted as well as small
//! ones, and the held-out predictions are linearised at the all-sweeps fit, from which each
//! fold's fit differs little.

use crate::effects::{CH_RL, Effect, EffectParams, Evaluator, Perturb};
use crate::state::{self, Choice, Term};
use nalgebra::{DMatrix, DVector};

/// Prior standard deviation of a state effect's change of a factor's logarithm at the
/// largest state the data reach (a factor of e^±0.3), and of the loaded radius [mm]: a
/// coefficient the data barely determine stays near zero instead of extrapolating into the
/// held-out sweeps (with fourteen coefficients and four folds that happened, and a held-out
/// fold's χ² grew sevenfold).
const PRIOR_LOG_FACTOR: f64 = 0.3;
const PRIOR_RADIUS_MM: f64 = 3.0;

/// Step of a factor's logarithm for the sensitivities.
const LOG_STEP: f64 = 1e-4;
/// Gauss–Newton steps after the first linear solve.
const GN_STEPS: usize = 1;

/// Predictions and per-factor sensitivities of a model at every point.
#[derive(Debug, Clone)]
pub struct Linearization {
    /// Predictions [FX, FYW, MZW, DSTWOWHC].
    pub pred: Vec<[f64; 4]>,
    /// ∂pred/∂ln λ_f per [`state::SCALING`] factor.
    pub sens: Vec<[[f64; 4]; 8]>,
}

/// Linearises the model with `effects` at every point (nine model evaluations per point).
pub fn linearize(ev: &Evaluator<'_>, effects: &[EffectParams]) -> Linearization {
    let all: Vec<usize> = (0..ev.ds.len()).collect();
    let pred = ev.predict(effects, &all);
    let mut sens = vec![[[0.0; 4]; 8]; all.len()];
    for (f, _) in state::SCALING.iter().enumerate() {
        let up = ev.predict_perturbed(effects, &all, Some(Perturb { factor: f, log_step: LOG_STEP }));
        for (k, (u, p)) in up.iter().zip(&pred).enumerate() {
            sens[k][f] = std::array::from_fn(|ch| {
                let d = (u[ch] - p[ch]) / LOG_STEP;
                if d.is_finite() { d } else { 0.0 }
            });
        }
    }
    Linearization { pred, sens }
}

/// One column of the design: a term of one of the effects being fitted, with its basis values
/// at every point.
#[derive(Debug, Clone)]
pub struct Column {
    /// Index of the effect in the fitted list.
    pub slot: usize,
    /// The term.
    pub term: Term,
    /// φ at every point.
    pub phi: Vec<f64>,
    /// Precision (1/sd²) of the coefficient's zero-mean prior.
    pub prior_precision: f64,
    /// The sign the coefficient must keep ([`state::sign_bound`]).
    pub sign: Option<state::Sign>,
}

/// The state effects being fitted together: their choices and terms as design columns.
#[derive(Debug, Clone)]
pub struct Design {
    /// The effects with their present coefficients (the linearisation point).
    pub effects: Vec<EffectParams>,
    /// Columns.
    pub cols: Vec<Column>,
}

impl Design {
    /// A design for `effects` (state-scaling effects with their present coefficients) whose
    /// terms are `terms[i]` (a new effect's terms start at 0).
    pub fn new(ev: &Evaluator<'_>, effects: Vec<EffectParams>, terms: &[Vec<Term>]) -> Self {
        let mut cols = Vec::new();
        for (slot, (e, ts)) in effects.iter().zip(terms).enumerate() {
            let choice = e.parsed().choice;
            let mut cache: Vec<(u8, Vec<f64>)> = Vec::new();
            for &t in ts {
                let phi = match cache.iter().find(|(b, _)| *b == t.basis) {
                    Some((_, v)) => v.clone(),
                    None => {
                        let v = ev.basis_at_points(e.effect, t.basis, &choice);
                        cache.push((t.basis, v.clone()));
                        v
                    }
                };
                // The prior is on the state's own range, also where the fit sees it with the
                // operating point's share taken out.
                let raw;
                let range = if ev.partialled(e.effect) {
                    raw = ev.raw_basis_at_points(e.effect, t.basis, &choice);
                    &raw
                } else {
                    &phi
                };
                let phi_max = range.iter().fold(0.0f64, |m, v| m.max(v.abs())).max(1e-9);
                let sd = if t.factor == state::Factor::Radius { PRIOR_RADIUS_MM } else { PRIOR_LOG_FACTOR } / phi_max;
                cols.push(Column {
                    slot,
                    term: t,
                    phi,
                    prior_precision: 1.0 / (sd * sd),
                    sign: state::sign_bound(e.effect, t),
                });
            }
        }
        Self { effects, cols }
    }

    /// Row of the design at point `k`, channel `ch`.
    fn row(&self, lin: &Linearization, k: usize, ch: usize, out: &mut [f64]) {
        for (o, c) in out.iter_mut().zip(&self.cols) {
            *o = if c.term.factor == state::Factor::Radius {
                if ch == CH_RL { 1e-3 * c.phi[k] } else { 0.0 }
            } else {
                c.term.factor.scaling_indices().iter().map(|&f| lin.sens[k][f][ch]).sum::<f64>() * c.phi[k]
            };
        }
    }

    /// The effects with their coefficients moved by `delta` (one value per column).
    pub fn updated(&self, delta: &DVector<f64>) -> Vec<EffectParams> {
        let mut out = self.effects.clone();
        for (c, d) in self.cols.iter().zip(delta.iter()) {
            let e = &mut out[c.slot];
            let key = state::term_key(e.effect, c.term);
            match e.keys.iter().position(|k| *k == key) {
                Some(i) => e.values[i] += d,
                None => {
                    e.keys.push(key);
                    e.values.push(*d);
                }
            }
        }
        out
    }
}

/// Normal equations over a set of points.
#[derive(Debug, Clone)]
struct Normal {
    a: DMatrix<f64>,
    b: DVector<f64>,
}

/// Accumulates JᵀWJ and JᵀW(target − pred) over `which`, with `target(k)` the measured values
/// (less any correction) at point `k`.
fn normal(
    design: &Design,
    lin: &Linearization,
    which: &[usize],
    target: &dyn Fn(usize) -> [f64; 4],
    sigma: &[f64; 4],
) -> Normal {
    let m = design.cols.len();
    let mut a = DMatrix::<f64>::zeros(m, m);
    let mut b = DVector::<f64>::zeros(m);
    let mut row = vec![0.0; m];
    for &k in which {
        let t = target(k);
        for ch in 0..4 {
            let r = (t[ch] - lin.pred[k][ch]) / sigma[ch];
            if !r.is_finite() {
                continue;
            }
            design.row(lin, k, ch, &mut row);
            for i in 0..m {
                let ri = row[i] / sigma[ch];
                if ri == 0.0 {
                    continue;
                }
                b[i] += ri * r;
                for j in 0..=i {
                    a[(i, j)] += ri * row[j] / sigma[ch];
                }
            }
        }
    }
    for i in 0..m {
        for j in 0..i {
            a[(j, i)] = a[(i, j)];
        }
    }
    // The prior: ½·Σ p_i·(c0_i + Δ_i)², c0 the design's present coefficients.
    for (i, c) in design.cols.iter().enumerate() {
        let e = &design.effects[c.slot];
        let c0 = e.get(&state::term_key(e.effect, c.term));
        a[(i, i)] += c.prior_precision;
        b[i] -= c.prior_precision * c0;
    }
    Normal { a, b }
}

/// Solves the normal equations with a small ridge (a column the data do not reach stays at 0).
fn solve(n: &Normal) -> DVector<f64> {
    let m = n.b.len();
    let mut a = n.a.clone();
    let scale = (0..m).map(|i| a[(i, i)]).fold(0.0, f64::max).max(1e-300);
    for i in 0..m {
        a[(i, i)] += 1e-9 * scale + if a[(i, i)] <= 1e-12 * scale { scale } else { 0.0 };
    }
    a.cholesky().map_or_else(|| DVector::zeros(m), |c| c.solve(&n.b))
}

/// Solves the normal equations of `design` with its columns' sign bounds: a column whose
/// coefficient (present value plus step) would take the wrong sign is held at zero and the
/// rest solved again, one column at a time, most violated first (an active set that only
/// grows: the bounded columns are few and rarely more than one is active).
fn solve_bounded(design: &Design, n: &Normal) -> DVector<f64> {
    let m = n.b.len();
    let present: Vec<f64> = design
        .cols
        .iter()
        .map(|c| {
            let e = &design.effects[c.slot];
            e.get(&state::term_key(e.effect, c.term))
        })
        .collect();
    let mut held: Vec<usize> = Vec::new();
    loop {
        let free: Vec<usize> = (0..m).filter(|i| !held.contains(i)).collect();
        let mut delta = DVector::<f64>::zeros(m);
        for &i in &held {
            delta[i] = -present[i];
        }
        let reduced = Normal {
            a: DMatrix::from_fn(free.len(), free.len(), |r, c| n.a[(free[r], free[c])]),
            b: DVector::from_fn(free.len(), |r, _| {
                n.b[free[r]] - held.iter().map(|&i| n.a[(free[r], i)] * delta[i]).sum::<f64>()
            }),
        };
        if !free.is_empty() {
            for (r, d) in free.iter().zip(solve(&reduced).iter()) {
                delta[*r] = *d;
            }
        }
        let worst = free
            .iter()
            .filter_map(|&i| {
                let sign = design.cols.get(i)?.sign?;
                let c = present[i] + delta[i];
                (!sign.holds(c)).then_some((i, c.abs()))
            })
            .max_by(|a, b| a.1.total_cmp(&b.1));
        match worst {
            Some((i, _)) => held.push(i),
            None => return delta,
        }
    }
}

/// Columns of the effect in `slot` the data determine (for the parameter count of the
/// evidence): a column the points never reach (FX terms on a cornering run) adds nothing.
pub fn determined_columns(
    ev: &Evaluator<'_>,
    design: &Design,
    lin: &Linearization,
    sigma: &[f64; 4],
    slot: usize,
) -> usize {
    let all: Vec<usize> = (0..ev.ds.len()).collect();
    let n = normal(design, lin, &all, &|_| [0.0; 4], sigma);
    // Determined: the data's own information exceeds the prior's.
    (0..n.b.len())
        .filter(|&i| design.cols[i].slot == slot && n.a[(i, i)] > 2.0 * design.cols[i].prior_precision)
        .count()
}

/// Least share of a term's state variation (weighted by how much its factor moves the
/// prediction at each point) that must be left at a fixed operating point for the term to be
/// fitted with the operating point's share taken out ([`crate::form::PartialOut`]). Below it
/// the state is as good as a function of the operating point where the term acts: fitted on
/// the little that is left and applied to the whole state, its coefficient is wild (benchmark
/// of real-like TTC runs: a specimen's λμx, seen on the drive/brake run's tyre only, came out
/// at e^191 and the final model's FX RMS at 1,622 N).
pub const MIN_PARTIALLED_SHARE: f64 = 0.1;

/// The least share [`without_aliased`] asks of a term: [`MIN_PARTIALLED_SHARE`], and
/// [`MIN_WEAR_RADIUS_SHARE`] for wear's radius.
pub fn min_partialled_share(effect: Effect, term: Term) -> f64 {
    match (effect, term.factor) {
        (Effect::Wear, state::Factor::Radius) => MIN_WEAR_RADIUS_SHARE,
        _ => MIN_PARTIALLED_SHARE,
    }
}

/// The least share for wear's radius term: tread loss is wear's one sure sign, and the term only
/// shrinks the radius ([`state::sign_bound`]), so what a thermal effect does to the radius
/// (a warming tyre's pressure rises and its radius grows) cannot pass for it.
pub const MIN_WEAR_RADIUS_SHARE: f64 = 0.05;

/// The design without the columns of `slot` whose state, where their factor acts, is
/// (nearly) fixed by the operating point ([`min_partialled_share`]; the state's own share
/// decides for every function of it, [`state_basis`], and a factor of several components by
/// its best one, [`column_share`]). Only where `ev` partials the effect out; otherwise the
/// design as it is.
pub fn without_aliased(
    ev: &Evaluator<'_>,
    design: Design,
    lin: &Linearization,
    sigma: &[f64; 4],
    slot: usize,
) -> Design {
    let Some(shares) = slot_shares(ev, &design, lin, sigma, slot) else { return design };
    let effect = design.effects[slot].effect;
    let keep: Vec<bool> = design
        .cols
        .iter()
        .zip(&shares)
        .map(|(c, s)| s.is_none_or(|v| v >= min_partialled_share(effect, c.term)))
        .collect();
    let cols = design.cols.into_iter().zip(keep).filter(|(_, k)| *k).map(|(c, _)| c).collect();
    Design { effects: design.effects, cols }
}

/// A share of a state's variance left at fixed operating points ([`without_aliased`]) and the
/// share its term needs ([`min_partialled_share`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PartialledShare {
    /// The share kept.
    pub share: f64,
    /// The share needed to fit the term.
    pub needed: f64,
}

/// Of the columns of `slot`, the share of the one nearest to passing the screen of
/// [`without_aliased`] (the largest share for what it needs); `None` where `ev` does not partial
/// the effect out or the slot has no column. What a user is told when every column is screened
/// out: how nearly the plan ties the state to the operating point.
pub fn largest_partialled_share(
    ev: &Evaluator<'_>,
    design: &Design,
    lin: &Linearization,
    sigma: &[f64; 4],
    slot: usize,
) -> Option<PartialledShare> {
    let effect = design.effects.get(slot)?.effect;
    slot_shares(ev, design, lin, sigma, slot)?
        .into_iter()
        .zip(&design.cols)
        .filter_map(|(s, c)| Some(PartialledShare { share: s?, needed: min_partialled_share(effect, c.term) }))
        .max_by(|a, b| (a.share / a.needed).total_cmp(&(b.share / b.needed)))
}

/// Per column of `design`, the share of [`column_share`] for the columns of `slot` (`None` for
/// the others); `None` where `ev` does not partial the slot's effect out.
fn slot_shares(
    ev: &Evaluator<'_>,
    design: &Design,
    lin: &Linearization,
    sigma: &[f64; 4],
    slot: usize,
) -> Option<Vec<Option<f64>>> {
    let effect = design.effects.get(slot).map(|e| e.effect)?;
    if !ev.partialled(effect) {
        return None;
    }
    let choice = design.effects[slot].parsed().choice;
    // The state's own values, as given and with the operating point's share taken out, by
    // basis (see [`state_basis`]).
    let mut cache: Vec<(u8, Vec<f64>, Vec<f64>)> = Vec::new();
    let shares = design
        .cols
        .iter()
        .map(|c| {
            if c.slot != slot {
                return None;
            }
            let b = state_basis(effect, c.term.basis);
            let at = match cache.iter().position(|(cb, _, _)| *cb == b) {
                Some(at) => at,
                None => {
                    cache.push((b, ev.raw_basis_at_points(effect, b, &choice), ev.basis_at_points(effect, b, &choice)));
                    cache.len() - 1
                }
            };
            let (_, raw, left) = &cache[at];
            Some(column_share(lin, sigma, raw, left, c.term.factor))
        })
        .collect();
    Some(shares)
}

/// The basis whose values are the state itself, for the screen of [`without_aliased`]: whether
/// the operating point fixes the state is a question about the state (thermal's x, wear's
/// energy, break-in's recovery), not about each function of it. Scored on x² itself,
/// thermal's curvature was dropped where x kept its share (an outsider's grip factor with an
/// optimum inside the data: x² at 0.065–0.089 beside x at 0.11–0.25) and the straight line
/// left was beaten by a temperature that did not set grip. A specimen's bases are its tyres.
fn state_basis(effect: Effect, basis: u8) -> u8 {
    match effect {
        Effect::Thermal => 1,
        Effect::Wear | Effect::BreakIn => 0,
        _ => basis,
    }
}

/// The share of a state's variance left at fixed operating points where `factor` acts (see
/// [`partialled_share`]). A factor that moves several scaling factors at once (the force
/// level) is determined wherever one of them is: its share is its best component's. Pooled,
/// the force level's points span runs whose temperatures differ with the runs' own cells (a
/// TTC cornering run cold, its drive/brake run hot), a difference the operating point takes
/// whole: on an outsider's thermal effect in TTC-style runs the pooled share was 0.05 where
/// λμx and λμy each kept 0.2, and the two-coefficient force level was never fitted.
fn column_share(lin: &Linearization, sigma: &[f64; 4], raw: &[f64], left: &[f64], factor: state::Factor) -> f64 {
    match factor {
        state::Factor::Radius => partialled_share(lin, sigma, raw, left, None),
        f => f.scaling_indices().iter().map(|&i| partialled_share(lin, sigma, raw, left, Some(i))).fold(0.0, f64::max),
    }
}

/// The share of a state column's variance about its mean left with the operating point's
/// share taken out (`left`: the partialled basis; `raw`: the basis as the state gives it),
/// weighted at each point by how much the scaling factor `component` (`None`: the loaded
/// radius) moves the channels there, in noise units, over the points where it acts at all (a
/// hundredth of its largest pull: λμx barely moves FX at zero slip ratio, and those points
/// must not lend it a state variation it cannot show). 0 where nothing varies.
fn partialled_share(lin: &Linearization, sigma: &[f64; 4], raw: &[f64], left: &[f64], component: Option<usize>) -> f64 {
    let weight = |k: usize| -> f64 {
        match component {
            None => f64::from(u8::from(lin.pred[k][CH_RL].is_finite())),
            Some(f) => (0..4).map(|ch| (lin.sens[k][f][ch] / sigma[ch]).powi(2)).filter(|v| v.is_finite()).sum(),
        }
    };
    let w: Vec<f64> = (0..raw.len()).map(weight).collect();
    let w_max = w.iter().copied().fold(0.0, f64::max);
    let acts = |k: usize| w[k] > 0.01 * w_max && raw[k].is_finite() && left[k].is_finite();
    let (mut sw, mut swx, mut swp) = (0.0, 0.0, 0.0);
    for k in (0..raw.len()).filter(|&k| acts(k)) {
        sw += w[k];
        swx += w[k] * raw[k];
        swp += w[k] * left[k];
    }
    if sw <= 0.0 {
        return 0.0;
    }
    // Both about their means: a level left by the smoother's shrinkage is no variation.
    let (mean, mean_left) = (swx / sw, swp / sw);
    let (mut raw_var, mut left_var) = (0.0, 0.0);
    for k in (0..raw.len()).filter(|&k| acts(k)) {
        raw_var += w[k] * (raw[k] - mean).powi(2);
        left_var += w[k] * (left[k] - mean_left).powi(2);
    }
    if raw_var > 1e-12 * sw { left_var / raw_var } else { 0.0 }
}

/// What fitting a state design on all sweeps gives.
#[derive(Debug, Clone)]
pub struct Fitted {
    /// The effects with fitted coefficients.
    pub effects: Vec<EffectParams>,
    /// Linearisation at the fit (its predictions are the fit's).
    pub lin: Linearization,
    /// The design at the fit (columns as fitted).
    pub design: Design,
}

/// Fits a design on all points to `target` (measured less any correction), with Gauss–Newton
/// steps from the linearisation `lin0` of the model at the design's present coefficients.
pub fn fit_all(
    ev: &Evaluator<'_>,
    design: Design,
    lin0: &Linearization,
    fixed: &[EffectParams],
    target: &dyn Fn(usize) -> [f64; 4],
    sigma: &[f64; 4],
) -> Fitted {
    let all: Vec<usize> = (0..ev.ds.len()).collect();
    let chi2_of = |lin: &Linearization| -> f64 {
        let mut c = 0.0;
        for (k, p) in lin.pred.iter().enumerate() {
            let t = target(k);
            for ch in 0..4 {
                let r = (t[ch] - p[ch]) / sigma[ch];
                if r.is_finite() {
                    c += r * r;
                }
            }
        }
        c
    };
    let mut design = design;
    let mut lin = lin0.clone();
    let mut chi = chi2_of(&lin);
    for _ in 0..=GN_STEPS {
        let mut delta = solve_bounded(&design, &normal(&design, &lin, &all, target, sigma));
        // A step the model's own evaluation does not confirm is halved (the linearisation
        // overshoots where a factor changes the curve's shape strongly), at most four times.
        for _ in 0..4 {
            let effects = design.updated(&delta);
            let model: Vec<EffectParams> = fixed.iter().cloned().chain(effects.iter().cloned()).collect();
            let trial = linearize(ev, &model);
            let c = chi2_of(&trial);
            if c <= chi {
                chi = c;
                lin = trial;
                design = Design { effects, cols: design.cols };
                break;
            }
            delta *= 0.5;
        }
    }
    Fitted { effects: design.effects.clone(), lin, design }
}

/// Cross-validated predictions of a design linearised at `lin`: for each fold, the
/// coefficients refitted on the other folds by the linearised normal equations (to
/// `target_of_fold`, the measurements less that fold's correction), and the fold's points
/// predicted by the model itself with those coefficients (with `fixed` effects), plus
/// `held_out_add` (its correction). The model, not its linearisation, predicts: a fold without
/// the sweeps that determine a coefficient falls back towards zero, far from where the
/// linearisation holds.
#[allow(clippy::too_many_arguments)]
pub fn cross_validate(
    ev: &Evaluator<'_>,
    design: &Design,
    fixed: &[EffectParams],
    lin: &Linearization,
    folds: &[Vec<usize>],
    target_of_fold: &dyn Fn(usize, usize) -> [f64; 4],
    held_out_add: &dyn Fn(usize, usize) -> [f64; 4],
    sigma: &[f64; 4],
) -> Vec<[f64; 4]> {
    let mut out = vec![[f64::NAN; 4]; lin.pred.len()];
    for fi in 0..folds.len() {
        predict_fold(ev, design, fixed, lin, folds, fi, target_of_fold, held_out_add, sigma, &mut out);
    }
    out
}

/// Fold `fi` of a cross-validation: the design solved on the other folds' points, the fold's
/// points predicted by the model with those coefficients plus `held_out_add`, into `out`.
#[allow(clippy::too_many_arguments)]
fn predict_fold(
    ev: &Evaluator<'_>,
    design: &Design,
    fixed: &[EffectParams],
    lin: &Linearization,
    folds: &[Vec<usize>],
    fi: usize,
    target_of_fold: &dyn Fn(usize, usize) -> [f64; 4],
    held_out_add: &dyn Fn(usize, usize) -> [f64; 4],
    sigma: &[f64; 4],
    out: &mut [[f64; 4]],
) {
    let train = crate::fit::training(folds, fi);
    let delta = if design.cols.is_empty() {
        DVector::zeros(0)
    } else {
        solve_bounded(design, &normal(design, lin, &train, &|k| target_of_fold(fi, k), sigma))
    };
    let model: Vec<EffectParams> = fixed.iter().cloned().chain(design.updated(&delta)).collect();
    let test = &folds[fi];
    for (&k, p) in test.iter().zip(ev.predict(&model, test)) {
        let add = held_out_add(fi, k);
        out[k] = std::array::from_fn(|ch| p[ch] + add[ch]);
    }
}

/// As [`cross_validate`], with each fold's own evaluator (`evs[fi]`: a state partialled out
/// over that fold's training points, [`crate::form::PartialOut::per_fold`]): the design's
/// basis values and the present prediction are taken again with it, the sensitivities kept.
#[allow(clippy::too_many_arguments)]
pub fn cross_validate_refolded(
    evs: &[Evaluator<'_>],
    design: &Design,
    fixed: &[EffectParams],
    lin: &Linearization,
    folds: &[Vec<usize>],
    target_of_fold: &dyn Fn(usize, usize) -> [f64; 4],
    held_out_add: &dyn Fn(usize, usize) -> [f64; 4],
    sigma: &[f64; 4],
) -> Vec<[f64; 4]> {
    let n_points = lin.pred.len();
    let mut out = vec![[f64::NAN; 4]; n_points];
    let mut terms: Vec<Vec<Term>> = vec![Vec::new(); design.effects.len()];
    for c in &design.cols {
        terms[c.slot].push(c.term);
    }
    let model0: Vec<EffectParams> = fixed.iter().cloned().chain(design.effects.iter().cloned()).collect();
    let all: Vec<usize> = (0..n_points).collect();
    for (fi, ev) in evs.iter().enumerate().take(folds.len()) {
        let d = Design::new(ev, design.effects.clone(), &terms);
        let lin_f = Linearization { pred: ev.predict(&model0, &all), sens: lin.sens.clone() };
        predict_fold(ev, &d, fixed, &lin_f, folds, fi, target_of_fold, held_out_add, sigma, &mut out);
    }
    out
}

/// The design of present state effects plus a new candidate with `choice` (its terms at 0).
pub fn with_candidate(
    ev: &Evaluator<'_>,
    present: &[EffectParams],
    present_terms: &[Vec<Term>],
    effect: Effect,
    choice: Choice,
    terms: Vec<Term>,
) -> Design {
    let entries = choice.entries(effect);
    let new = EffectParams {
        effect,
        keys: entries.iter().map(|(k, _)| k.clone()).collect(),
        values: entries.iter().map(|(_, v)| *v).collect(),
    };
    let mut effects = present.to_vec();
    effects.push(new);
    let mut ts = present_terms.to_vec();
    ts.push(terms);
    Design::new(ev, effects, &ts)
}

/// χ² of `target` against a design's linear prediction after a solve on all points (for
/// choosing among a candidate's discrete choices).
pub fn chi2_after_solve(
    ev: &Evaluator<'_>,
    design: &Design,
    lin: &Linearization,
    target: &dyn Fn(usize) -> [f64; 4],
    sigma: &[f64; 4],
) -> f64 {
    let all: Vec<usize> = (0..ev.ds.len()).collect();
    let n = normal(design, lin, &all, target, sigma);
    let d = solve_bounded(design, &n);
    // χ²(Δ) = χ²(0) − 2bᵀΔ + ΔᵀAΔ; only the part that depends on Δ is needed to compare.
    -2.0 * n.b.dot(&d) + (d.transpose() * &n.a * &d)[(0, 0)]
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two runs of one tyre, each at its own cells: a cold cornering run (FY moves with λμy)
    /// and a hot drive/brake run (FX moves with λμx), the temperature varying by ±5 K within
    /// each run's cells. The operating point takes the 60 K between the runs; what is left is
    /// the within-run variation, all of it for either grip factor alone. The force level, which
    /// moves both, is as determined as they are: pooled over both runs its share would be
    /// 25 / (25 + 900) ≈ 0.03, and it was dropped.
    #[test]
    fn the_force_level_keeps_the_share_of_its_best_component() {
        let n = 200;
        let cold = |k: usize| k < n / 2;
        let within = |k: usize| if k.is_multiple_of(2) { 5.0 } else { -5.0 };
        let raw: Vec<f64> = (0..n).map(|k| if cold(k) { 30.0 } else { 90.0 } + within(k)).collect();
        let left: Vec<f64> = (0..n).map(within).collect();
        let mut sens = vec![[[0.0; 4]; 8]; n];
        for (k, s) in sens.iter_mut().enumerate() {
            if cold(k) {
                s[1][1] = 100.0; // λμy on FYW
            } else {
                s[0][0] = 100.0; // λμx on FX
            }
        }
        let lin = Linearization { pred: vec![[0.0; 4]; n], sens };
        let sigma = [10.0, 10.0, 1.0, 1e-4];
        for factor in [state::Factor::MuX, state::Factor::MuY, state::Factor::Force] {
            let share = column_share(&lin, &sigma, &raw, &left, factor);
            assert!((share - 1.0).abs() < 1e-9, "{factor:?}: {share}");
        }
        // The radius, which every point shows, sees both runs: the operating point took the
        // difference between them, and little is left.
        let share = column_share(&lin, &sigma, &raw, &left, state::Factor::Radius);
        assert!(share < MIN_PARTIALLED_SHARE, "radius: {share}");
        // Thermal's x² is screened by x, break-in's slow stage by its fast one.
        assert_eq!(state_basis(Effect::Thermal, 2), 1);
        assert_eq!(state_basis(Effect::BreakIn, 1), 0);
        assert_eq!(state_basis(Effect::Specimen, 2), 2);
    }
}

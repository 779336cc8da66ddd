//! The doctor's loop: simulate, find, name (greedy, cross-validated), add, show.

use crate::DoctorError;
use crate::data::Dataset;
use crate::effects::{CH_FY, CH_RL, CHANNELS, Effect, EffectParams, Evaluator, param_specs, untestable_reason};
use crate::fit::{
    FitOptions, FitSpec, chi2, count_valid, cross_validate, cross_validate_corrected, fit_effects, folds, measured,
    noise_floor,
};
use crate::form::{self, Bandwidths};
use mftyre::TyreParams;
use serde::Serialize;

/// Settings of a diagnosis.
#[derive(Debug, Clone)]
pub struct DoctorConfig {
    /// Held-out folds (sweeps are dealt round-robin into them).
    pub folds: usize,
    /// Smallest evidence (share of the held-out χ² explained, after the parameter penalty) for
    /// an effect to be named.
    pub min_evidence: f64,
    /// Smallest excess of the present model's held-out χ² over the noise floor (χ²/N − 1) for
    /// anything to be looked for.
    pub min_excess: f64,
    /// Most effects named.
    pub max_effects: usize,
    /// Candidates tested.
    pub candidates: Vec<Effect>,
    /// An effect's region: points where it changes the prediction of its main channel by more
    /// than this many noise σ.
    pub region_sigma: f64,
    /// Fit settings.
    pub fit: FitOptions,
    /// Worker threads scoring candidates.
    pub threads: usize,
    /// Smallest cut of the held-out RMS in a candidate's own region for it to be named.
    pub min_region_cut: f64,
    /// Channels (FX, FYW, MZW, DSTWOWHC, in [`CHANNELS`] order) not diagnosed, with the reason:
    /// a channel the base model was neither fitted for nor given for would show the base's own
    /// gap, and the doctor would "explain" it with some effect.
    pub not_diagnosed: Vec<(usize, String)>,
    /// Score state effects (thermal, wear, break-in, transient, speed) against the present model
    /// plus the cross-fitted form error ([`crate::form`]): on for a base fitted to the same
    /// logs, whose remaining misfit is mostly the MF form's own.
    pub form_correction: bool,
}

impl Default for DoctorConfig {
    fn default() -> Self {
        Self {
            folds: 4,
            min_evidence: 0.05,
            min_excess: 0.1,
            max_effects: 3,
            candidates: Effect::ALL.to_vec(),
            region_sigma: 2.0,
            fit: FitOptions::default(),
            threads: std::thread::available_parallelism().map_or(1, |n| n.get()).min(4),
            min_region_cut: 0.1,
            not_diagnosed: Vec::new(),
            form_correction: false,
        }
    }
}

/// A candidate's score in one round.
#[derive(Debug, Clone, Serialize)]
pub struct CandidateScore {
    /// The candidate.
    pub effect: Effect,
    /// Testable on this data (else `reason`).
    pub testable: bool,
    /// Why not testable.
    pub reason: String,
    /// Parameters it adds.
    pub n_params: usize,
    /// Held-out χ² of the present model.
    pub chi2_before_heldout: f64,
    /// Held-out χ² with the candidate added.
    pub chi2_after_heldout: f64,
    /// Held-out folds it improved, of `folds`.
    pub folds_improved: usize,
    /// Folds.
    pub folds: usize,
    /// Evidence: (Δχ² − k·ln N) / χ²_before on held-out sweeps.
    pub evidence: f64,
    /// Held-out χ² reduction per channel.
    pub delta_chi2_by_channel: [f64; 4],
    /// Significant (would be named if best).
    pub significant: bool,
    /// Scored against the present model plus the form error common to all sweeps at the
    /// operating point ([`crate::form`]).
    pub form_corrected: bool,
}

/// A named effect with its evidence and before/after RMS.
#[derive(Debug, Clone, Serialize)]
pub struct NamedEffect {
    /// The effect.
    pub effect: Effect,
    /// Its evidence score.
    pub evidence: f64,
    /// The best other candidate of the round and its evidence.
    pub runner_up: Option<(Effect, f64)>,
    /// Main channel (largest held-out χ² reduction).
    pub channel: String,
    /// The region where the effect changes the prediction beyond the noise, in words.
    pub region: String,
    /// Points in the region.
    pub region_points: usize,
    /// RMS of the main channel's residual in the region, fitted model before the effect.
    pub rms_before: f64,
    /// … and with it (fit on all sweeps).
    pub rms_after: f64,
    /// The same on held-out sweeps (cross-validated predictions).
    pub rms_before_heldout: f64,
    /// … and with it.
    pub rms_after_heldout: f64,
    /// Correlation of the present residual (main channel) with the effect's predicted change.
    pub correlation: f64,
    /// The RMS before/after are of the residual left after the form error common to all
    /// sweeps at each operating point ([`crate::form`]).
    pub form_corrected: bool,
    /// Fitted parameters (on all sweeps).
    pub params: EffectParams,
}

/// One bin of the region search.
#[derive(Debug, Clone, Serialize)]
pub struct RegionBin {
    /// Variable binned.
    pub variable: String,
    /// Bin label.
    pub bin: String,
    /// Points.
    pub n: usize,
    /// RMS / noise σ per channel (FX, FYW, MZW, DSTWOWHC) of the base model's residual.
    pub rms_over_noise: [f64; 4],
    /// Beyond noise: some channel's RMS/σ exceeds 1.3 on ≥ 20 points.
    pub flagged: bool,
}

/// Per-channel RMS table.
#[derive(Debug, Clone, Serialize)]
pub struct RmsTable {
    /// Channel names.
    pub channels: [&'static str; 4],
    /// Noise floor σ (physical units: N, N, N·m, m).
    pub noise: [f64; 4],
    /// Base model, all points.
    pub base: [f64; 4],
    /// Final model fitted on all sweeps.
    pub final_fit: [f64; 4],
    /// Final model, held-out sweeps.
    pub final_heldout: [f64; 4],
}

/// Everything a diagnosis found.
#[derive(Debug, Clone, Serialize)]
pub struct Diagnosis {
    /// Effects named, in order.
    pub named: Vec<NamedEffect>,
    /// Candidate scores per round.
    pub rounds: Vec<Vec<CandidateScore>>,
    /// Region bins of the base model's residual.
    pub regions: Vec<RegionBin>,
    /// RMS per channel.
    pub rms: RmsTable,
    /// Points and sweeps used.
    pub points: usize,
    /// Sweeps.
    pub sweeps: usize,
    /// Why the search stopped.
    pub stop_reason: String,
    /// Reference temperature of the thermal extension [°C].
    pub t_ref_c: f64,
    /// Reference speed of the speed extension [m/s].
    pub v_ref_mps: f64,
    /// Per log, the decay time constant of the laser flash fitted out of the quiet tread
    /// temperatures [s] (`None`: none evident) — see [`crate::flash`].
    pub flash_decay_s: Vec<Option<f64>>,
    /// Channels left out of the diagnosis, and why (e.g. `DSTWOWHC not diagnosed: the base's
    /// loaded radius was not fitted from these logs`).
    pub not_diagnosed: Vec<String>,
    /// State effects were scored against the form error ([`DoctorConfig::form_correction`]).
    pub form_correction: bool,
    /// Plot data (not serialised).
    #[serde(skip)]
    pub plot: PlotData,
}

/// Arrays the report plots from.
#[derive(Debug, Clone, Default)]
pub struct PlotData {
    /// Measured values at the points.
    pub meas: Vec<[f64; 4]>,
    /// Base model predictions.
    pub base: Vec<[f64; 4]>,
    /// Fitted predictions before each named effect (with the form error where it was scored
    /// with it).
    pub before: Vec<Vec<[f64; 4]>>,
    /// Fitted predictions after each named effect (index 0 = after the first).
    pub after: Vec<Vec<[f64; 4]>>,
    /// Held-out predictions before each named effect.
    pub before_heldout: Vec<Vec<[f64; 4]>>,
    /// Held-out predictions after each named effect.
    pub after_heldout: Vec<Vec<[f64; 4]>>,
    /// Region points of each named effect.
    pub region: Vec<Vec<usize>>,
}

/// A candidate's score with its effect set and held-out predictions (testable candidates).
type Scored = (CandidateScore, Option<(Vec<FitSpec>, Vec<[f64; 4]>)>);

/// The present model's form error, cross-fitted per fold and from all other sweeps.
struct FormError {
    /// Per fold: the correction of every point (held-out from training sweeps, training points
    /// from the other training sweeps).
    per_fold: Vec<form::FoldCorrection>,
    /// Every point's correction from all other sweeps (fits on all sweeps).
    all: form::FoldCorrection,
    /// Held-out predictions of the present model plus the correction.
    before_heldout: Vec<[f64; 4]>,
}

fn add(a: &[[f64; 4]], b: &[[f64; 4]]) -> Vec<[f64; 4]> {
    a.iter().zip(b).map(|(x, y)| std::array::from_fn(|ch| x[ch] + y[ch])).collect()
}

fn residual(meas: &[[f64; 4]], pred: &[[f64; 4]]) -> Vec<[f64; 4]> {
    meas.iter().zip(pred).map(|(m, p)| std::array::from_fn(|ch| m[ch] - p[ch])).collect()
}

fn rms_of(meas: &[[f64; 4]], pred: &[[f64; 4]], ch: usize, which: &[usize]) -> f64 {
    let (mut s, mut n) = (0.0, 0usize);
    for &k in which {
        let r = meas[k][ch] - pred[k][ch];
        if r.is_finite() {
            s += r * r;
            n += 1;
        }
    }
    if n == 0 { 0.0 } else { (s / n as f64).sqrt() }
}

fn total(c: [f64; 4]) -> f64 {
    c.iter().sum()
}

/// Runs the doctor on `ds` with the base model `base`.
pub fn diagnose(ds: &Dataset, base: &TyreParams, cfg: &DoctorConfig) -> Result<Diagnosis, DoctorError> {
    let ev = Evaluator::new(ds, base);
    let all: Vec<usize> = (0..ds.len()).collect();
    let mut meas = measured(&ev);
    // Channels not diagnosed take no part: their measured values are treated as missing.
    for (ch, _) in &cfg.not_diagnosed {
        for m in meas.iter_mut() {
            if let Some(v) = m.get_mut(*ch) {
                *v = f64::NAN;
            }
        }
    }
    let not_diagnosed: Vec<String> = cfg
        .not_diagnosed
        .iter()
        .map(|(ch, why)| format!("{} not diagnosed: {why}", CHANNELS.get(*ch).copied().unwrap_or("?")))
        .collect();
    let base_pred = ev.predict(&[], &all);
    let sigma = noise_floor(&ev, &meas, &base_pred);
    let fl = folds(&ev, cfg.folds.max(2));
    if fl.len() < 2 {
        return Err(DoctorError::NoData {
            what: format!("{} sweep(s): cross-validation needs at least 2", ds.sweeps.len()),
        });
    }
    let n_res = count_valid(&meas, &all).max(1) as f64;
    let mut fold_of = vec![0usize; ds.len()];
    for (fi, f) in fl.iter().enumerate() {
        for &k in f {
            fold_of[k] = fi;
        }
    }
    let bandwidths = Bandwidths::from_data(ds);
    let regions = find_regions(ds, &meas, &base_pred, &sigma);

    let mut chosen: Vec<FitSpec> = Vec::new();
    let mut cur_fit = base_pred.clone();
    let mut cur_ho = base_pred.clone();
    let mut named = Vec::new();
    let mut rounds = Vec::new();
    let mut plot = PlotData { meas: meas.clone(), base: base_pred.clone(), ..Default::default() };
    let mut stop_reason = String::new();
    let mut final_params: Vec<EffectParams> = Vec::new();

    while named.len() < cfg.max_effects {
        let fold_chi_before: Vec<f64> = fl.iter().map(|f| total(chi2(&meas, &cur_ho, &sigma, f))).collect();
        let chi_before: f64 = fold_chi_before.iter().sum();
        let excess = chi_before / n_res - 1.0;
        if excess < cfg.min_excess {
            stop_reason = format!(
                "the residual is at the noise floor (held-out χ²/N = {:.3}, excess {:.3} < {})",
                chi_before / n_res,
                excess,
                cfg.min_excess
            );
            break;
        }
        // The present model's form error (state candidates are scored against it).
        let form_error = cfg.form_correction.then(|| {
            let per_fold = form::cross_fitted(ds, &residual(&meas, &cur_ho), &fl, &bandwidths);
            let all_corr = form::leave_one_sweep_out(ds, &residual(&meas, &cur_fit), &bandwidths);
            let before_heldout: Vec<[f64; 4]> =
                (0..ds.len()).map(|k| std::array::from_fn(|ch| cur_ho[k][ch] + per_fold[fold_of[k]][k][ch])).collect();
            FormError { per_fold, all: all_corr, before_heldout }
        });
        let corrected_for = |eff: Effect| form_error.as_ref().filter(|_| !eff.is_refit());
        let todo: Vec<Effect> =
            cfg.candidates.iter().copied().filter(|e| !chosen.iter().any(|c| c.effect == *e)).collect();
        let score_one = |eff: Effect| -> Scored {
            if let Some(reason) = untestable_reason(eff, ds) {
                let s = CandidateScore {
                    effect: eff,
                    testable: false,
                    reason,
                    n_params: 0,
                    chi2_before_heldout: chi_before,
                    chi2_after_heldout: chi_before,
                    folds_improved: 0,
                    folds: fl.len(),
                    evidence: 0.0,
                    delta_chi2_by_channel: [0.0; 4],
                    significant: false,
                    form_corrected: false,
                };
                return (s, None);
            }
            let fe = corrected_for(eff);
            let before_ho = fe.map_or(&cur_ho, |f| &f.before_heldout);
            let fold_chi_before: Vec<f64> = match fe {
                Some(_) => fl.iter().map(|f| total(chi2(&meas, before_ho, &sigma, f))).collect(),
                None => fold_chi_before.clone(),
            };
            let chi_before: f64 = fold_chi_before.iter().sum();
            let mut specs = chosen.clone();
            let new = FitSpec { effect: eff, params: param_specs(eff, ds, base) };
            let k = new.params.len() + usize::from(eff == Effect::BreakIn);
            specs.push(new);
            let pred = match fe {
                Some(f) => cross_validate_corrected(&ev, &specs, &fl, &meas, sigma, cfg.fit, &f.per_fold),
                None => cross_validate(&ev, &specs, &fl, &meas, sigma, cfg.fit),
            };
            let fold_chi: Vec<f64> = fl.iter().map(|f| total(chi2(&meas, &pred, &sigma, f))).collect();
            let chi_after: f64 = fold_chi.iter().sum();
            let improved = fold_chi.iter().zip(&fold_chi_before).filter(|(a, b)| a < b).count();
            let cb = chi2(&meas, before_ho, &sigma, &all);
            let ca = chi2(&meas, &pred, &sigma, &all);
            let evidence = (chi_before - chi_after - k as f64 * n_res.ln()) / chi_before;
            let significant = evidence >= cfg.min_evidence && improved + 1 >= fl.len();
            let s = CandidateScore {
                effect: eff,
                testable: true,
                reason: String::new(),
                n_params: k,
                chi2_before_heldout: chi_before,
                chi2_after_heldout: chi_after,
                folds_improved: improved,
                folds: fl.len(),
                evidence,
                delta_chi2_by_channel: [cb[0] - ca[0], cb[1] - ca[1], cb[2] - ca[2], cb[3] - ca[3]],
                significant,
                form_corrected: fe.is_some(),
            };
            (s, Some((specs, pred)))
        };
        // Candidates are independent: score them on `threads` workers, results in catalogue order.
        let threads = cfg.threads.max(1).min(todo.len().max(1));
        let mut results: Vec<Option<Scored>> = vec![None; todo.len()];
        std::thread::scope(|sc| {
            let chunks: Vec<Vec<(usize, Effect)>> =
                (0..threads).map(|t| todo.iter().copied().enumerate().skip(t).step_by(threads).collect()).collect();
            let handles: Vec<_> = chunks
                .into_iter()
                .map(|chunk| sc.spawn(|| chunk.into_iter().map(|(i, e)| (i, score_one(e))).collect::<Vec<_>>()))
                .collect();
            for h in handles {
                // A worker only panics on a bug; surface it rather than hide a candidate.
                for (i, r) in h.join().expect("candidate worker") {
                    results[i] = Some(r);
                }
            }
        });
        let (mut scores, cv_preds): (Vec<CandidateScore>, Vec<_>) = results.into_iter().flatten().unzip();
        let mut order: Vec<usize> = (0..scores.len()).filter(|&i| scores[i].testable).collect();
        order.sort_by(|&a, &b| scores[b].evidence.total_cmp(&scores[a].evidence));
        // Take the significant candidates in order of evidence; the first whose fit also cuts
        // the held-out residual in its own region is named. An effect that helps χ² overall
        // while its region gets worse is not the effect in the data.
        let mut accepted = None;
        for (pos, &bi) in order.iter().enumerate() {
            if !scores[bi].significant {
                break;
            }
            let Some((specs, pred_ho)) = cv_preds[bi].clone() else { continue };
            let score = scores[bi].clone();
            let fe = corrected_for(score.effect);
            // With the form error: fitted to what the other sweeps at the same operating point
            // do not explain, and judged against the present model plus that correction.
            let (fitted, _) = match fe {
                Some(f) => fit_effects(&ev, &specs, &all, &residual(&meas, &f.all), sigma, cfg.fit),
                None => fit_effects(&ev, &specs, &all, &meas, sigma, cfg.fit),
            };
            let pred_fit = ev.predict(&fitted, &all);
            let (before_fit_c, after_fit_c, before_ho_c) = match fe {
                Some(f) => (add(&cur_fit, &f.all), add(&pred_fit, &f.all), f.before_heldout.clone()),
                None => (cur_fit.clone(), pred_fit.clone(), cur_ho.clone()),
            };
            let ch = (0..4)
                .max_by(|&a, &b| score.delta_chi2_by_channel[a].total_cmp(&score.delta_chi2_by_channel[b]))
                .unwrap_or(CH_FY);
            // Region: where the new effect moves the prediction of the main channel beyond noise.
            let mut thr = cfg.region_sigma;
            let mut region: Vec<usize>;
            loop {
                region = all
                    .iter()
                    .copied()
                    .filter(|&k| {
                        ((pred_fit[k][ch] - cur_fit[k][ch]) / sigma[ch]).abs() > thr && meas[k][ch].is_finite()
                    })
                    .collect();
                if region.len() >= 20 || thr <= 0.5 {
                    break;
                }
                thr /= 2.0;
            }
            let before_ho = rms_of(&meas, &before_ho_c, ch, &region);
            let after_ho = rms_of(&meas, &pred_ho, ch, &region);
            if after_ho > (1.0 - cfg.min_region_cut) * before_ho {
                scores[bi].significant = false;
                scores[bi].reason = format!(
                    "rejected: held-out {} RMS in its own region {:.4} → {:.4} (needs ≥ {:.0} % less)",
                    CHANNELS[ch],
                    before_ho,
                    after_ho,
                    100.0 * cfg.min_region_cut
                );
                continue;
            }
            let runner_up =
                order.iter().enumerate().find(|(p, _)| *p != pos).map(|(_, &i)| (scores[i].effect, scores[i].evidence));
            let corr = correlation(
                all.iter().map(|&k| meas[k][ch] - cur_fit[k][ch]),
                all.iter().map(|&k| pred_fit[k][ch] - cur_fit[k][ch]),
            );
            let eff_params = fitted.iter().find(|e| e.effect == score.effect).cloned().unwrap_or(EffectParams {
                effect: score.effect,
                keys: vec![],
                values: vec![],
                threshold_w: 0.0,
            });
            let ne = NamedEffect {
                effect: score.effect,
                evidence: score.evidence,
                runner_up,
                channel: CHANNELS[ch].to_owned(),
                region: describe_region(ds, &ev, score.effect, &region, thr),
                region_points: region.len(),
                rms_before: rms_of(&meas, &before_fit_c, ch, &region),
                rms_after: rms_of(&meas, &after_fit_c, ch, &region),
                rms_before_heldout: before_ho,
                rms_after_heldout: after_ho,
                correlation: corr,
                form_corrected: fe.is_some(),
                params: eff_params,
            };
            // The model's own held-out predictions go on to the next round (the correction is
            // not part of the model).
            let pred_ho_model: Vec<[f64; 4]> = match fe {
                Some(f) => (0..ds.len())
                    .map(|k| std::array::from_fn(|c| pred_ho[k][c] - f.per_fold[fold_of[k]][k][c]))
                    .collect(),
                None => pred_ho.clone(),
            };
            let plots = [before_fit_c, after_fit_c, before_ho_c, pred_ho];
            accepted = Some((ne, specs, pred_fit, pred_ho_model, fitted, region, plots));
            break;
        }
        rounds.push(scores.clone());
        let Some((ne, specs, pred_fit, pred_ho, fitted, region, plots)) = accepted else {
            let best = order.first().copied();
            stop_reason = match best {
                Some(i) if !scores[i].reason.is_empty() => {
                    format!(
                        "no significant candidate left: the best, {}, was {}",
                        scores[i].effect.name(),
                        scores[i].reason
                    )
                }
                Some(i) => format!(
                    "no significant candidate left: the best, {}, explains {:.1} % of the held-out χ² (needs {:.1} %) and improves {}/{} folds",
                    scores[i].effect.name(),
                    100.0 * scores[i].evidence,
                    100.0 * cfg.min_evidence,
                    scores[i].folds_improved,
                    scores[i].folds
                ),
                None => "no testable candidate".to_owned(),
            };
            break;
        };
        named.push(ne);
        let [before_fit_c, after_fit_c, before_ho_c, after_ho_c] = plots;
        plot.before.push(before_fit_c);
        plot.after.push(after_fit_c);
        plot.before_heldout.push(before_ho_c);
        plot.after_heldout.push(after_ho_c);
        plot.region.push(region);
        chosen = specs;
        cur_fit = pred_fit;
        cur_ho = pred_ho;
        final_params = fitted;
    }
    if stop_reason.is_empty() {
        stop_reason = format!("stopped at the limit of {} effects", cfg.max_effects);
    }
    // Keep each named effect's parameters from the final joint fit.
    for ne in &mut named {
        if let Some(p) = final_params.iter().find(|p| p.effect == ne.effect) {
            ne.params = p.clone();
        }
    }
    let rms = RmsTable {
        channels: CHANNELS,
        noise: sigma,
        base: std::array::from_fn(|ch| rms_of(&meas, &base_pred, ch, &all)),
        final_fit: std::array::from_fn(|ch| rms_of(&meas, &cur_fit, ch, &all)),
        final_heldout: std::array::from_fn(|ch| rms_of(&meas, &cur_ho, ch, &all)),
    };
    Ok(Diagnosis {
        named,
        rounds,
        regions,
        rms,
        points: ds.len(),
        sweeps: ds.sweeps.len(),
        stop_reason,
        t_ref_c: ev.t_ref_c,
        v_ref_mps: ev.v_ref_mps,
        flash_decay_s: ds.flash_decay_s.clone(),
        not_diagnosed,
        form_correction: cfg.form_correction,
        plot,
    })
}

/// Pearson correlation.
pub fn correlation(a: impl Iterator<Item = f64>, b: impl Iterator<Item = f64>) -> f64 {
    let pairs: Vec<(f64, f64)> = a.zip(b).filter(|(x, y)| x.is_finite() && y.is_finite()).collect();
    let n = pairs.len() as f64;
    if n < 3.0 {
        return 0.0;
    }
    let (ma, mb) = (pairs.iter().map(|p| p.0).sum::<f64>() / n, pairs.iter().map(|p| p.1).sum::<f64>() / n);
    let (mut sab, mut saa, mut sbb) = (0.0, 0.0, 0.0);
    for (x, y) in pairs {
        sab += (x - ma) * (y - mb);
        saa += (x - ma).powi(2);
        sbb += (y - mb).powi(2);
    }
    if saa <= 0.0 || sbb <= 0.0 { 0.0 } else { sab / (saa * sbb).sqrt() }
}

fn percentile(mut v: Vec<f64>, q: f64) -> f64 {
    v.retain(|x| x.is_finite());
    if v.is_empty() {
        return f64::NAN;
    }
    v.sort_by(f64::total_cmp);
    v[((v.len() - 1) as f64 * q).round() as usize]
}

fn describe_region(ds: &Dataset, ev: &Evaluator<'_>, effect: Effect, region: &[usize], thr: f64) -> String {
    if region.is_empty() {
        return "nowhere beyond the noise".to_owned();
    }
    let s = &ds.series;
    let idx: Vec<usize> = region.iter().map(|&k| ds.points[k]).collect();
    let range = |f: &dyn Fn(usize) -> f64| {
        let v: Vec<f64> = idx.iter().map(|&i| f(i)).collect();
        (percentile(v.clone(), 0.05), percentile(v, 0.95))
    };
    let mut parts = Vec::new();
    if ds.has_lateral() {
        let (a, b) = range(&|i| s.alpha_deg[i].abs());
        parts.push(format!("|SLIPANGL| {a:.1}–{b:.1}°"));
    }
    if ds.has_longitudinal() {
        let (a, b) = range(&|i| s.kappa[i].abs() * 100.0);
        parts.push(format!("|LONGSLIP| {a:.1}–{b:.1} %"));
    }
    let (a, b) = range(&|i| s.fz_n[i] * 1e-3);
    parts.push(format!("FZW {a:.1}–{b:.1} kN"));
    let (name, unit) = effect.variable();
    let (a, b) = range(&|i| effect.variable_value(ds, i));
    parts.push(format!("{name} {a:.2}–{b:.2} {unit}"));
    let sw: std::collections::BTreeSet<usize> = region.iter().map(|&k| ds.point_sweep(k)).collect();
    let _ = ev;
    format!(
        "{} ({} of {} points, {} of {} sweeps, where the effect moves the prediction by > {:.1} σ)",
        parts.join(", "),
        region.len(),
        ds.len(),
        sw.len(),
        ds.sweeps.len(),
        thr
    )
}

/// Bins the base residual by operating region, time in the test, thermal state and slip rate.
fn find_regions(ds: &Dataset, meas: &[[f64; 4]], pred: &[[f64; 4]], sigma: &[f64; 4]) -> Vec<RegionBin> {
    let s = &ds.series;
    type Getter<'g> = Box<dyn Fn(usize) -> f64 + 'g>;
    let n_sw = ds.sweeps.len().max(1) as f64;
    let e_max = ds.points.iter().map(|&i| s.sliding_energy_j[i]).fold(0.0, f64::max).max(1.0);
    let vars: Vec<(&str, Getter<'_>, Vec<f64>)> = vec![
        ("|SLIPANGL| [deg]", Box::new(|i| s.alpha_deg[i].abs()), vec![0.0, 1.0, 3.0, 6.0, 10.0, 90.0]),
        ("|LONGSLIP| [%]", Box::new(|i| s.kappa[i].abs() * 100.0), vec![0.0, 1.0, 3.0, 8.0, 100.0]),
        ("FZW [kN]", Box::new(|i| s.fz_n[i] * 1e-3), vec![0.0, 3.0, 5.0, 7.0, 9.0, 100.0]),
        ("INCLANGL [deg]", Box::new(|i| s.gamma_deg[i]), vec![-90.0, -1.0, 1.0, 90.0]),
        ("INFLPRES [bar]", Box::new(|i| s.p_pa[i] * 1e-5), vec![0.0, 2.35, 2.95, 10.0]),
        ("sweep (share of test)", Box::new(move |i| s.sweep[i] as f64 / n_sw), vec![0.0, 0.25, 0.5, 0.75, 1.01]),
        (
            "sliding energy (share of max)",
            Box::new(move |i| s.sliding_energy_j[i] / e_max),
            vec![0.0, 0.25, 0.5, 0.75, 1.01],
        ),
        ("grip temperature [°C]", Box::new(|i| s.temp_grip_c[i]), vec![-50.0, 30.0, 45.0, 60.0, 75.0, 300.0]),
        ("slip-angle rate [deg/s]", Box::new(|i| s.alpha_rate_dps[i]), vec![-1e9, -10.0, -1.0, 1.0, 10.0, 1e9]),
    ];
    let mut out = Vec::new();
    for (name, get, edges) in vars {
        for w in edges.windows(2) {
            let which: Vec<usize> = (0..ds.len())
                .filter(|&k| {
                    let v = get(ds.points[k]);
                    v >= w[0] && v < w[1]
                })
                .collect();
            if which.is_empty() {
                continue;
            }
            let r: [f64; 4] = std::array::from_fn(|ch| rms_of(meas, pred, ch, &which) / sigma[ch]);
            let flagged = which.len() >= 20 && r.iter().any(|&x| x > 1.3);
            let fmt = |x: f64| if x.abs() >= 1e8 { "∞".to_owned() } else { format!("{x}") };
            out.push(RegionBin {
                variable: name.to_owned(),
                bin: format!("[{}, {})", fmt(w[0]), fmt(w[1])),
                n: which.len(),
                rms_over_noise: r,
                flagged,
            });
        }
    }
    let _ = CH_RL;
    out
}

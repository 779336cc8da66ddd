//! The choice of the next sweep and the stop rule.
//!
//! At a slot the planner scores every candidate not yet run: its value is the reduction of the
//! predicted mean-squared prediction error over the envelope grid of the targets it informs
//! ([`crate::design`]), its cost the predicted rig time to the end of its cool-down from where
//! the rig is (a pressure change counts when the pressure differs, so sweeps at the pressure the
//! rig is at are cheaper: pressure changes come grouped) plus the rig time of the tread it wears
//! (its sliding energy as the live model predicts it, at a tyre change per usable tread:
//! [`AdaptiveConfig::wear_mm_per_mj`], weighed against the rate the monitor measures on the tyre
//! under test once it has: [`Planner::on_measured_wear_rate`]). It runs the best value per second among
//! the ordinary candidates, and severe ones (high slip angle or load: wear, heat) only when no
//! ordinary candidate is worth running any more. It stops a slot when the predicted error over
//! the slot's targets is within [`AdaptiveConfig::target_ratio`] of what every remaining
//! candidate together would give (the full procedure's content), when nothing left lowers it by
//! [`AdaptiveConfig::min_relative_gain`], or when the slot's rig-time budget is spent. With
//! [`AdaptiveConfig::cover_envelope`], before it closes, the candidates that take the slot's data
//! beyond where they have been (load, slip, camber: [`crate::extent`]) run, cheapest first.

use nalgebra::DMatrix;
use procedure::Setpoint;
use serde::{Deserialize, Serialize};

use crate::config::AdaptiveConfig;
use crate::design;
use crate::extent::Extent;
use crate::library::{Candidate, Library};
use crate::model::{ModelView, Target};

/// One decision, with why (the sequencer logs it and puts it on `/diagnostics`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Decision {
    /// The slot.
    pub slot: usize,
    /// The chosen candidate; `None`: the slot is closed.
    pub candidate: Option<usize>,
    /// Its sweep name (empty when closing).
    pub name: String,
    /// Its predicted value: reduction of the mean squared predicted error, (% of peak)².
    #[serde(with = "crate::nan_as_null")]
    pub value: f64,
    /// Its predicted rig time to the end of its cool-down \[s\] (what the slot's budget counts).
    #[serde(with = "crate::nan_as_null")]
    pub cost_s: f64,
    /// Tread it is predicted to wear \[mm\] (its sliding energy × `wear_mm_per_mj`); its cost
    /// in the choice is `cost_s` plus this × `wear_cost_s_per_mm`.
    #[serde(default)]
    pub wear_mm: f64,
    /// The wear rate it was predicted with \[mm/MJ\] ([`Planner::wear_rate_mm_per_mj`]; 0 in
    /// older checkpoints and when wear is left out of the cost).
    #[serde(default)]
    pub wear_rate_mm_per_mj: f64,
    /// Predicted error over the slot's targets before it (% of peak, RMS over targets).
    #[serde(with = "crate::nan_as_null")]
    pub error_pct: f64,
    /// Predicted error after it.
    #[serde(with = "crate::nan_as_null")]
    pub error_after_pct: f64,
    /// Predicted error if every remaining candidate ran (the full procedure's content).
    #[serde(with = "crate::nan_as_null")]
    pub full_error_pct: f64,
    /// The error the slot stops at.
    #[serde(with = "crate::nan_as_null")]
    pub target_pct: f64,
    /// Why, in words.
    pub reason: String,
}

/// What the planner has decided so far: enough to continue after a checkpoint.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct PlannerState {
    /// Candidates chosen, in order.
    pub used: Vec<usize>,
    /// Slots closed.
    pub closed: Vec<usize>,
    /// Predicted rig time spent per slot \[s\].
    pub spent_s: Vec<f64>,
    /// Every decision.
    pub decisions: Vec<Decision>,
    /// Per slot: decisions in a row at which its target was met (reset when it is not).
    #[serde(default)]
    pub target_met: Vec<u32>,
    /// The newest wear rate measured on the tyre under test (none until the monitor has one):
    /// kept in the checkpoint, so a resumed run prices wear as the interrupted one did.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub measured_wear: Option<MeasuredWearRate>,
}

/// A wear rate measured on the tyre under test: the monitor's fit of tread loss (from the
/// rolling radius) against sliding energy, with its standard error.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct MeasuredWearRate {
    /// Tread lost per sliding energy \[mm/MJ\].
    pub mm_per_mj: f64,
    /// Its standard error \[mm/MJ\].
    pub sd_mm_per_mj: f64,
}

impl MeasuredWearRate {
    /// Its spread as the standard deviation of the rate's logarithm (delta method), or `None`
    /// when it says nothing a log-normal weighing can use: not finite, a rate ≤ 0 (wear below
    /// what the radius resolves yet) or a spread ≤ 0.
    fn log_sd(&self) -> Option<f64> {
        let ok = self.mm_per_mj.is_finite() && self.sd_mm_per_mj.is_finite();
        (ok && self.mm_per_mj > 0.0 && self.sd_mm_per_mj > 0.0).then(|| self.sd_mm_per_mj / self.mm_per_mj)
    }
}

/// A state that does not belong to the library.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("adaptive planner state: {0}")]
pub struct StateMismatch(pub String);

/// The planner.
#[derive(Debug, Clone)]
pub struct Planner {
    cfg: AdaptiveConfig,
    lib: Library,
    state: PlannerState,
}

struct Scored {
    id: usize,
    value: f64,
    cost_s: f64,
    wear_mm: f64,
    /// `cost_s` plus the rig time of the tread it wears: what value is divided by.
    charged_s: f64,
    error_after_pct: f64,
}

/// RMS over targets of per-target errors (% of peak).
fn rms(errors: &[f64]) -> f64 {
    if errors.is_empty() {
        return 0.0;
    }
    (errors.iter().map(|e| e * e).sum::<f64>() / errors.len() as f64).sqrt()
}

impl Planner {
    /// A planner with nothing decided.
    pub fn new(lib: Library, cfg: AdaptiveConfig) -> Self {
        let spent_s = vec![0.0; lib.slots.len()];
        Planner { cfg, lib, state: PlannerState { spent_s, ..PlannerState::default() } }
    }

    /// A planner continuing from `state` (a checkpoint's).
    pub fn restore(lib: Library, cfg: AdaptiveConfig, state: PlannerState) -> Result<Self, StateMismatch> {
        if let Some(bad) = state.used.iter().find(|&&id| id >= lib.candidates.len()) {
            return Err(StateMismatch(format!("candidate {bad} not in the library ({})", lib.candidates.len())));
        }
        if let Some(bad) = state.closed.iter().find(|&&s| s >= lib.slots.len()) {
            return Err(StateMismatch(format!("slot {bad} not in the library ({})", lib.slots.len())));
        }
        let mut state = state;
        state.spent_s.resize(lib.slots.len(), 0.0);
        Ok(Planner { cfg, lib, state })
    }

    /// The library.
    pub fn library(&self) -> &Library {
        &self.lib
    }

    /// What was decided so far.
    pub fn state(&self) -> &PlannerState {
        &self.state
    }

    /// The settings.
    pub fn config(&self) -> &AdaptiveConfig {
        &self.cfg
    }

    /// Takes the wear rate the monitor measured on the tyre under test (the newest replaces
    /// the one before: the monitor's fit already holds all its evidence). A measurement that
    /// says nothing usable ([`MeasuredWearRate`]: a rate ≤ 0, no spread) is ignored and the
    /// previous one stays. True when it was taken.
    pub fn on_measured_wear_rate(&mut self, rate: MeasuredWearRate) -> bool {
        if rate.log_sd().is_none() {
            return false;
        }
        self.state.measured_wear = Some(rate);
        true
    }

    /// The wear rate candidates are priced at \[mm/MJ\]: the configured `wear_mm_per_mj` and
    /// the measured rate weighed by their inverse variances in log space (a rate is positive
    /// and its uncertainty a factor, not an offset). Without a measurement, or with
    /// `wear_rate_log_sd = 0`, the configured rate; 0 when wear is left out of the cost.
    pub fn wear_rate_mm_per_mj(&self) -> f64 {
        let prior = self.cfg.wear_mm_per_mj;
        let prior_sd = self.cfg.wear_rate_log_sd;
        let measured = self.state.measured_wear.and_then(|m| m.log_sd().map(|sd| (m.mm_per_mj, sd)));
        match measured {
            Some((rate, sd)) if prior > 0.0 && prior_sd > 0.0 => {
                let (w_prior, w_measured) = (prior_sd.powi(-2), sd.powi(-2));
                ((w_prior * prior.ln() + w_measured * rate.ln()) / (w_prior + w_measured)).exp()
            }
            _ => prior,
        }
    }

    /// Rig time [s] the open slots may still spend on sweeps not chosen yet: each open slot's
    /// budget (`budget_fraction` × the predicted cost of all its candidates) less what its
    /// choices cost so far. An upper bound on what the plan adds (the stop rule usually closes
    /// a slot sooner), so a control room's remaining time is not optimistic while slots are
    /// open.
    pub fn open_slots_bound_s(&self) -> f64 {
        self.lib
            .slots
            .iter()
            .filter(|slot| !self.is_closed(slot.id))
            .map(|slot| {
                let spent = self.state.spent_s.get(slot.id).copied().unwrap_or(0.0);
                (self.cfg.budget_fraction * slot.full_cost_s - spent).max(0.0)
            })
            .sum()
    }

    /// True once `slot` is closed.
    pub fn is_closed(&self, slot: usize) -> bool {
        self.state.closed.contains(&slot)
    }

    fn remaining(&self, slot: usize) -> Vec<&Candidate> {
        self.lib.slots[slot]
            .candidates
            .iter()
            .filter(|id| !self.state.used.contains(id))
            .map(|&id| &self.lib.candidates[id])
            .collect()
    }

    /// The slot's targets: what any of its candidates informs.
    fn targets(&self, slot: usize) -> Vec<Target> {
        let mut t: Vec<Target> = Vec::new();
        for &id in &self.lib.slots[slot].candidates {
            for &x in self.lib.candidates[id].kind.targets() {
                if !t.contains(&x) {
                    t.push(x);
                }
            }
        }
        t.sort();
        t
    }

    /// Decide what runs next in `slot`, the rig at `from`, the live model `view`;
    /// `pause_scale`: observed pauses over the pause model's so far (1 without evidence).
    pub fn decide(&mut self, slot: usize, from: Setpoint, view: &dyn ModelView, pause_scale: f64) -> Decision {
        let d = self.evaluate(slot, from, view, pause_scale);
        // Count the decisions in a row at which the slot's target was met (as `evaluate` did).
        if self.state.target_met.len() <= slot {
            self.state.target_met.resize(slot + 1, 0);
        }
        let met = &mut self.state.target_met[slot];
        *met = if d.error_pct <= d.target_pct { *met + 1 } else { 0 };
        match d.candidate {
            Some(id) => {
                self.state.used.push(id);
                self.state.spent_s[slot] += d.cost_s;
            }
            None => {
                if !self.state.closed.contains(&slot) {
                    self.state.closed.push(slot);
                }
            }
        }
        self.state.decisions.push(d.clone());
        d
    }

    /// What [`Planner::decide`] would decide, without deciding it.
    pub fn evaluate(&self, slot: usize, from: Setpoint, view: &dyn ModelView, pause_scale: f64) -> Decision {
        let wear_rate = self.wear_rate_mm_per_mj();
        let close = |reason: String, e: f64, full: f64, target: f64| Decision {
            slot,
            candidate: None,
            name: String::new(),
            value: 0.0,
            cost_s: 0.0,
            wear_mm: 0.0,
            wear_rate_mm_per_mj: wear_rate,
            error_pct: e,
            error_after_pct: e,
            full_error_pct: full,
            target_pct: target,
            reason,
        };
        if slot >= self.lib.slots.len() || self.is_closed(slot) {
            return close("no such open slot".into(), f64::NAN, f64::NAN, f64::NAN);
        }
        let scale = if pause_scale.is_finite() && pause_scale > 0.0 { pause_scale } else { 1.0 };
        let limits = self.lib.limits;
        let remaining = self.remaining(slot);
        if remaining.is_empty() {
            return close("every candidate has run".into(), f64::NAN, f64::NAN, f64::NAN);
        }
        let budget_s = self.cfg.budget_fraction * self.lib.slots[slot].full_cost_s;
        let spent = self.state.spent_s.get(slot).copied().unwrap_or(0.0);
        let affordable = |c: &Candidate| spent + c.cost_s(from, &limits, scale) <= budget_s + 1e-9;
        // Predicted tread loss and what it costs in rig time (a tyre change per usable tread).
        let wear_of = |c: &Candidate| -> (f64, f64) {
            if wear_rate <= 0.0 {
                return (0.0, 0.0);
            }
            let mm = c.sliding_energy_j(view).map_or(0.0, |e| wear_rate * e * 1e-6);
            (mm, mm * self.cfg.wear_cost_s_per_mm())
        };
        let charged = |c: &Candidate| c.cost_s(from, &limits, scale) + wear_of(c).1;
        let targets = self.targets(slot);

        // Bootstrap: a target without a model yet (its stage not fitted) is learnt first, by
        // the cheapest candidate that informs it (ordinary before severe).
        let missing: Vec<Target> = targets.iter().copied().filter(|t| view.target(*t).is_none()).collect();
        let informs_missing = |c: &&Candidate| c.kind.targets().iter().any(|t| missing.contains(t));
        let boot: Vec<&Candidate> =
            remaining.iter().copied().filter(informs_missing).filter(|c| affordable(c)).collect();
        if !boot.is_empty() {
            let best = boot
                .iter()
                .min_by(|a, b| {
                    (a.severe, charged(a)).partial_cmp(&(b.severe, charged(b))).unwrap_or(std::cmp::Ordering::Equal)
                })
                .copied()
                .unwrap_or(boot[0]);
            let names: Vec<&str> = missing.iter().map(|t| t.name()).collect();
            return Decision {
                slot,
                candidate: Some(best.id),
                name: best.name.clone(),
                value: f64::NAN,
                cost_s: best.cost_s(from, &limits, scale),
                wear_mm: wear_of(best).0,
                wear_rate_mm_per_mj: wear_rate,
                error_pct: f64::NAN,
                error_after_pct: f64::NAN,
                full_error_pct: f64::NAN,
                target_pct: f64::NAN,
                reason: format!("no model of {} yet: the cheapest sweep that measures it", names.join(", ")),
            };
        }

        // The known targets' models; errors now and with every remaining candidate.
        let known: Vec<(Target, &crate::model::TargetModel)> =
            targets.iter().filter_map(|&t| view.target(t).map(|m| (t, m))).collect();
        if known.is_empty() {
            return close(
                "no target of this slot has a model, and no candidate measures one".into(),
                f64::NAN,
                f64::NAN,
                f64::NAN,
            );
        }
        let sens = |c: &Candidate, t: Target| -> Option<DMatrix<f64>> {
            c.kind.targets().contains(&t).then(|| view.sensitivities(t, &c.points))
        };
        let now: Vec<f64> = known.iter().map(|(_, m)| m.error_pct()).collect();
        let e_now = rms(&now);
        let full: Vec<f64> = known
            .iter()
            .map(|(t, m)| {
                let mut cov = m.cov.clone();
                for c in &remaining {
                    if let Some(j) = sens(c, *t) {
                        cov = design::updated(&cov, &j, m.sigma);
                    }
                }
                100.0 * design::mean_variance(&m.h, &cov).sqrt()
            })
            .collect();
        let e_full = rms(&full);
        // More data never raises the variance: a full-run prediction above today's (or not a
        // number) is round-off, and no reason to call the target met.
        let full_is_sound = e_full.is_finite() && full.iter().zip(&now).all(|(f, n)| f <= &(n * (1.0 + 1e-9)));
        let mut target = if full_is_sound { self.cfg.target_ratio * e_full } else { 0.0 };
        if let Some(abs) = self.cfg.target_error_pct {
            target = target.max(abs);
        }
        let met = if e_now <= target { self.state.target_met.get(slot).copied().unwrap_or(0) + 1 } else { 0 };
        let needed = self.cfg.target_confirmations.max(1);
        let confirm_note =
            if met > 0 { format!("; target met {met} of {needed} decisions in a row") } else { String::new() };
        // Predicted value and error after a candidate.
        let value_of = |c: &Candidate| -> (f64, f64) {
            let after: Vec<f64> = known
                .iter()
                .map(|(t, m)| match sens(c, *t) {
                    Some(j) => 100.0 * design::mean_variance(&m.h, &design::updated(&m.cov, &j, m.sigma)).sqrt(),
                    None => m.error_pct(),
                })
                .collect();
            let value: f64 =
                now.iter().zip(&after).map(|(a, b)| (a * a - b * b).max(0.0)).sum::<f64>() / known.len() as f64;
            (value, rms(&after))
        };
        // Before the slot closes, for whatever reason: its data must reach where its sweeps reach.
        let widen_or_close = |why: String| -> Decision {
            match self.widening(slot, &remaining, &affordable, from, scale) {
                Some((c, beyond)) => {
                    let (value, e_after) = value_of(c);
                    Decision {
                        slot,
                        candidate: Some(c.id),
                        name: c.name.clone(),
                        value,
                        cost_s: c.cost_s(from, &limits, scale),
                        wear_mm: wear_of(c).0,
                        wear_rate_mm_per_mj: wear_rate,
                        error_pct: e_now,
                        error_after_pct: e_after,
                        full_error_pct: e_full,
                        target_pct: target,
                        reason: format!(
                            "the data must reach where the slot's sweeps reach before it closes ({why}): {}; predicted error {e_now:.3} → {e_after:.3} % (target {target:.3} %){confirm_note}",
                            beyond.join(", ")
                        ),
                    }
                }
                None => close(why, e_now, e_full, target),
            }
        };
        if met >= needed {
            let in_a_row = if needed > 1 { format!(", {met} decisions in a row") } else { String::new() };
            return widen_or_close(format!(
                "predicted error {e_now:.3} % ≤ target {target:.3} % (full procedure: {e_full:.3} %){in_a_row}"
            ));
        }

        let scored: Vec<(bool, bool, Scored)> = remaining
            .iter()
            .map(|c| {
                let (value, e_after) = value_of(c);
                let useful = e_after <= e_now * (1.0 - self.cfg.min_relative_gain);
                let cost_s = c.cost_s(from, &limits, scale);
                let (wear_mm, wear_s) = wear_of(c);
                let s =
                    Scored { id: c.id, value, cost_s, wear_mm, charged_s: cost_s + wear_s, error_after_pct: e_after };
                (c.severe, useful && affordable(c), s)
            })
            .collect();
        let best_of = |severe: bool| {
            scored.iter().filter(|(sv, ok, _)| *sv == severe && *ok).map(|(_, _, s)| s).fold(
                None::<&Scored>,
                |best, s| match best {
                    Some(b) if b.value / b.charged_s.max(1e-9) >= s.value / s.charged_s.max(1e-9) => Some(b),
                    _ => Some(s),
                },
            )
        };
        let (pick, tier) = match best_of(false) {
            Some(s) => (s, "best value per second"),
            None => match best_of(true) {
                Some(s) => (s, "severe, run last: best value per second"),
                None => {
                    let any_useful_unaffordable = scored.iter().any(|(_, ok, s)| !ok && s.error_after_pct < e_now);
                    let why = if any_useful_unaffordable && spent > 0.0 {
                        format!("rig-time budget of {budget_s:.0} s spent ({spent:.0} s)")
                    } else {
                        format!(
                            "no sweep lowers the predicted error ({e_now:.3} %) by {:.1} % or more",
                            100.0 * self.cfg.min_relative_gain
                        )
                    };
                    return widen_or_close(why);
                }
            },
        };
        let c = &self.lib.candidates[pick.id];
        let wear_note = if pick.wear_mm > 0.0 {
            let weighed = self.state.measured_wear.is_some() && self.cfg.wear_rate_log_sd > 0.0;
            let measured = if weighed { ", measured" } else { "" };
            format!(
                " + {:.0} s of tread ({:.4} mm at {wear_rate:.3} mm/MJ{measured})",
                pick.charged_s - pick.cost_s,
                pick.wear_mm
            )
        } else {
            String::new()
        };
        let pressure_note = if (c.pressure_bar - from.pressure_bar).abs() > 1e-9 {
            format!(", pressure {} → {} bar", fmt(from.pressure_bar), fmt(c.pressure_bar))
        } else {
            String::new()
        };
        Decision {
            slot,
            candidate: Some(pick.id),
            name: c.name.clone(),
            value: pick.value,
            cost_s: pick.cost_s,
            wear_mm: pick.wear_mm,
            wear_rate_mm_per_mj: wear_rate,
            error_pct: e_now,
            error_after_pct: pick.error_after_pct,
            full_error_pct: e_full,
            target_pct: target,
            reason: format!(
                "{tier}: {:.4} (%²) in {:.0} s{wear_note}{pressure_note}; predicted error {e_now:.3} → {:.3} % (target {target:.3} %){confirm_note}",
                pick.value, pick.cost_s, pick.error_after_pct
            ),
        }
    }
}

impl Planner {
    /// The affordable candidate of `slot` that takes the slot's data furthest beyond where the
    /// candidates of its kind run so far reached (most axes, then the cheapest), with where;
    /// `None` when none does or [`AdaptiveConfig::cover_envelope`] is off.
    fn widening<'a>(
        &self,
        slot: usize,
        remaining: &[&'a Candidate],
        affordable: &dyn Fn(&Candidate) -> bool,
        from: Setpoint,
        scale: f64,
    ) -> Option<(&'a Candidate, Vec<String>)> {
        if !self.cfg.cover_envelope {
            return None;
        }
        let mut best: Option<(&'a Candidate, Vec<String>, f64)> = None;
        for &c in remaining.iter().filter(|c| affordable(c)) {
            let data = self
                .state
                .used
                .iter()
                .map(|&id| &self.lib.candidates[id])
                .filter(|u| u.slot == slot && u.kind == c.kind)
                .map(|u| u.extent)
                .reduce(Extent::union);
            let beyond = match data {
                Some(d) => c.extent.beyond(&d),
                None => vec![format!("no {:?} sweep has run", c.kind).to_lowercase()],
            };
            if beyond.is_empty() {
                continue;
            }
            let cost = c.cost_s(from, &self.lib.limits, scale);
            let better = match &best {
                None => true,
                Some((_, b, bc)) => beyond.len() > b.len() || (beyond.len() == b.len() && cost < *bc),
            };
            if better {
                best = Some((c, beyond, cost));
            }
        }
        best.map(|(c, b, _)| (c, b))
    }
}

fn fmt(x: f64) -> String {
    procedure::primitives::fmt_num(x)
}

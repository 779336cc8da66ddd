//! Stage 5, `fy_combined`: the combined-slip weighting Gyκ of FY and the κ-induced side force
//! SVyκ (RBY1–4, RCY1, REY1–2, RHY1–2, RVY1–6) from slip-ratio sweeps at a held slip angle.
//! The weighting stays in [0, 1] by construction (penalties); a square friction ellipse — the
//! known local minimum (thesis §5) — sends the fit to other starts.

use mftyre::TyreParams;

use crate::checks;
use crate::engine::{Channel, apply};
use crate::error::FitError;
use crate::physics::MarginSet;
use crate::stages::context::{Ctx, StagePoints};
use crate::stages::fx_combined::combined_points;
use crate::stages::steps::{decide_keys, finish, run_steps};
use crate::stages::{Stage, StageReport};

const KEYS: [&str; 15] = [
    "RBY1", "RBY2", "RBY3", "RCY1", "REY1", "RHY1", "REY2", "RHY2", "RBY4", "RVY1", "RVY2", "RVY4", "RVY5", "RVY6",
    "RVY3",
];
/// The weighting function's keys (fitted first, before the side-force terms join).
const WEIGHTING: [&str; 9] = ["RBY1", "RBY2", "RBY3", "RCY1", "REY1", "RHY1", "REY2", "RHY2", "RBY4"];

/// Pure-FY keys the combined sweeps identify when no cornering sweeps fitted them (a
/// drive/brake/combined run alone): friction with its load and camber terms, cornering
/// stiffness with its load and camber terms, and the offsets. The curve's shape (C, E) needs a
/// slip-angle sweep; two or three held slip angles do not give it, so it keeps the template's.
const PURE_FROM_COMBINED: [&str; 8] = ["PDY1", "PDY2", "PDY3", "PKY1", "PKY2", "PKY6", "PHY1", "PVY1"];
/// Points a pure-lateral stage needs (`fy_pure`'s minimum).
const FY_PURE_MIN_POINTS: usize = 50;

/// The pure-FY keys this stage must fit itself: all of [`PURE_FROM_COMBINED`] when `fy_pure`
/// had too few points to run (and was not skipped on request: then the template is wanted).
fn pure_keys_to_fit(ctx: &Ctx) -> Vec<&'static str> {
    if ctx.opts.skip_stages.iter().any(|s| s == "fy_pure") {
        return Vec::new();
    }
    let pure_points = crate::stages::fy_pure::FyPure.select(ctx).map_or(0, |s| s.points.len());
    if pure_points >= FY_PURE_MIN_POINTS { Vec::new() } else { PURE_FROM_COMBINED.to_vec() }
}

/// The stage.
#[derive(Debug)]
pub struct FyCombined;

impl Stage for FyCombined {
    fn name(&self) -> &'static str {
        "fy_combined"
    }

    fn channel(&self) -> Channel {
        Channel::Fy
    }

    fn margins(&self) -> Option<MarginSet> {
        Some(MarginSet::FyCombined)
    }

    fn select(&self, ctx: &Ctx) -> Option<StagePoints> {
        Some(combined_points(ctx, |s| s.fy_n, ctx.opts.max_points * 2 / 3))
    }

    fn fit(
        &self,
        ctx: &Ctx,
        params: &mut TyreParams,
        data: &StagePoints,
        rep: &mut StageReport,
    ) -> Result<(), FitError> {
        let all = &data.points;
        if all.len() < 30 {
            return Err(FitError::NotEnoughData { stage: self.name().into(), points: all.len(), needed: 30 });
        }
        //           RBY1  RBY2  RBY3 RCY1 REY1 RHY1 REY2 RHY2 RBY4 RVY1 RVY2 RVY4 RVY5 RVY6 RVY3
        let starts: [[f64; 15]; 3] = [
            [10.0, 8.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.9, 10.0, 0.0],
            [20.0, 15.0, 0.0, 1.1, -0.5, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.9, 20.0, 0.0],
            [6.0, 4.0, 0.0, 0.9, 0.3, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.9, 5.0, 0.0],
        ];
        apply(params, &KEYS, &starts[0]);
        let pure = pure_keys_to_fit(ctx);
        // Near-pure points: the combined sweeps' passes through zero slip ratio.
        let near_pure: Vec<_> = all.iter().copied().filter(|p| p.input.kappa.abs() < 0.02).collect();
        if !pure.is_empty() {
            // Friction starts at the largest |FY|/FZ seen near zero slip ratio (a lower bound:
            // the held slip angles may sit below the peak).
            let mu = near_pure.iter().map(|p| (p.measured / p.input.fz_n).abs()).fold(0.0, f64::max);
            if mu > 0.2 && mu.is_finite() {
                apply(params, &["PDY1", "PDY2"], &[1.05 * mu, 0.0]);
            }
            rep.notes.push(format!(
                "fy_pure had no cornering data: its friction, stiffness and offset terms ({}) are fitted here from the combined sweeps ({} near-pure points; friction starts at {:.2})",
                pure.join(", "),
                near_pure.len(),
                1.05 * mu
            ));
        }
        // Fitting pure FY here, its margins (friction > 0, curvature ≤ 1, stiffness sign) bind too.
        let margins = if pure.is_empty() { self.margins() } else { Some(MarginSet::FyPureAndCombined) };
        let start = params.clone();
        let candidates: Vec<&'static str> = pure.iter().copied().chain(KEYS).collect();
        decide_keys(ctx, params, &start, rep, &candidates, data, Channel::Fy);
        let mut steps: Vec<crate::stages::steps::Step> = Vec::new();
        if !pure.is_empty() && near_pure.len() > 2 * pure.len() {
            steps.push(("pure from near-pure points", pure.clone(), near_pure.clone()));
        }
        steps.push(("weighting", WEIGHTING.to_vec(), all.clone()));
        steps.push(("all", candidates.clone(), all.clone()));
        let (fz0, p0) = (ctx.nominal.fz0_n, ctx.nominal.p0_pa);
        let mut best: Option<(f64, TyreParams, StageReport)> = None;
        for (i, st) in starts.iter().enumerate() {
            let mut trial = params.clone();
            let (keys, values): (Vec<&'static str>, Vec<f64>) =
                KEYS.iter().copied().zip(st.iter().copied()).filter(|(k, _)| rep.free.contains(k)).unzip();
            // Warm: the first trial is the previous solution (decide_keys put it in place).
            if i > 0 || ctx.warm(self.name()).is_none() {
                apply(&mut trial, &keys, &values);
            }
            let mut r = rep.clone();
            run_steps(ctx, &mut trial, &mut r, Channel::Fy, all, &steps, margins)?;
            let square = checks::ellipse_squareness(&trial, fz0, p0);
            let physical = margins.is_none_or(|m| crate::physics::worst(&trial, m, &ctx.grid).is_none());
            let ok = physical && square < checks::SQUARE_LIMIT;
            if i > 0 {
                rep.notes.push(format!(
                    "start {}: rmse {:.1} N, ellipse squareness {square:.2}{}",
                    i + 1,
                    r.rmse,
                    if physical { "" } else { " (non-physical)" }
                ));
            }
            let score = if ok { r.rmse } else { f64::INFINITY };
            if best.as_ref().is_none_or(|b| score < b.0 || (b.0.is_infinite() && r.rmse < b.2.rmse)) {
                best = Some((score, trial, r));
            }
            if ok && i == 0 {
                break;
            }
            if i == 0 {
                rep.notes.push(format!(
                    "friction ellipse squareness {square:.2} (limit {}){}: trying other starts",
                    checks::SQUARE_LIMIT,
                    if physical { "" } else { ", weighting non-physical" }
                ));
            }
        }
        if let Some((_, t, r)) = best {
            *params = t;
            rep.adopt_fit(&r);
        }
        rep.notes.push(format!(
            "friction ellipse squareness {:.2} at Fz0 (1 = round, 2 = square; limit {})",
            checks::ellipse_squareness(params, fz0, p0),
            checks::SQUARE_LIMIT
        ));
        finish(ctx, params, &start, rep, Channel::Fy, data, margins)
    }
}

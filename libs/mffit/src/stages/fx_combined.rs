//! Stage 4, `fx_combined`: the combined-slip weighting Gxα of FX (RBX1–3, RCX1, REX1–2, RHX1)
//! from slip-ratio sweeps at a held slip angle. Gxα stays in [0, 1] by construction: the
//! [`MarginSet::FxCombined`] margins are penalties of the fit.

use mftyre::TyreParams;

use crate::engine::{Channel, apply};
use crate::error::FitError;
use crate::physics::MarginSet;
use crate::stages::context::{Ctx, StagePoints, peak_abs};
use crate::stages::fx_pure::slip_ratio_sweep;
use crate::stages::steps::{decide_keys, finish, run_steps};
use crate::stages::{Stage, StageReport};

/// |α| from which a slip-ratio sweep counts as combined slip.
pub const COMBINED_ALPHA_DEG: f64 = 0.5;

const KEYS: [&str; 7] = ["RBX1", "RBX2", "RCX1", "REX1", "RHX1", "REX2", "RBX3"];

/// Combined-slip points of `measured`: slip-ratio sweeps at |α| ≥ [`COMBINED_ALPHA_DEG`].
pub fn combined_points(ctx: &Ctx, measured: fn(&crate::data::Sample) -> f64, max: usize) -> StagePoints {
    ctx.points(|s| slip_ratio_sweep(s, ctx), |s| s.alpha_rad.abs() >= COMBINED_ALPHA_DEG.to_radians(), measured, max)
}

/// The stage.
#[derive(Debug)]
pub struct FxCombined;

impl Stage for FxCombined {
    fn name(&self) -> &'static str {
        "fx_combined"
    }

    fn channel(&self) -> Channel {
        Channel::Fx
    }

    fn margins(&self) -> Option<MarginSet> {
        Some(MarginSet::FxCombined)
    }

    fn select(&self, ctx: &Ctx) -> Option<StagePoints> {
        Some(combined_points(ctx, |s| s.fx_n, ctx.opts.max_points * 2 / 3))
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
        // Starts: Gxα falls to ~cos(atan(Bxα·α)) — a typical tyre halves its Fx near 10° slip
        // angle (Bxα ≈ 10); a race tyre holds it longer.
        let starts: [[f64; 7]; 3] = [
            [10.0, 8.0, 1.0, 0.0, 0.0, 0.0, 0.0],
            [20.0, 15.0, 1.1, -0.5, 0.0, 0.0, 0.0],
            [5.0, 5.0, 0.9, 0.3, 0.0, 0.0, 0.0],
        ];
        apply(params, &KEYS, &starts[0]);
        let start = params.clone();
        decide_keys(ctx, params, &start, rep, &KEYS, data, Channel::Fx);
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
            run_steps(
                ctx,
                &mut trial,
                &mut r,
                Channel::Fx,
                all,
                &[("all", KEYS.to_vec(), all.clone())],
                self.margins(),
            )?;
            let physical = crate::physics::worst(&trial, MarginSet::FxCombined, &ctx.grid).is_none();
            if i > 0 {
                rep.notes.push(format!(
                    "start {}: rmse {:.1} N{}",
                    i + 1,
                    r.rmse,
                    if physical { "" } else { " (non-physical)" }
                ));
            }
            // Physical first, then the lower RMSE.
            let score = if physical { r.rmse } else { f64::INFINITY };
            if best.as_ref().is_none_or(|b| score < b.0 || (b.0.is_infinite() && r.rmse < b.2.rmse)) {
                best = Some((score, trial, r));
            }
            if physical && i == 0 && best.as_ref().is_some_and(|b| b.2.rmse < 0.03 * peak_abs(all)) {
                break;
            }
        }
        if let Some((_, t, r)) = best {
            *params = t;
            rep.adopt_fit(&r);
        }
        finish(ctx, params, &start, rep, Channel::Fx, data, self.margins())
    }
}

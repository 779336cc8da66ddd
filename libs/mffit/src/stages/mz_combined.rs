//! Stage 6, `mz_combined`: the s-arm of the combined aligning moment (SSZ1–4): Fx times a lever
//! that depends on Fy and camber; a fit that makes MZ non-finite or worse is not kept. Then the
//! trail and residual torque under combined slip are refined with `mz_pure`'s points
//! ([`crate::stages::mz_joint`]), kept only when the pure fit stays where it was.

use mftyre::TyreParams;

use crate::engine::{Channel, apply};
use crate::error::FitError;
use crate::fit::rms;
use crate::physics::MarginSet;
use crate::stages::context::{Ctx, StagePoints};
use crate::stages::fx_combined::combined_points;
use crate::stages::steps::{decide_keys, finish, run_steps};
use crate::stages::{Stage, StageReport};

/// The arm s of the combined moment (SSZ1–4), this stage's own keys.
pub(crate) const KEYS: [&str; 4] = ["SSZ1", "SSZ2", "SSZ3", "SSZ4"];
/// Pure-MZ keys the combined sweeps identify when no cornering sweeps fitted them: the trail's
/// size with its load term, its stiffness, the residual torque and the offset. The trail's
/// shape (C, E) needs a slip-angle sweep.
const PURE_FROM_COMBINED: [&str; 6] = ["QDZ1", "QDZ2", "QBZ1", "QDZ6", "QDZ7", "QHZ1"];
/// Points `mz_pure` needs.
const MZ_PURE_MIN_POINTS: usize = 50;

/// The pure-MZ keys this stage fits itself: when `mz_pure` had too few points to run and was
/// not skipped on request.
fn pure_keys_to_fit(ctx: &Ctx) -> Vec<&'static str> {
    if ctx.opts.skip_stages.iter().any(|s| s == "mz_pure") {
        return Vec::new();
    }
    let pure_points = crate::stages::mz_pure::MzPure.select(ctx).map_or(0, |s| s.points.len());
    if pure_points >= MZ_PURE_MIN_POINTS { Vec::new() } else { PURE_FROM_COMBINED.to_vec() }
}

/// The stage.
#[derive(Debug)]
pub struct MzCombined;

impl Stage for MzCombined {
    fn name(&self) -> &'static str {
        "mz_combined"
    }

    fn channel(&self) -> Channel {
        Channel::Mz
    }

    fn select(&self, ctx: &Ctx) -> Option<StagePoints> {
        Some(combined_points(ctx, |s| s.mz_nm, ctx.opts.max_points / 2))
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
        apply(params, &KEYS, &[0.0; 4]);
        let at_zero = rms(params, all, Channel::Mz);
        if !at_zero.is_finite() {
            rep.notes.push(
                "the combined MZ of the earlier stages is not finite on this data: the s-arm cannot be fitted".into(),
            );
        }
        let pure = pure_keys_to_fit(ctx);
        let margins = if pure.is_empty() {
            None
        } else {
            rep.notes.push(format!(
                "mz_pure had no cornering data: its trail, residual-torque and offset terms ({}) are fitted here from the combined sweeps",
                pure.join(", ")
            ));
            Some(MarginSet::MzPure)
        };
        let candidates: Vec<&'static str> = pure.iter().copied().chain(KEYS).collect();
        let start = params.clone();
        decide_keys(ctx, params, &start, rep, &candidates, data, Channel::Mz);
        let mut steps: Vec<crate::stages::steps::Step> = Vec::new();
        if !pure.is_empty() {
            steps.push(("pure trail", pure.clone(), all.clone()));
        }
        steps.push(("arm", candidates.clone(), all.clone()));
        run_steps(ctx, params, rep, Channel::Mz, all, &steps, margins)?;
        if !(rep.rmse.is_finite() && rep.rmse <= at_zero) {
            *params = start.clone();
            apply(params, &KEYS, &[0.0; 4]);
            rep.rmse = at_zero;
            rep.notes.push("the fitted s-arm did not improve MZ: kept at zero".into());
        }
        rep.notes
            .push("coupled-drive MZ is noisy (thesis: ~22 % on a 385 N·m signal); the s-arm is fitted first".into());
        finish(ctx, params, &start, rep, Channel::Mz, data, margins)?;
        // With cornering data, the trail and residual torque the combined sweeps show are
        // refined together with mz_pure's points (without, they were fitted above).
        if pure.is_empty() {
            crate::stages::mz_joint::refine(ctx, params, rep, data)?;
        }
        Ok(())
    }
}

//! Stage 6, `mz_combined`: the s-arm of the combined aligning moment (SSZ1–4): Fx times a lever
//! that depends on Fy and camber. Coupled-drive MZ is noisy (thesis: ~22 % on a 385 N·m signal),
//! so only the arm is fitted; a fit that makes MZ non-finite or worse is not kept.

use mftyre::TyreParams;

use crate::engine::{Channel, apply};
use crate::error::FitError;
use crate::fit::rms;
use crate::stages::context::{Ctx, StagePoints};
use crate::stages::fx_combined::combined_points;
use crate::stages::steps::{decide_keys, finish, run_steps};
use crate::stages::{Stage, StageReport};

const KEYS: [&str; 4] = ["SSZ1", "SSZ2", "SSZ3", "SSZ4"];

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
        let start = params.clone();
        decide_keys(ctx, params, &start, rep, &KEYS, data, Channel::Mz);
        run_steps(ctx, params, rep, Channel::Mz, all, &[("arm", KEYS.to_vec(), all.clone())], None)?;
        if !(rep.rmse.is_finite() && rep.rmse <= at_zero) {
            apply(params, &KEYS, &[0.0; 4]);
            rep.rmse = at_zero;
            rep.notes.push("the fitted s-arm did not improve MZ: kept at zero".into());
        }
        rep.notes.push(
            "coupled-drive MZ is noisy (thesis: ~22 % on a 385 N·m signal); only the s-arm is fitted here".into(),
        );
        finish(ctx, params, &start, rep, Channel::Mz, data, None)
    }
}

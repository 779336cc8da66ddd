//! Stage 7, `mx`: overturning moment (QSX1–14, PPMX1) on free-rolling data (coupled-drive MX is
//! 25× noisier, thesis §5): the linear terms first, then all, the nonlinear ones kept only if
//! they improve on the linear fit. The nonlinear terms run from several starts (their product
//! has basins the one start does not reach) and the best fit to the data is kept.

use mftyre::TyreParams;

use crate::engine::{Channel, apply};
use crate::error::FitError;
use crate::identify::Held;
use crate::stages::context::{Ctx, StagePoints};
use crate::stages::fy_pure::cornering;
use crate::stages::steps::{decide_keys, finish, run_steps, run_with_restarts};
use crate::stages::{Stage, StageReport};

const LINEAR: [&str; 7] = ["QSX1", "QSX2", "QSX3", "QSX12", "QSX13", "QSX14", "PPMX1"];
const NONLINEAR: [&str; 8] = ["QSX4", "QSX5", "QSX6", "QSX7", "QSX8", "QSX9", "QSX10", "QSX11"];
/// Where the nonlinear terms start: they multiply each other, so zero has no derivatives.
const NONLINEAR_START: [f64; 8] = [0.05, 0.5, 1.0, 1.0, 0.5, 0.5, 0.1, 1.0];
/// Other starts of the nonlinear terms, tried after the first whatever its RMSE (the stage takes
/// a fraction of a second): `QSX4·cos(…)·sin(QSX7·γ + QSX8·atan(QSX9·Fy/Fz0))` reaches the same
/// curve with its sine's arguments of either sign, and the optimiser does not cross from one
/// sign to the other. Measured on an adaptive-plan log of the virtual rig (MF tyre, seed 1): from
/// the first start the fit stopped at RMSE 2.22 N·m (3.8 % of peak from the true tyre), from the
/// second at 1.34 N·m (1.75 %). On GS2MF's log both end at 1.40 N·m.
const NONLINEAR_ALTERNATIVES: [[f64; 8]; 3] = [
    // The whole sine negated (QSX7 and QSX9 with the other sign).
    [0.05, 0.5, 1.0, -1.0, 0.5, -0.5, 0.1, 1.0],
    // Camber against lateral force (QSX7 alone negated).
    [0.05, 0.5, 1.0, -1.0, 0.5, 0.5, 0.1, 1.0],
    // A larger term with a stronger load fade.
    [0.2, 1.0, 5.0, 3.0, 1.0, 0.5, 1.0, 3.0],
];

/// The stage.
#[derive(Debug)]
pub struct Mx;

impl Stage for Mx {
    fn name(&self) -> &'static str {
        "mx"
    }

    fn channel(&self) -> Channel {
        Channel::Mx
    }

    fn select(&self, ctx: &Ctx) -> Option<StagePoints> {
        Some(ctx.points(|s| cornering(s, ctx), |_| true, |s| s.mx_nm, ctx.opts.max_points / 2))
    }

    fn fit(
        &self,
        ctx: &Ctx,
        params: &mut TyreParams,
        data: &StagePoints,
        rep: &mut StageReport,
    ) -> Result<(), FitError> {
        let all = &data.points;
        if all.len() < 50 {
            return Err(FitError::NotEnoughData { stage: self.name().into(), points: all.len(), needed: 50 });
        }
        rep.notes.push("fitted on free-rolling data (coupled-drive MX too noisy, thesis §5)".into());
        let candidates: Vec<&'static str> = [LINEAR.as_slice(), NONLINEAR.as_slice()].concat();
        // The linear terms first, with the nonlinear ones off.
        apply(params, &LINEAR, &[0.0; 7]);
        apply(params, &NONLINEAR, &[0.0; 8]);
        // Held keys go back to zero (no such term), whatever start they were tried from.
        let start = params.clone();
        decide_keys(ctx, params, &start, rep, &candidates, data, Channel::Mx);
        run_steps(ctx, params, rep, Channel::Mx, all, &[("linear", LINEAR.to_vec(), all.clone())], None)?;
        let linear = params.clone();
        let linear_rep = rep.clone();
        let free_nonlinear: Vec<(&'static str, f64)> =
            NONLINEAR.iter().copied().zip(NONLINEAR_START).filter(|(k, _)| rep.free.contains(k)).collect();
        if !free_nonlinear.is_empty() {
            let (k, v): (Vec<&'static str>, Vec<f64>) = free_nonlinear.into_iter().unzip();
            // Warm: the nonlinear terms continue from the previous solution instead.
            if ctx.warm(self.name()).is_none() {
                apply(params, &k, &v);
            }
            let mut r = rep.clone();
            let alternatives: Vec<(&[&'static str], Vec<f64>)> =
                NONLINEAR_ALTERNATIVES.iter().map(|v| (NONLINEAR.as_slice(), v.to_vec())).collect();
            // A floor of zero: every alternative is tried (a warm live update continues from its
            // previous solution instead, `Ctx::restarts`).
            let steps = [("all", candidates.clone(), all.clone())];
            run_with_restarts(ctx, params, &mut r, Channel::Mx, all, &steps, 0.0, &alternatives, None)?;
            if r.rmse.is_finite() && r.rmse < linear_rep.rmse {
                *rep = r;
            } else {
                *params = linear;
                *rep = linear_rep;
                rep.notes.push("nonlinear QSX4–QSX11 did not improve on the linear terms; kept at zero".into());
                // Only the linear keys were fitted: the nonlinear ones are held at zero.
                for k in NONLINEAR.iter().filter(|k| rep.free.contains(k)) {
                    rep.held.push(Held {
                        key: (*k).into(),
                        value: 0.0,
                        reason: "fitting it did not lower the MX error below the linear terms' fit".into(),
                    });
                }
                rep.free.retain(|k| !NONLINEAR.contains(k));
            }
        }
        finish(ctx, params, &start, rep, Channel::Mx, data, None)
    }
}

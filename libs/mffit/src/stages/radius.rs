//! Stage 8, `radius_stiffness`: loaded radius (VERTICAL_STIFFNESS, Q_RE0, Q_FZ2, PFZ1, Q_V1–2,
//! and the force and camber effects Q_FCY, Q_CAM, Q_FCX) and the effective rolling radius
//! (BREFF, DREFF, FREFF from Re = Vx/Ω).
//!
//! Loaded radius under load alone comes from rolling-radius holds where the test has them
//! (GS2MF) and from the near-free-rolling samples inside every sweep (|SA| < 1°, |SR| < 1 %):
//! any real test has those, with or without a rolling-radius section.

use mftyre::TyreParams;

use crate::data::{DataKind, Procedure, Segment};
use crate::engine::{Channel, Point};
use crate::error::FitError;
use crate::fit::{fit_step, rms};
use crate::stages::context::{Ctx, StagePoints, near_p0, peak_abs};
use crate::stages::fx_pure::slip_ratio_sweep;
use crate::stages::fy_pure::cornering;
use crate::stages::steps::{decide_keys, finish, run_steps};
use crate::stages::{Stage, StageReport};
use crate::starts;

const LOADED: [&str; 6] = ["VERTICAL_STIFFNESS", "Q_RE0", "Q_FZ2", "PFZ1", "Q_V2", "Q_V1"];
const LATERAL: [&str; 2] = ["Q_FCY", "Q_CAM"];
const LONGITUDINAL: [&str; 1] = ["Q_FCX"];
const EFFECTIVE: [&str; 3] = ["BREFF", "DREFF", "FREFF"];

fn rolling_radius(seg: &Segment) -> bool {
    seg.kind == DataKind::RollingRadius
}

fn near_free(seg: &Segment, s: &crate::data::Sample) -> bool {
    s.alpha_rad.abs() < 1f64.to_radians() && (seg.procedure == Procedure::FreeRolling || s.kappa.abs() < 0.01)
}

/// The stage.
#[derive(Debug)]
pub struct Radius;

impl Radius {
    /// Loaded-radius points under load alone: rolling-radius holds, and near-free-rolling sweep
    /// samples.
    fn loaded_points(ctx: &Ctx) -> StagePoints {
        let mut sel = ctx.points(rolling_radius, |s| s.rl_m > 0.0 && s.vx_mps > 1.0, |s| s.rl_m, ctx.opts.max_points);
        for (i, seg) in ctx.data.segments.iter().enumerate() {
            if !(cornering(seg, ctx) || slip_ratio_sweep(seg, ctx)) {
                continue;
            }
            let free = seg.procedure == Procedure::FreeRolling;
            for s in ctx.resampled(i).iter() {
                if near_free(seg, s) && s.rl_m > 0.0 && s.vx_mps > 1.0 && s.fz_n > 50.0 && s.rl_m.is_finite() {
                    sel.points.push(Point { input: crate::stages::context::input_of(s, free), measured: s.rl_m });
                    sel.groups.push(i);
                }
            }
        }
        sel.decimated(ctx.opts.max_points)
    }
}

impl Stage for Radius {
    fn name(&self) -> &'static str {
        "radius_stiffness"
    }

    fn channel(&self) -> Channel {
        Channel::Rl
    }

    fn select(&self, ctx: &Ctx) -> Option<StagePoints> {
        Some(Radius::loaded_points(ctx))
    }

    fn fit(
        &self,
        ctx: &Ctx,
        params: &mut TyreParams,
        data: &StagePoints,
        rep: &mut StageReport,
    ) -> Result<(), FitError> {
        let rr = &data.points;
        if rr.len() < 20 {
            return Err(FitError::NotEnoughData { stage: self.name().into(), points: rr.len(), needed: 20 });
        }
        let n_holds = ctx.data.segments.iter().filter(|s| rolling_radius(s)).count();
        rep.notes.push(if n_holds > 0 {
            format!("loaded radius from {n_holds} rolling-radius section(s) and the near-free-rolling sweep samples")
        } else {
            "no rolling-radius section: loaded radius from the near-free-rolling sweep samples (|SA| < 1 deg, |SR| < 1 %)"
                .into()
        });
        // Vertical stiffness start: the slope of radius against load at nominal pressure.
        let xy: Vec<(f64, f64)> =
            rr.iter().filter(|p| near_p0(p, ctx.nominal.p0_pa)).map(|p| (p.input.fz_n, p.measured)).collect();
        if let Some((_, b)) = starts::line_fit(&xy)
            && b < 0.0
        {
            let _ = params.set("VERTICAL_STIFFNESS", -1.0 / b);
        }
        let sweeps = ctx.points(
            |s| cornering(s, ctx) && s.kind == DataKind::Sweep,
            |s| s.rl_m > 0.0,
            |s| s.rl_m,
            ctx.opts.max_points / 3,
        );
        let long = ctx.points(
            |s| slip_ratio_sweep(s, ctx) && s.kind == DataKind::Sweep,
            |s| s.rl_m > 0.0 && s.alpha_rad.abs() < 0.3f64.to_radians(),
            |s| s.rl_m,
            ctx.opts.max_points / 3,
        );
        // Judge all keys on all loaded-radius data together.
        let mut judged = data.clone();
        judged.extend(sweeps.clone());
        judged.extend(long.clone());
        let candidates: Vec<&'static str> = [LOADED.as_slice(), LATERAL.as_slice(), LONGITUDINAL.as_slice()].concat();
        let start = params.clone();
        decide_keys(ctx, params, &start, rep, &candidates, &judged, Channel::Rl);
        let mut steps = vec![("loaded radius", LOADED.to_vec(), rr.clone())];
        if sweeps.len() > 20 {
            steps.push(("lateral force and camber", LATERAL.to_vec(), sweeps.points.clone()));
        }
        if long.len() > 20 {
            steps.push(("longitudinal force", LONGITUDINAL.to_vec(), long.points.clone()));
        }
        // A warm start runs only the last step; this stage's steps free disjoint keys on
        // disjoint points, so its last step is all of them on all of the points.
        if ctx.warm(self.name()).is_some() {
            steps = vec![("all keys", candidates.clone(), judged.points.clone())];
        }
        run_steps(ctx, params, rep, Channel::Rl, rr, &steps, None)?;
        // Judged and refitted on every loaded-radius point: refitted on the near-free-rolling points
        // alone, the force terms drift to whatever fits there (a thermal radius growth moved Q_FCY
        // to 0.14, a 7 mm drop at 10° the cornering sweeps do not show).
        finish(ctx, params, &start, rep, Channel::Rl, &judged, None)?;
        // Effective rolling radius from the free-rolling wheel speed: Re = Vx/Ω.
        let re = ctx.points(
            |s| rolling_radius(s) || cornering(s, ctx),
            |s| s.omega_radps > 1.0 && s.vx_mps > 1.0 && s.alpha_rad.abs() < 1f64.to_radians(),
            |s| s.vx_mps / s.omega_radps,
            ctx.opts.max_points,
        );
        if re.len() > 20 {
            let levels = crate::identify::Levels::of(&re.points, ctx.nominal.fz0_n);
            let judged = crate::identify::structural(params, &EFFECTIVE, &levels);
            for h in judged.held {
                rep.held.push(h);
            }
            if !judged.free.is_empty() {
                let scale = peak_abs(&re.points) / 100.0;
                let o = fit_step(self.name(), params, &judged.free, &re.points, Channel::Re, scale, &ctx.settings)?;
                rep.iterations += o.iterations;
                rep.keys.extend(judged.free.iter().map(|k| k.to_string()));
                rep.notes.push(format!(
                    "effective rolling radius: rmse {:.2} mm over {} points",
                    rms(params, &re.points, Channel::Re) * 1e3,
                    re.len()
                ));
            }
        } else {
            rep.notes.push("no free-rolling wheel speed: BREFF, DREFF, FREFF keep the template's values".into());
        }
        rep.notes.push(format!("loaded radius rmse {:.2} mm", rep.rmse * 1e3));
        Ok(())
    }
}

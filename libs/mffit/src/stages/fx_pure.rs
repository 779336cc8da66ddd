//! Stage 3, `fx_pure`: pure longitudinal force Fx0 (PCX1 … PPX4) from slip-ratio sweeps at
//! (nearly) zero slip angle.

use mftyre::TyreParams;

use crate::data::{Procedure, Segment};
use crate::engine::{Channel, Point, apply};
use crate::error::FitError;
use crate::physics::MarginSet;
use crate::stages::context::{Ctx, StagePoints, is_fm, near_nominal_camber, near_p0};
use crate::stages::steps::{decide_keys, finish, run_with_restarts};
use crate::stages::{Stage, StageReport};
use crate::starts;

const NOMINAL: [&str; 14] =
    ["PCX1", "PDX1", "PDX2", "PEX1", "PEX2", "PEX3", "PEX4", "PKX1", "PKX2", "PKX3", "PHX1", "PHX2", "PVX1", "PVX2"];
const PRESSURE: [&str; 4] = ["PPX1", "PPX2", "PPX3", "PPX4"];
const CURV: &[&str] = &["PEX1", "PEX2", "PEX3", "PEX4"];

/// |α| below which a slip-ratio sweep is pure longitudinal.
pub const PURE_ALPHA_DEG: f64 = 0.3;

/// Slip-ratio (drive/brake and combined) force & moment sweeps.
pub fn slip_ratio_sweep(seg: &Segment, ctx: &Ctx) -> bool {
    seg.procedure == Procedure::BrkDrv && is_fm(seg, ctx.opts)
}

/// The stage.
#[derive(Debug)]
pub struct FxPure;

impl Stage for FxPure {
    fn name(&self) -> &'static str {
        "fx_pure"
    }

    fn channel(&self) -> Channel {
        Channel::Fx0
    }

    fn margins(&self) -> Option<MarginSet> {
        Some(MarginSet::FxPure)
    }

    fn select(&self, ctx: &Ctx) -> Option<StagePoints> {
        Some(ctx.points(
            |s| slip_ratio_sweep(s, ctx),
            |s| s.alpha_rad.abs() < PURE_ALPHA_DEG.to_radians(),
            |s| s.fx_n,
            ctx.opts.max_points,
        ))
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
        let p0 = ctx.nominal.p0_pa;
        let fz0 = ctx.nominal.fz0_n;
        let nominal: Vec<Point> = all.iter().copied().filter(|p| near_nominal_camber(p) && near_p0(p, p0)).collect();
        let base = if nominal.len() > 100 { nominal.clone() } else { all.clone() };
        let mut pk = Vec::new();
        for sw in &ctx.segment_points(|s| slip_ratio_sweep(s, ctx), |s| s.fx_n) {
            let nom: Vec<Point> = sw
                .iter()
                .copied()
                .filter(|p| {
                    p.input.alpha_rad.abs() < PURE_ALPHA_DEG.to_radians() && near_nominal_camber(p) && near_p0(p, p0)
                })
                .collect();
            pk.extend(starts::peaks(&nom, |p| p.input.kappa));
        }
        // Friction and the peak's position only from curves that pass their peak.
        let pk = starts::past_peak(&pk);
        let (mu0, dmu) = starts::friction(&pk, fz0).unwrap_or((1.0, 0.0));
        let c = starts::shape_factor(&pk, 1.6);
        let k = starts::slope_at_zero(&base, |p| p.input.kappa, 0.02).unwrap_or(20.0).max(1.0);
        let bx = k / (c * mu0);
        let x_peak = starts::median(pk.iter().map(|p| p.slip_at_peak).collect()).unwrap_or(0.1);
        let e = starts::curvature(bx, c, x_peak);
        apply(params, &["PCX1", "PDX1", "PDX2", "PEX1", "PKX1", "PKX2", "PKX3"], &[c, mu0, dmu, e, k, 0.0, 0.0]);
        rep.notes.push(format!("start from data: mu {mu0:.3} ({dmu:+.3}/dfz), C {c:.2}, Kxk/Fz {k:.1}, E {e:.2}"));
        let mut candidates: Vec<&'static str> = NOMINAL.to_vec();
        candidates.push("PDX3");
        candidates.extend(PRESSURE);
        let start = params.clone();
        decide_keys(ctx, params, &start, rep, &candidates, data, Channel::Fx0);
        let lin: Vec<Point> = base.iter().copied().filter(|p| p.input.kappa.abs() < 0.03).collect();
        let camber: Vec<Point> = all.iter().copied().filter(|p| near_p0(p, p0)).collect();
        let steps = vec![
            ("stiffness", vec!["PKX1", "PKX2", "PHX1", "PVX1"], lin),
            ("nominal", NOMINAL.to_vec(), base.clone()),
            ("camber", vec!["PDX3"], camber),
            ("pressure", PRESSURE.to_vec(), all.clone()),
            ("all", candidates.clone(), all.clone()),
        ];
        // Ex's load and sign(κ) terms trade off against each other: always try the other
        // curvatures (the stage takes ~0.1 s, and the slip-ratio noise makes the FX noise-floor
        // estimate too high to tell a local minimum from noise).
        let alts = [(CURV, vec![0.3, 0.0, 0.0, 0.3]), (CURV, vec![-0.5, 0.0, 0.0, -0.3])];
        run_with_restarts(ctx, params, rep, Channel::Fx0, all, &steps, 0.0, &alts, self.margins())?;
        finish(ctx, params, &start, rep, Channel::Fx0, data, self.margins())
    }
}

//! Stage 1, `fy_pure`: pure lateral force Fy0 (PCY1 … PPY5) from cornering sweeps, plus the
//! pure-lateral points of slip-ratio sweeps (where the slip ratio crosses zero at a held slip
//! angle and camber): a drive/brake/combined run is often the only data at other cambers.

use mftyre::TyreParams;

use crate::data::{Procedure, Sample, Segment};
use crate::engine::{Channel, Point, apply};
use crate::error::FitError;
use crate::identify::Levels;
use crate::physics::MarginSet;
use crate::stages::context::{Ctx, StagePoints, is_fm, near_nominal_camber, near_p0};
use crate::stages::steps::{decide_keys, finish, run_with_restarts};
use crate::stages::{Stage, StageReport};
use crate::starts;

/// |κ| below which a sample of a slip-ratio sweep counts as pure lateral (Gyκ > 0.999 for any
/// real tyre).
pub const PURE_KAPPA: f64 = 0.005;

const NOMINAL: [&str; 12] =
    ["PCY1", "PDY1", "PDY2", "PEY1", "PEY2", "PEY3", "PKY1", "PKY2", "PKY4", "PHY1", "PHY2", "PVY1"];
const CAMBER: [&str; 10] = ["PDY3", "PEY4", "PEY5", "PKY3", "PKY5", "PKY6", "PKY7", "PVY2", "PVY3", "PVY4"];
const PRESSURE: [&str; 5] = ["PPY1", "PPY2", "PPY3", "PPY4", "PPY5"];

/// The stage.
#[derive(Debug)]
pub struct FyPure;

/// Cornering (free-rolling) force & moment sweeps.
pub fn cornering(seg: &Segment, ctx: &Ctx) -> bool {
    seg.procedure == Procedure::FreeRolling && is_fm(seg, ctx.opts)
}

/// Pure-lateral points of `measured` for the lateral stages: cornering sweeps; and — when those
/// hold fewer than two cambers with the slip angle swept (a camber sweep at one slip angle does
/// not count), or are too few — the samples of slip-ratio sweeps where the
/// wheel is not driven or braked (|κ| < [`PURE_KAPPA`] and |FX| < 3 % of FZ; their κ set to 0).
/// A drive/brake/combined run is often the only data a test has at other cambers. Both
/// conditions matter: at a fast sweep's zero crossing the tread's slip lags the rim's, and the
/// force says where the tread really is.
pub fn lateral_points(ctx: &Ctx, measured: fn(&Sample) -> f64, max: usize) -> StagePoints {
    let sel = ctx.points(|s| cornering(s, ctx), |_| true, measured, usize::MAX);
    let cambers = Levels::of(&sel.points, ctx.nominal.fz0_n).swept_cambers_rad.len();
    if cambers >= 2 && sel.len() >= 50 {
        return sel.decimated(max);
    }
    let mut extra = ctx.points(
        |s| s.procedure == Procedure::BrkDrv && is_fm(s, ctx.opts),
        |s| s.kappa.abs() < PURE_KAPPA && s.fx_n.abs() < 0.03 * s.fz_n,
        measured,
        usize::MAX,
    );
    for p in &mut extra.points {
        p.input.kappa = 0.0;
    }
    // Decimate the cornering data only: the few pure points of the slip-ratio sweeps are all
    // kept (they carry the cambers the cornering data lack).
    let room = max.saturating_sub(extra.len()).max(max / 2);
    let mut sel = sel.decimated(room);
    sel.extend(extra);
    sel
}

impl Stage for FyPure {
    fn name(&self) -> &'static str {
        "fy_pure"
    }

    fn channel(&self) -> Channel {
        Channel::Fy0
    }

    fn margins(&self) -> Option<MarginSet> {
        Some(MarginSet::FyPure)
    }

    fn select(&self, ctx: &Ctx) -> Option<StagePoints> {
        Some(lateral_points(ctx, |s| s.fy_n, ctx.opts.max_points))
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
        let base = if nominal.len() > 100 { &nominal } else { all };

        // Starting values from the data.
        let sweeps = ctx.segment_points(|s| cornering(s, ctx), |s| s.fy_n);
        let mut pk = Vec::new();
        for sw in &sweeps {
            let nom: Vec<Point> = sw.iter().copied().filter(|p| near_nominal_camber(p) && near_p0(p, p0)).collect();
            pk.extend(starts::peaks(&nom, |p| p.input.alpha_rad));
        }
        // Friction and the peak's position only from curves that pass their peak; the maxima of
        // every curve (sweep ends included) give one of the other starts below.
        let every_max = starts::friction(&pk, fz0).unwrap_or((1.0, 0.0));
        let pk = starts::past_peak(&pk);
        let (mu0, dmu) = starts::friction(&pk, fz0).unwrap_or((1.0, 0.0));
        let c = starts::shape_factor(&pk, 1.3);
        let k = starts::slope_at_zero(base, |p| p.input.alpha_rad, 1.5f64.to_radians()).unwrap_or(-15.0);
        // Kyα/Fz ≈ PKY1·sin(PKY4·atan(1/PKY2)) at Fz0 with PKY4 = 2, PKY2 = 1.8.
        let pky1 = k / (2.0 * (1.0f64 / 1.8).atan()).sin();
        let by = (k / (c * mu0)).abs();
        let x_peak = starts::median(pk.iter().map(|p| p.slip_at_peak).collect()).unwrap_or(0.15);
        let e = starts::curvature(by, c, x_peak);
        let shift = starts::line_fit(
            &base
                .iter()
                .filter(|p| p.input.alpha_rad.abs() < 1.0f64.to_radians())
                .map(|p| (p.input.alpha_rad, p.measured / p.input.fz_n))
                .collect::<Vec<_>>(),
        )
        .map(|(a, _)| a)
        .unwrap_or(0.0);
        apply(
            params,
            &["PCY1", "PDY1", "PDY2", "PEY1", "PKY1", "PKY2", "PKY4", "PVY1"],
            &[c, mu0, dmu, e, pky1, 1.8, 2.0, shift],
        );
        rep.notes.push(format!(
            "start from data: mu {mu0:.3} ({dmu:+.3}/dfz), C {c:.2}, Kya/Fz {k:.2}/rad, E {e:.2}, peak at {:.1} deg",
            x_peak.to_degrees()
        ));
        if pk.is_empty() {
            rep.notes.push("no sweep reaches its peak at nominal camber and pressure: friction starts from 1.0".into());
        }
        let mut candidates: Vec<&'static str> = NOMINAL.to_vec();
        candidates.extend(CAMBER);
        candidates.extend(PRESSURE);
        let start = params.clone();
        decide_keys(ctx, params, &start, rep, &candidates, data, Channel::Fy0);

        // Stiffness first on the near-linear part, where the curve says the most about it.
        let lin: Vec<Point> = base.iter().copied().filter(|p| p.input.alpha_rad.abs() < 2.0f64.to_radians()).collect();
        let camber: Vec<Point> = all.iter().copied().filter(|p| near_p0(p, p0)).collect();
        let steps = vec![
            ("stiffness", vec!["PKY1", "PKY2", "PVY1", "PHY1"], lin),
            ("nominal", NOMINAL.to_vec(), base.clone()),
            ("camber", [NOMINAL.as_slice(), CAMBER.as_slice()].concat(), camber),
            ("pressure", PRESSURE.to_vec(), all.clone()),
            ("all", candidates.clone(), all.clone()),
        ];
        // Shape and curvature have local minima (C at its bound, a huge camber term): if the fit
        // stays well above the noise, other shapes — the brush tyre of the virtual rig lands in
        // one from either friction start on some seeds.
        let floor = ctx.noise_floor(|s| cornering(s, ctx), |s| s.fy_n);
        let shape: &[&'static str] = &["PCY1", "PDY1", "PDY2", "PEY1"];
        let alts = [
            (shape, vec![1.3, mu0, dmu, -1.0]),
            (shape, vec![c, every_max.0, every_max.1, e]),
            (shape, vec![1.6, mu0, dmu, 0.0]),
        ];
        run_with_restarts(ctx, params, rep, Channel::Fy0, all, &steps, floor, &alts, self.margins())?;
        finish(ctx, params, &start, rep, Channel::Fy0, data, self.margins())
    }
}

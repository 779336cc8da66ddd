//! Stage 2, `mz_pure`: pure aligning moment Mz0 (QBZ*, QCZ1, QDZ*, QEZ*, QHZ*, PPZ1–2) on the
//! same points as `fy_pure`, through the full model (the trail multiplies the fitted Fy).
//!
//! The full model at κ = 0 is Mz0 + s·Fx(κ = 0) ([`Channel::Mz0`]); the arm s (SSZ) and the
//! force at zero slip ratio (SVx, SHx) are fitted by later stages, so the stage is fitted once
//! more after them where they moved its prediction ([`refit_after_arm`]).

use mftyre::TyreParams;

use crate::engine::{Channel, Point, apply, values_of};
use crate::error::FitError;
use crate::physics::MarginSet;
use crate::stages::context::{Ctx, StagePoints, near_nominal_camber, near_p0};
use crate::stages::fy_pure::{cornering, lateral_points};
use crate::stages::steps::{Step, decide_keys, finish, run_steps, run_with_restarts};
use crate::stages::{Stage, StageData, StageReport};
use crate::starts;

const NOMINAL: [&str; 16] = [
    "QBZ1", "QBZ2", "QBZ3", "QBZ9", "QBZ10", "QCZ1", "QDZ1", "QDZ2", "QDZ6", "QDZ7", "QEZ1", "QEZ2", "QEZ3", "QEZ4",
    "QHZ1", "QHZ2",
];
const CAMBER: [&str; 11] = ["QBZ4", "QBZ5", "QDZ3", "QDZ4", "QDZ8", "QDZ9", "QDZ10", "QDZ11", "QEZ5", "QHZ3", "QHZ4"];
const PRESSURE: [&str; 2] = ["PPZ1", "PPZ2"];
const TRAIL: &[&str] = &["QBZ1", "QCZ1", "QDZ1", "QEZ1"];

/// The stage.
#[derive(Debug)]
pub struct MzPure;

impl Stage for MzPure {
    fn name(&self) -> &'static str {
        "mz_pure"
    }

    fn channel(&self) -> Channel {
        Channel::Mz0
    }

    fn margins(&self) -> Option<MarginSet> {
        Some(MarginSet::MzPure)
    }

    fn select(&self, ctx: &Ctx) -> Option<StagePoints> {
        // Mz runs through the full model: fewer points keep the stage fast; 10 Hz data of a few
        // hundred sweeps still gives thousands.
        Some(lateral_points(ctx, |s| s.mz_nm, ctx.opts.max_points * 2 / 3))
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
        let r0 = ctx.nominal.r0_m;
        let nominal: Vec<Point> = all.iter().copied().filter(|p| near_nominal_camber(p) && near_p0(p, p0)).collect();
        let base = if nominal.len() > 100 { nominal.clone() } else { all.clone() };
        // Pneumatic trail at small slip: t = −Mz/Fy (Fy from the fitted model, less noisy).
        let trails: Vec<f64> = base
            .iter()
            .filter(|p| (0.5f64.to_radians()..2.0f64.to_radians()).contains(&p.input.alpha_rad.abs()))
            .filter_map(|p| {
                let fy = Channel::Fy0.eval(params, &p.input);
                (fy.abs() > 0.05 * p.input.fz_n).then(|| -p.measured / fy * fz0 / (p.input.fz_n * r0))
            })
            .collect();
        let qdz1 = starts::median(trails).unwrap_or(0.1).clamp(0.01, 0.5);
        // Mz changes sign where the trail vanishes: Ct·atan(Bt·α₀) = π/2 with Ct = 1.2.
        let mut crossings = Vec::new();
        for sw in &ctx.segment_points(|s| cornering(s, ctx), |s| s.mz_nm) {
            for w in sw.windows(2) {
                let (a, b) = (w[0], w[1]);
                if a.input.alpha_rad.abs() > 2.0f64.to_radians()
                    && a.measured.signum() != b.measured.signum()
                    && a.input.alpha_rad.signum() == b.input.alpha_rad.signum()
                {
                    crossings.push(a.input.alpha_rad.abs());
                }
            }
        }
        let qbz1 = match starts::median(crossings) {
            Some(a0) if a0 > 0.02 => ((std::f64::consts::FRAC_PI_2 / 1.2).tan() / a0).clamp(2.0, 40.0),
            _ => 10.0,
        };
        apply(params, &["QBZ1", "QCZ1", "QDZ1", "QEZ1"], &[qbz1, 1.2, qdz1, 0.0]);
        rep.notes.push(format!("start from data: trail/R0 {qdz1:.3}, Bt {qbz1:.1}"));
        let mut candidates: Vec<&'static str> = NOMINAL.to_vec();
        candidates.extend(CAMBER);
        candidates.extend(PRESSURE);
        let start = params.clone();
        decide_keys(ctx, params, &start, rep, &candidates, data, Channel::Mz0);
        let camber: Vec<Point> = all.iter().copied().filter(|p| near_p0(p, p0)).collect();
        let steps = vec![
            ("trail", vec!["QBZ1", "QCZ1", "QDZ1", "QDZ2", "QEZ1", "QHZ1"], base.clone()),
            ("nominal", NOMINAL.to_vec(), base.clone()),
            ("camber", [NOMINAL.as_slice(), CAMBER.as_slice()].concat(), camber),
            ("pressure", PRESSURE.to_vec(), all.clone()),
            ("all", candidates.clone(), all.clone()),
        ];
        // Mz's trail and residual-torque terms have local minima: other trail shapes if needed.
        let floor = ctx.noise_floor(|s| cornering(s, ctx), |s| s.mz_nm);
        let alts = [(TRAIL, vec![qbz1 * 0.6, 1.5, qdz1, -1.0]), (TRAIL, vec![qbz1 * 1.5, 1.0, qdz1, 0.5])];
        run_with_restarts(ctx, params, rep, Channel::Mz0, all, &steps, floor, &alts, self.margins())?;
        finish(ctx, params, &start, rep, Channel::Mz0, data, self.margins())
    }
}

/// Smallest RMS change of the pure moment at `mz_pure`'s points since the stage was fitted
/// (what the later stages' arm s·Fx(κ = 0) moved it by), as a share of the stage's RMSE there,
/// for which the stage is refined: below it the later stages moved the pure moment by less than
/// the fit's own scatter (a live update whose arm barely moved is not refined again).
const ARM_SHARE: f64 = 0.1;
/// Largest growth of the combined MZ RMSE (on `mz_combined`'s points) the refinement may cost:
/// the joint refinement of the trail with the combined sweeps traded some pure fit for a
/// combined gain of at least 2 %, and refining the pure fit must not undo that gain.
const COMBINED_TOLERANCE: f64 = 1.02;

/// Refines `mz_pure`'s fitted coefficients once more, on its own points with every other
/// coefficient as the later stages left it, where the arm s·Fx(κ = 0) those stages fitted moves
/// its prediction ([`ARM_SHARE`]): `mz_pure` ran before FX pure and the arm were fitted, so it
/// took the moment of the force the tyre carries at zero slip ratio for its own trail and
/// residual torque, and the written model counted it twice (the virtual rig's MF tyre, three
/// seeds: its MZ at 2·Fz0 off the true tyre's by up to 9.8 N·m; refined, the stage's RMSE
/// 1.81–1.83 → 1.05–1.07 N·m). From where the coefficients are, not from the data's start (a
/// second start-from-data fit with the other coefficients fitted landed in another basin: RMSE
/// 12.8 N·m). Kept where it fits the pure points better and the combined MZ no worse than
/// [`COMBINED_TOLERANCE`]; the stage's report (RMSE, iterations, estimates) follows it.
///
/// `after_stage` holds the model as each stage left it.
pub fn refit_after_arm(
    ctx: &Ctx,
    params: &mut TyreParams,
    stages: &mut [StageReport],
    data: &[StageData],
    after_stage: &[(&'static str, TyreParams)],
) {
    let Some(d) = data.iter().find(|d| d.stage == MzPure.name()) else { return };
    let Some(rep) = stages.iter_mut().find(|r| r.stage == MzPure.name() && r.skipped.is_none()) else { return };
    let Some((_, at_fit)) = after_stage.iter().find(|(name, _)| *name == MzPure.name()) else { return };
    let now = crate::fit::rms(params, &d.points, Channel::Mz0);
    // The pure moment with this stage's own keys as they are now (a joint refinement may have
    // moved them) and everything else as when the stage was fitted: what the later stages moved.
    let own: Vec<&'static str> = [NOMINAL.as_slice(), CAMBER.as_slice(), PRESSURE.as_slice()].concat();
    let mut then = at_fit.clone();
    apply(&mut then, &own, &values_of(params, &own));
    let moved = Channel::Mz0.values_at(params, &d.points);
    let before = Channel::Mz0.values_at(&then, &d.points);
    let arm_rms =
        (moved.iter().zip(&before).map(|(a, b)| (a - b).powi(2)).sum::<f64>() / moved.len().max(1) as f64).sqrt();
    // NaN (no points) counts as nothing moved.
    if arm_rms.is_nan() || arm_rms <= ARM_SHARE * now {
        return;
    }
    let combined = data.iter().find(|c| c.stage == "mz_combined");
    let combined_rms = |p: &TyreParams| combined.map_or(0.0, |c| crate::fit::rms(p, &c.points, Channel::Mz));
    let t = std::time::Instant::now();
    let keys: Vec<&'static str> = rep.free.iter().copied().filter(|k| rep.keys.iter().any(|x| x == k)).collect();
    let sel = StagePoints { points: d.points.clone(), groups: d.groups.clone() };
    let refine: Vec<Step> = vec![("after the arm", keys, d.points.clone())];
    let (start, first_rmse) = (params.clone(), rep.rmse);
    let mut trial = params.clone();
    let mut again = rep.clone();
    let refined = run_steps(ctx, &mut trial, &mut again, Channel::Mz0, &d.points, &refine, MzPure.margins())
        .and_then(|_| finish(ctx, &mut trial, &start, &mut again, Channel::Mz0, &sel, MzPure.margins()));
    let (comb_before, comb_after) = (combined_rms(params), combined_rms(&trial));
    if refined.is_ok() && again.rmse < now && comb_after <= COMBINED_TOLERANCE * comb_before {
        again.notes.push(format!(
            "refined after the arm s·Fx at κ = 0 was fitted (mz_combined's SSZ, fx_pure's force at zero slip \
             ratio; they moved the pure moment here by {arm_rms:.4} RMS): RMSE {first_rmse:.4} at its own fit, {now:.4} with the arm, \
             {:.4} refined; MZ combined {comb_before:.4} → {comb_after:.4}",
            again.rmse
        ));
        again.wall_s += t.elapsed().as_secs_f64();
        *params = trial;
        *rep = again;
    }
}

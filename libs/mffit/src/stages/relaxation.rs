//! Stage 9, `relaxation`: σy from step-steer (distance to 63.2 % of the saturated force minus
//! the distance where the force crosses zero, ± pairs averaged), then Cx from static
//! longitudinal tests (slope of FX against belt travel). The carcass stiffnesses follow:
//! Cy = Kyα/σy, σx = Kxκ/Cx. Not a least-squares fit over sweeps, so not cross-validated.

use mftyre::{MfInput, TyreParams};

use crate::data::{DataKind, Sample};
use crate::engine::{Channel, Point};
use crate::error::FitError;
use crate::fit::{fit_step, rms};
use crate::stages::context::{Ctx, StagePoints, input_of};
use crate::stages::{Stage, StageReport};
use crate::starts;

/// The stage.
#[derive(Debug)]
pub struct Relaxation;

impl Stage for Relaxation {
    fn name(&self) -> &'static str {
        "relaxation"
    }

    fn channel(&self) -> Channel {
        Channel::SigmaY
    }

    fn select(&self, _ctx: &Ctx) -> Option<StagePoints> {
        None
    }

    fn fit(
        &self,
        ctx: &Ctx,
        params: &mut TyreParams,
        _data: &StagePoints,
        rep: &mut StageReport,
    ) -> Result<(), FitError> {
        stage_relaxation(ctx, params, rep)
    }
}

fn stage_relaxation(ctx: &Ctx, params: &mut TyreParams, rep: &mut StageReport) -> Result<(), FitError> {
    let mut sigma_pts = Vec::new();
    for seg in ctx.data.segments.iter().filter(|s| s.kind == DataKind::StepSteer) {
        if let Some((sigma, s)) = step_steer_length(&seg.samples) {
            let input = MfInput {
                alpha_rad: 0.0,
                kappa: 0.0,
                vx_mps: ctx.nominal.v0_mps,
                omega_radps: 0.0,
                ..input_of(&s, true)
            };
            sigma_pts.push(Point { input, measured: sigma });
        }
    }
    let mut cx_pts = Vec::new();
    let static_tests = ctx.data.segments.iter().filter(|s| s.kind == DataKind::StaticLong).count();
    for seg in ctx.data.segments.iter().filter(|s| s.kind == DataKind::StaticLong) {
        if let Some((cx, s)) = static_stiffness(&seg.samples) {
            let input = MfInput {
                alpha_rad: 0.0,
                kappa: 0.0,
                gamma_rad: 0.0,
                vx_mps: ctx.nominal.v0_mps,
                omega_radps: 0.0,
                ..input_of(&s, true)
            };
            cx_pts.push(Point { input, measured: cx });
        }
    }
    if sigma_pts.is_empty() && cx_pts.is_empty() {
        rep.skipped = Some(format!(
            "no usable step-steer or static longitudinal tests ({static_tests} static tests without resolved belt travel)"
        ));
        return Ok(());
    }
    if cx_pts.len() >= 2 {
        let mean = cx_pts.iter().map(|p| p.measured).sum::<f64>() / cx_pts.len() as f64;
        let _ = params.set("LONGITUDINAL_STIFFNESS", mean);
        let keys: Vec<&'static str> = if cx_pts.len() > 6 {
            vec!["LONGITUDINAL_STIFFNESS", "PCFX1", "PCFX2", "PCFX3"]
        } else {
            vec!["LONGITUDINAL_STIFFNESS"]
        };
        let o = fit_step("relaxation", params, &keys, &cx_pts, Channel::Cx, mean / 100.0, &ctx.settings)?;
        rep.iterations += o.iterations;
        rep.keys.extend(keys.iter().map(|k| k.to_string()));
        let sx: Vec<f64> =
            cx_pts.iter().map(|p| mftyre::evaluate(params, mftyre::UseMode::M211, &p.input).sigmax_m).collect();
        rep.notes.push(format!(
            "static longitudinal: {} tests, Cx {:.0} N/m at Fz0; sigma_x = Kxk/Cx {:.3}..{:.3} m",
            cx_pts.len(),
            params.get("LONGITUDINAL_STIFFNESS").unwrap_or(f64::NAN),
            sx.iter().copied().fold(f64::INFINITY, f64::min),
            sx.iter().copied().fold(f64::NEG_INFINITY, f64::max)
        ));
    } else {
        rep.notes.push(if static_tests > 0 {
            format!(
                "{static_tests} static longitudinal tests, but the belt is not seen moving in TRAJVELW during the drag, so LONGDISP is unknown: LONGITUDINAL_STIFFNESS keeps the template value"
            )
        } else {
            "no static longitudinal data: LONGITUDINAL_STIFFNESS keeps the template value".into()
        });
    }
    if sigma_pts.len() >= 2 {
        // Cy = Kyα/σy point by point for the start.
        let cys: Vec<f64> = sigma_pts
            .iter()
            .map(|p| (mftyre::evaluate(params, mftyre::UseMode::M211, &p.input).kya_nprad / p.measured).abs())
            .collect();
        let _ = params.set("LATERAL_STIFFNESS", cys.iter().sum::<f64>() / cys.len() as f64);
        let keys: Vec<&'static str> = if sigma_pts.len() > 6 {
            vec!["LATERAL_STIFFNESS", "PCFY1", "PCFY2", "PCFY3"]
        } else {
            vec!["LATERAL_STIFFNESS"]
        };
        let mean = sigma_pts.iter().map(|p| p.measured).sum::<f64>() / sigma_pts.len() as f64;
        let o = fit_step("relaxation", params, &keys, &sigma_pts, Channel::SigmaY, mean / 100.0, &ctx.settings)?;
        rep.iterations += o.iterations;
        rep.keys.extend(keys.iter().map(|k| k.to_string()));
        rep.rmse = rms(params, &sigma_pts, Channel::SigmaY);
        rep.points = sigma_pts.len();
        // The stage selects no force points: its NRMSE is in % of the largest relaxation length.
        rep.peak = sigma_pts.iter().map(|p| p.measured.abs()).fold(0.0, f64::max);
        rep.notes.push(format!(
            "step-steer: {} tests, sigma_y {:.3} m mean, rmse {:.3} m",
            sigma_pts.len(),
            mean,
            rep.rmse
        ));
    } else {
        rep.notes.push("no step-steer data: LATERAL_STIFFNESS keeps the template value".into());
    }
    rep.termination = "direct".into();
    Ok(())
}

/// Lateral relaxation length of one step-steer test and the mean rolling sample.
///
/// The test rolls at zero slip, stops, steers at standstill and rolls again holding the slip
/// angle; only the roll after the last standstill counts (the segment may begin with the
/// previous test's steer-back).
pub fn step_steer_length(samples: &[Sample]) -> Option<(f64, Sample)> {
    let a_max = samples.iter().map(|s| s.alpha_rad.abs()).fold(0.0, f64::max);
    if a_max < 0.2f64.to_radians() {
        return None;
    }
    // The standstill with the wheel steered: the roll starts after it.
    let stop = samples.iter().rposition(|s| s.vx_mps.abs() < 0.05 && s.alpha_rad.abs() > 0.5 * a_max)?;
    let rolling: Vec<&Sample> = samples[stop..].iter().take_while(|s| s.alpha_rad.abs() > 0.5 * a_max).collect();
    if rolling.len() < 20 {
        return None;
    }
    let d0 = rolling[0].dist_m;
    let n = rolling.len();
    let tail = &rolling[n * 3 / 4..];
    let fy_sat = tail.iter().map(|s| s.fy_n).sum::<f64>() / tail.len() as f64;
    if fy_sat.abs() < 50.0 {
        return None;
    }
    // Smooth lightly: noise near zero would trigger the crossings early.
    let smooth: Vec<f64> = (0..n)
        .map(|i| {
            let lo = i.saturating_sub(2);
            let hi = (i + 3).min(n);
            rolling[lo..hi].iter().map(|s| s.fy_n).sum::<f64>() / (hi - lo) as f64
        })
        .collect();
    let cross = |level: f64| -> Option<f64> {
        if (smooth[0] - level) * fy_sat.signum() >= 0.0 {
            return Some(0.0);
        }
        (1..n).find(|&i| (smooth[i] - level) * fy_sat.signum() >= 0.0).map(|i| {
            let (a, b) = (smooth[i - 1], smooth[i]);
            let f = if (b - a).abs() > 1e-9 { ((level - a) / (b - a)).clamp(0.0, 1.0) } else { 0.0 };
            rolling[i - 1].dist_m + f * (rolling[i].dist_m - rolling[i - 1].dist_m) - d0
        })
    };
    let d63 = cross(0.632 * fy_sat)?;
    let dz = cross(0.0).unwrap_or(0.0).min(d63);
    let mut mean = *rolling[n / 2];
    mean.fz_n = rolling.iter().map(|s| s.fz_n).sum::<f64>() / n as f64;
    mean.p_pa = rolling.iter().map(|s| s.p_pa).sum::<f64>() / n as f64;
    Some((d63 - dz, mean))
}

/// Static longitudinal stiffness of one test: the slope of FX against belt travel (LONGDISP)
/// over the elastic part (below half the largest force, before the patch slides). `None` when
/// the belt is not seen moving over that part (e.g. a rig that reports TRAJVELW = 0 while it
/// drags the belt).
pub fn static_stiffness(samples: &[Sample]) -> Option<(f64, Sample)> {
    let fmax = samples.iter().map(|s| s.fx_n.abs()).fold(0.0, f64::max);
    if fmax < 100.0 {
        return None;
    }
    // The drag itself: from the last rolling sample on.
    let start = samples.iter().rposition(|s| s.vx_mps > 0.05).map(|i| i + 1).unwrap_or(0);
    let drag = &samples[start.min(samples.len())..];
    let xy: Vec<(f64, f64)> = drag.iter().filter(|s| s.fx_n.abs() < 0.5 * fmax).map(|s| (s.dist_m, s.fx_n)).collect();
    // The belt must be seen moving: a mean TRAJVELW clearly above its noise (integrating pure
    // noise gives a random walk, not a displacement).
    let v: Vec<f64> =
        drag.iter().filter(|s| (0.1 * fmax..0.5 * fmax).contains(&s.fx_n.abs())).map(|s| s.vx_mps).collect();
    let n = v.len().max(1) as f64;
    let mean_v = v.iter().sum::<f64>() / n;
    let sd_v = (v.iter().map(|x| (x - mean_v) * (x - mean_v)).sum::<f64>() / n).sqrt();
    if v.len() < 5 || mean_v.abs() < 1e-3 || mean_v.abs() < 3.0 * sd_v / n.sqrt() {
        return None;
    }
    let (_, b) = starts::line_fit(&xy)?;
    let mut mean = drag[drag.len() / 2];
    mean.fz_n = drag.iter().map(|s| s.fz_n).sum::<f64>() / drag.len() as f64;
    mean.p_pa = drag.iter().map(|s| s.p_pa).sum::<f64>() / drag.len() as f64;
    (b.abs() > 0.0).then_some((b.abs(), mean))
}

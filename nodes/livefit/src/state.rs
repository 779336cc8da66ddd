//! A fit as a `tyre_msgs/ModelState`: per stage status, error and coefficients, and the
//! prediction-uncertainty maps.

use mffit::FitResult;
use mffit::identify::is_structural;
use mffit::prediction::{EnvelopeGrid, MapChannel, PredictionMap};
use mffit::stages::{STAGES, StageReport};
use tyre_msgs::{ModelCoefficient, ModelMap, ModelStage, ModelState};

/// A stage's status and, unless identified, why not.
///
/// - WAITING: the stage has not been fitted (no or not enough data yet).
/// - FITTING: fitted, but a coefficient is held because the data lack a level of what it
///   multiplies (a camber, pressure or load not yet tested), or a fitted coefficient's standard
///   deviation is not finite (the data do not separate it yet).
/// - IDENTIFIED: fitted, no coefficient held for want of data, every fitted coefficient with a
///   finite standard deviation. Coefficients the Jacobian found without effect or not separable
///   from the others (held at their template values with that reason) do not keep a stage from
///   being identified: no more of the same data would change that.
pub fn stage_status(rep: &StageReport) -> (u8, String) {
    if rep.skipped.is_some() || rep.keys.is_empty() {
        let why = rep.skipped.clone().unwrap_or_else(|| "no data yet".into());
        return (ModelStage::WAITING, why);
    }
    let missing: Vec<&str> = rep.held.iter().filter(|h| is_structural(h)).map(|h| h.key.as_str()).collect();
    if !missing.is_empty() {
        return (ModelStage::FITTING, format!("held for want of data: {}", missing.join(", ")));
    }
    let unsure: Vec<&str> = rep.estimates.iter().filter(|e| !e.std.is_finite()).map(|e| e.key.as_str()).collect();
    if !unsure.is_empty() {
        return (ModelStage::FITTING, format!("no finite standard deviation: {}", unsure.join(", ")));
    }
    (ModelStage::IDENTIFIED, String::new())
}

fn stage_msg(rep: &StageReport) -> ModelStage {
    let (status, status_reason) = stage_status(rep);
    ModelStage {
        status,
        stage: rep.stage.clone(),
        channel: rep.channel.clone(),
        status_reason,
        points: rep.points as u32,
        rmse: rep.rmse,
        nrmse_pct: rep.nrmse_pct(),
        iterations: rep.iterations as u32,
        wall_s: rep.wall_s,
        coefficients: rep
            .estimates
            .iter()
            .map(|e| ModelCoefficient { key: e.key.clone(), value: e.value, std: e.std })
            .collect(),
        held: rep.held.iter().map(|h| format!("{}: {}", h.key, h.reason)).collect(),
    }
}

/// The model state of `result` (every stage WAITING without one) with `maps` over `grid`.
/// Header, counters and error are the caller's.
pub fn model_state(result: Option<&FitResult>, grid: Option<&EnvelopeGrid>, maps: &[PredictionMap]) -> ModelState {
    let stages = STAGES
        .iter()
        .map(|stage| match result.and_then(|r| r.stages.iter().find(|s| s.stage == stage.name())) {
            Some(rep) => stage_msg(rep),
            None => ModelStage {
                status: ModelStage::WAITING,
                stage: stage.name().into(),
                channel: stage.channel().name().into(),
                status_reason: "no data yet".into(),
                rmse: f64::NAN,
                nrmse_pct: f64::NAN,
                ..ModelStage::default()
            },
        })
        .collect();
    let mut st = ModelState { stages, ..ModelState::default() };
    if let Some(g) = grid {
        st.grid_fz_n = g.fz_n.clone();
        st.grid_slip_angle_deg = g.slip_angle_deg.clone();
        st.grid_slip_ratio = g.slip_ratio.clone();
        st.grid_camber_deg = g.camber_deg.clone();
        st.grid_pressure_pa = g.pressure_pa.clone();
        st.grid_speed_mps = g.speed_mps;
    }
    st.maps = maps
        .iter()
        .map(|m| ModelMap {
            channel: m.channel.tydex_name().into(),
            slip_axis: match m.channel {
                MapChannel::FxPure => "slip_ratio".into(),
                _ => "slip_angle_deg".into(),
            },
            residual_rmse: m.residual_rmse,
            value: m.value.clone(),
            std: m.std.clone(),
        })
        .collect();
    st.maps_extrapolated = maps.iter().flat_map(|m| m.extrapolated.iter().copied()).collect();
    st.maps_repeat_band = maps.iter().map(|m| m.repeat_band).collect();
    st
}

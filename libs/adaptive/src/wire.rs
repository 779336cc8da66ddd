//! A [`ModelSnapshot`] as `tyre_msgs/ModelCovariance` and back: how the live model reaches a
//! sequencer node over DDS (`model/covariance`). The parameter set travels as `.tir` text, which
//! reads back to identical values, so the sequencer's planner sees the model the fit node has,
//! number for number.

use mftyre::TyreParams;
use tyre_msgs::{ModelCovariance, StageCovariance};

use crate::model::{ModelSnapshot, StageSnapshot};

/// Where the topic's message did not hold a usable model, and why.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("model/covariance (update {update_index}): {field}: {message}")]
pub struct WireError {
    /// The message's update index.
    pub update_index: u32,
    /// The field (`tir`, `r0_m`, `stages[fy_pure].covariance`, ...).
    pub field: String,
    /// What was wrong.
    pub message: String,
}

/// The message of `model` (header, update index and sweep index are the sender's).
pub fn to_msg(model: &ModelSnapshot) -> ModelCovariance {
    ModelCovariance {
        has_model: true,
        tir: model.params.to_tir_string(),
        fz0_n: model.fz0_n,
        p0_pa: model.p0_pa,
        v0_mps: model.v0_mps,
        r0_m: model.r0_m,
        stages: model
            .stages
            .iter()
            .map(|s| StageCovariance {
                stage: s.stage.clone(),
                rmse: s.rmse,
                keys: s.keys.clone(),
                covariance: s.covariance.clone(),
                held_for_want_of_data: s.held_for_want_of_data.clone(),
            })
            .collect(),
        ..ModelCovariance::default()
    }
}

/// The model a message carries; `None` when it says there is none yet.
pub fn from_msg(msg: &ModelCovariance) -> Result<Option<ModelSnapshot>, WireError> {
    if !msg.has_model {
        return Ok(None);
    }
    let err = |field: String, message: String| WireError { update_index: msg.update_index, field, message };
    let params =
        TyreParams::from_tir_str(&msg.tir, "model/covariance tir").map_err(|e| err("tir".into(), e.to_string()))?;
    for (field, v) in [("fz0_n", msg.fz0_n), ("p0_pa", msg.p0_pa), ("v0_mps", msg.v0_mps), ("r0_m", msg.r0_m)] {
        if !(v.is_finite() && v > 0.0) {
            return Err(err(field.into(), format!("expected a positive number, got {v}")));
        }
    }
    let mut stages = Vec::with_capacity(msg.stages.len());
    for s in &msg.stages {
        let n = s.keys.len();
        if s.covariance.len() != n * n {
            return Err(err(
                format!("stages[{}].covariance", s.stage),
                format!("{} values, expected {} ({n} keys squared)", s.covariance.len(), n * n),
            ));
        }
        stages.push(StageSnapshot {
            stage: s.stage.clone(),
            rmse: s.rmse,
            keys: s.keys.clone(),
            covariance: s.covariance.clone(),
            held_for_want_of_data: s.held_for_want_of_data.clone(),
        });
    }
    Ok(Some(ModelSnapshot { params, fz0_n: msg.fz0_n, p0_pa: msg.p0_pa, v0_mps: msg.v0_mps, r0_m: msg.r0_m, stages }))
}

//! The `/diagnostics` record of each adaptive-plan decision: which sweep was chosen and why, or
//! why a slot closed. The headless run and the DDS node publish the same record.

use crate::SequencerEvent;
use tyre_msgs::diagnostic_msgs::{DiagnosticArray, DiagnosticStatus, KeyValue};
use tyre_msgs::std_msgs::Header;

/// The live model a decision was made with: its update index and the `sweep_index` of the
/// newest sweep in its data (`model/covariance`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ModelRef {
    pub update_index: u32,
    pub last_sweep_index: u32,
}

/// The `/diagnostics` record of an adaptive decision: what was chosen and why, and with which
/// model (`None`: no model yet).
pub fn decision_status(ev: &SequencerEvent, t: f64, model: Option<ModelRef>) -> Option<DiagnosticArray> {
    let kv = |k: &str, v: String| KeyValue { key: k.into(), value: v };
    let (message, values) = match ev {
        SequencerEvent::SweepChosen {
            slot,
            name,
            value,
            cost_s,
            wear_mm,
            wear_rate_mm_per_mj,
            error_pct,
            error_after_pct,
            target_pct,
            reason,
        } => (
            format!("chose {name}: {reason}"),
            vec![
                kv("slot", slot.to_string()),
                kv("sweep", name.clone()),
                kv("value_pct2", format!("{value:.6}")),
                kv("cost_s", format!("{cost_s:.1}")),
                kv("wear_mm", format!("{wear_mm:.5}")),
                kv("wear_rate_mm_per_mj", format!("{wear_rate_mm_per_mj:.4}")),
                kv("predicted_error_pct", format!("{error_pct:.4}")),
                kv("predicted_error_after_pct", format!("{error_after_pct:.4}")),
                kv("target_pct", format!("{target_pct:.4}")),
            ],
        ),
        SequencerEvent::SlotClosed { slot, sweeps, error_pct, reason } => (
            format!("slot {slot} closed after {sweeps} sweeps: {reason}"),
            vec![
                kv("slot", slot.to_string()),
                kv("sweeps", sweeps.to_string()),
                kv("predicted_error_pct", format!("{error_pct:.4}")),
            ],
        ),
        _ => return None,
    };
    let mut values = values;
    values.push(kv("rig_time_s", format!("{t:.3}")));
    if let Some(m) = model {
        values.push(kv("model_update_index", m.update_index.to_string()));
        values.push(kv("model_last_sweep_index", m.last_sweep_index.to_string()));
    }
    Some(DiagnosticArray {
        header: Header::iso_w(t),
        status: vec![DiagnosticStatus {
            level: DiagnosticStatus::OK,
            name: "sequencer: adaptive".into(),
            message,
            hardware_id: "sequencer".into(),
            values,
        }],
    })
}

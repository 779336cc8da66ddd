//! The adaptive plan's decision inside the headless loop: the sequencer waits at a slot, the
//! live fit's latest model decides, the decision goes to the log (`/diagnostics`, the
//! `procedure/state` that follows) and the run summary.

use super::{Headless, HeadlessError};
use crate::sink::{MessageSink, Outgoing};
use crate::summary::SummaryBuilder;
use adaptive::FitView;
use adaptive::model::NoModel;
use sequencer::SequencerEvent;
use tyre_msgs::diagnostic_msgs::{DiagnosticArray, DiagnosticStatus, KeyValue};
use tyre_msgs::std_msgs::Header;

impl Headless {
    /// Asks the sequencer's planner for the next sweep with the live fit's latest model (none
    /// yet: every target unknown) and publishes what came of it. True when that completed the
    /// procedure (the last slot closed at the plan's end).
    pub(super) fn plan_next(
        &mut self,
        t: f64,
        sink: &mut dyn MessageSink,
        sum: &mut SummaryBuilder,
    ) -> Result<bool, HeadlessError> {
        let cfg = *self.seq.planner().map(|p| p.config()).ok_or_else(|| {
            HeadlessError::Sequencer("a slot of the adaptive plan without an adaptive planner".into())
        })?;
        let out = match self.live_fit.as_ref().and_then(|f| f.latest()) {
            Some(result) => self.seq.plan_next(t, &FitView::new(result, &cfg)),
            None => self.seq.plan_next(t, &NoModel),
        };
        if let Some(st) = &out.state {
            self.gate.on_procedure_state(t, st);
            self.pipeline.on_procedure_state(st);
            if let Some(fit) = self.live_fit.as_mut() {
                fit.on_procedure_state(st);
            }
            sum.on_state(st);
            sink.put(t, Outgoing::Procedure(st))?;
        }
        let mut completed = false;
        for ev in &out.events {
            sum.on_event(ev);
            completed |= matches!(ev, SequencerEvent::Completed { .. });
            if let Some(d) = decision_status(ev, t) {
                sink.put(t, Outgoing::Diagnostics(&d))?;
            }
        }
        Ok(completed)
    }
}

/// The `/diagnostics` record of an adaptive decision: what was chosen and why.
fn decision_status(ev: &SequencerEvent, t: f64) -> Option<DiagnosticArray> {
    let kv = |k: &str, v: String| KeyValue { key: k.into(), value: v };
    let (message, values) = match ev {
        SequencerEvent::SweepChosen { slot, name, value, cost_s, error_pct, error_after_pct, target_pct, reason } => (
            format!("chose {name}: {reason}"),
            vec![
                kv("slot", slot.to_string()),
                kv("sweep", name.clone()),
                kv("value_pct2", format!("{value:.6}")),
                kv("cost_s", format!("{cost_s:.1}")),
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

//! The adaptive plan's decision inside the headless loop: the sequencer waits at a slot, the
//! live fit's latest model decides, the decision goes to the log (`/diagnostics`, the
//! `procedure/state` that follows) and the run summary.

use super::{Headless, HeadlessError};
use crate::sink::{MessageSink, Outgoing};
use crate::summary::SummaryBuilder;
use adaptive::model::NoModel;
use adaptive::{FitView, ModelSnapshot};
use sequencer::SequencerEvent;

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
        let fit = self.live_fit.as_ref();
        let decided_with = fit
            .filter(|f| f.latest().is_some())
            .and_then(|f| f.latest_reach())
            .map(|(update_index, last_sweep_index)| sequencer::ModelRef { update_index, last_sweep_index });
        let out = match fit.and_then(|f| f.latest()) {
            Some(result) => self.seq.plan_next(t, &FitView::new(&ModelSnapshot::of(result), &cfg)),
            None => self.seq.plan_next(t, &NoModel),
        };
        if let Some(st) = &out.state {
            self.sweeps_run.on_state(st);
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
            if let Some(d) = sequencer::decision_status(ev, t, decided_with) {
                sink.put(t, Outgoing::Diagnostics(&d))?;
            }
        }
        Ok(completed)
    }
}

//! Which model an adaptive sequencer decides with at a slot when the live fit runs in another
//! node: the latest `model/covariance`, once its data include every sweep run before the slot.
//!
//! The fit closes a segment on the first sample after it, and updates then: when a slot follows
//! a data step directly, the sequencer reaches it before the model has seen that step. Both
//! ways of running wait for it ([`SweepsRun`]): headless, the update follows within a sample;
//! over DDS the fit node updates on its own time (0.02–5 s per update), so the sequencer holds
//! the rig at zero slip until a model arrives whose `last_sweep_index` reaches the newest data
//! sweep it ran, and decides with the model the headless run has at that point. A fit node that
//! is gone or stuck must not hold the rig for ever: after `wait_s` of waiting (wall time,
//! measured by the shell) it decides with the newest model it has and says so.
//!
//! Pure: the shell passes the wait so far; no clock is read here.

use adaptive::ModelSnapshot;
use adaptive::wire::{WireError, from_msg};
use mffit::DataKind;
use tyre_msgs::{ModelCovariance, ProcedureState};

/// The data sweeps the sequencer has run, as its procedure states say: what a model must have
/// seen to be the model of all data so far.
#[derive(Debug, Default, Clone, Copy)]
pub struct SweepsRun {
    /// `sweep_index` of the newest data sweep (not a warm-up: those are never fitted).
    newest: Option<u32>,
}

impl SweepsRun {
    /// Notes a procedure state the sequencer published.
    pub fn on_state(&mut self, st: &ProcedureState) {
        if st.phase == ProcedureState::PHASE_SWEEP
            && !st.sweep_name.is_empty()
            && DataKind::from_names(&st.section, &st.sweep_name) != DataKind::WarmUp
        {
            self.newest = Some(self.newest.map_or(st.sweep_index, |n| n.max(st.sweep_index)));
        }
    }

    /// The newest data sweep's index, if one has run.
    pub fn newest(&self) -> Option<u32> {
        self.newest
    }

    /// True when a model whose data reach sweep `reach` has seen every data sweep run so far.
    pub fn covered_by(&self, reach: Option<u32>) -> bool {
        match (self.newest, reach) {
            (None, _) => true,
            (Some(needed), Some(reach)) => reach >= needed,
            (Some(_), None) => false,
        }
    }
}

/// The live model as the sequencer node has received it.
#[derive(Debug, Default)]
pub struct PlanModel {
    /// Newest usable model (a message that did not parse leaves the previous one).
    model: Option<ModelSnapshot>,
    /// Update index and data reach of the newest message.
    latest: Option<(u32, u32)>,
    sweeps: SweepsRun,
}

/// What to do at a slot.
#[derive(Debug)]
pub enum PlanModelReady<'a> {
    /// Keep holding: the newest model has not seen the last sweep yet.
    Wait,
    /// Decide with this model (`None`: no model yet). `stale` says why it is not the model of
    /// all data: the wait ran out.
    Decide { model: Option<&'a ModelSnapshot>, stale: Option<String> },
}

impl PlanModel {
    /// Notes a procedure state the sequencer published: a data sweep raises the reach needed.
    pub fn on_state(&mut self, st: &ProcedureState) {
        self.sweeps.on_state(st);
    }

    /// Takes a `model/covariance`. An older update than the newest held (a late repair) is
    /// ignored; one that does not parse keeps the previous model and is returned as the error.
    pub fn on_model(&mut self, msg: &ModelCovariance) -> Result<(), WireError> {
        if self.latest.is_some_and(|(index, _)| msg.update_index < index) {
            return Ok(());
        }
        self.latest = Some((msg.update_index, msg.last_sweep_index));
        if let Some(m) = from_msg(msg)? {
            self.model = Some(m);
        }
        Ok(())
    }

    /// The newest model/covariance: its update index and data reach.
    pub fn latest(&self) -> Option<crate::ModelRef> {
        self.latest.map(|(update_index, last_sweep_index)| crate::ModelRef { update_index, last_sweep_index })
    }

    /// True when the newest model's data include every data sweep run so far.
    pub fn current(&self) -> bool {
        self.sweeps.covered_by(self.latest.map(|(_, reach)| reach))
    }

    /// At a slot, after `waited_s` of holding for it: wait on, or decide with which model.
    pub fn ready(&self, waited_s: f64, wait_s: f64) -> PlanModelReady<'_> {
        if self.current() {
            return PlanModelReady::Decide { model: self.model.as_ref(), stale: None };
        }
        if waited_s < wait_s {
            return PlanModelReady::Wait;
        }
        let had = match self.latest {
            Some((index, reach)) => format!("update {index}, data to sweep {reach}"),
            None => "no model/covariance at all".to_owned(),
        };
        let needed = self.sweeps.newest().unwrap_or(0);
        PlanModelReady::Decide {
            model: self.model.as_ref(),
            stale: Some(format!(
                "no model of the data to sweep {needed} after {waited_s:.1} s of waiting ({had}): deciding with the newest model"
            )),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn state(section: &str, sweep: &str, index: u32) -> ProcedureState {
        ProcedureState {
            phase: ProcedureState::PHASE_SWEEP,
            section: section.into(),
            sweep_name: sweep.into(),
            sweep_index: index,
            ..ProcedureState::default()
        }
    }

    fn model(update_index: u32, last_sweep_index: u32) -> ModelCovariance {
        let params = mftyre::TyreParams::from_tir_str(mffit::stages::TEMPLATE_TIR, "template").unwrap();
        let snap = ModelSnapshot { params, fz0_n: 4000.0, p0_pa: 2.2e5, v0_mps: 16.6, r0_m: 0.31, stages: vec![] };
        ModelCovariance { update_index, last_sweep_index, ..adaptive::wire::to_msg(&snap) }
    }

    fn decided(m: &PlanModel, waited_s: f64) -> Option<(bool, Option<String>)> {
        match m.ready(waited_s, 120.0) {
            PlanModelReady::Wait => None,
            PlanModelReady::Decide { model, stale } => Some((model.is_some(), stale)),
        }
    }

    #[test]
    fn before_any_data_sweep_the_plan_decides_at_once() {
        let mut m = PlanModel::default();
        // Warm-up sweeps are never fitted: the fit will not update for them.
        m.on_state(&state("warmup", "FreeRoll_warmup_1", 0));
        assert_eq!(decided(&m, 0.0), Some((false, None)));
    }

    #[test]
    fn the_plan_waits_for_a_model_that_has_seen_the_last_sweep() {
        let mut m = PlanModel::default();
        m.on_state(&state("force_moment_2.6bar", "FreeRoll_sw5", 4));
        assert_eq!(decided(&m, 1.0), None, "no model yet");
        m.on_model(&model(3, 3)).unwrap();
        assert_eq!(decided(&m, 5.0), None, "the model has not seen sweep 4");
        m.on_model(&model(4, 4)).unwrap();
        assert_eq!(decided(&m, 6.0), Some((true, None)));
        assert_eq!(m.latest(), Some(crate::ModelRef { update_index: 4, last_sweep_index: 4 }));
        // A late repair of an older update changes nothing.
        m.on_model(&model(3, 3)).unwrap();
        assert_eq!(decided(&m, 0.0), Some((true, None)));
    }

    #[test]
    fn a_silent_fit_node_holds_the_rig_only_until_the_wait_runs_out() {
        let mut m = PlanModel::default();
        m.on_state(&state("force_moment_2.6bar", "FreeRoll_sw5", 7));
        assert_eq!(decided(&m, 119.9), None);
        let (has_model, stale) = decided(&m, 120.0).unwrap();
        assert!(!has_model);
        let why = stale.expect("a stale decision says so");
        assert!(why.contains("sweep 7") && why.contains("no model/covariance at all"), "{why}");

        m.on_model(&model(2, 5)).unwrap();
        let (has_model, stale) = decided(&m, 130.0).unwrap();
        assert!(has_model, "the newest model is used");
        assert!(stale.unwrap().contains("update 2, data to sweep 5"));
    }

    #[test]
    fn a_message_that_does_not_parse_keeps_the_previous_model() {
        let mut m = PlanModel::default();
        m.on_state(&state("force_moment_2.6bar", "FreeRoll_sw5", 2));
        m.on_model(&model(1, 2)).unwrap();
        let mut bad = model(2, 2);
        bad.tir = "[VERTICAL]\nFNOMIN = heavy\n".into();
        let e = m.on_model(&bad).unwrap_err();
        assert_eq!(e.field, "tir");
        assert_eq!(decided(&m, 0.0), Some((true, None)), "decides with update 1's model");
    }
}

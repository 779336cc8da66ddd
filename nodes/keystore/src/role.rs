//! Roles: what each kind of participant may publish and subscribe to.
//!
//! A role is the access-control half of an enclave: `create-enclave` writes the role's topics into
//! the enclave's permissions document, and every secured peer refuses what the document does not
//! grant. The suite's rules (issue 14): only the sequencer publishes setpoints, only operator
//! enclaves publish commands, the recorder and the monitor only subscribe (the recorder's one
//! publication is its loss and silent-stream alarms on `/diagnostics`).

use node_runtime::SuiteTopic;

/// What a participant is for. Node kinds map to the role of the same name (the virtual rig, or
/// a real rig's driver, to [`Role::Rig`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Role {
    /// The rig (virtual or real): publishes samples and `/clock`, takes setpoints.
    Rig,
    /// The thermal gate.
    Thermal,
    /// The procedure sequencer: the only publisher of setpoints.
    Sequencer,
    /// Live channels and the quality monitor (the `quality` node).
    Quality,
    /// The live MF-Tyre fit (the `fit` node): reads samples and states, publishes the model and
    /// its coefficient covariance.
    Fit,
    /// The recorder: subscribes to every topic, publishes only its alarms on `/diagnostics`.
    Recorder,
    /// An operator station: publishes procedure commands, reads everything.
    Operator,
    /// A read-only station or third-party tool (dashboards, plotting, bridges): reads everything.
    Monitor,
}

use SuiteTopic as T;

impl Role {
    pub const ALL: [Role; 8] = [
        Role::Rig,
        Role::Thermal,
        Role::Sequencer,
        Role::Quality,
        Role::Fit,
        Role::Recorder,
        Role::Operator,
        Role::Monitor,
    ];

    pub fn name(self) -> &'static str {
        match self {
            Role::Rig => "rig",
            Role::Thermal => "thermal",
            Role::Sequencer => "sequencer",
            Role::Quality => "quality",
            Role::Fit => "fit",
            Role::Recorder => "recorder",
            Role::Operator => "operator",
            Role::Monitor => "monitor",
        }
    }

    pub fn parse(s: &str) -> Option<Role> {
        Role::ALL.into_iter().find(|r| r.name() == s)
    }

    /// The role a suite node kind (`kind` in a launch file) runs with; `None` for kinds that have
    /// no place on a secured domain (the test pattern publishes every topic, commands included).
    pub fn of_node_kind(kind: &str) -> Option<Role> {
        match kind {
            "virtual_rig" => Some(Role::Rig),
            "thermal" => Some(Role::Thermal),
            "sequencer" => Some(Role::Sequencer),
            "quality" => Some(Role::Quality),
            "fit" => Some(Role::Fit),
            "recorder" => Some(Role::Recorder),
            // The Foxglove screen reads every topic; one whose launch file lets clients send
            // commands (`allow_commands`) needs an operator enclave, given with `--role`.
            "foxglove" => Some(Role::Monitor),
            _ => None,
        }
    }

    /// The role an enclave named `…/<base_name>` gets when none is given: a role's name, a node
    /// kind's role, or that of a participant `tyrerig` itself opens (`run_watcher`, the watcher
    /// of `tyrerig run`, only reads).
    pub fn default_for(base_name: &str) -> Option<Role> {
        match base_name {
            "run_watcher" => Some(Role::Monitor),
            _ => Role::parse(base_name).or_else(|| Role::of_node_kind(base_name)),
        }
    }

    /// Suite topics the role may publish.
    pub fn publishes(self) -> &'static [SuiteTopic] {
        match self {
            Role::Rig => &[T::RigSample, T::Clock, T::Diagnostics],
            Role::Thermal => &[T::ThermalState, T::Diagnostics],
            Role::Sequencer => &[T::RigSetpoint, T::ProcedureState, T::Diagnostics],
            Role::Quality => &[T::LiveChannels, T::SweepSummary, T::Derived, T::QualityReport, T::Diagnostics],
            Role::Fit => &[T::ModelState, T::ModelCovariance, T::Diagnostics],
            // The recorder's only output besides its log: its loss and silent-stream alarms
            // (loss is never silent, docs/reliability.md).
            Role::Recorder => &[T::Diagnostics],
            Role::Monitor => &[],
            Role::Operator => &[T::ProcedureCommand],
        }
    }

    /// Suite topics the role may subscribe to.
    pub fn subscribes(self) -> &'static [SuiteTopic] {
        match self {
            Role::Rig => &[T::RigSetpoint],
            Role::Thermal => &[T::RigSample, T::ProcedureState],
            // The adaptive plan (`plan = "adaptive"`) plans on the live fit's model and covariance,
            // and prices wear with the rate the monitor reports on `/diagnostics`.
            Role::Sequencer => {
                &[T::RigSample, T::ThermalState, T::ProcedureCommand, T::ModelCovariance, T::Diagnostics]
            }
            // The quality node also follows the live fit's model (monitor::model_watch).
            Role::Quality => &[T::RigSample, T::ProcedureState, T::ModelState],
            Role::Fit => &[T::RigSample, T::ProcedureState],
            Role::Recorder | Role::Operator | Role::Monitor => &SuiteTopic::ALL,
        }
    }
}

impl std::fmt::Display for Role {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_suite_rules_hold() {
        let publishers =
            |t: SuiteTopic| Role::ALL.into_iter().filter(|r| r.publishes().contains(&t)).collect::<Vec<_>>();
        assert_eq!(publishers(T::RigSetpoint), [Role::Sequencer], "only the sequencer publishes setpoints");
        assert_eq!(publishers(T::ProcedureCommand), [Role::Operator], "only operators publish commands");
        assert_eq!(publishers(T::RigSample), [Role::Rig]);
        assert_eq!(Role::Recorder.publishes(), [T::Diagnostics], "the recorder only reports on /diagnostics");
        assert!(Role::Monitor.publishes().is_empty());
        assert_eq!(Role::Recorder.subscribes(), &SuiteTopic::ALL);
        assert_eq!(publishers(T::ModelCovariance), [Role::Fit], "only the live fit publishes its covariance");
        assert!(Role::Sequencer.subscribes().contains(&T::ModelCovariance), "the adaptive plan reads the covariance");
    }

    #[test]
    fn every_suite_node_may_announce_on_diagnostics() {
        // Every node shell opens a /diagnostics writer at start (loss and alarms,
        // docs/reliability.md): a role without it keeps its node from starting when secured.
        for kind in ["virtual_rig", "thermal", "sequencer", "quality", "recorder"] {
            let role = Role::of_node_kind(kind).expect("a suite node kind");
            assert!(role.publishes().contains(&T::Diagnostics), "{kind} ({role})");
        }
    }

    #[test]
    fn every_published_topic_has_a_reader_role_and_names_parse() {
        for t in SuiteTopic::ALL {
            assert!(Role::ALL.iter().any(|r| r.subscribes().contains(&t)), "{t:?}");
        }
        for r in Role::ALL {
            assert_eq!(Role::parse(r.name()), Some(r));
        }
        assert_eq!(Role::of_node_kind("virtual_rig"), Some(Role::Rig));
        assert_eq!(Role::of_node_kind("test_pattern"), None);
        assert_eq!(Role::of_node_kind("foxglove"), Some(Role::Monitor), "a screen only reads unless told");
        assert_eq!(Role::default_for("operator"), Some(Role::Operator));
        assert_eq!(Role::default_for("virtual_rig"), Some(Role::Rig));
        assert_eq!(Role::default_for("run_watcher"), Some(Role::Monitor));
        assert_eq!(Role::default_for("operator_1"), None, "stations say what they may do");
    }
}

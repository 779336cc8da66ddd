//! The suite's topic table: one place that says which topic carries which type with which QoS.
//!
//! Publishers, subscribers, the recorder and replay all build their endpoints from here, so a
//! QoS mismatch (for instance a transient-local reader on a volatile writer, which DDS silently
//! refuses to match) cannot happen between suite nodes.

use ros2_client::{
    QosProfile,
    qos::{Durability, History, Reliability, WhenFull},
};
use std::time::Duration;
use tyre_msgs::{
    DerivedMeasurement, LiveChannels, ModelCovariance, ModelState, ProcedureCommand, ProcedureState, QualityReport,
    RigSample, RigSetpoint, RosMessage, SweepSummary, ThermalState, diagnostic_msgs::DiagnosticArray,
    rosgraph_msgs::Clock, topics as names,
};

/// QoS presets. Names say what the topic is used for, not how DDS does it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Qos {
    /// High-rate data (samples, setpoints, live channels): reliable, volatile, deep history so
    /// a 1 kHz stream survives a scheduling hiccup without loss.
    Stream,
    /// "The latest state" (procedure, thermal gate): reliable, transient-local, keep last 1, so a
    /// control room that joins late sees where the rig is at once.
    State,
    /// Events a late joiner needs all of (sweep summaries, quality reports): reliable,
    /// transient-local, keep last 1000.
    Events,
    /// Operator commands: reliable, volatile (a command must never replay to a late joiner).
    Command,
    /// `/clock`: the ROS convention — best effort, keep last 1.
    Clock,
    /// `/diagnostics`: the ROS default profile — reliable, volatile, keep last 10.
    Diagnostics,
}

impl Qos {
    /// The DDS QoS profile of this preset.
    pub fn profile(self) -> QosProfile {
        let reliable = Reliability::Reliable { when_full: WhenFull::Wait(Duration::from_millis(200)) };
        // A stream's writer (the rig's samples) never waits more than 1 ms for its send window:
        // a reader far behind (or, before vendor/rustdds patch 3, one that died without leaving
        // and held the window full until its participant lease ended, ~50 s) makes it full; the
        // sample is then refused, and every reader sees the gap in its sequence numbers instead
        // of the rig stalling. Patch 3 stops waiting for a reader silent for 2 s.
        let stream = Reliability::Reliable { when_full: WhenFull::Wait(Duration::from_millis(1)) };
        let base = QosProfile::publisher_default();
        match self {
            Qos::Stream => {
                base.reliability(stream).durability(Durability::Volatile).history(History::KeepLast { depth: 2000 })
            }
            Qos::State => base
                .reliability(reliable)
                .durability(Durability::TransientLocal)
                .history(History::KeepLast { depth: 1 }),
            Qos::Events => base
                .reliability(reliable)
                .durability(Durability::TransientLocal)
                .history(History::KeepLast { depth: 1000 }),
            Qos::Command => {
                base.reliability(reliable).durability(Durability::Volatile).history(History::KeepLast { depth: 50 })
            }
            Qos::Clock => base
                .reliability(Reliability::BestEffort)
                .durability(Durability::Volatile)
                .history(History::KeepLast { depth: 1 }),
            Qos::Diagnostics => {
                base.reliability(reliable).durability(Durability::Volatile).history(History::KeepLast { depth: 10 })
            }
        }
    }
}

/// Reader history of a recorder on a [`Qos::Stream`] topic [samples]. The recorder's reader
/// is the one that must never drop: its history is where samples wait while the writer thread
/// compresses a chunk, so it is far deeper than the stream's (100 s at 1 kHz, ~40 MB of
/// RigSamples at most). History depth is a reader-local setting; it does not affect matching.
pub const RECORDER_STREAM_DEPTH: usize = 100_000;

impl Qos {
    /// The QoS a recorder's reader uses: the preset's, with a deeper history on streams.
    pub fn recording_profile(self) -> QosProfile {
        match self {
            Qos::Stream => self.profile().history(History::KeepLast { depth: RECORDER_STREAM_DEPTH }),
            other => other.profile(),
        }
    }
}

/// One row of the topic table.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct TopicSpec {
    /// Relative names live under the configured namespace; names starting with `/` are absolute
    /// (ROS conventions such as `/clock` and `/diagnostics`).
    pub name: &'static str,
    pub qos: Qos,
}

/// Every topic of the suite.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum SuiteTopic {
    RigSample,
    RigSetpoint,
    ProcedureState,
    ProcedureCommand,
    ThermalState,
    LiveChannels,
    SweepSummary,
    Derived,
    QualityReport,
    ModelState,
    ModelCovariance,
    Diagnostics,
    Clock,
}

/// Generic code over the topic table (the recorder and replay handle every type the same way):
/// [`SuiteTopic::visit`] calls `visit::<M>` with the topic's message type.
pub trait TopicVisitor {
    type Output;
    fn visit<M: RosMessage + Send + Sync + 'static>(self, topic: SuiteTopic) -> Self::Output;
}

impl SuiteTopic {
    pub const ALL: [SuiteTopic; 13] = [
        SuiteTopic::RigSample,
        SuiteTopic::RigSetpoint,
        SuiteTopic::ProcedureState,
        SuiteTopic::ProcedureCommand,
        SuiteTopic::ThermalState,
        SuiteTopic::LiveChannels,
        SuiteTopic::SweepSummary,
        SuiteTopic::Derived,
        SuiteTopic::QualityReport,
        SuiteTopic::ModelState,
        SuiteTopic::ModelCovariance,
        SuiteTopic::Diagnostics,
        SuiteTopic::Clock,
    ];

    /// Name and QoS of the topic.
    pub const fn spec(self) -> TopicSpec {
        let (name, qos) = match self {
            SuiteTopic::RigSample => (names::RIG_SAMPLE, Qos::Stream),
            SuiteTopic::RigSetpoint => (names::RIG_SETPOINT, Qos::Stream),
            SuiteTopic::ProcedureState => (names::PROCEDURE_STATE, Qos::State),
            SuiteTopic::ProcedureCommand => (names::PROCEDURE_COMMAND, Qos::Command),
            SuiteTopic::ThermalState => (names::THERMAL_STATE, Qos::Stream),
            SuiteTopic::LiveChannels => (names::CHANNELS_LIVE, Qos::Stream),
            SuiteTopic::SweepSummary => (names::SWEEP_SUMMARY, Qos::Events),
            SuiteTopic::Derived => (names::DERIVED, Qos::Events),
            SuiteTopic::QualityReport => (names::QUALITY_REPORT, Qos::Events),
            SuiteTopic::ModelState => (names::MODEL_STATE, Qos::State),
            SuiteTopic::ModelCovariance => (names::MODEL_COVARIANCE, Qos::State),
            SuiteTopic::Diagnostics => (names::DIAGNOSTICS, Qos::Diagnostics),
            SuiteTopic::Clock => (names::CLOCK, Qos::Clock),
        };
        TopicSpec { name, qos }
    }

    /// Fully qualified ROS topic name under `namespace` (e.g. `/rig/sample`).
    pub fn full_name(self, namespace: &str) -> String {
        let rel = self.spec().name;
        if rel.starts_with('/') {
            rel.to_owned()
        } else if namespace == "/" {
            format!("/{rel}")
        } else {
            format!("{}/{rel}", namespace.trim_end_matches('/'))
        }
    }

    /// The ROS 2 type name of the topic's messages (`tyre_msgs/msg/RigSample`).
    pub fn ros_type_name(self) -> String {
        struct TypeName;
        impl TopicVisitor for TypeName {
            type Output = String;
            fn visit<M: RosMessage + Send + Sync + 'static>(self, _: SuiteTopic) -> String {
                M::ros_type_name()
            }
        }
        self.visit(TypeName)
    }

    /// Finds the topic whose full name under `namespace` is `full_name`.
    pub fn from_full_name(full_name: &str, namespace: &str) -> Option<SuiteTopic> {
        Self::ALL.into_iter().find(|t| t.full_name(namespace) == full_name)
    }

    /// Calls `visitor.visit::<M>` with this topic's message type.
    pub fn visit<V: TopicVisitor>(self, visitor: V) -> V::Output {
        match self {
            SuiteTopic::RigSample => visitor.visit::<RigSample>(self),
            SuiteTopic::RigSetpoint => visitor.visit::<RigSetpoint>(self),
            SuiteTopic::ProcedureState => visitor.visit::<ProcedureState>(self),
            SuiteTopic::ProcedureCommand => visitor.visit::<ProcedureCommand>(self),
            SuiteTopic::ThermalState => visitor.visit::<ThermalState>(self),
            SuiteTopic::LiveChannels => visitor.visit::<LiveChannels>(self),
            SuiteTopic::SweepSummary => visitor.visit::<SweepSummary>(self),
            SuiteTopic::Derived => visitor.visit::<DerivedMeasurement>(self),
            SuiteTopic::QualityReport => visitor.visit::<QualityReport>(self),
            SuiteTopic::ModelState => visitor.visit::<ModelState>(self),
            SuiteTopic::ModelCovariance => visitor.visit::<ModelCovariance>(self),
            SuiteTopic::Diagnostics => visitor.visit::<DiagnosticArray>(self),
            SuiteTopic::Clock => visitor.visit::<Clock>(self),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_under_namespace() {
        assert_eq!(SuiteTopic::RigSample.full_name("/rig"), "/rig/sample");
        assert_eq!(SuiteTopic::ProcedureState.full_name("/lab/rig"), "/lab/rig/procedure/state");
        assert_eq!(SuiteTopic::Clock.full_name("/rig"), "/clock");
        assert_eq!(SuiteTopic::RigSample.full_name("/"), "/sample");
        assert_eq!(SuiteTopic::from_full_name("/rig/channels/live", "/rig"), Some(SuiteTopic::LiveChannels));
        assert_eq!(SuiteTopic::RigSample.ros_type_name(), "tyre_msgs/msg/RigSample");
        assert_eq!(SuiteTopic::Diagnostics.ros_type_name(), "diagnostic_msgs/msg/DiagnosticArray");
        assert_eq!(SuiteTopic::ModelCovariance.full_name("/rig"), "/rig/model/covariance");
        assert_eq!(SuiteTopic::ModelCovariance.ros_type_name(), "tyre_msgs/msg/ModelCovariance");
        assert_eq!(SuiteTopic::ModelCovariance.spec().qos, Qos::State, "transient-local, like model/state");
    }

    #[test]
    fn names_are_unique() {
        let mut names: Vec<_> = SuiteTopic::ALL.iter().map(|t| t.full_name("/rig")).collect();
        names.sort();
        names.dedup();
        assert_eq!(names.len(), SuiteTopic::ALL.len());
    }
}

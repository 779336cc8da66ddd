//! sequencer: runs a tyre test rig through an expanded procedure ([`procedure::Plan`]).
//!
//! This crate holds the sequencer's pure core ([`core::Sequencer`]) and its configuration
//! ([`config::SequencerConfig`]). The core reads no clock and does no I/O: time comes in as
//! data (`now_s`, rig time), so the same core runs headless at full speed in tests and inside
//! the DDS node, whose shell maps topics to calls:
//!
//! - subscribes `procedure/command` (`ProcedureCommand`) → [`core::Sequencer::on_command`]
//! - subscribes `thermal/state` (`ThermalState`) and `rig/sample` (`RigSample`) → passed to
//!   [`core::Sequencer::step`], called at the control rate
//! - publishes `rig/setpoint` (`RigSetpoint`) and `procedure/state` (`ProcedureState`,
//!   on change and at 2 Hz) from [`core::SequencerOutput`]
//! - writes [`core::Checkpoint`] to disk on [`core::SequencerEvent::CheckpointChanged`]; after a
//!   restart, [`core::Sequencer::resume`] continues at the interrupted sweep.
//! - with `plan = "adaptive"`: subscribes `model/covariance` (`ModelCovariance`) → [`PlanModel`];
//!   at a slot, once the model has seen the last sweep, [`core::Sequencer::plan_next`] decides
//!   and each decision goes to `/diagnostics` ([`decision_status`]); subscribes `/diagnostics`
//!   for the monitor's measured wear rate ([`measured_wear_rate`]) →
//!   [`core::Sequencer::on_wear_rate`].

pub mod config;
pub mod core;
pub mod decisions;
pub mod plan_model;
#[cfg(feature = "dds")]
pub mod shell;
pub mod wear_rate;

pub use config::{PlanKind, SequencerConfig};
pub use core::{Checkpoint, CommandRejected, Sequencer, SequencerError, SequencerEvent, SequencerOutput};
pub use decisions::{ModelRef, decision_status};
pub use plan_model::{PlanModel, PlanModelReady, SweepsRun};
pub use wear_rate::measured_wear_rate;

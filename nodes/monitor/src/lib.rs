//! monitor: the online quality monitor of tyrerig — its pure core, configuration, and the
//! end-of-run report.
//!
//! In the thesis every quality judgement (graph-sweep drift, wear from DSTWOWHC, break-in,
//! chatter, a wrong load rating typed in at the rig) was made by hand after the test. The
//! monitor makes them live (`gs2mf-reference.md` §3, §5, §8; `docs/monitoring.md`).
//!
//! Topics (the DDS shell maps them to [`MonitorCore`] calls):
//! - in: `rig/sample` (`tyre_msgs/RigSample`) → [`MonitorCore::on_sample`];
//!   `procedure/state` (`tyre_msgs/ProcedureState`) → [`MonitorCore::on_procedure_state`];
//!   `rig/channels/live` (`tyre_msgs/LiveChannels`) → [`MonitorCore::on_live_channels`];
//!   `rig/channels/sweep_summary` (`tyre_msgs/SweepSummary`) → [`MonitorCore::on_sweep_summary`];
//! - out: `rig/quality/report` (`tyre_msgs/QualityReport`, transient-local, on change) and
//!   `/diagnostics` (`diagnostic_msgs/DiagnosticArray`, one status per check) from
//!   [`MonitorOutput`]; its [`Alarm`]s go to the run summary's `alarms`.
//!
//! [`ModelWatch`] follows the live fit (`model/state`): stages identified, when, failed updates;
//! the quality node logs it and puts it on `/diagnostics`, the report plots it.
//!
//! Checks ([`core::CHECKS`]): `load_rating`, `wear`, `graph_sweep_drift`, `break_in`, `chatter`,
//! `thermal_timeout`; thresholds in [`MonitorConfig`] with their thesis sources.
//!
//! `shell` (feature `dds`, on by default) runs both cores in one DDS node through [`Pipeline`],
//! in the same order as a headless run and a replay.
//!
//! [`report`] replays an MCAP log through the channels and monitor cores and writes the
//! Markdown report with plots (`tyrerig report`).

pub mod config;
pub mod core;
pub mod drift;
pub mod model_watch;
pub mod pipeline;
pub mod report;
#[cfg(feature = "dds")]
pub mod shell;
pub mod wear;

pub use config::{ConfigError, Levels, MonitorConfig, TyreInfo};
pub use core::{Alarm, MonitorCore, MonitorOutput, WearEstimate};
pub use model_watch::{ModelWatch, ModelWatchOutput};
pub use pipeline::{Pipeline, PipelineError, PipelineOutput};

//! The suite's topic names. Relative names live under the configured namespace (default `/rig`,
//! so `sample` is `/rig/sample`, `rt/rig/sample` on the DDS wire); absolute names follow ROS
//! conventions. QoS is the DDS runtime's business (`node_runtime::topics`).

/// `tyre_msgs/RigSample`: rig or virtual rig → all.
pub const RIG_SAMPLE: &str = "sample";
/// `tyre_msgs/RigSetpoint`: sequencer → rig.
pub const RIG_SETPOINT: &str = "setpoint";
/// `tyre_msgs/ProcedureState`: sequencer → all.
pub const PROCEDURE_STATE: &str = "procedure/state";
/// `tyre_msgs/ProcedureCommand`: operator → sequencer.
pub const PROCEDURE_COMMAND: &str = "procedure/command";
/// `tyre_msgs/ThermalState`: thermal gate → sequencer, all.
pub const THERMAL_STATE: &str = "thermal/state";
/// `tyre_msgs/LiveChannels`: channels → all.
pub const CHANNELS_LIVE: &str = "channels/live";
/// `tyre_msgs/SweepSummary`: channels → monitor, all.
pub const SWEEP_SUMMARY: &str = "channels/sweep_summary";
/// `tyre_msgs/DerivedMeasurement`: channels → all.
pub const DERIVED: &str = "channels/derived";
/// `tyre_msgs/QualityReport`: monitor → all.
pub const QUALITY_REPORT: &str = "quality/report";
/// `tyre_msgs/ModelState`: live fit → all.
pub const MODEL_STATE: &str = "model/state";
/// `tyre_msgs/ModelCovariance`: live fit → sequencer (adaptive plan), any consumer.
pub const MODEL_COVARIANCE: &str = "model/covariance";
/// `diagnostic_msgs/DiagnosticArray`: every node → all (ROS convention).
pub const DIAGNOSTICS: &str = "/diagnostics";
/// `rosgraph_msgs/Clock`: the virtual rig on simulated time (ROS convention).
pub const CLOCK: &str = "/clock";

/// The monitor's wear verdict on [`DIAGNOSTICS`] (status name). Besides the verdict's own
/// key-values it carries the wear rate measured on the tyre under test, once measurable, under
/// [`WEAR_RATE_KEY`] and [`WEAR_RATE_SD_KEY`]: the adaptive sequencer prices wear with it.
pub const WEAR_STATUS: &str = "tyrerig monitor: wear";
/// Tread lost per sliding energy, the monitor's fit \[mm/MJ\] (a decimal number).
pub const WEAR_RATE_KEY: &str = "wear_rate_mm_per_mj";
/// Its standard error \[mm/MJ\].
pub const WEAR_RATE_SD_KEY: &str = "wear_rate_sd_mm_per_mj";

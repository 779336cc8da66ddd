//! The suite's own messages, mirroring `msg/*.msg` field for field.

use crate::std_msgs::Header;
use serde::{Deserialize, Serialize};

/// `tyre_msgs/RigSample`: one sample of every rig channel (TYDEX names, ISO-W axes).
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct RigSample {
    pub header: Header,
    pub seq: u64,
    pub runtime_s: f64,
    pub fx_n: f64,
    pub fyw_n: f64,
    pub fzw_n: f64,
    pub mxw_nm: f64,
    pub myw_nm: f64,
    pub mzw_nm: f64,
    pub slipangl_deg: f64,
    pub longslip: f64,
    pub inclangl_deg: f64,
    pub inflpres_pa: f64,
    pub trajvelw_mps: f64,
    pub wheel_speed_radps: f64,
    pub dstwowhc_m: f64,
    pub trdtempi_c: f64,
    pub trdtempc_c: f64,
    pub trdtempo_c: f64,
    pub rig_mode: u8,
    pub fault_flags: u32,
}

crate::ros_message!(
    RigSample,
    "tyre_msgs",
    "RigSample",
    [FAULT_FORCE, FAULT_TEMPERATURE, FAULT_RADIUS, FAULT_ENVELOPE, FAULT_ESTOP,]
);

impl RigSample {
    pub const FAULT_FORCE: u32 = 1;
    pub const FAULT_TEMPERATURE: u32 = 2;
    pub const FAULT_RADIUS: u32 = 4;
    pub const FAULT_ENVELOPE: u32 = 8;
    pub const FAULT_ESTOP: u32 = 16;
}

/// `tyre_msgs/RigSetpoint`: what the rig should do now.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct RigSetpoint {
    pub header: Header,
    pub seq: u64,
    pub mode: u8,
    pub slip_angle_deg: f64,
    pub slip_ratio: f64,
    pub fz_n: f64,
    pub camber_deg: f64,
    pub pressure_pa: f64,
    pub speed_mps: f64,
    pub belt_displacement_m: f64,
    pub hold_slip_angle: bool,
    pub hold_slip_ratio: bool,
    pub hold_load: bool,
    pub hold_camber: bool,
    pub sweep_name: String,
}

crate::ros_message!(
    RigSetpoint,
    "tyre_msgs",
    "RigSetpoint",
    [MODE_FREE_ROLLING, MODE_COUPLED, MODE_STATIC, MODE_SAFE,]
);

impl RigSetpoint {
    pub const MODE_FREE_ROLLING: u8 = 0;
    pub const MODE_COUPLED: u8 = 1;
    pub const MODE_STATIC: u8 = 2;
    pub const MODE_SAFE: u8 = 3;
}

/// `tyre_msgs/ProcedureCommand`: an operator's command to the sequencer.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct ProcedureCommand {
    pub header: Header,
    pub command: u8,
    pub procedure: String,
    pub operator: String,
}

crate::ros_message!(ProcedureCommand, "tyre_msgs", "ProcedureCommand", [START, PAUSE, RESUME, ABORT, ESTOP,]);

impl ProcedureCommand {
    pub const START: u8 = 0;
    pub const PAUSE: u8 = 1;
    pub const RESUME: u8 = 2;
    pub const ABORT: u8 = 3;
    pub const ESTOP: u8 = 4;
}

/// `tyre_msgs/ProcedureState`: where the sequencer is.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct ProcedureState {
    pub header: Header,
    pub phase: u8,
    pub procedure: String,
    pub section: String,
    pub section_index: u32,
    pub sweep_name: String,
    pub sweep_index: u32,
    pub sweep_count: u32,
    pub sweep_started_hot: bool,
    pub progress: f64,
    pub elapsed_rig_time_s: f64,
    pub estimated_remaining_s: f64,
}

crate::ros_message!(
    ProcedureState,
    "tyre_msgs",
    "ProcedureState",
    [
        PHASE_IDLE,
        PHASE_SWEEP,
        PHASE_THERMAL_PAUSE,
        PHASE_FREE_ROLLING_REF,
        PHASE_SETTLE,
        PHASE_PAUSED,
        PHASE_ABORTED,
        PHASE_ESTOP,
        PHASE_COMPLETE,
        PHASE_TYRE_CHANGE,
    ]
);

impl ProcedureState {
    pub const PHASE_IDLE: u8 = 0;
    pub const PHASE_SWEEP: u8 = 1;
    pub const PHASE_THERMAL_PAUSE: u8 = 2;
    pub const PHASE_FREE_ROLLING_REF: u8 = 3;
    pub const PHASE_SETTLE: u8 = 4;
    pub const PHASE_PAUSED: u8 = 5;
    pub const PHASE_ABORTED: u8 = 6;
    pub const PHASE_ESTOP: u8 = 7;
    pub const PHASE_COMPLETE: u8 = 8;
    pub const PHASE_TYRE_CHANGE: u8 = 9;
}

/// `tyre_msgs/ThermalState`: the thermal gate's view of the tyre.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct ThermalState {
    pub header: Header,
    pub status: u8,
    pub gate_open: bool,
    pub trdtempi_c: f64,
    pub trdtempc_c: f64,
    pub trdtempo_c: f64,
    pub weighted_temp_c: f64,
    pub filtered_temp_c: f64,
    pub baseline_c: f64,
    pub pause_elapsed_s: f64,
    pub predicted_wait_s: f64,
    pub cooling_time_constant_s: f64,
    pub fault: String,
}

crate::ros_message!(
    ThermalState,
    "tyre_msgs",
    "ThermalState",
    [STATUS_WAITING, STATUS_RELEASED, STATUS_TIMED_OUT, STATUS_FAULT, STATUS_IDLE,]
);

impl ThermalState {
    pub const STATUS_WAITING: u8 = 0;
    pub const STATUS_RELEASED: u8 = 1;
    pub const STATUS_TIMED_OUT: u8 = 2;
    pub const STATUS_FAULT: u8 = 3;
    pub const STATUS_IDLE: u8 = 4;
}

/// `tyre_msgs/LiveChannels`: channels computed live from every `RigSample`.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct LiveChannels {
    pub header: Header,
    pub sample_seq: u64,
    pub segment: String,
    pub zeroed_runtime_s: f64,
    pub longdisp_m: f64,
    pub slip_ratio_calspan: f64,
    pub slip_ratio_effective_radius: f64,
    pub px_w: f64,
    pub py_w: f64,
    pub p_w: f64,
    pub acsldeny_j: f64,
    pub total_sliding_energy_j: f64,
}

crate::ros_message!(LiveChannels, "tyre_msgs", "LiveChannels");

/// `tyre_msgs/SweepSummary`: published at the end of every sweep.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct SweepSummary {
    pub header: Header,
    pub procedure: String,
    pub section: String,
    pub sweep_name: String,
    pub sweep_index: u32,
    pub started_hot: bool,
    pub cool_down_complete: bool,
    pub start_time_s: f64,
    pub duration_s: f64,
    pub start_temp_c: f64,
    pub peak_temp_c: f64,
    pub sliding_energy_j: f64,
    pub cool_down_s: f64,
    pub mech_hysteresis_n: f64,
    pub slip_angle_min_deg: f64,
    pub slip_angle_max_deg: f64,
    pub slip_ratio_min: f64,
    pub slip_ratio_max: f64,
    pub mean_fz_n: f64,
    pub mean_pressure_pa: f64,
    pub mean_camber_deg: f64,
    pub peak_fx_n: f64,
    pub peak_fy_n: f64,
    pub mean_dstwowhc_m: f64,
}

crate::ros_message!(SweepSummary, "tyre_msgs", "SweepSummary");

/// `tyre_msgs/QualityCheck`: one quality check's verdict.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct QualityCheck {
    pub level: u8,
    pub check: String,
    pub message: String,
    pub value: f64,
    pub threshold: f64,
    pub unit: String,
    pub rig_time_s: f64,
}

crate::ros_message!(QualityCheck, "tyre_msgs", "QualityCheck", [OK, WARN, ERROR,]);

impl QualityCheck {
    pub const OK: u8 = 0;
    pub const WARN: u8 = 1;
    pub const ERROR: u8 = 2;
}

/// `tyre_msgs/QualityReport`: the online quality monitor's report.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct QualityReport {
    pub header: Header,
    pub level: u8,
    pub checks: Vec<QualityCheck>,
    pub wear_mm: f64,
    pub wear_pct_usable: f64,
    pub wear_forecast_mm: f64,
    pub tread_depth_new_mm: f64,
    pub tread_depth_min_mm: f64,
}

crate::ros_message!(QualityReport, "tyre_msgs", "QualityReport");

//! The suite's own messages, mirroring `msg/*.msg` field for field.

use crate::std_msgs::Header;
use serde::{Deserialize, Serialize};

/// `tyre_msgs/RigSample`: one sample of every rig channel (TYDEX names, ISO-W axes).
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct RigSample {
    /// header.stamp = rig time the sample was taken; frame_id = "iso_w"
    pub header: Header,
    /// sample sequence number: 0 at rig start, +1 per sample, never reused
    pub seq: u64,
    /// RUNTIME: rig time since the rig started \[s\]
    pub runtime_s: f64,
    /// FX: longitudinal force, + forward (driving) \[N\]
    pub fx_n: f64,
    /// FYW: lateral force \[N\]
    pub fyw_n: f64,
    /// FZW: vertical load on the tyre, positive when loaded (MF convention) \[N\]
    pub fzw_n: f64,
    /// MXW: overturning moment \[N*m\]
    pub mxw_nm: f64,
    /// MYW: rolling resistance moment \[N*m\]
    pub myw_nm: f64,
    /// MZW: self-aligning moment \[N*m\]
    pub mzw_nm: f64,
    /// SLIPANGL: slip angle, + gives negative FYW for a normal tyre \[deg\]
    pub slipangl_deg: f64,
    /// LONGSLIP: slip ratio as the rig reports it, + driving \[-\]
    pub longslip: f64,
    /// INCLANGL: inclination (camber) angle \[deg\]
    pub inclangl_deg: f64,
    /// INFLPRES: inflation pressure (gauge) \[Pa\]
    pub inflpres_pa: f64,
    /// TRAJVELW: forward (belt) velocity of the wheel centre \[m/s\]
    pub trajvelw_mps: f64,
    /// W: wheel rotational speed \[rad/s\]
    pub wheel_speed_radps: f64,
    /// DSTWOWHC: wheel centre to ground distance = loaded radius \[m\]
    pub dstwowhc_m: f64,
    /// TRDTEMPI: inner tread surface temperature (laser) \[degC\]
    pub trdtempi_c: f64,
    /// TRDTEMPC: centre tread surface temperature (laser) \[degC\]
    pub trdtempc_c: f64,
    /// TRDTEMPO: outer tread surface temperature (laser) \[degC\]
    pub trdtempo_c: f64,
    /// RigSetpoint.MODE_* the rig is in while this sample was taken
    pub rig_mode: u8,
    /// FAULT_* bits; 0 = every channel valid
    pub fault_flags: u32,
}

crate::ros_message!(
    RigSample,
    "tyre_msgs",
    "RigSample",
    [FAULT_FORCE, FAULT_TEMPERATURE, FAULT_RADIUS, FAULT_ENVELOPE, FAULT_ESTOP]
);

impl RigSample {
    /// force/moment channels invalid
    pub const FAULT_FORCE: u32 = 1;
    /// tread temperature channels invalid
    pub const FAULT_TEMPERATURE: u32 = 2;
    /// DSTWOWHC invalid
    pub const FAULT_RADIUS: u32 = 4;
    /// the last setpoint was refused (outside the rig envelope)
    pub const FAULT_ENVELOPE: u32 = 8;
    /// the rig is in its safe state after an e-stop
    pub const FAULT_ESTOP: u32 = 16;
}

/// `tyre_msgs/RigSetpoint`: what the rig should do now.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct RigSetpoint {
    /// header.stamp = rig time the setpoint applies from
    pub header: Header,
    /// setpoint sequence number
    pub seq: u64,
    /// One of the `MODE_*` constants.
    pub mode: u8,
    /// SLIPANGL target \[deg\]
    pub slip_angle_deg: f64,
    /// LONGSLIP target, coupled mode only \[-\]
    pub slip_ratio: f64,
    /// FZW target, vertical load \[N\]
    pub fz_n: f64,
    /// INCLANGL target \[deg\]
    pub camber_deg: f64,
    /// INFLPRES target (gauge) \[Pa\]
    pub pressure_pa: f64,
    /// belt speed target \[m/s\]
    pub speed_mps: f64,
    /// static mode: belt displacement target from the lock point \[m\]
    pub belt_displacement_m: f64,
    /// keep the present slip angle, ignore slip_angle_deg
    pub hold_slip_angle: bool,
    /// keep the present slip ratio, ignore slip_ratio
    pub hold_slip_ratio: bool,
    /// keep the present load, ignore fz_n
    pub hold_load: bool,
    /// keep the present camber, ignore camber_deg
    pub hold_camber: bool,
    /// the sweep this setpoint belongs to ("" between sweeps)
    pub sweep_name: String,
}

crate::ros_message!(RigSetpoint, "tyre_msgs", "RigSetpoint", [MODE_FREE_ROLLING, MODE_COUPLED, MODE_STATIC, MODE_SAFE]);

impl RigSetpoint {
    /// drive un-coupled: the tyre rolls freely, slip ratio ~0
    pub const MODE_FREE_ROLLING: u8 = 0;
    /// drive coupled: slip ratio controlled
    pub const MODE_COUPLED: u8 = 1;
    /// wheel locked, belt moved (static longitudinal test, step-steer)
    pub const MODE_STATIC: u8 = 2;
    /// safe state: slip to zero, load off, belt stopped (e-stop, abort)
    pub const MODE_SAFE: u8 = 3;
}

/// `tyre_msgs/ProcedureCommand`: an operator's command to the sequencer.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct ProcedureCommand {
    /// Stamp of the command (rig time) and frame.
    pub header: Header,
    /// One of the command constants (`START` .. `ESTOP`).
    pub command: u8,
    /// START only: procedure name (e.g. "gs2mf") or file
    pub procedure: String,
    /// who sent it (free text, logged)
    pub operator_name: String,
}

crate::ros_message!(ProcedureCommand, "tyre_msgs", "ProcedureCommand", [START, PAUSE, RESUME, ABORT, ESTOP]);

impl ProcedureCommand {
    /// start `procedure` (or resume from its checkpoint)
    pub const START: u8 = 0;
    /// finish the present setpoint ramp to zero slip and hold
    pub const PAUSE: u8 = 1;
    /// continue after PAUSE
    pub const RESUME: u8 = 2;
    /// stop the procedure, bring the rig to its safe state, keep the checkpoint
    pub const ABORT: u8 = 3;
    /// emergency stop: safe state at once, no ramp
    pub const ESTOP: u8 = 4;
}

/// `tyre_msgs/ProcedureState`: where the sequencer is.
///
/// `Deserialize` is written out so that a state recorded before `plan_reason` and
/// `predicted_error_pct` existed still decodes (they are then empty and 0): older logs stay
/// readable.
#[derive(Debug, Clone, PartialEq, Default, Serialize)]
pub struct ProcedureState {
    /// Stamp (rig time) of this state.
    pub header: Header,
    /// One of the `PHASE_*` constants.
    pub phase: u8,
    /// e.g. "gs2mf_freerolling"
    pub procedure: String,
    /// e.g. "force_moment_2.6bar"
    pub section: String,
    /// 0-based index of the section in the procedure.
    pub section_index: u32,
    /// thesis naming, e.g. FreeRoll_sw14_VariableRate_LR2_HR30_TH4_1
    pub sweep_name: String,
    /// 0-based index of the sweep in the procedure
    pub sweep_index: u32,
    /// number of sweeps in the procedure
    pub sweep_count: u32,
    /// the thermal gate timed out before this sweep
    pub sweep_started_hot: bool,
    /// 0..1 of the procedure's planned setpoint time
    pub progress: f64,
    /// rig time since the procedure started
    pub elapsed_rig_time_s: f64,
    /// planned sweep time left + predicted thermal pauses
    pub estimated_remaining_s: f64,
    /// Why the step in progress runs. Empty for a fixed procedure; in an adaptive plan "fixed"
    /// for the procedure's own steps, else the planner's reason for choosing it.
    pub plan_reason: String,
    /// adaptive plan: predicted held-out error after the chosen sweep \[% of peak\]; 0 otherwise
    pub predicted_error_pct: f64,
}

impl<'de> Deserialize<'de> for ProcedureState {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        const FIELDS: [&str; 14] = [
            "header",
            "phase",
            "procedure",
            "section",
            "section_index",
            "sweep_name",
            "sweep_index",
            "sweep_count",
            "sweep_started_hot",
            "progress",
            "elapsed_rig_time_s",
            "estimated_remaining_s",
            "plan_reason",
            "predicted_error_pct",
        ];
        struct V;
        impl<'de> serde::de::Visitor<'de> for V {
            type Value = ProcedureState;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("tyre_msgs/ProcedureState")
            }
            fn visit_seq<A: serde::de::SeqAccess<'de>>(self, mut seq: A) -> Result<ProcedureState, A::Error> {
                use serde::de::Error;
                let mut n = 0;
                macro_rules! field {
                    () => {{
                        n += 1;
                        seq.next_element()?.ok_or_else(|| A::Error::invalid_length(n - 1, &self))?
                    }};
                }
                let mut st = ProcedureState {
                    header: field!(),
                    phase: field!(),
                    procedure: field!(),
                    section: field!(),
                    section_index: field!(),
                    sweep_name: field!(),
                    sweep_index: field!(),
                    sweep_count: field!(),
                    sweep_started_hot: field!(),
                    progress: field!(),
                    elapsed_rig_time_s: field!(),
                    estimated_remaining_s: field!(),
                    ..ProcedureState::default()
                };
                // Fields added later: a message that ends before them is an older one (CDR
                // has no field markers, so "ended" shows as an error or as no element).
                if let Ok(Some(reason)) = seq.next_element::<String>() {
                    st.plan_reason = reason;
                    if let Ok(Some(e)) = seq.next_element::<f64>() {
                        st.predicted_error_pct = e;
                    }
                }
                Ok(st)
            }
        }
        d.deserialize_struct("ProcedureState", &FIELDS, V)
    }
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
        PHASE_TYRE_CHANGE
    ]
);

impl ProcedureState {
    /// no procedure running
    pub const PHASE_IDLE: u8 = 0;
    /// a sweep is running
    pub const PHASE_SWEEP: u8 = 1;
    /// zero slip, waiting on the thermal gate
    pub const PHASE_THERMAL_PAUSE: u8 = 2;
    /// free-rolling hold before a longitudinal sweep: capture VX1 and W1 now
    pub const PHASE_FREE_ROLLING_REF: u8 = 3;
    /// moving between load cases, pressures or modes (no data of interest)
    pub const PHASE_SETTLE: u8 = 4;
    /// paused by the operator (PAUSE)
    pub const PHASE_PAUSED: u8 = 5;
    /// aborted (ABORT); the checkpoint is kept
    pub const PHASE_ABORTED: u8 = 6;
    /// emergency stop (ESTOP)
    pub const PHASE_ESTOP: u8 = 7;
    /// the procedure finished
    pub const PHASE_COMPLETE: u8 = 8;
    /// waiting for a tyre change
    pub const PHASE_TYRE_CHANGE: u8 = 9;
}

/// `tyre_msgs/ThermalState`: the thermal gate's view of the tyre.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct ThermalState {
    /// Stamp (rig time) of the temperature sample judged.
    pub header: Header,
    /// One of the `STATUS_*` constants.
    pub status: u8,
    /// true only for RELEASED and TIMED_OUT
    pub gate_open: bool,
    /// inputs as received \[degC\]
    pub trdtempi_c: f64,
    /// TRDTEMPC as received \[degC\]
    pub trdtempc_c: f64,
    /// TRDTEMPO as received \[degC\]
    pub trdtempo_c: f64,
    /// configurable weighting of inner/centre/outer \[degC\]
    pub weighted_temp_c: f64,
    /// weighted temperature after flash-spike filtering \[degC\]
    pub filtered_temp_c: f64,
    /// release threshold \[degC\]
    pub baseline_c: f64,
    /// time in the present thermal pause \[s\]
    pub pause_elapsed_s: f64,
    /// cooling model's estimate of the pause time left \[s\]
    pub predicted_wait_s: f64,
    /// the online cooling model's present time constant \[s\]
    pub cooling_time_constant_s: f64,
    /// why the gate holds in STATUS_FAULT ("" otherwise)
    pub fault: String,
}

crate::ros_message!(
    ThermalState,
    "tyre_msgs",
    "ThermalState",
    [STATUS_WAITING, STATUS_RELEASED, STATUS_TIMED_OUT, STATUS_FAULT, STATUS_IDLE]
);

impl ThermalState {
    /// cooling towards the baseline; the gate is closed
    pub const STATUS_WAITING: u8 = 0;
    /// at or below the baseline: the next sweep may start
    pub const STATUS_RELEASED: u8 = 1;
    /// released by the time-out: the next sweep starts hot (alarm)
    pub const STATUS_TIMED_OUT: u8 = 2;
    /// temperature not trustworthy (NaN, stuck, stale, absurd): holding
    pub const STATUS_FAULT: u8 = 3;
    /// no pause in progress
    pub const STATUS_IDLE: u8 = 4;
}

/// `tyre_msgs/LiveChannels`: channels computed live from every `RigSample`.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct LiveChannels {
    /// stamp copied from the RigSample
    pub header: Header,
    /// RigSample.seq these channels were computed from
    pub sample_seq: u64,
    /// sweep or section the sample belongs to ("" between sweeps)
    pub segment: String,
    /// RUNTIME minus the segment's first RUNTIME \[s\]
    pub zeroed_runtime_s: f64,
    /// LONGDISP: travelled distance in the segment \[m\]
    pub longdisp_m: f64,
    /// SR = (VX1/W1)(W/VX) - 1 with VX1, W1 from the free-rolling reference \[-\]
    pub slip_ratio_calspan: f64,
    /// SR = (W*Re - VX)/VX, Re from the radius model \[-\]
    pub slip_ratio_effective_radius: f64,
    /// PX = FX*SR*VX*cos(SA) \[W\]
    pub px_w: f64,
    /// PY = FY*VX*sin(SA) \[W\]
    pub py_w: f64,
    /// resultant sliding power sqrt(PX^2 + PY^2) \[W\]
    pub p_w: f64,
    /// AcSldEny: accumulated sliding energy in the segment (trapezoidal) \[J\]
    pub acsldeny_j: f64,
    /// accumulated over the whole tyre life so far \[J\]
    pub total_sliding_energy_j: f64,
}

crate::ros_message!(LiveChannels, "tyre_msgs", "LiveChannels");

/// `tyre_msgs/SweepSummary`: published at the end of every sweep.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct SweepSummary {
    /// Stamp (rig time) of the publication.
    pub header: Header,
    /// Procedure name.
    pub procedure: String,
    /// Section name.
    pub section: String,
    /// Sweep name (thesis naming).
    pub sweep_name: String,
    /// 0-based index of the sweep in the procedure.
    pub sweep_index: u32,
    /// the sweep started after a thermal time-out
    pub started_hot: bool,
    /// false for the first publication, true when cool_down_s is final
    pub cool_down_complete: bool,
    /// RUNTIME at the sweep's start \[s\]
    pub start_time_s: f64,
    /// sweep duration \[s\]
    pub duration_s: f64,
    /// TRDTEMPC at the start \[degC\]
    pub start_temp_c: f64,
    /// highest TRDTEMPC during the sweep \[degC\]
    pub peak_temp_c: f64,
    /// total sliding energy of the sweep \[J\]
    pub sliding_energy_j: f64,
    /// thermal pause that followed \[s\]
    pub cool_down_s: f64,
    /// max - min force at zero-slip crossings \[N\]
    pub mech_hysteresis_n: f64,
    /// Smallest slip angle in the sweep \[deg\].
    pub slip_angle_min_deg: f64,
    /// Largest slip angle in the sweep \[deg\].
    pub slip_angle_max_deg: f64,
    /// Smallest slip ratio in the sweep \[-\].
    pub slip_ratio_min: f64,
    /// Largest slip ratio in the sweep \[-\].
    pub slip_ratio_max: f64,
    /// Mean vertical load \[N\].
    pub mean_fz_n: f64,
    /// Mean inflation pressure (gauge) \[Pa\].
    pub mean_pressure_pa: f64,
    /// Mean inclination angle \[deg\].
    pub mean_camber_deg: f64,
    /// largest |FX| (signed value) \[N\]
    pub peak_fx_n: f64,
    /// largest |FYW| (signed value) \[N\]
    pub peak_fy_n: f64,
    /// mean loaded radius during the sweep \[m\]
    pub mean_dstwowhc_m: f64,
}

crate::ros_message!(SweepSummary, "tyre_msgs", "SweepSummary");

/// `tyre_msgs/DerivedMeasurement`: a tyre property derived live from a finished test section.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct DerivedMeasurement {
    /// Stamp (rig time) of the derivation.
    pub header: Header,
    /// What it is: `cornering_stiffness`, `rsat`, `rcf`, `loaded_radius`, `vertical_stiffness`,
    /// `unloaded_radius`, `lateral_relaxation_length`, `longitudinal_stiffness`.
    pub quantity: String,
    /// The value, in `unit`.
    pub value: f64,
    /// Unit of `value` (`N/deg`, `N*m`, `N`, `m`, `N/m`).
    pub unit: String,
    /// Procedure name.
    pub procedure: String,
    /// The section it was derived from.
    pub section: String,
    /// Mean vertical load (NaN if it spans loads) \[N\].
    pub fz_n: f64,
    /// Mean inflation pressure (NaN if it spans pressures) \[Pa\].
    pub pressure_pa: f64,
    /// Mean forward speed \[m/s\].
    pub speed_mps: f64,
    /// Slip angle the test held (NaN if none) \[deg\].
    pub slip_angle_deg: f64,
    /// Clumps, samples or tests that went into it.
    pub n_points: u32,
}

crate::ros_message!(DerivedMeasurement, "tyre_msgs", "DerivedMeasurement");

/// `tyre_msgs/QualityCheck`: one quality check's verdict.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct QualityCheck {
    /// One of `OK`, `WARN`, `ERROR`.
    pub level: u8,
    /// load_rating, wear, graph_sweep_drift, break_in, chatter, thermal_timeout, ...
    pub check: String,
    /// what was seen, in words
    pub message: String,
    /// the measured figure (NaN if none)
    pub value: f64,
    /// the threshold it was judged against (NaN if none)
    pub threshold: f64,
    /// unit of value and threshold
    pub unit: String,
    /// rig time of the verdict \[s\]
    pub rig_time_s: f64,
}

crate::ros_message!(QualityCheck, "tyre_msgs", "QualityCheck", [OK, WARN, ERROR]);

impl QualityCheck {
    /// the check passed
    pub const OK: u8 = 0;
    /// worth a look; the procedure goes on
    pub const WARN: u8 = 1;
    /// the data or the tyre are at risk
    pub const ERROR: u8 = 2;
}

/// `tyre_msgs/QualityReport`: the online quality monitor's report.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct QualityReport {
    /// Stamp (rig time) of the report.
    pub header: Header,
    /// worst QualityCheck level (QualityCheck.OK / WARN / ERROR)
    pub level: u8,
    /// Every check's latest verdict.
    pub checks: Vec<QualityCheck>,
    /// tread lost so far, measured from DSTWOWHC \[mm\]
    pub wear_mm: f64,
    /// of the usable tread (new minus legal minimum) \[%\]
    pub wear_pct_usable: f64,
    /// expected total wear at the end of the procedure \[mm\]
    pub wear_forecast_mm: f64,
    /// Tread depth of the new tyre \[mm\].
    pub tread_depth_new_mm: f64,
    /// Legal minimum tread depth \[mm\].
    pub tread_depth_min_mm: f64,
}

crate::ros_message!(QualityReport, "tyre_msgs", "QualityReport");

/// `tyre_msgs/ModelCoefficient`: one fitted coefficient of the live fit.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct ModelCoefficient {
    /// .tir key (PCY1, QBZ1, ...)
    pub key: String,
    /// fitted value
    pub value: f64,
    /// standard deviation (1 sigma); NaN/Inf when unidentified
    pub std: f64,
}

crate::ros_message!(ModelCoefficient, "tyre_msgs", "ModelCoefficient");

/// `tyre_msgs/ModelStage`: one stage of the live staged fit.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct ModelStage {
    /// One of `WAITING`, `FITTING`, `IDENTIFIED`.
    pub status: u8,
    /// fy_pure, mz_pure, ...
    pub stage: String,
    /// FY, MZ, FX, MX, RL, ...
    pub channel: String,
    /// why the stage is not identified yet (empty when it is)
    pub status_reason: String,
    /// data points the stage fitted
    pub points: u32,
    /// RMS residual, channel units
    pub rmse: f64,
    /// RMS residual in % of the stage's peak
    pub nrmse_pct: f64,
    /// optimiser iterations in this update
    pub iterations: u32,
    /// wall time of the stage in this update \[s\]
    pub wall_s: f64,
    /// fitted coefficients with standard deviations
    pub coefficients: Vec<ModelCoefficient>,
    /// coefficients kept at template values, as "KEY: reason"
    pub held: Vec<String>,
}

crate::ros_message!(ModelStage, "tyre_msgs", "ModelStage", [WAITING, FITTING, IDENTIFIED]);

impl ModelStage {
    /// no or not enough data for the stage yet
    pub const WAITING: u8 = 0;
    /// fitted, but the data do not yet pin every coefficient down
    pub const FITTING: u8 = 1;
    /// fitted; every coefficient the stage needs has a finite standard deviation
    pub const IDENTIFIED: u8 = 2;

    /// The status in words (`waiting`, `fitting`, `identified`).
    pub fn status_name(status: u8) -> &'static str {
        match status {
            Self::WAITING => "waiting",
            Self::FITTING => "fitting",
            Self::IDENTIFIED => "identified",
            _ => "unknown",
        }
    }
}

/// `tyre_msgs/ModelMap`: one channel's prediction and uncertainty over the envelope grid.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct ModelMap {
    /// FYW, FX or MZW
    pub channel: String,
    /// slip_angle_deg or slip_ratio
    pub slip_axis: String,
    /// the stage's residual RMSE
    pub residual_rmse: f64,
    /// model prediction at each grid point
    pub value: Vec<f64>,
    /// 1 sigma of the model's mean: parameter covariance and form error in quadrature
    pub std: Vec<f64>,
}

crate::ros_message!(ModelMap, "tyre_msgs", "ModelMap");

/// `tyre_msgs/ModelState`: the live fit's model after the latest completed sweep.
///
/// `Deserialize` is written out so that a state recorded before `maps_extrapolated` or
/// `maps_repeat_band` existed still decodes (nothing is then marked extrapolated, no repeat band
/// given): older logs stay readable.
#[derive(Debug, Clone, PartialEq, Default, Serialize)]
pub struct ModelState {
    /// stamp = rig time of the end of the sweep that triggered the update
    pub header: Header,
    /// 1 for the first update
    pub update_index: u32,
    /// force & moment segments in the data so far
    pub sweeps_used: u32,
    /// every data segment so far
    pub segments_used: u32,
    /// "section/sweep" of the segment that triggered the update
    pub last_sweep: String,
    /// the update at the procedure's end
    pub final_update: bool,
    /// wall time the update took \[s\]
    pub update_wall_s: f64,
    /// why the update failed (empty when it did not)
    pub error: String,
    /// per stage
    pub stages: Vec<ModelStage>,
    /// grid loads \[N\]
    pub grid_fz_n: Vec<f64>,
    /// slip axis of the FYW and MZW maps \[deg\]
    pub grid_slip_angle_deg: Vec<f64>,
    /// slip axis of the FX map
    pub grid_slip_ratio: Vec<f64>,
    /// grid cambers \[deg\]
    pub grid_camber_deg: Vec<f64>,
    /// grid pressures \[Pa\]
    pub grid_pressure_pa: Vec<f64>,
    /// speed of every grid point \[m/s\]
    pub grid_speed_mps: f64,
    /// one map per channel
    pub maps: Vec<ModelMap>,
    /// per map in `maps` order, one per grid point: outside the tested envelope (the value there
    /// is extrapolated); empty in a state recorded before the flag existed
    pub maps_extrapolated: Vec<bool>,
    /// per map in `maps` order: the band for a repeat measurement, ± this around the map's value
    /// holds 95 % of the stage's held-out residuals (channel units; NaN before the stage is
    /// fitted); empty in a state recorded before it existed
    pub maps_repeat_band: Vec<f64>,
}

impl ModelState {
    /// Whether grid point `i` of `maps[k]` is extrapolated (false when the state has no flags).
    pub fn extrapolated(&self, k: usize, i: usize) -> bool {
        let start: usize = self.maps.iter().take(k).map(|m| m.value.len()).sum();
        self.maps_extrapolated.get(start + i).copied().unwrap_or(false)
    }

    /// The band for a repeat measurement of `maps[k]` (NaN when the state has none).
    pub fn repeat_band(&self, k: usize) -> f64 {
        self.maps_repeat_band.get(k).copied().unwrap_or(f64::NAN)
    }
}

impl<'de> Deserialize<'de> for ModelState {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        const FIELDS: [&str; 18] = [
            "header",
            "update_index",
            "sweeps_used",
            "segments_used",
            "last_sweep",
            "final_update",
            "update_wall_s",
            "error",
            "stages",
            "grid_fz_n",
            "grid_slip_angle_deg",
            "grid_slip_ratio",
            "grid_camber_deg",
            "grid_pressure_pa",
            "grid_speed_mps",
            "maps",
            "maps_extrapolated",
            "maps_repeat_band",
        ];
        struct V;
        impl<'de> serde::de::Visitor<'de> for V {
            type Value = ModelState;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("tyre_msgs/ModelState")
            }
            fn visit_seq<A: serde::de::SeqAccess<'de>>(self, mut seq: A) -> Result<ModelState, A::Error> {
                use serde::de::Error;
                let mut n = 0;
                macro_rules! field {
                    () => {{
                        n += 1;
                        seq.next_element()?.ok_or_else(|| A::Error::invalid_length(n - 1, &self))?
                    }};
                }
                let mut st = ModelState {
                    header: field!(),
                    update_index: field!(),
                    sweeps_used: field!(),
                    segments_used: field!(),
                    last_sweep: field!(),
                    final_update: field!(),
                    update_wall_s: field!(),
                    error: field!(),
                    stages: field!(),
                    grid_fz_n: field!(),
                    grid_slip_angle_deg: field!(),
                    grid_slip_ratio: field!(),
                    grid_camber_deg: field!(),
                    grid_pressure_pa: field!(),
                    grid_speed_mps: field!(),
                    maps: field!(),
                    ..ModelState::default()
                };
                // Added later: a message that ends before it is an older one (CDR has no field
                // markers, so "ended" shows as an error or as no element).
                if let Ok(Some(flags)) = seq.next_element::<Vec<bool>>() {
                    st.maps_extrapolated = flags;
                    if let Ok(Some(bands)) = seq.next_element::<Vec<f64>>() {
                        st.maps_repeat_band = bands;
                    }
                }
                Ok(st)
            }
        }
        d.deserialize_struct("ModelState", &FIELDS, V)
    }
}

crate::ros_message!(ModelState, "tyre_msgs", "ModelState");

/// `tyre_msgs/StageCovariance`: one fitted stage of the live model in a `ModelCovariance`, the
/// covariance of its coefficients.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct StageCovariance {
    /// fy_pure, mz_pure, fx_pure, fx_combined, fy_combined, mz_combined, mx, ...
    pub stage: String,
    /// RMS residual of the stage, channel units (SI)
    pub rmse: f64,
    /// .tir keys, in the covariance's row order
    pub keys: Vec<String>,
    /// row-major keys x keys (delta method, serial-correlation inflation included); NaN/Inf
    /// where a coefficient is not identified
    pub covariance: Vec<f64>,
    /// keys held at template values because the data lack levels of what they multiply (a
    /// pressure or camber not tested yet)
    pub held_for_want_of_data: Vec<String>,
}

crate::ros_message!(StageCovariance, "tyre_msgs", "StageCovariance");

/// `tyre_msgs/ModelCovariance`: the live fit's whole model with the coefficient covariance of
/// each fitted stage, published with every `ModelState` (same stamp and update_index).
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct ModelCovariance {
    /// as the model/state of the same update
    pub header: Header,
    /// as the model/state of the same update
    pub update_index: u32,
    /// false until the first successful fit (tir and stages then empty)
    pub has_model: bool,
    /// ProcedureState.sweep_index of the newest segment (not a warm-up) in the update's data
    pub last_sweep_index: u32,
    /// "section/sweep" of that segment
    pub last_sweep: String,
    /// the model as .tir text (FITTYP 61); reads back to identical values
    pub tir: String,
    /// nominal load the fit found (FNOMIN) \[N\]
    pub fz0_n: f64,
    /// nominal pressure (NOMPRES) \[Pa\]
    pub p0_pa: f64,
    /// nominal speed (LONGVL) \[m/s\]
    pub v0_mps: f64,
    /// unloaded radius (UNLOADED_RADIUS) \[m\]
    pub r0_m: f64,
    /// the fitted stages, in fit order
    pub stages: Vec<StageCovariance>,
}

crate::ros_message!(ModelCovariance, "tyre_msgs", "ModelCovariance");

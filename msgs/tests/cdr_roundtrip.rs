//! Every message type through CDR and back, with a non-default value in every field.

use tyre_msgs::RosMessage;
use tyre_msgs::builtin_interfaces::Time;
use tyre_msgs::cdr::{from_cdr_with_header, to_cdr_with_header};
use tyre_msgs::diagnostic_msgs::{DiagnosticArray, DiagnosticStatus, KeyValue};
use tyre_msgs::introspect::exemplar;
use tyre_msgs::rosgraph_msgs::Clock;
use tyre_msgs::std_msgs::Header;
use tyre_msgs::*;

/// Round-trip a generated value with every field set (sequences of 3, unicode strings).
fn round_trip<M: RosMessage + PartialEq + Default>() {
    let value: M = exemplar(3).unwrap_or_else(|e| panic!("{}: {e}", M::ros_type_name()));
    assert_ne!(value, M::default(), "{}: exemplar is default", M::ros_type_name());
    let bytes = to_cdr_with_header(&value).unwrap();
    assert_eq!(bytes[..4], [0, 1, 0, 0]);
    let back: M = from_cdr_with_header(&bytes).unwrap_or_else(|e| panic!("{}: {e}", M::ros_type_name()));
    assert_eq!(back, value, "{}", M::ros_type_name());
    // Empty sequences and empty strings are a different code path (length 0 / length 1).
    let empty = M::default();
    let back: M = from_cdr_with_header(&to_cdr_with_header(&empty).unwrap()).unwrap();
    assert_eq!(back, empty, "{} (default)", M::ros_type_name());
}

#[test]
fn every_type_round_trips() {
    round_trip::<RigSample>();
    round_trip::<RigSetpoint>();
    round_trip::<ProcedureCommand>();
    round_trip::<ProcedureState>();
    round_trip::<ThermalState>();
    round_trip::<LiveChannels>();
    round_trip::<SweepSummary>();
    round_trip::<DerivedMeasurement>();
    round_trip::<QualityCheck>();
    round_trip::<QualityReport>();
    round_trip::<ModelCoefficient>();
    round_trip::<ModelStage>();
    round_trip::<ModelMap>();
    round_trip::<ModelState>();
    round_trip::<StageCovariance>();
    round_trip::<ModelCovariance>();
    round_trip::<Time>();
    round_trip::<Header>();
    round_trip::<KeyValue>();
    round_trip::<DiagnosticStatus>();
    round_trip::<DiagnosticArray>();
    round_trip::<Clock>();
}

/// A hand-written value, to not depend only on generated data.
#[test]
fn hand_written_quality_report_round_trips() {
    let report = QualityReport {
        header: Header::iso_w(12.5),
        level: QualityCheck::WARN,
        checks: vec![
            QualityCheck {
                level: QualityCheck::WARN,
                check: "graph_sweep_drift".to_owned(),
                message: "Fy drift 4.2 % über Schwelle — prüfen".to_owned(),
                value: 4.2,
                threshold: 3.0,
                unit: "%".to_owned(),
                rig_time_s: 12.4,
            },
            QualityCheck {
                level: QualityCheck::OK,
                check: "wear".to_owned(),
                message: "ok ✓".to_owned(),
                value: 0.31,
                threshold: 2.0,
                unit: "mm".to_owned(),
                rig_time_s: 12.5,
            },
            QualityCheck::default(),
        ],
        wear_mm: 0.31,
        wear_pct_usable: 5.2,
        wear_forecast_mm: 1.9,
        tread_depth_new_mm: 8.0,
        tread_depth_min_mm: 1.6,
    };
    let bytes = to_cdr_with_header(&report).unwrap();
    assert_eq!(from_cdr_with_header::<QualityReport>(&bytes).unwrap(), report);
    // Truncating anywhere must give an error, never a panic.
    for cut in 0..bytes.len() {
        assert!(from_cdr_with_header::<QualityReport>(&bytes[..cut]).is_err());
    }
}

/// `ProcedureState` as it was before `plan_reason` and `predicted_error_pct`: what older logs
/// hold.
#[derive(serde::Serialize)]
struct ProcedureStateV1 {
    header: Header,
    phase: u8,
    procedure: String,
    section: String,
    section_index: u32,
    sweep_name: String,
    sweep_index: u32,
    sweep_count: u32,
    sweep_started_hot: bool,
    progress: f64,
    elapsed_rig_time_s: f64,
    estimated_remaining_s: f64,
}

#[test]
fn a_procedure_state_from_an_older_log_still_decodes() {
    let old = ProcedureStateV1 {
        header: Header::iso_w(12.5),
        phase: ProcedureState::PHASE_SWEEP,
        procedure: "gs2mf_freerolling".into(),
        section: "force_moment".into(),
        section_index: 3,
        sweep_name: "FreeRoll_sw14".into(),
        sweep_index: 14,
        sweep_count: 80,
        sweep_started_hot: true,
        progress: 0.25,
        elapsed_rig_time_s: 900.0,
        estimated_remaining_s: 2700.0,
    };
    let back: ProcedureState = from_cdr_with_header(&to_cdr_with_header(&old).unwrap()).unwrap();
    assert_eq!((back.sweep_name.as_str(), back.sweep_index, back.estimated_remaining_s), ("FreeRoll_sw14", 14, 2700.0));
    assert!(back.sweep_started_hot);
    assert_eq!((back.plan_reason.as_str(), back.predicted_error_pct), ("", 0.0));
    // A cut message is still an error, not a default.
    let bytes = to_cdr_with_header(&old).unwrap();
    assert!(from_cdr_with_header::<ProcedureState>(&bytes[..bytes.len() - 12]).is_err());
    // And the new fields survive.
    let new = ProcedureState { plan_reason: "value 0.2 %²/s".into(), predicted_error_pct: 1.4, ..back };
    let again: ProcedureState = from_cdr_with_header(&to_cdr_with_header(&new).unwrap()).unwrap();
    assert_eq!(again, new);
}

/// `ModelState` as it was before `maps_extrapolated`: what older live-fit logs hold.
#[derive(serde::Serialize)]
struct ModelStateV1 {
    header: Header,
    update_index: u32,
    sweeps_used: u32,
    segments_used: u32,
    last_sweep: String,
    final_update: bool,
    update_wall_s: f64,
    error: String,
    stages: Vec<ModelStage>,
    grid_fz_n: Vec<f64>,
    grid_slip_angle_deg: Vec<f64>,
    grid_slip_ratio: Vec<f64>,
    grid_camber_deg: Vec<f64>,
    grid_pressure_pa: Vec<f64>,
    grid_speed_mps: f64,
    maps: Vec<ModelMap>,
}

impl ModelStateV1 {
    /// `now` as a state of before `maps_extrapolated` held it.
    fn of(now: &ModelState) -> Self {
        ModelStateV1 {
            header: now.header.clone(),
            update_index: now.update_index,
            sweeps_used: now.sweeps_used,
            segments_used: now.segments_used,
            last_sweep: now.last_sweep.clone(),
            final_update: now.final_update,
            update_wall_s: now.update_wall_s,
            error: now.error.clone(),
            stages: now.stages.clone(),
            grid_fz_n: now.grid_fz_n.clone(),
            grid_slip_angle_deg: now.grid_slip_angle_deg.clone(),
            grid_slip_ratio: now.grid_slip_ratio.clone(),
            grid_camber_deg: now.grid_camber_deg.clone(),
            grid_pressure_pa: now.grid_pressure_pa.clone(),
            grid_speed_mps: now.grid_speed_mps,
            maps: now.maps.clone(),
        }
    }
}

#[test]
fn a_model_state_from_an_older_log_still_decodes_with_nothing_extrapolated() {
    let now: ModelState = exemplar(3).unwrap();
    assert!(!now.maps_extrapolated.is_empty());
    let old = ModelStateV1::of(&now);
    let bytes = to_cdr_with_header(&old).unwrap();
    let back: ModelState = from_cdr_with_header(&bytes).unwrap();
    assert_eq!(back, ModelState { maps_extrapolated: Vec::new(), maps_repeat_band: Vec::new(), ..now.clone() });
    assert!(!back.extrapolated(0, 0));
    assert!(back.repeat_band(0).is_nan());
    // A cut message is still an error, not a default.
    assert!(from_cdr_with_header::<ModelState>(&bytes[..bytes.len() - 12]).is_err());
    // The flags of a state now survive, and index per map.
    let n = now.maps[0].value.len();
    assert!(now.maps.len() >= 2 && now.maps.iter().all(|m| m.value.len() == n));
    let flagged = ModelState { maps_extrapolated: (0..now.maps.len() * n).map(|i| i == n).collect(), ..now };
    let again: ModelState = from_cdr_with_header(&to_cdr_with_header(&flagged).unwrap()).unwrap();
    assert_eq!(again, flagged);
    assert!(again.extrapolated(1, 0) && !again.extrapolated(0, 0) && !again.extrapolated(1, 1));
}

/// `ModelState` as it was before `maps_repeat_band` (with `maps_extrapolated`).
#[derive(serde::Serialize)]
struct ModelStateV2 {
    v1: ModelStateV1,
    maps_extrapolated: Vec<bool>,
}

#[test]
fn a_model_state_from_before_the_repeat_band_still_decodes_without_one() {
    let now: ModelState = exemplar(5).unwrap();
    assert!(!now.maps_repeat_band.is_empty() && !now.maps_extrapolated.is_empty());
    let old = ModelStateV2 { v1: ModelStateV1::of(&now), maps_extrapolated: now.maps_extrapolated.clone() };
    let back: ModelState = from_cdr_with_header(&to_cdr_with_header(&old).unwrap()).unwrap();
    assert_eq!(back, ModelState { maps_repeat_band: Vec::new(), ..now.clone() });
    assert!(back.repeat_band(0).is_nan());
    // A state now keeps its bands, one per map.
    let again: ModelState = from_cdr_with_header(&to_cdr_with_header(&now).unwrap()).unwrap();
    assert_eq!(again, now);
    assert_eq!(again.repeat_band(0), now.maps_repeat_band[0]);
}

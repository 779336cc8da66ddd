//! Prints the CDR payloads (encapsulation header included, as hex) of a fixed set of messages,
//! or the `ros2msg` schema text of a type. `tests/python/test_idl_roundtrip.py` builds the same
//! values with Python `cyclonedds` and compares byte for byte, and decodes these payloads with
//! `mcap-ros2-support` using the schema text.
//!
//! ```text
//! cargo run -p tyre_msgs --example encode_sample            # "<ros type name> <hex>" per line
//! cargo run -p tyre_msgs --example encode_sample -- schema tyre_msgs/msg/RigSample
//! cargo run -p tyre_msgs --example encode_sample -- types   # every embedded type name
//! ```

use std::process::ExitCode;
use tyre_msgs::builtin_interfaces::Time;
use tyre_msgs::cdr::to_cdr_with_header;
use tyre_msgs::diagnostic_msgs::{DiagnosticArray, DiagnosticStatus, KeyValue};
use tyre_msgs::rosgraph_msgs::Clock;
use tyre_msgs::schema::{DEFINITIONS, ros2msg_schema_for};
use tyre_msgs::std_msgs::Header;
use tyre_msgs::{ProcedureCommand, QualityCheck, QualityReport, RigSample, RigSetpoint, RosMessage};

fn header(sec: i32, nanosec: u32, frame_id: &str) -> Header {
    Header { stamp: Time { sec, nanosec }, frame_id: frame_id.to_owned() }
}

// The values below are mirrored in tests/python/test_idl_roundtrip.py: change both together.

fn rig_sample() -> RigSample {
    RigSample {
        header: header(12, 345_678_901, "iso_w"),
        seq: 1_234_567,
        runtime_s: 12.345678901,
        fx_n: -1523.25,
        fyw_n: 2210.5,
        fzw_n: 4000.0,
        mxw_nm: -12.75,
        myw_nm: 3.5,
        mzw_nm: -45.125,
        slipangl_deg: -2.5,
        longslip: 0.0625,
        inclangl_deg: 1.5,
        inflpres_pa: 250_000.0,
        trajvelw_mps: 16.5,
        wheel_speed_radps: 52.25,
        dstwowhc_m: 0.3125,
        trdtempi_c: 41.5,
        trdtempc_c: 43.25,
        trdtempo_c: 40.0,
        rig_mode: RigSetpoint::MODE_COUPLED,
        fault_flags: RigSample::FAULT_TEMPERATURE | RigSample::FAULT_ESTOP,
    }
}

fn rig_setpoint() -> RigSetpoint {
    RigSetpoint {
        header: header(3, 0, "iso_w"),
        seq: 99,
        mode: RigSetpoint::MODE_STATIC,
        slip_angle_deg: 4.0,
        slip_ratio: -0.125,
        fz_n: 3000.0,
        camber_deg: -1.0,
        pressure_pa: 180_000.0,
        speed_mps: 0.0,
        belt_displacement_m: 0.015,
        hold_slip_angle: true,
        hold_slip_ratio: false,
        hold_load: true,
        hold_camber: false,
        sweep_name: "FreeRoll_sw14_VariableRate_LR2_HR30_TH4_1".to_owned(),
    }
}

fn procedure_command() -> ProcedureCommand {
    ProcedureCommand {
        header: header(5, 6, ""),
        command: ProcedureCommand::ABORT,
        procedure: "gs2mf".to_owned(),
        operator_name: "Zoë Ångström".to_owned(),
    }
}

fn quality_report() -> QualityReport {
    QualityReport {
        header: header(100, 5, ""),
        level: QualityCheck::WARN,
        checks: vec![
            QualityCheck {
                level: QualityCheck::WARN,
                check: "graph_sweep_drift".to_owned(),
                message: "Fy-Drift 4,2 % — über Schwelle".to_owned(),
                value: 4.25,
                threshold: 3.0,
                unit: "%".to_owned(),
                rig_time_s: 99.5,
            },
            QualityCheck {
                level: QualityCheck::OK,
                check: "wear".to_owned(),
                message: "ok ✓".to_owned(),
                value: 0.375,
                threshold: 2.0,
                unit: "mm".to_owned(),
                rig_time_s: 100.0,
            },
        ],
        wear_mm: 0.375,
        wear_pct_usable: 5.5,
        wear_forecast_mm: 1.875,
        tread_depth_new_mm: 8.0,
        tread_depth_min_mm: 1.5,
    }
}

fn diagnostic_array() -> DiagnosticArray {
    DiagnosticArray {
        header: header(7, 8, "rig"),
        status: vec![
            DiagnosticStatus {
                level: DiagnosticStatus::WARN,
                name: "tyrerig: thermal".to_owned(),
                message: "Abkühlung läuft".to_owned(),
                hardware_id: "rig-1".to_owned(),
                values: vec![
                    KeyValue { key: "baseline_c".to_owned(), value: "45.0".to_owned() },
                    KeyValue { key: "ü".to_owned(), value: "✓".to_owned() },
                ],
            },
            DiagnosticStatus { level: DiagnosticStatus::OK, name: "x".to_owned(), ..DiagnosticStatus::default() },
        ],
    }
}

fn clock() -> Clock {
    Clock { clock: Time { sec: 1_700_000_000, nanosec: 999_999_999 } }
}

fn line<M: RosMessage>(msg: &M) -> Result<String, tyre_msgs::cdr::CdrError> {
    let bytes = to_cdr_with_header(msg)?;
    let hex: String = bytes.iter().map(|b| format!("{b:02x}")).collect();
    Ok(format!("{} {hex}", M::ros_type_name()))
}

fn run(args: &[String]) -> Result<(), String> {
    match args {
        [] => {
            let lines = [
                line(&rig_sample()),
                line(&rig_setpoint()),
                line(&procedure_command()),
                line(&quality_report()),
                line(&diagnostic_array()),
                line(&clock()),
            ];
            for l in lines {
                println!("{}", l.map_err(|e| e.to_string())?);
            }
            Ok(())
        }
        [cmd, type_name] if cmd == "schema" => {
            print!("{}", ros2msg_schema_for(type_name).map_err(|e| e.to_string())?);
            Ok(())
        }
        [cmd] if cmd == "types" => {
            for d in DEFINITIONS {
                println!("{}", d.ros_type_name());
            }
            Ok(())
        }
        _ => Err("usage: encode_sample [schema <pkg/msg/Type> | types]".to_owned()),
    }
}

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    match run(&args) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("encode_sample: {e}");
            ExitCode::FAILURE
        }
    }
}

//! The drift test: every `.msg` file against its Rust type, field by field and constant by
//! constant. See `tyre_msgs::drift` for how the comparison works.

use tyre_msgs::RosMessage;
use tyre_msgs::builtin_interfaces::Time;
use tyre_msgs::diagnostic_msgs::{DiagnosticArray, DiagnosticStatus, KeyValue};
use tyre_msgs::drift::check_message;
use tyre_msgs::rosgraph_msgs::Clock;
use tyre_msgs::schema::DEFINITIONS;
use tyre_msgs::std_msgs::Header;
use tyre_msgs::*;

/// Check one type; return its ROS name and every drift found, as text.
fn check<M: RosMessage>() -> (String, Vec<String>) {
    let drifts = match check_message::<M>() {
        Ok(d) => d.iter().map(ToString::to_string).collect(),
        Err(e) => vec![e.to_string()],
    };
    (M::ros_type_name(), drifts)
}

#[test]
fn no_rust_type_drifts_from_its_msg_file() {
    let results = [
        check::<RigSample>(),
        check::<RigSetpoint>(),
        check::<ProcedureCommand>(),
        check::<ProcedureState>(),
        check::<ThermalState>(),
        check::<LiveChannels>(),
        check::<SweepSummary>(),
        check::<DerivedMeasurement>(),
        check::<QualityCheck>(),
        check::<QualityReport>(),
        check::<ModelCoefficient>(),
        check::<ModelStage>(),
        check::<ModelMap>(),
        check::<ModelState>(),
        check::<StageCovariance>(),
        check::<ModelCovariance>(),
        check::<Time>(),
        check::<Header>(),
        check::<KeyValue>(),
        check::<DiagnosticStatus>(),
        check::<DiagnosticArray>(),
        check::<Clock>(),
    ];
    let failures: Vec<String> =
        results.iter().flat_map(|(name, drifts)| drifts.iter().map(move |d| format!("{name}: {d}"))).collect();
    assert!(failures.is_empty(), "Rust types drifted from their .msg files:\n{}", failures.join("\n"));

    // Every embedded .msg must have been checked: a new .msg without a Rust type (or a Rust
    // type left out of the list above) fails here.
    let mut checked: Vec<String> = results.iter().map(|(n, _)| n.clone()).collect();
    let mut embedded: Vec<String> = DEFINITIONS.iter().map(|d| d.ros_type_name()).collect();
    checked.sort();
    embedded.sort();
    assert_eq!(checked, embedded);
}

#[test]
fn every_msg_file_in_msg_dir_is_embedded() {
    // CMakeLists.txt, msg/ and the embedded list must agree, or colcon and Rust see different
    // packages.
    let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/msg");
    let mut on_disk: Vec<String> = std::fs::read_dir(dir)
        .expect("msg/ is readable")
        .filter_map(|e| e.ok())
        .filter_map(|e| e.file_name().into_string().ok())
        .filter(|n| n.ends_with(".msg"))
        .map(|n| format!("msg/{n}"))
        .collect();
    on_disk.sort();
    let mut embedded: Vec<String> =
        DEFINITIONS.iter().filter(|d| d.package == "tyre_msgs").map(|d| d.path.to_owned()).collect();
    embedded.sort();
    assert_eq!(on_disk, embedded);

    let cmake = include_str!("../CMakeLists.txt");
    for path in &on_disk {
        assert!(cmake.contains(&format!("\"{path}\"")), "{path} is not listed in CMakeLists.txt");
    }
}

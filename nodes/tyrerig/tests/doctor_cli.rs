//! `tyrerig doctor` on measured files (the TTC-style fixtures of the virtual brush race tyre,
//! `tests/fixtures/ttc`), end to end with the built binary: the files are imported, the base
//! model is fitted, and channels the base was not fitted for are not diagnosed.

use std::path::PathBuf;
use std::process::Command;

fn fixture(name: &str) -> String {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../tests/fixtures/ttc").join(name).display().to_string()
}

fn doctor(files: &[&str], extra: &[&str], out: &str) -> serde_json::Value {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("doctor_cli").join(out);
    let mut args: Vec<String> = vec!["doctor".into()];
    args.extend(files.iter().map(|f| fixture(f)));
    args.extend(["--fit".into(), "--skip-stage".into(), "mx".into(), "--out".into(), dir.display().to_string()]);
    args.extend(extra.iter().map(|s| s.to_string()));
    let o = Command::new(env!("CARGO_BIN_EXE_tyrerig")).args(&args).output().expect("run tyrerig");
    assert!(
        o.status.success(),
        "tyrerig {args:?}: {}\n{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    );
    let json = std::fs::read_to_string(dir.join("doctor.json")).expect("doctor.json");
    serde_json::from_str(&json).expect("doctor.json parses")
}

/// Acceptance (issue 12): on the brush-tyre logs without the hidden temperature dependence of
/// friction and with no radius fit, nothing is named on DSTWOWHC — the report says the channel
/// is not diagnosed, and no named effect has it as its channel. The flash of the drive/brake
/// run's tread lasers is found and fitted out (a decay of seconds, as the rig's longitudinal
/// flash has).
#[test]
fn no_radius_fit_names_nothing_on_the_loaded_radius() {
    let d = doctor(
        &["race_cornering.dat", "race_drive_brake_no_thermal_grip.dat"],
        &["--skip-stage", "radius_stiffness"],
        "no_thermal_grip",
    );
    let nd: Vec<String> = d["not_diagnosed"]
        .as_array()
        .expect("not_diagnosed")
        .iter()
        .map(|v| v.as_str().unwrap_or("").to_owned())
        .collect();
    assert!(
        nd.iter().any(|s| s.starts_with("DSTWOWHC not diagnosed: the base's loaded radius was not fitted")),
        "{nd:?}"
    );
    for e in d["effects"].as_array().expect("effects") {
        assert_ne!(e["channel"].as_str(), Some("DSTWOWHC"), "named on DSTWOWHC: {e}");
    }
    let taus = d["laser_flash_decay_s"].as_array().expect("laser_flash_decay_s");
    assert_eq!(taus.len(), 2, "one flash fit per log: {taus:?}");
    let tau_db = taus[1].as_f64().expect("the drive/brake run's flash is found");
    assert!((0.5..=4.0).contains(&tau_db), "flash decay {tau_db} s");
}

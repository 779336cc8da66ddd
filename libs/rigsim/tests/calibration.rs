//! The acceptance test: the thesis's comparison sweeps (Tables 3.6.2-H and 3.6.2-I), the warm-up
//! and the wear check on the virtual rig with the default tyre and the committed config. Prints
//! the same table as `tyrerig rig calibrate` (run with `--nocapture` to see it).

use std::path::PathBuf;

use rigsim::calibration::{format_report, run_calibration};
use rigsim::{RigConfig, TyreParams};

#[test]
fn virtual_rig_matches_the_thesis() {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../launch-config/virtual_rig.toml");
    let cfg = RigConfig::load(&path).expect("config");
    let params = TyreParams::read_tir(&cfg.tyre_file).expect("tyre");
    let report = run_calibration(&cfg, &params).expect("calibration runs");
    let table = format_report(&report);
    println!("{table}");
    assert!(report.pass(), "calibration misses:\n{table}");
}

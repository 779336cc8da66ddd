//! The acceptance test: the thesis's comparison sweeps (Tables 3.6.2-H and 3.6.2-I), the BrkDrv
//! threshold analysis, the warm-up and the wear check on the virtual rig with the default tyre
//! and the committed config, for every noise seed 0..=9 (the figures must not depend on the luck
//! of the noise). Prints seed 0's table (as `tyrerig rig calibrate`) and each figure's min–max
//! over the seeds (as `tyrerig rig calibrate --seeds 10`); run with `--nocapture` to see them.

use std::path::PathBuf;

use rigsim::calibration::{format_report, format_spread, run_calibration_seeds, seed_spread};
use rigsim::{RigConfig, TyreParams};

#[test]
fn virtual_rig_matches_the_thesis_for_every_seed() {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../launch-config/virtual_rig.toml");
    let cfg = RigConfig::load(&path).expect("config");
    let params = TyreParams::read_tir(&cfg.tyre_file).expect("tyre");
    let reports = run_calibration_seeds(&cfg, &params, 0..=9).expect("calibration runs");
    println!("{}", format_report(&reports[0]));
    let spread = seed_spread(&reports);
    println!("{}", format_spread(&spread));
    let missed: Vec<String> = reports
        .iter()
        .filter(|r| !r.pass())
        .map(|r| format!("seed {}:\n  {}", r.seed, r.failures.join("\n  ")))
        .collect();
    assert!(missed.is_empty(), "calibration misses:\n{}", missed.join("\n"));
}

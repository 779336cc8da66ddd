//! Runs the calibration and prints the table: `cargo run --release -p rigsim --example calibrate [config]`.

use std::path::PathBuf;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let path = std::env::args()
        .nth(1)
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../launch-config/virtual_rig.toml"));
    let cfg = rigsim::RigConfig::load(&path)?;
    let params = rigsim::TyreParams::read_tir(&cfg.tyre_file)?;
    let t = std::time::Instant::now();
    let report = rigsim::calibration::run_calibration(&cfg, &params)?;
    print!("{}", rigsim::calibration::format_report(&report));
    eprintln!("wall {:.2} s", t.elapsed().as_secs_f64());
    Ok(())
}

//! Writes the synthetic TTC-like runs the tests use as files, to try the readers by hand:
//!
//! `cargo run --release -p rigdata --example ttc_fixtures -- out/ttc` then
//! `tyrerig inspect out/ttc/cornering.dat`, `tyrerig import ttc out/ttc --dry-run`, …

use rigdata::fixture::{FixtureSpec, ttc_run};
use rigdata::mat::{MatWriteOptions, write_mat};
use rigdata::table::{DatLayout, to_dat};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let dir = std::path::PathBuf::from(std::env::args().nth(1).unwrap_or_else(|| "out/ttc".into()));
    std::fs::create_dir_all(&dir)?;
    for (name, spec) in [("cornering", FixtureSpec::cornering()), ("drive_brake", FixtureSpec::drive_brake())] {
        let run = ttc_run(&spec);
        std::fs::write(dir.join(format!("{name}.dat")), to_dat(&run.table, DatLayout::default()))?;
        write_mat(&dir.join(format!("{name}.mat")), &run.table, &MatWriteOptions::default())?;
        let fitted = run.sweeps.iter().filter(|s| !s.conditioning).count();
        println!(
            "{name}: {} rows, {} sweeps planned ({} conditioning)",
            run.table.rows(),
            fitted,
            run.sweeps.len() - fitted
        );
    }
    Ok(())
}

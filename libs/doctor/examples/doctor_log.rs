//! The doctor on MCAP logs without the full `tyrerig` binary (same library calls as
//! `tyrerig doctor --model`): `cargo run --release -p doctor --example doctor_log -- <base.tir>
//! <out dir> <log.mcap>…`. Prints the named effects and the wall time.

use doctor::{DataOptions, Dataset, DoctorConfig, RawLog, diagnose, report};
use std::path::Path;
use std::time::Instant;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    if args.len() < 3 {
        eprintln!("usage: doctor_log <base.tir> <out dir> <log.mcap>…");
        std::process::exit(2);
    }
    let t0 = Instant::now();
    let base = mftyre::TyreParams::read_tir(Path::new(&args[0]))?;
    let logs = args[2..].iter().map(|p| RawLog::read_mcap(Path::new(p))).collect::<Result<Vec<_>, _>>()?;
    let t_read = t0.elapsed().as_secs_f64();
    let ds = Dataset::from_logs(&logs, &DataOptions::default())?;
    eprintln!("read {t_read:.1} s; {} points in {} sweeps", ds.len(), ds.sweeps.len());
    let dx = diagnose(&ds, &base, &DoctorConfig::default())?;
    let wall = t0.elapsed().as_secs_f64();
    let w = report::write_all(Path::new(&args[1]), &ds, &base, &dx, &args[0], wall)?;
    for n in &dx.named {
        println!(
            "{} evidence {:.3} runner-up {:?} {} region RMS fit {:.4} → {:.4}, held-out {:.4} → {:.4}",
            n.effect.name(),
            n.evidence,
            n.runner_up.map(|(e, v)| (e.name(), v)),
            n.channel,
            n.rms_before,
            n.rms_after,
            n.rms_before_heldout,
            n.rms_after_heldout
        );
    }
    if dx.named.is_empty() {
        println!("nothing named: {}", dx.stop_reason);
    }
    println!("{}; wall time {wall:.1} s", w.markdown.display());
    Ok(())
}

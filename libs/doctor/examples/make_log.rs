//! Writes a virtual-rig MCAP log with chosen hidden effects, in-process (the headless suite),
//! for trying the doctor without the full `tyrerig` binary:
//! `cargo run --release -p doctor --example make_log -- <gs2mf|freerolling|brkdrv|procedure.toml>
//! <effects> <out.mcap> [wear multiplier]`.

use std::path::{Path, PathBuf};
use suite::{Headless, McapSink, ProcedureChoice, RunSpec};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    if args.len() < 3 {
        eprintln!("usage: make_log <procedure name or .toml> <effects> <out.mcap> [wear multiplier]");
        std::process::exit(2);
    }
    let launch = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../launch-config");
    let mut spec = match ProcedureChoice::parse(&args[0]) {
        Ok(choice) => RunSpec::new(&launch, choice),
        Err(_) => {
            let mut s = RunSpec::new(&launch, ProcedureChoice::FreeRolling);
            s.procedure_file = PathBuf::from(&args[0]);
            s
        }
    };
    spec.effects = Some(args[1].clone());
    spec.wear_multiplier = args.get(3).map(|s| s.parse()).transpose()?;
    let t0 = std::time::Instant::now();
    let mut h = Headless::new(&spec, thermal::ThermalConfig::default(), sequencer::SequencerConfig::default())?;
    let mut sink = McapSink::create(Path::new(&args[2]), "/rig", &h.metadata(&spec))?;
    let summary = h.run(&mut sink, &mut |_, _| {})?;
    let n = sink.finish()?;
    eprintln!(
        "{}: {n} messages, {:.0} s of rig time in {:.1} s",
        args[2],
        summary.total_rig_time_s,
        t0.elapsed().as_secs_f64()
    );
    Ok(())
}

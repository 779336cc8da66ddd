//! End-to-end acceptance: run GS2MF headless on the virtual rig, fit the log, compare with the
//! rig's true tyre on the held-out grid, write the report.
//!
//! `cargo run --release -p mffit --example gs2mf_acceptance -- [effects] [seed] [out_dir]`
//! (effects as `tyrerig run --effects`: `noise` by default, `all` for every effect).

use std::path::{Path, PathBuf};
use std::time::Instant;

use mffit::stages::{FitOptions, fit};
use suite::{Headless, McapSink, ProcedureChoice, RunSpec};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let effects = args.get(1).cloned().unwrap_or_else(|| "noise".into());
    let seed: u64 = args.get(2).and_then(|s| s.parse().ok()).unwrap_or(1);
    let out_dir = PathBuf::from(args.get(3).cloned().unwrap_or_else(|| format!("/tmp/mffit_acceptance_{effects}")));
    std::fs::create_dir_all(&out_dir)?;
    let launch = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../launch-config");
    let log = out_dir.join("gs2mf.mcap");
    let mut spec = RunSpec::new(&launch, ProcedureChoice::Gs2mf);
    spec.effects = Some(effects.clone());
    spec.seed = seed;
    if !log.exists() {
        let t = Instant::now();
        let mut h = Headless::new(&spec, thermal::ThermalConfig::default(), sequencer::SequencerConfig::default())?;
        let md = h.metadata(&spec);
        let mut sink = McapSink::create(&log, "/rig", &md)?;
        let summary = h.run(&mut sink, &mut |_, _| {})?;
        sink.finish()?;
        eprintln!(
            "ran GS2MF ({effects}): {:.0} s rig time in {:.1} s",
            summary.total_rig_time_s,
            t.elapsed().as_secs_f64()
        );
    }
    let (_, truth) = suite::headless::rig_config(&spec)?;
    let t = Instant::now();
    let data = mffit::logs::read_log(&log)?;
    let read_s = t.elapsed().as_secs_f64();
    let mut kinds = std::collections::BTreeMap::new();
    for s in &data.segments {
        *kinds.entry(format!("{:?}/{:?}", s.procedure, s.kind)).or_insert(0usize) += s.samples.len();
    }
    eprintln!("read {} segments, {} samples in {read_s:.1} s: {kinds:?}", data.segments.len(), data.len());
    let result = fit(&data, &FitOptions::default())?;
    for s in &result.stages {
        eprintln!(
            "{:<18} {:>6} pts rmse {:>10.4} (start {:>10.4}) {:>6.2} s it {:>4} {:?}{}",
            s.stage,
            s.points,
            s.rmse,
            s.initial_rmse,
            s.wall_s,
            s.iterations,
            s.notes,
            s.skipped.as_deref().map(|r| format!(" SKIPPED {r}")).unwrap_or_default()
        );
        if let Some(h) = &s.heldout {
            eprintln!(
                "    k-fold: held-out {:.2} % of peak (fit {:.2} %) over {} sweeps",
                h.nrmse_pct, h.fit_nrmse_pct, h.sweeps
            );
        }
        for h in &s.held {
            eprintln!("    held {} = {}: {}", h.key, h.value, h.reason);
        }
    }
    eprintln!("warnings: {:?}", result.warnings);
    let support = mffit::accuracy::Support::of_fit(&result);
    let acc = mffit::accuracy::compare(&truth, &result.params, &result.range, &support);
    let boxed = mffit::accuracy::compare(&truth, &result.params, &result.range, &mffit::accuracy::Support::default());
    eprintln!("| channel | grid pts | RMS % of peak | max % | whole-box RMS % |");
    for (a, b) in acc.iter().zip(&boxed) {
        eprintln!(
            "| {} | {} | {:.2} | {:.2} | {:.2} |",
            a.channel, a.points, a.rms_pct_of_peak, a.max_pct_of_peak, b.rms_pct_of_peak
        );
    }
    eprintln!("fit wall time {:.2} s (+ {read_s:.1} s reading the log)", result.wall_s);
    std::fs::write(out_dir.join("fitted.tir"), result.params.to_tir_string())?;
    mffit::report::write(&out_dir.join("report"), &result, Some(&acc))?;
    Ok(())
}

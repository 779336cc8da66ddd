//! Acceptance on a real log: a full GS2MF run on the virtual rig (headless runner, sensor noise
//! on, thermal grip, wear and break-in off), fitted end to end. On the held-out grid inside the
//! tested range the fitted FY, FX and MZ are within 2 % of peak (RMS) of the rig's true tyre,
//! MX within 5 %, and the friction ellipse is round. ~30 s in release (CI runs tests in release).

use std::path::Path;

use mffit::stages::{FitOptions, fit};
use suite::{Headless, McapSink, ProcedureChoice, RunSpec};

#[test]
fn gs2mf_log_with_noise_fits_within_acceptance() {
    let dir = tempfile::tempdir().unwrap();
    let log = dir.path().join("gs2mf.mcap");
    let launch = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../launch-config");
    let mut spec = RunSpec::new(&launch, ProcedureChoice::Gs2mf);
    spec.effects = Some("noise".into());
    spec.seed = 7;
    let mut h = Headless::new(&spec, thermal::ThermalConfig::default(), sequencer::SequencerConfig::default()).unwrap();
    let md = h.metadata(&spec);
    let mut sink = McapSink::create(&log, "/rig", &md).unwrap();
    let summary = h.run(&mut sink, &mut |_, _| {}).unwrap();
    sink.finish().unwrap();
    assert!(summary.completed);
    let (_, truth) = suite::headless::rig_config(&spec).unwrap();

    let data = mffit::logs::read_log(&log).unwrap();
    let result = fit(&data, &FitOptions::default()).unwrap();
    for s in &result.stages {
        eprintln!("{:<18} {:>6} pts rmse {:>10.4} {:>6.2} s {:?}", s.stage, s.points, s.rmse, s.wall_s, s.skipped);
    }
    let support = mffit::accuracy::Support::of_fit(&result);
    let acc = mffit::accuracy::compare(&truth, &result.params, &result.range, &support);
    for a in &acc {
        eprintln!("{:<12} {:>6.2} % of peak", a.channel, a.rms_pct_of_peak);
    }
    let pct = |c: &str| acc.iter().find(|a| a.channel == c).unwrap().rms_pct_of_peak;
    assert!(pct("FY pure") < 2.0);
    assert!(pct("FX pure") < 2.0);
    assert!(pct("MZ pure") < 2.0);
    assert!(pct("MX pure") < 5.0);
    assert!(pct("FY combined") < 2.0 && pct("FX combined") < 2.0);
    let sq = mffit::checks::ellipse_squareness(&result.params, result.nominal.fz0_n, result.nominal.p0_pa);
    let sq_true = mffit::checks::ellipse_squareness(&truth, result.nominal.fz0_n, result.nominal.p0_pa);
    assert!(sq < mffit::checks::SQUARE_LIMIT && (sq - sq_true).abs() < 0.1, "squareness {sq} vs true {sq_true}");
    assert!(result.warnings.iter().all(|w| !w.contains("square")));
    // The written file reads back; the report is complete.
    let tir = dir.path().join("fitted.tir");
    std::fs::write(&tir, result.params.to_tir_string()).unwrap();
    let back = mftyre::TyreParams::read_tir(&tir).unwrap();
    assert_eq!(back.fittyp, 61);
    let files = mffit::report::write(&dir.path().join("report"), &result, Some(&acc)).unwrap();
    assert!(files.len() > 20);
}

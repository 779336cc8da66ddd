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
    // The written model, evaluated whole as MFeval and the rig evaluate it, gives the true
    // tyre's aligning moment at the high-load free-rolling points it was fitted to. At κ = 0
    // that is Mz0 + s·Fx(κ = 0) (this tyre carries 7 % of its load at zero slip ratio); fitted
    // before FX pure and the arm, `mz_pure` took that moment for its own trail and the written
    // model counted it twice (−5 to −10 N·m at 2·Fz0) until it was refined after the arm. On
    // this log: MZ pure on the grid 0.56 → 0.24 % of peak, above 1.5·Fz0 0.33 → 0.22 %.
    assert!(pct("MZ pure") < 0.4, "MZ pure {:.3} % of peak", pct("MZ pure"));
    let high_load_mz_pct = free_rolling_mz_error_pct(&truth, &result, 1.5);
    eprintln!("MZ at κ = 0 above 1.5·Fz0, written model against the true tyre: {high_load_mz_pct:.3} % of peak RMS");
    assert!(high_load_mz_pct < 0.28, "MZ at κ = 0 above 1.5·Fz0: {high_load_mz_pct:.3} % of peak RMS");
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

/// RMS over `mz_pure`'s points above `load_share`·Fz0 of the written model's MZ at κ = 0,
/// evaluated whole (combined-slip mode), against the true tyre's; % of the true tyre's peak there.
fn free_rolling_mz_error_pct(truth: &mftyre::TyreParams, result: &mffit::stages::FitResult, load_share: f64) -> f64 {
    use mftyre::{MfInput, UseMode};
    let whole =
        |p: &mftyre::TyreParams, x: &MfInput| mftyre::evaluate(p, UseMode::M111, &MfInput { kappa: 0.0, ..*x }).mz_nm;
    let pure = result.data.iter().find(|d| d.stage == "mz_pure").expect("mz_pure points");
    let fz_min = load_share * result.nominal.fz0_n;
    let errors: Vec<(f64, f64)> = pure
        .points
        .iter()
        .filter(|p| p.input.fz_n > fz_min)
        .map(|p| (whole(&result.params, &p.input) - whole(truth, &p.input), whole(truth, &p.input)))
        .collect();
    assert!(errors.len() > 50, "{} free-rolling points above {load_share}·Fz0", errors.len());
    let rms = (errors.iter().map(|(e, _)| e * e).sum::<f64>() / errors.len() as f64).sqrt();
    let peak = errors.iter().map(|(_, t)| t.abs()).fold(0.0, f64::max);
    100.0 * rms / peak
}

//! `tyrerig fit` on measured-style files of a tyre the Magic Formula cannot represent exactly:
//! the committed TTC-style runs of the virtual brush race tyre (`tests/fixtures/ttc/`, a
//! cornering run at four pressures and a drive/brake/combined run at three cambers), with the
//! repeat run on the second specimen as `--validate`. The command must exit 0 (every stage
//! physical), cross-validate every fitted stage over sweeps, and reach the accuracy on
//! the held-out sweeps: FY/FX pure ≤ 3 %, FX/FY combined ≤ 5 %, MZ ≤ 8 % of peak.

use std::path::{Path, PathBuf};
use std::process::Command;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../..")
}

fn fixture(name: &str) -> String {
    root().join("tests/fixtures/ttc").join(name).display().to_string()
}

/// Runs `tyrerig fit ARGS --out DIR/TIR --report DIR/report`, which must exit 0; returns the
/// report's `fit.json` and the command's stderr.
fn fit(dir: &Path, tir: &str, args: &[&str]) -> (serde_json::Value, String) {
    let report = dir.join("report");
    let out = Command::new(env!("CARGO_BIN_EXE_tyrerig"))
        .arg("fit")
        .args(args)
        .arg("--out")
        .arg(dir.join(tir))
        .arg("--report")
        .arg(&report)
        .output()
        .expect("run tyrerig fit");
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    assert!(out.status.success(), "tyrerig fit exited {:?} (3 = non-physical):\n{stderr}", out.status.code());
    let json =
        serde_json::from_str(&std::fs::read_to_string(report.join("fit.json")).expect("fit.json")).expect("json");
    (json, stderr)
}

#[test]
fn race_brush_tyre_ttc_runs_fit_physical_and_within_the_limits() {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("brush_fit_race");
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("scratch dir");
    let (cornering, drive_brake, repeat) =
        (fixture("race_cornering.dat"), fixture("race_drive_brake.dat"), fixture("race_drive_brake_tyre2.dat"));
    // `--out` into a folder that does not exist yet: the command makes it.
    let (json, stderr) =
        fit(&dir, "model/race.tir", &[&cornering, &drive_brake, "--validate", &repeat, "--folds", "3"]);
    assert!(dir.join("model/race.tir").exists(), "no .tir written into the folder --out names");
    assert!(json["nonphysical_stages"].as_array().is_some_and(Vec::is_empty), "{}", json["nonphysical_stages"]);

    let stage = |name: &str| {
        json["stages"]
            .as_array()
            .and_then(|a| a.iter().find(|s| s["stage"] == name))
            .unwrap_or_else(|| panic!("stage {name} missing from fit.json:\n{stderr}"))
    };
    // Held-out (k-fold over sweeps) NRMSE in % of peak, per stage, against its limit.
    let limits = [
        ("fy_pure", 3.0),
        ("fx_pure", 3.0),
        ("fx_combined", 5.0),
        ("fy_combined", 5.0),
        ("mz_pure", 8.0),
        ("mz_combined", 8.0),
    ];
    for (name, limit) in limits {
        let s = stage(name);
        let heldout = s["heldout_nrmse_pct"].as_f64().unwrap_or_else(|| panic!("{name}: no held-out NRMSE: {s}"));
        let fit = s["nrmse_pct"].as_f64().expect("nrmse");
        assert!(heldout <= limit, "{name}: held-out NRMSE {heldout:.2} % > {limit} % (fit {fit:.2} %)");
        // Every fitted coefficient carries an uncertainty.
        let coefs = s["coefficients"].as_array().expect("coefficients");
        assert!(!coefs.is_empty(), "{name}: no coefficients fitted");
        assert!(
            coefs.iter().all(|c| c["std"].as_f64().is_some_and(|v| v.is_finite() && v >= 0.0)),
            "{name}: {coefs:?}"
        );
    }
    // Camber 0 only in cornering; the three cambers of drive/brake reach pure lateral slip only
    // at the slip-ratio sweeps' zero crossings (28 points, under 20 per camber): too few to fit
    // camber terms to, so FY's camber stiffness keeps its template value, with the reason.
    let fy = stage("fy_pure");
    let fy_held = fy["held"].as_array().expect("held");
    let pky6 = fy_held.iter().find(|h| h["key"] == "PKY6").unwrap_or_else(|| panic!("PKY6 fitted: {fy_held:?}"));
    assert!(pky6["reason"].as_str().is_some_and(|r| r.contains("camber level")), "{pky6}");
    // One pressure in drive/brake: FX's pressure terms are held, with the reason.
    let fx = stage("fx_pure");
    let fx_held = fx["held"].as_array().expect("held");
    let ppx = fx_held.iter().find(|h| h["key"] == "PPX1").unwrap_or_else(|| panic!("PPX1 not held: {fx_held:?}"));
    assert!(ppx["reason"].as_str().is_some_and(|r| r.contains("pressure")), "{ppx}");

    mz_combined_within_target(&json, "race");
    plots_engineers_read(&dir.join("report"));

    // The repeat run on the second specimen scores the model too.
    let validation = json["validation"].as_array().expect("validation");
    assert_eq!(validation.len(), 1, "{validation:?}");
    let rows = validation[0][1].as_array().expect("rows");
    for name in ["fx_pure", "fx_combined", "fy_combined"] {
        let row = rows.iter().find(|r| r["stage"] == name).unwrap_or_else(|| panic!("{name} not validated: {rows:?}"));
        let v = row["nrmse_pct"].as_f64().expect("nrmse");
        assert!(v.is_finite() && v < 10.0, "{name} on the repeat run: {v:.2} %");
        // The band predicted for a repeat run is checked on it (a second specimen: it may hold
        // less than the 95 % predicted for this tyre; the report says so).
        assert!(row["in_repeat_band_pct"].as_f64().is_some_and(|p| (0.0..=100.0).contains(&p)), "{row}");
    }
    let md = std::fs::read_to_string(dir.join("report/report.md")).expect("report.md");
    assert!(md.contains("## Band for a repeat run") && md.contains("| in band % |"), "report.md lacks the bands");
}

/// The combined aligning moment on held-out sweeps: ≤ 8 % NRMSE (issue 31) and at most 1.6× the
/// tyre's pure MZ. While only the s-arm was fitted the race tyre's stood at 6.32 % against MZ
/// pure's 3.58 % (1.77×: this test failed); with the trail and residual torque refined jointly
/// with mz_pure's points, 5.54 % against 3.57 % (1.55×; the road tyre 6.42 % against 4.30 %,
/// 1.49×). The 1.5× is not reached on the race tyre (docs/fitting.md says why).
fn mz_combined_within_target(json: &serde_json::Value, tyre: &str) {
    let heldout = |name: &str| {
        json["stages"]
            .as_array()
            .and_then(|a| a.iter().find(|s| s["stage"] == name))
            .and_then(|s| s["heldout_nrmse_pct"].as_f64())
            .unwrap_or(f64::NAN)
    };
    let (combined, pure) = (heldout("mz_combined"), heldout("mz_pure"));
    assert!(combined <= 8.0, "{tyre}: MZ combined held-out {combined:.2} % > 8 %");
    assert!(combined <= 1.6 * pure, "{tyre}: MZ combined held-out {combined:.2} % > 1.6 × MZ pure's {pure:.2} %");
}

/// The report's plots: each stage over the slip it sweeps with its residuals, the friction ellipse.
fn plots_engineers_read(report: &Path) {
    for stem in ["mz_combined_mz", "fx_combined_fx", "fy_pure_fy", "friction_ellipse", "mz_combined_mz_residuals"] {
        for ext in ["png", "svg"] {
            let path = report.join(format!("{stem}.{ext}"));
            assert!(path.metadata().is_ok_and(|m| m.len() > 1000), "{} missing or empty", path.display());
        }
    }
    let md = std::fs::read_to_string(report.join("report.md")).expect("report.md");
    assert!(md.contains("one panel per held slip angle"), "report.md does not explain the plots");
}

/// The brush road tyre's runs: MZ combined within the target on held-out sweeps.
#[test]
fn road_brush_tyre_mz_combined_within_target() {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("brush_fit_road");
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("scratch dir");
    let (cornering, drive_brake) = (fixture("road_cornering.dat"), fixture("road_drive_brake.dat"));
    let (json, _) = fit(&dir, "road.tir", &[&cornering, &drive_brake, "--folds", "3"]);
    assert!(json["nonphysical_stages"].as_array().is_some_and(Vec::is_empty), "{}", json["nonphysical_stages"]);
    mz_combined_within_target(&json, "road");
}

/// A drive/brake/combined run alone (no cornering sweeps): the pure lateral stages have no data,
/// so the combined stages fit the pure FY and MZ terms the held slip angles identify (friction,
/// stiffness, trail, offsets; not the curve's shape). Without that, FY combined stood at 27 %
/// and MZ combined at 12 % (the template's pure FY under a fitted weighting).
#[test]
fn drive_brake_run_alone_fits_combined_lateral_physically() {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("brush_fit_drive_brake_only");
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("scratch dir");
    let (json, stderr) = fit(&dir, "db.tir", &[&fixture("race_drive_brake.dat"), "--folds", "3"]);
    let stages = json["stages"].as_array().expect("stages");
    let stage = |name: &str| stages.iter().find(|s| s["stage"] == name).unwrap_or_else(|| panic!("{name}: {stderr}"));
    for (name, limit) in [("fx_pure", 3.0), ("fx_combined", 5.0), ("fy_combined", 5.0), ("mz_combined", 8.0)] {
        let h = stage(name)["heldout_nrmse_pct"].as_f64().unwrap_or(f64::NAN);
        assert!(h <= limit, "{name}: held-out NRMSE {h:.2} % > {limit} %");
    }
    let fitted = |name: &str| -> Vec<String> {
        stage(name)["coefficients"].as_array().expect("coefficients").iter().map(|c| c["key"].to_string()).collect()
    };
    assert!(
        fitted("fy_combined").iter().any(|k| k == "\"PDY1\""),
        "pure FY friction not fitted: {:?}",
        fitted("fy_combined")
    );
    assert!(
        fitted("mz_combined").iter().any(|k| k == "\"QDZ1\""),
        "pure trail not fitted: {:?}",
        fitted("mz_combined")
    );
}

/// Full GS2MF runs of the virtual brush *road* tyre (seeds 1 and 2), fitted as `tyrerig fit`
/// does. On these logs the fit once ended with FY pure at 4.2–4.6 % NRMSE (PCY1 at its bound)
/// where the other seed reached 0.4 %: the friction start was read from sweeps that stop short
/// of their peak (seed 2), and after the Jacobian held PKY4 at its start the refit of the
/// others fell into another basin (seed 1, with the better start). Every lateral stage must now
/// fit near the data's level.
#[test]
fn brush_road_gs2mf_runs_fit_the_lateral_stages() {
    for seed in ["1", "2"] {
        brush_road_gs2mf_fits_the_lateral_stages(seed);
    }
}

fn brush_road_gs2mf_fits_the_lateral_stages(seed: &str) {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join(format!("brush_road_gs2mf_seed{seed}"));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("scratch dir");
    let log = dir.join("run.mcap");
    let run = Command::new(env!("CARGO_BIN_EXE_tyrerig"))
        .current_dir(root())
        .args(["run", "--headless", "--effects", "noise", "--seed", seed])
        .args(["--rig-config", "launch-config/virtual_rig_brush_road.toml", "--out"])
        .arg(&log)
        .output()
        .expect("run tyrerig run");
    assert!(run.status.success(), "tyrerig run: {}", String::from_utf8_lossy(&run.stderr));
    let (json, stderr) = fit(&dir, "fit.tir", &[&log.display().to_string(), "--folds", "0"]);
    let stages = json["stages"].as_array().expect("stages");
    // Fit NRMSE in % of peak (measured with the fix, seeds 1 and 2: 0.32 and 0.32, 2.47 and
    // 2.45, 0.23 and 0.23 %; with forward-difference Jacobians the offline fits of the same
    // seeds' `--effects noise` logs give 0.32 and 0.32, 2.25 and 2.37, 0.23 and 0.23 %). With
    // the hold rule switched off (HOLD_COST_LIMIT huge) this test fails, central or forward.
    for (name, limit) in [("fy_pure", 0.6), ("mz_pure", 3.0), ("mx", 0.6)] {
        let s = stages.iter().find(|s| s["stage"] == name).unwrap_or_else(|| panic!("{name}: {stderr}"));
        let nrmse = s["nrmse_pct"].as_f64().unwrap_or(f64::NAN);
        assert!(nrmse <= limit, "seed {seed}, {name}: NRMSE {nrmse:.2} % > {limit} %\n{s}");
    }
}

/// Runs `tyrerig run --headless` of `procedure` on `rig` with `seed` into `dir/<name>.mcap`.
fn headless_run(dir: &Path, rig: &str, procedure: &str, seed: u32, name: &str) -> String {
    let log = dir.join(format!("{name}.mcap"));
    let out = Command::new(env!("CARGO_BIN_EXE_tyrerig"))
        .args(["run", "--headless", "--quiet", "--seed", &seed.to_string(), "--rig-config"])
        .arg(root().join("launch-config").join(rig))
        .arg("--procedure")
        .arg(root().join("launch-config/procedures").join(format!("{procedure}.toml")))
        .arg("--out")
        .arg(&log)
        .output()
        .expect("run tyrerig run");
    assert!(out.status.success(), "tyrerig run: {}", String::from_utf8_lossy(&out.stderr));
    log.display().to_string()
}

/// The band a fit predicts for a repeat run (95 % of its held-out sweeps' errors) holds a repeat
/// run of the same tyre: a second drive/brake run of the brush race tyre (another seed: its own
/// noise and its own thermal history), the brush tyre being one the Magic Formula cannot
/// represent. The usual in-sample band, ±1.96·RMSE, is reported beside it for what it holds of
/// the held-out sweeps.
#[test]
fn a_repeat_run_of_the_same_tyre_falls_in_the_band_the_fit_predicts() {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("brush_fit_repeat");
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("scratch dir");
    let rig = "virtual_rig_brush_race.toml";
    let first = headless_run(&dir, rig, "ttc_drive_brake_race", 3, "first");
    let repeat = headless_run(&dir, rig, "ttc_drive_brake_race", 4, "repeat");
    let (json, stderr) = fit(&dir, "race.tir", &[&first, "--validate", &repeat, "--folds", "4"]);
    assert!(stderr.contains("band for a repeat run"), "{stderr}");
    let rows = json["validation"][0][1].as_array().expect("validation rows");
    for name in ["fx_pure", "fx_combined", "fy_combined", "mz_combined"] {
        let stage = json["stages"].as_array().unwrap().iter().find(|s| s["stage"] == name).expect(name);
        let band = stage["repeat_band_95"].as_f64().unwrap_or_else(|| panic!("{name}: no band: {stage}"));
        let rmse_band = stage["fit_band_heldout_pct"].as_f64().expect("fit band");
        let row = rows.iter().find(|r| r["stage"] == name).unwrap_or_else(|| panic!("{name}: {rows:?}"));
        assert_eq!(row["repeat_band"].as_f64(), Some(band), "{row}");
        let inside = row["in_repeat_band_pct"].as_f64().expect("in band");
        eprintln!("{name}: ±{band:.3}, repeat run {inside:.1} % in band; ±1.96·RMSE holds {rmse_band:.1} % held out");
        // 95.3–97.1 % measured; ±1.96·RMSE of the fit holds 91.7–93.0 % of the held-out sweeps.
        assert!((93.0..=99.0).contains(&inside), "{name}: {inside:.1} % of the repeat run within ±{band:.3}");
    }
}

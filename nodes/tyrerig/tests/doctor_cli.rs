//! `tyrerig doctor` on measured files (the TTC-style fixtures of the virtual brush race tyre,
//! `tests/fixtures/ttc`), end to end with the built binary: the files are imported, the base
//! model is fitted, and channels the base was not fitted for are not diagnosed.

use std::path::PathBuf;
use std::process::Command;

fn fixture(name: &str) -> String {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../tests/fixtures/ttc").join(name).display().to_string()
}

fn doctor(files: &[&str], extra: &[&str], out: &str) -> serde_json::Value {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("doctor_cli").join(out);
    let mut args: Vec<String> = vec!["doctor".into()];
    args.extend(files.iter().map(|f| fixture(f)));
    args.extend(["--fit".into(), "--skip-stage".into(), "mx".into(), "--out".into(), dir.display().to_string()]);
    args.extend(extra.iter().map(|s| s.to_string()));
    let o = Command::new(env!("CARGO_BIN_EXE_tyrerig")).args(&args).output().expect("run tyrerig");
    assert!(
        o.status.success(),
        "tyrerig {args:?}: {}\n{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    );
    let json = std::fs::read_to_string(dir.join("doctor.json")).expect("doctor.json");
    serde_json::from_str(&json).expect("doctor.json parses")
}

/// Acceptance (issue 12): on the brush-tyre logs without the hidden temperature dependence of
/// friction and with no radius fit, nothing is named on DSTWOWHC — the report says the channel
/// is not diagnosed, and no named effect has it as its channel. The flash of the drive/brake
/// run's tread lasers is found and fitted out (a decay of seconds, as the rig's longitudinal
/// flash has).
#[test]
fn no_radius_fit_names_nothing_on_the_loaded_radius() {
    let d = doctor(
        &["race_cornering.dat", "race_drive_brake_no_thermal_grip.dat"],
        &["--skip-stage", "radius_stiffness"],
        "no_thermal_grip",
    );
    let nd: Vec<String> = d["not_diagnosed"]
        .as_array()
        .expect("not_diagnosed")
        .iter()
        .map(|v| v.as_str().unwrap_or("").to_owned())
        .collect();
    assert!(
        nd.iter().any(|s| s.starts_with("DSTWOWHC not diagnosed: the base's loaded radius was not fitted")),
        "{nd:?}"
    );
    for e in d["effects"].as_array().expect("effects") {
        assert_ne!(e["channel"].as_str(), Some("DSTWOWHC"), "named on DSTWOWHC: {e}");
    }
    let taus = d["laser_flash_decay_s"].as_array().expect("laser_flash_decay_s");
    assert_eq!(taus.len(), 2, "one flash fit per log: {taus:?}");
    let tau_db = taus[1].as_f64().expect("the drive/brake run's flash is found");
    assert!((0.5..=4.0).contains(&tau_db), "flash decay {tau_db} s");
}

/// A short lateral procedure (`libs/doctor/tests/fixtures/doctor_lateral.toml`: hot sweeps,
/// a thermal pause, a cool-down, cold sweeps) run on a virtual brush tyre with sensor noise and
/// tread temperatures, with or without its hidden temperature dependence of friction; returns
/// `doctor --fit`'s `doctor.json` (the base fitted to the same log: an MF model of a tyre MF
/// cannot represent exactly).
fn doctor_on_brush_run(rig: &str, effects: &str, extra: &[&str], out: &str) -> serde_json::Value {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../..");
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("doctor_cli").join(out);
    std::fs::create_dir_all(&dir).expect("output dir");
    let log = dir.join("run.mcap");
    let run = Command::new(env!("CARGO_BIN_EXE_tyrerig"))
        .args(["run", "--headless", "--quiet", "--seed", "1", "--effects", effects])
        .arg("--rig-config")
        .arg(root.join("launch-config").join(rig))
        .arg("--procedure")
        .arg(root.join("libs/doctor/tests/fixtures/doctor_lateral.toml"))
        .arg("--out")
        .arg(&log)
        .output()
        .expect("run tyrerig");
    assert!(run.status.success(), "tyrerig run: {}", String::from_utf8_lossy(&run.stderr));
    let o = Command::new(env!("CARGO_BIN_EXE_tyrerig"))
        .arg("doctor")
        .arg(&log)
        .args(["--fit", "--out"])
        .arg(dir.join("doctor"))
        .args(extra)
        .output()
        .expect("run tyrerig");
    assert!(o.status.success(), "tyrerig doctor: {}", String::from_utf8_lossy(&o.stderr));
    let json = std::fs::read_to_string(dir.join("doctor/doctor.json")).expect("doctor.json");
    serde_json::from_str(&json).expect("doctor.json parses")
}

fn named(d: &serde_json::Value) -> Vec<String> {
    d["named_effects"].as_array().expect("named_effects").iter().map(|v| v.as_str().unwrap_or("").to_owned()).collect()
}

/// Acceptance (issue 12): on brush-tyre logs with the hidden temperature dependence of
/// friction, `thermal` is named first, with its region's held-out RMS cut by at least half —
/// the base being MF-Tyre 6.1 fitted to the same log, so the doctor works against the MF
/// form's own misfit of a brush tyre, as on a real tyre.
fn thermal_is_named_on_brush(rig: &str, out: &str) {
    let d = doctor_on_brush_run(rig, "noise,thermal,thermal_grip", &[], out);
    assert_eq!(d["form_correction"].as_bool(), Some(true), "--fit scores state effects against the form error");
    let names = named(&d);
    assert_eq!(names.first().map(String::as_str), Some("thermal"), "named {names:?}; {}", d["stop_reason"]);
    let (before, after) = region_rms(&d, "thermal");
    assert!(after <= 0.5 * before, "held-out RMS in the thermal region {before} → {after}: less than a 50 % cut");
}

#[test]
fn brush_road_tyre_thermal_grip_is_named() {
    thermal_is_named_on_brush("virtual_rig_brush_road.toml", "brush_road_thermal");
}

#[test]
fn brush_race_tyre_thermal_grip_is_named() {
    thermal_is_named_on_brush("virtual_rig_brush_race.toml", "brush_race_thermal");
}

/// The control: the same runs without the hidden effect, and no radius fit — nothing named,
/// and DSTWOWHC not diagnosed.
#[test]
fn brush_tyres_without_thermal_grip_name_nothing() {
    for rig in ["virtual_rig_brush_road.toml", "virtual_rig_brush_race.toml"] {
        let d =
            doctor_on_brush_run(rig, "noise,thermal", &["--skip-stage", "radius_stiffness"], &format!("{rig}_control"));
        assert!(named(&d).is_empty(), "{rig}: named {:?} on a log without a hidden effect", named(&d));
        let nd = d["not_diagnosed"].to_string();
        assert!(nd.contains("DSTWOWHC not diagnosed"), "{rig}: {nd}");
    }
}

/// Issue 30: a strong thermal effect hidden in TTC-style runs of the brush race tyre (the
/// benchmark's case `brush_race/ttc/thermal/s2`: drawn by the injector, not the doctor's own
/// form — asymmetric μ(T) with an optimum, a 96 s bulk lag, 31.5 σ; the drive/brake run opened
/// by warm-up sweeps) is named. Each cell of a TTC run is visited about once, so with the form
/// error taken out its gain is real but uneven over sweeps (bootstrap p 0.013, above the
/// round's α/m): it is named because the plain residual names it at α/m. Before, the report
/// called it "not identifiable".
#[test]
fn a_strong_thermal_effect_in_ttc_runs_of_a_brush_tyre_is_named() {
    let (names, form_errors) = bench_case("brush_race/ttc/thermal/s2", "bench_ttc_thermal");
    assert_eq!(names, ["thermal"], "named {names:?}, form errors {form_errors}");
}

/// Issue 30: break-in hidden in a free-rolling GS2MF run of the brush road tyre (the
/// benchmark's case `brush_road/gs2mf_fr/break_in/s2`, 6.8 σ) is not named thermal. `thermal`
/// explained 0.346 of the plain residual but only 0.091 with the form error taken out (it was
/// doing the operating point's work), and the plain score confirmed it by a hair (p 0.0055 ≤
/// 0.0056): the plain score now confirms only a candidate that keeps half its evidence.
#[test]
fn break_in_on_a_free_rolling_brush_road_run_is_not_named_thermal() {
    let (names, form_errors) = bench_case("brush_road/gs2mf_fr/break_in/s2", "bench_fr_break_in");
    assert!(!names.contains(&"thermal".to_owned()), "named {names:?}, form errors {form_errors}");
}

/// Issue 30: thermal and wear hidden together in TTC-style runs of the MF tyre, diagnosed with
/// `--model` against the clean tyre as an outsider's files are (the benchmark's case
/// `mf/ttc/thermal+wear/s1`, 10.2 σ and 9.8 σ): both are named. The temperature rises through the
/// test as the sliding energy does, so wear's grip terms beside thermal lose on held-out sweeps
/// what its radius gains (−9.7 % of the held-out χ²): only `thermal` was named until wear could
/// be scored by its radius alone.
#[test]
fn thermal_and_wear_hidden_together_in_ttc_runs_are_both_named() {
    let (mut names, form_errors) = bench_case("mf/ttc/thermal+wear/s1", "bench_ttc_thermal_wear");
    names.sort();
    assert_eq!(names, ["thermal", "wear"], "named {names:?}, form errors {form_errors}");
}

/// The project's free-rolling plan on the MF tyre with a break-in hidden (a two-stage recovery
/// whose slow stage outlasts the test) against the tyre's own model: the tread heats while the
/// tyre breaks in, and `thermal` explains what `break_in` does (each beside the other adds less
/// than the 5 % that counts as evidence). Nothing is named; the pair is reported as not told
/// apart. (Decided head to head, `thermal` was named for it.)
#[test]
fn a_break_in_the_logs_cannot_tell_from_thermal_names_neither() {
    let case = bench_case_json("mf/gs2mf_fr/break_in/s1", "bench_fr_break_in_mf");
    assert_eq!(case["named"], serde_json::json!([]), "{case}");
    let pair = case["indistinct"].as_array().and_then(|a| a.first()).cloned().unwrap_or_default();
    let mut pair: Vec<&str> =
        pair.as_array().map(|p| p.iter().filter_map(|v| v.as_str()).collect()).unwrap_or_default();
    pair.sort_unstable();
    assert_eq!(pair, ["break_in", "thermal"], "{case}");
}

/// Issue 30: thermal and wear hidden together in a free-rolling GS2MF run of the MF tyre (the
/// benchmark's case `mf/gs2mf_fr/thermal+wear/s1`, 6.2 σ and 8.0 σ): both are named, and no
/// third. `break_in` was named third on what the two left (evidence 0.062) while it cut the
/// held-out RMS in its own region by 11 % only (472 → 420 N); a state effect is now named only
/// if it cuts its region by 20 %.
#[test]
fn thermal_and_wear_on_a_free_rolling_run_are_named_without_a_third() {
    let (mut names, form_errors) = bench_case("mf/gs2mf_fr/thermal+wear/s1", "bench_fr_thermal_wear");
    names.sort();
    assert_eq!(names, ["thermal", "wear"], "named {names:?}, form errors {form_errors}");
}

/// Runs one case of `tyrerig bench doctor` in its own work directory; the state effects the
/// doctor named and its form errors.
fn bench_case(id: &str, work: &str) -> (Vec<String>, serde_json::Value) {
    let case = bench_case_json(id, work);
    let names = case["named"].as_array().expect("named").iter().filter_map(|v| v.as_str().map(str::to_owned)).collect();
    (names, case["form_errors"].clone())
}

/// Runs one case of `tyrerig bench doctor` in its own work directory; its record in the
/// benchmark's JSON.
fn bench_case_json(id: &str, work: &str) -> serde_json::Value {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("doctor_cli").join(work);
    let json = dir.join("bench.json");
    // The benchmark reads its rig configs and procedures from launch-config/ in the repository.
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../..");
    let o = Command::new(env!("CARGO_BIN_EXE_tyrerig"))
        .current_dir(root)
        .args(["bench", "doctor", "--cases", id, "--work-dir"])
        .arg(&dir)
        .arg("--json")
        .arg(&json)
        .output()
        .expect("run tyrerig");
    assert!(o.status.success(), "tyrerig bench doctor: {}", String::from_utf8_lossy(&o.stderr));
    let d: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&json).expect("bench json")).unwrap();
    let case = d["cases"][0].clone();
    assert_eq!(case["case"].as_str(), Some(id));
    assert!(case["error"].is_null(), "{}", case["error"]);
    case
}

/// A named effect's held-out RMS in its own region, before and after it was added (`doctor.json`
/// `effects[i]`); panics when `effect` was not named.
fn region_rms(d: &serde_json::Value, effect: &str) -> (f64, f64) {
    let e = d["effects"].as_array().expect("effects").iter().find(|e| e["effect"] == effect).expect(effect);
    (e["rms_before_heldout"].as_f64().unwrap_or(0.0), e["rms_after_heldout"].as_f64().unwrap_or(f64::MAX))
}

/// Runs the built `tyrerig` with `args`; panics with its stderr when it fails.
fn run_tyrerig(args: Vec<std::ffi::OsString>) {
    let o = Command::new(env!("CARGO_BIN_EXE_tyrerig")).args(&args).output().expect("run tyrerig");
    assert!(o.status.success(), "tyrerig {args:?}: {}", String::from_utf8_lossy(&o.stderr));
}

/// `tyrerig doctor <files> --fit --skip-stage mx --out <out>`; its doctor.json.
fn doctor_with_fit(files: &[PathBuf], out: &std::path::Path) -> serde_json::Value {
    let mut args: Vec<std::ffi::OsString> = vec!["doctor".into()];
    args.extend(files.iter().map(|f| f.as_os_str().to_owned()));
    args.extend(["--fit", "--skip-stage", "mx", "--out"].map(std::ffi::OsString::from));
    args.push(out.as_os_str().to_owned());
    run_tyrerig(args);
    serde_json::from_str(&std::fs::read_to_string(out.join("doctor.json")).expect("doctor.json")).expect("parses")
}

/// The brush race tyre's TTC cornering run (4 pressures) and drive/brake run with warm-up
/// sweeps, headless with the rig's relaxation on (`noise,thermal,transient`: FY lags SA, as in
/// real runs), logged in `dir` and exported to TTC `.dat` beside each log; the logs' paths.
fn relaxing_ttc_runs(dir: &std::path::Path) -> Vec<PathBuf> {
    let rig = repo_root().join("launch-config/virtual_rig_brush_race.toml");
    ["ttc_cornering_race", "ttc_drive_brake_race_warmup"].map(|p| relaxing_ttc_run(&rig, p, dir)).to_vec()
}

/// One TTC-style procedure `proc_name` run headless on the rig `rig` with the rig's relaxation
/// on (`noise,thermal,transient`), logged in `dir` and exported to TTC `.dat` beside the log;
/// the log's path.
fn relaxing_ttc_run(rig: &std::path::Path, proc_name: &str, dir: &std::path::Path) -> PathBuf {
    use std::ffi::OsString;
    let log = dir.join(format!("{proc_name}.mcap"));
    let mut run: Vec<OsString> =
        ["run", "--headless", "--quiet", "--effects", "noise,thermal,transient", "--rig-config"]
            .iter()
            .map(OsString::from)
            .collect();
    run.extend([rig.into(), "--procedure".into()]);
    run.push(repo_root().join(format!("launch-config/procedures/{proc_name}.toml")).into());
    run.extend(["--out".into(), log.clone().into()]);
    run_tyrerig(run);
    run_tyrerig(vec!["export".into(), "ttc".into(), log.clone().into()]);
    log
}

/// The repository's root (launch-config, tyres, procedures).
fn repo_root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// Issue 30: real runs relax (FY lags the slip angle), and a thermal effect hidden in them must
/// still be named, beside `transient` — the injector's, and an outsider's hidden in the files
/// (forces scaled, radius untouched); the runs as they are name `transient` alone (the test
/// after this one checks that). TTC-style runs of the brush race tyre with the rig's
/// relaxation on, a thermal effect drawn by the injector at twice its typical size (seed 1: an
/// asymmetric μ(T) with an optimum at 57 °C, a 96 s bulk lag), exported to TTC files. Once
/// `thermal` was named, `transient` used to be scored against a form error made for the state
/// effects' per-fold refits, not for the all-sweeps fit it holds, and lost 0 of 4 folds with
/// twice the held-out χ²: only `thermal` was named.
#[test]
fn thermal_hidden_in_relaxing_ttc_runs_is_named_beside_transient() {
    use std::ffi::OsString;
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../..");
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("doctor_cli").join("relaxing_ttc_thermal");
    std::fs::create_dir_all(&dir).expect("output dir");
    let rig = root.join("launch-config/virtual_rig_brush_race.toml");
    let os = |v: &[&str]| v.iter().map(OsString::from).collect::<Vec<_>>();
    let clean = relaxing_ttc_runs(&dir);
    let hidden: Vec<PathBuf> = clean.iter().map(|c| c.with_extension("thermal.mcap")).collect();
    let mut inject = os(&["inject"]);
    inject.extend(clean.iter().map(OsString::from));
    for h in &hidden {
        inject.push("--out".into());
        inject.push(h.into());
    }
    inject.push("--rig-config".into());
    inject.push(rig.clone().into());
    inject.extend(os(&["--effect", "thermal:2", "--seed", "1"]));
    run_tyrerig(inject);
    for h in &hidden {
        run_tyrerig(vec!["export".into(), "ttc".into(), h.into()]);
    }
    let d = doctor_with_fit(&hidden.iter().map(|h| h.with_extension("dat")).collect::<Vec<_>>(), &dir.join("doctor"));
    let names = named(&d);
    assert_eq!(names, ["thermal", "transient"], "named {names:?}; {}", d["stop_reason"]);

    // The same clean runs with a thermal grip factor hidden as an outsider hides one in real
    // runs' files: every force (FX, FY, MZ and the normalised NFX, NFY) of the `.dat` times a
    // factor of the tread's bulk temperature (the lasers' mean through a 60 s lag), the loaded
    // radius left alone; an asymmetric optimum at 50 °C, 17 % less grip at 80 °C with a power
    // of 1.6 on the hot side, a quadratic 12 % at 20 °C on the cold side, at most 28 %. Not
    // `tyrerig inject`'s form and not the doctor's.
    let mut hidden_dat = Vec::new();
    for c in &clean {
        let dat = c.with_extension("dat");
        let out = c.with_extension("outsider.dat");
        hide_outsider_thermal(&dat, &out, &OutsiderThermal::B, None);
        hidden_dat.push(out);
    }
    let d = doctor_with_fit(&hidden_dat, &dir.join("doctor_outsider"));
    let mut names = named(&d);
    names.sort();
    assert_eq!(names, ["thermal", "transient"], "named {names:?}; {}", d["stop_reason"]);
    let (before, after) = region_rms(&d, "thermal");
    assert!(after < 0.5 * before, "thermal's region, held-out: {before} -> {after}");
    // Its score says which sweeps carry it: named sweeps of these runs, gaining on net.
    let scored = d["rounds"]
        .as_array()
        .expect("rounds")
        .iter()
        .flat_map(|r| r.as_array().into_iter().flatten())
        .find(|c| c["effect"] == "thermal" && c["significant"] == true)
        .expect("a significant thermal score");
    let support = &scored["support"];
    let first = &support["carried_by"][0];
    assert!(
        first["name"].as_str().is_some_and(|n| !n.is_empty()) && first["chi2_gain"].as_f64() > Some(0.0),
        "{support}"
    );
    assert!(support["carrying_sweeps"].as_f64() >= Some(1.0), "{support}");
    assert!(support["gained_chi2"].as_f64() > support["lost_chi2"].as_f64(), "{support}");
}

/// Issue 30: an outsider's wear hidden in relaxing TTC-style runs is named `wear`, beside
/// `transient`, and nothing else — not `pressure` or `load` for what the wear form leaves (as an
/// independent generator's wear had been named with both). The form is not the doctor's nor the
/// injector's: every force of the `.dat` times 1 − 0.10·w^0.6 and the loaded radius 0.8 mm·w
/// smaller, w the file's sliding energy so far (|FY·sin SA|·V + |FX·SL|·V integrated over ET)
/// over its total. The same runs as they are name `transient` alone.
#[test]
fn wear_hidden_by_an_outsider_in_relaxing_ttc_runs_is_named_beside_transient_alone() {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("doctor_cli").join("relaxing_ttc_wear");
    std::fs::create_dir_all(&dir).expect("output dir");
    let clean = relaxing_ttc_runs(&dir);
    let worn: Vec<PathBuf> = clean
        .iter()
        .map(|c| {
            let out = c.with_extension("worn.dat");
            hide_outsider_wear(&c.with_extension("dat"), &out);
            out
        })
        .collect();
    let d = doctor_with_fit(&worn, &dir.join("doctor_worn"));
    let mut names = named(&d);
    names.sort();
    assert_eq!(names, ["transient", "wear"], "named {names:?}; {}", d["stop_reason"]);

    // The control: the same runs as they are (the rig's relaxation, no grip effect of heat).
    let d =
        doctor_with_fit(&clean.iter().map(|c| c.with_extension("dat")).collect::<Vec<_>>(), &dir.join("doctor_clean"));
    let names = named(&d);
    assert_eq!(names, ["transient"], "named {names:?} on the runs as they are; {}", d["stop_reason"]);
}

/// Issue 30: an outsider's break-in hidden in relaxing TTC-style runs is named `break_in`, beside
/// `transient`, and cuts its region by half. Its form is neither the doctor's nor the injector's:
/// grip, not stiffness — every force times 1 − 0.15·exp(−s/s₀)·(1 − exp(−(|α| + |κ|)/0.05)), s
/// the sliding distance so far (V·(|sin SA| + |SL|) over ET), s₀ 8 % of the file's total, each
/// file a fresh specimen. It lives in each run's first sweeps, which are of one kind per run
/// (cornering, or driving and braking): with every factor its own coefficients, a held-out first
/// cornering sweep was predicted from what was left, and break-in lost 43 % of the held-out χ²
/// (only `transient` was named); on the force level both runs' first sweeps tell one factor
/// (measured: FX in its region 70.9 → 29.6 N held-out, −58 %).
#[test]
fn break_in_hidden_by_an_outsider_in_relaxing_ttc_runs_is_named_beside_transient() {
    let (d, names) = diagnose_hidden_in_relaxing_ttc_runs("relaxing_ttc_break_in", |clean, out, _| {
        hide_outsider_break_in(clean, out);
    });
    assert_eq!(names, ["break_in", "transient"], "named {names:?}; {}", d["stop_reason"]);
    let (before, after) = region_rms(&d, "break_in");
    assert!(after <= 0.5 * before, "break_in's region, held-out: {before} -> {after}");
}

/// Issue 30: an outsider's thermal effect (A, at the temperatures real runs read) and wear (the
/// form of `wear_hidden_by_an_outsider_…`) hidden together in relaxing TTC-style runs: nothing is
/// named that is not there (an independent generator's thermal + wear had been named `wear,
/// thermal, load`), `thermal`, `wear` and `transient` are named, and thermal cuts its region by
/// half (measured 78.5 → 27.8 N held-out; wear's radius 0.201 → 0.106 mm). Wear was missed here
/// while its radius term needed the 10 % share of the sliding energy's variance at fixed
/// operating points every term needs: it keeps 9.0 %; a sign-bounded radius needs 5 %
/// (`linfit::MIN_WEAR_RADIUS_SHARE`, docs/doctor.md).
#[test]
fn thermal_and_wear_hidden_by_an_outsider_in_relaxing_ttc_runs_name_nothing_that_is_not_there() {
    let (d, names) = diagnose_hidden_in_relaxing_ttc_runs("relaxing_ttc_thermal_wear", |clean, out, run| {
        let hot = out.with_extension("thermal.dat");
        hide_outsider_thermal(clean, &hot, &OutsiderThermal::A, Some(REAL_RUNS_LASERS_C[run]));
        hide_outsider_wear(&hot, out);
    });
    assert_eq!(names, ["thermal", "transient", "wear"], "named {names:?}; {}", d["stop_reason"]);
    let (before, after) = region_rms(&d, "thermal");
    assert!(after <= 0.5 * before, "thermal's region, held-out: {before} -> {after}");
}

/// The relaxing TTC-style runs (`relaxing_ttc_runs`, in `doctor_cli/<case>`) with an effect
/// hidden in each exported `.dat` by `hide(clean, hidden, run)` (run 0 cornering, 1
/// drive/brake), diagnosed with `--fit`: the doctor's JSON and the names it gave, sorted.
fn diagnose_hidden_in_relaxing_ttc_runs(
    case: &str,
    hide: impl Fn(&std::path::Path, &std::path::Path, usize),
) -> (serde_json::Value, Vec<String>) {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("doctor_cli").join(case);
    std::fs::create_dir_all(&dir).expect("output dir");
    let hidden: Vec<PathBuf> = relaxing_ttc_runs(&dir)
        .iter()
        .enumerate()
        .map(|(run, c)| {
            let out = c.with_extension("hidden.dat");
            hide(&c.with_extension("dat"), &out, run);
            out
        })
        .collect();
    let d = doctor_with_fit(&hidden, &dir.join("doctor"));
    let mut names = named(&d);
    names.sort();
    (d, names)
}

/// Issue 30: the thermal effect hidden in real runs, at the temperatures real runs read. Real
/// cornering runs read 15–55 °C on the tread lasers and drive/brake runs 55–120 °C
/// (../shared/real-rig-data.md); the virtual runs read 38–67 °C and 38–100 °C. The same relaxing
/// TTC-style runs of the brush race tyre with their lasers mapped to those ranges, and the grip
/// factor the real runs hid (17 % less grip at 92 °C, an optimum at 55 °C, 12 % at 20 °C,
/// at most 28 %) applied to the forces: `thermal` is named beside `transient` (what the runs as
/// they are name), and it cuts the held-out FYW RMS in its region by half (measured 87.0 → 35.5
/// N, −59 %). At the virtual runs' own temperatures this factor stays within 12 % and is undecided
/// (docs/doctor.md, "TTC-style runs with an outsider's thermal effect"). Then B (optimum 50 °C),
/// C (symmetric) and A on a second specimen: each named beside `transient`, each cutting its
/// region by half, as the force level the outsider scaled the files by (B and C were cut by
/// 35 % and 49.6 % while that form was screened out, and A on a second specimen by 47 %).
#[test]
fn thermal_hidden_at_real_runs_temperatures_is_named_and_cuts_its_region_by_half() {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("doctor_cli").join("relaxing_ttc_real_temperatures");
    std::fs::create_dir_all(&dir).expect("output dir");
    let clean = relaxing_ttc_runs(&dir);
    let named_beside_transient_cutting_half = |d: &serde_json::Value, case: &str| {
        let mut names = named(d);
        names.sort();
        assert_eq!(names, ["thermal", "transient"], "{case}: named {names:?}; dropped {}", d["dropped"]);
        let (before, after) = region_rms(d, "thermal");
        assert!(after <= 0.5 * before, "{case}: thermal's region, held-out: {before} -> {after}");
        let thermal = d["effects"].as_array().and_then(|e| e.iter().find(|e| e["effect"] == "thermal"));
        let parameters = thermal.map(|t| &t["parameters"]).expect("thermal's parameters");
        assert!(parameters.get("THERMAL_FORCE_1").is_some(), "{case}: not the force level: {parameters}");
    };
    let d = diagnose_at_real_temperatures(&clean, &dir, &OutsiderThermal::A, "a", None);
    named_beside_transient_cutting_half(&d, "A");

    // B at those temperatures holds the drive/brake run at its 28 % floor; `transient` must
    // survive the backward check beside it. When that check let the thermal effect refitted
    // without `transient` choose its temperature afresh, a temperature rising through each sweep
    // took the relaxation's hysteresis and `transient` was dropped (2.7 % beside it).
    let d = diagnose_at_real_temperatures(&clean, &dir, &OutsiderThermal::B, "b", None);
    named_beside_transient_cutting_half(&d, "B");

    // C (symmetric): the model as written must fit the logs better than the base. When an
    // effect fitted with its operating-point share taken out was exempt from the written-model
    // rule, its model fitted FYW at 199–239 N RMS against the base's 80 N.
    let d = diagnose_at_real_temperatures(&clean, &dir, &OutsiderThermal::C, "c", None);
    named_beside_transient_cutting_half(&d, "C");
    for ch in ["FX", "FYW"] {
        let (base, written) = (d["rms"]["base"][ch].as_f64(), d["rms"]["final_fit"][ch].as_f64());
        assert!(written < base, "{ch}: the written model {written:?} against the base {base:?}");
    }
    assert_eq!(d["written_model_worse"], serde_json::json!([]), "{}", d["written_model_worse"]);

    // A, the drive/brake run on a second specimen (real pairs' peak forces differ by 10–14 %):
    // its FX and NFX × 0.90, FY, MZ and NFY × 0.93.
    let d = diagnose_at_real_temperatures(&clean, &dir, &OutsiderThermal::A, "a_specimen", Some([0.90, 0.93]));
    named_beside_transient_cutting_half(&d, "A, second specimen");
    assert_eq!(d["written_model_worse"], serde_json::json!([]), "{}", d["written_model_worse"]);
}

/// Issue 30: real pairs run cornering and drive/brake on two tyres of one model, whose peak
/// forces differ by 10–14 % and slip stiffness by ~20 % (../shared/real-rig-data.md). Here the
/// drive/brake run is made on a second specimen of the brush race tyre — tread 20 % softer,
/// friction 10 % lower (a physically different tyre, not scaled forces) — with the same
/// relaxation and heating. The pair as it is names `transient` alone: the difference between the
/// specimens is not a state effect of either. With the outsider's thermal factor A hidden at the
/// temperatures real runs read, `thermal` is named beside `transient` and cuts its region by
/// half (measured 101.9 → 46.3 N held-out, −55 %).
#[test]
fn a_drive_brake_run_on_a_second_specimen_names_no_state_and_keeps_thermal() {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("doctor_cli").join("second_specimen");
    let specimen = dir.join("specimen2");
    std::fs::create_dir_all(specimen.join("tyres")).expect("output dir");
    let cornering =
        relaxing_ttc_run(&repo_root().join("launch-config/virtual_rig_brush_race.toml"), "ttc_cornering_race", &dir);

    let mut second =
        std::fs::read_to_string(repo_root().join("launch-config/tyres/brush_race.toml")).expect("brush race tyre");
    for (from, to) in [
        ("longitudinal_stiffness_n_per_m2 = 9.8e6", "longitudinal_stiffness_n_per_m2 = 7.84e6"),
        ("lateral_stiffness_n_per_m2 = 7.0e6", "lateral_stiffness_n_per_m2 = 5.6e6"),
        ("mu_x = 2.30", "mu_x = 2.07"),
        ("mu_y = 2.45", "mu_y = 2.28"),
    ] {
        assert!(second.contains(from), "the brush race tyre no longer reads {from:?}");
        second = second.replace(from, to);
    }
    std::fs::write(specimen.join("tyres/brush_race.toml"), second).expect("second specimen");
    let rig = specimen.join("virtual_rig_brush_race.toml");
    std::fs::copy(repo_root().join("launch-config/virtual_rig_brush_race.toml"), &rig).expect("rig config");
    let drive_brake = relaxing_ttc_run(&rig, "ttc_drive_brake_race_warmup", &specimen);

    let pair = [cornering, drive_brake];
    let d = doctor_with_fit(&pair.each_ref().map(|log| log.with_extension("dat")), &dir.join("doctor_clean"));
    assert_eq!(named(&d), ["transient"], "{}", d["stop_reason"]);

    let d = diagnose_at_real_temperatures(&pair, &dir, &OutsiderThermal::A, "a", None);
    let mut names = named(&d);
    names.sort();
    assert_eq!(names, ["thermal", "transient"], "named {names:?}; dropped {}", d["dropped"]);
    let (before, after) = region_rms(&d, "thermal");
    assert!(after <= 0.5 * before, "thermal's region, held-out: {before} -> {after}");
    assert_eq!(d["written_model_worse"], serde_json::json!([]), "{}", d["written_model_worse"]);
}

/// The ranges of the tread lasers' mean real runs read [°C]: a cornering run, a drive/brake run
/// (../shared/real-rig-data.md).
const REAL_RUNS_LASERS_C: [[f64; 2]; 2] = [[15.0, 55.0], [55.0, 120.0]];

/// The relaxing runs `clean` (cornering, drive/brake) with their tread lasers mapped to the
/// ranges real runs read (15–55 °C cornering, 55–120 °C drive/brake) and `form` hidden in their
/// forces, written beside them as `*.real_temperatures_<tag>.dat` and diagnosed with a fit.
/// With `second_specimen` = [fx, fy] the drive/brake run is another tyre's: its FX and NFX
/// times fx, FY, MZ and NFY times fy.
fn diagnose_at_real_temperatures(
    clean: &[PathBuf],
    dir: &std::path::Path,
    form: &OutsiderThermal,
    tag: &str,
    second_specimen: Option<[f64; 2]>,
) -> serde_json::Value {
    let hidden: Vec<PathBuf> = clean
        .iter()
        .zip(REAL_RUNS_LASERS_C)
        .enumerate()
        .map(|(run, (c, to))| {
            let out = c.with_extension(format!("real_temperatures_{tag}.dat"));
            hide_outsider_thermal(&c.with_extension("dat"), &out, form, Some(to));
            if let (1, Some([fx, fy])) = (run, second_specimen) {
                scale_forces(&out, fx, fy);
            }
            out
        })
        .collect();
    doctor_with_fit(&hidden, &dir.join(format!("doctor_{tag}")))
}

/// An outsider's thermal grip factor of the tread's bulk temperature (the lasers' mean through a
/// 60 s lag): an asymmetric optimum, 17 % less grip `hot_span_c` above it (a power of 1.6),
/// 12 % `cold_span_c` below it (quadratic), at most 28 %.
struct OutsiderThermal {
    optimum_c: f64,
    hot_span_c: f64,
    cold_span_c: f64,
    hot_power: f64,
}

impl OutsiderThermal {
    /// Optimum 50 °C, 17 % at 80 °C, 12 % at 20 °C.
    const B: Self = Self { optimum_c: 50.0, hot_span_c: 30.0, cold_span_c: 30.0, hot_power: 1.6 };
    /// Optimum 55 °C, 17 % at 92 °C, 12 % at 20 °C (the form the real runs hid).
    const A: Self = Self { optimum_c: 55.0, hot_span_c: 37.0, cold_span_c: 35.0, hot_power: 1.6 };
    /// Symmetric: a quadratic about 55 °C, 17 % at 18 and 92 °C.
    const C: Self = Self { optimum_c: 55.0, hot_span_c: 37.0, cold_span_c: 31.1, hot_power: 2.0 };

    fn factor(&self, t: f64) -> f64 {
        let loss = if t >= self.optimum_c {
            0.17 * ((t - self.optimum_c) / self.hot_span_c).powf(self.hot_power)
        } else {
            0.12 * ((self.optimum_c - t) / self.cold_span_c).powi(2)
        };
        1.0 - loss.min(0.28)
    }
}

/// Scales the forces of a TTC `.dat` by `form`'s grip factor of the lagged mean tread
/// temperature (see `thermal_hidden_in_relaxing_ttc_runs_is_named_beside_transient`); the loaded
/// radius and everything else unchanged. With `lasers_to`, the three tread lasers are first
/// mapped linearly so that the 2–98 % range of their mean spans it (and written so): the
/// temperatures real runs read.
fn hide_outsider_thermal(
    input: &std::path::Path,
    output: &std::path::Path,
    form: &OutsiderThermal,
    lasers_to: Option<[f64; 2]>,
) {
    let mut dat = DatTable::read(input);
    if let Some(to) = lasers_to {
        dat.map_lasers_to(to);
    }
    let (et, lasers, forces) = (dat.col("ET"), dat.lasers(), ["FX", "FY", "MZ", "NFX", "NFY"].map(|n| dat.col(n)));
    let (mut bulk, mut last_t) = (f64::NAN, 0.0);
    for v in &mut dat.rows {
        let t = field(v, et);
        let surface = DatTable::lasers_mean(&lasers, v);
        if !bulk.is_finite() {
            bulk = surface;
        } else if surface.is_finite() {
            bulk += (1.0 - (-(t - last_t).max(0.0) / 60.0).exp()) * (surface - bulk);
        }
        last_t = t;
        let g = if bulk.is_finite() { form.factor(bulk) } else { 1.0 };
        for &i in &forces {
            let x = field(v, i);
            if x.is_finite() {
                v[i] = format!("{:.6}", x * g);
            }
        }
    }
    dat.write(output);
}

/// Scales a TTC `.dat`'s longitudinal forces (FX, NFX) by `fx` and its lateral ones (FY, MZ,
/// NFY) by `fy`, in place: the same run on another specimen of the tyre.
fn scale_forces(path: &std::path::Path, fx: f64, fy: f64) {
    let mut dat = DatTable::read(path);
    let scales: Vec<(usize, f64)> =
        [("FX", fx), ("NFX", fx), ("FY", fy), ("MZ", fy), ("NFY", fy)].iter().map(|&(n, k)| (dat.col(n), k)).collect();
    for v in &mut dat.rows {
        for &(i, k) in &scales {
            if let Ok(x) = v[i].parse::<f64>() {
                v[i] = format!("{:.6}", x * k);
            }
        }
    }
    dat.write(path);
}

/// Hides an outsider's wear in a TTC `.dat` (see
/// `wear_hidden_by_an_outsider_in_relaxing_ttc_runs_is_named_beside_transient_alone`): forces times 1 − 0.10·w^0.6,
/// the loaded radius (cm) 0.08·w smaller, w the sliding energy so far over the file's total.
fn hide_outsider_wear(input: &std::path::Path, output: &std::path::Path) {
    let mut dat = DatTable::read(input);
    let (et, v_kph, sa, sl, fx, fy, rl) =
        (dat.col("ET"), dat.col("V"), dat.col("SA"), dat.col("SL"), dat.col("FX"), dat.col("FY"), dat.col("RL"));
    let forces: Vec<usize> = ["FX", "FY", "MZ", "NFX", "NFY"].iter().map(|n| dat.col(n)).collect();
    let finite_or_zero = |x: f64| if x.is_finite() { x } else { 0.0 };
    let mut energy = Vec::with_capacity(dat.rows.len());
    let (mut e, mut last_t) = (0.0, f64::NAN);
    for v in &dat.rows {
        let t = field(v, et);
        let speed = field(v, v_kph) / 3.6;
        let power = finite_or_zero((field(v, fy) * field(v, sa).to_radians().sin()).abs() * speed)
            + finite_or_zero((field(v, fx) * field(v, sl)).abs() * speed);
        if (t - last_t).is_finite() {
            e += power * (t - last_t).max(0.0);
        }
        if t.is_finite() {
            last_t = t;
        }
        energy.push(e);
    }
    let total = e.max(1.0);
    for (v, e) in dat.rows.iter_mut().zip(energy) {
        let w = (e / total).clamp(0.0, 1.0);
        let g = 1.0 - 0.10 * w.powf(0.6);
        for &i in &forces {
            let x = field(v, i);
            if x.is_finite() {
                v[i] = format!("{:.6}", x * g);
            }
        }
        let r = field(v, rl);
        if r.is_finite() {
            v[rl] = format!("{:.6}", r - 0.08 * w);
        }
    }
    dat.write(output);
}

/// A TTC `.dat` as text: its three header lines and its rows' fields.
struct DatTable {
    header: String,
    names: Vec<String>,
    rows: Vec<Vec<String>>,
}

impl DatTable {
    fn read(path: &std::path::Path) -> Self {
        let text = std::fs::read_to_string(path).expect("a .dat");
        let mut lines = text.lines();
        let (title, names, units) =
            (lines.next().expect("title"), lines.next().expect("names"), lines.next().expect("units"));
        let rows = lines.filter(|l| !l.trim().is_empty()).map(|l| l.split('\t').map(str::to_owned).collect()).collect();
        Self {
            header: format!("{title}\n{names}\n{units}\n"),
            names: names.split('\t').map(str::to_owned).collect(),
            rows,
        }
    }

    fn col(&self, name: &str) -> usize {
        self.names.iter().position(|c| c == name).unwrap_or_else(|| panic!("no {name} in {:?}", self.names))
    }

    /// The three tread lasers' columns.
    fn lasers(&self) -> [usize; 3] {
        ["TSTI", "TSTC", "TSTO"].map(|n| self.col(n))
    }

    /// The mean of a row's finite readings in `lasers` (NaN where none is).
    fn lasers_mean(lasers: &[usize; 3], v: &[String]) -> f64 {
        let ts: Vec<f64> = lasers.iter().map(|&i| field(v, i)).filter(|x| x.is_finite()).collect();
        ts.iter().sum::<f64>() / ts.len() as f64
    }

    /// Maps the tread lasers linearly so that the 2–98 % range of their mean spans `[lo, hi]`.
    fn map_lasers_to(&mut self, [lo, hi]: [f64; 2]) {
        let lasers = self.lasers();
        let mut s: Vec<f64> =
            self.rows.iter().map(|v| Self::lasers_mean(&lasers, v)).filter(|x| x.is_finite()).collect();
        s.sort_by(f64::total_cmp);
        let q = |p: f64| s[((s.len() - 1) as f64 * p) as usize];
        let (q_lo, q_hi) = (q(0.02), q(0.98));
        for v in &mut self.rows {
            for &i in &lasers {
                let x = field(v, i);
                if x.is_finite() {
                    v[i] = format!("{:.3}", lo + (x - q_lo) * (hi - lo) / (q_hi - q_lo));
                }
            }
        }
    }

    fn write(&self, path: &std::path::Path) {
        let mut out = self.header.clone();
        for v in &self.rows {
            out.push_str(&v.join("\t"));
            out.push('\n');
        }
        std::fs::write(path, out).expect("write the .dat");
    }
}

/// A field of a `.dat` row as a number (NaN where it is not one).
fn field(v: &[String], i: usize) -> f64 {
    v[i].parse::<f64>().unwrap_or(f64::NAN)
}

/// Hides an outsider's break-in in a TTC `.dat` (see
/// `break_in_hidden_by_an_outsider_in_relaxing_ttc_runs_is_named_beside_transient`): forces times
/// 1 − 0.15·exp(−s/s₀)·(1 − exp(−(|α| + |κ|)/0.05)), s the sliding distance so far, s₀ 8 % of its
/// total; the loaded radius untouched.
fn hide_outsider_break_in(input: &std::path::Path, output: &std::path::Path) {
    let mut dat = DatTable::read(input);
    let (et, v_kph, sa, sl) = (dat.col("ET"), dat.col("V"), dat.col("SA"), dat.col("SL"));
    let forces: Vec<usize> = ["FX", "FY", "MZ", "NFX", "NFY"].iter().map(|n| dat.col(n)).collect();
    let finite_or_zero = |x: f64| if x.is_finite() { x } else { 0.0 };
    let slips = |v: &[String]| (finite_or_zero(field(v, sa)).to_radians().abs(), finite_or_zero(field(v, sl)).abs());
    let mut distance = Vec::with_capacity(dat.rows.len());
    let (mut s, mut last_t) = (0.0, f64::NAN);
    for v in &dat.rows {
        let t = field(v, et);
        let (alpha, kappa) = slips(v);
        if (t - last_t).is_finite() {
            s += finite_or_zero(field(v, v_kph) / 3.6) * (alpha.sin() + kappa) * (t - last_t).max(0.0);
        }
        if t.is_finite() {
            last_t = t;
        }
        distance.push(s);
    }
    let s0 = 0.08 * s.max(1e-9);
    for (v, s) in dat.rows.iter_mut().zip(distance) {
        let (alpha, kappa) = slips(v);
        let g = 1.0 - 0.15 * (-s / s0).exp() * (1.0 - (-(alpha + kappa) / 0.05).exp());
        for &i in &forces {
            let x = field(v, i);
            if x.is_finite() {
                v[i] = format!("{:.6}", x * g);
            }
        }
    }
    dat.write(output);
}

/// Issue 30: a third tyre, neither MF-Tyre 6.1 nor the brush tyre — `rigdata::fixture`'s own
/// analytic race tyre (arctangent curves with a friction ellipse, grip falling with load, no
/// pressure dependence and no camber on FX) — in a TTC pair laid out as real runs are: cornering
/// at four pressures with real runs' loads and the load wandering through each sweep, drive/brake
/// at three cambers and slip angles opened by warm-up sweeps, the tread heated by sliding
/// (`FixtureSpec::race_cornering_heated`, `race_drive_brake_heated`). As written, nothing is
/// named. With the outsider's thermal factor A hidden at the temperatures real runs read,
/// `thermal` alone is named and cuts its region by half (measured 94.4 → 39.9 N held-out,
/// −58 %); with an outsider's break-in, `break_in` (−58 %). With an outsider's wear (forces down
/// by up to 10 %, the radius 0.8 mm smaller over each run), `wear` (its radius 0.237 → 0.132 mm
/// held-out in its region). A break-in whose grip terms took any sign was named for that wear
/// (grip *falling* with sliding energy); a new tyre's grip is never above its broken-in grip, so
/// those terms are held to the sign physics gives. The wear was then missed until its radius
/// term, which keeps 8.9 % of the sliding energy's variance at fixed operating points, needed 5 %
/// instead of the 10 % other terms need (docs/doctor.md).
#[test]
fn a_third_tyres_ttc_runs_name_what_is_hidden_and_nothing_that_is_not() {
    use rigdata::fixture::{FixtureSpec, ttc_run};
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("doctor_cli").join("third_tyre");
    std::fs::create_dir_all(&dir).expect("output dir");
    let runs: Vec<PathBuf> =
        [("cornering", FixtureSpec::race_cornering_heated()), ("drive_brake", FixtureSpec::race_drive_brake_heated())]
            .iter()
            .zip(REAL_RUNS_LASERS_C)
            .map(|((name, spec), to)| {
                let path = dir.join(format!("{name}.dat"));
                let table = ttc_run(spec).table;
                std::fs::write(&path, rigdata::table::to_dat(&table, rigdata::table::DatLayout::default()))
                    .expect("write");
                // At the temperatures real runs read, as the outsider's effects below are hidden.
                let mut dat = DatTable::read(&path);
                dat.map_lasers_to(to);
                dat.write(&path);
                path
            })
            .collect();
    let diagnose = |tag: &str, hide: &dyn Fn(&std::path::Path, &std::path::Path)| {
        let hidden: Vec<PathBuf> = runs
            .iter()
            .map(|clean| {
                let out = clean.with_extension(format!("{tag}.dat"));
                hide(clean, &out);
                out
            })
            .collect();
        let d = doctor_with_fit(&hidden, &dir.join(format!("doctor_{tag}")));
        let names = named(&d);
        (d, names)
    };

    let d = doctor_with_fit(&runs, &dir.join("doctor_clean"));
    assert_eq!(named(&d), Vec::<String>::new(), "as written: {}", d["stop_reason"]);

    let (d, names) = diagnose("thermal_a", &|clean, out| {
        hide_outsider_thermal(clean, out, &OutsiderThermal::A, None);
    });
    assert_eq!(names, ["thermal"], "thermal A: {}", d["stop_reason"]);
    let (before, after) = region_rms(&d, "thermal");
    assert!(after <= 0.5 * before, "thermal's region, held-out: {before} -> {after}");

    let (d, names) = diagnose("break_in", &|clean, out| hide_outsider_break_in(clean, out));
    assert_eq!(names, ["break_in"], "break-in: {}", d["stop_reason"]);
    let (before, after) = region_rms(&d, "break_in");
    assert!(after <= 0.5 * before, "break_in's region, held-out: {before} -> {after}");

    let (d, names) = diagnose("wear", &|clean, out| hide_outsider_wear(clean, out));
    assert_eq!(names, ["wear"], "wear: {}", d["stop_reason"]);
}

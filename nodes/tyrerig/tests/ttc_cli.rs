//! `tyrerig run --headless --rig-config … --procedure <TTC plan>` then `tyrerig export ttc`, end
//! to end with the built binary: the file has the layout and the quirks of a real TTC run, and
//! its rows agree with the ISO-W log they came from.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::Command;

use tyre_msgs::RigSample;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../..")
}

fn scratch(name: &str) -> PathBuf {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("ttc_cli");
    std::fs::create_dir_all(&dir).expect("scratch dir");
    dir.join(name)
}

fn tyrerig(args: &[&str]) {
    let out = Command::new(env!("CARGO_BIN_EXE_tyrerig")).args(args).output().expect("run tyrerig");
    assert!(
        out.status.success(),
        "tyrerig {args:?}: {}\n{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
}

/// A `.dat` as written: title, channel → (unit, values).
struct Dat {
    title: String,
    names: Vec<String>,
    cols: BTreeMap<String, (String, Vec<f64>)>,
}

impl Dat {
    fn read(path: &Path) -> Dat {
        let text = std::fs::read_to_string(path).expect("dat");
        let mut lines = text.split("\r\n");
        let title = lines.next().unwrap().to_owned();
        let names: Vec<String> = lines.next().unwrap().split('\t').map(str::to_owned).collect();
        let units: Vec<&str> = lines.next().unwrap().split('\t').collect();
        let mut cols: BTreeMap<String, (String, Vec<f64>)> =
            names.iter().zip(&units).map(|(n, u)| (n.clone(), ((*u).to_owned(), Vec::new()))).collect();
        for line in lines.filter(|l| !l.is_empty()) {
            for (n, v) in names.iter().zip(line.split('\t')) {
                cols.get_mut(n).unwrap().1.push(v.parse().unwrap_or_else(|e| panic!("{n}: {v:?}: {e}")));
            }
        }
        Dat { title, names, cols }
    }

    fn col(&self, n: &str) -> &[f64] {
        &self.cols[n].1
    }
}

/// Runs a TTC plan on the brush race tyre and exports it.
fn run_and_export(plan: &str, extra: &[&str]) -> (Dat, PathBuf) {
    let log = scratch(&format!("{plan}.mcap"));
    let dat = scratch(&format!("{plan}.dat"));
    let cfg = root().join("launch-config/virtual_rig_brush_race.toml");
    let proc_file = root().join("launch-config/procedures").join(format!("{plan}.toml"));
    tyrerig(&[
        "run",
        "--headless",
        "--quiet",
        "--rig-config",
        cfg.to_str().unwrap(),
        "--procedure",
        proc_file.to_str().unwrap(),
        "--seed",
        "3",
        "--out",
        log.to_str().unwrap(),
    ]);
    let mut args = vec!["export", "ttc", log.to_str().unwrap(), "--out", dat.to_str().unwrap()];
    args.extend_from_slice(extra);
    tyrerig(&args);
    (Dat::read(&dat), log)
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

#[test]
fn cornering_run_exports_as_a_ttc_file_with_its_quirks() {
    let (d, log) = run_and_export("ttc_cornering_race", &[]);
    assert!(d.title.starts_with("TIRF Data File: Project 2356; Run 004; Test Cornering, Various pressures;"));
    assert!(
        d.title.contains("Tire_Name=tyrerig brush race 20.5x7.0-13 (virtual)") && d.title.ends_with("Rim_Width=7.0")
    );
    assert_eq!(d.names.join(" "), "ET V N SA IA RL RE P FX FY FZ MX MZ NFX NFY RST TSTI TSTC TSTO AMBTMP SR SL");
    assert_eq!(d.cols["P"].0, "kPa");
    let (v, sr, sl, p) = (d.col("V"), d.col("SR"), d.col("SL"), d.col("P"));
    // 50 Hz rows; standstill (belt stopped, load on) at both ends.
    assert!(d.col("ET").windows(2).all(|w| (w[1] - w[0] - 0.02).abs() < 1e-6));
    assert!(v[..100].iter().all(|x| x.abs() < 0.5) && v[v.len() - 100..].iter().all(|x| x.abs() < 0.5));
    assert!(d.col("FZ")[..100].iter().all(|f| *f < -900.0), "standstill with the load applied");
    // Cornering: SL exactly 0 everywhere, SR off zero and noisy, about −0.9 at standstill.
    assert!(sl.iter().all(|x| *x == 0.0));
    let rolling: Vec<f64> = (0..v.len()).filter(|&i| v[i] > 35.0).map(|i| sr[i]).collect();
    let m = median(rolling.clone());
    assert!((-0.015..=-0.005).contains(&m), "median SR {m}");
    assert!(rolling.iter().filter(|x| x.abs() > 0.005).count() as f64 > 0.6 * rolling.len() as f64);
    let still: Vec<f64> = (0..v.len()).filter(|&i| v[i].abs() < 0.3).map(|i| sr[i]).collect();
    assert!((median(still) + 0.9).abs() < 0.03);
    // Four pressures with ramps between them, in kPa.
    for target in [70.0, 84.0, 98.0, 112.0] {
        assert!(p.iter().filter(|x| (*x - target).abs() < 0.5).count() > 2000, "{target} kPa");
    }
    assert!(p.iter().any(|x| (*x - 77.0).abs() < 4.0), "a pressure ramp is in the file");
    // SA to ±13° (SAE sign = −ISO), FZ negative, tread 45–60 °C while sweeping.
    let sa = d.col("SA");
    assert!(sa.iter().cloned().fold(0.0, f64::max) > 12.9 && sa.iter().cloned().fold(0.0, f64::min) < -12.9);
    let tc: Vec<f64> = (0..v.len()).filter(|&i| v[i] > 35.0).map(|i| d.col("TSTC")[i]).collect();
    let tm = median(tc);
    assert!((45.0..=62.0).contains(&tm), "median tread temperature {tm}");
    // Against the ISO-W log: the peak lateral force's sign flips, its size stays.
    let reader = mcaplog::LogReader::open(&log).expect("log");
    let samples = reader.typed::<RigSample>("/rig/sample").expect("samples");
    let iso_max = samples.iter().map(|(_, s)| s.fyw_n).fold(f64::MIN, f64::max);
    let sae_min = d.col("FY").iter().cloned().fold(f64::MAX, f64::min);
    assert!((sae_min + iso_max).abs() < 0.05 * iso_max, "SAE min FY {sae_min} vs ISO max FYW {iso_max}");
}

#[test]
fn drive_brake_run_exports_with_options_and_a_climbing_tread_temperature() {
    let (d, _) = run_and_export("ttc_drive_brake_race", &["--psi", "--lbf", "--no-nfx"]);
    assert!(d.title.contains("Test Drive/Brake/Combined, 12psi;"));
    assert!(!d.names.iter().any(|n| n == "NFX"));
    assert_eq!((d.cols["P"].0.as_str(), d.cols["FX"].0.as_str()), ("psi", "lbf"));
    let p = median(d.col("P").to_vec());
    assert!((p - 12.18).abs() < 0.1, "84 kPa = 12.18 psi, got {p}");
    let (sl, fx, sa, ia) = (d.col("SL"), d.col("FX"), d.col("SA"), d.col("IA"));
    // SL sweeps ±0.2 and drives; slip angles 0/−3/−6° SAE (0/3/6° ISO), cambers 0/2/4°.
    assert!(sl.iter().cloned().fold(0.0, f64::max) > 0.19 && sl.iter().cloned().fold(0.0, f64::min) < -0.19);
    assert!((0..sl.len()).filter(|&i| sl[i] > 0.05).all(|i| fx[i] > 0.0));
    for s in [0.0, -3.0, -6.0] {
        assert!(sa.iter().filter(|x| (*x - s).abs() < 0.1).count() > 1000, "SA {s}");
    }
    for c in [0.0, 2.0, 4.0] {
        assert!(ia.iter().filter(|x| (*x - c).abs() < 0.1).count() > 1000, "IA {c}");
    }
    // No thermal pauses: the tread climbs from ~38 °C to well over 80 °C.
    let tc = d.col("TSTC");
    let n = tc.len();
    let first = median(tc[..n / 10].to_vec());
    let hottest = tc.iter().cloned().fold(0.0, f64::max);
    assert!(first < 45.0 && hottest > 85.0, "TSTC {first} → max {hottest}");
    // AMBTMP: degF under a degC label.
    assert_eq!(d.cols["AMBTMP"].0, "degC");
    assert!(d.col("AMBTMP").iter().all(|t| (84.0..88.0).contains(t)));
}

/// `tyrerig export quirk-fixtures` writes one file per quirk of other test rounds, and
/// `tyrerig inspect --json` on each finds the planned sweeps by kind, the conditioning ones,
/// and accounts for every row.
#[test]
fn inspect_reads_every_quirk_fixture_and_accounts_for_every_row() {
    let dir = scratch("quirks");
    tyrerig(&["export", "quirk-fixtures", dir.to_str().unwrap()]);
    for q in rigdata::fixture::quirk_fixtures() {
        let path = dir.join(q.file);
        let out = Command::new(env!("CARGO_BIN_EXE_tyrerig"))
            .args(["inspect", path.to_str().unwrap(), "--json"])
            .output()
            .expect("run tyrerig");
        assert!(out.status.success(), "{}: {}", q.file, String::from_utf8_lossy(&out.stderr));
        let v: serde_json::Value = serde_json::from_slice(&out.stdout).expect("json");
        let f = &v["files"][0];
        let n = |k: &str| f[k].as_u64().unwrap_or_else(|| panic!("{}: {k}", q.file));
        let excluded: u64 = f["excluded"].as_array().unwrap().iter().map(|e| e[1].as_u64().unwrap()).sum();
        assert_eq!(n("rows_in_sweeps") + n("rows_in_conditioning") + excluded, n("rows"), "{}", q.file);
        // The sweeps the run was made with, by kind (SR's noise hides the short 0.04
        // conditioning sweeps of an SR-only drive/brake file: planned, excluded either way).
        let plan = rigdata::fixture::ttc_run(&q.spec).sweeps;
        let sr_only = q.spec.older_round && !q.spec.cornering;
        let kind_of = |p: &rigdata::fixture::PlannedSweep| {
            if p.camber_sweep { "camber".to_owned() } else { p.kind.name().to_owned() }
        };
        let mut planned: Vec<(String, bool)> =
            plan.iter().filter(|p| !(sr_only && p.conditioning)).map(|p| (kind_of(p), p.conditioning)).collect();
        let mut found: Vec<(String, bool)> = f["sweeps"]
            .as_array()
            .unwrap()
            .iter()
            .map(|s| (s["kind"].as_str().unwrap().to_owned(), s["conditioning"].as_bool().unwrap()))
            .filter(|s| !(sr_only && s.1))
            .collect();
        planned.sort();
        found.sort();
        assert_eq!(found, planned, "{}: {}", q.file, q.quirk);
    }
}

/// `tyrerig fit FILES --folds F --out OUT.tir --report OUT/`, and its `fit.json`.
fn fit_json(files: &[PathBuf], folds: usize, out: &Path) -> serde_json::Value {
    let (tir, folds) = (out.with_extension("tir"), folds.to_string());
    let mut args: Vec<&str> = vec!["fit"];
    args.extend(files.iter().map(|f| f.to_str().unwrap()));
    args.extend(["--folds", &folds, "--out", tir.to_str().unwrap(), "--report", out.to_str().unwrap()]);
    tyrerig(&args);
    serde_json::from_str(&std::fs::read_to_string(out.join("fit.json")).unwrap()).unwrap()
}

/// An older round's pair as a user would fit it: the cornering/camber run (no `SL`, `SR` not a
/// slip ratio, the load wandering ±15 %, camber sweeps) with its pure longitudinal run to ±0.65
/// read from `SR` alone. On real files of such a round the fit was non-physical (Dy/Fz −0.007,
/// exit 3); here it must be physical (exit 0), with the lateral, aligning and longitudinal
/// stages fitted close to the data.
#[test]
fn an_older_rounds_pair_fits_a_physical_model() {
    let dir = scratch("older_round_fit");
    tyrerig(&["export", "quirk-fixtures", dir.to_str().unwrap()]);
    let files = [dir.join("older_round_cornering_camber.dat"), dir.join("older_round_pure_longitudinal_065.dat")];
    let fit = fit_json(&files, 3, &dir.join("older_round"));
    assert!(fit["nonphysical_stages"].as_array().unwrap().is_empty(), "{}", fit["warnings"]);
    let stage = |name: &str| {
        fit["stages"]
            .as_array()
            .unwrap()
            .iter()
            .find(|s| s["stage"] == name)
            .unwrap_or_else(|| panic!("{name}"))
            .clone()
    };
    for (name, most_pct) in [("fy_pure", 2.0), ("mz_pure", 6.0), ("fx_pure", 4.0)] {
        let s = stage(name);
        let (fit_pct, held_out_pct) = (s["nrmse_pct"].as_f64().unwrap(), s["heldout_nrmse_pct"].as_f64());
        eprintln!("{name}: {} points, {fit_pct:.2} % fit, held out {held_out_pct:?}", s["points"]);
        assert!(fit_pct < most_pct, "{name}: {fit_pct} %");
    }
    // The camber sweeps give camber thrust; the curve's camber shape stays held.
    let fy = stage("fy_pure");
    let fitted: Vec<&str> = fy["coefficients"].as_array().unwrap().iter().filter_map(|c| c["key"].as_str()).collect();
    assert!(fitted.contains(&"PKY6"), "{fitted:?}");
    let held: Vec<&str> = fy["held"].as_array().unwrap().iter().filter_map(|h| h["key"].as_str()).collect();
    assert!(held.contains(&"PDY3") && held.contains(&"PVY3"), "{held:?}");
}

/// A cornering run and a drive/brake run that name two tyres (two specimens of one model, as
/// TTC rounds often are) are fitted as one tyre, with a warning that says so; files naming one
/// tyre get none.
#[test]
fn files_naming_two_tyres_are_fitted_with_a_specimen_warning() {
    let dir = scratch("two_specimens");
    tyrerig(&["export", "quirk-fixtures", dir.to_str().unwrap()]);
    let cornering = dir.join("cold_start_cornering.dat");
    let drive = dir.join("warmup_drive_brake.dat");
    let text = std::fs::read_to_string(&drive).unwrap();
    assert!(text.contains("Tire_Name=Fixture"), "{}", &text[..200]);
    let other = dir.join("warmup_drive_brake_tire21.dat");
    std::fs::write(&other, text.replacen("Tire_Name=Fixture", "Tire_Name=Tire 21", 1)).unwrap();
    let warnings = |drive: &Path, name: &str| {
        let fit = fit_json(&[cornering.clone(), drive.to_path_buf()], 0, &dir.join(name));
        fit["warnings"].as_array().unwrap().iter().map(|w| w.as_str().unwrap().to_owned()).collect::<Vec<_>>()
    };
    let two = warnings(&other, "two");
    let w = two.iter().find(|w| w.contains("the files name 2 tyres")).unwrap_or_else(|| panic!("{two:?}"));
    assert!(w.contains("\"Tire 21 ") && w.contains("fitted as one tyre"), "{w}");
    let one = warnings(&drive, "one");
    assert!(!one.iter().any(|w| w.contains("tyres (")), "{one:?}");
}

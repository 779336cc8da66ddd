//! `tyrerig inject` end to end with the built binary: a short virtual-rig run (TTC-style
//! cornering on the MF tyre, sensor noise and tread temperatures), effects hidden in it, the
//! truth JSON checked, the injected log read back and exported as a TTC file.

use std::path::{Path, PathBuf};
use std::process::Command;

use mcaplog::LogReader;
use tyre_msgs::RigSample;

fn tyrerig(args: &[&str]) -> String {
    let o = Command::new(env!("CARGO_BIN_EXE_tyrerig")).args(args).output().expect("run tyrerig");
    assert!(
        o.status.success(),
        "tyrerig {args:?}: {}\n{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    );
    String::from_utf8_lossy(&o.stdout).into_owned()
}

fn samples(path: &Path) -> Vec<RigSample> {
    let log = LogReader::open(path).expect("the log reads back");
    log.typed::<RigSample>("/rig/sample").expect("RigSamples").into_iter().map(|(_, s)| s).collect()
}

#[test]
fn injected_truth_and_log_read_back() {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../..");
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("inject_cli");
    std::fs::create_dir_all(&dir).expect("output dir");
    let s = |p: &Path| p.display().to_string();
    let (clean, injected, truth, dat) =
        (dir.join("clean.mcap"), dir.join("injected.mcap"), dir.join("truth.json"), dir.join("injected.dat"));
    let rig = root.join("launch-config/virtual_rig.toml");
    let procedure = root.join("launch-config/procedures/ttc_cornering_road.toml");
    tyrerig(&[
        "run",
        "--headless",
        "--quiet",
        "--seed",
        "1",
        "--effects",
        "noise,thermal",
        "--rig-config",
        &s(&rig),
        "--procedure",
        &s(&procedure),
        "--out",
        &s(&clean),
    ]);
    let out = tyrerig(&[
        "inject",
        &s(&clean),
        "--out",
        &s(&injected),
        "--rig-config",
        &s(&rig),
        "--effect",
        "thermal:2",
        "--effect",
        "wear",
        "--seed",
        "4",
        "--truth-json",
        &s(&truth),
    ]);
    assert!(out.contains("thermal (strength 2)"), "{out}");

    let t: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&truth).expect("truth JSON written")).expect("truth parses");
    assert_eq!(t["tool"], "tyrerig inject");
    assert_eq!(t["seed"], 4);
    assert_eq!(t["kinds"], serde_json::json!(["thermal", "wear"]));
    let effects = t["effects"].as_array().expect("effects");
    assert_eq!(effects[0]["kind"], "thermal");
    assert_eq!(effects[0]["strength"], 2.0);
    assert_eq!(effects[0]["effect"]["kind"], "thermal", "the drawn form is recorded");
    assert!(effects[0]["resolved"]["grip_optimum_c"].as_f64().is_some_and(|c| c > 20.0 && c < 120.0));
    assert!(effects[1]["resolved"]["rate_mm_per_mj"].as_f64().is_some_and(|r| r > 0.0));
    for e in effects {
        let size = e["size"]["strength_noise_units"].as_f64().expect("size in noise units");
        assert!(size > 1.0, "{e}");
    }
    assert!(t["noise_sigma"]["fyw_n"].as_f64() == Some(40.0), "the rig config's noise: {}", t["noise_sigma"]);

    // The injected log reads back with the same samples, only FX, FYW, MZW, DSTWOWHC changed.
    let (a, b) = (samples(&clean), samples(&injected));
    assert_eq!(a.len(), b.len());
    assert_eq!(t["logs"][0]["samples"].as_u64(), Some(a.len() as u64));
    let mut moved = 0usize;
    for (x, y) in a.iter().zip(&b) {
        let mut z = y.clone();
        (z.fx_n, z.fyw_n, z.mzw_nm, z.dstwowhc_m) = (x.fx_n, x.fyw_n, x.mzw_nm, x.dstwowhc_m);
        assert_eq!(&z, x, "a field other than the four changed");
        moved += usize::from(x.fyw_n != y.fyw_n);
    }
    assert!(moved > a.len() / 2, "FYW changed in {moved} of {} samples", a.len());
    let (ra, rb) = (LogReader::open(&clean).expect("clean"), LogReader::open(&injected).expect("injected"));
    assert_eq!(ra.topics(), rb.topics(), "every topic is copied");
    assert_eq!(ra.metadata(), rb.metadata(), "every metadata record is copied");

    // And it goes through the TTC export like any virtual run.
    tyrerig(&["export", "ttc", &s(&injected), "--out", &s(&dat)]);
    assert!(std::fs::metadata(&dat).expect("the .dat is written").len() > 10_000);
}

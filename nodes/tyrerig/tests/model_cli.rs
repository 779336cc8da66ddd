//! `tyrerig model eval` / `model plot` end to end: the built binary against MFeval's reference.

use std::path::{Path, PathBuf};
use std::process::Command;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../..")
}

fn fixtures() -> PathBuf {
    root().join("tests/fixtures/mfeval")
}

fn tir() -> PathBuf {
    root().join("launch-config/tyres/MagicFormula61_Paramerters.tir")
}

fn scratch(name: &str) -> PathBuf {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("model_cli");
    std::fs::create_dir_all(&dir).expect("scratch dir");
    dir.join(name)
}

fn tyrerig(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_tyrerig")).args(args).output().expect("run tyrerig")
}

fn read_csv(path: &Path) -> (Vec<String>, Vec<Vec<Option<f64>>>) {
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let mut lines = text.lines();
    let header = lines.next().expect("header").split(',').map(str::to_owned).collect();
    let rows = lines.map(|l| l.split(',').map(|v| v.trim().parse::<f64>().ok()).collect()).collect();
    (header, rows)
}

/// Runs `model eval` and compares every listed column row by row (1e-9 relative, with a
/// 1e-6 absolute floor for forces/moments and 1e-9 of the column scale for the rest).
fn eval_and_compare(inputs: &str, reference: &str, mode: &str, columns: &[&str]) {
    let out = scratch(&format!("{reference}.{mode}.out.csv"));
    let input = fixtures().join(inputs);
    let status = tyrerig(&[
        "model",
        "eval",
        "--tir",
        tir().to_str().expect("utf-8 path"),
        "--input",
        input.to_str().expect("utf-8 path"),
        "--output",
        out.to_str().expect("utf-8 path"),
        "--use-mode",
        mode,
    ]);
    assert!(status.status.success(), "{}", String::from_utf8_lossy(&status.stderr));
    let (got_h, got) = read_csv(&out);
    let (want_h, want) = read_csv(&fixtures().join(reference));
    assert_eq!(got_h, want_h, "column names must be MFeval's");
    assert_eq!(got.len(), want.len());
    for name in columns {
        let c = want_h.iter().position(|h| h == name).expect("column");
        let scale = want.iter().filter_map(|r| r[c]).fold(0.0_f64, |m, v| m.max(v.abs()));
        let force = ["Fx", "Fy", "Fz", "Mx", "My", "Mz", "Mzr"].contains(name);
        let floor = if force { 1e-6 } else { 1e-9 * scale };
        for (i, (g, w)) in got.iter().zip(&want).enumerate() {
            let (g, w) = (g[c].expect("number"), w[c].expect("number"));
            let d = (g - w).abs();
            assert!(
                d <= 1e-9 * w.abs() || d <= floor,
                "{reference} line {} {name}: tyrerig {g:e} vs MFeval {w:e}",
                i + 2
            );
        }
    }
    // instKya is MFeval's row-to-row finite difference, not a model value: left empty.
    let ik = got_h.iter().position(|h| h == "instKya").expect("instKya");
    assert!(got.iter().all(|r| r[ik].is_none()));
}

const SLIP_COLUMNS: &[&str] = &[
    "Fx", "Fy", "Fz", "Mx", "My", "Mz", "kappa", "alpha", "gamma", "phit", "Vx", "P", "2a", "t", "mux", "muy", "2b",
    "Mzr", "Cx", "Cy", "Kya", "sigmax", "sigmay", "Kxk",
];

#[test]
fn eval_matches_mfeval_mode_111() {
    eval_and_compare("mf61_reference_inputs.csv", "mf61_reference.csv", "111", SLIP_COLUMNS);
}

#[test]
fn eval_matches_mfeval_mode_121() {
    eval_and_compare("mf61_reference_inputs.csv", "mf61_reference_mode121.csv", "121", SLIP_COLUMNS);
}

#[test]
fn eval_matches_mfeval_with_given_omega() {
    let mut cols = SLIP_COLUMNS.to_vec();
    cols.extend(["Re", "rho", "Rl", "Cz", "omega"]);
    eval_and_compare("mf61_reference_omegaVxR0_inputs.csv", "mf61_reference_omegaVxR0.csv", "111", &cols);
}

#[test]
fn bad_input_names_file_line_and_column() {
    let input = scratch("bad_input.csv");
    std::fs::write(
        &input,
        "Fz,kappa,alpha,gamma,phit,Vx,P,omega,note\n\
         4000,0,0.1,0,0,16.6,0,0,a\n\
         4000,0,0.1,0,0,16.6,0,0,b\n\
         4000,0.1,abc,0,0,16.6,0,0,c\n",
    )
    .expect("write");
    let out = scratch("bad_output.csv");
    let r = tyrerig(&[
        "model",
        "eval",
        "--tir",
        tir().to_str().expect("path"),
        "--input",
        input.to_str().expect("path"),
        "--output",
        out.to_str().expect("path"),
    ]);
    assert!(!r.status.success());
    let msg = String::from_utf8_lossy(&r.stderr);
    assert!(msg.contains("bad_input.csv:4") && msg.contains("alpha") && msg.contains("abc"), "{msg}");

    std::fs::write(&input, "Fz,kappa,alpha,gamma,Vx,P,omega\n4000,0,0,0,16.6,0,0\n").expect("write");
    let r = tyrerig(&[
        "model",
        "eval",
        "--tir",
        tir().to_str().expect("path"),
        "--input",
        input.to_str().expect("path"),
        "--output",
        out.to_str().expect("path"),
    ]);
    assert!(!r.status.success());
    let msg = String::from_utf8_lossy(&r.stderr);
    assert!(msg.contains("missing column `phit`"), "{msg}");

    let r = tyrerig(&[
        "model",
        "eval",
        "--tir",
        "/nonexistent.tir",
        "--input",
        input.to_str().expect("path"),
        "--output",
        out.to_str().expect("path"),
    ]);
    assert!(!r.status.success());
    assert!(String::from_utf8_lossy(&r.stderr).contains("/nonexistent.tir"));
}

#[test]
fn plot_writes_png_and_svg() {
    let dir = scratch("plots");
    let _ = std::fs::remove_dir_all(&dir);
    let r = tyrerig(&[
        "model",
        "plot",
        "--tir",
        tir().to_str().expect("path"),
        "--out",
        dir.to_str().expect("path"),
        "--format",
        "both",
    ]);
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    for stem in ["fy_alpha_load", "fx_kappa_pressure", "mz_alpha_load", "combined_fx_fy"] {
        for ext in ["png", "svg"] {
            let p = dir.join(format!("{stem}.{ext}"));
            let len = std::fs::metadata(&p).map(|m| m.len()).unwrap_or(0);
            assert!(len > 1000, "{} missing or empty", p.display());
        }
    }
}

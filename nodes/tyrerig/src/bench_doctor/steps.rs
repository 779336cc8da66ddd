//! The steps of one case: the clean logs (made once, cached), the injection, the TTC export and
//! the doctor, run exactly as the CLI runs it.

use anyhow::{Context, Result, bail};
use hidden::score::{NamedEffect, TruthEffect};
use std::path::{Path, PathBuf};
use std::process::Command;

use super::cases::{Case, Plan, Tyre};

/// Virtual-rig effects of the clean logs: sensor noise and tread temperatures, no hidden grip
/// effect (and no relaxation, which the doctor may rightly name as `transient`).
const CLEAN_EFFECTS: &str = "noise,thermal";
/// Noise seed of every clean log.
const RIG_SEED: u64 = 1;

/// The clean logs of a tyre and plan, made on the virtual rig unless already in `dir`.
pub fn clean_logs(launch: &Path, dir: &Path, tyre: Tyre, plan: Plan) -> Result<Vec<PathBuf>> {
    let mut out = Vec::new();
    for proc_file in plan.procedures(tyre) {
        let stem = proc_file.trim_end_matches(".toml");
        let path = dir.join(format!("{}_{stem}.mcap", tyre.name()));
        if !readable(&path) {
            let t0 = std::time::Instant::now();
            make_clean_log(launch, tyre, proc_file, &path)?;
            eprintln!("  clean log {} in {:.1} s", path.display(), t0.elapsed().as_secs_f64());
        }
        out.push(path);
    }
    Ok(out)
}

/// A cached log counts only if it reads back whole (a killed run leaves a cut file).
fn readable(path: &Path) -> bool {
    path.exists() && mcaplog::LogReader::open(path).is_ok()
}

fn make_clean_log(launch: &Path, tyre: Tyre, proc_file: &str, path: &Path) -> Result<()> {
    let mut spec = suite::RunSpec::new(launch, suite::ProcedureChoice::Gs2mf);
    spec.procedure_file = launch.join("procedures").join(proc_file);
    spec.rig_config = tyre.rig_config(launch);
    spec.effects = Some(CLEAN_EFFECTS.into());
    spec.seed = RIG_SEED;
    let mut h = suite::Headless::new(&spec, thermal::ThermalConfig::default(), sequencer::SequencerConfig::default())
        .with_context(|| format!("{}: setting up the virtual rig", spec.procedure_file.display()))?;
    // Written under a temporary name: an interrupted run leaves no log that looks complete.
    let partial = path.with_extension("mcap.partial");
    let mut sink = suite::McapSink::create(&partial, "/rig", &h.metadata(&spec))?;
    h.run(&mut sink, &mut |_, _| {}).with_context(|| format!("running {}", spec.procedure_file.display()))?;
    sink.finish()?;
    std::fs::rename(&partial, path).with_context(|| format!("{}: cannot rename into place", partial.display()))?;
    Ok(())
}

/// Injects the case's effects into the clean logs (into `case_dir`), writes `truth.json`, and
/// returns the logs the doctor is to read and the truth. A clean case reads the clean logs.
pub fn inject(
    case: &Case,
    rig_config: &Path,
    clean: &[PathBuf],
    case_dir: &Path,
) -> Result<(Vec<PathBuf>, Vec<TruthEffect>)> {
    if case.effects.is_empty() {
        return Ok((clean.to_vec(), Vec::new()));
    }
    let (tyre, noise) = crate::cmd_inject::load_rig(rig_config)?;
    let kinds: Vec<_> = case.effects.iter().map(|&k| (k, case.strength())).collect();
    let effects = crate::cmd_inject::draw_effects(&kinds, case.seed)?;
    let pairs: Vec<(PathBuf, PathBuf)> = clean
        .iter()
        .map(|c| (c.clone(), case_dir.join(c.file_name().unwrap_or_default()).with_extension("injected.mcap")))
        .collect();
    let report = hidden::inject_logs(&pairs, &tyre, &noise, &effects)?;
    let truth_path = case_dir.join("truth.json");
    let v = crate::cmd_inject::truth_json(&report, case.seed, rig_config)?;
    std::fs::write(&truth_path, serde_json::to_string_pretty(&v)?)
        .with_context(|| format!("{}: cannot write", truth_path.display()))?;
    let truth = report
        .effects
        .iter()
        .map(|e| TruthEffect { kind: e.kind, strength_noise_units: e.size.strength_noise_units })
        .collect();
    Ok((pairs.into_iter().map(|p| p.1).collect(), truth))
}

/// `tyrerig export ttc` of each log into `case_dir` (run numbers 1, 2, …; the exporter's
/// defaults otherwise): the files the doctor then reads.
pub fn export_ttc(logs: &[PathBuf], case_dir: &Path) -> Result<Vec<PathBuf>> {
    use rigdata::virtual_export::{TtcExportOptions, VirtualRun, export_ttc, to_dat_compact};
    let mut out = Vec::new();
    for (i, log) in logs.iter().enumerate() {
        let run = VirtualRun::from_log(log)?;
        let opts = TtcExportOptions { run: i as u32 + 1, ..TtcExportOptions::default() };
        let table = export_ttc(&run, &opts)?;
        let stem = log.file_stem().map_or_else(|| format!("run{i}"), |s| s.to_string_lossy().into_owned());
        let dat = case_dir.join(format!("{stem}.dat"));
        std::fs::write(&dat, to_dat_compact(&table)).with_context(|| format!("writing {}", dat.display()))?;
        out.push(dat);
    }
    Ok(out)
}

/// What the doctor said about a case (its `doctor.json`).
#[derive(Debug, Clone, Default)]
pub struct Verdict {
    pub named: Vec<String>,
    pub named_detail: Vec<NamedEffect>,
    pub form_errors: Vec<String>,
    /// Each state effect in the model and the one it was not told apart from.
    pub indistinct: Vec<[String; 2]>,
    pub wall_time_s: f64,
}

/// Runs `tyrerig doctor` (this binary) on `inputs` into `out` and reads its `doctor.json`.
/// The MF tyre is diagnosed against its own .tir (`--model`), a brush tyre against an MF fit
/// to the same logs (`--fit`; its MX stage skipped: the doctor does not diagnose MX). `extra`
/// goes on the command line after those.
pub fn doctor(launch: &Path, tyre: Tyre, inputs: &[PathBuf], extra: &[String], out: &Path) -> Result<Verdict> {
    let exe = std::env::current_exe().context("locating the tyrerig binary")?;
    let mut cmd = Command::new(exe);
    cmd.arg("doctor").args(inputs).arg("--out").arg(out);
    match tyre {
        Tyre::Mf => cmd.arg("--model").arg(launch.join("tyres/MagicFormula61_Paramerters.tir")),
        Tyre::BrushRoad | Tyre::BrushRace => cmd.args(["--fit", "--skip-stage", "mx"]),
    };
    cmd.args(extra);
    let o = cmd.output().context("running tyrerig doctor")?;
    let log = out.join("doctor.log");
    let text =
        format!("{}\n--- stderr ---\n{}", String::from_utf8_lossy(&o.stdout), String::from_utf8_lossy(&o.stderr));
    std::fs::write(&log, &text).with_context(|| format!("{}: cannot write", log.display()))?;
    if !o.status.success() {
        let stderr = String::from_utf8_lossy(&o.stderr);
        let mut tail: Vec<&str> = stderr.lines().rev().take(3).collect();
        tail.reverse();
        bail!("tyrerig doctor failed ({}): {}", o.status, tail.join(" | "));
    }
    read_verdict(&out.join("doctor.json"))
}

fn read_verdict(path: &Path) -> Result<Verdict> {
    let text = std::fs::read_to_string(path).with_context(|| format!("{}: cannot read", path.display()))?;
    let v: serde_json::Value = serde_json::from_str(&text).with_context(|| format!("{}: not JSON", path.display()))?;
    let strings = |key: &str| -> Vec<String> {
        v.get(key)
            .and_then(|a| a.as_array())
            .map(|a| a.iter().filter_map(|s| s.as_str().map(str::to_owned)).collect())
            .unwrap_or_default()
    };
    let Some(named) = v.get("named_effects").and_then(|a| a.as_array()) else {
        bail!("{}: no `named_effects` array", path.display());
    };
    let named: Vec<String> = named.iter().filter_map(|s| s.as_str().map(str::to_owned)).collect();
    let named_detail = v
        .get("effects")
        .and_then(|a| a.as_array())
        .map(|a| {
            a.iter()
                .filter_map(|e| {
                    Some(NamedEffect {
                        effect: e.get("effect")?.as_str()?.to_owned(),
                        rms_before_heldout: e.get("rms_before_heldout").and_then(|x| x.as_f64()).unwrap_or(f64::NAN),
                        rms_after_heldout: e.get("rms_after_heldout").and_then(|x| x.as_f64()).unwrap_or(f64::NAN),
                    })
                })
                .collect()
        })
        .unwrap_or_default();
    let indistinct = v
        .get("indistinct_effects")
        .and_then(|a| a.as_array())
        .map(|a| {
            a.iter()
                .filter_map(|e| Some([e.get("in_model")?.as_str()?.to_owned(), e.get("or")?.as_str()?.to_owned()]))
                .collect()
        })
        .unwrap_or_default();
    Ok(Verdict {
        named,
        named_detail,
        form_errors: strings("form_errors"),
        indistinct,
        wall_time_s: v.get("wall_time_s").and_then(|x| x.as_f64()).unwrap_or(f64::NAN),
    })
}

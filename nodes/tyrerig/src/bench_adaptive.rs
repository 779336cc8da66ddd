//! `tyrerig bench adaptive`: rig time to accuracy of the adaptive plan against GS2MF and the
//! Square Matrix, per tyre and seed (issue 17's figure of merit).
//!
//! For each seed the three procedures run headless on the same virtual rig (the adaptive one
//! with its live fit). Every log is then cut after its data segments at a few points, each
//! prefix fitted offline as `tyrerig fit --folds 0` would, and the model compared with the
//! rig's true tyre on one held-out grid: the range and support of the full GS2MF run's fit of
//! the same tyre and seed (so every model is scored on the same points). The error is the mean
//! over the seven channels (FY, MZ, MX, FX pure; FX, FY, MZ combined) of the RMS difference in
//! % of the true tyre's peak. Rig time to accuracy: the rig time at the end of the first prefix
//! whose error is at most the full GS2MF model's (and, as a looser figure, within 10 % of it).

use anyhow::Context as _;
use livefit::replay::{feed, inputs_of_log};
use livefit::{LiveFit, LiveFitConfig};
use mffit::accuracy::{AccuracyRow, Support, compare_with};
use mffit::{Dataset, FitResult};
use mftyre::{MfInput, UseMode};
use serde_json::json;
use std::path::{Path, PathBuf};
use suite::headless::{Headless, rig_and_tyre};
use suite::{McapSink, ProcedureChoice, RunSpec, RunSummary};

/// `tyrerig bench adaptive` arguments.
#[derive(Debug, clap::Args)]
pub struct AdaptiveBench {
    /// Virtual rig configs, one per tyre (default: the MF tyre and the brush road tyre).
    #[arg(long, value_delimiter = ',', default_values = ["launch-config/virtual_rig.toml", "launch-config/virtual_rig_brush_road.toml"])]
    pub rig_config: Vec<PathBuf>,
    /// Seeds.
    #[arg(long, value_delimiter = ',', default_values_t = [1u64, 2, 3])]
    pub seeds: Vec<u64>,
    /// The launch-config directory (procedure files).
    #[arg(long, default_value = "launch-config")]
    pub launch_config: PathBuf,
    /// Where the logs go; a log already there (with its summary) is reused.
    #[arg(long, default_value = "out/bench_adaptive")]
    pub out_dir: PathBuf,
    /// Prefixes fitted per log (evenly spread over its data segments from `--from` on).
    #[arg(long, default_value_t = 6)]
    pub prefixes: usize,
    /// First prefix, as a fraction of the log's data segments (before it the longitudinal
    /// channels have no data in GS2MF, so no model reaches the target).
    #[arg(long, default_value_t = 0.5)]
    pub from: f64,
    /// The adaptive plan's `target_ratio` (default: the sequencer's); a non-default one runs
    /// as `adaptive-r<ratio>` with its own logs.
    #[arg(long)]
    pub target_ratio: Option<f64>,
    /// The adaptive plan's `wear_mm_per_mj` (default: the sequencer's; 0 leaves wear out of
    /// the candidates' cost); a non-default one runs as `adaptive-w<rate>` with its own logs.
    #[arg(long)]
    pub wear_mm_per_mj: Option<f64>,
    /// The adaptive plan's `wear_rate_log_sd` (default: the sequencer's; 0 prices wear at the
    /// configured rate whatever the monitor measures); a non-default one runs as
    /// `adaptive-s<sd>` with its own logs.
    #[arg(long)]
    pub wear_rate_log_sd: Option<f64>,
    /// Leave out the Square Matrix (its runs and fits take the longest).
    #[arg(long)]
    pub no_square_matrix: bool,
    /// Write every figure as JSON too.
    #[arg(long)]
    pub json: Option<PathBuf>,
}

struct Plan {
    label: String,
    choice: ProcedureChoice,
    adaptive: bool,
}

fn plans(args: &AdaptiveBench) -> Vec<Plan> {
    let mut adaptive = String::from("adaptive");
    if let Some(r) = args.target_ratio {
        adaptive += &format!("-r{r}");
    }
    if let Some(w) = args.wear_mm_per_mj {
        adaptive += &format!("-w{w}");
    }
    if let Some(sd) = args.wear_rate_log_sd {
        adaptive += &format!("-s{sd}");
    }
    let mut p = vec![
        Plan { label: "gs2mf".into(), choice: ProcedureChoice::Gs2mf, adaptive: false },
        Plan { label: adaptive, choice: ProcedureChoice::Gs2mf, adaptive: true },
    ];
    if !args.no_square_matrix {
        p.push(Plan { label: "square-matrix".into(), choice: ProcedureChoice::SquareMatrix, adaptive: false });
    }
    p
}

/// Runs (or reuses) one procedure's log; returns its summary.
fn run_log(args: &AdaptiveBench, rig: &Path, seed: u64, plan: &Plan, log: &Path) -> anyhow::Result<RunSummary> {
    let sum_path = log.with_extension("json");
    if log.exists()
        && let Ok(text) = std::fs::read_to_string(&sum_path)
        && let Ok(s) = serde_json::from_str::<RunSummary>(&text)
    {
        return Ok(s);
    }
    let mut spec = RunSpec::new(&args.launch_config, plan.choice);
    spec.rig_config = rig.to_owned();
    spec.seed = seed;
    let mut seq_cfg = sequencer::SequencerConfig {
        plan: if plan.adaptive { sequencer::PlanKind::Adaptive } else { sequencer::PlanKind::Fixed },
        ..sequencer::SequencerConfig::default()
    };
    if let Some(r) = args.target_ratio {
        seq_cfg.adaptive.target_ratio = r;
    }
    if let Some(w) = args.wear_mm_per_mj {
        seq_cfg.adaptive.wear_mm_per_mj = w;
    }
    if let Some(sd) = args.wear_rate_log_sd {
        seq_cfg.adaptive.wear_rate_log_sd = sd;
    }
    seq_cfg.validate()?;
    let mut h = Headless::new(&spec, thermal::ThermalConfig::default(), seq_cfg)?;
    if plan.adaptive {
        h = h.with_live_fit(LiveFitConfig::default());
    }
    let md = h.metadata(&spec);
    let mut sink = McapSink::create(log, "/rig", &md)?;
    let wall = std::time::Instant::now();
    let summary = h.run(&mut sink, &mut |_, _| {})?;
    sink.finish()?;
    eprintln!(
        "  ran {} seed {seed}: {:.0} s rig time in {:.0} s wall",
        plan.label,
        summary.total_rig_time_s,
        wall.elapsed().as_secs_f64()
    );
    std::fs::write(&sum_path, serde_json::to_string_pretty(&summary)?)?;
    Ok(summary)
}

/// A log's data (segments as the fit reads them) and the rig time each segment ended at.
fn timeline(log: &Path) -> anyhow::Result<(Dataset, Vec<f64>)> {
    let reader = mcaplog::LogReader::open(log)?;
    let inputs = inputs_of_log(&reader).map_err(|e| anyhow::anyhow!("{}: {e}", log.display()))?;
    let fz0 = reader.metadata().get("procedure").and_then(|p| p.get("fz0_n")).and_then(|v| v.parse::<f64>().ok());
    drop(reader);
    let mut core = LiveFit::new(LiveFitConfig { fz0_n: fz0, ..LiveFitConfig::default() });
    let mut ends = Vec::new();
    let mut t = 0.0;
    for input in &inputs {
        if let livefit::replay::Input::Sample(s) = input {
            t = s.header.stamp.as_secs_f64();
        }
        feed(&mut core, input);
        while ends.len() < core.data().segments.len() {
            ends.push(t);
        }
    }
    let _ = core.begin_final();
    while ends.len() < core.data().segments.len() {
        ends.push(t);
    }
    Ok((core.data().clone(), ends))
}

fn fit_prefix(data: &Dataset, n: usize) -> anyhow::Result<FitResult> {
    let mut d = data.clone();
    d.segments.truncate(n);
    let opts = LiveFitConfig { fz0_n: data.fnomin_n, ..LiveFitConfig::default() }.fit_options();
    mffit::fit(&d, &opts).map_err(|e| anyhow::anyhow!("fit of {n} segments: {e}"))
}

fn mean_error(rows: &[AccuracyRow]) -> f64 {
    let v: Vec<f64> =
        rows.iter().map(|r| if r.rms_pct_of_peak.is_finite() { r.rms_pct_of_peak } else { 1e9 }).collect();
    v.iter().sum::<f64>() / v.len().max(1) as f64
}

pub fn run(args: &AdaptiveBench) -> anyhow::Result<()> {
    std::fs::create_dir_all(&args.out_dir)?;
    let mut all = Vec::new();
    println!(
        "{:<12} {:>4} {:<13} {:>8} {:>6} {:>8} {:>7} {:>10} {:>10} {:>7} {:>9}",
        "tyre", "seed", "plan", "rig_s", "sweeps", "err_%", "/gs2mf", "t_acc_s", "t_acc10_s", "peak_C", "wear_mm"
    );
    for rig in &args.rig_config {
        let tyre_label = rig.file_stem().map(|s| s.to_string_lossy().replace("virtual_rig", "rig")).unwrap_or_default();
        for &seed in &args.seeds {
            let mut spec = RunSpec::new(&args.launch_config, ProcedureChoice::Gs2mf);
            spec.rig_config = rig.clone();
            spec.seed = seed;
            let (_, tyre) = rig_and_tyre(&spec)?;
            let truth = |mode: UseMode, x: &MfInput| tyre.reference(mode, x);
            let mut logs = Vec::new();
            for plan in plans(args) {
                let log = args.out_dir.join(format!("{tyre_label}_{}_s{seed}.mcap", plan.label));
                let summary =
                    run_log(args, rig, seed, &plan, &log).with_context(|| format!("{} seed {seed}", plan.label))?;
                logs.push((plan, log, summary));
            }
            // The reference: the full GS2MF run's model, and the grid every model is scored on.
            let (g_data, _) = timeline(&logs[0].1)?;
            let reference = fit_prefix(&g_data, g_data.segments.len())?;
            let support = Support::of_fit(&reference);
            let score = |fit: &FitResult| compare_with(&truth, &fit.params, &reference.range, &support);
            let e_ref = mean_error(&score(&reference));
            let mut times = Vec::new();
            for (plan, log, summary) in &logs {
                let (data, ends) = timeline(log)?;
                let n = data.segments.len();
                let k = args.prefixes.max(1);
                let mut cuts: Vec<usize> = (0..k)
                    .map(|i| {
                        let f = args.from + (1.0 - args.from) * (i as f64 + 1.0) / k as f64;
                        ((f * n as f64).round() as usize).clamp(1, n)
                    })
                    .collect();
                cuts.dedup();
                let mut curve = Vec::new();
                let mut final_rows: Vec<AccuracyRow> = Vec::new();
                for &c in &cuts {
                    let rows = if plan.label == "gs2mf" && c == n {
                        score(&reference)
                    } else {
                        fit_prefix(&data, c).map(|f| score(&f)).unwrap_or_default()
                    };
                    let e = if rows.is_empty() { f64::INFINITY } else { mean_error(&rows) };
                    curve.push((ends[c - 1], c, e));
                    final_rows = rows;
                }
                let per_channel: Vec<String> =
                    final_rows.iter().map(|r| format!("{} {:.2}", r.channel, r.rms_pct_of_peak)).collect();
                eprintln!(
                    "  {tyre_label} seed {seed} {}: final model per channel (% of peak): {}",
                    plan.label,
                    per_channel.join(", ")
                );
                let reach =
                    |tol: f64| curve.iter().find(|(_, _, e)| *e <= e_ref * (1.0 + tol) + 1e-12).map(|(t, _, _)| *t);
                let (t_acc, t_acc10) = (reach(0.0), reach(0.10));
                let e_final = curve.last().map_or(f64::NAN, |c| c.2);
                // A log without the rig's truth (a run over DDS, summarised from its log) has the
                // monitor's wear, measured from the rolling radius.
                let max_of = |v: &[f64]| v.iter().copied().filter(|w| w.is_finite()).fold(0.0, f64::max);
                let (wear, wear_source) = if summary.wear_mm_true.is_empty() {
                    (max_of(&summary.wear_mm_measured), "measured")
                } else {
                    (max_of(&summary.wear_mm_true), "true")
                };
                if wear_source == "measured" {
                    eprintln!(
                        "  {tyre_label} seed {seed} {}: wear measured from radius (no truth in the log)",
                        plan.label
                    );
                }
                let show = |t: Option<f64>| t.map_or("not reached".to_owned(), |t| format!("{t:.0}"));
                println!(
                    "{:<12} {:>4} {:<13} {:>8.0} {:>6} {:>8.3} {:>7.3} {:>10} {:>10} {:>7.1} {:>9.3}",
                    tyre_label,
                    seed,
                    plan.label,
                    summary.total_rig_time_s,
                    summary.sweeps,
                    e_final,
                    e_final / e_ref,
                    show(t_acc),
                    show(t_acc10),
                    summary.max_temp_c,
                    wear
                );
                times.push((plan.adaptive, plan.label == "gs2mf", t_acc, t_acc10));
                all.push(json!({
                    "tyre": tyre_label, "seed": seed, "plan": plan.label,
                    "rig_time_s": summary.total_rig_time_s, "sweeps": summary.sweeps,
                    "error_pct": e_final, "error_over_gs2mf": e_final / e_ref, "gs2mf_error_pct": e_ref,
                    "rig_time_to_accuracy_s": t_acc, "rig_time_to_accuracy_10pct_s": t_acc10,
                    "peak_tread_temp_c": summary.max_temp_c, "peak_sweep_start_temp_c": summary.max_sweep_start_temp_c,
                    "wear_mm_true": summary.wear_mm_true, "wear_mm_measured": summary.wear_mm_measured,
                    "wear_mm": wear, "wear_source": wear_source, "curve": curve.iter().map(|(t, c, e)| json!({"rig_time_s": t, "segments": c, "error_pct": e})).collect::<Vec<_>>(),
                    "adaptive_decisions": summary.adaptive.len(),
                    "final_per_channel_pct": final_rows.iter().map(|r| json!({"channel": r.channel, "rms_pct_of_peak": r.rms_pct_of_peak})).collect::<Vec<_>>(),
                    "alarms": summary.alarms.iter().filter(|a| a.check == "graph_sweep_drift").map(|a| a.message.clone()).collect::<Vec<_>>(),
                }));
            }
            let g = times.iter().find(|t| t.1).map_or((None, None), |t| (t.2, t.3));
            let a = times.iter().find(|t| t.0).map_or((None, None), |t| (t.2, t.3));
            let ratio = |a: Option<f64>, g: Option<f64>| match (a, g) {
                (Some(a), Some(g)) => format!("{:.3}", a / g),
                _ => "not reached".into(),
            };
            println!(
                "{:<12} {:>4} adaptive / gs2mf rig time to accuracy: {} (to within 10 % of it: {})",
                tyre_label,
                seed,
                ratio(a.0, g.0),
                ratio(a.1, g.1)
            );
        }
    }
    if let Some(p) = &args.json {
        std::fs::write(p, serde_json::to_string_pretty(&all)?)?;
    }
    Ok(())
}

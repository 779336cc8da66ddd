//! `tyrerig bench live-fit`: a recorded run fed to the live fit's core as the suite produced it,
//! timing every update (wall clock, this machine), with the point in the procedure where each
//! stage becomes identified; optionally the end-of-run model against the offline `tyrerig fit`
//! of the same log and a reference tyre, and its predicted bands on another run.

use anyhow::Context as _;
use livefit::replay::{Input, feed, inputs_of_log};
use livefit::{LiveFit, LiveFitConfig, Trigger};
use mffit::accuracy::{AccuracyRow, ReferenceTyre, Support, compare_with};
use mffit::calibration::Calibration;
use mffit::prediction::{EnvelopeGrid, PredictionMap};
use mftyre::{MfInput, TyreParams, UseMode};
use rigsim::VirtualTyre;
use serde_json::json;
use std::path::PathBuf;
use std::time::Instant;
use tyre_msgs::{ModelStage, ModelState};

use crate::cmd_bench::percentile;

/// `tyrerig bench live-fit` arguments.
#[derive(Debug, clap::Args)]
pub struct LiveFitBench {
    /// A GS2MF log (e.g. from `tyrerig run --headless`).
    pub log: PathBuf,
    /// The run's true tyre (the virtual rig's `.tir`, or its brush tyre file): accuracy of the live and the offline model.
    #[arg(long)]
    pub truth: Option<PathBuf>,
    /// Also fit the log offline (as `tyrerig fit --folds 0`) and compare.
    #[arg(long)]
    pub offline: bool,
    /// Another run of the same tyre (e.g. another seed): coverage of the live model's predicted
    /// 95 % bands on its points, which the fit never saw.
    #[arg(long)]
    pub heldout: Option<PathBuf>,
    /// Worker threads per update (default: all cores).
    #[arg(long)]
    pub threads: Option<usize>,
    /// Print every update (wall time, slow stages) as it happens.
    #[arg(long)]
    pub verbose: bool,
    /// Write every figure as JSON too.
    #[arg(long)]
    pub json: Option<PathBuf>,
}

struct Update {
    wall_s: f64,
    state: ModelState,
}

pub fn run(args: &LiveFitBench) -> anyhow::Result<()> {
    let reader = mcaplog::LogReader::open(&args.log)?;
    let inputs = inputs_of_log(&reader).map_err(|e| anyhow::anyhow!("{}: {e}", args.log.display()))?;
    let fz0 = reader.metadata().get("procedure").and_then(|p| p.get("fz0_n")).and_then(|v| v.parse::<f64>().ok());
    drop(reader);
    let mut cfg = LiveFitConfig { fz0_n: fz0, ..LiveFitConfig::default() };
    if let Some(t) = args.threads {
        cfg.threads = t.max(1);
    }
    let mut core = LiveFit::new(cfg.clone());
    let mut updates: Vec<Update> = Vec::new();
    let mut end_s = 0.0f64;
    let total = Instant::now();
    for input in &inputs {
        if let Input::Sample(s) = input {
            end_s = s.header.stamp.as_secs_f64();
        }
        match feed(&mut core, input) {
            Trigger::Update => {
                let t = Instant::now();
                let state = core.update();
                let wall_s = t.elapsed().as_secs_f64();
                if args.verbose {
                    // A stage refitted from the data's start (new operating levels) is marked.
                    let cold = |stage: &str| {
                        core.latest()
                            .and_then(|r| r.stages.iter().find(|r| r.stage == stage))
                            .and_then(|r| r.notes.iter().find(|n| n.ends_with(mffit::stages::COLD_START_NOTE)))
                    };
                    let stages: Vec<String> = state
                        .stages
                        .iter()
                        .filter(|s| s.wall_s > 0.05)
                        .map(|s| {
                            let mark = cold(&s.stage).map_or(String::new(), |why| format!(" ({why})"));
                            format!("{} {:.2}s/{}it{mark}", s.stage, s.wall_s, s.iterations)
                        })
                        .collect();
                    let nrmse: Vec<String> = state
                        .stages
                        .iter()
                        .filter(|s| s.nrmse_pct.is_finite())
                        .map(|s| format!("{} {:.2}", s.stage, s.nrmse_pct))
                        .collect();
                    eprintln!(
                        "update {:>3} at {:>6.0} s, {:>3} segments: {wall_s:.3} s  {}\n    NRMSE %: {}",
                        state.update_index,
                        state.header.stamp.as_secs_f64(),
                        state.segments_used,
                        stages.join(", "),
                        nrmse.join(", ")
                    );
                }
                updates.push(Update { wall_s, state });
            }
            Trigger::Final | Trigger::None => {}
        }
    }
    let t = Instant::now();
    let state = core.finish();
    updates.push(Update { wall_s: t.elapsed().as_secs_f64(), state });
    let total_s = total.elapsed().as_secs_f64();
    let live = core.latest().context("the live fit never produced a model")?.clone();
    if let Some(w) = live.warnings.first().filter(|w| w.starts_with("final model")) {
        println!("{w}; final update {:.2} s", updates.last().map_or(f64::NAN, |u| u.wall_s));
    }

    // The updates after each sweep (the final one, at the procedure's end, is reported apart).
    let mut walls: Vec<f64> = updates.iter().filter(|u| !u.state.final_update).map(|u| u.wall_s).collect();
    walls.sort_by(f64::total_cmp);
    let (p50, p99, max) =
        (percentile(&walls, 0.5), percentile(&walls, 0.99), walls.last().copied().unwrap_or(f64::NAN));
    let sum: f64 = walls.iter().sum();
    println!(
        "live fit of {}: {} updates over {:.0} s of rig time; wall time of an update after a sweep: p50 {:.3} s, p99 {:.3} s, max {:.3} s; \
         sum {:.1} s ({:.1} s with feeding)",
        args.log.display(),
        walls.len(),
        end_s,
        p50,
        p99,
        max,
        sum,
        total_s
    );

    // When each stage became identified (and stayed so to the end).
    println!(
        "{:<18} {:>10} {:>10} {:>8} {:>10}  final status",
        "stage", "first fit", "identified", "update", "segments"
    );
    let mut timeline = Vec::new();
    let last = &updates.last().context("no update")?.state;
    for (i, st) in last.stages.iter().enumerate() {
        let status_at = |u: &Update| u.state.stages.get(i).map_or(ModelStage::WAITING, |s| s.status);
        let first_fit = updates.iter().find(|u| status_at(u) != ModelStage::WAITING);
        // The first update from which on the stage stays identified.
        let stays = updates.iter().rposition(|u| status_at(u) != ModelStage::IDENTIFIED).map_or(0, |k| k + 1);
        let ident = updates.get(stays).filter(|u| status_at(u) == ModelStage::IDENTIFIED);
        let t =
            |u: Option<&Update>| u.map_or("–".to_owned(), |u| format!("{:.0} s", u.state.header.stamp.as_secs_f64()));
        println!(
            "{:<18} {:>10} {:>10} {:>8} {:>10}  {}{}",
            st.stage,
            t(first_fit),
            t(ident),
            ident.map_or("–".into(), |u| u.state.update_index.to_string()),
            ident.map_or("–".into(), |u| u.state.segments_used.to_string()),
            ModelStage::status_name(st.status),
            if st.status_reason.is_empty() { String::new() } else { format!(" ({})", st.status_reason) }
        );
        timeline.push(json!({
            "stage": st.stage,
            "first_fit_rig_s": first_fit.map(|u| u.state.header.stamp.as_secs_f64()),
            "identified_rig_s": ident.map(|u| u.state.header.stamp.as_secs_f64()),
            "identified_update": ident.map(|u| u.state.update_index),
            "identified_segments": ident.map(|u| u.state.segments_used),
            "final_status": ModelStage::status_name(st.status),
            "final_reason": st.status_reason,
        }));
    }

    let truth = args.truth.as_deref().map(read_truth).transpose()?;
    let reference = truth.as_ref().map(|t| move |mode: UseMode, x: &MfInput| t.reference(mode, x));
    let accuracy = |fit: &mffit::FitResult| -> Vec<AccuracyRow> {
        reference.as_ref().map_or_else(Vec::new, |t| compare_with(t, &fit.params, &fit.range, &Support::of_fit(fit)))
    };
    let live_acc = accuracy(&live);
    let mut offline_json = serde_json::Value::Null;
    if args.offline {
        let data = mffit::logs::read_log(&args.log)?;
        let opts = mffit::FitOptions { folds: 0, threads: cfg.fit_options().threads, ..mffit::FitOptions::default() };
        let t = Instant::now();
        let offline = mffit::fit(&data, &opts)?;
        let offline_s = t.elapsed().as_secs_f64();
        let off_acc = accuracy(&offline);
        println!("offline fit of the same log (cold, --folds 0): {offline_s:.2} s");
        if !off_acc.is_empty() {
            println!("{:<14} {:>10} {:>10} {:>9}", "channel", "live %", "offline %", "live/off");
        }
        let mut rows = Vec::new();
        for (l, o) in live_acc.iter().zip(&off_acc) {
            let ratio = l.rms_pct_of_peak / o.rms_pct_of_peak;
            println!("{:<14} {:>10.3} {:>10.3} {:>9.3}", l.channel, l.rms_pct_of_peak, o.rms_pct_of_peak, ratio);
            rows.push(json!({"channel": l.channel, "live_pct": l.rms_pct_of_peak, "offline_pct": o.rms_pct_of_peak, "ratio": ratio}));
        }
        offline_json = json!({"wall_s": offline_s, "accuracy": rows});
    } else {
        for l in &live_acc {
            println!("{:<14} live model {:.3} % of peak RMS against the truth", l.channel, l.rms_pct_of_peak);
        }
    }
    let calibration_json = match reference.as_ref() {
        Some(t) => {
            let grid = grid_of(last);
            let maps = mffit::prediction::prediction_maps(&live, &grid);
            let support = Support::of_fit(&live);
            let score = |std: fn(&PredictionMap) -> &Vec<f64>| {
                let band: Vec<PredictionMap> =
                    maps.iter().map(|m| PredictionMap { std: std(m).clone(), ..m.clone() }).collect();
                mffit::calibration::calibrate(&band, &grid, live.nominal.r0_m, t, &support)
            };
            let param = score(|m| &m.std_param);
            let total = score(|m| &m.std);
            print_calibration("σ of the coefficients alone (delta method)", &param);
            print_calibration("σ with the form error", &total);
            json!({"param": param, "total": total, "tested_points": tested_points(&maps, &grid, live.nominal.r0_m, t)})
        }
        None => serde_json::Value::Null,
    };
    let mut coverage_json = serde_json::Value::Null;
    if let Some(h) = &args.heldout {
        let other = mffit::logs::read_log(h)?;
        let reference = reference.as_ref().map(|t| t as &ReferenceTyre<'_>);
        let rows = mffit::prediction::coverage(&live, &other, &cfg.fit_options(), reference);
        println!("predicted 95 % bands on {} (points the fit never saw):", h.display());
        for r in &rows {
            println!(
                "  {:<4} {:>6} points: {:>5.1} % of measured values in the band ±1.96·√(σ²+RMSE²){}; median σ {:.3}, RMSE {:.3}; {:.1} % within the repeat band ±{:.3} (predicted 95 %)",
                r.channel,
                r.points,
                r.measured_in_band_pct,
                r.truth_in_band_pct.map_or(String::new(), |p| format!(", {p:.1} % of true values in ±1.96·σ")),
                r.median_std,
                r.residual_rmse,
                r.measured_in_repeat_band_pct,
                r.repeat_band
            );
        }
        coverage_json = serde_json::to_value(&rows)?;
    }
    if let Some(path) = &args.json {
        let doc = json!({
            "log": args.log.display().to_string(),
            "updates": updates.len(),
            "rig_time_s": end_s,
            "update_wall_s": {"p50": p50, "p99": p99, "max": max, "sum": sum},
            "update_wall_all_s": updates.iter().map(|u| u.wall_s).collect::<Vec<_>>(),
            "identification": timeline,
            "live_accuracy": live_acc.iter().map(|a| json!({"channel": a.channel, "pct": a.rms_pct_of_peak})).collect::<Vec<_>>(),
            "offline": offline_json,
            "coverage": coverage_json,
            "calibration": calibration_json,
        });
        std::fs::write(path, serde_json::to_string_pretty(&doc)?).with_context(|| format!("{}", path.display()))?;
    }
    Ok(())
}

/// The envelope grid of a model state (its own axes).
fn grid_of(st: &ModelState) -> EnvelopeGrid {
    EnvelopeGrid {
        fz_n: st.grid_fz_n.clone(),
        slip_angle_deg: st.grid_slip_angle_deg.clone(),
        slip_ratio: st.grid_slip_ratio.clone(),
        camber_deg: st.grid_camber_deg.clone(),
        pressure_pa: st.grid_pressure_pa.clone(),
        speed_mps: st.grid_speed_mps,
    }
}

/// Every tested grid point of `maps` with the true value and the parts of σ (for analysis).
fn tested_points(
    maps: &[PredictionMap],
    grid: &EnvelopeGrid,
    r0_m: f64,
    truth: &ReferenceTyre<'_>,
) -> serde_json::Value {
    let mut out = Vec::new();
    for m in maps {
        for (i, x) in grid.inputs(m.channel, r0_m).iter().enumerate().filter(|(i, _)| !m.extrapolated[*i]) {
            out.push(json!({
                "channel": m.channel.tydex_name(),
                "fz_n": x.fz_n, "alpha_deg": x.alpha_rad.to_degrees(), "kappa": x.kappa,
                "camber_deg": x.gamma_rad.to_degrees(), "p_pa": x.p_pa,
                "truth": m.channel.channel().eval_reference(truth, x), "value": m.value[i],
                "std_param": m.std_param[i], "std_form": m.std_form[i],
            }));
        }
    }
    serde_json::Value::Array(out)
}

/// Prints how the final model's band of the mean (`what` σ) holds the true tyre, per channel.
fn print_calibration(what: &str, rows: &[Calibration]) {
    println!("band of the mean (value ± 1.96·σ), {what}, against the true tyre on the model state's grid:");
    for r in rows {
        let part = |b: &mffit::calibration::BandScore| {
            format!(
                "{:>4} points {:>5.1} % in band, median |error|/σ {:>6.2}, median σ {:.3}, median |error| {:.3}",
                b.points, b.in_band_pct, b.median_error_over_std, b.median_std, b.median_abs_error
            )
        };
        println!("  {:<4} tested envelope: {}", r.channel, part(&r.tested));
        println!("  {:<4} outside it:      {}", r.channel, part(&r.outside));
    }
}

/// The run's true tyre: a `.tir` (MF-Tyre) or a brush tyre file (`.toml`).
fn read_truth(path: &std::path::Path) -> anyhow::Result<VirtualTyre> {
    let tyre = if path.extension().is_some_and(|e| e.eq_ignore_ascii_case("tir")) {
        VirtualTyre::from(TyreParams::read_tir(path)?)
    } else {
        VirtualTyre::from(
            rigsim::brush::BrushParams::load(path).with_context(|| format!("--truth {}", path.display()))?,
        )
    };
    Ok(tyre)
}

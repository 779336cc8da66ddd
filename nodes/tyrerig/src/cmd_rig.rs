//! `tyrerig rig …`: the virtual rig's calibration against the thesis.
//!
//! `tyrerig rig calibrate` runs the comparison sweeps of Tables 3.6.2-H (FreeRolling) and
//! 3.6.2-I (BrkDrv) on the virtual rig with the default tyre, the warm-up check and the wear
//! check (see `rigsim::calibration`), prints the virtual rig's figures beside the thesis's, and
//! optionally writes them as JSON and plots each sweep. `--seeds N` runs it for N noise seeds
//! and prints every figure's min–max over them.

use std::path::{Path, PathBuf};

use anyhow::Context;
use clap::Subcommand;
use plotters::prelude::*;
use rigsim::calibration::{CalibrationReport, SweepAxis, SweepOutcome};
use rigsim::{Effects, RigConfig, TyreParams};

/// Virtual-rig subcommands.
#[derive(Debug, Subcommand)]
pub enum RigCmd {
    /// Run the thesis's comparison sweeps on the virtual rig and print its figures beside the thesis's
    Calibrate {
        /// Also write the table as JSON: {"freerolling": [...], "brkdrv": [...], ...}
        #[arg(long, value_name = "FILE")]
        json: Option<PathBuf>,
        /// The virtual rig's config file
        #[arg(long, value_name = "FILE", default_value = "launch-config/virtual_rig.toml")]
        config: PathBuf,
        /// Effects to switch on, overriding the config: none, all, or a comma list of
        /// transient, thermal, thermal_grip, wear, break_in, noise, chatter, rim_slip
        #[arg(long, value_name = "LIST")]
        effects: Option<String>,
        /// Write a PNG per comparison sweep (force vs slip, TRDTEMPC vs time) into this directory
        #[arg(long, value_name = "DIR")]
        plots: Option<PathBuf>,
        /// Also run the calibration for N noise seeds (the config's seed and the next N − 1) and
        /// print each figure's min–max over them; fails if any seed misses a criterion
        #[arg(long, value_name = "N", default_value_t = 1)]
        seeds: u64,
    },
}

/// Runs a `rig` subcommand.
pub fn run(cmd: RigCmd) -> anyhow::Result<()> {
    match cmd {
        RigCmd::Calibrate { json, config, effects, plots, seeds } => {
            calibrate(&config, effects.as_deref(), json.as_deref(), plots.as_deref(), seeds)
        }
    }
}

fn calibrate(
    config: &Path,
    effects: Option<&str>,
    json: Option<&Path>,
    plots: Option<&Path>,
    seeds: u64,
) -> anyhow::Result<()> {
    let mut cfg = RigConfig::load(config)?;
    if let Some(e) = effects {
        cfg.effects = Effects::parse(e).context("--effects")?;
    }
    let params =
        TyreParams::read_tir(&cfg.tyre_file).with_context(|| format!("tyre file {}", cfg.tyre_file.display()))?;
    let seeds = seeds.max(1);
    let reports = rigsim::calibration::run_calibration_seeds(&cfg, &params, cfg.seed..cfg.seed + seeds)?;
    let report = &reports[0];
    println!("Virtual rig calibration ({}; effects: {}; seed {})", config.display(), cfg.effects, cfg.seed);
    print!("{}", rigsim::calibration::format_report(report));
    let spread = (seeds > 1).then(|| rigsim::calibration::seed_spread(&reports));
    if let Some(sp) = &spread {
        println!();
        print!("{}", rigsim::calibration::format_spread(sp));
    }
    if let Some(path) = json {
        let o = &report.brkdrv_optimum;
        let value = serde_json::json!({
            "seed": report.seed,
            "freerolling": report.freerolling,
            "brkdrv": report.brkdrv,
            "brkdrv_variable_note": rigsim::calibration::BRKDRV_VARIABLE_NOTE,
            "brkdrv_optimum_th2": {
                "sweep": "variable",
                "low_rate_per_s": 0.10,
                "high_rate_per_s": 0.60,
                "threshold": rigsim::calibration::BRKDRV_OPTIMUM_THRESHOLD,
                "hysteresis_n": o.hysteresis_n,
                "peak_temp_c": o.peak_temp_c,
                "sweep_plus_cool_s": o.sweep_plus_cool_s,
                "sweep_s": o.sweep_s,
                "sliding_energy_kj": o.sliding_energy_kj,
                "graded": false,
                "thesis": o.thesis,
                "thesis_note": "the thesis figures are of BrkDrv_sw14 (10 % threshold), shown for comparison only",
                "misses_if_graded_as_variable": report.brkdrv_optimum_as_variable_misses,
            },
            "threshold_analysis": report.threshold_analysis,
            "warmup": report.warmup,
            "wear": report.wear,
            "investigation_wear": report.investigation_wear,
            "pass": report.pass(),
            "failures": report.failures,
            "seeds": spread.as_ref().map(|sp| serde_json::json!({
                "spread": sp,
                "per_seed": reports.iter().map(|r| serde_json::json!({
                    "seed": r.seed, "pass": r.pass(), "failures": r.failures,
                })).collect::<Vec<_>>(),
            })),
        });
        std::fs::write(path, serde_json::to_string_pretty(&value)? + "\n")
            .with_context(|| format!("writing {}", path.display()))?;
        println!("wrote {}", path.display());
    }
    if let Some(dir) = plots {
        write_plots(report, dir)?;
    }
    if let Some(sp) = &spread
        && !sp.failed_seeds.is_empty()
    {
        anyhow::bail!("calibration missed a criterion for seeds {:?}", sp.failed_seeds);
    }
    Ok(())
}

fn write_plots(report: &CalibrationReport, dir: &Path) -> anyhow::Result<()> {
    std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    for (name, axis, outcome) in &report.outcomes {
        let path = dir.join(format!("{name}.png"));
        plot_sweep(&path, name, *axis, outcome).map_err(|e| anyhow::anyhow!("plotting {}: {e}", path.display()))?;
        println!("wrote {}", path.display());
    }
    Ok(())
}

type PlotResult = Result<(), Box<dyn std::error::Error>>;

fn plot_sweep(path: &Path, name: &str, axis: SweepAxis, o: &SweepOutcome) -> PlotResult {
    let root = BitMapBackend::new(path, (1400, 560)).into_drawing_area();
    root.fill(&WHITE)?;
    let (left, right) = root.split_horizontally(700);
    let t_end = o.start_time_s + o.sweep_s;
    let sweep: Vec<(f64, f64)> = o
        .samples
        .iter()
        .filter(|s| s.runtime_s <= t_end + 0.3)
        .map(|s| match axis {
            SweepAxis::Lateral => (s.slipangl_deg, s.fyw_n),
            SweepAxis::Longitudinal => (s.longslip * 100.0, s.fx_n),
        })
        .collect();
    let (xl, yl) = match axis {
        SweepAxis::Lateral => ("SLIPANGL [deg]", "FYW [N]"),
        SweepAxis::Longitudinal => ("LONGSLIP [%]", "FX [N]"),
    };
    let (x0, x1) = bounds(sweep.iter().map(|p| p.0));
    let (y0, y1) = bounds(sweep.iter().map(|p| p.1));
    let mut c = ChartBuilder::on(&left)
        .caption(format!("{name}: hysteresis {:.0} N", o.hysteresis_n), ("sans-serif", 22))
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(60)
        .build_cartesian_2d(x0..x1, y0..y1)?;
    c.configure_mesh().x_desc(xl).y_desc(yl).draw()?;
    c.draw_series(LineSeries::new(sweep.iter().copied(), BLUE.stroke_width(1)))?;
    // Mark zero slip, where the hysteresis is read.
    c.draw_series(LineSeries::new([(0.0, y0), (0.0, y1)], BLACK.mix(0.4)))?;

    let temp: Vec<(f64, f64)> = o.samples.iter().map(|s| (s.runtime_s - o.start_time_s, s.trdtempc_c)).collect();
    let (tx0, tx1) = bounds(temp.iter().map(|p| p.0));
    let (_, ty1) = bounds(temp.iter().map(|p| p.1));
    let mut c = ChartBuilder::on(&right)
        .caption(
            format!("TRDTEMPC: peak {:.1} °C, sweep {:.1} s + cool {:.1} s", o.peak_temp_c, o.sweep_s, o.cool_s),
            ("sans-serif", 22),
        )
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(60)
        .build_cartesian_2d(tx0..tx1, 30.0..ty1.max(50.0))?;
    c.configure_mesh().x_desc("time from sweep start [s]").y_desc("TRDTEMPC [°C]").draw()?;
    c.draw_series(LineSeries::new(temp.iter().copied(), RED.stroke_width(1)))?;
    c.draw_series(LineSeries::new(
        [(tx0, rigsim::calibration::BASELINE_C), (tx1, rigsim::calibration::BASELINE_C)],
        BLACK.mix(0.4),
    ))?;
    c.draw_series(LineSeries::new([(o.sweep_s, 30.0), (o.sweep_s, ty1.max(50.0))], BLACK.mix(0.2)))?;
    root.present()?;
    Ok(())
}

/// Finite min/max with a little margin (and a non-empty range).
fn bounds(values: impl Iterator<Item = f64>) -> (f64, f64) {
    let (lo, hi) =
        values.filter(|v| v.is_finite()).fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| (a.min(v), b.max(v)));
    if !lo.is_finite() {
        return (0.0, 1.0);
    }
    let pad = ((hi - lo) * 0.05).max(1e-6);
    (lo - pad, hi + pad)
}

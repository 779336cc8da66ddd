//! `tyrerig run`: the main job — a procedure on the virtual rig, logged to MCAP, summarised.

use anyhow::Context as _;
use procedure::SweepStyle;
use std::path::PathBuf;
use suite::{Headless, McapSink, ProcedureChoice, RunSpec};

/// `tyrerig run [--procedure …] [--tyre …] [--load-index N] [--effects …] [--seed N] [--sweeps …] --out <log.mcap>`
#[derive(Debug, clap::Args)]
pub struct RunArgs {
    /// gs2mf | freerolling | brkdrv | staticlong | square-matrix
    #[arg(long, default_value = "gs2mf", value_parser = ProcedureChoice::parse)]
    pub procedure: ProcedureChoice,
    /// MF-Tyre 6.1 .tir file of the virtual tyre (default: the rig config's).
    #[arg(long)]
    pub tyre: Option<PathBuf>,
    /// ETRTO load index entered for the tyre (drives the loads; the thesis's tyre is 110).
    #[arg(long, default_value_t = 110)]
    pub load_index: u32,
    /// Virtual-rig effects: none | all | comma list of transient, thermal, thermal_grip, wear,
    /// break_in, noise, chatter, rim_slip (default: the rig config's).
    #[arg(long)]
    pub effects: Option<String>,
    /// Multiply the virtual tyre's wear rate (e.g. 5 to rehearse the wear alarm).
    #[arg(long)]
    pub wear_multiplier: Option<f64>,
    /// Noise seed of the virtual rig.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// variable (the thesis's shark-tooth sweeps) | continuous (continually variable rate).
    #[arg(long, default_value = "variable")]
    pub sweeps: SweepStyle,
    /// The MCAP log to write.
    #[arg(long, default_value = "out/run.mcap")]
    pub out: PathBuf,
    /// Also write the summary as JSON.
    #[arg(long)]
    pub summary_json: Option<PathBuf>,
    /// Run the cores directly (no DDS), as fast as the machine goes.
    #[arg(long)]
    pub headless: bool,
    /// launch-config directory (procedures, virtual_rig.toml, tyres).
    #[arg(long, default_value = "launch-config")]
    pub launch_config: PathBuf,
    /// No progress bar.
    #[arg(long)]
    pub quiet: bool,
}

pub fn spec_of(args: &RunArgs) -> RunSpec {
    let mut spec = RunSpec::new(&args.launch_config, args.procedure);
    spec.tyre = args.tyre.clone();
    spec.effects = args.effects.clone();
    spec.wear_multiplier = args.wear_multiplier;
    spec.seed = args.seed;
    spec.inputs.load_index = args.load_index;
    spec.inputs.sweeps = args.sweeps;
    spec
}

pub fn run(args: RunArgs) -> anyhow::Result<()> {
    let spec = spec_of(&args);
    let wall = std::time::Instant::now();
    let mut headless = Headless::new(&spec, thermal::ThermalConfig::default(), sequencer::SequencerConfig::default())?;
    let metadata = headless.metadata(&spec);
    let mut sink = McapSink::create(&args.out, "/rig", &metadata)?;
    let planned = headless.plan().estimate_total_s(&procedure::PauseModel::default());
    let bar = if args.quiet {
        indicatif::ProgressBar::hidden()
    } else {
        let b = indicatif::ProgressBar::new(1000);
        b.set_style(
            indicatif::ProgressStyle::with_template("{prefix} {bar:40.cyan/blue} {percent:>3}% rig {msg} eta {eta}")
                .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
        );
        b.set_prefix(format!("{} (planned ~{:.0} s rig time)", args.procedure.name(), planned));
        b
    };
    let summary = headless.run(&mut sink, &mut |progress, t| {
        bar.set_position((progress.clamp(0.0, 1.0) * 1000.0) as u64);
        bar.set_message(format!("{t:.0} s"));
    })?;
    bar.finish_and_clear();
    let messages = sink.finish()?;
    let wall_s = wall.elapsed().as_secs_f64();
    println!("{}", summary.table());
    println!(
        "log: {} ({} messages); rig time {:.0} s in {:.1} s wall = {:.0}x real time{}",
        args.out.display(),
        messages,
        summary.total_rig_time_s,
        wall_s,
        summary.total_rig_time_s / wall_s.max(1e-9),
        if args.headless { " (headless)" } else { "" }
    );
    if !summary.alarms.is_empty() {
        println!("alarms:");
        for a in &summary.alarms {
            println!("  {:>8.1} s  {:<5} {:<16} {}", a.rig_time_s, a.level, a.check, a.message);
        }
    }
    if let Some(path) = &args.summary_json {
        let mut json = serde_json::to_value(&summary)?;
        json["wall_time_s"] = serde_json::json!(wall_s);
        json["log"] = serde_json::json!(args.out.display().to_string());
        std::fs::write(path, serde_json::to_string_pretty(&json)?).with_context(|| format!("{}", path.display()))?;
    }
    if !summary.completed {
        anyhow::bail!("the procedure did not complete");
    }
    Ok(())
}

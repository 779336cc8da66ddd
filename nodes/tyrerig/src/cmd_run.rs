//! `tyrerig run`: the main job — a procedure on the virtual rig, logged to MCAP, summarised.

use anyhow::Context as _;
use procedure::SweepStyle;
use std::path::PathBuf;
use suite::{Headless, McapSink, ProcedureChoice, RunSpec};

/// Wall time the rig waits after discovering its readers before the first sample on a secured
/// domain [s] (plain: the rig node's default, 2 s).
const SECURED_START_DELAY_S: f64 = 5.0;

/// `tyrerig run [--procedure …] [--rig-config …] [--tyre …] [--load-index N] [--effects …] [--seed N] [--sweeps …] --out <log.mcap>`
#[derive(Debug, clap::Args)]
pub struct RunArgs {
    /// gs2mf | freerolling | brkdrv | staticlong | square-matrix, or a procedure file
    #[arg(long, default_value = "gs2mf", value_parser = ProcedureArg::parse)]
    pub procedure: ProcedureArg,
    /// The virtual rig's config (default: <launch-config>/virtual_rig.toml); e.g.
    /// launch-config/virtual_rig_brush_race.toml for the brush race tyre.
    #[arg(long)]
    pub rig_config: Option<PathBuf>,
    /// The virtual tyre's file, replacing the rig config's (a .tir, or a brush file when the
    /// config's tyre model is brush).
    #[arg(long)]
    pub tyre: Option<PathBuf>,
    /// ETRTO load index entered for the tyre (drives the loads; default 110, the thesis's tyre;
    /// a brush tyre brings its own rating and test pressures unless this is given).
    #[arg(long)]
    pub load_index: Option<u32>,
    /// Virtual-rig effects: none | all | comma list of transient, thermal, thermal_grip, wear,
    /// break_in, noise, chatter, rim_slip (default: the rig config's). Without `thermal` or
    /// `noise` the tread temperature never changes and the thermal gate holds on it as a stuck
    /// sensor (a headless run then ends with the fault named): `none,noise` for a clean tyre.
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
    /// Serve the run live to Foxglove on this port (default 8765): open
    /// `ws://<host>:<port>` in the Foxglove app with launch-config/foxglove/tyre-rig.json.
    #[arg(long, value_name = "PORT", num_args = 0..=1, default_missing_value = "8765")]
    pub foxglove: Option<u16>,
    /// Address the Foxglove server listens on (0.0.0.0 to serve other machines).
    #[arg(long, default_value = "127.0.0.1", requires = "foxglove")]
    pub foxglove_host: String,
    /// Commands Foxglove clients may send on procedure/command (e.g. PAUSE,RESUME); none by default.
    #[arg(long, value_delimiter = ',', requires = "foxglove")]
    pub foxglove_allow: Vec<String>,
    /// Over DDS: at most this many times real time (default: as fast as the nodes answer).
    #[arg(long, conflicts_with = "headless")]
    pub max_speed: Option<f64>,
    /// Run the live MF-Tyre 6.1 fit too (docs/live-fit.md): it publishes `model/state` after
    /// every completed sweep (recorded in the log) and writes the model at the end. Off by
    /// default: each update refits the staged model (~0.5–2 s of CPU).
    #[arg(long)]
    pub fit: bool,
    /// fixed (every step of the procedure) | adaptive (docs/adaptive-plan.md: the fixed parts,
    /// the other sweeps chosen by the live model's predicted variance reduction per rig second
    /// until the model is predicted as good as the full procedure's; turns on --fit; over DDS the
    /// sequencer decides with the fit node's `model/covariance`).
    #[arg(long, default_value = "fixed")]
    pub plan: sequencer::PlanKind,
    /// With --plan adaptive: stop a slot when its predicted error is within this factor of the
    /// full procedure's predicted error (default 1.15).
    #[arg(long)]
    pub target_ratio: Option<f64>,
    /// With --fit: the fitted .tir written at the end (default: the log's path with .tir).
    #[arg(long, requires = "fit")]
    pub fit_tir: Option<PathBuf>,
    /// With --fit: also write the fit report (report.md, fit.json, plots) into this directory.
    #[arg(long, requires = "fit")]
    pub fit_report: Option<PathBuf>,
    /// DDS Security (not with --headless): the SROS2 keystore holding the enclaves /rig/recorder,
    /// /rig/thermal, /rig/sequencer, /rig/quality, /rig/virtual_rig and /rig/run_watcher (and
    /// /rig/foxglove with --foxglove: a monitor, an operator with --foxglove-allow).
    #[arg(long, conflicts_with = "headless")]
    pub keystore: Option<PathBuf>,
}

/// A procedure by name, or a procedure file.
#[derive(Debug, Clone)]
pub enum ProcedureArg {
    Named(ProcedureChoice),
    File(PathBuf),
}

impl ProcedureArg {
    fn parse(s: &str) -> Result<Self, String> {
        match ProcedureChoice::parse(s) {
            Ok(c) => Ok(Self::Named(c)),
            Err(_) if s.ends_with(".toml") || s.contains('/') => Ok(Self::File(PathBuf::from(s))),
            Err(e) => Err(format!("{e}, or a procedure file (.toml)")),
        }
    }

    fn name(&self) -> String {
        match self {
            Self::Named(c) => c.name().to_owned(),
            Self::File(p) => {
                p.file_stem().map_or_else(|| p.display().to_string(), |s| s.to_string_lossy().into_owned())
            }
        }
    }
}

pub fn spec_of(args: &RunArgs) -> RunSpec {
    let choice = match &args.procedure {
        ProcedureArg::Named(c) => *c,
        ProcedureArg::File(_) => ProcedureChoice::Gs2mf,
    };
    let mut spec = RunSpec::new(&args.launch_config, choice);
    if let ProcedureArg::File(p) = &args.procedure {
        spec.procedure_file = p.clone();
    }
    if let Some(c) = &args.rig_config {
        spec.rig_config = c.clone();
    }
    spec.tyre = args.tyre.clone();
    spec.effects = args.effects.clone();
    spec.wear_multiplier = args.wear_multiplier;
    spec.seed = args.seed;
    if let Some(li) = args.load_index {
        spec.inputs.load_index = li;
        spec.use_tyre_ratings = false;
    }
    spec.inputs.sweeps = args.sweeps;
    spec
}

/// Where `--fit` writes the model.
fn fit_output(args: &RunArgs) -> livefit::output::ModelOutput {
    livefit::output::ModelOutput {
        tir: Some(args.fit_tir.clone().unwrap_or_else(|| args.out.with_extension("tir"))),
        report: args.fit_report.clone(),
    }
}

pub fn run(args: RunArgs) -> anyhow::Result<()> {
    if !args.headless {
        return run_dds(&args);
    }
    if args.foxglove.is_some() {
        anyhow::bail!("--foxglove serves the suite's DDS topics; a --headless run has none (drop --headless)");
    }
    let spec = spec_of(&args);
    let wall = std::time::Instant::now();
    let mut seq_cfg = sequencer::SequencerConfig { plan: args.plan, ..sequencer::SequencerConfig::default() };
    if let Some(r) = args.target_ratio {
        seq_cfg.adaptive.target_ratio = r;
    }
    seq_cfg.validate()?;
    let adaptive = args.plan == sequencer::PlanKind::Adaptive;
    let mut headless = Headless::new(&spec, thermal::ThermalConfig::default(), seq_cfg)?;
    if args.fit || adaptive {
        headless = headless.with_live_fit(livefit::LiveFitConfig::default());
    }
    let mut metadata = headless.metadata(&spec);
    if let Some(p) = metadata.get_mut("procedure") {
        p.insert("plan".into(), format!("{:?}", args.plan).to_lowercase());
    }
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
    if args.fit || adaptive {
        let result = headless.live_fit_result().context("--fit: the live fit produced no model")?;
        let files = livefit::output::write_model(result, &fit_output(&args))?;
        let mut walls = headless.live_fit_update_walls().to_vec();
        walls.sort_by(f64::total_cmp);
        println!(
            "live fit: {} updates, fit wall time per update p50 {:.3} s, p99 {:.3} s; wrote {}",
            walls.len(),
            crate::cmd_bench::percentile(&walls, 0.5),
            crate::cmd_bench::percentile(&walls, 0.99),
            files.iter().map(|f| f.display().to_string()).collect::<Vec<_>>().join(", ")
        );
    }
    println!("{}", summary.table());
    for c in &summary.adaptive {
        if c.sweep.is_empty() {
            println!("adaptive {:>7.0} s  slot {} closed: {}", c.rig_time_s, c.slot, c.reason);
        } else {
            println!("adaptive {:>7.0} s  slot {} {}: {}", c.rig_time_s, c.slot, c.sweep, c.reason);
        }
    }
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
    write_summary_json(&args, &summary, wall_s)?;
    if !summary.completed {
        anyhow::bail!("the procedure did not complete");
    }
    Ok(())
}

fn write_summary_json(args: &RunArgs, summary: &suite::RunSummary, wall_s: f64) -> anyhow::Result<()> {
    if let Some(path) = &args.summary_json {
        let mut json = serde_json::to_value(summary)?;
        json["wall_time_s"] = serde_json::json!(wall_s);
        json["log"] = serde_json::json!(args.out.display().to_string());
        std::fs::write(path, serde_json::to_string_pretty(&json)?).with_context(|| format!("{}", path.display()))?;
    }
    Ok(())
}

fn table(entries: &[(&str, toml::Value)]) -> toml::Table {
    entries.iter().map(|(k, v)| ((*k).to_owned(), v.clone())).collect()
}

fn path_value(p: &std::path::Path) -> anyhow::Result<toml::Value> {
    let abs = std::path::absolute(p).with_context(|| format!("{}: cannot resolve", p.display()))?;
    Ok(toml::Value::String(abs.display().to_string()))
}

/// The suite over DDS: virtual rig (lockstep clock), thermal gate, sequencer, quality (live
/// channels + monitor) and recorder, each its own participant in this process; the summary is
/// computed from the recorded log.
fn run_dds(args: &RunArgs) -> anyhow::Result<()> {
    use crate::launch::{NodeEntry, run_node};
    use node_runtime::{RosNode, RuntimeConfig, Shutdown, SuiteTopic};
    use toml::Value as V;

    let spec = spec_of(args);
    // The adaptive plan decides with the live fit's model: the fit node runs too.
    let adaptive = args.plan == sequencer::PlanKind::Adaptive;
    let fit = args.fit || adaptive;
    // The headless suite validates every input and gives the metadata the log carries.
    let headless = Headless::new(&spec, thermal::ThermalConfig::default(), sequencer::SequencerConfig::default())?;
    let mut metadata = headless.metadata(&spec);
    let planned = headless.plan().estimate_total_s(&procedure::PauseModel::default());
    let headless_fz0 = headless.plan().fz0_n;
    drop(headless);
    if let Some(sw) = metadata.get_mut("tyrerig") {
        sw.insert("mode".to_owned(), "dds".to_owned());
        sw.insert("log_time".to_owned(), "when the recorder received the message (wall clock), ns".to_owned());
    }
    // The monitor judges the loads against the tyre's own rating (as headless runs do), not
    // against the index the operator entered.
    let (rig_cfg, tyre) = suite::headless::rig_and_tyre(&spec)?;
    let declared_index = suite::headless::declared_load_index(&tyre);
    let inputs = suite::headless::run_inputs(&spec, &rig_cfg, &tyre);

    let mut rig = vec![
        ("rig_config", path_value(&spec.rig_config)?),
        ("seed", V::Integer(spec.seed as i64)),
        ("clock", V::String("lockstep".into())),
    ];
    if let Some(t) = &spec.tyre {
        rig.push(("tyre", path_value(t)?));
    }
    if let Some(e) = &spec.effects {
        rig.push(("effects", V::String(e.clone())));
    }
    // Thermal, sequencer, quality and recorder (and the fit) read the samples: none may miss the start.
    rig.push(("wait_for_subscribers", V::Integer(if fit { 5 } else { 4 })));
    if let Some(m) = args.max_speed {
        rig.push(("max_time_scale", V::Float(m)));
    }
    // Secured participants go on exchanging crypto tokens after they have discovered each other;
    // on a loaded 2-core machine a reader was still unable to decode for ~3 s after discovery and
    // missed the first 34 samples with the plain 2 s start delay.
    if args.keystore.is_some() {
        rig.push(("start_delay_s", V::Float(SECURED_START_DELAY_S)));
    }
    let mut sequencer = vec![
        ("procedure", path_value(&spec.procedure_file)?),
        ("load_index", V::Integer(i64::from(inputs.load_index))),
        ("pressures_bar", V::Array(inputs.pressures_bar.iter().map(|p| V::Float(*p)).collect())),
        ("sweeps", V::String(format!("{:?}", spec.inputs.sweeps).to_lowercase())),
        ("autostart", V::Boolean(true)),
        ("exit_when_done", V::Boolean(true)),
    ];
    // A brush race tyre: its own Fz0 and the rig's pressure range (down to 0.5 bar).
    if let Some(f) = inputs.fz0_n {
        sequencer.push(("fz0_n", V::Float(f)));
    }
    let envelope = table(&[
        ("min_pressure_bar", V::Float(inputs.limits.min_pressure_bar)),
        ("max_pressure_bar", V::Float(inputs.limits.max_pressure_bar)),
    ]);
    let mut core = vec![("envelope", V::Table(envelope))];
    if adaptive {
        core.push(("plan", V::String("adaptive".into())));
        if let Some(r) = args.target_ratio {
            core.push(("adaptive", V::Table(table(&[("target_ratio", V::Float(r))]))));
        }
    }
    sequencer.push(("core", V::Table(table(&core))));
    let md: toml::Table = metadata
        .iter()
        .map(|(k, m)| (k.clone(), V::Table(m.iter().map(|(a, b)| (a.clone(), V::String(b.clone()))).collect())))
        .collect();
    let recorder = vec![("output", path_value(&args.out)?), ("metadata", V::Table(md))];
    let mut quality = vec![("load_index", V::Integer(i64::from(declared_index)))];
    if tyre.brush_params().is_some() {
        // A brush tyre's own rating and tread, as the headless monitor gets them.
        quality.push(("fz0_n", V::Float(tyre.fnomin_n())));
        quality.push(("tread_new_mm", V::Float(rig_cfg.tyre.new_tread_depth_mm)));
        quality.push(("tread_min_mm", V::Float(rig_cfg.tyre.legal_min_tread_depth_mm)));
    }
    let mut nodes = vec![
        NodeEntry { name: "recorder".into(), kind: "recorder".into(), config: table(&recorder) },
        NodeEntry { name: "thermal".into(), kind: "thermal".into(), config: toml::Table::new() },
        NodeEntry { name: "sequencer".into(), kind: "sequencer".into(), config: table(&sequencer) },
        NodeEntry { name: "quality".into(), kind: "quality".into(), config: table(&quality) },
        NodeEntry { name: "virtual_rig".into(), kind: "virtual_rig".into(), config: table(&rig) },
    ];
    if fit {
        let out = fit_output(args);
        let mut output = vec![];
        if let Some(t) = &out.tir {
            output.push(("tir", path_value(t)?));
        }
        if let Some(r) = &out.report {
            output.push(("report", path_value(r)?));
        }
        let fit = vec![("fz0_n", V::Float(headless_fz0))];
        let config = table(&[("fit", V::Table(table(&fit))), ("output", V::Table(table(&output)))]);
        nodes.push(NodeEntry { name: "fit".into(), kind: "fit".into(), config });
    }
    if let Some(port) = args.foxglove {
        let foxglove = vec![
            ("host", V::String(args.foxglove_host.clone())),
            ("port", V::Integer(i64::from(port))),
            ("allow_commands", V::Array(args.foxglove_allow.iter().map(|c| V::String(c.clone())).collect())),
            ("procedure", path_value(&spec.procedure_file)?),
            ("load_index", V::Integer(i64::from(spec.inputs.load_index))),
            ("sweeps", V::String(format!("{:?}", spec.inputs.sweeps).to_lowercase())),
        ];
        let entry = NodeEntry { name: "foxglove".into(), kind: "foxglove".into(), config: table(&foxglove) };
        // Checked before anything starts, so a bad --foxglove-allow names itself at once.
        let c: foxglove_node::FoxgloveNodeConfig =
            toml::Value::Table(entry.config.clone()).try_into().map_err(|e| anyhow::anyhow!("--foxglove: {e}"))?;
        c.validate().map_err(|e| anyhow::anyhow!("--foxglove-allow: {e}"))?;
        // Before the rig starts, so a browser sees the run from its first sample.
        nodes.insert(0, entry);
    }
    let runtime =
        RuntimeConfig { security: args.keystore.clone().map(node_runtime::SecurityConfig::new), ..Default::default() };
    if let Some(sec) = &runtime.security {
        // Every participant's enclave must be there before any node starts.
        for name in nodes.iter().map(|n| n.name.as_str()).chain(["run_watcher"]) {
            sec.enclave_dir(name, &runtime.namespace).map_err(|e| match name {
                // Its default role (monitor) may not send the commands --foxglove-allow lets through.
                "foxglove" if !args.foxglove_allow.is_empty() => {
                    anyhow::anyhow!("{e}; --foxglove-allow sends commands, so give it `--role operator`")
                }
                _ => e.into(),
            })?;
        }
    }
    let wall = std::time::Instant::now();
    let rt = tokio::runtime::Builder::new_multi_thread().enable_all().build()?;
    let bar = if args.quiet { indicatif::ProgressBar::hidden() } else { indicatif::ProgressBar::new(1000) };
    bar.set_style(
        indicatif::ProgressStyle::with_template("{prefix} {bar:40.cyan/blue} {percent:>3}% rig {msg} eta {eta}")
            .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
    );
    bar.set_prefix(format!("{} over DDS (planned ~{planned:.0} s rig time)", args.procedure.name()));
    rt.block_on(async {
        // Two stops: the producers first, then (once their last messages are out) the recorder,
        // so the log holds everything the nodes published, the quality node's final verdicts too.
        let shutdown = Shutdown::new();
        let recorder_shutdown = Shutdown::new();
        shutdown.on_signals()?;
        let mut tasks = tokio::task::JoinSet::new();
        let mut recorder_task = None;
        for entry in nodes {
            let rt_cfg = runtime.clone();
            if entry.kind == "recorder" {
                let sd = recorder_shutdown.clone();
                recorder_task = Some(tokio::spawn(async move { run_node(&entry, &rt_cfg, sd).await }));
            } else {
                let sd = shutdown.clone();
                tasks.spawn(async move {
                    let r = run_node(&entry, &rt_cfg, sd).await;
                    (entry.name, r)
                });
            }
        }
        // Watch the procedure like a control room would, and end the run when it ends.
        let mut watcher = RosNode::new("run_watcher", &runtime)?;
        let states = watcher.subscription::<tyre_msgs::ProcedureState>(SuiteTopic::ProcedureState)?;
        let watch = async {
            use tyre_msgs::ProcedureState as PS;
            loop {
                let Ok((st, _)) = states.async_take().await else { continue };
                bar.set_position((st.progress.clamp(0.0, 1.0) * 1000.0) as u64);
                bar.set_message(format!("{:.0} s", st.elapsed_rig_time_s));
                if matches!(st.phase, PS::PHASE_COMPLETE | PS::PHASE_ABORTED | PS::PHASE_ESTOP) {
                    return st.phase;
                }
            }
        };
        let mut recorder_task = recorder_task.context("the node list has no recorder")?;
        let mut recorder_ended = false;
        let mut failed: Option<anyhow::Error> = None;
        tokio::pin!(watch);
        // A node that ends normally (the sequencer exits when its procedure is done) does not end
        // the run by itself: the watcher still has to see the final state, within a grace period.
        let mut grace: Option<std::pin::Pin<Box<tokio::time::Sleep>>> = None;
        loop {
            tokio::select! {
                _ = shutdown.wait() => break,
                // A recorder that stops (disk full, file refused) ends the run: nothing would be kept.
                r = &mut recorder_task => {
                    recorder_ended = true;
                    failed = Some(match r {
                        Ok(Err(e)) => e.context("node recorder"),
                        Ok(Ok(())) => anyhow::anyhow!("the recorder stopped before the procedure ended"),
                        Err(e) => anyhow::anyhow!("node recorder: {e}"),
                    });
                    break;
                }
                phase = &mut watch => {
                    tracing::info!(phase, "procedure ended; stopping the suite");
                    // Let the last messages reach the other nodes.
                    tokio::time::sleep(std::time::Duration::from_secs(1)).await;
                    break;
                }
                // A node that fails while the procedure runs ends the run at once (the recorder
                // still completes its file), instead of leaving the watcher waiting forever.
                Some(done) = tasks.join_next() => match done {
                    Ok((_, Ok(()))) => {
                        grace.get_or_insert_with(|| Box::pin(tokio::time::sleep(std::time::Duration::from_secs(5))));
                    }
                    Ok((name, Err(e))) => {
                        failed = Some(e.context(format!("node {name}")));
                        break;
                    }
                    Err(e) => {
                        failed = Some(anyhow::anyhow!("a node task failed: {e}"));
                        break;
                    }
                },
                _ = async { grace.as_mut().expect("guarded").await }, if grace.is_some() => {
                    tracing::warn!("a node ended but the procedure's final state never came; stopping the suite");
                    break;
                }
            }
        }
        shutdown.trigger();
        while let Some(done) = tasks.join_next().await {
            if let Ok((name, Err(e))) = done {
                failed.get_or_insert(e.context(format!("node {name}")));
            }
        }
        // The producers' final messages (reliable QoS) need a moment to arrive.
        tokio::time::sleep(std::time::Duration::from_millis(500)).await;
        recorder_shutdown.trigger();
        if !recorder_ended && let Ok(Err(e)) = recorder_task.await {
            failed.get_or_insert(e.context("node recorder"));
        }
        if let Some(e) = failed {
            return Err(e);
        }
        anyhow::Ok(())
    })?;
    bar.finish_and_clear();
    let wall_s = wall.elapsed().as_secs_f64();
    let log = mcaplog::LogReader::open(&args.out)?;
    let summary = suite::summary_from_log(&log, "/rig")?;
    println!("{}", summary.table());
    println!(
        "log: {} ({} messages); rig time {:.0} s in {:.1} s wall = {:.1}x real time (DDS, lockstep)",
        args.out.display(),
        log.messages().len(),
        summary.total_rig_time_s,
        wall_s,
        summary.total_rig_time_s / wall_s.max(1e-9)
    );
    for a in &summary.alarms {
        println!("  {:>8.1} s  {:<5} {:<16} {}", a.rig_time_s, a.level, a.check, a.message);
    }
    write_summary_json(args, &summary, wall_s)?;
    if !summary.completed {
        anyhow::bail!("the procedure did not complete");
    }
    Ok(())
}

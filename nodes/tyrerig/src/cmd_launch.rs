//! `tyrerig launch` and `tyrerig node`: bring up the nodes of a launch file.

use crate::launch::{LaunchFile, NodeKind, run_node};
use anyhow::Context as _;
use node_runtime::Shutdown;
use std::os::unix::process::CommandExt as _;
use std::path::PathBuf;

/// `tyrerig launch <file>`
#[derive(Debug, clap::Args)]
pub struct LaunchArgs {
    /// Launch file (TOML) listing the nodes.
    pub file: PathBuf,
    /// Run every node as its own OS process (`tyrerig node …`) instead of in this process.
    #[arg(long)]
    pub processes: bool,
}

/// `tyrerig node <name> --config <file>`
#[derive(Debug, clap::Args)]
pub struct NodeArgs {
    /// Node name in the launch file.
    pub name: String,
    /// Launch file holding the node's entry.
    #[arg(long)]
    pub config: PathBuf,
}

fn runtime() -> anyhow::Result<tokio::runtime::Runtime> {
    tokio::runtime::Builder::new_multi_thread().enable_all().build().context("cannot start the tokio runtime")
}

/// Runs one node of a launch file alone.
pub fn run_single(args: NodeArgs) -> anyhow::Result<()> {
    let file = LaunchFile::load(&args.config)?;
    let entry = file
        .node(&args.name)
        .with_context(|| {
            format!(
                "{}: no node named {:?} (nodes: {})",
                args.config.display(),
                args.name,
                file.nodes.iter().map(|n| n.name.as_str()).collect::<Vec<_>>().join(", ")
            )
        })?
        .clone();
    runtime()?.block_on(async move {
        let shutdown = Shutdown::new();
        shutdown.on_signals()?;
        run_node(&entry, &file.runtime, shutdown).await
    })
}

/// Runs every node of a launch file, in-process (one participant each) or as processes.
pub fn run_launch(args: LaunchArgs) -> anyhow::Result<()> {
    let file = LaunchFile::load(&args.file)?;
    if file.nodes.is_empty() {
        anyhow::bail!("{}: no [[node]] entries", args.file.display());
    }
    file.check_enclaves(&args.file)?;
    if args.processes {
        return run_processes(&args.file, &file);
    }
    runtime()?.block_on(async move {
        // Two stops: on Ctrl-C (or a failing node) the producers stop first, and the recorders
        // 0.5 s after the last of them, so the log keeps every producer's final messages.
        let shutdown = Shutdown::new();
        let recorder_shutdown = Shutdown::new();
        shutdown.on_signals()?;
        let mut producers = tokio::task::JoinSet::new();
        let mut recorders = tokio::task::JoinSet::new();
        for entry in file.nodes.clone() {
            let rt = file.runtime.clone();
            let is_recorder = entry.kind == NodeKind::Recorder.name();
            let sd = if is_recorder { recorder_shutdown.clone() } else { shutdown.clone() };
            let set = if is_recorder { &mut recorders } else { &mut producers };
            set.spawn(async move {
                let r = run_node(&entry, &rt, sd).await;
                (entry.name, r)
            });
        }
        // A node that fails brings the launch down (like `required` in ROS launch); a node that
        // finishes normally (e.g. a replay or a finite test pattern) lets the others go on.
        let mut first_err = None;
        let mut on_done = |done: Result<(String, anyhow::Result<()>), tokio::task::JoinError>| match done {
            Ok((name, Ok(()))) => tracing::info!(node = name, "node finished"),
            Ok((name, Err(e))) => {
                tracing::error!(node = name, "node failed: {e:#}");
                first_err.get_or_insert(e.context(format!("node {name}")));
                shutdown.trigger();
            }
            Err(e) => {
                first_err.get_or_insert(anyhow::anyhow!("node task panicked: {e}"));
                shutdown.trigger();
            }
        };
        let mut recorders_stopped = false;
        while !(producers.is_empty() && recorders.is_empty()) {
            if shutdown.is_triggered() && producers.is_empty() && !recorders_stopped {
                tokio::time::sleep(std::time::Duration::from_millis(500)).await;
                recorder_shutdown.trigger();
                recorders_stopped = true;
            }
            tokio::select! {
                Some(done) = producers.join_next(), if !producers.is_empty() => on_done(done),
                Some(done) = recorders.join_next(), if !recorders.is_empty() => on_done(done),
                _ = shutdown.wait(), if !shutdown.is_triggered() => {}
            }
        }
        first_err.map_or(Ok(()), Err)
    })
}

fn run_processes(path: &std::path::Path, file: &LaunchFile) -> anyhow::Result<()> {
    let exe = std::env::current_exe().context("cannot find the tyrerig executable")?;
    let mut children = Vec::new();
    for n in &file.nodes {
        // Each node in its own process group: a Ctrl-C in the terminal reaches this launcher
        // only, which stops the nodes in order (below) instead of all at once.
        let child = std::process::Command::new(&exe)
            .process_group(0)
            .arg("node")
            .arg(&n.name)
            .arg("--config")
            .arg(path)
            .spawn()
            .with_context(|| format!("cannot start node {}", n.name))?;
        children.push((n.name.clone(), n.kind == NodeKind::Recorder.name(), child));
    }
    // Forward SIGINT/SIGTERM to the children and wait for all of them: the producers first, the
    // recorders 0.5 s after the last producer has exited (so their final messages are logged).
    let term = std::sync::Arc::new(std::sync::atomic::AtomicBool::new(false));
    signal_hook::flag::register(signal_hook::consts::SIGINT, term.clone())?;
    signal_hook::flag::register(signal_hook::consts::SIGTERM, term.clone())?;
    let terminate = |c: &std::process::Child| {
        // SIGTERM lets each node finish its work (the recorder completes its file).
        if let Some(pid) = rustix::process::Pid::from_raw(c.id() as i32) {
            let _ = rustix::process::kill_process(pid, rustix::process::Signal::TERM);
        }
    };
    let mut failed = Vec::new();
    let mut producers_told = false;
    let mut recorders_told_at: Option<std::time::Instant> = None;
    let mut producers_gone_at: Option<std::time::Instant> = None;
    while !children.is_empty() {
        if term.load(std::sync::atomic::Ordering::Relaxed) {
            if !producers_told {
                children.iter().filter(|(_, rec, _)| !rec).for_each(|(_, _, c)| terminate(c));
                producers_told = true;
            }
            if children.iter().all(|(_, rec, _)| *rec) {
                let gone = *producers_gone_at.get_or_insert_with(std::time::Instant::now);
                if recorders_told_at.is_none() && gone.elapsed() >= std::time::Duration::from_millis(500) {
                    children.iter().for_each(|(_, _, c)| terminate(c));
                    recorders_told_at = Some(std::time::Instant::now());
                }
            }
        }
        let mut i = 0;
        while i < children.len() {
            if let Some(status) = children[i].2.try_wait()? {
                let (name, _, _) = children.remove(i);
                if !status.success() {
                    failed.push(format!("{name} ({status})"));
                }
            } else {
                i += 1;
            }
        }
        std::thread::sleep(std::time::Duration::from_millis(50));
    }
    if failed.is_empty() { Ok(()) } else { anyhow::bail!("nodes failed: {}", failed.join(", ")) }
}

//! `tyrerig launch` and `tyrerig node`: bring up the nodes of a launch file.

use crate::launch::{LaunchFile, run_node};
use anyhow::Context as _;
use node_runtime::Shutdown;
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
    if args.processes {
        return run_processes(&args.file, &file);
    }
    runtime()?.block_on(async move {
        let shutdown = Shutdown::new();
        shutdown.on_signals()?;
        let mut tasks = tokio::task::JoinSet::new();
        for entry in file.nodes.clone() {
            let (rt, sd) = (file.runtime.clone(), shutdown.clone());
            tasks.spawn(async move {
                let r = run_node(&entry, &rt, sd).await;
                (entry.name, r)
            });
        }
        // A node that fails brings the launch down (like `required` in ROS launch); a node that
        // finishes normally (e.g. a replay or a finite test pattern) lets the others go on.
        let mut first_err = None;
        while let Some(done) = tasks.join_next().await {
            match done {
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
            }
        }
        first_err.map_or(Ok(()), Err)
    })
}

fn run_processes(path: &std::path::Path, file: &LaunchFile) -> anyhow::Result<()> {
    let exe = std::env::current_exe().context("cannot find the tyrerig executable")?;
    let mut children = Vec::new();
    for n in &file.nodes {
        let child = std::process::Command::new(&exe)
            .arg("node")
            .arg(&n.name)
            .arg("--config")
            .arg(path)
            .spawn()
            .with_context(|| format!("cannot start node {}", n.name))?;
        children.push((n.name.clone(), child));
    }
    // Forward SIGINT/SIGTERM to the children and wait for all of them.
    let term = std::sync::Arc::new(std::sync::atomic::AtomicBool::new(false));
    signal_hook::flag::register(signal_hook::consts::SIGINT, term.clone())?;
    signal_hook::flag::register(signal_hook::consts::SIGTERM, term.clone())?;
    let mut failed = Vec::new();
    let mut forwarded = false;
    while !children.is_empty() {
        if term.load(std::sync::atomic::Ordering::Relaxed) && !forwarded {
            for (_, c) in &children {
                // SIGTERM lets each node finish its work (the recorder completes its file).
                if let Some(pid) = rustix::process::Pid::from_raw(c.id() as i32) {
                    let _ = rustix::process::kill_process(pid, rustix::process::Signal::TERM);
                }
            }
            forwarded = true;
        }
        let mut i = 0;
        while i < children.len() {
            if let Some(status) = children[i].1.try_wait()? {
                let (name, _) = children.remove(i);
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

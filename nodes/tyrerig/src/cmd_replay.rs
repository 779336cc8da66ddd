//! `tyrerig replay`: republish a recorded log onto its topics.

use anyhow::Context as _;
use node_runtime::{RosNode, RuntimeConfig, Shutdown};
use recorder::{LogReader, replay::ReplayOptions};
use std::path::PathBuf;

/// `tyrerig replay <file.mcap> [--speed X] [--topics a,b]`
#[derive(Debug, clap::Args)]
pub struct ReplayArgs {
    /// The MCAP log to replay.
    pub file: PathBuf,
    /// Time scale: 1 = as recorded, 10 = ten times faster.
    #[arg(long, default_value_t = 1.0, conflicts_with = "max_speed")]
    pub speed: f64,
    /// Publish as fast as DDS accepts, ignoring the recorded timing.
    #[arg(long)]
    pub max_speed: bool,
    /// Only these topics (relative names like `sample` or full names like `/rig/sample`).
    #[arg(long, value_delimiter = ',')]
    pub topics: Option<Vec<String>>,
    /// Namespace to publish under (default: the one the log was recorded under).
    #[arg(long)]
    pub namespace: Option<String>,
    /// DDS domain (default: ROS_DOMAIN_ID, else 0).
    #[arg(long)]
    pub domain_id: Option<u16>,
    /// Seconds to wait for subscribers to discover the replay before publishing.
    #[arg(long, default_value_t = 1.0)]
    pub discovery_wait_s: f64,
    /// Also serve the replay to Foxglove on this port (default 8765), with the plan of the
    /// procedure the log names; Foxglove clients may not send commands to a replay.
    #[arg(long, value_name = "PORT", num_args = 0..=1, default_missing_value = "8765")]
    pub foxglove: Option<u16>,
    /// Address the Foxglove server listens on (0.0.0.0 to serve other machines).
    #[arg(long, default_value = "127.0.0.1", requires = "foxglove")]
    pub foxglove_host: String,
}

/// The foxglove node's config for a replayed log: the plan from the procedure file and inputs
/// its metadata names, when that file is still there.
fn foxglove_config(args: &ReplayArgs, log: &LogReader, port: u16) -> foxglove_node::FoxgloveNodeConfig {
    let mut c = foxglove_node::FoxgloveNodeConfig { host: args.foxglove_host.clone(), port, ..Default::default() };
    let md = log.metadata();
    if let Some(file) = md.get("procedure").and_then(|p| p.get("file")).map(PathBuf::from) {
        if file.exists() {
            c.procedure = Some(file);
        } else {
            tracing::warn!("{}: procedure file {} not found; no plan view", args.file.display(), file.display());
        }
    }
    if let Some(li) = md.get("tyre").and_then(|t| t.get("load_index")).and_then(|v| v.parse().ok()) {
        c.load_index = li;
    }
    if let Some(style) = md.get("procedure").and_then(|p| p.get("sweeps")).and_then(|v| v.parse().ok()) {
        c.sweeps = style;
    }
    c
}

pub fn run(args: ReplayArgs) -> anyhow::Result<()> {
    let log = LogReader::open(&args.file)?;
    let namespace = args
        .namespace
        .clone()
        .or_else(|| log.metadata().get("tyrerig").and_then(|m| m.get("namespace")).cloned())
        .unwrap_or_else(|| RuntimeConfig::default().namespace);
    let runtime = RuntimeConfig { namespace, domain_id: args.domain_id, ..Default::default() };
    let opts = ReplayOptions {
        speed: if args.max_speed { None } else { Some(args.speed) },
        topics: args.topics.clone(),
        discovery_wait_s: args.discovery_wait_s,
        progress: true,
    };
    let rt = tokio::runtime::Builder::new_multi_thread().enable_all().build().context("tokio runtime")?;
    let foxglove = args.foxglove.map(|port| foxglove_config(&args, &log, port));
    let stats = rt.block_on(async {
        let shutdown = Shutdown::new();
        shutdown.on_signals()?;
        // The foxglove node first, so it discovers the replay's publishers within their wait.
        let server = match foxglove {
            Some(cfg) => {
                let node = RosNode::new("foxglove", &runtime)?;
                let sd = shutdown.clone();
                Some(tokio::spawn(async move { foxglove_node::run(node, cfg, sd).await }))
            }
            None => None,
        };
        let node = RosNode::new("replay", &runtime)?;
        let stats = recorder::replay::replay(node, &log, &opts, shutdown.clone()).await;
        if let Some(server) = server {
            // Let the last messages reach the clients, then stop the server with the replay.
            tokio::time::sleep(std::time::Duration::from_millis(500)).await;
            shutdown.trigger();
            server.await.context("foxglove node")??;
        }
        anyhow::Ok(stats?)
    })?;
    let factor = if stats.wall_s > 0.0 { stats.log_span_s / stats.wall_s } else { f64::INFINITY };
    println!(
        "replayed {} messages covering {:.2} s of log in {:.2} s wall ({:.1}× real time)",
        stats.messages, stats.log_span_s, stats.wall_s, factor
    );
    Ok(())
}

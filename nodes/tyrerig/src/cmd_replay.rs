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
    let stats = rt.block_on(async {
        let shutdown = Shutdown::new();
        shutdown.on_signals()?;
        let node = RosNode::new("replay", &runtime)?;
        anyhow::Ok(recorder::replay::replay(node, &log, &opts, shutdown).await?)
    })?;
    let factor = if stats.wall_s > 0.0 { stats.log_span_s / stats.wall_s } else { f64::INFINITY };
    println!(
        "replayed {} messages covering {:.2} s of log in {:.2} s wall ({:.1}× real time)",
        stats.messages, stats.log_span_s, stats.wall_s, factor
    );
    Ok(())
}

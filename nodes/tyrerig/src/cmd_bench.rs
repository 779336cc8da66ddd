//! `tyrerig bench`: speed figures measured through real DDS (benchmarks, never test assertions).

use anyhow::Context as _;
use futures::StreamExt;
use node_runtime::{RosNode, RuntimeConfig, Shutdown, SuiteTopic};
use std::time::{Duration, Instant, SystemTime};
use tyre_msgs::{RigSample, builtin_interfaces::Time, std_msgs::Header};

#[derive(Debug, clap::Subcommand)]
pub enum BenchCmd {
    /// One-way latency of RigSample between two nodes (two DDS participants) in this process.
    DdsLatency {
        #[arg(long, default_value_t = 1000.0)]
        rate_hz: f64,
        #[arg(long, default_value_t = 10.0)]
        seconds: f64,
        /// With DDS Security (a throwaway keystore; governance and roles as the suite's).
        #[arg(long)]
        secure: bool,
    },
    /// RigSamples published at a rate (0 = flat out) and recorded by the recorder node through DDS.
    Recorder {
        #[arg(long, default_value_t = 1000.0)]
        rate_hz: f64,
        #[arg(long, default_value_t = 10.0)]
        seconds: f64,
        #[arg(long, default_value = "out/bench_recorder.mcap")]
        out: std::path::PathBuf,
        /// With DDS Security (a throwaway keystore; governance and roles as the suite's).
        #[arg(long)]
        secure: bool,
    },
}

/// A keystore for one secured benchmark run, in the temp directory, removed afterwards.
#[derive(Debug)]
struct BenchKeystore(std::path::PathBuf);

impl Drop for BenchKeystore {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

/// The runtime config of the benchmark's nodes: plain, or secured with a fresh keystore whose
/// enclaves are the bench nodes' (publisher = rig, subscriber = monitor, recorder = recorder).
/// Prints how long the keystore took to make.
#[cfg(feature = "security")]
fn bench_config(secure: bool) -> anyhow::Result<(RuntimeConfig, Option<BenchKeystore>)> {
    use keystore::{EnclaveName, Keystore, Role};
    if !secure {
        return Ok((RuntimeConfig::default(), None));
    }
    let dir = BenchKeystore(std::env::temp_dir().join(format!("tyrerig-bench-keystore-{}", std::process::id())));
    let now_s = SystemTime::now().duration_since(SystemTime::UNIX_EPOCH).unwrap_or_default().as_secs() as i64;
    let t = Instant::now();
    let ks = Keystore::create(&dir.0, now_s)?;
    let ks_ms = t.elapsed().as_secs_f64() * 1e3;
    let t = Instant::now();
    let enclaves =
        [("/rig/bench_pub", Role::Rig), ("/rig/bench_sub", Role::Monitor), ("/rig/bench_recorder", Role::Recorder)];
    for (name, role) in enclaves {
        ks.create_enclave(&EnclaveName::parse(name)?, role, now_s)?;
    }
    let enclave_ms = t.elapsed().as_secs_f64() * 1e3 / enclaves.len() as f64;
    println!("keystore: CAs and governance in {ks_ms:.1} ms, {enclave_ms:.1} ms per enclave");
    let cfg = RuntimeConfig { security: Some(node_runtime::SecurityConfig::new(&dir.0)), ..Default::default() };
    Ok((cfg, Some(dir)))
}

#[cfg(not(feature = "security"))]
fn bench_config(secure: bool) -> anyhow::Result<(RuntimeConfig, Option<BenchKeystore>)> {
    if secure {
        anyhow::bail!(
            "--secure: this tyrerig was built without DDS Security (cargo build --release --features security)"
        );
    }
    Ok((RuntimeConfig::default(), None))
}

fn wall_time() -> Time {
    let d = SystemTime::now().duration_since(SystemTime::UNIX_EPOCH).unwrap_or_default();
    Time { sec: d.as_secs() as i32, nanosec: d.subsec_nanos() }
}

fn sample(seq: u64) -> RigSample {
    RigSample {
        header: Header { stamp: wall_time(), frame_id: "iso_w".into() },
        seq,
        runtime_s: seq as f64 * 1e-3,
        fyw_n: -6000.0,
        fzw_n: 6752.0,
        ..Default::default()
    }
}

fn percentile(sorted: &[f64], p: f64) -> f64 {
    if sorted.is_empty() {
        return f64::NAN;
    }
    sorted[((sorted.len() - 1) as f64 * p).round() as usize]
}

pub fn run(cmd: BenchCmd) -> anyhow::Result<()> {
    let rt = tokio::runtime::Builder::new_multi_thread().enable_all().build().context("tokio")?;
    let secure = matches!(cmd, BenchCmd::DdsLatency { secure: true, .. } | BenchCmd::Recorder { secure: true, .. });
    let (cfg, _keystore) = bench_config(secure)?;
    let security = if secure { "secured" } else { "plain" };
    match cmd {
        BenchCmd::DdsLatency { rate_hz, seconds, .. } => rt.block_on(async {
            let mut a = RosNode::new("bench_pub", &cfg)?;
            let mut b = RosNode::new("bench_sub", &cfg)?;
            let publisher = a.publisher::<RigSample>(SuiteTopic::RigSample)?;
            let sub = b.subscription::<RigSample>(SuiteTopic::RigSample)?;
            let total = (rate_hz * seconds) as u64;
            let receiver = tokio::spawn(async move {
                let mut lat_us = Vec::with_capacity(total as usize);
                let mut stream = Box::pin(sub.async_stream());
                let deadline = tokio::time::Instant::now() + Duration::from_secs_f64(seconds + 15.0);
                while (lat_us.len() as u64) < total {
                    let item = tokio::select! {
                        _ = tokio::time::sleep_until(deadline) => break,
                        item = stream.next() => item,
                    };
                    let Some(Ok((s, _))) = item else { continue };
                    if s.seq == u64::MAX {
                        continue; // discovery probes
                    }
                    let now = wall_time();
                    lat_us.push((now.as_nanos() as f64 - s.header.stamp.as_nanos() as f64) * 1e-3);
                }
                lat_us
            });
            // Wait for discovery with probes, then the timed stream.
            for _ in 0..30 {
                let _ = publisher.publish(RigSample { seq: u64::MAX, ..sample(0) });
                tokio::time::sleep(Duration::from_millis(100)).await;
            }
            let mut tick = tokio::time::interval(Duration::from_secs_f64(1.0 / rate_hz));
            for seq in 0..total {
                tick.tick().await;
                publisher.publish(sample(seq)).map_err(|e| anyhow::anyhow!("{e:?}"))?;
            }
            let mut lat = receiver.await?;
            lat.sort_by(f64::total_cmp);
            println!(
                "DDS one-way latency, RigSample at {rate_hz} Hz for {seconds} s, two {security} participants: \
                 received {}/{total}; p50 {:.0} us, p99 {:.0} us, max {:.0} us",
                lat.len(),
                percentile(&lat, 0.5),
                percentile(&lat, 0.99),
                lat.last().copied().unwrap_or(f64::NAN)
            );
            anyhow::Ok(())
        }),
        BenchCmd::Recorder { rate_hz, seconds, out, .. } => rt.block_on(async {
            let shutdown = Shutdown::new();
            let mut rec_cfg = recorder::RecorderConfig::to_file(&out);
            rec_cfg.topics = Some(vec!["sample".into()]);
            let rec_node = RosNode::new("bench_recorder", &cfg)?;
            let sd = shutdown.clone();
            let rec = tokio::spawn(async move { recorder::shell::run(rec_node, rec_cfg, sd).await });
            let mut a = RosNode::new("bench_pub", &cfg)?;
            let publisher = a.publisher::<RigSample>(SuiteTopic::RigSample)?;
            tokio::time::sleep(Duration::from_secs(3)).await;
            let start = Instant::now();
            let mut seq = 0u64;
            if rate_hz > 0.0 {
                let mut tick = tokio::time::interval(Duration::from_secs_f64(1.0 / rate_hz));
                while start.elapsed().as_secs_f64() < seconds {
                    tick.tick().await;
                    publisher.publish(sample(seq)).map_err(|e| anyhow::anyhow!("{e:?}"))?;
                    seq += 1;
                }
            } else {
                let mut blocked = 0u64;
                while start.elapsed().as_secs_f64() < seconds {
                    // Flat out, the reliable writer's history fills when the recorder falls
                    // behind; back off and retry (flow control), never drop.
                    while publisher.publish(sample(seq)).is_err() {
                        blocked += 1;
                        tokio::time::sleep(Duration::from_millis(1)).await;
                    }
                    seq += 1;
                    if seq.is_multiple_of(256) {
                        tokio::task::yield_now().await;
                    }
                }
                tracing::info!(blocked, "publisher back-offs");
            }
            let publish_s = start.elapsed().as_secs_f64();
            tokio::time::sleep(Duration::from_secs(2)).await;
            shutdown.trigger();
            let stats = rec.await??;
            let size = std::fs::metadata(&out).map(|m| m.len()).unwrap_or(0);
            println!(
                "recorder through {security} DDS, {}: published {seq} in {publish_s:.1} s, recorded {} \
                 ({:.0} msg/s, {:.2} MB/s payload, file {:.2} MB)",
                if rate_hz > 0.0 { format!("{rate_hz} Hz") } else { "flat out".into() },
                stats.messages,
                stats.messages as f64 / publish_s,
                stats.payload_bytes as f64 / publish_s / 1e6,
                size as f64 / 1e6
            );
            anyhow::Ok(())
        }),
    }
}

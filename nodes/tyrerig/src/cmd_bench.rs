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
    },
    /// RigSamples published at a rate (0 = flat out) and recorded by the recorder node through DDS.
    Recorder {
        #[arg(long, default_value_t = 1000.0)]
        rate_hz: f64,
        #[arg(long, default_value_t = 10.0)]
        seconds: f64,
        #[arg(long, default_value = "out/bench_recorder.mcap")]
        out: std::path::PathBuf,
    },
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
    let cfg = RuntimeConfig::default();
    match cmd {
        BenchCmd::DdsLatency { rate_hz, seconds } => rt.block_on(async {
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
                "DDS one-way latency, RigSample at {rate_hz} Hz for {seconds} s, two participants: \
                 received {}/{total}; p50 {:.0} us, p99 {:.0} us, max {:.0} us",
                lat.len(),
                percentile(&lat, 0.5),
                percentile(&lat, 0.99),
                lat.last().copied().unwrap_or(f64::NAN)
            );
            anyhow::Ok(())
        }),
        BenchCmd::Recorder { rate_hz, seconds, out } => rt.block_on(async {
            let shutdown = Shutdown::new();
            let mut rec_cfg = recorder::RecorderConfig::to_file(&out);
            rec_cfg.topics = Some(vec!["sample".into()]);
            let rec_node = RosNode::new("bench_recorder", &cfg)?;
            let sd = shutdown.clone();
            let rec = tokio::spawn(async move { recorder::shell::run(rec_node, rec_cfg, sd).await });
            let mut a = RosNode::new("bench_pub", &cfg)?;
            let publisher = a.publisher::<RigSample>(SuiteTopic::RigSample)?;
            tokio::time::sleep(Duration::from_secs(3)).await;
            // Every publish call is timed: the rig's publisher must never be held up.
            let mut call_us: Vec<f64> = Vec::with_capacity((rate_hz.max(1e5) * seconds) as usize);
            let mut refused = 0u64;
            let start = Instant::now();
            let mut seq = 0u64;
            let mut publish = |seq: u64, call_us: &mut Vec<f64>| {
                let t0 = Instant::now();
                let ok = publisher.publish(sample(seq)).is_ok();
                call_us.push(t0.elapsed().as_secs_f64() * 1e6);
                ok
            };
            if rate_hz > 0.0 {
                let mut tick = tokio::time::interval(Duration::from_secs_f64(1.0 / rate_hz));
                while start.elapsed().as_secs_f64() < seconds {
                    tick.tick().await;
                    if !publish(seq, &mut call_us) {
                        refused += 1; // the sample is gone: RigSample.seq shows the gap
                    }
                    seq += 1;
                }
            } else {
                while start.elapsed().as_secs_f64() < seconds {
                    if !publish(seq, &mut call_us) {
                        refused += 1;
                    }
                    seq += 1;
                    if seq.is_multiple_of(256) {
                        tokio::task::yield_now().await;
                    }
                }
            }
            let publish_s = start.elapsed().as_secs_f64();
            tokio::time::sleep(Duration::from_secs(2)).await;
            shutdown.trigger();
            let stats = rec.await??;
            let size = std::fs::metadata(&out).map(|m| m.len()).unwrap_or(0);
            call_us.sort_by(f64::total_cmp);
            let over_1ms = call_us.iter().filter(|&&u| u > 1000.0).count();
            // Read the log back: what it holds and what it says it lost must add up to what was
            // published (the first sample had seq 0).
            let log = mcaplog::LogReader::open(&out)?;
            let (in_log, _, seq_missing) = log.sample_seq_gaps("/rig/sample")?;
            let samples = log.typed::<RigSample>("/rig/sample")?;
            let first = samples.first().map_or(0, |(_, s)| s.seq);
            let after_last = samples.last().map_or(seq, |(_, s)| seq.saturating_sub(1).saturating_sub(s.seq));
            println!(
                "recorder through DDS, {}: published {seq} in {publish_s:.1} s ({:.0} msg/s), {refused} refused by the writer",
                if rate_hz > 0.0 { format!("{rate_hz} Hz") } else { "flat out".into() },
                seq as f64 / publish_s
            );
            println!(
                "  recorded {} ({:.0} msg/s, {:.2} MB/s payload, file {:.2} MB); the recorder reports {} lost, {} malformed",
                stats.messages,
                stats.messages as f64 / publish_s,
                stats.payload_bytes as f64 / publish_s / 1e6,
                size as f64 / 1e6,
                stats.lost,
                stats.malformed
            );
            println!(
                "  the log read back: {in_log} samples, {seq_missing} missing by RigSample.seq between the first ({first}) \
                 and the last; {} published after the last recorded; {} not in the log and not reported",
                after_last,
                seq.saturating_sub(in_log + stats.lost.max(seq_missing) + first + after_last)
            );
            println!(
                "  publish call: p50 {:.1} us, p99.9 {:.1} us, max {:.1} us; {over_1ms} of {} calls over 1 ms",
                percentile(&call_us, 0.5),
                percentile(&call_us, 0.999),
                call_us.last().copied().unwrap_or(f64::NAN),
                call_us.len()
            );
            anyhow::Ok(())
        }),
    }
}

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
    /// A rig sample's way through the whole suite: from the rig's write of a sample to the
    /// LiveChannels, the ThermalState and the RigSetpoint computed from it, with every node
    /// running (virtual rig in real time at --rate-hz, thermal, sequencer running FreeRolling,
    /// quality, recorder), in this process or --processes; or, with --attach, a suite already
    /// running elsewhere (other hosts: docs/deployment.md).
    SuiteLatency {
        #[arg(long, default_value_t = 1000)]
        rate_hz: u32,
        #[arg(long, default_value_t = 10.0)]
        seconds: f64,
        /// Every node its own OS process (`tyrerig launch --processes`).
        #[arg(long)]
        processes: bool,
        /// Start no nodes: only the probe, here, on the domain of `ROS_DOMAIN_ID`, timing a suite
        /// that runs elsewhere (the probe's host and the rig's must share a clock, e.g. by PTP,
        /// or the figures include their offset).
        #[arg(long, conflicts_with = "processes")]
        attach: bool,
        /// launch-config directory (virtual_rig.toml, procedures).
        #[arg(long, default_value = "launch-config")]
        launch_config: std::path::PathBuf,
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
    /// The foxglove node (its own process) serving RigSamples to N WebSocket clients: delivered
    /// msg/s, latency against a plain DDS subscriber, and the node's CPU.
    Foxglove {
        /// Foxglove protocol clients subscribed to /rig/sample.
        #[arg(long, default_value_t = 1)]
        clients: usize,
        /// Publish rate (0 = flat out, for throughput).
        #[arg(long, default_value_t = 1000.0)]
        rate_hz: f64,
        #[arg(long, default_value_t = 10.0)]
        seconds: f64,
        /// Port of the node's WebSocket server.
        #[arg(long, default_value_t = 18766)]
        port: u16,
    },
    /// The live fit (docs/live-fit.md) on a recorded run: wall time of every update, when each
    /// stage becomes identified; with --offline/--truth/--heldout its accuracy and band coverage.
    LiveFit(crate::bench_livefit::LiveFitBench),
    /// The adaptive plan (docs/adaptive-plan.md): rig time to accuracy against the true tyre,
    /// beside GS2MF and the Square Matrix, per tyre and seed.
    Adaptive(crate::bench_adaptive::AdaptiveBench),
    /// The doctor's diagnosis benchmark (docs/doctor-benchmark.md): known effects hidden in
    /// virtual-rig logs of 3 tyres × 3 plans, diagnosed; confusion, precision, recall, cuts.
    Doctor(crate::bench_doctor::DoctorBench),
}

/// Wall clock, ns since the UNIX epoch.
pub(crate) fn wall_ns() -> f64 {
    let d = SystemTime::now().duration_since(SystemTime::UNIX_EPOCH).unwrap_or_default();
    d.as_secs_f64() * 1e9
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

pub(crate) fn sample(seq: u64) -> RigSample {
    RigSample {
        header: Header { stamp: wall_time(), frame_id: "iso_w".into() },
        seq,
        runtime_s: seq as f64 * 1e-3,
        fyw_n: -6000.0,
        fzw_n: 6752.0,
        ..Default::default()
    }
}

pub(crate) fn percentile(sorted: &[f64], p: f64) -> f64 {
    if sorted.is_empty() {
        return f64::NAN;
    }
    sorted[((sorted.len() - 1) as f64 * p).round() as usize]
}

pub fn run(cmd: BenchCmd) -> anyhow::Result<()> {
    if let BenchCmd::LiveFit(args) = &cmd {
        return crate::bench_livefit::run(args);
    }
    if let BenchCmd::Adaptive(args) = &cmd {
        return crate::bench_adaptive::run(args);
    }
    if let BenchCmd::Doctor(args) = &cmd {
        return crate::bench_doctor::run(args);
    }
    let rt = tokio::runtime::Builder::new_multi_thread().enable_all().build().context("tokio")?;
    let secure = matches!(cmd, BenchCmd::DdsLatency { secure: true, .. } | BenchCmd::Recorder { secure: true, .. });
    let (cfg, _keystore) = bench_config(secure)?;
    let security = if secure { "secured" } else { "plain" };
    match cmd {
        // Returned above, before the DDS set-up it does not need.
        BenchCmd::LiveFit(args) => crate::bench_livefit::run(&args),
        BenchCmd::Adaptive(args) => crate::bench_adaptive::run(&args),
        BenchCmd::Doctor(args) => crate::bench_doctor::run(&args),
        BenchCmd::Foxglove { clients, rate_hz, seconds, port } => {
            rt.block_on(crate::bench_foxglove::run(clients, rate_hz, seconds, port))
        }
        BenchCmd::SuiteLatency { rate_hz, seconds, processes, attach, launch_config } => {
            let how = match (attach, processes) {
                (true, _) => SuiteStart::Attach,
                (false, true) => SuiteStart::Processes,
                (false, false) => SuiteStart::InProcess,
            };
            rt.block_on(suite_latency(rate_hz, seconds, how, &launch_config))
        }
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
            // Wait for discovery with probes, then the timed stream. A probe may fail before
            // discovery completes; that is what the probes wait out, so failures are only counted.
            let mut failed_probes = 0usize;
            for _ in 0..30 {
                if let Err(e) = publisher.publish(RigSample { seq: u64::MAX, ..sample(0) }) {
                    failed_probes += 1;
                    tracing::debug!(error = ?e, "discovery probe not published");
                }
                tokio::time::sleep(Duration::from_millis(100)).await;
            }
            if failed_probes > 0 {
                tracing::info!(failed_probes, "discovery probes not published (before discovery completed)");
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
            // Every publish call is timed: the rig's publisher must never be held up.
            let mut call_us: Vec<f64> = Vec::with_capacity((rate_hz.max(1e5) * seconds) as usize);
            let mut refused = 0u64;
            let start = Instant::now();
            let mut seq = 0u64;
            let publish = |seq: u64, call_us: &mut Vec<f64>| {
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
                "recorder through {security} DDS, {}: published {seq} in {publish_s:.1} s ({:.0} msg/s), {refused} refused by the writer",
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

fn nanos_now() -> i64 {
    SystemTime::now().duration_since(SystemTime::UNIX_EPOCH).map_or(0, |d| d.as_nanos() as i64)
}

/// The launch file of the latency bench: the whole suite, the rig in real time at `rate_hz`.
fn latency_launch_file(dir: &std::path::Path, rate_hz: u32, launch_config: &std::path::Path) -> anyhow::Result<String> {
    let abs = |p: std::path::PathBuf| -> anyhow::Result<String> {
        Ok(std::path::absolute(&p).with_context(|| format!("{}", p.display()))?.display().to_string())
    };
    let rig = abs(launch_config.join("virtual_rig.toml"))?;
    let procedure = abs(launch_config.join("procedures/gs2mf_freerolling.toml"))?;
    let out = abs(dir.join("latency.mcap"))?;
    Ok(format!(
        r#"
[[node]]
name = "recorder"
kind = "recorder"
[node.config]
output = "{out}"

[[node]]
name = "virtual_rig"
kind = "virtual_rig"
[node.config]
rig_config = "{rig}"
clock = "realtime"
publish_rate_hz = {rate_hz}
start_delay_s = 3.0

[[node]]
name = "thermal"
kind = "thermal"

[[node]]
name = "sequencer"
kind = "sequencer"
[node.config]
procedure = "{procedure}"
autostart = true

[[node]]
name = "quality"
kind = "quality"
"#
    ))
}

/// How `bench suite-latency` gets its suite.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum SuiteStart {
    /// Every node a participant of this process.
    InProcess,
    /// `tyrerig launch --processes`.
    Processes,
    /// Already running elsewhere: only the probe runs here.
    Attach,
}

/// Receive times (ns, wall clock) of the messages computed from each sample, keyed by the
/// sample's stamp (every derived message carries it).
#[derive(Default)]
struct Arrivals {
    sample_written_ns: std::collections::HashMap<u64, i64>,
    /// The samples themselves at the probe: (stamp, arrival).
    sample_ns: Vec<(u64, i64)>,
    live_ns: Vec<(u64, i64)>,
    thermal_ns: Vec<(u64, i64)>,
    setpoint_ns: Vec<(u64, i64)>,
}

async fn suite_latency(
    rate_hz: u32,
    seconds: f64,
    how: SuiteStart,
    launch_config: &std::path::Path,
) -> anyhow::Result<()> {
    use tyre_msgs::{LiveChannels, RigSetpoint, ThermalState};
    let dir = std::env::temp_dir().join(format!("tyrerig-latency-{}", std::process::id()));
    let shutdown = Shutdown::new();
    let mut child = None;
    let mut tasks = tokio::task::JoinSet::new();
    let runtime = if how == SuiteStart::Attach {
        node_runtime::RuntimeConfig::default()
    } else {
        std::fs::create_dir_all(&dir)?;
        let launch_path = dir.join("latency.toml");
        std::fs::write(&launch_path, latency_launch_file(&dir, rate_hz, launch_config)?)?;
        let file = crate::launch::LaunchFile::load(&launch_path)?;
        if how == SuiteStart::Processes {
            let exe = std::env::current_exe().context("cannot find the tyrerig executable")?;
            child = Some(
                std::process::Command::new(exe)
                    .arg("launch")
                    .arg(&launch_path)
                    .arg("--processes")
                    .spawn()
                    .context("cannot start the suite")?,
            );
        } else {
            for entry in file.nodes.clone() {
                let (rt_cfg, sd) = (file.runtime.clone(), shutdown.clone());
                tasks.spawn(async move { crate::launch::run_node(&entry, &rt_cfg, sd).await });
            }
        }
        file.runtime
    };
    // The probe: its own participant, like a control room's.
    let mut probe = RosNode::new("latency_probe", &runtime)?;
    let samples = probe.subscription::<RigSample>(SuiteTopic::RigSample)?;
    let live = probe.subscription::<LiveChannels>(SuiteTopic::LiveChannels)?;
    let thermal = probe.subscription::<ThermalState>(SuiteTopic::ThermalState)?;
    let setpoints = probe.subscription::<RigSetpoint>(SuiteTopic::RigSetpoint)?;
    let (mut s_st, mut l_st, mut t_st, mut p_st) = (
        Box::pin(samples.async_stream()),
        Box::pin(live.async_stream()),
        Box::pin(thermal.async_stream()),
        Box::pin(setpoints.async_stream()),
    );
    let mut a = Arrivals::default();
    let mut started: Option<tokio::time::Instant> = None;
    let give_up = tokio::time::Instant::now() + Duration::from_secs(60);
    loop {
        if started.is_some_and(|t| t.elapsed().as_secs_f64() >= seconds) || tokio::time::Instant::now() > give_up {
            break;
        }
        tokio::select! {
            Some(Ok((s, info))) = s_st.next() => {
                started.get_or_insert_with(tokio::time::Instant::now);
                // When the rig wrote it (DDS source timestamp, same host clock).
                let written = info.source_timestamp().map_or_else(nanos_now, |t| t.to_nanos());
                a.sample_written_ns.insert(s.header.stamp.as_nanos(), written);
                a.sample_ns.push((s.header.stamp.as_nanos(), nanos_now()));
            }
            Some(Ok((m, _))) = l_st.next() => a.live_ns.push((m.header.stamp.as_nanos(), nanos_now())),
            Some(Ok((m, _))) = t_st.next() => a.thermal_ns.push((m.header.stamp.as_nanos(), nanos_now())),
            Some(Ok((m, _))) = p_st.next() => a.setpoint_ns.push((m.header.stamp.as_nanos(), nanos_now())),
            _ = tokio::time::sleep(Duration::from_millis(100)) => {}
        }
    }
    shutdown.trigger();
    if let Some(mut c) = child {
        if let Some(pid) = rustix::process::Pid::from_raw(c.id() as i32) {
            let _ = rustix::process::kill_process(pid, rustix::process::Signal::INT);
        }
        let _ = c.wait();
    }
    while tasks.join_next().await.is_some() {}
    let n_samples = a.sample_written_ns.len();
    let how = match how {
        SuiteStart::InProcess => format!("rig at {rate_hz} Hz in real time, every node in one process"),
        SuiteStart::Processes => format!("rig at {rate_hz} Hz in real time, every node its own process"),
        SuiteStart::Attach => "a suite running elsewhere".to_owned(),
    };
    println!("suite latency, {how}, {seconds} s: {n_samples} samples");
    if n_samples == 0 {
        anyhow::bail!("no rig sample arrived within 60 s");
    }
    for (what, arrivals) in [
        ("sample -> this probe", &a.sample_ns),
        ("sample -> LiveChannels (quality node)", &a.live_ns),
        ("sample -> ThermalState (thermal node)", &a.thermal_ns),
        ("sample -> RigSetpoint answering it (sequencer)", &a.setpoint_ns),
    ] {
        let mut lat_us: Vec<f64> = arrivals
            .iter()
            .filter_map(|(stamp, at)| a.sample_written_ns.get(stamp).map(|w| (at - w) as f64 * 1e-3))
            .collect();
        lat_us.sort_by(f64::total_cmp);
        println!(
            "  {what:<48} {:>6} matched: p50 {:>7.0} us, p99 {:>7.0} us, max {:>7.0} us",
            lat_us.len(),
            percentile(&lat_us, 0.5),
            percentile(&lat_us, 0.99),
            lat_us.last().copied().unwrap_or(f64::NAN)
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
    Ok(())
}

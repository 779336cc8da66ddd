//! `tyrerig bench foxglove`: what serving the suite to Foxglove costs, measured through real DDS
//! and real WebSocket connections on this machine.
//!
//! The foxglove node runs as its own process (`tyrerig node foxglove`), so its CPU time is read
//! from `/proc/<pid>/stat`; this process publishes RigSamples stamped with the wall clock, holds
//! a plain DDS subscriber (the latency DDS alone adds) and N Foxglove protocol clients.

use anyhow::Context as _;
use futures::{SinkExt as _, StreamExt as _};
use node_runtime::{RosNode, RuntimeConfig, SuiteTopic};
use std::time::{Duration, Instant};
use tokio_tungstenite::tungstenite::{Message, client::IntoClientRequest as _, http::HeaderValue};
use tyre_msgs::RigSample;

/// What one WebSocket client saw.
#[derive(Debug, Default)]
struct ClientTally {
    messages: u64,
    bytes: u64,
    latency_us: Vec<f64>,
}

/// Connects a Foxglove protocol client, subscribes to `/rig/sample` and counts what arrives
/// until `until`. Latency = receive time − the sample's wall-clock stamp.
async fn client(url: String, until: tokio::time::Instant) -> anyhow::Result<ClientTally> {
    let mut req = url.as_str().into_client_request()?;
    req.headers_mut().insert("sec-websocket-protocol", HeaderValue::from_static("foxglove.sdk.v1"));
    let (mut ws, _) = tokio_tungstenite::connect_async(req).await.context("connect")?;
    let mut tally = ClientTally::default();
    let mut subscribed = false;
    loop {
        let msg = tokio::select! {
            _ = tokio::time::sleep_until(until) => break,
            m = ws.next() => match m { Some(m) => m?, None => break },
        };
        match msg {
            Message::Text(text) if !subscribed => {
                let v: serde_json::Value = serde_json::from_str(&text)?;
                if v["op"] == "advertise"
                    && let Some(ch) =
                        v["channels"].as_array().and_then(|a| a.iter().find(|c| c["topic"] == "/rig/sample"))
                {
                    let sub =
                        serde_json::json!({"op": "subscribe", "subscriptions": [{"id": 1, "channelId": ch["id"]}]});
                    ws.send(Message::Text(sub.to_string().into())).await?;
                    subscribed = true;
                }
            }
            Message::Binary(b) if b.first() == Some(&1) && b.len() > 13 + 12 => {
                // opcode 1 = message data: u32 subscription, u64 log time, then the CDR payload.
                let cdr = &b[13..];
                let sec = i32::from_le_bytes(cdr[4..8].try_into()?);
                let nanosec = u32::from_le_bytes(cdr[8..12].try_into()?);
                let stamp_ns = f64::from(sec) * 1e9 + f64::from(nanosec);
                tally.latency_us.push((super::cmd_bench::wall_ns() - stamp_ns) * 1e-3);
                tally.messages += 1;
                tally.bytes += b.len() as u64;
            }
            _ => {}
        }
    }
    Ok(tally)
}

/// utime + stime of a process [s].
fn cpu_s(pid: u32) -> anyhow::Result<f64> {
    let stat = std::fs::read_to_string(format!("/proc/{pid}/stat"))?;
    // Fields after the command name (which may hold spaces) start at ") ".
    let rest = stat.rsplit_once(") ").context("stat format")?.1;
    let f: Vec<&str> = rest.split_whitespace().collect();
    let ticks: f64 = f[11].parse::<f64>()? + f[12].parse::<f64>()?;
    Ok(ticks / 100.0) // USER_HZ is 100 on Linux
}

pub async fn run(clients: usize, rate_hz: f64, seconds: f64, port: u16) -> anyhow::Result<()> {
    let dir = tempfile_dir()?;
    let launch = dir.join("bench_foxglove.toml");
    std::fs::write(
        &launch,
        format!(
            "[[node]]\nname = \"foxglove\"\nkind = \"foxglove\"\n[node.config]\nport = {port}\nmessage_backlog = 1024\n"
        ),
    )?;
    let exe = std::env::current_exe()?;
    let mut child = std::process::Command::new(exe)
        .args(["node", "foxglove", "--config"])
        .arg(&launch)
        .spawn()
        .context("start the foxglove node")?;
    let pid = child.id();
    let result = measure(clients, rate_hz, seconds, port, pid).await;
    if let Some(p) = rustix::process::Pid::from_raw(pid as i32) {
        let _ = rustix::process::kill_process(p, rustix::process::Signal::TERM);
    }
    let _ = child.wait();
    let _ = std::fs::remove_dir_all(&dir);
    result
}

fn tempfile_dir() -> anyhow::Result<std::path::PathBuf> {
    let d = std::env::temp_dir().join(format!("tyrerig-bench-foxglove-{}", std::process::id()));
    std::fs::create_dir_all(&d)?;
    Ok(d)
}

async fn measure(clients: usize, rate_hz: f64, seconds: f64, port: u16, pid: u32) -> anyhow::Result<()> {
    let cfg = RuntimeConfig::default();
    let mut pub_node = RosNode::new("bench_pub", &cfg)?;
    let mut sub_node = RosNode::new("bench_dds_sub", &cfg)?;
    let publisher = pub_node.publisher::<RigSample>(SuiteTopic::RigSample)?;
    let sub = sub_node.subscription::<RigSample>(SuiteTopic::RigSample)?;
    // Discovery (the node's participant and ours) before the clients and the timed stream.
    tokio::time::sleep(Duration::from_secs(3)).await;
    let url = format!("ws://127.0.0.1:{port}");
    let warmup = Duration::from_secs(1);
    let until = tokio::time::Instant::now() + warmup + Duration::from_secs_f64(seconds) + Duration::from_millis(500);
    let tasks: Vec<_> = (0..clients).map(|_| tokio::spawn(client(url.clone(), until))).collect();
    let dds = tokio::spawn(async move {
        let mut lat = Vec::new();
        let mut stream = Box::pin(sub.async_stream());
        loop {
            let item = tokio::select! {
                _ = tokio::time::sleep_until(until) => break,
                item = stream.next() => item,
            };
            if let Some(Ok((s, _))) = item {
                lat.push((super::cmd_bench::wall_ns() - s.header.stamp.as_nanos() as f64) * 1e-3);
            }
        }
        lat
    });
    tokio::time::sleep(warmup).await;
    let cpu0 = cpu_s(pid)?;
    let start = Instant::now();
    let mut seq = 0u64;
    if rate_hz > 0.0 {
        let mut tick = tokio::time::interval(Duration::from_secs_f64(1.0 / rate_hz));
        while start.elapsed().as_secs_f64() < seconds {
            tick.tick().await;
            publisher.publish(super::cmd_bench::sample(seq)).map_err(|e| anyhow::anyhow!("{e:?}"))?;
            seq += 1;
        }
    } else {
        while start.elapsed().as_secs_f64() < seconds {
            // Flat out with flow control: back off when the reliable history is full.
            while publisher.publish(super::cmd_bench::sample(seq)).is_err() {
                tokio::time::sleep(Duration::from_millis(1)).await;
            }
            seq += 1;
            if seq.is_multiple_of(256) {
                tokio::task::yield_now().await;
            }
        }
    }
    let wall = start.elapsed().as_secs_f64();
    let cpu = cpu_s(pid)? - cpu0;
    let mut all_lat = Vec::new();
    let mut per_client = Vec::new();
    for t in tasks {
        let tally = t.await??;
        per_client.push(tally.messages);
        all_lat.extend(tally.latency_us);
    }
    let mut dds_lat = dds.await?;
    all_lat.sort_by(f64::total_cmp);
    dds_lat.sort_by(f64::total_cmp);
    let p = super::cmd_bench::percentile;
    let rate = if rate_hz > 0.0 { format!("{rate_hz} Hz") } else { "flat out".to_owned() };
    println!(
        "foxglove node, RigSample {rate} for {seconds} s to {clients} client(s): published {seq} ({:.0} msg/s); \
         per client received {per_client:?} ({:.0} msg/s each, {:.0} msg/s in all)",
        seq as f64 / wall,
        per_client.iter().sum::<u64>() as f64 / clients.max(1) as f64 / wall,
        per_client.iter().sum::<u64>() as f64 / wall,
    );
    println!(
        "latency publish -> Foxglove client: p50 {:.0} us, p99 {:.0} us; publish -> plain DDS subscriber: \
         p50 {:.0} us, p99 {:.0} us ({} samples)",
        p(&all_lat, 0.5),
        p(&all_lat, 0.99),
        p(&dds_lat, 0.5),
        p(&dds_lat, 0.99),
        dds_lat.len()
    );
    println!(
        "foxglove node process CPU: {cpu:.2} s in {wall:.1} s = {:.1} % of one core ({} cores here)",
        100.0 * cpu / wall,
        std::thread::available_parallelism().map(|n| n.get()).unwrap_or(0)
    );
    Ok(())
}

//! A reliable reader killed without leaving (SIGKILL) costs the other readers nothing.
//!
//! The killed reader's participant stays matched until its lease ends (~50 s in RustDDS), and
//! its reader never acknowledges again. RustDDS 0.15.1 kept waiting for it: the writer's send
//! window (8,192 samples) filled with samples only the dead reader had not acknowledged, and
//! from then on every write failed, for every reader. The vendored RustDDS makes such a reader
//! inactive after 2 s without an ACKNACK (vendor/rustdds/PATCHES.md, patch 3), so the writer
//! goes on for the others. Without that patch this test fails: at 2,000 samples/s the window
//! fills ~4 s after the kill and the writer refuses thousands of samples.
//!
//! The dead reader is a child process: this test binary run again with `DEAD_READER_CHILD` set,
//! where `dead_reader_child` subscribes, says when it has a sample, and takes samples until it
//! is killed. Like every DDS test here it runs inside `scripts/netns-run`.

use futures::StreamExt;
use node_runtime::{RosNode, RuntimeConfig, SuiteTopic};
use std::{
    io::{BufRead, BufReader},
    process::{Command, Stdio},
    sync::{Arc, Mutex},
    time::Duration,
};
use tyre_msgs::{RigSample, std_msgs::Header};

const CHILD_ENV: &str = "DEAD_READER_CHILD";
const READY: &str = "DEAD_READER_READY";
/// Samples per second: the default send window (8,192) lasts ~4 s with a dead reader in it,
/// twice the time the patched writer gives a silent reader.
const RATE_PER_MS: u64 = 2;
/// How long the writer goes on after the kill.
const AFTER_KILL: Duration = Duration::from_secs(12);

fn test_config() -> RuntimeConfig {
    let cfg = RuntimeConfig::default();
    let domain = cfg.resolved_domain_id().expect("ROS_DOMAIN_ID must be a valid domain id");
    assert_ne!(domain, 0, "DDS tests run on a non-zero ROS_DOMAIN_ID inside scripts/netns-run");
    cfg
}

fn sample(seq: u64) -> RigSample {
    RigSample { header: Header::iso_w(seq as f64 * 0.001), seq, runtime_s: seq as f64 * 0.001, ..Default::default() }
}

/// The reader to be killed (runs only in the child process).
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn dead_reader_child() -> anyhow::Result<()> {
    if std::env::var_os(CHILD_ENV).is_none() {
        return Ok(());
    }
    let mut node = RosNode::new("test_dead_reader_recorder", &test_config())?;
    // A recorder's reader, as in the suite.
    let subscription = node.recording_subscription::<RigSample>(SuiteTopic::RigSample)?;
    let mut stream = Box::pin(subscription.async_stream());
    let mut ready = false;
    while let Some(item) = stream.next().await {
        item.map_err(|e| anyhow::anyhow!("{e:?}"))?;
        if !ready {
            println!("{READY}");
            ready = true;
        }
    }
    Ok(())
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_killed_reader_costs_the_other_readers_nothing() -> anyhow::Result<()> {
    if std::env::var_os(CHILD_ENV).is_some() {
        return Ok(());
    }
    // RustDDS's writer says when it stops waiting for a reader (and, at info, when it waits again).
    node_runtime::logging::init();
    let cfg = test_config();
    let mut rig = RosNode::new("test_dead_reader_rig", &cfg)?;
    let mut live = RosNode::new("test_dead_reader_live", &cfg)?;
    let publisher = rig.publisher::<RigSample>(SuiteTopic::RigSample)?;
    let subscription = live.subscription::<RigSample>(SuiteTopic::RigSample)?;

    // The live reader keeps every RigSample.seq it gets.
    let got = Arc::new(Mutex::new(Vec::<u64>::new()));
    let got_in_task = Arc::clone(&got);
    let reader_task = tokio::spawn(async move {
        let mut stream = Box::pin(subscription.async_stream());
        while let Some(Ok((s, _))) = stream.next().await {
            got_in_task.lock().expect("lock").push(s.seq);
        }
    });

    let mut child = Command::new(std::env::current_exe()?)
        .args(["dead_reader_child", "--exact", "--nocapture", "--test-threads", "1"])
        .env(CHILD_ENV, "1")
        .stdout(Stdio::piped())
        .spawn()?;
    let stdout = child.stdout.take().expect("piped stdout");
    let (ready_tx, mut ready_rx) = tokio::sync::oneshot::channel::<()>();
    std::thread::spawn(move || {
        let mut ready_tx = Some(ready_tx);
        for line in BufReader::new(stdout).lines().map_while(Result::ok) {
            if line.contains(READY)
                && let Some(tx) = ready_tx.take()
            {
                let _ = tx.send(());
            }
        }
    });

    let mut seq = 0u64;
    let mut refused_before_kill = 0u64;
    let mut tick = tokio::time::interval(Duration::from_millis(1));
    // Publish until both readers have samples (discovery), then one more second.
    let mut ready_at = None;
    let start = tokio::time::Instant::now();
    loop {
        tick.tick().await;
        for _ in 0..RATE_PER_MS {
            if publisher.publish(sample(seq)).is_err() {
                refused_before_kill += 1;
            }
            seq += 1;
        }
        if ready_at.is_none() && ready_rx.try_recv().is_ok() {
            ready_at = Some(tokio::time::Instant::now());
        }
        if ready_at.is_some_and(|t| t.elapsed() >= Duration::from_secs(1)) && !got.lock().expect("lock").is_empty() {
            break;
        }
        anyhow::ensure!(start.elapsed() < Duration::from_secs(30), "the readers got no sample within 30 s");
    }

    child.kill()?; // SIGKILL: the reader leaves nothing behind but its silence
    child.wait()?;
    let first_after_kill = seq;
    let mut refused = 0u64;
    let killed_at = tokio::time::Instant::now();
    while killed_at.elapsed() < AFTER_KILL {
        tick.tick().await;
        for _ in 0..RATE_PER_MS {
            if publisher.publish(sample(seq)).is_err() {
                refused += 1;
            }
            seq += 1;
        }
    }
    let last = seq - 1;
    // What was written arrives.
    let deadline = tokio::time::Instant::now() + Duration::from_secs(10);
    while got.lock().expect("lock").last().is_none_or(|s| *s < last) && tokio::time::Instant::now() < deadline {
        tokio::time::sleep(Duration::from_millis(50)).await;
    }
    reader_task.abort();

    let got = got.lock().expect("lock").clone();
    let after: Vec<u64> = got.iter().copied().filter(|s| *s >= first_after_kill).collect();
    let missing = (last - first_after_kill + 1).saturating_sub(after.len() as u64);
    println!(
        "dead reader: {} samples written in {:.0} s after the kill, {refused} refused; the live reader got {} of \
         them ({missing} missing); {refused_before_kill} refused before the kill",
        last - first_after_kill + 1,
        AFTER_KILL.as_secs_f64(),
        after.len()
    );
    assert_eq!(
        refused, 0,
        "the writer refused {refused} samples after a reader was killed: the dead reader held the window"
    );
    assert_eq!(
        after,
        (first_after_kill..=last).collect::<Vec<_>>(),
        "the live reader missed {missing} samples after the other reader was killed"
    );
    Ok(())
}

//! A reliable reader whose process is stopped (SIGSTOP) for longer than the writer waits for it
//! costs the other readers nothing, and gets every sample once it is continued.
//!
//! The vendored RustDDS stops waiting for a reader that has sent no ACKNACK for 2 s
//! (vendor/rustdds/PATCHES.md, patch 3), but keeps what it has not acknowledged in the writer's
//! history (up to the resource limit, 8,192 samples) and repairs it when it acknowledges again;
//! it holds the send window again once it has caught up. Here the reader is stopped for 3 s at
//! 2,000 samples/s (6,000 samples), then continued: the writer must refuse nothing at any time,
//! the live reader must get every sample, and the continued reader too. Without patch 3 the
//! window does not fill in 3 s at this rate either, so this test guards the patch's other half
//! (nothing a returning reader could still get is dropped, and its return blocks no one);
//! `dead_reader.rs` is the test that fails without it.
//!
//! The stopped reader is a child process: this test binary run again with `STOPPED_READER_CHILD`
//! set. Like every DDS test here it runs inside `scripts/netns-run`.

use futures::StreamExt;
use node_runtime::{RosNode, RuntimeConfig, SuiteTopic};
use std::{
    io::{BufRead, BufReader, Write},
    process::{Command, Stdio},
    sync::{Arc, Mutex},
    time::Duration,
};
use tyre_msgs::{RigSample, std_msgs::Header};

const CHILD_ENV: &str = "STOPPED_READER_CHILD";
const GOT: &str = "STOPPED_READER_GOT";
const RATE_PER_MS: u64 = 2;
const STOPPED: Duration = Duration::from_secs(3);
const AFTER_CONT: Duration = Duration::from_secs(6);

fn test_config() -> RuntimeConfig {
    let cfg = RuntimeConfig::default();
    let domain = cfg.resolved_domain_id().expect("ROS_DOMAIN_ID must be a valid domain id");
    assert_ne!(domain, 0, "DDS tests run on a non-zero ROS_DOMAIN_ID inside scripts/netns-run");
    cfg
}

fn sample(seq: u64) -> RigSample {
    RigSample { header: Header::iso_w(seq as f64 * 0.001), seq, runtime_s: seq as f64 * 0.001, ..Default::default() }
}

fn signal(pid: u32, sig: &str) {
    let status = Command::new("kill").args([sig, &pid.to_string()]).status().expect("run kill");
    assert!(status.success(), "kill {sig} {pid}: {status}");
}

/// The reader to be stopped (runs only in the child process): reports `GOT <count> <first>
/// <last>` every 100 ms.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn stopped_reader_child() -> anyhow::Result<()> {
    if std::env::var_os(CHILD_ENV).is_none() {
        return Ok(());
    }
    let mut node = RosNode::new("test_stopped_reader_recorder", &test_config())?;
    let subscription = node.recording_subscription::<RigSample>(SuiteTopic::RigSample)?;
    let mut stream = Box::pin(subscription.async_stream());
    let (mut count, mut first, mut last) = (0u64, 0u64, None::<u64>);
    let mut reported = std::time::Instant::now();
    loop {
        match tokio::time::timeout(Duration::from_millis(100), stream.next()).await {
            Ok(Some(item)) => {
                let (s, _) = item.map_err(|e| anyhow::anyhow!("{e:?}"))?;
                count += 1;
                if last.is_none() {
                    first = s.seq;
                }
                last = Some(s.seq);
            }
            Ok(None) => break,
            Err(_) => {} // quiet for 100 ms: report what we have
        }
        if let Some(last) = last
            && reported.elapsed() >= Duration::from_millis(100)
        {
            println!("{GOT} {count} {first} {last}");
            std::io::stdout().flush()?;
            reported = std::time::Instant::now();
        }
    }
    Ok(())
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_stopped_reader_costs_the_others_nothing_and_gets_everything_back() -> anyhow::Result<()> {
    if std::env::var_os(CHILD_ENV).is_some() {
        return Ok(());
    }
    // RustDDS's writer says when it stops waiting for a reader (and, at info, when it waits again).
    node_runtime::logging::init();
    let cfg = test_config();
    let mut rig = RosNode::new("test_stopped_reader_rig", &cfg)?;
    let mut live = RosNode::new("test_stopped_reader_live", &cfg)?;
    let publisher = rig.publisher::<RigSample>(SuiteTopic::RigSample)?;
    let subscription = live.subscription::<RigSample>(SuiteTopic::RigSample)?;

    let got = Arc::new(Mutex::new(Vec::<u64>::new()));
    let got_in_task = Arc::clone(&got);
    let reader_task = tokio::spawn(async move {
        let mut stream = Box::pin(subscription.async_stream());
        while let Some(Ok((s, _))) = stream.next().await {
            got_in_task.lock().expect("lock").push(s.seq);
        }
    });

    let mut child = Command::new(std::env::current_exe()?)
        .args(["stopped_reader_child", "--exact", "--nocapture", "--test-threads", "1"])
        .env(CHILD_ENV, "1")
        .stdout(Stdio::piped())
        .spawn()?;
    let pid = child.id();
    let stdout = child.stdout.take().expect("piped stdout");
    // The child's latest report: (count, first, last).
    let report = Arc::new(Mutex::new(None::<(u64, u64, u64)>));
    let report_in_thread = Arc::clone(&report);
    std::thread::spawn(move || {
        for line in BufReader::new(stdout).lines().map_while(Result::ok) {
            let mut words = line.split_whitespace();
            if words.next() != Some(GOT) {
                continue;
            }
            let n: Vec<u64> = words.filter_map(|w| w.parse().ok()).collect();
            if let [count, first, last] = n[..] {
                *report_in_thread.lock().expect("lock") = Some((count, first, last));
            }
        }
    });

    let mut seq = 0u64;
    let mut refused = 0u64;
    let mut tick = tokio::time::interval(Duration::from_millis(1));
    let mut publish_for = async |d: Duration, seq: &mut u64, refused: &mut u64| {
        let t = tokio::time::Instant::now();
        while t.elapsed() < d {
            tick.tick().await;
            for _ in 0..RATE_PER_MS {
                if publisher.publish(sample(*seq)).is_err() {
                    *refused += 1;
                }
                *seq += 1;
            }
        }
    };
    // Until both readers have samples, then one more second.
    let start = tokio::time::Instant::now();
    while report.lock().expect("lock").is_none() || got.lock().expect("lock").is_empty() {
        anyhow::ensure!(start.elapsed() < Duration::from_secs(30), "the readers got no sample within 30 s");
        publish_for(Duration::from_millis(50), &mut seq, &mut refused).await;
    }
    publish_for(Duration::from_secs(1), &mut seq, &mut refused).await;

    signal(pid, "-STOP");
    let stopped_at = seq;
    publish_for(STOPPED, &mut seq, &mut refused).await;
    signal(pid, "-CONT");
    let continued_at = seq;
    publish_for(AFTER_CONT, &mut seq, &mut refused).await;
    let last = seq - 1;

    // What was written arrives, at both readers.
    let deadline = tokio::time::Instant::now() + Duration::from_secs(15);
    let child_done = || report.lock().expect("lock").is_some_and(|(_, _, l)| l >= last);
    while (got.lock().expect("lock").last().is_none_or(|s| *s < last) || !child_done())
        && tokio::time::Instant::now() < deadline
    {
        tokio::time::sleep(Duration::from_millis(50)).await;
    }
    reader_task.abort();
    child.kill()?;
    child.wait()?;

    let got = got.lock().expect("lock").clone();
    let live_first = got.first().copied().unwrap_or(0);
    let live_missing = (last - live_first + 1).saturating_sub(got.len() as u64);
    let (count, first, child_last) = report.lock().expect("lock").unwrap_or((0, 0, 0));
    let child_missing = (child_last.saturating_sub(first) + 1).saturating_sub(count);
    println!(
        "stopped reader: stopped at seq {stopped_at} for {:.0} s, continued at {continued_at}, last {last}; {refused} \
         refused; the live reader missed {live_missing}; the stopped reader got {count} of {first}..={child_last} \
         ({child_missing} missing)",
        STOPPED.as_secs_f64()
    );
    assert_eq!(refused, 0, "the writer refused {refused} samples while a reader was stopped");
    assert_eq!(got, (live_first..=last).collect::<Vec<_>>(), "the live reader missed {live_missing} samples");
    assert_eq!(child_last, last, "the continued reader never caught up (last {child_last} of {last})");
    assert_eq!(child_missing, 0, "the continued reader lost {child_missing} samples the writer still held");
    Ok(())
}

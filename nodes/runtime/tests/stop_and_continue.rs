//! A process stopped and continued (SIGSTOP, SIGCONT: a debugger, `kill -STOP`, a frozen VM or
//! container) keeps talking DDS afterwards.
//!
//! Linux makes `epoll_wait` fail with EINTR in every thread that was blocked in it when a stopped
//! process is continued, even with no signal handler installed (signal(7)). RustDDS 0.15.1's
//! participant event loop and discovery loop took that for a fatal poll error and exited, so the
//! participant neither sent nor received again; the vendored RustDDS polls again instead
//! (vendor/rustdds/PATCHES.md). Without that patch this test fails: no sample crosses after the
//! stop.
//!
//! The test stops its own process through a child shell (which keeps running while this process
//! is stopped, and continues it), so it lives alone in this test binary: nothing else runs in the
//! process while it is stopped. Like every DDS test here it runs inside `scripts/netns-run`.

use futures::StreamExt;
use node_runtime::{RosNode, RuntimeConfig, SuiteTopic};
use std::time::Duration;
use tyre_msgs::{RigSample, std_msgs::Header};

fn test_config() -> RuntimeConfig {
    let cfg = RuntimeConfig::default();
    let domain = cfg.resolved_domain_id().expect("ROS_DOMAIN_ID must be a valid domain id");
    assert_ne!(domain, 0, "DDS tests run on a non-zero ROS_DOMAIN_ID inside scripts/netns-run");
    cfg
}

fn sample(seq: u64) -> RigSample {
    RigSample { header: Header::iso_w(seq as f64 * 0.01), seq, runtime_s: seq as f64 * 0.01, ..Default::default() }
}

/// Stops this process for `stopped_ms` and continues it, from a child shell.
fn stop_and_continue_self(stopped_ms: u32) {
    let pid = std::process::id().to_string();
    let script = format!("kill -STOP \"$1\"; sleep {}; kill -CONT \"$1\"", f64::from(stopped_ms) / 1000.0);
    let status = std::process::Command::new("sh").args(["-c", &script, "sh", &pid]).status().expect("run sh");
    assert!(status.success(), "sh: {status}");
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn participants_talk_after_the_process_is_stopped_and_continued() -> anyhow::Result<()> {
    let cfg = test_config();
    let mut rig = RosNode::new("test_stopped_rig", &cfg)?;
    let mut listener = RosNode::new("test_stopped_listener", &cfg)?;
    let publisher = rig.publisher::<RigSample>(SuiteTopic::RigSample)?;
    let subscription = listener.subscription::<RigSample>(SuiteTopic::RigSample)?;
    let mut stream = Box::pin(subscription.async_stream());

    // Publish `seq` until it (or a later one) arrives, within `within`.
    let mut publish_until_received = async |seq: u64, within: Duration| {
        tokio::time::timeout(within, async {
            loop {
                publisher.publish(sample(seq)).map_err(|e| anyhow::anyhow!("{e:?}"))?;
                if let Ok(Some(msg)) = tokio::time::timeout(Duration::from_millis(200), stream.next()).await {
                    let got = msg.map_err(|e| anyhow::anyhow!("{e:?}"))?.0;
                    if got.seq >= seq {
                        return anyhow::Ok(got.seq);
                    }
                }
            }
        })
        .await
    };

    publish_until_received(0, Duration::from_secs(20))
        .await
        .map_err(|_| anyhow::anyhow!("no sample before the stop (discovery)"))??;

    // Three stops, each once the DDS threads are idle in their poll: every one of them must be
    // followed by samples crossing again.
    for round in 1..=3u64 {
        tokio::time::sleep(Duration::from_millis(500)).await;
        tokio::task::spawn_blocking(|| stop_and_continue_self(300)).await?;
        publish_until_received(round, Duration::from_secs(10))
            .await
            .map_err(|_| anyhow::anyhow!("no sample crossed in 10 s after stop/continue #{round}"))??;
    }
    Ok(())
}

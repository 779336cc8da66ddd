//! A node about to exit waits until its readers have its last messages
//! ([`RosNode::flush_before_exit`], vendor/rustdds PATCHES.md 4), and a reader killed without
//! leaving does not hold it for the reader's whole lease.
//!
//! The killed reader is a child process: this test binary run again with `FLUSH_READER_CHILD`
//! set, where `flush_reader_child` subscribes to the procedure state, says when it has one and
//! reads until it is killed. Like every DDS test here it runs inside `scripts/netns-run`.

use futures::StreamExt;
use node_runtime::{FLUSH_DEADLINE, RosNode, RuntimeConfig, SuiteTopic};
use std::{
    io::{BufRead, BufReader},
    process::{Command, Stdio},
    time::Duration,
};
use tyre_msgs::{ProcedureState, std_msgs::Header};

const CHILD_ENV: &str = "FLUSH_READER_CHILD";
const READY: &str = "FLUSH_READER_READY";

fn test_config() -> RuntimeConfig {
    let cfg = RuntimeConfig::default();
    let domain = cfg.resolved_domain_id().expect("ROS_DOMAIN_ID must be a valid domain id");
    assert_ne!(domain, 0, "DDS tests run on a non-zero ROS_DOMAIN_ID inside scripts/netns-run");
    cfg
}

fn state(index: u32, phase: u8) -> ProcedureState {
    ProcedureState {
        header: Header::iso_w(f64::from(index)),
        phase,
        sweep_index: index,
        procedure: "flush_test".into(),
        ..Default::default()
    }
}

/// The reader to be killed (runs only in the child process).
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn flush_reader_child() -> anyhow::Result<()> {
    if std::env::var_os(CHILD_ENV).is_none() {
        return Ok(());
    }
    let mut node = RosNode::new("test_flush_dead_recorder", &test_config())?;
    let subscription = node.recording_subscription::<ProcedureState>(SuiteTopic::ProcedureState)?;
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
async fn a_flush_waits_for_the_live_reader_and_not_for_a_killed_one() -> anyhow::Result<()> {
    if std::env::var_os(CHILD_ENV).is_some() {
        return Ok(());
    }
    node_runtime::logging::init();
    let cfg = test_config();
    let mut sequencer = RosNode::new("test_flush_sequencer", &cfg)?;
    let mut live = RosNode::new("test_flush_live_recorder", &cfg)?;
    let publisher = sequencer.publisher::<ProcedureState>(SuiteTopic::ProcedureState)?;
    let subscription = live.recording_subscription::<ProcedureState>(SuiteTopic::ProcedureState)?;
    let (last_tx, mut last_rx) = tokio::sync::watch::channel(None::<ProcedureState>);
    let reader_task = tokio::spawn(async move {
        let mut stream = Box::pin(subscription.async_stream());
        while let Some(Ok((s, _))) = stream.next().await {
            last_tx.send_replace(Some(s));
        }
    });

    let mut child = Command::new(std::env::current_exe()?)
        .args(["flush_reader_child", "--exact", "--nocapture", "--test-threads", "1"])
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
                tx.send(()).ok();
            }
        }
    });

    // States at 20 Hz until both readers have one (discovery done).
    let start = tokio::time::Instant::now();
    let mut index = 0u32;
    loop {
        publisher.publish(state(index, ProcedureState::PHASE_SWEEP)).map_err(|e| anyhow::anyhow!("{e:?}"))?;
        index += 1;
        tokio::time::sleep(Duration::from_millis(50)).await;
        if ready_rx.try_recv().is_ok() && last_rx.borrow().is_some() {
            break;
        }
        anyhow::ensure!(start.elapsed() < Duration::from_secs(30), "the readers got no state within 30 s");
    }

    child.kill()?; // SIGKILL: its reader stays matched until its lease ends, silent
    child.wait()?;
    publisher.publish(state(index, ProcedureState::PHASE_COMPLETE)).map_err(|e| anyhow::anyhow!("{e:?}"))?;
    let flush_start = tokio::time::Instant::now();
    let unacknowledged = sequencer.flush_before_exit(&[(SuiteTopic::ProcedureState, publisher.guid())]).await;
    let took = flush_start.elapsed();
    println!("flush with a killed reader: {:.1} s, {unacknowledged} writer(s) unacknowledged", took.as_secs_f64());
    assert_eq!(
        unacknowledged,
        0,
        "the killed reader held the flush for its deadline ({} s) instead of dropping out",
        FLUSH_DEADLINE.as_secs()
    );
    // Acknowledged means the live reader's DDS cache has it: the application gets it at once.
    let got = tokio::time::timeout(Duration::from_secs(5), async {
        loop {
            if let Some(s) = last_rx.borrow_and_update().as_ref()
                && s.phase == ProcedureState::PHASE_COMPLETE
            {
                return s.sweep_index;
            }
            if last_rx.changed().await.is_err() {
                return u32::MAX;
            }
        }
    })
    .await;
    reader_task.abort();
    assert_eq!(got.ok(), Some(index), "the live reader did not get the final state the flush waited for");
    Ok(())
}

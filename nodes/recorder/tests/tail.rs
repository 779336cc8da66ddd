//! A stream that stops early while its writer is still there is loss in the recorder's log.
//!
//! A gap shows only when a later message arrives, so a rig whose samples stop reaching the
//! recorder (refused by its writer, say) used to leave a log that said "nothing lost". The rig
//! announces its own count of what it made (`<node>: published` on `/diagnostics`, a
//! `WriterTally`); the recorder counts what was made but never arrived as the stream's tail.
//! Here a stand-in rig publishes samples 0..=499, refuses 500..=799 (it counts them but does not
//! publish them) and keeps announcing its count: the log's loss record must hold a tail of 300.
//! The control: a rig whose count matches what it published leaves a clean record.
//!
//! The recorder records only `sample`, so it listens to `/diagnostics` for the counts alone.
//! Each test has its own namespace. Like every DDS test here it runs inside `scripts/netns-run`.

use node_runtime::{RosNode, RuntimeConfig, Shutdown, SuiteTopic, WriterTally, loss::publisher_id};
use recorder::{LogReader, RecorderConfig};
use std::time::Duration;
use streamloss::SeqSource;
use tyre_msgs::{RigSample, diagnostic_msgs::DiagnosticArray, std_msgs::Header};

fn test_config(namespace: &str) -> RuntimeConfig {
    let mut cfg = RuntimeConfig::default();
    let domain = cfg.resolved_domain_id().expect("ROS_DOMAIN_ID must be a valid domain id");
    assert_ne!(domain, 0, "DDS tests run on a non-zero ROS_DOMAIN_ID inside scripts/netns-run");
    cfg.namespace = namespace.to_owned();
    cfg
}

fn sample(seq: u64) -> RigSample {
    RigSample { header: Header::iso_w(seq as f64 * 0.001), seq, runtime_s: seq as f64 * 0.001, ..Default::default() }
}

/// Runs a recorder of `sample` while a stand-in rig publishes samples `0..published`, then counts
/// `made - published` more as refused, announcing its count every 100 ms for 1.5 s after its last
/// sample. Returns the log's loss report and the recorder's lost count.
async fn record(namespace: &str, published: u64, made: u64) -> anyhow::Result<(streamloss::LossReport, u64)> {
    let cfg = test_config(namespace);
    let dir = tempfile::tempdir()?;
    let out = dir.path().join("tail.mcap");
    let mut rec_cfg = RecorderConfig::to_file(&out);
    rec_cfg.topics = Some(vec!["sample".into()]);
    rec_cfg.flush_interval_s = 0.25;
    let rec_node = RosNode::new("test_tail_recorder", &cfg)?;
    let shutdown = Shutdown::new();
    let sd = shutdown.clone();
    let recorder = tokio::spawn(async move { recorder::shell::run(rec_node, rec_cfg, sd).await });

    let mut rig = RosNode::new("test_tail_rig", &cfg)?;
    let samples = rig.publisher::<RigSample>(SuiteTopic::RigSample)?;
    let diagnostics = rig.publisher::<DiagnosticArray>(SuiteTopic::Diagnostics)?;
    let deadline = tokio::time::Instant::now() + Duration::from_secs(20);
    while rig.discovered_subscriptions(SuiteTopic::RigSample) < 1
        || rig.discovered_subscriptions(SuiteTopic::Diagnostics) < 1
    {
        anyhow::ensure!(tokio::time::Instant::now() < deadline, "the recorder's readers were not discovered in 20 s");
        tokio::time::sleep(Duration::from_millis(50)).await;
    }
    // Discovery of the readers by this participant is not yet matching by the writer.
    tokio::time::sleep(Duration::from_millis(1500)).await;

    let writer = publisher_id(&samples);
    let topic = rig.topic_name(SuiteTopic::RigSample);
    let tally = |last_seq: u64, refused: u64| {
        let t = WriterTally { topic: topic.clone(), writer, last_seq, published: last_seq + 1 - refused, refused };
        DiagnosticArray { header: Header::default(), status: vec![t.to_status("test_tail_rig")] }
    };
    let mut tick = tokio::time::interval(Duration::from_millis(1));
    for seq in 0..made {
        tick.tick().await;
        if seq < published {
            samples.publish(sample(seq)).map_err(|e| anyhow::anyhow!("publish: {e:?}"))?;
        }
        if seq % 100 == 99 {
            let _ = diagnostics.publish(tally(seq, seq.saturating_sub(published - 1)));
        }
    }
    // The rig is still there, counting, but its stream has stopped.
    for _ in 0..15 {
        let _ = diagnostics.publish(tally(made - 1, made - published));
        tokio::time::sleep(Duration::from_millis(100)).await;
    }
    shutdown.trigger();
    let stats = recorder.await??;
    let log = LogReader::open(&out)?;
    let report = log.loss_report().ok_or_else(|| anyhow::anyhow!("no loss record"))??;
    Ok((report, stats.lost))
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_stream_that_stops_while_its_rig_counts_on_is_a_tail() -> anyhow::Result<()> {
    let (report, lost) = record("/tail_refused", 500, 800).await?;
    let stream = report
        .streams
        .iter()
        .find(|s| s.source == SeqSource::Message)
        .ok_or_else(|| anyhow::anyhow!("no RigSample.seq stream in {report:?}"))?;
    assert_eq!((stream.first_seq, stream.last_seq, stream.lost), (0, 499, 0), "{stream:?}");
    assert_eq!(stream.tail, 300, "samples 500-799 were made and never arrived: {stream:?}");
    assert_eq!((report.lost_total(), lost), (300, 300));
    assert!(report.complete && !report.is_clean());
    let lines = report.summary_lines().join("\n");
    assert!(lines.contains("300 of them made after the last one received"), "{lines}");
    Ok(())
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_rig_count_that_matches_the_log_is_no_loss() -> anyhow::Result<()> {
    let (report, lost) = record("/tail_whole", 800, 800).await?;
    let stream = report.streams.iter().find(|s| s.source == SeqSource::Message).expect("a RigSample.seq stream");
    assert_eq!((stream.first_seq, stream.last_seq, stream.tail), (0, 799, 0), "{stream:?}");
    assert!(report.is_clean() && lost == 0, "{report:?}");
    Ok(())
}

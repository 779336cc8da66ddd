//! The recorder node: every suite topic → one MCAP log.
//!
//! One subscription task per topic encodes what arrives and hands it to a single writer thread
//! (file I/O stays off the async runtime). `log_time` is taken on arrival.
//!
//! Nothing is lost silently: every message's writer and sequence numbers (DDS, and `RigSample.seq`)
//! go with it to the writer thread, which keeps the [`LossWatch`]. A gap, or a message that does
//! not decode, is announced on `/diagnostics` at once and written into the log as the
//! `tyrerig.loss` metadata record (again at most once a second while loss goes on, so a killed
//! recorder's file still says what it missed, and a final tally on stop). A stream that stops
//! early leaves no gap; the rig's own count of what it made (`<node>: published` on
//! `/diagnostics`, [`WriterTally`]) shows what never arrived, and the loss record counts it as the
//! stream's tail (`/diagnostics` is subscribed for that even when it is not recorded). The readers
//! have a deep history ([`node_runtime::Qos::recording_profile`]) so the recorder keeps up far
//! above any rig's rate; beyond its ceiling the loss is counted, never hidden.

use crate::config::{OnExisting, RecorderConfig, RecorderConfigError};
use crate::forward::{DRAIN_LIMIT, forward};
use mcaplog::{LogWriteError, McapLog, McapLogOptions, codec};
use node_runtime::{LossWatch, RosNode, RuntimeError, Shutdown, SuiteTopic, WriterTally, topics::TopicVisitor};
use ros2_client::{MessageInfo, ros2::ReadError};
use std::{
    collections::BTreeMap,
    path::{Path, PathBuf},
    time::{Instant, SystemTime},
};
use tokio::sync::mpsc;
use tyre_msgs::{
    RigSample, RosMessage,
    builtin_interfaces::Time,
    diagnostic_msgs::{DiagnosticArray, DiagnosticStatus, KeyValue},
};

/// Why the recorder stopped with an error.
#[derive(Debug, thiserror::Error)]
pub enum RecorderError {
    #[error("recorder config: {0}")]
    Config(#[from] RecorderConfigError),
    #[error("recorder config: topic {0:?} is not a suite topic")]
    UnknownTopic(String),
    #[error(transparent)]
    Runtime(#[from] RuntimeError),
    #[error(transparent)]
    Write(#[from] LogWriteError),
    #[error("recorder: no ros2msg schema: {0}")]
    Schema(String),
    #[error("recorder writer thread failed: {0}")]
    Join(String),
}

/// What was recorded.
#[derive(Debug, Clone, PartialEq)]
pub struct RecorderStats {
    pub messages: u64,
    pub payload_bytes: u64,
    /// Messages missing from the streams recorded (gaps in writer or sample sequence numbers).
    pub lost: u64,
    /// Messages that arrived but did not decode.
    pub malformed: u64,
    /// The file written (the configured output, or a new name beside it, see `on_existing`).
    pub output: PathBuf,
}

/// What a subscription task hands the writer thread.
enum Received {
    Message {
        topic: SuiteTopic,
        log_time_ns: u64,
        publish_time_ns: u64,
        data: Vec<u8>,
        info: MessageInfo,
        /// `RigSample.seq` for samples.
        message_seq: Option<u64>,
        /// Writers' own counts (`/diagnostics`), taken before the stop only: what a writer made
        /// after the recorder stopped listening was not owed to it.
        tallies: Vec<WriterTally>,
    },
    Refused {
        topic: SuiteTopic,
        error: ReadError,
    },
}

fn now_ns() -> u64 {
    SystemTime::now().duration_since(SystemTime::UNIX_EPOCH).map(|d| d.as_nanos() as u64).unwrap_or(0)
}

/// Stream topics (samples, setpoints, thermal states, live channels) flow steadily while their
/// node lives. One that stops while another still flows means its node has gone (killed, hung):
/// announced on `/diagnostics` after [`SILENT_AFTER`], and again when it flows once more.
pub const SILENT_AFTER: std::time::Duration = std::time::Duration::from_millis(500);

#[derive(Debug, Default)]
struct StreamSilence {
    /// topic → (last receipt, messages so far, announced silent)
    topics: BTreeMap<SuiteTopic, (Option<Instant>, u64, bool)>,
}

impl StreamSilence {
    fn new(topics: &[SuiteTopic]) -> Self {
        let topics = topics
            .iter()
            .filter(|t| t.spec().qos == node_runtime::Qos::Stream)
            .map(|t| (*t, (None, 0, false)))
            .collect();
        Self { topics }
    }

    /// Notes a receipt on `topic` at `now`; returns what changed (topic, silent for, true =
    /// silent / false = back).
    fn on_message(&mut self, topic: SuiteTopic, now: Instant) -> Vec<(SuiteTopic, f64, bool)> {
        let mut changes = Vec::new();
        if let Some((last, n, silent)) = self.topics.get_mut(&topic) {
            if *silent {
                changes.push((topic, last.map_or(0.0, |l| now.duration_since(l).as_secs_f64()), false));
                *silent = false;
            }
            *last = Some(now);
            *n += 1;
        } else {
            return changes;
        }
        // Another stream still flows: any that stopped (after flowing) has gone silent.
        for (t, (last, n, silent)) in &mut self.topics {
            if let Some(l) = last
                && *n >= 10
                && !*silent
                && now.duration_since(*l) >= SILENT_AFTER
            {
                *silent = true;
                changes.push((*t, now.duration_since(*l).as_secs_f64(), true));
            }
        }
        changes
    }
}

/// The `/diagnostics` status of a stream gone silent (or flowing again) after `silent_s`.
fn silence_status(node_name: &str, topic: &str, silent_s: f64, silent: bool) -> DiagnosticStatus {
    let message = if silent {
        format!("{topic}: silent for {silent_s:.1} s while other streams flow (its node stopped?)")
    } else {
        format!("{topic}: flowing again after {silent_s:.1} s")
    };
    tracing::warn!("{message}");
    DiagnosticStatus {
        level: if silent { DiagnosticStatus::ERROR } else { DiagnosticStatus::WARN },
        name: format!("{node_name}: stream_silent"),
        message,
        hardware_id: "dds".into(),
        values: vec![KeyValue { key: "topic".into(), value: topic.to_owned() }],
    }
}

/// The topics a config selects.
pub fn selected_topics(cfg: &RecorderConfig, namespace: &str) -> Result<Vec<SuiteTopic>, RecorderError> {
    match &cfg.topics {
        None => Ok(SuiteTopic::ALL.to_vec()),
        Some(names) => names
            .iter()
            .map(|n| {
                SuiteTopic::ALL
                    .into_iter()
                    .find(|t| t.spec().name == n || t.full_name(namespace) == *n)
                    .ok_or_else(|| RecorderError::UnknownTopic(n.clone()))
            })
            .collect(),
    }
}

/// The file to write: `output` itself, or with `on_existing = "new_file"` and `output` already
/// there (a recorder restarted mid-run), the first free `<stem>.<n>.mcap` beside it, so the
/// earlier file is never overwritten.
pub fn output_path(cfg: &RecorderConfig) -> PathBuf {
    if cfg.on_existing == OnExisting::Overwrite || !cfg.output.exists() {
        return cfg.output.clone();
    }
    let stem = cfg.output.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
    let dir = cfg.output.parent().unwrap_or(Path::new(""));
    (1u32..)
        .map(|n| dir.join(format!("{stem}.{n}.mcap")))
        .find(|p| !p.exists())
        .expect("some numbered file name is free")
}

/// Runs the recorder until `shutdown`, then completes the log (summary, indexes, footer).
pub async fn run(mut node: RosNode, cfg: RecorderConfig, shutdown: Shutdown) -> Result<RecorderStats, RecorderError> {
    cfg.validate()?;
    let topics = selected_topics(&cfg, node.namespace())?;
    let options = McapLogOptions {
        chunk_size_bytes: cfg.chunk_size_bytes,
        flush_interval_s: cfg.flush_interval_s,
        zstd_level: cfg.zstd_level,
    };
    let output = output_path(&cfg);
    if output != cfg.output {
        tracing::warn!(existing = %cfg.output.display(), new = %output.display(), "log exists; recording to a new file");
    }
    let mut log = McapLog::create(&output, options)?;
    let mut suite_md = BTreeMap::new();
    suite_md.insert("software".to_owned(), "tyrerig".to_owned());
    suite_md.insert("software_version".to_owned(), env!("CARGO_PKG_VERSION").to_owned());
    suite_md.insert("namespace".to_owned(), node.namespace().to_owned());
    suite_md.insert("domain_id".to_owned(), node.domain_id().to_string());
    suite_md.insert("recording_started_unix_ns".to_owned(), now_ns().to_string());
    suite_md.insert("log_time".to_owned(), "receive time at the recorder, ns since the UNIX epoch".to_owned());
    suite_md.insert("publish_time".to_owned(), "the message's header.stamp (rig time), ns".to_owned());
    if output != cfg.output {
        suite_md.insert("continues".to_owned(), cfg.output.display().to_string());
    }
    log.write_metadata("tyrerig", &suite_md)?;
    for (name, entries) in &cfg.metadata {
        log.write_metadata(name, entries)?;
    }
    // Channels are registered up front so a reader sees every topic, even silent ones.
    let mut channel_ids = BTreeMap::new();
    for &t in &topics {
        let id = log.ensure_channel(&t.full_name(node.namespace()), &t.ros_type_name(), &schema_of(t)?)?;
        channel_ids.insert(t, id);
    }
    log.flush()?;

    let (tx, mut rx) = mpsc::channel::<Received>(65_536);
    let mut tasks = Vec::new();
    // The rig's count of its samples comes on `/diagnostics`: listened to even when not recorded.
    let mut subscribed = topics.clone();
    if topics.contains(&SuiteTopic::RigSample) && !topics.contains(&SuiteTopic::Diagnostics) {
        subscribed.push(SuiteTopic::Diagnostics);
    }
    for &t in &subscribed {
        tasks.push(t.visit(Subscribe { node: &mut node, tx: tx.clone(), shutdown: shutdown.clone() })?);
    }
    drop(tx);
    let diagnostics = node.publisher::<DiagnosticArray>(SuiteTopic::Diagnostics)?;
    let namespace = node.namespace().to_owned();
    let topic_names: BTreeMap<SuiteTopic, String> = subscribed.iter().map(|t| (*t, t.full_name(&namespace))).collect();
    let mut watch = LossWatch::new(node.name());
    let mut silence = StreamSilence::new(&topics);
    let node_name = node.name().to_owned();
    tracing::info!(output = %output.display(), topics = topics.len(), "recording");

    let out_path = output.clone();
    let writer = tokio::task::spawn_blocking(move || -> Result<RecorderStats, LogWriteError> {
        // Rig time of the latest message, for the stamps of loss announcements.
        let mut stamp = Time::default();
        let mut loss_written_at: Option<Instant> = None;
        let mut loss_seen = 0u64;
        while let Some(r) = rx.blocking_recv() {
            match r {
                Received::Message { topic, log_time_ns, publish_time_ns, data, info, message_seq, tallies } => {
                    let arrived = Instant::now();
                    for tally in &tallies {
                        watch.on_tally(tally, arrived);
                    }
                    // A topic without a channel is subscribed for the tallies alone.
                    if let Some(&channel) = channel_ids.get(&topic) {
                        log.write(channel, log_time_ns, publish_time_ns, &data)?;
                        // `/clock` is best effort by ROS convention: dropping a tick is its contract,
                        // not loss.
                        if topic.spec().qos != node_runtime::Qos::Clock {
                            watch.on_message(&topic_names[&topic], &info, message_seq);
                        }
                        if publish_time_ns > 0 {
                            stamp = Time::from_nanos(publish_time_ns);
                        }
                        let changes = silence.on_message(topic, Instant::now());
                        if !changes.is_empty() {
                            let status = changes
                                .into_iter()
                                .map(|(t, silent_s, silent)| {
                                    silence_status(&node_name, &topic_names[&t], silent_s, silent)
                                })
                                .collect();
                            let d = DiagnosticArray {
                                header: tyre_msgs::std_msgs::Header { stamp, frame_id: String::new() },
                                status,
                            };
                            if let Err(e) = diagnostics.publish(d) {
                                tracing::warn!("/diagnostics publish: {e:?}");
                            }
                        }
                    }
                }
                Received::Refused { topic, error } => watch.on_read_error(&topic_names[&topic], &error),
            }
            let now = Instant::now();
            watch.apply_tallies(Some(now));
            if let Some(d) = watch.announcement(now, stamp)
                && let Err(e) = diagnostics.publish(d)
            {
                tracing::warn!("/diagnostics publish: {e:?}");
            }
            // The log says what it is missing while the loss happens, not only at the end.
            let ledger = watch.ledger();
            let seen = ledger.lost_total().saturating_add(ledger.malformed_total());
            if seen != loss_seen
                && loss_written_at.is_none_or(|t| now.duration_since(t) >= node_runtime::loss::ANNOUNCE_EVERY)
            {
                log.write_metadata(streamloss::LOSS_RECORD, &ledger.report(false).to_entries())?;
                loss_written_at = Some(now);
                loss_seen = seen;
            }
        }
        // Everything that will arrive has: what the writers said they made before the stop and
        // is not here is the streams' tails.
        watch.apply_tallies(None);
        let report = watch.ledger().report(true);
        log.write_metadata(streamloss::LOSS_RECORD, &report.to_entries())?;
        let stats = RecorderStats {
            messages: log.message_count(),
            payload_bytes: log.payload_bytes(),
            lost: report.lost_total(),
            malformed: report.malformed_total(),
            output: out_path,
        };
        log.finish()?;
        Ok(stats)
    });
    for t in tasks {
        let _ = t.await;
    }
    let stats = writer.await.map_err(|e| RecorderError::Join(e.to_string()))??;
    if stats.lost == 0 && stats.malformed == 0 {
        tracing::info!(messages = stats.messages, output = %stats.output.display(), "recording complete, nothing lost");
    } else {
        tracing::warn!(
            messages = stats.messages,
            lost = stats.lost,
            malformed = stats.malformed,
            output = %stats.output.display(),
            "recording complete WITH LOSS (see `tyrerig mcap info`)"
        );
    }
    Ok(stats)
}

/// The `ros2msg` schema text of a topic's type (the `.msg` text with its dependencies appended).
pub fn schema_of(topic: SuiteTopic) -> Result<String, RecorderError> {
    struct Schema;
    impl TopicVisitor for Schema {
        type Output = Result<String, tyre_msgs::schema::SchemaError>;
        fn visit<M: RosMessage + Send + Sync + 'static>(self, _: SuiteTopic) -> Self::Output {
            tyre_msgs::schema::ros2msg_schema::<M>()
        }
    }
    topic.visit(Schema).map_err(|e| RecorderError::Schema(e.to_string()))
}

struct Subscribe<'a> {
    node: &'a mut RosNode,
    tx: mpsc::Sender<Received>,
    shutdown: Shutdown,
}

impl TopicVisitor for Subscribe<'_> {
    type Output = Result<tokio::task::JoinHandle<()>, RecorderError>;
    fn visit<M: RosMessage + Send + Sync + 'static>(self, topic: SuiteTopic) -> Self::Output {
        let sub = self.node.recording_subscription::<M>(topic)?;
        let (tx, shutdown) = (self.tx, self.shutdown);
        let type_name = M::ros_type_name();
        Ok(tokio::spawn(async move {
            let convert = |item: Result<(M, MessageInfo), ReadError>| match item {
                Ok((msg, info)) => {
                    let log_time_ns = now_ns();
                    let message_seq = (&msg as &dyn std::any::Any).downcast_ref::<RigSample>().map(|s| s.seq);
                    let tallies = match (&msg as &dyn std::any::Any).downcast_ref::<DiagnosticArray>() {
                        Some(d) if !shutdown.is_triggered() => {
                            d.status.iter().filter_map(WriterTally::from_status).collect()
                        }
                        _ => Vec::new(),
                    };
                    match codec::encode(&msg, &type_name) {
                        Ok(data) => {
                            let publish_time_ns = codec::leading_stamp(&data).map_or(0, |t| t.as_nanos());
                            Some(Received::Message {
                                topic,
                                log_time_ns,
                                publish_time_ns,
                                data,
                                info,
                                message_seq,
                                tallies,
                            })
                        }
                        Err(e) => {
                            tracing::error!("{topic:?}: {e}");
                            None
                        }
                    }
                }
                Err(error) => Some(Received::Refused { topic, error }),
            };
            let done = forward(sub.async_stream(), &shutdown, &tx, convert).await;
            if done.drain_cut_short {
                tracing::warn!(
                    drained = done.drained,
                    "{topic:?}: still arriving {} s after the stop; the log ends here",
                    DRAIN_LIMIT.as_secs_f64()
                );
            } else if done.drained > 0 {
                tracing::debug!(drained = done.drained, "{topic:?}: taken from the reader after the stop");
            }
        }))
    }
}

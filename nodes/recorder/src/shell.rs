//! The recorder node: every suite topic → one MCAP log.
//!
//! One subscription task per topic encodes what arrives and hands it to a single writer thread
//! (file I/O stays off the async runtime). `log_time` is taken on arrival.

use crate::config::{RecorderConfig, RecorderConfigError};
use futures::StreamExt;
use mcaplog::{LogWriteError, McapLog, McapLogOptions, codec};
use node_runtime::{RosNode, RuntimeError, Shutdown, SuiteTopic, topics::TopicVisitor};
use std::{collections::BTreeMap, time::SystemTime};
use tokio::sync::mpsc;
use tyre_msgs::RosMessage;

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
}

struct Received {
    topic: SuiteTopic,
    log_time_ns: u64,
    publish_time_ns: u64,
    data: Vec<u8>,
}

fn now_ns() -> u64 {
    SystemTime::now().duration_since(SystemTime::UNIX_EPOCH).map(|d| d.as_nanos() as u64).unwrap_or(0)
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

/// Runs the recorder until `shutdown`, then completes the log (summary, indexes, footer).
pub async fn run(mut node: RosNode, cfg: RecorderConfig, shutdown: Shutdown) -> Result<RecorderStats, RecorderError> {
    cfg.validate()?;
    let topics = selected_topics(&cfg, node.namespace())?;
    let options = McapLogOptions {
        chunk_size_bytes: cfg.chunk_size_bytes,
        flush_interval_s: cfg.flush_interval_s,
        zstd_level: cfg.zstd_level,
    };
    let mut log = McapLog::create(&cfg.output, options)?;
    let mut suite_md = BTreeMap::new();
    suite_md.insert("software".to_owned(), "tyrerig".to_owned());
    suite_md.insert("software_version".to_owned(), env!("CARGO_PKG_VERSION").to_owned());
    suite_md.insert("namespace".to_owned(), node.namespace().to_owned());
    suite_md.insert("domain_id".to_owned(), node.domain_id().to_string());
    suite_md.insert("recording_started_unix_ns".to_owned(), now_ns().to_string());
    suite_md.insert("log_time".to_owned(), "receive time at the recorder, ns since the UNIX epoch".to_owned());
    suite_md.insert("publish_time".to_owned(), "the message's header.stamp (rig time), ns".to_owned());
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
    for &t in &topics {
        tasks.push(t.visit(Subscribe { node: &mut node, tx: tx.clone(), shutdown: shutdown.clone() })?);
    }
    drop(tx);
    tracing::info!(output = %cfg.output.display(), topics = topics.len(), "recording");

    let writer = tokio::task::spawn_blocking(move || -> Result<RecorderStats, LogWriteError> {
        while let Some(r) = rx.blocking_recv() {
            log.write(channel_ids[&r.topic], r.log_time_ns, r.publish_time_ns, &r.data)?;
        }
        let stats = RecorderStats { messages: log.message_count(), payload_bytes: log.payload_bytes() };
        log.finish()?;
        Ok(stats)
    });
    for t in tasks {
        let _ = t.await;
    }
    let stats = writer.await.map_err(|e| RecorderError::Join(e.to_string()))??;
    tracing::info!(messages = stats.messages, output = %cfg.output.display(), "recording complete");
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
        let sub = self.node.subscription::<M>(topic)?;
        let (tx, shutdown) = (self.tx, self.shutdown);
        let type_name = M::ros_type_name();
        Ok(tokio::spawn(async move {
            let mut stream = Box::pin(sub.async_stream());
            loop {
                let item = tokio::select! {
                    _ = shutdown.wait() => break,
                    item = stream.next() => item,
                };
                match item {
                    Some(Ok((msg, _info))) => {
                        let log_time_ns = now_ns();
                        match codec::encode(&msg, &type_name) {
                            Ok(data) => {
                                let publish_time_ns = codec::leading_stamp(&data).map_or(0, |t| t.as_nanos());
                                let rec = Received { topic, log_time_ns, publish_time_ns, data };
                                if tx.send(rec).await.is_err() {
                                    break;
                                }
                            }
                            Err(e) => tracing::error!("{topic:?}: {e}"),
                        }
                    }
                    Some(Err(e)) => tracing::warn!("{topic:?}: receive error: {e:?}"),
                    None => break,
                }
            }
        }))
    }
}

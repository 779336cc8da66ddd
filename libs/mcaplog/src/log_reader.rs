//! [`LogReader`]: a suite log read back — messages in log order, typed on demand, and metadata.

use crate::codec;
use std::{
    collections::BTreeMap,
    path::{Path, PathBuf},
};
use tyre_msgs::RosMessage;

/// Why a log could not be read. Always names the file.
#[derive(Debug, thiserror::Error)]
pub enum LogError {
    #[error("{path}: cannot read: {source}")]
    Io { path: PathBuf, source: std::io::Error },
    #[error("{path}: not a readable MCAP file: {detail}")]
    NotMcap { path: PathBuf, detail: String },
    #[error(
        "{path}: the log ends early ({detail}) after {messages} messages; was the recorder killed? \
         `tyrerig mcap recover {path}` rescues every complete chunk"
    )]
    Truncated { path: PathBuf, detail: String, messages: usize },
    #[error("{path}: topic {topic:?}, message {index}: {detail}")]
    Decode { path: PathBuf, topic: String, index: usize, detail: String },
    #[error("{path}: topic {topic:?} carries {found:?}, not {expected:?}")]
    WrongType { path: PathBuf, topic: String, found: String, expected: String },
    #[error("{path}: channel {topic:?} uses message encoding {encoding:?}; only \"cdr\" (ROS 2) is supported")]
    Encoding { path: PathBuf, topic: String, encoding: String },
}

/// One recorded message.
#[derive(Debug, Clone)]
pub struct LogMessage {
    pub topic: String,
    /// ROS 2 type name from the channel's schema (`tyre_msgs/msg/RigSample`).
    pub ros_type: String,
    /// When the recorder received it [ns since the UNIX epoch].
    pub log_time_ns: u64,
    /// The message's own stamp (rig time) [ns].
    pub publish_time_ns: u64,
    /// Encapsulation header + CDR body.
    pub data: Vec<u8>,
}

/// [`LogReader::loss_summary`]: whether anything is missing, and lines saying what.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct LossSummary {
    /// Nothing lost, nothing malformed, no gap in `RigSample.seq`.
    pub clean: bool,
    pub lines: Vec<String>,
}

/// Per-topic statistics of a log.
#[derive(Debug, Clone, PartialEq)]
pub struct TopicInfo {
    pub topic: String,
    pub ros_type: String,
    pub messages: usize,
    pub first_log_time_ns: u64,
    pub last_log_time_ns: u64,
}

/// A log held in memory, fully checked on open.
#[derive(Debug)]
pub struct LogReader {
    path: PathBuf,
    messages: Vec<LogMessage>,
    metadata: BTreeMap<String, BTreeMap<String, String>>,
}

impl LogReader {
    /// Reads and checks the whole file (CRCs of chunks included). A file cut short is an error
    /// that says how to recover it.
    pub fn open(path: &Path) -> Result<Self, LogError> {
        let bytes = std::fs::read(path).map_err(|source| LogError::Io { path: path.to_owned(), source })?;
        Self::from_bytes(path, &bytes)
    }

    /// As [`LogReader::open`], from bytes already in memory (`path` names them in errors).
    /// Every length the file states is bounded ([`crate::records`]), so a damaged file is an
    /// error, never an unbounded allocation.
    pub fn from_bytes(path: &Path, bytes: &[u8]) -> Result<Self, LogError> {
        use crate::records::LogRecord;
        let p = || path.to_owned();
        if !bytes.starts_with(mcap::MAGIC) {
            return Err(LogError::NotMcap { path: p(), detail: "no MCAP magic at the start".into() });
        }
        let mut messages = Vec::new();
        let mut metadata = BTreeMap::new();
        // schema id → ROS type name; channel id → (topic, schema id)
        let mut schemas: BTreeMap<u16, String> = BTreeMap::new();
        let mut channels: BTreeMap<u16, (String, String)> = BTreeMap::new();
        for rec in crate::records::Records::new(bytes) {
            let rec = rec.map_err(|detail| LogError::Truncated { path: p(), detail, messages: messages.len() })?;
            match rec {
                LogRecord::Schema { id, name, .. } => {
                    schemas.insert(id, name);
                }
                LogRecord::Channel { id, schema_id, topic, message_encoding } => {
                    if message_encoding != "cdr" {
                        return Err(LogError::Encoding { path: p(), topic, encoding: message_encoding });
                    }
                    let ros_type = schemas.get(&schema_id).cloned().unwrap_or_default();
                    channels.insert(id, (topic, ros_type));
                }
                LogRecord::Message { channel_id, log_time, publish_time, data, .. } => {
                    let (topic, ros_type) = channels.get(&channel_id).cloned().ok_or_else(|| LogError::Truncated {
                        path: p(),
                        detail: format!("a message on channel {channel_id}, which was never defined"),
                        messages: messages.len(),
                    })?;
                    messages.push(LogMessage {
                        topic,
                        ros_type,
                        log_time_ns: log_time,
                        publish_time_ns: publish_time,
                        data,
                    });
                }
                LogRecord::Metadata { name, entries } => {
                    metadata.insert(name, entries);
                }
                LogRecord::Other => {}
            }
        }
        // Chunks are written in log-time order per chunk; sort once so readers see one timeline.
        messages.sort_by_key(|m| m.log_time_ns);
        Ok(Self { path: path.to_owned(), messages, metadata })
    }

    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Every message, in log-time order.
    pub fn messages(&self) -> &[LogMessage] {
        &self.messages
    }

    /// Metadata records by name (`tyrerig`, `tyre`, `procedure`, …).
    pub fn metadata(&self) -> &BTreeMap<String, BTreeMap<String, String>> {
        &self.metadata
    }

    /// What the recorder lost, from its `tyrerig.loss` record: `None` when the log has none
    /// (headless runs, imports, older recorders).
    pub fn loss_report(&self) -> Option<Result<streamloss::LossReport, streamloss::RecordError>> {
        self.metadata.get(streamloss::LOSS_RECORD).map(streamloss::LossReport::from_entries)
    }

    /// The gaps in `RigSample.seq` on `topic`, read from the messages themselves (independent of
    /// the recorder's own count, and available for every log): (samples, gaps, missing).
    pub fn sample_seq_gaps(&self, topic: &str) -> Result<(u64, Vec<streamloss::Gap>, u64), LogError> {
        let mut tracker = streamloss::SeqTracker::new();
        for (_, s) in self.typed::<tyre_msgs::RigSample>(topic)? {
            tracker.observe(s.seq);
        }
        Ok((tracker.received(), tracker.gaps().to_vec(), tracker.lost()))
    }

    /// What the log says it is missing, for people: the recorder's own tally (`tyrerig.loss`)
    /// and, for every RigSample topic, the gaps in `RigSample.seq` read from the messages.
    pub fn loss_summary(&self) -> LossSummary {
        let mut out = LossSummary { clean: true, lines: Vec::new() };
        match self.loss_report() {
            None => {
                out.lines.push("loss: no tyrerig.loss record (a headless run, an import or an older recorder)".into())
            }
            Some(Err(e)) => {
                out.clean = false;
                out.lines.push(format!("loss: {e}"));
            }
            Some(Ok(r)) => {
                let tally = if r.complete { "final tally" } else { "interim tally: the recorder did not stop cleanly" };
                if r.is_clean() {
                    out.lines.push(format!("loss ({tally}): nothing lost, nothing malformed"));
                } else {
                    out.clean = false;
                    out.lines.push(format!(
                        "loss ({tally}): {} message(s) lost, {} malformed",
                        r.lost_total(),
                        r.malformed_total()
                    ));
                    out.lines.extend(r.summary_lines().into_iter().map(|l| format!("  {l}")));
                }
            }
        }
        let sample_type = tyre_msgs::RigSample::ros_type_name();
        for t in self.topics().into_iter().filter(|t| t.ros_type == sample_type) {
            match self.sample_seq_gaps(&t.topic) {
                Ok((n, _, 0)) => out.lines.push(format!("{}: RigSample.seq continuous over {n} samples", t.topic)),
                Ok((n, gaps, missing)) => {
                    out.clean = false;
                    out.lines.push(format!(
                        "{}: RigSample.seq has {missing} missing in {} gap(s) over {n} samples (first: {})",
                        t.topic,
                        gaps.len(),
                        gaps.iter().take(5).map(ToString::to_string).collect::<Vec<_>>().join(" ")
                    ));
                }
                Err(e) => {
                    out.clean = false;
                    out.lines.push(format!("{}: {e}", t.topic));
                }
            }
        }
        out
    }

    /// Topics with their types and message counts, sorted by topic name.
    pub fn topics(&self) -> Vec<TopicInfo> {
        let mut by_topic: BTreeMap<&str, TopicInfo> = BTreeMap::new();
        for m in &self.messages {
            let e = by_topic.entry(&m.topic).or_insert_with(|| TopicInfo {
                topic: m.topic.clone(),
                ros_type: m.ros_type.clone(),
                messages: 0,
                first_log_time_ns: m.log_time_ns,
                last_log_time_ns: m.log_time_ns,
            });
            e.messages += 1;
            e.first_log_time_ns = e.first_log_time_ns.min(m.log_time_ns);
            e.last_log_time_ns = e.last_log_time_ns.max(m.log_time_ns);
        }
        by_topic.into_values().collect()
    }

    /// All messages of `topic`, decoded as `M`, with their log time, in log order.
    pub fn typed<M: RosMessage>(&self, topic: &str) -> Result<Vec<(u64, M)>, LogError> {
        let mut out = Vec::new();
        for (index, m) in self.messages.iter().filter(|m| m.topic == topic).enumerate() {
            if m.ros_type != M::ros_type_name() {
                return Err(LogError::WrongType {
                    path: self.path.clone(),
                    topic: topic.to_owned(),
                    found: m.ros_type.clone(),
                    expected: M::ros_type_name(),
                });
            }
            let msg = codec::decode::<M>(&m.data, &m.ros_type).map_err(|e| LogError::Decode {
                path: self.path.clone(),
                topic: topic.to_owned(),
                index,
                detail: e.to_string(),
            })?;
            out.push((m.log_time_ns, msg));
        }
        Ok(out)
    }
}

//! Replay: a recorded log back onto the same topics, with its original timing scaled.

use mcaplog::{LogError, LogReader, codec};
use node_runtime::{RosNode, RuntimeError, Shutdown, SuiteTopic, topics::TopicVisitor};
use std::{collections::BTreeMap, time::Duration};
use tyre_msgs::RosMessage;

/// How to replay.
#[derive(Debug, Clone)]
pub struct ReplayOptions {
    /// Time scale: 1 = as recorded, 10 = ten times faster. `None` = as fast as DDS takes it.
    pub speed: Option<f64>,
    /// Topics to replay (relative or full names); `None` = every topic in the log.
    pub topics: Option<Vec<String>>,
    /// Wait this long after creating the publishers, so subscribers can discover them.
    pub discovery_wait_s: f64,
    /// Draw a progress bar on stderr.
    pub progress: bool,
}

/// Why a replay failed.
#[derive(Debug, thiserror::Error)]
pub enum ReplayError {
    #[error(transparent)]
    Log(#[from] LogError),
    #[error(transparent)]
    Runtime(#[from] RuntimeError),
    #[error("{path}: topic {topic:?} is not a suite topic under namespace {namespace:?} (suite topics: {known})")]
    UnknownTopic { path: String, topic: String, namespace: String, known: String },
    #[error("--topics names {0:?}, which is not in the log")]
    TopicNotInLog(String),
    #[error("--speed {0}: expected a positive number (1 = real time)")]
    Speed(f64),
    #[error("{path}: topic {topic:?}, message {index}: {detail}")]
    Decode { path: String, topic: String, index: usize, detail: String },
    #[error("topic {topic:?}: publish failed: {detail}")]
    Publish { topic: String, detail: String },
}

/// What a replay did.
#[derive(Debug, Clone, PartialEq)]
pub struct ReplayStats {
    pub messages: u64,
    /// Log time covered [s].
    pub log_span_s: f64,
    /// Wall time spent publishing [s].
    pub wall_s: f64,
}

trait ErasedPublisher: Send {
    fn publish_cdr(&self, data: &[u8]) -> Result<(), String>;
}

struct Typed<M: RosMessage>(ros2_client::Publisher<M>);

impl<M: RosMessage + Send + Sync> ErasedPublisher for Typed<M> {
    fn publish_cdr(&self, data: &[u8]) -> Result<(), String> {
        let msg: M = codec::decode(data, &M::ros_type_name()).map_err(|e| e.to_string())?;
        self.0.publish(msg).map_err(|e| format!("{e:?}"))
    }
}

struct MakePublisher<'a>(&'a mut RosNode);

impl TopicVisitor for MakePublisher<'_> {
    type Output = Result<Box<dyn ErasedPublisher>, RuntimeError>;
    fn visit<M: RosMessage + Send + Sync + 'static>(self, topic: SuiteTopic) -> Self::Output {
        Ok(Box::new(Typed(self.0.publisher::<M>(topic)?)))
    }
}

/// Replays `log` through `node` (whose namespace must be the recording's).
pub async fn replay(
    mut node: RosNode,
    log: &LogReader,
    opts: &ReplayOptions,
    shutdown: Shutdown,
) -> Result<ReplayStats, ReplayError> {
    if let Some(s) = opts.speed
        && !(s.is_finite() && s > 0.0)
    {
        return Err(ReplayError::Speed(s));
    }
    let ns = node.namespace().to_owned();
    let path = log.path().display().to_string();
    let in_log: Vec<String> = log.topics().into_iter().map(|t| t.topic).collect();
    let wanted: Vec<String> = match &opts.topics {
        None => in_log.clone(),
        Some(list) => {
            let mut out = Vec::new();
            for name in list {
                let full = in_log
                    .iter()
                    .find(|t| {
                        *t == name || SuiteTopic::ALL.iter().any(|s| s.spec().name == name && s.full_name(&ns) == **t)
                    })
                    .ok_or_else(|| ReplayError::TopicNotInLog(name.clone()))?;
                out.push(full.clone());
            }
            out
        }
    };
    let mut publishers: BTreeMap<String, Box<dyn ErasedPublisher>> = BTreeMap::new();
    for topic in &wanted {
        let suite = SuiteTopic::from_full_name(topic, &ns).ok_or_else(|| ReplayError::UnknownTopic {
            path: path.clone(),
            topic: topic.clone(),
            namespace: ns.clone(),
            known: SuiteTopic::ALL.iter().map(|t| t.full_name(&ns)).collect::<Vec<_>>().join(", "),
        })?;
        publishers.insert(topic.clone(), suite.visit(MakePublisher(&mut node))?);
    }
    tokio::time::sleep(Duration::from_secs_f64(opts.discovery_wait_s.max(0.0))).await;

    let messages: Vec<_> = log.messages().iter().filter(|m| publishers.contains_key(&m.topic)).collect();
    let first_ns = messages.first().map_or(0, |m| m.log_time_ns);
    let last_ns = messages.last().map_or(0, |m| m.log_time_ns);
    let bar = if opts.progress {
        let b = indicatif::ProgressBar::new(messages.len() as u64);
        b.set_style(
            indicatif::ProgressStyle::with_template(
                "replay {bar:40.cyan/blue} {pos}/{len} msgs {elapsed_precise} eta {eta}",
            )
            .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
        );
        b
    } else {
        indicatif::ProgressBar::hidden()
    };
    let start = tokio::time::Instant::now();
    let mut sent = 0u64;
    let mut per_topic_index: BTreeMap<&str, usize> = BTreeMap::new();
    for m in &messages {
        if shutdown.is_triggered() {
            break;
        }
        if let Some(speed) = opts.speed {
            let due = Duration::from_secs_f64((m.log_time_ns - first_ns) as f64 * 1e-9 / speed);
            tokio::time::sleep_until(start + due).await;
        }
        let index = per_topic_index.entry(&m.topic).or_default();
        publishers[&m.topic].publish_cdr(&m.data).map_err(|detail| {
            if detail.contains("decode") {
                ReplayError::Decode { path: path.clone(), topic: m.topic.clone(), index: *index, detail }
            } else {
                ReplayError::Publish { topic: m.topic.clone(), detail }
            }
        })?;
        *index += 1;
        sent += 1;
        bar.inc(1);
    }
    bar.finish_and_clear();
    Ok(ReplayStats {
        messages: sent,
        log_span_s: (last_ns - first_ns) as f64 * 1e-9,
        wall_s: start.elapsed().as_secs_f64(),
    })
}

//! The test-pattern node: publishes message `n` of every selected topic at `rate_hz`.

use crate::pattern::pattern_message;
use node_runtime::{RosNode, RuntimeError, Shutdown, SuiteTopic, topics::TopicVisitor};
use serde::Deserialize;
use std::time::Duration;
use tyre_msgs::RosMessage;

/// `[node.config]` of a test_pattern node.
#[derive(Debug, Clone, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct TestPatternConfig {
    /// Messages per second per topic.
    #[serde(default = "default_rate")]
    pub rate_hz: f64,
    /// Stop after this many messages per topic (absent: until shut down).
    #[serde(default)]
    pub count: Option<u64>,
    /// Wait before the first message so subscribers can discover the publishers [s]. With
    /// `wait_for_subscribers`, this wait starts once they are discovered: it covers the
    /// writer-to-reader match that follows discovery.
    #[serde(default = "default_wait")]
    pub discovery_wait_s: f64,
    /// Before the first message, wait until every selected topic has this many subscriptions
    /// from other participants. A fixed wait alone loses the first samples of a volatile topic
    /// whenever discovery is slower than the wait (a loaded CI machine: it did).
    #[serde(default)]
    pub wait_for_subscribers: usize,
    /// Relative or full topic names; absent = every suite topic.
    #[serde(default)]
    pub topics: Option<Vec<String>>,
    /// After the last message, stay up this long so reliable DDS can retransmit anything a
    /// subscriber missed: a writer that exits at once can lose its last samples [s].
    #[serde(default = "default_linger")]
    pub linger_s: f64,
}

fn default_linger() -> f64 {
    2.0
}

fn default_rate() -> f64 {
    10.0
}
fn default_wait() -> f64 {
    1.0
}

/// Why the node stopped with an error.
#[derive(Debug, thiserror::Error)]
pub enum TestPatternError {
    #[error("test_pattern: rate_hz = {0}: expected 0 < rate ≤ 10000")]
    Rate(f64),
    #[error("test_pattern: topic {0:?} is not a suite topic")]
    UnknownTopic(String),
    #[error(transparent)]
    Runtime(#[from] RuntimeError),
    #[error("test_pattern: topic {topic}: {detail}")]
    Publish { topic: String, detail: String },
}

type PublishFn = Box<dyn Fn(u64) -> Result<(), String> + Send>;

struct Make<'a>(&'a mut RosNode);

impl TopicVisitor for Make<'_> {
    type Output = Result<PublishFn, RuntimeError>;
    fn visit<M: RosMessage + Send + Sync + 'static>(self, topic: SuiteTopic) -> Self::Output {
        let p = self.0.publisher::<M>(topic)?;
        Ok(Box::new(move |n| {
            let msg: M = pattern_message(n).map_err(|e| e.to_string())?;
            p.publish(msg).map_err(|e| format!("{e:?}"))
        }))
    }
}

/// Publishes until `count` is reached or shutdown. Returns the messages sent per topic.
pub async fn run(mut node: RosNode, cfg: TestPatternConfig, shutdown: Shutdown) -> Result<u64, TestPatternError> {
    if !(cfg.rate_hz.is_finite() && cfg.rate_hz > 0.0 && cfg.rate_hz <= 10_000.0) {
        return Err(TestPatternError::Rate(cfg.rate_hz));
    }
    let ns = node.namespace().to_owned();
    let topics: Vec<SuiteTopic> = match &cfg.topics {
        None => SuiteTopic::ALL.to_vec(),
        Some(names) => names
            .iter()
            .map(|n| {
                SuiteTopic::ALL
                    .into_iter()
                    .find(|t| t.spec().name == n || t.full_name(&ns) == *n)
                    .ok_or_else(|| TestPatternError::UnknownTopic(n.clone()))
            })
            .collect::<Result<_, _>>()?,
    };
    let mut publishers = Vec::new();
    for t in &topics {
        publishers.push((t.full_name(&ns), t.visit(Make(&mut node))?));
    }
    let mut last_report = tokio::time::Instant::now();
    while let Some(short) = topics.iter().find(|t| node.discovered_subscriptions(**t) < cfg.wait_for_subscribers) {
        if last_report.elapsed() >= Duration::from_secs(5) {
            let found = node.discovered_subscriptions(*short);
            let topic = short.full_name(&ns);
            tracing::info!("waiting for {} subscribers of {topic}, {found} so far", cfg.wait_for_subscribers);
            last_report = tokio::time::Instant::now();
        }
        tokio::select! {
            _ = shutdown.wait() => return Ok(0),
            _ = tokio::time::sleep(Duration::from_millis(50)) => {}
        }
    }
    tokio::select! {
        _ = shutdown.wait() => return Ok(0),
        _ = tokio::time::sleep(Duration::from_secs_f64(cfg.discovery_wait_s.max(0.0))) => {}
    }
    let mut tick = tokio::time::interval(Duration::from_secs_f64(1.0 / cfg.rate_hz));
    tick.set_missed_tick_behavior(tokio::time::MissedTickBehavior::Burst);
    let mut n = 0u64;
    while cfg.count.is_none_or(|c| n < c) {
        tokio::select! {
            _ = shutdown.wait() => break,
            _ = tick.tick() => {}
        }
        for (topic, publish) in &publishers {
            publish(n).map_err(|detail| TestPatternError::Publish { topic: topic.clone(), detail })?;
        }
        n += 1;
    }
    tokio::select! {
        _ = shutdown.wait() => {}
        _ = tokio::time::sleep(Duration::from_secs_f64(cfg.linger_s.max(0.0))) => {}
    }
    tracing::info!(messages_per_topic = n, "test pattern done");
    Ok(n)
}

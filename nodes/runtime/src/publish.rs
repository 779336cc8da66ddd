//! Publish errors of a node's shell, counted and logged — never dropped with `let _`.
//!
//! A publish fails when the writer refuses the message (its send window full for longer than the
//! topic's QoS waits) or DDS itself fails. The shell goes on (a control loop must not stop for a
//! status message), but the failure is counted per topic and logged: the first few and then
//! every 1,000th, so a persistent failure neither floods the log nor goes unseen.

use std::collections::BTreeMap;
use std::sync::Mutex;

use crate::SuiteTopic;

/// Failures logged in full before only every [`LOG_EVERY`]th is.
const LOG_FIRST: u64 = 5;
/// After the first [`LOG_FIRST`], every this many failures of a topic are logged.
const LOG_EVERY: u64 = 1000;

/// Publish failures of one node, per topic.
#[derive(Debug, Default)]
pub struct PublishErrors {
    counts: Mutex<BTreeMap<SuiteTopic, u64>>,
}

impl PublishErrors {
    pub fn new() -> Self {
        Self::default()
    }

    /// Counts and logs `result`'s error, if any, as a failed publish on `topic`.
    pub fn check<E: std::fmt::Debug>(&self, topic: SuiteTopic, result: Result<(), E>) {
        let Err(e) = result else { return };
        let n = {
            let mut counts = self.counts.lock().unwrap_or_else(std::sync::PoisonError::into_inner);
            let n = counts.entry(topic).or_default();
            *n += 1;
            *n
        };
        if n <= LOG_FIRST || n.is_multiple_of(LOG_EVERY) {
            let detail: String = format!("{e:?}").chars().take(80).collect();
            tracing::warn!("publish on {topic:?} failed ({n} so far): {detail}");
        }
    }

    /// Failures counted on `topic` so far.
    pub fn count(&self, topic: SuiteTopic) -> u64 {
        self.counts.lock().unwrap_or_else(std::sync::PoisonError::into_inner).get(&topic).copied().unwrap_or(0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn failures_are_counted_per_topic_and_successes_are_not() {
        let errors = PublishErrors::new();
        errors.check(SuiteTopic::Diagnostics, Ok::<(), &str>(()));
        for _ in 0..3 {
            errors.check(SuiteTopic::Diagnostics, Err::<(), _>("window full"));
        }
        errors.check(SuiteTopic::RigSetpoint, Err::<(), _>("window full"));
        assert_eq!(errors.count(SuiteTopic::Diagnostics), 3);
        assert_eq!(errors.count(SuiteTopic::RigSetpoint), 1);
        assert_eq!(errors.count(SuiteTopic::Clock), 0);
    }
}

//! [`LossLedger`]: every stream one node listens to.

use crate::record::{LossReport, StreamLoss};
use crate::tracker::{Observation, SeqTracker};
use std::collections::BTreeMap;

/// Which sequence number a tracker follows.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum SeqSource {
    /// The DDS writer's sequence number (every topic): what the transport or the reader lost.
    Dds,
    /// The message's own counter (`RigSample.seq`): what was lost anywhere after the rig made
    /// the sample, publisher side included.
    Message,
}

impl SeqSource {
    pub fn as_str(self) -> &'static str {
        match self {
            SeqSource::Dds => "dds",
            SeqSource::Message => "msg",
        }
    }

    pub fn parse(s: &str) -> Option<Self> {
        match s {
            "dds" => Some(SeqSource::Dds),
            "msg" => Some(SeqSource::Message),
            _ => None,
        }
    }
}

/// One stream: a topic, a writer on it, and which sequence number.
#[derive(Debug, Clone, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct StreamKey {
    pub topic: String,
    /// The writer's id (DDS GUID as 128 bits).
    pub writer: u128,
    pub source: SeqSource,
}

#[derive(Debug, Clone, Default)]
struct TopicEntry {
    streams: BTreeMap<(u128, SeqSource), SeqTracker>,
    malformed: u64,
}

/// Writers per topic a ledger follows at most; messages of further writers are counted under
/// one catch-all writer id 0, so a peer inventing writers cannot grow a node's memory.
pub const MAX_WRITERS_PER_TOPIC: usize = 64;

/// Every stream one node receives, with its losses and its malformed messages.
#[derive(Debug, Clone, Default)]
pub struct LossLedger {
    topics: BTreeMap<String, TopicEntry>,
    lost_total: u64,
    /// The streams' tails summed, kept up to date by `observe` and `claim` (a tail only shrinks
    /// when a message arrives and only grows on a claim).
    tails_total: u64,
    malformed_total: u64,
}

impl LossLedger {
    pub fn new() -> Self {
        Self::default()
    }

    fn entry(&mut self, topic: &str) -> &mut TopicEntry {
        // Look up by &str first: the hot path allocates nothing.
        if !self.topics.contains_key(topic) {
            self.topics.insert(topic.to_owned(), TopicEntry::default());
        }
        self.topics.get_mut(topic).expect("inserted above")
    }

    /// Records sequence number `seq` of `writer` on `topic`.
    pub fn observe(&mut self, topic: &str, writer: u128, source: SeqSource, seq: u64) -> Observation {
        let entry = self.entry(topic);
        let writer = if entry.streams.contains_key(&(writer, source))
            || entry.streams.keys().filter(|(_, s)| *s == source).count() < MAX_WRITERS_PER_TOPIC
        {
            writer
        } else {
            0
        };
        let tracker = entry.streams.entry((writer, source)).or_default();
        let tail_before = tracker.tail();
        let obs = tracker.observe(seq);
        let shrunk = tail_before - tracker.tail();
        self.tails_total = self.tails_total.saturating_sub(shrunk);
        if let Observation::Gap(g) = obs {
            self.lost_total = self.lost_total.saturating_add(g.len());
        }
        obs
    }

    /// Counts a message on `topic` that arrived but could not be decoded; returns the topic's
    /// count so far.
    pub fn malformed(&mut self, topic: &str) -> u64 {
        self.malformed_total = self.malformed_total.saturating_add(1);
        let e = self.entry(topic);
        e.malformed = e.malformed.saturating_add(1);
        e.malformed
    }

    /// `writer` says it made every message of `topic` up to sequence number `upto` (by
    /// `source`): see [`SeqTracker::claim`]. Returns the stream's tail after the claim (0 for a
    /// writer this ledger has not seen a message from).
    pub fn claim(&mut self, topic: &str, writer: u128, source: SeqSource, upto: u64) -> u64 {
        match self.topics.get_mut(topic).and_then(|e| e.streams.get_mut(&(writer, source))) {
            Some(t) => {
                let before = t.tail();
                t.claim(upto);
                self.tails_total = self.tails_total.saturating_add(t.tail() - before);
                t.tail()
            }
            None => 0,
        }
    }

    /// Messages lost on every stream so far (both sources): gaps, and tails (what writers say
    /// they made after the last message received).
    pub fn lost_total(&self) -> u64 {
        self.lost_total.saturating_add(self.tails_total)
    }

    /// Malformed messages so far.
    pub fn malformed_total(&self) -> u64 {
        self.malformed_total
    }

    /// The tracker of one stream, if it has seen anything.
    pub fn tracker(&self, key: &StreamKey) -> Option<&SeqTracker> {
        self.topics.get(&key.topic)?.streams.get(&(key.writer, key.source))
    }

    /// The ledger as a report (`complete` says whether the node is done receiving).
    pub fn report(&self, complete: bool) -> LossReport {
        let mut streams = Vec::new();
        let mut malformed = BTreeMap::new();
        for (topic, e) in &self.topics {
            if e.malformed > 0 {
                malformed.insert(topic.clone(), e.malformed);
            }
            for (&(writer, source), t) in &e.streams {
                streams.push(StreamLoss {
                    topic: topic.clone(),
                    writer,
                    source,
                    received: t.received(),
                    lost: t.lost(),
                    late: t.late(),
                    first_seq: t.first_seq().unwrap_or(0),
                    last_seq: t.last_seq().unwrap_or(0),
                    gaps: t.gaps().to_vec(),
                    gaps_total: t.gaps_total(),
                    tail: t.tail(),
                });
            }
        }
        LossReport { complete, streams, malformed }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Gap;

    #[test]
    fn writers_and_sources_are_separate_streams() {
        let mut l = LossLedger::new();
        l.observe("/rig/sample", 1, SeqSource::Dds, 1);
        l.observe("/rig/sample", 1, SeqSource::Dds, 3);
        l.observe("/rig/sample", 2, SeqSource::Dds, 10);
        l.observe("/rig/sample", 1, SeqSource::Message, 0);
        l.observe("/rig/sample", 1, SeqSource::Message, 1);
        assert_eq!(l.lost_total(), 1);
        let key = StreamKey { topic: "/rig/sample".into(), writer: 1, source: SeqSource::Dds };
        assert_eq!(l.tracker(&key).map(|t| t.gaps().to_vec()), Some(vec![Gap { first: 2, last: 2 }]));
        assert_eq!(l.report(false).streams.len(), 3);
    }

    #[test]
    fn invented_writers_share_one_catch_all_stream() {
        let mut l = LossLedger::new();
        for w in 1..=1000u128 {
            l.observe("/rig/sample", w, SeqSource::Dds, 1);
        }
        let r = l.report(true);
        assert_eq!(r.streams.len(), MAX_WRITERS_PER_TOPIC + 1);
        assert!(r.streams.iter().any(|s| s.writer == 0));
    }

    #[test]
    fn a_tail_counts_as_loss_until_the_stream_goes_on() {
        let mut l = LossLedger::new();
        assert_eq!(l.claim("/rig/sample", 1, SeqSource::Message, 9), 0, "no message seen: nothing owed");
        for s in 0..5 {
            l.observe("/rig/sample", 1, SeqSource::Message, s);
        }
        assert_eq!(l.claim("/rig/sample", 1, SeqSource::Message, 9), 5);
        assert_eq!(l.lost_total(), 5);
        let r = l.report(true);
        assert_eq!((r.streams[0].tail, r.lost_total()), (5, 5));
        assert!(!r.is_clean());
        l.observe("/rig/sample", 1, SeqSource::Message, 12);
        assert_eq!(l.lost_total(), 7, "the tail became a gap of 7 (5-11)");
        l.claim("/rig/sample", 1, SeqSource::Message, 20);
        l.observe("/rig/sample", 1, SeqSource::Message, 13);
        assert_eq!(l.lost_total(), 14, "gaps 7, tail 14-20");
        let r = l.report(true);
        assert_eq!(r.lost_total(), l.lost_total());
    }

    proptest::proptest! {
        /// Whatever arrives and whatever the writers claim, the running total is every stream's
        /// gaps plus its tail.
        #[test]
        fn the_running_total_is_gaps_plus_tails(
            events in proptest::collection::vec((0u128..3, proptest::bool::ANY, 0u64..300), 1..200)
        ) {
            let mut l = LossLedger::new();
            for (writer, is_claim, seq) in events {
                if is_claim {
                    l.claim("/t", writer, SeqSource::Message, seq);
                } else {
                    l.observe("/t", writer, SeqSource::Message, seq);
                }
            }
            let r = l.report(false);
            let sum: u64 = r.streams.iter().map(|s| s.lost + s.tail).sum();
            proptest::prop_assert_eq!(l.lost_total(), sum);
        }
    }

    #[test]
    fn malformed_counts_per_topic() {
        let mut l = LossLedger::new();
        assert_eq!(l.malformed("/rig/sample"), 1);
        assert_eq!(l.malformed("/rig/sample"), 2);
        l.malformed("/rig/setpoint");
        assert_eq!(l.malformed_total(), 3);
        assert_eq!(l.report(true).malformed.get("/rig/sample"), Some(&2));
    }
}

//! [`LossReport`]: a ledger frozen, as the log's key/value record and as lines for people.
//!
//! The record (MCAP metadata named [`LOSS_RECORD`]) holds, for every stream,
//! `"<topic> <source> <writer> <field>" = value`:
//! `received`, `lost`, `late`, `first_seq`, `last_seq`, `gaps` (the first ranges,
//! `"12-15 40"`), `gaps_total` and `tail` (what the writer says it made after the last message
//! received: a stream that stopped early); and per topic `"<topic> malformed"`. Topic names never
//! hold a space, so the key splits unambiguously. `complete = true` marks the final count; a log
//! whose recorder was killed keeps the last interim record (`complete = false`). Records of
//! format 1 (before tails were counted) read with a tail of 0.

use crate::ledger::SeqSource;
use crate::tracker::Gap;
use std::collections::BTreeMap;

/// Name of the metadata record holding a log's loss report.
pub const LOSS_RECORD: &str = "tyrerig.loss";
const FORMAT: &str = "tyrerig-loss/2";
/// The format before `tail`; still read.
const FORMAT_1: &str = "tyrerig-loss/1";

/// One stream's losses.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct StreamLoss {
    pub topic: String,
    pub writer: u128,
    pub source: SeqSource,
    pub received: u64,
    pub lost: u64,
    pub late: u64,
    pub first_seq: u64,
    pub last_seq: u64,
    /// The first gaps (at most [`crate::tracker::MAX_GAP_RANGES`]).
    pub gaps: Vec<Gap>,
    pub gaps_total: u64,
    /// Messages the writer says it made after `last_seq` that never arrived (its own count,
    /// announced beside the stream): lost, though no later message shows a gap.
    pub tail: u64,
}

/// What a receiver lost, per stream, and what it could not decode, per topic.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct LossReport {
    /// The receiver had stopped when the report was made (final count).
    pub complete: bool,
    pub streams: Vec<StreamLoss>,
    pub malformed: BTreeMap<String, u64>,
}

/// A loss record that cannot be read.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("loss record {LOSS_RECORD:?}: {0}")]
pub struct RecordError(pub String);

/// Per-topic totals of a report.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct TopicLoss {
    pub topic: String,
    pub writers: usize,
    pub received: u64,
    pub lost: u64,
    pub gaps: u64,
    /// Lost by the message's own counter (`RigSample.seq`), where the topic has one; tails
    /// included.
    pub msg_lost: Option<u64>,
    /// Of the losses, what writers made after the last message received (tails).
    pub tail: u64,
    pub malformed: u64,
}

impl LossReport {
    /// Messages lost on every stream (the larger of the two counts where a topic has both).
    pub fn lost_total(&self) -> u64 {
        self.by_topic().iter().map(|t| t.lost.max(t.msg_lost.unwrap_or(0))).fold(0, u64::saturating_add)
    }

    pub fn malformed_total(&self) -> u64 {
        self.malformed.values().fold(0, |a, b| a.saturating_add(*b))
    }

    /// Nothing lost, nothing malformed.
    pub fn is_clean(&self) -> bool {
        self.lost_total() == 0 && self.malformed_total() == 0
    }

    /// Totals per topic, sorted by topic.
    pub fn by_topic(&self) -> Vec<TopicLoss> {
        let mut out: BTreeMap<&str, TopicLoss> = BTreeMap::new();
        for s in &self.streams {
            let t = out.entry(&s.topic).or_insert_with(|| TopicLoss { topic: s.topic.clone(), ..Default::default() });
            let lost = s.lost.saturating_add(s.tail);
            t.tail = t.tail.saturating_add(s.tail);
            match s.source {
                SeqSource::Dds => {
                    t.writers += 1;
                    t.received = t.received.saturating_add(s.received);
                    t.lost = t.lost.saturating_add(lost);
                    t.gaps = t.gaps.saturating_add(s.gaps_total);
                }
                SeqSource::Message => t.msg_lost = Some(t.msg_lost.unwrap_or(0).saturating_add(lost)),
            }
        }
        for (topic, n) in &self.malformed {
            out.entry(topic).or_insert_with(|| TopicLoss { topic: topic.clone(), ..Default::default() }).malformed = *n;
        }
        out.into_values().collect()
    }

    /// One line per topic that lost or refused anything (empty when clean), for `mcap info`,
    /// reports and the fitter.
    pub fn summary_lines(&self) -> Vec<String> {
        let mut lines = Vec::new();
        for t in self.by_topic() {
            if t.lost == 0 && t.msg_lost.unwrap_or(0) == 0 && t.malformed == 0 {
                continue;
            }
            let mut line = format!("{}: lost {} of {} in {} gap(s)", t.topic, t.lost, t.received + t.lost, t.gaps);
            if let Some(m) = t.msg_lost {
                line.push_str(&format!(", {m} missing by the message counter"));
            }
            if t.tail > 0 {
                line.push_str(&format!(
                    ", {} of them made after the last one received and never arrived (the writer's own count)",
                    t.tail
                ));
            }
            if t.malformed > 0 {
                line.push_str(&format!(", {} malformed message(s) refused", t.malformed));
            }
            lines.push(line);
        }
        if !self.complete && !lines.is_empty() {
            lines.push("(interim count: the recorder stopped before its final tally)".into());
        }
        lines
    }

    /// The report as the log's key/value record.
    pub fn to_entries(&self) -> BTreeMap<String, String> {
        let mut m = BTreeMap::new();
        m.insert("format".to_owned(), FORMAT.to_owned());
        m.insert("complete".to_owned(), self.complete.to_string());
        m.insert("lost_total".to_owned(), self.lost_total().to_string());
        m.insert("malformed_total".to_owned(), self.malformed_total().to_string());
        for s in &self.streams {
            let k = |field: &str| format!("{} {} {:032x} {field}", s.topic, s.source.as_str(), s.writer);
            m.insert(k("received"), s.received.to_string());
            m.insert(k("lost"), s.lost.to_string());
            m.insert(k("late"), s.late.to_string());
            m.insert(k("first_seq"), s.first_seq.to_string());
            m.insert(k("last_seq"), s.last_seq.to_string());
            m.insert(k("gaps_total"), s.gaps_total.to_string());
            m.insert(k("tail"), s.tail.to_string());
            m.insert(k("gaps"), s.gaps.iter().map(ToString::to_string).collect::<Vec<_>>().join(" "));
        }
        for (topic, n) in &self.malformed {
            m.insert(format!("{topic} malformed"), n.to_string());
        }
        m
    }

    /// Reads a record written by [`LossReport::to_entries`]; errors name the key.
    pub fn from_entries(entries: &BTreeMap<String, String>) -> Result<Self, RecordError> {
        let err = |m: String| RecordError(m);
        match entries.get("format").map(String::as_str) {
            Some(FORMAT | FORMAT_1) => {}
            other => return Err(err(format!("format {other:?}: expected {FORMAT:?} or {FORMAT_1:?}"))),
        }
        let complete = match entries.get("complete").map(String::as_str) {
            Some("true") => true,
            Some("false") => false,
            other => return Err(err(format!("complete = {other:?}: expected true or false"))),
        };
        let mut streams: BTreeMap<(String, SeqSource, u128), StreamLoss> = BTreeMap::new();
        let mut malformed = BTreeMap::new();
        for (key, value) in entries {
            if matches!(key.as_str(), "format" | "complete" | "lost_total" | "malformed_total") {
                continue;
            }
            let number = || value.parse::<u64>().map_err(|_| err(format!("{key:?} = {value:?}: expected a count")));
            let parts: Vec<&str> = key.split(' ').collect();
            match parts.as_slice() {
                [topic, "malformed"] => {
                    malformed.insert((*topic).to_owned(), number()?);
                }
                [topic, source, writer, field] => {
                    let source = SeqSource::parse(source)
                        .ok_or_else(|| err(format!("{key:?}: source {source:?} is not dds or msg")))?;
                    let writer = u128::from_str_radix(writer, 16)
                        .map_err(|_| err(format!("{key:?}: writer {writer:?} is not a hexadecimal id")))?;
                    let s = streams.entry(((*topic).to_owned(), source, writer)).or_insert_with(|| StreamLoss {
                        topic: (*topic).to_owned(),
                        writer,
                        source,
                        received: 0,
                        lost: 0,
                        late: 0,
                        first_seq: 0,
                        last_seq: 0,
                        gaps: Vec::new(),
                        gaps_total: 0,
                        tail: 0,
                    });
                    match *field {
                        "received" => s.received = number()?,
                        "lost" => s.lost = number()?,
                        "late" => s.late = number()?,
                        "first_seq" => s.first_seq = number()?,
                        "last_seq" => s.last_seq = number()?,
                        "gaps_total" => s.gaps_total = number()?,
                        "tail" => s.tail = number()?,
                        "gaps" => s.gaps = parse_gaps(value).map_err(|m| err(format!("{key:?}: {m}")))?,
                        other => return Err(err(format!("{key:?}: unknown field {other:?}"))),
                    }
                }
                _ => return Err(err(format!("unexpected key {key:?}"))),
            }
        }
        Ok(Self { complete, streams: streams.into_values().collect(), malformed })
    }
}

fn parse_gaps(text: &str) -> Result<Vec<Gap>, String> {
    let bad = |g: &str| format!("gap {g:?}: expected N or FIRST-LAST with FIRST <= LAST");
    text.split_whitespace()
        .take(crate::tracker::MAX_GAP_RANGES)
        .map(|g| {
            let (a, b) = g.split_once('-').unwrap_or((g, g));
            let first = a.parse::<u64>().map_err(|_| bad(g))?;
            let last = b.parse::<u64>().map_err(|_| bad(g))?;
            if first > last { Err(bad(g)) } else { Ok(Gap { first, last }) }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::LossLedger;
    use proptest::prelude::*;

    fn sample_ledger() -> LossLedger {
        let mut l = LossLedger::new();
        for s in [1, 2, 3, 7, 8, 20] {
            l.observe("/rig/sample", 0xabc, SeqSource::Dds, s);
        }
        for s in [0, 1, 2, 6, 7, 19] {
            l.observe("/rig/sample", 0xabc, SeqSource::Message, s);
        }
        l.observe("/rig/setpoint", 0xdef, SeqSource::Dds, 5);
        l.malformed("/rig/sample");
        l
    }

    #[test]
    fn the_record_round_trips() {
        let r = sample_ledger().report(true);
        let e = r.to_entries();
        assert_eq!(e["lost_total"], "14");
        assert_eq!(e[&format!("/rig/sample dds {:032x} gaps", 0xabc)], "4-6 9-19");
        assert_eq!(LossReport::from_entries(&e), Ok(r));
    }

    #[test]
    fn summary_names_topics_with_loss_only() {
        let lines = sample_ledger().report(true).summary_lines();
        assert_eq!(
            lines,
            [
                "/rig/sample: lost 14 of 20 in 2 gap(s), 14 missing by the message counter, 1 malformed message(s) refused"
            ]
        );
        assert!(LossLedger::new().report(true).summary_lines().is_empty());
        assert!(LossLedger::new().report(true).is_clean());
    }

    #[test]
    fn a_tail_is_loss_in_the_record_and_the_summary() {
        let mut l = sample_ledger();
        l.claim("/rig/sample", 0xabc, SeqSource::Message, 25); // made up to 25, got up to 19
        let r = l.report(true);
        let e = r.to_entries();
        assert_eq!(e[&format!("/rig/sample msg {:032x} tail", 0xabc)], "6");
        assert_eq!(e[&format!("/rig/sample msg {:032x} lost", 0xabc)], "14", "gaps alone");
        assert_eq!(e["lost_total"], "20");
        assert_eq!(LossReport::from_entries(&e), Ok(r.clone()));
        assert_eq!(
            r.summary_lines(),
            ["/rig/sample: lost 14 of 20 in 2 gap(s), 20 missing by the message counter, 6 of them made after the \
                 last one received and never arrived (the writer's own count), 1 malformed message(s) refused"]
        );
        // A stream that lost nothing but its tail is not clean.
        let mut clean = LossLedger::new();
        for s in 0..10 {
            clean.observe("/rig/sample", 1, SeqSource::Message, s);
        }
        assert!(clean.report(true).is_clean());
        clean.claim("/rig/sample", 1, SeqSource::Message, 12);
        assert!(!clean.report(true).is_clean());
    }

    #[test]
    fn format_1_records_still_read() {
        let r = sample_ledger().report(true);
        let mut e = r.to_entries();
        e.insert("format".into(), FORMAT_1.into());
        e.retain(|k, _| !k.ends_with(" tail"));
        assert_eq!(LossReport::from_entries(&e), Ok(r));
    }

    #[test]
    fn bad_records_are_named() {
        let mut e = sample_ledger().report(true).to_entries();
        e.insert("/rig/sample dds zz lost".into(), "1".into());
        let msg = LossReport::from_entries(&e).expect_err("bad writer").to_string();
        assert!(msg.contains("zz") && msg.contains(LOSS_RECORD), "{msg}");
        let mut e = sample_ledger().report(true).to_entries();
        e.insert(format!("/rig/sample dds {:032x} gaps", 1), "9-3".into());
        assert!(LossReport::from_entries(&e).expect_err("reversed gap").to_string().contains("9-3"));
        assert!(LossReport::from_entries(&BTreeMap::new()).is_err());
    }

    proptest! {
        #![proptest_config(ProptestConfig { cases: 256, ..ProptestConfig::default() })]

        /// Any key/value map is either a report or a clear error; never a panic.
        #[test]
        fn any_record_reads_or_errs(entries in proptest::collection::btree_map(".{0,40}", ".{0,40}", 0..8),
                                    keep_format in any::<bool>()) {
            let mut entries = entries;
            if keep_format {
                entries.insert("format".into(), FORMAT.into());
                entries.insert("complete".into(), "true".into());
            }
            let _ = LossReport::from_entries(&entries);
        }

        /// Whatever sequence arrives, received + lost spans first..=last, and the report
        /// round-trips.
        #[test]
        fn accounting_adds_up(seqs in proptest::collection::vec(0u64..500, 1..200)) {
            let mut l = LossLedger::new();
            for s in &seqs {
                l.observe("/t", 7, SeqSource::Dds, *s);
            }
            let r = l.report(false);
            let s = &r.streams[0];
            prop_assert_eq!(s.received + s.lost, s.last_seq - s.first_seq + 1);
            prop_assert_eq!(s.received + s.late, seqs.len() as u64);
            prop_assert_eq!(LossReport::from_entries(&r.to_entries()), Ok(r.clone()));
        }
    }
}

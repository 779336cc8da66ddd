//! [`LossWatch`]: every subscriber's loss and malformed-input accounting, and its
//! `/diagnostics` announcements.
//!
//! A shell hands each item its subscription streams yield to the watch: a message with its DDS
//! `MessageInfo` (the writer's GUID and sequence number, and for `RigSample` the rig's own
//! `seq`), or a read error. Gaps in either sequence are loss; a payload that does not decode is
//! counted as malformed (the DDS reader skips it, so it also leaves a one-message gap in its
//! writer's sequence). The bookkeeping is `streamloss`; this module adds the DDS side and the
//! announcements: the first loss or refusal is announced at once, later ones are gathered and
//! announced at most once per [`ANNOUNCE_EVERY`], so a flood cannot flood `/diagnostics` too.
//!
//! A gap shows only when a later message arrives: a stream that stops early while its writer is
//! still there (its samples refused by a full send window, say) leaves none. So a publisher also
//! announces its own count ([`WriterTally`], on `/diagnostics` once a second: the last
//! `RigSample.seq` it made, how many it published and how many its writer refused), and a watch
//! that is given those ([`LossWatch::on_tally`]) counts what was made after the last message it
//! received as the stream's tail, [`TALLY_GRACE`] after the announcement arrived.

use ros2_client::{MessageInfo, ros2::ReadError};
use std::{
    collections::{BTreeMap, VecDeque},
    time::{Duration, Instant},
};
use streamloss::{LossLedger, Observation, SeqSource};
use tyre_msgs::{
    builtin_interfaces::Time,
    diagnostic_msgs::{DiagnosticArray, DiagnosticStatus, KeyValue},
    std_msgs::Header,
};

/// Shortest time between two loss announcements of one node.
pub const ANNOUNCE_EVERY: Duration = Duration::from_secs(1);
/// Notes kept for the next announcement; more are counted, not kept.
const MAX_NOTES: usize = 8;

/// The writer of a received message as a 128-bit id (its DDS GUID).
pub fn writer_id(info: &MessageInfo) -> u128 {
    u128::from_be_bytes(info.publisher_gid().to_bytes16())
}

/// A publisher's id in the form [`writer_id`] gives its messages.
pub fn publisher_id<M: serde::Serialize>(publisher: &ros2_client::Publisher<M>) -> u128 {
    u128::from_be_bytes(publisher.gid().to_bytes16())
}

/// How long after a [`WriterTally`] arrives what it claims must have arrived too. A tally is
/// published right after the message it counts, on another writer, so it can overtake it.
pub const TALLY_GRACE: Duration = Duration::from_secs(1);

/// Suffix of a tally's `/diagnostics` status name (`virtual_rig: published`).
pub const TALLY_STATUS: &str = ": published";

/// A publisher's own count of one stream (a topic with a message counter, `RigSample.seq`),
/// announced on `/diagnostics` as a status named `<node>: published` so that readers can tell a
/// tail that never came ([`LossWatch::on_tally`]).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct WriterTally {
    /// The topic's full name.
    pub topic: String,
    /// The DDS writer ([`publisher_id`]).
    pub writer: u128,
    /// The message counter of the last message made (published or refused).
    pub last_seq: u64,
    /// Messages the writer took.
    pub published: u64,
    /// Messages the writer refused (its send window full).
    pub refused: u64,
}

impl WriterTally {
    /// The tally as a `/diagnostics` status of `node`: OK, or WARN once the writer has refused
    /// anything.
    pub fn to_status(&self, node: &str) -> DiagnosticStatus {
        let kv = |key: &str, value: String| KeyValue { key: key.into(), value };
        DiagnosticStatus {
            level: if self.refused == 0 { DiagnosticStatus::OK } else { DiagnosticStatus::WARN },
            name: format!("{node}{TALLY_STATUS}"),
            message: format!(
                "{}: made up to seq {}, {} published, {} refused by the writer",
                self.topic, self.last_seq, self.published, self.refused
            ),
            hardware_id: "dds".into(),
            values: vec![
                kv("topic", self.topic.clone()),
                kv("writer", format!("{:032x}", self.writer)),
                kv("last_seq", self.last_seq.to_string()),
                kv("published", self.published.to_string()),
                kv("refused", self.refused.to_string()),
            ],
        }
    }

    /// A tally read back from a status; `None` for any other status (or a malformed one).
    pub fn from_status(status: &DiagnosticStatus) -> Option<Self> {
        if !status.name.ends_with(TALLY_STATUS) {
            return None;
        }
        let get = |key: &str| status.values.iter().find(|kv| kv.key == key).map(|kv| kv.value.as_str());
        Some(Self {
            topic: get("topic")?.to_owned(),
            writer: u128::from_str_radix(get("writer")?, 16).ok()?,
            last_seq: get("last_seq")?.parse().ok()?,
            published: get("published")?.parse().ok()?,
            refused: get("refused")?.parse().ok()?,
        })
    }
}

/// Streams with tallies a watch follows at most (a peer inventing writers cannot grow it).
const MAX_TALLIED_STREAMS: usize = 64;
/// Tallies waiting out their grace per stream; older ones are dropped (a later claim covers them).
const MAX_PENDING_TALLIES: usize = 8;

/// One node's loss accounting.
#[derive(Debug)]
pub struct LossWatch {
    node: String,
    ledger: LossLedger,
    notes: Vec<String>,
    notes_dropped: u64,
    last_announce: Option<Instant>,
    /// (topic, writer) → tallies not yet applied: (arrival, last_seq made).
    tallies: BTreeMap<(String, u128), VecDeque<(Instant, u64)>>,
    /// (topic, writer) → the tail last announced.
    tails: BTreeMap<(String, u128), u64>,
}

impl LossWatch {
    pub fn new(node: &str) -> Self {
        Self {
            node: node.to_owned(),
            ledger: LossLedger::new(),
            notes: Vec::new(),
            notes_dropped: 0,
            last_announce: None,
            tallies: BTreeMap::new(),
            tails: BTreeMap::new(),
        }
    }

    fn note(&mut self, text: String) {
        if self.notes.len() < MAX_NOTES {
            self.notes.push(text);
        } else {
            self.notes_dropped += 1;
        }
    }

    /// A message arrived on `topic`: checks its writer's DDS sequence and, when the message has
    /// one (`RigSample.seq`), its own counter. Returns true if anything was found missing.
    pub fn on_message(&mut self, topic: &str, info: &MessageInfo, message_seq: Option<u64>) -> bool {
        let writer = writer_id(info);
        let mut gap = false;
        let dds_seq = info.sequence_number();
        if dds_seq >= 0
            && let Observation::Gap(g) = self.ledger.observe(topic, writer, SeqSource::Dds, dds_seq as u64)
        {
            tracing::warn!(
                "{}: lost {} message(s) on {topic} from writer {writer:032x}: DDS seq {g}",
                self.node,
                g.len()
            );
            self.note(format!("{topic}: {} lost (DDS seq {g})", g.len()));
            gap = true;
        }
        if let Some(seq) = message_seq
            && let Observation::Gap(g) = self.ledger.observe(topic, writer, SeqSource::Message, seq)
        {
            tracing::warn!("{}: {} sample(s) missing on {topic}: seq {g}", self.node, g.len());
            self.note(format!("{topic}: {} missing (seq {g})", g.len()));
            gap = true;
        }
        gap
    }

    /// A read error on `topic`: a payload that does not decode is counted as malformed.
    pub fn on_read_error(&mut self, topic: &str, error: &ReadError) {
        match error {
            ReadError::Deserialization { reason } => {
                let n = self.ledger.malformed(topic);
                // The first few per topic are logged in full; then every 1000th, so a hostile
                // peer cannot fill the log.
                if n <= 5 || n.is_multiple_of(1000) {
                    tracing::warn!("{}: malformed message on {topic} refused ({n} so far): {reason}", self.node);
                }
                self.note(format!("{topic}: malformed message refused ({n} so far)"));
            }
            other => tracing::warn!("{}: receive error on {topic}: {other:?}", self.node),
        }
    }

    /// A writer's own count arrived at `now` ([`WriterTally`]): everything it made up to
    /// `last_seq` must have arrived [`TALLY_GRACE`] later. Applied by [`LossWatch::apply_tallies`].
    pub fn on_tally(&mut self, tally: &WriterTally, now: Instant) {
        let key = (tally.topic.clone(), tally.writer);
        if !self.tallies.contains_key(&key) && self.tallies.len() >= MAX_TALLIED_STREAMS {
            return;
        }
        let pending = self.tallies.entry(key).or_default();
        if pending.len() >= MAX_PENDING_TALLIES {
            pending.pop_front();
        }
        pending.push_back((now, tally.last_seq));
    }

    /// Applies the tallies that arrived at least [`TALLY_GRACE`] before `now` (every one, with
    /// `now = None`: the receiver has taken all it will take). A stream whose writer made more
    /// than arrived has a tail: lost, logged and announced as it grows.
    pub fn apply_tallies(&mut self, now: Option<Instant>) {
        let mut claims = Vec::new();
        for ((topic, writer), pending) in &mut self.tallies {
            while let Some(&(at, seq)) = pending.front() {
                if now.is_some_and(|n| n.duration_since(at) < TALLY_GRACE) {
                    break;
                }
                claims.push((topic.clone(), *writer, seq));
                pending.pop_front();
            }
        }
        for (topic, writer, seq) in claims {
            let tail = self.ledger.claim(&topic, writer, SeqSource::Message, seq);
            let before = self.tails.get(&(topic.clone(), writer)).copied().unwrap_or(0);
            if tail > before {
                let last = self
                    .ledger
                    .tracker(&streamloss::StreamKey { topic: topic.clone(), writer, source: SeqSource::Message })
                    .and_then(|t| t.last_seq())
                    .unwrap_or(0);
                tracing::warn!(
                    "{}: {tail} message(s) on {topic} from writer {writer:032x} never arrived: its writer made up to \
                     seq {seq}, the last received is {last}",
                    self.node
                );
                self.note(format!("{topic}: {tail} made but not received after seq {last} (the writer's count)"));
            }
            self.tails.insert((topic, writer), tail);
        }
    }

    /// The `/diagnostics` announcement due now, if any: at once for the first loss, then at most
    /// once per [`ANNOUNCE_EVERY`]. `stamp` is the node's current (rig) time.
    pub fn announcement(&mut self, now: Instant, stamp: Time) -> Option<DiagnosticArray> {
        if self.notes.is_empty() || self.last_announce.is_some_and(|t| now.duration_since(t) < ANNOUNCE_EVERY) {
            return None;
        }
        self.last_announce = Some(now);
        let mut message = self.notes.join("; ");
        if self.notes_dropped > 0 {
            message.push_str(&format!("; and {} more", self.notes_dropped));
        }
        self.notes.clear();
        self.notes_dropped = 0;
        let status = DiagnosticStatus {
            level: DiagnosticStatus::WARN,
            name: format!("{}: data loss", self.node),
            message,
            hardware_id: "dds".into(),
            values: vec![
                KeyValue { key: "lost_total".into(), value: self.ledger.lost_total().to_string() },
                KeyValue { key: "malformed_total".into(), value: self.ledger.malformed_total().to_string() },
            ],
        };
        Some(DiagnosticArray { header: Header { stamp, frame_id: String::new() }, status: vec![status] })
    }

    /// Publishes the announcement due now (see [`LossWatch::announcement`]) on `diagnostics`.
    pub fn announce(&mut self, diagnostics: &ros2_client::Publisher<DiagnosticArray>, stamp: Time) {
        if let Some(d) = self.announcement(Instant::now(), stamp)
            && let Err(e) = diagnostics.publish(d)
        {
            tracing::warn!("/diagnostics publish: {e:?}");
        }
    }

    pub fn ledger(&self) -> &LossLedger {
        &self.ledger
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use ros2_client::{Gid, MessageInfo};

    const TOPIC: &str = "/rig/sample";

    fn info(writer: u128, dds_seq: i64) -> MessageInfo {
        MessageInfo::new(None, None, dds_seq, Gid::from(writer.to_be_bytes()), None)
    }

    fn tally(writer: u128, last_seq: u64, refused: u64) -> WriterTally {
        WriterTally { topic: TOPIC.into(), writer, last_seq, published: last_seq + 1 - refused, refused }
    }

    #[test]
    fn a_tally_round_trips_through_its_status_and_others_are_not_tallies() {
        let t = tally(0xfeed, 4711, 3);
        let st = t.to_status("virtual_rig");
        assert_eq!((st.name.as_str(), st.level), ("virtual_rig: published", DiagnosticStatus::WARN));
        assert_eq!(WriterTally::from_status(&st), Some(t));
        let mut other = st.clone();
        other.name = "virtual_rig: data loss".into();
        assert_eq!(WriterTally::from_status(&other), None);
        let mut broken = st;
        broken.values.retain(|kv| kv.key != "last_seq");
        assert_eq!(WriterTally::from_status(&broken), None);
    }

    #[test]
    fn a_stream_that_stops_while_its_writer_counts_on_has_a_tail() {
        let mut w = LossWatch::new("recorder");
        let t0 = Instant::now();
        for s in 0..100u64 {
            w.on_message(TOPIC, &info(7, s as i64 + 1), Some(s));
        }
        // The writer says it made up to 149: the last 50 never came.
        w.on_tally(&tally(7, 149, 50), t0);
        w.apply_tallies(Some(t0 + TALLY_GRACE / 2));
        assert_eq!(w.ledger().lost_total(), 0, "within the grace the tail may still be on its way");
        w.apply_tallies(Some(t0 + TALLY_GRACE));
        assert_eq!(w.ledger().lost_total(), 50);
        assert!(w.announcement(t0, Time::default()).is_some_and(|d| d.status[0].message.contains("50 made but")));
        // Another writer's tally (a restarted rig) leaves this stream alone.
        w.on_tally(&tally(8, 10_000, 0), t0);
        w.apply_tallies(None);
        assert_eq!(w.ledger().lost_total(), 50);
        assert!(!w.ledger().report(true).is_clean());
    }

    #[test]
    fn a_tally_of_what_arrived_is_no_loss() {
        let mut w = LossWatch::new("recorder");
        let t0 = Instant::now();
        for s in 0..100u64 {
            w.on_message(TOPIC, &info(7, s as i64 + 1), Some(s));
        }
        w.on_tally(&tally(7, 99, 0), t0);
        w.apply_tallies(None);
        assert!(w.ledger().report(true).is_clean());
    }
}

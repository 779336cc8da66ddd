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

use ros2_client::{MessageInfo, ros2::ReadError};
use std::time::{Duration, Instant};
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

/// One node's loss accounting.
#[derive(Debug)]
pub struct LossWatch {
    node: String,
    ledger: LossLedger,
    notes: Vec<String>,
    notes_dropped: u64,
    last_announce: Option<Instant>,
}

impl LossWatch {
    pub fn new(node: &str) -> Self {
        Self {
            node: node.to_owned(),
            ledger: LossLedger::new(),
            notes: Vec::new(),
            notes_dropped: 0,
            last_announce: None,
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

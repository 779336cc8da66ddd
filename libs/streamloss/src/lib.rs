//! streamloss: what a subscriber did not receive, per stream and per writer.
//!
//! Every message a suite node receives carries two sequence numbers: the DDS writer's (one per
//! sample it wrote, from 1) and, for `RigSample`, the rig's own `seq` (one per sample it
//! produced, from 0). A receiver that sees them jump knows exactly what it missed. This crate is
//! the bookkeeping, with no DDS and no I/O:
//!
//! - [`SeqTracker`]: one sequence from one writer — received, lost, gap ranges, late copies;
//! - [`LossLedger`]: every (topic, writer) a node listens to, plus messages that arrived but
//!   could not be decoded (malformed), keyed by topic;
//! - [`LossReport`]: the ledger frozen, written into a log as the key/value record
//!   [`LOSS_RECORD`] and read back from it ([`LossReport::to_entries`], [`LossReport::from_entries`]).
//!
//! Loss is counted after the first message of a writer: a reader that joins late (volatile QoS)
//! did not lose what was written before it existed, but the report keeps the first sequence
//! number seen, so a restarted recorder's two files can be joined up.

mod ledger;
mod record;
mod tracker;

pub use ledger::{LossLedger, SeqSource, StreamKey};
pub use record::{LOSS_RECORD, LossReport, RecordError, StreamLoss};
pub use tracker::{Gap, Observation, SeqTracker};

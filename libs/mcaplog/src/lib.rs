//! mcaplog: the suite's MCAP logs (ROS 2 profile) without DDS — writing, reading, recovery.
//!
//! - [`McapLog`]: writes a ROS 2-profile MCAP (`ros2msg` schemas, `cdr` messages, zstd chunks,
//!   message indexes, summary, metadata). Chunks are closed at least every `flush_interval_s`
//!   of log time, so a killed writer loses at most that much.
//! - [`recover`]: turns a file cut short (writer killed, disk full) into a valid MCAP holding
//!   every message of every complete chunk.
//! - [`LogReader`]: reads a log back, typed, for replay and the offline tools, and says what it
//!   is missing ([`LogReader::loss_summary`]: the recorder's `tyrerig.loss` record and the gaps in
//!   `RigSample.seq`).
//!
//! Timestamps: an MCAP message's `log_time` is when the recorder received it (or, in headless
//! runs, the simulated time it was produced); its `publish_time` is the message's own stamp
//! (`header.stamp`, or `clock` for `/clock`), i.e. rig time.

pub mod codec;
pub mod log_reader;
pub mod log_writer;
pub mod records;
pub mod recover;

pub use log_reader::{LogError, LogMessage, LogReader, LossSummary, TopicInfo};
pub use log_writer::{LogWriteError, McapLog, McapLogOptions};
pub use recover::{RecoverError, RecoveryReport, recover};

//! recorder: MCAP logs of the suite (ROS 2 profile), their recovery, reading and replay.
//!
//! - [`log_writer::McapLog`]: writes a ROS 2-profile MCAP (`ros2msg` schemas, `cdr` messages,
//!   zstd chunks, message indexes, summary, metadata). Chunks are closed at least every
//!   `flush_interval_s` of log time, so a killed recorder loses at most that much.
//! - [`recover`]: turns a file cut short (recorder killed, disk full) into a valid MCAP holding
//!   every message of every complete chunk.
//! - [`log_reader::LogReader`]: reads a log back, typed, for replay and the offline tools.
//! - [`shell`]: the recorder node — subscribes to every suite topic and writes the log.
//!   Topics: all of [`node_runtime::SuiteTopic::ALL`] (subscribes).
//! - [`replay`]: republishes a log onto the same topics with its original timing, scaled.
//!
//! Timestamps: an MCAP message's `log_time` is when the recorder received it (system clock, ns
//! since the UNIX epoch); its `publish_time` is the message's own stamp (`header.stamp`, or
//! `clock` for `/clock`), i.e. rig time.

pub mod codec;
pub mod config;
pub mod log_reader;
pub mod log_writer;
pub mod recover;
pub mod replay;
pub mod shell;

pub use config::RecorderConfig;
pub use log_reader::{LogError, LogMessage, LogReader};
pub use log_writer::{LogWriteError, McapLog, McapLogOptions};

//! `tracing` set-up for every binary of the suite.
//!
//! RustDDS logs through the `log` facade, and chattily (every discovery packet at debug, some
//! benign conditions at warn). Its records are bridged into `tracing` and held at `error` unless
//! `RUST_LOG` asks for more, so an operator sees the suite's own messages.

use tracing_subscriber::{EnvFilter, fmt};

/// Default filter: our crates at info, the DDS stack quiet. Two RustDDS targets are off because
/// they report library behaviour, not faults: `dds::pubsub` logs a closed event loop at ERROR on
/// every clean shutdown, and `discovery::discovery_db` logs a "type inconsistency" on `/clock`
/// because ros2-client 0.12's spinner declares `/clock` as `builtin_interfaces/Time` where ROS 2
/// (and our virtual rig) use `rosgraph_msgs/Clock` (same CDR layout, different type name). The
/// RTPS writer's warnings are on: among them, that a reader stopped acknowledging and the writer
/// no longer waits for it (vendor/rustdds/PATCHES.md, patch 3), and QoS mismatches.
pub const DEFAULT_FILTER: &str = "info,rustdds=error,rustdds::rtps::writer=warn,rustdds::dds::pubsub=off,\
     rustdds::discovery::discovery_db=off,ros2_client=error,mio=error";

/// Installs the global subscriber (idempotent: a second call is a no-op). Logs go to stderr so
/// that stdout stays free for a command's real output (tables, JSON).
pub fn init() {
    let filter = EnvFilter::try_from_default_env().unwrap_or_else(|_| EnvFilter::new(DEFAULT_FILTER));
    // `try_init` also installs the log→tracing bridge (tracing-log feature).
    let _ = fmt().with_env_filter(filter).with_writer(std::io::stderr).with_target(true).try_init();
}

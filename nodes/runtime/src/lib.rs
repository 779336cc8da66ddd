//! node_runtime: the one place besides the node shells that knows DDS.
//!
//! What a node gets from here:
//! - [`RuntimeConfig`]: namespace (default `/rig`) and domain id (config, else `ROS_DOMAIN_ID`, else 0);
//! - [`security`]: DDS Security (SROS2 keystore, an enclave per node), when the launch file has a
//!   `[security]` section; needs the cargo feature `security` (off by default);
//! - [`topics`]: the suite's topic table — every topic's relative name, message type and QoS preset,
//!   shared by publishers, subscribers, the recorder and replay so their QoS always match;
//! - [`RosNode`]: one DDS participant and one ROS 2 node per suite node (two participants on one
//!   host discover each other over loopback unicast; one participant never hears itself), with a
//!   background spinner, typed publishers and subscriptions;
//! - [`logging`]: `tracing` output with RustDDS's `log` records bridged in and quietened;
//! - [`shutdown`]: SIGINT/SIGTERM turned into a cooperative shutdown signal;
//! - [`publish`]: publish errors counted per topic and logged (never `let _`);
//! - [`loss`]: per-writer loss and malformed-input accounting every subscriber keeps, with its
//!   `/diagnostics` announcements.
//!
//! Node logic never sees any of this: each node is a pure core driven by its shell.

pub mod config;
pub mod logging;
pub mod loss;
pub mod node;
pub mod publish;
pub mod security;
pub mod shutdown;
pub mod topics;

pub use config::{RuntimeConfig, RuntimeConfigError};
pub use loss::{LossWatch, WriterTally};
pub use node::{FLUSH_DEADLINE, RosNode, RuntimeError};
pub use publish::PublishErrors;
pub use security::{SecurityConfig, SecurityConfigError};
pub use shutdown::Shutdown;
pub use topics::{Qos, SuiteTopic, TopicSpec};

//! foxglove_node: the control room's screen. Serves every suite topic live over the Foxglove
//! WebSocket protocol (the Foxglove app in a browser, or any `@foxglove/ws-protocol` client),
//! with each topic's ROS 2 `ros2msg` schema and the CDR bytes DDS carried, so nothing needs a
//! ROS install; adds views of the run (plan, progress and ETA, the running and the previous
//! sweep's forces over slip, alarms, the live fit's model and its bands) shaped for Foxglove's panels; and, only when the launch
//! file allows it, lets clients publish the listed commands on `procedure/command`.
//!
//! Topics: subscribes to every [`node_runtime::SuiteTopic`]; publishes `procedure/command`
//! (client commands, when allowed); serves `<ns>/foxglove/*` views ([`views`]).
//!
//! - [`config`]: `[node.config]` (host, port, allowed commands, per-client backlog, view rate);
//! - [`core`]: the pure view core (no I/O, no clock; the shell ticks it);
//! - [`trace`], [`alarms`], [`model`], [`latch`], [`command`]: its parts, one job each;
//! - [`shell`]: DDS subscriptions → the SDK's WebSocket server, and client commands → DDS.
//!
//! A slow client drops its own frames: the SDK keeps a bounded queue per client and drops that
//! client's oldest messages when it is full; the DDS tasks never wait on a client.

pub mod alarms;
pub mod command;
pub mod config;
pub mod core;
pub mod latch;
pub mod model;
pub mod shell;
pub mod trace;
pub mod views;

pub use config::FoxgloveNodeConfig;
pub use shell::{FoxgloveNodeError, FoxgloveStats, plan_view, run};

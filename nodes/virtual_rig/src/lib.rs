//! virtual_rig: the virtual flat-track rig as a ROS 2 node (the DDS shell around `rigsim`).
//!
//! Topics: subscribes `setpoint` (`tyre_msgs/RigSetpoint`); publishes `sample`
//! (`tyre_msgs/RigSample`) at the rig's publish rate and `/clock` (`rosgraph_msgs/Clock`) with
//! the simulated time.
//!
//! Clock modes:
//! - `realtime`: simulated time follows the wall clock, like a real rig.
//! - `lockstep`: accelerated simulated time. After publishing the sample for time t the rig
//!   waits for the sequencer's setpoint stamped ≥ t (its answer to that sample), then
//!   integrates to the next sample. The suite then makes the same decisions as a headless run,
//!   as fast as DDS carries the messages. If no answer comes within `lockstep_timeout_s` of wall
//!   time (no sequencer running), the rig goes on with the setpoint it has.

pub mod shell;

pub use shell::{ClockMode, VirtualRigNodeConfig, run};

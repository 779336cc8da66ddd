//! `rosgraph_msgs`: the simulated clock.

use crate::builtin_interfaces::Time;
use serde::{Deserialize, Serialize};

/// `rosgraph_msgs/Clock`: published on `/clock` when the virtual rig runs on simulated time.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct Clock {
    /// The current simulated time.
    pub clock: Time,
}

crate::ros_message!(Clock, "rosgraph_msgs", "Clock");

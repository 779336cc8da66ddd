//! `std_msgs`: the standard header.

use crate::builtin_interfaces::Time;
use serde::{Deserialize, Serialize};

/// `std_msgs/Header`: stamp and coordinate frame.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct Header {
    /// When the data was taken (rig time or simulated time).
    pub stamp: Time,
    /// Coordinate frame of the data (`iso_w` for rig data).
    pub frame_id: String,
}

crate::ros_message!(Header, "std_msgs", "Header");

impl Header {
    /// Header stamped at `t_s` seconds in the ISO-W frame.
    pub fn iso_w(t_s: f64) -> Self {
        Self { stamp: Time::from_secs_f64(t_s), frame_id: "iso_w".to_owned() }
    }
}

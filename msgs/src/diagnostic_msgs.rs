//! `diagnostic_msgs`: the ROS convention for health reporting on `/diagnostics`.

use crate::std_msgs::Header;
use serde::{Deserialize, Serialize};

/// `diagnostic_msgs/KeyValue`.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct KeyValue {
    pub key: String,
    pub value: String,
}

crate::ros_message!(KeyValue, "diagnostic_msgs", "KeyValue");

/// `diagnostic_msgs/DiagnosticStatus`.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct DiagnosticStatus {
    pub level: u8,
    pub name: String,
    pub message: String,
    pub hardware_id: String,
    pub values: Vec<KeyValue>,
}

crate::ros_message!(DiagnosticStatus, "diagnostic_msgs", "DiagnosticStatus", [OK, WARN, ERROR, STALE]);

impl DiagnosticStatus {
    pub const OK: u8 = 0;
    pub const WARN: u8 = 1;
    pub const ERROR: u8 = 2;
    pub const STALE: u8 = 3;
}

/// `diagnostic_msgs/DiagnosticArray`.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct DiagnosticArray {
    pub header: Header,
    pub status: Vec<DiagnosticStatus>,
}

crate::ros_message!(DiagnosticArray, "diagnostic_msgs", "DiagnosticArray");

//! `diagnostic_msgs`: the ROS convention for health reporting on `/diagnostics`.

use crate::std_msgs::Header;
use serde::{Deserialize, Serialize};

/// `diagnostic_msgs/KeyValue`.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct KeyValue {
    /// What the value is.
    pub key: String,
    /// The value, as text.
    pub value: String,
}

crate::ros_message!(KeyValue, "diagnostic_msgs", "KeyValue");

/// `diagnostic_msgs/DiagnosticStatus`.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct DiagnosticStatus {
    /// One of `OK`, `WARN`, `ERROR`, `STALE`.
    pub level: u8,
    /// Component name, e.g. `tyrerig: thermal`.
    pub name: String,
    /// Short human-readable summary.
    pub message: String,
    /// Hardware the status is about (empty if none).
    pub hardware_id: String,
    /// Extra named values.
    pub values: Vec<KeyValue>,
}

crate::ros_message!(DiagnosticStatus, "diagnostic_msgs", "DiagnosticStatus", [OK, WARN, ERROR, STALE]);

impl DiagnosticStatus {
    /// Component healthy.
    pub const OK: u8 = 0;
    /// Component degraded.
    pub const WARN: u8 = 1;
    /// Component failed.
    pub const ERROR: u8 = 2;
    /// No recent report from the component.
    pub const STALE: u8 = 3;
}

/// `diagnostic_msgs/DiagnosticArray`.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct DiagnosticArray {
    /// Stamp of the batch.
    pub header: Header,
    /// One status per component.
    pub status: Vec<DiagnosticStatus>,
}

crate::ros_message!(DiagnosticArray, "diagnostic_msgs", "DiagnosticArray");

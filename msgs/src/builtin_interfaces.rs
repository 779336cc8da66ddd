//! `builtin_interfaces`: time stamps.

use serde::{Deserialize, Serialize};

/// `builtin_interfaces/Time`: seconds and nanoseconds since an epoch (rig time or sim time).
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Default, Serialize, Deserialize)]
pub struct Time {
    /// Whole seconds (may be negative).
    pub sec: i32,
    /// Nanoseconds within the second, 0..999_999_999.
    pub nanosec: u32,
}

crate::ros_message!(Time, "builtin_interfaces", "Time");

impl Time {
    /// Time from seconds; negative or non-finite input saturates at zero.
    pub fn from_secs_f64(t_s: f64) -> Self {
        if !t_s.is_finite() || t_s <= 0.0 {
            return Self::default();
        }
        let total_ns = (t_s * 1e9).round();
        let sec = (total_ns / 1e9).floor();
        let nanosec = (total_ns - sec * 1e9) as u32;
        Self { sec: sec.min(i32::MAX as f64) as i32, nanosec }
    }

    /// Seconds as `f64`.
    pub fn as_secs_f64(&self) -> f64 {
        f64::from(self.sec) + f64::from(self.nanosec) * 1e-9
    }

    /// Nanoseconds since the epoch (for MCAP timestamps); negative times map to 0.
    pub fn as_nanos(&self) -> u64 {
        if self.sec < 0 {
            return 0;
        }
        self.sec as u64 * 1_000_000_000 + u64::from(self.nanosec)
    }

    /// From nanoseconds since the epoch.
    pub fn from_nanos(ns: u64) -> Self {
        Self { sec: (ns / 1_000_000_000).min(i32::MAX as u64) as i32, nanosec: (ns % 1_000_000_000) as u32 }
    }
}

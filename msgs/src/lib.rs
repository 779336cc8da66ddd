//! tyre_msgs: the Rust side of the `tyre_msgs` ROS 2 interface package.
//!
//! The `.msg` files in `msg/` are the source of truth. The structs here mirror them field for
//! field, in order, with serde derives so that CDR (via `cdr-encoding`) produces exactly the bytes
//! a ROS 2 node generated from the same `.msg` files would. A test parses the `.msg` files and
//! fails if a struct drifts from its definition.
//!
//! Standard interfaces the suite reuses (`builtin_interfaces/Time`, `std_msgs/Header`,
//! `diagnostic_msgs/DiagnosticArray`, `rosgraph_msgs/Clock`) are defined in their own modules
//! with their upstream field lists.
//!
//! Axes are ISO-W (TYDEX-W); units are in field names or the `.msg` comments.

pub mod builtin_interfaces;
pub mod diagnostic_msgs;
pub mod msg;
pub mod rosgraph_msgs;
pub mod std_msgs;

pub use msg::*;

/// A ROS 2 message type: its fully qualified name as ROS 2 writes it.
pub trait RosMessage:
    serde::Serialize + serde::de::DeserializeOwned + Clone + std::fmt::Debug
{
    /// Package name, e.g. `tyre_msgs`.
    const PACKAGE: &'static str;
    /// Message name, e.g. `RigSample`.
    const NAME: &'static str;

    /// The ROS 2 type name used in MCAP schemas and `ros2 topic`: `tyre_msgs/msg/RigSample`.
    fn ros_type_name() -> String {
        format!("{}/msg/{}", Self::PACKAGE, Self::NAME)
    }

    /// The DDS type name on the wire (rmw convention): `tyre_msgs::msg::dds_::RigSample_`.
    fn dds_type_name() -> String {
        format!("{}::msg::dds_::{}_", Self::PACKAGE, Self::NAME)
    }
}

macro_rules! ros_message {
    ($ty:ty, $pkg:literal, $name:literal) => {
        impl $crate::RosMessage for $ty {
            const PACKAGE: &'static str = $pkg;
            const NAME: &'static str = $name;
        }
    };
}
pub(crate) use ros_message;

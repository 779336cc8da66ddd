//! tyre_msgs: the Rust side of the `tyre_msgs` ROS 2 interface package.
//!
//! The `.msg` files in `msg/` are the source of truth. The structs here mirror them field for
//! field, in order, with serde derives so that CDR (via `cdr-encoding`) produces exactly the bytes
//! a ROS 2 node generated from the same `.msg` files would. A test parses the `.msg` files and
//! fails if a struct drifts from its definition (see [`drift`]).
//!
//! Standard interfaces the suite reuses (`builtin_interfaces/Time`, `std_msgs/Header`,
//! `diagnostic_msgs/DiagnosticArray`, `rosgraph_msgs/Clock`) are defined in their own modules
//! with their upstream field lists; their `.msg` text is embedded from `std/`.
//!
//! What else is here:
//! - [`msgdef`]: a `.msg` parser (fields, arrays, defaults, constants, errors with file:line);
//! - [`schema`]: the embedded definitions and the MCAP `ros2msg` schema text
//!   ([`RosMessage::schema_text`], [`schema::all_schemas`]);
//! - [`cdr`]: CDR with the 4-byte encapsulation header ([`cdr::to_cdr_with_header`],
//!   [`cdr::from_cdr_with_header`]), the payload format of DDS and of MCAP `cdr` channels;
//! - [`introspect`] and [`drift`]: the machinery of the drift test.
//!
//! Axes are ISO-W (TYDEX-W); units are in field names or the `.msg` comments.
//!
//! ```
//! use tyre_msgs::cdr::{from_cdr_with_header, to_cdr_with_header};
//! use tyre_msgs::{RigSample, RosMessage};
//!
//! let sample = RigSample { fx_n: -1.5, fault_flags: RigSample::FAULT_ESTOP, ..RigSample::default() };
//! // What DDS sends and MCAP stores: encapsulation header (CDR little-endian), then the body.
//! let payload = to_cdr_with_header(&sample)?;
//! assert_eq!(payload[..4], [0x00, 0x01, 0x00, 0x00]);
//! assert_eq!(from_cdr_with_header::<RigSample>(&payload)?, sample);
//!
//! // The MCAP channel's schema: name, encoding "ros2msg", and this text.
//! assert_eq!(RigSample::ros_type_name(), "tyre_msgs/msg/RigSample");
//! let schema = RigSample::schema_text();
//! assert!(schema.contains("\nMSG: std_msgs/Header\n"));
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

pub mod builtin_interfaces;
pub mod cdr;
pub mod diagnostic_msgs;
pub mod drift;
pub mod introspect;
pub mod msg;
pub mod msgdef;
pub mod rosgraph_msgs;
pub mod schema;
pub mod std_msgs;
pub mod topics;

pub use msg::*;

/// A ROS 2 message type: its fully qualified name as ROS 2 writes it.
pub trait RosMessage: serde::Serialize + serde::de::DeserializeOwned + Clone + std::fmt::Debug {
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

    /// The constants the `.msg` declares, as this type's associated consts with their Rust
    /// types. The drift test compares this table with the `.msg` file.
    fn constants() -> Vec<RosConstant> {
        Vec::new()
    }

    /// The MCAP `ros2msg` schema text: this type's `.msg`, then each dependency once after a
    /// line of 80 `=` and `MSG: pkg/Type`. See [`schema::ros2msg_schema_for`].
    fn try_schema_text() -> Result<String, schema::SchemaError> {
        schema::ros2msg_schema_for(&Self::ros_type_name())
    }

    /// [`RosMessage::try_schema_text`] for types whose `.msg` is embedded in this crate.
    ///
    /// # Panics
    /// If the type has no embedded definition. Every type in this crate has one (a test checks
    /// it), so this only fires for an outside type that implements the trait without a `.msg`.
    fn schema_text() -> String {
        match Self::try_schema_text() {
            Ok(text) => text,
            Err(e) => panic!("no ros2msg schema for {}: {e}", Self::ros_type_name()),
        }
    }
}

/// One message constant as the Rust side defines it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RosConstant {
    /// Constant name, e.g. `MODE_SAFE`.
    pub name: &'static str,
    /// Value, tagged with its Rust type.
    pub value: ConstValue,
}

impl RosConstant {
    /// A constant from an associated const; the value's Rust type picks the variant.
    pub fn new(name: &'static str, value: impl Into<ConstValue>) -> Self {
        Self { name, value: value.into() }
    }
}

/// A constant's value, tagged with its Rust type.
#[derive(Debug, Clone, Copy, PartialEq)]
#[allow(missing_docs)]
pub enum ConstValue {
    Bool(bool),
    U8(u8),
    I8(i8),
    U16(u16),
    I16(i16),
    U32(u32),
    I32(i32),
    U64(u64),
    I64(i64),
    F32(f32),
    F64(f64),
    Str(&'static str),
}

macro_rules! const_value_from {
    ($($t:ty => $v:ident),* $(,)?) => {
        $(impl From<$t> for ConstValue {
            fn from(v: $t) -> Self {
                Self::$v(v)
            }
        })*
    };
}
const_value_from!(
    bool => Bool, u8 => U8, i8 => I8, u16 => U16, i16 => I16, u32 => U32, i32 => I32,
    u64 => U64, i64 => I64, f32 => F32, f64 => F64, &'static str => Str,
);

/// Implements [`RosMessage`] for a type; the optional list names its associated consts, which
/// must be exactly the constants of its `.msg` (the drift test checks both directions).
macro_rules! ros_message {
    ($ty:ty, $pkg:literal, $name:literal) => {
        $crate::ros_message!($ty, $pkg, $name, []);
    };
    ($ty:ty, $pkg:literal, $name:literal, [$($konst:ident),* $(,)?]) => {
        impl $crate::RosMessage for $ty {
            const PACKAGE: &'static str = $pkg;
            const NAME: &'static str = $name;

            fn constants() -> Vec<$crate::RosConstant> {
                vec![$($crate::RosConstant::new(stringify!($konst), <$ty>::$konst)),*]
            }
        }
    };
}
pub(crate) use ros_message;

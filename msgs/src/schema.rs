//! The embedded `.msg` definitions and the MCAP `ros2msg` schema text built from them.
//!
//! MCAP's ROS 2 profile (and rosbag2) store a channel's schema as the top-level `.msg` text
//! followed, for each message type it uses (transitively, each once), by a separator line of 80
//! `=`, a line `MSG: pkg/Type`, and that type's `.msg` text. Readers such as Python's
//! `mcap-ros2-support` resolve unqualified type names in a section relative to that section's
//! package, so each file's text is embedded verbatim, comments and all.

use crate::RosMessage;
use crate::msgdef::{MsgDef, MsgDefError, TypeRef, parse_msg};

/// MCAP schema encoding for ROS 2 `.msg` text.
pub const SCHEMA_ENCODING: &str = "ros2msg";

/// MCAP message encoding for ROS 2 CDR payloads (with the 4-byte encapsulation header).
pub const MESSAGE_ENCODING: &str = "cdr";

/// The separator between sections of a `ros2msg` schema.
pub const SECTION_SEPARATOR: &str = "================================================================================";

/// One embedded `.msg` file.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Definition {
    /// Package, e.g. `tyre_msgs`.
    pub package: &'static str,
    /// Type name, e.g. `RigSample`.
    pub name: &'static str,
    /// Path of the file inside this crate, for error messages.
    pub path: &'static str,
    /// The file's text.
    pub text: &'static str,
}

impl Definition {
    /// `pkg/msg/Name`.
    pub fn ros_type_name(&self) -> String {
        format!("{}/msg/{}", self.package, self.name)
    }

    /// Parse the embedded text.
    pub fn parse(&self) -> Result<MsgDef, MsgDefError> {
        parse_msg(self.package, self.name, self.path, self.text)
    }
}

macro_rules! definitions {
    ($( $pkg:literal / $name:literal => $path:literal ),* $(,)?) => {
        /// Every embedded definition: the suite's own (`msg/`) and the standard ones it uses
        /// (`std/`).
        pub const DEFINITIONS: &[Definition] = &[
            $( Definition {
                package: $pkg,
                name: $name,
                path: $path,
                text: include_str!(concat!("../", $path)),
            }, )*
        ];
    };
}

definitions! {
    "tyre_msgs" / "RigSample" => "msg/RigSample.msg",
    "tyre_msgs" / "RigSetpoint" => "msg/RigSetpoint.msg",
    "tyre_msgs" / "ProcedureCommand" => "msg/ProcedureCommand.msg",
    "tyre_msgs" / "ProcedureState" => "msg/ProcedureState.msg",
    "tyre_msgs" / "ThermalState" => "msg/ThermalState.msg",
    "tyre_msgs" / "LiveChannels" => "msg/LiveChannels.msg",
    "tyre_msgs" / "SweepSummary" => "msg/SweepSummary.msg",
    "tyre_msgs" / "DerivedMeasurement" => "msg/DerivedMeasurement.msg",
    "tyre_msgs" / "QualityCheck" => "msg/QualityCheck.msg",
    "tyre_msgs" / "QualityReport" => "msg/QualityReport.msg",
    "tyre_msgs" / "ModelCoefficient" => "msg/ModelCoefficient.msg",
    "tyre_msgs" / "ModelStage" => "msg/ModelStage.msg",
    "tyre_msgs" / "ModelMap" => "msg/ModelMap.msg",
    "tyre_msgs" / "ModelState" => "msg/ModelState.msg",
    "tyre_msgs" / "StageCovariance" => "msg/StageCovariance.msg",
    "tyre_msgs" / "ModelCovariance" => "msg/ModelCovariance.msg",
    "builtin_interfaces" / "Time" => "std/builtin_interfaces/msg/Time.msg",
    "std_msgs" / "Header" => "std/std_msgs/msg/Header.msg",
    "diagnostic_msgs" / "KeyValue" => "std/diagnostic_msgs/msg/KeyValue.msg",
    "diagnostic_msgs" / "DiagnosticStatus" => "std/diagnostic_msgs/msg/DiagnosticStatus.msg",
    "diagnostic_msgs" / "DiagnosticArray" => "std/diagnostic_msgs/msg/DiagnosticArray.msg",
    "rosgraph_msgs" / "Clock" => "std/rosgraph_msgs/msg/Clock.msg",
}

/// A schema could not be built.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SchemaError {
    /// The type name is not one of the embedded definitions.
    #[error("unknown message type `{type_name}`{}", referenced_from.as_ref().map(|(f, l)| format!(" (referenced at {f}:{l})")).unwrap_or_default())]
    UnknownType {
        /// The name asked for.
        type_name: String,
        /// File and line of the field that refers to it, if it came from a field.
        referenced_from: Option<(String, usize)>,
    },
    /// The type's (or a dependency's) `.msg` text does not parse.
    #[error(transparent)]
    Parse(#[from] MsgDefError),
    /// A message contains itself (directly or through others), which CDR cannot encode.
    #[error("message type `{0}` contains itself")]
    Recursive(String),
}

/// Find an embedded definition by `pkg/msg/Name` or `pkg/Name`.
pub fn find_definition(type_name: &str) -> Option<&'static Definition> {
    let t = TypeRef::parse(type_name, "")?;
    DEFINITIONS.iter().find(|d| d.package == t.package && d.name == t.name)
}

fn lookup(t: &TypeRef, from: Option<(&str, usize)>) -> Result<&'static Definition, SchemaError> {
    DEFINITIONS.iter().find(|d| d.package == t.package && d.name == t.name).ok_or_else(|| SchemaError::UnknownType {
        type_name: t.short_name(),
        referenced_from: from.map(|(f, l)| (f.to_owned(), l)),
    })
}

/// The definition of `type_name` and of every type it uses, transitively, each once: the
/// top-level type first, then dependencies depth-first in field order.
pub fn definition_closure(type_name: &str) -> Result<Vec<&'static Definition>, SchemaError> {
    let top = find_definition(type_name)
        .ok_or_else(|| SchemaError::UnknownType { type_name: type_name.to_owned(), referenced_from: None })?;
    let mut out: Vec<&'static Definition> = Vec::new();
    let mut path: Vec<&'static Definition> = Vec::new();
    visit(top, &mut out, &mut path)?;
    Ok(out)
}

fn visit(
    def: &'static Definition,
    out: &mut Vec<&'static Definition>,
    path: &mut Vec<&'static Definition>,
) -> Result<(), SchemaError> {
    if path.contains(&def) {
        return Err(SchemaError::Recursive(def.ros_type_name()));
    }
    if out.contains(&def) {
        return Ok(());
    }
    out.push(def);
    path.push(def);
    let parsed = def.parse()?;
    for field in &parsed.fields {
        if let crate::msgdef::BaseType::Message(t) = &field.ty.base {
            let dep = lookup(t, Some((def.path, field.line)))?;
            visit(dep, out, path)?;
        }
    }
    path.pop();
    Ok(())
}

/// The MCAP `ros2msg` schema text for a type given as `pkg/msg/Name` or `pkg/Name`.
pub fn ros2msg_schema_for(type_name: &str) -> Result<String, SchemaError> {
    let defs = definition_closure(type_name)?;
    let mut text = String::new();
    for (i, def) in defs.iter().enumerate() {
        if i > 0 {
            text.push_str(SECTION_SEPARATOR);
            text.push('\n');
            // rosbag2 writes `MSG: std_msgs/Header`, without `/msg/`.
            text.push_str(&format!("MSG: {}/{}\n", def.package, def.name));
        }
        text.push_str(def.text.trim_end());
        text.push('\n');
    }
    Ok(text)
}

/// The MCAP `ros2msg` schema text for `M`.
pub fn ros2msg_schema<M: RosMessage>() -> Result<String, SchemaError> {
    ros2msg_schema_for(&M::ros_type_name())
}

/// `(ros_type_name, schema_text)` for every embedded definition (ours and the standard ones),
/// e.g. `("tyre_msgs/msg/RigSample", "...")`, so the recorder can look schemas up by type name.
pub fn all_schemas() -> Result<Vec<(String, String)>, SchemaError> {
    DEFINITIONS
        .iter()
        .map(|d| {
            let name = d.ros_type_name();
            ros2msg_schema_for(&name).map(|text| (name, text))
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_definition_parses_and_resolves() {
        for d in DEFINITIONS {
            d.parse().unwrap_or_else(|e| panic!("{e}"));
            definition_closure(&d.ros_type_name()).unwrap_or_else(|e| panic!("{e}"));
        }
        assert_eq!(all_schemas().unwrap().len(), DEFINITIONS.len());
    }

    #[test]
    fn lookup_accepts_both_spellings() {
        assert_eq!(find_definition("std_msgs/Header"), find_definition("std_msgs/msg/Header"));
        assert!(find_definition("std_msgs/Header").is_some());
        assert!(find_definition("nope/Thing").is_none());
        assert!(find_definition("garbage").is_none());
    }

    #[test]
    fn rig_sample_schema_has_header_then_time() {
        let text = ros2msg_schema_for("tyre_msgs/msg/RigSample").unwrap();
        let sep = format!("\n{SECTION_SEPARATOR}\n");
        let sections: Vec<&str> = text.split(&sep).collect();
        assert_eq!(sections.len(), 3);
        assert!(sections[0].starts_with("# One sample of every rig channel"));
        assert!(sections[1].starts_with("MSG: std_msgs/Header\n"));
        assert!(sections[2].starts_with("MSG: builtin_interfaces/Time\n"));
        assert_eq!(SECTION_SEPARATOR.len(), 80);
        assert!(SECTION_SEPARATOR.bytes().all(|b| b == b'='));
        assert!(text.ends_with("uint32 nanosec   # nanoseconds within the second, 0..999999999\n"));
    }

    #[test]
    fn dependencies_appear_once() {
        // DiagnosticArray -> Header -> Time, DiagnosticStatus -> KeyValue.
        let names: Vec<String> = definition_closure("diagnostic_msgs/msg/DiagnosticArray")
            .unwrap()
            .iter()
            .map(|d| d.ros_type_name())
            .collect();
        assert_eq!(
            names,
            [
                "diagnostic_msgs/msg/DiagnosticArray",
                "std_msgs/msg/Header",
                "builtin_interfaces/msg/Time",
                "diagnostic_msgs/msg/DiagnosticStatus",
                "diagnostic_msgs/msg/KeyValue",
            ]
        );
        let report = ros2msg_schema_for("tyre_msgs/QualityReport").unwrap();
        assert_eq!(report.matches("MSG: ").count(), 3);
        assert_eq!(report.matches("MSG: tyre_msgs/QualityCheck\n").count(), 1);
    }

    #[test]
    fn unknown_type_is_an_error() {
        assert!(matches!(ros2msg_schema_for("tyre_msgs/msg/Nope"), Err(SchemaError::UnknownType { .. })));
    }
}

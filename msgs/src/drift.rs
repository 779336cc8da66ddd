//! Drift detection: does a Rust message type still match its `.msg` file?
//!
//! The `.msg` side is parsed ([`crate::msgdef`]) and expanded into the [`Shape`] CDR would give
//! it, with nested types (e.g. `std_msgs/Header`) expanded from the embedded definitions. The
//! Rust side is an [`exemplar`] value (every sequence holding one element, so element types are
//! visible) walked by the recording serializer ([`shape_of`]). The two shapes are compared
//! field by field and in order: names, primitive kinds, nested struct names, sequences versus
//! fixed arrays. Constants are compared separately, against the table that
//! [`RosMessage::constants`] builds from the type's associated consts: every `.msg` constant
//! must exist there with the same type and value, and nothing else may.

use crate::introspect::{IntrospectError, Kind, Shape, exemplar, shape_of};
use crate::msgdef::{ArrayKind, BaseType, Literal, MsgDef, Primitive, TypeRef, parse_msg};
use crate::schema::{SchemaError, find_definition};
use crate::{ConstValue, RosConstant, RosMessage};
use std::fmt;

/// One difference between a `.msg` file and its Rust type.
#[derive(Debug, Clone, PartialEq)]
pub struct Drift {
    /// Where: `RigSample.header.stamp.sec`, `RigSample.fields[3]` or `RigSample.MODE_SAFE`.
    pub path: String,
    /// What the `.msg` says (with the file:line where it says it, when known).
    pub expected: String,
    /// What the Rust type has.
    pub found: String,
}

impl fmt::Display for Drift {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}: .msg says {}, Rust has {}", self.path, self.expected, self.found)
    }
}

/// The comparison itself could not run.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum DriftError {
    /// The `.msg` (or a type it uses) could not be found or parsed.
    #[error(transparent)]
    Schema(#[from] SchemaError),
    /// The Rust type uses serde features a ROS message cannot have.
    #[error("Rust type {type_name}: {source}")]
    Introspect {
        /// The Rust type's ROS name.
        type_name: String,
        /// What went wrong.
        #[source]
        source: IntrospectError,
    },
}

/// Compare `M` with its embedded `.msg` file (fields and constants).
pub fn check_message<M: RosMessage>() -> Result<Vec<Drift>, DriftError> {
    let type_name = M::ros_type_name();
    let def = find_definition(&type_name)
        .ok_or_else(|| SchemaError::UnknownType { type_name: type_name.clone(), referenced_from: None })?
        .parse()
        .map_err(SchemaError::from)?;
    check_against_def::<M>(&def)
}

/// Compare `M` with arbitrary `.msg` text for its type (nested types still come from the
/// embedded definitions). This is how the tests show that a mismatch is caught.
pub fn check_against_text<M: RosMessage>(text: &str) -> Result<Vec<Drift>, DriftError> {
    let file = format!("<text for {}>", M::ros_type_name());
    let def = parse_msg(M::PACKAGE, M::NAME, &file, text).map_err(SchemaError::from)?;
    check_against_def::<M>(&def)
}

/// Compare `M` with a parsed definition (fields and constants).
pub fn check_against_def<M: RosMessage>(def: &MsgDef) -> Result<Vec<Drift>, DriftError> {
    let introspect = |source| DriftError::Introspect { type_name: M::ros_type_name(), source };
    let value: M = exemplar(1).map_err(introspect)?;
    let actual = shape_of(&value).map_err(introspect)?;
    let expected = expected_shape(def, &mut Vec::new())?;
    let mut drifts = Vec::new();
    compare_shapes(&expected, &actual, &def.ty.name, &mut drifts);
    drifts.extend(compare_constants(def, &M::constants()));
    Ok(drifts)
}

/// The shape a definition has on the wire, nested types expanded from the embedded files.
/// `stack` guards against a type that contains itself.
pub fn expected_shape(def: &MsgDef, stack: &mut Vec<TypeRef>) -> Result<Shape, SchemaError> {
    if stack.contains(&def.ty) {
        return Err(SchemaError::Recursive(def.ty.short_name()));
    }
    stack.push(def.ty.clone());
    let mut fields = Vec::with_capacity(def.fields.len());
    for field in &def.fields {
        let element = match &field.ty.base {
            BaseType::Message(t) => {
                let nested = find_definition(&t.short_name())
                    .ok_or_else(|| SchemaError::UnknownType {
                        type_name: t.short_name(),
                        referenced_from: Some((def.file.clone(), field.line)),
                    })?
                    .parse()?;
                expected_shape(&nested, stack)?
            }
            BaseType::Primitive(p) => Shape::Prim(kind_of(*p)),
            BaseType::BoundedString { .. } => Shape::Prim(Kind::String),
        };
        let shape = match field.ty.array {
            ArrayKind::Scalar => element,
            ArrayKind::Unbounded | ArrayKind::Bounded(_) => Shape::Sequence(Some(Box::new(element))),
            ArrayKind::Fixed(n) => Shape::Array(n, Box::new(element)),
        };
        fields.push((field.name.clone(), shape));
    }
    stack.pop();
    Ok(Shape::Struct { name: def.ty.name.clone(), fields })
}

/// The serde kind a ROS primitive is written with.
pub fn kind_of(p: Primitive) -> Kind {
    match p {
        Primitive::Bool => Kind::Bool,
        // `byte` and `char` are single octets in ROS 2, exactly like uint8.
        Primitive::Byte | Primitive::Char | Primitive::Uint8 => Kind::U8,
        Primitive::Int8 => Kind::I8,
        Primitive::Int16 => Kind::I16,
        Primitive::Uint16 => Kind::U16,
        Primitive::Int32 => Kind::I32,
        Primitive::Uint32 => Kind::U32,
        Primitive::Int64 => Kind::I64,
        Primitive::Uint64 => Kind::U64,
        Primitive::Float32 => Kind::F32,
        Primitive::Float64 => Kind::F64,
        Primitive::String | Primitive::WString => Kind::String,
    }
}

fn describe(shape: &Shape) -> String {
    match shape {
        Shape::Struct { name, fields } => format!("struct {name} ({} fields)", fields.len()),
        other => other.to_string(),
    }
}

/// Compare two shapes, appending every difference under `path`.
pub fn compare_shapes(expected: &Shape, actual: &Shape, path: &str, out: &mut Vec<Drift>) {
    match (expected, actual) {
        (Shape::Struct { name: en, fields: ef }, Shape::Struct { name: an, fields: af }) => {
            if en != an {
                out.push(Drift { path: path.to_owned(), expected: format!("type {en}"), found: format!("type {an}") });
            }
            for i in 0..ef.len().max(af.len()) {
                match (ef.get(i), af.get(i)) {
                    (Some((e_name, e_shape)), Some((a_name, a_shape))) => {
                        if e_name != a_name {
                            out.push(Drift {
                                path: format!("{path}.fields[{i}]"),
                                expected: format!("field `{e_name}`: {}", describe(e_shape)),
                                found: format!("field `{a_name}`: {}", describe(a_shape)),
                            });
                        } else {
                            compare_shapes(e_shape, a_shape, &format!("{path}.{e_name}"), out);
                        }
                    }
                    (Some((e_name, e_shape)), None) => out.push(Drift {
                        path: format!("{path}.fields[{i}]"),
                        expected: format!("field `{e_name}`: {}", describe(e_shape)),
                        found: "no such field".to_owned(),
                    }),
                    (None, Some((a_name, a_shape))) => out.push(Drift {
                        path: format!("{path}.fields[{i}]"),
                        expected: "no such field".to_owned(),
                        found: format!("field `{a_name}`: {}", describe(a_shape)),
                    }),
                    (None, None) => {}
                }
            }
        }
        (Shape::Sequence(Some(e)), Shape::Sequence(Some(a))) => {
            compare_shapes(e, a, &format!("{path}[]"), out);
        }
        (Shape::Array(en, e), Shape::Array(an, a)) => {
            if en != an {
                out.push(Drift {
                    path: path.to_owned(),
                    expected: format!("fixed array of {en}"),
                    found: format!("fixed array of {an}"),
                });
            }
            compare_shapes(e, a, &format!("{path}[]"), out);
        }
        (e, a) if e == a => {}
        (e, a) => out.push(Drift { path: path.to_owned(), expected: describe(e), found: describe(a) }),
    }
}

/// Compare a definition's constants with the Rust table, both ways.
pub fn compare_constants(def: &MsgDef, rust: &[RosConstant]) -> Vec<Drift> {
    let mut out = Vec::new();
    let path = |name: &str| format!("{}.{name}", def.ty.name);
    for c in &def.constants {
        let expected = format!("{} {}={} ({}:{})", c.ty, c.name, c.value, def.file, c.line);
        match rust.iter().find(|r| r.name == c.name) {
            None => out.push(Drift {
                path: path(&c.name),
                expected,
                found: "no such associated const in the constants table".to_owned(),
            }),
            Some(r) if !const_matches(c.ty, &c.value, &r.value) => {
                out.push(Drift { path: path(&c.name), expected, found: format!("{:?}", r.value) })
            }
            Some(_) => {}
        }
    }
    for r in rust {
        if def.constant(r.name).is_none() {
            out.push(Drift {
                path: path(r.name),
                expected: "no such constant".to_owned(),
                found: format!("{:?}", r.value),
            });
        }
    }
    out
}

/// Same type (by the ROS-to-Rust mapping) and same value.
fn const_matches(ty: Primitive, lit: &Literal, rust: &ConstValue) -> bool {
    let int = |v: i128| matches!(lit, Literal::Int(i) if *i == v);
    match (ty, rust) {
        (Primitive::Bool, ConstValue::Bool(b)) => matches!(lit, Literal::Bool(l) if l == b),
        (Primitive::Byte | Primitive::Char | Primitive::Uint8, ConstValue::U8(v)) => int((*v).into()),
        (Primitive::Int8, ConstValue::I8(v)) => int((*v).into()),
        (Primitive::Uint16, ConstValue::U16(v)) => int((*v).into()),
        (Primitive::Int16, ConstValue::I16(v)) => int((*v).into()),
        (Primitive::Uint32, ConstValue::U32(v)) => int((*v).into()),
        (Primitive::Int32, ConstValue::I32(v)) => int((*v).into()),
        (Primitive::Uint64, ConstValue::U64(v)) => int((*v).into()),
        (Primitive::Int64, ConstValue::I64(v)) => int((*v).into()),
        // A float32 constant is compared after rounding the .msg text to f32, as C++ would.
        (Primitive::Float32, ConstValue::F32(v)) => {
            matches!(lit, Literal::Float(x) if (*x as f32).to_bits() == v.to_bits())
        }
        (Primitive::Float64, ConstValue::F64(v)) => {
            matches!(lit, Literal::Float(x) if x.to_bits() == v.to_bits())
        }
        (Primitive::String | Primitive::WString, ConstValue::Str(s)) => {
            matches!(lit, Literal::Str(l) if l == s)
        }
        _ => false,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{QualityCheck, QualityReport, RigSample, RigSetpoint};

    /// Build a RigSample .msg text from the real one with a line replaced.
    fn rig_sample_with(from: &str, to: &str) -> String {
        let text = find_definition("tyre_msgs/RigSample").unwrap().text;
        assert!(text.contains(from), "fixture line `{from}` not in RigSample.msg");
        text.replacen(from, to, 1)
    }

    fn drift_paths(drifts: &[Drift]) -> Vec<&str> {
        drifts.iter().map(|d| d.path.as_str()).collect()
    }

    #[test]
    fn the_real_file_has_no_drift() {
        assert_eq!(check_message::<RigSample>().unwrap(), []);
    }

    #[test]
    fn changed_primitive_type_is_caught() {
        let text = rig_sample_with("uint64 seq ", "uint32 seq ");
        let drifts = check_against_text::<RigSample>(&text).unwrap();
        assert_eq!(drift_paths(&drifts), ["RigSample.seq"]);
        assert_eq!(drifts[0].expected, "U32");
        assert_eq!(drifts[0].found, "U64");
    }

    #[test]
    fn reordered_fields_are_caught() {
        let text = rig_sample_with(
            "float64 fyw_n               # FYW: lateral force [N]\nfloat64 fzw_n ",
            "float64 fzw_n               # swapped\nfloat64 fyw_n ",
        );
        let drifts = check_against_text::<RigSample>(&text).unwrap();
        assert_eq!(drift_paths(&drifts), ["RigSample.fields[4]", "RigSample.fields[5]"]);
    }

    #[test]
    fn added_field_and_nested_type_change_are_caught() {
        let text = rig_sample_with("uint32 fault_flags ", "uint32 fault_flags\nfloat64 new_channel #");
        let drifts = check_against_text::<RigSample>(&text).unwrap();
        assert_eq!(drift_paths(&drifts), ["RigSample.fields[21]"]);
        assert_eq!(drifts[0].found, "no such field");

        // Header replaced by a bare Time: the nested type name and its fields differ.
        let text = rig_sample_with("std_msgs/Header header", "builtin_interfaces/Time header");
        let drifts = check_against_text::<RigSample>(&text).unwrap();
        assert!(drift_paths(&drifts).contains(&"RigSample.header"));
    }

    #[test]
    fn sequence_element_type_is_checked() {
        let text = find_definition("tyre_msgs/QualityReport")
            .unwrap()
            .text
            .replace("QualityCheck[] checks", "diagnostic_msgs/KeyValue[] checks");
        let drifts = check_against_text::<QualityReport>(&text).unwrap();
        assert!(drifts.iter().any(|d| d.path == "QualityReport.checks[]"), "{drifts:?}");
        let text = find_definition("tyre_msgs/QualityReport")
            .unwrap()
            .text
            .replace("QualityCheck[] checks", "QualityCheck[2] checks");
        let drifts = check_against_text::<QualityReport>(&text).unwrap();
        assert_eq!(drift_paths(&drifts), ["QualityReport.checks"]);
    }

    #[test]
    fn constants_are_checked_both_ways() {
        // A .msg constant the Rust side lacks.
        let text = rig_sample_with("uint32 FAULT_ESTOP=16", "uint32 FAULT_ESTOP=16\nuint32 FAULT_BELT=32");
        let drifts = check_against_text::<RigSample>(&text).unwrap();
        assert_eq!(drift_paths(&drifts), ["RigSample.FAULT_BELT"]);
        // A changed value.
        let text = rig_sample_with("uint32 FAULT_RADIUS=4", "uint32 FAULT_RADIUS=5");
        let drifts = check_against_text::<RigSample>(&text).unwrap();
        assert_eq!(drift_paths(&drifts), ["RigSample.FAULT_RADIUS"]);
        // A changed type, same value.
        let text =
            find_definition("tyre_msgs/RigSetpoint").unwrap().text.replace("uint8 MODE_SAFE=3", "uint32 MODE_SAFE=3");
        let drifts = check_against_text::<RigSetpoint>(&text).unwrap();
        assert_eq!(drift_paths(&drifts), ["RigSetpoint.MODE_SAFE"]);
        // A Rust constant the .msg lacks.
        let text = find_definition("tyre_msgs/QualityCheck").unwrap().text.replace("uint8 ERROR=2\n", "");
        let drifts = check_against_text::<QualityCheck>(&text).unwrap();
        assert_eq!(drift_paths(&drifts), ["QualityCheck.ERROR"]);
        assert_eq!(drifts[0].expected, "no such constant");
    }

    #[test]
    fn parse_errors_surface_with_file_and_line() {
        let err = check_against_text::<RigSample>("uint8 ok\nnot_a_type x\n").unwrap_err();
        let text = err.to_string();
        assert!(text.contains(":2:"), "{text}");
        assert!(text.contains("not_a_type"), "{text}");
    }
}

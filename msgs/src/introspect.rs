//! Looking at a Rust message type through serde, the same way CDR does.
//!
//! - [`shape_of`] walks a value with a recording [`serde::Serializer`] and returns its
//!   [`Shape`]: struct names, field names in order, primitive kinds, sequences and fixed arrays.
//!   Since CDR is produced by the same `Serialize` impl, the shape is exactly what goes on the
//!   wire, whatever the Rust source looks like.
//! - [`exemplar`] builds a value of any `DeserializeOwned` message type with a recording-free
//!   [`serde::Deserializer`] that answers every request with a distinct non-default value and
//!   every sequence with `seq_len` elements. With `seq_len >= 1` the element types of sequences
//!   show up in the shape, and the value doubles as a "every field non-default" round-trip
//!   input.

use serde::de::{self, DeserializeOwned, Visitor};
use serde::ser::{self, Serialize};
use std::fmt;

/// A primitive kind as serde (and so CDR) sees it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[allow(missing_docs)]
pub enum Kind {
    Bool,
    U8,
    I8,
    U16,
    I16,
    U32,
    I32,
    U64,
    I64,
    F32,
    F64,
    /// A Rust `char` (4 bytes in cdr-encoding; no ROS type maps to it).
    Char,
    /// A string (`String` / `&str`).
    String,
}

/// The serialized structure of a value.
#[derive(Debug, Clone, PartialEq)]
pub enum Shape {
    /// A primitive.
    Prim(Kind),
    /// A struct: its serde name (the Rust type name) and fields in serialization order.
    Struct {
        /// serde's struct name.
        name: String,
        /// Field names and shapes, in order.
        fields: Vec<(String, Shape)>,
    },
    /// A length-prefixed sequence; the element shape is `None` when the value had no element.
    Sequence(Option<Box<Shape>>),
    /// A fixed-size array (a serde tuple, e.g. `[f64; 3]`): no length on the wire.
    Array(usize, Box<Shape>),
}

impl fmt::Display for Shape {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Shape::Prim(k) => write!(f, "{k:?}"),
            Shape::Struct { name, .. } => write!(f, "struct {name}"),
            Shape::Sequence(Some(e)) => write!(f, "sequence<{e}>"),
            Shape::Sequence(None) => write!(f, "sequence<?>"),
            Shape::Array(n, e) => write!(f, "{e}[{n}]"),
        }
    }
}

/// The value uses a serde feature that has no ROS message equivalent.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("{0}")]
pub struct IntrospectError(pub String);

impl ser::Error for IntrospectError {
    fn custom<T: fmt::Display>(msg: T) -> Self {
        Self(msg.to_string())
    }
}

impl de::Error for IntrospectError {
    fn custom<T: fmt::Display>(msg: T) -> Self {
        Self(msg.to_string())
    }
}

fn unsupported<T>(what: &str) -> Result<T, IntrospectError> {
    Err(IntrospectError(format!("{what} has no ROS 2 message equivalent")))
}

/// The shape of `value` as serde serializes it.
pub fn shape_of<T: Serialize + ?Sized>(value: &T) -> Result<Shape, IntrospectError> {
    value.serialize(ShapeSerializer)
}

/// The recording serializer behind [`shape_of`].
#[derive(Debug, Clone, Copy)]
struct ShapeSerializer;

/// Collects the elements of a sequence or tuple.
#[derive(Debug)]
struct ElementsShape {
    fixed_len: Option<usize>,
    elements: Vec<Shape>,
}

impl ElementsShape {
    fn finish(self) -> Result<Shape, IntrospectError> {
        let mut iter = self.elements.into_iter();
        let first = iter.next();
        // Every element must look the same, or the "element type" would be a lie.
        if let Some(first) = &first
            && let Some(other) = iter.find(|e| e != first)
        {
            return Err(IntrospectError(format!("sequence elements differ in shape: {first} vs {other}")));
        }
        match self.fixed_len {
            Some(n) => match first {
                Some(e) => Ok(Shape::Array(n, Box::new(e))),
                None => unsupported("a zero-length array"),
            },
            None => Ok(Shape::Sequence(first.map(Box::new))),
        }
    }
}

/// Collects the fields of a struct.
#[derive(Debug)]
struct StructShape {
    name: &'static str,
    fields: Vec<(String, Shape)>,
}

impl ser::Serializer for ShapeSerializer {
    type Ok = Shape;
    type Error = IntrospectError;
    type SerializeSeq = ElementsShape;
    type SerializeTuple = ElementsShape;
    type SerializeTupleStruct = ElementsShape;
    type SerializeTupleVariant = ser::Impossible<Shape, IntrospectError>;
    type SerializeMap = ser::Impossible<Shape, IntrospectError>;
    type SerializeStruct = StructShape;
    type SerializeStructVariant = ser::Impossible<Shape, IntrospectError>;

    fn serialize_bool(self, _: bool) -> Result<Shape, IntrospectError> {
        Ok(Shape::Prim(Kind::Bool))
    }
    fn serialize_i8(self, _: i8) -> Result<Shape, IntrospectError> {
        Ok(Shape::Prim(Kind::I8))
    }
    fn serialize_i16(self, _: i16) -> Result<Shape, IntrospectError> {
        Ok(Shape::Prim(Kind::I16))
    }
    fn serialize_i32(self, _: i32) -> Result<Shape, IntrospectError> {
        Ok(Shape::Prim(Kind::I32))
    }
    fn serialize_i64(self, _: i64) -> Result<Shape, IntrospectError> {
        Ok(Shape::Prim(Kind::I64))
    }
    fn serialize_u8(self, _: u8) -> Result<Shape, IntrospectError> {
        Ok(Shape::Prim(Kind::U8))
    }
    fn serialize_u16(self, _: u16) -> Result<Shape, IntrospectError> {
        Ok(Shape::Prim(Kind::U16))
    }
    fn serialize_u32(self, _: u32) -> Result<Shape, IntrospectError> {
        Ok(Shape::Prim(Kind::U32))
    }
    fn serialize_u64(self, _: u64) -> Result<Shape, IntrospectError> {
        Ok(Shape::Prim(Kind::U64))
    }
    fn serialize_f32(self, _: f32) -> Result<Shape, IntrospectError> {
        Ok(Shape::Prim(Kind::F32))
    }
    fn serialize_f64(self, _: f64) -> Result<Shape, IntrospectError> {
        Ok(Shape::Prim(Kind::F64))
    }
    fn serialize_char(self, _: char) -> Result<Shape, IntrospectError> {
        Ok(Shape::Prim(Kind::Char))
    }
    fn serialize_str(self, _: &str) -> Result<Shape, IntrospectError> {
        Ok(Shape::Prim(Kind::String))
    }
    fn serialize_bytes(self, _: &[u8]) -> Result<Shape, IntrospectError> {
        // serde_bytes-style byte buffers go out as a u8 sequence.
        Ok(Shape::Sequence(Some(Box::new(Shape::Prim(Kind::U8)))))
    }
    fn serialize_none(self) -> Result<Shape, IntrospectError> {
        unsupported("Option")
    }
    fn serialize_some<T: Serialize + ?Sized>(self, _: &T) -> Result<Shape, IntrospectError> {
        unsupported("Option")
    }
    fn serialize_unit(self) -> Result<Shape, IntrospectError> {
        unsupported("()")
    }
    fn serialize_unit_struct(self, name: &'static str) -> Result<Shape, IntrospectError> {
        // An empty .msg becomes a struct with no fields (rosidl adds a dummy byte; we do not
        // need one yet, so refuse rather than guess).
        unsupported(&format!("unit struct {name}"))
    }
    fn serialize_unit_variant(self, name: &'static str, _: u32, _: &'static str) -> Result<Shape, IntrospectError> {
        unsupported(&format!("enum {name}"))
    }
    fn serialize_newtype_struct<T: Serialize + ?Sized>(
        self,
        _: &'static str,
        value: &T,
    ) -> Result<Shape, IntrospectError> {
        // CDR writes a newtype as its content, so it is transparent here too.
        value.serialize(self)
    }
    fn serialize_newtype_variant<T: Serialize + ?Sized>(
        self,
        name: &'static str,
        _: u32,
        _: &'static str,
        _: &T,
    ) -> Result<Shape, IntrospectError> {
        unsupported(&format!("enum {name}"))
    }
    fn serialize_seq(self, len: Option<usize>) -> Result<ElementsShape, IntrospectError> {
        Ok(ElementsShape { fixed_len: None, elements: Vec::with_capacity(len.unwrap_or(0)) })
    }
    fn serialize_tuple(self, len: usize) -> Result<ElementsShape, IntrospectError> {
        Ok(ElementsShape { fixed_len: Some(len), elements: Vec::with_capacity(len) })
    }
    fn serialize_tuple_struct(self, _: &'static str, len: usize) -> Result<ElementsShape, IntrospectError> {
        self.serialize_tuple(len)
    }
    fn serialize_tuple_variant(
        self,
        name: &'static str,
        _: u32,
        _: &'static str,
        _: usize,
    ) -> Result<Self::SerializeTupleVariant, IntrospectError> {
        unsupported(&format!("enum {name}"))
    }
    fn serialize_map(self, _: Option<usize>) -> Result<Self::SerializeMap, IntrospectError> {
        unsupported("a map")
    }
    fn serialize_struct(self, name: &'static str, len: usize) -> Result<StructShape, IntrospectError> {
        Ok(StructShape { name, fields: Vec::with_capacity(len) })
    }
    fn serialize_struct_variant(
        self,
        name: &'static str,
        _: u32,
        _: &'static str,
        _: usize,
    ) -> Result<Self::SerializeStructVariant, IntrospectError> {
        unsupported(&format!("enum {name}"))
    }
}

impl ser::SerializeSeq for ElementsShape {
    type Ok = Shape;
    type Error = IntrospectError;
    fn serialize_element<T: Serialize + ?Sized>(&mut self, v: &T) -> Result<(), IntrospectError> {
        self.elements.push(v.serialize(ShapeSerializer)?);
        Ok(())
    }
    fn end(self) -> Result<Shape, IntrospectError> {
        self.finish()
    }
}

impl ser::SerializeTuple for ElementsShape {
    type Ok = Shape;
    type Error = IntrospectError;
    fn serialize_element<T: Serialize + ?Sized>(&mut self, v: &T) -> Result<(), IntrospectError> {
        ser::SerializeSeq::serialize_element(self, v)
    }
    fn end(self) -> Result<Shape, IntrospectError> {
        self.finish()
    }
}

impl ser::SerializeTupleStruct for ElementsShape {
    type Ok = Shape;
    type Error = IntrospectError;
    fn serialize_field<T: Serialize + ?Sized>(&mut self, v: &T) -> Result<(), IntrospectError> {
        ser::SerializeSeq::serialize_element(self, v)
    }
    fn end(self) -> Result<Shape, IntrospectError> {
        self.finish()
    }
}

impl ser::SerializeStruct for StructShape {
    type Ok = Shape;
    type Error = IntrospectError;
    fn serialize_field<T: Serialize + ?Sized>(&mut self, key: &'static str, v: &T) -> Result<(), IntrospectError> {
        self.fields.push((key.to_owned(), v.serialize(ShapeSerializer)?));
        Ok(())
    }
    fn skip_field(&mut self, key: &'static str) -> Result<(), IntrospectError> {
        // A skipped field would vanish from CDR while the .msg still has it.
        Err(IntrospectError(format!("field `{key}` of {} is skipped by serde", self.name)))
    }
    fn end(self) -> Result<Shape, IntrospectError> {
        Ok(Shape::Struct { name: self.name.to_owned(), fields: self.fields })
    }
}

/// A value of `T` with every primitive set to a distinct non-default value, every string to a
/// distinct non-ASCII string, every bool to `true` and every sequence filled with `seq_len`
/// elements (themselves filled the same way).
pub fn exemplar<T: DeserializeOwned>(seq_len: usize) -> Result<T, IntrospectError> {
    let mut de = ExemplarDeserializer { counter: 0, seq_len };
    T::deserialize(&mut de)
}

/// The deserializer behind [`exemplar`].
#[derive(Debug)]
struct ExemplarDeserializer {
    counter: u64,
    seq_len: usize,
}

impl ExemplarDeserializer {
    /// Next counter value, starting at 1 so nothing is ever zero.
    fn next(&mut self) -> u64 {
        self.counter += 1;
        self.counter
    }

    /// A finite, non-integer, sign-alternating float (NaN would break `PartialEq` round trips).
    fn next_float(&mut self) -> f64 {
        let n = self.next();
        let sign = if n.is_multiple_of(2) { -1.0 } else { 1.0 };
        sign * (n as f64 * 1.25 + 0.125)
    }
}

/// Hands out `remaining` elements, each deserialized by the same exemplar deserializer.
struct ExemplarSeq<'a> {
    de: &'a mut ExemplarDeserializer,
    remaining: usize,
}

impl<'de> de::SeqAccess<'de> for ExemplarSeq<'_> {
    type Error = IntrospectError;
    fn next_element_seed<S: de::DeserializeSeed<'de>>(&mut self, seed: S) -> Result<Option<S::Value>, IntrospectError> {
        if self.remaining == 0 {
            return Ok(None);
        }
        self.remaining -= 1;
        seed.deserialize(&mut *self.de).map(Some)
    }
    fn size_hint(&self) -> Option<usize> {
        Some(self.remaining)
    }
}

impl<'de> de::Deserializer<'de> for &mut ExemplarDeserializer {
    type Error = IntrospectError;

    fn deserialize_any<V: Visitor<'de>>(self, _: V) -> Result<V::Value, IntrospectError> {
        unsupported("a self-describing (untyped) field")
    }
    fn deserialize_bool<V: Visitor<'de>>(self, v: V) -> Result<V::Value, IntrospectError> {
        v.visit_bool(true)
    }
    fn deserialize_i8<V: Visitor<'de>>(self, v: V) -> Result<V::Value, IntrospectError> {
        let n = (self.next() % 100) as i8 + 1;
        v.visit_i8(-n)
    }
    fn deserialize_i16<V: Visitor<'de>>(self, v: V) -> Result<V::Value, IntrospectError> {
        let n = (self.next() % 30_000) as i16 + 1;
        v.visit_i16(-n)
    }
    fn deserialize_i32<V: Visitor<'de>>(self, v: V) -> Result<V::Value, IntrospectError> {
        // Positive: builtin_interfaces/Time.sec is an i32 and negative stamps are odd test data.
        let n = self.next() as i32;
        v.visit_i32(1_000 + n)
    }
    fn deserialize_i64<V: Visitor<'de>>(self, v: V) -> Result<V::Value, IntrospectError> {
        let n = self.next() as i64;
        v.visit_i64(-(1 << 40) - n)
    }
    fn deserialize_u8<V: Visitor<'de>>(self, v: V) -> Result<V::Value, IntrospectError> {
        let n = (self.next() % 200) as u8 + 1;
        v.visit_u8(n)
    }
    fn deserialize_u16<V: Visitor<'de>>(self, v: V) -> Result<V::Value, IntrospectError> {
        let n = (self.next() % 60_000) as u16 + 1;
        v.visit_u16(n)
    }
    fn deserialize_u32<V: Visitor<'de>>(self, v: V) -> Result<V::Value, IntrospectError> {
        // Kept below 1e9 so it is also a valid Time.nanosec.
        let n = (self.next() % 1_000) as u32;
        v.visit_u32(123_000_000 + n)
    }
    fn deserialize_u64<V: Visitor<'de>>(self, v: V) -> Result<V::Value, IntrospectError> {
        let n = self.next();
        v.visit_u64((1 << 33) + n)
    }
    fn deserialize_f32<V: Visitor<'de>>(self, v: V) -> Result<V::Value, IntrospectError> {
        let x = self.next_float() as f32;
        v.visit_f32(x)
    }
    fn deserialize_f64<V: Visitor<'de>>(self, v: V) -> Result<V::Value, IntrospectError> {
        let x = self.next_float();
        v.visit_f64(x)
    }
    fn deserialize_char<V: Visitor<'de>>(self, v: V) -> Result<V::Value, IntrospectError> {
        v.visit_char('é')
    }
    fn deserialize_str<V: Visitor<'de>>(self, v: V) -> Result<V::Value, IntrospectError> {
        self.deserialize_string(v)
    }
    fn deserialize_string<V: Visitor<'de>>(self, v: V) -> Result<V::Value, IntrospectError> {
        let n = self.next();
        v.visit_string(format!("Reifen-{n} Δα µ ✓ 🛞"))
    }
    fn deserialize_bytes<V: Visitor<'de>>(self, v: V) -> Result<V::Value, IntrospectError> {
        self.deserialize_byte_buf(v)
    }
    fn deserialize_byte_buf<V: Visitor<'de>>(self, v: V) -> Result<V::Value, IntrospectError> {
        let n = self.next() as u8;
        v.visit_byte_buf(vec![n; self.seq_len])
    }
    fn deserialize_option<V: Visitor<'de>>(self, _: V) -> Result<V::Value, IntrospectError> {
        unsupported("Option")
    }
    fn deserialize_unit<V: Visitor<'de>>(self, _: V) -> Result<V::Value, IntrospectError> {
        unsupported("()")
    }
    fn deserialize_unit_struct<V: Visitor<'de>>(self, name: &'static str, _: V) -> Result<V::Value, IntrospectError> {
        unsupported(&format!("unit struct {name}"))
    }
    fn deserialize_newtype_struct<V: Visitor<'de>>(self, _: &'static str, v: V) -> Result<V::Value, IntrospectError> {
        v.visit_newtype_struct(self)
    }
    fn deserialize_seq<V: Visitor<'de>>(self, v: V) -> Result<V::Value, IntrospectError> {
        let remaining = self.seq_len;
        v.visit_seq(ExemplarSeq { de: self, remaining })
    }
    fn deserialize_tuple<V: Visitor<'de>>(self, len: usize, v: V) -> Result<V::Value, IntrospectError> {
        v.visit_seq(ExemplarSeq { de: self, remaining: len })
    }
    fn deserialize_tuple_struct<V: Visitor<'de>>(
        self,
        _: &'static str,
        len: usize,
        v: V,
    ) -> Result<V::Value, IntrospectError> {
        self.deserialize_tuple(len, v)
    }
    fn deserialize_map<V: Visitor<'de>>(self, _: V) -> Result<V::Value, IntrospectError> {
        unsupported("a map")
    }
    fn deserialize_struct<V: Visitor<'de>>(
        self,
        _: &'static str,
        fields: &'static [&'static str],
        v: V,
    ) -> Result<V::Value, IntrospectError> {
        // serde-derived structs accept their fields positionally, which is how CDR reads them.
        v.visit_seq(ExemplarSeq { de: self, remaining: fields.len() })
    }
    fn deserialize_enum<V: Visitor<'de>>(
        self,
        name: &'static str,
        _: &'static [&'static str],
        _: V,
    ) -> Result<V::Value, IntrospectError> {
        unsupported(&format!("enum {name}"))
    }
    fn deserialize_identifier<V: Visitor<'de>>(self, _: V) -> Result<V::Value, IntrospectError> {
        unsupported("an identifier")
    }
    fn deserialize_ignored_any<V: Visitor<'de>>(self, _: V) -> Result<V::Value, IntrospectError> {
        unsupported("an ignored value")
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::QualityReport;
    use crate::std_msgs::Header;

    #[test]
    fn header_shape() {
        let shape = shape_of(&Header::default()).unwrap();
        let Shape::Struct { name, fields } = shape else { panic!("not a struct") };
        assert_eq!(name, "Header");
        assert_eq!(fields[1], ("frame_id".to_owned(), Shape::Prim(Kind::String)));
        assert!(matches!(&fields[0].1, Shape::Struct { name, .. } if name == "Time"));
    }

    #[test]
    fn exemplar_fills_sequences_and_differs_from_default() {
        let r: QualityReport = exemplar(2).unwrap();
        assert_eq!(r.checks.len(), 2);
        assert_ne!(r.checks[0], r.checks[1]);
        assert_ne!(r, QualityReport::default());
        assert!(r.header.frame_id.contains('Δ'));
        let Shape::Struct { fields, .. } = shape_of(&r).unwrap() else { panic!("not a struct") };
        let (name, checks) = &fields[2];
        assert_eq!(name, "checks");
        assert!(matches!(checks, Shape::Sequence(Some(e)) if matches!(**e, Shape::Struct { .. })));
        // Empty sequences hide their element type.
        let Shape::Struct { fields, .. } = shape_of(&QualityReport::default()).unwrap() else { panic!("not a struct") };
        assert_eq!(fields[2].1, Shape::Sequence(None));
    }

    #[test]
    fn arrays_and_unsupported_types() {
        assert_eq!(shape_of(&[1.0f64; 3]).unwrap(), Shape::Array(3, Box::new(Shape::Prim(Kind::F64))));
        assert!(shape_of(&Some(1u8)).is_err());
        assert!(shape_of(&std::collections::BTreeMap::<u8, u8>::new()).is_err());
        let arr: [u16; 4] = exemplar(0).unwrap();
        assert!(arr.iter().all(|x| *x != 0));
    }
}

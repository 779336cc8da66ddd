//! The pattern generator: a serde `Deserializer` that invents values by the documented rule,
//! so it fills any message type without per-type code.

use serde::de::{self, DeserializeOwned, DeserializeSeed, SeqAccess, Visitor};

/// Message number `n` of type `M` (see the crate docs for the rule).
pub fn pattern_message<M: DeserializeOwned>(n: u64) -> Result<M, PatternError> {
    let mut k = 0u64;
    M::deserialize(Pattern { n, k: &mut k })
}

/// A type the pattern cannot fill (maps, enums, options: none appear in ROS messages).
#[derive(Debug, thiserror::Error)]
#[error("test pattern: {0}")]
pub struct PatternError(String);

impl de::Error for PatternError {
    fn custom<T: std::fmt::Display>(msg: T) -> Self {
        Self(msg.to_string())
    }
}

struct Pattern<'a> {
    n: u64,
    k: &'a mut u64,
}

impl Pattern<'_> {
    fn next(&mut self) -> u64 {
        let v = self.n.wrapping_add(*self.k);
        *self.k += 1;
        v
    }
}

macro_rules! unsigned {
    ($name:ident, $visit:ident, $ty:ty) => {
        fn $name<V: Visitor<'de>>(mut self, v: V) -> Result<V::Value, PatternError> {
            v.$visit(self.next() as $ty)
        }
    };
}
macro_rules! signed {
    ($name:ident, $visit:ident, $ty:ty, $bits:expr) => {
        fn $name<V: Visitor<'de>>(mut self, v: V) -> Result<V::Value, PatternError> {
            v.$visit((self.next() % (1u64 << ($bits - 1))) as $ty)
        }
    };
}

impl<'de> de::Deserializer<'de> for Pattern<'_> {
    type Error = PatternError;

    fn deserialize_any<V: Visitor<'de>>(self, _: V) -> Result<V::Value, PatternError> {
        Err(PatternError("only typed fields can be filled".into()))
    }
    unsigned!(deserialize_u8, visit_u8, u8);
    unsigned!(deserialize_u16, visit_u16, u16);
    unsigned!(deserialize_u32, visit_u32, u32);
    unsigned!(deserialize_u64, visit_u64, u64);
    signed!(deserialize_i8, visit_i8, i8, 8);
    signed!(deserialize_i16, visit_i16, i16, 16);
    signed!(deserialize_i32, visit_i32, i32, 32);
    signed!(deserialize_i64, visit_i64, i64, 64);

    fn deserialize_f64<V: Visitor<'de>>(mut self, v: V) -> Result<V::Value, PatternError> {
        let n = self.n as f64;
        let k = *self.k as f64;
        self.next();
        v.visit_f64(n + k / 8.0)
    }
    fn deserialize_f32<V: Visitor<'de>>(mut self, v: V) -> Result<V::Value, PatternError> {
        let n = self.n as f32;
        let k = *self.k as f32;
        self.next();
        v.visit_f32(n + k / 8.0)
    }
    fn deserialize_bool<V: Visitor<'de>>(mut self, v: V) -> Result<V::Value, PatternError> {
        v.visit_bool(self.next() % 2 == 1)
    }
    fn deserialize_string<V: Visitor<'de>>(self, v: V) -> Result<V::Value, PatternError> {
        let s = format!("{}:{}:ü", self.n, self.k);
        *self.k += 1;
        v.visit_string(s)
    }
    fn deserialize_str<V: Visitor<'de>>(self, v: V) -> Result<V::Value, PatternError> {
        self.deserialize_string(v)
    }
    fn deserialize_seq<V: Visitor<'de>>(mut self, v: V) -> Result<V::Value, PatternError> {
        let len = (self.next() % 3) as usize;
        v.visit_seq(Elements { n: self.n, k: self.k, left: len })
    }
    fn deserialize_struct<V: Visitor<'de>>(
        self,
        _name: &'static str,
        fields: &'static [&'static str],
        v: V,
    ) -> Result<V::Value, PatternError> {
        v.visit_seq(Elements { n: self.n, k: self.k, left: fields.len() })
    }
    fn deserialize_tuple<V: Visitor<'de>>(self, len: usize, v: V) -> Result<V::Value, PatternError> {
        v.visit_seq(Elements { n: self.n, k: self.k, left: len })
    }
    fn deserialize_newtype_struct<V: Visitor<'de>>(self, _: &'static str, v: V) -> Result<V::Value, PatternError> {
        v.visit_newtype_struct(self)
    }

    serde::forward_to_deserialize_any! {
        i128 u128 char bytes byte_buf option unit unit_struct
        tuple_struct map enum identifier ignored_any
    }
}

struct Elements<'a> {
    n: u64,
    k: &'a mut u64,
    left: usize,
}

impl<'de> SeqAccess<'de> for Elements<'_> {
    type Error = PatternError;
    fn next_element_seed<T: DeserializeSeed<'de>>(&mut self, seed: T) -> Result<Option<T::Value>, PatternError> {
        if self.left == 0 {
            return Ok(None);
        }
        self.left -= 1;
        seed.deserialize(Pattern { n: self.n, k: self.k }).map(Some)
    }
    fn size_hint(&self) -> Option<usize> {
        Some(self.left)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use tyre_msgs::{QualityReport, RigSample, RigSetpoint, diagnostic_msgs::DiagnosticArray, rosgraph_msgs::Clock};

    #[test]
    fn rig_sample_follows_the_rule() {
        let s: RigSample = pattern_message(10).expect("pattern");
        // leaves: stamp.sec (k0), stamp.nanosec (k1), frame_id (k2), seq (k3), runtime_s (k4), fx_n (k5) ...
        assert_eq!(s.header.stamp.sec, 10);
        assert_eq!(s.header.stamp.nanosec, 11);
        assert_eq!(s.header.frame_id, "10:2:ü");
        assert_eq!(s.seq, 13);
        assert_eq!(s.runtime_s, 10.5);
        assert_eq!(s.fx_n, 10.625);
        // rig_mode follows the 18 float64 channels after seq: leaf k = 4 + 17 = 21.
        assert_eq!(s.rig_mode, (10 + 21) as u8);
        assert_eq!(s.fault_flags, 10 + 22);
    }

    #[test]
    fn every_field_differs_and_messages_differ() {
        let a: RigSetpoint = pattern_message(3).expect("pattern");
        let b: RigSetpoint = pattern_message(4).expect("pattern");
        assert_ne!(a, b);
        let floats = [a.slip_angle_deg, a.slip_ratio, a.fz_n, a.camber_deg, a.pressure_pa, a.speed_mps];
        for (i, x) in floats.iter().enumerate() {
            for y in &floats[i + 1..] {
                assert_ne!(x, y);
            }
        }
    }

    #[test]
    fn arrays_and_nesting() {
        for n in 0..6 {
            let d: DiagnosticArray = pattern_message(n).expect("pattern");
            assert_eq!(d.header.stamp.sec as u64, n);
            // array length is (n + k) mod 3 with k = 3 (after sec, nanosec, frame_id)
            assert_eq!(d.status.len() as u64, (n + 3) % 3);
            let q: QualityReport = pattern_message(n).expect("pattern");
            assert_eq!(q.header.stamp.sec as u64, n);
        }
        let c: Clock = pattern_message(7).expect("pattern");
        assert_eq!(c.clock.sec, 7);
    }
}

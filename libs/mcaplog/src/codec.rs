//! CDR as MCAP's `cdr` encoding and ROS 2 put it on the wire: a 4-byte encapsulation header
//! (`00 01 00 00` = plain CDR, little-endian) followed by the CDR body.

use serde::{Serialize, de::DeserializeOwned};
use tyre_msgs::{
    builtin_interfaces::Time,
    cdr::{from_cdr_with_header, to_cdr_with_header},
};

/// Big-endian plain CDR's encapsulation header (accepted when reading).
const CDR_BE_HEADER: [u8; 2] = [0x00, 0x00];

/// A message that did not encode or decode, named by its ROS type.
#[derive(Debug, thiserror::Error)]
#[error("{type_name}: {source}")]
pub struct CodecError {
    pub type_name: String,
    #[source]
    pub source: tyre_msgs::cdr::CdrError,
}

/// Encodes a message as encapsulation header + little-endian CDR body.
pub fn encode<M: Serialize>(msg: &M, type_name: &str) -> Result<Vec<u8>, CodecError> {
    to_cdr_with_header(msg).map_err(|source| CodecError { type_name: type_name.to_owned(), source })
}

/// Decodes encapsulation header + CDR body.
pub fn decode<M: DeserializeOwned>(bytes: &[u8], type_name: &str) -> Result<M, CodecError> {
    from_cdr_with_header(bytes).map_err(|source| CodecError { type_name: type_name.to_owned(), source })
}

/// The stamp every suite topic's message starts with (`header.stamp`, or `Clock.clock`), read
/// straight from the encoded bytes so the recorder needs no per-type code. Returns `None` when
/// the bytes are too short.
pub fn leading_stamp(bytes: &[u8]) -> Option<Time> {
    let header: [u8; 4] = bytes.get(..4)?.try_into().ok()?;
    let sec: [u8; 4] = bytes.get(4..8)?.try_into().ok()?;
    let nsec: [u8; 4] = bytes.get(8..12)?.try_into().ok()?;
    let (sec, nanosec) = if header[..2] == CDR_BE_HEADER {
        (i32::from_be_bytes(sec), u32::from_be_bytes(nsec))
    } else {
        (i32::from_le_bytes(sec), u32::from_le_bytes(nsec))
    };
    Some(Time { sec, nanosec })
}

#[cfg(test)]
mod tests {
    use super::*;
    use tyre_msgs::{RigSample, std_msgs::Header};

    #[test]
    fn round_trip_and_stamp() {
        let msg = RigSample { header: Header::iso_w(12.5), seq: 7, fx_n: -1.5, ..Default::default() };
        let bytes = encode(&msg, "RigSample").expect("encode");
        assert_eq!(&bytes[..4], &tyre_msgs::cdr::CDR_LE_HEADER);
        let back: RigSample = decode(&bytes, "RigSample").expect("decode");
        assert_eq!(back, msg);
        assert_eq!(leading_stamp(&bytes), Some(msg.header.stamp));
    }

    #[test]
    fn bad_bytes_are_named() {
        let err = decode::<RigSample>(&[0, 1], "RigSample").expect_err("too short");
        assert!(err.to_string().contains("RigSample"), "{err}");
        let err = decode::<RigSample>(&[9, 9, 0, 0, 1], "RigSample").expect_err("bad header");
        assert!(err.to_string().contains("encapsulation"));
        let err = decode::<RigSample>(&[0, 1, 0, 0, 1], "tyre_msgs/msg/RigSample").expect_err("short body");
        assert!(err.to_string().contains("tyre_msgs/msg/RigSample"), "{err}");
    }
}

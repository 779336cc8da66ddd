//! CDR (plain XCDR1, as ROS 2 and DDS put it on the wire) with the 4-byte encapsulation header.
//!
//! A serialized payload — on the wire in DDS and in MCAP with message encoding `cdr` — is a
//! 4-byte encapsulation header followed by the CDR body. The header's first two bytes name the
//! representation (`00 01` = CDR little-endian, `00 00` = CDR big-endian); the last two are
//! options (RTPS uses the low bits for the padding added at the end) and are ignored on read.
//! Alignment inside the body is counted from the body's first byte, so the body is encoded on
//! its own and the header prepended.

use byteorder::{BigEndian, LittleEndian};
use cdr_encoding::CdrSerializer;
use serde::Serialize;
use serde::de::DeserializeOwned;

/// Encapsulation header for CDR little-endian, options zero: what this crate writes.
pub const CDR_LE_HEADER: [u8; 4] = [0x00, 0x01, 0x00, 0x00];

/// Representation identifier for CDR big-endian (read, never written).
const CDR_BE_ID: [u8; 2] = [0x00, 0x00];
/// Representation identifier for CDR little-endian.
const CDR_LE_ID: [u8; 2] = [0x00, 0x01];

/// Encoding or decoding CDR failed.
#[derive(Debug, thiserror::Error)]
pub enum CdrError {
    /// The value could not be encoded (a serde feature CDR has no form for, e.g. a map).
    #[error("CDR encoding failed: {0}")]
    Encode(#[source] cdr_encoding::Error),
    /// The payload is shorter than the encapsulation header.
    #[error("CDR payload of {len} bytes is shorter than the 4-byte encapsulation header")]
    TooShort {
        /// Payload length.
        len: usize,
    },
    /// The header names a representation this crate does not read (e.g. XCDR2 or PL_CDR).
    #[error(
        "unsupported CDR encapsulation {:02x} {:02x} (expected 00 01 = CDR_LE or 00 00 = CDR_BE)",
        id[0],
        id[1]
    )]
    UnsupportedEncapsulation {
        /// The representation identifier found.
        id: [u8; 2],
    },
    /// The body does not decode as the requested type.
    #[error("CDR decoding failed after {consumed} of {len} body bytes: {source}")]
    Decode {
        /// Bytes consumed before the failure (0 if unknown).
        consumed: usize,
        /// Body length.
        len: usize,
        /// The decoder's error.
        #[source]
        source: cdr_encoding::Error,
    },
    /// The body decoded but left more bytes than end-of-message padding can explain.
    #[error("{extra} bytes left over after decoding a {len}-byte CDR body")]
    TrailingBytes {
        /// Unconsumed bytes.
        extra: usize,
        /// Body length.
        len: usize,
    },
}

/// Encode `msg` as a little-endian CDR body (no encapsulation header).
pub fn to_cdr<M: Serialize + ?Sized>(msg: &M) -> Result<Vec<u8>, CdrError> {
    let mut out = Vec::with_capacity(64);
    write_body(&mut out, msg)?;
    Ok(out)
}

/// Encode `msg` as a serialized payload: [`CDR_LE_HEADER`] followed by the little-endian body.
/// This is what DDS sends and what MCAP stores for message encoding `cdr`.
pub fn to_cdr_with_header<M: Serialize + ?Sized>(msg: &M) -> Result<Vec<u8>, CdrError> {
    let mut out = Vec::with_capacity(64);
    out.extend_from_slice(&CDR_LE_HEADER);
    // A fresh serializer counts alignment from its own first byte, i.e. from the body start.
    write_body(&mut out, msg)?;
    Ok(out)
}

fn write_body<M: Serialize + ?Sized>(out: &mut Vec<u8>, msg: &M) -> Result<(), CdrError> {
    msg.serialize(&mut CdrSerializer::<_, LittleEndian>::new(out)).map_err(CdrError::Encode)
}

/// Decode a little-endian CDR body (no encapsulation header).
pub fn from_cdr<M: DeserializeOwned>(body: &[u8]) -> Result<M, CdrError> {
    decode::<M, LittleEndian>(body)
}

/// Decode a serialized payload: check the encapsulation header (CDR_LE or CDR_BE), then decode
/// the body. Up to 3 trailing bytes are accepted as the end-of-message padding DDS writers add.
pub fn from_cdr_with_header<M: DeserializeOwned>(bytes: &[u8]) -> Result<M, CdrError> {
    let (header, body) = bytes.split_first_chunk::<4>().ok_or(CdrError::TooShort { len: bytes.len() })?;
    match [header[0], header[1]] {
        CDR_LE_ID => decode::<M, LittleEndian>(body),
        CDR_BE_ID => decode::<M, BigEndian>(body),
        id => Err(CdrError::UnsupportedEncapsulation { id }),
    }
}

fn decode<M: DeserializeOwned, BO: byteorder::ByteOrder>(body: &[u8]) -> Result<M, CdrError> {
    let (msg, consumed) = cdr_encoding::from_bytes::<M, BO>(body).map_err(|source| CdrError::Decode {
        consumed: 0,
        len: body.len(),
        source,
    })?;
    let extra = body.len().saturating_sub(consumed);
    if extra > 3 {
        return Err(CdrError::TrailingBytes { extra, len: body.len() });
    }
    Ok(msg)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::builtin_interfaces::Time;
    use crate::std_msgs::Header;
    use crate::{QualityCheck, QualityReport, RigSample};

    #[test]
    fn header_is_cdr_le() {
        let bytes = to_cdr_with_header(&Time { sec: 1, nanosec: 2 }).unwrap();
        assert_eq!(bytes, [0, 1, 0, 0, 1, 0, 0, 0, 2, 0, 0, 0]);
        assert_eq!(from_cdr_with_header::<Time>(&bytes).unwrap(), Time { sec: 1, nanosec: 2 });
    }

    #[test]
    fn big_endian_is_read() {
        let bytes = [0, 0, 0, 0, 0, 0, 0, 1, 0, 0, 0, 2];
        assert_eq!(from_cdr_with_header::<Time>(&bytes).unwrap(), Time { sec: 1, nanosec: 2 });
    }

    #[test]
    fn bad_payloads_are_errors_not_panics() {
        assert!(matches!(from_cdr_with_header::<Time>(&[0, 1]), Err(CdrError::TooShort { len: 2 })));
        assert!(matches!(
            from_cdr_with_header::<Time>(&[0, 7, 0, 0, 1, 0, 0, 0, 2, 0, 0, 0]),
            Err(CdrError::UnsupportedEncapsulation { id: [0, 7] })
        ));
        assert!(matches!(from_cdr_with_header::<Time>(&[0, 1, 0, 0, 1, 0, 0]), Err(CdrError::Decode { .. })));
        let mut long = to_cdr_with_header(&Time::default()).unwrap();
        long.extend_from_slice(&[0; 4]);
        assert!(matches!(from_cdr_with_header::<Time>(&long), Err(CdrError::TrailingBytes { extra: 4, .. })));
        // A string length that runs past the end must not panic.
        assert!(from_cdr_with_header::<Header>(&[0, 1, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 255, 255, 255, 255]).is_err());
        // Up to 3 bytes of end padding are fine.
        let mut padded = to_cdr_with_header(&QualityCheck::default()).unwrap();
        padded.extend_from_slice(&[0; 3]);
        assert!(from_cdr_with_header::<QualityCheck>(&padded).is_ok());
    }

    /// Every byte of a small RigSample, worked out by hand from the CDR alignment rules.
    #[test]
    fn rig_sample_bytes_are_exact() {
        let sample = RigSample {
            header: Header { stamp: Time { sec: 3, nanosec: 500_000_000 }, frame_id: "iso_w".to_owned() },
            seq: 42,
            runtime_s: 3.5,
            fx_n: -1.0,
            fzw_n: 4000.0,
            rig_mode: 1,
            fault_flags: RigSample::FAULT_TEMPERATURE | RigSample::FAULT_ESTOP,
            ..RigSample::default()
        };
        let mut expected: Vec<u8> = vec![0x00, 0x01, 0x00, 0x00]; // CDR_LE encapsulation
        // body offset 0: header.stamp.sec (int32) = 3
        expected.extend_from_slice(&[0x03, 0x00, 0x00, 0x00]);
        // 4: header.stamp.nanosec (uint32) = 500_000_000 = 0x1DCD6500
        expected.extend_from_slice(&[0x00, 0x65, 0xCD, 0x1D]);
        // 8: frame_id: length 6 (5 bytes + NUL), "iso_w", NUL -> ends at 18
        expected.extend_from_slice(&[0x06, 0x00, 0x00, 0x00]);
        expected.extend_from_slice(b"iso_w\0");
        // 18: seq (uint64) aligns to 8 -> 6 bytes padding, at 24
        expected.extend_from_slice(&[0; 6]);
        expected.extend_from_slice(&42u64.to_le_bytes());
        // 32: runtime_s 3.5 = 0x400C000000000000
        expected.extend_from_slice(&[0, 0, 0, 0, 0, 0, 0x0C, 0x40]);
        // 40: fx_n -1.0 = 0xBFF0000000000000
        expected.extend_from_slice(&[0, 0, 0, 0, 0, 0, 0xF0, 0xBF]);
        // 48: fyw_n 0.0
        expected.extend_from_slice(&[0; 8]);
        // 56: fzw_n 4000.0 = 0x40AF400000000000
        expected.extend_from_slice(&[0, 0, 0, 0, 0, 0x40, 0xAF, 0x40]);
        // 64..168: the other 13 float64 fields (mxw_nm .. trdtempo_c), all 0.0
        expected.extend_from_slice(&[0; 13 * 8]);
        // 168: rig_mode (uint8) = 1
        expected.push(0x01);
        // 169: fault_flags (uint32) aligns to 4 -> 3 bytes padding, at 172: 2 | 16 = 18
        expected.extend_from_slice(&[0, 0, 0]);
        expected.extend_from_slice(&[0x12, 0, 0, 0]);
        // body ends at 176 (180 with the header)
        assert_eq!(expected.len(), 180);
        let bytes = to_cdr_with_header(&sample).unwrap();
        assert_eq!(bytes, expected);
        assert_eq!(to_cdr(&sample).unwrap(), expected[4..]);
        assert_eq!(from_cdr_with_header::<RigSample>(&bytes).unwrap(), sample);
    }

    /// A sequence of structs: u32 count, then each element aligned as its first member needs.
    #[test]
    fn sequence_of_structs_bytes_are_exact() {
        let report = QualityReport {
            level: 2,
            checks: vec![QualityCheck { level: 1, check: "ab".to_owned(), ..QualityCheck::default() }],
            ..QualityReport::default()
        };
        let body = to_cdr(&report).unwrap();
        let mut expected: Vec<u8> = Vec::new();
        expected.extend_from_slice(&[0; 8]); // stamp
        expected.extend_from_slice(&[1, 0, 0, 0, 0]); // frame_id "" = length 1 + NUL, ends at 13
        expected.push(2); // 13: level
        expected.extend_from_slice(&[0, 0]); // pad to 16
        expected.extend_from_slice(&[1, 0, 0, 0]); // 16: checks length 1
        expected.push(1); // 20: checks[0].level
        expected.extend_from_slice(&[0, 0, 0]); // pad to 24
        expected.extend_from_slice(&[3, 0, 0, 0, b'a', b'b', 0]); // 24: check "ab" -> 31
        expected.push(0); // pad to 32
        expected.extend_from_slice(&[1, 0, 0, 0, 0]); // 32: message "" -> 37
        expected.extend_from_slice(&[0, 0, 0]); // pad to 40
        expected.extend_from_slice(&[0; 16]); // 40: value, threshold
        expected.extend_from_slice(&[1, 0, 0, 0, 0]); // 56: unit "" -> 61
        expected.extend_from_slice(&[0, 0, 0]); // pad to 64
        expected.extend_from_slice(&[0; 8]); // 64: rig_time_s
        expected.extend_from_slice(&[0; 40]); // 72: five float64 -> 112
        assert_eq!(body, expected);
    }
}

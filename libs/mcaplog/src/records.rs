//! Every record of an MCAP file in order, chunks unpacked — with every length the file states
//! checked against the bytes that are really there before anything is allocated for it.
//!
//! `mcap`'s readers trust length fields: `ChunkFlattener` (behind `MessageStream`) a record's
//! length inside a chunk, and its record parser a string's length inside a record; a corrupt one
//! asks for gigabytes (both found by fuzzing, `tests/fuzz`). Here the sans-io reader runs with a
//! record length limit, and the four records a suite log needs (schema, channel, message,
//! metadata) are decoded by hand with bounds checks; the rest (indexes, statistics, summary) are
//! skipped, as every reader here rebuilds or ignores them.

use mcap::records::op;
use mcap::sans_io::{LinearReadEvent, LinearReader, LinearReaderOptions};
use std::collections::BTreeMap;

/// The longest record (or decompressed chunk) accepted in a file of `file_len` bytes: a chunk
/// may decompress to far more than its compressed size, but not without bound. The suite writes
/// chunks of 1 MiB.
pub fn record_length_limit(file_len: usize) -> usize {
    file_len.saturating_mul(64).clamp(16 << 20, 1 << 30)
}

/// A record of a suite log.
#[derive(Debug, Clone, PartialEq)]
pub enum LogRecord {
    Schema {
        id: u16,
        name: String,
        encoding: String,
        data: Vec<u8>,
    },
    Channel {
        id: u16,
        schema_id: u16,
        topic: String,
        message_encoding: String,
    },
    Message {
        channel_id: u16,
        sequence: u32,
        log_time: u64,
        publish_time: u64,
        data: Vec<u8>,
    },
    Metadata {
        name: String,
        entries: BTreeMap<String, String>,
    },
    /// Any other record (header, indexes, statistics, attachments, footer…).
    Other,
}

/// Records of `bytes`, chunks flattened, chunk CRCs checked.
pub struct Records<'a> {
    buf: &'a [u8],
    reader: LinearReader,
}

impl std::fmt::Debug for Records<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Records").field("unread_bytes", &self.buf.len()).finish()
    }
}

impl<'a> Records<'a> {
    pub fn new(bytes: &'a [u8]) -> Self {
        let options = LinearReaderOptions::default()
            .with_validate_chunk_crcs(true)
            .with_record_length_limit(record_length_limit(bytes.len()));
        Self { buf: bytes, reader: LinearReader::new_with_options(options) }
    }
}

impl Iterator for Records<'_> {
    /// A record, or why reading stopped.
    type Item = Result<LogRecord, String>;

    fn next(&mut self) -> Option<Self::Item> {
        while let Some(event) = self.reader.next_event() {
            match event {
                Ok(LinearReadEvent::ReadRequest(need)) => {
                    let len = need.min(self.buf.len());
                    if len == 0 {
                        return Some(Err("the file ends inside a record".to_owned()));
                    }
                    self.reader.insert(len).copy_from_slice(&self.buf[..len]);
                    self.reader.notify_read(len);
                    self.buf = &self.buf[len..];
                }
                Ok(LinearReadEvent::Record { data, opcode }) => return Some(parse(opcode, data)),
                Err(e) => return Some(Err(e.to_string())),
            }
        }
        None
    }
}

/// A cursor over one record's body whose every read is bounded by what is left.
struct Body<'a> {
    rest: &'a [u8],
    what: &'static str,
}

impl<'a> Body<'a> {
    fn take(&mut self, n: usize, field: &str) -> Result<&'a [u8], String> {
        if n > self.rest.len() {
            return Err(format!(
                "{} record: {field} claims {n} bytes, {} are left in the record",
                self.what,
                self.rest.len()
            ));
        }
        let (head, tail) = self.rest.split_at(n);
        self.rest = tail;
        Ok(head)
    }
    fn u16(&mut self, field: &str) -> Result<u16, String> {
        Ok(u16::from_le_bytes(self.take(2, field)?.try_into().expect("2 bytes")))
    }
    fn u32(&mut self, field: &str) -> Result<u32, String> {
        Ok(u32::from_le_bytes(self.take(4, field)?.try_into().expect("4 bytes")))
    }
    fn u64(&mut self, field: &str) -> Result<u64, String> {
        Ok(u64::from_le_bytes(self.take(8, field)?.try_into().expect("8 bytes")))
    }
    fn bytes(&mut self, field: &str) -> Result<&'a [u8], String> {
        let n = self.u32(field)? as usize;
        self.take(n, field)
    }
    fn string(&mut self, field: &str) -> Result<String, String> {
        let b = self.bytes(field)?;
        String::from_utf8(b.to_vec()).map_err(|_| format!("{} record: {field} is not UTF-8", self.what))
    }
    fn map(&mut self, field: &str) -> Result<BTreeMap<String, String>, String> {
        let mut inner = Body { rest: self.bytes(field)?, what: self.what };
        let mut m = BTreeMap::new();
        while !inner.rest.is_empty() {
            let k = inner.string(field)?;
            let v = inner.string(field)?;
            m.insert(k, v);
        }
        Ok(m)
    }
}

fn parse(opcode: u8, data: &[u8]) -> Result<LogRecord, String> {
    Ok(match opcode {
        op::SCHEMA => {
            let mut b = Body { rest: data, what: "schema" };
            let id = b.u16("id")?;
            let name = b.string("name")?;
            let encoding = b.string("encoding")?;
            let data = b.bytes("data")?.to_vec();
            LogRecord::Schema { id, name, encoding, data }
        }
        op::CHANNEL => {
            let mut b = Body { rest: data, what: "channel" };
            let id = b.u16("id")?;
            let schema_id = b.u16("schema_id")?;
            let topic = b.string("topic")?;
            let message_encoding = b.string("message_encoding")?;
            let _ = b.map("metadata")?;
            LogRecord::Channel { id, schema_id, topic, message_encoding }
        }
        op::MESSAGE => {
            let mut b = Body { rest: data, what: "message" };
            let channel_id = b.u16("channel_id")?;
            let sequence = b.u32("sequence")?;
            let log_time = b.u64("log_time")?;
            let publish_time = b.u64("publish_time")?;
            LogRecord::Message { channel_id, sequence, log_time, publish_time, data: b.rest.to_vec() }
        }
        op::METADATA => {
            let mut b = Body { rest: data, what: "metadata" };
            let name = b.string("name")?;
            let entries = b.map("metadata")?;
            LogRecord::Metadata { name, entries }
        }
        _ => LogRecord::Other,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lengths_beyond_the_record_are_refused_without_allocating() {
        // A metadata record whose name claims 3.6 GB.
        let mut rec = Vec::new();
        rec.extend_from_slice(&3_631_611_911u32.to_le_bytes());
        rec.extend_from_slice(b"tyrerig");
        let err = parse(op::METADATA, &rec).expect_err("too long");
        assert!(err.contains("metadata record") && err.contains("3631611911"), "{err}");
        // A truncated message header.
        assert!(parse(op::MESSAGE, &[1, 0, 0]).is_err());
    }
}

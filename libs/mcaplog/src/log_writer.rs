//! [`McapLog`]: the ROS 2-profile MCAP writer behind the recorder (and any tool writing logs).

use std::{
    collections::{BTreeMap, HashMap},
    fs::File,
    io::BufWriter,
    path::{Path, PathBuf},
};

/// How the log is laid out.
#[derive(Debug, Clone)]
pub struct McapLogOptions {
    /// Uncompressed bytes after which a chunk is closed.
    pub chunk_size_bytes: u64,
    /// A chunk is also closed when it holds messages spanning more than this much log time, so
    /// a killed recorder loses at most this much (and a quiet topic still reaches the disk).
    pub flush_interval_s: f64,
    /// zstd level (1–19); 3 is zstd's own default, fast enough for 1 kHz streams.
    pub zstd_level: u32,
}

impl Default for McapLogOptions {
    fn default() -> Self {
        Self { chunk_size_bytes: 1 << 20, flush_interval_s: 1.0, zstd_level: 3 }
    }
}

/// Why the log could not be written. Names the file.
#[derive(Debug, thiserror::Error)]
pub enum LogWriteError {
    #[error("{path}: cannot create the log file: {source}")]
    Create { path: PathBuf, source: std::io::Error },
    #[error("{path}: MCAP write failed: {detail}")]
    Mcap { path: PathBuf, detail: String },
    #[error("{path}: no ros2msg schema known for type {type_name:?}")]
    UnknownType { path: PathBuf, type_name: String },
}

/// An open ROS 2-profile MCAP log.
pub struct McapLog {
    writer: Option<mcap::Writer<BufWriter<File>>>,
    path: PathBuf,
    options: McapLogOptions,
    /// topic → (channel id, next sequence number)
    channels: HashMap<String, (u16, u32)>,
    /// ros type → schema id
    schemas: HashMap<String, u16>,
    chunk_started_ns: Option<u64>,
    messages: u64,
    bytes: u64,
}

impl std::fmt::Debug for McapLog {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("McapLog").field("path", &self.path).field("messages", &self.messages).finish()
    }
}

impl McapLog {
    /// Creates `path` (and its parent directories) and writes the header.
    pub fn create(path: &Path, options: McapLogOptions) -> Result<Self, LogWriteError> {
        if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
            std::fs::create_dir_all(dir).map_err(|source| LogWriteError::Create { path: path.to_owned(), source })?;
        }
        let file = File::create(path).map_err(|source| LogWriteError::Create { path: path.to_owned(), source })?;
        let writer = mcap::WriteOptions::new()
            .profile("ros2")
            .library(format!("tyrerig {}", env!("CARGO_PKG_VERSION")))
            .compression(Some(mcap::Compression::Zstd))
            .compression_level(options.zstd_level)
            .chunk_size(Some(options.chunk_size_bytes))
            .emit_message_indexes(true)
            .emit_summary_records(true)
            .create(BufWriter::new(file))
            .map_err(|e| LogWriteError::Mcap { path: path.to_owned(), detail: e.to_string() })?;
        Ok(Self {
            writer: Some(writer),
            path: path.to_owned(),
            options,
            channels: HashMap::new(),
            schemas: HashMap::new(),
            chunk_started_ns: None,
            messages: 0,
            bytes: 0,
        })
    }

    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Messages written so far.
    pub fn message_count(&self) -> u64 {
        self.messages
    }

    /// Message payload bytes written so far (before compression).
    pub fn payload_bytes(&self) -> u64 {
        self.bytes
    }

    fn mcap_err(&self, e: impl std::fmt::Display) -> LogWriteError {
        LogWriteError::Mcap { path: self.path.clone(), detail: e.to_string() }
    }

    fn writer(&mut self) -> Result<&mut mcap::Writer<BufWriter<File>>, LogWriteError> {
        let path = self.path.clone();
        self.writer.as_mut().ok_or(LogWriteError::Mcap { path, detail: "log already finished".into() })
    }

    /// Writes a metadata record (e.g. `tyre`, `procedure`, `tyrerig`). Closes the open chunk
    /// first so the record lands on disk at once.
    pub fn write_metadata(&mut self, name: &str, entries: &BTreeMap<String, String>) -> Result<(), LogWriteError> {
        let md = mcap::records::Metadata { name: name.to_owned(), metadata: entries.clone() };
        let r = self.writer()?.write_metadata(&md);
        r.map_err(|e| self.mcap_err(e))
    }

    /// Registers `topic` carrying `ros_type` (schema text `schema`, `ros2msg`) and returns its
    /// channel id; repeated calls return the same id.
    pub fn ensure_channel(&mut self, topic: &str, ros_type: &str, schema: &str) -> Result<u16, LogWriteError> {
        if let Some((id, _)) = self.channels.get(topic) {
            return Ok(*id);
        }
        let schema_id = match self.schemas.get(ros_type) {
            Some(id) => *id,
            None => {
                let r = self.writer()?.add_schema(ros_type, "ros2msg", schema.as_bytes());
                let id = r.map_err(|e| self.mcap_err(e))?;
                self.schemas.insert(ros_type.to_owned(), id);
                id
            }
        };
        let r = self.writer()?.add_channel(schema_id, topic, "cdr", &BTreeMap::new());
        let id = r.map_err(|e| self.mcap_err(e))?;
        self.channels.insert(topic.to_owned(), (id, 0));
        Ok(id)
    }

    /// Writes one encoded message (encapsulation header + CDR) on a registered channel.
    pub fn write(
        &mut self,
        channel_id: u16,
        log_time_ns: u64,
        publish_time_ns: u64,
        data: &[u8],
    ) -> Result<(), LogWriteError> {
        let sequence = match self.channels.values_mut().find(|(id, _)| *id == channel_id) {
            Some((_, seq)) => {
                let s = *seq;
                *seq = seq.wrapping_add(1);
                s
            }
            None => return Err(self.mcap_err(format!("channel {channel_id} was never registered"))),
        };
        let header =
            mcap::records::MessageHeader { channel_id, sequence, log_time: log_time_ns, publish_time: publish_time_ns };
        let r = self.writer()?.write_to_known_channel(&header, data);
        r.map_err(|e| self.mcap_err(e))?;
        self.messages += 1;
        self.bytes += data.len() as u64;
        let started = *self.chunk_started_ns.get_or_insert(log_time_ns);
        if log_time_ns.saturating_sub(started) as f64 * 1e-9 >= self.options.flush_interval_s {
            self.flush()?;
        }
        Ok(())
    }

    /// Closes the open chunk and flushes it to the file.
    pub fn flush(&mut self) -> Result<(), LogWriteError> {
        self.chunk_started_ns = None;
        let r = self.writer()?.flush();
        r.map_err(|e| self.mcap_err(e))
    }

    /// Writes the summary and footer. The log is complete and indexed afterwards.
    pub fn finish(mut self) -> Result<u64, LogWriteError> {
        self.finish_in_place()
    }

    fn finish_in_place(&mut self) -> Result<u64, LogWriteError> {
        if let Some(mut w) = self.writer.take() {
            w.finish().map_err(|e| self.mcap_err(e))?;
            let mut inner = w.into_inner();
            std::io::Write::flush(&mut inner).map_err(|e| self.mcap_err(e))?;
        }
        Ok(self.messages)
    }
}

impl Drop for McapLog {
    fn drop(&mut self) {
        // An orderly drop (panic unwinding, early return) still leaves a complete file.
        if self.writer.is_some()
            && let Err(e) = self.finish_in_place()
        {
            tracing::error!("{e}");
        }
    }
}

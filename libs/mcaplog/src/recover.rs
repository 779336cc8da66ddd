//! Recovery of a log cut short: keep every record of every complete chunk, write a valid MCAP.
//!
//! A killed recorder leaves the header, the metadata, every chunk it had closed (each with its
//! message indexes) and possibly half a chunk. Reading linearly until the first damaged record
//! and rewriting what came before gives a file every MCAP reader accepts.

use crate::log_writer::{LogWriteError, McapLog, McapLogOptions};
use std::{
    collections::HashMap,
    path::{Path, PathBuf},
};

/// What recovery found.
#[derive(Debug, Clone, PartialEq)]
pub struct RecoveryReport {
    pub messages: u64,
    pub channels: usize,
    pub metadata_records: usize,
    /// Why reading stopped (`None` when the input was already complete).
    pub stopped_at: Option<String>,
}

/// Why recovery failed outright.
#[derive(Debug, thiserror::Error)]
pub enum RecoverError {
    #[error("{path}: cannot read: {source}")]
    Io { path: PathBuf, source: std::io::Error },
    #[error("{path}: not an MCAP file (no MCAP magic at the start)")]
    NotMcap { path: PathBuf },
    #[error(transparent)]
    Write(#[from] LogWriteError),
    #[error("{input}: refusing to overwrite the input; choose another output path")]
    SamePath { input: PathBuf },
}

/// Reads `input` up to its first damaged record and writes everything before it to `output`.
pub fn recover(input: &Path, output: &Path) -> Result<RecoveryReport, RecoverError> {
    if input.canonicalize().ok().is_some_and(|i| output.canonicalize().ok().is_some_and(|o| o == i)) {
        return Err(RecoverError::SamePath { input: input.to_owned() });
    }
    let bytes = std::fs::read(input).map_err(|source| RecoverError::Io { path: input.to_owned(), source })?;
    if !bytes.starts_with(mcap::MAGIC) {
        return Err(RecoverError::NotMcap { path: input.to_owned() });
    }
    let mut out = McapLog::create(output, McapLogOptions { flush_interval_s: f64::INFINITY, ..Default::default() })?;
    let mut schemas: HashMap<u16, (String, String)> = HashMap::new(); // id → (name, text)
    let mut channel_map: HashMap<u16, u16> = HashMap::new(); // old id → new id
    let mut report = RecoveryReport { messages: 0, channels: 0, metadata_records: 0, stopped_at: None };
    // Bounded lengths: a damaged length field stops recovery, it cannot exhaust memory.
    let records = crate::records::Records::new(&bytes);
    for rec in records {
        let rec = match rec {
            Ok(r) => r,
            Err(e) => {
                report.stopped_at = Some(e);
                break;
            }
        };
        use crate::records::LogRecord;
        match rec {
            LogRecord::Schema { id, name, data, .. } => {
                schemas.insert(id, (name, String::from_utf8_lossy(&data).into_owned()));
            }
            LogRecord::Channel { id: old_id, schema_id, topic, .. } => {
                if channel_map.contains_key(&old_id) {
                    continue;
                }
                let (name, text) = schemas.get(&schema_id).cloned().unwrap_or_default();
                let id = out.ensure_channel(&topic, &name, &text)?;
                channel_map.insert(old_id, id);
                report.channels += 1;
            }
            LogRecord::Message { channel_id, log_time, publish_time, data, .. } => {
                if let Some(&id) = channel_map.get(&channel_id) {
                    out.write(id, log_time, publish_time, &data)?;
                    report.messages += 1;
                }
            }
            LogRecord::Metadata { name, entries } => {
                out.write_metadata(&name, &entries)?;
                report.metadata_records += 1;
            }
            // Indexes, statistics and the footer are rebuilt by the writer.
            LogRecord::Other => {}
        }
    }
    out.finish()?;
    Ok(report)
}

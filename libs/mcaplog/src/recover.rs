//! Recovery of a log cut short: keep every record of every complete chunk, write a valid MCAP.
//!
//! A killed recorder leaves the header, the metadata, every chunk it had closed (each with its
//! message indexes) and possibly half a chunk. Reading linearly until the first damaged record
//! and rewriting what came before gives a file every MCAP reader accepts.

use crate::log_writer::{LogWriteError, McapLog, McapLogOptions};
use std::{
    collections::{BTreeMap, HashMap},
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
    let records =
        match mcap::read::ChunkFlattener::new_with_options(&bytes, mcap::read::Options::ValidateChunkCrcs.into()) {
            Ok(r) => r,
            Err(e) => {
                return Err(RecoverError::Write(LogWriteError::Mcap { path: input.to_owned(), detail: e.to_string() }));
            }
        };
    for rec in records {
        let rec = match rec {
            Ok(r) => r,
            Err(e) => {
                report.stopped_at = Some(e.to_string());
                break;
            }
        };
        use mcap::records::Record;
        match rec {
            Record::Schema { header, data } => {
                schemas.insert(header.id, (header.name, String::from_utf8_lossy(&data).into_owned()));
            }
            Record::Channel(ch) => {
                if channel_map.contains_key(&ch.id) {
                    continue;
                }
                let (name, text) = schemas.get(&ch.schema_id).cloned().unwrap_or_default();
                let id = out.ensure_channel(&ch.topic, &name, &text)?;
                channel_map.insert(ch.id, id);
                report.channels += 1;
            }
            Record::Message { header, data } => {
                if let Some(&id) = channel_map.get(&header.channel_id) {
                    out.write(id, header.log_time, header.publish_time, &data)?;
                    report.messages += 1;
                }
            }
            Record::Metadata(md) => {
                let entries: BTreeMap<String, String> = md.metadata;
                out.write_metadata(&md.name, &entries)?;
                report.metadata_records += 1;
            }
            // Indexes, statistics and the footer are rebuilt by the writer.
            _ => {}
        }
    }
    out.finish()?;
    Ok(report)
}

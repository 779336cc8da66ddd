//! The recorder node's typed configuration.

use serde::Deserialize;
use std::{collections::BTreeMap, path::PathBuf};

/// `[node.config]` of a recorder in a launch file.
#[derive(Debug, Clone, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct RecorderConfig {
    /// The MCAP file to write (directories are created).
    pub output: PathBuf,
    /// Topics to record, as relative or absolute suite topic names; absent = every suite topic.
    #[serde(default)]
    pub topics: Option<Vec<String>>,
    /// Uncompressed bytes after which a chunk is closed.
    #[serde(default = "default_chunk_size")]
    pub chunk_size_bytes: u64,
    /// Longest log time a chunk may span: bounds what a killed recorder loses [s].
    #[serde(default = "default_flush_interval")]
    pub flush_interval_s: f64,
    /// zstd compression level.
    #[serde(default = "default_zstd_level")]
    pub zstd_level: u32,
    /// Extra metadata records: record name → key → value (e.g. `tyre`, `procedure`).
    #[serde(default)]
    pub metadata: BTreeMap<String, BTreeMap<String, String>>,
    /// What to do when `output` exists already: `overwrite` it (the default, as a rerun of
    /// `tyrerig run` expects) or record to a `new_file` beside it (`<stem>.1.mcap`, …), so a
    /// recorder restarted mid-run never destroys the first part of the run.
    #[serde(default)]
    pub on_existing: OnExisting,
}

/// See [`RecorderConfig::on_existing`].
#[derive(Debug, Clone, Copy, Default, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum OnExisting {
    #[default]
    Overwrite,
    NewFile,
}

fn default_chunk_size() -> u64 {
    1 << 20
}
fn default_flush_interval() -> f64 {
    1.0
}
fn default_zstd_level() -> u32 {
    3
}

/// A recorder setting that cannot work.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum RecorderConfigError {
    #[error("flush_interval_s = {0}: expected a positive number of seconds")]
    FlushInterval(f64),
    #[error("zstd_level = {0}: expected 1..=19")]
    ZstdLevel(u32),
    #[error("chunk_size_bytes = {0}: expected at least 1024")]
    ChunkSize(u64),
    #[error("output is empty: expected a file path such as \"out/run.mcap\"")]
    Output,
}

impl RecorderConfig {
    /// A config writing `output` with defaults for everything else.
    pub fn to_file(output: impl Into<PathBuf>) -> Self {
        Self {
            output: output.into(),
            topics: None,
            chunk_size_bytes: default_chunk_size(),
            flush_interval_s: default_flush_interval(),
            zstd_level: default_zstd_level(),
            metadata: BTreeMap::new(),
            on_existing: OnExisting::Overwrite,
        }
    }

    pub fn validate(&self) -> Result<(), RecorderConfigError> {
        if self.output.as_os_str().is_empty() {
            return Err(RecorderConfigError::Output);
        }
        if !(self.flush_interval_s.is_finite() && self.flush_interval_s > 0.0) {
            return Err(RecorderConfigError::FlushInterval(self.flush_interval_s));
        }
        if !(1..=19).contains(&self.zstd_level) {
            return Err(RecorderConfigError::ZstdLevel(self.zstd_level));
        }
        if self.chunk_size_bytes < 1024 {
            return Err(RecorderConfigError::ChunkSize(self.chunk_size_bytes));
        }
        Ok(())
    }
}

//! Errors of the fitter and the data converters.

use std::path::PathBuf;

/// Why a fit, an import or an export failed.
#[derive(Debug, thiserror::Error)]
pub enum FitError {
    /// A stage has too few points for its coefficients.
    #[error("stage `{stage}`: {points} data points cannot determine {needed} coefficients")]
    NotEnoughData {
        /// Stage name.
        stage: String,
        /// Points available.
        points: usize,
        /// Points needed.
        needed: usize,
    },
    /// The optimiser refused the problem.
    #[error("stage `{stage}`: optimiser: {source}")]
    Solver {
        /// Stage name.
        stage: String,
        /// Underlying error.
        source: lsq::LsqError,
    },
    /// No usable data at all.
    #[error("no usable data: {0}")]
    NoData(String),
    /// A log could not be read.
    #[error("{path}: {message}")]
    Log {
        /// File.
        path: PathBuf,
        /// What went wrong.
        message: String,
    },
    /// A TYDEX/TTC file is malformed.
    #[error("{path}:{line}: {message}")]
    Format {
        /// File.
        path: PathBuf,
        /// 1-based line (0 = whole file).
        line: usize,
        /// What was expected.
        message: String,
    },
    /// File I/O.
    #[error("{path}: {source}")]
    Io {
        /// File.
        path: PathBuf,
        /// Underlying error.
        source: std::io::Error,
    },
    /// `.tir` handling.
    #[error("tyre property file: {0}")]
    Tir(#[from] mftyre::TirError),
    /// Plotting.
    #[error("plot {path}: {message}")]
    Plot {
        /// Output file.
        path: PathBuf,
        /// Backend message.
        message: String,
    },
}

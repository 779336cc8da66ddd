//! The live fit's files at the procedure's end: the `.tir` and the fit report (the same report
//! `tyrerig fit --report` writes). I/O, so not part of the core: the DDS shell and the headless
//! suite call it with the core's final fit.

use std::path::{Path, PathBuf};

use mffit::FitResult;

/// Where the live fit writes its model at the end.
#[derive(Debug, Clone, Default, PartialEq, serde::Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct ModelOutput {
    /// The fitted `.tir` (FITTYP 61); nothing written when absent.
    pub tir: Option<PathBuf>,
    /// The fit report's directory (report.md, fit.json, plots); nothing written when absent.
    pub report: Option<PathBuf>,
}

/// Why the model could not be written.
#[derive(Debug, thiserror::Error)]
pub enum OutputError {
    #[error("{path}: cannot write the fitted model: {source}")]
    Tir { path: String, source: std::io::Error },
    #[error("{path}: fit report: {message}")]
    Report { path: String, message: String },
}

/// Writes `result` as `.tir` and report where `out` says; returns the files written.
pub fn write_model(result: &FitResult, out: &ModelOutput) -> Result<Vec<PathBuf>, OutputError> {
    let mut files = Vec::new();
    if let Some(tir) = &out.tir {
        if let Some(dir) = tir.parent().filter(|d| !d.as_os_str().is_empty()) {
            std::fs::create_dir_all(dir)
                .map_err(|source| OutputError::Tir { path: tir.display().to_string(), source })?;
        }
        std::fs::write(tir, result.params.to_tir_string())
            .map_err(|source| OutputError::Tir { path: tir.display().to_string(), source })?;
        files.push(tir.clone());
    }
    if let Some(dir) = &out.report {
        files.extend(write_report(dir, result)?);
    }
    Ok(files)
}

fn write_report(dir: &Path, result: &FitResult) -> Result<Vec<PathBuf>, OutputError> {
    mffit::report::write(dir, result, None)
        .map_err(|e| OutputError::Report { path: dir.display().to_string(), message: e.to_string() })
}

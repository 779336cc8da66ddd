//! doctor: find where an MF-Tyre 6.1 model and rig measurements disagree beyond the noise,
//! name the missing effect, add it as a parametric extension, and show the gap shrink.
//!
//! MF-Tyre 6.1 has no temperature, wear or history. The doctor:
//! 1. **Simulates** the model at every measured operating point ([`data::Dataset`]: slip angle,
//!    slip ratio, load, camber, pressure, speed; points at ~10 Hz inside sweeps) and takes the
//!    residuals of FX, FYW, MZW and DSTWOWHC; the noise floor comes from the data itself
//!    ([`fit::noise_floor`]: point-to-point scatter of the residual along each sweep).
//! 2. **Finds** where the residual exceeds the noise: bins by slip, load, camber, pressure,
//!    time in the test, sliding energy, grip temperature and slip rate ([`diagnose::RegionBin`]).
//! 3. **Names** the effect: each candidate of the catalogue ([`effects::Effect`]) has a physical
//!    variable and a parametric extension; each is fitted on training sweeps and scored on
//!    held-out sweeps (folds of sweeps in a fixed shuffled order) by the share of the held-out χ² it explains after a
//!    k·ln N penalty for its parameters. The best is named only when that evidence exceeds a
//!    threshold and it improves every held-out fold but a quarter (at least one may lose); then the search repeats
//!    greedily with the named effects in the model, until nothing significant remains.
//! 4. **Adds** it: the extension is fitted on all sweeps and written into the `.tir`
//!    ([`extension`]: refitted MF coefficients in their sections, new terms in
//!    `[TYRERIG_EXTENSIONS]`).
//! 5. **Shows** it: RMS before/after per channel and in the effect's region, on the fit and on
//!    held-out sweeps; plots; `report.md` and `doctor.json` ([`report`]).
//!
//! ```no_run
//! use doctor::{DataOptions, Dataset, DoctorConfig, RawLog, diagnose, report};
//! let log = RawLog::read_mcap(std::path::Path::new("log.mcap"))?;
//! let ds = Dataset::from_logs(&[log], &DataOptions::default())?;
//! let base = mftyre::TyreParams::read_tir(std::path::Path::new("base.tir"))?;
//! let dx = diagnose(&ds, &base, &DoctorConfig::default())?;
//! report::write_all(std::path::Path::new("out"), &ds, &base, &dx, "base.tir", 0.0)?;
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

pub mod data;
pub mod diagnose;
pub mod effects;
pub mod extension;
pub mod fit;
pub mod flash;
pub mod form;
pub mod linfit;
pub mod report;
pub mod state;

pub use data::{DataOptions, Dataset, RawLog};
pub use diagnose::{Diagnosis, DoctorConfig, NamedEffect, diagnose};
pub use effects::{Effect, Family};
pub use extension::{ExtState, Extensions};

/// What can go wrong, naming the file, channel or sweep.
#[derive(Debug, thiserror::Error)]
pub enum DoctorError {
    /// A log could not be read.
    #[error("{file}: {detail}")]
    Log {
        /// The log.
        file: String,
        /// What failed.
        detail: String,
    },
    /// Not enough data to diagnose.
    #[error("not enough data: {what}")]
    NoData {
        /// What is missing.
        what: String,
    },
    /// A model file's extension section is malformed.
    #[error("{file}: {detail}")]
    Model {
        /// The model file.
        file: String,
        /// What is wrong.
        detail: String,
    },
    /// Writing the report failed.
    #[error("{path}: {detail}")]
    Write {
        /// The file.
        path: String,
        /// What failed.
        detail: String,
    },
}

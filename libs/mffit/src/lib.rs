//! mffit: fits MF-Tyre 6.1 models to GS2MF test data (thesis chapter 5). Pure library, no DDS.
//!
//! * [`data`]: the fitter's view of test data ([`Dataset`] of tagged [`Segment`]s, ISO-W, SI)
//!   and 10 Hz resampling.
//! * [`logs`]: extraction of segments from MCAP logs (`/rig/sample` split by
//!   `/rig/procedure/state`: procedure, section, sweep name, phase).
//! * [`stages`]: the staged fit in the thesis's order — nominal values → FY pure → MZ pure →
//!   FX pure → FX combined → FY combined → MZ combined → MX → radius/vertical stiffness →
//!   relaxation lengths (MY skipped) — each stage with starting values from the data
//!   ([`starts`]) and bounded Levenberg–Marquardt ([`lsq`]) through [`engine`].
//! * [`checks`]: failure-mode detection (non-physical C/D/E, square friction ellipse,
//!   extrapolation instability).
//! * [`metrics`], [`report`]: per-stage/per-channel RMSE, NRMSE, bias, max error, R² grouped by
//!   load, pressure and camber; Markdown, `fit.json` and PNG/SVG plots.
//! * [`accuracy`]: fitted-versus-reference model comparison on a held-out grid.
//! * [`calibration`]: how well the band of the mean holds a known true tyre.
//! * [`synth`]: synthetic GS2MF-like data from a known tyre (tests, demos).
//!
//! ```no_run
//! let data = mffit::logs::read_logs(&["freerolling.mcap".as_ref(), "brkdrv.mcap".as_ref()]).unwrap();
//! let result = mffit::stages::fit(&data, &mffit::stages::FitOptions::default()).unwrap();
//! std::fs::write("fitted.tir", result.params.to_tir_string()).unwrap();
//! ```

pub mod accuracy;
pub mod calibration;
pub mod checks;
pub mod data;
pub mod engine;
mod error;
pub mod fit;
pub mod form_error;
pub mod identify;
pub mod logs;
pub mod metrics;
pub mod physics;
pub mod plots;
pub mod prediction;
pub mod report;
pub mod stages;
pub mod starts;
pub mod synth;

pub use data::{Cell, DataKind, Dataset, Origin, Procedure, Sample, Segment, SweepKind, ValidRange};
pub use error::FitError;
pub use stages::{FitOptions, FitResult, WarmStart, fit};

//! livefit: the live MF-Tyre 6.1 fit node — a model that grows with the test and says how sure
//! it is (`docs/live-fit.md`).
//!
//! The pure core ([`LiveFit`]) takes the suite's rig samples and procedure states, cuts them into
//! the same segments the offline fit reads from a log ([`mffit::logs::Segmenter`]), and after
//! every completed data segment (a sweep, an on-centre hold, a rolling-radius hold, a step steer
//! or static test) refits the staged MF-Tyre 6.1 model on all data so far, warm-started from the
//! previous update's coefficients ([`mffit::WarmStart`]), decimated as the offline fit is. Each
//! update gives a [`tyre_msgs::ModelState`]: per stage its status (waiting for data / fitting /
//! identified), RMSE and coefficients with standard deviations, and the predicted uncertainty of
//! FY, FX and MZ over a fixed operating-envelope grid ([`mffit::prediction`]). When the procedure
//! completes, the final update's [`mffit::FitResult`] is what the shell writes as `.tir` and
//! fit report.
//!
//! Topics (the DDS shell, `shell.rs`, feature `dds`, maps them to core calls):
//! - in: `sample` (`tyre_msgs/RigSample`) → [`LiveFit::on_sample`]; `procedure/state`
//!   (`tyre_msgs/ProcedureState`) → [`LiveFit::on_procedure_state`];
//! - out: `model/state` (`tyre_msgs/ModelState`, transient-local, keep last 1) and, with it,
//!   `model/covariance` (`tyre_msgs/ModelCovariance` from [`LiveFit::model_covariance`]: the
//!   whole model and each stage's covariance, which the adaptive plan's sequencer plans with).
//!
//! The core reads no clock and does no I/O: its time is the stamps of the messages, and an
//! update's wall time is the fitter's own measurement.

pub mod config;
pub mod core;
pub mod output;
pub mod replay;
#[cfg(feature = "dds")]
pub mod shell;
pub mod state;

pub use config::LiveFitConfig;
pub use core::{LiveFit, Trigger, UpdateDone, UpdateJob};
pub use state::stage_status;

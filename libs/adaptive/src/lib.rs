//! adaptive: an adaptive test plan. Instead of running every cell of a procedure, choose the
//! next sweep where the live model is unsure, by predicted variance reduction per rig second,
//! and stop when the model is predicted to be as good as the full procedure would make it.
//!
//! Pure: no clock, no I/O. The sequencer owns a [`Planner`] and asks it for the next sweep
//! whenever it reaches a slot of the plan; the caller passes the live fit's latest model.
//!
//! - [`library`]: the candidate sweeps, cut out of the expanded procedure (the sweeps GS2MF
//!   would run), with their predicted cost in rig seconds, and the fixed plan with a slot where
//!   each run of candidates was.
//! - [`design`]: the linearised I-optimal criterion: the reduction of the model's prediction
//!   variance over the envelope grid if a candidate's points were added.
//! - [`model`]: the model's sensitivities and covariance per target channel, from an
//!   `mffit::FitResult` ([`model::FitView`]) or any other [`model::ModelView`].
//! - [`planner`]: the choice (value per second, pressure changes grouped, severe sweeps last)
//!   and the stop rule; its state goes into the sequencer's checkpoint.
//!
//! `docs/adaptive-plan.md` describes the method and its measured figures.

pub mod config;
pub mod design;
pub mod library;
pub mod model;
pub mod planner;

pub use config::AdaptiveConfig;
pub use library::{Candidate, Library, Slot};
pub use model::{FitView, ModelView, Target, TargetModel};
pub use planner::{Decision, Planner, PlannerState};

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
//!   live model snapshot ([`model::ModelSnapshot`], from an `mffit::FitResult` or `model/covariance`) through [`model::FitView`] or any other [`model::ModelView`].
//! - [`wire`]: the model snapshot as `tyre_msgs/ModelCovariance` (`model/covariance`) and back,
//!   for a sequencer node that plans over DDS.
//! - [`extent`]: how far a sweep reaches into the envelope (load, slip, camber): a slot does not
//!   close while one of its sweeps would take the data where they have not been.
//! - [`planner`]: the choice (value per second, pressure changes grouped, severe sweeps last)
//!   and the stop rule; its state goes into the sequencer's checkpoint.
//!
//! `docs/adaptive-plan.md` describes the method and its measured figures.

pub mod config;
pub mod design;
pub mod extent;
pub mod library;
pub mod model;
pub mod planner;
pub mod wire;

pub use config::AdaptiveConfig;
pub use library::{Candidate, Library, Slot};
pub use model::{FitView, ModelSnapshot, ModelView, StageSnapshot, Target, TargetModel};
pub use planner::{Decision, MeasuredWearRate, Planner, PlannerState};

/// Serde for an `f64` that may be NaN ("not known"): JSON has no NaN and writes it as `null`,
/// so `null` reads back as NaN (checkpoints and run summaries round-trip).
pub mod nan_as_null {
    use serde::{Deserialize, Deserializer, Serializer};

    /// Writes NaN as `null`, anything else as the number.
    pub fn serialize<S: Serializer>(v: &f64, s: S) -> Result<S::Ok, S::Error> {
        if v.is_finite() { s.serialize_f64(*v) } else { s.serialize_none() }
    }

    /// Reads `null` as NaN.
    pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<f64, D::Error> {
        Ok(Option::<f64>::deserialize(d)?.unwrap_or(f64::NAN))
    }
}

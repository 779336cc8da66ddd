//! mftyre: the MF-Tyre 6.1 model (ISO-W, SI) and `.tir` property-file I/O. Pure library.
//!
//! * [`TyreParams`]: a typed MF-Tyre 6.1 parameter set, grouped by [`CoefGroup`] and addressable
//!   by `.tir` key (`params.get("PKY1")`, `params.set("PKY1", v)`), read and written by
//!   [`TyreParams::read_tir`], [`TyreParams::from_tir_str`] and [`TyreParams::to_tir_string`].
//! * [`evaluate`] / [`evaluate_scaled`]: forces, moments, radii, stiffnesses and relaxation
//!   lengths at one operating point, matching MFeval 4.3.1 (TNO-compatible choices) to better
//!   than 1e-10 relative (≤ 2e-11 N, 1e-12 N·m absolute) on its reference tables;
//!   [`evaluate_batch`] for struct-of-arrays batches (load-case terms shared along sweeps);
//!   [`pure_fy`] / [`pure_fx`] for the cheapest pure-slip calls.
//!
//! Turn slip is not modelled: the model is evaluated with φt = 0 whatever the input says
//! (the output flags [`Clamped::PHIT_IGNORED`]), and turn-slip use modes are rejected.

mod batch;
mod kernel;
mod lanes;
mod model;
mod params;
mod tir;

pub use batch::{BatchInput, BatchLengthError, BatchOutput, evaluate_batch, evaluate_batch_scaled, pure_fy_batch};
pub use model::{Clamped, MfInput, MfOutput, UseMode, UseModeError, evaluate, evaluate_scaled, pure_fx, pure_fy};
pub use params::{
    Aligning, CoefGroup, Combined, ContactPatch, Dimension, Inertia, Limits, ModelParams, OperatingConditions,
    OtherEntry, Overturning, Pressure, PureFx, PureFy, Rolling, ScalingFactors, Structural, TurnSlip, TyreParams,
    Vertical,
};
pub use tir::{ExtraSection, TirError, TirValue};

//! mftyre: the MF-Tyre 6.1 model (ISO-W, SI) and `.tir` property-file I/O. Pure library.
//!
//! * [`TyreParams`]: a typed MF-Tyre 6.1 parameter set, grouped by [`CoefGroup`] and addressable
//!   by `.tir` key (`params.get("PKY1")`, `params.set("PKY1", v)`), read and written by
//!   [`TyreParams::read_tir`], [`TyreParams::from_tir_str`] and [`TyreParams::to_tir_string`].
//! * [`evaluate`] / [`evaluate_scaled`]: forces, moments, radii, stiffnesses and relaxation
//!   lengths at one operating point, matching MFeval 4.3.1 (TNO-compatible choices) to better
//!   than 1e-10 relative (≤ 2e-11 N, 1e-12 N·m absolute) on its reference tables;
//!   [`evaluate_batch`] for struct-of-arrays batches: a lane-wise kernel that evaluates four
//!   points at once with its own vectorised atan/sin/cos/exp/ln (≤ 2 ulp), agreeing with
//!   [`evaluate`] to ≤ 1e-13 relative, with an AVX2+FMA build chosen at run time (5.1–5.3 M
//!   full combined-slip evaluations per second per core on random points, 9.6–10 M along sweeps,
//!   50 M pure Fy; `cargo run --release -p mftyre --example throughput`, README "Speed");
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

pub use batch::{
    BatchColumn, BatchInput, BatchLengthError, BatchOutput, evaluate_batch, evaluate_batch_scaled, evaluate_column,
    pure_fy_batch,
};
pub use model::{Clamped, MfInput, MfOutput, UseMode, UseModeError, evaluate, evaluate_scaled, pure_fx, pure_fy};
pub use params::{
    Aligning, CoefGroup, Combined, ContactPatch, Dimension, Inertia, Limits, ModelParams, OperatingConditions,
    OtherEntry, Overturning, Pressure, PureFx, PureFy, Rolling, ScalingFactors, Structural, TurnSlip, TyreParams,
    Vertical,
};
pub use tir::{ExtraSection, TirError, TirValue};

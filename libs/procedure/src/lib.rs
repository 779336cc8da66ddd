//! procedure: GS2MF / Square Matrix procedure files, sweep primitives and their expansion into
//! a plan of setpoint trajectories.
//!
//! Pure: no clock, no DDS. The only I/O is [`file::load`], which reads a procedure file and its
//! includes; [`file::parse_with`] does the same from memory.
//!
//! - [`load_index`]: the ETRTO load-index table and Fz0 = 0.65 × capacity × 9.81.
//! - [`sweep`]: rate laws (constant, variable, continually variable), slip paths, load and camber
//!   couplings, keyframe trajectories.
//! - [`primitives`]: the GS2MF building blocks (vertical-load sweep, on-centre holds,
//!   rolling-radius steps, step-steer, static drag, pressure change, warm-up, graph sweeps,
//!   settles, tyre changes, thermal-pause setpoint) and sweep naming.
//! - [`file`]: the TOML procedure format, validated with file/line/key errors.
//! - [`expand`]: procedure + [`RunInputs`] → [`Plan`].
//! - [`plan`]: the plan and its time estimates.

pub mod expand;
pub mod file;
pub mod load_index;
pub mod plan;
pub mod primitives;
pub mod setpoint;
pub mod sweep;

pub use expand::{RunInputs, SweepStyle, expand};
pub use file::{ProcedureDoc, ProcedureError, load, parse_with};
pub use load_index::fz0_n;
pub use plan::{PauseModel, Plan, PlanStep, PlanSummary, StepKind};
pub use setpoint::{RigLimits, RigMode, Setpoint};
pub use sweep::{RateLaw, SlipAxis, SlipPath, Trajectory};

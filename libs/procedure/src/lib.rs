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
//! - [`file`](mod@file): the TOML procedure format, validated with file/line/key errors.
//! - [`expand`](mod@expand): procedure + [`RunInputs`] → [`Plan`].
//! - [`plan`]: the plan and its time estimates.
//!
//! ```
//! use procedure::{RunInputs, StepKind, expand, parse_with, ProcedureError};
//!
//! let src = r#"
//! [procedure]
//! name = "demo"
//! title = "Demo"
//! config_tag = "FreeRoll"
//!
//! [[section]]
//! name = "force_moment"
//! pressures = ["low", "high"]
//!
//! [[section.step]]
//! kind = "sweep"
//! peak_deg = 16.0
//! low_rate_dps = 2.0
//! high_rate_dps = 30.0
//! threshold_deg = 4.0
//! asym = "medium"
//! "#;
//! let mut no_includes = |p: &str| -> Result<String, ProcedureError> { unreachable!("{p}") };
//! let doc = parse_with("demo.toml", src, &mut no_includes)?;
//! let plan = expand(&doc, &RunInputs::default())?; // LI 110, 2.1/2.6/3.3 bar, 16.6 m/s
//! let sweeps: Vec<_> = plan.steps.iter().filter(|s| s.kind == StepKind::Sweep).collect();
//! assert_eq!(sweeps[0].name, "FreeRoll_sw1_VariableRate_LR2_HR30_TH4_AsymMedium_1");
//! assert!((sweeps[0].duration_s - 9.6).abs() < 1e-9);
//! assert!(sweeps.iter().all(|s| s.thermal_pause_after));
//! # Ok::<(), ProcedureError>(())
//! ```

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

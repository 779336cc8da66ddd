//! channels: the calculated-channels node of tyrerig — its pure core, configuration and the
//! derived measurements (thesis §3.6.2, §3.10–§3.12; `gs2mf-reference.md` §3, §9).
//!
//! Topics (the DDS shell maps them to [`ChannelsCore`] calls):
//! - in: `rig/sample` (`tyre_msgs/RigSample`) → [`ChannelsCore::on_sample`];
//!   `procedure/state` (`tyre_msgs/ProcedureState`) → [`ChannelsCore::on_procedure_state`];
//! - out: `rig/channels/live` (`tyre_msgs/LiveChannels`, one per sample),
//!   `rig/channels/sweep_summary` (`tyre_msgs/SweepSummary`, transient-local: at each sweep's
//!   end and again with its cool-down), and the [`DerivedMeasurement`]s of each finished section
//!   (no message type yet: the shell logs them; the report and the monitor read them).
//!
//! # Live channels
//! - Slip ratio, Calspan form SR = (VX1/W1)·(W/VX) − 1: VX1 and W1 are the means over the
//!   sequencer's `PHASE_FREE_ROLLING_REF` hold and are held for the sweep that follows (NaN
//!   otherwise); effective-radius form SR = (W·Re − VX)/VX with Re = VX/W learnt from free-rolling
//!   samples per pressure case as a line in Fz (NaN until ~1 s of such data exists).
//! - PX = FX·SR·VX·cos(SA), PY = FY·VX·sin(SA), P = √(PX² + PY²); SR is the Calspan one when held,
//!   else the rig's LONGSLIP.
//! - AcSldEny (trapezoidal ∫P dt) and LONGDISP (∫VX dt) per segment; zeroed runtime per segment. A
//!   segment is a data step (sweep, hold, warm-up sweep) or a stretch between them (`""`).
//!   `total_sliding_energy_j` runs over the specimen's life (reset at a tyre change).
//!
//! # Sweep summaries
//! Duration, start and peak TRDTEMPC, sliding energy, mechanical hysteresis (FYW at SA = 0
//! crossings, or FX at SR = 0 crossings for a longitudinal sweep: max − min), slip ranges, means,
//! peaks; published when the sweep ends and again with `cool_down_s` when the pause after it ends.
//!
//! # Derived measurements ([`derived`])
//! At each section's end: cornering stiffness, RSAT, RCF per load and pressure (on-centre holds);
//! loaded radius per step, vertical stiffness per pressure and speed, unloaded radius per pressure
//! (slowest speed) and averaged (rolling-radius steps); lateral relaxation length per step-steer
//! and per ± pair; longitudinal stiffness per load and pressure averaged over repeats (static
//! drags).

pub mod config;
pub mod core;
pub mod derived;
pub mod state_queue;

pub use config::{ChannelsConfig, ConfigError};
pub use core::{ChannelsCore, ChannelsOutput};
pub use derived::{DerivedMeasurement, Quantity};
pub use state_queue::StateQueue;

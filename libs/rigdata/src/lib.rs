//! rigdata: measured files as real rigs write them, read into the fitter's [`mffit::Dataset`].
//!
//! Real tyre-rig data does not come as GS2MF logs. It comes as Calspan TIRF / FSAE TTC run files
//! (ASCII `.dat` and MATLAB Level 5 `.mat`), and as TYDEX `.tdx` files from other rigs (one
//! measurement per file, a folder per test), in SAE or ISO axes and in whatever units the rig
//! wrote. This crate reads them as they are (see `docs/real-data.md`):
//!
//! * [`table`]: [`ChannelTable`], a file's raw content — named channels with their units as
//!   written, plus the run's title, tyre and test ids — the common shape of every format before
//!   any interpretation. Writers for the TTC text layout live here too, for fixtures and exports.
//!
//! Pure library: no DDS, no clock.

pub mod table;
pub mod virtual_export;

pub use table::{ChannelTable, Column};

//! rigdata: measured files as real rigs write them, read into the fitter's [`mffit::Dataset`].
//!
//! Real tyre-rig data does not come as GS2MF logs. It comes as Calspan TIRF / FSAE TTC run files
//! (ASCII `.dat` and MATLAB Level 5 `.mat`), and as TYDEX `.tdx` files from other rigs (one
//! measurement per file, a folder per test), in SAE or ISO axes and in whatever units the rig
//! wrote. This crate reads them as they are (see `docs/real-data.md`) in three steps:
//!
//! 1. **Read** a file into a [`ChannelTable`] — named channels with their units as written, plus
//!    title, tyre and test ids — whatever the format: [`dat`] (TTC ASCII), [`mat`] (MATLAB Level
//!    5 read and write, Level 4 read), [`tydex`] (TYDEX, plus tyrerig's own exact TYDEX export).
//!    Oddities (CRLF, trailing tabs, blank lines, `NaN`, a truncated last line, extra or missing
//!    values, corrupt `.mat` elements) are warnings or errors naming file, line and channel
//!    ([`error`]); no input makes a reader panic or allocate beyond what the file can hold.
//! 2. **Interpret** the channels ([`interpret`]): roles from TTC or TYDEX names ([`channels`]),
//!    units from the units line or, where there is none, the TTC units checked against the
//!    magnitudes ([`units`]), the sign convention from the data (SAE: FZ negative under load),
//!    conversion to ISO-W and SI; `SL` is the slip ratio, `SR` only without `SL` and never where
//!    the wheel rolls free.
//! 3. **Find the sweeps** ([`sweeps`]): standstill, unloaded rows, load and pressure ramps,
//!    camber and speed changes excluded and counted; sweeps cut on the slip channel that moves,
//!    each with its [`mffit::Cell`] and kind; conditioning sweeps labelled `WarmUp`.
//!
//! [`import::read_path`] does all three for a file or a folder and returns the dataset with an
//! [`inspect::Inspection`] of what was found. [`table::to_dat`] and [`mat::to_mat`] write
//! tables back out (fixtures, conversions); [`fixture`] makes synthetic TTC-like runs for tests.
//!
//! Pure library: no DDS, no clock.

pub mod camber;
pub mod channels;
pub mod conditioning;
pub mod dat;
pub mod error;
pub mod fixture;
pub mod import;
pub mod inspect;
pub mod interpret;
pub mod mat;
pub mod sweeps;
pub mod table;
pub mod tydex;
pub mod units;
pub mod virtual_export;

pub use error::{Place, ReadError, Warning};
pub use import::{Import, ReadOptions, read_path};
pub use interpret::Convention;
pub use table::{ChannelTable, Column};

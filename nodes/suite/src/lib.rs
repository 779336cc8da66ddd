//! suite: the whole rig suite wired together.
//!
//! - [`headless`]: the pure cores (virtual rig, thermal gate, sequencer) driven by plain function
//!   calls on simulated time, as fast as the machine goes — for tests, for generating logs, and
//!   as the reference the DDS run must agree with.
//! - [`summary`]: the run summary (rig time per procedure, thermal pauses, tyres, alarms) and
//!   the thesis's §11 table beside it.
//! - [`sink`]: where a run's messages go (an MCAP log, a counter, a test's vectors).

pub mod headless;
pub mod sink;
pub mod spec;
pub mod summary;

pub use headless::{Headless, HeadlessError, SENSOR_FAULT_HOLD_LIMIT_S};
pub use sink::{McapSink, MessageSink, NullSink, Outgoing};
pub use spec::{ProcedureChoice, RunSpec};
pub use summary::{Alarm, ProcedureTimes, RunSummary, summary_from_log};

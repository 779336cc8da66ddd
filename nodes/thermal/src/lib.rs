//! thermal: the thermal-gate node of tyrerig — its pure core and configuration.
//!
//! GS2MF (§3.5 of the thesis; `gs2mf-reference.md` §5) starts every sweep at the same tread
//! temperature: after each sweep the rig holds zero slip until the tread has cooled to the
//! baseline (45 °C), then the next sweep starts by itself. A time-out (120 s) stops a
//! never-ending wait; the sweep after a time-out starts hot and is marked so.
//!
//! Topics (the DDS shell, written separately, maps them to [`ThermalGate`] calls):
//! - in: `rig/sample` (`tyre_msgs/RigSample`: TRDTEMPI/C/O, stamp, fault flags) →
//!   [`ThermalGate::on_sample`]; `procedure/state` (`tyre_msgs/ProcedureState`) →
//!   [`ThermalGate::on_procedure_state`];
//! - out: `thermal/state` (`tyre_msgs/ThermalState`) from [`ThermalGate::step`], called after every
//!   sample and on a timer; its alarms go to `/diagnostics`.
//!
//! # The gate
//! A pause runs while the sequencer reports `PHASE_THERMAL_PAUSE` (or between
//! [`ThermalGate::begin_pause`] and [`ThermalGate::end_pause`]). Statuses:
//! - `STATUS_WAITING`: cooling; gate closed; `predicted_wait_s` says for how long still.
//! - `STATUS_RELEASED`: the filtered temperature is at or below `baseline_c` and the sensor is
//!   healthy; gate open. The release latches for the rest of the pause (the temperature does not
//!   chatter the gate) but a fault clears it.
//! - `STATUS_TIMED_OUT`: the pause reached `timeout_s` with a healthy sensor above the baseline;
//!   gate open, a `thermal_timeout` WARN alarm, and [`ThermalOutput::next_sweep_started_hot`]
//!   stays set until the next pause begins.
//! - `STATUS_FAULT`: the temperature is not trustworthy; gate closed, always — the time-out does
//!   not open it (an ERROR `thermal_timeout` alarm says so instead).
//! - `STATUS_IDLE`: no pause.
//!
//! # Temperature
//! The gate temperature is a weighted mean of TRDTEMPI/C/O (`weights`; the default, centre only,
//! reproduces the thesis's rig). Channels with zero weight are ignored entirely.
//!
//! # Flash-spike filter
//! The laser reads the outermost surface, where flash temperatures above 140 °C that vanish in
//! moments are normal. The weighted temperature passes a running median over `window_s` (0.5 s;
//! never fewer than `min_samples` samples, which must be present before the median can release).
//! A median rejects any excursion shorter than half its window completely, up or down, where a
//! low-pass filter would smear a spike into a bias lasting seconds; it delays real changes by
//! about a quarter second, nothing against cooling time constants of tens of seconds.
//!
//! # Cooling model
//! Newton cooling `T(t) = Ta + (T0 − Ta)·exp(−t/τ)` is fitted online to the filtered
//! temperature of the present pause. Integrating `dT/dt = −(T − Ta)/τ` gives
//! `T(t) − T(0) = −k·∫₀ᵗT dt + c·t` with `k = 1/τ` and `c = Ta/τ`: linear in `(k, c)`, and the
//! integral averages the noise instead of differentiating it. The 2×2 normal equations are
//! accumulated per sample (O(1) time and memory), weighted per second of data, with Gaussian
//! priors on τ and on `Ta` taken from the previous pause's fit (the first pause uses the
//! configured `initial_tau_s` and `ambient_c`). Early in a pause the data fix mainly the slope,
//! and the priors fix the rest; as curvature shows, the data take over. The gate publishes
//! `cooling_time_constant_s = τ` and `predicted_wait_s = τ·ln((T − Ta)/(baseline − Ta))`,
//! capped by the time left to the time-out.
//!
//! # Fail-safe rules
//! A temperature that is NaN/∞, outside `[absurd_min_c, absurd_max_c]` (−40…250 °C), flagged
//! invalid by the rig (`FAULT_TEMPERATURE`), stuck (identical readings for `stuck.after_s` while a
//! sweep runs or the cooling model expects a change), or stale (no sample for `stale_after_s`, also
//! when none arrived since the pause began) puts the gate in `STATUS_FAULT` with an ERROR alarm
//! (`thermal_sensor`, `thermal_stuck`, `thermal_stale`). It never releases a sweep, not even by
//! time-out. The fault clears only after `recovery_s` of healthy samples (a WARN alarm says so);
//! a release latched before the fault must be earned again. Samples that arrive out of order are
//! dropped with a WARN.
//!
//! Limitation: a channel that freezes below the baseline at the very start of a pause releases the
//! gate before the stuck check can notice; a freeze during the preceding sweep is caught, because
//! a sweep always changes the tread temperature.
//!
//! # Warm-up
//! [`ThermalGate::warm_up_reached`] latches once the filtered temperature reaches the warm-up
//! target's lower end (40 °C); [`ThermalGate::warm_up_status`] classifies the present temperature
//! against the 40–45 °C range.

pub mod config;
pub mod core;
#[cfg(feature = "dds")]
pub mod shell;

pub use crate::config::{
    ConfigError, CoolingConfig, SpikeFilterConfig, StuckConfig, TempWeights, ThermalConfig, WarmUpConfig,
};
pub use crate::core::{
    AlarmLevel, Channel, CoolingEstimate, SensorFault, ThermalAlarm, ThermalCheck, ThermalGate, ThermalOutput,
    WarmUpStatus, warm_up_status,
};

//! The pure thermal gate: samples and procedure states in, a `ThermalState` and alarms out.
//!
//! No I/O and no clock reads: every call carries the rig time `now_s`, so the same gate runs at
//! full speed in tests and replays and inside the DDS node.

use std::collections::VecDeque;
use std::fmt;

use tyre_msgs::builtin_interfaces::Time;
use tyre_msgs::std_msgs::Header;
use tyre_msgs::{ProcedureState, RigSample, ThermalState};

use crate::config::{ConfigError, CoolingConfig, ThermalConfig, WarmUpConfig};

/// One of the three tread surface temperature channels.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Channel {
    /// TRDTEMPI, inner tread surface.
    Inner,
    /// TRDTEMPC, centre tread surface.
    Centre,
    /// TRDTEMPO, outer tread surface.
    Outer,
}

impl Channel {
    const ALL: [Channel; 3] = [Channel::Inner, Channel::Centre, Channel::Outer];

    /// The TYDEX channel name.
    pub fn tydex_name(self) -> &'static str {
        match self {
            Channel::Inner => "TRDTEMPI",
            Channel::Centre => "TRDTEMPC",
            Channel::Outer => "TRDTEMPO",
        }
    }

    fn index(self) -> usize {
        match self {
            Channel::Inner => 0,
            Channel::Centre => 1,
            Channel::Outer => 2,
        }
    }
}

impl fmt::Display for Channel {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.tydex_name())
    }
}

/// Why the gate does not trust the temperature (shown in `ThermalState.fault`).
#[derive(Debug, Clone, PartialEq)]
pub enum SensorFault {
    /// The rig flagged the temperature channels invalid (`RigSample::FAULT_TEMPERATURE`).
    Flagged,
    /// A weighted channel read NaN or ±∞.
    NonFinite {
        /// The channel.
        channel: Channel,
    },
    /// A weighted channel read outside `[absurd_min_c, absurd_max_c]`.
    Absurd {
        /// The channel.
        channel: Channel,
        /// The reading (°C).
        value_c: f64,
    },
    /// A weighted channel repeated the same reading while the tyre should be changing.
    Stuck {
        /// The channel.
        channel: Channel,
        /// How long the reading has not changed (s).
        unchanged_s: f64,
    },
    /// No sample arrived for longer than `stale_after_s`.
    Stale {
        /// Time since the last sample (or since the pause began, if none came) (s).
        silent_s: f64,
    },
}

impl SensorFault {
    /// The alarm check this fault reports under.
    pub fn check(&self) -> ThermalCheck {
        match self {
            SensorFault::Flagged | SensorFault::NonFinite { .. } | SensorFault::Absurd { .. } => ThermalCheck::Sensor,
            SensorFault::Stuck { .. } => ThermalCheck::Stuck,
            SensorFault::Stale { .. } => ThermalCheck::Stale,
        }
    }

    /// Same kind of fault on the same channel (used so that a persisting fault alarms once,
    /// although its measured duration changes every step).
    fn same_kind(&self, other: &SensorFault) -> bool {
        match (self, other) {
            (SensorFault::Flagged, SensorFault::Flagged) | (SensorFault::Stale { .. }, SensorFault::Stale { .. }) => {
                true
            }
            (SensorFault::NonFinite { channel: a }, SensorFault::NonFinite { channel: b })
            | (SensorFault::Absurd { channel: a, .. }, SensorFault::Absurd { channel: b, .. })
            | (SensorFault::Stuck { channel: a, .. }, SensorFault::Stuck { channel: b, .. }) => a == b,
            _ => false,
        }
    }
}

impl fmt::Display for SensorFault {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            SensorFault::Flagged => write!(f, "rig flags the tread temperature channels invalid"),
            SensorFault::NonFinite { channel } => write!(f, "{channel} is not a number"),
            SensorFault::Absurd { channel, value_c } => {
                write!(f, "{channel} reads an absurd {value_c:.1} degC")
            }
            SensorFault::Stuck { channel, unchanged_s } => write!(
                f,
                "{channel} stuck: identical readings for {unchanged_s:.1} s while the tyre \
                 temperature should change"
            ),
            SensorFault::Stale { silent_s } => {
                write!(f, "temperature stream stale: no sample for {silent_s:.1} s")
            }
        }
    }
}

/// Severity of a [`ThermalAlarm`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum AlarmLevel {
    /// Something the operator should know; the procedure continues.
    Warn,
    /// The gate holds until the condition clears.
    Error,
}

/// Which check raised a [`ThermalAlarm`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum ThermalCheck {
    /// The pause reached the time-out (`"thermal_timeout"`).
    Timeout,
    /// NaN, absurd, flagged or out-of-order temperature samples (`"thermal_sensor"`).
    Sensor,
    /// A stuck channel (`"thermal_stuck"`).
    Stuck,
    /// A stale stream (`"thermal_stale"`).
    Stale,
}

impl ThermalCheck {
    /// The check's name as it appears in diagnostics.
    pub fn as_str(self) -> &'static str {
        match self {
            ThermalCheck::Timeout => "thermal_timeout",
            ThermalCheck::Sensor => "thermal_sensor",
            ThermalCheck::Stuck => "thermal_stuck",
            ThermalCheck::Stale => "thermal_stale",
        }
    }
}

impl fmt::Display for ThermalCheck {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.as_str())
    }
}

/// An alarm raised by the gate. Raised once per event (fault onset, fault cleared, time-out),
/// not repeated on every step.
#[derive(Debug, Clone, PartialEq)]
pub struct ThermalAlarm {
    /// Severity.
    pub level: AlarmLevel,
    /// The check that raised it.
    pub check: ThermalCheck,
    /// Human-readable explanation.
    pub message: String,
    /// Rig time of the event (s).
    pub rig_time_s: f64,
}

/// What one [`ThermalGate::step`] produces.
#[derive(Debug, Clone, PartialEq)]
pub struct ThermalOutput {
    /// The gate's view, ready to publish on `thermal/state`.
    pub state: ThermalState,
    /// Alarms raised since the previous step.
    pub alarms: Vec<ThermalAlarm>,
    /// The sweep after the present (or last) pause starts hot: the pause timed out. Stays set
    /// until the next pause begins, so the sequencer can read it when it starts the sweep.
    pub next_sweep_started_hot: bool,
}

/// Where the filtered temperature stands against the warm-up target.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum WarmUpStatus {
    /// No trustworthy temperature yet.
    Unknown,
    /// Below `warm_up.target_min_c`: keep warming up.
    Below,
    /// Within the target range.
    InRange,
    /// Above `warm_up.target_max_c`: warm enough; a thermal pause will cool it to baseline.
    Above,
}

/// Classifies a temperature against the warm-up target range.
pub fn warm_up_status(temp_c: f64, config: &WarmUpConfig) -> WarmUpStatus {
    if !temp_c.is_finite() {
        WarmUpStatus::Unknown
    } else if temp_c < config.target_min_c {
        WarmUpStatus::Below
    } else if temp_c <= config.target_max_c {
        WarmUpStatus::InRange
    } else {
        WarmUpStatus::Above
    }
}

/// The cooling model's present estimate.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CoolingEstimate {
    /// Time constant τ (s).
    pub tau_s: f64,
    /// Effective ambient temperature the tread cools towards (°C).
    pub ambient_eff_c: f64,
    /// Seconds of pause data behind the estimate (0: the priors alone) (s).
    pub data_s: f64,
}

impl CoolingEstimate {
    /// Time for the tread to cool from `temp_c` to `target_c` (s): 0 if already there,
    /// `f64::INFINITY` if the effective ambient is at or above the target.
    pub fn time_to_reach_s(&self, temp_c: f64, target_c: f64) -> f64 {
        if temp_c <= target_c {
            0.0
        } else if self.ambient_eff_c >= target_c {
            f64::INFINITY
        } else {
            self.tau_s * ((temp_c - self.ambient_eff_c) / (target_c - self.ambient_eff_c)).ln()
        }
    }

    /// Expected rate of temperature change at `temp_c` (°C/s) (negative while cooling).
    pub fn rate_c_per_s(&self, temp_c: f64) -> f64 {
        -(temp_c - self.ambient_eff_c) / self.tau_s
    }
}

/// Running median over a sliding time window that never holds fewer than `min_samples`.
#[derive(Debug, Clone)]
struct MedianFilter {
    window_s: f64,
    min_samples: usize,
    samples: VecDeque<(f64, f64)>,
    scratch: Vec<f64>,
}

impl MedianFilter {
    fn new(window_s: f64, min_samples: usize) -> Self {
        Self { window_s, min_samples, samples: VecDeque::new(), scratch: Vec::new() }
    }

    fn push(&mut self, t_s: f64, value: f64) {
        self.samples.push_back((t_s, value));
        // Keep the time window, but never fewer than `min_samples`, so a slow stream still
        // gets a median over several samples rather than the raw value.
        while self.samples.len() > self.min_samples
            && self.samples.front().is_some_and(|&(t, _)| t_s - t > self.window_s)
        {
            self.samples.pop_front();
        }
    }

    fn clear(&mut self) {
        self.samples.clear();
    }

    fn ready(&self) -> bool {
        self.samples.len() >= self.min_samples
    }

    /// The window spans its full length, so the median's lag behind the signal is steady (about
    /// half the window). While the window fills, the lag grows, which would bend a cooling curve.
    fn settled(&self) -> bool {
        match (self.samples.front(), self.samples.back()) {
            (Some(&(first, _)), Some(&(last, _))) => self.ready() && last - first >= 0.98 * self.window_s,
            _ => false,
        }
    }

    fn median(&mut self) -> f64 {
        let n = self.samples.len();
        if n == 0 {
            return f64::NAN;
        }
        self.scratch.clear();
        self.scratch.extend(self.samples.iter().map(|&(_, v)| v));
        let mid = n / 2;
        let (lower, upper, _) = self.scratch.select_nth_unstable_by(mid, f64::total_cmp);
        let upper = *upper;
        if n % 2 == 1 {
            upper
        } else {
            let lower_max = lower.iter().copied().fold(f64::NEG_INFINITY, f64::max);
            0.5 * (lower_max + upper)
        }
    }
}

/// Online fit of Newton cooling on the integral form of `dT/dt = −k·(T − Ta)`:
/// `T(t) − T(0) = −k·∫T dt + c·t` with `k = 1/τ`, `c = Ta/τ`, linear in `(k, c)`.
///
/// The normal equations are accumulated (2×2, O(1) per sample, no sample storage) together with
/// Gaussian priors: `k ~ N(1/τ_p, (r·/τ_p)²)` and `(c − k·Ta_p) ~ N(0, (σ_a/τ_p)²)`, the latter
/// being "Ta ≈ Ta_p" written linearly.
#[derive(Debug, Clone)]
struct CoolingFit {
    t0_s: f64,
    temp0_c: f64,
    last_t_s: f64,
    last_temp_c: f64,
    integral_cs: f64,
    a11: f64,
    a12: f64,
    a22: f64,
    b1: f64,
    b2: f64,
    data_s: f64,
    started: bool,
    prior_tau_s: f64,
    prior_ambient_c: f64,
}

impl CoolingFit {
    fn new(prior_tau_s: f64, prior_ambient_c: f64) -> Self {
        Self {
            t0_s: 0.0,
            temp0_c: 0.0,
            last_t_s: 0.0,
            last_temp_c: 0.0,
            integral_cs: 0.0,
            a11: 0.0,
            a12: 0.0,
            a22: 0.0,
            b1: 0.0,
            b2: 0.0,
            data_s: 0.0,
            started: false,
            prior_tau_s,
            prior_ambient_c,
        }
    }

    fn add(&mut self, t_s: f64, temp_c: f64, config: &CoolingConfig) {
        if !self.started {
            self.started = true;
            self.t0_s = t_s;
            self.temp0_c = temp_c;
            self.last_t_s = t_s;
            self.last_temp_c = temp_c;
            return;
        }
        let dt = t_s - self.last_t_s;
        if dt <= 0.0 {
            return;
        }
        self.integral_cs += 0.5 * (temp_c + self.last_temp_c) * dt;
        self.last_t_s = t_s;
        self.last_temp_c = temp_c;
        self.data_s = t_s - self.t0_s;
        // Weight by dt so the information grows with seconds of data, not with the sample rate
        // (the median filter makes neighbouring samples strongly correlated anyway).
        let w = dt / (config.sensor_noise_c * config.sensor_noise_c);
        let x1 = -self.integral_cs;
        let x2 = self.data_s;
        let y = temp_c - self.temp0_c;
        self.a11 += w * x1 * x1;
        self.a12 += w * x1 * x2;
        self.a22 += w * x2 * x2;
        self.b1 += w * x1 * y;
        self.b2 += w * x2 * y;
    }

    fn prior(&self) -> CoolingEstimate {
        CoolingEstimate { tau_s: self.prior_tau_s, ambient_eff_c: self.prior_ambient_c, data_s: 0.0 }
    }

    fn estimate(&self, config: &CoolingConfig) -> CoolingEstimate {
        let k_p = 1.0 / self.prior_tau_s;
        let ta_p = self.prior_ambient_c;
        let info_k = 1.0 / (config.tau_prior_rel_sigma * k_p).powi(2);
        let info_a = 1.0 / (config.ambient_prior_sigma_c * k_p).powi(2);
        // Prior rows: e1 with weight info_k and target k_p; g = (−Ta_p, 1) with target 0.
        let a11 = self.a11 + info_k + info_a * ta_p * ta_p;
        let a12 = self.a12 - info_a * ta_p;
        let a22 = self.a22 + info_a;
        let b1 = self.b1 + info_k * k_p;
        let b2 = self.b2;
        let det = a11 * a22 - a12 * a12;
        if !(det.is_finite() && det > 0.0) {
            return self.prior();
        }
        let k = (a22 * b1 - a12 * b2) / det;
        let c = (a11 * b2 - a12 * b1) / det;
        if !(k.is_finite() && c.is_finite() && k > 0.0) {
            // Not cooling at all (or numerically meaningless): trust the priors.
            return self.prior();
        }
        let tau_s = (1.0 / k).clamp(config.tau_min_s, config.tau_max_s);
        CoolingEstimate { tau_s, ambient_eff_c: c / k, data_s: self.data_s }
    }
}

#[derive(Debug, Clone)]
struct Pause {
    start_s: f64,
    released: bool,
    timed_out: bool,
    timeout_alarmed: bool,
    timeout_fault_alarmed: bool,
    fit: CoolingFit,
}

#[derive(Debug, Clone, Copy)]
struct ChannelTrack {
    last_c: Option<f64>,
    unchanged_since_s: f64,
}

/// The thermal gate of GS2MF §3.5, with the fail-safe checks described in the crate docs.
#[derive(Debug, Clone)]
pub struct ThermalGate {
    config: ThermalConfig,
    weights: [f64; 3],
    filter: MedianFilter,
    tracks: [ChannelTrack; 3],
    last_sample_s: Option<f64>,
    raw_c: [f64; 3],
    weighted_c: f64,
    filtered_c: f64,
    pause: Option<Pause>,
    sweeping: bool,
    prior_tau_s: f64,
    prior_ambient_c: f64,
    fault: Option<SensorFault>,
    last_unhealthy_s: Option<f64>,
    reported_fault: Option<SensorFault>,
    pending: Vec<ThermalAlarm>,
    started_hot: bool,
    warm_up_reached: bool,
    /// `RigSample.seq` of the last sample judged.
    last_seq: Option<u64>,
    /// Gaps in `RigSample.seq` the median did not span.
    seq_gaps: u64,
}

impl ThermalGate {
    /// A gate with a validated configuration, idle, with no samples yet.
    pub fn new(config: ThermalConfig) -> Result<Self, ConfigError> {
        config.validate()?;
        let w = config.weights;
        Ok(Self {
            weights: [w.inner, w.centre, w.outer],
            filter: MedianFilter::new(config.spike_filter.window_s, config.spike_filter.min_samples as usize),
            tracks: [ChannelTrack { last_c: None, unchanged_since_s: 0.0 }; 3],
            last_sample_s: None,
            raw_c: [f64::NAN; 3],
            weighted_c: f64::NAN,
            filtered_c: f64::NAN,
            pause: None,
            sweeping: false,
            prior_tau_s: config.cooling.initial_tau_s,
            prior_ambient_c: config.cooling.ambient_c,
            fault: None,
            last_unhealthy_s: None,
            reported_fault: None,
            pending: Vec::new(),
            started_hot: false,
            warm_up_reached: false,
            last_seq: None,
            seq_gaps: 0,
            config,
        })
    }

    /// Gaps in `RigSample.seq` seen so far; the median filter restarts after each.
    pub fn seq_gaps(&self) -> u64 {
        self.seq_gaps
    }

    /// The configuration in use.
    pub fn config(&self) -> &ThermalConfig {
        &self.config
    }

    /// Feeds one rig sample. `now_s` is the sample's rig time (the shell passes
    /// `header.stamp`); samples older than the previous one are dropped with a warning.
    pub fn on_sample(&mut self, now_s: f64, sample: &RigSample) {
        if !now_s.is_finite() || self.last_sample_s.is_some_and(|last| now_s < last) {
            self.pending.push(ThermalAlarm {
                level: AlarmLevel::Warn,
                check: ThermalCheck::Sensor,
                message: format!(
                    "sample seq {} dropped: rig time {now_s} s is not after the previous sample",
                    sample.seq
                ),
                rig_time_s: self.last_sample_s.unwrap_or(0.0),
            });
            return;
        }
        self.last_sample_s = Some(now_s);
        // Samples lost on the way (a jump in RigSample.seq; a repeated number means a source
        // without a counter): the median must not span the gap.
        if let Some(last) = self.last_seq
            && sample.seq != last
            && sample.seq != last.wrapping_add(1)
        {
            self.seq_gaps += 1;
            self.filter.clear();
        }
        self.last_seq = Some(sample.seq);
        self.raw_c = [sample.trdtempi_c, sample.trdtempc_c, sample.trdtempo_c];

        if let Some(fault) = self.judge_sample(sample) {
            self.mark_unhealthy(now_s, fault);
            self.weighted_c = f64::NAN;
            return;
        }

        let mut sum = 0.0;
        let mut weight_sum = 0.0;
        for channel in Channel::ALL {
            let i = channel.index();
            if self.weights[i] == 0.0 {
                continue;
            }
            let value = self.raw_c[i];
            let track = &mut self.tracks[i];
            if track.last_c.is_none_or(|last| (value - last).abs() > self.config.stuck.tolerance_c) {
                track.unchanged_since_s = now_s;
            }
            track.last_c = Some(value);
            sum += self.weights[i] * value;
            weight_sum += self.weights[i];
        }
        self.weighted_c = sum / weight_sum;
        self.filter.push(now_s, self.weighted_c);
        self.filtered_c = self.filter.median();

        if !self.filter.ready() || self.fault_active(now_s) {
            return;
        }
        if self.filtered_c >= self.config.warm_up.target_min_c {
            self.warm_up_reached = true;
        }
        if let Some(pause) = &mut self.pause
            && self.filter.settled()
        {
            pause.fit.add(now_s, self.filtered_c, &self.config.cooling);
        }
    }

    /// Follows the sequencer: a pause runs while `phase == PHASE_THERMAL_PAUSE`; sweeps are
    /// when the tread temperature must be changing (used by the stuck check).
    pub fn on_procedure_state(&mut self, now_s: f64, state: &ProcedureState) {
        self.sweeping = state.phase == ProcedureState::PHASE_SWEEP;
        if state.phase == ProcedureState::PHASE_THERMAL_PAUSE {
            self.begin_pause(now_s);
        } else {
            self.end_pause(now_s);
        }
    }

    /// Starts a thermal pause (no-op if one is running): the time-out clock starts, the cooling
    /// model starts a fresh fit seeded with the previous pause's estimate, the started-hot mark
    /// of the previous pause is cleared.
    pub fn begin_pause(&mut self, now_s: f64) {
        if self.pause.is_some() {
            return;
        }
        self.started_hot = false;
        self.pause = Some(Pause {
            start_s: now_s,
            released: false,
            timed_out: false,
            timeout_alarmed: false,
            timeout_fault_alarmed: false,
            fit: CoolingFit::new(self.prior_tau_s, self.prior_ambient_c),
        });
    }

    /// Ends the thermal pause (no-op if none runs). A fit with enough data becomes the prior of
    /// the next pause.
    pub fn end_pause(&mut self, _now_s: f64) {
        let Some(pause) = self.pause.take() else {
            return;
        };
        let estimate = pause.fit.estimate(&self.config.cooling);
        if estimate.data_s >= self.config.cooling.min_fit_data_s
            && estimate.data_s > 0.0
            && estimate.ambient_eff_c > self.config.absurd_min_c
            && estimate.ambient_eff_c < self.config.absurd_max_c
        {
            self.prior_tau_s = estimate.tau_s;
            self.prior_ambient_c = estimate.ambient_eff_c;
        }
    }

    /// True while a thermal pause runs.
    pub fn in_pause(&self) -> bool {
        self.pause.is_some()
    }

    /// The cooling model: the present pause's fit, or the prior for the next pause.
    pub fn cooling_model(&self) -> CoolingEstimate {
        match &self.pause {
            Some(pause) => pause.fit.estimate(&self.config.cooling),
            None => CoolingEstimate { tau_s: self.prior_tau_s, ambient_eff_c: self.prior_ambient_c, data_s: 0.0 },
        }
    }

    /// Predicted length of a pause that starts at `start_temp_c`, from the present cooling
    /// model (the fit of a running pause, else the prior for the next one), capped at the
    /// time-out. For the sequencer's ETA of the pauses still to come (s).
    pub fn predict_pause_s(&self, start_temp_c: f64) -> f64 {
        if !start_temp_c.is_finite() {
            return self.config.timeout_s;
        }
        self.cooling_model().time_to_reach_s(start_temp_c, self.config.baseline_c).min(self.config.timeout_s)
    }

    /// The filtered temperature against the warm-up target right now.
    pub fn warm_up_status(&self) -> WarmUpStatus {
        if self.fault.is_some() || !self.filter.ready() {
            return WarmUpStatus::Unknown;
        }
        warm_up_status(self.filtered_c, &self.config.warm_up)
    }

    /// True once a trustworthy filtered temperature reached `warm_up.target_min_c` (latched
    /// until [`ThermalGate::reset_warm_up`]).
    pub fn warm_up_reached(&self) -> bool {
        self.warm_up_reached
    }

    /// Forgets the warm-up completion (e.g. after a tyre change).
    pub fn reset_warm_up(&mut self) {
        self.warm_up_reached = false;
    }

    /// Judges the gate at `now_s`: stale and stuck checks, release, time-out, prediction.
    /// Call after every sample and on a timer (so that a silent stream is noticed).
    pub fn step(&mut self, now_s: f64) -> ThermalOutput {
        self.check_stale(now_s);
        self.check_stuck(now_s);
        let fault_active = self.fault_active(now_s);
        self.report_fault_changes(now_s, fault_active);

        let baseline_c = self.config.baseline_c;
        let timeout_s = self.config.timeout_s;
        let filter_ready = self.filter.ready();
        let filtered_c = self.filtered_c;
        let mut status = if fault_active { ThermalState::STATUS_FAULT } else { ThermalState::STATUS_IDLE };
        let mut pause_elapsed_s = 0.0;
        let mut predicted_wait_s = 0.0;
        let estimate = self.cooling_model();

        if let Some(pause) = &mut self.pause {
            pause_elapsed_s = (now_s - pause.start_s).max(0.0);
            if fault_active {
                // Fail-safe: an untrusted temperature never releases, not even by time-out.
                pause.released = false;
                if pause_elapsed_s >= timeout_s && !pause.timeout_fault_alarmed {
                    pause.timeout_fault_alarmed = true;
                    self.pending.push(ThermalAlarm {
                        level: AlarmLevel::Error,
                        check: ThermalCheck::Timeout,
                        message: format!(
                            "thermal pause reached its {timeout_s:.0} s time-out with a faulty \
                             temperature sensor: holding zero slip"
                        ),
                        rig_time_s: now_s,
                    });
                }
            } else {
                if !pause.timed_out && filter_ready && filtered_c <= baseline_c {
                    pause.released = true;
                }
                if !pause.released && pause_elapsed_s >= timeout_s {
                    pause.timed_out = true;
                    self.started_hot = true;
                    if !pause.timeout_alarmed {
                        pause.timeout_alarmed = true;
                        self.pending.push(ThermalAlarm {
                            level: AlarmLevel::Warn,
                            check: ThermalCheck::Timeout,
                            message: format!(
                                "thermal pause timed out after {timeout_s:.0} s at \
                                 {filtered_c:.1} degC (baseline {baseline_c:.1} degC): the next \
                                 sweep starts hot"
                            ),
                            rig_time_s: now_s,
                        });
                    }
                }
                status = if pause.timed_out {
                    ThermalState::STATUS_TIMED_OUT
                } else if pause.released {
                    ThermalState::STATUS_RELEASED
                } else {
                    ThermalState::STATUS_WAITING
                };
            }
            if status == ThermalState::STATUS_WAITING || status == ThermalState::STATUS_FAULT {
                let to_timeout_s = (timeout_s - pause_elapsed_s).max(0.0);
                let model_s = if filter_ready && filtered_c.is_finite() {
                    estimate.time_to_reach_s(filtered_c, baseline_c)
                } else {
                    f64::INFINITY
                };
                // While waiting, the time-out bounds the pause; in a fault it does not, but an
                // ETA needs a finite number, and the model's is the best there is.
                predicted_wait_s = if status == ThermalState::STATUS_WAITING {
                    model_s.min(to_timeout_s)
                } else if model_s.is_finite() {
                    model_s
                } else {
                    to_timeout_s
                };
            }
        }

        let gate_open = status == ThermalState::STATUS_RELEASED || status == ThermalState::STATUS_TIMED_OUT;
        let fault =
            if fault_active { self.fault.as_ref().map(ToString::to_string).unwrap_or_default() } else { String::new() };
        let state = ThermalState {
            header: Header { stamp: Time::from_secs_f64(now_s), frame_id: String::new() },
            status,
            gate_open,
            trdtempi_c: self.raw_c[0],
            trdtempc_c: self.raw_c[1],
            trdtempo_c: self.raw_c[2],
            weighted_temp_c: self.weighted_c,
            filtered_temp_c: self.filtered_c,
            baseline_c,
            pause_elapsed_s,
            predicted_wait_s,
            cooling_time_constant_s: estimate.tau_s,
            fault,
        };
        ThermalOutput { state, alarms: std::mem::take(&mut self.pending), next_sweep_started_hot: self.started_hot }
    }

    fn judge_sample(&self, sample: &RigSample) -> Option<SensorFault> {
        if sample.fault_flags & RigSample::FAULT_TEMPERATURE != 0 {
            return Some(SensorFault::Flagged);
        }
        for channel in Channel::ALL {
            let i = channel.index();
            if self.weights[i] == 0.0 {
                continue;
            }
            let value_c = self.raw_c[i];
            if !value_c.is_finite() {
                return Some(SensorFault::NonFinite { channel });
            }
            if value_c < self.config.absurd_min_c || value_c > self.config.absurd_max_c {
                return Some(SensorFault::Absurd { channel, value_c });
            }
        }
        None
    }

    fn mark_unhealthy(&mut self, now_s: f64, fault: SensorFault) {
        self.last_unhealthy_s = Some(now_s);
        self.fault = Some(fault);
    }

    fn fault_active(&self, now_s: f64) -> bool {
        self.last_unhealthy_s.is_some_and(|t| now_s <= t || now_s - t < self.config.recovery_s)
    }

    fn check_stale(&mut self, now_s: f64) {
        let reference_s = self.last_sample_s.or_else(|| self.pause.as_ref().map(|p| p.start_s));
        if let Some(reference_s) = reference_s {
            let silent_s = now_s - reference_s;
            if silent_s >= self.config.stale_after_s {
                // Samples from before the gap must not form a median with those after it.
                self.filter.clear();
                self.mark_unhealthy(now_s, SensorFault::Stale { silent_s });
            }
        }
    }

    fn check_stuck(&mut self, now_s: f64) {
        let expect_change = if self.sweeping {
            true
        } else if self.pause.is_some() && self.filtered_c.is_finite() {
            let estimate = self.cooling_model();
            estimate.rate_c_per_s(self.filtered_c).abs() * self.config.stuck.after_s
                >= self.config.stuck.min_expected_change_c
        } else {
            false
        };
        if !expect_change {
            return;
        }
        for channel in Channel::ALL {
            let track = self.tracks[channel.index()];
            if self.weights[channel.index()] == 0.0 || track.last_c.is_none() {
                continue;
            }
            let unchanged_s = now_s - track.unchanged_since_s;
            if unchanged_s >= self.config.stuck.after_s {
                self.mark_unhealthy(now_s, SensorFault::Stuck { channel, unchanged_s });
            }
        }
    }

    fn report_fault_changes(&mut self, now_s: f64, fault_active: bool) {
        if fault_active {
            let Some(fault) = &self.fault else { return };
            if self.reported_fault.as_ref().is_none_or(|reported| !reported.same_kind(fault)) {
                self.pending.push(ThermalAlarm {
                    level: AlarmLevel::Error,
                    check: fault.check(),
                    message: format!("{fault}: holding the thermal gate closed"),
                    rig_time_s: now_s,
                });
                self.reported_fault = Some(fault.clone());
            }
        } else if let Some(reported) = self.reported_fault.take() {
            self.pending.push(ThermalAlarm {
                level: AlarmLevel::Warn,
                check: reported.check(),
                message: format!(
                    "temperature trusted again after {:.1} s healthy (was: {reported})",
                    self.config.recovery_s
                ),
                rig_time_s: now_s,
            });
            self.fault = None;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn fit_exponential(prior: (f64, f64), tau_s: f64, ambient_c: f64, dur_s: f64) -> CoolingEstimate {
        let config = CoolingConfig::default();
        let mut fit = CoolingFit::new(prior.0, prior.1);
        for i in 0..=(dur_s / 0.01).round() as usize {
            let t = i as f64 * 0.01;
            fit.add(t, ambient_c + (70.0 - ambient_c) * (-t / tau_s).exp(), &config);
        }
        fit.estimate(&config)
    }

    #[test]
    fn exact_priors_are_kept_by_exact_data() {
        let e = fit_exponential((30.0, 25.0), 30.0, 25.0, 10.0);
        assert!((e.tau_s - 30.0).abs() < 0.05, "{e:?}");
        assert!((e.ambient_eff_c - 25.0).abs() < 0.05, "{e:?}");
    }

    #[test]
    fn data_override_wrong_priors() {
        let e = fit_exponential((40.0, 25.0), 20.0, 25.0, 15.0);
        assert!((e.tau_s - 20.0).abs() < 0.6, "{e:?}");
        let e = fit_exponential((40.0, 25.0), 60.0, 35.0, 60.0);
        assert!((e.tau_s - 60.0).abs() < 3.0, "{e:?}");
        assert!((e.ambient_eff_c - 35.0).abs() < 1.0, "{e:?}");
    }

    #[test]
    fn no_data_gives_the_priors() {
        let e = fit_exponential((33.0, 21.0), 30.0, 25.0, 0.0);
        assert!((e.tau_s - 33.0).abs() < 1e-9 && (e.ambient_eff_c - 21.0).abs() < 1e-9);
        assert_eq!(e.data_s, 0.0);
    }

    #[test]
    fn median_rejects_short_excursions() {
        let mut f = MedianFilter::new(0.5, 3);
        for i in 0..100 {
            let t = f64::from(i) * 0.01;
            f.push(t, if (50..55).contains(&i) { 150.0 } else { 47.0 });
            assert_eq!(f.median(), 47.0);
        }
        // A slow stream keeps `min_samples` however old they are.
        let mut f = MedianFilter::new(0.5, 3);
        for i in 0..5 {
            f.push(f64::from(i) * 10.0, f64::from(i));
        }
        assert!(f.ready());
        assert_eq!(f.median(), 3.0);
    }
}

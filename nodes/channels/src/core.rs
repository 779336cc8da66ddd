//! The channels node's pure core: live channels for every sample, a summary per sweep, derived
//! measurements per section. No I/O, no clock: time comes from the message stamps.
//!
//! # Ordering of states and samples
//! The sequencer stamps a `ProcedureState` with the rig time of the sample that caused it, so a
//! state stamped `t` governs the samples *after* `t`. The core therefore holds a state until a
//! sample stamped later than it arrives (a state more than [`FUTURE_STATE_S`] ahead of the
//! samples is applied at once: a clock mismatch must not freeze the phase). Live (sample, then
//! state) and replayed (log-time order, ties in either order) inputs thus give the same outputs.

use std::collections::BTreeMap;

use tyre_msgs::std_msgs::Header;
use tyre_msgs::{LiveChannels, ProcedureState, RigSample, RigSetpoint, SweepSummary};

use crate::config::{ChannelsConfig, ConfigError};
use crate::derived::{self, DerivedMeasurement, OnCentreClump, Quantity, ZeroCrossings};

pub use crate::state_queue::FUTURE_STATE_S;
use crate::state_queue::StateQueue;
/// Consecutive samples further apart than this are not integrated across (a gap in the data) [s].
/// A gap in `RigSample.seq` (samples lost on the way) is never integrated across either.
const MAX_INTEGRATION_GAP_S: f64 = 1.0;
/// Below this speed the wheel is at a standstill (step-steer, static drag) [m/s].
const STANDSTILL_MPS: f64 = 0.05;
/// Effective-radius model: samples of a pressure case before the model is trusted.
const RE_MODEL_MIN_SAMPLES: f64 = 100.0;
/// Effective-radius model: load spread (std dev) needed to fit the slope [N].
const RE_MODEL_MIN_LOAD_SPREAD_N: f64 = 500.0;

/// What one sample produced.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct ChannelsOutput {
    /// Live channels of this sample (`rig/channels/live`).
    pub live: LiveChannels,
    /// Sweep summaries completed with this sample (`rig/channels/sweep_summary`): a sweep's first
    /// publication when it ends, and its update (`cool_down_complete`) when its pause ends.
    pub sweep_summaries: Vec<SweepSummary>,
    /// Derived measurements of a section that completed with this sample.
    pub derived: Vec<DerivedMeasurement>,
}

/// Which data-step type a sweep name says it is (the procedure's type names).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum HoldKind {
    OnCentre,
    RollingRadius,
    StepSteer,
    StaticDrag,
    Other,
}

impl HoldKind {
    fn of(sweep_name: &str) -> Self {
        if sweep_name.contains("OnCentre") {
            Self::OnCentre
        } else if sweep_name.contains("RollingRadius") {
            Self::RollingRadius
        } else if sweep_name.contains("StepSteer") {
            Self::StepSteer
        } else if sweep_name.contains("StaticDrag") {
            Self::StaticDrag
        } else {
            Self::Other
        }
    }
}

/// Running sums of a load plateau.
#[derive(Debug, Clone, Copy, Default)]
struct PlateauAcc {
    ref_fz_n: f64,
    n_all: f64,
    ref_sa_deg: f64,
    t_start_s: f64,
    t_last_s: f64,
    n: f64,
    fz: f64,
    sa: f64,
    fy: f64,
    mz: f64,
    radius: f64,
    pressure: f64,
    speed: f64,
}

/// A finished plateau (means).
#[derive(Debug, Clone, Copy, PartialEq)]
struct Plateau {
    fz_n: f64,
    sa_deg: f64,
    fy_n: f64,
    mz_nm: f64,
    radius_m: f64,
    pressure_pa: f64,
    speed_mps: f64,
    n: usize,
}

/// Finds load plateaus in a hold step.
#[derive(Debug, Clone, Default)]
struct PlateauFinder {
    acc: Option<PlateauAcc>,
    done: Vec<Plateau>,
}

impl PlateauFinder {
    fn push(&mut self, cfg: &ChannelsConfig, t: f64, s: &RigSample) {
        let vals = [s.fzw_n, s.slipangl_deg, s.fyw_n, s.mzw_nm, s.dstwowhc_m, s.inflpres_pa, s.trajvelw_mps];
        if !vals.iter().all(|v| v.is_finite()) {
            return;
        }
        let tol = (cfg.plateau_load_tol_frac * s.fzw_n.abs()).max(cfg.plateau_load_tol_n);
        let same = self.acc.as_ref().is_some_and(|a| {
            (s.fzw_n - a.ref_fz_n).abs() < tol && (s.slipangl_deg - a.ref_sa_deg).abs() < 0.2 && t - a.t_last_s < 1.0
        });
        if !same {
            self.close(cfg);
            self.acc = Some(PlateauAcc {
                ref_fz_n: s.fzw_n,
                ref_sa_deg: s.slipangl_deg,
                t_start_s: t,
                t_last_s: t,
                ..PlateauAcc::default()
            });
        }
        let Some(a) = self.acc.as_mut() else { return };
        a.t_last_s = t;
        // The reference follows the plateau's running mean so noise on its first sample does
        // not split it.
        a.n_all += 1.0;
        a.ref_fz_n += (s.fzw_n - a.ref_fz_n) / a.n_all;
        if t - a.t_start_s >= cfg.plateau_settle_s {
            a.n += 1.0;
            a.fz += s.fzw_n;
            a.sa += s.slipangl_deg;
            a.fy += s.fyw_n;
            a.mz += s.mzw_nm;
            a.radius += s.dstwowhc_m;
            a.pressure += s.inflpres_pa;
            a.speed += s.trajvelw_mps;
        }
    }

    fn close(&mut self, cfg: &ChannelsConfig) {
        if let Some(a) = self.acc.take()
            && a.t_last_s - a.t_start_s >= cfg.plateau_settle_s + cfg.plateau_min_s
            && a.n > 0.0
        {
            self.done.push(Plateau {
                fz_n: a.fz / a.n,
                sa_deg: a.sa / a.n,
                fy_n: a.fy / a.n,
                mz_nm: a.mz / a.n,
                radius_m: a.radius / a.n,
                pressure_pa: a.pressure / a.n,
                speed_mps: a.speed / a.n,
                n: a.n as usize,
            });
        }
    }
}

/// One step-steer or static-drag test's samples.
#[derive(Debug, Clone, Default)]
struct TestTrace {
    /// (distance in the step [m], FYW or FX, SA, VX, FZ, pressure, rig mode)
    pts: Vec<[f64; 6]>,
    modes: Vec<u8>,
}

/// Data of the section in progress, for the derived measurements at its end.
#[derive(Debug, Clone, Default)]
struct SectionData {
    name: String,
    on_centre: Vec<Plateau>,
    rolling_radius: Vec<Plateau>,
    step_steers: Vec<TestTrace>,
    static_drags: Vec<TestTrace>,
}

/// A sweep in progress.
#[derive(Debug, Clone)]
struct SweepAcc {
    state: ProcedureState,
    start_time_s: f64,
    last_time_s: f64,
    start_temp_c: f64,
    peak_temp_c: f64,
    sa_min: f64,
    sa_max: f64,
    sr_min: f64,
    sr_max: f64,
    n: f64,
    fz: f64,
    pressure: f64,
    camber: f64,
    radius: f64,
    n_radius: f64,
    peak_fx: f64,
    peak_fy: f64,
    lat: ZeroCrossings,
    long: ZeroCrossings,
    kind: HoldKind,
    plateaus: PlateauFinder,
    trace: TestTrace,
}

/// Free-rolling reference (VX1, W1) sums.
#[derive(Debug, Clone, Copy, Default)]
struct RefAcc {
    n: f64,
    vx: f64,
    w: f64,
}

impl RefAcc {
    fn value(&self) -> Option<(f64, f64)> {
        (self.n > 0.0 && self.w.abs() > 1e-9).then(|| (self.vx / self.n, self.w / self.n))
    }
}

/// Sums for Re = a + b·Fz of one pressure case.
#[derive(Debug, Clone, Copy, Default)]
struct ReAcc {
    n: f64,
    x: f64,
    y: f64,
    xx: f64,
    xy: f64,
}

impl ReAcc {
    fn push(&mut self, fz: f64, re: f64) {
        self.n += 1.0;
        self.x += fz;
        self.y += re;
        self.xx += fz * fz;
        self.xy += fz * re;
    }

    fn eval(&self, fz: f64) -> Option<f64> {
        if self.n < RE_MODEL_MIN_SAMPLES {
            return None;
        }
        let mx = self.x / self.n;
        let my = self.y / self.n;
        let var = self.xx / self.n - mx * mx;
        if var > RE_MODEL_MIN_LOAD_SPREAD_N.powi(2) {
            let b = (self.xy / self.n - mx * my) / var;
            Some(my + b * (fz - mx))
        } else {
            Some(my)
        }
    }
}

/// The last sample of the segment, for the trapezoids.
#[derive(Debug, Clone, Copy)]
struct Prev {
    t: f64,
    seq: u64,
    p_w: f64,
    vx: f64,
}

/// `next` follows `prev` without a sample missing between them. A repeated number counts as
/// continuous (sources without a counter send 0 throughout); a jump either way (samples lost,
/// or a restarted rig counting from 0 again) is a gap.
pub fn seq_continuous(prev: u64, next: u64) -> bool {
    next == prev || next == prev.wrapping_add(1)
}

/// The channels core. Feed [`ChannelsCore::on_procedure_state`] and
/// [`ChannelsCore::on_sample`] in arrival order.
#[derive(Debug, Clone)]
pub struct ChannelsCore {
    cfg: ChannelsConfig,
    pending_states: StateQueue,
    state: ProcedureState,
    last_sample_t: f64,

    segment: String,
    segment_key: (u8, u32, String),
    seg_t0: f64,
    longdisp_m: f64,
    acsldeny_j: f64,
    total_energy_j: f64,
    prev: Option<Prev>,

    ref_acc: RefAcc,
    held_ref: Option<(f64, f64)>,
    re_model: BTreeMap<i64, ReAcc>,

    sweep: Option<SweepAcc>,
    /// A summary waiting for its cool-down: (summary, pause start time).
    awaiting_cool_down: Option<(SweepSummary, Option<f64>)>,
    section: SectionData,
    section_key: Option<(String, u32)>,
    out_summaries: Vec<SweepSummary>,
    out_derived: Vec<DerivedMeasurement>,
    /// Gaps in `RigSample.seq` not integrated across.
    seq_gaps: u64,
}

impl ChannelsCore {
    /// A core with a validated configuration.
    pub fn new(cfg: ChannelsConfig) -> Result<Self, ConfigError> {
        cfg.validate()?;
        Ok(Self {
            cfg,
            pending_states: StateQueue::default(),
            state: ProcedureState::default(),
            last_sample_t: f64::NEG_INFINITY,
            segment: String::new(),
            segment_key: (ProcedureState::PHASE_IDLE, 0, String::new()),
            seg_t0: f64::NAN,
            longdisp_m: 0.0,
            acsldeny_j: 0.0,
            total_energy_j: 0.0,
            prev: None,
            ref_acc: RefAcc::default(),
            held_ref: None,
            re_model: BTreeMap::new(),
            sweep: None,
            awaiting_cool_down: None,
            section: SectionData::default(),
            section_key: None,
            out_summaries: Vec::new(),
            out_derived: Vec::new(),
            seq_gaps: 0,
        })
    }

    /// Gaps in `RigSample.seq` seen so far (the integrals — sliding energy, LONGDISP — skip them).
    pub fn seq_gaps(&self) -> u64 {
        self.seq_gaps
    }

    /// The configuration.
    pub fn config(&self) -> &ChannelsConfig {
        &self.cfg
    }

    /// The sequencer's state (`procedure/state`). Takes effect for samples stamped after it.
    pub fn on_procedure_state(&mut self, state: &ProcedureState) {
        if let Some(now) = self.pending_states.offer(state, self.last_sample_t) {
            self.apply_state(now);
        }
    }

    /// Flushes everything in progress as if the procedure had ended (end of a log): the open
    /// sweep's summary, a pending cool-down, the section's derived measurements.
    pub fn finish(&mut self) -> ChannelsOutput {
        for s in self.pending_states.drain() {
            self.apply_state(s);
        }
        self.end_sweep();
        if let Some((mut s, pause_t0)) = self.awaiting_cool_down.take() {
            s.cool_down_s = pause_t0.map_or(0.0, |t0| (self.last_sample_t - t0).max(0.0));
            s.cool_down_complete = true;
            self.out_summaries.push(s);
        }
        self.end_section();
        ChannelsOutput {
            live: LiveChannels::default(),
            sweep_summaries: std::mem::take(&mut self.out_summaries),
            derived: std::mem::take(&mut self.out_derived),
        }
    }

    /// One rig sample (`rig/sample`) → its live channels, and whatever completed with it.
    pub fn on_sample(&mut self, s: &RigSample) -> ChannelsOutput {
        let t = if s.runtime_s.is_finite() { s.runtime_s } else { s.header.stamp.as_secs_f64() };
        // States stamped before this sample govern it (see the module docs).
        for st in self.pending_states.due(t) {
            self.apply_state(st);
        }
        self.last_sample_t = self.last_sample_t.max(t);

        let phase = self.state.phase;
        let vx = s.trajvelw_mps;
        let w = s.wheel_speed_radps;
        let speed_ok = vx.is_finite() && vx.abs() >= self.cfg.min_speed_mps;

        // Free-rolling reference: capture VX1, W1 while the sequencer holds the load case.
        if phase == ProcedureState::PHASE_FREE_ROLLING_REF && speed_ok && w.is_finite() {
            self.ref_acc.vx += vx;
            self.ref_acc.w += w;
            self.ref_acc.n += 1.0;
        }
        // Effective-radius model from free-rolling samples.
        let free_rolling =
            s.rig_mode == RigSetpoint::MODE_FREE_ROLLING || phase == ProcedureState::PHASE_FREE_ROLLING_REF;
        if free_rolling
            && speed_ok
            && s.fault_flags & RigSample::FAULT_FORCE == 0
            && s.slipangl_deg.abs() < self.cfg.re_model_max_slip_angle_deg
            && w.is_finite()
            && w.abs() > 1e-6
            && s.fzw_n.is_finite()
            && s.inflpres_pa.is_finite()
        {
            self.re_model.entry(self.pressure_key(s.inflpres_pa)).or_default().push(s.fzw_n, vx / w);
        }

        let sr_calspan = match (phase, self.held_ref, self.ref_acc.value()) {
            (ProcedureState::PHASE_SWEEP, Some((vx1, w1)), _) if speed_ok => {
                derived::slip_ratio_calspan(vx1, w1, w, vx)
            }
            (ProcedureState::PHASE_FREE_ROLLING_REF, _, Some((vx1, w1))) if speed_ok => {
                derived::slip_ratio_calspan(vx1, w1, w, vx)
            }
            _ => f64::NAN,
        };
        let sr_re = match self.re_at(s.inflpres_pa, s.fzw_n) {
            Some(re) if speed_ok => derived::slip_ratio_effective_radius(w, re, vx),
            _ => f64::NAN,
        };
        // Sliding power uses the best slip ratio there is: Calspan, else the rig's own.
        let sr = if sr_calspan.is_finite() { sr_calspan } else { s.longslip };
        let forces_ok = s.fault_flags & RigSample::FAULT_FORCE == 0;
        let (px, py, p) = if forces_ok && vx.is_finite() {
            derived::sliding_power_w(s.fx_n, s.fyw_n, if sr.is_finite() { sr } else { 0.0 }, s.slipangl_deg, vx)
        } else {
            (f64::NAN, f64::NAN, f64::NAN)
        };

        // Segment: the data step, or "" between them; zeroed per segment.
        let key = (phase, self.state.sweep_index, self.state.sweep_name.clone());
        let in_data = phase == ProcedureState::PHASE_SWEEP;
        let key = if in_data { key } else { (u8::MAX, 0, String::new()) };
        if key != self.segment_key || !self.seg_t0.is_finite() {
            self.segment_key = key;
            self.segment = if in_data { self.state.sweep_name.clone() } else { String::new() };
            self.seg_t0 = t;
            self.longdisp_m = 0.0;
            self.acsldeny_j = 0.0;
            self.prev = None;
        }
        let p_int = if p.is_finite() { p } else { 0.0 };
        let vx_int = if vx.is_finite() { vx } else { 0.0 };
        if let Some(pr) = self.prev {
            let dt = t - pr.t;
            if !seq_continuous(pr.seq, s.seq) {
                self.seq_gaps += 1;
            } else if dt > 0.0 && dt <= MAX_INTEGRATION_GAP_S {
                let de = 0.5 * (pr.p_w + p_int) * dt;
                self.acsldeny_j += de;
                self.total_energy_j += de;
                self.longdisp_m += 0.5 * (pr.vx + vx_int) * dt;
            }
        }
        self.prev = Some(Prev { t, seq: s.seq, p_w: p_int, vx: vx_int });

        if in_data {
            self.sweep_sample(t, s, sr);
        }

        let live = LiveChannels {
            header: Header { stamp: s.header.stamp, frame_id: s.header.frame_id.clone() },
            sample_seq: s.seq,
            segment: self.segment.clone(),
            zeroed_runtime_s: t - self.seg_t0,
            longdisp_m: self.longdisp_m,
            slip_ratio_calspan: sr_calspan,
            slip_ratio_effective_radius: sr_re,
            px_w: px,
            py_w: py,
            p_w: p,
            acsldeny_j: self.acsldeny_j,
            total_sliding_energy_j: self.total_energy_j,
        };
        ChannelsOutput {
            live,
            sweep_summaries: std::mem::take(&mut self.out_summaries),
            derived: std::mem::take(&mut self.out_derived),
        }
    }

    fn pressure_key(&self, p: f64) -> i64 {
        (p / self.cfg.pressure_tol_pa).round() as i64
    }

    /// Re from the model of the nearest pressure case that has one.
    fn re_at(&self, p: f64, fz: f64) -> Option<f64> {
        if !(p.is_finite() && fz.is_finite()) {
            return None;
        }
        let k = self.pressure_key(p);
        self.re_model
            .iter()
            .filter_map(|(kk, acc)| acc.eval(fz).map(|re| ((kk - k).abs(), re)))
            .min_by_key(|(d, _)| *d)
            .map(|(_, re)| re)
    }

    fn apply_state(&mut self, st: ProcedureState) {
        let t = st.header.stamp.as_secs_f64();
        let old = std::mem::replace(&mut self.state, st);
        let new = &self.state;
        let sweep_changed = old.phase == ProcedureState::PHASE_SWEEP
            && (new.phase != ProcedureState::PHASE_SWEEP
                || new.sweep_index != old.sweep_index
                || new.sweep_name != old.sweep_name);
        if sweep_changed {
            self.end_sweep();
            // The free-rolling reference belongs to the sweep that followed it.
            self.held_ref = None;
        }
        let new_phase = self.state.phase;
        // Cool-down bookkeeping of the last finished sweep.
        if let Some((_, pause_t0)) = self.awaiting_cool_down.as_mut() {
            if new_phase == ProcedureState::PHASE_THERMAL_PAUSE {
                if pause_t0.is_none() {
                    *pause_t0 = Some(t);
                }
            } else if new_phase != old.phase || new_phase == ProcedureState::PHASE_SWEEP {
                let (mut s, pause_t0) = self.awaiting_cool_down.take().unwrap_or_default();
                s.cool_down_s = pause_t0.map_or(0.0, |t0| (t - t0).max(0.0));
                s.cool_down_complete = true;
                s.header = Header::iso_w(t);
                self.out_summaries.push(s);
            }
        }
        if new_phase == ProcedureState::PHASE_FREE_ROLLING_REF && old.phase != ProcedureState::PHASE_FREE_ROLLING_REF {
            self.ref_acc = RefAcc::default();
        }
        if new_phase == ProcedureState::PHASE_SWEEP && old.phase == ProcedureState::PHASE_FREE_ROLLING_REF {
            self.held_ref = self.ref_acc.value();
        }
        if new_phase == ProcedureState::PHASE_TYRE_CHANGE && old.phase != ProcedureState::PHASE_TYRE_CHANGE {
            // A new specimen: its life's sliding energy starts at zero.
            self.total_energy_j = 0.0;
            self.re_model.clear();
        }
        // Section bookkeeping.
        let sec_key = (self.state.procedure.clone(), self.state.section_index);
        let active = !matches!(new_phase, ProcedureState::PHASE_IDLE);
        if new_phase == ProcedureState::PHASE_COMPLETE
            || new_phase == ProcedureState::PHASE_ABORTED
            || (active && self.section_key.as_ref().is_some_and(|k| *k != sec_key))
        {
            self.end_sweep();
            self.end_section();
        }
        if active && !matches!(new_phase, ProcedureState::PHASE_COMPLETE | ProcedureState::PHASE_ABORTED) {
            if self.section_key.is_none() {
                self.section.name = self.state.section.clone();
            }
            self.section_key = Some(sec_key);
        }
        if new_phase == ProcedureState::PHASE_SWEEP && self.sweep.is_none() {
            let st = self.state.clone();
            self.sweep = Some(SweepAcc {
                kind: HoldKind::of(&st.sweep_name),
                state: st,
                start_time_s: f64::NAN,
                last_time_s: f64::NAN,
                start_temp_c: f64::NAN,
                peak_temp_c: f64::NAN,
                sa_min: f64::NAN,
                sa_max: f64::NAN,
                sr_min: f64::NAN,
                sr_max: f64::NAN,
                n: 0.0,
                fz: 0.0,
                pressure: 0.0,
                camber: 0.0,
                radius: 0.0,
                n_radius: 0.0,
                peak_fx: 0.0,
                peak_fy: 0.0,
                lat: ZeroCrossings::new(self.cfg.hysteresis_arm_slip_angle_deg),
                long: ZeroCrossings::new(self.cfg.hysteresis_arm_slip_ratio),
                plateaus: PlateauFinder::default(),
                trace: TestTrace::default(),
            });
        }
    }

    fn sweep_sample(&mut self, t: f64, s: &RigSample, sr: f64) {
        let cfg = self.cfg.clone();
        let longdisp = self.longdisp_m;
        let Some(a) = self.sweep.as_mut() else { return };
        if !a.start_time_s.is_finite() {
            a.start_time_s = t;
        }
        a.last_time_s = t;
        let fmin = |m: f64, v: f64| if v.is_finite() && (m.is_nan() || v < m) { v } else { m };
        let fmax = |m: f64, v: f64| if v.is_finite() && (m.is_nan() || v > m) { v } else { m };
        let temp_ok = s.fault_flags & RigSample::FAULT_TEMPERATURE == 0 && s.trdtempc_c.is_finite();
        if temp_ok {
            if !a.start_temp_c.is_finite() {
                a.start_temp_c = s.trdtempc_c;
            }
            a.peak_temp_c = fmax(a.peak_temp_c, s.trdtempc_c);
        }
        a.sa_min = fmin(a.sa_min, s.slipangl_deg);
        a.sa_max = fmax(a.sa_max, s.slipangl_deg);
        a.sr_min = fmin(a.sr_min, sr);
        a.sr_max = fmax(a.sr_max, sr);
        if [s.fzw_n, s.inflpres_pa, s.inclangl_deg].iter().all(|v| v.is_finite()) {
            a.n += 1.0;
            a.fz += s.fzw_n;
            a.pressure += s.inflpres_pa;
            a.camber += s.inclangl_deg;
        }
        if s.fault_flags & RigSample::FAULT_RADIUS == 0 && s.dstwowhc_m.is_finite() {
            a.radius += s.dstwowhc_m;
            a.n_radius += 1.0;
        }
        if s.fault_flags & RigSample::FAULT_FORCE == 0 {
            if s.fx_n.is_finite() && s.fx_n.abs() > a.peak_fx.abs() {
                a.peak_fx = s.fx_n;
            }
            if s.fyw_n.is_finite() && s.fyw_n.abs() > a.peak_fy.abs() {
                a.peak_fy = s.fyw_n;
            }
            a.lat.push(s.slipangl_deg, s.fyw_n);
            a.long.push(sr, s.fx_n);
        }
        match a.kind {
            HoldKind::OnCentre | HoldKind::RollingRadius
                if s.fault_flags & (RigSample::FAULT_FORCE | RigSample::FAULT_RADIUS) == 0 =>
            {
                a.plateaus.push(&cfg, t, s)
            }
            HoldKind::StepSteer | HoldKind::StaticDrag if s.fault_flags & RigSample::FAULT_FORCE == 0 => {
                let f = if a.kind == HoldKind::StepSteer { s.fyw_n } else { s.fx_n };
                a.trace.pts.push([longdisp, f, s.slipangl_deg, s.trajvelw_mps, s.fzw_n, s.inflpres_pa]);
                a.trace.modes.push(s.rig_mode);
            }
            _ => {}
        }
    }

    fn end_sweep(&mut self) {
        let Some(mut a) = self.sweep.take() else { return };
        if !a.start_time_s.is_finite() {
            return;
        }
        a.plateaus.close(&self.cfg);
        match a.kind {
            HoldKind::OnCentre => self.section.on_centre.append(&mut a.plateaus.done),
            HoldKind::RollingRadius => self.section.rolling_radius.append(&mut a.plateaus.done),
            HoldKind::StepSteer => self.section.step_steers.push(std::mem::take(&mut a.trace)),
            HoldKind::StaticDrag => self.section.static_drags.push(std::mem::take(&mut a.trace)),
            HoldKind::Other => {}
        }
        let sr_range = if a.sr_min.is_finite() && a.sr_max.is_finite() { a.sr_max - a.sr_min } else { 0.0 };
        let longitudinal = sr_range > self.cfg.longitudinal_sweep_min_slip_ratio;
        let n = a.n.max(1.0);
        let st = &a.state;
        let summary = SweepSummary {
            header: Header::iso_w(a.last_time_s),
            procedure: st.procedure.clone(),
            section: st.section.clone(),
            sweep_name: st.sweep_name.clone(),
            sweep_index: st.sweep_index,
            started_hot: st.sweep_started_hot,
            cool_down_complete: false,
            start_time_s: a.start_time_s,
            duration_s: a.last_time_s - a.start_time_s,
            start_temp_c: a.start_temp_c,
            peak_temp_c: a.peak_temp_c,
            sliding_energy_j: self.acsldeny_j,
            cool_down_s: 0.0,
            mech_hysteresis_n: if longitudinal { a.long.hysteresis_n() } else { a.lat.hysteresis_n() },
            slip_angle_min_deg: a.sa_min,
            slip_angle_max_deg: a.sa_max,
            slip_ratio_min: a.sr_min,
            slip_ratio_max: a.sr_max,
            mean_fz_n: if a.n > 0.0 { a.fz / n } else { f64::NAN },
            mean_pressure_pa: if a.n > 0.0 { a.pressure / n } else { f64::NAN },
            mean_camber_deg: if a.n > 0.0 { a.camber / n } else { f64::NAN },
            peak_fx_n: a.peak_fx,
            peak_fy_n: a.peak_fy,
            mean_dstwowhc_m: if a.n_radius > 0.0 { a.radius / a.n_radius } else { f64::NAN },
        };
        // A previous sweep still waiting (no pause in between) completes with no cool-down.
        if let Some((mut prev, pause_t0)) = self.awaiting_cool_down.take() {
            prev.cool_down_s = pause_t0.map_or(0.0, |t0| (a.start_time_s - t0).max(0.0));
            prev.cool_down_complete = true;
            self.out_summaries.push(prev);
        }
        self.out_summaries.push(summary.clone());
        self.awaiting_cool_down = Some((summary, None));
    }

    fn end_section(&mut self) {
        let data = std::mem::take(&mut self.section);
        // The key names the section's own procedure (the state may already be the next one's).
        let procedure = self.section_key.take().map(|(p, _)| p).unwrap_or_default();
        let t = self.last_sample_t;
        let cfg = &self.cfg;
        let mut out = Vec::new();
        // Groups points by (pressure case, load case): loads within `load_case_tol_frac`.
        let group = |pl: &[Plateau]| -> Vec<Vec<Plateau>> {
            let mut groups: Vec<Vec<Plateau>> = Vec::new();
            for p in pl {
                let g = groups.iter_mut().find(|g| {
                    (g[0].pressure_pa - p.pressure_pa).abs() < cfg.pressure_tol_pa
                        && (g[0].fz_n - p.fz_n).abs() < cfg.load_case_tol_frac * g[0].fz_n.abs().max(1000.0)
                });
                match g {
                    Some(g) => g.push(*p),
                    None => groups.push(vec![*p]),
                }
            }
            groups
        };
        let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len().max(1) as f64;
        // On-centre: one line per load and pressure through the slip-angle clumps.
        for g in group(&data.on_centre) {
            let clumps: Vec<OnCentreClump> =
                g.iter().map(|p| OnCentreClump { slip_angle_deg: p.sa_deg, fy_n: p.fy_n, mz_nm: p.mz_nm }).collect();
            if let Some(r) = derived::on_centre(&clumps) {
                let fz = mean(&g.iter().map(|p| p.fz_n).collect::<Vec<_>>());
                let pr = mean(&g.iter().map(|p| p.pressure_pa).collect::<Vec<_>>());
                let v = mean(&g.iter().map(|p| p.speed_mps).collect::<Vec<_>>());
                for (q, val) in [
                    (Quantity::CorneringStiffness, r.cornering_stiffness_n_per_deg),
                    (Quantity::Rsat, r.rsat_nm),
                    (Quantity::Rcf, r.rcf_n),
                ] {
                    let mut m = DerivedMeasurement::new(q, val, &data.name, t);
                    m.fz_n = fz;
                    m.pressure_pa = pr;
                    m.speed_mps = v;
                    m.n_points = clumps.len();
                    out.push(m);
                }
            }
        }
        // Rolling radius: loaded radius per step; per pressure and speed a line R(Fz).
        if !data.rolling_radius.is_empty() {
            for p in &data.rolling_radius {
                let mut m = DerivedMeasurement::new(Quantity::LoadedRadius, p.radius_m, &data.name, t);
                m.fz_n = p.fz_n;
                m.pressure_pa = p.pressure_pa;
                m.speed_mps = p.speed_mps;
                m.n_points = p.n;
                out.push(m);
            }
            // Pressure cases, then speed cases within each.
            let mut cases: Vec<(f64, f64, Vec<Plateau>)> = Vec::new();
            for p in &data.rolling_radius {
                match cases
                    .iter_mut()
                    .find(|c| (c.0 - p.pressure_pa).abs() < cfg.pressure_tol_pa && (c.1 - p.speed_mps).abs() < 0.5)
                {
                    Some(c) => c.2.push(*p),
                    None => cases.push((p.pressure_pa, p.speed_mps, vec![*p])),
                }
            }
            // Unloaded radius per pressure: from the slowest speed (no centrifugal growth).
            let mut per_pressure: Vec<(f64, f64, f64)> = Vec::new(); // (pressure, speed, R0)
            for (pr, v, pts) in &cases {
                let fz: Vec<f64> = pts.iter().map(|p| p.fz_n).collect();
                let r: Vec<f64> = pts.iter().map(|p| p.radius_m).collect();
                if let Some(fit) = derived::rolling_radius(&fz, &r) {
                    let mut m =
                        DerivedMeasurement::new(Quantity::VerticalStiffness, fit.vertical_stiffness_npm, &data.name, t);
                    m.pressure_pa = mean(&pts.iter().map(|p| p.pressure_pa).collect::<Vec<_>>());
                    m.speed_mps = *v;
                    m.n_points = fit.n;
                    out.push(m);
                    match per_pressure.iter_mut().find(|e| (e.0 - pr).abs() < cfg.pressure_tol_pa) {
                        Some(e) if *v < e.1 => *e = (*pr, *v, fit.unloaded_radius_m),
                        Some(_) => {}
                        None => per_pressure.push((*pr, *v, fit.unloaded_radius_m)),
                    }
                }
            }
            for (pr, v, r0) in &per_pressure {
                let mut m = DerivedMeasurement::new(Quantity::UnloadedRadius, *r0, &data.name, t);
                m.pressure_pa = *pr;
                m.speed_mps = *v;
                m.n_points = 1;
                out.push(m);
            }
            if !per_pressure.is_empty() {
                let mut m = DerivedMeasurement::new(
                    Quantity::UnloadedRadius,
                    mean(&per_pressure.iter().map(|e| e.2).collect::<Vec<_>>()),
                    &data.name,
                    t,
                );
                m.n_points = per_pressure.len();
                out.push(m);
            }
        }
        // Step-steer: one length per test, then the ± pair's mean per load and pressure.
        let mut tests: Vec<(f64, f64, f64, f64)> = Vec::new(); // (fz, p, sa, length)
        for tr in &data.step_steers {
            if let Some((fz, pr, sa, r)) = step_steer_length(cfg, tr) {
                let mut m = DerivedMeasurement::new(Quantity::LateralRelaxationLength, r.length_m, &data.name, t);
                m.fz_n = fz;
                m.pressure_pa = pr;
                m.speed_mps = mean(&tr.pts.iter().filter(|p| p[3] > STANDSTILL_MPS).map(|p| p[3]).collect::<Vec<_>>());
                m.slip_angle_deg = sa;
                m.n_points = 1;
                out.push(m);
                tests.push((fz, pr, sa, r.length_m));
            }
        }
        let mut used = vec![false; tests.len()];
        for i in 0..tests.len() {
            if used[i] {
                continue;
            }
            let same: Vec<usize> = (i..tests.len())
                .filter(|&j| {
                    !used[j]
                        && (tests[j].1 - tests[i].1).abs() < cfg.pressure_tol_pa
                        && (tests[j].0 - tests[i].0).abs() < cfg.load_case_tol_frac * tests[i].0.abs().max(1000.0)
                })
                .collect();
            let has_both = same.iter().any(|&j| tests[j].2 > 0.0) && same.iter().any(|&j| tests[j].2 < 0.0);
            if has_both {
                for &j in &same {
                    used[j] = true;
                }
                let mut m = DerivedMeasurement::new(
                    Quantity::LateralRelaxationLength,
                    mean(&same.iter().map(|&j| tests[j].3).collect::<Vec<_>>()),
                    &data.name,
                    t,
                );
                m.fz_n = mean(&same.iter().map(|&j| tests[j].0).collect::<Vec<_>>());
                m.pressure_pa = mean(&same.iter().map(|&j| tests[j].1).collect::<Vec<_>>());
                m.n_points = same.len();
                out.push(m);
            }
        }
        // Static drags: stiffness per test, averaged over repeats per load and pressure.
        let mut drags: Vec<(f64, f64, f64)> = Vec::new();
        for tr in &data.static_drags {
            let idx: Vec<usize> = (0..tr.pts.len()).filter(|&i| tr.modes[i] == RigSetpoint::MODE_STATIC).collect();
            if idx.len() < 5 {
                continue;
            }
            let x0 = tr.pts[idx[0]][0];
            let xs: Vec<f64> = idx.iter().map(|&i| tr.pts[i][0] - x0).collect();
            let fx: Vec<f64> = idx.iter().map(|&i| tr.pts[i][1]).collect();
            if let Some(k) = derived::longitudinal_stiffness(&xs, &fx, cfg.static_drag_linear_frac) {
                let fz = mean(&idx.iter().map(|&i| tr.pts[i][4]).collect::<Vec<_>>());
                let pr = mean(&idx.iter().map(|&i| tr.pts[i][5]).collect::<Vec<_>>());
                drags.push((fz, pr, k));
            }
        }
        let mut used = vec![false; drags.len()];
        for i in 0..drags.len() {
            if used[i] {
                continue;
            }
            let same: Vec<usize> = (i..drags.len())
                .filter(|&j| {
                    !used[j]
                        && (drags[j].1 - drags[i].1).abs() < cfg.pressure_tol_pa
                        && (drags[j].0 - drags[i].0).abs() < cfg.load_case_tol_frac * drags[i].0.abs().max(1000.0)
                })
                .collect();
            for &j in &same {
                used[j] = true;
            }
            let mut m = DerivedMeasurement::new(
                Quantity::LongitudinalStiffness,
                mean(&same.iter().map(|&j| drags[j].2).collect::<Vec<_>>()),
                &data.name,
                t,
            );
            m.fz_n = mean(&same.iter().map(|&j| drags[j].0).collect::<Vec<_>>());
            m.pressure_pa = mean(&same.iter().map(|&j| drags[j].1).collect::<Vec<_>>());
            m.n_points = same.len();
            out.push(m);
        }
        for m in &mut out {
            m.procedure.clone_from(&procedure);
        }
        self.out_derived.extend(out);
    }
}

/// The measured part of a step-steer: from the last standstill sample (steered at standstill)
/// while the slip angle stays at the value it was steered to. Returns (Fz, pressure, SA, result).
fn step_steer_length(cfg: &ChannelsConfig, tr: &TestTrace) -> Option<(f64, f64, f64, derived::RelaxationResult)> {
    let pts = &tr.pts;
    // The last standstill sample that is followed by rolling.
    let i0 = (0..pts.len()).rev().find(|&i| pts[i][3].abs() < STANDSTILL_MPS && i + 1 < pts.len())?;
    // The held slip angle: the median while rolling after the standstill (the steer at standstill
    // may overshoot; the median is not pulled by it nor by the steer back at the end).
    let mut rolling_sa: Vec<f64> =
        pts[i0..].iter().filter(|p| p[3] > 0.5 * cfg.min_speed_mps && p[2].is_finite()).map(|p| p[2]).collect();
    if rolling_sa.len() < 10 {
        return None;
    }
    rolling_sa.sort_by(f64::total_cmp);
    let sa_held = rolling_sa[rolling_sa.len() / 2];
    if sa_held.abs() < 0.2 {
        return None;
    }
    let tol = 0.1 * sa_held.abs() + 0.05;
    // The measurement ends where the wheel is steered back.
    let mut end = i0;
    for (i, p) in pts.iter().enumerate().skip(i0 + 1) {
        if p[3] > 0.5 * cfg.min_speed_mps && (p[2] - sa_held).abs() > tol {
            break;
        }
        end = i;
    }
    let win = &pts[i0..=end];
    if win.len() < 10 {
        return None;
    }
    let x0 = win[0][0];
    let xs: Vec<f64> = win.iter().map(|p| p[0] - x0).collect();
    let fy: Vec<f64> = win.iter().map(|p| p[1]).collect();
    let r = derived::relaxation_length(&xs, &fy, cfg.step_steer_saturated_frac)?;
    let rolling: Vec<&[f64; 6]> = win.iter().filter(|p| p[3] > STANDSTILL_MPS).collect();
    let n = rolling.len().max(1) as f64;
    let fz = rolling.iter().map(|p| p[4]).sum::<f64>() / n;
    let pr = rolling.iter().map(|p| p[5]).sum::<f64>() / n;
    Some((fz, pr, sa_held, r))
}

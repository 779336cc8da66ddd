//! The monitor's pure core: quality checks judged live from samples, procedure states, live
//! channels and sweep summaries. No I/O, no clock: time comes from the message stamps.
//!
//! States are applied to the samples stamped after them, exactly as in the channels core (see
//! `channels::core`), so live and replayed inputs give the same outputs.

use std::collections::{BTreeMap, VecDeque};

use serde::{Deserialize, Serialize};
use tyre_msgs::diagnostic_msgs::{DiagnosticArray, DiagnosticStatus, KeyValue};
use tyre_msgs::std_msgs::Header;
use tyre_msgs::topics;
use tyre_msgs::{LiveChannels, ProcedureState, QualityCheck, QualityReport, RigSample, RigSetpoint, SweepSummary};

use crate::config::{ConfigError, MonitorConfig, TyreInfo};
use crate::drift::{self, CurveFigures, SweepCurve};
use crate::wear::{self, Hold, HoldAcc, MatchTol, WearFit};

/// A specimen with less sliding energy than this has not been tested (sensor noise only) [J].
const MIN_SPECIMEN_ENERGY_J: f64 = 10_000.0;
/// The highest load GS2MF asks for, as a factor of Fz0 (BrkDrv, thesis §3.3).
const GS2MF_MAX_LOAD_FACTOR: f64 = 2.25;

/// Check names, in report order.
pub const CHECKS: [&str; 6] = ["load_rating", "wear", "graph_sweep_drift", "break_in", "chatter", "thermal_timeout"];

/// An alarm: a check rising to WARN or ERROR (and every sweep started hot). The run summary's
/// `alarms` entries have this shape.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Alarm {
    /// `WARN` or `ERROR`.
    pub level: String,
    /// Check name (see [`CHECKS`]).
    pub check: String,
    /// What was seen.
    pub message: String,
    /// Rig time [s].
    pub rig_time_s: f64,
}

/// What one input produced.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct MonitorOutput {
    /// The report, when a verdict or the wear figure changed (`rig/quality/report`).
    pub report: Option<QualityReport>,
    /// The same verdicts for `/diagnostics`, with every report.
    pub diagnostics: Option<DiagnosticArray>,
    /// Alarms raised by this input.
    pub alarms: Vec<Alarm>,
}

/// The monitor's wear figures.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WearEstimate {
    /// Tread lost so far [mm] (NaN until measurable).
    pub wear_mm: f64,
    /// Its 2 σ uncertainty [mm].
    pub wear_2sigma_mm: f64,
    /// Forecast at the end of the procedure [mm].
    pub forecast_mm: f64,
    /// Forecast with the rate's lower bound (rate − 2 σ) [mm].
    pub forecast_low_mm: f64,
    /// The fit behind it.
    pub fit: Option<WearFit>,
}

/// A graph-sweep pair compared.
#[derive(Debug, Clone, PartialEq)]
pub struct DriftRecord {
    /// Procedure.
    pub procedure: String,
    /// Position in the block (0-based).
    pub ordinal: usize,
    /// Graph sweep 1's and 2's names.
    pub names: (String, String),
    /// The figures.
    pub drift: drift::Drift,
    /// Worst level.
    pub level: u8,
}

#[derive(Debug, Clone, Default)]
struct GraphBlocks {
    /// Section index of each block seen, in order.
    sections: Vec<u32>,
    /// Per block: (name, figures) in order.
    sweeps: Vec<Vec<(String, CurveFigures)>>,
}

/// The monitor core.
#[derive(Debug, Clone)]
pub struct MonitorCore {
    cfg: MonitorConfig,
    tyre: TyreInfo,
    pending_states: channels::StateQueue,
    state: ProcedureState,
    last_t: f64,
    checks: Vec<QualityCheck>,
    /// The checks' levels and messages and the wear (0.01 mm) of the last report published:
    /// a report goes out when they change.
    last_signature: (Vec<(u8, String)>, i64),
    out_alarms: Vec<Alarm>,
    all_alarms: Vec<Alarm>,

    // load rating
    load_window: VecDeque<(f64, f64)>,
    load_sum: f64,
    max_load_factor: f64,
    entered_checked: bool,

    // energy and wear
    live_seen: bool,
    energy_j: f64,
    own_energy_j: f64,
    own_prev: Option<(f64, f64)>,
    hold: Option<HoldAcc>,
    holds: Vec<Hold>,
    wear: WearEstimate,
    sweeps_done: u32,
    specimen_wear_mm: Vec<f64>,

    // drift
    curve: Option<(ProcedureState, SweepCurve)>,
    graph: BTreeMap<String, GraphBlocks>,
    drifts: Vec<DriftRecord>,
    /// First of `drifts` on the specimen on the rig.
    drift_start: usize,

    // break-in
    repeats: BTreeMap<String, Vec<f64>>,

    // chatter
    fz_hist: [f64; 2],
    fz_hist_n: usize,
    fz_hist_t: f64,
    win: (f64, f64, f64, f64, f64),
    noise_floor: Option<f64>,
    chatter_worst_n: f64,

    // thermal
    hot_starts: u32,
    sweeps_seen: u32,
}

impl MonitorCore {
    /// A core for the tyre `tyre`, judged with `cfg`.
    pub fn new(cfg: MonitorConfig, tyre: TyreInfo) -> Result<Self, ConfigError> {
        cfg.validate()?;
        tyre.validate()?;
        let checks = CHECKS
            .iter()
            .map(|c| QualityCheck {
                level: QualityCheck::OK,
                check: (*c).to_owned(),
                message: match *c {
                    "load_rating" => "no load yet",
                    "wear" => "not measurable yet (needs two zero-slip holds of one load case)",
                    "graph_sweep_drift" => "no graph sweep 2 yet",
                    "break_in" => "no repeated sweeps yet",
                    "chatter" => "no vibration seen",
                    _ => "no sweep started hot",
                }
                .to_owned(),
                value: f64::NAN,
                threshold: f64::NAN,
                unit: String::new(),
                rig_time_s: 0.0,
            })
            .collect();
        Ok(Self {
            cfg,
            tyre,
            pending_states: channels::StateQueue::default(),
            state: ProcedureState::default(),
            last_t: f64::NEG_INFINITY,
            checks,
            last_signature: (Vec::new(), i64::MIN),
            out_alarms: Vec::new(),
            all_alarms: Vec::new(),
            load_window: VecDeque::new(),
            load_sum: 0.0,
            max_load_factor: 0.0,
            entered_checked: false,
            live_seen: false,
            energy_j: 0.0,
            own_energy_j: 0.0,
            own_prev: None,
            hold: None,
            holds: Vec::new(),
            wear: WearEstimate {
                wear_mm: f64::NAN,
                wear_2sigma_mm: f64::NAN,
                forecast_mm: f64::NAN,
                forecast_low_mm: f64::NAN,
                fit: None,
            },
            sweeps_done: 0,
            specimen_wear_mm: Vec::new(),
            curve: None,
            graph: BTreeMap::new(),
            drifts: Vec::new(),
            drift_start: 0,
            repeats: BTreeMap::new(),
            fz_hist: [0.0; 2],
            fz_hist_n: 0,
            fz_hist_t: f64::NAN,
            win: (0.0, 0.0, f64::NAN, 0.0, 0.0),
            noise_floor: None,
            chatter_worst_n: 0.0,
            hot_starts: 0,
            sweeps_seen: 0,
        })
    }

    /// The tyre description.
    pub fn tyre(&self) -> &TyreInfo {
        &self.tyre
    }

    /// The configuration.
    pub fn config(&self) -> &MonitorConfig {
        &self.cfg
    }

    /// Every alarm raised so far.
    pub fn alarms(&self) -> &[Alarm] {
        &self.all_alarms
    }

    /// The wear figures of the specimen on the rig.
    pub fn wear(&self) -> WearEstimate {
        self.wear
    }

    /// Wear measured on each specimen that has been taken off (tyre changes), then the one on the
    /// rig [mm].
    pub fn wear_by_specimen_mm(&self) -> Vec<f64> {
        let mut v = self.specimen_wear_mm.clone();
        if self.wear.wear_mm.is_finite() || self.energy() > MIN_SPECIMEN_ENERGY_J {
            v.push(self.wear.wear_mm);
        }
        v
    }

    /// The averaged zero-slip holds of the specimen on the rig.
    pub fn holds(&self) -> &[Hold] {
        &self.holds
    }

    /// Graph-sweep comparisons so far.
    pub fn drifts(&self) -> &[DriftRecord] {
        &self.drifts
    }

    /// Largest sustained load seen, as a factor of the declared Fz0.
    pub fn max_load_factor(&self) -> f64 {
        self.max_load_factor
    }

    /// The current verdicts.
    pub fn checks(&self) -> &[QualityCheck] {
        &self.checks
    }

    /// The sequencer's state (`procedure/state`). Takes effect for samples stamped after it.
    pub fn on_procedure_state(&mut self, state: &ProcedureState) {
        if let Some(now) = self.pending_states.offer(state, self.last_t) {
            self.apply_state(now);
        }
    }

    /// Live channels (`rig/channels/live`): the specimen's accumulated sliding energy.
    pub fn on_live_channels(&mut self, live: &LiveChannels) {
        if live.total_sliding_energy_j.is_finite() {
            self.live_seen = true;
            self.energy_j = live.total_sliding_energy_j;
        }
    }

    /// A sweep summary (`rig/channels/sweep_summary`): break-in and thermal time-outs.
    pub fn on_sweep_summary(&mut self, s: &SweepSummary) -> MonitorOutput {
        let t = s.header.stamp.as_secs_f64();
        if !s.cool_down_complete {
            self.sweeps_seen += 1;
            if s.started_hot {
                self.hot_starts += 1;
                let pct = f64::from(self.hot_starts) / f64::from(self.sweeps_seen) * 100.0;
                let mut lvl = self.cfg.hot_starts_pct.level(pct).max(QualityCheck::WARN);
                if self.hot_starts < self.cfg.hot_starts_error_min {
                    lvl = lvl.min(QualityCheck::WARN);
                }
                let msg = format!(
                    "sweep {} started hot at {:.1} °C (the thermal gate timed out); {} of {} sweeps ({pct:.0} %) \
                     started hot so far",
                    s.sweep_name, s.start_temp_c, self.hot_starts, self.sweeps_seen
                );
                // Every hot start is an event the control room should see.
                self.push_alarm(lvl, "thermal_timeout", &msg, t);
                let thr = self.cfg.hot_starts_pct.error;
                self.set("thermal_timeout", lvl, msg, pct, thr, "% of sweeps", t, false);
            }
            self.break_in(s, t);
        }
        self.emit(t)
    }

    /// One rig sample (`rig/sample`).
    pub fn on_sample(&mut self, s: &RigSample) -> MonitorOutput {
        let t = if s.runtime_s.is_finite() { s.runtime_s } else { s.header.stamp.as_secs_f64() };
        // States stamped before this sample govern it (`channels::state_queue`).
        for st in self.pending_states.due(t) {
            self.apply_state(st);
        }
        self.last_t = self.last_t.max(t);
        let forces_ok = s.fault_flags & RigSample::FAULT_FORCE == 0;
        if !self.entered_checked {
            self.entered_checked = true;
            if let Some(entered) = self.tyre.entered_load_index
                && entered != self.tyre.load_index
            {
                let msg = format!(
                    "load index {entered} entered at the rig, but the tyre declares {}: every load of the procedure is \
                     wrong (thesis §3.9 failure case)",
                    self.tyre.load_index
                );
                self.set(
                    "load_rating",
                    QualityCheck::ERROR,
                    msg,
                    f64::from(entered),
                    f64::from(self.tyre.load_index),
                    "LI",
                    t,
                    true,
                );
            } else {
                self.set(
                    "load_rating",
                    QualityCheck::OK,
                    format!("loads consistent with LI {} (Fz0 {:.0} N)", self.tyre.load_index, self.tyre.fz0_n),
                    0.0,
                    self.cfg.load_factor.warn,
                    "x Fz0",
                    t,
                    false,
                );
            }
        }
        // Own sliding-energy integral, used only if no live channels arrive.
        let p = if forces_ok {
            let sa = s.slipangl_deg.to_radians();
            let sr = if s.longslip.is_finite() { s.longslip } else { 0.0 };
            (s.fyw_n * s.trajvelw_mps * sa.sin()).hypot(s.fx_n * sr * s.trajvelw_mps * sa.cos())
        } else {
            0.0
        };
        let p = if p.is_finite() { p } else { 0.0 };
        if let Some((tp, pp)) = self.own_prev {
            let dt = t - tp;
            if dt > 0.0 && dt <= 1.0 {
                self.own_energy_j += 0.5 * (p + pp) * dt;
            }
        }
        self.own_prev = Some((t, p));

        if forces_ok && s.rig_mode != RigSetpoint::MODE_SAFE && s.fzw_n.is_finite() {
            self.load_sample(t, s.fzw_n);
        }
        let phase = self.state.phase;
        if phase == ProcedureState::PHASE_THERMAL_PAUSE {
            self.hold_sample(t, s);
        }
        if phase == ProcedureState::PHASE_SWEEP
            && forces_ok
            && let Some((_, c)) = self.curve.as_mut()
        {
            c.push(s.slipangl_deg, s.longslip, s.fyw_n, s.fx_n, s.trdtempc_c, t);
        }
        if forces_ok && s.fzw_n.is_finite() {
            self.chatter_sample(t, s, phase);
        } else {
            self.fz_hist_n = 0;
        }
        self.emit(t)
    }

    /// Ends whatever is in progress (end of a log): the open hold and graph sweep.
    pub fn finish(&mut self) -> MonitorOutput {
        for s in self.pending_states.drain() {
            self.apply_state(s);
        }
        let t = self.last_t;
        self.end_hold(t);
        self.end_curve(t);
        self.emit(t)
    }

    /// The report as it stands at `t_s`.
    pub fn report(&self, t_s: f64) -> QualityReport {
        QualityReport {
            header: Header::iso_w(t_s),
            level: self.checks.iter().map(|c| c.level).max().unwrap_or(QualityCheck::OK),
            checks: self.checks.clone(),
            wear_mm: self.wear.wear_mm,
            wear_pct_usable: self.wear.wear_mm / self.tyre.usable_mm() * 100.0,
            wear_forecast_mm: self.wear.forecast_mm,
            tread_depth_new_mm: self.tyre.tread_new_mm,
            tread_depth_min_mm: self.tyre.tread_min_mm,
        }
    }

    /// The verdicts as `/diagnostics` statuses (`tyrerig monitor: <check>`).
    pub fn diagnostics(&self, t_s: f64) -> DiagnosticArray {
        let kv = |k: &str, v: String| KeyValue { key: k.to_owned(), value: v };
        DiagnosticArray {
            header: Header::iso_w(t_s),
            status: self
                .checks
                .iter()
                .map(|c| {
                    let mut values = vec![
                        kv("value", format!("{}", c.value)),
                        kv("threshold", format!("{}", c.threshold)),
                        kv("unit", c.unit.clone()),
                        kv("rig_time_s", format!("{:.3}", c.rig_time_s)),
                    ];
                    // The measured rate, for the adaptive plan's price of wear (m/J → mm/MJ).
                    if c.check == "wear"
                        && let Some(fit) = self.wear.fit
                    {
                        values.push(kv(topics::WEAR_RATE_KEY, format!("{}", fit.rate_m_per_j * 1e9)));
                        values.push(kv(topics::WEAR_RATE_SD_KEY, format!("{}", fit.rate_se_m_per_j * 1e9)));
                    }
                    DiagnosticStatus {
                        level: c.level,
                        name: format!("tyrerig monitor: {}", c.check),
                        message: c.message.clone(),
                        hardware_id: format!("tyre LI {}", self.tyre.load_index),
                        values,
                    }
                })
                .collect(),
        }
    }

    // --- plumbing ---

    fn energy(&self) -> f64 {
        if self.live_seen { self.energy_j } else { self.own_energy_j }
    }

    fn push_alarm(&mut self, level: u8, check: &str, message: &str, t: f64) {
        let a = Alarm {
            level: if level >= QualityCheck::ERROR { "ERROR" } else { "WARN" }.to_owned(),
            check: check.to_owned(),
            message: message.to_owned(),
            rig_time_s: t,
        };
        self.out_alarms.push(a.clone());
        self.all_alarms.push(a);
    }

    /// Sets a check's verdict; an alarm when its level rises to WARN or ERROR (`_alarm` is kept
    /// for call-site readability: the rise alone decides).
    #[allow(clippy::too_many_arguments)]
    fn set(
        &mut self,
        check: &str,
        level: u8,
        message: String,
        value: f64,
        threshold: f64,
        unit: &str,
        t: f64,
        _alarm: bool,
    ) {
        let Some(i) = self.checks.iter().position(|c| c.check == check) else { return };
        let old = self.checks[i].level;
        if level > old && check != "thermal_timeout" {
            self.push_alarm(level, check, &message, t);
        }
        let c = &mut self.checks[i];
        c.level = level;
        c.message = message;
        c.value = value;
        c.threshold = threshold;
        c.unit = unit.to_owned();
        c.rig_time_s = t;
    }

    fn level_of(&self, check: &str) -> u8 {
        self.checks.iter().find(|c| c.check == check).map_or(0, |c| c.level)
    }

    fn emit(&mut self, t: f64) -> MonitorOutput {
        let wear_cmp = if self.wear.wear_mm.is_finite() { (self.wear.wear_mm * 100.0).round() as i64 } else { -1 };
        // Compared in place: this runs for every sample, and formatting a signature each time
        // was a visible part of a headless run.
        let (last_checks, last_wear) = &self.last_signature;
        let unchanged = *last_wear == wear_cmp
            && last_checks.len() == self.checks.len()
            && last_checks
                .iter()
                .zip(&self.checks)
                .all(|((level, message), c)| *level == c.level && *message == c.message);
        let alarms = std::mem::take(&mut self.out_alarms);
        if unchanged {
            return MonitorOutput { report: None, diagnostics: None, alarms };
        }
        self.last_signature = (self.checks.iter().map(|c| (c.level, c.message.clone())).collect(), wear_cmp);
        MonitorOutput { report: Some(self.report(t)), diagnostics: Some(self.diagnostics(t)), alarms }
    }

    fn apply_state(&mut self, st: ProcedureState) {
        let t = st.header.stamp.as_secs_f64();
        let old = std::mem::replace(&mut self.state, st);
        let new_phase = self.state.phase;
        if old.phase == ProcedureState::PHASE_THERMAL_PAUSE && new_phase != ProcedureState::PHASE_THERMAL_PAUSE {
            self.end_hold(t);
        }
        let sweep_changed = old.phase == ProcedureState::PHASE_SWEEP
            && (new_phase != ProcedureState::PHASE_SWEEP
                || self.state.sweep_index != old.sweep_index
                || self.state.sweep_name != old.sweep_name);
        if sweep_changed {
            self.sweeps_done += 1;
            self.end_curve(t);
            self.update_forecast(t);
        }
        if new_phase == ProcedureState::PHASE_THERMAL_PAUSE && self.hold.is_none() {
            self.hold = Some(HoldAcc::new(t, self.energy()));
        }
        if new_phase == ProcedureState::PHASE_SWEEP
            && self.curve.is_none()
            && self.state.sweep_name.contains("GraphSweep")
        {
            self.curve = Some((self.state.clone(), SweepCurve::default()));
        }
        if new_phase == ProcedureState::PHASE_TYRE_CHANGE && old.phase != ProcedureState::PHASE_TYRE_CHANGE {
            self.new_specimen();
        }
    }

    fn new_specimen(&mut self) {
        // The first mounting (nothing run yet) is no specimen taken off.
        if self.wear.wear_mm.is_finite() || self.energy() > MIN_SPECIMEN_ENERGY_J {
            self.specimen_wear_mm.push(self.wear.wear_mm);
        }
        self.holds.clear();
        self.hold = None;
        self.energy_j = 0.0;
        self.own_energy_j = 0.0;
        self.sweeps_done = 0;
        self.repeats.clear();
        self.wear = WearEstimate {
            wear_mm: f64::NAN,
            wear_2sigma_mm: f64::NAN,
            forecast_mm: f64::NAN,
            forecast_low_mm: f64::NAN,
            fit: None,
        };
        self.chatter_worst_n = 0.0;
        self.drift_start = self.drifts.len();
        // Verdicts about the tyre start again with the new one (so its alarms are raised again);
        // the load rating and the thermal time-outs are about the rig and the procedure and go on.
        let t = self.last_t.max(0.0);
        for check in ["wear", "graph_sweep_drift", "break_in", "chatter"] {
            if let Some(c) = self.checks.iter_mut().find(|c| c.check == check) {
                c.level = QualityCheck::OK;
                c.message = "new specimen mounted: no data on it yet".to_owned();
                c.value = f64::NAN;
                c.rig_time_s = t;
            }
        }
    }

    // --- load rating ---

    fn load_sample(&mut self, t: f64, fz: f64) {
        self.load_window.push_back((t, fz));
        self.load_sum += fz;
        while let Some(&(t0, f0)) = self.load_window.front() {
            if t - t0 > self.cfg.load_window_s {
                self.load_window.pop_front();
                self.load_sum -= f0;
            } else {
                break;
            }
        }
        let span = self.load_window.back().map_or(0.0, |b| b.0) - self.load_window.front().map_or(0.0, |f| f.0);
        if span < 0.8 * self.cfg.load_window_s {
            return;
        }
        let mean = self.load_sum / self.load_window.len() as f64;
        let factor = mean / self.tyre.fz0_n;
        if factor > self.max_load_factor + 0.02 || (factor > self.max_load_factor && self.level_of("load_rating") == 0)
        {
            self.max_load_factor = factor;
            let lvl = self.cfg.load_factor.level(factor).max(self.level_of("load_rating"));
            if lvl > QualityCheck::OK {
                let implied = implied_load_index(mean / GS2MF_MAX_LOAD_FACTOR);
                let msg = format!(
                    "sustained load {mean:.0} N = {factor:.2} × Fz0 of the declared LI {} ({:.0} N), above GS2MF's highest \
                     {GS2MF_MAX_LOAD_FACTOR} × Fz0 (section {}): the rig runs the loads of LI ≥ {} — wrong load index \
                     entered?",
                    self.tyre.load_index,
                    self.tyre.fz0_n,
                    self.state.section,
                    implied.map_or("?".to_owned(), |li| li.to_string()),
                );
                self.set("load_rating", lvl, msg, factor, self.cfg.load_factor.warn, "x Fz0", t, true);
            }
        }
    }

    // --- wear ---

    fn hold_sample(&mut self, t: f64, s: &RigSample) {
        let Some(h) = self.hold.as_mut() else { return };
        let ok = s.fault_flags & (RigSample::FAULT_RADIUS | RigSample::FAULT_FORCE | RigSample::FAULT_ENVELOPE) == 0
            && s.rig_mode != RigSetpoint::MODE_SAFE
            && s.slipangl_deg.abs() < 0.3
            && (!s.longslip.is_finite() || s.longslip.abs() < 0.01)
            && s.trajvelw_mps > 1.0
            && [s.dstwowhc_m, s.fzw_n, s.inflpres_pa, s.trajvelw_mps, s.inclangl_deg].iter().all(|v| v.is_finite());
        if ok && t - h.t0_s >= self.cfg.wear_hold_settle_s {
            h.push(t, s.dstwowhc_m, s.fzw_n, s.inflpres_pa, s.trajvelw_mps, s.inclangl_deg);
        }
    }

    fn tol(&self) -> MatchTol {
        MatchTol {
            load_n: self.cfg.wear_match_load_n,
            pressure_pa: self.cfg.wear_match_pressure_pa,
            speed_mps: self.cfg.wear_match_speed_mps,
            camber_deg: self.cfg.wear_match_camber_deg,
        }
    }

    fn end_hold(&mut self, t: f64) {
        let Some(h) = self.hold.take() else { return };
        if let Some(mut hold) = h.finish(self.cfg.wear_hold_min_s) {
            // No sliding during the pause: the energy at its end is the hold's.
            hold.energy_j = self.energy();
            self.holds.push(hold);
            self.update_forecast(t);
        }
    }

    fn update_forecast(&mut self, t: f64) {
        let Some(fit) = wear::fit(&self.holds, &self.tol()) else { return };
        let e = self.energy();
        let rate = fit.rate_m_per_j.max(0.0);
        let rate_lo = (fit.rate_m_per_j - 2.0 * fit.rate_se_m_per_j).max(0.0);
        let remaining_sweeps = f64::from(self.state.sweep_count.saturating_sub(self.state.sweep_index + 1));
        let per_sweep = if self.sweeps_done > 0 { e / f64::from(self.sweeps_done) } else { 0.0 };
        let e_end = e + per_sweep * remaining_sweeps;
        self.wear = WearEstimate {
            wear_mm: rate * e * 1e3,
            wear_2sigma_mm: 2.0 * fit.rate_se_m_per_j * e * 1e3,
            forecast_mm: rate * e_end * 1e3,
            forecast_low_mm: rate_lo * e_end * 1e3,
            fit: Some(fit),
        };
        let usable = self.tyre.usable_mm();
        let wear_lo_pct = rate_lo * e * 1e3 / usable * 100.0;
        let fc_lo_pct = self.wear.forecast_low_mm / usable * 100.0;
        let lvl_now = self.cfg.wear_pct_usable.level(wear_lo_pct);
        let lvl_fc = self.cfg.wear_forecast_pct_usable.level(fc_lo_pct);
        let lvl = lvl_now.max(lvl_fc);
        let w = self.wear;
        let mut msg = format!(
            "tread worn {:.2} ± {:.2} mm ({:.0} % of the usable {:.1} mm) from {} matched zero-slip holds in {} load \
             cases; {:.0} kJ sliding energy; forecast {:.2} mm ({:.0} % usable) at the end of the procedure",
            w.wear_mm,
            w.wear_2sigma_mm,
            w.wear_mm / usable * 100.0,
            usable,
            fit.n_matched,
            fit.n_cases,
            e / 1e3,
            w.forecast_mm,
            w.forecast_mm / usable * 100.0,
        );
        if lvl_fc > QualityCheck::OK {
            msg.push_str(&format!(
                "; even the low forecast {:.2} mm exceeds {:.0} % of the usable tread",
                w.forecast_low_mm,
                if lvl_fc == QualityCheck::ERROR {
                    self.cfg.wear_forecast_pct_usable.error
                } else {
                    self.cfg.wear_forecast_pct_usable.warn
                }
            ));
        }
        // Wear verdicts latch at their highest level: worn tread does not grow back.
        let lvl = lvl.max(self.level_of("wear"));
        self.set("wear", lvl, msg, w.wear_mm, self.cfg.wear_pct_usable.warn / 100.0 * usable, "mm", t, true);
    }

    // --- graph-sweep drift ---

    fn end_curve(&mut self, t: f64) {
        let Some((st, curve)) = self.curve.take() else { return };
        let Some(fig) = curve.figures(self.cfg.drift_bin_deg, self.cfg.drift_bin_slip_ratio) else { return };
        let blocks = self.graph.entry(st.procedure.clone()).or_default();
        let block = match blocks.sections.iter().position(|s| *s == st.section_index) {
            Some(b) => b,
            None => {
                blocks.sections.push(st.section_index);
                blocks.sweeps.push(Vec::new());
                blocks.sections.len() - 1
            }
        };
        blocks.sweeps[block].push((st.sweep_name.clone(), fig));
        if block == 0 {
            return;
        }
        let ordinal = blocks.sweeps[block].len() - 1;
        let Some((name1, fig1)) = blocks.sweeps[0].get(ordinal).cloned() else { return };
        let (name2, fig2) = blocks.sweeps[block][ordinal].clone();
        let d = drift::compare(&fig1, &fig2);
        let c = &self.cfg;
        let level = [
            c.drift_rms_pct.level(d.rms_pct),
            c.drift_peak_pct.level(d.peak_pct.abs()),
            if d.longitudinal {
                c.drift_peak_shift_pct_sr.level(d.peak_shift)
            } else {
                c.drift_peak_shift.level(d.peak_shift)
            },
            c.drift_stiffness_pct.level(d.stiffness_pct.abs()),
            c.drift_temp_pct.level(d.temp_pct),
        ]
        .into_iter()
        .max()
        .unwrap_or(0);
        self.drifts.push(DriftRecord {
            procedure: st.procedure.clone(),
            ordinal,
            names: (name1, name2.clone()),
            drift: d,
            level,
        });
        // The check shows the worst pair so far.
        let mine = &self.drifts[self.drift_start.min(self.drifts.len() - 1)..];
        let worst = mine.iter().max_by_key(|r| r.level).cloned().unwrap_or_else(|| mine[0].clone());
        let n_pairs = mine.len();
        let wd = worst.drift;
        let (su, slip) = if wd.longitudinal { ("% SR", "slip") } else { ("°", "cornering") };
        let msg = format!(
            "graph sweep 2 vs 1 ({} pair(s)); worst: #{} of {}: curve RMS {:.1} % of peak, peak force {:+.1} %, peak \
             position {:.2} {su}, {slip} stiffness {:+.1} %, temperature profile {:.1} %",
            n_pairs,
            worst.ordinal + 1,
            worst.procedure,
            wd.rms_pct,
            wd.peak_pct,
            wd.peak_shift,
            wd.stiffness_pct,
            wd.temp_pct,
        );
        self.set("graph_sweep_drift", worst.level, msg, wd.peak_pct, self.cfg.drift_peak_pct.warn, "%", t, true);
    }

    // --- break-in ---

    fn break_in(&mut self, s: &SweepSummary, t: f64) {
        let peak = s.peak_fy_n.abs().max(s.peak_fx_n.abs());
        if !(s.mean_fz_n > 100.0 && peak > 0.0 && peak.is_finite()) {
            return;
        }
        // Same sweep type = the name without its sweep number and repeat, at the same load and
        // pressure case.
        let parts: Vec<&str> = s.sweep_name.split('_').collect();
        let typ: Vec<&str> = parts
            .iter()
            .enumerate()
            .filter(|(i, p)| {
                !(p.starts_with("sw") && p[2..].chars().all(|c| c.is_ascii_digit())) && *i + 1 != parts.len()
            })
            .map(|(_, p)| *p)
            .collect();
        if !self.cfg.break_in_sweep_types.iter().any(|k| s.sweep_name.contains(k.as_str())) {
            return;
        }
        let key = format!(
            "{}|{}|{:.0}|{:.0}|{:.0}",
            s.procedure,
            typ.join("_"),
            s.mean_fz_n / 500.0,
            s.mean_pressure_pa / 1e4,
            s.mean_camber_deg * 2.0
        );
        let mu = peak / s.mean_fz_n;
        let seq = self.repeats.entry(key).or_default();
        seq.push(mu);
        if seq.len() < 3 {
            return;
        }
        let first = seq[0];
        let n = seq.len();
        let rise_total = (seq[n - 1] / first - 1.0) * 100.0;
        let rise_last = (seq[n - 1] / seq[n - 2] - 1.0) * 100.0;
        let rising = rise_total > self.cfg.break_in_rise_pct && rise_last > self.cfg.break_in_stable_pct;
        if rising {
            let msg = format!(
                "grip still rising: peak force / load {:+.1} % over {n} repeats of {} (last {:+.1} %) — the tyre is not \
                 broken in (thesis: +14.2 % over five sweeps of a new tyre)",
                rise_total,
                typ.join("_"),
                rise_last
            );
            self.set("break_in", QualityCheck::WARN, msg, rise_total, self.cfg.break_in_rise_pct, "%", t, true);
        } else if self.level_of("break_in") > QualityCheck::OK
            || self.checks.iter().any(|c| c.check == "break_in" && c.value.is_nan())
        {
            let msg = format!("grip stable over {n} repeats of {} ({:+.1} % in total)", typ.join("_"), rise_total);
            self.set("break_in", QualityCheck::OK, msg, rise_total, self.cfg.break_in_rise_pct, "%", t, false);
        }
    }

    // --- chatter ---

    fn chatter_sample(&mut self, t: f64, s: &RigSample, phase: u8) {
        // Second difference of FZ: removes the load's slow changes, keeps vibration.
        if self.fz_hist_n > 0 && !(t - self.fz_hist_t > 0.0 && t - self.fz_hist_t < 0.05) {
            self.fz_hist_n = 0;
        }
        self.fz_hist_t = t;
        if self.fz_hist_n < 2 {
            self.fz_hist[1] = self.fz_hist[0];
            self.fz_hist[0] = s.fzw_n;
            self.fz_hist_n += 1;
            return;
        }
        let d = s.fzw_n - 2.0 * self.fz_hist[0] + self.fz_hist[1];
        self.fz_hist[1] = self.fz_hist[0];
        self.fz_hist[0] = s.fzw_n;
        let (ref mut sum, ref mut n, ref mut t0, ref mut max_sa, ref mut fz) = self.win;
        if t0.is_nan() {
            *t0 = t;
        }
        *sum += d * d;
        *n += 1.0;
        *max_sa = max_sa.max(s.slipangl_deg.abs().max(s.longslip.abs() * 100.0));
        *fz += s.fzw_n;
        if t - *t0 < self.cfg.chatter_window_s {
            return;
        }
        let rms = (*sum / *n).sqrt();
        let (slip, mean_fz) = (*max_sa, *fz / *n);
        self.win = (0.0, 0.0, f64::NAN, 0.0, 0.0);
        if phase == ProcedureState::PHASE_THERMAL_PAUSE {
            // Quiet windows teach the noise floor.
            self.noise_floor = Some(self.noise_floor.map_or(rms, |f| 0.9 * f + 0.1 * rms));
            return;
        }
        if phase != ProcedureState::PHASE_SWEEP {
            return;
        }
        let Some(floor) = self.noise_floor else { return };
        // A sine of amplitude A gives a second difference of RMS ≤ 2A/√2 (2 at half the sample
        // rate): the estimate is a lower bound of the amplitude.
        let amp = (rms * rms - floor * floor).max(0.0).sqrt() * std::f64::consts::SQRT_2 / 2.0;
        if amp > self.chatter_worst_n {
            self.chatter_worst_n = amp;
            let lvl = self.cfg.chatter_amplitude_n.level(amp).max(self.level_of("chatter"));
            let msg = format!(
                "rig vibration ≈ {amp:.0} N on FZ at {mean_fz:.0} N ({:.2} × Fz0) and slip {slip:.1} (deg or %) in {} \
                 (thesis §3.9: chatter at high load and slip as the tyre wears)",
                mean_fz / self.tyre.fz0_n,
                self.state.sweep_name
            );
            self.set("chatter", lvl, msg, amp, self.cfg.chatter_amplitude_n.warn, "N", t, true);
        }
    }
}

/// The smallest ETRTO load index whose Fz0 is at least `fz0_n`.
fn implied_load_index(fz0_n: f64) -> Option<u32> {
    (60..=130).find(|&li| procedure::fz0_n(li).is_ok_and(|f| f >= fz0_n * 0.999))
}

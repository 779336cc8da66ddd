//! The node's pure core: from the suite's messages to the views a control room looks at.
//!
//! No I/O and no clock: time is the stamp of the message being handled, and the shell calls
//! [`ViewCore::tick`] at the view rate to collect what changed since the last tick.

use crate::alarms::AlarmDetector;
use crate::latch::Latch;
use crate::trace::{SweepTrace, TraceBuilder};
use crate::views::{
    GateView, LOG_ERROR, LOG_INFO, LOG_WARNING, LogLine, LogTime, PlanView, PlannedSweep, ProgressView, View,
    duration_words,
};
use procedure::{PauseModel, Plan};
use serde::Serialize;
use tyre_msgs::diagnostic_msgs::{DiagnosticArray, DiagnosticStatus as DS};
use tyre_msgs::{ModelState, ProcedureCommand, ProcedureState as PS, QualityReport, RigSample, ThermalState as TS};

/// A suite message the views are built from.
#[derive(Debug, Clone, Copy)]
pub enum Input<'a> {
    Sample(&'a RigSample),
    State(&'a PS),
    Thermal(&'a TS),
    Quality(&'a QualityReport),
    Diagnostics(&'a DiagnosticArray),
    Model(&'a ModelState),
}

/// A view message ready to send: its channel, log time (rig time, ns) and JSON.
#[derive(Debug, Clone, PartialEq)]
pub struct ViewMessage {
    pub view: View,
    pub log_time_ns: u64,
    pub json: Vec<u8>,
}

/// Views of one run.
#[derive(Debug)]
pub struct ViewCore {
    plan: Option<PlanView>,
    trace_max_points: usize,
    rig_time_s: f64,
    state: Option<PS>,
    thermal: Option<TS>,
    quality: Option<QualityReport>,
    current: Option<TraceBuilder>,
    alarms: AlarmDetector,
    alarm_count: u32,
    progress_dirty: bool,
    trace_dirty: bool,
    latch: Latch<View>,
}

pub fn phase_name(phase: u8) -> &'static str {
    match phase {
        PS::PHASE_IDLE => "IDLE",
        PS::PHASE_SWEEP => "SWEEP",
        PS::PHASE_THERMAL_PAUSE => "THERMAL_PAUSE",
        PS::PHASE_FREE_ROLLING_REF => "FREE_ROLLING_REF",
        PS::PHASE_SETTLE => "SETTLE",
        PS::PHASE_PAUSED => "PAUSED",
        PS::PHASE_ABORTED => "ABORTED",
        PS::PHASE_ESTOP => "ESTOP",
        PS::PHASE_COMPLETE => "COMPLETE",
        PS::PHASE_TYRE_CHANGE => "TYRE_CHANGE",
        _ => "?",
    }
}

pub fn gate_status_name(status: u8) -> &'static str {
    match status {
        TS::STATUS_WAITING => "WAITING",
        TS::STATUS_RELEASED => "RELEASED",
        TS::STATUS_TIMED_OUT => "TIMED_OUT",
        TS::STATUS_FAULT => "FAULT",
        TS::STATUS_IDLE => "IDLE",
        _ => "?",
    }
}

fn level_name(level: u8) -> &'static str {
    match level {
        DS::OK => "OK",
        DS::WARN => "WARN",
        DS::ERROR => "ERROR",
        _ => "STALE",
    }
}

/// Phases an operator wants in the log when the procedure enters or leaves them (the
/// sweep ↔ thermal pause alternation happens hundreds of times and is not logged).
fn is_notable(phase: u8) -> bool {
    matches!(
        phase,
        PS::PHASE_IDLE
            | PS::PHASE_PAUSED
            | PS::PHASE_ABORTED
            | PS::PHASE_ESTOP
            | PS::PHASE_COMPLETE
            | PS::PHASE_TYRE_CHANGE
    )
}

fn secs_to_ns(t_s: f64) -> u64 {
    if t_s.is_finite() && t_s > 0.0 { (t_s * 1e9) as u64 } else { 0 }
}

impl PlanView {
    /// The data steps of `plan` with their planned time; every status "to do".
    pub fn from_plan(plan: &Plan, pauses: &PauseModel) -> Self {
        let sweeps = plan
            .steps
            .iter()
            .filter_map(|s| {
                Some(PlannedSweep {
                    sweep_index: s.sweep_index?,
                    name: s.name.clone(),
                    kind: serde_json::to_value(s.kind).ok()?.as_str().unwrap_or("").to_owned(),
                    section: plan.sections.get(s.section_index).map(|x| x.name.clone()).unwrap_or_default(),
                    planned_s: s.duration_s,
                    thermal_pause_after: s.thermal_pause_after,
                    status: "to do",
                })
            })
            .collect();
        Self {
            procedure: plan.procedure.clone(),
            title: plan.title.clone(),
            sweep_count: plan.sweep_count(),
            setpoint_time_s: plan.planned_duration_s(),
            estimated_total_s: plan.estimate_total_s(pauses),
            current_sweep: 0,
            sweeps,
        }
    }

    /// Marks sweeps before `current` done and `current` running (or all done when complete).
    fn set_current(&mut self, current: u32, complete: bool) {
        self.current_sweep = if complete { self.sweep_count } else { current };
        for s in &mut self.sweeps {
            s.status = if complete || s.sweep_index < current {
                "done"
            } else if s.sweep_index == current {
                "running"
            } else {
                "to do"
            };
        }
    }
}

impl ViewCore {
    pub fn new(plan: Option<PlanView>, trace_max_points: usize) -> Self {
        Self {
            plan,
            trace_max_points,
            rig_time_s: 0.0,
            state: None,
            thermal: None,
            quality: None,
            current: None,
            alarms: AlarmDetector::default(),
            alarm_count: 0,
            progress_dirty: true,
            trace_dirty: false,
            latch: Latch::new(View::ALL.map(|v| (v, v.latched()))),
        }
    }

    /// Rig time of the latest stamped message [s].
    pub fn rig_time_s(&self) -> f64 {
        self.rig_time_s
    }

    /// The messages a late subscriber of `view` is sent first.
    pub fn latched(&self, view: View) -> Vec<(u64, Vec<u8>)> {
        self.latch.replay(view)
    }

    /// The plan view as it stands (for the first publication).
    pub fn start(&mut self) -> Vec<ViewMessage> {
        let mut out = Vec::new();
        if let Some(plan) = &self.plan {
            let plan = plan.clone();
            self.emit(&mut out, View::Plan, &plan);
        }
        out
    }

    /// Handles one suite message; returns what must go out now (alarms, plan updates).
    pub fn on_input(&mut self, input: Input<'_>) -> Vec<ViewMessage> {
        let mut out = Vec::new();
        match input {
            Input::Sample(s) => {
                self.advance(s.header.stamp.as_secs_f64());
                let sweeping = self.state.as_ref().is_some_and(|st| st.phase == PS::PHASE_SWEEP);
                if sweeping && let Some(t) = &mut self.current {
                    t.push(s);
                    self.trace_dirty = true;
                }
            }
            Input::State(st) => self.on_state(st, &mut out),
            Input::Thermal(th) => {
                self.advance(th.header.stamp.as_secs_f64());
                self.thermal = Some(th.clone());
                self.progress_dirty = true;
            }
            Input::Quality(q) => {
                self.advance(q.header.stamp.as_secs_f64());
                self.quality = Some(q.clone());
                self.progress_dirty = true;
            }
            Input::Model(m) => {
                self.advance(m.header.stamp.as_secs_f64());
                self.emit(&mut out, View::Model, &crate::model::ModelView::of(m));
            }
            Input::Diagnostics(d) => {
                self.advance(d.header.stamp.as_secs_f64());
                for a in self.alarms.on_diagnostics(d) {
                    self.alarm_count += 1;
                    let level = if a.level == DS::ERROR { LOG_ERROR } else { LOG_WARNING };
                    let line = log_line(a.rig_time_s, level, &a.check, format!("{}: {}", a.check, a.message));
                    self.emit(&mut out, View::Alarms, &line);
                    self.progress_dirty = true;
                }
            }
        }
        out
    }

    /// Rig time only moves forward (a late message does not move the views back).
    fn advance(&mut self, t_s: f64) {
        if t_s.is_finite() {
            self.rig_time_s = self.rig_time_s.max(t_s);
        }
    }

    fn on_state(&mut self, st: &PS, out: &mut Vec<ViewMessage>) {
        let t = st.header.stamp.as_secs_f64();
        self.advance(t);
        let previous = self.state.replace(st.clone());
        let old_phase = previous.as_ref().map(|p| p.phase);
        // The first state seen is logged too: it tells the operator where the procedure is.
        if old_phase != Some(st.phase) && (old_phase.is_none_or(is_notable) || is_notable(st.phase)) {
            let level = if matches!(st.phase, PS::PHASE_ABORTED | PS::PHASE_ESTOP) { LOG_WARNING } else { LOG_INFO };
            let from = old_phase.map_or("start", phase_name);
            let msg = format!(
                "procedure {}: {from} -> {} (sweep {} of {}, {:.1} % done)",
                st.procedure,
                phase_name(st.phase),
                (st.sweep_index + 1).min(st.sweep_count),
                st.sweep_count,
                st.progress * 100.0
            );
            self.emit(out, View::Alarms, &log_line(t, level, "sequencer", msg));
        }
        // A new sweep: the one that ran becomes the previous trace, complete.
        let new_sweep =
            st.phase == PS::PHASE_SWEEP && self.current.as_ref().is_none_or(|c| c.trace().sweep_name != st.sweep_name);
        if new_sweep {
            if let Some(done) = self.current.take() {
                let done = done.into_trace();
                if done.samples > 0 {
                    self.emit(out, View::PreviousSweepTrace, &done);
                }
            }
            self.current = Some(TraceBuilder::new(&st.sweep_name, st.sweep_index, self.trace_max_points));
            self.trace_dirty = true;
        }
        let complete = st.phase == PS::PHASE_COMPLETE;
        if let Some(plan) = &mut self.plan
            && (plan.current_sweep != st.sweep_index || complete)
            && plan.current_sweep != plan.sweep_count
        {
            plan.set_current(st.sweep_index, complete);
            let plan = plan.clone();
            self.emit(out, View::Plan, &plan);
        }
        self.progress_dirty = true;
    }

    /// A command a client sent: logged whether it went out or was refused.
    pub fn on_command(&mut self, client: &str, outcome: &Result<ProcedureCommand, String>) -> Vec<ViewMessage> {
        let mut out = Vec::new();
        let line = match outcome {
            Ok(c) => log_line(
                self.rig_time_s,
                LOG_INFO,
                "foxglove",
                format!("{} from {client} sent to the sequencer", crate::config::command_name(c.command)),
            ),
            Err(why) => {
                log_line(self.rig_time_s, LOG_WARNING, "foxglove", format!("refused a command from {client}: {why}"))
            }
        };
        self.emit(&mut out, View::Alarms, &line);
        out
    }

    /// The progress and the running sweep's trace, if they changed since the last tick.
    pub fn tick(&mut self) -> Vec<ViewMessage> {
        let mut out = Vec::new();
        if self.progress_dirty {
            self.progress_dirty = false;
            let p = self.progress();
            self.emit(&mut out, View::Progress, &p);
        }
        if self.trace_dirty {
            self.trace_dirty = false;
            if let Some(t) = &self.current {
                let t: SweepTrace = t.trace().clone();
                self.emit(&mut out, View::SweepTrace, &t);
            }
        }
        out
    }

    /// The progress view as it stands.
    pub fn progress(&self) -> ProgressView {
        let mut p = ProgressView { rig_time_s: self.rig_time_s, alarms: self.alarm_count, ..ProgressView::default() };
        if let Some(st) = &self.state {
            p.procedure = st.procedure.clone();
            p.phase = phase_name(st.phase).to_owned();
            p.phase_code = st.phase;
            p.section = st.section.clone();
            p.sweep_name = st.sweep_name.clone();
            p.sweep_index = st.sweep_index;
            p.sweep_count = st.sweep_count;
            p.sweep = format!("{} / {}", (st.sweep_index + 1).min(st.sweep_count), st.sweep_count);
            p.progress_pct = st.progress * 100.0;
            p.elapsed_rig_time_s = st.elapsed_rig_time_s;
            p.eta_s = st.estimated_remaining_s;
            p.eta = duration_words(st.estimated_remaining_s);
            p.sweep_started_hot = st.sweep_started_hot;
            p.plan_reason = st.plan_reason.clone();
            p.predicted_error_pct = st.predicted_error_pct;
        } else {
            p.phase = "no procedure state yet".to_owned();
            p.eta = duration_words(f64::NAN);
        }
        if let Some(th) = &self.thermal {
            let waiting = th.status == TS::STATUS_WAITING;
            p.gate = GateView {
                status: gate_status_name(th.status).to_owned(),
                gate_open: th.gate_open,
                filtered_temp_c: th.filtered_temp_c,
                baseline_c: th.baseline_c,
                above_baseline_k: th.filtered_temp_c - th.baseline_c,
                predicted_wait_s: th.predicted_wait_s,
                predicted_release_s: if waiting {
                    th.header.stamp.as_secs_f64() + th.predicted_wait_s
                } else {
                    f64::NAN
                },
            };
        }
        if let Some(q) = &self.quality {
            p.quality_level = level_name(q.level).to_owned();
            p.wear_mm = q.wear_mm;
            p.wear_forecast_mm = q.wear_forecast_mm;
        }
        p
    }

    fn emit<T: Serialize>(&mut self, out: &mut Vec<ViewMessage>, view: View, value: &T) {
        // Serialising plain structs of numbers and strings cannot fail; NaN becomes null.
        let Ok(json) = serde_json::to_vec(value) else { return };
        let log_time_ns = secs_to_ns(self.rig_time_s);
        self.latch.keep(view, log_time_ns, &json);
        out.push(ViewMessage { view, log_time_ns, json });
    }
}

fn log_line(t_s: f64, level: u8, name: &str, message: String) -> LogLine {
    LogLine {
        timestamp: LogTime::from_secs_f64(t_s),
        level,
        message,
        name: name.to_owned(),
        file: String::new(),
        line: 0,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use tyre_msgs::builtin_interfaces::Time;
    use tyre_msgs::std_msgs::Header;

    fn header(t: f64) -> Header {
        Header { stamp: Time::from_secs_f64(t), ..Header::default() }
    }

    fn state(t: f64, phase: u8, sweep: &str, index: u32) -> PS {
        PS {
            header: header(t),
            phase,
            procedure: "gs2mf".into(),
            sweep_name: sweep.into(),
            sweep_index: index,
            sweep_count: 3,
            progress: f64::from(index) / 3.0,
            estimated_remaining_s: 125.0,
            ..PS::default()
        }
    }

    fn sample(t: f64, slip: f64) -> RigSample {
        RigSample { header: header(t), slipangl_deg: slip, fyw_n: -1000.0 * slip, ..RigSample::default() }
    }

    fn json(m: &ViewMessage) -> serde_json::Value {
        serde_json::from_slice(&m.json).expect("json")
    }

    fn of(out: &[ViewMessage], view: View) -> Vec<serde_json::Value> {
        out.iter().filter(|m| m.view == view).map(json).collect()
    }

    #[test]
    fn sweeps_become_traces_and_the_finished_one_the_previous_trace() {
        let mut core = ViewCore::new(None, 1000);
        core.on_input(Input::State(&state(1.0, PS::PHASE_SWEEP, "sw0", 0)));
        for i in 0..10 {
            core.on_input(Input::Sample(&sample(1.0 + f64::from(i) * 0.01, f64::from(i))));
        }
        let trace = of(&core.tick(), View::SweepTrace);
        assert_eq!(trace.len(), 1);
        assert_eq!(trace[0]["sweep_name"], "sw0");
        assert_eq!(trace[0]["fyw_n"].as_array().expect("array").len(), 10);
        // Thermal pause: samples are not part of any sweep.
        core.on_input(Input::State(&state(2.0, PS::PHASE_THERMAL_PAUSE, "sw0", 0)));
        core.on_input(Input::Sample(&sample(2.1, 99.0)));
        assert!(of(&core.tick(), View::SweepTrace).is_empty());
        // The next sweep starts: sw0 goes out complete as the previous trace.
        let out = core.on_input(Input::State(&state(3.0, PS::PHASE_SWEEP, "sw1", 1)));
        let prev = of(&out, View::PreviousSweepTrace);
        assert_eq!(prev.len(), 1);
        assert_eq!(prev[0]["sweep_name"], "sw0");
        assert_eq!(prev[0]["samples"], 10);
        assert_eq!(core.latched(View::PreviousSweepTrace).len(), 1);
        // Nothing changed since the last tick but the new (empty) trace.
        let t = of(&core.tick(), View::SweepTrace);
        assert_eq!(t[0]["sweep_name"], "sw1");
        assert!(of(&core.tick(), View::SweepTrace).is_empty());
    }

    #[test]
    fn progress_reads_state_gate_and_quality() {
        let mut core = ViewCore::new(None, 100);
        let p = of(&core.tick(), View::Progress);
        assert_eq!(p[0]["phase"], "no procedure state yet");
        core.on_input(Input::State(&state(10.0, PS::PHASE_THERMAL_PAUSE, "sw1", 1)));
        let th = TS {
            header: header(10.5),
            status: TS::STATUS_WAITING,
            filtered_temp_c: 41.0,
            baseline_c: 38.0,
            predicted_wait_s: 20.0,
            ..TS::default()
        };
        core.on_input(Input::Thermal(&th));
        core.on_input(Input::Quality(&QualityReport { level: DS::WARN, wear_mm: 0.4, ..QualityReport::default() }));
        let p = &of(&core.tick(), View::Progress)[0];
        assert_eq!(p["phase"], "THERMAL_PAUSE");
        assert_eq!(p["sweep"], "2 / 3");
        assert_eq!(p["eta"], "2 min 05 s");
        assert_eq!(p["gate"]["status"], "WAITING");
        assert_eq!(p["gate"]["above_baseline_k"], 3.0);
        assert_eq!(p["gate"]["predicted_release_s"], 30.5);
        assert_eq!(p["quality_level"], "WARN");
        assert_eq!(p["rig_time_s"], 10.5);
        // Not waiting: no predicted release (null in JSON).
        core.on_input(Input::Thermal(&TS { status: TS::STATUS_RELEASED, ..th }));
        assert!(of(&core.tick(), View::Progress)[0]["gate"]["predicted_release_s"].is_null());
    }

    #[test]
    fn notable_phase_changes_and_rising_alarms_are_logged_and_latched() {
        let mut core = ViewCore::new(None, 100);
        core.on_input(Input::State(&state(1.0, PS::PHASE_SWEEP, "sw0", 0)));
        assert!(
            of(&core.on_input(Input::State(&state(2.0, PS::PHASE_THERMAL_PAUSE, "sw0", 0))), View::Alarms).is_empty()
        );
        let paused = of(&core.on_input(Input::State(&state(3.0, PS::PHASE_PAUSED, "sw0", 0))), View::Alarms);
        assert!(paused[0]["message"].as_str().expect("text").contains("THERMAL_PAUSE -> PAUSED"), "{paused:?}");
        assert_eq!(paused[0]["level"], LOG_INFO);
        let mut d = DiagnosticArray { header: header(4.0), ..DiagnosticArray::default() };
        d.status.push(DS { name: "quality: wear".into(), level: DS::ERROR, message: "5 mm".into(), ..DS::default() });
        let alarm = of(&core.on_input(Input::Diagnostics(&d)), View::Alarms);
        assert_eq!(alarm[0]["level"], LOG_ERROR);
        assert_eq!(alarm[0]["timestamp"]["sec"], 4);
        assert!(of(&core.on_input(Input::Diagnostics(&d)), View::Alarms).is_empty(), "a repeat is no new alarm");
        assert_eq!(core.latched(View::Alarms).len(), 3, "start, paused and the alarm");
        assert_eq!(core.progress().alarms, 1);
    }

    #[test]
    fn commands_are_logged_accepted_or_refused() {
        let mut core = ViewCore::new(None, 100);
        let ok = core
            .on_command("client 1", &Ok(ProcedureCommand { command: ProcedureCommand::PAUSE, ..Default::default() }));
        assert!(json(&ok[0])["message"].as_str().expect("text").contains("PAUSE from client 1"));
        let no = core.on_command("client 2", &Err("ESTOP is not allowed".into()));
        assert_eq!(json(&no[0])["level"], LOG_WARNING);
    }
}

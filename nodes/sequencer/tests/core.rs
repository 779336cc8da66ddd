//! The sequencer core, driven headless with a fake thermal gate.

use procedure::file::{ProcedureError, parse_with};
use procedure::{PauseModel, Plan, RigMode, RunInputs, StepKind, SweepStyle, expand};
use sequencer::SequencerConfig;
use sequencer::core::{Checkpoint, CommandRejected, Sequencer, SequencerEvent, SequencerOutput};
use tyre_msgs::std_msgs::Header;
use tyre_msgs::{ProcedureCommand, ProcedureState, RigSample, RigSetpoint, ThermalState};

const MINI: &str = r#"
[procedure]
name = "mini"
title = "Mini"
config_tag = "FreeRoll"

[[section]]
name = "a"
pressure = "mid"

[[section.step]]
kind = "sweep"
peak_deg = 8.0
low_rate_dps = 2.0
high_rate_dps = 30.0
threshold_deg = 4.0
loads = [0.8, 1.2]

[[section.step]]
kind = "on_centre"
slip_angles_deg = [1.0]
loads = [1.0]
hold_s = 2.0

[[section]]
name = "b"
pressure = "high"
mode = "coupled"
specimen = "B"

[[section.step]]
kind = "sweep"
peak_pct = 10.0
low_rate_pct_ps = 10.0
high_rate_pct_ps = 60.0
threshold_pct = 2.0
load = 1.0
"#;

fn mini_plan() -> Plan {
    let mut read = |p: &str| -> Result<String, ProcedureError> {
        Err(ProcedureError::Read { file: p.into(), source: std::io::Error::from(std::io::ErrorKind::NotFound) })
    };
    let doc = parse_with("mini.toml", MINI, &mut read).unwrap();
    expand(&doc, &RunInputs::default()).unwrap()
}

fn cmd(c: u8) -> ProcedureCommand {
    ProcedureCommand { header: Header::default(), command: c, procedure: String::new(), operator_name: "test".into() }
}

/// A fake thermal gate: opens `open_after_s` after it sees a thermal pause begin.
struct FakeGate {
    open_after_s: f64,
    pause_since: Option<f64>,
    timed_out: bool,
}

impl FakeGate {
    fn new(open_after_s: f64) -> Self {
        Self { open_after_s, pause_since: None, timed_out: false }
    }
    fn observe(&mut self, now: f64, out: &SequencerOutput) {
        for e in &out.events {
            match e {
                SequencerEvent::ThermalPauseStarted { .. } => self.pause_since = Some(now),
                SequencerEvent::ThermalPauseEnded { .. } => self.pause_since = None,
                _ => {}
            }
        }
    }
    fn state(&self, now: f64) -> ThermalState {
        let open = self.pause_since.is_none_or(|t| now - t >= self.open_after_s);
        ThermalState {
            header: Header::iso_w(now),
            status: if !open {
                ThermalState::STATUS_WAITING
            } else if self.timed_out {
                ThermalState::STATUS_TIMED_OUT
            } else {
                ThermalState::STATUS_RELEASED
            },
            gate_open: open,
            predicted_wait_s: self.pause_since.map_or(0.0, |t| (t + self.open_after_s - now).max(0.0)),
            ..ThermalState::default()
        }
    }
}

/// Drive the sequencer from `t` until `until(out)` or `t_end`; returns (t, outputs).
struct Harness {
    seq: Sequencer,
    gate: FakeGate,
    t: f64,
    dt: f64,
    log: Vec<(f64, SequencerOutput)>,
}

impl Harness {
    fn new(seq: Sequencer, gate_s: f64) -> Self {
        Self { seq, gate: FakeGate::new(gate_s), t: 0.0, dt: 0.01, log: Vec::new() }
    }
    fn command(&mut self, c: u8) -> Result<SequencerOutput, CommandRejected> {
        let out = self.seq.on_command(self.t, &cmd(c))?;
        self.gate.observe(self.t, &out);
        self.log.push((self.t, out.clone()));
        Ok(out)
    }
    fn tick(&mut self) -> SequencerOutput {
        self.t += self.dt;
        let th = self.gate.state(self.t);
        let out = self.seq.step(self.t, Some(&th), None);
        self.gate.observe(self.t, &out);
        self.log.push((self.t, out.clone()));
        out
    }
    fn run_until(&mut self, t_max: f64, mut f: impl FnMut(&SequencerOutput) -> bool) -> bool {
        while self.t < t_max {
            let out = self.tick();
            if f(&out) {
                return true;
            }
        }
        false
    }
    fn events(&self) -> Vec<SequencerEvent> {
        self.log.iter().flat_map(|(_, o)| o.events.clone()).collect()
    }
    fn sweeps_started(&self) -> Vec<String> {
        self.events()
            .into_iter()
            .filter_map(|e| match e {
                SequencerEvent::SweepStarted { name, .. } => Some(name),
                _ => None,
            })
            .collect()
    }
}

fn completed(out: &SequencerOutput) -> bool {
    out.events.iter().any(|e| matches!(e, SequencerEvent::Completed { .. }))
}

#[test]
fn start_runs_to_completion_with_thermal_pauses() {
    let plan = mini_plan();
    let planned = plan.planned_duration_s();
    let pauses = plan.steps.iter().filter(|s| s.thermal_pause_after).count();
    assert_eq!(pauses, 3);
    let mut h = Harness::new(Sequencer::new(plan.clone(), SequencerConfig::default()).unwrap(), 5.0);
    let out = h.command(ProcedureCommand::START).unwrap();
    assert!(out.state.is_some());
    assert!(h.run_until(1000.0, completed));
    let ev = h.events();
    let ended: Vec<f64> = ev
        .iter()
        .filter_map(|e| match e {
            SequencerEvent::ThermalPauseEnded { duration_s, .. } => Some(*duration_s),
            _ => None,
        })
        .collect();
    assert_eq!(ended.len(), 3);
    assert!(ended.iter().all(|d| *d >= 5.0 && *d < 5.1), "{ended:?}");
    assert_eq!(
        h.sweeps_started(),
        plan.steps.iter().filter(|s| s.sweep_index.is_some()).map(|s| s.name.clone()).collect::<Vec<_>>()
    );
    let total = h.t;
    assert!((total - (planned + 15.0)).abs() < 0.5, "{total} vs {}", planned + 15.0);
    // Final state: complete, progress 1, nothing remaining.
    let last_state = h.log.iter().rev().find_map(|(_, o)| o.state.clone()).unwrap();
    assert_eq!(last_state.phase, ProcedureState::PHASE_COMPLETE);
    assert_eq!(last_state.progress, 1.0);
    assert_eq!(last_state.estimated_remaining_s, 0.0);
    // Idle after completion: no setpoints; START refused.
    assert!(h.tick().setpoint.is_none());
    assert_eq!(h.command(ProcedureCommand::START).unwrap_err(), CommandRejected::AlreadyComplete);
}

#[test]
fn setpoints_follow_the_plan_and_carry_sweep_names() {
    let plan = mini_plan();
    let mut h = Harness::new(Sequencer::new(plan.clone(), SequencerConfig::default()).unwrap(), 1.0);
    h.command(ProcedureCommand::START).unwrap();
    let first = plan.steps.iter().find(|s| s.kind == StepKind::Sweep).unwrap();
    let mut t_start = None;
    h.run_until(100.0, |o| {
        o.events.iter().any(|e| matches!(e, SequencerEvent::SweepStarted { name, .. } if *name == first.name))
    });
    for (t, o) in h.log.iter().rev() {
        if o.events.iter().any(|e| matches!(e, SequencerEvent::StepStarted { index, .. } if *index == first.index)) {
            t_start = Some(*t);
            break;
        }
    }
    let _ = t_start;
    // Sample the sweep: every streamed setpoint matches the trajectory at the sweep's time.
    let mut n = 0;
    let mut prev_seq = 0;
    loop {
        let o = h.tick();
        let sp = o.setpoint.clone().unwrap();
        assert!(sp.seq > prev_seq);
        prev_seq = sp.seq;
        if sp.sweep_name != first.name {
            break;
        }
        assert_eq!(sp.mode, RigSetpoint::MODE_FREE_ROLLING);
        assert!(sp.slip_angle_deg.abs() <= 8.0 + 1e-9);
        assert!((sp.pressure_pa - 2.6e5).abs() < 1e-6);
        n += 1;
    }
    assert!((n as f64 * 0.01 - first.duration_s).abs() < 0.03, "{n} ticks vs {} s", first.duration_s);
}

#[test]
fn free_rolling_reference_phase_before_longitudinal_sweep() {
    let plan = mini_plan();
    let mut h = Harness::new(Sequencer::new(plan, SequencerConfig::default()).unwrap(), 1.0);
    h.command(ProcedureCommand::START).unwrap();
    h.run_until(1000.0, completed);
    let mut saw_ref = false;
    let mut ref_then_coupled = false;
    let mut last_phase = None;
    for (_, o) in &h.log {
        if let Some(s) = &o.state {
            last_phase = Some(s.phase);
            if s.phase == ProcedureState::PHASE_FREE_ROLLING_REF {
                saw_ref = true;
                assert!(s.sweep_name.starts_with("FreeRoll_sw4_VariableRate_LR10_HR60_TH2"), "{}", s.sweep_name);
            }
        }
        if let (Some(sp), Some(ProcedureState::PHASE_FREE_ROLLING_REF)) = (&o.setpoint, last_phase) {
            assert_eq!(sp.mode, RigSetpoint::MODE_FREE_ROLLING);
        }
        if saw_ref
            && let Some(sp) = &o.setpoint
            && sp.mode == RigSetpoint::MODE_COUPLED
            && !sp.sweep_name.is_empty()
        {
            ref_then_coupled = true;
        }
    }
    assert!(saw_ref && ref_then_coupled);
}

#[test]
fn pause_ramps_to_zero_slip_and_resume_restarts_the_sweep() {
    let plan = mini_plan();
    let mut h = Harness::new(Sequencer::new(plan, SequencerConfig::default()).unwrap(), 1.0);
    h.command(ProcedureCommand::START).unwrap();
    // Run into the first sweep until |slip| > 5°.
    h.run_until(100.0, |o| o.setpoint.as_ref().is_some_and(|s| s.slip_angle_deg.abs() > 5.0));
    let interrupted = h.log.last().unwrap().1.setpoint.clone().unwrap().sweep_name;
    let out = h.command(ProcedureCommand::PAUSE).unwrap();
    assert_eq!(out.state.unwrap().phase, ProcedureState::PHASE_PAUSED);
    for _ in 0..100 {
        h.tick();
    }
    let held = h.tick().setpoint.unwrap();
    assert_eq!(held.slip_angle_deg, 0.0, "slip ramped to zero and held");
    assert!(held.fz_n > 0.0 && held.mode == RigSetpoint::MODE_FREE_ROLLING);
    // PAUSE again refused; RESUME restarts the interrupted sweep.
    assert_eq!(h.command(ProcedureCommand::PAUSE).unwrap_err(), CommandRejected::NotRunning);
    let out = h.command(ProcedureCommand::RESUME).unwrap();
    assert!(out.events.iter().any(|e| matches!(e, SequencerEvent::Resumed { .. })));
    assert_eq!(h.command(ProcedureCommand::RESUME).unwrap_err(), CommandRejected::NotPaused);
    h.run_until(1000.0, completed);
    let started = h.sweeps_started();
    assert_eq!(started.iter().filter(|n| **n == interrupted).count(), 2, "{started:?}");
}

#[test]
fn abort_goes_safe_keeps_checkpoint_and_start_resumes() {
    let plan = mini_plan();
    let mut h = Harness::new(Sequencer::new(plan.clone(), SequencerConfig::default()).unwrap(), 1.0);
    h.command(ProcedureCommand::START).unwrap();
    // Into the second sweep.
    let second = plan.steps.iter().filter(|s| s.kind == StepKind::Sweep).nth(1).unwrap().clone();
    h.run_until(1000.0, |o| {
        o.setpoint.as_ref().is_some_and(|s| s.sweep_name == second.name && s.slip_angle_deg.abs() > 1.0)
    });
    let out = h.command(ProcedureCommand::ABORT).unwrap();
    assert_eq!(out.state.unwrap().phase, ProcedureState::PHASE_ABORTED);
    let sp = h.tick().setpoint.unwrap();
    assert_eq!(sp.mode, RigSetpoint::MODE_SAFE);
    let cp = h.seq.checkpoint();
    assert_eq!(cp.next_step, second.restart_from);
    assert!(!cp.complete);
    assert_eq!(h.command(ProcedureCommand::ABORT).unwrap_err(), CommandRejected::NotRunning);
    let before = h.sweeps_started().len();
    h.command(ProcedureCommand::START).unwrap();
    h.run_until(1000.0, completed);
    let after: Vec<String> = h.sweeps_started()[before..].to_vec();
    assert_eq!(after.first(), Some(&second.name), "{after:?}");
    assert!(!after.contains(&plan.steps.iter().find(|s| s.kind == StepKind::Sweep).unwrap().name));
}

#[test]
fn estop_is_safe_at_once_from_any_state() {
    let plan = mini_plan();
    let mut h = Harness::new(Sequencer::new(plan, SequencerConfig::default()).unwrap(), 1.0);
    // From idle.
    let out = h.command(ProcedureCommand::ESTOP).unwrap();
    assert_eq!(out.state.as_ref().unwrap().phase, ProcedureState::PHASE_ESTOP);
    // Mid-sweep: the command's own output carries the safe setpoint, no ramp.
    let mut h = Harness::new(Sequencer::new(mini_plan(), SequencerConfig::default()).unwrap(), 1.0);
    h.command(ProcedureCommand::START).unwrap();
    h.run_until(100.0, |o| o.setpoint.as_ref().is_some_and(|s| s.slip_angle_deg.abs() > 5.0));
    let out = h.command(ProcedureCommand::ESTOP).unwrap();
    assert_eq!(out.state.as_ref().unwrap().phase, ProcedureState::PHASE_ESTOP);
    assert!(out.events.contains(&SequencerEvent::EStop));
    let sp = out.setpoint.expect("safe setpoint in the command's output");
    assert_eq!(sp.mode, RigSetpoint::MODE_SAFE);
    for _ in 0..50 {
        assert_eq!(h.tick().setpoint.unwrap().mode, RigSetpoint::MODE_SAFE);
    }
    // RESUME does not leave an e-stop; START does (from the checkpoint).
    assert_eq!(h.command(ProcedureCommand::RESUME).unwrap_err(), CommandRejected::NotPaused);
    h.command(ProcedureCommand::START).unwrap();
    assert!(h.run_until(1000.0, completed));
}

#[test]
fn rejected_commands() {
    let mut s = Sequencer::new(mini_plan(), SequencerConfig::default()).unwrap();
    assert_eq!(s.on_command(0.0, &cmd(ProcedureCommand::PAUSE)).unwrap_err(), CommandRejected::NotRunning);
    assert_eq!(s.on_command(0.0, &cmd(ProcedureCommand::RESUME)).unwrap_err(), CommandRejected::NotPaused);
    assert_eq!(s.on_command(0.0, &cmd(ProcedureCommand::ABORT)).unwrap_err(), CommandRejected::NotRunning);
    assert_eq!(s.on_command(0.0, &cmd(42)).unwrap_err(), CommandRejected::Unknown(42));
    let mut wrong = cmd(ProcedureCommand::START);
    wrong.procedure = "square_matrix".into();
    assert!(matches!(s.on_command(0.0, &wrong).unwrap_err(), CommandRejected::WrongProcedure { .. }));
    let mut right = cmd(ProcedureCommand::START);
    right.procedure = "launch-config/procedures/mini.toml".into();
    s.on_command(0.0, &right).unwrap();
    assert_eq!(s.on_command(0.0, &cmd(ProcedureCommand::START)).unwrap_err(), CommandRejected::AlreadyRunning);
}

#[test]
fn checkpoint_resume_restarts_interrupted_sweep_and_skips_completed() {
    let plan = mini_plan();
    let cfg = SequencerConfig::default();
    let mut h = Harness::new(Sequencer::new(plan.clone(), cfg).unwrap(), 2.0);
    h.command(ProcedureCommand::START).unwrap();
    let sweeps: Vec<_> = plan.steps.iter().filter(|s| s.kind == StepKind::Sweep).cloned().collect();
    // Interrupt mid-way through the second sweep (the process dies: no command).
    h.run_until(1000.0, |o| {
        o.setpoint.as_ref().is_some_and(|s| s.sweep_name == sweeps[1].name && s.slip_angle_deg.abs() > 2.0)
    });
    let cp: Checkpoint = serde_json::from_str(&serde_json::to_string(&h.seq.checkpoint()).unwrap()).unwrap();
    assert_eq!(cp.next_step, sweeps[1].restart_from);
    assert!(cp.completed_steps > sweeps[0].index);
    assert!(cp.elapsed_rig_time_s > 0.0);
    let t_crash = h.t;
    // A new process: resume from the checkpoint, fed a sample of where the rig is.
    let mut s2 = Sequencer::resume(plan.clone(), cfg, &cp).unwrap();
    let sample =
        RigSample { fzw_n: 5000.0, inflpres_pa: 2.6e5, trajvelw_mps: 16.6, slipangl_deg: 3.0, ..RigSample::default() };
    let out0 = s2.step(t_crash + 5.0, None, Some(&sample));
    assert!(out0.setpoint.is_none(), "idle until START");
    let mut h2 = Harness::new(s2, 2.0);
    h2.t = t_crash + 5.0;
    let out = h2.command(ProcedureCommand::START).unwrap();
    assert!(out.events.iter().any(|e| matches!(e, SequencerEvent::Started { resumed: true, .. })));
    // The first setpoint ramps from the sampled state, not from the plan's assumption.
    let first = h2.tick().setpoint.unwrap();
    assert!((first.slip_angle_deg - 3.0).abs() < 0.5, "{first:?}");
    assert!(h2.run_until(t_crash + 1000.0, completed));
    let started = h2.sweeps_started();
    assert_eq!(started[0], sweeps[1].name);
    assert!(!started.contains(&sweeps[0].name), "completed sweep repeated: {started:?}");
    let last_state = h2.log.iter().rev().find_map(|(_, o)| o.state.clone()).unwrap();
    assert!(last_state.elapsed_rig_time_s > cp.elapsed_rig_time_s);
}

#[test]
fn checkpoint_during_thermal_pause_resumes_with_a_pause() {
    let plan = mini_plan();
    let cfg = SequencerConfig::default();
    let mut h = Harness::new(Sequencer::new(plan.clone(), cfg).unwrap(), 30.0);
    h.command(ProcedureCommand::START).unwrap();
    h.run_until(1000.0, |o| o.events.iter().any(|e| matches!(e, SequencerEvent::ThermalPauseStarted { .. })));
    h.tick();
    let cp = h.seq.checkpoint();
    assert!(cp.thermal_pause_first);
    let first_sweep = plan.steps.iter().find(|s| s.kind == StepKind::Sweep).unwrap();
    assert_eq!(cp.next_step, first_sweep.index + 1);
    let s2 = Sequencer::resume(plan.clone(), cfg, &cp).unwrap();
    let mut h2 = Harness::new(s2, 3.0);
    h2.t = h.t;
    let out = h2.command(ProcedureCommand::START).unwrap();
    assert!(out.events.iter().any(|e| matches!(e, SequencerEvent::ThermalPauseStarted { .. })), "{:?}", out.events);
    assert!(h2.run_until(h.t + 1000.0, completed));
    assert!(!h2.sweeps_started().contains(&first_sweep.name));
}

#[test]
fn checkpoint_for_another_plan_is_refused() {
    let plan = mini_plan();
    let mut cp = Sequencer::new(plan.clone(), SequencerConfig::default()).unwrap().checkpoint();
    cp.plan_fingerprint ^= 1;
    assert!(Sequencer::resume(plan, SequencerConfig::default(), &cp).is_err());
}

#[test]
fn missing_or_stale_thermal_state_holds_the_pause() {
    let plan = mini_plan();
    let mut s = Sequencer::new(plan, SequencerConfig::default()).unwrap();
    s.on_command(0.0, &cmd(ProcedureCommand::START)).unwrap();
    let mut t = 0.0;
    // Run to the first pause with no thermal state at all.
    loop {
        t += 0.01;
        let o = s.step(t, None, None);
        if o.events.iter().any(|e| matches!(e, SequencerEvent::ThermalPauseStarted { .. })) {
            break;
        }
        assert!(t < 100.0);
    }
    let t_pause = t;
    let open_stale = ThermalState {
        header: Header::iso_w(t_pause + 2.0),
        gate_open: true,
        status: ThermalState::STATUS_RELEASED,
        ..ThermalState::default()
    };
    for i in 0..6000 {
        t = t_pause + 0.01 * f64::from(i + 1);
        // Nothing for 10 s, then a gate-open message that goes stale (stamped t_pause + 2 s).
        let th = (t > 10.0 + t_pause).then_some(&open_stale);
        let o = s.step(t, th, None);
        assert!(
            !o.events.iter().any(|e| matches!(e, SequencerEvent::ThermalPauseEnded { .. })),
            "released at {t} by a missing/stale state"
        );
        let sp = o.setpoint.unwrap();
        assert_eq!(sp.slip_angle_deg, 0.0);
        assert_eq!(sp.slip_ratio, 0.0);
    }
    // A gate open judged before the pause began (+min) does not release either.
    let early = ThermalState { header: Header::iso_w(t_pause + 0.5), gate_open: true, ..ThermalState::default() };
    let o = s.step(t_pause + 0.6, Some(&early), None);
    assert!(!o.events.iter().any(|e| matches!(e, SequencerEvent::ThermalPauseEnded { .. })));
    // A fresh open gate releases.
    t += 0.01;
    let fresh = ThermalState {
        header: Header::iso_w(t),
        gate_open: true,
        status: ThermalState::STATUS_RELEASED,
        ..ThermalState::default()
    };
    let o = s.step(t, Some(&fresh), None);
    assert!(o.events.iter().any(|e| matches!(e, SequencerEvent::ThermalPauseEnded { timed_out: false, .. })));
}

#[test]
fn timed_out_gate_marks_next_sweep_started_hot() {
    let plan = mini_plan();
    let mut h = Harness::new(Sequencer::new(plan, SequencerConfig::default()).unwrap(), 2.0);
    h.gate.timed_out = true;
    h.command(ProcedureCommand::START).unwrap();
    h.run_until(1000.0, completed);
    let hot: Vec<bool> = h
        .events()
        .into_iter()
        .filter_map(|e| match e {
            SequencerEvent::SweepStarted { started_hot, .. } => Some(started_hot),
            _ => None,
        })
        .collect();
    assert!(!hot[0], "nothing timed out before the first");
    assert!(hot[1], "{hot:?}");
    assert!(h.log.iter().filter_map(|(_, o)| o.state.as_ref()).any(|s| s.sweep_started_hot));
}

#[test]
fn envelope_refusal() {
    let plan = mini_plan();
    let mut cfg = SequencerConfig::default();
    cfg.envelope.max_fz_n = 5000.0;
    let e = Sequencer::new(plan.clone(), cfg).unwrap_err();
    assert!(e.to_string().contains("fz_n"), "{e}");
    // At run time: an interlock lowers the envelope mid-run; the next setpoint is refused.
    let mut h = Harness::new(Sequencer::new(plan, SequencerConfig::default()).unwrap(), 1.0);
    h.command(ProcedureCommand::START).unwrap();
    h.run_until(100.0, |o| o.setpoint.as_ref().is_some_and(|s| s.slip_angle_deg.abs() > 2.0));
    let mut tight = SequencerConfig::default().envelope;
    tight.max_slip_angle_deg = 1.0;
    h.seq.set_envelope(tight);
    let o = h.tick();
    assert!(
        o.events.iter().any(|e| matches!(e, SequencerEvent::SetpointRefused { axis, .. } if axis == "slip_angle_deg"))
    );
    assert_eq!(o.setpoint.unwrap().mode, RigSetpoint::MODE_SAFE);
    assert_eq!(o.state.unwrap().phase, ProcedureState::PHASE_ABORTED);
}

#[test]
fn state_published_on_change_and_at_2hz_with_falling_eta() {
    let plan = mini_plan();
    let mut h = Harness::new(Sequencer::new(plan, SequencerConfig::default()).unwrap(), 3.0);
    h.command(ProcedureCommand::START).unwrap();
    h.run_until(1000.0, completed);
    let states: Vec<(f64, ProcedureState)> =
        h.log.iter().filter_map(|(t, o)| o.state.clone().map(|s| (*t, s))).collect();
    for w in states.windows(2) {
        let gap = w[1].0 - w[0].0;
        assert!(gap <= 0.5 + 1e-6, "gap {gap}");
        assert!(w[1].1.progress >= w[0].1.progress - 1e-12);
    }
    let n = states.len() as f64;
    assert!(n >= 2.0 * h.t * 0.95, "{n} states in {} s", h.t);
    let eta0 = states[1].1.estimated_remaining_s;
    let mid = &states[states.len() / 2].1;
    assert!(mid.estimated_remaining_s < eta0);
    assert!(states.iter().any(|(_, s)| s.phase == ProcedureState::PHASE_THERMAL_PAUSE));
    assert!(states.iter().all(|(_, s)| s.sweep_count == 4));
}

#[test]
fn tyre_change_phase_between_specimens() {
    let mut read = |p: &str| -> Result<String, ProcedureError> {
        Err(ProcedureError::Read { file: p.into(), source: std::io::Error::from(std::io::ErrorKind::NotFound) })
    };
    let src = MINI.replace("name = \"mini\"", "name = \"mini\"\ntyre_change_s = 30.0");
    let doc = parse_with("mini.toml", &src, &mut read).unwrap();
    let plan = expand(&doc, &RunInputs::default()).unwrap();
    assert_eq!(plan.steps.iter().filter(|s| s.kind == StepKind::TyreChange).count(), 1);
    let mut h = Harness::new(Sequencer::new(plan, SequencerConfig::default()).unwrap(), 1.0);
    h.command(ProcedureCommand::START).unwrap();
    h.run_until(1000.0, completed);
    assert!(h.events().iter().any(
        |e| matches!(e, SequencerEvent::TyreChange { specimen, duration_s } if specimen == "B" && *duration_s == 30.0)
    ));
    let tc: Vec<_> = h
        .log
        .iter()
        .filter(|(_, o)| o.state.as_ref().is_some_and(|s| s.phase == ProcedureState::PHASE_TYRE_CHANGE))
        .collect();
    assert!(tc.len() >= 59, "2 Hz over 30 s");
    assert!(tc.iter().all(|(_, o)| o.setpoint.as_ref().is_none_or(|s| s.mode == RigSetpoint::MODE_SAFE)));
}

fn full_run(file: &str, model: &PauseModel, sweeps: SweepStyle) -> f64 {
    let dir = std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../launch-config/procedures");
    let doc = procedure::load(&dir.join(file)).unwrap();
    let plan = expand(&doc, &RunInputs { sweeps, ..RunInputs::default() }).unwrap();
    // A fake gate that opens after the pause model's estimate for the sweep just run.
    let pauses: Vec<f64> = plan.steps.iter().map(|s| model.pause_after_s(s)).collect();
    let mut s = Sequencer::new(plan.clone(), SequencerConfig::default()).unwrap();
    s.on_command(0.0, &cmd(ProcedureCommand::START)).unwrap();
    let (mut t, dt) = (0.0, 0.1);
    let mut pause: Option<(f64, f64)> = None;
    let mut sweep_step = 0usize;
    let mut predicted_total = None;
    loop {
        t += dt;
        let th = ThermalState {
            header: Header::iso_w(t),
            gate_open: pause.is_none_or(|(t0, d)| t - t0 >= d),
            ..ThermalState::default()
        };
        let o = s.step(t, Some(&th), None);
        for e in &o.events {
            match e {
                SequencerEvent::StepStarted { index, .. } => sweep_step = *index,
                SequencerEvent::ThermalPauseStarted { .. } => pause = Some((t, pauses[sweep_step].max(1.0))),
                SequencerEvent::ThermalPauseEnded { .. } => pause = None,
                _ => {}
            }
        }
        if let Some(sp) = &o.setpoint {
            assert!(sp.fz_n.is_finite());
            assert!(sp.mode == RigSetpoint::MODE_SAFE || sp.fz_n > 0.0);
        }
        if let Some(st) = &o.state
            && predicted_total.is_none()
            && t >= 1000.0
        {
            predicted_total = Some(st.elapsed_rig_time_s + st.estimated_remaining_s);
        }
        if completed(&o) {
            // With the gate following the model, the ETA after 1,000 s is close to the truth.
            let p = predicted_total.unwrap();
            assert!((p - t).abs() / t < 0.02, "{file}: predicted {p} s, took {t} s");
            return t;
        }
        assert!(t < 200_000.0, "never completed");
    }
}

#[test]
fn full_gs2mf_and_square_matrix_complete_headless() {
    let m = PauseModel::default();
    let g = full_run("gs2mf.toml", &m, SweepStyle::Variable);
    let sm = full_run("square_matrix.toml", &m, SweepStyle::Variable);
    let gc = full_run("gs2mf.toml", &m, SweepStyle::Continuous);
    println!("headless: GS2MF {g:.0} s (continuous {gc:.0} s), Square Matrix {sm:.0} s, ratio {:.3}", g / sm);
    assert!(g <= 0.27 * sm, "{g} vs {sm}");
    assert!(gc < g, "continuous {gc} vs variable {g}");
}

#[test]
fn idle_sequencer_streams_nothing() {
    let mut s = Sequencer::new(mini_plan(), SequencerConfig::default()).unwrap();
    let o = s.step(0.0, None, None);
    assert!(o.setpoint.is_none());
    assert_eq!(o.state.unwrap().phase, ProcedureState::PHASE_IDLE);
    let _ = RigMode::Safe;
}

#[test]
fn rig_faults_estop_and_refused_setpoint() {
    let mut s = Sequencer::new(mini_plan(), SequencerConfig::default()).unwrap();
    s.on_command(0.0, &cmd(ProcedureCommand::START)).unwrap();
    let ok = RigSample { fzw_n: 5000.0, inflpres_pa: 2.6e5, trajvelw_mps: 16.6, ..RigSample::default() };
    for i in 1..100 {
        s.step(f64::from(i) * 0.01, None, Some(&ok));
    }
    let refused = RigSample { fault_flags: RigSample::FAULT_ENVELOPE, ..ok.clone() };
    let o = s.step(1.0, None, Some(&refused));
    assert!(o.events.iter().any(|e| matches!(e, SequencerEvent::RigRefusedSetpoint { .. })));
    let o = s.step(1.01, None, Some(&refused));
    assert!(!o.events.iter().any(|e| matches!(e, SequencerEvent::RigRefusedSetpoint { .. })), "rising edge only");
    assert_ne!(o.setpoint.unwrap().mode, RigSetpoint::MODE_SAFE, "the run goes on");
    let estop = RigSample { fault_flags: RigSample::FAULT_ESTOP, ..ok };
    let o = s.step(1.02, None, Some(&estop));
    assert!(o.events.contains(&SequencerEvent::EStop));
    assert_eq!(o.setpoint.unwrap().mode, RigSetpoint::MODE_SAFE);
    assert_eq!(o.state.unwrap().phase, ProcedureState::PHASE_ESTOP);
}

#[test]
fn deterministic_outputs() {
    let run = || {
        let mut h = Harness::new(Sequencer::new(mini_plan(), SequencerConfig::default()).unwrap(), 2.5);
        h.command(ProcedureCommand::START).unwrap();
        h.run_until(1000.0, completed);
        h.log
    };
    assert_eq!(run(), run());
}

fn rig_sample(t: f64, sp: &RigSetpoint) -> RigSample {
    RigSample {
        header: Header::iso_w(t),
        slipangl_deg: sp.slip_angle_deg,
        longslip: sp.slip_ratio,
        fzw_n: sp.fz_n,
        trajvelw_mps: sp.speed_mps,
        inflpres_pa: sp.pressure_pa,
        rig_mode: sp.mode,
        ..RigSample::default()
    }
}

/// The rig goes silent mid-sweep (killed, stopped, cable pulled): the watchdog's call holds zero
/// slip in the same output; when samples come back the interrupted sweep's group reruns.
#[test]
fn a_silent_rig_is_held_at_zero_slip_and_the_interrupted_sweep_reruns() {
    let mut h = Harness::new(Sequencer::new(mini_plan(), SequencerConfig::default()).unwrap(), 1.0);
    h.command(ProcedureCommand::START).unwrap();
    h.run_until(100.0, |o| o.setpoint.as_ref().is_some_and(|s| s.slip_angle_deg.abs() > 5.0));
    let last = h.log.last().unwrap().1.setpoint.clone().unwrap();
    let interrupted = last.sweep_name.clone();

    let out = h.seq.on_rig_silent(0.5);
    assert!(out.events.contains(&SequencerEvent::RigSilent { silent_s: 0.5, estop: false }), "{:?}", out.events);
    let held = out.setpoint.expect("the hold goes out at once");
    assert_eq!((held.slip_angle_deg, held.slip_ratio), (0.0, 0.0));
    assert_eq!(held.fz_n, last.fz_n, "the load stays: zero slip, not unloaded");
    assert_eq!(out.state.expect("state").phase, ProcedureState::PHASE_PAUSED);
    // The watchdog keeps firing while the rig is silent: nothing more happens.
    assert_eq!(h.seq.on_rig_silent(1.0).events, vec![]);
    // Without samples (thermal only), the hold stands.
    let o = h.tick();
    assert_eq!(o.setpoint.unwrap().slip_angle_deg, 0.0);

    // The rig answers again: the interrupted sweep's group restarts by itself.
    h.t += h.dt;
    let th = h.gate.state(h.t);
    let out = h.seq.step(h.t, Some(&th), Some(&rig_sample(h.t, &held)));
    h.gate.observe(h.t, &out);
    h.log.push((h.t, out.clone()));
    assert!(out.events.contains(&SequencerEvent::RigBack { resumed: true }), "{:?}", out.events);
    assert!(out.events.iter().any(|e| matches!(e, SequencerEvent::Resumed { .. })));
    h.run_until(1000.0, completed);
    let started = h.sweeps_started();
    assert_eq!(started.iter().filter(|n| **n == interrupted).count(), 2, "{started:?}");
}

/// With `estop_on_rig_silence` the silent rig is e-stopped instead; START resumes later.
#[test]
fn a_silent_rig_is_estopped_where_configured() {
    let cfg = SequencerConfig { estop_on_rig_silence: true, ..SequencerConfig::default() };
    let mut h = Harness::new(Sequencer::new(mini_plan(), cfg).unwrap(), 1.0);
    h.command(ProcedureCommand::START).unwrap();
    h.run_until(100.0, |o| o.setpoint.as_ref().is_some_and(|s| s.slip_angle_deg.abs() > 5.0));
    let out = h.seq.on_rig_silent(0.5);
    assert!(out.events.contains(&SequencerEvent::EStop));
    assert_eq!(out.setpoint.expect("safe at once").mode, RigSetpoint::MODE_SAFE);
    assert_eq!(out.state.expect("state").phase, ProcedureState::PHASE_ESTOP);
}

/// No fresh ThermalState while running raises ThermalLost once (within thermal_alarm_after_s of
/// rig time), never releases a pause, and ThermalBack follows when states come back.
#[test]
fn lost_thermal_state_alarms_once_and_recovers() {
    let mut s = Sequencer::new(mini_plan(), SequencerConfig::default()).unwrap();
    s.on_command(0.0, &cmd(ProcedureCommand::START)).unwrap();
    let fresh = |t: f64| ThermalState { header: Header::iso_w(t), ..ThermalState::default() };
    let mut t = 0.0;
    let mut lost_at = Vec::new();
    for i in 1..=300 {
        t = f64::from(i) * 0.01;
        // Fresh states for 1 s, then none.
        let th = (t <= 1.0).then(|| fresh(t));
        let o = s.step(t, th.as_ref(), None);
        for e in &o.events {
            if matches!(e, SequencerEvent::ThermalLost { .. }) {
                lost_at.push(t);
            }
            assert!(!matches!(e, SequencerEvent::ThermalPauseEnded { .. }));
        }
    }
    assert_eq!(lost_at.len(), 1, "{lost_at:?}");
    assert!(lost_at[0] > 1.5 && lost_at[0] <= 1.52, "{lost_at:?}");
    t += 0.01;
    let o = s.step(t, Some(&fresh(t)), None);
    assert!(o.events.contains(&SequencerEvent::ThermalBack));
}

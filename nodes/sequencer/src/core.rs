//! The sequencer's pure state machine: no I/O, no clock; time is the `now_s` argument.
//!
//! Life of a run: `Idle` → START → running steps of the plan in order. Each step streams its
//! trajectory; a step flagged `thermal_pause_after` is followed by a thermal pause (zero slip)
//! that ends only when a fresh `ThermalState` says `gate_open`. PAUSE ramps to zero slip and
//! holds; RESUME restarts the interrupted step's group (settle, free-rolling reference, sweep) —
//! a half-run sweep's data are useless. ABORT and ESTOP put the rig in its safe state (ESTOP at
//! once, in the command's own output); START afterwards resumes from the checkpoint.

use crate::config::{PlanKind, SequencerConfig};
use adaptive::model::ModelView;
use adaptive::{Library, MeasuredWearRate, Planner, PlannerState};
use procedure::plan::PlanEnvelopeError;
use procedure::primitives::thermal_pause_setpoint;
use procedure::setpoint::{EnvelopeViolation, PA_PER_BAR};
use procedure::sweep::{Keyframes, Trajectory};
use procedure::{Plan, RigMode, Setpoint, StepKind};
use serde::{Deserialize, Serialize};
use tyre_msgs::std_msgs::Header;
use tyre_msgs::{ProcedureCommand, ProcedureState, RigSample, RigSetpoint, ThermalState};

/// Why a command was refused (the state is unchanged).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum CommandRejected {
    /// START while a procedure runs or is paused.
    #[error("a procedure is already running")]
    AlreadyRunning,
    /// START after the procedure completed.
    #[error("the procedure is complete")]
    AlreadyComplete,
    /// START naming another procedure.
    #[error("START names `{requested}` but the loaded procedure is `{loaded}`")]
    WrongProcedure {
        /// Name in the command.
        requested: String,
        /// The plan's procedure.
        loaded: String,
    },
    /// PAUSE / ABORT with nothing running.
    #[error("no procedure is running")]
    NotRunning,
    /// RESUME while not paused.
    #[error("not paused")]
    NotPaused,
    /// An unknown command code.
    #[error("unknown command code {0}")]
    Unknown(u8),
}

/// Errors creating or resuming a sequencer.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SequencerError {
    /// The configuration is invalid.
    #[error(transparent)]
    Config(#[from] crate::config::ConfigError),
    /// The plan leaves the configured envelope.
    #[error(transparent)]
    Envelope(#[from] PlanEnvelopeError),
    /// The plan is empty.
    #[error("the plan has no steps")]
    EmptyPlan,
    /// The adaptive plan cannot be made from this procedure, or a checkpoint's adaptive part
    /// does not fit it.
    #[error("adaptive plan: {0}")]
    Adaptive(String),
    /// The checkpoint belongs to another plan.
    #[error(
        "checkpoint is for `{checkpoint_procedure}` (fingerprint {checkpoint_fingerprint:016x}), \
         not `{plan_procedure}` ({plan_fingerprint:016x})"
    )]
    CheckpointMismatch {
        /// Procedure in the checkpoint.
        checkpoint_procedure: String,
        /// Fingerprint in the checkpoint.
        checkpoint_fingerprint: u64,
        /// The plan's procedure.
        plan_procedure: String,
        /// The plan's fingerprint.
        plan_fingerprint: u64,
    },
}

/// Something that happened during a call.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "event", rename_all = "snake_case")]
pub enum SequencerEvent {
    /// The run started (or restarted) at `from_step`.
    Started {
        /// Procedure.
        procedure: String,
        /// First step run.
        from_step: usize,
        /// Whether this continues an earlier run (checkpoint or abort).
        resumed: bool,
    },
    /// A plan step began.
    StepStarted {
        /// Step index.
        index: usize,
        /// Step name.
        name: String,
        /// Step kind.
        kind: StepKind,
        /// Section name.
        section: String,
    },
    /// A data step (sweep, hold, warm-up) began.
    SweepStarted {
        /// Thesis-style name.
        name: String,
        /// 0-based index among data steps.
        sweep_index: u32,
        /// Section name.
        section: String,
        /// (Sub-)procedure.
        procedure: String,
        /// The thermal gate timed out before it: the tyre starts hot.
        started_hot: bool,
    },
    /// A data step ended.
    SweepEnded {
        /// Name.
        name: String,
        /// Index.
        sweep_index: u32,
        /// Section.
        section: String,
        /// Its duration \[s\].
        duration_s: f64,
    },
    /// A thermal pause began after `after_sweep`.
    ThermalPauseStarted {
        /// The sweep just finished.
        after_sweep: String,
    },
    /// The thermal gate released.
    ThermalPauseEnded {
        /// The sweep before the pause.
        after_sweep: String,
        /// Pause length \[s\].
        duration_s: f64,
        /// Released by the gate's time-out (the next sweep starts hot).
        timed_out: bool,
    },
    /// A tyre change began (`PHASE_TYRE_CHANGE` for its duration).
    TyreChange {
        /// Specimen being mounted.
        specimen: String,
        /// Planned rig time \[s\].
        duration_s: f64,
    },
    /// PAUSE obeyed.
    Paused,
    /// RESUME obeyed; the interrupted group restarts at `from_step`.
    Resumed {
        /// First step rerun.
        from_step: usize,
    },
    /// The run was aborted (by command or by a refused setpoint).
    Aborted {
        /// Why.
        reason: String,
    },
    /// Emergency stop.
    EStop,
    /// Every step done.
    Completed {
        /// Rig time of the whole run \[s\].
        elapsed_rig_time_s: f64,
    },
    /// A setpoint outside the envelope was not sent; the run was aborted.
    SetpointRefused {
        /// Step index.
        step: usize,
        /// What was outside.
        axis: String,
        /// Requested value.
        value: f64,
        /// Limit.
        limit: f64,
    },
    /// Progress advanced: write [`Sequencer::checkpoint`] now.
    CheckpointChanged,
    /// The rig sent nothing for `silent_s` (wall time, the shell's watchdog) while a procedure
    /// ran: the rig is held at zero slip (or e-stopped, `estop_on_rig_silence`).
    RigSilent {
        /// How long it had been silent \[s\].
        silent_s: f64,
        /// ESTOP rather than a zero-slip hold.
        estop: bool,
    },
    /// Samples flow again after [`SequencerEvent::RigSilent`]; `resumed`: the interrupted group
    /// restarts at once (else an operator RESUME does it).
    RigBack {
        /// Whether the run resumed by itself.
        resumed: bool,
    },
    /// No fresh `ThermalState` for `silent_s` of rig time while running: no sweep will be
    /// released until it comes back.
    ThermalLost {
        /// Rig time since the last fresh state (or the run's start) \[s\].
        silent_s: f64,
    },
    /// Fresh `ThermalState`s again after [`SequencerEvent::ThermalLost`].
    ThermalBack,
    /// The adaptive plan reached a slot: the caller must call [`Sequencer::plan_next`] with the
    /// live model (the rig holds at zero slip until then).
    PlanNeeded {
        /// The slot.
        slot: usize,
    },
    /// The adaptive plan chose the next sweep, and why.
    SweepChosen {
        /// The slot.
        slot: usize,
        /// The sweep's name.
        name: String,
        /// Predicted reduction of the mean squared predicted error, (% of peak)².
        value: f64,
        /// Predicted rig time to the end of its cool-down \[s\].
        cost_s: f64,
        /// Predicted tread it wears \[mm\] (its cost in the choice besides `cost_s`).
        wear_mm: f64,
        /// The wear rate that prediction used \[mm/MJ\] (configured, or weighed with the
        /// monitor's measurement: [`Sequencer::on_wear_rate`]).
        wear_rate_mm_per_mj: f64,
        /// Predicted error before it, % of peak.
        error_pct: f64,
        /// Predicted error after it, % of peak.
        error_after_pct: f64,
        /// The slot's stop target, % of peak.
        target_pct: f64,
        /// Why, in words.
        reason: String,
    },
    /// The adaptive plan closed a slot (the plan goes on with its fixed steps).
    SlotClosed {
        /// The slot.
        slot: usize,
        /// Sweeps it ran.
        sweeps: usize,
        /// Predicted error at the close, % of peak.
        error_pct: f64,
        /// Why, in words.
        reason: String,
    },
    /// The rig reports it refused a setpoint (`RigSample.FAULT_ENVELOPE`, rising edge): its
    /// envelope is tighter than the sequencer's configured one. The run goes on; the data of
    /// the present step are suspect.
    RigRefusedSetpoint {
        /// Step running when the rig reported it.
        step: usize,
    },
}

/// What one call produced.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct SequencerOutput {
    /// Setpoint to publish now (None while idle or complete).
    pub setpoint: Option<RigSetpoint>,
    /// State to publish (on change, and every `state_period_s`).
    pub state: Option<ProcedureState>,
    /// Events, in order.
    pub events: Vec<SequencerEvent>,
}

/// Persistent progress (the shell writes it to disk as JSON or TOML).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Checkpoint {
    /// Plan procedure name.
    pub procedure: String,
    /// [`Plan::fingerprint`]: resume refuses another plan.
    pub plan_fingerprint: u64,
    /// Step to run first on resume (the start of the interrupted group).
    pub next_step: usize,
    /// Start with a thermal pause (the run stopped while waiting on the gate).
    pub thermal_pause_first: bool,
    /// Steps completed.
    pub completed_steps: usize,
    /// Rig time used so far \[s\].
    pub elapsed_rig_time_s: f64,
    /// The whole plan is done.
    pub complete: bool,
    /// The adaptive plan's decisions so far (`plan = "adaptive"`), so a resumed run rebuilds the
    /// same plan and continues the same decisions.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub adaptive: Option<AdaptiveCheckpoint>,
}

/// The adaptive part of a [`Checkpoint`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct AdaptiveCheckpoint {
    /// Fingerprint of the fixed plan (the procedure without its candidates).
    pub fixed_fingerprint: u64,
    /// Every candidate inserted, in order, with where the rig was (its group is built from it).
    pub insertions: Vec<Insertion>,
    /// The planner's decisions.
    pub planner: PlannerState,
    /// Observed thermal pauses so far and the pause model's estimate of the same pauses \[s\]:
    /// their ratio scales the predicted cool-downs, so it must survive a resume too.
    #[serde(default)]
    pub pause_sum_s: f64,
    /// See `pause_sum_s`.
    #[serde(default)]
    pub pause_model_sum_s: f64,
}

/// One inserted candidate.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Insertion {
    /// The slot.
    pub slot: usize,
    /// The candidate id.
    pub candidate: usize,
    /// The rig's setpoint its group starts from.
    pub from: Setpoint,
    /// Why the planner chose it (its `ProcedureState.plan_reason`; empty in older checkpoints).
    #[serde(default)]
    pub reason: String,
    /// The predicted error after it, % of peak (0 in older checkpoints).
    #[serde(default)]
    pub error_after_pct: f64,
}

/// The adaptive plan's state inside the sequencer.
#[derive(Debug, Clone)]
struct AdaptiveRun {
    planner: Planner,
    /// Index in the running plan of the step each slot's sweeps go before.
    slot_at: Vec<usize>,
    insertions: Vec<Insertion>,
    fixed_fingerprint: u64,
}

/// Where inside a running plan we are.
#[derive(Debug, Clone, PartialEq)]
enum Run {
    /// A ramp the sequencer built (after START/RESUME) to the start of `cursor`'s step, or,
    /// with `pause_after`, to the thermal-pause hold after `cursor`'s step.
    Transition { traj: Trajectory, t0: f64, pause_after: bool },
    /// Streaming step `cursor` since `t0`.
    Step { t0: f64 },
    /// Waiting on the thermal gate after step `cursor`.
    ThermalPause { t0: f64, sp: Setpoint },
    /// Holding `sp` until the adaptive plan decides what runs at step `at` (slot `slot`).
    AwaitPlan { sp: Setpoint, at: usize, slot: usize },
}

#[derive(Debug, Clone, PartialEq)]
enum State {
    Idle,
    Running(Run),
    Paused { hold: Box<Trajectory>, t0: f64, was: Run },
    Aborted,
    EStop,
    Complete,
}

/// The sequencer.
#[derive(Debug, Clone)]
pub struct Sequencer {
    plan: Plan,
    cfg: SequencerConfig,
    state: State,
    /// Current step (or the step a pause follows).
    cursor: usize,
    /// First step of the next run (Idle/Aborted/EStop).
    restart_at: usize,
    /// The next run starts with a thermal pause.
    restart_with_pause: bool,
    completed_steps: usize,
    seq: u64,
    last_setpoint: Option<Setpoint>,
    last_sample: Option<Setpoint>,
    /// Rig time accumulated by earlier runs \[s\].
    elapsed_before_s: f64,
    run_started_s: Option<f64>,
    frozen_elapsed_s: Option<f64>,
    started_hot: bool,
    next_started_hot: bool,
    /// Observed pause time, and the model's estimate for the same pauses \[s\].
    pause_sum_s: f64,
    pause_model_sum_s: f64,
    /// The model's pause estimate after each step \[s\].
    pause_estimates_s: Vec<f64>,
    /// Why each step runs, for the adaptive plan's chosen steps: (reason, predicted error after
    /// it, % of peak); `None` for the procedure's own steps.
    step_reasons: Vec<Option<(String, f64)>>,
    predicted_wait_s: Option<f64>,
    last_state_s: Option<f64>,
    last_state_key: Option<(u8, usize)>,
    resumed: bool,
    /// Rig time of the latest call (checkpoints are taken between calls).
    last_now_s: f64,
    /// The last sample carried FAULT_ENVELOPE (events fire on the rising edge).
    rig_envelope_fault: bool,
    /// The pause in force was entered because the rig went silent (lifted by its next sample).
    fault_hold: bool,
    /// A [`SequencerEvent::ThermalLost`] is in force.
    thermal_lost: bool,
    /// Rig time of the last fresh `ThermalState`.
    thermal_fresh_at: Option<f64>,
    /// The adaptive plan (`plan = "adaptive"`).
    adaptive: Option<AdaptiveRun>,
}

fn phase_of_kind(kind: StepKind) -> u8 {
    match kind {
        StepKind::Sweep | StepKind::Hold | StepKind::WarmUp => ProcedureState::PHASE_SWEEP,
        StepKind::Settle | StepKind::PressureChange => ProcedureState::PHASE_SETTLE,
        StepKind::FreeRollingRef => ProcedureState::PHASE_FREE_ROLLING_REF,
        StepKind::TyreChange => ProcedureState::PHASE_TYRE_CHANGE,
    }
}

fn safe_setpoint() -> Setpoint {
    Setpoint { mode: RigMode::Safe, ..Setpoint::default() }
}

fn sample_setpoint(s: &RigSample) -> Setpoint {
    let mode = match s.rig_mode {
        RigSetpoint::MODE_COUPLED => RigMode::Coupled,
        RigSetpoint::MODE_STATIC => RigMode::Static,
        RigSetpoint::MODE_SAFE => RigMode::Safe,
        _ => RigMode::FreeRolling,
    };
    Setpoint {
        mode,
        slip_angle_deg: s.slipangl_deg,
        slip_ratio: s.longslip,
        fz_n: s.fzw_n,
        camber_deg: s.inclangl_deg,
        pressure_bar: s.inflpres_pa / PA_PER_BAR,
        speed_mps: s.trajvelw_mps,
        belt_displacement_m: 0.0,
    }
}

impl Sequencer {
    /// A sequencer for `plan`, idle at its first step. Refuses a plan outside `cfg.envelope`.
    pub fn new(plan: Plan, cfg: SequencerConfig) -> Result<Self, SequencerError> {
        cfg.validate()?;
        if plan.steps.is_empty() {
            return Err(SequencerError::EmptyPlan);
        }
        plan.check_envelope(&cfg.envelope)?;
        let pause_estimates_s = plan.steps.iter().map(|s| cfg.pause_model.pause_after_s(s)).collect();
        let n_steps = plan.steps.len();
        Ok(Self {
            plan,
            cfg,
            state: State::Idle,
            cursor: 0,
            restart_at: 0,
            restart_with_pause: false,
            completed_steps: 0,
            seq: 0,
            last_setpoint: None,
            last_sample: None,
            elapsed_before_s: 0.0,
            run_started_s: None,
            frozen_elapsed_s: None,
            started_hot: false,
            next_started_hot: false,
            pause_sum_s: 0.0,
            pause_model_sum_s: 0.0,
            step_reasons: vec![None; n_steps],
            pause_estimates_s,
            predicted_wait_s: None,
            last_state_s: None,
            last_state_key: None,
            resumed: false,
            last_now_s: 0.0,
            rig_envelope_fault: false,
            fault_hold: false,
            thermal_lost: false,
            thermal_fresh_at: None,
            adaptive: None,
        })
    }

    /// The sequencer `cfg.plan` asks for: [`Sequencer::new`] or [`Sequencer::new_adaptive`].
    pub fn for_config(plan: Plan, cfg: SequencerConfig) -> Result<Self, SequencerError> {
        match cfg.plan {
            PlanKind::Fixed => Self::new(plan, cfg),
            PlanKind::Adaptive => Self::new_adaptive(plan, cfg),
        }
    }

    /// [`Sequencer::resume`] or [`Sequencer::resume_adaptive`], as `cfg.plan` asks.
    pub fn resume_for_config(plan: Plan, cfg: SequencerConfig, cp: &Checkpoint) -> Result<Self, SequencerError> {
        match cfg.plan {
            PlanKind::Fixed => Self::resume(plan, cfg, cp),
            PlanKind::Adaptive => Self::resume_adaptive(plan, cfg, cp),
        }
    }

    /// An adaptive sequencer (`docs/adaptive-plan.md`): `plan` (the expanded procedure) is cut
    /// into its fixed steps and a candidate library ([`adaptive::Library`]); the fixed steps run
    /// in order, and at each slot the sequencer raises [`SequencerEvent::PlanNeeded`] and holds
    /// until [`Sequencer::plan_next`] decides. Every candidate is checked against the envelope
    /// here, so no chosen sweep can leave it.
    pub fn new_adaptive(plan: Plan, cfg: SequencerConfig) -> Result<Self, SequencerError> {
        cfg.validate()?;
        plan.check_envelope(&cfg.envelope)?;
        let lib = Library::from_plan(&plan, &cfg.pause_model, &cfg.envelope, &cfg.adaptive)
            .map_err(|e| SequencerError::Adaptive(e.to_string()))?;
        let mut s = Self::new(lib.fixed.clone(), cfg)?;
        s.adaptive = Some(AdaptiveRun {
            slot_at: lib.slots.iter().map(|x| x.at).collect(),
            insertions: Vec::new(),
            fixed_fingerprint: lib.fixed.fingerprint(),
            planner: Planner::new(lib, cfg.adaptive),
        });
        Ok(s)
    }

    /// An adaptive sequencer continuing from `checkpoint`: the same insertions rebuild the same
    /// plan, the planner continues from its decisions, the run restarts where it stopped.
    pub fn resume_adaptive(plan: Plan, cfg: SequencerConfig, checkpoint: &Checkpoint) -> Result<Self, SequencerError> {
        let mut s = Self::new_adaptive(plan, cfg)?;
        let Some(cp) = checkpoint.adaptive.as_ref() else {
            return Err(SequencerError::Adaptive("the checkpoint is not of an adaptive run".into()));
        };
        let a = s.adaptive.as_ref().expect("new_adaptive sets it");
        if cp.fixed_fingerprint != a.fixed_fingerprint {
            return Err(SequencerError::Adaptive(format!(
                "the checkpoint's fixed plan ({:016x}) is not this procedure's ({:016x})",
                cp.fixed_fingerprint, a.fixed_fingerprint
            )));
        }
        let n_cand = a.planner.library().candidates.len();
        let n_slot = a.slot_at.len();
        for ins in &cp.insertions {
            if ins.candidate >= n_cand || ins.slot >= n_slot {
                return Err(SequencerError::Adaptive(format!(
                    "checkpoint inserts candidate {} in slot {}: not in this library",
                    ins.candidate, ins.slot
                )));
            }
            s.insert_candidate(ins.slot, ins.candidate, ins.from, ins.reason.clone(), ins.error_after_pct);
        }
        let a = s.adaptive.as_mut().expect("new_adaptive sets it");
        let lib = a.planner.library().clone();
        a.planner = Planner::restore(lib, cfg.adaptive, cp.planner.clone())
            .map_err(|e| SequencerError::Adaptive(e.to_string()))?;
        s.pause_sum_s = cp.pause_sum_s;
        s.pause_model_sum_s = cp.pause_model_sum_s;
        s.check_checkpoint(checkpoint)?;
        s.position(checkpoint);
        Ok(s)
    }

    /// Where the plan has the rig when the sweeps of the slot before step `at` begin: the end of
    /// step `at − 1` (its thermal-pause hold when a pause follows it). Decisions are taken from
    /// here, not from the measured state, so a resumed run decides as the original did.
    fn slot_from(&self, at: usize) -> Setpoint {
        match at.checked_sub(1).and_then(|i| self.plan.steps.get(i)) {
            Some(prev) if prev.thermal_pause_after => thermal_pause_setpoint(&prev.trajectory.end()),
            Some(prev) => prev.trajectory.end(),
            None => self.plan.steps[0].trajectory.start(),
        }
    }

    /// The adaptive planner (its library and decisions), for an adaptive sequencer.
    pub fn planner(&self) -> Option<&Planner> {
        self.adaptive.as_ref().map(|a| &a.planner)
    }

    /// The wear rate the monitor measured on the tyre under test: the adaptive plan prices
    /// the tread of the sweeps it chooses from then on with it (weighed against the configured
    /// rate, [`Planner::wear_rate_mm_per_mj`]). The rate belongs to the tyre's construction, so
    /// it stays over a tyre change until the monitor measures the new specimen. Ignored by a
    /// fixed plan; true when the planner took it.
    pub fn on_wear_rate(&mut self, rate: MeasuredWearRate) -> bool {
        self.adaptive.as_mut().is_some_and(|a| a.planner.on_measured_wear_rate(rate))
    }

    /// The slot waiting for [`Sequencer::plan_next`], if any.
    pub fn awaiting_plan(&self) -> Option<usize> {
        match &self.state {
            State::Running(Run::AwaitPlan { slot, .. }) => Some(*slot),
            _ => None,
        }
    }

    /// The open slot whose sweeps go before step `i`.
    fn open_slot_at(&self, i: usize) -> Option<usize> {
        let a = self.adaptive.as_ref()?;
        a.slot_at.iter().position(|&at| at == i).filter(|&slot| !a.planner.is_closed(slot))
    }

    /// Inserts candidate `id`'s group (built from `from`) before slot `slot`'s next step; every
    /// step of it carries the planner's `reason` and predicted error after it.
    fn insert_candidate(&mut self, slot: usize, id: usize, from: Setpoint, reason: String, error_after_pct: f64) {
        let Some(a) = self.adaptive.as_mut() else { return };
        let Some(cand) = a.planner.library().candidate(id) else { return };
        let mut group = cand.group(from, &a.planner.library().limits);
        let at = a.slot_at[slot];
        let k = group.len();
        for st in &mut self.plan.steps[at..] {
            st.index += k;
            if st.restart_from >= at {
                st.restart_from += k;
            }
        }
        for st in &mut group {
            st.index += at;
            st.restart_from += at;
        }
        let estimates: Vec<f64> = group.iter().map(|s| self.cfg.pause_model.pause_after_s(s)).collect();
        self.plan.steps.splice(at..at, group);
        self.pause_estimates_s.splice(at..at, estimates);
        self.step_reasons.splice(at..at, std::iter::repeat_n(Some((reason.clone(), error_after_pct)), k));
        let mut data = 0u32;
        for st in &mut self.plan.steps {
            st.sweep_index = st.kind.is_data().then(|| {
                data += 1;
                data - 1
            });
        }
        for s_at in &mut a.slot_at {
            if *s_at >= at {
                *s_at += k;
            }
        }
        a.insertions.push(Insertion { slot, candidate: id, from, reason, error_after_pct });
    }

    /// The adaptive plan's decision at the slot it waits on, with the live model `view` (an
    /// [`adaptive::FitView`] of the latest fit, or [`adaptive::model::NoModel`]): the chosen
    /// sweep's group is inserted and runs at once, or the slot closes and the fixed plan goes
    /// on. Does nothing unless [`Sequencer::awaiting_plan`].
    pub fn plan_next(&mut self, now_s: f64, view: &dyn ModelView) -> SequencerOutput {
        let mut out = SequencerOutput::default();
        self.last_now_s = now_s;
        let State::Running(Run::AwaitPlan { sp, at, slot }) = self.state.clone() else {
            return out;
        };
        let scale = if self.pause_model_sum_s > 0.0 { self.pause_sum_s / self.pause_model_sum_s } else { 1.0 };
        let from = self.slot_from(at);
        let Some(a) = self.adaptive.as_mut() else { return out };
        let d = a.planner.decide(slot, from, view, scale);
        match d.candidate {
            Some(id) => {
                self.insert_candidate(slot, id, from, d.reason.clone(), d.error_after_pct);
                out.events.push(SequencerEvent::SweepChosen {
                    slot,
                    name: d.name.clone(),
                    value: d.value,
                    cost_s: d.cost_s,
                    wear_mm: d.wear_mm,
                    wear_rate_mm_per_mj: d.wear_rate_mm_per_mj,
                    error_pct: d.error_pct,
                    error_after_pct: d.error_after_pct,
                    target_pct: d.target_pct,
                    reason: d.reason.clone(),
                });
            }
            None => {
                let sweeps = a.insertions.iter().filter(|i| i.slot == slot).count();
                out.events.push(SequencerEvent::SlotClosed { slot, sweeps, error_pct: d.error_pct, reason: d.reason });
            }
        }
        out.events.push(SequencerEvent::CheckpointChanged);
        // Ramp from the hold the sequencer commanded (in a run that did not stop, where the
        // chosen group was built from): a measured sample differs in every axis by noise (its
        // pressure alone would make the ramp a 20 s pressure change).
        self.begin_at_from(now_s, at, false, Some(sp), &mut out);
        self.emit(now_s, &mut out, true);
        out
    }

    /// Hold `hold` until the adaptive plan decides what runs at step `at`.
    fn await_plan(&mut self, at: usize, slot: usize, hold: Setpoint) {
        self.cursor = at.saturating_sub(1).min(self.plan.steps.len() - 1);
        self.state = State::Running(Run::AwaitPlan { sp: hold, at, slot });
        // `step` raises PlanNeeded on every call until the plan is decided (level, not edge:
        // a START or RESUME that lands on a slot is answered at the next control tick).
    }

    /// Move on to step `next` (after a step or a thermal pause ended at `t0`; `hold` is where
    /// the rig is): a slot's decision first if one is open there, else the step, else complete.
    fn advance(&mut self, t0: f64, now_s: f64, next: usize, hold: Setpoint, out: &mut SequencerOutput) {
        if let Some(slot) = self.open_slot_at(next) {
            out.events.push(SequencerEvent::CheckpointChanged);
            self.last_setpoint = Some(hold);
            self.await_plan(next, slot, hold);
        } else if next >= self.plan.steps.len() {
            self.last_setpoint = Some(hold);
            self.complete(now_s, out);
        } else {
            self.cursor = next;
            self.enter_step(t0, out);
        }
    }

    /// A sequencer that continues from `checkpoint`: idle, positioned at the interrupted
    /// group; START runs it without repeating completed steps.
    pub fn resume(plan: Plan, cfg: SequencerConfig, checkpoint: &Checkpoint) -> Result<Self, SequencerError> {
        let mut s = Self::new(plan, cfg)?;
        s.check_checkpoint(checkpoint)?;
        s.position(checkpoint);
        Ok(s)
    }

    fn check_checkpoint(&self, checkpoint: &Checkpoint) -> Result<(), SequencerError> {
        let plan = &self.plan;
        if checkpoint.procedure != plan.procedure || checkpoint.plan_fingerprint != plan.fingerprint() {
            return Err(SequencerError::CheckpointMismatch {
                checkpoint_procedure: checkpoint.procedure.clone(),
                checkpoint_fingerprint: checkpoint.plan_fingerprint,
                plan_procedure: plan.procedure.clone(),
                plan_fingerprint: plan.fingerprint(),
            });
        }
        Ok(())
    }

    /// Idle at the checkpoint's interrupted group.
    fn position(&mut self, checkpoint: &Checkpoint) {
        let s = self;
        let n = s.plan.steps.len();
        s.restart_at = checkpoint.next_step.min(n);
        s.cursor = s.restart_at.min(n - 1);
        s.restart_with_pause = checkpoint.thermal_pause_first;
        s.completed_steps = checkpoint.completed_steps.min(n);
        s.elapsed_before_s = checkpoint.elapsed_rig_time_s.max(0.0);
        s.resumed = true;
        if checkpoint.complete || (s.restart_at >= n && s.open_slot_at(n).is_none()) {
            s.state = State::Complete;
            s.frozen_elapsed_s = Some(s.elapsed_before_s);
        }
    }

    /// Replace the envelope at run time (e.g. a rig interlock lowers the load limit): setpoints
    /// outside the new envelope are refused from the next call on, which aborts the run.
    pub fn set_envelope(&mut self, envelope: procedure::RigLimits) {
        self.cfg.envelope = envelope;
    }

    /// The plan.
    pub fn plan(&self) -> &Plan {
        &self.plan
    }

    /// Progress to persist.
    pub fn checkpoint(&self) -> Checkpoint {
        let (next_step, thermal_pause_first) = match &self.state {
            State::Idle | State::Aborted | State::EStop => (self.restart_at, self.restart_with_pause),
            State::Complete => (self.plan.steps.len(), false),
            State::Running(run) | State::Paused { was: run, .. } => self.restart_point(run),
        };
        Checkpoint {
            procedure: self.plan.procedure.clone(),
            plan_fingerprint: self.plan.fingerprint(),
            next_step,
            thermal_pause_first,
            completed_steps: self.completed_steps,
            elapsed_rig_time_s: self.elapsed_at(self.last_now_s),
            complete: self.state == State::Complete,
            adaptive: self.adaptive.as_ref().map(|a| AdaptiveCheckpoint {
                fixed_fingerprint: a.fixed_fingerprint,
                insertions: a.insertions.clone(),
                planner: a.planner.state().clone(),
                pause_sum_s: self.pause_sum_s,
                pause_model_sum_s: self.pause_model_sum_s,
            }),
        }
    }

    /// Where a run interrupted in `run` restarts.
    fn restart_point(&self, run: &Run) -> (usize, bool) {
        match run {
            Run::ThermalPause { .. } | Run::Transition { pause_after: true, .. } => (self.cursor + 1, true),
            Run::AwaitPlan { at, .. } => (*at, false),
            Run::Transition { .. } | Run::Step { .. } => {
                let step = &self.plan.steps[self.cursor];
                (step.restart_from.min(self.cursor), false)
            }
        }
    }

    fn elapsed_at(&self, now_s: f64) -> f64 {
        if let Some(f) = self.frozen_elapsed_s {
            return f;
        }
        match self.run_started_s {
            Some(t0) => self.elapsed_before_s + (now_s - t0).max(0.0),
            None => self.elapsed_before_s,
        }
    }

    /// Obey an operator command. The output carries what to publish at once (ESTOP: the safe
    /// setpoint, without waiting for the next control tick).
    pub fn on_command(&mut self, now_s: f64, cmd: &ProcedureCommand) -> Result<SequencerOutput, CommandRejected> {
        let mut out = SequencerOutput::default();
        self.last_now_s = now_s;
        match cmd.command {
            ProcedureCommand::START => self.start(now_s, &cmd.procedure, &mut out)?,
            ProcedureCommand::PAUSE => {
                let State::Running(run) = &self.state else {
                    return Err(CommandRejected::NotRunning);
                };
                let run = run.clone();
                let from = self.last_setpoint.unwrap_or_else(|| self.step_start_sp());
                let hold = self.ramp_to_zero_slip(from);
                self.state = State::Paused { hold: Box::new(hold), t0: now_s, was: run };
                out.events.push(SequencerEvent::Paused);
            }
            ProcedureCommand::RESUME => {
                let State::Paused { was, .. } = &self.state else {
                    return Err(CommandRejected::NotPaused);
                };
                let was = was.clone();
                match was {
                    // A thermal pause goes on where it was: the tyre kept cooling.
                    Run::ThermalPause { t0, sp } => {
                        self.state = State::Running(Run::ThermalPause { t0, sp });
                        out.events.push(SequencerEvent::Resumed { from_step: self.cursor + 1 });
                    }
                    other => {
                        let (from_step, pause_first) = self.restart_point(&other);
                        out.events.push(SequencerEvent::Resumed { from_step });
                        self.begin_at(now_s, from_step, pause_first, &mut out);
                    }
                }
            }
            ProcedureCommand::ABORT => {
                match &self.state {
                    State::Running(run) | State::Paused { was: run, .. } => {
                        let (at, pause) = self.restart_point(&run.clone());
                        self.stop(now_s, at, pause);
                    }
                    _ => return Err(CommandRejected::NotRunning),
                }
                self.state = State::Aborted;
                out.events.push(SequencerEvent::Aborted { reason: format!("operator `{}`", cmd.operator_name) });
                out.events.push(SequencerEvent::CheckpointChanged);
            }
            ProcedureCommand::ESTOP => {
                // Always obeyed, from any state.
                if let State::Running(run) | State::Paused { was: run, .. } = &self.state {
                    let (at, pause) = self.restart_point(&run.clone());
                    self.stop(now_s, at, pause);
                    out.events.push(SequencerEvent::CheckpointChanged);
                }
                self.state = State::EStop;
                out.events.push(SequencerEvent::EStop);
            }
            other => return Err(CommandRejected::Unknown(other)),
        }
        if matches!(self.state, State::Aborted | State::EStop) {
            // Safe state at once: the shell publishes this without waiting for the next tick.
            out.setpoint = Some(self.setpoint_msg(now_s, &safe_setpoint()));
        }
        self.emit(now_s, &mut out, true);
        Ok(out)
    }

    /// The shell's watchdog: the rig has sent no sample for `silent_s` (wall time). A running
    /// procedure is held at once — zero slip at the present load and speed (the setpoint is in
    /// this call's output), or ESTOP with `estop_on_rig_silence`. Rig time stands still while
    /// the rig is silent, so the hold is stamped with the last sample's time. Idempotent.
    pub fn on_rig_silent(&mut self, silent_s: f64) -> SequencerOutput {
        let mut out = SequencerOutput::default();
        let now_s = self.last_now_s;
        let State::Running(run) = &self.state else {
            return out;
        };
        let run = run.clone();
        if self.cfg.estop_on_rig_silence {
            let (at, pause) = self.restart_point(&run);
            self.stop(now_s, at, pause);
            self.state = State::EStop;
            out.events.push(SequencerEvent::RigSilent { silent_s, estop: true });
            out.events.push(SequencerEvent::EStop);
            out.events.push(SequencerEvent::CheckpointChanged);
            out.setpoint = Some(self.setpoint_msg(now_s, &safe_setpoint()));
        } else {
            let from = self.last_setpoint.unwrap_or_else(|| self.step_start_sp());
            let mut hold = from.zero_slip();
            if hold.mode == RigMode::Static {
                hold.mode = RigMode::FreeRolling;
            }
            self.state =
                State::Paused { hold: Box::new(Trajectory::Keyframes(Keyframes::start(hold))), t0: now_s, was: run };
            self.fault_hold = true;
            out.events.push(SequencerEvent::RigSilent { silent_s, estop: false });
            out.events.push(SequencerEvent::Paused);
            self.last_setpoint = Some(hold);
            out.setpoint = Some(self.setpoint_msg(now_s, &hold));
        }
        self.emit(now_s, &mut out, true);
        out
    }

    /// Samples came back after a fault hold: rerun the interrupted group (as RESUME does), unless
    /// configured to wait for the operator or the rig's clock went back (a restarted rig).
    fn rig_back(&mut self, prev_now_s: f64, now_s: f64, out: &mut SequencerOutput) {
        self.fault_hold = false;
        let State::Paused { was, .. } = self.state.clone() else {
            return;
        };
        let restarted = now_s + 1.0 < prev_now_s;
        let resume = self.cfg.resume_after_rig_silence && !restarted;
        out.events.push(SequencerEvent::RigBack { resumed: resume });
        if !resume {
            return;
        }
        match was {
            Run::ThermalPause { t0, sp } => {
                self.state = State::Running(Run::ThermalPause { t0, sp });
                out.events.push(SequencerEvent::Resumed { from_step: self.cursor + 1 });
            }
            other => {
                let (from_step, pause_first) = self.restart_point(&other);
                out.events.push(SequencerEvent::Resumed { from_step });
                self.begin_at(now_s, from_step, pause_first, out);
            }
        }
    }

    /// Raises [`SequencerEvent::ThermalLost`] / [`SequencerEvent::ThermalBack`] on the edges.
    fn watch_thermal(&mut self, now_s: f64, thermal: Option<&ThermalState>, out: &mut SequencerOutput) {
        let fresh = thermal.is_some_and(|th| now_s - th.header.stamp.as_secs_f64() <= self.cfg.thermal_alarm_after_s);
        if fresh {
            self.thermal_fresh_at = Some(now_s);
            if self.thermal_lost {
                self.thermal_lost = false;
                out.events.push(SequencerEvent::ThermalBack);
            }
            return;
        }
        let running = matches!(self.state, State::Running(_) | State::Paused { .. });
        if !running || self.thermal_lost {
            return;
        }
        let since = self.thermal_fresh_at.into_iter().chain(self.run_started_s).fold(f64::NEG_INFINITY, f64::max);
        if since.is_finite() && now_s - since > self.cfg.thermal_alarm_after_s {
            self.thermal_lost = true;
            out.events.push(SequencerEvent::ThermalLost { silent_s: now_s - since });
        }
    }

    fn stop(&mut self, now_s: f64, at: usize, pause: bool) {
        self.restart_at = at;
        self.restart_with_pause = pause;
        self.cursor = at.min(self.plan.steps.len() - 1);
        self.elapsed_before_s = self.elapsed_at(now_s);
        self.frozen_elapsed_s = Some(self.elapsed_before_s);
        self.run_started_s = None;
    }

    fn start(&mut self, now_s: f64, requested: &str, out: &mut SequencerOutput) -> Result<(), CommandRejected> {
        match self.state {
            State::Running(_) | State::Paused { .. } => return Err(CommandRejected::AlreadyRunning),
            State::Complete => return Err(CommandRejected::AlreadyComplete),
            State::Idle | State::Aborted | State::EStop => {}
        }
        let stem =
            std::path::Path::new(requested).file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
        if !requested.is_empty() && requested != self.plan.procedure && stem != self.plan.procedure {
            return Err(CommandRejected::WrongProcedure {
                requested: requested.to_owned(),
                loaded: self.plan.procedure.clone(),
            });
        }
        let resumed = self.resumed || !matches!(self.state, State::Idle);
        self.resumed = true;
        self.frozen_elapsed_s = None;
        self.run_started_s = Some(now_s);
        out.events.push(SequencerEvent::Started {
            procedure: self.plan.procedure.clone(),
            from_step: self.restart_at,
            resumed,
        });
        let (at, pause) = (self.restart_at, self.restart_with_pause);
        self.begin_at(now_s, at, pause, out);
        Ok(())
    }

    /// Keep a measured state inside the envelope before ramping from it (a parked rig reports
    /// no load; the first commanded load is the envelope's minimum).
    fn clamp_to_envelope(&self, mut sp: Setpoint) -> Setpoint {
        let e = &self.cfg.envelope;
        let c = |x: f64, lo: f64, hi: f64| if x.is_finite() { x.clamp(lo, hi) } else { lo.max(0.0).min(hi) };
        sp.slip_angle_deg = c(sp.slip_angle_deg, -e.max_slip_angle_deg, e.max_slip_angle_deg);
        sp.slip_ratio = c(sp.slip_ratio, -e.max_slip_ratio, e.max_slip_ratio);
        sp.fz_n = c(sp.fz_n, e.min_fz_n, e.max_fz_n);
        sp.camber_deg = c(sp.camber_deg, -e.max_camber_deg, e.max_camber_deg);
        sp.pressure_bar = c(sp.pressure_bar, e.min_pressure_bar, e.max_pressure_bar);
        sp.speed_mps = c(sp.speed_mps, 0.0, e.max_speed_mps);
        sp.belt_displacement_m = c(sp.belt_displacement_m, -e.max_belt_displacement_m, e.max_belt_displacement_m);
        sp
    }

    /// Run from step `at` (after a thermal pause if `pause_first`). When the rig's state is
    /// known (last sample or setpoint), ramp from it to where the plan expects the rig; a
    /// settle at `at` is folded into that ramp.
    fn begin_at(&mut self, now_s: f64, at: usize, pause_first: bool, out: &mut SequencerOutput) {
        let from = self.last_sample.or(self.last_setpoint);
        self.begin_at_from(now_s, at, pause_first, from, out);
    }

    /// [`Self::begin_at`] ramping from `from` (`None`: the rig's state is unknown).
    fn begin_at_from(
        &mut self,
        now_s: f64,
        at: usize,
        pause_first: bool,
        from: Option<Setpoint>,
        out: &mut SequencerOutput,
    ) {
        if !pause_first && let Some(slot) = self.open_slot_at(at) {
            let from = from.unwrap_or_else(|| self.plan.steps[0].trajectory.start());
            let mut hold = self.clamp_to_envelope(from).zero_slip();
            if matches!(hold.mode, RigMode::Static | RigMode::Safe) {
                hold.mode = RigMode::FreeRolling;
            }
            self.last_setpoint = Some(hold);
            self.await_plan(at, slot, hold);
            return;
        }
        let steps = &self.plan.steps;
        let n = steps.len();
        if at >= n {
            self.complete(now_s, out);
            return;
        }
        let (cursor, target, pause) = if pause_first && at > 0 {
            (at - 1, thermal_pause_setpoint(&steps[at - 1].trajectory.end()), true)
        } else if steps[at].kind == StepKind::Settle && at + 1 < n && from.is_some() {
            (at + 1, steps[at].trajectory.end(), false)
        } else {
            (at, steps[at].trajectory.start(), false)
        };
        self.cursor = cursor;
        match from {
            Some(from) if target.mode != RigMode::Safe => {
                let mut from = self.clamp_to_envelope(from);
                if from.mode == RigMode::Safe {
                    from.mode = target.mode;
                }
                let traj = procedure::primitives::settle(from, target, &self.cfg.envelope).trajectory;
                self.state = State::Running(Run::Transition { traj, t0: now_s, pause_after: pause });
            }
            _ if pause => self.enter_pause(now_s, target, out),
            _ => self.enter_step(now_s, out),
        }
    }

    fn enter_pause(&mut self, t0: f64, sp: Setpoint, out: &mut SequencerOutput) {
        out.events.push(SequencerEvent::ThermalPauseStarted { after_sweep: self.plan.steps[self.cursor].name.clone() });
        self.state = State::Running(Run::ThermalPause { t0, sp });
    }

    fn step_start_sp(&self) -> Setpoint {
        self.plan.steps[self.cursor].trajectory.start()
    }

    /// Pause hold: slip to zero at half the rig's fastest slip rates, then hold.
    fn ramp_to_zero_slip(&self, from: Setpoint) -> Trajectory {
        let lim = &self.cfg.envelope;
        let t = (from.slip_angle_deg.abs() / (0.5 * lim.max_slip_angle_rate_dps))
            .max(from.slip_ratio.abs() / (0.5 * lim.max_slip_ratio_rate_ps))
            .max(from.belt_displacement_m.abs() / 0.05);
        let mut to = from.zero_slip();
        if to.mode == RigMode::Static {
            to.mode = RigMode::FreeRolling;
        }
        Trajectory::Keyframes(Keyframes::start(from).to(t, to))
    }

    fn enter_step(&mut self, t0: f64, out: &mut SequencerOutput) {
        let step = &self.plan.steps[self.cursor];
        let section = self.section_name(step.section_index);
        out.events.push(SequencerEvent::StepStarted {
            index: step.index,
            name: step.name.clone(),
            kind: step.kind,
            section: section.clone(),
        });
        if let Some(sweep_index) = step.sweep_index {
            self.started_hot = self.next_started_hot;
            self.next_started_hot = false;
            out.events.push(SequencerEvent::SweepStarted {
                name: step.name.clone(),
                sweep_index,
                section,
                procedure: step.procedure.clone(),
                started_hot: self.started_hot,
            });
        }
        if step.kind == StepKind::TyreChange {
            out.events
                .push(SequencerEvent::TyreChange { specimen: step.specimen.clone(), duration_s: step.duration_s });
        }
        self.state = State::Running(Run::Step { t0 });
    }

    fn complete(&mut self, now_s: f64, out: &mut SequencerOutput) {
        self.state = State::Complete;
        self.restart_at = self.plan.steps.len();
        self.elapsed_before_s = self.elapsed_at(now_s);
        self.frozen_elapsed_s = Some(self.elapsed_before_s);
        out.events.push(SequencerEvent::Completed { elapsed_rig_time_s: self.elapsed_before_s });
        out.events.push(SequencerEvent::CheckpointChanged);
    }

    /// React to the rig's fault flags: a hardware e-stop is an ESTOP; a refused setpoint is
    /// reported.
    fn rig_faults(&mut self, now_s: f64, s: &RigSample, out: &mut SequencerOutput) {
        let running = matches!(self.state, State::Running(_) | State::Paused { .. });
        if s.fault_flags & RigSample::FAULT_ESTOP != 0 && running {
            if let State::Running(run) | State::Paused { was: run, .. } = &self.state {
                let (at, pause) = self.restart_point(&run.clone());
                self.stop(now_s, at, pause);
            }
            self.state = State::EStop;
            out.events.push(SequencerEvent::EStop);
            out.events.push(SequencerEvent::CheckpointChanged);
        }
        let envelope_fault = s.fault_flags & RigSample::FAULT_ENVELOPE != 0;
        if envelope_fault && !self.rig_envelope_fault && running {
            out.events.push(SequencerEvent::RigRefusedSetpoint { step: self.cursor });
        }
        self.rig_envelope_fault = envelope_fault;
    }

    fn thermal_releases(&self, now_s: f64, pause_t0: f64, th: Option<&ThermalState>) -> Option<bool> {
        let th = th?;
        let stamp = th.header.stamp.as_secs_f64();
        let fresh = now_s - stamp <= self.cfg.thermal_stale_after_s;
        let judged_after_start = stamp >= pause_t0 + self.cfg.min_thermal_pause_s;
        (th.gate_open && fresh && judged_after_start).then_some(th.status == ThermalState::STATUS_TIMED_OUT)
    }

    /// Advance to `now_s`: stream the setpoint, handle step ends and thermal pauses.
    /// `thermal`: the latest `ThermalState` (None or stale holds any pause). `sample`: the
    /// latest `RigSample` (used to ramp from where the rig really is after START/RESUME).
    pub fn step(&mut self, now_s: f64, thermal: Option<&ThermalState>, sample: Option<&RigSample>) -> SequencerOutput {
        let mut out = SequencerOutput::default();
        let prev_now_s = self.last_now_s;
        self.last_now_s = now_s;
        if let Some(s) = sample {
            self.last_sample = Some(sample_setpoint(s));
            if self.fault_hold {
                self.rig_back(prev_now_s, now_s, &mut out);
            }
            self.rig_faults(now_s, s, &mut out);
        }
        self.watch_thermal(now_s, thermal, &mut out);
        if let Some(th) = thermal
            && now_s - th.header.stamp.as_secs_f64() <= self.cfg.thermal_stale_after_s
        {
            self.predicted_wait_s = Some(th.predicted_wait_s.max(0.0));
        } else {
            self.predicted_wait_s = None;
        }
        // Advance through as many step ends as `now_s` covers (zero-length steps included).
        let sp = loop {
            match self.state.clone() {
                State::Idle | State::Complete => break None,
                State::Aborted | State::EStop => break Some(safe_setpoint()),
                State::Paused { hold, t0, .. } => break Some(hold.at(now_s - t0)),
                State::Running(Run::Transition { traj, t0, pause_after }) => {
                    let d = traj.duration_s();
                    if now_s - t0 < d {
                        break Some(traj.at(now_s - t0));
                    }
                    if pause_after {
                        self.enter_pause(t0 + d, traj.end(), &mut out);
                    } else {
                        self.enter_step(t0 + d, &mut out);
                    }
                }
                State::Running(Run::Step { t0 }) => {
                    let step = &self.plan.steps[self.cursor];
                    let d = step.duration_s;
                    if now_s - t0 < d {
                        break Some(step.trajectory.at(now_s - t0));
                    }
                    let end = step.trajectory.end();
                    let name = step.name.clone();
                    let pause = step.thermal_pause_after;
                    if let Some(sweep_index) = step.sweep_index {
                        out.events.push(SequencerEvent::SweepEnded {
                            name: name.clone(),
                            sweep_index,
                            section: self.section_name(step.section_index),
                            duration_s: d,
                        });
                    }
                    self.completed_steps = self.completed_steps.max(self.cursor + 1);
                    out.events.push(SequencerEvent::CheckpointChanged);
                    if pause {
                        self.enter_pause(t0 + d, thermal_pause_setpoint(&end), &mut out);
                    } else {
                        self.advance(t0 + d, now_s, self.cursor + 1, end, &mut out);
                    }
                }
                State::Running(Run::AwaitPlan { sp, slot, .. }) => {
                    out.events.push(SequencerEvent::PlanNeeded { slot });
                    break Some(sp);
                }
                State::Running(Run::ThermalPause { t0, sp }) => {
                    let Some(timed_out) = self.thermal_releases(now_s, t0, thermal) else {
                        break Some(sp);
                    };
                    let duration_s = now_s - t0;
                    self.pause_sum_s += duration_s;
                    self.pause_model_sum_s += self.pause_estimates_s[self.cursor];
                    self.next_started_hot = timed_out;
                    out.events.push(SequencerEvent::ThermalPauseEnded {
                        after_sweep: self.plan.steps[self.cursor].name.clone(),
                        duration_s,
                        timed_out,
                    });
                    let next = self.cursor + 1;
                    if next < self.plan.steps.len() && self.open_slot_at(next).is_none() {
                        out.events.push(SequencerEvent::CheckpointChanged);
                    }
                    self.advance(now_s, now_s, next, sp, &mut out);
                }
            }
        };
        if let Some(sp) = sp {
            match self.cfg.envelope.check(&sp) {
                Ok(()) => {
                    self.last_setpoint = Some(sp);
                    out.setpoint = Some(self.setpoint_msg(now_s, &sp));
                }
                Err(v) => self.refuse(now_s, v, &mut out),
            }
        }
        self.emit(now_s, &mut out, false);
        out
    }

    fn refuse(&mut self, now_s: f64, v: EnvelopeViolation, out: &mut SequencerOutput) {
        out.events.push(SequencerEvent::SetpointRefused {
            step: self.cursor,
            axis: v.axis.to_owned(),
            value: v.value,
            limit: v.limit,
        });
        if let State::Running(run) | State::Paused { was: run, .. } = &self.state {
            let (at, pause) = self.restart_point(&run.clone());
            self.stop(now_s, at, pause);
        }
        self.state = State::Aborted;
        out.events.push(SequencerEvent::Aborted { reason: format!("setpoint refused: {v}") });
        out.events.push(SequencerEvent::CheckpointChanged);
        out.setpoint = Some(self.setpoint_msg(now_s, &safe_setpoint()));
    }

    fn setpoint_msg(&mut self, now_s: f64, sp: &Setpoint) -> RigSetpoint {
        self.seq += 1;
        let sweep_name = match &self.state {
            State::Running(Run::Step { .. }) => {
                let st = &self.plan.steps[self.cursor];
                if st.kind.is_data() { st.name.clone() } else { String::new() }
            }
            _ => String::new(),
        };
        RigSetpoint {
            header: Header::iso_w(now_s),
            seq: self.seq,
            mode: sp.mode.as_msg_mode(),
            slip_angle_deg: sp.slip_angle_deg,
            slip_ratio: sp.slip_ratio,
            fz_n: sp.fz_n,
            camber_deg: sp.camber_deg,
            pressure_pa: sp.pressure_bar * PA_PER_BAR,
            speed_mps: sp.speed_mps,
            belt_displacement_m: sp.belt_displacement_m,
            hold_slip_angle: false,
            hold_slip_ratio: false,
            hold_load: false,
            hold_camber: false,
            sweep_name,
        }
    }

    fn section_name(&self, i: usize) -> String {
        self.plan.sections.get(i).map(|s| s.name.clone()).unwrap_or_default()
    }

    fn phase(&self) -> u8 {
        match &self.state {
            State::Idle => ProcedureState::PHASE_IDLE,
            State::Running(Run::Transition { .. } | Run::AwaitPlan { .. }) => ProcedureState::PHASE_SETTLE,
            State::Running(Run::Step { .. }) => phase_of_kind(self.plan.steps[self.cursor].kind),
            State::Running(Run::ThermalPause { .. }) => ProcedureState::PHASE_THERMAL_PAUSE,
            State::Paused { .. } => ProcedureState::PHASE_PAUSED,
            State::Aborted => ProcedureState::PHASE_ABORTED,
            State::EStop => ProcedureState::PHASE_ESTOP,
            State::Complete => ProcedureState::PHASE_COMPLETE,
        }
    }

    /// The data step the state refers to: the current one, else the next in its group, else
    /// the last one before (during a thermal pause: the sweep just run).
    fn display_step(&self) -> Option<usize> {
        let steps = &self.plan.steps;
        let c = self.cursor.min(steps.len() - 1);
        if steps[c].sweep_index.is_some() {
            return Some(c);
        }
        steps[c..]
            .iter()
            .take_while(|s| s.restart_from == steps[c].restart_from)
            .find(|s| s.sweep_index.is_some())
            .map(|s| s.index)
            .or_else(|| steps[..c].iter().rev().find(|s| s.sweep_index.is_some()).map(|s| s.index))
    }

    /// Build `ProcedureState` for `now_s`.
    pub fn procedure_state(&self, now_s: f64) -> ProcedureState {
        let steps = &self.plan.steps;
        let c = self.cursor.min(steps.len() - 1);
        let step = &steps[c];
        let total = self.plan.planned_duration_s().max(1e-9);
        let (done_s, in_step_s) = match &self.state {
            State::Complete => (total, 0.0),
            State::Running(Run::Step { t0 }) => (
                self.plan.planned_duration_s() - self.plan.remaining_from_s(c),
                (now_s - t0).clamp(0.0, step.duration_s),
            ),
            State::Running(Run::ThermalPause { .. }) => {
                (self.plan.planned_duration_s() - self.plan.remaining_from_s(c + 1), 0.0)
            }
            _ => (self.plan.planned_duration_s() - self.plan.remaining_from_s(c), 0.0),
        };
        let in_pause = matches!(self.state, State::Running(Run::ThermalPause { .. }));
        let first_left = if in_pause { c + 1 } else { c };
        // The model's pauses, scaled by how the pauses so far compared with it (this tyre, rig).
        let scale = if self.pause_model_sum_s > 0.0 { self.pause_sum_s / self.pause_model_sum_s } else { 1.0 };
        let pauses_left: f64 = self.pause_estimates_s.iter().skip(first_left).sum::<f64>() * scale;
        let current_pause =
            if in_pause { self.predicted_wait_s.unwrap_or(self.pause_estimates_s[c] * scale) } else { 0.0 };
        // An adaptive plan's open slots may still add sweeps: count their budgets (an upper
        // bound) rather than nothing, so neither figure is optimistic until they close.
        let open_slots_s = match (&self.adaptive, &self.state) {
            (Some(a), s) if *s != State::Complete => a.planner.open_slots_bound_s(),
            _ => 0.0,
        };
        let remaining = if self.state == State::Complete {
            0.0
        } else {
            (total - done_s - in_step_s).max(0.0) + pauses_left + current_pause + open_slots_s
        };
        let shown_i = self.display_step();
        let shown = shown_i.map(|i| &steps[i]);
        let (plan_reason, predicted_error_pct) =
            match (&self.adaptive, shown_i.and_then(|i| self.step_reasons[i].as_ref())) {
                (None, _) => (String::new(), 0.0),
                (Some(_), Some((reason, err))) => (reason.clone(), *err),
                (Some(_), None) => ("fixed".to_owned(), 0.0),
            };
        ProcedureState {
            header: Header::iso_w(now_s),
            phase: self.phase(),
            procedure: step.procedure.clone(),
            section: self.section_name(step.section_index),
            section_index: step.section_index as u32,
            sweep_name: shown.map(|s| s.name.clone()).unwrap_or_default(),
            sweep_index: shown.and_then(|s| s.sweep_index).unwrap_or(0),
            sweep_count: self.plan.sweep_count(),
            sweep_started_hot: self.started_hot,
            progress: ((done_s + in_step_s) / (total + open_slots_s)).clamp(0.0, 1.0),
            elapsed_rig_time_s: self.elapsed_at(now_s),
            estimated_remaining_s: remaining,
            plan_reason,
            predicted_error_pct,
        }
    }

    fn emit(&mut self, now_s: f64, out: &mut SequencerOutput, force: bool) {
        let key = (self.phase(), self.cursor);
        let due = self.last_state_s.is_none_or(|t| now_s - t >= self.cfg.state_period_s - 1e-6);
        if force || due || self.last_state_key != Some(key) {
            out.state = Some(self.procedure_state(now_s));
            self.last_state_s = Some(now_s);
            self.last_state_key = Some(key);
        }
    }
}

//! The sequencer's DDS shell: samples, thermal state and commands in; setpoints and procedure
//! state out; the checkpoint on disk.
//!
//! The core is stepped once per rig sample with the sample's stamp as `now`, so the node runs
//! at the rig's rate on real, real-time virtual and accelerated (lockstep) rigs alike. Each
//! setpoint carries the stamp of the sample it answers: a lockstep rig waits for exactly that.
//!
//! A watchdog (the one wall-clock reading here) checks every control cycle that samples still
//! come: after `rig_silent_after_s` without one while a procedure runs, the core holds the rig
//! safe in that same cycle and `/diagnostics` says so. Lost or malformed input on any topic is
//! counted and announced (`node_runtime::LossWatch`).

use crate::{Checkpoint, PlanModel, PlanModelReady, Sequencer, SequencerConfig, SequencerEvent, decision_status};
use adaptive::FitView;
use adaptive::model::NoModel;
use futures::StreamExt;
use node_runtime::{LossWatch, RosNode, RuntimeError, Shutdown, SuiteTopic};
use procedure::{RunInputs, SweepStyle};
use serde::Deserialize;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};
use tyre_msgs::diagnostic_msgs::{DiagnosticArray, DiagnosticStatus, KeyValue};
use tyre_msgs::{
    ModelCovariance, ProcedureCommand, ProcedureState, RigSample, RigSetpoint, ThermalState, std_msgs::Header,
};

/// `[node.config]` of a sequencer node.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SequencerNodeConfig {
    /// The procedure file (`launch-config/procedures/gs2mf.toml`, …).
    pub procedure: PathBuf,
    /// ETRTO load index of the tyre on the rig.
    #[serde(default = "default_li")]
    pub load_index: u32,
    /// The tyre's nominal load Fz0 [N] when it has no ETRTO index (race tyres); replaces the
    /// load index's.
    #[serde(default)]
    pub fz0_n: Option<f64>,
    /// Low, middle, high inflation pressure [bar].
    #[serde(default = "default_pressures")]
    pub pressures_bar: [f64; 3],
    #[serde(default = "default_speed")]
    pub nominal_speed_mps: f64,
    #[serde(default)]
    pub sweeps: SweepStyle,
    /// Where progress is checkpointed; a restarted sequencer resumes from it.
    #[serde(default)]
    pub checkpoint: Option<PathBuf>,
    /// Start the procedure without waiting for a START command.
    #[serde(default)]
    pub autostart: bool,
    /// Stop the node when the procedure completes, aborts or e-stops.
    #[serde(default)]
    pub exit_when_done: bool,
    /// Core settings (control rate, staleness, envelope, …).
    #[serde(default)]
    pub core: SequencerConfig,
    /// Wall time without a rig sample, while a procedure runs, after which the rig is held
    /// safe and an alarm raised \[s\].
    #[serde(default = "default_rig_silent")]
    pub rig_silent_after_s: f64,
    /// With `plan = "adaptive"`: wall time a slot waits for a `model/covariance` that has seen
    /// the last sweep before it decides with the newest model it has \[s\]
    /// (`docs/adaptive-plan.md`, Over DDS).
    #[serde(default = "default_plan_model_wait")]
    pub plan_model_wait_s: f64,
}

fn default_plan_model_wait() -> f64 {
    120.0
}

impl SequencerNodeConfig {
    /// Checks the core's settings and the node's own.
    pub fn validate(&self) -> Result<(), crate::config::ConfigError> {
        self.core.validate()?;
        for (key, v) in [("rig_silent_after_s", self.rig_silent_after_s), ("plan_model_wait_s", self.plan_model_wait_s)]
        {
            if !(v.is_finite() && v >= 0.0) {
                return Err(crate::config::ConfigError { key, message: format!("expected a number ≥ 0, got {v}") });
            }
        }
        Ok(())
    }
}

fn default_rig_silent() -> f64 {
    0.5
}

/// The `/diagnostics` status for a sequencer event that an operator must see, if it is one.
pub fn event_status(node: &str, ev: &SequencerEvent, rig_time_s: f64) -> Option<DiagnosticStatus> {
    let (level, check, message) = match ev {
        SequencerEvent::RigSilent { silent_s, estop } => (
            DiagnosticStatus::ERROR,
            "rig_silent",
            format!(
                "no rig sample for {silent_s:.2} s: rig {}",
                if *estop { "e-stopped" } else { "held at zero slip" }
            ),
        ),
        SequencerEvent::RigBack { resumed } => (
            DiagnosticStatus::WARN,
            "rig_silent",
            format!(
                "rig samples back{}",
                if *resumed { ": the interrupted sweep reruns" } else { ": waiting for RESUME" }
            ),
        ),
        SequencerEvent::ThermalLost { silent_s } => (
            DiagnosticStatus::ERROR,
            "thermal_lost",
            format!("no fresh thermal/state for {silent_s:.2} s of rig time: no sweep will be released"),
        ),
        SequencerEvent::ThermalBack => (DiagnosticStatus::WARN, "thermal_lost", "thermal/state fresh again".to_owned()),
        SequencerEvent::EStop => (DiagnosticStatus::ERROR, "estop", "emergency stop".to_owned()),
        _ => return None,
    };
    Some(DiagnosticStatus {
        level,
        name: format!("{node}: {check}"),
        message,
        hardware_id: "sequencer".into(),
        values: vec![KeyValue { key: "rig_time_s".into(), value: format!("{rig_time_s:.3}") }],
    })
}

fn default_li() -> u32 {
    110
}
fn default_pressures() -> [f64; 3] {
    [2.1, 2.6, 3.3]
}
fn default_speed() -> f64 {
    16.6
}

/// Why the node stopped with an error.
#[derive(Debug, thiserror::Error)]
pub enum SequencerNodeError {
    #[error("procedure: {0}")]
    Procedure(String),
    #[error("sequencer: {0}")]
    Core(String),
    #[error("{path}: checkpoint: {detail}")]
    Checkpoint { path: PathBuf, detail: String },
    #[error(transparent)]
    Runtime(#[from] RuntimeError),
}

fn read_checkpoint(path: &Path) -> Result<Option<Checkpoint>, SequencerNodeError> {
    match std::fs::read_to_string(path) {
        Ok(text) => serde_json::from_str(&text)
            .map(Some)
            .map_err(|e| SequencerNodeError::Checkpoint { path: path.to_owned(), detail: e.to_string() }),
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => Ok(None),
        Err(e) => Err(SequencerNodeError::Checkpoint { path: path.to_owned(), detail: e.to_string() }),
    }
}

/// Writes atomically (temp file + rename) so a crash never leaves half a checkpoint.
fn write_checkpoint(path: &Path, cp: &Checkpoint) -> Result<(), SequencerNodeError> {
    let err = |detail: String| SequencerNodeError::Checkpoint { path: path.to_owned(), detail };
    let json = serde_json::to_string_pretty(cp).map_err(|e| err(e.to_string()))?;
    let tmp = path.with_extension("json.tmp");
    std::fs::write(&tmp, json).map_err(|e| err(e.to_string()))?;
    std::fs::rename(&tmp, path).map_err(|e| err(e.to_string()))
}

/// Notes the procedure states of `out` (which data sweeps ran) for the adaptive plan's model wait.
fn observe(out: &crate::SequencerOutput, plan_model: &mut PlanModel) {
    if let Some(st) = &out.state {
        plan_model.on_state(st);
    }
}

/// A `/diagnostics` record about the adaptive plan's model (a stale decision, a bad message).
fn plan_status(node: &str, level: u8, message: String, rig_time_s: f64) -> DiagnosticArray {
    DiagnosticArray {
        header: Header {
            stamp: tyre_msgs::builtin_interfaces::Time::from_secs_f64(rig_time_s),
            frame_id: String::new(),
        },
        status: vec![DiagnosticStatus {
            level,
            name: format!("{node}: adaptive_model"),
            message,
            hardware_id: "sequencer".into(),
            values: vec![KeyValue { key: "rig_time_s".into(), value: format!("{rig_time_s:.3}") }],
        }],
    }
}

/// Runs the sequencer until shutdown (or, with `exit_when_done`, the end of the procedure).
pub async fn run(mut node: RosNode, cfg: SequencerNodeConfig, shutdown: Shutdown) -> Result<(), SequencerNodeError> {
    let doc = procedure::load(&cfg.procedure).map_err(|e| SequencerNodeError::Procedure(e.to_string()))?;
    let inputs = RunInputs {
        load_index: cfg.load_index,
        fz0_n: cfg.fz0_n,
        pressures_bar: cfg.pressures_bar,
        nominal_speed_mps: cfg.nominal_speed_mps,
        sweeps: cfg.sweeps,
        // The plan is expanded inside the envelope the core guards (a race tyre's 0.7 bar
        // needs a lower pressure limit than the default 1 bar).
        limits: cfg.core.envelope,
    };
    let plan = procedure::expand(&doc, &inputs).map_err(|e| SequencerNodeError::Procedure(e.to_string()))?;
    let adaptive = cfg.core.plan == crate::PlanKind::Adaptive;
    let checkpoint = match &cfg.checkpoint {
        Some(p) => read_checkpoint(p)?,
        None => None,
    };
    let mut seq = match &checkpoint {
        Some(cp) if !cp.complete => {
            tracing::info!(next_step = cp.next_step, "resuming from checkpoint");
            Sequencer::resume_for_config(plan, cfg.core, cp)
        }
        _ => Sequencer::for_config(plan, cfg.core),
    }
    .map_err(|e| SequencerNodeError::Core(e.to_string()))?;

    let setpoint_pub = node.publisher::<RigSetpoint>(SuiteTopic::RigSetpoint)?;
    let state_pub = node.publisher::<ProcedureState>(SuiteTopic::ProcedureState)?;
    let diag_pub = node.publisher::<DiagnosticArray>(SuiteTopic::Diagnostics)?;
    let node_name = node.name().to_owned();
    let samples = node.subscription::<RigSample>(SuiteTopic::RigSample)?;
    let thermal = node.subscription::<ThermalState>(SuiteTopic::ThermalState)?;
    let commands = node.subscription::<ProcedureCommand>(SuiteTopic::ProcedureCommand)?;
    let mut samples = Box::pin(samples.async_stream());
    let mut thermal = Box::pin(thermal.async_stream());
    let mut commands = Box::pin(commands.async_stream());
    // The adaptive plan decides with the live fit's model (`model/covariance`); a fixed plan
    // does not subscribe (its DDS Security permissions need not allow it).
    let models = if adaptive { Some(node.subscription::<ModelCovariance>(SuiteTopic::ModelCovariance)?) } else { None };
    let mut models = models.as_ref().map(|m| Box::pin(m.async_stream()));
    let model_topic = node.topic_name(SuiteTopic::ModelCovariance);
    // … and prices the tread its sweeps wear with the rate the monitor measures on the tyre,
    // which the monitor's wear status on `/diagnostics` carries.
    let diagnostics =
        if adaptive { Some(node.subscription::<DiagnosticArray>(SuiteTopic::Diagnostics)?) } else { None };
    let mut diagnostics = diagnostics.as_ref().map(|d| Box::pin(d.async_stream()));
    let diagnostics_topic = node.topic_name(SuiteTopic::Diagnostics);
    let mut plan_model = PlanModel::default();
    let mut plan_wait_since: Option<Instant> = None;
    let mut latest_thermal: Option<ThermalState> = None;
    let mut now_s = 0.0;
    let mut pending_start = cfg.autostart;
    let (sample_topic, thermal_topic, command_topic) = (
        node.topic_name(SuiteTopic::RigSample),
        node.topic_name(SuiteTopic::ThermalState),
        node.topic_name(SuiteTopic::ProcedureCommand),
    );
    let mut loss = LossWatch::new(node.name());
    let publish_errors = node_runtime::PublishErrors::new();
    // Watchdog: checked every control cycle; armed by the first sample.
    let mut watchdog = tokio::time::interval(Duration::from_secs_f64(1.0 / cfg.core.control_rate_hz));
    watchdog.set_missed_tick_behavior(tokio::time::MissedTickBehavior::Delay);
    let mut last_sample_at: Option<Instant> = None;
    let silent_after = Duration::from_secs_f64(cfg.rig_silent_after_s.max(0.0));

    let handle = |out: crate::SequencerOutput, seq: &Sequencer| -> Result<bool, SequencerNodeError> {
        let rig_time_s = out.setpoint.as_ref().map(|sp| sp.header.stamp.as_secs_f64());
        if let Some(sp) = out.setpoint {
            publish_errors.check(SuiteTopic::RigSetpoint, setpoint_pub.publish(sp));
        }
        if let Some(st) = out.state {
            publish_errors.check(SuiteTopic::ProcedureState, state_pub.publish(st));
        }
        let statuses: Vec<_> =
            out.events.iter().filter_map(|ev| event_status(&node_name, ev, rig_time_s.unwrap_or(0.0))).collect();
        if !statuses.is_empty() {
            for st in &statuses {
                tracing::warn!("{}: {}", st.name, st.message);
            }
            let header = Header {
                stamp: tyre_msgs::builtin_interfaces::Time::from_secs_f64(rig_time_s.unwrap_or(0.0)),
                frame_id: String::new(),
            };
            publish_errors
                .check(SuiteTopic::Diagnostics, diag_pub.publish(DiagnosticArray { header, status: statuses }));
        }
        let mut done = false;
        for ev in &out.events {
            match ev {
                SequencerEvent::CheckpointChanged => {
                    if let Some(p) = &cfg.checkpoint {
                        write_checkpoint(p, &seq.checkpoint())?;
                    }
                }
                SequencerEvent::Completed { .. } | SequencerEvent::Aborted { .. } | SequencerEvent::EStop => {
                    tracing::info!("procedure ended: {ev:?}");
                    done = true;
                }
                SequencerEvent::SweepStarted { name, .. } => tracing::debug!("sweep {name}"),
                _ => {}
            }
        }
        Ok(done)
    };

    loop {
        tokio::select! {
            _ = shutdown.wait() => break,
            _ = watchdog.tick() => {
                if let Some(at) = last_sample_at
                    && at.elapsed() >= silent_after
                {
                    let out = seq.on_rig_silent(at.elapsed().as_secs_f64());
                    observe(&out, &mut plan_model);
                    if handle(out, &seq)? && cfg.exit_when_done { break; }
                }
            },
            item = commands.next() => match item {
                Some(Ok((cmd, info))) => {
                    loss.on_message(&command_topic, &info, None);
                    match seq.on_command(now_s, &cmd) {
                    Ok(out) => {
                        observe(&out, &mut plan_model);
                        if handle(out, &seq)? && cfg.exit_when_done { break; }
                    }
                    Err(rejected) => tracing::warn!("command refused: {rejected}"),
                    }
                }
                Some(Err(e)) => loss.on_read_error(&command_topic, &e),
                None => break,
            },
            item = async { models.as_mut().expect("guarded").next().await }, if models.is_some() => match item {
                Some(Ok((msg, info))) => {
                    loss.on_message(&model_topic, &info, None);
                    if let Err(e) = plan_model.on_model(&msg) {
                        tracing::error!("{e}; the planner keeps the previous model");
                        publish_errors.check(SuiteTopic::Diagnostics, diag_pub.publish(plan_status(&node_name, DiagnosticStatus::ERROR, e.to_string(), now_s)));
                    }
                }
                Some(Err(e)) => loss.on_read_error(&model_topic, &e),
                None => break,
            },
            item = async { diagnostics.as_mut().expect("guarded").next().await }, if diagnostics.is_some() => match item {
                Some(Ok((msg, info))) => {
                    loss.on_message(&diagnostics_topic, &info, None);
                    if let Some(rate) = crate::measured_wear_rate(&msg)
                        && seq.on_wear_rate(rate)
                    {
                        tracing::debug!(rate.mm_per_mj, rate.sd_mm_per_mj, "measured wear rate");
                    }
                }
                Some(Err(e)) => loss.on_read_error(&diagnostics_topic, &e),
                None => break,
            },
            item = thermal.next() => match item {
                Some(Ok((th, info))) => {
                    loss.on_message(&thermal_topic, &info, None);
                    latest_thermal = Some(th)
                }
                Some(Err(e)) => loss.on_read_error(&thermal_topic, &e),
                None => break,
            },
            item = samples.next() => match item {
                Some(Ok((s, info))) => {
                    loss.on_message(&sample_topic, &info, Some(s.seq));
                    last_sample_at = Some(Instant::now());
                    now_s = s.header.stamp.as_secs_f64();
                    if pending_start {
                        pending_start = false;
                        let start = ProcedureCommand { command: ProcedureCommand::START, operator_name: "autostart".into(), ..Default::default() };
                        match seq.on_command(now_s, &start) {
                            Ok(out) => { handle(out, &seq)?; }
                            Err(e) => return Err(SequencerNodeError::Core(e.to_string())),
                        }
                    }
                    let out = seq.step(now_s, latest_thermal.as_ref(), Some(&s));
                    observe(&out, &mut plan_model);
                    if handle(out, &seq)? && cfg.exit_when_done { break; }
                }
                Some(Err(e)) => loss.on_read_error(&sample_topic, &e),
                None => break,
            },
        }
        if adaptive && seq.awaiting_plan().is_some() {
            let since = *plan_wait_since.get_or_insert_with(Instant::now);
            if let PlanModelReady::Decide { model, stale } =
                plan_model.ready(since.elapsed().as_secs_f64(), cfg.plan_model_wait_s)
            {
                plan_wait_since = None;
                if let Some(why) = stale {
                    tracing::warn!("adaptive plan: {why}");
                    publish_errors.check(
                        SuiteTopic::Diagnostics,
                        diag_pub.publish(plan_status(&node_name, DiagnosticStatus::WARN, why, now_s)),
                    );
                }
                let planner_cfg = seq.planner().map(|p| *p.config()).unwrap_or_default();
                let decided_with = model.and(plan_model.latest());
                let out = match model {
                    Some(m) => seq.plan_next(now_s, &FitView::new(m, &planner_cfg)),
                    None => seq.plan_next(now_s, &NoModel),
                };
                for ev in &out.events {
                    if let Some(d) = decision_status(ev, now_s, decided_with) {
                        tracing::info!("adaptive plan: {}", d.status.first().map_or("", |s| s.message.as_str()));
                        publish_errors.check(SuiteTopic::Diagnostics, diag_pub.publish(d));
                    }
                }
                observe(&out, &mut plan_model);
                if handle(out, &seq)? && cfg.exit_when_done {
                    break;
                }
            }
        } else {
            // Not at a slot (or paused there): the next slot's wait starts afresh.
            plan_wait_since = None;
        }
        loss.announce(&diag_pub, tyre_msgs::builtin_interfaces::Time::from_secs_f64(now_s));
    }
    if cfg.exit_when_done {
        // The final ProcedureState (COMPLETE, ABORTED, ESTOP) was just written: the participant
        // stays until every reader has it (or a repair of it), or the log may end without the
        // state that says how the procedure ended.
        node.flush_before_exit(&[
            (SuiteTopic::ProcedureState, state_pub.guid()),
            (SuiteTopic::RigSetpoint, setpoint_pub.guid()),
            (SuiteTopic::Diagnostics, diag_pub.guid()),
        ])
        .await;
    }
    Ok(())
}

//! The sequencer's DDS shell: samples, thermal state and commands in; setpoints and procedure
//! state out; the checkpoint on disk.
//!
//! The core is stepped once per rig sample with the sample's stamp as `now`, so the node runs
//! at the rig's rate on real, real-time virtual and accelerated (lockstep) rigs alike. Each
//! setpoint carries the stamp of the sample it answers: a lockstep rig waits for exactly that.

use crate::{Checkpoint, Sequencer, SequencerConfig, SequencerEvent};
use futures::StreamExt;
use node_runtime::{RosNode, RuntimeError, Shutdown, SuiteTopic};
use procedure::{RunInputs, SweepStyle};
use serde::Deserialize;
use std::path::{Path, PathBuf};
use tyre_msgs::{ProcedureCommand, ProcedureState, RigSample, RigSetpoint, ThermalState};

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
    let checkpoint = match &cfg.checkpoint {
        Some(p) => read_checkpoint(p)?,
        None => None,
    };
    let mut seq = match &checkpoint {
        Some(cp) if !cp.complete => {
            tracing::info!(next_step = cp.next_step, "resuming from checkpoint");
            Sequencer::resume(plan, cfg.core, cp)
        }
        _ => Sequencer::new(plan, cfg.core),
    }
    .map_err(|e| SequencerNodeError::Core(e.to_string()))?;

    let setpoint_pub = node.publisher::<RigSetpoint>(SuiteTopic::RigSetpoint)?;
    let state_pub = node.publisher::<ProcedureState>(SuiteTopic::ProcedureState)?;
    let samples = node.subscription::<RigSample>(SuiteTopic::RigSample)?;
    let thermal = node.subscription::<ThermalState>(SuiteTopic::ThermalState)?;
    let commands = node.subscription::<ProcedureCommand>(SuiteTopic::ProcedureCommand)?;
    let mut samples = Box::pin(samples.async_stream());
    let mut thermal = Box::pin(thermal.async_stream());
    let mut commands = Box::pin(commands.async_stream());
    let mut latest_thermal: Option<ThermalState> = None;
    let mut now_s = 0.0;
    let mut pending_start = cfg.autostart;

    let handle = |out: crate::SequencerOutput, seq: &Sequencer| -> Result<bool, SequencerNodeError> {
        if let Some(sp) = out.setpoint {
            let _ = setpoint_pub.publish(sp);
        }
        if let Some(st) = out.state {
            let _ = state_pub.publish(st);
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
            item = commands.next() => match item {
                Some(Ok((cmd, _))) => match seq.on_command(now_s, &cmd) {
                    Ok(out) => {
                        if handle(out, &seq)? && cfg.exit_when_done { break; }
                    }
                    Err(rejected) => tracing::warn!("command refused: {rejected}"),
                },
                Some(Err(e)) => tracing::warn!("procedure/command: {e:?}"),
                None => break,
            },
            item = thermal.next() => match item {
                Some(Ok((th, _))) => latest_thermal = Some(th),
                Some(Err(e)) => tracing::warn!("thermal/state: {e:?}"),
                None => break,
            },
            item = samples.next() => match item {
                Some(Ok((s, _))) => {
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
                    if handle(out, &seq)? && cfg.exit_when_done { break; }
                }
                Some(Err(e)) => tracing::warn!("sample: {e:?}"),
                None => break,
            },
        }
    }
    Ok(())
}

//! The thermal node's DDS shell: samples and procedure state in, gate state and diagnostics out.
//!
//! Time is each message's stamp (rig time), never the wall clock, so the node behaves the same
//! on a real rig, a real-time virtual rig and an accelerated (lockstep) one.

use crate::{AlarmLevel, ThermalConfig, ThermalGate};
use futures::StreamExt;
use node_runtime::{RosNode, RuntimeError, Shutdown, SuiteTopic};
use tyre_msgs::{
    ProcedureState, RigSample, ThermalState,
    diagnostic_msgs::{DiagnosticArray, DiagnosticStatus, KeyValue},
};

/// Why the node stopped with an error.
#[derive(Debug, thiserror::Error)]
pub enum ThermalNodeError {
    #[error("thermal config: {0}")]
    Config(#[from] crate::ConfigError),
    #[error(transparent)]
    Runtime(#[from] RuntimeError),
}

/// Runs the gate until shutdown.
pub async fn run(mut node: RosNode, cfg: ThermalConfig, shutdown: Shutdown) -> Result<(), ThermalNodeError> {
    let mut gate = ThermalGate::new(cfg)?;
    let state_pub = node.publisher::<ThermalState>(SuiteTopic::ThermalState)?;
    let diag_pub = node.publisher::<DiagnosticArray>(SuiteTopic::Diagnostics)?;
    let samples = node.subscription::<RigSample>(SuiteTopic::RigSample)?;
    let states = node.subscription::<ProcedureState>(SuiteTopic::ProcedureState)?;
    let mut samples = Box::pin(samples.async_stream());
    let mut states = Box::pin(states.async_stream());
    loop {
        tokio::select! {
            _ = shutdown.wait() => break,
            item = states.next() => match item {
                Some(Ok((st, _))) => gate.on_procedure_state(st.header.stamp.as_secs_f64(), &st),
                Some(Err(e)) => tracing::warn!("procedure/state: {e:?}"),
                None => break,
            },
            item = samples.next() => match item {
                Some(Ok((s, _))) => {
                    let t = s.header.stamp.as_secs_f64();
                    gate.on_sample(t, &s);
                    let out = gate.step(t);
                    if let Err(e) = state_pub.publish(out.state.clone()) {
                        tracing::warn!("thermal/state publish: {e:?}");
                    }
                    if !out.alarms.is_empty() {
                        let status = out.alarms.iter().map(|a| DiagnosticStatus {
                            level: match a.level { AlarmLevel::Warn => DiagnosticStatus::WARN, AlarmLevel::Error => DiagnosticStatus::ERROR },
                            name: format!("{}: {}", node.name(), a.check.as_str()),
                            message: a.message.clone(),
                            hardware_id: "tyre tread temperature".into(),
                            values: vec![KeyValue { key: "rig_time_s".into(), value: format!("{:.3}", a.rig_time_s) }],
                        }).collect();
                        let _ = diag_pub.publish(DiagnosticArray { header: out.state.header.clone(), status });
                    }
                }
                Some(Err(e)) => tracing::warn!("sample: {e:?}"),
                None => break,
            },
        }
    }
    Ok(())
}

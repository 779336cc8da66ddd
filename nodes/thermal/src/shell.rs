//! The thermal node's DDS shell: samples and procedure state in, gate state and diagnostics out.
//!
//! Time is each message's stamp (rig time), never the wall clock, so the node behaves the same
//! on a real rig, a real-time virtual rig and an accelerated (lockstep) one.

use crate::{AlarmLevel, ThermalConfig, ThermalGate};
use futures::StreamExt;
use node_runtime::{LossWatch, RosNode, RuntimeError, Shutdown, SuiteTopic};
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
    let (sample_topic, state_topic) =
        (node.topic_name(SuiteTopic::RigSample), node.topic_name(SuiteTopic::ProcedureState));
    let mut loss = LossWatch::new(node.name());
    let publish_errors = node_runtime::PublishErrors::new();
    let mut stamp = tyre_msgs::builtin_interfaces::Time::default();
    loop {
        tokio::select! {
            _ = shutdown.wait() => break,
            item = states.next() => match item {
                Some(Ok((st, info))) => {
                    loss.on_message(&state_topic, &info, None);
                    gate.on_procedure_state(st.header.stamp.as_secs_f64(), &st)
                }
                Some(Err(e)) => loss.on_read_error(&state_topic, &e),
                None => break,
            },
            item = samples.next() => match item {
                Some(Ok((s, info))) => {
                    loss.on_message(&sample_topic, &info, Some(s.seq));
                    stamp = s.header.stamp;
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
                        publish_errors.check(SuiteTopic::Diagnostics, diag_pub.publish(DiagnosticArray { header: out.state.header.clone(), status }));
                    }
                }
                Some(Err(e)) => loss.on_read_error(&sample_topic, &e),
                None => break,
            },
        }
        loss.announce(&diag_pub, stamp);
    }
    Ok(())
}

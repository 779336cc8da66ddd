//! The quality node's DDS shell: the channels and monitor cores in one process, wired by
//! [`Pipeline`] exactly as a headless run and a replay wire them, so a recorded log replays to
//! the same outputs.
//!
//! In: `rig/sample`, `procedure/state`. Out: `rig/channels/live` (every sample),
//! `rig/channels/sweep_summary`, `rig/quality/report` (on change), `/diagnostics` (with every
//! report). Derived measurements and alarms are logged (tracing) as they come.
//!
//! Time is each message's stamp (rig time), never the wall clock.

use futures::StreamExt;
use node_runtime::{RosNode, RuntimeError, Shutdown, SuiteTopic};
use tyre_msgs::diagnostic_msgs::DiagnosticArray;
use tyre_msgs::{LiveChannels, ProcedureState, QualityReport, RigSample, SweepSummary};

use crate::config::{MonitorConfig, TyreInfo};
use crate::pipeline::{Pipeline, PipelineError};

/// Why the node stopped with an error.
#[derive(Debug, thiserror::Error)]
pub enum QualityNodeError {
    /// A configuration was refused.
    #[error(transparent)]
    Config(#[from] PipelineError),
    /// DDS failed.
    #[error(transparent)]
    Runtime(#[from] RuntimeError),
}

/// Runs the channels and monitor cores until shutdown.
pub async fn run(
    mut node: RosNode,
    channels_cfg: channels::ChannelsConfig,
    monitor_cfg: MonitorConfig,
    tyre: TyreInfo,
    shutdown: Shutdown,
) -> Result<(), QualityNodeError> {
    let mut p = Pipeline::new(channels_cfg, monitor_cfg, tyre)?;
    let live_pub = node.publisher::<LiveChannels>(SuiteTopic::LiveChannels)?;
    let sum_pub = node.publisher::<SweepSummary>(SuiteTopic::SweepSummary)?;
    let rep_pub = node.publisher::<QualityReport>(SuiteTopic::QualityReport)?;
    let diag_pub = node.publisher::<DiagnosticArray>(SuiteTopic::Diagnostics)?;
    let samples = node.subscription::<RigSample>(SuiteTopic::RigSample)?;
    let states = node.subscription::<ProcedureState>(SuiteTopic::ProcedureState)?;
    let mut samples = Box::pin(samples.async_stream());
    let mut states = Box::pin(states.async_stream());
    // The late joiner's view: the current verdicts at once.
    let _ = rep_pub.publish(p.monitor.report(0.0));
    loop {
        tokio::select! {
            _ = shutdown.wait() => break,
            item = states.next() => match item {
                Some(Ok((st, _))) => p.on_procedure_state(&st),
                Some(Err(e)) => tracing::warn!("procedure/state: {e:?}"),
                None => break,
            },
            item = samples.next() => match item {
                Some(Ok((s, _))) => {
                    let o = p.on_sample(&s);
                    if let Err(e) = live_pub.publish(o.live) {
                        tracing::warn!("channels/live publish: {e:?}");
                    }
                    for x in o.sweep_summaries {
                        let _ = sum_pub.publish(x);
                    }
                    for d in &o.derived {
                        tracing::info!("{}: {} = {} {} (Fz {:.0} N, p {:.0} Pa)", d.section, d.quantity.name(), d.value, d.quantity.unit(), d.fz_n, d.pressure_pa);
                    }
                    for a in &o.alarms {
                        tracing::warn!("{} {} at {:.1} s: {}", a.level, a.check, a.rig_time_s, a.message);
                    }
                    if let Some(r) = o.report {
                        let _ = rep_pub.publish(r);
                    }
                    if let Some(d) = o.diagnostics {
                        let _ = diag_pub.publish(d);
                    }
                }
                Some(Err(e)) => tracing::warn!("sample: {e:?}"),
                None => break,
            },
        }
    }
    Ok(())
}

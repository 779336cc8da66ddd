//! The fit node's DDS shell: samples and procedure states in, `model/state` and
//! `model/covariance` out, the `.tir` and report written when the procedure completes.
//!
//! An update runs on a blocking thread while the node keeps taking samples (a sweep's data must
//! not wait in a reader's history while the model is refitted). When sweeps complete faster
//! than updates finish, the next update takes every sweep completed meanwhile: the model is
//! never more than one update behind the data. Time is each message's stamp (rig time).

use futures::StreamExt;
use node_runtime::{LossWatch, RosNode, RuntimeError, Shutdown, SuiteTopic};
use tokio::task::JoinHandle;
use tyre_msgs::diagnostic_msgs::DiagnosticArray;
use tyre_msgs::{ModelCovariance, ModelState, ProcedureState, RigSample};

use crate::LiveFitConfig;
use crate::core::{LiveFit, Trigger, UpdateDone};
use crate::output::{ModelOutput, write_model};

/// The fit node's config (`[node.config]` of a launch file with `kind = "fit"`).
#[derive(Debug, Clone, Default, PartialEq, serde::Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct FitNodeConfig {
    /// The fit's settings.
    pub fit: LiveFitConfig,
    /// Where the final model goes.
    pub output: ModelOutput,
}

/// Why the node stopped with an error.
#[derive(Debug, thiserror::Error)]
pub enum FitNodeError {
    #[error(transparent)]
    Runtime(#[from] RuntimeError),
    #[error(transparent)]
    Output(#[from] crate::output::OutputError),
}

/// Runs the live fit until shutdown. A final update that is running when shutdown comes is
/// finished (and its model written) first.
pub async fn run(mut node: RosNode, cfg: FitNodeConfig, shutdown: Shutdown) -> Result<(), FitNodeError> {
    let mut core = LiveFit::new(cfg.fit.clone());
    let state_pub = node.publisher::<ModelState>(SuiteTopic::ModelState)?;
    let covariance_pub = node.publisher::<ModelCovariance>(SuiteTopic::ModelCovariance)?;
    let diag_pub = node.publisher::<DiagnosticArray>(SuiteTopic::Diagnostics)?;
    let samples = node.subscription::<RigSample>(SuiteTopic::RigSample)?;
    let states = node.subscription::<ProcedureState>(SuiteTopic::ProcedureState)?;
    let mut samples = Box::pin(samples.async_stream());
    let mut states = Box::pin(states.async_stream());
    let (sample_topic, state_topic) =
        (node.topic_name(SuiteTopic::RigSample), node.topic_name(SuiteTopic::ProcedureState));
    let mut loss = LossWatch::new(node.name());
    let mut stamp = tyre_msgs::builtin_interfaces::Time::default();
    let mut running: Option<JoinHandle<UpdateDone>> = None;
    let mut final_due = false;
    let mut final_started = false;
    loop {
        // Start an update when one is due and none is running.
        if running.is_none() {
            if final_due && !final_started {
                final_started = true;
                let job = core.begin_final();
                running = Some(tokio::task::spawn_blocking(move || job.run()));
            } else if !final_started && core.update_due() {
                let job = core.begin_update();
                running = Some(tokio::task::spawn_blocking(move || job.run()));
            }
        }
        tokio::select! {
            _ = shutdown.wait(), if !final_started || running.is_none() => break,
            done = async { running.as_mut().expect("guarded").await }, if running.is_some() => {
                running = None;
                let Ok(done) = done else {
                    tracing::error!("a live-fit update panicked; the node keeps the previous model");
                    continue;
                };
                let st = core.end_update(done);
                if !st.error.is_empty() {
                    tracing::info!(error = st.error, "live fit: no model yet");
                }
                if let Err(e) = state_pub.publish(st.clone()) {
                    tracing::warn!("model/state publish: {e:?}");
                }
                if let Err(e) = covariance_pub.publish(core.model_covariance()) {
                    tracing::warn!("model/covariance publish: {e:?}");
                }
                if st.final_update {
                    if let Some(result) = core.latest() {
                        let files = write_model(result, &cfg.output)?;
                        tracing::info!(files = files.len(), "live fit: final model written");
                    }
                    final_due = false;
                }
            }
            item = states.next() => match item {
                Some(Ok((st, info))) => {
                    loss.on_message(&state_topic, &info, None);
                    if core.on_procedure_state(&st) == Trigger::Final {
                        final_due = true;
                    }
                }
                Some(Err(e)) => loss.on_read_error(&state_topic, &e),
                None => break,
            },
            item = samples.next() => match item {
                Some(Ok((s, info))) => {
                    loss.on_message(&sample_topic, &info, Some(s.seq));
                    stamp = s.header.stamp;
                    core.on_sample(&s);
                }
                Some(Err(e)) => loss.on_read_error(&sample_topic, &e),
                None => break,
            },
        }
        loss.announce(&diag_pub, stamp);
    }
    Ok(())
}

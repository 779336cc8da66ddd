//! The quality node's DDS shell: the channels and monitor cores in one process, wired by
//! [`Pipeline`] exactly as a headless run and a replay wire them, so a recorded log replays to
//! the same outputs.
//!
//! In: `rig/sample`, `procedure/state`, `model/state` (the live fit's, when one runs: followed by
//! [`ModelWatch`]). Out: `rig/channels/live` (every sample),
//! `rig/channels/sweep_summary`, `rig/quality/report` (on change), `/diagnostics` (with every
//! report and every model update). Derived measurements and alarms are logged (tracing) as they come.
//!
//! Time is each message's stamp (rig time), never the wall clock.

use futures::StreamExt;
use node_runtime::{LossWatch, RosNode, RuntimeError, Shutdown, SuiteTopic};
use tyre_msgs::diagnostic_msgs::DiagnosticArray;
use tyre_msgs::{DerivedMeasurement, LiveChannels, ModelState, ProcedureState, QualityReport, RigSample, SweepSummary};

use crate::config::{ConfigError, MonitorConfig, TyreInfo};
use crate::model_watch::ModelWatch;
use crate::pipeline::{Pipeline, PipelineError, PipelineOutput};

/// The quality node's config (`[node.config]` of a launch file with `kind = "quality"`).
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct QualityNodeConfig {
    /// The ETRTO load index the tyre declares (sidewall, data sheet): the monitor judges the
    /// loads against this rating, not against what the operator typed in at the rig.
    pub load_index: u32,
    /// The tyre's own nominal load [N] when its rating is not an ETRTO index (race tyres);
    /// replaces the index's Fz0.
    pub fz0_n: Option<f64>,
    /// Tread depth of the new tyre [mm].
    pub tread_new_mm: f64,
    /// Legal minimum tread depth [mm].
    pub tread_min_mm: f64,
    /// The channels core's settings.
    pub channels: channels::ChannelsConfig,
    /// The monitor core's settings (thresholds).
    pub monitor: MonitorConfig,
}

impl Default for QualityNodeConfig {
    fn default() -> Self {
        Self {
            load_index: 110,
            fz0_n: None,
            tread_new_mm: 5.6,
            tread_min_mm: 1.6,
            channels: channels::ChannelsConfig::default(),
            monitor: MonitorConfig::default(),
        }
    }
}

impl QualityNodeConfig {
    /// The tyre as the monitor sees it; an unknown load index or a tread depth that is not
    /// positive and above the minimum is refused.
    pub fn tyre(&self) -> Result<TyreInfo, ConfigError> {
        let mut t = TyreInfo::from_load_index(self.load_index)?;
        if !(self.tread_min_mm.is_finite() && self.tread_min_mm >= 0.0) {
            return Err(ConfigError::Invalid {
                key: "tread_min_mm",
                value: self.tread_min_mm,
                reason: "needs a finite depth ≥ 0 mm",
            });
        }
        if !(self.tread_new_mm.is_finite() && self.tread_new_mm > self.tread_min_mm) {
            return Err(ConfigError::Invalid {
                key: "tread_new_mm",
                value: self.tread_new_mm,
                reason: "needs a finite depth above tread_min_mm",
            });
        }
        t.tread_new_mm = self.tread_new_mm;
        t.tread_min_mm = self.tread_min_mm;
        if let Some(f) = self.fz0_n {
            t.fz0_n = f;
            t.validate()?;
        }
        Ok(t)
    }

    /// Checks every setting (also done when the node starts).
    pub fn validate(&self) -> Result<(), PipelineError> {
        Pipeline::new(self.channels.clone(), self.monitor.clone(), self.tyre()?).map(|_| ())
    }
}

/// Why the node stopped with an error.
#[derive(Debug, thiserror::Error)]
pub enum QualityNodeError {
    /// A configuration was refused.
    #[error(transparent)]
    Config(#[from] PipelineError),
    /// The tyre's rating or tread depths were refused.
    #[error(transparent)]
    Tyre(#[from] ConfigError),
    /// DDS failed.
    #[error(transparent)]
    Runtime(#[from] RuntimeError),
}

/// Runs the channels and monitor cores until shutdown.
pub async fn run(mut node: RosNode, cfg: QualityNodeConfig, shutdown: Shutdown) -> Result<(), QualityNodeError> {
    let tyre = cfg.tyre()?;
    let mut p = Pipeline::new(cfg.channels, cfg.monitor, tyre)?;
    let live_pub = node.publisher::<LiveChannels>(SuiteTopic::LiveChannels)?;
    let sum_pub = node.publisher::<SweepSummary>(SuiteTopic::SweepSummary)?;
    let derived_pub = node.publisher::<DerivedMeasurement>(SuiteTopic::Derived)?;
    let rep_pub = node.publisher::<QualityReport>(SuiteTopic::QualityReport)?;
    let diag_pub = node.publisher::<DiagnosticArray>(SuiteTopic::Diagnostics)?;
    let samples = node.subscription::<RigSample>(SuiteTopic::RigSample)?;
    let states = node.subscription::<ProcedureState>(SuiteTopic::ProcedureState)?;
    let mut samples = Box::pin(samples.async_stream());
    let models = node.subscription::<ModelState>(SuiteTopic::ModelState)?;
    let mut states = Box::pin(states.async_stream());
    let mut models = Box::pin(models.async_stream());
    let mut watch = ModelWatch::new();
    let publish_errors = node_runtime::PublishErrors::new();
    // The late joiner's view: the current verdicts at once.
    publish_errors.check(SuiteTopic::QualityReport, rep_pub.publish(p.monitor.report(0.0)));
    let publish = |o: PipelineOutput, live: bool| {
        if live && let Err(e) = live_pub.publish(o.live) {
            tracing::warn!("channels/live publish: {e:?}");
        }
        for x in o.sweep_summaries {
            publish_errors.check(SuiteTopic::SweepSummary, sum_pub.publish(x));
        }
        for d in &o.derived {
            publish_errors.check(SuiteTopic::Derived, derived_pub.publish(d.to_msg()));
            tracing::info!(
                "{}: {} = {} {} (Fz {:.0} N, p {:.0} Pa)",
                d.section,
                d.quantity.name(),
                d.value,
                d.quantity.unit(),
                d.fz_n,
                d.pressure_pa
            );
        }
        for a in &o.alarms {
            tracing::warn!("{} {} at {:.1} s: {}", a.level, a.check, a.rig_time_s, a.message);
        }
        if let Some(r) = o.report {
            publish_errors.check(SuiteTopic::QualityReport, rep_pub.publish(r));
        }
        if let Some(d) = o.diagnostics {
            publish_errors.check(SuiteTopic::Diagnostics, diag_pub.publish(d));
        }
    };
    let (sample_topic, state_topic, model_topic) = (
        node.topic_name(SuiteTopic::RigSample),
        node.topic_name(SuiteTopic::ProcedureState),
        node.topic_name(SuiteTopic::ModelState),
    );
    let mut loss = LossWatch::new(node.name());
    let mut stamp = tyre_msgs::builtin_interfaces::Time::default();
    loop {
        tokio::select! {
            _ = shutdown.wait() => break,
            item = states.next() => match item {
                Some(Ok((st, info))) => {
                    loss.on_message(&state_topic, &info, None);
                    p.on_procedure_state(&st)
                }
                Some(Err(e)) => loss.on_read_error(&state_topic, &e),
                None => break,
            },
            // The live fit (when one runs): its progress on the log and /diagnostics.
            item = models.next() => match item {
                Some(Ok((m, info))) => {
                    loss.on_message(&model_topic, &info, None);
                    let o = watch.on_model_state(&m);
                    tracing::info!("{}", o.summary);
                    for e in &o.events {
                        if e.level == tyre_msgs::diagnostic_msgs::DiagnosticStatus::OK {
                            tracing::info!("live model at {:.1} s: {}", e.rig_time_s, e.message);
                        } else {
                            tracing::warn!("live model at {:.1} s: {}", e.rig_time_s, e.message);
                        }
                    }
                    publish_errors.check(SuiteTopic::Diagnostics, diag_pub.publish(o.diagnostics));
                }
                Some(Err(e)) => loss.on_read_error(&model_topic, &e),
                None => break,
            },
            item = samples.next() => match item {
                Some(Ok((s, info))) => {
                    loss.on_message(&sample_topic, &info, Some(s.seq));
                    stamp = s.header.stamp;
                    publish(p.on_sample(&s), true)
                }
                Some(Err(e)) => loss.on_read_error(&sample_topic, &e),
                None => break,
            },
        }
        loss.announce(&diag_pub, stamp);
    }
    // The sweep in progress, the last section's derived measurements and the final verdicts (a
    // recorder still running logs them). The participant lives on briefly so that reliable DDS
    // delivers them before it goes.
    publish(p.finish(), false);
    tokio::time::sleep(std::time::Duration::from_millis(300)).await;
    Ok(())
}

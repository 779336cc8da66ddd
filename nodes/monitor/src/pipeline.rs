//! The channels and monitor cores wired together in one fixed order — what a headless runner,
//! a combined node or a replay calls, so that all of them produce the same outputs from the
//! same inputs.
//!
//! Per sample: the channels core first, then the monitor with the sample, then the sample's
//! live channels, then each sweep summary the sample completed. A procedure state goes to both
//! cores (each applies it to the samples stamped after it).

use channels::{ChannelsConfig, ChannelsCore, DerivedMeasurement};
use tyre_msgs::diagnostic_msgs::DiagnosticArray;
use tyre_msgs::{LiveChannels, ProcedureState, QualityReport, RigSample, SweepSummary};

use crate::config::{MonitorConfig, TyreInfo};
use crate::core::{Alarm, MonitorCore, MonitorOutput};

/// Why the pipeline could not be built.
#[derive(Debug, thiserror::Error)]
pub enum PipelineError {
    /// The channels configuration is invalid.
    #[error(transparent)]
    Channels(#[from] channels::ConfigError),
    /// The monitor configuration or tyre description is invalid.
    #[error(transparent)]
    Monitor(#[from] crate::config::ConfigError),
}

/// Everything one input produced, ready to publish.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct PipelineOutput {
    /// `rig/channels/live` (default-valued from [`Pipeline::finish`]).
    pub live: LiveChannels,
    /// `rig/channels/sweep_summary`.
    pub sweep_summaries: Vec<SweepSummary>,
    /// Derived measurements of sections that ended.
    pub derived: Vec<DerivedMeasurement>,
    /// `rig/quality/report`, when it changed.
    pub report: Option<QualityReport>,
    /// `/diagnostics`, with every report.
    pub diagnostics: Option<DiagnosticArray>,
    /// New alarms for the run summary.
    pub alarms: Vec<Alarm>,
}

impl PipelineOutput {
    fn absorb(&mut self, m: MonitorOutput) {
        if m.report.is_some() {
            self.report = m.report;
            self.diagnostics = m.diagnostics;
        }
        self.alarms.extend(m.alarms);
    }
}

/// The channels core feeding the monitor core.
#[derive(Debug, Clone)]
pub struct Pipeline {
    /// The channels core.
    pub channels: ChannelsCore,
    /// The monitor core.
    pub monitor: MonitorCore,
}

impl Pipeline {
    /// Both cores, validated.
    pub fn new(channels: ChannelsConfig, monitor: MonitorConfig, tyre: TyreInfo) -> Result<Self, PipelineError> {
        Ok(Self { channels: ChannelsCore::new(channels)?, monitor: MonitorCore::new(monitor, tyre)? })
    }

    /// A procedure state.
    pub fn on_procedure_state(&mut self, st: &ProcedureState) {
        self.channels.on_procedure_state(st);
        self.monitor.on_procedure_state(st);
    }

    /// A rig sample.
    pub fn on_sample(&mut self, s: &RigSample) -> PipelineOutput {
        let c = self.channels.on_sample(s);
        let mut out = PipelineOutput::default();
        out.absorb(self.monitor.on_sample(s));
        self.monitor.on_live_channels(&c.live);
        for ss in &c.sweep_summaries {
            out.absorb(self.monitor.on_sweep_summary(ss));
        }
        out.live = c.live;
        out.sweep_summaries = c.sweep_summaries;
        out.derived = c.derived;
        out
    }

    /// The end of the run or log: flushes both cores.
    pub fn finish(&mut self) -> PipelineOutput {
        let c = self.channels.finish();
        let mut out = PipelineOutput::default();
        for ss in &c.sweep_summaries {
            out.absorb(self.monitor.on_sweep_summary(ss));
        }
        out.absorb(self.monitor.finish());
        out.sweep_summaries = c.sweep_summaries;
        out.derived = c.derived;
        out
    }
}

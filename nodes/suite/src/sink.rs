//! Where a run's messages go.

use mcaplog::{LogWriteError, McapLog, McapLogOptions, codec};
use std::{collections::BTreeMap, path::Path};
use tyre_msgs::{
    DerivedMeasurement, LiveChannels, ModelCovariance, ModelState, ProcedureState, QualityReport, RigSample,
    RigSetpoint, RosMessage, SweepSummary, ThermalState, diagnostic_msgs::DiagnosticArray, topics,
};

/// One message leaving the cores, tagged with its topic.
#[derive(Debug, Clone, Copy)]
pub enum Outgoing<'a> {
    Sample(&'a RigSample),
    Setpoint(&'a RigSetpoint),
    Thermal(&'a ThermalState),
    Procedure(&'a ProcedureState),
    Live(&'a LiveChannels),
    SweepSummary(&'a SweepSummary),
    Derived(&'a DerivedMeasurement),
    Quality(&'a QualityReport),
    Diagnostics(&'a DiagnosticArray),
    Model(&'a ModelState),
    Covariance(&'a ModelCovariance),
}

impl Outgoing<'_> {
    /// Topic name relative to the namespace (or absolute), as in the suite's topic table.
    pub fn topic(&self) -> &'static str {
        match self {
            Outgoing::Sample(_) => topics::RIG_SAMPLE,
            Outgoing::Setpoint(_) => topics::RIG_SETPOINT,
            Outgoing::Thermal(_) => topics::THERMAL_STATE,
            Outgoing::Procedure(_) => topics::PROCEDURE_STATE,
            Outgoing::Live(_) => topics::CHANNELS_LIVE,
            Outgoing::SweepSummary(_) => topics::SWEEP_SUMMARY,
            Outgoing::Derived(_) => topics::DERIVED,
            Outgoing::Quality(_) => topics::QUALITY_REPORT,
            Outgoing::Diagnostics(_) => topics::DIAGNOSTICS,
            Outgoing::Model(_) => topics::MODEL_STATE,
            Outgoing::Covariance(_) => topics::MODEL_COVARIANCE,
        }
    }
}

/// A consumer of a run's messages. `t_s` is the rig (simulated) time they were produced at.
pub trait MessageSink {
    fn put(&mut self, t_s: f64, msg: Outgoing<'_>) -> Result<(), LogWriteError>;
}

/// Drops everything (speed measurements, tests that only need the summary).
#[derive(Debug, Default)]
pub struct NullSink {
    pub messages: u64,
}

impl MessageSink for NullSink {
    fn put(&mut self, _t_s: f64, _msg: Outgoing<'_>) -> Result<(), LogWriteError> {
        self.messages += 1;
        Ok(())
    }
}

/// Writes a ROS 2-profile MCAP log. In a headless run `log_time` is the simulated time the
/// message was produced at (there is no receive time); `publish_time` is its stamp, as always.
pub struct McapSink {
    log: McapLog,
    namespace: String,
    channels: BTreeMap<&'static str, u16>,
}

impl std::fmt::Debug for McapSink {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("McapSink").field("log", &self.log).finish()
    }
}

impl McapSink {
    /// Creates the log with the given metadata records.
    pub fn create(
        path: &Path,
        namespace: &str,
        metadata: &BTreeMap<String, BTreeMap<String, String>>,
    ) -> Result<Self, LogWriteError> {
        let mut log = McapLog::create(path, McapLogOptions { flush_interval_s: 10.0, ..Default::default() })?;
        for (name, entries) in metadata {
            log.write_metadata(name, entries)?;
        }
        Ok(Self { log, namespace: namespace.trim_end_matches('/').to_owned(), channels: BTreeMap::new() })
    }

    fn channel<M: RosMessage>(&mut self, topic: &'static str) -> Result<u16, LogWriteError> {
        if let Some(id) = self.channels.get(topic) {
            return Ok(*id);
        }
        let full = if topic.starts_with('/') { topic.to_owned() } else { format!("{}/{topic}", self.namespace) };
        let schema = tyre_msgs::schema::ros2msg_schema::<M>().map_err(|e| LogWriteError::UnknownType {
            path: self.log.path().to_owned(),
            type_name: format!("{} ({e})", M::ros_type_name()),
        })?;
        let id = self.log.ensure_channel(&full, &M::ros_type_name(), &schema)?;
        self.channels.insert(topic, id);
        Ok(id)
    }

    fn write<M: RosMessage>(&mut self, topic: &'static str, t_s: f64, msg: &M) -> Result<(), LogWriteError> {
        let id = self.channel::<M>(topic)?;
        // The type name only for the error: formatting it for each of millions of messages was
        // a visible part of a headless run.
        let data = tyre_msgs::cdr::to_cdr_with_header(msg).map_err(|e| LogWriteError::Mcap {
            path: self.log.path().to_owned(),
            detail: format!("{}: {e}", M::ros_type_name()),
        })?;
        let publish = codec::leading_stamp(&data).map_or(0, |s| s.as_nanos());
        let log_time = (t_s.max(0.0) * 1e9).round() as u64;
        self.log.write(id, log_time, publish, &data)
    }

    /// Completes the log (summary, indexes, footer). Returns the number of messages.
    pub fn finish(self) -> Result<u64, LogWriteError> {
        self.log.finish()
    }
}

impl MessageSink for McapSink {
    fn put(&mut self, t_s: f64, msg: Outgoing<'_>) -> Result<(), LogWriteError> {
        let topic = msg.topic();
        match msg {
            Outgoing::Sample(m) => self.write(topic, t_s, m),
            Outgoing::Setpoint(m) => self.write(topic, t_s, m),
            Outgoing::Thermal(m) => self.write(topic, t_s, m),
            Outgoing::Procedure(m) => self.write(topic, t_s, m),
            Outgoing::Live(m) => self.write(topic, t_s, m),
            Outgoing::SweepSummary(m) => self.write(topic, t_s, m),
            Outgoing::Derived(m) => self.write(topic, t_s, m),
            Outgoing::Quality(m) => self.write(topic, t_s, m),
            Outgoing::Diagnostics(m) => self.write(topic, t_s, m),
            Outgoing::Model(m) => self.write(topic, t_s, m),
            Outgoing::Covariance(m) => self.write(topic, t_s, m),
        }
    }
}

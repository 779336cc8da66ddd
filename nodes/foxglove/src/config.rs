//! The foxglove node's typed configuration (`[node.config]` of a `kind = "foxglove"` node).

use procedure::SweepStyle;
use serde::Deserialize;
use std::path::PathBuf;
use tyre_msgs::ProcedureCommand;

/// `[node.config]` of a foxglove node.
#[derive(Debug, Clone, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct FoxgloveNodeConfig {
    /// Address the WebSocket server listens on. The default serves this machine only; a control
    /// room on another machine needs `"0.0.0.0"` (or the interface's address).
    #[serde(default = "default_host")]
    pub host: String,
    /// TCP port (Foxglove's default is 8765; 0 picks a free one and logs it).
    #[serde(default = "default_port")]
    pub port: u16,
    /// Commands a Foxglove client may publish on `procedure/command` (`"PAUSE"`, `"RESUME"`,
    /// `"START"`, `"ABORT"`, `"ESTOP"`). Empty (the default): clients may only watch.
    #[serde(default)]
    pub allow_commands: Vec<String>,
    /// Outgoing messages queued per client; when a slow client's queue is full its oldest
    /// messages are dropped (never the suite's).
    #[serde(default = "default_backlog")]
    pub message_backlog: usize,
    /// How often (wall clock) the sweep trace and progress views are refreshed [Hz].
    #[serde(default = "default_view_rate")]
    pub view_rate_hz: f64,
    /// Most points kept per sweep in the sweep trace (decimated evenly when a sweep has more).
    #[serde(default = "default_trace_points")]
    pub trace_max_points: usize,
    /// The procedure file of the run, to serve its plan (`foxglove/plan`); absent = no plan view.
    #[serde(default)]
    pub procedure: Option<PathBuf>,
    /// ETRTO load index the plan is expanded for (as the sequencer's).
    #[serde(default = "default_load_index")]
    pub load_index: u32,
    /// Sweep style the plan is expanded with (as the sequencer's).
    #[serde(default)]
    pub sweeps: SweepStyle,
}

fn default_host() -> String {
    "127.0.0.1".to_owned()
}
fn default_port() -> u16 {
    8765
}
fn default_backlog() -> usize {
    1024
}
fn default_view_rate() -> f64 {
    5.0
}
fn default_trace_points() -> usize {
    2000
}
fn default_load_index() -> u32 {
    110
}

impl Default for FoxgloveNodeConfig {
    fn default() -> Self {
        Self {
            host: default_host(),
            port: default_port(),
            allow_commands: Vec::new(),
            message_backlog: default_backlog(),
            view_rate_hz: default_view_rate(),
            trace_max_points: default_trace_points(),
            procedure: None,
            load_index: default_load_index(),
            sweeps: SweepStyle::default(),
        }
    }
}

/// A foxglove setting that cannot work; each names its key.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum FoxgloveConfigError {
    #[error("allow_commands: {0:?} is not a ProcedureCommand (expected START, PAUSE, RESUME, ABORT or ESTOP)")]
    UnknownCommand(String),
    #[error("message_backlog = {0}: expected at least 16 messages")]
    Backlog(usize),
    #[error("view_rate_hz = {0}: expected a rate in (0, 100] Hz")]
    ViewRate(f64),
    #[error("trace_max_points = {0}: expected 10..=100000")]
    TracePoints(usize),
    #[error("host is empty: expected an address such as \"127.0.0.1\" or \"0.0.0.0\"")]
    Host,
}

/// The command constant a name stands for (case-insensitive).
pub fn command_code(name: &str) -> Option<u8> {
    match name.to_ascii_uppercase().as_str() {
        "START" => Some(ProcedureCommand::START),
        "PAUSE" => Some(ProcedureCommand::PAUSE),
        "RESUME" => Some(ProcedureCommand::RESUME),
        "ABORT" => Some(ProcedureCommand::ABORT),
        "ESTOP" => Some(ProcedureCommand::ESTOP),
        _ => None,
    }
}

/// The name of a command constant (`"?"` for a value the `.msg` does not define).
pub fn command_name(code: u8) -> &'static str {
    match code {
        ProcedureCommand::START => "START",
        ProcedureCommand::PAUSE => "PAUSE",
        ProcedureCommand::RESUME => "RESUME",
        ProcedureCommand::ABORT => "ABORT",
        ProcedureCommand::ESTOP => "ESTOP",
        _ => "?",
    }
}

impl FoxgloveNodeConfig {
    pub fn validate(&self) -> Result<(), FoxgloveConfigError> {
        if self.host.trim().is_empty() {
            return Err(FoxgloveConfigError::Host);
        }
        for c in &self.allow_commands {
            command_code(c).ok_or_else(|| FoxgloveConfigError::UnknownCommand(c.clone()))?;
        }
        if self.message_backlog < 16 {
            return Err(FoxgloveConfigError::Backlog(self.message_backlog));
        }
        if !(self.view_rate_hz.is_finite() && self.view_rate_hz > 0.0 && self.view_rate_hz <= 100.0) {
            return Err(FoxgloveConfigError::ViewRate(self.view_rate_hz));
        }
        if !(10..=100_000).contains(&self.trace_max_points) {
            return Err(FoxgloveConfigError::TracePoints(self.trace_max_points));
        }
        Ok(())
    }

    /// The allowed command codes (validated names only).
    pub fn allowed_codes(&self) -> Vec<u8> {
        self.allow_commands.iter().filter_map(|c| command_code(c)).collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn defaults_validate_and_allow_nothing() {
        let c = FoxgloveNodeConfig::default();
        assert_eq!(c.validate(), Ok(()));
        assert!(c.allowed_codes().is_empty());
        assert_eq!(c.port, 8765);
    }

    #[test]
    fn bad_settings_name_their_key() {
        let bad = |f: &dyn Fn(&mut FoxgloveNodeConfig)| {
            let mut c = FoxgloveNodeConfig::default();
            f(&mut c);
            c.validate().expect_err("must be refused").to_string()
        };
        assert!(bad(&|c| c.allow_commands = vec!["PAUSE".into(), "REBOOT".into()]).contains("\"REBOOT\""));
        assert!(bad(&|c| c.message_backlog = 2).contains("message_backlog"));
        assert!(bad(&|c| c.view_rate_hz = 0.0).contains("view_rate_hz"));
        assert!(bad(&|c| c.trace_max_points = 1).contains("trace_max_points"));
        assert!(bad(&|c| c.host = String::new()).contains("host"));
    }

    #[test]
    fn command_names_round_trip() {
        for name in ["START", "PAUSE", "RESUME", "ABORT", "ESTOP"] {
            assert_eq!(command_name(command_code(name).expect(name)), name);
            assert_eq!(command_code(&name.to_lowercase()), command_code(name));
        }
        assert_eq!(command_code("STOP"), None);
    }
}

//! The command gate: what a Foxglove client publishes on `procedure/command` reaches the
//! sequencer only if the launch file allows that command. Everything else is refused with a
//! reason the client is shown (and the node logs).

use crate::config::command_name;
use tyre_msgs::{ProcedureCommand, RosMessage, builtin_interfaces::Time, cdr::from_cdr_with_header};

/// Judges client messages against the allowed commands.
#[derive(Debug, Clone)]
pub struct CommandGate {
    allowed: Vec<u8>,
    topic: String,
}

impl CommandGate {
    /// `topic`: the full name of `procedure/command` under the node's namespace.
    pub fn new(allowed: Vec<u8>, topic: String) -> Self {
        Self { allowed, topic }
    }

    /// Whether clients may publish at all (the server then offers the client-publish capability).
    pub fn any_allowed(&self) -> bool {
        !self.allowed.is_empty()
    }

    pub fn allowed_names(&self) -> Vec<&'static str> {
        self.allowed.iter().map(|c| command_name(*c)).collect()
    }

    /// Checks a client's channel advertisement before any message: `Err` says why its
    /// messages will be refused.
    pub fn check_channel(&self, topic: &str, encoding: &str, schema_name: &str) -> Result<(), String> {
        if !self.any_allowed() {
            return Err("this server takes no commands (the launch file allows none)".to_owned());
        }
        if topic != self.topic {
            return Err(format!("clients may publish only on {} (not {topic})", self.topic));
        }
        if encoding != "cdr" {
            return Err(format!("{topic}: message encoding {encoding:?}; expected \"cdr\""));
        }
        let ours = ProcedureCommand::ros_type_name();
        let short = format!("{}/{}", ProcedureCommand::PACKAGE, ProcedureCommand::NAME);
        if !schema_name.is_empty() && schema_name != ours && schema_name != short {
            return Err(format!("{topic}: schema {schema_name:?}; expected {ours:?}"));
        }
        Ok(())
    }

    /// Decodes and judges one client message. On success the command is ready to publish:
    /// an unset stamp becomes `rig_time_s`, an unset operator becomes `client`.
    pub fn judge(
        &self,
        topic: &str,
        encoding: &str,
        schema_name: &str,
        payload: &[u8],
        client: &str,
        rig_time_s: f64,
    ) -> Result<ProcedureCommand, String> {
        self.check_channel(topic, encoding, schema_name)?;
        let mut cmd: ProcedureCommand = from_cdr_with_header(payload)
            .map_err(|e| format!("{topic}: not a CDR tyre_msgs/msg/ProcedureCommand ({e})"))?;
        let name = command_name(cmd.command);
        if name == "?" {
            return Err(format!("{topic}: command = {} is not a ProcedureCommand constant", cmd.command));
        }
        if !self.allowed.contains(&cmd.command) {
            return Err(format!(
                "{topic}: {name} is not allowed from Foxglove (the launch file allows: {})",
                self.allowed_names().join(", ")
            ));
        }
        if cmd.header.stamp == Time::default() {
            cmd.header.stamp = Time::from_secs_f64(rig_time_s.max(0.0));
        }
        if cmd.operator_name.trim().is_empty() {
            cmd.operator_name = client.to_owned();
        }
        Ok(cmd)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use tyre_msgs::cdr::to_cdr_with_header;

    const TOPIC: &str = "/rig/procedure/command";
    const SCHEMA: &str = "tyre_msgs/msg/ProcedureCommand";

    fn payload(command: u8) -> Vec<u8> {
        to_cdr_with_header(&ProcedureCommand { command, ..ProcedureCommand::default() }).expect("cdr")
    }

    #[test]
    fn allowed_commands_pass_with_stamp_and_operator_filled_in() {
        let gate = CommandGate::new(vec![ProcedureCommand::PAUSE, ProcedureCommand::RESUME], TOPIC.into());
        let cmd = gate.judge(TOPIC, "cdr", SCHEMA, &payload(ProcedureCommand::PAUSE), "foxglove 1", 12.5).expect("ok");
        assert_eq!(cmd.command, ProcedureCommand::PAUSE);
        assert_eq!(cmd.operator_name, "foxglove 1");
        assert_eq!(cmd.header.stamp.as_secs_f64(), 12.5);
    }

    #[test]
    fn everything_else_is_refused_with_a_reason() {
        let gate = CommandGate::new(vec![ProcedureCommand::PAUSE], TOPIC.into());
        let refuse = |topic: &str, enc: &str, schema: &str, bytes: &[u8]| {
            gate.judge(topic, enc, schema, bytes, "c", 0.0).expect_err("must be refused")
        };
        assert!(refuse(TOPIC, "cdr", SCHEMA, &payload(ProcedureCommand::ESTOP)).contains("ESTOP is not allowed"));
        assert!(refuse(TOPIC, "cdr", SCHEMA, &payload(9)).contains("command = 9"));
        assert!(refuse("/rig/setpoint", "cdr", SCHEMA, &payload(1)).contains("only on /rig/procedure/command"));
        assert!(refuse(TOPIC, "json", SCHEMA, b"{}").contains("\"json\""));
        assert!(refuse(TOPIC, "cdr", "std_msgs/msg/String", &payload(1)).contains("std_msgs/msg/String"));
        assert!(refuse(TOPIC, "cdr", SCHEMA, &[0, 1, 0, 0, 7]).contains("not a CDR"));
        let closed = CommandGate::new(Vec::new(), TOPIC.into());
        assert!(!closed.any_allowed());
        assert!(closed.judge(TOPIC, "cdr", SCHEMA, &payload(1), "c", 0.0).expect_err("closed").contains("allows none"));
    }
}

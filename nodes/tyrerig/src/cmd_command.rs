//! `tyrerig command`: an operator station's command to the sequencer over DDS, plain or, with
//! `--keystore`, authenticated as an operator enclave (docs/security.md).

use anyhow::Context as _;
use foxglove_node::core::phase_name;
use futures::StreamExt as _;
use node_runtime::{RosNode, RuntimeConfig, SecurityConfig, SuiteTopic};
use std::{path::PathBuf, time::Duration};
use tyre_msgs::{ProcedureCommand, ProcedureState as PS, builtin_interfaces::Time, std_msgs::Header};

#[derive(Debug, Clone, Copy, clap::ValueEnum)]
pub enum CommandKind {
    Start,
    Pause,
    Resume,
    Abort,
    Estop,
}

impl CommandKind {
    fn code(self) -> u8 {
        match self {
            CommandKind::Start => ProcedureCommand::START,
            CommandKind::Pause => ProcedureCommand::PAUSE,
            CommandKind::Resume => ProcedureCommand::RESUME,
            CommandKind::Abort => ProcedureCommand::ABORT,
            CommandKind::Estop => ProcedureCommand::ESTOP,
        }
    }
}

/// `tyrerig command <start|pause|resume|abort|estop> [--keystore DIR --enclave /rig/operator_1]`
#[derive(Debug, clap::Args)]
pub struct CommandArgs {
    pub command: CommandKind,
    /// START only: procedure name or file (empty: the sequencer's own procedure).
    #[arg(long, default_value = "")]
    pub procedure: String,
    /// Who sends it (logged with the command). Default: $USER.
    #[arg(long)]
    pub operator: Option<String>,
    /// Namespace of the rig's topics.
    #[arg(long, default_value = "/rig")]
    pub namespace: String,
    /// DDS domain (default: ROS_DOMAIN_ID, else 0).
    #[arg(long)]
    pub domain_id: Option<u16>,
    /// SROS2 keystore: send as an authenticated operator station (DDS Security).
    #[arg(long)]
    pub keystore: Option<PathBuf>,
    /// The station's enclave in the keystore (it needs the operator role).
    #[arg(long, default_value = "/rig/operator")]
    pub enclave: String,
    /// How long to wait for the sequencer to be discovered.
    #[arg(long, default_value_t = 20.0)]
    pub timeout_s: f64,
    /// After sending, wait this long [s] for the sequencer's `procedure/state` to show the
    /// command taken (START: running, PAUSE: paused, RESUME: running again, ABORT: aborted,
    /// ESTOP: e-stopped), and fail if it does not; 0: do not wait. "Sent" alone does not prove
    /// that the sequencer heard it: any subscriber of `procedure/command` (a recorder) lets
    /// the command go (docs/security.md, a stalled handshake).
    #[arg(long, default_value_t = 10.0)]
    pub confirm_s: f64,
}

/// Phases in which no procedure runs.
const STOPPED: [u8; 4] = [PS::PHASE_IDLE, PS::PHASE_COMPLETE, PS::PHASE_ABORTED, PS::PHASE_ESTOP];

/// Whether the sequencer's state `now` shows `command` taken, given the phase it showed before
/// the command was sent (`None`: no state seen before).
pub fn taken(command: u8, before: Option<u8>, now: u8) -> bool {
    let running = |p: u8| !STOPPED.contains(&p) && p != PS::PHASE_PAUSED;
    match command {
        ProcedureCommand::START => running(now) && before.is_none_or(|b| STOPPED.contains(&b)),
        ProcedureCommand::PAUSE => now == PS::PHASE_PAUSED,
        ProcedureCommand::RESUME => running(now) && before.is_none_or(|b| b == PS::PHASE_PAUSED),
        ProcedureCommand::ABORT => now == PS::PHASE_ABORTED,
        ProcedureCommand::ESTOP => now == PS::PHASE_ESTOP,
        _ => false,
    }
}

pub fn run(args: CommandArgs) -> anyhow::Result<()> {
    // The node is named after the enclave's last segment, in the rig's namespace.
    let node_name = args.enclave.rsplit('/').next().filter(|s| !s.is_empty()).unwrap_or("operator").to_owned();
    let security = args.keystore.as_ref().map(|k| {
        let mut s = SecurityConfig::new(k);
        s.enclaves.insert(node_name.clone(), args.enclave.clone());
        s
    });
    let cfg = RuntimeConfig { namespace: args.namespace.clone(), domain_id: args.domain_id, security };
    let operator = args.operator.clone().or_else(|| std::env::var("USER").ok()).unwrap_or_else(|| "operator".into());
    let rt = tokio::runtime::Builder::new_multi_thread().enable_all().build().context("tokio")?;
    rt.block_on(async {
        let mut node = RosNode::new(&node_name, &cfg)?;
        let publisher = node.publisher::<ProcedureCommand>(SuiteTopic::ProcedureCommand)?;
        let topic = node.topic_name(SuiteTopic::ProcedureCommand);
        // Commands are volatile (never replayed to late joiners): send only once someone listens.
        let deadline = tokio::time::Instant::now() + Duration::from_secs_f64(args.timeout_s);
        while node.discovered_subscriptions(SuiteTopic::ProcedureCommand) == 0 {
            if tokio::time::Instant::now() > deadline {
                anyhow::bail!(
                    "no subscriber on {topic} (domain {}) within {} s: is the suite running{}?",
                    node.domain_id(),
                    args.timeout_s,
                    if cfg.security.is_some() { ", with this keystore" } else { " without [security]" }
                );
            }
            tokio::time::sleep(Duration::from_millis(50)).await;
        }
        // Discovery comes first; the writer's match (and, secured, the key exchange) and the
        // other subscribers (sequencer and recorder) follow within moments. Meanwhile the
        // sequencer's state says where the procedure stands before the command.
        let states = if args.confirm_s > 0.0 {
            Some(node.subscription::<PS>(SuiteTopic::ProcedureState)?)
        } else {
            None
        };
        let mut states = states.as_ref().map(|s| Box::pin(s.async_stream()));
        let mut before: Option<u8> = None;
        // When confirming, send only once the sequencer's own state has arrived (up to the
        // discovery deadline): that proves the sequencer and this station have matched
        // (secured: authenticated each other), where a discovered recorder proves nothing. A
        // START sent 3 s after a secured suite's launch was lost that way.
        let settle = tokio::time::sleep(Duration::from_millis(1500));
        tokio::pin!(settle);
        let mut settled = false;
        loop {
            if settled && (states.is_none() || before.is_some() || tokio::time::Instant::now() > deadline) {
                break;
            }
            tokio::select! {
                _ = &mut settle, if !settled => settled = true,
                _ = tokio::time::sleep(Duration::from_millis(50)), if settled => {}
                Some(Ok((st, _))) = async { match states.as_mut() { Some(s) => s.next().await, None => None } } => {
                    before = Some(st.phase);
                }
            }
        }
        let now = std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH).unwrap_or_default();
        let cmd = ProcedureCommand {
            header: Header {
                stamp: Time { sec: now.as_secs() as i32, nanosec: now.subsec_nanos() },
                frame_id: String::new(),
            },
            command: args.command.code(),
            procedure: args.procedure.clone(),
            operator_name: operator.clone(),
        };
        publisher.publish(cmd).map_err(|e| anyhow::anyhow!("{topic}: cannot send: {e:?}"))?;
        println!("{:?} sent on {topic} by {operator:?}", args.command);
        let Some(states) = states.as_mut() else {
            // Reliable delivery (and any resend) needs the participant alive a moment longer.
            tokio::time::sleep(Duration::from_secs(1)).await;
            return anyhow::Ok(());
        };
        let code = args.command.code();
        let mut last = before;
        let wait = tokio::time::sleep(Duration::from_secs_f64(args.confirm_s));
        tokio::pin!(wait);
        loop {
            tokio::select! {
                _ = &mut wait => break,
                Some(Ok((st, _))) = states.next() => {
                    last = Some(st.phase);
                    if taken(code, before, st.phase) {
                        println!("{:?} taken: the sequencer is {} ({})", args.command, phase_name(st.phase), st.procedure);
                        return anyhow::Ok(());
                    }
                }
            }
        }
        let state_topic = node.topic_name(SuiteTopic::ProcedureState);
        let seen = match last {
            Some(p) => format!("the sequencer's {state_topic} says {}", phase_name(p)),
            None => format!("no state on {state_topic}"),
        };
        anyhow::bail!(
            "{:?} was sent but not seen taken within {} s ({seen}{}). The sequencer may not have \
             heard it or may have refused it in that phase (its /diagnostics say which); send it \
             again to retry from a fresh participant",
            args.command,
            args.confirm_s,
            before.map(|b| format!("; before the command: {}", phase_name(b))).unwrap_or_default()
        )
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_command_is_taken_only_when_the_state_shows_its_effect() {
        let (c, p) = (ProcedureCommand::START, Some(PS::PHASE_IDLE));
        assert!(taken(c, p, PS::PHASE_SETTLE) && taken(c, None, PS::PHASE_SWEEP));
        assert!(!taken(c, p, PS::PHASE_IDLE));
        // START while a procedure runs is not taken (the sequencer refuses it).
        assert!(!taken(c, Some(PS::PHASE_SWEEP), PS::PHASE_SWEEP));
        assert!(taken(ProcedureCommand::PAUSE, Some(PS::PHASE_SWEEP), PS::PHASE_PAUSED));
        assert!(!taken(ProcedureCommand::PAUSE, Some(PS::PHASE_SWEEP), PS::PHASE_THERMAL_PAUSE));
        assert!(taken(ProcedureCommand::RESUME, Some(PS::PHASE_PAUSED), PS::PHASE_THERMAL_PAUSE));
        assert!(!taken(ProcedureCommand::RESUME, Some(PS::PHASE_PAUSED), PS::PHASE_PAUSED));
        assert!(!taken(ProcedureCommand::RESUME, Some(PS::PHASE_SWEEP), PS::PHASE_SWEEP));
        assert!(taken(ProcedureCommand::ABORT, Some(PS::PHASE_SWEEP), PS::PHASE_ABORTED));
        assert!(!taken(ProcedureCommand::ABORT, None, PS::PHASE_SWEEP));
        assert!(taken(ProcedureCommand::ESTOP, None, PS::PHASE_ESTOP));
        assert!(!taken(ProcedureCommand::ESTOP, None, PS::PHASE_ABORTED));
    }
}

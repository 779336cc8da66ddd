//! `tyrerig command`: an operator station's command to the sequencer over DDS, plain or, with
//! `--keystore`, authenticated as an operator enclave (docs/security.md).

use anyhow::Context as _;
use node_runtime::{RosNode, RuntimeConfig, SecurityConfig, SuiteTopic};
use std::{path::PathBuf, time::Duration};
use tyre_msgs::{ProcedureCommand, builtin_interfaces::Time, std_msgs::Header};

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
        // other subscribers (sequencer and recorder) follow within moments.
        tokio::time::sleep(Duration::from_millis(1500)).await;
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
        // Reliable delivery (and any resend) needs the participant alive a moment longer.
        tokio::time::sleep(Duration::from_secs(1)).await;
        println!("{:?} sent on {topic} by {operator:?}", args.command);
        anyhow::Ok(())
    })
}

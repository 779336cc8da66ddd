//! Real secured participants (RustDDS's builtin DDS Security plugins) with enclaves from a
//! keystore made here: who gets a ProcedureCommand through to the sequencer.
//!
//! - an operator enclave of the keystore: its commands arrive (the control);
//! - a plain participant (no credentials): never heard;
//! - an operator enclave with the same name from another keystore (another identity CA and
//!   permissions CA): never admitted;
//! - a monitor enclave (authenticated, but no publish permission on `procedure/command`):
//!   refused when it tries to make the publisher.
//!
//! Runs only inside `scripts/netns-run` (loopback only, non-zero domain), like every DDS test.

use futures::StreamExt;
use keystore::{EnclaveName, Keystore, Role};
use node_runtime::{RosNode, RuntimeConfig, SecurityConfig, SuiteTopic};
use std::{collections::BTreeSet, path::Path, time::Duration};
use tyre_msgs::ProcedureCommand;

fn now() -> i64 {
    std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH).expect("clock").as_secs() as i64
}

fn keystore(root: &Path, enclaves: &[(&str, Role)]) -> Keystore {
    let ks = Keystore::create(root, now()).expect("keystore");
    for (name, role) in enclaves {
        ks.create_enclave(&EnclaveName::parse(name).expect("name"), *role, now()).expect("enclave");
    }
    ks
}

fn config(ks: Option<&Keystore>) -> RuntimeConfig {
    let cfg = RuntimeConfig { security: ks.map(|k| SecurityConfig::new(k.root())), ..Default::default() };
    let domain = cfg.resolved_domain_id().expect("ROS_DOMAIN_ID must be a valid domain id");
    assert_ne!(domain, 0, "DDS tests run on a non-zero ROS_DOMAIN_ID inside scripts/netns-run");
    cfg
}

fn command(who: &str) -> ProcedureCommand {
    ProcedureCommand { command: ProcedureCommand::ABORT, operator_name: who.into(), ..Default::default() }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn only_the_keystores_operator_reaches_the_sequencer() -> anyhow::Result<()> {
    node_runtime::logging::init();
    let dir = tempfile::tempdir()?;
    let ours = keystore(
        &dir.path().join("ours"),
        &[("/rig/sequencer", Role::Sequencer), ("/rig/operator", Role::Operator), ("/rig/monitor", Role::Monitor)],
    );
    let theirs = keystore(&dir.path().join("theirs"), &[("/rig/operator", Role::Operator)]);

    let mut sequencer = RosNode::new("sequencer", &config(Some(&ours)))?;
    let commands = sequencer.subscription::<ProcedureCommand>(SuiteTopic::ProcedureCommand)?;

    // Authenticated but not authorised: the monitor's own access control refuses the writer.
    let mut monitor = RosNode::new("monitor", &config(Some(&ours)))?;
    let Err(err) = monitor.publisher::<ProcedureCommand>(SuiteTopic::ProcedureCommand) else {
        panic!("a monitor enclave must not get a procedure/command publisher");
    };
    let err = err.to_string();
    assert!(err.contains("security"), "the refusal should say security refused it: {err}");

    let mut operator = RosNode::new("operator", &config(Some(&ours)))?;
    let mut stranger = RosNode::new("operator", &config(Some(&theirs)))?;
    let mut plain = RosNode::new("plain_operator", &config(None))?;
    let senders = [
        ("operator", operator.publisher::<ProcedureCommand>(SuiteTopic::ProcedureCommand)?),
        ("other CA", stranger.publisher::<ProcedureCommand>(SuiteTopic::ProcedureCommand)?),
        ("plain", plain.publisher::<ProcedureCommand>(SuiteTopic::ProcedureCommand)?),
    ];

    // Everyone sends every 100 ms. Once the operator's commands arrive, the others have had
    // the same discovery time; give them 3 s more, then look at who was heard.
    let mut heard = BTreeSet::new();
    let mut stream = Box::pin(commands.async_stream());
    let mut first_at = None;
    let start = tokio::time::Instant::now();
    while first_at.is_none_or(|t: tokio::time::Instant| t.elapsed() < Duration::from_secs(3)) {
        assert!(start.elapsed() < Duration::from_secs(30), "the operator's command never arrived");
        for (who, p) in &senders {
            // A writer that matched nobody may refuse nothing; errors here are not the point.
            let _ = p.publish(command(who));
        }
        let deadline = tokio::time::sleep(Duration::from_millis(100));
        tokio::pin!(deadline);
        loop {
            tokio::select! {
                _ = &mut deadline => break,
                Some(Ok((c, _))) = stream.next() => {
                    if c.operator_name == "operator" {
                        first_at.get_or_insert_with(tokio::time::Instant::now);
                    }
                    heard.insert(c.operator_name);
                }
            }
        }
    }
    assert_eq!(heard, BTreeSet::from(["operator".to_owned()]), "only the operator may reach the sequencer");
    Ok(())
}

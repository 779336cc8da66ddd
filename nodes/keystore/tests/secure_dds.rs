//! Real secured participants (RustDDS's builtin DDS Security plugins) with enclaves from a
//! keystore made here: who gets a ProcedureCommand through to the sequencer.
//!
//! - an operator enclave of the keystore: its commands arrive (the control);
//! - a plain participant (no credentials): never heard;
//! - an operator enclave with the same name from another keystore (another identity CA and
//!   permissions CA): never admitted;
//! - a monitor enclave (authenticated, no publish permission on `procedure/command`): its own
//!   access control refuses the publisher;
//! - the same monitor enclave with a governance that skips write access control on commands
//!   (a peer that does not check itself, simulated): it gets its publisher, is never heard, and
//!   the secured peers log that the permissions it presented do not let it publish commands.
//!
//! Runs only inside `scripts/netns-run` (loopback only, non-zero domain), like every DDS test.

use futures::StreamExt;
use keystore::{EnclaveName, Keystore, Role, pki, policy};
use node_runtime::{RosNode, RuntimeConfig, SecurityConfig, SuiteTopic};
use std::{
    collections::BTreeSet,
    path::{Path, PathBuf},
    time::Duration,
};
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

fn config(keystore: Option<&Path>) -> RuntimeConfig {
    let cfg = RuntimeConfig { security: keystore.map(SecurityConfig::new), ..Default::default() };
    let domain = cfg.resolved_domain_id().expect("ROS_DOMAIN_ID must be a valid domain id");
    assert_ne!(domain, 0, "DDS tests run on a non-zero ROS_DOMAIN_ID inside scripts/netns-run");
    cfg
}

fn command(who: &str) -> ProcedureCommand {
    ProcedureCommand { command: ProcedureCommand::ABORT, operator_name: who.into(), ..Default::default() }
}

/// A keystore directory in `root` holding copies of `enclaves` of `ks`, whose governance has
/// write access control off for `procedure/command` (signed by `ks`'s permissions CA, so it
/// verifies): a participant using it creates command writers without consulting its
/// permissions.
fn without_command_write_control(ks: &Keystore, root: &Path, enclaves: &[&str]) -> PathBuf {
    let xml = policy::governance_xml();
    let rule = xml.find("rt/*/procedure/command").expect("command rule");
    let on = "<enable_write_access_control>true";
    let at = rule + xml[rule..].find(on).expect("write control");
    let forged = format!("{}<enable_write_access_control>false{}", &xml[..at], &xml[at + on.len()..]);
    let ca = openssl::x509::X509::from_pem(&std::fs::read(ks.permissions_ca_cert()).expect("ca")).expect("pem");
    let key =
        openssl::pkey::PKey::private_key_from_pem(&std::fs::read(ks.permissions_ca_key()).expect("key")).expect("pem");
    let governance = pki::smime_sign(forged.as_bytes(), &ca, &key).expect("sign");
    for e in enclaves {
        let name = EnclaveName::parse(e).expect("name");
        let (from, to) = (ks.enclave_dir(&name), root.join("enclaves").join(name.relative_dir()));
        std::fs::create_dir_all(&to).expect("mkdir");
        for f in ["cert.pem", "key.pem", "permissions.p7s", "identity_ca.cert.pem", "permissions_ca.cert.pem"] {
            std::fs::copy(from.join(f), to.join(f)).expect("copy");
        }
        std::fs::write(to.join("governance.p7s"), &governance).expect("write");
    }
    root.to_owned()
}

/// RustDDS's own log records (bridged from `log` into `tracing`), kept for assertions on what the
/// security plugins decided.
mod capture {
    use std::sync::{Arc, Mutex};
    use tracing_subscriber::{Layer, layer::SubscriberExt as _, util::SubscriberInitExt as _};

    #[derive(Clone, Default)]
    pub struct Log(Arc<Mutex<Vec<String>>>);

    impl Log {
        pub fn lines_with(&self, needle: &str) -> Vec<String> {
            self.0.lock().expect("log").iter().filter(|l| l.contains(needle)).cloned().collect()
        }
    }

    struct Message<'a>(&'a mut String);
    impl tracing::field::Visit for Message<'_> {
        fn record_debug(&mut self, field: &tracing::field::Field, value: &dyn std::fmt::Debug) {
            if field.name() == "message" {
                *self.0 = format!("{value:?}");
            }
        }
    }

    impl<S: tracing::Subscriber> Layer<S> for Log {
        fn on_event(&self, event: &tracing::Event<'_>, _: tracing_subscriber::layer::Context<'_, S>) {
            let mut line = String::new();
            event.record(&mut Message(&mut line));
            self.0.lock().expect("log").push(line);
        }
    }

    /// Installs the capture (RustDDS's security decisions are logged at info).
    pub fn install() -> Log {
        let log = Log::default();
        let filter = tracing_subscriber::EnvFilter::new("rustdds::discovery::secure_discovery=info");
        tracing_subscriber::registry().with(log.clone().with_filter(filter)).try_init().expect("one subscriber");
        log
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn only_operators_of_the_keystore_reach_the_sequencer() -> anyhow::Result<()> {
    let log = capture::install();
    let dir = tempfile::tempdir()?;
    let ours = keystore(
        &dir.path().join("ours"),
        &[("/rig/sequencer", Role::Sequencer), ("/rig/operator", Role::Operator), ("/rig/monitor", Role::Monitor)],
    );
    let theirs = keystore(&dir.path().join("theirs"), &[("/rig/operator", Role::Operator)]);
    let lax = without_command_write_control(&ours, &dir.path().join("lax"), &["/rig/monitor"]);

    let mut sequencer = RosNode::new("sequencer", &config(Some(ours.root())))?;
    let commands = sequencer.subscription::<ProcedureCommand>(SuiteTopic::ProcedureCommand)?;

    // Authenticated but not authorised: the monitor's own access control refuses the writer.
    let mut monitor = RosNode::new("monitor", &config(Some(ours.root())))?;
    let Err(err) = monitor.publisher::<ProcedureCommand>(SuiteTopic::ProcedureCommand) else {
        panic!("a monitor enclave must not get a procedure/command publisher");
    };
    assert!(err.to_string().contains("security"), "the refusal should say security refused it: {err}");

    let mut nodes = [
        ("operator", RosNode::new("operator", &config(Some(ours.root())))?),
        ("other CA", RosNode::new("operator", &config(Some(theirs.root())))?),
        ("plain", RosNode::new("plain_operator", &config(None))?),
        ("lax monitor", RosNode::new("monitor", &config(Some(&lax)))?),
    ];
    let mut senders = Vec::new();
    for (who, node) in &mut nodes {
        senders.push((*who, node.publisher::<ProcedureCommand>(SuiteTopic::ProcedureCommand)?));
    }

    // Everyone sends every 100 ms. Once the operator's commands arrive, the others have had the
    // same discovery time; give them 3 s more, then look at who was heard.
    let controls = BTreeSet::from(["operator".to_owned()]);
    let mut heard = BTreeSet::new();
    let mut stream = Box::pin(commands.async_stream());
    let mut controls_at = None;
    let start = tokio::time::Instant::now();
    // RustDDS 0.15.1 sometimes never completes one pair's handshake: the lower-GUID side sends
    // its request and ten resends, the other side never sees them, and both stay
    // "Authenticating" for good (about 1 start in 12 here; docs/security.md). That is a
    // liveness fault of the library, not an admission decision, so the control gets one fresh
    // participant (a new GUID, a new handshake) if it is unheard after 15 s. Who may *not* get
    // through is checked the same either way.
    let mut control_restarted = false;
    // The lax monitor's refusal comes after its own handshake, which takes longer on a loaded
    // machine: keep going (up to 40 s) until a peer has logged it, too.
    let refused = || {
        log.lines_with("Access control check did not pass")
            .iter()
            .any(|l| l.contains("to publish to topic rt/rig/procedure/command"))
    };
    while controls_at.is_none_or(|t: tokio::time::Instant| t.elapsed() < Duration::from_secs(3)) || !refused() {
        if start.elapsed() > Duration::from_secs(if control_restarted { 55 } else { 40 }) {
            assert!(controls_at.is_some(), "the operators were never heard: {heard:?}");
            break;
        }
        if controls_at.is_none() && !control_restarted && start.elapsed() > Duration::from_secs(15) {
            eprintln!("the operator was unheard after 15 s: starting it again as a fresh participant");
            control_restarted = true;
            nodes[0].1 = RosNode::new("operator", &config(Some(ours.root())))?;
            senders[0].1 = nodes[0].1.publisher::<ProcedureCommand>(SuiteTopic::ProcedureCommand)?;
        }
        for (who, p) in &senders {
            // Writers that matched nobody accept the write and send nothing; nothing to check.
            let _ = p.publish(command(who));
        }
        let tick = tokio::time::sleep(Duration::from_millis(100));
        tokio::pin!(tick);
        loop {
            tokio::select! {
                _ = &mut tick => break,
                Some(Ok((c, _))) = stream.next() => { heard.insert(c.operator_name); }
            }
        }
        if controls_at.is_none() && controls.is_subset(&heard) {
            controls_at = Some(tokio::time::Instant::now());
        }
    }
    assert_eq!(heard, controls, "only the keystore's operator may reach the sequencer");
    // The lax monitor was refused on its permissions, not merely unmatched.
    let refusals = log.lines_with("Access control check did not pass");
    assert!(
        refusals.iter().any(|l| l.contains("to publish to topic rt/rig/procedure/command")),
        "no secured peer logged refusing the monitor's command writer: {refusals:?}"
    );
    Ok(())
}

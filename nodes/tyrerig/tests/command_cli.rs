//! `tyrerig command` against a live suite over DDS (the sequencer, the thermal gate and the
//! virtual rig, each its own participant): a command counts as done only when the sequencer's
//! `procedure/state` shows it taken, and one the sequencer does not act on fails, saying so.
//!
//! Runs only inside `scripts/netns-run` (loopback only, non-zero domain), like every DDS test.

use std::path::PathBuf;
use std::process::{Child, Command, Output};

fn launch_config() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../launch-config")
}

fn domain_id() -> u16 {
    let d: u16 = std::env::var("ROS_DOMAIN_ID").ok().and_then(|v| v.parse().ok()).unwrap_or(0);
    assert_ne!(d, 0, "DDS tests run on a non-zero ROS_DOMAIN_ID inside scripts/netns-run");
    d
}

/// Stops the suite when the test ends, however it ends.
struct Suite(Child);
impl Drop for Suite {
    fn drop(&mut self) {
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}

fn command(args: &[&str]) -> Output {
    let mut all = vec!["command"];
    all.extend_from_slice(args);
    let d = domain_id().to_string();
    all.extend_from_slice(&["--domain-id", &d, "--operator", "command_cli_test"]);
    Command::new(env!("CARGO_BIN_EXE_tyrerig")).args(&all).env_remove("RUST_BACKTRACE").output().expect("tyrerig")
}

fn text(o: &Output) -> String {
    format!("{}{}", String::from_utf8_lossy(&o.stdout), String::from_utf8_lossy(&o.stderr))
}

#[test]
fn a_command_is_done_when_the_sequencer_shows_it_taken() {
    let dir = tempfile::tempdir().expect("tempdir");
    let cfg = launch_config();
    let launch = dir.path().join("suite.toml");
    std::fs::write(
        &launch,
        format!(
            r#"[runtime]
namespace = "/rig"
domain_id = {domain}

[[node]]
name = "virtual_rig"
kind = "virtual_rig"
[node.config]
rig_config = "{rig}"
clock = "realtime"
time_scale = 5.0

[[node]]
name = "thermal"
kind = "thermal"

[[node]]
name = "sequencer"
kind = "sequencer"
[node.config]
procedure = "{procedure}"
load_index = 110
"#,
            domain = domain_id(),
            rig = cfg.join("virtual_rig.toml").display(),
            procedure = cfg.join("procedures/gs2mf_freerolling.toml").display(),
        ),
    )
    .expect("launch file");
    let _suite = Suite(
        Command::new(env!("CARGO_BIN_EXE_tyrerig"))
            .arg("launch")
            .arg(&launch)
            .stdout(std::process::Stdio::null())
            .stderr(std::fs::File::create(dir.path().join("suite.log")).expect("log"))
            .spawn()
            .expect("tyrerig launch"),
    );

    let start = command(&["start", "--confirm-s", "20"]);
    assert!(start.status.success(), "START: {}", text(&start));
    assert!(text(&start).contains("Start taken"), "{}", text(&start));
    let pause = command(&["pause", "--confirm-s", "20"]);
    assert!(pause.status.success() && text(&pause).contains("PAUSED"), "PAUSE: {}", text(&pause));
    let resume = command(&["resume", "--confirm-s", "20"]);
    assert!(resume.status.success() && text(&resume).contains("Resume taken"), "RESUME: {}", text(&resume));
    // A second START while the procedure runs: sent, but the sequencer does not act on it.
    let again = command(&["start", "--confirm-s", "4"]);
    assert!(!again.status.success(), "a START while running must not count as taken: {}", text(&again));
    assert!(text(&again).contains("not seen taken"), "{}", text(&again));
    let abort = command(&["abort", "--confirm-s", "20"]);
    assert!(abort.status.success() && text(&abort).contains("ABORTED"), "ABORT: {}", text(&abort));
}

//! Launch files and the node registry: which nodes exist, how each is configured, how it runs.
//!
//! A launch file (`launch-config/*.toml`):
//! ```toml
//! [runtime]                 # optional: namespace (default "/rig") and domain_id (else ROS_DOMAIN_ID)
//! namespace = "/rig"
//!
//! [security]                # optional: DDS Security (docs/security.md); needs --features security
//! keystore = "../out/keystore"   # each node authenticates as <namespace>/<node name>
//!
//! [[node]]
//! name = "recorder"         # ROS node name, unique in the file
//! kind = "recorder"         # which node (see NodeKind)
//! [node.config]             # the node's own typed config (deny_unknown_fields)
//! output = "out/run.mcap"
//! ```
//! `tyrerig node <name> --config <file>` runs one node of a launch file alone, so a control room
//! can spread nodes over machines with one shared file.

use anyhow::{Context as _, bail};
use node_runtime::{RosNode, RuntimeConfig, SecurityConfig, Shutdown};
use serde::Deserialize;
use std::path::{Path, PathBuf};

/// A parsed launch file.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LaunchFile {
    #[serde(default)]
    pub runtime: RuntimeConfig,
    /// `[security]`: copied into `runtime.security` (keystore resolved against the file) on load.
    #[serde(default)]
    pub security: Option<SecurityConfig>,
    #[serde(default, rename = "node")]
    pub nodes: Vec<NodeEntry>,
}

/// One `[[node]]` of a launch file.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct NodeEntry {
    pub name: String,
    pub kind: String,
    #[serde(default)]
    pub config: toml::Table,
}

/// Every node kind the suite has.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum NodeKind {
    Recorder,
    TestPattern,
    VirtualRig,
    Thermal,
    Sequencer,
    /// Live channels and the quality monitor in one node (`monitor::shell`).
    Quality,
    /// The Foxglove WebSocket server for control-room screens (`foxglove_node`).
    Foxglove,
    /// The live MF-Tyre 6.1 fit (`livefit::shell`).
    Fit,
}

impl NodeKind {
    pub const ALL: [NodeKind; 8] = [
        NodeKind::Recorder,
        NodeKind::TestPattern,
        NodeKind::VirtualRig,
        NodeKind::Thermal,
        NodeKind::Sequencer,
        NodeKind::Quality,
        NodeKind::Foxglove,
        NodeKind::Fit,
    ];

    pub fn name(self) -> &'static str {
        match self {
            NodeKind::Recorder => "recorder",
            NodeKind::TestPattern => "test_pattern",
            NodeKind::VirtualRig => "virtual_rig",
            NodeKind::Thermal => "thermal",
            NodeKind::Sequencer => "sequencer",
            NodeKind::Quality => "quality",
            NodeKind::Foxglove => "foxglove",
            NodeKind::Fit => "fit",
        }
    }

    pub fn parse(s: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|k| k.name() == s)
    }
}

impl LaunchFile {
    /// Reads and validates a launch file; errors name the file, the line where TOML allows,
    /// the node and the key.
    pub fn load(path: &Path) -> anyhow::Result<Self> {
        let text =
            std::fs::read_to_string(path).with_context(|| format!("{}: cannot read launch file", path.display()))?;
        Self::parse(path, &text)
    }

    /// As [`LaunchFile::load`], from the file's text (`path` names it and anchors relative paths).
    pub fn parse(path: &Path, text: &str) -> anyhow::Result<Self> {
        let mut file: LaunchFile =
            toml::from_str(text).map_err(|e| anyhow::anyhow!("{}: {}", path.display(), e.to_string().trim_end()))?;
        file.runtime.validate().map_err(|e| anyhow::anyhow!("{}: [runtime]: {e}", path.display()))?;
        let base = path.parent().unwrap_or(Path::new("."));
        if let Some(sec) = &file.security {
            if let Some(stray) = sec.enclaves.keys().find(|n| !file.nodes.iter().any(|e| &e.name == *n)) {
                bail!("{}: [security.enclaves]: {stray:?} is not a node of this file", path.display());
            }
            file.runtime.security = Some(sec.clone().resolved_against(base));
        }
        let mut seen = std::collections::BTreeSet::new();
        for n in &mut file.nodes {
            if NodeKind::parse(&n.kind).is_none() {
                bail!(
                    "{}: node {:?}: kind {:?} is not a tyrerig node (expected one of: {})",
                    path.display(),
                    n.name,
                    n.kind,
                    NodeKind::ALL.map(|k| k.name()).join(", ")
                );
            }
            if !seen.insert(n.name.clone()) {
                bail!("{}: node name {:?} appears twice; node names must be unique", path.display(), n.name);
            }
            // Paths in node configs are relative to the launch file, like ROS launch files.
            n.config.insert("_base_dir".into(), toml::Value::String(base.display().to_string()));
            // Check the typed config now, before anything starts.
            typed_config_check(n).map_err(|e| anyhow::anyhow!("{}: node {:?}: {e}", path.display(), n.name))?;
        }
        Ok(file)
    }

    pub fn node(&self, name: &str) -> Option<&NodeEntry> {
        self.nodes.iter().find(|n| n.name == name)
    }

    /// With `[security]`, checks every node has its enclave in the keystore, so a launch fails
    /// before any node starts rather than half-way.
    pub fn check_enclaves(&self, path: &Path) -> anyhow::Result<()> {
        if let Some(sec) = &self.runtime.security {
            for n in &self.nodes {
                sec.enclave_dir(&n.name, &self.runtime.namespace)
                    .map_err(|e| anyhow::anyhow!("{}: [security]: {e}", path.display()))?;
            }
        }
        Ok(())
    }
}

fn base_dir(entry: &NodeEntry) -> PathBuf {
    entry.config.get("_base_dir").and_then(|v| v.as_str()).map(PathBuf::from).unwrap_or_else(|| PathBuf::from("."))
}

fn config_of<T: serde::de::DeserializeOwned>(entry: &NodeEntry) -> anyhow::Result<T> {
    let mut table = entry.config.clone();
    table.remove("_base_dir");
    T::deserialize(toml::Value::Table(table))
        .map_err(|e| anyhow::anyhow!("[node.config]: {}", e.to_string().trim_end()))
}

/// Resolves a config path relative to the launch file's directory.
fn resolve(entry: &NodeEntry, p: &Path) -> PathBuf {
    if p.is_absolute() { p.to_owned() } else { base_dir(entry).join(p) }
}

fn typed_config_check(entry: &NodeEntry) -> anyhow::Result<()> {
    match NodeKind::parse(&entry.kind) {
        Some(NodeKind::Recorder) => {
            let c: recorder::RecorderConfig = config_of(entry)?;
            c.validate()?;
        }
        Some(NodeKind::TestPattern) => {
            let _: test_pattern::TestPatternConfig = config_of(entry)?;
        }
        Some(NodeKind::VirtualRig) => {
            let c: virtual_rig::VirtualRigNodeConfig = config_of(entry)?;
            c.validate()?;
        }
        Some(NodeKind::Thermal) => {
            let c: thermal::ThermalConfig = config_of(entry)?;
            c.validate()?;
        }
        Some(NodeKind::Sequencer) => {
            let c: sequencer::shell::SequencerNodeConfig = config_of(entry)?;
            c.validate()?;
        }
        Some(NodeKind::Quality) => {
            let c: monitor::shell::QualityNodeConfig = config_of(entry)?;
            c.validate()?;
        }
        Some(NodeKind::Foxglove) => {
            let c: foxglove_node::FoxgloveNodeConfig = config_of(entry)?;
            c.validate()?;
        }
        Some(NodeKind::Fit) => {
            let _: livefit::shell::FitNodeConfig = config_of(entry)?;
        }
        None => bail!("unknown node kind {:?}", entry.kind),
    }
    Ok(())
}

/// Runs one node until it finishes or `shutdown` fires. Creates its own DDS participant.
pub async fn run_node(entry: &NodeEntry, runtime: &RuntimeConfig, shutdown: Shutdown) -> anyhow::Result<()> {
    let node = RosNode::new(&entry.name, runtime)?;
    match NodeKind::parse(&entry.kind) {
        Some(NodeKind::Recorder) => {
            let mut c: recorder::RecorderConfig = config_of(entry)?;
            c.output = resolve(entry, &c.output);
            let stats = recorder::shell::run(node, c, shutdown).await?;
            tracing::info!(node = entry.name, messages = stats.messages, "recorder stopped");
        }
        Some(NodeKind::TestPattern) => {
            let c: test_pattern::TestPatternConfig = config_of(entry)?;
            test_pattern::run(node, c, shutdown).await?;
        }
        Some(NodeKind::VirtualRig) => {
            let mut c: virtual_rig::VirtualRigNodeConfig = config_of(entry)?;
            c.rig_config = resolve(entry, &c.rig_config);
            c.tyre = c.tyre.map(|t| resolve(entry, &t));
            virtual_rig::run(node, c, shutdown).await?;
        }
        Some(NodeKind::Thermal) => {
            let c: thermal::ThermalConfig = config_of(entry)?;
            thermal::shell::run(node, c, shutdown).await?;
        }
        Some(NodeKind::Sequencer) => {
            let mut c: sequencer::shell::SequencerNodeConfig = config_of(entry)?;
            c.procedure = resolve(entry, &c.procedure);
            c.checkpoint = c.checkpoint.map(|p| resolve(entry, &p));
            sequencer::shell::run(node, c, shutdown).await?;
        }
        Some(NodeKind::Quality) => {
            let c: monitor::shell::QualityNodeConfig = config_of(entry)?;
            monitor::shell::run(node, c, shutdown).await?;
        }
        Some(NodeKind::Foxglove) => {
            let mut c: foxglove_node::FoxgloveNodeConfig = config_of(entry)?;
            c.procedure = c.procedure.map(|p| resolve(entry, &p));
            foxglove_node::run(node, c, shutdown).await?;
        }
        Some(NodeKind::Fit) => {
            let mut c: livefit::shell::FitNodeConfig = config_of(entry)?;
            c.output.tir = c.output.tir.map(|p| resolve(entry, &p));
            c.output.report = c.output.report.map(|p| resolve(entry, &p));
            livefit::shell::run(node, c, shutdown).await?;
        }
        None => bail!("unknown node kind {:?}", entry.kind),
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn launch_config() -> PathBuf {
        PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../launch-config")
    }

    #[test]
    fn the_shipped_launch_files_load() {
        for name in ["demo.toml", "suite.toml", "suite-secure.toml"] {
            let file = LaunchFile::load(&launch_config().join(name)).unwrap_or_else(|e| panic!("{name}: {e:#}"));
            assert!(!file.nodes.is_empty(), "{name}");
        }
        let suite = LaunchFile::load(&launch_config().join("suite.toml")).expect("suite.toml");
        let kinds: Vec<_> = suite.nodes.iter().map(|n| n.kind.as_str()).collect();
        for k in ["recorder", "virtual_rig", "thermal", "sequencer", "quality", "foxglove"] {
            assert!(kinds.contains(&k), "suite.toml has no {k} node: {kinds:?}");
        }
        assert!(suite.runtime.security.is_none(), "the plain suite needs no keystore");
    }

    #[test]
    fn the_secure_suite_is_the_suite_with_a_keystore() {
        let plain = LaunchFile::load(&launch_config().join("suite.toml")).expect("suite.toml");
        let secure = LaunchFile::load(&launch_config().join("suite-secure.toml")).expect("suite-secure.toml");
        let names = |f: &LaunchFile| f.nodes.iter().map(|n| (n.name.clone(), n.kind.clone())).collect::<Vec<_>>();
        assert_eq!(names(&plain), names(&secure));
        let sec = secure.runtime.security.expect("[security]");
        assert!(sec.keystore.is_absolute() || sec.keystore.starts_with(launch_config()), "{:?}", sec.keystore);
        assert!(sec.keystore.ends_with("out/keystore"), "{:?}", sec.keystore);
    }

    #[test]
    fn security_sections_are_checked() {
        let dir = tempfile::tempdir().expect("tempdir");
        let path = dir.path().join("s.toml");
        let node = "[[node]]\nname = \"thermal\"\nkind = \"thermal\"\n";
        std::fs::write(
            &path,
            format!("[security]\nkeystore = \"ks\"\n[security.enclaves]\nthermal = \"/rig/t\"\n{node}"),
        )
        .expect("write");
        let file = LaunchFile::load(&path).expect("valid");
        let sec = file.runtime.security.as_ref().expect("security");
        assert_eq!(sec.keystore, dir.path().join("ks"));
        let err = format!("{:#}", file.check_enclaves(&path).expect_err("no keystore"));
        assert!(err.contains("s.toml") && err.contains("\"thermal\"") && err.contains("ks/enclaves/rig/t/"), "{err}");
        for (body, expect) in [
            (
                "[security]\nkeystore = \"ks\"\n[security.enclaves]\nsequencer = \"/rig/s\"\n",
                "\"sequencer\" is not a node",
            ),
            ("[security]\nkeystre = \"ks\"\n", "keystre"),
            ("[runtime]\nsecurity = \"x\"\n", "security"),
        ] {
            std::fs::write(&path, format!("{body}{node}")).expect("write");
            let err = format!("{:#}", LaunchFile::load(&path).expect_err(body));
            assert!(err.contains("s.toml") && err.contains(expect), "{body}: {err}");
        }
    }

    /// Launch files are user input: fuzzed with the parser_fuzz harness (every node kind's
    /// typed config is checked when the file loads).
    #[test]
    fn launch_files_fuzz() {
        let seeds = ["demo.toml", "suite.toml"]
            .map(|n| std::fs::read(launch_config().join(n)).expect("seed launch file"))
            .to_vec();
        let at = launch_config().join("fuzz.toml");
        let cases = std::env::var("FUZZ_CASES").ok().and_then(|v| v.parse().ok()).unwrap_or(2000);
        parser_fuzz::fuzz("launch TOML", seeds, cases, |b| {
            LaunchFile::parse(&at, &parser_fuzz::text(b)).map(|_| ()).map_err(|e| format!("{e:#}"))
        });
    }

    #[test]
    fn a_bad_quality_config_is_refused_naming_the_node_and_key() {
        let dir = tempfile::tempdir().expect("tempdir");
        let path = dir.path().join("bad.toml");
        for (body, expect) in [
            ("load_index = 3", "load index 3"),
            ("tread_new_mm = 1.0", "tread_new_mm"),
            ("lod_index = 110", "lod_index"),
        ] {
            std::fs::write(&path, format!("[[node]]\nname = \"q\"\nkind = \"quality\"\n[node.config]\n{body}\n"))
                .expect("write");
            let err = format!("{:#}", LaunchFile::load(&path).expect_err(body));
            assert!(err.contains("bad.toml") && err.contains("\"q\"") && err.contains(expect), "{body}: {err}");
        }
        std::fs::write(&path, "[[node]]\nname = \"q\"\nkind = \"foxglove\"\n[node.config]\nallow_commands = [\"PAUSE\", \"SELFDESTRUCT\"]\n")
            .expect("write");
        let err = format!("{:#}", LaunchFile::load(&path).expect_err("unknown command"));
        assert!(err.contains("bad.toml") && err.contains("allow_commands") && err.contains("SELFDESTRUCT"), "{err}");
        for (body, expect) in [("time_scale = 0.0", "time_scale"), ("time_scale = -3.0", "time_scale")] {
            std::fs::write(
                &path,
                format!(
                    "[[node]]\nname = \"q\"\nkind = \"virtual_rig\"\n[node.config]\nrig_config = \"x.toml\"\n{body}\n"
                ),
            )
            .expect("write");
            let err = format!("{:#}", LaunchFile::load(&path).expect_err(body));
            assert!(err.contains("bad.toml") && err.contains("\"q\"") && err.contains(expect), "{body}: {err}");
        }
    }
}

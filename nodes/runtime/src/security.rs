//! DDS Security for a node's participant: the launch file's `[security]` section and how a node
//! finds its enclave in an SROS2 keystore.
//!
//! ```toml
//! [security]
//! keystore = "../out/keystore"      # made by `tyrerig security create-keystore`
//! [security.enclaves]               # optional: node name -> enclave; default <namespace>/<node>
//! recorder = "/rig/recorder_b"
//! ```
//!
//! With a `[security]` section every node of the file authenticates with its enclave's
//! certificate, checks every peer's certificate and permissions, and signs or encrypts what it
//! sends as the keystore's governance says (RustDDS's builtin plugins, cargo feature
//! `security`). Without one the node joins the domain as plain DDS, as before.

use serde::Deserialize;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// The `[security]` section of a launch file.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SecurityConfig {
    /// SROS2 keystore directory (relative paths are resolved against the launch file).
    pub keystore: PathBuf,
    /// Enclave of a node by node name, where it is not `<namespace>/<node name>`.
    #[serde(default)]
    pub enclaves: BTreeMap<String, String>,
}

/// The files of an enclave directory a participant needs (SROS2's names; RustDDS reads these).
pub const ENCLAVE_FILES: [&str; 6] =
    ["identity_ca.cert.pem", "cert.pem", "key.pem", "permissions_ca.cert.pem", "governance.p7s", "permissions.p7s"];

/// Why a node cannot join the secured domain.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum SecurityConfigError {
    #[error(
        "node {node:?}: enclave {enclave:?}: {} is missing (create the enclave with `tyrerig security create-enclave {} {enclave}`)",
        missing.display(), keystore.display()
    )]
    MissingEnclaveFile { node: String, enclave: String, keystore: PathBuf, missing: PathBuf },
    #[error("node {node:?}: enclave {enclave:?}: expected an absolute name such as \"/rig/{node}\"")]
    BadEnclave { node: String, enclave: String },
    #[error(
        "node {node:?}: the launch file has a [security] section, but this tyrerig was built without DDS Security; \
         rebuild with `cargo build --release --features security` (needs OpenSSL's headers: libssl-dev)"
    )]
    NotBuiltWithSecurity { node: String },
    #[error(
        "node {node:?}: domain {domain_id}: a secured domain must be 0..={MAX_SECURE_DOMAIN} (DDS Security schemas)"
    )]
    DomainOutOfRange { node: String, domain_id: u16 },
}

/// The largest domain id the DDS Security governance and permissions schemas allow.
pub const MAX_SECURE_DOMAIN: u16 = 230;

impl SecurityConfig {
    /// A config using `keystore` with the default enclave for every node.
    pub fn new(keystore: impl Into<PathBuf>) -> Self {
        Self { keystore: keystore.into(), enclaves: BTreeMap::new() }
    }

    /// The config with a relative keystore path made relative to `base` (the launch file's
    /// directory), as every path in a launch file is.
    pub fn resolved_against(mut self, base: &Path) -> Self {
        if self.keystore.is_relative() {
            self.keystore = base.join(&self.keystore);
        }
        self
    }

    /// The enclave a node authenticates as: listed under `[security.enclaves]`, else the node's
    /// fully qualified name (`/rig/sequencer`), as `ros2 security create-enclave` names them.
    pub fn enclave_of(&self, node: &str, namespace: &str) -> String {
        match self.enclaves.get(node) {
            Some(e) => e.clone(),
            None if namespace == "/" => format!("/{node}"),
            None => format!("{}/{node}", namespace.trim_end_matches('/')),
        }
    }

    /// The enclave directory of `node`, checked to hold every file a participant needs.
    pub fn enclave_dir(&self, node: &str, namespace: &str) -> Result<PathBuf, SecurityConfigError> {
        let enclave = self.enclave_of(node, namespace);
        let segments: Vec<&str> = enclave.trim_start_matches('/').split('/').collect();
        if !enclave.starts_with('/') || segments.iter().any(|s| s.is_empty() || *s == "." || *s == "..") {
            return Err(SecurityConfigError::BadEnclave { node: node.to_owned(), enclave });
        }
        let dir: PathBuf = segments.iter().fold(self.keystore.join("enclaves"), |d, s| d.join(s));
        for f in ENCLAVE_FILES {
            let p = dir.join(f);
            if !p.is_file() {
                return Err(SecurityConfigError::MissingEnclaveFile {
                    node: node.to_owned(),
                    enclave,
                    keystore: self.keystore.clone(),
                    missing: p,
                });
            }
        }
        Ok(dir)
    }
}

/// Turns on DDS Security for a participant about to be created for `node`.
#[cfg(feature = "security")]
pub(crate) fn secure(
    options: ros2_client::ContextOptions,
    cfg: &SecurityConfig,
    node: &str,
    namespace: &str,
    domain_id: u16,
) -> Result<ros2_client::ContextOptions, SecurityConfigError> {
    if domain_id > MAX_SECURE_DOMAIN {
        return Err(SecurityConfigError::DomainOutOfRange { node: node.to_owned(), domain_id });
    }
    let dir = cfg.enclave_dir(node, namespace)?;
    tracing::debug!(node, enclave = %dir.display(), "DDS Security on");
    // SROS2 keys are unencrypted PKCS#8 (RustDDS reads no other); the password is unused.
    Ok(options.enable_security(dir, String::new()))
}

#[cfg(not(feature = "security"))]
pub(crate) fn secure(
    _options: ros2_client::ContextOptions,
    _cfg: &SecurityConfig,
    node: &str,
    _namespace: &str,
    _domain_id: u16,
) -> Result<ros2_client::ContextOptions, SecurityConfigError> {
    Err(SecurityConfigError::NotBuiltWithSecurity { node: node.to_owned() })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn enclaves_default_to_the_node_name_and_missing_files_are_named() {
        let mut cfg = SecurityConfig::new("/nonexistent/ks");
        assert_eq!(cfg.enclave_of("sequencer", "/rig"), "/rig/sequencer");
        assert_eq!(cfg.enclave_of("sequencer", "/"), "/sequencer");
        cfg.enclaves.insert("recorder".into(), "/lab/recorder_b".into());
        assert_eq!(cfg.enclave_of("recorder", "/rig"), "/lab/recorder_b");
        let err = cfg.enclave_dir("recorder", "/rig").expect_err("missing").to_string();
        assert!(
            err.contains("/nonexistent/ks/enclaves/lab/recorder_b/identity_ca.cert.pem")
                && err.contains("tyrerig security create-enclave /nonexistent/ks /lab/recorder_b"),
            "{err}"
        );
        cfg.enclaves.insert("x".into(), "/rig/../../etc".into());
        assert!(matches!(cfg.enclave_dir("x", "/rig"), Err(SecurityConfigError::BadEnclave { .. })));
    }

    #[test]
    fn relative_keystores_follow_the_launch_file() {
        let cfg = SecurityConfig::new("ks").resolved_against(Path::new("/etc/rig"));
        assert_eq!(cfg.keystore, PathBuf::from("/etc/rig/ks"));
        let cfg = SecurityConfig::new("/abs/ks").resolved_against(Path::new("/etc/rig"));
        assert_eq!(cfg.keystore, PathBuf::from("/abs/ks"));
    }
}

//! Enclave names: the identity a participant authenticates as (SROS2's "enclave").

use crate::KeystoreError;
use std::path::PathBuf;

/// An enclave name such as `/rig/sequencer`: an absolute ROS name with a namespace and a base
/// name. The certificate's subject is `CN=<name>`; the suite topics its permissions grant are
/// those of the namespace it is under (`/rig`), so a node's default enclave is its own fully
/// qualified name.
#[derive(Debug, Clone, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct EnclaveName(String);

impl EnclaveName {
    pub fn parse(name: &str) -> Result<Self, KeystoreError> {
        let bad = |why: &str| KeystoreError::BadEnclaveName { name: name.to_owned(), why: why.to_owned() };
        let Some(rest) = name.strip_prefix('/') else {
            return Err(bad("expected an absolute name such as \"/rig/operator_1\""));
        };
        let segments: Vec<&str> = rest.split('/').collect();
        for s in &segments {
            let ok = s.chars().next().is_some_and(|c| c.is_ascii_alphabetic() || c == '_')
                && s.chars().all(|c| c.is_ascii_alphanumeric() || c == '_');
            if !ok {
                return Err(bad(&format!(
                    "segment {s:?}: expected letters, digits and '_', not starting with a digit"
                )));
            }
        }
        if segments.len() < 2 {
            return Err(bad(
                "expected a namespace and a name (\"/rig/operator_1\"): the enclave's topics are those of its namespace",
            ));
        }
        Ok(Self(name.to_owned()))
    }

    pub fn as_str(&self) -> &str {
        &self.0
    }

    /// The namespace the enclave is under (`/rig` for `/rig/sequencer`).
    pub fn namespace(&self) -> &str {
        let cut = self.0.rfind('/').unwrap_or(0);
        &self.0[..cut]
    }

    /// The last segment (`sequencer`).
    pub fn base_name(&self) -> &str {
        self.0.rsplit('/').next().unwrap_or(&self.0)
    }

    /// The certificate subject and permissions grant subject: `CN=/rig/sequencer`.
    pub fn subject_name(&self) -> String {
        format!("CN={}", self.0)
    }

    /// The enclave's directory below `<keystore>/enclaves` (`rig/sequencer`).
    pub fn relative_dir(&self) -> PathBuf {
        self.0.trim_start_matches('/').split('/').collect()
    }

    /// Number of path segments (2 for `/rig/sequencer`).
    pub fn depth(&self) -> usize {
        self.0.trim_start_matches('/').split('/').count()
    }
}

impl std::fmt::Display for EnclaveName {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names() {
        let e = EnclaveName::parse("/lab/rig2/operator_1").expect("valid");
        assert_eq!(e.namespace(), "/lab/rig2");
        assert_eq!(e.base_name(), "operator_1");
        assert_eq!(e.relative_dir(), PathBuf::from("lab/rig2/operator_1"));
        assert_eq!(e.subject_name(), "CN=/lab/rig2/operator_1");
        assert_eq!(e.depth(), 3);
        for bad in ["rig/x", "/x", "/", "/rig/", "//x", "/rig/1x", "/rig/a-b", "/rig/a b", "/rig/x/"] {
            let err = EnclaveName::parse(bad).expect_err(bad).to_string();
            assert!(err.contains(&format!("{bad:?}")), "{err}");
        }
    }
}

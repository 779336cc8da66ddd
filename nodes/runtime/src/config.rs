//! Runtime configuration shared by every node: namespace, DDS domain and DDS Security.

use crate::SecurityConfig;
use serde::Deserialize;

/// Where a node lives on the DDS network.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RuntimeConfig {
    /// ROS namespace the suite's topics live under (absolute, e.g. `/rig`).
    #[serde(default = "default_namespace")]
    pub namespace: String,
    /// DDS domain id; when absent, `ROS_DOMAIN_ID` is used, else 0 (the ROS convention).
    #[serde(default)]
    pub domain_id: Option<u16>,
    /// DDS Security (the launch file's top-level `[security]` section, not a `[runtime]` key):
    /// `None` joins the domain as plain DDS.
    #[serde(skip)]
    pub security: Option<SecurityConfig>,
}

fn default_namespace() -> String {
    "/rig".to_owned()
}

impl Default for RuntimeConfig {
    fn default() -> Self {
        Self { namespace: default_namespace(), domain_id: None, security: None }
    }
}

/// A runtime setting that cannot work.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum RuntimeConfigError {
    #[error("namespace {namespace:?}: expected an absolute ROS name such as \"/rig\" (letters, digits, '_' and '/')")]
    BadNamespace { namespace: String },
    #[error("ROS_DOMAIN_ID={value:?}: expected an integer 0..=232")]
    BadDomainEnv { value: String },
    #[error("domain id {domain_id}: expected 0..=232 (DDS port mapping limit)")]
    DomainOutOfRange { domain_id: u16 },
}

impl RuntimeConfig {
    /// Checks the namespace is a valid absolute ROS name.
    pub fn validate(&self) -> Result<(), RuntimeConfigError> {
        let ns = &self.namespace;
        let ok = ns.starts_with('/')
            && !ns.contains("//")
            && (ns.len() == 1 || !ns.ends_with('/'))
            && ns.chars().all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '/')
            && ns.split('/').filter(|s| !s.is_empty()).all(|s| !s.starts_with(|c: char| c.is_ascii_digit()));
        if !ok {
            return Err(RuntimeConfigError::BadNamespace { namespace: ns.clone() });
        }
        if let Some(d) = self.domain_id {
            check_domain(d)?;
        }
        Ok(())
    }

    /// The domain id to join: the config's, else `ROS_DOMAIN_ID`, else 0.
    pub fn resolved_domain_id(&self) -> Result<u16, RuntimeConfigError> {
        if let Some(d) = self.domain_id {
            return check_domain(d).map(|()| d);
        }
        match std::env::var("ROS_DOMAIN_ID") {
            Ok(v) if !v.trim().is_empty() => {
                let d: u16 = v.trim().parse().map_err(|_| RuntimeConfigError::BadDomainEnv { value: v.clone() })?;
                check_domain(d).map(|()| d)
            }
            _ => Ok(0),
        }
    }
}

fn check_domain(d: u16) -> Result<(), RuntimeConfigError> {
    // RTPS port mapping: 7400 + 250 * domain must stay below 65535.
    if d > 232 { Err(RuntimeConfigError::DomainOutOfRange { domain_id: d }) } else { Ok(()) }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn namespaces() {
        for good in ["/", "/rig", "/lab_2/rig"] {
            let c = RuntimeConfig { namespace: good.into(), ..Default::default() };
            assert_eq!(c.validate(), Ok(()), "{good}");
        }
        for bad in ["rig", "/rig/", "//rig", "/rig-1", "/1rig"] {
            let c = RuntimeConfig { namespace: bad.into(), ..Default::default() };
            assert!(c.validate().is_err(), "{bad}");
        }
    }

    #[test]
    fn domain_from_config_wins_and_is_checked() {
        let c = RuntimeConfig { domain_id: Some(7), ..Default::default() };
        assert_eq!(c.resolved_domain_id(), Ok(7));
        let c = RuntimeConfig { domain_id: Some(300), ..Default::default() };
        assert!(c.resolved_domain_id().is_err());
    }
}

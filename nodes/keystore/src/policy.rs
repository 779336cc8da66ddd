//! The two XML documents of DDS Security's access control, written from the suite's topic table:
//! the domain governance (how each topic is protected) and an enclave's permissions (what its
//! role may publish and subscribe to). Both follow the OMG DDS Security 1.1 schemas, element
//! order included, as SROS2 writes them, so RustDDS, Cyclone DDS and Fast DDS all read them.
//! Pure text generation: signing is [`crate::pki`]'s job.
//!
//! Topics are protected at the submessage level (`metadata_protection_kind`): every DATA,
//! HEARTBEAT, ACKNACK and GAP of a topic is encrypted or MAC'd as a whole, payload included.
//! Payload-level protection (`data_protection_kind`) stays NONE because RustDDS 0.15.1 cannot
//! decode it: `Data::write_to` pads the encoded payload to 4 bytes and
//! `decode_serialized_payload` takes the CryptoFooter from the end of the padded buffer, so every
//! payload whose CDR length is not a multiple of 4 fails its MAC check (ring's `Unspecified`) and
//! the reliable writer resends it forever (docs/security.md, "Known limits").

use crate::{EnclaveName, Role};
use node_runtime::SuiteTopic;
use std::fmt::Write as _;

/// Domains the documents cover: every domain id the DDS Security schemas allow (0..=230; the
/// runtime's plain limit of 232 is not a valid `DomainId` there, and Cyclone DDS refuses the
/// whole document over it).
pub const DOMAIN_MIN: u16 = 0;
pub const DOMAIN_MAX: u16 = 230;

/// How a topic (or all topics) is protected on the wire.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Protection {
    /// Submessages encrypted and authenticated (AES-GCM, per-writer session keys).
    Encrypt,
    /// Submessages carry a message authentication code (AES-GMAC): readable by whoever is on the
    /// wire, but nobody without the keys can forge, alter or replay them.
    Sign,
}

impl Protection {
    fn xml(self) -> &'static str {
        match self {
            Protection::Encrypt => "ENCRYPT",
            Protection::Sign => "SIGN",
        }
    }
}

/// The topics the governance protects more than the default, with why: commands and setpoints
/// move the rig, so nobody may read or forge them. Globs match any namespace below the root.
pub const ENCRYPTED_TOPICS: [(&str, &str); 2] = [
    ("rt/*/procedure/command", "operator commands: START, ABORT, E-STOP"),
    ("rt/*/setpoint", "what the rig is told to do"),
];

/// Every other topic (the sample stream, states, reports, ROS 2 plumbing) is signed.
pub const DEFAULT_PROTECTION: Protection = Protection::Sign;

/// The DDS topic name of a suite topic in `namespace` (`/rig/sample` → `rt/rig/sample`).
pub fn dds_topic(topic: SuiteTopic, namespace: &str) -> String {
    format!("rt{}", topic.full_name(namespace))
}

/// The domain governance document: discovery and liveliness encrypted, only authenticated
/// participants admitted, read and write access control on every topic; commands and
/// setpoints encrypted, everything else signed.
pub fn governance_xml() -> String {
    let mut x = String::new();
    x.push_str(XML_HEAD);
    x.push_str(
        "<dds xmlns:xsi=\"http://www.w3.org/2001/XMLSchema-instance\" \
         xsi:noNamespaceSchemaLocation=\"http://www.omg.org/spec/DDS-Security/20170801/omg_shared_ca_governance.xsd\">\n",
    );
    x.push_str("  <domain_access_rules>\n    <domain_rule>\n");
    let _ = writeln!(x, "      <domains>{}</domains>", domain_range());
    x.push_str("      <!-- a participant without a certificate from the identity CA is ignored -->\n");
    x.push_str("      <allow_unauthenticated_participants>false</allow_unauthenticated_participants>\n");
    x.push_str("      <enable_join_access_control>true</enable_join_access_control>\n");
    x.push_str("      <discovery_protection_kind>ENCRYPT</discovery_protection_kind>\n");
    x.push_str("      <liveliness_protection_kind>ENCRYPT</liveliness_protection_kind>\n");
    // Whole-message protection would add a second MAC to every datagram on top of the
    // per-topic protection below; the submessages that matter are protected there already.
    x.push_str("      <rtps_protection_kind>NONE</rtps_protection_kind>\n");
    x.push_str("      <topic_access_rules>\n");
    for (expr, why) in ENCRYPTED_TOPICS {
        topic_rule(&mut x, expr, Protection::Encrypt, why);
    }
    topic_rule(&mut x, "*", DEFAULT_PROTECTION, "everything else: samples, states, reports, ROS 2 plumbing");
    x.push_str("      </topic_access_rules>\n    </domain_rule>\n  </domain_access_rules>\n</dds>\n");
    x
}

fn topic_rule(x: &mut String, expression: &str, p: Protection, why: &str) {
    let _ = write!(
        x,
        "        <!-- {why} -->\n\
         \x20       <topic_rule>\n\
         \x20         <topic_expression>{expression}</topic_expression>\n\
         \x20         <enable_discovery_protection>true</enable_discovery_protection>\n\
         \x20         <enable_liveliness_protection>true</enable_liveliness_protection>\n\
         \x20         <enable_read_access_control>true</enable_read_access_control>\n\
         \x20         <enable_write_access_control>true</enable_write_access_control>\n\
         \x20         <metadata_protection_kind>{p}</metadata_protection_kind>\n\
         \x20         <data_protection_kind>NONE</data_protection_kind>\n\
         \x20       </topic_rule>\n",
        p = p.xml()
    );
}

/// What an enclave may publish and subscribe to, as DDS topic names.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Grants {
    pub publish: Vec<String>,
    pub subscribe: Vec<String>,
}

/// The grants of `role` for an enclave: the role's suite topics in the namespace the enclave is
/// under, plus the ROS 2 plumbing every ros2-client node uses (graph info, parameter events,
/// `/clock`, and the parameter services of the node the enclave names: requests in, replies out).
pub fn grants(enclave: &EnclaveName, role: Role) -> Grants {
    let ns = enclave.namespace();
    let mut publish: Vec<String> = role.publishes().iter().map(|t| dds_topic(*t, ns)).collect();
    let mut subscribe: Vec<String> = role.subscribes().iter().map(|t| dds_topic(*t, ns)).collect();
    publish.extend(["ros_discovery_info".into(), "rt/parameter_events".into(), "rt/rosout".into()]);
    publish.push(format!("rr{}/*", enclave.as_str()));
    subscribe.extend(["ros_discovery_info".into(), "rt/clock".into()]);
    subscribe.push(format!("rq{}/*", enclave.as_str()));
    for list in [&mut publish, &mut subscribe] {
        let mut seen = std::collections::BTreeSet::new();
        list.retain(|t| seen.insert(t.clone()));
    }
    Grants { publish, subscribe }
}

/// The permissions document of one enclave: one grant for the certificate subject `CN=<enclave>`,
/// valid over `[not_before, not_after]` (UTC, `YYYY-MM-DDTHH:MM:SS`), deny by default.
pub fn permissions_xml(enclave: &EnclaveName, role: Role, not_before: &str, not_after: &str) -> String {
    let g = grants(enclave, role);
    let mut x = String::new();
    x.push_str(XML_HEAD);
    x.push_str(
        "<dds xmlns:xsi=\"http://www.w3.org/2001/XMLSchema-instance\" \
         xsi:noNamespaceSchemaLocation=\"http://www.omg.org/spec/DDS-Security/20170801/omg_shared_ca_permissions.xsd\">\n",
    );
    let _ = write!(
        x,
        "  <permissions>\n\
         \x20   <!-- role: {role} -->\n\
         \x20   <grant name=\"{e}\">\n\
         \x20     <subject_name>{subject}</subject_name>\n\
         \x20     <validity>\n\
         \x20       <not_before>{not_before}</not_before>\n\
         \x20       <not_after>{not_after}</not_after>\n\
         \x20     </validity>\n\
         \x20     <allow_rule>\n\
         \x20       <domains>{domains}</domains>\n",
        e = enclave.as_str(),
        subject = enclave.subject_name(),
        domains = domain_range(),
    );
    for (tag, topics) in [("publish", &g.publish), ("subscribe", &g.subscribe)] {
        let _ = writeln!(x, "        <{tag}>\n          <topics>");
        for t in topics {
            let _ = writeln!(x, "            <topic>{t}</topic>");
        }
        let _ = writeln!(x, "          </topics>\n        </{tag}>");
    }
    x.push_str("      </allow_rule>\n      <default>DENY</default>\n    </grant>\n  </permissions>\n</dds>\n");
    x
}

const XML_HEAD: &str = "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n";

fn domain_range() -> String {
    format!("<id_range><min>{DOMAIN_MIN}</min><max>{DOMAIN_MAX}</max></id_range>")
}

/// `unix_s` (seconds since the UNIX epoch) as an XSD dateTime in UTC without zone suffix
/// (`2031-05-04T12:00:09`), the form the permissions schema's validity uses.
pub fn xsd_datetime_utc(unix_s: i64) -> String {
    let days = unix_s.div_euclid(86_400);
    let secs = unix_s.rem_euclid(86_400);
    let (y, m, d) = civil_from_days(days);
    format!("{y:04}-{m:02}-{d:02}T{:02}:{:02}:{:02}", secs / 3600, secs % 3600 / 60, secs % 60)
}

/// Proleptic Gregorian date of a day count since 1970-01-01 (the era-based algorithm: 400-year
/// eras of 146,097 days, years starting in March so the leap day falls last).
fn civil_from_days(days: i64) -> (i64, u32, u32) {
    let z = days + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z.rem_euclid(146_097); // day of era, 0..=146_096
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365; // year of era, 0..=399
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100); // day of year from 1 March, 0..=365
    let mp = (5 * doy + 2) / 153; // month from March, 0..=11
    let d = (doy - (153 * mp + 2) / 5 + 1) as u32;
    let m = if mp < 10 { mp + 3 } else { mp - 9 } as u32;
    let y = yoe + era * 400 + i64::from(m <= 2);
    (y, m, d)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn documents_cover_exactly_the_domains_a_secured_node_joins() {
        assert_eq!(DOMAIN_MAX, node_runtime::security::MAX_SECURE_DOMAIN);
        assert!(governance_xml().contains("<max>230</max>"));
    }

    #[test]
    fn dates() {
        assert_eq!(xsd_datetime_utc(0), "1970-01-01T00:00:00");
        assert_eq!(xsd_datetime_utc(951_782_400), "2000-02-29T00:00:00");
        assert_eq!(xsd_datetime_utc(1_700_000_000), "2023-11-14T22:13:20");
        assert_eq!(xsd_datetime_utc(4_102_444_799), "2099-12-31T23:59:59");
        assert_eq!(xsd_datetime_utc(-1), "1969-12-31T23:59:59");
    }

    #[test]
    fn sequencer_grants() {
        let e = EnclaveName::parse("/rig/sequencer").expect("valid");
        let g = grants(&e, Role::Sequencer);
        assert!(g.publish.contains(&"rt/rig/setpoint".to_owned()));
        assert!(!g.publish.contains(&"rt/rig/procedure/command".to_owned()));
        assert!(g.subscribe.contains(&"rt/rig/procedure/command".to_owned()));
        assert!(g.subscribe.contains(&"rt/rig/model/covariance".to_owned()), "the adaptive plan's input");
        assert!(g.publish.contains(&"rr/rig/sequencer/*".to_owned()));
        assert!(g.subscribe.contains(&"rq/rig/sequencer/*".to_owned()));
        // /clock is both a suite topic (recorder) and plumbing: listed once.
        let e = EnclaveName::parse("/lab/rig2/recorder").expect("valid");
        let g = grants(&e, Role::Recorder);
        assert_eq!(g.subscribe.iter().filter(|t| *t == "rt/clock").count(), 1);
        assert!(g.subscribe.contains(&"rt/lab/rig2/sample".to_owned()));
        assert!(!g.publish.iter().any(|t| t.starts_with("rt/lab")), "{:?}", g.publish);
    }

    #[test]
    fn documents_name_what_they_protect() {
        let gov = governance_xml();
        assert!(gov.contains("<allow_unauthenticated_participants>false<"));
        assert!(!gov.contains("<data_protection_kind>SIGN") && !gov.contains("<data_protection_kind>ENCRYPT"));
        let cmd = gov.find("rt/*/procedure/command").expect("command rule");
        let star = gov.find("<topic_expression>*<").expect("default rule");
        assert!(cmd < star, "specific rules must come before the catch-all (first match wins)");
        let e = EnclaveName::parse("/rig/operator_1").expect("valid");
        let p = permissions_xml(&e, Role::Operator, "2025-01-01T00:00:00", "2035-01-01T00:00:00");
        assert!(p.contains("<subject_name>CN=/rig/operator_1</subject_name>"));
        assert!(p.contains("<topic>rt/rig/procedure/command</topic>"));
        assert!(p.contains("<default>DENY</default>"));
    }
}

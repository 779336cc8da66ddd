//! A keystore made on disk has SROS2's layout, protected private keys, and documents and
//! certificates that verify against its own CAs (and not against another keystore's).

use keystore::{EnclaveName, Keystore, KeystoreError, Role, pki};
use openssl::x509::X509;
use std::os::unix::fs::PermissionsExt as _;
use std::path::Path;

fn now() -> i64 {
    std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH).expect("clock").as_secs() as i64
}

fn cert(p: &Path) -> X509 {
    X509::from_pem(&std::fs::read(p).unwrap_or_else(|e| panic!("{}: {e}", p.display()))).expect("pem")
}

#[test]
fn keystore_and_enclave_layout() {
    let dir = tempfile::tempdir().expect("tempdir");
    let root = dir.path().join("ks");
    let ks = Keystore::create(&root, now()).expect("create");
    for f in [
        "public/identity_ca.cert.pem",
        "public/permissions_ca.cert.pem",
        "private/identity_ca.key.pem",
        "private/permissions_ca.key.pem",
        "enclaves/governance.xml",
        "enclaves/governance.p7s",
    ] {
        assert!(root.join(f).is_file(), "{f}");
    }
    for k in ["private/identity_ca.key.pem", "private/permissions_ca.key.pem"] {
        let mode = std::fs::metadata(root.join(k)).expect("meta").permissions().mode() & 0o777;
        assert_eq!(mode, 0o600, "{k}");
    }
    // A second create in the same place is refused, naming what is there.
    let err = Keystore::create(&root, now()).expect_err("exists").to_string();
    assert!(err.contains("is a keystore already") && err.contains("ca.cert.pem"), "{err}");

    let name = EnclaveName::parse("/rig/sequencer").expect("name");
    let report = ks.create_enclave(&name, Role::Sequencer, now()).expect("enclave");
    assert!(report.new_identity);
    let e = root.join("enclaves/rig/sequencer");
    assert_eq!(report.dir, e);
    for f in [
        "cert.pem",
        "key.pem",
        "permissions.xml",
        "permissions.p7s",
        "governance.p7s",
        "identity_ca.cert.pem",
        "permissions_ca.cert.pem",
    ] {
        assert!(e.join(f).is_file(), "{f} (links must resolve)");
    }
    assert!(std::fs::read_link(e.join("governance.p7s")).expect("link").is_relative());
    assert_eq!(std::fs::metadata(e.join("key.pem")).expect("meta").permissions().mode() & 0o777, 0o600);

    // The identity: CN=/rig/sequencer, issued by the identity CA (not by the permissions CA).
    let id = cert(&e.join("cert.pem"));
    let cn = id.subject_name().entries().next().expect("cn").data().to_string().expect("utf8");
    assert_eq!(cn, "/rig/sequencer");
    assert!(pki::verify_issued_by(&id, &cert(&ks.identity_ca_cert())).expect("verify"));
    assert!(!pki::verify_issued_by(&id, &cert(&ks.permissions_ca_cert())).expect("verify"));

    // Both documents verify against the permissions CA and carry what was written.
    let perm_ca = cert(&ks.permissions_ca_cert());
    let gov = pki::smime_verify(&std::fs::read(ks.governance()).expect("read"), &perm_ca).expect("governance");
    assert!(String::from_utf8_lossy(&gov).contains("rt/*/setpoint"));
    let perms = pki::smime_verify(&std::fs::read(e.join("permissions.p7s")).expect("read"), &perm_ca).expect("perm");
    let perms = String::from_utf8_lossy(&perms).replace("\r\n", "\n");
    assert_eq!(perms, std::fs::read_to_string(e.join("permissions.xml")).expect("xml"));
    assert!(perms.contains("<topic>rt/rig/setpoint</topic>"));

    // Again with another role: same identity, new permissions.
    let again = ks.create_enclave(&name, Role::Monitor, now()).expect("again");
    assert!(!again.new_identity);
    assert_eq!(cert(&e.join("cert.pem")).to_der().expect("der"), id.to_der().expect("der"));
    let xml = std::fs::read_to_string(e.join("permissions.xml")).expect("xml");
    let publish = &xml[xml.find("<publish>").expect("publish")..xml.find("</publish>").expect("/publish")];
    assert!(xml.contains("role: monitor") && !publish.contains("rt/rig/setpoint"), "{xml}");
}

#[test]
fn another_keystore_is_another_authority() {
    let dir = tempfile::tempdir().expect("tempdir");
    let a = Keystore::create(&dir.path().join("a"), now()).expect("a");
    let b = Keystore::create(&dir.path().join("b"), now()).expect("b");
    let name = EnclaveName::parse("/rig/operator").expect("name");
    let ea = a.create_enclave(&name, Role::Operator, now()).expect("enclave");
    let id = cert(&ea.dir.join("cert.pem"));
    assert!(!pki::verify_issued_by(&id, &cert(&b.identity_ca_cert())).expect("verify"));
    let signed = std::fs::read(ea.dir.join("permissions.p7s")).expect("read");
    assert!(pki::smime_verify(&signed, &cert(&b.permissions_ca_cert())).is_err());
    // An enclave directory copied in from keystore a is not re-signed by keystore b.
    let eb = b.enclave_dir(&name);
    std::fs::create_dir_all(&eb).expect("mkdir");
    for f in ["cert.pem", "key.pem"] {
        std::fs::copy(ea.dir.join(f), eb.join(f)).expect("copy");
    }
    assert!(matches!(b.create_enclave(&name, Role::Operator, now()), Err(KeystoreError::ForeignIdentity { .. })));
}

#[test]
fn opening_a_directory_that_is_not_a_keystore_names_the_missing_file() {
    let dir = tempfile::tempdir().expect("tempdir");
    let err = Keystore::open(dir.path()).expect_err("empty").to_string();
    assert!(err.contains("not a keystore") && err.contains("permissions_ca.cert.pem"), "{err}");
    assert!(err.contains("tyrerig security create-keystore"), "{err}");
}

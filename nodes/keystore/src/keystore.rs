//! The keystore on disk: creating it, adding enclaves, finding files.

use crate::{
    EnclaveName, Role,
    pki::{self, CertKind, Validity},
    policy,
};
use openssl::{
    asn1::Asn1Time,
    error::ErrorStack,
    pkey::{PKey, Private},
    x509::X509,
};
use std::{
    io::Write as _,
    os::unix::fs::OpenOptionsExt as _,
    path::{Path, PathBuf},
};

/// Certificates and grants are valid for ten years, as SROS2 makes them.
pub const VALIDITY_S: i64 = 10 * 365 * 86_400;
/// Certificates and grants start this much before their creation, so a peer whose clock is a
/// few minutes behind still accepts them.
pub const CLOCK_SKEW_S: i64 = 600;

/// Common names of the two certificate authorities.
pub const IDENTITY_CA_CN: &str = "tyrerig identity CA";
pub const PERMISSIONS_CA_CN: &str = "tyrerig permissions CA";

/// Something that stops a keystore from being created or used; names the file and what to do.
#[derive(Debug, thiserror::Error)]
pub enum KeystoreError {
    #[error("{}: {what}: {source}", path.display())]
    Io { path: PathBuf, what: &'static str, source: std::io::Error },
    #[error("{}: {what}: {source}", path.display())]
    Crypto { path: PathBuf, what: &'static str, source: ErrorStack },
    #[error("{}: is a keystore already (it has {}); use another directory, or add enclaves to it with `tyrerig security create-enclave`", path.display(), found.display())]
    Exists { path: PathBuf, found: PathBuf },
    #[error("{}: not a keystore: {} is missing (make one with `tyrerig security create-keystore {}`)", path.display(), missing.display(), path.display())]
    NotAKeystore { path: PathBuf, missing: PathBuf },
    #[error("enclave name {name:?}: {why}")]
    BadEnclaveName { name: String, why: String },
    #[error("{}: the enclave's certificate was not issued by this keystore's identity CA; remove the enclave directory to give it a new identity", path.display())]
    ForeignIdentity { path: PathBuf },
}

/// A keystore directory (see the crate docs for the layout).
#[derive(Debug, Clone)]
pub struct Keystore {
    root: PathBuf,
}

/// What [`Keystore::create_enclave`] did.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct EnclaveReport {
    pub dir: PathBuf,
    pub role: Role,
    /// False when the enclave existed: its key and certificate were kept, only its permissions
    /// were written and signed again (as SROS2 does).
    pub new_identity: bool,
}

fn io(path: &Path, what: &'static str) -> impl FnOnce(std::io::Error) -> KeystoreError {
    let path = path.to_owned();
    move |source| KeystoreError::Io { path, what, source }
}

fn crypto(path: &Path, what: &'static str) -> impl FnOnce(ErrorStack) -> KeystoreError {
    let path = path.to_owned();
    move |source| KeystoreError::Crypto { path, what, source }
}

impl Keystore {
    pub fn identity_ca_cert(&self) -> PathBuf {
        self.root.join("public/identity_ca.cert.pem")
    }
    pub fn permissions_ca_cert(&self) -> PathBuf {
        self.root.join("public/permissions_ca.cert.pem")
    }
    pub fn identity_ca_key(&self) -> PathBuf {
        self.root.join("private/identity_ca.key.pem")
    }
    pub fn permissions_ca_key(&self) -> PathBuf {
        self.root.join("private/permissions_ca.key.pem")
    }
    pub fn governance(&self) -> PathBuf {
        self.root.join("enclaves/governance.p7s")
    }
    pub fn root(&self) -> &Path {
        &self.root
    }
    /// The directory of an enclave (whether or not it exists).
    pub fn enclave_dir(&self, name: &EnclaveName) -> PathBuf {
        self.root.join("enclaves").join(name.relative_dir())
    }

    /// The files a valid keystore has (SROS2's test for one).
    fn required(&self) -> [PathBuf; 5] {
        [
            self.permissions_ca_cert(),
            self.identity_ca_cert(),
            self.permissions_ca_key(),
            self.identity_ca_key(),
            self.governance(),
        ]
    }

    /// Opens an existing keystore; the error names the first missing file.
    pub fn open(root: &Path) -> Result<Self, KeystoreError> {
        let ks = Self { root: root.to_owned() };
        if let Some(missing) = ks.required().into_iter().find(|p| !p.is_file()) {
            return Err(KeystoreError::NotAKeystore { path: root.to_owned(), missing });
        }
        Ok(ks)
    }

    /// Creates a keystore in `root` (made if missing; refused if it holds a keystore already):
    /// two certificate authorities and the signed governance. `now_s`: seconds since the UNIX
    /// epoch, the start of every validity period.
    pub fn create(root: &Path, now_s: i64) -> Result<Self, KeystoreError> {
        let ks = Self { root: root.to_owned() };
        if let Some(found) = ks.required().into_iter().find(|p| p.exists()) {
            return Err(KeystoreError::Exists { path: root.to_owned(), found });
        }
        for d in ["public", "private", "enclaves"] {
            let p = root.join(d);
            std::fs::create_dir_all(&p).map_err(io(&p, "cannot create the directory"))?;
        }
        let validity = Validity { not_before_s: now_s - CLOCK_SKEW_S, not_after_s: now_s + VALIDITY_S };
        for (cn, kind, cert_path, key_path) in [
            (IDENTITY_CA_CN, CertKind::IdentityCa, ks.identity_ca_cert(), ks.identity_ca_key()),
            (PERMISSIONS_CA_CN, CertKind::PermissionsCa, ks.permissions_ca_cert(), ks.permissions_ca_key()),
        ] {
            let key = pki::new_key().map_err(crypto(&key_path, "cannot make a key"))?;
            let cert = pki::certificate(cn, &key, kind, validity, None)
                .map_err(crypto(&cert_path, "cannot make the CA certificate"))?;
            write_key(&key_path, &key)?;
            write_cert(&cert_path, &cert)?;
        }
        let gov_xml = root.join("enclaves/governance.xml");
        let xml = policy::governance_xml();
        write_file(&gov_xml, xml.as_bytes(), 0o644)?;
        ks.sign_into(xml.as_bytes(), &ks.governance())?;
        Ok(ks)
    }

    fn permissions_ca(&self) -> Result<(X509, PKey<Private>), KeystoreError> {
        Ok((read_cert(&self.permissions_ca_cert())?, read_key(&self.permissions_ca_key())?))
    }

    fn sign_into(&self, document: &[u8], out: &Path) -> Result<(), KeystoreError> {
        let (ca, key) = self.permissions_ca()?;
        let signed = pki::smime_sign(document, &ca, &key).map_err(crypto(out, "cannot sign"))?;
        write_file(out, &signed, 0o644)
    }

    /// Creates (or refreshes) the enclave `name` with the permissions of `role`: key and
    /// certificate (kept if the enclave exists), permissions signed by the permissions CA,
    /// links to the CA certificates and the governance.
    pub fn create_enclave(&self, name: &EnclaveName, role: Role, now_s: i64) -> Result<EnclaveReport, KeystoreError> {
        let dir = self.enclave_dir(name);
        std::fs::create_dir_all(&dir).map_err(io(&dir, "cannot create the enclave directory"))?;
        let id_ca = read_cert(&self.identity_ca_cert())?;
        // Nothing the enclave holds may outlive the CA that vouches for it.
        let ca_end = asn1_unix(id_ca.not_after()).map_err(crypto(&self.identity_ca_cert(), "unreadable notAfter"))?;
        let validity = Validity { not_before_s: now_s - CLOCK_SKEW_S, not_after_s: (now_s + VALIDITY_S).min(ca_end) };
        let (cert_path, key_path) = (dir.join("cert.pem"), dir.join("key.pem"));
        let (new_identity, validity) = if cert_path.is_file() && key_path.is_file() {
            let cert = read_cert(&cert_path)?;
            if !pki::verify_issued_by(&cert, &id_ca).map_err(crypto(&cert_path, "cannot verify"))? {
                return Err(KeystoreError::ForeignIdentity { path: cert_path });
            }
            let kept = Validity {
                not_before_s: asn1_unix(cert.not_before()).map_err(crypto(&cert_path, "unreadable notBefore"))?,
                not_after_s: asn1_unix(cert.not_after()).map_err(crypto(&cert_path, "unreadable notAfter"))?,
            };
            (false, kept)
        } else {
            let id_key = read_key(&self.identity_ca_key())?;
            let key = pki::new_key().map_err(crypto(&key_path, "cannot make a key"))?;
            let cert = pki::certificate(name.as_str(), &key, CertKind::Enclave, validity, Some((&id_ca, &id_key)))
                .map_err(crypto(&cert_path, "cannot make the certificate"))?;
            write_key(&key_path, &key)?;
            write_cert(&cert_path, &cert)?;
            (true, validity)
        };
        let xml = policy::permissions_xml(
            name,
            role,
            &policy::xsd_datetime_utc(validity.not_before_s),
            &policy::xsd_datetime_utc(validity.not_after_s),
        );
        write_file(&dir.join("permissions.xml"), xml.as_bytes(), 0o644)?;
        self.sign_into(xml.as_bytes(), &dir.join("permissions.p7s"))?;
        // Relative links, as SROS2 makes them, so the keystore can be moved or copied whole.
        let up = |n: usize| "../".repeat(n);
        for (link, target) in [
            ("identity_ca.cert.pem", format!("{}public/identity_ca.cert.pem", up(name.depth() + 1))),
            ("permissions_ca.cert.pem", format!("{}public/permissions_ca.cert.pem", up(name.depth() + 1))),
            ("governance.p7s", format!("{}governance.p7s", up(name.depth()))),
        ] {
            let l = dir.join(link);
            if l.symlink_metadata().is_ok() {
                std::fs::remove_file(&l).map_err(io(&l, "cannot replace"))?;
            }
            std::os::unix::fs::symlink(&target, &l).map_err(io(&l, "cannot link"))?;
        }
        Ok(EnclaveReport { dir, role, new_identity })
    }
}

/// Seconds since the UNIX epoch of an ASN.1 time.
fn asn1_unix(t: &openssl::asn1::Asn1TimeRef) -> Result<i64, ErrorStack> {
    let d = Asn1Time::from_unix(0)?.diff(t)?;
    Ok(i64::from(d.days) * 86_400 + i64::from(d.secs))
}

fn write_file(path: &Path, bytes: &[u8], mode: u32) -> Result<(), KeystoreError> {
    let mut f = std::fs::OpenOptions::new()
        .write(true)
        .create(true)
        .truncate(true)
        .mode(mode)
        .open(path)
        .map_err(io(path, "cannot write"))?;
    f.write_all(bytes).map_err(io(path, "cannot write"))
}

fn write_key(path: &Path, key: &PKey<Private>) -> Result<(), KeystoreError> {
    let pem = key.private_key_to_pem_pkcs8().map_err(crypto(path, "cannot encode the key"))?;
    write_file(path, &pem, 0o600)
}

fn write_cert(path: &Path, cert: &X509) -> Result<(), KeystoreError> {
    let pem = cert.to_pem().map_err(crypto(path, "cannot encode the certificate"))?;
    write_file(path, &pem, 0o644)
}

fn read_cert(path: &Path) -> Result<X509, KeystoreError> {
    let pem = std::fs::read(path).map_err(io(path, "cannot read"))?;
    X509::from_pem(&pem).map_err(crypto(path, "not a PEM certificate"))
}

fn read_key(path: &Path) -> Result<PKey<Private>, KeystoreError> {
    let pem = std::fs::read(path).map_err(io(path, "cannot read"))?;
    PKey::private_key_from_pem(&pem).map_err(crypto(path, "not a PEM private key"))
}

//! Keys, certificates and signed documents, through OpenSSL (the `openssl` crate).
//!
//! Why OpenSSL: the DDS Security stack the suite runs on (RustDDS's `security` feature) already
//! links it, and it is what Cyclone DDS and Fast DDS verify documents with, so the S/MIME
//! signatures made here are the same bytes `openssl smime -sign -text` (and SROS2) produce.
//!
//! Choices, all as SROS2 makes them: EC keys on P-256 (the curve every DDS Security
//! implementation supports), ECDSA with SHA-256, unencrypted PKCS#8 private keys (RustDDS reads
//! no encrypted keys; the keystore's file modes protect them), 10-year validity.

use openssl::{
    asn1::Asn1Time,
    bn::{BigNum, MsbOption},
    ec::{EcGroup, EcKey},
    error::ErrorStack,
    hash::MessageDigest,
    nid::Nid,
    pkcs7::{Pkcs7, Pkcs7Flags},
    pkey::{PKey, Private},
    stack::Stack,
    x509::{
        X509, X509Builder, X509NameBuilder,
        extension::{AuthorityKeyIdentifier, BasicConstraints, KeyUsage, SubjectKeyIdentifier},
        store::X509StoreBuilder,
    },
};

/// A fresh P-256 key pair.
pub fn new_key() -> Result<PKey<Private>, ErrorStack> {
    let group = EcGroup::from_curve_name(Nid::X9_62_PRIME256V1)?;
    PKey::from_ec_key(EcKey::generate(&group)?)
}

/// Validity of a certificate, seconds since the UNIX epoch.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Validity {
    pub not_before_s: i64,
    pub not_after_s: i64,
}

/// What a certificate is for.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CertKind {
    /// The identity CA: signs enclave certificates.
    IdentityCa,
    /// The permissions CA: signs the governance and permissions documents (S/MIME).
    PermissionsCa,
    /// An enclave's identity: signs its authentication handshake.
    Enclave,
}

/// A certificate for `common_name` and `key`, self-signed when `issuer` is `None`.
pub fn certificate(
    common_name: &str,
    key: &PKey<Private>,
    kind: CertKind,
    validity: Validity,
    issuer: Option<(&X509, &PKey<Private>)>,
) -> Result<X509, ErrorStack> {
    let mut name = X509NameBuilder::new()?;
    name.append_entry_by_nid(Nid::COMMONNAME, common_name)?;
    let name = name.build();
    let mut b = X509Builder::new()?;
    b.set_version(2)?; // X.509 v3
    let mut serial = BigNum::new()?;
    serial.rand(127, MsbOption::MAYBE_ZERO, false)?;
    let serial = serial.to_asn1_integer()?;
    b.set_serial_number(&serial)?;
    b.set_subject_name(&name)?;
    b.set_issuer_name(issuer.map_or(&name, |(c, _)| c.subject_name()))?;
    b.set_pubkey(key)?;
    let (not_before, not_after) =
        (Asn1Time::from_unix(validity.not_before_s)?, Asn1Time::from_unix(validity.not_after_s)?);
    b.set_not_before(&not_before)?;
    b.set_not_after(&not_after)?;
    match kind {
        CertKind::IdentityCa => {
            b.append_extension(BasicConstraints::new().critical().ca().pathlen(0).build()?)?;
            b.append_extension(KeyUsage::new().critical().key_cert_sign().crl_sign().build()?)?;
        }
        CertKind::PermissionsCa => {
            // It signs the documents itself, so digitalSignature too (OpenSSL's S/MIME
            // verification checks the signer's key usage).
            b.append_extension(BasicConstraints::new().critical().ca().pathlen(0).build()?)?;
            b.append_extension(KeyUsage::new().critical().key_cert_sign().crl_sign().digital_signature().build()?)?;
        }
        CertKind::Enclave => {
            b.append_extension(BasicConstraints::new().critical().build()?)?;
            b.append_extension(KeyUsage::new().critical().digital_signature().build()?)?;
        }
    }
    let ski = SubjectKeyIdentifier::new().build(&b.x509v3_context(issuer.map(|(c, _)| &**c), None))?;
    b.append_extension(ski)?;
    if let Some((ca, _)) = issuer {
        let aki = AuthorityKeyIdentifier::new().keyid(true).build(&b.x509v3_context(Some(ca), None))?;
        b.append_extension(aki)?;
    }
    b.sign(issuer.map_or(key, |(_, k)| k), MessageDigest::sha256())?;
    Ok(b.build())
}

const SMIME_FLAGS: Pkcs7Flags = Pkcs7Flags::DETACHED.union(Pkcs7Flags::TEXT);

/// `document` signed by `signer` as S/MIME multipart/signed (detached PKCS#7 SignedData, the
/// signer certificate included, the content as text/plain): the `.p7s` format of DDS Security.
pub fn smime_sign(document: &[u8], signer: &X509, key: &PKey<Private>) -> Result<Vec<u8>, ErrorStack> {
    let no_extra_certs: Stack<X509> = Stack::new()?;
    let p7 = Pkcs7::sign(signer, key, &no_extra_certs, document, SMIME_FLAGS)?;
    p7.to_smime(document, SMIME_FLAGS)
}

/// Verifies an S/MIME signed document against a trusted CA certificate, as a DDS Security
/// access-control plugin does, and returns the signed content.
pub fn smime_verify(signed: &[u8], ca: &X509) -> Result<Vec<u8>, ErrorStack> {
    let (p7, content) = Pkcs7::from_smime(signed)?;
    let mut store = X509StoreBuilder::new()?;
    store.add_cert(ca.clone())?;
    let store = store.build();
    let mut out = Vec::new();
    let no_extra_certs: Stack<X509> = Stack::new()?;
    p7.verify(&no_extra_certs, &store, content.as_deref(), Some(&mut out), Pkcs7Flags::TEXT)?;
    Ok(out)
}

/// Checks `cert` was issued by `ca` (signature and validity now), as authentication does.
pub fn verify_issued_by(cert: &X509, ca: &X509) -> Result<bool, ErrorStack> {
    let mut store = X509StoreBuilder::new()?;
    store.add_cert(ca.clone())?;
    let store = store.build();
    let mut ctx = openssl::x509::X509StoreContext::new()?;
    let no_chain: Stack<X509> = Stack::new()?;
    ctx.init(&store, cert, &no_chain, |c| c.verify_cert())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn validity() -> Validity {
        let now = std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH).expect("clock").as_secs() as i64;
        Validity { not_before_s: now - 60, not_after_s: now + 86_400 }
    }

    #[test]
    fn a_chain_verifies_and_a_foreign_ca_does_not() {
        let ca_key = new_key().expect("key");
        let ca = certificate("test identity CA", &ca_key, CertKind::IdentityCa, validity(), None).expect("ca");
        let key = new_key().expect("key");
        let cert =
            certificate("/rig/sequencer", &key, CertKind::Enclave, validity(), Some((&ca, &ca_key))).expect("cert");
        assert!(verify_issued_by(&cert, &ca).expect("verify"));
        let other_key = new_key().expect("key");
        let other = certificate("test identity CA", &other_key, CertKind::IdentityCa, validity(), None).expect("ca");
        assert!(!verify_issued_by(&cert, &other).expect("verify"), "same name, other key: not the issuer");
    }

    #[test]
    fn signed_documents_verify_and_tampering_is_caught() {
        let key = new_key().expect("key");
        let ca = certificate("test permissions CA", &key, CertKind::PermissionsCa, validity(), None).expect("ca");
        let doc = b"<dds>\n  <x>1</x>\n</dds>\n";
        let signed = smime_sign(doc, &ca, &key).expect("sign");
        let text = String::from_utf8(signed.clone()).expect("utf8");
        assert!(text.starts_with("MIME-Version: 1.0"), "{text}");
        assert!(text.contains("multipart/signed") && text.contains("Content-Type: text/plain"));
        let content = smime_verify(&signed, &ca).expect("verify");
        assert_eq!(String::from_utf8_lossy(&content).replace("\r\n", "\n"), String::from_utf8_lossy(doc));
        let tampered = text.replacen("<x>1</x>", "<x>2</x>", 1);
        assert!(smime_verify(tampered.as_bytes(), &ca).is_err(), "an altered document must not verify");
        let other_key = new_key().expect("key");
        let other =
            certificate("test permissions CA", &other_key, CertKind::PermissionsCa, validity(), None).expect("ca");
        assert!(smime_verify(&signed, &other).is_err(), "signed by another CA");
    }
}

//! keystore: SROS2-compatible DDS Security keystores for the suite.
//!
//! `tyrerig security create-keystore` and `create-enclave` are thin wrappers around
//! [`Keystore::create`] and [`Keystore::create_enclave`]. The layout is SROS2's, so a ROS 2 user
//! recognises it and `ros2 security` tools can work on it:
//!
//! ```text
//! <keystore>/
//!   public/identity_ca.cert.pem       identity CA: signs enclave certificates
//!   public/permissions_ca.cert.pem    permissions CA: signs governance and permissions
//!   private/identity_ca.key.pem       (mode 0600; keep offline once the enclaves exist)
//!   private/permissions_ca.key.pem    (mode 0600)
//!   enclaves/governance.xml, governance.p7s
//!   enclaves/<enclave>/               one per participant, e.g. enclaves/rig/sequencer/
//!     cert.pem  key.pem               the enclave's identity (CN=/rig/sequencer), key mode 0600
//!     permissions.xml  permissions.p7s
//!     identity_ca.cert.pem  permissions_ca.cert.pem  governance.p7s   (relative symlinks)
//! ```
//!
//! An enclave directory is what a participant is given: `node_runtime` passes it to RustDDS's
//! builtin security plugins, and any other DDS Security implementation (Cyclone DDS, Fast DDS)
//! takes the same six files. What each enclave may do is its [`Role`] (see [`role`]); how each
//! topic is protected is the governance (see [`policy`]).

pub mod enclave_name;
pub mod keystore;
pub mod pki;
pub mod policy;
pub mod role;

pub use enclave_name::EnclaveName;
pub use keystore::{EnclaveReport, Keystore, KeystoreError};
pub use role::Role;

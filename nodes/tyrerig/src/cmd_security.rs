//! `tyrerig security`: SROS2 keystores for DDS Security (docs/security.md).

use std::path::PathBuf;

#[derive(Debug, clap::Subcommand)]
pub enum SecurityCmd {
    /// Create a keystore: identity CA, permissions CA and the signed governance (SROS2 layout)
    CreateKeystore {
        /// Directory to create it in (made if missing; refused if it holds a keystore already).
        dir: PathBuf,
    },
    /// Create enclaves in a keystore: key, certificate and signed permissions for each name
    CreateEnclave {
        /// The keystore.
        dir: PathBuf,
        /// Enclave names such as /rig/sequencer; a node's enclave is its fully qualified name.
        #[arg(required = true)]
        names: Vec<String>,
        /// rig | thermal | sequencer | quality | recorder | operator | monitor. Default: the
        /// name's last segment when it is a role or a node kind (/rig/virtual_rig → rig,
        /// /rig/foxglove → monitor; /rig/run_watcher → monitor).
        #[arg(long)]
        role: Option<String>,
    },
}

#[cfg(not(feature = "security"))]
pub fn run(_cmd: SecurityCmd) -> anyhow::Result<()> {
    anyhow::bail!(
        "this tyrerig was built without DDS Security; rebuild with `cargo build --release --features security` \
         (needs OpenSSL's headers: libssl-dev)"
    )
}

#[cfg(feature = "security")]
pub fn run(cmd: SecurityCmd) -> anyhow::Result<()> {
    use keystore::{EnclaveName, Keystore, Role};
    use std::time::Instant;

    let now_s = now_s()?;
    match cmd {
        SecurityCmd::CreateKeystore { dir } => {
            let t = Instant::now();
            Keystore::create(&dir, now_s)?;
            println!(
                "keystore {}: identity CA, permissions CA, governance signed ({:.1} ms)\n\
                 next: tyrerig security create-enclave {} /rig/<node> … (one per node and operator station)",
                dir.display(),
                t.elapsed().as_secs_f64() * 1e3,
                dir.display()
            );
        }
        SecurityCmd::CreateEnclave { dir, names, role } => {
            let ks = Keystore::open(&dir)?;
            let roles = Role::ALL.map(|r| r.name()).join(", ");
            let given = match role.as_deref() {
                Some(r) => {
                    Some(Role::parse(r).ok_or_else(|| anyhow::anyhow!("--role {r:?}: expected one of {roles}"))?)
                }
                None => None,
            };
            for name in names {
                let name = EnclaveName::parse(&name)?;
                let base = name.base_name();
                let role = given.or_else(|| Role::default_for(base)).ok_or_else(|| {
                    anyhow::anyhow!(
                        "enclave {name}: {base:?} is neither a role nor a node kind; say what it may do with \
                         --role (one of {roles})"
                    )
                })?;
                let t = Instant::now();
                let report = ks.create_enclave(&name, role, now_s)?;
                println!(
                    "{name}: role {role}, {} ({:.1} ms) → {}",
                    if report.new_identity { "new identity" } else { "identity kept, permissions signed again" },
                    t.elapsed().as_secs_f64() * 1e3,
                    report.dir.display()
                );
            }
        }
    }
    Ok(())
}

#[cfg(feature = "security")]
fn now_s() -> anyhow::Result<i64> {
    let d = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_err(|_| anyhow::anyhow!("the system clock is before 1970; certificates need a date"))?;
    Ok(d.as_secs() as i64)
}

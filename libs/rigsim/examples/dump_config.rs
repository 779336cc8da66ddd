//! Prints `RigConfig::default()` as TOML (the values `launch-config/virtual_rig.toml` holds).
fn main() {
    print!("{}", toml::to_string(&rigsim::RigConfig::default()).expect("serialises"));
}

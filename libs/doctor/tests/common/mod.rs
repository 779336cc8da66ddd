//! Builds logs in-process on the virtual rig (headless suite), without MCAP.
#![allow(dead_code)]

use doctor::RawLog;
use std::path::{Path, PathBuf};
use suite::sink::{MessageSink, Outgoing};
use suite::{Headless, ProcedureChoice, RunSpec};

/// Collects samples and procedure states.
#[derive(Default)]
struct VecSink(RawLog);

impl MessageSink for VecSink {
    fn put(&mut self, _t_s: f64, msg: Outgoing<'_>) -> Result<(), mcaplog::LogWriteError> {
        match msg {
            Outgoing::Sample(s) => self.0.samples.push(s.clone()),
            Outgoing::Procedure(s) => self.0.states.push(s.clone()),
            _ => {}
        }
        Ok(())
    }
}

pub fn repo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

pub fn fixture(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures").join(name)
}

/// Runs `procedure` (a fixture file name) with `effects` on the virtual rig.
pub fn run_log(procedure: &str, effects: &str, wear_multiplier: Option<f64>, seed: u64) -> RawLog {
    let mut spec = RunSpec::new(&repo().join("launch-config"), ProcedureChoice::FreeRolling);
    spec.procedure_file = fixture(procedure);
    spec.effects = Some(effects.to_owned());
    spec.wear_multiplier = wear_multiplier;
    spec.seed = seed;
    run_spec(&spec, &format!("{procedure} [{effects}]"))
}

/// Runs `spec` on the virtual rig; the log, its source named `source`.
pub fn run_spec(spec: &RunSpec, source: &str) -> RawLog {
    let mut h = Headless::new(spec, thermal::ThermalConfig::default(), sequencer::SequencerConfig::default())
        .expect("headless run");
    let mut sink = VecSink::default();
    sink.0.source = source.to_owned();
    h.run(&mut sink, &mut |_, _| {}).expect("run");
    sink.0
}

/// The clean base model (the virtual rig's tyre).
pub fn base_tir() -> mftyre::TyreParams {
    mftyre::TyreParams::read_tir(&repo().join("launch-config/tyres/MagicFormula61_Paramerters.tir")).expect("tir")
}

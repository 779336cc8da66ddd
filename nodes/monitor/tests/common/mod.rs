//! A headless virtual-rig run (VirtualRig + ThermalGate + Sequencer, as the suite's runner wires
//! them) for the channels and monitor tests.
#![allow(dead_code)]

use std::path::PathBuf;

use procedure::{RunInputs, expand};
use rigsim::{RigConfig, TyreParams, VirtualRig};
use sequencer::SequencerConfig;
use sequencer::core::{Sequencer, SequencerEvent};
use thermal::ThermalConfig;
use thermal::core::ThermalGate;
use tyre_msgs::{ProcedureCommand, ProcedureState, RigSample};

/// What the run feeds its observer.
pub enum Ev<'a> {
    Sample(&'a RigSample),
    State(&'a ProcedureState),
}

/// Run options.
pub struct Opts {
    pub procedure_file: &'static str,
    /// Load index entered at the rig (procedure loads and the rig's load cap).
    pub entered_load_index: u32,
    pub wear_multiplier: f64,
    pub seed: u64,
    /// Stop after this rig time [s].
    pub max_time_s: f64,
}

impl Default for Opts {
    fn default() -> Self {
        Self {
            procedure_file: "gs2mf_freerolling.toml",
            entered_load_index: 110,
            wear_multiplier: 1.0,
            seed: 7,
            max_time_s: 30_000.0,
        }
    }
}

pub fn launch_config() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../launch-config")
}

pub fn rig_config(opts: &Opts) -> (RigConfig, TyreParams) {
    let mut cfg = RigConfig::load(&launch_config().join("virtual_rig.toml")).unwrap();
    cfg.tyre.load_index = opts.entered_load_index;
    cfg.tyre.wear_rate_multiplier = opts.wear_multiplier;
    let params = TyreParams::read_tir(&cfg.tyre_file).unwrap();
    (cfg, params)
}

/// Result of a run.
pub struct RunEnd {
    pub end_time_s: f64,
    /// Tread lost by the specimen on the rig at the end [mm].
    pub tread_worn_mm: f64,
    pub completed: bool,
    /// Tread lost by each specimen taken off before, then the last one [mm].
    pub specimens_worn_mm: Vec<f64>,
}

/// Runs the procedure; `obs` sees every sample, then the state it caused. `obs` returns false to
/// stop early.
pub fn run(opts: &Opts, obs: &mut dyn FnMut(Ev<'_>, &VirtualRig) -> bool) -> RunEnd {
    let (cfg, params) = rig_config(opts);
    let mut rig = VirtualRig::new(cfg.clone(), params.clone(), opts.seed).unwrap();
    // A tyre change mounts a new specimen: a new virtual rig whose clock and sample numbers go
    // on from the old one's (as the suite's headless runner does).
    let (mut t_offset, mut seq_offset, mut last_seq) = (0.0, 0u64, 0u64);
    let mut specimens: Vec<f64> = Vec::new();
    let mut first_mount_done = false;
    let mounts =
        |o: &sequencer::core::SequencerOutput| o.events.iter().any(|e| matches!(e, SequencerEvent::TyreChange { .. }));
    let doc = procedure::load(&launch_config().join("procedures").join(opts.procedure_file)).unwrap();
    let plan = expand(&doc, &RunInputs { load_index: opts.entered_load_index, ..RunInputs::default() }).unwrap();
    let mut seq = Sequencer::new(plan, SequencerConfig::default()).unwrap();
    let mut gate = ThermalGate::new(ThermalConfig::default()).unwrap();
    let start = ProcedureCommand { command: ProcedureCommand::START, ..Default::default() };
    let out = seq.on_command(0.0, &start).unwrap();
    if let Some(st) = &out.state {
        obs(Ev::State(st), &rig);
    }
    // The first setpoint before the first sample: a rig still in its safe state reads as an
    // e-stop to the sequencer.
    let first = seq.step(0.0, None, None);
    first_mount_done |= mounts(&out) || mounts(&first);
    for sp in out.setpoint.iter().chain(first.setpoint.iter()) {
        let _ = rig.apply_setpoint(sp);
    }
    let end = |rig: &VirtualRig, t: f64, completed: bool, specimens: &[f64]| {
        let worn = rig.truth().tread_worn_mm;
        let mut all = specimens.to_vec();
        all.push(worn);
        RunEnd { end_time_s: t, tread_worn_mm: worn, completed, specimens_worn_mm: all }
    };
    loop {
        let Some(mut s) = rig.step() else { continue };
        if t_offset > 0.0 {
            s.runtime_s += t_offset;
            s.header.stamp = tyre_msgs::builtin_interfaces::Time::from_secs_f64(s.runtime_s);
            s.seq += seq_offset;
        }
        last_seq = last_seq.max(s.seq);
        let t = s.runtime_s;
        if !obs(Ev::Sample(&s), &rig) {
            return end(&rig, t, false, &specimens);
        }
        gate.on_sample(t, &s);
        let th = gate.step(t);
        let out = seq.step(t, Some(&th.state), Some(&s));
        if let Some(st) = &out.state {
            gate.on_procedure_state(t, st);
            if !obs(Ev::State(st), &rig) {
                return end(&rig, t, false, &specimens);
            }
        }
        if let Some(sp) = &out.setpoint {
            let _ = rig.apply_setpoint(sp);
        }
        for e in &out.events {
            if matches!(e, SequencerEvent::TyreChange { .. }) {
                if first_mount_done {
                    specimens.push(rig.truth().tread_worn_mm);
                    t_offset += rig.time_s();
                    seq_offset = last_seq + 1;
                    rig = VirtualRig::new(cfg.clone(), params.clone(), opts.seed + specimens.len() as u64).unwrap();
                }
                first_mount_done = true;
            }
        }
        let done = out.events.iter().any(|e| matches!(e, SequencerEvent::Completed { .. } | SequencerEvent::EStop));
        if done || t > opts.max_time_s {
            return end(&rig, t, done, &specimens);
        }
    }
}

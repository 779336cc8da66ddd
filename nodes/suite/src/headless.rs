//! The headless run: virtual rig, thermal gate and sequencer cores wired by function calls.
//!
//! Per rig sample (publish rate, 100 Hz by default): the gate judges the sample, the sequencer
//! steps with the gate's state and the sample, and its setpoint goes to the rig, which integrates
//! at its internal rate until the next sample. This is exactly the data flow of the DDS suite
//! with zero transport delay, so the same procedure gives the same decisions in both.

use crate::{
    sink::{MessageSink, Outgoing},
    spec::RunSpec,
    summary::{RunSummary, SummaryBuilder},
};
use mcaplog::LogWriteError;
use monitor::{MonitorConfig, TyreInfo, pipeline::Pipeline};
use procedure::Plan;
use procedure::RunInputs;
use rigsim::{RigConfig, TyreParams, VirtualRig, VirtualTyre};
use sequencer::{Sequencer, SequencerConfig, SequencerEvent};
use std::collections::BTreeMap;
use thermal::{ThermalConfig, ThermalGate};
use tyre_msgs::{ProcedureCommand, RigSample, builtin_interfaces::Time, std_msgs::Header};

mod adaptive_step;

/// Why a headless run could not start or went wrong.
#[derive(Debug, thiserror::Error)]
pub enum HeadlessError {
    #[error("virtual rig config: {0}")]
    RigConfig(String),
    #[error("{path}: {detail}")]
    Tyre { path: String, detail: String },
    #[error("procedure: {0}")]
    Procedure(String),
    #[error("thermal gate config: {0}")]
    Thermal(String),
    #[error("sequencer: {0}")]
    Sequencer(String),
    #[error("--effects: {0}")]
    Effects(String),
    #[error("log: {0}")]
    Log(#[from] LogWriteError),
    #[error("the procedure did not finish within {limit_s} s of rig time (at {at})")]
    TooLong { limit_s: f64, at: String },
    #[error(
        "the thermal gate held the rig for {held_s:.0} s of rig time on a sensor fault ({fault}) at {at}; \
         a headless run has no operator to clear it{hint}"
    )]
    SensorFaultHeld { held_s: f64, fault: String, at: String, hint: String },
}

/// Rig time a headless run lets the thermal gate hold on a sensor fault before it ends the run.
/// On a real rig the gate holds and an operator clears the fault; headless, nothing will, and
/// the run would otherwise go on to its rig-time limit (`--effects none` on a GS2MF run: a
/// temperature that never changes is a stuck sensor, and 200,000 s of held rig time wrote a
/// 2.4 GB log). Ten minutes is well beyond the gate's own recovery time.
pub const SENSOR_FAULT_HOLD_LIMIT_S: f64 = 600.0;

/// A ready-to-run headless suite.
pub struct Headless {
    rig: VirtualRig,
    rig_cfg: RigConfig,
    tyre: VirtualTyre,
    /// The run inputs the plan was expanded with (the spec's, or the brush tyre's ratings).
    inputs: RunInputs,
    gate: ThermalGate,
    seq: Sequencer,
    seed: u64,
    /// Rig time and sample numbers carried over from earlier tyre specimens: a tyre change
    /// mounts a fresh specimen on a fresh simulator, but the rig's clock runs on.
    time_offset_s: f64,
    seq_offset: u64,
    max_rig_time_s: f64,
    wear_true: Vec<f64>,
    /// Live channels and the online quality monitor (one per tyre specimen).
    pipeline: Pipeline,
    /// The live MF-Tyre fit, when the run has one ([`Headless::with_live_fit`]).
    live_fit: Option<livefit::LiveFit>,
    /// Wall time of each live-fit update after a sweep, s (the fitter's own measurement).
    live_fit_walls: Vec<f64>,
    /// The monitor's view of the live fit (its `/diagnostics`, as the quality node's).
    model_watch: monitor::ModelWatch,
    /// The data sweeps run so far: at a slot the adaptive plan decides once the live model has
    /// seen all of them (`sequencer::plan_model`).
    sweeps_run: sequencer::SweepsRun,
}

impl std::fmt::Debug for Headless {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Headless").field("procedure", &self.seq.plan().procedure).finish()
    }
}

/// Loads the rig config of `spec` with its overrides and its MF-Tyre 6.1 tyre (the truth a fit
/// of an MF rig's log is compared with); a brush tyre is an error here ([`rig_and_tyre`]).
pub fn rig_config(spec: &RunSpec) -> Result<(RigConfig, TyreParams), HeadlessError> {
    let (cfg, tyre) = rig_and_tyre(spec)?;
    match tyre {
        VirtualTyre::Mf(p) => Ok((cfg, *p)),
        VirtualTyre::Brush(_) => Err(HeadlessError::Tyre {
            path: cfg.tyre_file.display().to_string(),
            detail: "a brush tyre, not an MF-Tyre 6.1 .tir".into(),
        }),
    }
}

/// Loads the rig config of `spec` with its overrides (tyre, effects, wear multiplier) and the
/// tyre it names (MF `.tir` or brush file, per the config's `[tyre] model`).
pub fn rig_and_tyre(spec: &RunSpec) -> Result<(RigConfig, VirtualTyre), HeadlessError> {
    let mut cfg = RigConfig::load(&spec.rig_config).map_err(|e| HeadlessError::RigConfig(e.to_string()))?;
    if let Some(t) = &spec.tyre {
        cfg.tyre_file = t.clone();
    }
    if let Some(e) = &spec.effects {
        cfg.effects = rigsim::Effects::parse(e).map_err(|e| HeadlessError::Effects(e.to_string()))?;
    }
    if let Some(m) = spec.wear_multiplier {
        cfg.tyre.wear_rate_multiplier *= m;
    }
    // The rig's load envelope follows the rating the operator entered, as on a real rig: a wrong
    // entry loads the tyre too hard, and the monitor has to catch it from the data.
    cfg.tyre.load_index = spec.inputs.load_index;
    let tyre = VirtualTyre::load(&cfg)
        .map_err(|e| HeadlessError::Tyre { path: cfg.tyre_file.display().to_string(), detail: e.to_string() })?;
    Ok((cfg, tyre))
}

/// The run inputs for `spec` on `tyre`: the spec's, except that a brush tyre (with
/// `use_tyre_ratings`) brings its own nominal load (its load index when it has one, else Fz0
/// directly) and test pressures; the plan's pressure envelope is the rig's.
pub fn run_inputs(spec: &RunSpec, cfg: &RigConfig, tyre: &VirtualTyre) -> RunInputs {
    let mut inputs = spec.inputs;
    if let (Some(b), true) = (tyre.brush_params(), spec.use_tyre_ratings) {
        match b.load_index {
            Some(li) => inputs.load_index = li,
            None => inputs.fz0_n = Some(b.nominal.load_n),
        }
        inputs.pressures_bar = b.nominal.test_pressures_bar;
    }
    let rig = cfg.limits();
    inputs.limits.min_pressure_bar = rig.min_pressure_pa / procedure::setpoint::PA_PER_BAR;
    inputs.limits.max_pressure_bar = rig.max_pressure_pa / procedure::setpoint::PA_PER_BAR;
    inputs
}

/// The ETRTO load index a tyre declares, from its nominal load: the index whose
/// Fz0 = 0.65 × capacity × 9.81 is nearest FNOMIN (the thesis's tyre: 6,752 N → 110).
pub fn declared_load_index(tyre: &VirtualTyre) -> u32 {
    if let Some(li) = tyre.brush_params().and_then(|b| b.load_index) {
        return li;
    }
    let fnomin = tyre.fnomin_n();
    (60..=130)
        .filter_map(|li| procedure::fz0_n(li).ok().map(|fz0| (li, (fz0 - fnomin).abs())))
        .min_by(|a, b| a.1.total_cmp(&b.1))
        .map_or(110, |(li, _)| li)
}

/// Loads and expands the procedure of `spec` with `inputs` ([`run_inputs`]).
pub fn plan(spec: &RunSpec, inputs: &RunInputs) -> Result<Plan, HeadlessError> {
    let doc = procedure::load(&spec.procedure_file).map_err(|e| HeadlessError::Procedure(e.to_string()))?;
    procedure::expand(&doc, inputs).map_err(|e| HeadlessError::Procedure(e.to_string()))
}

/// The monitor's view of the tyre: its own rating (sidewall), whatever the operator entered.
fn tyre_info(cfg: &RigConfig, tyre: &VirtualTyre) -> Result<TyreInfo, HeadlessError> {
    let li = declared_load_index(tyre);
    let mut info = TyreInfo::from_load_index(li).map_err(|e| HeadlessError::Procedure(format!("load index: {e}")))?;
    if tyre.brush_params().is_some() {
        // A brush tyre states its nominal load (race tyres have no index of their own) and tread.
        info.fz0_n = tyre.fnomin_n();
        info.tread_new_mm = cfg.tyre.new_tread_depth_mm;
        info.tread_min_mm = cfg.tyre.legal_min_tread_depth_mm;
    }
    Ok(info)
}

/// Rig time a slot of the adaptive plan waits, at most, for the live fit to update on the data
/// step before it (it needs one sample; a segment too short to keep never comes).
const PLAN_MODEL_WAIT_S: f64 = 1.0;

impl Headless {
    /// Builds the cores for `spec`.
    pub fn new(spec: &RunSpec, thermal_cfg: ThermalConfig, seq_cfg: SequencerConfig) -> Result<Self, HeadlessError> {
        let (rig_cfg, tyre) = rig_and_tyre(spec)?;
        let inputs = run_inputs(spec, &rig_cfg, &tyre);
        let plan = plan(spec, &inputs)?;
        let rig = VirtualRig::new(rig_cfg.clone(), tyre.clone(), spec.seed)
            .map_err(|e| HeadlessError::RigConfig(e.to_string()))?;
        let gate = ThermalGate::new(thermal_cfg).map_err(|e| HeadlessError::Thermal(e.to_string()))?;
        let mut seq_cfg = seq_cfg;
        // The sequencer guards the same machine as the rig: its pressure envelope is the rig's.
        seq_cfg.envelope.min_pressure_bar = inputs.limits.min_pressure_bar;
        seq_cfg.envelope.max_pressure_bar = inputs.limits.max_pressure_bar;
        let seq = Sequencer::for_config(plan, seq_cfg).map_err(|e| HeadlessError::Sequencer(e.to_string()))?;
        // The monitor judges the data against the tyre's own (sidewall) rating, which the
        // operator's entry may contradict: it is not told the entry, it has to see it in the loads.
        let tyre_info = tyre_info(&rig_cfg, &tyre)?;
        let pipeline = Pipeline::new(channels::ChannelsConfig::default(), MonitorConfig::default(), tyre_info)
            .map_err(|e| HeadlessError::Procedure(format!("monitor: {e}")))?;
        Ok(Self {
            rig,
            rig_cfg,
            tyre,
            inputs,
            gate,
            seq,
            seed: spec.seed,
            time_offset_s: 0.0,
            seq_offset: 0,
            max_rig_time_s: spec.max_rig_time_s,
            wear_true: Vec::new(),
            pipeline,
            live_fit: None,
            live_fit_walls: Vec::new(),
            model_watch: monitor::ModelWatch::new(),
            sweeps_run: sequencer::SweepsRun::default(),
        })
    }

    /// Adds the live fit (`docs/live-fit.md`): after every completed data segment the staged
    /// MF-Tyre 6.1 fit is updated in the loop, before the next sample (so a headless run stays
    /// deterministic), and its `ModelState` goes to the sink on `model/state`. The run's nominal
    /// load is the plan's.
    pub fn with_live_fit(mut self, mut cfg: livefit::LiveFitConfig) -> Self {
        cfg.fz0_n = cfg.fz0_n.or(Some(self.seq.plan().fz0_n));
        self.live_fit = Some(livefit::LiveFit::new(cfg));
        self
    }

    /// The live fit's final model (after [`Headless::run`]), for the caller to write.
    pub fn live_fit_result(&self) -> Option<&mffit::FitResult> {
        self.live_fit.as_ref().and_then(|f| f.latest())
    }

    /// Wall time of each live-fit update after a sweep, s (the final update not included).
    pub fn live_fit_update_walls(&self) -> &[f64] {
        &self.live_fit_walls
    }

    /// The expanded plan.
    pub fn plan(&self) -> &Plan {
        self.seq.plan()
    }

    /// The metadata records a log of this run carries.
    pub fn metadata(&self, spec: &RunSpec) -> BTreeMap<String, BTreeMap<String, String>> {
        let mut md = BTreeMap::new();
        let mut tyre = BTreeMap::new();
        tyre.insert("file".to_owned(), self.rig_cfg.tyre_file.display().to_string());
        tyre.insert("fnomin_n".to_owned(), format!("{}", self.tyre.fnomin_n()));
        tyre.insert("unloaded_radius_m".to_owned(), format!("{}", self.tyre.unloaded_radius_m()));
        tyre.insert("load_index".to_owned(), self.inputs.load_index.to_string());
        if let Some(b) = self.tyre.brush_params() {
            tyre.insert("model".to_owned(), "brush".to_owned());
            tyre.insert("name".to_owned(), b.name.clone());
            tyre.insert("rim_width_in".to_owned(), format!("{}", b.dimensions.rim_width_in));
            tyre.insert("width_m".to_owned(), format!("{}", b.dimensions.width_m));
        }
        md.insert("tyre".to_owned(), tyre);
        let mut proc_ = BTreeMap::new();
        proc_.insert("name".to_owned(), self.seq.plan().procedure.clone());
        proc_.insert("title".to_owned(), self.seq.plan().title.clone());
        proc_.insert("file".to_owned(), spec.procedure_file.display().to_string());
        proc_.insert("fz0_n".to_owned(), format!("{}", self.seq.plan().fz0_n));
        proc_.insert("pressures_bar".to_owned(), format!("{:?}", self.inputs.pressures_bar));
        proc_.insert("nominal_speed_mps".to_owned(), format!("{}", self.inputs.nominal_speed_mps));
        proc_.insert("sweeps".to_owned(), format!("{:?}", spec.inputs.sweeps).to_lowercase());
        md.insert("procedure".to_owned(), proc_);
        let mut rig = BTreeMap::new();
        rig.insert("kind".to_owned(), "virtual".to_owned());
        rig.insert("effects".to_owned(), self.rig_cfg.effects.to_string());
        rig.insert("seed".to_owned(), self.seed.to_string());
        rig.insert("publish_rate_hz".to_owned(), self.rig_cfg.publish_rate_hz.to_string());
        rig.insert("config".to_owned(), spec.rig_config.display().to_string());
        rig.insert("ambient_temp_c".to_owned(), format!("{}", self.rig_cfg.environment.ambient_temp_c));
        rig.insert("belt_temp_c".to_owned(), format!("{}", self.rig_cfg.environment.belt_temp_c));
        md.insert("rig".to_owned(), rig);
        let mut sw = BTreeMap::new();
        sw.insert("software".to_owned(), "tyrerig".to_owned());
        sw.insert("software_version".to_owned(), env!("CARGO_PKG_VERSION").to_owned());
        sw.insert("mode".to_owned(), "headless".to_owned());
        sw.insert("namespace".to_owned(), "/rig".to_owned());
        sw.insert("log_time".to_owned(), "simulated rig time the message was produced at, ns".to_owned());
        sw.insert("publish_time".to_owned(), "the message's header.stamp (rig time), ns".to_owned());
        md.insert("tyrerig".to_owned(), sw);
        md
    }

    fn retime(&self, mut s: RigSample) -> RigSample {
        if self.time_offset_s > 0.0 {
            s.runtime_s += self.time_offset_s;
            let stamp = Time::from_secs_f64(s.runtime_s);
            s.header = Header { stamp, frame_id: std::mem::take(&mut s.header.frame_id) };
            s.seq += self.seq_offset;
        }
        s
    }

    /// Mounts a new specimen: a fresh tyre (new tread, not broken in, at room temperature).
    fn mount_new_tyre(&mut self, last_seq: u64) -> Result<(), HeadlessError> {
        self.wear_true.push(self.rig.truth().tread_worn_mm);
        // One channels/monitor pipeline serves the whole run: its cores see PHASE_TYRE_CHANGE
        // and keep per-specimen wear themselves, so a replay of the log matches the live run.
        self.time_offset_s += self.rig.time_s();
        self.seq_offset = last_seq + 1;
        let seed = self.seed.wrapping_add(self.wear_true.len() as u64);
        self.rig = VirtualRig::new(self.rig_cfg.clone(), self.tyre.clone(), seed)
            .map_err(|e| HeadlessError::RigConfig(e.to_string()))?;
        Ok(())
    }

    /// Publishes what the channels/monitor pipeline produced and keeps its alarms and wear.
    fn pipeline_out(
        &self,
        t: f64,
        p: &monitor::pipeline::PipelineOutput,
        sink: &mut dyn MessageSink,
        sum: &mut SummaryBuilder,
    ) -> Result<(), HeadlessError> {
        if p.live.header.stamp.as_nanos() > 0 {
            sink.put(t, Outgoing::Live(&p.live))?;
        }
        for ss in &p.sweep_summaries {
            sink.put(t, Outgoing::SweepSummary(ss))?;
        }
        for d in &p.derived {
            sink.put(t, Outgoing::Derived(&d.to_msg()))?;
        }
        if let Some(r) = &p.report {
            sink.put(t, Outgoing::Quality(r))?;
        }
        if let Some(d) = &p.diagnostics {
            sink.put(t, Outgoing::Diagnostics(d))?;
        }
        for a in &p.alarms {
            sum.alarm(&a.level, &a.check, a.message.clone(), a.rig_time_s);
        }
        Ok(())
    }

    /// The error ending a run whose gate held on a sensor fault for `held_s`, with what to do
    /// where the virtual rig's own settings cause it.
    fn sensor_fault_held(&self, held_s: f64, fault: &str, t: f64) -> HeadlessError {
        let st = self.seq.procedure_state(t);
        let effects = &self.rig_cfg.effects;
        let hint = if !effects.thermal && !effects.noise {
            ". Without `thermal` or `noise` in --effects the virtual tyre's temperature never changes, \
             which the gate reads as a stuck sensor, as it must: add one of them"
                .to_owned()
        } else {
            String::new()
        };
        HeadlessError::SensorFaultHeld {
            held_s,
            fault: fault.to_owned(),
            at: format!("{} / {} / {}", st.procedure, st.section, st.sweep_name),
            hint,
        }
    }

    /// Runs the procedure to its end. `progress` receives the sequencer's progress (0..1).
    pub fn run(
        &mut self,
        sink: &mut dyn MessageSink,
        progress: &mut dyn FnMut(f64, f64),
    ) -> Result<RunSummary, HeadlessError> {
        let plan_name = self.seq.plan().procedure.clone();
        let mut sum = SummaryBuilder::new(&plan_name);
        let dt_sample = 1.0 / f64::from(self.rig_cfg.publish_rate_hz);
        let start =
            ProcedureCommand { command: ProcedureCommand::START, procedure: plan_name.clone(), ..Default::default() };
        let out = self.seq.on_command(0.0, &start).map_err(|e| HeadlessError::Sequencer(e.to_string()))?;
        let mut first_tyre_mounted = false;
        for ev in &out.events {
            sum.on_event(ev);
            // A procedure that starts with mounting its first specimen: that tyre is the one on
            // the rig already.
            first_tyre_mounted |= matches!(ev, SequencerEvent::TyreChange { .. });
        }
        if let Some(sp) = &out.setpoint {
            let _ = self.rig.apply_setpoint(sp);
        }
        let mut last_seq = 0;
        let mut refusing = false;
        let mut in_sweep = false;
        // Rig time a slot has waited for the live model to see the sweep before it.
        let mut plan_wait_from: Option<f64> = None;
        // Rig time since the gate went into a sensor fault it has not left.
        let mut fault_from: Option<f64> = None;
        loop {
            let Some(local) = self.rig.step() else { continue };
            let sample = self.retime(local);
            let t = sample.runtime_s;
            last_seq = sample.seq.max(last_seq);
            sink.put(t, Outgoing::Sample(&sample))?;
            sum.add_time(dt_sample);
            if in_sweep {
                sum.summary.max_temp_c = sum.summary.max_temp_c.max(sample.trdtempc_c);
            }

            self.gate.on_sample(t, &sample);
            let th = self.gate.step(t);
            sink.put(t, Outgoing::Thermal(&th.state))?;
            for a in th.alarms.iter().filter(|a| a.check != thermal::ThermalCheck::Timeout) {
                let level = match a.level {
                    thermal::core::AlarmLevel::Warn => "WARN",
                    thermal::core::AlarmLevel::Error => "ERROR",
                };
                sum.alarm(level, a.check.as_str(), a.message.clone(), a.rig_time_s);
            }

            if th.state.status == tyre_msgs::ThermalState::STATUS_FAULT {
                let since = *fault_from.get_or_insert(t);
                if t - since >= SENSOR_FAULT_HOLD_LIMIT_S {
                    return Err(self.sensor_fault_held(t - since, &th.state.fault, t));
                }
            } else {
                fault_from = None;
            }

            let p = self.pipeline.on_sample(&sample);
            self.pipeline_out(t, &p, sink, &mut sum)?;
            // The wear rate the monitor measured prices the adaptive plan's wear: read from its
            // `/diagnostics` record, as the sequencer node does over DDS.
            if let Some(rate) = p.diagnostics.as_ref().and_then(sequencer::measured_wear_rate) {
                self.seq.on_wear_rate(rate);
            }
            if let Some(fit) = self.live_fit.as_mut()
                && fit.on_sample(&sample) == livefit::Trigger::Update
            {
                let st = fit.update();
                self.live_fit_walls.push(st.update_wall_s);
                sink.put(t, Outgoing::Model(&st))?;
                sink.put(t, Outgoing::Covariance(&fit.model_covariance()))?;
                sink.put(t, Outgoing::Diagnostics(&self.model_watch.on_model_state(&st).diagnostics))?;
            }

            let out = self.seq.step(t, Some(&th.state), Some(&sample));
            if let Some(st) = &out.state {
                self.sweeps_run.on_state(st);
                self.gate.on_procedure_state(t, st);
                self.pipeline.on_procedure_state(st);
                if let Some(fit) = self.live_fit.as_mut() {
                    fit.on_procedure_state(st);
                }
                sum.on_state(st);
                progress(st.progress, t);
                sink.put(t, Outgoing::Procedure(st))?;
            }
            let mut done = false;
            if out.events.iter().any(|e| matches!(e, SequencerEvent::PlanNeeded { .. })) {
                // The adaptive plan decides with the model of all data so far. The fit closes a
                // segment on the sample after it and updates in this loop at once, so a slot
                // right after a data step waits a sample or two (the sequencer holds); a
                // segment the fit dropped (too short) must not hold it longer than a second.
                // Closing a slot at the plan's end completes the run.
                let reach = self.live_fit.as_ref().and_then(|f| f.latest_reach()).map(|(_, sweep)| sweep);
                let since = *plan_wait_from.get_or_insert(t);
                if self.live_fit.is_none() || self.sweeps_run.covered_by(reach) || t - since >= PLAN_MODEL_WAIT_S {
                    plan_wait_from = None;
                    done = self.plan_next(t, sink, &mut sum)?;
                }
            }
            for ev in &out.events {
                sum.on_event(ev);
                match ev {
                    SequencerEvent::TyreChange { .. } => {
                        // The thesis counts the first mounting too; only later ones need a new tyre.
                        if first_tyre_mounted {
                            self.mount_new_tyre(last_seq)?;
                        }
                        first_tyre_mounted = true;
                    }
                    SequencerEvent::SweepStarted { .. } => {
                        in_sweep = true;
                        sum.summary.max_sweep_start_temp_c = sum.summary.max_sweep_start_temp_c.max(sample.trdtempc_c);
                    }
                    SequencerEvent::SweepEnded { .. } => in_sweep = false,
                    SequencerEvent::Completed { .. } | SequencerEvent::EStop => done = true,
                    SequencerEvent::Aborted { reason } => {
                        sum.alarm("ERROR", "procedure", format!("aborted: {reason}"), t);
                        done = true;
                    }
                    SequencerEvent::SetpointRefused { step, axis, value, limit } => sum.alarm(
                        "ERROR",
                        "envelope",
                        format!("step {step}: {axis} = {value} outside the rig envelope (limit {limit})"),
                        t,
                    ),
                    _ => {}
                }
            }
            if let Some(sp) = &out.setpoint {
                sink.put(t, Outgoing::Setpoint(sp))?;
                match self.rig.apply_setpoint(sp) {
                    // One alarm per refusal episode, not one per control tick.
                    Err(refusal) if !refusing => {
                        refusing = true;
                        sum.alarm("ERROR", "envelope", format!("virtual rig refused a setpoint: {refusal}"), t);
                    }
                    Err(_) => {}
                    Ok(()) => refusing = false,
                }
            }
            if done {
                break;
            }
            if t > self.max_rig_time_s {
                let st = self.seq.procedure_state(t);
                return Err(HeadlessError::TooLong {
                    limit_s: self.max_rig_time_s,
                    at: format!("{} / {} / {}", st.procedure, st.section, st.sweep_name),
                });
            }
        }
        let p = self.pipeline.finish();
        let t_end = self.time_offset_s + self.rig.time_s();
        self.pipeline_out(t_end, &p, sink, &mut sum)?;
        if let Some(fit) = self.live_fit.as_mut() {
            let st = fit.finish();
            sink.put(t_end, Outgoing::Model(&st))?;
            sink.put(t_end, Outgoing::Covariance(&fit.model_covariance()))?;
            sink.put(t_end, Outgoing::Diagnostics(&self.model_watch.on_model_state(&st).diagnostics))?;
        }
        if first_tyre_mounted || self.wear_true.is_empty() {
            self.wear_true.push(self.rig.truth().tread_worn_mm);
        }
        sum.summary.wear_mm_measured = self.pipeline.monitor.wear_by_specimen_mm();
        sum.summary.tyres_used = if sum.summary.tyre_changes > 0 { sum.summary.tyre_changes } else { 1 };
        sum.summary.wear_mm_true = self.wear_true.clone();
        Ok(sum.summary)
    }
}

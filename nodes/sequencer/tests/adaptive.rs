//! The adaptive plan in the sequencer core: slots filled by the planner's choices, the thermal
//! gate still the only thing that releases a sweep, checkpoint/resume continuing the same
//! decisions. The model is a synthetic linear one (the planner's maths is tested in
//! `libs/adaptive`; the live fit in `nodes/suite`).

use adaptive::design;
use adaptive::model::{ModelView, Target, TargetModel};
use nalgebra::DMatrix;
use procedure::{Plan, RunInputs, Setpoint};
use sequencer::core::{Checkpoint, Sequencer, SequencerEvent, SequencerOutput};
use sequencer::{PlanKind, SequencerConfig};
use std::path::PathBuf;
use tyre_msgs::std_msgs::Header;
use tyre_msgs::{ProcedureCommand, ThermalState};

fn gs2mf() -> Plan {
    let f = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../launch-config/procedures/gs2mf.toml");
    procedure::expand(&procedure::load(&f).unwrap(), &RunInputs::default()).unwrap()
}

fn cfg() -> SequencerConfig {
    SequencerConfig { plan: PlanKind::Adaptive, ..SequencerConfig::default() }
}

fn features(sp: &Setpoint) -> Vec<f64> {
    vec![
        1.0,
        sp.slip_angle_deg / 10.0 + sp.slip_ratio * 5.0,
        sp.pressure_bar - 2.6,
        sp.camber_deg / 4.0,
        sp.fz_n / 6759.0 - 1.0,
    ]
}

/// A linear "tyre" whose parameters multiply known features of the operating point.
struct Synth(Vec<(Target, TargetModel)>);

impl Synth {
    fn new() -> Self {
        let mut rows = Vec::new();
        for p in [2.2, 2.6, 3.0] {
            for c in [-4.0, 0.0, 4.0] {
                for sa in [-8.0, 8.0] {
                    rows.push(features(&Setpoint {
                        pressure_bar: p,
                        camber_deg: c,
                        slip_angle_deg: sa,
                        fz_n: 6759.0,
                        ..Setpoint::default()
                    }));
                }
            }
        }
        let g = DMatrix::from_fn(rows.len(), 5, |i, j| rows[i][j]);
        let h = design::grid_weight(&g);
        Synth(
            Target::ALL
                .iter()
                .map(|&t| (t, TargetModel { cov: DMatrix::identity(5, 5) * 0.01, h: h.clone(), sigma: 0.02 }))
                .collect(),
        )
    }
}

impl ModelView for Synth {
    fn target(&self, t: Target) -> Option<&TargetModel> {
        self.0.iter().find(|(x, _)| *x == t).map(|(_, m)| m)
    }
    fn sensitivities(&self, _: Target, points: &[Setpoint]) -> DMatrix<f64> {
        DMatrix::from_fn(points.len(), 5, |i, j| features(&points[i])[j])
    }
}

/// Runs `seq` from `t` with a thermal gate that opens `gate_s` after each pause begins, asking
/// the planner at every slot; stops after `max_decisions` decisions (at the next slot) or at
/// completion. Returns (t, events) and checks on the way that no sweep starts during a pause.
fn drive(seq: &mut Sequencer, mut t: f64, max_decisions: usize) -> (f64, Vec<SequencerEvent>) {
    let view = Synth::new();
    let dt = 0.05;
    let gate_s = 3.0;
    let mut pause_since: Option<f64> = None;
    let mut events = Vec::new();
    let mut decisions = 0;
    let take = |out: &SequencerOutput, t: f64, pause_since: &mut Option<f64>, events: &mut Vec<SequencerEvent>| {
        for e in &out.events {
            match e {
                SequencerEvent::ThermalPauseStarted { .. } => *pause_since = Some(t),
                SequencerEvent::ThermalPauseEnded { .. } => *pause_since = None,
                SequencerEvent::SweepStarted { name, .. } => {
                    assert!(pause_since.is_none(), "{name} started during a thermal pause");
                }
                _ => {}
            }
            events.push(e.clone());
        }
    };
    while t < 40_000.0 {
        t += dt;
        let open = pause_since.is_none_or(|p| t - p >= gate_s);
        let th = ThermalState {
            header: Header::iso_w(t),
            status: if open { ThermalState::STATUS_RELEASED } else { ThermalState::STATUS_WAITING },
            gate_open: open,
            ..ThermalState::default()
        };
        let out = seq.step(t, Some(&th), None);
        take(&out, t, &mut pause_since, &mut events);
        if out.events.iter().any(|e| matches!(e, SequencerEvent::Completed { .. })) {
            return (t, events);
        }
        if out.events.iter().any(|e| matches!(e, SequencerEvent::PlanNeeded { .. })) {
            if decisions == max_decisions {
                return (t, events);
            }
            assert!(seq.awaiting_plan().is_some());
            let out = seq.plan_next(t, &view);
            decisions += 1;
            take(&out, t, &mut pause_since, &mut events);
            // A slot at the plan's end: closing it completes the run.
            if out.events.iter().any(|e| matches!(e, SequencerEvent::Completed { .. })) {
                return (t, events);
            }
        }
    }
    panic!("the adaptive plan did not complete in 40,000 s of rig time");
}

fn start(seq: &mut Sequencer, t: f64) -> Vec<SequencerEvent> {
    let cmd = ProcedureCommand { command: ProcedureCommand::START, ..ProcedureCommand::default() };
    seq.on_command(t, &cmd).unwrap().events
}

fn chosen(events: &[SequencerEvent]) -> Vec<String> {
    events
        .iter()
        .filter_map(|e| match e {
            SequencerEvent::SweepChosen { name, .. } => Some(name.clone()),
            SequencerEvent::SlotClosed { slot, .. } => Some(format!("closed {slot}")),
            _ => None,
        })
        .collect()
}

#[test]
fn the_slots_run_the_chosen_sweeps_and_the_plan_completes_within_the_envelope() {
    let plan = gs2mf();
    let candidates = plan.steps.len();
    let mut seq = Sequencer::for_config(plan, cfg()).unwrap();
    assert!(seq.plan().steps.len() < candidates, "the fixed plan is shorter than the procedure");
    start(&mut seq, 0.0);
    let (_, events) = drive(&mut seq, 0.0, usize::MAX);
    let picks: Vec<String> = chosen(&events).into_iter().filter(|c| !c.starts_with("closed")).collect();
    assert!(!picks.is_empty());
    // Both slots closed, by the stop rule, before every candidate ran.
    let closed: Vec<&SequencerEvent> =
        events.iter().filter(|e| matches!(e, SequencerEvent::SlotClosed { .. })).collect();
    assert_eq!(closed.len(), 2, "{closed:?}");
    let lib = seq.planner().unwrap().library();
    assert!(picks.len() < lib.candidates.len(), "{} of {}", picks.len(), lib.candidates.len());
    // Every chosen sweep ran, after its choice; graph sweeps ran in full.
    let started: Vec<String> = events
        .iter()
        .filter_map(|e| match e {
            SequencerEvent::SweepStarted { name, .. } => Some(name.clone()),
            _ => None,
        })
        .collect();
    for p in &picks {
        assert!(started.contains(p), "{p} chosen but never run");
    }
    assert_eq!(started.iter().filter(|n| n.contains("GraphSweep")).count(), 20);
    // Nothing was refused or aborted: every setpoint inside the envelope.
    assert!(
        !events.iter().any(|e| matches!(e, SequencerEvent::SetpointRefused { .. } | SequencerEvent::Aborted { .. }))
    );
    // The plan the sequencer ran is inside the envelope, step by step.
    seq.plan().check_envelope(&cfg().envelope).unwrap();
}

#[test]
fn a_checkpoint_mid_slot_resumes_with_the_same_decisions() {
    let plan = gs2mf();
    let mut a = Sequencer::for_config(plan.clone(), cfg()).unwrap();
    start(&mut a, 0.0);
    // Stop at the slot after three decisions: the checkpoint holds them.
    let (t, _) = drive(&mut a, 0.0, 3);
    let cp: Checkpoint = serde_json::from_str(&serde_json::to_string(&a.checkpoint()).unwrap()).unwrap();
    assert_eq!(cp.adaptive.as_ref().unwrap().insertions.len(), 3);
    let mut b = Sequencer::resume_for_config(plan.clone(), cfg(), &cp).unwrap();
    assert_eq!(b.plan().fingerprint(), a.plan().fingerprint());
    // The original goes on from where it waits; the resumed one restarts at the same slot.
    let view = Synth::new();
    let out = a.plan_next(t, &view);
    let mut a_events = out.events.clone();
    let (_, rest) = drive(&mut a, t, usize::MAX);
    a_events.extend(rest);
    start(&mut b, t);
    let (_, b_events) = drive(&mut b, t, usize::MAX);
    assert_eq!(chosen(&a_events), chosen(&b_events));
    let names = |s: &Sequencer| s.plan().steps.iter().map(|x| x.name.clone()).collect::<Vec<_>>();
    assert_eq!(names(&a), names(&b));
    // A checkpoint of another procedure's fixed plan is refused.
    let mut bad = cp.clone();
    bad.adaptive.as_mut().unwrap().fixed_fingerprint ^= 1;
    assert!(Sequencer::resume_for_config(plan.clone(), cfg(), &bad).is_err());
    // A fixed run's checkpoint is not an adaptive one.
    let fixed = Sequencer::new(plan.clone(), SequencerConfig::default()).unwrap().checkpoint();
    assert!(Sequencer::resume_for_config(plan, cfg(), &fixed).is_err());
}

#[test]
fn the_procedure_state_says_why_a_chosen_sweep_runs_and_what_error_it_predicts() {
    let plan = gs2mf();
    let mut seq = Sequencer::for_config(plan.clone(), cfg()).unwrap();
    let first = start(&mut seq, 0.0);
    assert!(!first.is_empty());
    // The fixed steps before the first slot: "fixed", no prediction.
    let st = seq.procedure_state(1.0);
    assert_eq!((st.plan_reason.as_str(), st.predicted_error_pct), ("fixed", 0.0));
    let (t, _) = drive(&mut seq, 0.0, 0);
    let out = seq.plan_next(t, &Synth::new());
    let (reason, after) = out
        .events
        .iter()
        .find_map(|e| match e {
            SequencerEvent::SweepChosen { reason, error_after_pct, .. } => Some((reason.clone(), *error_after_pct)),
            _ => None,
        })
        .expect("the first slot chooses a sweep");
    assert!(!reason.is_empty() && after > 0.0, "{reason} {after}");
    let st = out.state.expect("a decision publishes the state");
    assert_eq!((st.plan_reason.as_str(), st.predicted_error_pct), (reason.as_str(), after));
    // The checkpoint keeps the reason, so a resumed run says the same.
    let cp: Checkpoint = serde_json::from_str(&serde_json::to_string(&seq.checkpoint()).unwrap()).unwrap();
    let ins = &cp.adaptive.as_ref().unwrap().insertions[0];
    // (JSON keeps the number to within a unit in the last place.)
    assert_eq!(ins.reason, reason);
    assert!((ins.error_after_pct - after).abs() <= 1e-12 * after, "{} vs {after}", ins.error_after_pct);
    // A fixed procedure's states carry no plan reason.
    let fixed = Sequencer::new(plan, SequencerConfig::default()).unwrap();
    assert_eq!(fixed.procedure_state(0.0).plan_reason, "");
}

#[test]
fn until_its_slots_close_the_remaining_time_counts_what_they_may_still_run() {
    let plan = gs2mf();
    let mut seq = Sequencer::for_config(plan, cfg()).unwrap();
    start(&mut seq, 0.0);
    let planner = seq.planner().unwrap();
    let budgets_s: f64 = planner.library().slots.iter().map(|s| planner.config().budget_fraction * s.full_cost_s).sum();
    assert!(budgets_s > 1000.0, "GS2MF's candidates take {budgets_s} s");
    // The same fixed steps run as a fixed plan: what the state would say without the slots.
    let mut fixed = Sequencer::new(planner.library().fixed.clone(), SequencerConfig::default()).unwrap();
    start(&mut fixed, 0.0);
    let (with_slots, fixed_only) = (seq.procedure_state(1.0), fixed.procedure_state(1.0));
    let added = with_slots.estimated_remaining_s - fixed_only.estimated_remaining_s;
    assert!((added - budgets_s).abs() < 1e-6 * budgets_s, "added {added} s, budgets {budgets_s} s");
    assert!(with_slots.progress < fixed_only.progress || fixed_only.progress == 0.0);
    // An upper bound: the run ends no later than the first state said.
    let promised_s = with_slots.elapsed_rig_time_s + with_slots.estimated_remaining_s;
    let (end_s, _) = drive(&mut seq, 0.0, usize::MAX);
    assert!(end_s <= promised_s, "ended at {end_s:.0} s, promised by {promised_s:.0} s");
    // Closed slots add nothing: the end state is complete, nothing remaining.
    let last = seq.procedure_state(end_s);
    assert_eq!((last.progress, last.estimated_remaining_s), (1.0, 0.0));
}

#[test]
fn the_measured_wear_rate_reaches_the_planner_and_survives_a_resume() {
    let plan = gs2mf();
    let mut a = Sequencer::for_config(plan.clone(), cfg()).unwrap();
    let configured = a.planner().unwrap().wear_rate_mm_per_mj();
    start(&mut a, 0.0);
    let (_, _) = drive(&mut a, 0.0, 2);
    // The monitor measured a tyre wearing three times the configured rate, to ±5 %.
    let measured = adaptive::MeasuredWearRate { mm_per_mj: 3.0 * configured, sd_mm_per_mj: 0.15 * configured };
    assert!(a.on_wear_rate(measured));
    let priced = a.planner().unwrap().wear_rate_mm_per_mj();
    assert!(priced > 2.9 * configured && priced < 3.0 * configured, "{priced} mm/MJ");
    // The checkpoint keeps it: the resumed run prices wear as the interrupted one did.
    let cp: Checkpoint = serde_json::from_str(&serde_json::to_string(&a.checkpoint()).unwrap()).unwrap();
    let b = Sequencer::resume_for_config(plan.clone(), cfg(), &cp).unwrap();
    assert_eq!(b.planner().unwrap().wear_rate_mm_per_mj(), priced);
    // A fixed plan has nothing to price: it ignores the rate.
    let mut fixed = Sequencer::new(plan, SequencerConfig::default()).unwrap();
    assert!(!fixed.on_wear_rate(measured));
}

//! The planner on the real GS2MF plan with a synthetic linear model whose sensitivities are
//! known features of the operating point (so what each sweep can teach is known exactly).

use adaptive::design;
use adaptive::library::CandidateKind;
use adaptive::model::{ModelView, Target, TargetModel};
use adaptive::{AdaptiveConfig, Library, MeasuredWearRate, Planner};
use nalgebra::DMatrix;
use procedure::{PauseModel, RigLimits, RunInputs, Setpoint};
use std::path::PathBuf;

fn gs2mf_library(cfg: &AdaptiveConfig) -> Library {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../launch-config/procedures/gs2mf.toml");
    let doc = procedure::load(&root).unwrap();
    let plan = procedure::expand(&doc, &RunInputs::default()).unwrap();
    Library::from_plan(&plan, &PauseModel::default(), &RigLimits::default(), cfg).unwrap()
}

/// Features of a setpoint: what a linear "tyre" depends on. Pressure and camber effects are only
/// learnt from sweeps away from 2.6 bar and 0°.
fn features(sp: &Setpoint) -> Vec<f64> {
    vec![
        1.0,
        sp.slip_angle_deg / 10.0 + sp.slip_ratio * 5.0,
        sp.pressure_bar - 2.6,
        sp.camber_deg / 4.0,
        sp.fz_n / 6759.0 - 1.0,
    ]
}

struct Synth {
    models: Vec<(Target, TargetModel)>,
    /// Targets whose output does not depend on the parameters at all (zero sensitivities).
    flat: Vec<Target>,
}

impl Synth {
    fn new(var: f64, sigma: f64) -> Self {
        let mut grid = Vec::new();
        for p in [2.2, 2.6, 3.0] {
            for c in [-4.0, 0.0, 4.0] {
                for sa in [-8.0, 0.0, 8.0] {
                    for fz in [3400.0, 6759.0, 10000.0] {
                        grid.push(features(&Setpoint {
                            pressure_bar: p,
                            camber_deg: c,
                            slip_angle_deg: sa,
                            fz_n: fz,
                            ..Setpoint::default()
                        }));
                    }
                }
            }
        }
        let g = DMatrix::from_fn(grid.len(), 5, |i, j| grid[i][j]);
        let h = design::grid_weight(&g);
        let models = Target::ALL
            .iter()
            .map(|&t| (t, TargetModel { cov: DMatrix::identity(5, 5) * var, h: h.clone(), sigma }))
            .collect();
        Synth { models, flat: Vec::new() }
    }
}

impl ModelView for Synth {
    fn target(&self, t: Target) -> Option<&TargetModel> {
        self.models.iter().find(|(x, _)| *x == t).map(|(_, m)| m)
    }
    fn sensitivities(&self, t: Target, points: &[Setpoint]) -> DMatrix<f64> {
        let k = if self.flat.contains(&t) { 0.0 } else { 1.0 };
        DMatrix::from_fn(points.len(), 5, |i, j| k * features(&points[i])[j])
    }
}

fn start(lib: &Library, slot: usize) -> Setpoint {
    let at = lib.slots[slot].at;
    lib.fixed.steps[at - 1].trajectory.end()
}

#[test]
fn gs2mf_has_a_lateral_and_a_longitudinal_slot_and_keeps_the_fixed_parts() {
    let cfg = AdaptiveConfig::default();
    let lib = gs2mf_library(&cfg);
    assert_eq!(lib.slots.len(), 2, "{:?}", lib.slots);
    let kinds =
        |s: usize| -> Vec<CandidateKind> { lib.slots[s].candidates.iter().map(|&c| lib.candidates[c].kind).collect() };
    assert!(kinds(0).iter().all(|k| *k == CandidateKind::Lateral));
    assert!(kinds(1).iter().all(|k| *k != CandidateKind::Lateral));
    assert!(kinds(1).contains(&CandidateKind::Combined) && kinds(1).contains(&CandidateKind::Longitudinal));
    // The fixed plan keeps graph sweeps (4 blocks of 5), warm-ups, holds, tyre changes.
    let graph = lib.fixed.steps.iter().filter(|s| s.name.contains("GraphSweep")).count();
    assert_eq!(graph, 20);
    assert!(lib.fixed.steps.iter().any(|s| s.name.contains("StaticDrag")));
    assert!(lib.fixed.steps.iter().any(|s| s.name.contains("StepSteer")));
    assert!(lib.fixed.steps.iter().any(|s| s.name.contains("heating") || s.section_index < lib.fixed.sections.len()));
    // Indices, groups and data numbers are consistent.
    let mut data = 0;
    for (i, s) in lib.fixed.steps.iter().enumerate() {
        assert_eq!(s.index, i);
        assert!(s.restart_from <= i);
        if let Some(k) = s.sweep_index {
            assert_eq!(k, data);
            data += 1;
        }
    }
    // Severe sweeps are the extreme and 22°/vertical-load ones.
    let severe: Vec<&str> = lib.candidates.iter().filter(|c| c.severe).map(|c| c.name.as_str()).collect();
    assert!(severe.iter().any(|n| n.contains("VerticalLoad")), "{severe:?}");
    assert!(lib.candidates.iter().any(|c| !c.severe));
}

#[test]
fn costs_add_up_to_the_steps_that_run() {
    let cfg = AdaptiveConfig::default();
    let lib = gs2mf_library(&cfg);
    let lim = RigLimits::default();
    let mut from = start(&lib, 0);
    let mut total_cost = 0.0;
    let mut total_steps = 0.0;
    for &id in lib.slots[0].candidates.iter().take(8) {
        let c = &lib.candidates[id];
        let group = c.group(from, &lim);
        let steps: f64 = group.iter().map(|s| s.duration_s).sum();
        assert!((c.cost_s(from, &lim, 1.0) - (steps + c.pause_s)).abs() < 1e-9);
        // A pressure change is in the group exactly when the pressure differs.
        let has_pc = group.iter().any(|s| s.kind == procedure::StepKind::PressureChange);
        assert_eq!(has_pc, (from.pressure_bar - c.pressure_bar).abs() > 1e-9);
        // The group ends with the sweep itself, and is continuous.
        assert_eq!(group.last().unwrap().name, c.name);
        for w in group.windows(2) {
            let (a, b) = (w[0].trajectory.end(), w[1].trajectory.start());
            assert!((a.fz_n - b.fz_n).abs() < 1e-6 && (a.pressure_bar - b.pressure_bar).abs() < 1e-9);
        }
        total_cost += c.cost_s(from, &lim, 1.0);
        total_steps += steps + c.pause_s;
        from = c.end();
    }
    assert!((total_cost - total_steps).abs() < 1e-6);
    // Scaling the pauses scales only the pause part.
    let c = &lib.candidates[lib.slots[0].candidates[0]];
    let f = start(&lib, 0);
    assert!((c.cost_s(f, &lim, 2.0) - c.cost_s(f, &lim, 1.0) - c.pause_s).abs() < 1e-9);
}

#[test]
fn a_sweep_that_teaches_nothing_new_has_no_value_and_variance_never_grows() {
    let cfg = AdaptiveConfig::default();
    let mut lib = gs2mf_library(&cfg);
    lib.slots[0].candidates.truncate(6);
    let mut view = Synth::new(0.01, 0.02);
    // FY, MZ and MX flat: nothing a lateral sweep measures depends on the parameters.
    view.flat = vec![Target::FyPure, Target::MzPure, Target::MxPure];
    let p = Planner::new(lib.clone(), cfg);
    let d = p.evaluate(0, start(&lib, 0), &view, 1.0);
    assert!(d.candidate.is_none(), "{d:?}");
    assert!(d.reason.contains("target") || d.reason.contains("lowers"), "{}", d.reason);
    // With real sensitivities every decision's predicted error after is ≤ before.
    let view = Synth::new(0.01, 0.02);
    let mut p = Planner::new(lib.clone(), cfg);
    let mut from = start(&lib, 0);
    for _ in 0..6 {
        let d = p.decide(0, from, &view, 1.0);
        let Some(id) = d.candidate else { break };
        assert!(d.error_after_pct <= d.error_pct + 1e-12, "{d:?}");
        assert!(d.value >= 0.0 && d.cost_s > 0.0);
        from = p.library().candidates[id].end();
    }
}

#[test]
fn severe_sweeps_come_last_and_the_slot_closes() {
    let cfg = AdaptiveConfig::default();
    let lib = gs2mf_library(&cfg);
    let view = Synth::new(0.01, 0.02);
    let mut p = Planner::new(lib.clone(), cfg);
    let from = start(&lib, 0);
    let d = p.decide(0, from, &view, 1.0);
    let c = &lib.candidates[d.candidate.unwrap()];
    assert!(!c.severe, "{}", c.name);
    // Severe candidates are chosen only after every ordinary one is used or worthless: check the
    // sequence never has an ordinary candidate after a severe one.
    let mut from = c.end();
    let mut seen_severe = false;
    while let Some(id) = p.decide(0, from, &view, 1.0).candidate {
        let c = &lib.candidates[id];
        assert!(!seen_severe || c.severe, "ordinary {} after a severe sweep", c.name);
        seen_severe |= c.severe;
        from = c.end();
    }
    assert!(p.is_closed(0));
}

#[test]
fn the_stop_rule_fires_on_the_target_and_on_the_budget() {
    let lib = gs2mf_library(&AdaptiveConfig::default());
    let from = start(&lib, 0);
    // Noise so large that no sweep can change the prediction: the full run's predicted error
    // equals today's, so the target is met at once (stopping at the first reading).
    let once = AdaptiveConfig { target_confirmations: 1, ..AdaptiveConfig::default() };
    let noisy = Synth::new(0.01, 1e6);
    let d = Planner::new(lib.clone(), once).evaluate(0, from, &noisy, 1.0);
    assert!(d.candidate.is_none() && d.reason.contains("≤ target"), "{d:?}");
    // An absolute target above today's error stops too.
    let view = Synth::new(0.01, 0.02);
    let cfg = AdaptiveConfig { target_error_pct: Some(1e6), ..once };
    let d = Planner::new(lib.clone(), cfg).evaluate(0, from, &view, 1.0);
    assert!(d.candidate.is_none() && d.reason.contains("≤ target"), "{d:?}");
    // A budget of 5 % of the slot's full cost admits a sweep or two, then stops.
    let cfg = AdaptiveConfig { budget_fraction: 0.05, ..AdaptiveConfig::default() };
    let mut p = Planner::new(lib.clone(), cfg);
    let mut from = from;
    let mut n = 0;
    loop {
        let d = p.decide(0, from, &view, 1.0);
        match d.candidate {
            Some(id) => {
                n += 1;
                from = lib.candidates[id].end();
            }
            None => {
                assert!(d.reason.contains("budget"), "{d:?}");
                break;
            }
        }
    }
    assert!(n >= 1 && n < lib.slots[0].candidates.len());
    assert!(p.state().spent_s[0] <= 0.05 * lib.slots[0].full_cost_s + 1e-9);
}

#[test]
fn a_restored_planner_continues_with_the_same_decisions() {
    let cfg = AdaptiveConfig::default();
    let lib = gs2mf_library(&cfg);
    let view = Synth::new(0.01, 0.02);
    let mut a = Planner::new(lib.clone(), cfg);
    let mut from = start(&lib, 0);
    for _ in 0..3 {
        let id = a.decide(0, from, &view, 1.0).candidate.unwrap();
        from = lib.candidates[id].end();
    }
    let json = serde_json::to_string(a.state()).unwrap();
    let mut b = Planner::restore(lib.clone(), cfg, serde_json::from_str(&json).unwrap()).unwrap();
    for _ in 0..4 {
        let da = a.decide(0, from, &view, 1.0);
        let db = b.decide(0, from, &view, 1.0);
        assert_eq!(da, db);
        match da.candidate {
            Some(id) => from = lib.candidates[id].end(),
            None => break,
        }
    }
    // A state from another library is refused.
    let mut bad = a.state().clone();
    bad.used.push(10_000);
    assert!(Planner::restore(lib, cfg, bad).is_err());
}

#[test]
fn a_target_without_a_model_is_bootstrapped_by_the_cheapest_sweep_that_measures_it() {
    let cfg = AdaptiveConfig::default();
    let lib = gs2mf_library(&cfg);
    let mut view = Synth::new(0.01, 0.02);
    view.models.retain(|(t, _)| *t != Target::FxCombined && *t != Target::FyCombined);
    let from = start(&lib, 1);
    let mut p = Planner::new(lib.clone(), cfg);
    let d = p.decide(1, from, &view, 1.0);
    let c = &lib.candidates[d.candidate.unwrap()];
    assert_eq!(c.kind, CandidateKind::Combined);
    assert!(!c.severe);
    assert!(d.reason.contains("FX combined"), "{}", d.reason);
    // Its predicted figures are unknown (NaN): the state still round-trips through JSON.
    assert!(d.value.is_nan());
    let json = serde_json::to_string(p.state()).unwrap();
    let back: adaptive::PlannerState = serde_json::from_str(&json).unwrap();
    assert_eq!(back.used, p.state().used);
    assert!(back.decisions[0].value.is_nan() && back.decisions[0].name == d.name);
}

#[test]
fn a_full_run_prediction_lost_to_round_off_never_closes_a_slot() {
    // A model that knows almost nothing yet (variance 1e30 on every coefficient): the update
    // in covariance form, Σ − ΣJᵀ(σ²I + JΣJᵀ)⁻¹JΣ, cancels 1e30-sized terms, and the predicted
    // error of "every remaining sweep run" came out as large as today's (on a brush-tyre run,
    // larger), which was read as the target already met: FreeRolling closed after 3 of its
    // candidates. The information form keeps it exact; the planner also refuses a full-run
    // prediction above today's.
    let lib = gs2mf_library(&AdaptiveConfig::default());
    let from = start(&lib, 0);
    let view = Synth::new(1e30, 0.02);
    let d = Planner::new(lib.clone(), AdaptiveConfig::default()).evaluate(0, from, &view, 1.0);
    assert!(d.candidate.is_some() && d.full_error_pct < 1e-6 * d.error_pct, "{d:?}");
}

#[test]
fn one_low_reading_does_not_close_a_slot_two_in_a_row_do() {
    // The live model's predicted error jumps between updates; by default the target must be met
    // at two decisions in a row, with a sweep between them.
    // A generous target (10⁶ × the full run's prediction) is met on a model that knows a little,
    // while sweeps still teach it something; on one that knows nothing (variance 10³⁰) it is not.
    let cfg = AdaptiveConfig { target_ratio: 1e6, ..AdaptiveConfig::default() };
    let lib = gs2mf_library(&cfg);
    let met = Synth::new(0.01, 0.02);
    let unsure = Synth::new(1e30, 0.02);
    let mut p = Planner::new(lib.clone(), cfg);
    let mut from = start(&lib, 0);
    let mut step = |p: &mut Planner, view: &Synth| {
        let d = p.decide(0, from, view, 1.0);
        if let Some(id) = d.candidate {
            from = lib.candidates[id].end();
        }
        d
    };
    let d = step(&mut p, &met);
    assert!(d.candidate.is_some() && d.reason.contains("target met 1 of 2"), "{d:?}");
    // A reading above the target starts the count again.
    let d = step(&mut p, &unsure);
    assert!(d.candidate.is_some() && !d.reason.contains("target met"), "{d:?}");
    let d = step(&mut p, &met);
    assert!(d.candidate.is_some() && d.reason.contains("target met 1 of 2"), "{d:?}");
    // The count survives a checkpoint.
    let json = serde_json::to_string(p.state()).unwrap();
    let mut p = Planner::restore(lib.clone(), cfg, serde_json::from_str(&json).unwrap()).unwrap();
    let d = step(&mut p, &met);
    assert!(d.candidate.is_none() && d.reason.contains("2 decisions in a row"), "{d:?}");
    // A checkpoint written before the count existed still reads (no slot has met it yet).
    let mut old: serde_json::Value = serde_json::to_value(p.state()).unwrap();
    old.as_object_mut().unwrap().remove("target_met");
    let state: adaptive::PlannerState = serde_json::from_value(old).unwrap();
    assert!(state.target_met.is_empty());
}

#[test]
fn a_slot_closes_only_once_its_data_reach_where_its_sweeps_reach() {
    // A target met at once (an absolute target far above any error): with the variance rule
    // alone the lateral slot closes at the first decision. With `cover_envelope` it first runs
    // the sweeps that take the data where none has been (the first of its kind, then those
    // reaching further in load, slip angle and camber), then closes, every extreme covered.
    let base = AdaptiveConfig {
        target_error_pct: Some(1e6),
        target_confirmations: 1,
        cover_envelope: true,
        ..AdaptiveConfig::default()
    };
    let lib = gs2mf_library(&base);
    let view = Synth::new(0.01, 0.02);
    let from = start(&lib, 0);
    let off = AdaptiveConfig { cover_envelope: false, ..base };
    assert!(Planner::new(lib.clone(), off).evaluate(0, from, &view, 1.0).candidate.is_none());

    let mut p = Planner::new(lib.clone(), base);
    let mut from = from;
    let mut run = Vec::new();
    loop {
        let d = p.decide(0, from, &view, 1.0);
        let Some(id) = d.candidate else {
            assert!(d.reason.contains("≤ target"), "{d:?}");
            break;
        };
        assert!(d.reason.contains("must reach where the slot's sweeps reach"), "{d:?}");
        run.push(id);
        from = lib.candidates[id].end();
        assert!(run.len() <= 10, "the envelope rule ran {} sweeps", run.len());
    }
    let slot: Vec<&adaptive::Candidate> = lib.slots[0].candidates.iter().map(|&id| &lib.candidates[id]).collect();
    let reach =
        |cs: &[&adaptive::Candidate]| cs.iter().map(|c| c.extent).reduce(adaptive::extent::Extent::union).unwrap();
    let all = reach(&slot);
    let ran: Vec<&adaptive::Candidate> = run.iter().map(|&id| &lib.candidates[id]).collect();
    let got = reach(&ran);
    assert!(all.beyond(&got).is_empty(), "{:?}", all.beyond(&got));
    assert!(got.fz_max_n > 1.7 * 6759.0, "highest load run {:.0} N", got.fz_max_n);
    assert!(ran.len() < slot.len(), "{} of {}", ran.len(), slot.len());
    // The same decisions after a checkpoint.
    let mut q = Planner::new(lib.clone(), base);
    let mut from = start(&lib, 0);
    let first = q.decide(0, from, &view, 1.0).candidate.unwrap();
    from = lib.candidates[first].end();
    let json = serde_json::to_string(q.state()).unwrap();
    let mut q = Planner::restore(lib.clone(), base, serde_json::from_str(&json).unwrap()).unwrap();
    assert_eq!(q.decide(0, from, &view, 1.0).candidate, Some(run[1]));
}

/// `Synth` whose tyre slides with a power that grows with the square of the slip angle (so wide
/// sweeps wear far more than narrow ones).
struct Wearing {
    synth: Synth,
    watts_per_deg2: f64,
}

impl ModelView for Wearing {
    fn target(&self, t: Target) -> Option<&TargetModel> {
        self.synth.target(t)
    }
    fn sensitivities(&self, t: Target, points: &[Setpoint]) -> DMatrix<f64> {
        self.synth.sensitivities(t, points)
    }
    fn sliding_power_w(&self, sp: &Setpoint) -> Option<f64> {
        Some(self.watts_per_deg2 * sp.slip_angle_deg * sp.slip_angle_deg)
    }
}

#[test]
fn wear_counts_in_the_cost_and_steers_the_choice_to_sweeps_that_slide_less() {
    let cfg = AdaptiveConfig::default();
    let lib = gs2mf_library(&cfg);
    let from = start(&lib, 0);
    let no_model_of_wear = Planner::new(lib.clone(), cfg).evaluate(0, from, &Synth::new(0.01, 0.02), 1.0);
    assert_eq!(no_model_of_wear.wear_mm, 0.0);
    let plain = no_model_of_wear.candidate.unwrap();

    // A tyre that slides hard at high slip angles: the choice moves to a sweep that wears less
    // per unit of what it teaches, and says what its tread costs.
    let view = Wearing { synth: Synth::new(0.01, 0.02), watts_per_deg2: 2_000.0 };
    let d = Planner::new(lib.clone(), cfg).evaluate(0, from, &view, 1.0);
    let chosen = d.candidate.unwrap();
    assert_ne!(chosen, plain, "{}", d.reason);
    let energy = |id: usize| lib.candidates[id].sliding_energy_j(&view).unwrap();
    assert!(energy(chosen) < energy(plain), "{} J against {} J", energy(chosen), energy(plain));
    let expected_mm = cfg.wear_mm_per_mj * energy(chosen) * 1e-6;
    assert!((d.wear_mm - expected_mm).abs() <= 1e-12 * expected_mm.max(1.0), "{} against {expected_mm}", d.wear_mm);
    assert!(d.reason.contains("of tread"), "{}", d.reason);
    // The rig-time cost (what the slot's budget counts) is the same as without wear.
    assert_eq!(d.cost_s, lib.candidates[chosen].cost_s(from, &lib.limits, 1.0));

    // A rate of zero leaves wear out: the same choice as a model without sliding power.
    let off = AdaptiveConfig { wear_mm_per_mj: 0.0, ..cfg };
    let d = Planner::new(lib.clone(), off).evaluate(0, from, &view, 1.0);
    assert_eq!((d.candidate, d.wear_mm), (Some(plain), 0.0));
}

#[test]
fn a_measured_wear_rate_is_weighed_against_the_configured_one_in_log_space() {
    let cfg = AdaptiveConfig::default();
    let lib = gs2mf_library(&cfg);
    let from = start(&lib, 0);
    let mut p = Planner::new(lib.clone(), cfg);
    assert_eq!(p.wear_rate_mm_per_mj(), cfg.wear_mm_per_mj, "nothing measured: the configured rate");

    // A tyre wearing four times the configured rate, measured to ±5 %: its rate all but replaces
    // the configured one (log-space weights 1/1² against 1/0.05²: 1 to 400).
    let fast = 4.0 * cfg.wear_mm_per_mj;
    assert!(p.on_measured_wear_rate(MeasuredWearRate { mm_per_mj: fast, sd_mm_per_mj: 0.05 * fast }));
    let expected = (cfg.wear_mm_per_mj.ln() / 401.0 + fast.ln() * 400.0 / 401.0).exp();
    assert!((p.wear_rate_mm_per_mj() - expected).abs() < 1e-12, "{}", p.wear_rate_mm_per_mj());
    assert!((p.wear_rate_mm_per_mj() / fast - 1.0).abs() < 0.005);
    // The choice prices the tread at that rate and says it was measured.
    let view = Wearing { synth: Synth::new(0.01, 0.02), watts_per_deg2: 2_000.0 };
    let d = p.evaluate(0, from, &view, 1.0);
    let id = d.candidate.unwrap();
    let mm = p.wear_rate_mm_per_mj() * lib.candidates[id].sliding_energy_j(&view).unwrap() * 1e-6;
    assert!((d.wear_mm - mm).abs() <= 1e-12 * mm, "{} against {mm}", d.wear_mm);
    assert_eq!(d.wear_rate_mm_per_mj, p.wear_rate_mm_per_mj());
    assert!(d.reason.contains("mm/MJ, measured"), "{}", d.reason);

    // As uncertain as the configured rate (±100 %, a log spread of 1): halfway in log space.
    assert!(p.on_measured_wear_rate(MeasuredWearRate { mm_per_mj: fast, sd_mm_per_mj: fast }));
    let geometric_mean = (cfg.wear_mm_per_mj * fast).sqrt();
    assert!((p.wear_rate_mm_per_mj() - geometric_mean).abs() < 1e-12);

    // What says nothing usable is ignored and the last measurement stays: a rate ≤ 0 (the radius
    // has not resolved any wear yet), no spread, not a number.
    for bad in [(-0.01, 0.02), (0.0, 0.02), (0.3, 0.0), (f64::NAN, 0.1), (0.3, f64::INFINITY)] {
        assert!(!p.on_measured_wear_rate(MeasuredWearRate { mm_per_mj: bad.0, sd_mm_per_mj: bad.1 }), "{bad:?}");
        assert!((p.wear_rate_mm_per_mj() - geometric_mean).abs() < 1e-12);
    }

    // It survives a checkpoint (the planner's state), so a resumed run prices wear the same.
    let resumed = Planner::restore(lib.clone(), cfg, p.state().clone()).unwrap();
    assert_eq!(resumed.wear_rate_mm_per_mj(), p.wear_rate_mm_per_mj());
    let json = serde_json::to_string(p.state()).unwrap();
    let back: adaptive::PlannerState = serde_json::from_str(&json).unwrap();
    assert_eq!(back.measured_wear, p.state().measured_wear);

    // `wear_rate_log_sd = 0` keeps the configured rate; `wear_mm_per_mj = 0` leaves wear out.
    for (cfg, rate) in [
        (AdaptiveConfig { wear_rate_log_sd: 0.0, ..cfg }, cfg.wear_mm_per_mj),
        (AdaptiveConfig { wear_mm_per_mj: 0.0, ..cfg }, 0.0),
    ] {
        let q = Planner::restore(lib.clone(), cfg, p.state().clone()).unwrap();
        assert_eq!(q.wear_rate_mm_per_mj(), rate);
    }
    // … and a choice priced at the configured rate does not claim a measured one.
    let configured_only = AdaptiveConfig { wear_rate_log_sd: 0.0, ..cfg };
    let q = Planner::restore(lib.clone(), configured_only, p.state().clone()).unwrap();
    let d = q.evaluate(0, from, &view, 1.0);
    assert!(d.reason.contains("mm/MJ)") && !d.reason.contains("measured"), "{}", d.reason);
}

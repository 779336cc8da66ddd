//! The shipped procedure files load, expand and match the thesis's structure.

use procedure::{PauseModel, Plan, RunInputs, StepKind, SweepStyle, expand, load};
use std::path::PathBuf;

fn dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../launch-config/procedures")
}

fn plan_with(name: &str, inputs: RunInputs) -> Plan {
    let doc = load(&dir().join(name)).unwrap_or_else(|e| panic!("{e}"));
    expand(&doc, &inputs).unwrap_or_else(|e| panic!("{e}"))
}

fn plan(name: &str, sweeps: SweepStyle) -> Plan {
    plan_with(name, RunInputs { sweeps, ..RunInputs::default() })
}

fn section_names(p: &Plan) -> Vec<String> {
    let mut v: Vec<String> = Vec::new();
    for s in &p.steps {
        let n = &p.sections[s.section_index].name;
        if v.last() != Some(n) {
            v.push(n.clone());
        }
    }
    v
}

fn count(p: &Plan, section_prefix: &str, kind: StepKind) -> usize {
    p.steps.iter().filter(|s| s.kind == kind && p.sections[s.section_index].name.starts_with(section_prefix)).count()
}

#[test]
fn freerolling_sections_and_content() {
    let p = plan("gs2mf_freerolling.toml", SweepStyle::Variable);
    assert_eq!(
        section_names(&p),
        [
            "warmup",
            "step_steer",
            "heating_sweep",
            "graph_sweep_1",
            "on_centre_rolling_radius_2.1bar",
            "on_centre_rolling_radius_2.6bar",
            "on_centre_rolling_radius_3.3bar",
            "force_moment_2.1bar",
            "force_moment_2.6bar",
            "force_moment_3.3bar",
            "graph_sweep_2"
        ]
    );
    assert_eq!(count(&p, "warmup", StepKind::WarmUp), 10);
    assert_eq!(count(&p, "step_steer", StepKind::Hold), 8, "4 loads × ± pairs");
    assert_eq!(count(&p, "graph_sweep_1", StepKind::Sweep), 5);
    assert_eq!(count(&p, "graph_sweep_2", StepKind::Sweep), 5);
    // On-centre: +1/0/−1 × 3 pressures; rolling radius: 3 speeds × 3 pressures.
    let oc = p.steps.iter().filter(|s| s.name.contains("OnCentre")).count();
    let rr = p.steps.iter().filter(|s| s.name.contains("RollingRadius")).count();
    assert_eq!((oc, rr), (9, 9));
    assert_eq!(count(&p, "force_moment", StepKind::Sweep), 36);
    // Loads within FreeRolling's 0.2–2.0 Fz0 range (asymmetric low case reaches 0.2).
    let fz0 = p.fz0_n;
    for s in &p.steps {
        for sp in s.trajectory.check_points() {
            if sp.mode != procedure::RigMode::Safe && s.kind != StepKind::Settle {
                assert!(sp.fz_n <= 2.0 * fz0 + 1e-6, "{} {}", s.name, sp.fz_n);
            }
        }
    }
    // Graph sweep 2 repeats graph sweep 1: same sweeps, repeat number 2.
    let g2: Vec<&str> = p
        .steps
        .iter()
        .filter(|s| p.sections[s.section_index].name == "graph_sweep_2" && s.kind == StepKind::Sweep)
        .map(|s| s.name.as_str())
        .collect();
    assert!(g2.iter().all(|n| n.ends_with("_2")), "{g2:?}");
}

#[test]
fn brkdrv_sections_and_content() {
    let p = plan("gs2mf_brkdrv.toml", SweepStyle::Variable);
    let names = section_names(&p);
    for s in [
        "warmup",
        "graph_sweep_1",
        "pure_long_a_3.3bar",
        "pure_long_b",
        "combined_a",
        "combined_b",
        "combined_d",
        "inflation_pressure_a_3.3bar",
        "extreme_a",
        "graph_sweep_2",
    ] {
        assert!(names.iter().any(|n| n == s), "{s} missing from {names:?}");
    }
    assert_eq!(count(&p, "pure_long_a", StepKind::Sweep), 12);
    assert_eq!(count(&p, "pure_long_b", StepKind::Sweep), 8);
    assert_eq!(count(&p, "combined_a", StepKind::Sweep), 4);
    assert_eq!(count(&p, "combined_d", StepKind::Sweep), 6);
    assert_eq!(count(&p, "inflation_pressure_a", StepKind::Sweep), 18);
    assert_eq!(count(&p, "extreme_a", StepKind::Sweep), 4);
    // Every longitudinal sweep is preceded by its free-rolling reference at the same load case.
    for (i, s) in p.steps.iter().enumerate() {
        if s.kind == StepKind::Sweep && s.trajectory.start().mode == procedure::RigMode::Coupled {
            let r = &p.steps[i - 1];
            assert_eq!(r.kind, StepKind::FreeRollingRef, "before {}", s.name);
            let (a, b) = (r.trajectory.start(), s.trajectory.start());
            assert_eq!((a.fz_n, a.slip_angle_deg, a.camber_deg), (b.fz_n, b.slip_angle_deg, b.camber_deg));
            assert!(s.name.starts_with("BrkDrv_sw"));
        }
    }
}

#[test]
fn staticlong_72_tests() {
    let p = plan("gs2mf_staticlong.toml", SweepStyle::Variable);
    let drags = p.steps.iter().filter(|s| s.name.contains("StaticDrag")).count();
    assert_eq!(drags, 72);
    assert!(p.steps.iter().all(|s| !s.thermal_pause_after));
    let t = p.planned_duration_s();
    assert!((600.0..=900.0).contains(&t), "{t} s vs the thesis's ~840 s");
}

#[test]
fn suite_and_square_matrix_tyre_changes_and_ratio() {
    let g = plan("gs2mf.toml", SweepStyle::Variable);
    let sm = plan("square_matrix.toml", SweepStyle::Variable);
    assert_eq!(g.summary().tyre_changes, 2);
    assert_eq!(sm.summary().tyre_changes, 10);
    assert_eq!(g.steps[0].kind, StepKind::TyreChange);
    assert_eq!(g.steps[0].duration_s, 900.0);
    // Square Matrix: 72 free-rolling + 144 longitudinal sweeps.
    let has = sm.steps.iter().filter(|s| s.name.contains("_HAS_")).count();
    let lat = sm.steps.iter().filter(|s| s.name.contains("_LAT_")).count();
    let long = sm
        .steps
        .iter()
        .filter(|s| s.kind == StepKind::Sweep && s.trajectory.start().mode == procedure::RigMode::Coupled)
        .count();
    assert_eq!((has, lat, long), (36, 36, 144));
    let m = PauseModel::default();
    let (tg, tsm) = (g.estimate_total_s(&m), sm.estimate_total_s(&m));
    println!(
        "GS2MF planned {:.0} s (est. with pauses {tg:.0} s); Square Matrix planned {:.0} s (est. {tsm:.0} s)",
        g.planned_duration_s(),
        sm.planned_duration_s()
    );
    assert!(tg <= 0.27 * tsm, "estimated ratio {}", tg / tsm);
}

#[test]
fn continuous_sweeps_are_shorter_and_graph_sweeps_unchanged() {
    let v = plan("gs2mf.toml", SweepStyle::Variable);
    let c = plan("gs2mf.toml", SweepStyle::Continuous);
    assert!(c.planned_duration_s() < v.planned_duration_s());
    let m = PauseModel::default();
    assert!(c.estimate_total_s(&m) < v.estimate_total_s(&m));
    assert_eq!(v.steps.len(), c.steps.len());
    for (a, b) in v.steps.iter().zip(&c.steps) {
        if a.name.contains("GraphSweep") {
            assert_eq!(a.name, b.name);
            assert_eq!(a.trajectory, b.trajectory);
        } else if a.name.contains("VariableRate") {
            assert!(b.name.contains("ContinuousRate"), "{}", b.name);
            assert!(b.duration_s < a.duration_s);
        }
    }
}

#[test]
fn load_index_drives_loads() {
    let a = plan_with("gs2mf_freerolling.toml", RunInputs::default());
    let b = plan_with("gs2mf_freerolling.toml", RunInputs { load_index: 91, ..RunInputs::default() });
    let ratio = b.fz0_n / a.fz0_n;
    assert!((ratio - 615.0 / 1060.0).abs() < 1e-12);
    let find = |p: &Plan| p.steps.iter().find(|s| s.name.contains("OnCentre")).unwrap().trajectory.start().fz_n;
    assert!((find(&b) / find(&a) - ratio).abs() < 1e-9);
    // Graph sweeps do not scale: identical for every tyre.
    let g = |p: &Plan| p.steps.iter().find(|s| s.name.contains("GraphSweep")).unwrap().trajectory.start().fz_n;
    assert_eq!(g(&a), g(&b));
}

#[test]
fn names_follow_the_thesis_convention() {
    let p = plan("gs2mf_freerolling.toml", SweepStyle::Variable);
    let heating = p
        .steps
        .iter()
        .find(|s| p.sections[s.section_index].name == "heating_sweep" && s.kind == StepKind::Sweep)
        .unwrap();
    assert!(heating.name.starts_with("FreeRoll_sw"));
    assert!(heating.name.contains("_VariableRate_LR2_HR30_TH4_"));
    assert!(heating.name.ends_with("_1"));
    let mut idx = 0;
    for s in &p.steps {
        if let Some(i) = s.sweep_index {
            assert_eq!(i, idx);
            idx += 1;
        }
    }
    assert_eq!(p.sweep_count(), idx);
}

#[test]
fn envelope_refuses_a_plan() {
    let doc = load(&dir().join("gs2mf_freerolling.toml")).unwrap();
    let mut inputs = RunInputs::default();
    inputs.limits.max_fz_n = 10_000.0;
    let e = expand(&doc, &inputs).unwrap_err();
    assert!(e.to_string().contains("fz_n"), "{e}");
    // A rig slower than the file's 30 °/s high rate.
    let mut inputs = RunInputs::default();
    inputs.limits.max_slip_angle_rate_dps = 20.0;
    let e = expand(&doc, &inputs).unwrap_err();
    assert!(e.to_string().contains("slip_angle_rate_dps"), "{e}");
    let e = expand(&doc, &RunInputs { load_index: 20, ..RunInputs::default() }).unwrap_err();
    assert!(e.to_string().contains("load index 20"), "{e}");
}

#[test]
fn fingerprint_tracks_tyre_and_pressures() {
    let a = plan_with("gs2mf_staticlong.toml", RunInputs::default());
    let b = plan_with("gs2mf_staticlong.toml", RunInputs::default());
    assert_eq!(a.fingerprint(), b.fingerprint());
    let c = plan_with("gs2mf_staticlong.toml", RunInputs { load_index: 111, ..RunInputs::default() });
    assert_ne!(a.fingerprint(), c.fingerprint());
    let d = plan_with("gs2mf_staticlong.toml", RunInputs { pressures_bar: [2.0, 2.6, 3.3], ..RunInputs::default() });
    assert_ne!(a.fingerprint(), d.fingerprint());
}

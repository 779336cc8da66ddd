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

/// Inputs of the brush race tyre: Fz0 given directly (no ETRTO index reaches 1.1 kN) and a race
/// tyre's pressures, inside an envelope that goes down to 0.5 bar.
fn race_inputs() -> RunInputs {
    let mut i = RunInputs { fz0_n: Some(1100.0), pressures_bar: [0.7, 0.84, 0.98], ..RunInputs::default() };
    i.limits.min_pressure_bar = 0.5;
    i
}

/// Every distinct (load, pressure, slip angle, camber) at the start of the plan's sweeps.
fn sweep_cells(p: &Plan) -> Vec<(f64, f64, f64, f64)> {
    p.steps
        .iter()
        .filter(|s| s.kind == StepKind::Sweep)
        .map(|s| {
            let a = s.trajectory.start();
            (a.fz_n, a.pressure_bar, a.slip_angle_deg, a.camber_deg)
        })
        .collect()
}

/// Largest |f| along a step's trajectory, sampled every millisecond.
fn peak_of(s: &procedure::PlanStep, f: impl Fn(&procedure::Setpoint) -> f64) -> f64 {
    let n = (s.duration_s * 1000.0).ceil() as usize;
    (0..=n).map(|k| f(&s.trajectory.at(s.duration_s * k as f64 / n as f64)).abs()).fold(0.0, f64::max)
}

#[test]
fn ttc_cornering_run_has_four_pressures_six_loads_standstills_and_no_pauses() {
    let p = plan_with("ttc_cornering_race.toml", race_inputs());
    assert!((p.fz0_n - 1100.0).abs() < 1e-9);
    assert!(p.steps.iter().all(|s| !s.thermal_pause_after), "no thermal pauses");
    let sweeps: Vec<_> = p.steps.iter().filter(|s| s.kind == StepKind::Sweep).collect();
    assert_eq!(sweeps.len(), 4 * 7, "per pressure a conditioning sweep and six load sweeps");
    let cells = sweep_cells(&p);
    let pressures: Vec<f64> = cells.iter().step_by(7).map(|c| c.1).collect();
    assert_eq!(pressures, [0.7, 0.84, 0.98, 1.12]);
    let loads: Vec<f64> = cells[1..7].iter().map(|c| c.0.round()).collect();
    assert_eq!(loads, [1100.0, 1540.0, 660.0, 220.0, 1100.0, 440.0]);
    for s in &sweeps {
        let peak = peak_of(s, |sp| sp.slip_angle_deg);
        let conditioning = s.name.contains("Conditioning");
        assert!((peak - if conditioning { 4.0 } else { 13.0 }).abs() < 0.01, "{}: {peak}", s.name);
        assert!((s.trajectory.start().speed_mps - 11.1).abs() < 1e-9);
    }
    // Standstill (belt stopped, load on) first and last; pressure changes in between.
    let still: Vec<_> = p.steps.iter().filter(|s| s.name == "Standstill").collect();
    assert_eq!(still.len(), 2);
    for s in &still {
        assert_eq!(s.kind, StepKind::Settle);
        let a = s.trajectory.start();
        assert!(a.speed_mps == 0.0 && (a.fz_n - 1100.0).abs() < 1e-9 && s.duration_s > 5.0);
    }
    assert_eq!(p.steps.iter().rposition(|s| s.name == "Standstill"), Some(p.steps.len() - 1));
    assert_eq!(p.steps.iter().filter(|s| s.kind == StepKind::PressureChange).count(), 3, "0.7 → 0.84 → 0.98 → 1.12");
    // The same file with the default (1.0 bar) envelope is refused, naming the pressure.
    let doc = load(&dir().join("ttc_cornering_race.toml")).unwrap();
    let e = expand(&doc, &RunInputs { fz0_n: Some(1100.0), ..RunInputs::default() }).unwrap_err().to_string();
    assert!(e.contains("pressure"), "{e}");
}

#[test]
fn ttc_drive_brake_run_covers_every_cell_at_one_pressure() {
    let p = plan_with("ttc_drive_brake_race.toml", race_inputs());
    assert!(p.steps.iter().all(|s| !s.thermal_pause_after));
    let cells = sweep_cells(&p);
    assert_eq!(cells.len(), 4 * 3 * 3 + 1, "four loads x three cambers x three slip angles, the first again");
    assert!(cells.iter().all(|c| (c.1 - 0.84).abs() < 1e-12));
    for load in [220.0, 660.0, 1100.0, 1540.0] {
        for sa in [0.0, 3.0, 6.0] {
            for ia in [0.0, 2.0, 4.0] {
                assert!(cells.iter().any(|c| (c.0 - load).abs() < 1e-6 && c.2 == sa && c.3 == ia), "{load} {sa} {ia}");
            }
        }
    }
    assert_eq!(cells.first(), cells.last(), "the first cell repeated at the end");
    for s in p.steps.iter().filter(|s| s.kind == StepKind::Sweep) {
        let peak = peak_of(s, |sp| sp.slip_ratio);
        assert!((peak - 0.2).abs() < 2e-4, "{}: {peak}", s.name);
        assert!((3.0..=9.0).contains(&s.duration_s), "{}: {} s", s.name, s.duration_s);
    }
    assert_eq!(p.steps.iter().filter(|s| s.name == "Standstill").count(), 2);
}

#[test]
fn the_warm_up_variant_opens_with_five_sweeps_at_a_cell_of_the_grid() {
    let plain = sweep_cells(&plan_with("ttc_drive_brake_race.toml", race_inputs()));
    let warm = sweep_cells(&plan_with("ttc_drive_brake_race_warmup.toml", race_inputs()));
    assert_eq!(warm.len(), plain.len() + 5);
    assert!(warm[..5].iter().all(|c| *c == (1100.0, 0.84, 0.0, 0.0)), "{:?}", &warm[..5]);
    assert!(plain.contains(&warm[0]), "the warm-up cell is swept again in the grid");
    assert_eq!(&warm[5..], &plain[..]);
}

#[test]
fn fz0_given_directly_replaces_the_load_index_and_scales_graph_sweeps() {
    let li = plan_with("gs2mf_freerolling.toml", RunInputs::default());
    let direct = plan_with("gs2mf_freerolling.toml", RunInputs { fz0_n: Some(1100.0), ..RunInputs::default() });
    assert!((direct.fz0_n - 1100.0).abs() < 1e-12);
    let graph_loads = |p: &Plan| -> Vec<f64> {
        p.steps.iter().filter(|s| s.name.contains("GraphSweep")).map(|s| s.trajectory.start().fz_n).collect()
    };
    let (a, b) = (graph_loads(&li), graph_loads(&direct));
    assert!(!a.is_empty() && a.len() == b.len());
    assert!((a[0] - 6000.0).abs() < 1e-9, "load-index runs keep the thesis's absolute loads");
    for (x, y) in a.iter().zip(&b) {
        assert!((y / x - 1100.0 / procedure::fz0_n(110).unwrap()).abs() < 1e-12, "{x} → {y}");
    }
    let e = expand(
        &load(&dir().join("gs2mf_freerolling.toml")).unwrap(),
        &RunInputs { fz0_n: Some(-5.0), ..RunInputs::default() },
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("fz0_n"), "{e}");
}

//! Acceptance: logs from the virtual rig with one effect the base model lacks switched on; the
//! doctor, run with the clean base model, must name that effect first and cut the held-out
//! residual RMS in the effect's region by at least half. A control log names nothing; a
//! thermal + wear log names both. Short procedures (tests/fixtures) keep CI fast.

mod common;

use doctor::{DataOptions, Dataset, Diagnosis, DoctorConfig, Effect, Extensions, diagnose, report};
use mftyre::TyreParams;

struct Case {
    procedure: &'static str,
    effects: &'static str,
    wear_multiplier: Option<f64>,
    zero_pressure_terms: bool,
}

fn run_case(name: &str, c: &Case) -> (Diagnosis, TyreParams, Dataset) {
    let t0 = std::time::Instant::now();
    let log = common::run_log(c.procedure, c.effects, c.wear_multiplier, 7);
    let ds =
        Dataset::from_logs(&[log], &DataOptions { point_rate_hz: 5.0, ..DataOptions::default() }).expect("dataset");
    let mut base = common::base_tir();
    if c.zero_pressure_terms {
        for k in mftyre::CoefGroup::Pressure.keys() {
            base.set(k, 0.0).expect("pressure key");
        }
    }
    let dx = diagnose(&ds, &base, &DoctorConfig::default()).expect("diagnose");
    let wall = t0.elapsed().as_secs_f64();
    // The report and the extended model are written and load again.
    let dir = tempfile::tempdir().expect("tempdir");
    let w = report::write_all(dir.path(), &ds, &base, &dx, "base.tir", wall).expect("report");
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&w.json).expect("json")).expect("parse");
    let named_json: Vec<String> = json["named_effects"]
        .as_array()
        .expect("named_effects")
        .iter()
        .map(|v| v.as_str().unwrap_or("").to_owned())
        .collect();
    assert_eq!(named_json, dx.state_effects().map(|n| n.effect.name().to_owned()).collect::<Vec<_>>());
    let form_json: Vec<&str> =
        json["form_errors"].as_array().expect("form_errors").iter().map(|v| v.as_str().unwrap_or("")).collect();
    assert_eq!(form_json, dx.form_errors().map(|n| n.effect.name()).collect::<Vec<_>>());
    let md = std::fs::read_to_string(&w.markdown).expect("md");
    assert!(md.contains("## Verdict"));
    if let Some(m) = &w.model {
        let p = TyreParams::read_tir(m).expect("extended model loads");
        let ext = Extensions::from_params(&p).expect("extension section");
        assert_eq!(ext.effects, dx.named.iter().map(|n| n.effect).collect::<Vec<_>>());
    } else {
        assert!(dx.named.is_empty());
    }
    for n in &dx.named {
        eprintln!(
            "| {name} | {} | {:.3} | {} | {} | {:.4} → {:.4} | {:.4} → {:.4} | {:.0} % | {wall:.1} s |",
            n.effect.name(),
            n.evidence,
            n.runner_up.map_or("–".to_owned(), |(e, v)| format!("{} {:.3}", e.name(), v)),
            n.channel,
            n.rms_before,
            n.rms_after,
            n.rms_before_heldout,
            n.rms_after_heldout,
            100.0 * (1.0 - n.rms_after_heldout / n.rms_before_heldout),
        );
    }
    if dx.named.is_empty() {
        let best = dx
            .rounds
            .first()
            .into_iter()
            .flatten()
            .filter(|c| c.testable)
            .max_by(|a, b| a.evidence.total_cmp(&b.evidence))
            .map_or("–".to_owned(), |c| format!("{} {:.3}", c.effect.name(), c.evidence));
        eprintln!("| {name} | none | – | {best} | – | – | – | – | {wall:.1} s | {} |", dx.stop_reason);
    }
    (dx, base, ds)
}

fn assert_first(dx: &Diagnosis, want: Effect) {
    let names: Vec<&str> = dx.named.iter().map(|n| n.effect.name()).collect();
    assert!(
        !dx.named.is_empty() && dx.named[0].effect == want,
        "expected {} first, named {names:?}: {}",
        want.name(),
        dx.stop_reason
    );
    let n = &dx.named[0];
    assert!(
        n.rms_after_heldout <= 0.5 * n.rms_before_heldout,
        "{}: held-out RMS in the region {} → {} (less than 50 % reduction)",
        want.name(),
        n.rms_before_heldout,
        n.rms_after_heldout
    );
}

#[test]
fn thermal_grip_is_named() {
    let (dx, _, _) = run_case(
        "thermal",
        &Case {
            procedure: "doctor_lateral.toml",
            effects: "noise,thermal,thermal_grip",
            wear_multiplier: None,
            zero_pressure_terms: false,
        },
    );
    assert_first(&dx, Effect::Thermal);
}

#[test]
fn wear_is_named() {
    let (dx, _, _) = run_case(
        "wear",
        &Case {
            procedure: "doctor_lateral.toml",
            effects: "noise,thermal,wear",
            wear_multiplier: Some(15.0),
            zero_pressure_terms: false,
        },
    );
    assert_first(&dx, Effect::Wear);
}

#[test]
fn break_in_is_named() {
    let (dx, _, _) = run_case(
        "break_in",
        &Case {
            procedure: "doctor_lateral.toml",
            effects: "noise,thermal,break_in",
            wear_multiplier: None,
            zero_pressure_terms: false,
        },
    );
    assert_first(&dx, Effect::BreakIn);
}

#[test]
fn transient_relaxation_is_named() {
    let (dx, _, _) = run_case(
        "transient",
        &Case {
            procedure: "doctor_fast.toml",
            effects: "noise,thermal,transient",
            wear_multiplier: None,
            zero_pressure_terms: false,
        },
    );
    assert_first(&dx, Effect::Transient);
}

#[test]
fn pressure_is_reported_as_form_error_for_a_model_without_pressure_terms() {
    let (dx, _, _) = run_case(
        "pressure",
        &Case {
            procedure: "doctor_pressure.toml",
            effects: "noise,thermal",
            wear_multiplier: None,
            zero_pressure_terms: true,
        },
    );
    assert_first(&dx, Effect::Pressure);
    // An operating-point misfit: the model's form error, not a missing effect of the tyre.
    assert_eq!(dx.named[0].family, doctor::Family::FormError);
    assert!(dx.state_effects().next().is_none(), "a state effect named for a pressure misfit");
}

#[test]
fn control_names_nothing() {
    let (dx, _, _) = run_case(
        "control",
        &Case {
            procedure: "doctor_lateral.toml",
            effects: "noise,thermal",
            wear_multiplier: None,
            zero_pressure_terms: false,
        },
    );
    assert!(
        dx.named.is_empty(),
        "named {:?} on data without a hidden effect",
        dx.named.iter().map(|n| n.effect.name()).collect::<Vec<_>>()
    );
}

#[test]
fn thermal_and_wear_are_both_named() {
    let (dx, _, _) = run_case(
        "thermal+wear",
        &Case {
            procedure: "doctor_lateral.toml",
            effects: "noise,thermal,thermal_grip,wear",
            wear_multiplier: Some(15.0),
            zero_pressure_terms: false,
        },
    );
    let mut first_two: Vec<Effect> = dx.named.iter().take(2).map(|n| n.effect).collect();
    first_two.sort();
    assert_eq!(first_two, vec![Effect::Thermal, Effect::Wear], "stop: {}", dx.stop_reason);
    assert_eq!(
        dx.named.len(),
        2,
        "a third effect named: {:?}",
        dx.named.iter().map(|n| n.effect.name()).collect::<Vec<_>>()
    );
}

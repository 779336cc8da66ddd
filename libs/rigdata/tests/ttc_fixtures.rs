//! The shipped TTC-style runs of the virtual brush tyres (`tests/fixtures/ttc`, made by the
//! virtual rig and `tyrerig export ttc`): every sweep of the plan found, in order, with its kind,
//! conditioning flag and cell — the plans are `launch-config/procedures/ttc_*_{race,road}.toml`.

use mffit::{DataKind, SweepKind};
use rigdata::import::{ReadOptions, read_file};
use std::path::PathBuf;

/// (kind, conditioning, load / nominal load, pressure [kPa] or NaN for "the run's one",
/// camber [deg], slip angle [deg]) of each planned sweep.
type Planned = (SweepKind, bool, f64, f64, f64, f64);

fn fixture(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../tests/fixtures/ttc").join(name)
}

/// `ttc_cornering_*.toml`: per pressure a conditioning sweep at the nominal load, then six
/// loads. The run begins on a tyre at ambient temperature, and one short conditioning sweep
/// does not bring it to temperature: the first full sweep starts with the tread still warming
/// fast (the race tyre 37.5 °C, then 43.2 and 49.4 °C at the next sweeps' starts, settling
/// about 50 °C; its repeat at the nominal load starts at 49.3 °C), so it is conditioning too
/// (a cold start: its cell is swept again once the tread has settled).
fn cornering_plan(pressures_kpa: [f64; 4]) -> Vec<Planned> {
    let mut plan = Vec::new();
    for (k, p) in pressures_kpa.into_iter().enumerate() {
        plan.push((SweepKind::Cornering, true, 1.0, p, 0.0, 0.0));
        for (j, l) in [1.0, 1.4, 0.6, 0.2, 1.0, 0.4].into_iter().enumerate() {
            plan.push((SweepKind::Cornering, k == 0 && j == 0, l, p, 0.0, 0.0));
        }
    }
    plan
}

/// `ttc_drive_brake_*.toml`: slip angle outermost, then camber, then four loads; one repeat of
/// the first cell at the end.
fn drive_brake_plan() -> Vec<Planned> {
    let mut plan = Vec::new();
    for sa in [0.0, 3.0, 6.0] {
        for ia in [0.0, 2.0, 4.0] {
            for l in [0.2, 0.6, 1.0, 1.4] {
                let kind = if sa == 0.0 { SweepKind::DriveBrake } else { SweepKind::Combined };
                plan.push((kind, false, l, f64::NAN, ia, sa));
            }
        }
    }
    plan.push((SweepKind::DriveBrake, false, 0.2, f64::NAN, 0.0, 0.0));
    plan
}

fn check(file: &str, fz0_n: f64, plan: &[Planned]) {
    let (d, r) = read_file(&fixture(file), &ReadOptions::default()).unwrap_or_else(|e| panic!("{file}: {e}"));
    let names: Vec<&str> = d.segments.iter().map(|s| s.sweep.as_str()).collect();
    assert_eq!(d.segments.len(), plan.len(), "{file}: sweeps found vs planned: {names:?}");
    for (s, p) in d.segments.iter().zip(plan) {
        let c = s.cell.unwrap_or_else(|| panic!("{file}: {} has no cell", s.sweep));
        let what = format!("{file}: {}", s.sweep);
        assert_eq!(c.kind, p.0, "{what}");
        assert_eq!(s.kind == DataKind::WarmUp, p.1, "{what}: conditioning");
        assert!((c.fz_n / fz0_n - p.2).abs() < 0.03, "{what}: load {} vs {}·{fz0_n}", c.fz_n, p.2);
        if p.3.is_finite() {
            // A pressure is regulated towards its set point: within 1.5 % (or 2 kPa).
            assert!((c.p_pa / 1e3 - p.3).abs() < (0.015 * p.3).max(2.0), "{what}: pressure {} kPa", c.p_pa / 1e3);
        }
        assert!((c.gamma_rad.to_degrees() - p.4).abs() < 0.1, "{what}: camber");
        assert!((c.alpha_rad.to_degrees() - p.5).abs() < 0.2, "{what}: slip angle");
    }
    // Standstill, ramps and rolling between sweeps are excluded and counted; every row is
    // either in a sweep or excluded.
    let total = r.rows_in_sweeps + r.rows_in_conditioning + r.excluded.iter().map(|e| e.1).sum::<usize>();
    assert_eq!(total, r.rows, "{file}");
    assert!(r.excluded.iter().any(|e| e.0.starts_with("standstill") && e.1 > 0), "{file}: {:?}", r.excluded);
}

#[test]
fn race_cornering_every_sweep_found() {
    // The first conditioning sweep starts while the rig is still coming up to speed and runs
    // straight into the first measuring sweep.
    check("race_cornering.dat", 1100.0, &cornering_plan([70.0, 84.0, 98.0, 112.0]));
}

#[test]
fn road_cornering_every_sweep_found() {
    check("road_cornering.dat", 5579.0, &cornering_plan([210.0, 250.0, 290.0, 330.0]));
}

#[test]
fn drive_brake_runs_every_sweep_found() {
    for f in ["race_drive_brake.dat", "race_drive_brake_no_thermal_grip.dat", "race_drive_brake_tyre2.dat"] {
        check(f, 1100.0, &drive_brake_plan());
    }
    for f in ["road_drive_brake.dat", "road_drive_brake_tyre2.dat"] {
        check(f, 5579.0, &drive_brake_plan());
    }
}

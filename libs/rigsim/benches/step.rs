//! Simulation speed of the core: internal steps per second with every effect on, during a
//! steady-state sweep-like operating point (slip changing, samples published at 100 Hz).

use std::hint::black_box;
use std::path::Path;

use criterion::{Criterion, criterion_group, criterion_main};
use rigsim::{RigSetpoint, VirtualRig};

/// The rig of `config` (under launch-config/) in a coupled, combined-slip operating point.
fn rig_of(config: &str, fz_n: f64, pressure_pa: f64) -> VirtualRig {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../launch-config").join(config);
    let mut rig = VirtualRig::from_config_file(&path).expect("config");
    rig.apply_setpoint(&RigSetpoint {
        mode: RigSetpoint::MODE_COUPLED,
        slip_angle_deg: 3.0,
        slip_ratio: 0.05,
        fz_n,
        pressure_pa,
        speed_mps: 16.6,
        ..RigSetpoint::default()
    })
    .expect("setpoint");
    rig.run_until(6.0, &mut |_| {});
    rig
}

fn rig() -> VirtualRig {
    rig_of("virtual_rig.toml", 6000.0, 260_000.0)
}

fn bench(c: &mut Criterion) {
    let mut r = rig();
    c.bench_function("step_1khz_all_effects", |b| b.iter(|| black_box(r.step())));
    let mut r = rig();
    c.bench_function("one_simulated_second", |b| {
        b.iter(|| {
            let t = r.time_s() + 1.0;
            let mut n = 0u32;
            r.run_until(t, &mut |s| n += s.seq as u32 & 1);
            black_box(n)
        })
    });
    // The brush tyre instead of the MF one, same effects and rates.
    for (name, config, fz, p) in [
        ("brush_road", "virtual_rig_brush_road.toml", 5500.0, 250_000.0),
        ("brush_race", "virtual_rig_brush_race.toml", 1100.0, 84_000.0),
    ] {
        let mut r = rig_of(config, fz, p);
        c.bench_function(&format!("step_1khz_all_effects_{name}"), |b| b.iter(|| black_box(r.step())));
        let mut r = rig_of(config, fz, p);
        c.bench_function(&format!("one_simulated_second_{name}"), |b| {
            b.iter(|| {
                let t = r.time_s() + 1.0;
                let mut n = 0u32;
                r.run_until(t, &mut |s| n += s.seq as u32 & 1);
                black_box(n)
            })
        });
    }
    // One tyre-model evaluation each, combined slip past the peak (the secant solve's worst case).
    let road = rigsim::BrushParams::load(
        &Path::new(env!("CARGO_MANIFEST_DIR")).join("../../launch-config/tyres/brush_road.toml"),
    )
    .expect("brush_road.toml");
    let input = rigsim::BrushInput::new(5500.0, 0.08, 6f64.to_radians(), 16.6);
    c.bench_function("brush_evaluate_combined", |b| b.iter(|| black_box(road.evaluate(black_box(&input)))));
    let mf = rigsim::TyreParams::read_tir(
        &Path::new(env!("CARGO_MANIFEST_DIR")).join("../../launch-config/tyres/MagicFormula61_Paramerters.tir"),
    )
    .expect("tir");
    let mfi = mftyre::MfInput {
        fz_n: 6000.0,
        kappa: 0.08,
        alpha_rad: 6f64.to_radians(),
        gamma_rad: 0.0,
        phit_per_m: 0.0,
        vx_mps: 16.6,
        p_pa: 260_000.0,
        omega_radps: 0.0,
    };
    c.bench_function("mf_evaluate_combined", |b| {
        b.iter(|| black_box(mftyre::evaluate(&mf, mftyre::UseMode::M111, black_box(&mfi))))
    });
}

criterion_group! {
    name = benches;
    config = Criterion::default().sample_size(20).measurement_time(std::time::Duration::from_secs(3)).warm_up_time(std::time::Duration::from_secs(1));
    targets = bench
}
criterion_main!(benches);

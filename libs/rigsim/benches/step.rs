//! Simulation speed of the core: internal steps per second with every effect on, during a
//! steady-state sweep-like operating point (slip changing, samples published at 100 Hz).

use std::hint::black_box;
use std::path::Path;

use criterion::{Criterion, criterion_group, criterion_main};
use rigsim::{RigSetpoint, VirtualRig};

fn rig() -> VirtualRig {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../launch-config/virtual_rig.toml");
    let mut rig = VirtualRig::from_config_file(&path).expect("config");
    rig.apply_setpoint(&RigSetpoint {
        mode: RigSetpoint::MODE_COUPLED,
        slip_angle_deg: 3.0,
        slip_ratio: 0.05,
        fz_n: 6000.0,
        pressure_pa: 260_000.0,
        speed_mps: 16.6,
        ..RigSetpoint::default()
    })
    .expect("setpoint");
    rig.run_until(6.0, &mut |_| {});
    rig
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
}

criterion_group! {
    name = benches;
    config = Criterion::default().sample_size(20).measurement_time(std::time::Duration::from_secs(3)).warm_up_time(std::time::Duration::from_secs(1));
    targets = bench
}
criterion_main!(benches);

//! Evaluations per second: pure Fy only and the full combined-slip output set, over a batch of
//! one million operating points — once spread at random over the sample tyre's valid input box
//! (every point a new load case) and once arranged as a rig measures them: 1,000 sweeps of
//! 1,000 points, each at one load, pressure and camber (pure α, pure κ and combined sweeps).
//!
//! Run: `cargo bench -p mftyre --bench evaluate -- --warm-up-time 1 --measurement-time 3`
//! Criterion reports throughput in elements/s = evaluations per second on one core.

use std::hint::black_box;
use std::path::PathBuf;

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use mftyre::{BatchInput, BatchOutput, TyreParams, UseMode, evaluate_batch, pure_fy_batch};

const N: usize = 1_000_000;

/// Deterministic uniform numbers in [0, 1) (a 64-bit LCG; quality is irrelevant here).
struct Lcg(u64);

impl Lcg {
    fn next(&mut self) -> f64 {
        self.0 = self.0.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }
    fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.next()
    }
}

struct Columns {
    fz: Vec<f64>,
    kappa: Vec<f64>,
    alpha: Vec<f64>,
    gamma: Vec<f64>,
    vx: Vec<f64>,
    p: Vec<f64>,
}

/// 1,000 sweeps × 1,000 points: alternating pure-α, pure-κ and κ-at-α sweeps, each at one
/// (Fz, camber) load case, as a flat-track procedure produces them.
fn sweep_columns() -> Columns {
    let mut c = Columns {
        fz: Vec::with_capacity(N),
        kappa: Vec::with_capacity(N),
        alpha: Vec::with_capacity(N),
        gamma: Vec::with_capacity(N),
        vx: Vec::with_capacity(N),
        p: Vec::with_capacity(N),
    };
    for i in 0..N {
        let case = i / 1000;
        let t = (i % 1000) as f64 / 999.0;
        let fz = 2000.0 + 10.0 * case as f64;
        let gamma = ((case % 5) as f64 - 2.0) * 0.02;
        let (kappa, alpha) = match case % 3 {
            0 => (0.0, 0.5 * t - 0.25),
            1 => (t - 0.5, 0.0),
            _ => (0.6 * t - 0.3, 0.05),
        };
        c.fz.push(fz);
        c.kappa.push(kappa);
        c.alpha.push(alpha);
        c.gamma.push(gamma);
        c.vx.push(16.6);
        c.p.push(260000.0);
    }
    c
}

fn columns() -> Columns {
    let mut r = Lcg(0x5eed);
    let mut c = Columns {
        fz: Vec::with_capacity(N),
        kappa: Vec::with_capacity(N),
        alpha: Vec::with_capacity(N),
        gamma: Vec::with_capacity(N),
        vx: Vec::with_capacity(N),
        p: Vec::with_capacity(N),
    };
    for _ in 0..N {
        c.fz.push(r.range(1000.0, 14000.0));
        c.kappa.push(r.range(-0.5, 0.5));
        c.alpha.push(r.range(-0.4, 0.4));
        c.gamma.push(r.range(-0.1, 0.1));
        c.vx.push(r.range(5.0, 40.0));
        c.p.push(r.range(200000.0, 350000.0));
    }
    c
}

fn bench(c: &mut Criterion) {
    let path =
        PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../launch-config/tyres/MagicFormula61_Paramerters.tir");
    let params = match TyreParams::read_tir(&path) {
        Ok(p) => p,
        Err(e) => panic!("{e}"),
    };
    let cols = columns();
    let inputs = BatchInput {
        fz_n: &cols.fz,
        kappa: &cols.kappa,
        alpha_rad: &cols.alpha,
        gamma_rad: &cols.gamma,
        vx_mps: &cols.vx,
        p_pa: &cols.p,
        ..Default::default()
    };
    let mut group = c.benchmark_group("mf61_1e6_points");
    group.throughput(Throughput::Elements(N as u64));
    group.sample_size(10);

    let mut fy = Vec::with_capacity(N);
    group.bench_function("pure_fy", |b| {
        b.iter(|| {
            pure_fy_batch(&params, UseMode::M111, black_box(&inputs), &mut fy).ok();
            black_box(&fy);
        })
    });

    let mut out = BatchOutput::default();
    group.bench_function("full_combined_111", |b| {
        b.iter(|| {
            evaluate_batch(&params, UseMode::M111, black_box(&inputs), &mut out).ok();
            black_box(&out);
        })
    });

    let sw = sweep_columns();
    let sweeps = BatchInput {
        fz_n: &sw.fz,
        kappa: &sw.kappa,
        alpha_rad: &sw.alpha,
        gamma_rad: &sw.gamma,
        vx_mps: &sw.vx,
        p_pa: &sw.p,
        ..Default::default()
    };
    group.bench_function("pure_fy_sweeps", |b| {
        b.iter(|| {
            pure_fy_batch(&params, UseMode::M111, black_box(&sweeps), &mut fy).ok();
            black_box(&fy);
        })
    });
    group.bench_function("full_combined_111_sweeps", |b| {
        b.iter(|| {
            evaluate_batch(&params, UseMode::M111, black_box(&sweeps), &mut out).ok();
            black_box(&out);
        })
    });
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);

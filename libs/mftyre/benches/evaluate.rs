//! Evaluations per second: pure Fy only and the full combined-slip output set, over a batch of
//! one million operating points spread over the sample tyre's valid input box.
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
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);

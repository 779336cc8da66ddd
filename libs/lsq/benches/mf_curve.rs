//! Fitting the Magic-Formula-like curve y = D·sin(C·atan(B·x − E·(B·x − atan(B·x)))) to 10k
//! noisy points, with bounds, analytic and finite-difference Jacobians.
//!
//! Run: `cargo bench -p lsq --bench mf_curve`

use std::hint::black_box;
use std::time::Duration;

use criterion::{Criterion, criterion_group, criterion_main};
use lsq::{Options, Problem, solve};
use nalgebra::{DMatrix, DVector};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;

struct MagicCurve {
    x: Vec<f64>,
    y: Vec<f64>,
    analytic: bool,
}

fn model(p: &[f64], x: f64) -> f64 {
    let u = p[0] * x;
    p[2] * (p[1] * (u - p[3] * (u - u.atan())).atan()).sin()
}

impl MagicCurve {
    fn new(n: usize, analytic: bool) -> Self {
        let mut rng = ChaCha8Rng::seed_from_u64(42);
        let truth = [10.0, 1.6, 5000.0, -0.5];
        let x: Vec<f64> = (0..n).map(|i| -0.3 + 0.6 * i as f64 / (n - 1) as f64).collect();
        let y = x
            .iter()
            .map(|&x| {
                // Box–Muller, σ = 25 N.
                let u1: f64 = rng.random::<f64>().max(f64::MIN_POSITIVE);
                let u2: f64 = rng.random();
                model(&truth, x) + 25.0 * (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()
            })
            .collect();
        Self { x, y, analytic }
    }
}

impl Problem for MagicCurve {
    fn num_residuals(&self) -> usize {
        self.x.len()
    }

    fn residuals(&self, p: &DVector<f64>, r: &mut DVector<f64>) {
        for (i, (&x, &y)) in self.x.iter().zip(&self.y).enumerate() {
            r[i] = model(p.as_slice(), x) - y;
        }
    }

    fn jacobian(&self, p: &DVector<f64>, j: &mut DMatrix<f64>) -> bool {
        if !self.analytic {
            return false;
        }
        let (b, c, d, e) = (p[0], p[1], p[2], p[3]);
        for (i, &x) in self.x.iter().enumerate() {
            let u = b * x;
            let phi = u - e * (u - u.atan());
            let (s, co) = (c * phi.atan()).sin_cos();
            let dtheta_dphi = c / (1.0 + phi * phi);
            j[(i, 0)] = d * co * dtheta_dphi * (x - e * (x - x / (1.0 + u * u)));
            j[(i, 1)] = d * co * phi.atan();
            j[(i, 2)] = s;
            j[(i, 3)] = -d * co * dtheta_dphi * (u - u.atan());
        }
        true
    }
}

fn bench(c: &mut Criterion) {
    let options = Options::default()
        .bounds(DVector::from_row_slice(&[1.0, 1.0, 0.0, -10.0]), DVector::from_row_slice(&[30.0, 2.0, 1e4, 1.0]));
    let p0 = DVector::from_row_slice(&[5.0, 1.3, 4000.0, 0.0]);
    let mut group = c.benchmark_group("mf_curve_10k");
    group.sample_size(20).warm_up_time(Duration::from_millis(500)).measurement_time(Duration::from_secs(3));
    for (name, analytic) in [("analytic", true), ("numeric", false)] {
        let problem = MagicCurve::new(10_000, analytic);
        let report = solve(&problem, p0.clone(), &options).expect("valid problem");
        assert!(report.termination.converged(), "{report:?}");
        group.bench_function(name, |b| {
            b.iter(|| solve(black_box(&problem), black_box(p0.clone()), &options).expect("valid problem"))
        });
    }
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);

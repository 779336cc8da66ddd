//! Test problems shared by the tests and the benchmark's sanity checks.
#![allow(dead_code)]

use std::cell::Cell;

use lsq::Problem;
use nalgebra::{DMatrix, DVector};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// Gaussian noise from a seeded ChaCha stream (Box–Muller), so data are identical everywhere.
pub struct Gauss(ChaCha8Rng);

impl Gauss {
    pub fn new(seed: u64) -> Self {
        Self(ChaCha8Rng::seed_from_u64(seed))
    }

    pub fn sample(&mut self, sigma: f64) -> f64 {
        let u1: f64 = self.0.random::<f64>().max(f64::MIN_POSITIVE);
        let u2: f64 = self.0.random();
        sigma * (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()
    }

    pub fn uniform(&mut self) -> f64 {
        self.0.random()
    }
}

/// Rosenbrock as least squares: r = (10·(y − x²), 1 − x), minimum at (1, 1).
pub struct Rosenbrock {
    pub analytic: bool,
}

impl Problem for Rosenbrock {
    fn num_residuals(&self) -> usize {
        2
    }

    fn residuals(&self, p: &DVector<f64>, r: &mut DVector<f64>) {
        r[0] = 10.0 * (p[1] - p[0] * p[0]);
        r[1] = 1.0 - p[0];
    }

    fn jacobian(&self, p: &DVector<f64>, j: &mut DMatrix<f64>) -> bool {
        if !self.analytic {
            return false;
        }
        j[(0, 0)] = -20.0 * p[0];
        j[(0, 1)] = 10.0;
        j[(1, 0)] = -1.0;
        j[(1, 1)] = 0.0;
        true
    }
}

/// y = a·exp(−b·t) + c.
pub struct ExpDecay {
    pub t: Vec<f64>,
    pub y: Vec<f64>,
    pub analytic: bool,
}

impl ExpDecay {
    pub fn model(p: &[f64], t: f64) -> f64 {
        p[0] * (-p[1] * t).exp() + p[2]
    }

    pub fn with_noise(truth: [f64; 3], n: usize, sigma: f64, seed: u64) -> Self {
        let mut g = Gauss::new(seed);
        let t: Vec<f64> = (0..n).map(|i| 10.0 * i as f64 / (n - 1) as f64).collect();
        let y = t.iter().map(|&t| Self::model(&truth, t) + g.sample(sigma)).collect();
        Self { t, y, analytic: true }
    }
}

impl Problem for ExpDecay {
    fn num_residuals(&self) -> usize {
        self.t.len()
    }

    fn residuals(&self, p: &DVector<f64>, r: &mut DVector<f64>) {
        for (i, (&t, &y)) in self.t.iter().zip(&self.y).enumerate() {
            r[i] = Self::model(p.as_slice(), t) - y;
        }
    }

    fn jacobian(&self, p: &DVector<f64>, j: &mut DMatrix<f64>) -> bool {
        if !self.analytic {
            return false;
        }
        for (i, &t) in self.t.iter().enumerate() {
            let e = (-p[1] * t).exp();
            j[(i, 0)] = e;
            j[(i, 1)] = -p[0] * t * e;
            j[(i, 2)] = 1.0;
        }
        true
    }
}

/// The Magic-Formula-like curve y = D·sin(C·atan(B·x − E·(B·x − atan(B·x)))), p = (B, C, D, E).
pub struct MagicCurve {
    pub x: Vec<f64>,
    pub y: Vec<f64>,
    pub analytic: bool,
}

impl MagicCurve {
    pub const TRUTH: [f64; 4] = [10.0, 1.6, 5000.0, -0.5];

    pub fn model(p: &[f64], x: f64) -> f64 {
        let (b, c, d, e) = (p[0], p[1], p[2], p[3]);
        let u = b * x;
        d * (c * (u - e * (u - u.atan())).atan()).sin()
    }

    /// `n` points of slip in [−0.3, 0.3] with Gaussian noise of `sigma` (force units).
    pub fn with_noise(n: usize, sigma: f64, seed: u64) -> Self {
        let mut g = Gauss::new(seed);
        let x: Vec<f64> = (0..n).map(|i| -0.3 + 0.6 * i as f64 / (n - 1) as f64).collect();
        let y = x.iter().map(|&x| Self::model(&Self::TRUTH, x) + g.sample(sigma)).collect();
        Self { x, y, analytic: true }
    }
}

impl Problem for MagicCurve {
    fn num_residuals(&self) -> usize {
        self.x.len()
    }

    fn residuals(&self, p: &DVector<f64>, r: &mut DVector<f64>) {
        for (i, (&x, &y)) in self.x.iter().zip(&self.y).enumerate() {
            r[i] = Self::model(p.as_slice(), x) - y;
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
            let theta = c * phi.atan();
            let (s, co) = theta.sin_cos();
            let dtheta_dphi = c / (1.0 + phi * phi);
            let dphi_db = x - e * (x - x / (1.0 + u * u));
            let dphi_de = -(u - u.atan());
            j[(i, 0)] = d * co * dtheta_dphi * dphi_db;
            j[(i, 1)] = d * co * phi.atan();
            j[(i, 2)] = s;
            j[(i, 3)] = d * co * dtheta_dphi * dphi_de;
        }
        true
    }
}

/// Wraps a problem and records whether it was ever evaluated outside the box.
pub struct BoxWatch<P> {
    pub inner: P,
    pub lower: DVector<f64>,
    pub upper: DVector<f64>,
    pub violations: Cell<usize>,
}

impl<P: Problem> Problem for BoxWatch<P> {
    fn num_residuals(&self) -> usize {
        self.inner.num_residuals()
    }

    fn residuals(&self, p: &DVector<f64>, r: &mut DVector<f64>) {
        if p.iter().zip(self.lower.iter().zip(self.upper.iter())).any(|(v, (lo, up))| v < lo || v > up) {
            self.violations.set(self.violations.get() + 1);
        }
        self.inner.residuals(p, r);
    }

    fn jacobian(&self, p: &DVector<f64>, j: &mut DMatrix<f64>) -> bool {
        self.inner.jacobian(p, j)
    }
}

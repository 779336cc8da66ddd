//! Deterministic Gaussian noise from a seeded ChaCha8 stream (portable across platforms).

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// Standard-normal draws by the Box–Muller transform; the second value of each pair is kept,
/// so the stream depends only on the seed and the number of draws.
#[derive(Debug, Clone)]
pub(crate) struct Gauss {
    rng: ChaCha8Rng,
    spare: Option<f64>,
}

impl Gauss {
    pub(crate) fn new(seed: u64) -> Self {
        Self { rng: ChaCha8Rng::seed_from_u64(seed), spare: None }
    }

    /// Uniform in (0, 1], never 0 (so the logarithm below is finite).
    fn uniform(&mut self) -> f64 {
        // 53 random bits → [0, 1), shifted to (0, 1].
        ((self.rng.next_u64() >> 11) as f64 + 1.0) * (1.0 / 9_007_199_254_740_992.0)
    }

    /// One N(0, 1) draw.
    pub(crate) fn normal(&mut self) -> f64 {
        if let Some(z) = self.spare.take() {
            return z;
        }
        let u1 = self.uniform();
        let u2 = self.uniform();
        let r = (-2.0 * u1.ln()).sqrt();
        let (s, c) = (std::f64::consts::TAU * u2).sin_cos();
        self.spare = Some(r * s);
        r * c
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn moments_and_determinism() {
        let mut g = Gauss::new(7);
        let n = 200_000;
        let xs: Vec<f64> = (0..n).map(|_| g.normal()).collect();
        let mean = xs.iter().sum::<f64>() / n as f64;
        let var = xs.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / n as f64;
        assert!(mean.abs() < 0.01, "{mean}");
        assert!((var - 1.0).abs() < 0.02, "{var}");
        let mut h = Gauss::new(7);
        assert_eq!(xs[..10], (0..10).map(|_| h.normal()).collect::<Vec<_>>()[..]);
    }
}

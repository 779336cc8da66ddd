//! Form error: what the fitted model systematically misses where the data are, as a residual
//! model over the operating point.
//!
//! The delta-method σ of [`crate::prediction`] is the uncertainty of the model's mean *if the
//! model could represent the tyre*: it shrinks with every point. What the Magic Formula cannot
//! represent (a brush tyre, every real tyre), what coefficients held at template values leave
//! out, and what the rig adds that is not noise stay in the residuals as a smooth part along each
//! sweep. This module estimates the size of that smooth part around each operating point:
//!
//! 1. residuals r = model − measured at the stage's points, each sweep's *held out*: what the
//!    model fitted without that sweep leaves there ([`held_out_values`], a linearised
//!    leave-one-sweep-out), so the error where no sweep ran counts too;
//! 2. per point i, the mean mᵢ of the residuals of its own sweep within a slip neighbourhood
//!    (±[`SMOOTH_SLIP_ANGLE_DEG`] or ±[`SMOOTH_SLIP_RATIO`]), kᵢ points: the smooth part plus
//!    noise/√kᵢ;
//! 3. the noise variance s² from the differences of neighbouring residuals in slip within each
//!    sweep (a difference of two noisy points has variance 2s²; the smooth part cancels);
//! 4. qᵢ = mᵢ² − s²/kᵢ, an unbiased estimate of the squared smooth residual at point i;
//! 5. at a grid point x, the form-error variance τ²(x): the mean over sweeps of each sweep's mean
//!    qᵢ in the region around x (load ±15 % Fz0, camber ±0.75°, pressure ±20 kPa, slip
//!    ±[`REGION_SLIP_ANGLE_DEG`] or ±[`REGION_SLIP_RATIO`]), shrunk toward the same mean over the
//!    whole stage (the region's k sweeps against one sweep's weight for the stage), at least 0.
//!
//! Between data points the model's error against the true tyre is taken to be of the size the
//! held-out residuals show nearby (no more, no less: nothing is tuned to a coverage). In-sample
//! residuals were used until 2026-12-02: a sweep alone at its cell pulls the coefficients its
//! way and then shows no error, though the model between that cell and the next is only as good
//! as the other sweeps make it.

use mftyre::MfInput;

use crate::engine::Point;

/// Half-width of a point's smoothing neighbourhood in slip angle, deg.
pub const SMOOTH_SLIP_ANGLE_DEG: f64 = 0.5;
/// Half-width of a point's smoothing neighbourhood in slip ratio.
pub const SMOOTH_SLIP_RATIO: f64 = 0.01;
/// Half-width of a grid point's region in slip angle, deg.
pub const REGION_SLIP_ANGLE_DEG: f64 = 2.0;
/// Half-width of a grid point's region in slip ratio.
pub const REGION_SLIP_RATIO: f64 = 0.04;
/// Half-width of a grid point's region in load, fraction of Fz0.
const REGION_LOAD_FRACTION: f64 = 0.15;
/// Half-width of a grid point's region in camber, deg.
const REGION_CAMBER_DEG: f64 = 0.75;
/// Half-width of a grid point's region in pressure, Pa.
const REGION_PRESSURE_PA: f64 = 20e3;

/// Which slip a channel's sweeps run over.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SlipAxis {
    /// Slip angle (FY, MZ).
    Angle,
    /// Slip ratio (FX).
    Ratio,
}

impl SlipAxis {
    fn of(self, x: &MfInput) -> f64 {
        match self {
            SlipAxis::Angle => x.alpha_rad.to_degrees(),
            SlipAxis::Ratio => x.kappa,
        }
    }

    fn smooth(self) -> f64 {
        match self {
            SlipAxis::Angle => SMOOTH_SLIP_ANGLE_DEG,
            SlipAxis::Ratio => SMOOTH_SLIP_RATIO,
        }
    }

    fn region(self) -> f64 {
        match self {
            SlipAxis::Angle => REGION_SLIP_ANGLE_DEG,
            SlipAxis::Ratio => REGION_SLIP_RATIO,
        }
    }
}

/// The model's values at the stage's points as each point's sweep would have them had the stage
/// been fitted without that sweep: a linearised leave-one-sweep-out.
///
/// In-sample residuals show what the model misses *where it was fitted*; the error of the
/// model where no sweep ran — between the tested loads, cambers and pressures, and at a cell
/// only one sweep informs — does not show in them, because that sweep pulled the coefficients
/// its way. For a least-squares fit with Jacobian J (rows Jᵢ = ∂valueᵢ/∂p at the solution) and
/// residuals r = model − measured, leaving out the points S of one sweep moves the coefficients
/// by δ = A₋ₛ⁺ J_Sᵀ r_S with A₋ₛ = JᵀJ − J_SᵀJ_S, and the held-out residuals are
/// r_S + J_S δ (exact for a linear model; the stage's coefficients move little when one of
/// many sweeps goes). A direction only that sweep informs is left where it was (A₋ₛ⁺ is the
/// pseudo-inverse): the data without it cannot say anything there.
///
/// `jacobian[k][i]` = ∂values\[i\]/∂(k-th coefficient). Returns `values` unchanged where the
/// Jacobian is empty or its shape does not match.
pub fn held_out_values(points: &[Point], groups: &[usize], values: &[f64], jacobian: &[Vec<f64>]) -> Vec<f64> {
    use nalgebra::{DMatrix, DVector};
    let n = points.len().min(groups.len()).min(values.len());
    let p = jacobian.len();
    if p == 0 || jacobian.iter().any(|row| row.len() < n) {
        return values.to_vec();
    }
    let res: Vec<f64> = (0..n).map(|i| values[i] - points[i].measured).collect();
    let usable = |i: usize| res[i].is_finite() && jacobian.iter().all(|row| row[i].is_finite());
    let gram = |idx: &mut dyn Iterator<Item = usize>| {
        let mut a = DMatrix::<f64>::zeros(p, p);
        for i in idx {
            for (k, rk) in jacobian.iter().enumerate() {
                for (l, rl) in jacobian.iter().enumerate().skip(k) {
                    a[(k, l)] += rk[i] * rl[i];
                }
            }
        }
        for k in 0..p {
            for l in 0..k {
                a[(k, l)] = a[(l, k)];
            }
        }
        a
    };
    let all = gram(&mut (0..n).filter(|&i| usable(i)));
    let mut by_group: std::collections::BTreeMap<usize, Vec<usize>> = Default::default();
    for i in (0..n).filter(|&i| usable(i)) {
        by_group.entry(groups[i]).or_default().push(i);
    }
    let mut out = values.to_vec();
    for idx in by_group.values() {
        let rest = &all - gram(&mut idx.iter().copied());
        let b = DVector::from_iterator(p, jacobian.iter().map(|row| idx.iter().map(|&i| row[i] * res[i]).sum()));
        // Relative threshold: directions the other sweeps do not inform stay put.
        let tol = 1e-9 * rest.diagonal().amax().max(f64::MIN_POSITIVE);
        let Ok(delta) = rest.svd(true, true).solve(&b, tol) else { continue };
        for &i in idx {
            let shift: f64 = jacobian.iter().zip(delta.iter()).map(|(row, d)| row[i] * d).sum();
            if shift.is_finite() {
                out[i] = values[i] + shift;
            }
        }
    }
    out
}

/// The squared smooth residual at each point of one stage, ready to be averaged over regions.
#[derive(Debug, Clone)]
pub struct FormError {
    inputs: Vec<MfInput>,
    /// qᵢ = mᵢ² − s²/kᵢ (may be negative: unbiased, not clamped per point).
    q: Vec<f64>,
    /// The sweep of each point.
    sweep: Vec<usize>,
    /// The stage-wide form-error variance: the mean of qᵢ over the sweeps' means, at least 0.
    pooled_var: f64,
    axis: SlipAxis,
    fz0_n: f64,
    /// The pooled noise variance s², channel units².
    noise_var: f64,
}

impl FormError {
    /// From the stage's `points` (their sweeps in `groups`) and the model's `values` at them.
    pub fn of(points: &[Point], groups: &[usize], values: &[f64], axis: SlipAxis, fz0_n: f64) -> Self {
        let n = points.len().min(groups.len()).min(values.len());
        let res: Vec<f64> = (0..n).map(|i| values[i] - points[i].measured).collect();
        let slip: Vec<f64> = points[..n].iter().map(|p| axis.of(&p.input)).collect();
        // Points of each sweep, sorted by slip: a neighbourhood is then a window.
        let mut by_group: std::collections::BTreeMap<usize, Vec<usize>> = Default::default();
        for i in (0..n).filter(|&i| res[i].is_finite()) {
            by_group.entry(groups[i]).or_default().push(i);
        }
        let mut mean = vec![f64::NAN; n];
        let mut count = vec![0usize; n];
        // Noise from neighbours in slip: r_{j+1} − r_j has variance 2s² plus the (small) change
        // of the smooth part between them. Pooled over the stage: a local estimate from the few
        // pairs of one window (tried) is so noisy that the regions' clamped means come out wider.
        let (mut diffs, mut pairs) = (0.0, 0usize);
        for idx in by_group.values_mut() {
            idx.sort_by(|&a, &b| slip[a].total_cmp(&slip[b]));
            for w in idx.windows(2) {
                diffs += (res[w[1]] - res[w[0]]).powi(2);
                pairs += 1;
            }
            let (mut lo, mut hi) = (0usize, 0usize);
            for (k, &i) in idx.iter().enumerate() {
                while slip[idx[lo]] < slip[i] - axis.smooth() {
                    lo += 1;
                }
                hi = hi.max(k);
                while hi + 1 < idx.len() && slip[idx[hi + 1]] <= slip[i] + axis.smooth() {
                    hi += 1;
                }
                let window = &idx[lo..=hi];
                mean[i] = window.iter().map(|&j| res[j]).sum::<f64>() / window.len() as f64;
                count[i] = window.len();
            }
        }
        let noise_var = if pairs == 0 { 0.0 } else { diffs / (2.0 * pairs as f64) };
        let mut inputs = Vec::with_capacity(n);
        let mut q = Vec::with_capacity(n);
        let mut sweep = Vec::with_capacity(n);
        for i in (0..n).filter(|&i| count[i] > 0) {
            inputs.push(points[i].input);
            q.push(mean[i] * mean[i] - noise_var / count[i] as f64);
            sweep.push(groups[i]);
        }
        let pooled_var = mean_over_sweeps(&q, &sweep).0.max(0.0);
        FormError { inputs, q, sweep, pooled_var, axis, fz0_n, noise_var }
    }

    /// The pooled noise variance the smooth residuals were corrected for, channel units².
    pub fn noise_var(&self) -> f64 {
        self.noise_var
    }

    /// τ(x): the form error's standard deviation in the region around `x`; `None` when no point
    /// lies in that region.
    pub fn std_at(&self, x: &MfInput) -> Option<f64> {
        self.over(std::slice::from_ref(x))[0].std
    }

    /// [`FormError::std_at`] at every one of `xs`, and whether each lies inside the tested
    /// envelope (a point within load ±15 % Fz0, slip angle ±1°, slip ratio ±0.02, camber ±0.75°,
    /// pressure ±20 kPa: the box of [`crate::accuracy::Support`]). The points are taken by load
    /// case (load, camber, pressure), so a grid costs one pass over the data per load case.
    pub fn over(&self, xs: &[MfInput]) -> Vec<Region> {
        let sf = REGION_LOAD_FRACTION * self.fz0_n.max(1.0);
        let sg = REGION_CAMBER_DEG.to_radians();
        let mut out = vec![Region { std: None, tested: false }; xs.len()];
        let mut cases: Vec<([f64; 3], Vec<usize>)> = Vec::new();
        for (i, x) in xs.iter().enumerate() {
            let key = [x.fz_n, x.gamma_rad, x.p_pa];
            match cases.iter_mut().find(|(k, _)| *k == key) {
                Some((_, v)) => v.push(i),
                None => cases.push((key, vec![i])),
            }
        }
        for ([fz, gamma, p], members) in cases {
            let near: Vec<usize> = (0..self.inputs.len())
                .filter(|&j| {
                    let d = &self.inputs[j];
                    (d.fz_n - fz).abs() <= sf
                        && (d.gamma_rad - gamma).abs() <= sg
                        && (d.p_pa - p).abs() <= REGION_PRESSURE_PA
                })
                .collect();
            for i in members {
                let x = &xs[i];
                let slip = self.axis.of(x);
                let mut tested = false;
                let (mut q, mut sweep) = (Vec::new(), Vec::new());
                for &j in &near {
                    let d = &self.inputs[j];
                    if (self.axis.of(d) - slip).abs() <= self.axis.region() {
                        q.push(self.q[j]);
                        sweep.push(self.sweep[j]);
                    }
                    tested |= (d.alpha_rad - x.alpha_rad).abs() <= TESTED_SLIP_ANGLE_DEG.to_radians()
                        && (d.kappa - x.kappa).abs() <= TESTED_SLIP_RATIO;
                }
                out[i] = Region { std: (!q.is_empty()).then(|| self.shrunk_var(&q, &sweep).sqrt()), tested };
            }
        }
        out
    }

    /// The region's form-error variance, shrunk toward the stage-wide one: the region's own
    /// estimate (the mean of its sweeps' mean qᵢ) counts as many sweeps as it holds, the
    /// stage-wide one as [`POOLED_WEIGHT_SWEEPS`]. A region one or two sweeps inform says little
    /// on its own — its noise-corrected mean is often 0 beside a region reading several times the
    /// stage's form error — and the data as a whole say how large the form error tends to be.
    fn shrunk_var(&self, q: &[f64], sweep: &[usize]) -> f64 {
        let (own, sweeps) = mean_over_sweeps(q, sweep);
        let sweeps = sweeps as f64;
        ((sweeps * own + POOLED_WEIGHT_SWEEPS * self.pooled_var) / (sweeps + POOLED_WEIGHT_SWEEPS)).max(0.0)
    }
}

/// Weight of the stage-wide form error in a region's estimate, in sweeps.
const POOLED_WEIGHT_SWEEPS: f64 = 1.0;

/// The mean over sweeps of each sweep's mean of `q` (each sweep counts once, however many
/// points it has), and how many sweeps; (0, 0) when empty.
fn mean_over_sweeps(q: &[f64], sweep: &[usize]) -> (f64, usize) {
    let mut by: std::collections::BTreeMap<usize, (f64, usize)> = Default::default();
    for (&v, &g) in q.iter().zip(sweep) {
        let e = by.entry(g).or_default();
        e.0 += v;
        e.1 += 1;
    }
    if by.is_empty() {
        return (0.0, 0);
    }
    (by.values().map(|(s, n)| s / *n as f64).sum::<f64>() / by.len() as f64, by.len())
}

/// The form error around one operating point.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Region {
    /// τ, channel units; `None` without data in the region.
    pub std: Option<f64>,
    /// True inside the tested envelope.
    pub tested: bool,
}

/// Half-width of the tested envelope's box in slip angle, deg ([`crate::accuracy::Support`]'s).
const TESTED_SLIP_ANGLE_DEG: f64 = 1.0;
/// Half-width of the tested envelope's box in slip ratio.
const TESTED_SLIP_RATIO: f64 = 0.02;

#[cfg(test)]
mod tests {
    use super::*;

    /// A free-rolling point at load `fz_n` and slip angle `alpha_deg`.
    fn free_rolling(fz_n: f64, alpha_deg: f64) -> MfInput {
        MfInput {
            fz_n,
            kappa: 0.0,
            alpha_rad: alpha_deg.to_radians(),
            gamma_rad: 0.0,
            phit_per_m: 0.0,
            vx_mps: 16.0,
            p_pa: 2e5,
            omega_radps: 0.0,
        }
    }

    fn sweep(group_bias: impl Fn(f64) -> f64, noise: &[f64]) -> (Vec<Point>, Vec<usize>, Vec<f64>) {
        let mut pts = Vec::new();
        let mut values = Vec::new();
        for (i, e) in noise.iter().enumerate() {
            let alpha_deg = -10.0 + 20.0 * i as f64 / (noise.len() - 1) as f64;
            pts.push(Point { input: free_rolling(4000.0, alpha_deg), measured: 0.0 });
            values.push(group_bias(alpha_deg) + e);
        }
        let groups = vec![0; pts.len()];
        (pts, groups, values)
    }

    /// Seeded white Gaussian noise of unit variance.
    fn noise(n: usize) -> Vec<f64> {
        use rand::SeedableRng;
        use rand_distr::Distribution;
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
        let normal = rand_distr::Normal::new(0.0, 1.0).expect("a normal distribution");
        (0..n).map(|_| normal.sample(&mut rng)).collect()
    }

    #[test]
    fn held_out_values_are_those_of_a_refit_without_the_sweep() {
        // A linear model y = c₀ + c₁·fz + c₂·α fitted by least squares on five sweeps of a
        // curved truth: leaving a sweep out by the formula must give what an explicit refit on
        // the other four predicts for it.
        use nalgebra::{DMatrix, DVector};
        let e = noise(200);
        let mut pts = Vec::new();
        let mut groups = Vec::new();
        for g in 0..5 {
            for k in 0..40 {
                let fz = 2000.0 + 1000.0 * g as f64;
                let alpha_deg = -8.0 + 16.0 * k as f64 / 39.0;
                let measured = 1e-4 * fz * fz + 30.0 * alpha_deg + e[g * 40 + k];
                pts.push(Point { input: free_rolling(fz, alpha_deg), measured });
                groups.push(g);
            }
        }
        let feature = |p: &Point| [1.0, p.input.fz_n / 1000.0, p.input.alpha_rad.to_degrees()];
        let fit = |keep: &dyn Fn(usize) -> bool| {
            let idx: Vec<usize> = (0..pts.len()).filter(|&i| keep(groups[i])).collect();
            let a = DMatrix::from_fn(idx.len(), 3, |r, c| feature(&pts[idx[r]])[c]);
            let y = DVector::from_iterator(idx.len(), idx.iter().map(|&i| pts[i].measured));
            a.svd(true, true).solve(&y, 1e-12).expect("least squares")
        };
        let predict = |c: &DVector<f64>, p: &Point| feature(p).iter().zip(c.iter()).map(|(f, c)| f * c).sum::<f64>();
        let all = fit(&|_| true);
        let values: Vec<f64> = pts.iter().map(|p| predict(&all, p)).collect();
        let jacobian: Vec<Vec<f64>> = (0..3).map(|k| pts.iter().map(|p| feature(p)[k]).collect()).collect();
        let held = held_out_values(&pts, &groups, &values, &jacobian);
        for g in 0..5 {
            let without = fit(&|h| h != g);
            for i in (0..pts.len()).filter(|&i| groups[i] == g) {
                let want = predict(&without, &pts[i]);
                assert!((held[i] - want).abs() < 1e-6 * want.abs().max(1.0), "sweep {g}: {} vs {want}", held[i]);
            }
        }
        // The end sweeps, which pulled the line their way, are missed by more held out.
        let rms = |v: &[f64], g: usize| {
            let r: Vec<f64> = (0..pts.len()).filter(|&i| groups[i] == g).map(|i| v[i] - pts[i].measured).collect();
            (r.iter().map(|x| x * x).sum::<f64>() / r.len() as f64).sqrt()
        };
        assert!(rms(&held, 4) > 1.5 * rms(&values, 4), "{} vs {}", rms(&held, 4), rms(&values, 4));
    }

    #[test]
    fn white_noise_alone_gives_next_to_no_form_error() {
        let (p, g, v) = sweep(|_| 0.0, &noise(2001));
        let f = FormError::of(&p, &g, &v, SlipAxis::Angle, 4000.0);
        assert!((f.noise_var() - 1.0).abs() < 0.1, "noise variance {}", f.noise_var());
        let tau = f.std_at(&p[1000].input).expect("data in the region");
        assert!(tau < 0.2, "τ {tau} from noise of σ 1");
    }

    #[test]
    fn a_smooth_bias_is_found_at_its_size_under_the_noise() {
        // A bias of 5 units under noise of 1: τ near 5 where it is, and none where the data are not.
        let (p, g, v) = sweep(|_| 5.0, &noise(2001));
        let f = FormError::of(&p, &g, &v, SlipAxis::Angle, 4000.0);
        let tau = f.std_at(&p[1000].input).expect("data in the region");
        assert!((tau - 5.0).abs() < 0.2, "τ {tau}");
        let far = MfInput { gamma_rad: 4f64.to_radians(), ..p[1000].input };
        assert_eq!(f.std_at(&far), None);
    }

    #[test]
    fn a_region_one_sweep_informs_leans_on_the_stage_wide_form_error() {
        // Five sweeps at loads 1,000 N apart (one per region: ±15 % of Fz0 = ±600 N), four
        // missing the data by 5 units and one by none, under noise of 1. Stage-wide, the form
        // error's variance is ~20 (four of five sweeps at 25): the clean sweep's region, on its
        // own evidence 0, reads √((0 + 20)/2) ≈ 3.2; a biased one √((25 + 20)/2) ≈ 4.7.
        let e = noise(5 * 401);
        let (mut pts, mut groups, mut values) = (Vec::new(), Vec::new(), Vec::new());
        for s in 0..5 {
            let bias = if s == 4 { 0.0 } else { 5.0 };
            let (p, _, v) = sweep(|_| bias, &e[s * 401..(s + 1) * 401]);
            for (mut pt, val) in p.into_iter().zip(v) {
                pt.input.fz_n = 2000.0 + 1000.0 * s as f64;
                pts.push(pt);
                groups.push(s);
                values.push(val);
            }
        }
        let f = FormError::of(&pts, &groups, &values, SlipAxis::Angle, 4000.0);
        let at = |s: usize| f.std_at(&pts[s * 401 + 200].input).expect("data in the region");
        assert!((2.6..3.8).contains(&at(4)), "clean sweep's region: τ {}", at(4));
        assert!((4.2..5.2).contains(&at(0)), "biased sweep's region: τ {}", at(0));
    }
}

//! The model's form error: the part of the residual that is a fixed function of the operating
//! point, and so no state effect can be.
//!
//! A base model fitted to the logs (`--fit`) is the best MF-Tyre 6.1 can do; on a real tyre (or
//! the virtual brush tyre) what it leaves is mostly the MF form's own misfit — at a given slip,
//! load, camber and pressure the same in every sweep. A small state effect (grip that follows
//! tread temperature by a few per cent) hides under it: scored against the whole held-out χ² it
//! explains a fraction of a per cent. But a state effect is what makes two visits to the same
//! operating point disagree. So state candidates are scored against the present model **plus**
//! a smooth, cross-fitted estimate of that fixed misfit: a kernel average of the residual of
//! *other sweeps* at neighbouring operating points (local-linear kernel regression, Gaussian
//! kernels in slip angle, slip ratio, load, camber and pressure). A point is never corrected with the
//! residual of its own **visit** — its sweep and the sweeps run straight before or after it at
//! the same cell, as warm-up sweeps are (that would absorb what the tyre's state was during
//! the visit: five cold warm-up sweeps corrected by each other keep none of their cold grip) —
//! nor a held-out point with held-out data.
//!
//! Limits: what the effect does *on average* at an operating point is absorbed with the form
//! error (a test plan that visits hot cells only at high load cannot separate heat from load);
//! the effect is then judged on what varies between visits.

use crate::data::Dataset;

/// Gaussian kernel widths of the operating-point smoother.
#[derive(Debug, Clone, Copy)]
pub struct Bandwidths {
    /// Slip angle [deg].
    pub alpha_deg: f64,
    /// Slip ratio [-].
    pub kappa: f64,
    /// Vertical load [N].
    pub fz_n: f64,
    /// Inclination [deg].
    pub gamma_deg: f64,
    /// Inflation pressure [Pa].
    pub p_pa: f64,
}

impl Bandwidths {
    /// Widths from the data: slip angle 0.5° (a sweep's curvature resolves within it), slip
    /// ratio 0.01, and for load, camber and pressure the median spacing of the levels the test
    /// visited (neighbouring levels then weigh e^−½; a single level gets a wide kernel, so it
    /// does not matter).
    pub fn from_data(ds: &Dataset) -> Self {
        let s = &ds.series;
        let level_spacing = |v: Vec<f64>, quantum: f64, fallback: f64| -> f64 {
            let mut lv: Vec<f64> = v.iter().map(|x| (x / quantum).round() * quantum).collect();
            lv.sort_by(f64::total_cmp);
            lv.dedup();
            // Levels closer than three quanta are the same level measured with noise.
            let mut levels: Vec<f64> = Vec::new();
            for x in lv {
                if levels.last().is_none_or(|&l| x - l > 3.0 * quantum) {
                    levels.push(x);
                }
            }
            let mut gaps: Vec<f64> = levels.windows(2).map(|w| w[1] - w[0]).collect();
            if gaps.is_empty() {
                return fallback;
            }
            gaps.sort_by(f64::total_cmp);
            gaps[gaps.len() / 2]
        };
        // Per-sweep medians: the levels, not the scatter within a sweep.
        let per_sweep = |f: &dyn Fn(usize) -> f64| -> Vec<f64> {
            let mut by_sweep: Vec<Vec<f64>> = vec![Vec::new(); ds.sweeps.len()];
            for (k, &i) in ds.points.iter().enumerate() {
                let v = f(i);
                if let Some(b) = by_sweep.get_mut(ds.point_sweep(k))
                    && v.is_finite()
                {
                    b.push(v);
                }
            }
            by_sweep
                .into_iter()
                .filter(|v| !v.is_empty())
                .map(|mut v| {
                    v.sort_by(f64::total_cmp);
                    v[v.len() / 2]
                })
                .collect()
        };
        Self {
            alpha_deg: 0.5,
            kappa: 0.01,
            fz_n: level_spacing(per_sweep(&|i| s.fz_n[i]), 20.0, 1e6),
            gamma_deg: level_spacing(per_sweep(&|i| s.gamma_deg[i]), 0.1, 1e3),
            p_pa: level_spacing(per_sweep(&|i| s.p_pa[i]), 1000.0, 1e8),
        }
    }
}

/// The form-error correction of every point for one held-out fold: held-out points from the
/// training sweeps, training points from the *other* training sweeps.
pub type FoldCorrection = Vec<[f64; 4]>;

/// Largest difference of two sweeps' median scaled operating point (slip angle, slip ratio,
/// load, camber, pressure) at which they are at one cell: half a bandwidth.
const SAME_CELL: f64 = 0.5;

/// The visit of every sweep: consecutive sweeps of one log at one cell (median operating point
/// within [`SAME_CELL`] in every coordinate) share a visit, and so the tyre's state.
fn visits(ds: &Dataset, x: &[[f64; 5]]) -> Vec<usize> {
    let mut coords: Vec<[Vec<f64>; 5]> = vec![Default::default(); ds.sweeps.len()];
    for (k, p) in x.iter().enumerate() {
        if let Some(c) = coords.get_mut(ds.point_sweep(k)) {
            for m in 0..5 {
                if p[m].is_finite() {
                    c[m].push(p[m]);
                }
            }
        }
    }
    let medians: Vec<Option<[f64; 5]>> = coords
        .into_iter()
        .map(|mut c| {
            c.iter().all(|v| !v.is_empty()).then(|| {
                std::array::from_fn(|m| {
                    c[m].sort_by(f64::total_cmp);
                    c[m][c[m].len() / 2]
                })
            })
        })
        .collect();
    let mut visit = Vec::with_capacity(ds.sweeps.len());
    for i in 0..ds.sweeps.len() {
        let same = i > 0
            && ds.sweeps[i].log == ds.sweeps[i - 1].log
            && match (medians[i], medians[i - 1]) {
                (Some(a), Some(b)) => (0..5).all(|m| (a[m] - b[m]).abs() <= SAME_CELL),
                _ => false,
            };
        visit.push(if same { visit[i - 1] } else { i });
    }
    visit
}

/// Operating point of a data point, scaled by the bandwidths.
fn scaled_points(ds: &Dataset, bw: &Bandwidths) -> Vec<[f64; 5]> {
    let s = &ds.series;
    ds.points
        .iter()
        .map(|&i| {
            [
                s.alpha_deg[i] / bw.alpha_deg,
                s.kappa[i] / bw.kappa,
                s.fz_n[i] / bw.fz_n,
                s.gamma_deg[i] / bw.gamma_deg,
                s.p_pa[i] / bw.p_pa,
            ]
        })
        .collect()
}

/// Pseudo-weight of a zero residual added to every local fit: where other sweeps barely
/// reach, the correction fades to nothing instead of copying one distant point.
const PRIOR_WEIGHT: f64 = 0.05;
/// Ridge on the local slopes (per bandwidth): a direction the neighbours do not span (all at
/// one camber) gets no slope instead of an arbitrary one.
const SLOPE_RIDGE: f64 = 0.5;
/// Squared scaled distance beyond which a neighbour is ignored (kernel weight < 10⁻³).
const MAX_D2: f64 = 13.8;

/// The points a smoother may draw on, indexed for neighbour search: cells of one cut-off
/// radius in slip ratio, load, camber and pressure, and within a cell the points sorted by slip
/// angle, so a query visits the 3⁴ neighbouring cells and only the slip-angle window within
/// the cut-off in each. The smoother was O(N²) (every point against every other); a full
/// GS2MF log (8,000 points) spent most of a diagnosis there.
struct NeighbourIndex {
    cells: std::collections::HashMap<[i64; 4], Vec<(f64, usize)>>,
}

/// Cut-off radius in scaled units (√MAX_D2).
fn cutoff() -> f64 {
    MAX_D2.sqrt()
}

impl NeighbourIndex {
    fn cell(p: &[f64; 5]) -> Option<[i64; 4]> {
        let r = cutoff();
        let c: [f64; 4] = std::array::from_fn(|m| (p[m + 1] / r).floor());
        c.iter().all(|v| v.is_finite() && v.abs() < 1e15).then(|| c.map(|v| v as i64))
    }

    fn new(x: &[[f64; 5]], from: &[usize]) -> Self {
        let mut cells: std::collections::HashMap<[i64; 4], Vec<(f64, usize)>> = std::collections::HashMap::new();
        for &j in from {
            if let Some(c) = Self::cell(&x[j])
                && x[j][0].is_finite()
            {
                cells.entry(c).or_default().push((x[j][0], j));
            }
        }
        for v in cells.values_mut() {
            v.sort_by(|a, b| a.0.total_cmp(&b.0));
        }
        Self { cells }
    }

    /// Calls `f` with every indexed point within the cut-off box around `p`.
    fn for_each_near(&self, p: &[f64; 5], mut f: impl FnMut(usize)) {
        let Some(c) = Self::cell(p) else { return };
        let r = cutoff();
        for d in 0..81i64 {
            let off = [d % 3 - 1, (d / 3) % 3 - 1, (d / 9) % 3 - 1, (d / 27) % 3 - 1];
            let key: [i64; 4] = std::array::from_fn(|m| c[m] + off[m]);
            let Some(v) = self.cells.get(&key) else { continue };
            let lo = v.partition_point(|e| e.0 < p[0] - r);
            for e in &v[lo..] {
                if e.0 > p[0] + r {
                    break;
                }
                f(e.1);
            }
        }
    }
}

/// Calls `f(j, w, z)` for every indexed point `j` of another visit than `k`'s within the
/// cut-off: its Gaussian kernel weight `w` and local-linear regressor z = (1, x_j − x_k).
fn for_each_kernel_neighbour(
    ds: &Dataset,
    x: &[[f64; 5]],
    visit: &[usize],
    index: &NeighbourIndex,
    k: usize,
    mut f: impl FnMut(usize, f64, nalgebra::Vector6<f64>),
) {
    let own = visit[ds.point_sweep(k)];
    index.for_each_near(&x[k], |j| {
        if visit[ds.point_sweep(j)] == own {
            return;
        }
        let d: [f64; 5] = std::array::from_fn(|m| x[j][m] - x[k][m]);
        let d2: f64 = d.iter().map(|v| v * v).sum();
        if d2 > MAX_D2 || !d2.is_finite() {
            return;
        }
        f(j, (-0.5 * d2).exp(), nalgebra::Vector6::new(1.0, d[0], d[1], d[2], d[3], d[4]));
    });
}

/// Local-linear kernel regression at point `k` of `resid` over the indexed points whose visit
/// differs from `k`'s: the form error between neighbouring loads, cambers and pressures is
/// interpolated along its trend, where a plain kernel average would be pulled towards the
/// side with more data (the highest load of a test has neighbours only below it).
fn smooth_at(
    ds: &Dataset,
    x: &[[f64; 5]],
    visit: &[usize],
    resid: &[[f64; 4]],
    index: &NeighbourIndex,
    k: usize,
) -> [f64; 4] {
    use nalgebra::{Matrix6, Vector6};
    let mut a = [Matrix6::<f64>::zeros(); 4];
    let mut b = [Vector6::<f64>::zeros(); 4];
    for_each_kernel_neighbour(ds, x, visit, index, k, |j, w, z| {
        let wzz = w * z * z.transpose();
        for ch in 0..4 {
            let r = resid[j][ch];
            if r.is_finite() {
                a[ch] += wzz;
                b[ch] += w * r * z;
            }
        }
    });
    std::array::from_fn(|ch| {
        let mut m = a[ch];
        m[(0, 0)] += PRIOR_WEIGHT;
        for i in 1..6 {
            m[(i, i)] += SLOPE_RIDGE;
        }
        m.cholesky().map_or(0.0, |c| c.solve(&b[ch])[0])
    })
}

/// Cross-fitted form-error corrections, one per fold (`folds` as in [`crate::fit::folds`]),
/// of the residual `resid` (measured − present model's held-out prediction).
pub fn cross_fitted(ds: &Dataset, resid: &[[f64; 4]], folds: &[Vec<usize>], bw: &Bandwidths) -> Vec<FoldCorrection> {
    let x = scaled_points(ds, bw);
    let visit = visits(ds, &x);
    let (x, visit, resid) = (&x, &visit, resid);
    // Folds are independent: one worker per fold.
    std::thread::scope(|sc| {
        let handles: Vec<_> = (0..folds.len())
            .map(|fi| {
                sc.spawn(move || {
                    let train = crate::fit::training(folds, fi);
                    let index = NeighbourIndex::new(x, &train);
                    (0..ds.len()).map(|k| smooth_at(ds, x, visit, resid, &index, k)).collect::<FoldCorrection>()
                })
            })
            .collect();
        // A worker only panics on a bug; surface it.
        handles.into_iter().map(|h| h.join().expect("form-error worker")).collect()
    })
}

/// The correction of every point from all other visits (for fits on all sweeps).
pub fn leave_one_sweep_out(ds: &Dataset, resid: &[[f64; 4]], bw: &Bandwidths) -> FoldCorrection {
    let x = scaled_points(ds, bw);
    let visit = visits(ds, &x);
    let all: Vec<usize> = (0..ds.len()).collect();
    let index = NeighbourIndex::new(&x, &all);
    (0..ds.len()).map(|k| smooth_at(ds, &x, &visit, resid, &index, k)).collect()
}

/// The operating point's share of a state variable, to be taken out of a state candidate
/// scored against the form error.
///
/// Scored against measured − model − form error, a state candidate sees only what its state
/// does *beyond* what the operating point predicts of it: the form error is the kernel average
/// of other visits' residuals, and those residuals carry the state effect of those visits. If
/// the candidate is then fitted with its raw state variable z, it must explain θ·(z − E[z | x])
/// with θ·z — its fit is pulled towards zero and explains less than the data show, the more so
/// the more the test plan ties the state to the operating point (a TTC run visits its cells in
/// time order, so temperature and wear grow with the cell). Fitted with z − E[z | x] instead
/// (Robinson's partialling-out), θ is estimated from what varies between visits of one
/// operating point and the evidence counts all of it — and nothing that the operating point
/// alone explains. E[· | x] is the same smoother as the form error's (local-linear, kernels in
/// slip, load, camber, pressure, other visits only), applied to the state variable at every
/// point: it is a covariate, not a measurement, so held-out points may use it.
#[derive(Debug, Clone)]
pub struct PartialOut {
    /// Per point, the smoother's equivalent-kernel weights over other points.
    rows: Vec<Vec<(u32, f32)>>,
}

impl PartialOut {
    /// The smoother's weights at every point of `ds`, over all other visits (as the
    /// correction of a fit on all sweeps, [`leave_one_sweep_out`], draws on them).
    pub fn new(ds: &Dataset, bw: &Bandwidths) -> Self {
        let all: Vec<usize> = (0..ds.len()).collect();
        Self::among(ds, bw, &all)
    }

    /// One smoother per fold, each over the other folds' points only, as that fold's
    /// correction ([`cross_fitted`]) draws on them: held-out points from the training sweeps,
    /// training points from the other training visits. Robinson's partialling takes the
    /// operating point's share out of the state and of the residual with one smoother; with
    /// the state partialled over all visits and the residual over the training ones, a cell
    /// visited twice had its two visits' states contrasted in the fit while their residuals
    /// were not (the held-out visit's residual is not in the fold's correction), and the
    /// fold's coefficient followed the mismatch: on TTC-style runs the two visits of one cell
    /// were predicted one better, one worse by about as much.
    pub fn per_fold(ds: &Dataset, bw: &Bandwidths, folds: &[Vec<usize>]) -> Vec<Self> {
        (0..folds.len()).map(|fi| Self::among(ds, bw, &crate::fit::training(folds, fi))).collect()
    }

    /// The smoother's weights at every point of `ds` over the points `from` (other visits
    /// only).
    fn among(ds: &Dataset, bw: &Bandwidths, from: &[usize]) -> Self {
        use nalgebra::{Matrix6, Vector6};
        let x = scaled_points(ds, bw);
        let visit = visits(ds, &x);
        let index = NeighbourIndex::new(&x, from);
        let row_at = |k: usize| -> Vec<(u32, f32)> {
            let mut near: Vec<(usize, f64, Vector6<f64>)> = Vec::new();
            let mut a = Matrix6::<f64>::zeros();
            for_each_kernel_neighbour(ds, &x, &visit, &index, k, |j, w, z| {
                a += w * z * z.transpose();
                near.push((j, w, z));
            });
            a[(0, 0)] += PRIOR_WEIGHT;
            for i in 1..6 {
                a[(i, i)] += SLOPE_RIDGE;
            }
            // The estimate at k is e₀ᵀA⁻¹Σ w_j z_j v_j: point j's weight is w_j z_jᵀA⁻¹e₀.
            let Some(v) = a.cholesky().map(|c| c.solve(&Vector6::new(1.0, 0.0, 0.0, 0.0, 0.0, 0.0))) else {
                return Vec::new();
            };
            near.into_iter().map(|(j, w, z)| (j as u32, (w * z.dot(&v)) as f32)).filter(|e| e.1 != 0.0).collect()
        };
        let n = ds.len();
        let threads = std::thread::available_parallelism().map_or(1, |t| t.get()).clamp(1, 4);
        let chunk = n.div_ceil(threads).max(1);
        let rows = std::thread::scope(|sc| {
            let handles: Vec<_> = (0..n)
                .step_by(chunk)
                .map(|lo| {
                    let row_at = &row_at;
                    sc.spawn(move || (lo..(lo + chunk).min(n)).map(row_at).collect::<Vec<_>>())
                })
                .collect();
            // A worker only panics on a bug; surface it.
            handles.into_iter().flat_map(|h| h.join().expect("partial-out worker")).collect()
        });
        Self { rows }
    }

    /// E[v | x] at point `k` from the other visits' values (non-finite values count as 0).
    pub fn expected_at<const M: usize>(&self, values: &[[f64; M]], k: usize) -> [f64; M] {
        let mut out = [0.0; M];
        for &(j, w) in self.rows.get(k).map_or(&[][..], |r| r.as_slice()) {
            if let Some(v) = values.get(j as usize) {
                for m in 0..M {
                    if v[m].is_finite() {
                        out[m] += f64::from(w) * v[m];
                    }
                }
            }
        }
        out
    }

    /// v − E[v | x] at every point.
    pub fn residualized(&self, values: &[f64]) -> Vec<f64> {
        let wrapped: Vec<[f64; 1]> = values.iter().map(|&v| [v]).collect();
        (0..values.len()).map(|k| self.residual_at(&wrapped, k)[0]).collect()
    }

    /// v − E[v | x] at point `k` (a non-finite value counts as 0, as in [`Self::expected_at`]).
    pub fn residual_at<const M: usize>(&self, values: &[[f64; M]], k: usize) -> [f64; M] {
        let e = self.expected_at(values, k);
        let v = values.get(k).copied().unwrap_or([0.0; M]);
        std::array::from_fn(|m| if v[m].is_finite() { v[m] - e[m] } else { -e[m] })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::data::{Series, SweepInfo};

    /// Appends a slip-angle sweep at `fz` (slip angles 0.1° apart over `alphas`), each
    /// point's residual from its slip angle.
    fn push_sweep(
        (ds, s, resid): (&mut Dataset, &mut Series, &mut Vec<[f64; 4]>),
        fz: f64,
        alphas: std::ops::RangeInclusive<f64>,
        residual: impl Fn(f64) -> [f64; 4],
    ) {
        let sweep = ds.sweeps.len();
        let n = ((alphas.end() - alphas.start()) / 0.1).round() as usize;
        for j in 0..=n {
            let a = alphas.start() + 0.1 * j as f64;
            ds.points.push(s.alpha_deg.len());
            s.alpha_deg.push(a);
            s.kappa.push(0.0);
            s.fz_n.push(fz);
            s.gamma_deg.push(0.0);
            s.p_pa.push(2.5e5);
            s.sweep.push(sweep);
            resid.push(residual(a));
        }
        ds.sweeps.push(SweepInfo {
            name: format!("sw{sweep}"),
            index_in_log: sweep as u32,
            log: "t".into(),
            ordinal: sweep,
            coupled: false,
        });
    }

    /// Six slip-angle sweeps, two at each of three loads, with a residual that is a fixed
    /// function of slip angle and load (the form error) plus, in the last sweep only, a
    /// sweep-long offset (a state effect).
    fn dataset() -> (Dataset, Vec<[f64; 4]>) {
        let mut ds = Dataset::default();
        let mut s = Series::default();
        let mut resid = Vec::new();
        let form = |a: f64, fz: f64| 30.0 * (a / 4.0).sin() * fz / 1000.0;
        for sweep in 0..6 {
            let fz = 1000.0 * (1 + sweep % 3) as f64;
            let state = if sweep == 5 { 50.0 } else { 0.0 };
            push_sweep((&mut ds, &mut s, &mut resid), fz, -10.0..=10.0, |a| {
                [form(a, fz) + state, form(a, fz), f64::NAN, 0.0]
            });
        }
        ds.series = s;
        (ds, resid)
    }

    #[test]
    fn the_neighbour_index_finds_every_point_within_the_cut_off() {
        // Points scattered over a few levels in every dimension; the index must return a
        // superset of the brute-force neighbours within the cut-off.
        let mut x = Vec::new();
        let mut seed = 7u64;
        let mut rnd = || {
            seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (seed >> 11) as f64 / (1u64 << 53) as f64
        };
        for _ in 0..600 {
            x.push([40.0 * rnd() - 20.0, 10.0 * rnd() - 5.0, (4.0 * rnd()).floor(), rnd() - 0.5, 2.0 * rnd()]);
        }
        let all: Vec<usize> = (0..x.len()).collect();
        let index = NeighbourIndex::new(&x, &all);
        for k in 0..x.len() {
            let mut found = Vec::new();
            index.for_each_near(&x[k], |j| found.push(j));
            for j in 0..x.len() {
                let d2: f64 = (0..5).map(|m| (x[j][m] - x[k][m]).powi(2)).sum();
                if d2 <= MAX_D2 {
                    assert!(found.contains(&j), "point {j} within the cut-off of {k} not found");
                }
            }
        }
    }

    #[test]
    fn bandwidths_follow_the_visited_levels() {
        let (ds, _) = dataset();
        let bw = Bandwidths::from_data(&ds);
        assert!((bw.fz_n - 1000.0).abs() < 1.0, "{bw:?}");
        assert!(bw.gamma_deg > 100.0 && bw.p_pa > 1e7, "one level: a wide kernel ({bw:?})");
    }

    #[test]
    fn other_sweeps_give_the_form_error_but_not_a_sweep_s_own_offset() {
        let (ds, resid) = dataset();
        let corr = leave_one_sweep_out(&ds, &resid, &Bandwidths::from_data(&ds));
        let form_only = |k: usize| resid[k][1];
        for (k, c) in corr.iter().enumerate() {
            // Channel 1 has no state effect: the correction reproduces the form error from the
            // other sweeps (interpolating along load at the highest and lowest loads too).
            assert!((c[1] - form_only(k)).abs() < 3.0, "point {k}: {} vs {}", c[1], form_only(k));
            // An all-NaN channel stays uncorrected, not NaN.
            assert_eq!(c[2], 0.0);
        }
        // Channel 0 of the last sweep keeps its own +50 N: the correction there is the form
        // error (its twin sweep at the same load has no offset).
        for k in (0..ds.len()).filter(|&k| ds.point_sweep(k) == 5) {
            let left = resid[k][0] - corr[k][0];
            assert!((left - 50.0).abs() < 5.0, "point {k}: {left} of the sweep's 50 N left");
        }
    }

    #[test]
    fn partialling_out_keeps_only_what_varies_between_visits_of_one_operating_point() {
        // A state that is a smooth function of load (as temperature is on a plan that heats
        // more at higher loads) plus, in the last sweep only, a visit of its own (that sweep
        // ran hotter than its twin at the same load).
        let (ds, _) = dataset();
        let fz = |k: usize| ds.series.fz_n[ds.points[k]];
        let z: Vec<f64> =
            (0..ds.len()).map(|k| 0.01 * fz(k) + if ds.point_sweep(k) == 5 { 5.0 } else { 0.0 }).collect();
        let po = PartialOut::new(&ds, &Bandwidths::from_data(&ds));
        let left = po.residualized(&z);
        for (k, &left_k) in left.iter().enumerate() {
            let (sweep, mid) = (ds.point_sweep(k), ds.series.alpha_deg[ds.points[k]].abs() < 5.0);
            if !mid {
                continue;
            }
            match sweep {
                // Its twin (sweep 2) says what the load predicts: the sweep's own +5 is left.
                5 => assert!((left_k - 5.0).abs() < 1.0, "point {k}: {left_k} of the visit's own 5 left"),
                // The twin of sweep 5 takes most of that offset as its expectation (−5..0).
                2 => assert!((-5.0..0.0).contains(&left_k), "point {k}: {left_k}"),
                // The state itself is 10–30 there: all of it the load's.
                _ => assert!(left_k.abs() < 1.2, "point {k}: the load's share was not taken out ({left_k})"),
            }
        }
    }

    #[test]
    fn sweeps_of_one_visit_do_not_correct_each_other() {
        // Sweeps 0–2 at one cell in a row (a warm-up) share a +40 N state offset; sweep 3 at
        // another load, sweep 4 at the first cell again without it.
        let mut ds = Dataset::default();
        let mut s = Series::default();
        let mut resid = Vec::new();
        for (fz, offset) in [(1000.0, 40.0), (1000.0, 40.0), (1000.0, 40.0), (2000.0, 0.0), (1000.0, 0.0)] {
            push_sweep((&mut ds, &mut s, &mut resid), fz, -5.0..=5.0, |_| [offset, 0.0, 0.0, 0.0]);
        }
        ds.series = s;
        let bw = Bandwidths::from_data(&ds);
        assert_eq!(visits(&ds, &scaled_points(&ds, &bw)), vec![0, 0, 0, 3, 4]);
        let corr = leave_one_sweep_out(&ds, &resid, &bw);
        for k in (0..ds.len()).filter(|&k| ds.point_sweep(k) < 3) {
            assert!(
                resid[k][0] - corr[k][0] > 30.0,
                "point {k}: the warm-up's own offset was absorbed ({})",
                corr[k][0]
            );
        }
    }

    #[test]
    fn held_out_points_are_corrected_from_training_sweeps_only() {
        let (ds, resid) = dataset();
        let held_out: Vec<usize> = (0..ds.len()).filter(|&k| ds.point_sweep(k) < 3).collect();
        let folds = vec![held_out.clone(), (0..ds.len()).filter(|&k| ds.point_sweep(k) >= 3).collect()];
        let bw = Bandwidths::from_data(&ds);
        let a = cross_fitted(&ds, &resid, &folds, &bw);
        // Whatever the held-out sweeps measured, their correction is the same.
        let mut changed = resid.clone();
        for &k in &held_out {
            changed[k][0] += 1000.0;
        }
        let b = cross_fitted(&ds, &changed, &folds, &bw);
        for &k in &held_out {
            assert_eq!(a[0][k][0], b[0][k][0], "held-out point {k} saw held-out data");
        }
        // Fold 1 held out (sweeps 3–5, trained on 0–2 that carry no offset): the form error.
        for k in (0..ds.len()).filter(|&k| ds.point_sweep(k) == 5) {
            assert!((a[1][k][0] - resid[k][1]).abs() < 3.0, "point {k}: {} vs {}", a[1][k][0], resid[k][1]);
        }
    }

    #[test]
    fn a_fold_partials_the_state_over_its_training_points_as_its_correction_does() {
        // The state and the residual are one and the same series: partialled per fold, the
        // state's operating-point share at every point must be exactly the fold's correction
        // of the residual (one smoother for both, Robinson), and never drawn from the fold's
        // held-out points.
        let (ds, resid) = dataset();
        let held_out: Vec<usize> = (0..ds.len()).filter(|&k| ds.point_sweep(k) % 2 == 0).collect();
        let folds = vec![held_out.clone(), (0..ds.len()).filter(|&k| ds.point_sweep(k) % 2 == 1).collect()];
        let bw = Bandwidths::from_data(&ds);
        let corr = cross_fitted(&ds, &resid, &folds, &bw);
        let per_fold = PartialOut::per_fold(&ds, &bw, &folds);
        let z: Vec<[f64; 1]> = resid.iter().map(|r| [r[0]]).collect();
        for (fi, po) in per_fold.iter().enumerate() {
            for (k, c) in corr[fi].iter().enumerate() {
                let e = po.expected_at(&z, k)[0];
                assert!((e - c[0]).abs() < 1e-3 * (1.0 + e.abs()), "fold {fi}, point {k}: {e} vs {}", c[0]);
            }
        }
        // Whatever the held-out sweeps' state, fold 0's expectation does not move.
        let mut changed = z.clone();
        for &k in &held_out {
            changed[k][0] += 1000.0;
        }
        for k in 0..ds.len() {
            assert_eq!(per_fold[0].expected_at(&z, k), per_fold[0].expected_at(&changed, k), "point {k}");
        }
        // The smoother over all visits does draw on them.
        let all = PartialOut::new(&ds, &bw);
        assert!((0..ds.len()).any(|k| all.expected_at(&z, k) != all.expected_at(&changed, k)));
    }
}

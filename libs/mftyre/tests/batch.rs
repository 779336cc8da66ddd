//! The lane-wise batch kernel against the scalar reference `evaluate`, point by point.

mod common;

use common::{column, sample_tyre};
use mftyre::{
    BatchColumn, BatchInput, BatchOutput, MfInput, MfOutput, UseMode, evaluate, evaluate_batch, evaluate_column,
    pure_fy, pure_fy_batch,
};

const COLUMNS: &[&str] = &[
    "Fx", "Fy", "Fz", "Mx", "My", "Mz", "kappa", "alpha", "gamma", "phit", "Vx", "P", "Re", "rho", "2a", "t", "mux",
    "muy", "omega", "Rl", "2b", "Mzr", "Cx", "Cy", "Cz", "Kya", "sigmax", "sigmay", "Kxk",
];

const MODES: [UseMode; 8] = [
    UseMode::M111,
    UseMode::M112,
    UseMode::M121,
    UseMode::M122,
    UseMode::M211,
    UseMode::M212,
    UseMode::M221,
    UseMode::M222,
];

struct Lcg(u64);

impl Lcg {
    fn range(&mut self, lo: f64, hi: f64) -> f64 {
        self.0 = self.0.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        lo + (hi - lo) * ((self.0 >> 11) as f64 / (1u64 << 53) as f64)
    }
    fn pick(&mut self, v: &[f64]) -> f64 {
        v[(self.range(0.0, v.len() as f64) as usize).min(v.len() - 1)]
    }
}

/// Random points over (and beyond) the valid box, with special values mixed in, and short
/// sweeps so that the load-case cache is exercised.
fn points(n: usize, seed: u64) -> Vec<MfInput> {
    let mut r = Lcg(seed);
    let mut v = Vec::with_capacity(n);
    while v.len() < n {
        let special = r.range(0.0, 1.0) < 0.3;
        let mut x = MfInput {
            fz_n: r.range(-500.0, 20000.0),
            kappa: r.range(-1.2, 1.2),
            alpha_rad: r.range(-1.0, 1.0),
            gamma_rad: r.range(-0.12, 0.12),
            phit_per_m: 0.0,
            vx_mps: r.range(-60.0, 60.0),
            p_pa: if r.range(0.0, 1.0) < 0.2 { 0.0 } else { r.range(1.5e5, 4.5e5) },
            omega_radps: if r.range(0.0, 1.0) < 0.5 { 0.0 } else { r.range(1.0, 200.0) },
        };
        if special {
            x.fz_n = r.pick(&[0.0, 1e-9, 50.0, 18000.0, 40000.0, -5.0, x.fz_n]);
            x.kappa = r.pick(&[0.0, -1.0, 1.0, -3.0, 1e-12, x.kappa]);
            x.alpha_rad = r.pick(&[0.0, 0.96, -0.96, 1.5, -1e-12, x.alpha_rad]);
            x.gamma_rad = r.pick(&[0.0, 0.105, -0.5, x.gamma_rad]);
            x.vx_mps = r.pick(&[0.0, 1e-9, -0.5, 0.9, 1.0, -30.0, x.vx_mps]);
            x.phit_per_m = r.pick(&[0.0, 0.1]);
        }
        // A short sweep: same load case, varying slip.
        let len = if r.range(0.0, 1.0) < 0.2 { (r.range(2.0, 13.0)) as usize } else { 1 };
        for j in 0..len {
            let mut y = x;
            if j > 0 {
                y.kappa = r.range(-0.5, 0.5);
                y.alpha_rad = r.range(-0.5, 0.5);
            }
            v.push(y);
        }
    }
    v.truncate(n);
    v
}

fn columns(pts: &[MfInput]) -> [Vec<f64>; 8] {
    let mut c: [Vec<f64>; 8] = Default::default();
    for x in pts {
        for (col, v) in
            c.iter_mut().zip([x.fz_n, x.kappa, x.alpha_rad, x.gamma_rad, x.phit_per_m, x.vx_mps, x.p_pa, x.omega_radps])
        {
            col.push(v);
        }
    }
    c
}

fn input_of(c: &[Vec<f64>; 8]) -> BatchInput<'_> {
    BatchInput {
        fz_n: &c[0],
        kappa: &c[1],
        alpha_rad: &c[2],
        gamma_rad: &c[3],
        phit_per_m: &c[4],
        vx_mps: &c[5],
        p_pa: &c[6],
        omega_radps: &c[7],
    }
}

/// Largest relative difference per column, with an absolute floor of `floor` × the column's
/// largest magnitude (differences near a zero crossing).
fn compare(want: &[MfOutput], got: &BatchOutput, rel: f64, floor: f64, what: &str) {
    assert_eq!(got.len(), want.len(), "{what}: length");
    for name in COLUMNS {
        let scale = want.iter().map(|o| column(o, name).abs()).filter(|v| v.is_finite()).fold(0.0, f64::max);
        let mut worst = 0.0_f64;
        for (i, w) in want.iter().enumerate() {
            let g = got.get(i).expect("point");
            let (a, b) = (column(&g, name), column(w, name));
            if a.to_bits() == b.to_bits() || (a.is_nan() && b.is_nan()) {
                continue;
            }
            let d = (a - b).abs();
            assert!(
                d <= rel * b.abs() || d <= floor * scale,
                "{what} point {i} {name}: batch {a:e}, scalar {b:e} (diff {d:e}) at {:?}",
                want[i]
            );
            worst = worst.max(d / b.abs().max(floor * scale / rel));
            assert_eq!(g.clamped, w.clamped, "{what} point {i}: flags");
        }
        println!("{what:<6} {name:<7} max rel diff {worst:9.2e}");
    }
}

#[test]
fn batch_equals_scalar_evaluation_in_every_mode() {
    let params = sample_tyre();
    let pts = points(20_011, 7);
    let cols = columns(&pts);
    let mut out = BatchOutput::default();
    for mode in MODES {
        evaluate_batch(&params, mode, &input_of(&cols), &mut out).expect("lengths");
        let want: Vec<MfOutput> = pts.iter().map(|x| evaluate(&params, mode, x)).collect();
        compare(&want, &out, 1e-13, 1e-13, &mode.to_string());
    }
}

#[test]
fn pure_fy_batch_equals_scalar() {
    let params = sample_tyre();
    let pts = points(10_003, 11);
    let cols = columns(&pts);
    let mut fy = Vec::new();
    for mode in MODES {
        pure_fy_batch(&params, mode, &input_of(&cols), &mut fy).expect("lengths");
        let scale = pts.iter().map(|x| pure_fy(&params, mode, x).abs()).fold(0.0, f64::max);
        for (x, got) in pts.iter().zip(&fy) {
            let want = pure_fy(&params, mode, x);
            let d = (got - want).abs();
            assert!(d <= 1e-13 * want.abs() || d <= 1e-14 * scale, "{mode} {x:?}: {got:e} vs {want:e}");
        }
    }
}

/// Each single-column evaluation gives its column of the full evaluation, in every mode, on
/// points over and beyond the valid box: the output masks skip work, never change a value.
#[test]
fn single_columns_equal_the_full_evaluation_in_every_mode() {
    let params = sample_tyre();
    let pts = points(20_011, 13);
    let cols = columns(&pts);
    let mut full = BatchOutput::default();
    let mut one = Vec::new();
    let all = [
        BatchColumn::FxN,
        BatchColumn::FyN,
        BatchColumn::MzNm,
        BatchColumn::MxNm,
        BatchColumn::MyNm,
        BatchColumn::ReM,
        BatchColumn::RlM,
        BatchColumn::CxNpm,
        BatchColumn::SigmayM,
    ];
    for mode in MODES {
        evaluate_batch(&params, mode, &input_of(&cols), &mut full).expect("lengths");
        for column in all {
            evaluate_column(&params, mode, &input_of(&cols), column, &mut one).expect("lengths");
            let want = match column {
                BatchColumn::FxN => &full.fx_n,
                BatchColumn::FyN => &full.fy_n,
                BatchColumn::MzNm => &full.mz_nm,
                BatchColumn::MxNm => &full.mx_nm,
                BatchColumn::MyNm => &full.my_nm,
                BatchColumn::ReM => &full.re_m,
                BatchColumn::RlM => &full.rl_m,
                BatchColumn::CxNpm => &full.cx_npm,
                BatchColumn::SigmayM => &full.sigmay_m,
            };
            assert_eq!(one.len(), want.len(), "{mode} {column:?}: length");
            let scale = want.iter().filter(|v| v.is_finite()).fold(0.0_f64, |m, v| m.max(v.abs()));
            let mut identical = 0;
            for (i, (a, b)) in one.iter().zip(want).enumerate() {
                if a.to_bits() == b.to_bits() || (a.is_nan() && b.is_nan()) {
                    identical += 1;
                    continue;
                }
                // A chunk the full evaluation handed to the scalar model (some other output left
                // the fast ranges) differs by a few ulp.
                let d = (a - b).abs();
                assert!(d <= 1e-13 * b.abs() || d <= 1e-13 * scale, "{mode} {column:?} point {i}: {a:e} vs {b:e}");
            }
            assert!(
                identical * 10 >= one.len() * 9,
                "{mode} {column:?}: only {identical} of {} bit-identical",
                one.len()
            );
        }
    }
}

#[test]
fn empty_columns_and_short_batches() {
    let params = sample_tyre();
    let mut out = BatchOutput::default();
    for n in [0, 1, 2, 3, 5, 9] {
        let fz: Vec<f64> = (0..n).map(|i| 3000.0 + 500.0 * i as f64).collect();
        let alpha: Vec<f64> = (0..n).map(|i| 0.01 * i as f64).collect();
        let vx = vec![16.6; n];
        let inp = BatchInput { fz_n: &fz, alpha_rad: &alpha, vx_mps: &vx, ..Default::default() };
        evaluate_batch(&params, UseMode::M111, &inp, &mut out).expect("lengths");
        let want: Vec<MfOutput> = (0..n).map(|i| evaluate(&params, UseMode::M111, &inp.point(i))).collect();
        compare(&want, &out, 1e-13, 1e-13, "short");
    }
}

/// Arguments outside the lane functions' fast ranges (huge angles) send their chunk through the
/// scalar model: those points equal `evaluate` bit for bit. Non-finite inputs give NaN where the
/// scalar model does, and the rest of the batch is unaffected.
#[test]
fn out_of_range_lanes_fall_back_to_the_scalar_model() {
    let params = sample_tyre();
    let mut pts = points(64, 3);
    pts[5].alpha_rad = 3.0e6;
    pts[17].gamma_rad = -2.0e5;
    pts[30].vx_mps = f64::NAN;
    pts[41].kappa = f64::INFINITY;
    pts[63].fz_n = 1e300;
    let cols = columns(&pts);
    let mut out = BatchOutput::default();
    for mode in [UseMode::M211, UseMode::M221, UseMode::M111] {
        evaluate_batch(&params, mode, &input_of(&cols), &mut out).expect("lengths");
        if !mode.limits_check() {
            for i in [5, 17] {
                let want = evaluate(&params, mode, &pts[i]);
                assert_eq!(format!("{:?}", out.get(i).expect("point")), format!("{want:?}"), "{mode} point {i}");
            }
        }
        let want: Vec<MfOutput> = pts.iter().map(|x| evaluate(&params, mode, x)).collect();
        compare(&want, &out, 1e-13, 1e-13, &mode.to_string());
    }
}

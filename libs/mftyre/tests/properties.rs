//! Property tests over the valid input box of the sample tyre.

mod common;

use mftyre::{MfInput, MfOutput, TyreParams, UseMode, evaluate};
use proptest::prelude::*;

fn params() -> &'static TyreParams {
    static P: std::sync::OnceLock<TyreParams> = std::sync::OnceLock::new();
    P.get_or_init(common::sample_tyre)
}

fn symmetric() -> &'static TyreParams {
    static P: std::sync::OnceLock<TyreParams> = std::sync::OnceLock::new();
    P.get_or_init(|| common::sample_tyre().symmetric_copy())
}

fn all_finite(o: &MfOutput) -> bool {
    [
        o.fx_n,
        o.fy_n,
        o.fz_n,
        o.mx_nm,
        o.my_nm,
        o.mz_nm,
        o.kappa,
        o.re_m,
        o.rho_m,
        o.contact_length_m,
        o.trail_m,
        o.mux,
        o.muy,
        o.omega_radps,
        o.rl_m,
        o.contact_width_m,
        o.mzr_nm,
        o.cx_npm,
        o.cy_npm,
        o.cz_npm,
        o.kya_nprad,
        o.sigmax_m,
        o.sigmay_m,
        o.kxk_n,
    ]
    .iter()
    .all(|v| v.is_finite())
}

fn modes() -> impl Strategy<Value = UseMode> {
    prop_oneof![
        Just(UseMode::M111),
        Just(UseMode::M112),
        Just(UseMode::M121),
        Just(UseMode::M122),
        Just(UseMode::M211),
        Just(UseMode::M221),
    ]
}

/// The `.tir` validity box (FZMIN..FZMAX etc.), speeds from standstill to 60 m/s either way,
/// pressure including 0 (= INFLPRES) and both given and estimated Ω.
fn valid_input() -> impl Strategy<Value = MfInput> {
    (
        0.0..18000.0_f64,
        -1.0..1.0_f64,
        -0.96..0.96_f64,
        -0.105..0.105_f64,
        -60.0..60.0_f64,
        prop_oneof![Just(0.0), 200000.0..400000.0_f64],
        prop_oneof![Just(0.0), 1.0..200.0_f64],
    )
        .prop_map(|(fz, kappa, alpha, gamma, vx, p, omega)| MfInput {
            fz_n: fz,
            kappa,
            alpha_rad: alpha,
            gamma_rad: gamma,
            phit_per_m: 0.0,
            vx_mps: vx,
            p_pa: p,
            omega_radps: omega,
        })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(4000))]

    #[test]
    fn pure_entry_points_equal_the_full_evaluation(x in valid_input(), mode in modes()) {
        let full = evaluate(params(), mode.pure(), &x);
        prop_assert_eq!(mftyre::pure_fx(params(), mode, &x).to_bits(), full.fx_n.to_bits());
        prop_assert_eq!(mftyre::pure_fy(params(), mode, &x).to_bits(), full.fy_n.to_bits());
    }

    #[test]
    fn outputs_are_finite_over_the_valid_box(x in valid_input(), mode in modes()) {
        let o = evaluate(params(), mode, &x);
        prop_assert!(all_finite(&o), "{x:?} {mode}: {o:?}");
    }

    #[test]
    fn outputs_are_finite_at_the_corners_and_beyond(
        fz in prop_oneof![Just(0.0), Just(1e-9), Just(18000.0), Just(-5.0), Just(40000.0)],
        kappa in prop_oneof![Just(-1.0), Just(0.0), Just(1.0), Just(-3.0), Just(5.0)],
        alpha in prop_oneof![Just(-0.96), Just(0.0), Just(0.96), Just(1.5)],
        gamma in prop_oneof![Just(-0.105), Just(0.0), Just(0.105), Just(0.5)],
        vx in prop_oneof![Just(0.0), Just(1e-9), Just(-0.5), Just(1.0), Just(16.6), Just(-30.0)],
        mode in prop_oneof![Just(UseMode::M111), Just(UseMode::M121), Just(UseMode::M112)],
    ) {
        let x = MfInput { fz_n: fz, kappa, alpha_rad: alpha, gamma_rad: gamma, vx_mps: vx, ..Default::default() };
        let o = evaluate(params(), mode, &x);
        prop_assert!(all_finite(&o), "{x:?} {mode}: {o:?}");
    }

    /// With the asymmetric coefficients zeroed, pure-slip curves are odd in α (at γ = 0)
    /// and Fx is odd in κ.
    #[test]
    fn pure_slip_is_symmetric_for_symmetric_params(
        fz in 500.0..18000.0_f64,
        alpha in 0.0..0.96_f64,
        kappa in 0.0..1.0_f64,
        p in 200000.0..400000.0_f64,
        mode in prop_oneof![Just(UseMode::M111), Just(UseMode::M121)],
    ) {
        let s = symmetric();
        let base = MfInput { fz_n: fz, vx_mps: 16.6, p_pa: p, ..Default::default() };
        let fy_pos = evaluate(s, mode, &MfInput { alpha_rad: alpha, ..base });
        let fy_neg = evaluate(s, mode, &MfInput { alpha_rad: -alpha, ..base });
        let tol_f = 1e-9 * fz;
        prop_assert!((fy_pos.fy_n + fy_neg.fy_n).abs() <= tol_f, "Fy {} vs {}", fy_pos.fy_n, fy_neg.fy_n);
        prop_assert!((fy_pos.mz_nm + fy_neg.mz_nm).abs() <= tol_f, "Mz {} vs {}", fy_pos.mz_nm, fy_neg.mz_nm);
        prop_assert!((fy_pos.mx_nm + fy_neg.mx_nm).abs() <= tol_f, "Mx {} vs {}", fy_pos.mx_nm, fy_neg.mx_nm);
        prop_assert!(fy_pos.fx_n.abs() <= tol_f);
        let fx_pos = evaluate(s, mode, &MfInput { kappa, ..base });
        let fx_neg = evaluate(s, mode, &MfInput { kappa: -kappa, ..base });
        prop_assert!((fx_pos.fx_n + fx_neg.fx_n).abs() <= tol_f, "Fx {} vs {}", fx_pos.fx_n, fx_neg.fx_n);
        prop_assert!(fx_pos.fy_n.abs() <= tol_f);
    }

    /// Combined slip never produces more force than the same slip in pure form.
    ///
    /// Two precise caveats of MF 6.1 itself: the κ-induced side force SVyκ is an offset, not a
    /// reduction, so it is switched off (LVYKA = 0) for the Fy comparison; and the weighting
    /// functions are shifted (SHxα = RHX1, SHyκ = RHY1 + RHY2·dfz), so G exceeds 1 by at most
    /// 1/G0 − 1 (< 1 % here) inside the band |slip + shift| < |shift|. Outside that band the
    /// bound is strict.
    #[test]
    fn combined_forces_do_not_exceed_pure_ones(
        fz in 500.0..18000.0_f64,
        kappa in -1.0..1.0_f64,
        alpha in -0.96..0.96_f64,
        gamma in -0.105..0.105_f64,
        p in 200000.0..400000.0_f64,
    ) {
        let pr = params();
        let mut s = pr.scaling;
        s.lvyka = 0.0;
        let x = MfInput { fz_n: fz, kappa, alpha_rad: alpha, gamma_rad: gamma, vx_mps: 16.6, p_pa: p, ..Default::default() };
        let combined = mftyre::evaluate_scaled(pr, &s, UseMode::M111, &x);
        let pure = mftyre::evaluate_scaled(pr, &s, UseMode::M112, &x);
        let shxa = pr.combined.rhx1;
        let dfz = (fz - pr.fnomin_n()) / pr.fnomin_n();
        let shyk = pr.combined.rhy1 + pr.combined.rhy2 * dfz;
        let fx_factor = if (alpha + shxa).abs() >= shxa.abs() { 1.0 + 1e-12 } else { 1.01 };
        let fy_factor = if (kappa + shyk).abs() >= shyk.abs() { 1.0 + 1e-12 } else { 1.01 };
        prop_assert!(combined.fx_n.abs() <= pure.fx_n.abs() * fx_factor + 1e-9,
            "Fx combined {} > pure {}", combined.fx_n, pure.fx_n);
        prop_assert!(combined.fy_n.abs() <= pure.fy_n.abs() * fy_factor + 1e-9,
            "Fy combined {} > pure {}", combined.fy_n, pure.fy_n);
        // With SVyκ back in (at most ~15 % of μy·Fz for this tyre at full camber), |Fy| stays
        // near the friction limit of pure cornering.
        let full = evaluate(pr, UseMode::M111, &x);
        prop_assert!(full.fy_n.abs() <= 1.25 * pure.muy * fz,
            "Fy with SVyk {} vs muy*Fz {}", full.fy_n, pure.muy * fz);
    }
}

/// With κ = 0, SVyκ vanishes and Gyκ = 1: combined Fy equals pure Fy.
#[test]
fn combined_equals_pure_without_the_other_slip() {
    let p = params();
    for alpha in [-0.3, -0.05, 0.0, 0.02, 0.2] {
        let x = MfInput { fz_n: 6752.0, alpha_rad: alpha, vx_mps: 16.6, ..Default::default() };
        let c = evaluate(p, UseMode::M111, &x);
        let q = evaluate(p, UseMode::M112, &x);
        assert!((c.fy_n - q.fy_n).abs() <= 1e-9 * 6752.0, "{alpha}: {} vs {}", c.fy_n, q.fy_n);
    }
}

#[test]
fn limits_are_clamped_and_flagged() {
    let p = params();
    let x = MfInput {
        fz_n: 30000.0,
        alpha_rad: 1.2,
        kappa: 2.0,
        gamma_rad: 0.3,
        p_pa: 500000.0,
        vx_mps: 16.6,
        ..Default::default()
    };
    let o = evaluate(p, UseMode::M111, &x);
    use mftyre::Clamped;
    for flag in [Clamped::FZ, Clamped::ALPHA, Clamped::KAPPA, Clamped::GAMMA, Clamped::PRESSURE] {
        assert!(o.clamped.contains(flag), "{flag:?} not set: {:?}", o.clamped);
    }
    assert_eq!(o.p_pa, 400000.0);
    let at_limit = evaluate(
        p,
        UseMode::M111,
        &MfInput {
            fz_n: 18000.0,
            alpha_rad: 0.96,
            kappa: 1.0,
            gamma_rad: 0.105,
            p_pa: 400000.0,
            vx_mps: 16.6,
            ..Default::default()
        },
    );
    assert_eq!(o.fy_n, at_limit.fy_n);
    let unclamped = evaluate(p, UseMode::M211, &x);
    assert!(unclamped.clamped.is_empty());
    let slow = evaluate(p, UseMode::M111, &MfInput { fz_n: 5000.0, vx_mps: 0.5, ..Default::default() });
    assert!(slow.clamped.contains(Clamped::LOW_SPEED));
    let standstill = evaluate(
        p,
        UseMode::M111,
        &MfInput { fz_n: 5000.0, vx_mps: 0.0, kappa: 0.1, alpha_rad: 0.1, ..Default::default() },
    );
    assert!(all_finite(&standstill), "{standstill:?}");
}

#[test]
fn spot_values_from_the_reference_readme() {
    let p = params();
    let o = evaluate(
        p,
        UseMode::M111,
        &MfInput { fz_n: 6752.0, alpha_rad: 4f64.to_radians(), vx_mps: 16.6, p_pa: 260000.0, ..Default::default() },
    );
    assert!((o.fy_n - -6320.515).abs() < 1e-3, "{}", o.fy_n);
    assert!((o.mz_nm - 65.295).abs() < 1e-3, "{}", o.mz_nm);
    assert!((o.mx_nm - 47.392).abs() < 1e-3, "{}", o.mx_nm);
    assert!((o.my_nm - -27.744).abs() < 1e-3, "{}", o.my_nm);
    assert!((o.fx_n - -29.72).abs() < 1e-2, "{}", o.fx_n);
    let o = evaluate(
        p,
        UseMode::M111,
        &MfInput { fz_n: 6752.0, kappa: 0.1, vx_mps: 16.6, p_pa: 260000.0, ..Default::default() },
    );
    assert!((o.fx_n - 8308.06).abs() < 1e-2, "{}", o.fx_n);
}

#[test]
fn evaluate_scaled_uses_the_given_scaling() {
    let p = params();
    let x = MfInput { fz_n: 6752.0, alpha_rad: 0.3, vx_mps: 16.6, ..Default::default() };
    let mut s = p.scaling;
    s.lmuy = 0.8;
    let a = mftyre::evaluate_scaled(p, &s, UseMode::M111, &x);
    let mut q = p.clone();
    q.scaling.lmuy = 0.8;
    let b = evaluate(&q, UseMode::M111, &x);
    assert_eq!(a, b);
    assert!(a.fy_n.abs() < evaluate(p, UseMode::M111, &x).fy_n.abs());
}

#[test]
fn batch_matches_single_point_evaluation() {
    let p = params();
    let fz = [3000.0, 6752.0, 9000.0];
    let kappa = [0.0, 0.05, -0.1];
    let alpha = [0.1, -0.05, 0.0];
    let vx = [16.6, 16.6, 30.0];
    let inputs = mftyre::BatchInput { fz_n: &fz, kappa: &kappa, alpha_rad: &alpha, vx_mps: &vx, ..Default::default() };
    let mut out = mftyre::BatchOutput::default();
    mftyre::evaluate_batch(p, UseMode::M111, &inputs, &mut out).expect("lengths agree");
    assert_eq!(out.len(), 3);
    for i in 0..3 {
        let single = evaluate(p, UseMode::M111, &inputs.point(i));
        assert_close(&out.get(i).expect("point"), &single, &format!("point {i}"));
    }
    let bad = mftyre::BatchInput { fz_n: &fz, kappa: &kappa[..2], ..Default::default() };
    assert!(mftyre::evaluate_batch(p, UseMode::M111, &bad, &mut out).is_err());
    let mut fy = Vec::new();
    mftyre::pure_fy_batch(p, UseMode::M111, &inputs, &mut fy).expect("ok");
    let want = mftyre::pure_fy(p, UseMode::M111, &inputs.point(0));
    assert!((fy[0] - want).abs() <= 1e-13 * want.abs(), "{} vs {want}", fy[0]);
}

/// The batch kernel uses its own vectorised atan/sin/cos/exp/ln (≤ 2 ulp), so it agrees with
/// the scalar `evaluate` to ~1e-13 relative rather than bit for bit (`tests/batch.rs` checks
/// this over random points in every mode).
fn assert_close(got: &MfOutput, want: &MfOutput, what: &str) {
    const NAMES: &[&str] = &[
        "Fx", "Fy", "Fz", "Mx", "My", "Mz", "kappa", "alpha", "gamma", "phit", "Vx", "P", "Re", "rho", "2a", "t",
        "mux", "muy", "omega", "Rl", "2b", "Mzr", "Cx", "Cy", "Cz", "Kya", "sigmax", "sigmay", "Kxk",
    ];
    for name in NAMES {
        let (a, b) = (common::column(got, name), common::column(want, name));
        let d = (a - b).abs();
        assert!(a.to_bits() == b.to_bits() || d <= 1e-13 * b.abs() || d <= 1e-12, "{what} {name}: {a:e} vs {b:e}");
    }
    assert_eq!(got.clamped, want.clamped, "{what}: flags");
}

#[test]
fn use_mode_parses() {
    assert_eq!("111".parse::<UseMode>(), Ok(UseMode::M111));
    assert_eq!("121".parse::<UseMode>(), Ok(UseMode::M121));
    assert!("113".parse::<UseMode>().is_err());
    assert_eq!(UseMode::M121.to_string(), "121");
}

/// Batches reuse load-case terms across a sweep; the result must equal the same batch kernel
/// run on each point alone bit for bit (MFeval's grid is made of such sweeps), and the scalar
/// evaluation to ~1e-13.
#[test]
fn batch_over_sweeps_equals_single_points_exactly() {
    let p = params();
    let table = common::read_table("mf61_reference_inputs.csv");
    let points = common::inputs_of(&table);
    let col = |f: fn(&MfInput) -> f64| points.iter().map(f).collect::<Vec<_>>();
    let (fz, k, a, g, vx, pr) = (
        col(|x| x.fz_n),
        col(|x| x.kappa),
        col(|x| x.alpha_rad),
        col(|x| x.gamma_rad),
        col(|x| x.vx_mps),
        col(|x| x.p_pa),
    );
    let inputs = mftyre::BatchInput {
        fz_n: &fz,
        kappa: &k,
        alpha_rad: &a,
        gamma_rad: &g,
        vx_mps: &vx,
        p_pa: &pr,
        ..Default::default()
    };
    for mode in [UseMode::M111, UseMode::M121, UseMode::M112] {
        let mut out = mftyre::BatchOutput::default();
        mftyre::evaluate_batch(p, mode, &inputs, &mut out).expect("lengths");
        let mut one = mftyre::BatchOutput::default();
        for (i, x) in points.iter().enumerate() {
            let single = [x.fz_n, x.kappa, x.alpha_rad, x.gamma_rad, x.vx_mps, x.p_pa];
            let input = mftyre::BatchInput {
                fz_n: &single[0..1],
                kappa: &single[1..2],
                alpha_rad: &single[2..3],
                gamma_rad: &single[3..4],
                vx_mps: &single[4..5],
                p_pa: &single[5..6],
                ..Default::default()
            };
            mftyre::evaluate_batch(p, mode, &input, &mut one).expect("lengths");
            let got = out.get(i).expect("row");
            assert_eq!(format!("{got:?}"), format!("{:?}", one.get(0).expect("one")), "row {i} mode {mode}");
            assert_close(&got, &evaluate(p, mode, x), &format!("row {i} mode {mode}"));
        }
    }
}

/// The low-speed model joins the normal one continuously at VXLOW and fades forces to zero at
/// standstill.
#[test]
fn low_speed_model_is_continuous_and_fades_out() {
    let p = params();
    let vxlow = p.vxlow_mps();
    let at = |vx: f64| {
        evaluate(
            p,
            UseMode::M111,
            &MfInput { fz_n: 6000.0, kappa: 0.05, alpha_rad: 0.05, gamma_rad: 0.02, vx_mps: vx, ..Default::default() },
        )
    };
    let (below, above) = (at(vxlow * (1.0 - 1e-9)), at(vxlow * (1.0 + 1e-9)));
    for (a, b) in
        [(below.fx_n, above.fx_n), (below.fy_n, above.fy_n), (below.mz_nm, above.mz_nm), (below.my_nm, above.my_nm)]
    {
        assert!((a - b).abs() <= 1e-4 * (1.0 + b.abs()), "{a} vs {b}");
    }
    let stand = at(0.0);
    assert!(stand.fx_n.abs() < 1e-6 && stand.mz_nm.abs() < 1e-6 && stand.my_nm == 0.0, "{stand:?}");
    // No jumps on the way: 1 % speed steps change Fx by well under 5 % of its range.
    let mut prev = at(0.0).fx_n;
    for i in 1..=100 {
        let fx = at(vxlow * i as f64 / 100.0).fx_n;
        assert!(fx.is_finite() && (fx - prev).abs() < 0.05 * above.fx_n.abs(), "Fx jumps at step {i}: {prev} -> {fx}");
        prev = fx;
    }
}

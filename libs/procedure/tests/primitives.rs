//! One test group per sweep primitive: shape, rates, thresholds, saturation, naming.

use procedure::primitives::{self as prim, GraphBlock, StaticDragParams, StepSteerParams, WarmUpParams};
use procedure::sweep::{AsymLevel, CamberCoupling, LoadCoupling, RateLaw, SlipAxis, SlipPath, Trajectory};
use procedure::{RigLimits, RigMode, Setpoint, StepKind};

const EPS: f64 = 1e-9;

fn base() -> Setpoint {
    Setpoint { mode: RigMode::FreeRolling, fz_n: 6000.0, pressure_bar: 2.6, speed_mps: 16.6, ..Setpoint::default() }
}

/// Numerical slip rate of a path at time t.
fn rate_at(p: &SlipPath, t: f64) -> f64 {
    let h = 1e-4;
    ((p.at(t + h) - p.at(t - h)) / (2.0 * h)).abs()
}

#[test]
fn constant_rate_shape_and_duration() {
    let p = SlipPath::full_cycle(10.0, RateLaw::Constant { rate: 4.0 });
    // 0 → −10 → +10 → 0: 40° at 4 °/s.
    assert!((p.duration_s() - 10.0).abs() < EPS);
    assert!((p.at(2.5) + 10.0).abs() < 1e-9);
    assert!((p.at(5.0) - 0.0).abs() < 1e-9);
    assert!((p.at(7.5) - 10.0).abs() < 1e-9);
    assert!(p.at(10.0).abs() < 1e-9);
    assert!(p.at(-1.0).abs() < 1e-9, "clamped before start");
    assert!(p.at(99.0).abs() < 1e-9, "clamped after end");
    for t in [0.3, 1.7, 4.0, 6.2, 9.1] {
        assert!((rate_at(&p, t) - 4.0).abs() < 1e-6);
    }
    assert_eq!(prim::rate_type_name(SlipAxis::SlipAngle, &p.law), "ConstantRate_4");
}

#[test]
fn square_matrix_has_waypoints() {
    let p = SlipPath::new(vec![0.0, -5.0, 28.0, -28.0, 5.0, 0.0], RateLaw::Constant { rate: 12.0 });
    assert!((p.duration_s() - 132.0 / 12.0).abs() < EPS);
    assert!((p.at(5.0 / 12.0) + 5.0).abs() < 1e-9);
    assert!((p.at(38.0 / 12.0) - 28.0).abs() < 1e-9);
    assert_eq!(p.peak_abs(), 28.0);
}

#[test]
fn variable_rate_low_below_threshold_high_beyond() {
    let law = RateLaw::Variable { low_rate: 2.0, high_rate: 30.0, threshold: 4.0 };
    let p = SlipPath::full_cycle(16.0, law);
    // Each of the four half-legs: 4° at 2 °/s + 12° at 30 °/s = 2.4 s.
    assert!((p.duration_s() - 9.6).abs() < 1e-9);
    assert!((rate_at(&p, 1.0) - 2.0).abs() < 1e-6, "low rate near zero");
    assert!((rate_at(&p, 2.2) - 30.0).abs() < 1e-6, "high rate beyond threshold");
    assert!((p.at(2.0) + 4.0).abs() < 1e-9, "threshold reached after 2 s");
    assert!((p.at(2.4) + 16.0).abs() < 1e-9, "peak after 2.4 s");
    // Coming back in: high rate down to the threshold, low rate through zero.
    assert!((rate_at(&p, 2.6) - 30.0).abs() < 1e-6);
    assert!((rate_at(&p, 4.0) - 2.0).abs() < 1e-6);
    assert!(p.at(4.8).abs() < 1e-9, "zero crossing at the middle");
    // The thesis's example: ±22° in 23 s is a 4.5 °/s constant sweep; naming per §3.6.2.
    let thesis = RateLaw::Variable { low_rate: 4.0, high_rate: 12.0, threshold: 4.0 };
    assert_eq!(prim::rate_type_name(SlipAxis::SlipAngle, &thesis), "VariableRate_LR4_HR12_TH4");
    let brk = RateLaw::Variable { low_rate: 0.10, high_rate: 0.60, threshold: 0.02 };
    assert_eq!(prim::rate_type_name(SlipAxis::SlipRatio, &brk), "VariableRate_LR10_HR60_TH2");
}

#[test]
fn continuous_rate_law_is_smooth_capped_and_faster() {
    let var = RateLaw::Variable { low_rate: 2.0, high_rate: 30.0, threshold: 4.0 };
    let law = RateLaw::continuous_from_variable(2.0, 30.0, 4.0, SlipAxis::SlipAngle);
    let RateLaw::Continuous { knee, .. } = law else { panic!() };
    assert!((knee - 4.0 / 3.0).abs() < EPS);
    // Rate at zero equals the variable sweep's low rate: same on-centre data quality.
    assert!((law.rate_at(0.0) - 2.0).abs() < EPS);
    // Rises continuously (no step at the threshold) and caps at the rig's maximum.
    let mut prev = law.rate_at(0.0);
    let mut s = 0.0;
    while s < 25.0 {
        s += 0.01;
        let r = law.rate_at(s);
        assert!(r >= prev - EPS && r - prev < 0.15, "smooth at {s}: {prev} → {r}");
        prev = r;
    }
    assert!((law.rate_at(25.0) - 30.0).abs() < EPS);
    // Time law and its inverse agree.
    for s in [0.0, 0.5, 3.0, 18.0, 18.7, 22.0] {
        let t = law.time_from_zero(s);
        assert!((law.slip_at_time_from_zero(t) - s).abs() < 1e-9, "{s}");
    }
    // Shorter than the variable-rate sweep to the same peak.
    let pv = SlipPath::full_cycle(16.0, var);
    let pc = SlipPath::full_cycle(16.0, law);
    assert!(pc.duration_s() < pv.duration_s(), "{} vs {}", pc.duration_s(), pv.duration_s());
    // Flat at zero slip: within a tenth of the knee the rate is within 1 % of the low rate, so
    // the slip history the tyre remembers at a zero crossing is the variable sweep's.
    assert!(law.rate_at(0.1 * knee) <= 2.0 * 1.01 + EPS);
    // Never slower than the variable sweep below its threshold.
    assert!((0..400).all(|i| law.rate_at(i as f64 * 0.01) >= var.rate_at(i as f64 * 0.01) - EPS));
    // The slip-ratio knee is the threshold itself.
    let brk = RateLaw::continuous_from_variable(0.10, 0.60, 0.02, SlipAxis::SlipRatio);
    assert!(matches!(brk, RateLaw::Continuous { knee, .. } if (knee - 0.02).abs() < EPS));
    // Numerical rate along the path follows the law.
    for t in [0.05, 0.4, 1.0, 1.5] {
        let s = pc.at(t).abs();
        assert!((rate_at(&pc, t) - law.rate_at(s)).abs() < 1e-3, "t={t}");
    }
    assert_eq!(prim::rate_type_name(SlipAxis::SlipAngle, &law), "ContinuousRate_LR2_HR30_KN1.33");
}

#[test]
fn asymmetric_load_factors_saturation_and_adverse() {
    let fz0 = 6752.0;
    let (n, p) = AsymLevel::High.factors();
    assert_eq!((n, p), (1.8, 0.6));
    assert_eq!(AsymLevel::Medium.factors(), (1.6, 0.4));
    assert_eq!(AsymLevel::Low.factors(), (1.4, 0.2));
    let c = LoadCoupling::asymmetric(fz0, 1.6, 0.4, false);
    assert!((c.at(-5.0) - 1.6 * fz0).abs() < 1e-6);
    assert!((c.at(-16.0) - 1.6 * fz0).abs() < 1e-6, "saturated beyond 5°");
    assert!((c.at(5.0) - 0.4 * fz0).abs() < 1e-6);
    assert!((c.at(12.0) - 0.4 * fz0).abs() < 1e-6);
    assert!((c.at(0.0) - fz0).abs() < 1e-6, "mean load at zero slip");
    assert!((c.at(-2.5) - 1.3 * fz0).abs() < 1e-6, "linear inside saturation");
    let adv = LoadCoupling::asymmetric(fz0, 1.6, 0.4, true);
    assert!((adv.at(-10.0) - 0.4 * fz0).abs() < 1e-6);
    assert!((adv.at(10.0) - 1.6 * fz0).abs() < 1e-6);
    // In a sweep: the load follows the slip angle.
    let s = prim::slip_sweep(
        SlipAxis::SlipAngle,
        SlipPath::full_cycle(16.0, RateLaw::Constant { rate: 8.0 }),
        base(),
        c,
        CamberCoupling::Constant { camber_deg: 0.0 },
    );
    let sp = s.trajectory.at(2.0); // −16°
    assert!((sp.slip_angle_deg + 16.0).abs() < 1e-9);
    assert!((sp.fz_n - 1.6 * fz0).abs() < 1e-6);
    assert!(s.thermal_pause_after);
    assert_eq!(s.kind, StepKind::Sweep);
}

#[test]
fn camber_coupled_to_slip_angle() {
    let c = CamberCoupling::Coupled { gain_deg: 1.8, saturation_deg: 5.0 };
    assert!((c.at(5.0) - 1.8).abs() < EPS);
    assert!((c.at(20.0) - 1.8).abs() < EPS);
    assert!((c.at(-20.0) + 1.8).abs() < EPS);
    assert!((c.at(2.5) - 0.9).abs() < EPS);
    let adverse = CamberCoupling::Coupled { gain_deg: -1.8, saturation_deg: 5.0 };
    assert!((adverse.at(10.0) + 1.8).abs() < EPS);
}

#[test]
fn vertical_load_sweep_shape() {
    let lim = RigLimits::default();
    let s = prim::vertical_load_sweep(-18.0, 1350.0, 12_000.0, 30.0, base(), &lim);
    let t = &s.trajectory;
    let d = t.duration_s();
    let steer = 18.0 / 30.0;
    let ramp = (12_000.0 - 1350.0) / lim.load_rate_nps;
    assert!((d - 2.0 * (steer + ramp)).abs() < 1e-9);
    // Steered out at low load, then loaded at full slip.
    let at_slip = t.at(steer);
    assert!((at_slip.slip_angle_deg + 18.0).abs() < 1e-9);
    assert!((at_slip.fz_n - 1350.0).abs() < 1e-9);
    let peak = t.at(steer + ramp);
    assert!((peak.fz_n - 12_000.0).abs() < 1e-9);
    assert!((peak.slip_angle_deg + 18.0).abs() < 1e-9);
    assert!(t.end().slip_angle_deg.abs() < 1e-9 && (t.end().fz_n - 1350.0).abs() < 1e-9);
    assert!(s.thermal_pause_after);
    assert_eq!(s.type_name, "VerticalLoad_SA-18_FZ12kN");
}

#[test]
fn on_centre_holds_step_loads() {
    let lim = RigLimits::default();
    let loads = [4000.0, 8000.0];
    let s = prim::on_centre_holds(1.0, &loads, 10.0, base(), &lim);
    let t = &s.trajectory;
    assert!((t.duration_s() - (10.0 + 0.4 + 10.0)).abs() < 1e-9);
    assert!((t.at(5.0).fz_n - 4000.0).abs() < EPS);
    assert!((t.at(15.0).fz_n - 8000.0).abs() < EPS);
    assert!((t.at(15.0).slip_angle_deg - 1.0).abs() < EPS, "slip angle held");
    assert!(!s.thermal_pause_after);
    assert_eq!(s.kind, StepKind::Hold);
    assert_eq!(s.type_name, "OnCentre_SA1");
}

#[test]
fn rolling_radius_steps_at_speed() {
    let lim = RigLimits::default();
    let s = prim::rolling_radius_steps(&[3000.0, 6000.0, 9000.0], 38.8, 8.0, base(), &lim);
    let t = &s.trajectory;
    assert!((t.at(1.0).speed_mps - 38.8).abs() < EPS);
    assert!(t.at(1.0).slip_angle_deg.abs() < EPS);
    assert!((t.duration_s() - (3.0 * 8.0 + 0.6)).abs() < 1e-9);
    assert_eq!(s.type_name, "RollingRadius_V38.8");
}

#[test]
fn step_steer_steers_at_standstill() {
    let lim = RigLimits::default();
    let p = StepSteerParams { roll_speed_mps: 1.0, pre_roll_s: 2.0, distance_m: 1.5, steer_rate_dps: 10.0 };
    let s = prim::step_steer(1.5, 5000.0, &p, base(), &lim);
    let Trajectory::Keyframes(k) = &s.trajectory else { panic!("keyframes") };
    // While the slip angle changes from 0 the belt is stopped and the mode is static.
    let frames = k.frames();
    let steer_start =
        frames.windows(2).find(|w| w[0].sp.slip_angle_deg == 0.0 && w[1].sp.slip_angle_deg > 0.0).unwrap();
    assert_eq!(steer_start[0].sp.speed_mps, 0.0);
    assert_eq!(steer_start[0].sp.mode, RigMode::Static);
    // Then it rolls again at 1 m/s holding the angle; distance covered ≈ 1.5 m.
    let mut dist = 0.0;
    let dt = 0.001;
    let mut t = 0.0;
    while t < s.duration_s() {
        let sp = s.trajectory.at(t);
        if (sp.slip_angle_deg - 1.5).abs() < 1e-9 {
            dist += sp.speed_mps * dt;
        }
        t += dt;
    }
    assert!((dist - 1.5).abs() < 0.02, "{dist}");
    assert_eq!(s.type_name, "StepSteer_SA1.5");
    assert!(!s.thermal_pause_after);
}

#[test]
fn static_drag_locks_and_moves_belt() {
    let lim = RigLimits::default();
    let p = StaticDragParams { displacement_m: 0.1, belt_speed_mps: 0.025, roll_speed_mps: 1.0, roll_s: 3.0 };
    let s = prim::static_drag(4000.0, &p, base(), &lim);
    let t = &s.trajectory;
    let mut max_disp: f64 = 0.0;
    let mut tt = 0.0;
    while tt <= t.duration_s() {
        let sp = t.at(tt);
        if sp.belt_displacement_m > 0.0 {
            assert_eq!(sp.mode, RigMode::Static);
            assert_eq!(sp.speed_mps, 0.0);
        }
        max_disp = max_disp.max(sp.belt_displacement_m);
        tt += 0.01;
    }
    assert!((max_disp - 0.1).abs() < 1e-3);
    assert!((t.duration_s() - (3.0 + 0.25 + 4.0 + 0.5)).abs() < 1e-9);
    assert!(!s.thermal_pause_after);
    assert_eq!(s.type_name, "StaticDrag_D0.1");
}

#[test]
fn pressure_change_ramps_at_zero_slip() {
    let mut from = base();
    from.slip_angle_deg = 3.0;
    let s = prim::pressure_change(from, 3.3, 20.0);
    assert_eq!(s.kind, StepKind::PressureChange);
    assert!((s.duration_s() - 20.0).abs() < EPS);
    assert!(s.trajectory.start().slip_angle_deg.abs() < EPS);
    assert!((s.trajectory.end().pressure_bar - 3.3).abs() < EPS);
    assert!((s.trajectory.at(10.0).pressure_bar - 2.95).abs() < 1e-9);
}

#[test]
fn warm_up_blocks_have_no_thermal_pause() {
    let p = WarmUpParams { blocks: 2, peak_deg: 10.0, rate_dps: 4.0, roll_s: 30.0 };
    let segs = prim::warm_up(&p, &[6000.0, 9000.0, 3000.0], base());
    assert_eq!(segs.len(), 6);
    for s in &segs {
        assert_eq!(s.kind, StepKind::WarmUp);
        assert!(!s.thermal_pause_after);
        assert!((s.duration_s() - 40.0).abs() < 1e-6);
        assert!((s.trajectory.at(2.5).slip_angle_deg + 10.0).abs() < 1e-6);
    }
}

#[test]
fn graph_sweep_blocks_are_fixed() {
    let fr = prim::graph_sweep_block(GraphBlock::FreeRolling, [2.1, 2.6, 3.3], base());
    let cases: Vec<(f64, f64, f64)> = fr
        .iter()
        .map(|s| {
            let sp = s.trajectory.start();
            (sp.fz_n, sp.camber_deg, sp.pressure_bar)
        })
        .collect();
    assert_eq!(
        cases,
        vec![(6000.0, 0.0, 2.6), (9000.0, 0.0, 2.6), (3000.0, 0.0, 2.6), (6000.0, -3.0, 2.6), (6000.0, 3.0, 2.6)]
    );
    let bd = prim::graph_sweep_block(GraphBlock::BrkDrv, [2.1, 2.6, 3.3], base());
    let p: Vec<f64> = bd.iter().map(|s| s.trajectory.start().pressure_bar).collect();
    assert_eq!(p, vec![2.6, 2.6, 2.6, 2.1, 3.3]);
    assert!(bd.iter().all(|s| s.trajectory.start().mode == RigMode::Coupled));
    assert!(bd.iter().all(|s| s.trajectory.start().camber_deg == 0.0));
    assert_eq!(fr[0].type_name, "GraphSweep_VariableRate_LR2_HR30_TH4");
    assert_eq!(bd[0].type_name, "GraphSweep_VariableRate_LR10_HR60_TH2");
    // Identical whatever the tyre: the block does not depend on the base load.
    let mut other = base();
    other.fz_n = 1234.0;
    let fr2 = prim::graph_sweep_block(GraphBlock::FreeRolling, [2.1, 2.6, 3.3], other);
    assert_eq!(fr, fr2);
}

#[test]
fn thermal_pause_is_zero_slip_hold() {
    let mut end = base();
    end.slip_angle_deg = 0.3;
    end.slip_ratio = 0.05;
    end.fz_n = 9000.0;
    let sp = prim::thermal_pause_setpoint(&end);
    assert_eq!(sp.slip_angle_deg, 0.0);
    assert_eq!(sp.slip_ratio, 0.0);
    assert_eq!(sp.fz_n, 9000.0);
    assert_eq!(sp.speed_mps, 16.6);
}

#[test]
fn settle_goes_through_zero_slip() {
    let lim = RigLimits::default();
    let mut a = base();
    a.slip_angle_deg = 2.0;
    let mut b = base();
    b.fz_n = 12_000.0;
    b.slip_angle_deg = -1.0;
    b.camber_deg = 3.0;
    let s = prim::settle(a, b, &lim);
    assert_eq!(s.kind, StepKind::Settle);
    let t = &s.trajectory;
    assert_eq!(t.start(), a);
    assert_eq!(t.end(), b);
    // Load changes only at zero slip.
    let mut tt = 0.0;
    while tt < t.duration_s() {
        let sp = t.at(tt);
        if sp.fz_n > 6000.0 + 1e-6 && sp.fz_n < 12_000.0 - 1e-6 {
            assert!(sp.slip_angle_deg.abs() < 1e-9);
        }
        tt += 0.01;
    }
    // Camber 3° at 5 °/s sets the time (0.6 s) plus slip legs and the dwell.
    let expect = 2.0 / 15.0 + 0.6 + 1.0 / 15.0 + lim.settle_dwell_s;
    assert!((t.duration_s() - expect).abs() < 1e-9);
}

#[test]
fn tyre_change_is_safe_state() {
    let s = prim::tyre_change(900.0, "B");
    assert_eq!(s.kind, StepKind::TyreChange);
    assert_eq!(s.duration_s(), 900.0);
    assert_eq!(s.trajectory.at(450.0).mode, RigMode::Safe);
    assert_eq!(s.type_name, "TyreChange_B");
}

#[test]
fn fmt_num_for_names() {
    assert_eq!(prim::fmt_num(4.0), "4");
    assert_eq!(prim::fmt_num(1.8), "1.8");
    assert_eq!(prim::fmt_num(0.333), "0.33");
    assert_eq!(prim::fmt_num(-18.0), "-18");
}

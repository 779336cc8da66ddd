//! Wear in the cost: a sweep's sliding energy as the live model predicts it.

use adaptive::model::{ModelSnapshot, StageSnapshot, input_of};
use adaptive::{AdaptiveConfig, FitView, ModelView};
use mffit::stages::TEMPLATE_TIR;
use mftyre::{TyreParams, UseMode, evaluate};
use procedure::Setpoint;

fn snapshot() -> ModelSnapshot {
    ModelSnapshot {
        params: TyreParams::from_tir_str(TEMPLATE_TIR, "template").unwrap(),
        fz0_n: 4000.0,
        p0_pa: 220_000.0,
        v0_mps: 16.6,
        r0_m: 0.3135,
        stages: vec![StageSnapshot {
            stage: "fy_pure".into(),
            rmse: 40.0,
            keys: vec!["PDY1".into()],
            covariance: vec![1e-4],
            held_for_want_of_data: Vec::new(),
        }],
    }
}

fn at(slip_angle_deg: f64, slip_ratio: f64, fz_n: f64) -> Setpoint {
    Setpoint { fz_n, slip_angle_deg, slip_ratio, pressure_bar: 2.2, speed_mps: 16.6, ..Setpoint::default() }
}

/// The same model evaluated by `mftyre` directly (combined slip, TNO's use mode), not through the
/// fitter's channels the view uses.
fn forces(params: &TyreParams, sp: &Setpoint) -> (f64, f64) {
    let o = evaluate(params, UseMode::M111, &input_of(sp, 0.3135));
    (o.fx_n, o.fy_n)
}

#[test]
fn sliding_power_is_force_times_slip_velocity_and_zero_without_slip() {
    let model = snapshot();
    let view = FitView::new(&model, &AdaptiveConfig::default());
    assert_eq!(view.sliding_power_w(&at(0.0, 0.0, 4000.0)), Some(0.0));
    for sp in [at(6.0, 0.0, 4000.0), at(-3.0, 0.0, 6000.0), at(0.0, 0.08, 4000.0), at(4.0, -0.05, 5000.0)] {
        let (fx, fy) = forces(&model.params, &sp);
        let expected =
            sp.speed_mps * (fx.abs() * sp.slip_ratio.abs() + fy.abs() * sp.slip_angle_deg.to_radians().tan().abs());
        let p = view.sliding_power_w(&sp).unwrap();
        assert!(expected > 100.0, "{sp:?}: a sliding tyre dissipates power ({expected} W)");
        assert!((p - expected).abs() <= 1e-6 * expected, "{sp:?}: {p} W against {expected} W");
    }
    // More load and more slip slide more (below the force peak as well as past it).
    let p = |sa: f64, fz: f64| view.sliding_power_w(&at(sa, 0.0, fz)).unwrap();
    assert!(p(4.0, 6000.0) > p(4.0, 3000.0));
    assert!(p(12.0, 4000.0) > p(6.0, 4000.0) && p(6.0, 4000.0) > p(2.0, 4000.0));
    // A car stopped on the road does not wear its tyre.
    let parked = Setpoint { speed_mps: 0.0, ..at(6.0, 0.0, 4000.0) };
    assert_eq!(view.sliding_power_w(&parked), Some(0.0));
}

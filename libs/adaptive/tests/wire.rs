//! The live model over DDS: a snapshot written as `tyre_msgs/ModelCovariance`, through CDR, and
//! read back is the same model, and the planner's view of it predicts the same numbers. Bad
//! messages are refused with the field that is wrong.

use adaptive::model::{ModelSnapshot, StageSnapshot};
use adaptive::wire::{from_msg, to_msg};
use adaptive::{AdaptiveConfig, FitView, ModelView, Target};
use mffit::stages::TEMPLATE_TIR;
use mftyre::TyreParams;
use procedure::Setpoint;
use tyre_msgs::ModelCovariance;
use tyre_msgs::cdr::{from_cdr_with_header, to_cdr_with_header};

fn snapshot() -> ModelSnapshot {
    let mut params = TyreParams::from_tir_str(TEMPLATE_TIR, "template").unwrap();
    // Values a fit would leave: not the template's, and not short decimals.
    params.set("PDY1", 1.0 / 0.7).unwrap();
    params.set("PKY1", -15.0 - 1.0 / 3.0).unwrap();
    let keys = ["PCY1", "PDY1", "PKY1"];
    // A positive-definite covariance with correlations, one of each size.
    let covariance = vec![1e-4, 2e-6, -1e-5, 2e-6, 4e-5, 3e-6, -1e-5, 3e-6, 2.5e-2];
    ModelSnapshot {
        params,
        fz0_n: 4000.0 + 1.0 / 3.0,
        p0_pa: 220_000.0,
        v0_mps: 16.6,
        r0_m: 0.3135,
        stages: vec![StageSnapshot {
            stage: "fy_pure".into(),
            rmse: 41.25,
            keys: keys.iter().map(|k| (*k).to_owned()).collect(),
            covariance,
            held_for_want_of_data: vec!["PPY1".into(), "PDY3".into()],
        }],
    }
}

fn over_the_wire(model: &ModelSnapshot) -> ModelSnapshot {
    let mut msg = to_msg(model);
    msg.update_index = 7;
    msg.last_sweep_index = 12;
    let bytes = to_cdr_with_header(&msg).unwrap();
    let back: ModelCovariance = from_cdr_with_header(&bytes).unwrap();
    assert_eq!(back, msg);
    from_msg(&back).unwrap().expect("has_model")
}

#[test]
fn a_model_sent_as_model_covariance_is_the_same_model_and_plans_the_same() {
    let sent = snapshot();
    let mut got = over_the_wire(&sent);
    assert_eq!(got.params.source, "model/covariance tir", "errors in it must say where it came from");
    got.params.source = sent.params.source.clone();
    assert_eq!(got, sent, "the snapshot read back differs");

    let cfg = AdaptiveConfig::default();
    let (here, there) = (FitView::new(&sent, &cfg), FitView::new(&got, &cfg));
    let a = here.target(Target::FyPure).expect("fy_pure is fitted: FY pure has a model");
    let b = there.target(Target::FyPure).unwrap();
    assert!(a.error_pct().is_finite() && a.error_pct() > 0.0, "{}", a.error_pct());
    assert_eq!(a.error_pct().to_bits(), b.error_pct().to_bits());
    assert_eq!(a.cov, b.cov);
    // Held for want of data: a prior on each, the planner's reason to test that level.
    assert_eq!(a.cov.nrows(), 5);
    let points =
        [Setpoint { fz_n: 4000.0, slip_angle_deg: 4.0, pressure_bar: 2.2, speed_mps: 16.6, ..Setpoint::default() }];
    assert_eq!(here.sensitivities(Target::FyPure, &points), there.sensitivities(Target::FyPure, &points));
    // Stages not in the snapshot: no model of what needs them.
    assert!(there.target(Target::FxPure).is_none() && there.target(Target::MzPure).is_none());
}

#[test]
fn no_model_yet_reads_as_none() {
    let msg = ModelCovariance { update_index: 3, ..ModelCovariance::default() };
    assert_eq!(from_msg(&msg).unwrap(), None);
}

#[test]
fn a_bad_message_names_the_field_that_is_wrong() {
    let good = to_msg(&snapshot());

    let mut bad = good.clone();
    bad.stages[0].covariance.pop();
    let e = from_msg(&bad).unwrap_err();
    assert_eq!(e.field, "stages[fy_pure].covariance", "{e}");
    assert!(e.to_string().contains("8 values, expected 9"), "{e}");

    let mut bad = good.clone();
    bad.tir = "[MODEL]\nFITTYP = 61\nLONGVL = fast\n".into();
    let e = from_msg(&bad).unwrap_err();
    assert_eq!(e.field, "tir", "{e}");

    let mut bad = good;
    bad.r0_m = f64::NAN;
    let e = from_msg(&bad).unwrap_err();
    assert_eq!(e.field, "r0_m", "{e}");
}

//! The monitor core on synthetic streams.

use monitor::{MonitorConfig, MonitorCore, TyreInfo};
use tyre_msgs::std_msgs::Header;
use tyre_msgs::{ProcedureState, QualityCheck, RigSample, RigSetpoint, SweepSummary};

fn sample(t: f64, fz: f64) -> RigSample {
    RigSample {
        header: Header::iso_w(t),
        runtime_s: t,
        fzw_n: fz,
        inflpres_pa: 2.6e5,
        trajvelw_mps: 16.6,
        dstwowhc_m: 0.37,
        trdtempc_c: 45.0,
        rig_mode: RigSetpoint::MODE_FREE_ROLLING,
        ..RigSample::default()
    }
}

fn core(entered: Option<u32>) -> MonitorCore {
    let mut t = TyreInfo::from_load_index(110).unwrap();
    t.entered_load_index = entered;
    MonitorCore::new(MonitorConfig::default(), t).unwrap()
}

#[test]
fn entered_index_different_from_the_declared_one_is_an_error_at_once() {
    let mut m = core(Some(125));
    let o = m.on_sample(&sample(0.01, 1000.0));
    assert_eq!(o.alarms.len(), 1);
    assert_eq!(o.alarms[0].level, "ERROR");
    assert_eq!(o.alarms[0].check, "load_rating");
    let r = o.report.unwrap();
    assert_eq!(r.level, QualityCheck::ERROR);
    let d = o.diagnostics.unwrap();
    assert!(d.status.iter().any(|s| s.name == "tyrerig monitor: load_rating" && s.level == 2));
}

#[test]
fn sustained_overload_is_an_error_a_spike_is_not() {
    let mut m = core(None);
    let fz0 = m.tyre().fz0_n;
    let mut alarms = Vec::new();
    // A 0.1 s spike to 3 × Fz0 inside a normal load: nothing.
    for i in 1..=300 {
        let t = f64::from(i) * 0.01;
        let fz = if (100..110).contains(&i) { 3.0 * fz0 } else { fz0 };
        alarms.extend(m.on_sample(&sample(t, fz)).alarms);
    }
    assert!(alarms.is_empty(), "{alarms:?}");
    // 1 s at 2.5 × Fz0: ERROR.
    for i in 301..=400 {
        alarms.extend(m.on_sample(&sample(f64::from(i) * 0.01, 2.5 * fz0)).alarms);
    }
    assert!(alarms.iter().any(|a| a.level == "ERROR" && a.check == "load_rating"), "{alarms:?}");
    assert!(m.max_load_factor() > 2.45);
}

#[test]
fn hot_starts_warn_each_and_error_as_a_large_fraction() {
    let mut m = core(None);
    let mut levels = Vec::new();
    for i in 0..8u32 {
        let s = SweepSummary {
            header: Header::iso_w(f64::from(i) * 60.0),
            sweep_name: format!("Sq_sw{i}_X_1"),
            sweep_index: i,
            started_hot: i % 2 == 1,
            start_temp_c: 60.0,
            mean_fz_n: 6000.0,
            ..SweepSummary::default()
        };
        let o = m.on_sweep_summary(&s);
        levels.extend(o.alarms.iter().map(|a| (i, a.level.clone())));
    }
    // Hot starts at sweeps 1, 3, 5, 7: 50 % of the sweeps; ERROR from the third on.
    assert_eq!(levels, vec![(1, "WARN".into()), (3, "WARN".into()), (5, "ERROR".into()), (7, "ERROR".into())]);
}

#[test]
fn nan_samples_and_missing_phases_do_not_panic() {
    let mut m = core(None);
    m.on_procedure_state(&ProcedureState { header: Header::iso_w(0.0), phase: 200, ..ProcedureState::default() });
    for i in 1..500 {
        let mut s = sample(f64::from(i) * 0.01, f64::NAN);
        s.dstwowhc_m = f64::NAN;
        s.runtime_s = if i % 5 == 0 { f64::NAN } else { s.runtime_s };
        let _ = m.on_sample(&s);
    }
    let _ = m.finish();
    assert!(m.wear().wear_mm.is_nan());
    assert_eq!(m.report(5.0).level, QualityCheck::OK);
}

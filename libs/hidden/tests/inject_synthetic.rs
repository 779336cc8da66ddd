//! The injector on small hand-made logs whose inputs are known: one steady cornering sweep on
//! the MF tyre with the tread temperature ramping from 40 to 80 °C.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use hidden::{EffectKind, GripCurve, HiddenEffect, inject};
use mcaplog::{LogReader, McapLog, McapLogOptions};
use mftyre::{MfInput, UseMode};
use rigsim::VirtualTyre;
use tyre_msgs::std_msgs::Header;
use tyre_msgs::{ProcedureState, RigSample, RigSetpoint, RosMessage};

const SAMPLES: u64 = 2000;
const SLIP_ANGLE_DEG: f64 = 6.0;
const FZ_N: f64 = 5000.0;
const V_MPS: f64 = 16.67;

fn tyre() -> VirtualTyre {
    let tir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../launch-config/tyres/MagicFormula61_Paramerters.tir");
    VirtualTyre::from(rigsim::TyreParams::read_tir(&tir).expect("the default tyre reads"))
}

fn input() -> MfInput {
    MfInput {
        fz_n: FZ_N,
        kappa: 0.0,
        alpha_rad: SLIP_ANGLE_DEG.to_radians(),
        gamma_rad: 0.0,
        phit_per_m: 0.0,
        vx_mps: V_MPS,
        p_pa: 2.2e5,
        omega_radps: V_MPS / 0.35,
    }
}

fn temp_at(k: u64) -> f64 {
    40.0 + 40.0 * k as f64 / (SAMPLES - 1) as f64
}

/// A 20 s sweep at 100 Hz: samples, one procedure state, a metadata record and a clock topic.
fn write_log(path: &Path, tyre: &VirtualTyre) {
    let p = tyre.mf_params().expect("an MF tyre");
    let out = mftyre::evaluate(p, UseMode::M111, &input());
    let mut log = McapLog::create(path, McapLogOptions::default()).expect("create");
    let schema = |ty: &str| tyre_msgs::schema::ros2msg_schema_for(ty).expect("schema");
    let st_ty = ProcedureState::ros_type_name();
    let rs_ty = RigSample::ros_type_name();
    let ch_state = log.ensure_channel("/rig/procedure/state", &st_ty, &schema(&st_ty)).expect("channel");
    let ch_sample = log.ensure_channel("/rig/sample", &rs_ty, &schema(&rs_ty)).expect("channel");
    log.write_metadata("tyre", &BTreeMap::from([("name".to_owned(), "synthetic".to_owned())])).expect("metadata");
    let state = ProcedureState {
        header: Header::iso_w(0.0),
        phase: ProcedureState::PHASE_SWEEP,
        sweep_name: "synthetic".into(),
        ..ProcedureState::default()
    };
    let enc = mcaplog::codec::encode(&state, &st_ty).expect("encode");
    log.write(ch_state, 0, 0, &enc).expect("write");
    for k in 0..SAMPLES {
        let t = k as f64 * 0.01;
        let ns = (t * 1e9).round() as u64;
        let s = RigSample {
            header: Header::iso_w(t),
            seq: k,
            runtime_s: t,
            fx_n: out.fx_n,
            fyw_n: out.fy_n,
            fzw_n: FZ_N,
            mxw_nm: out.mx_nm,
            myw_nm: out.my_nm,
            mzw_nm: out.mz_nm,
            slipangl_deg: SLIP_ANGLE_DEG,
            longslip: 0.0,
            inclangl_deg: 0.0,
            inflpres_pa: 2.2e5,
            trajvelw_mps: V_MPS,
            wheel_speed_radps: V_MPS / 0.35,
            dstwowhc_m: (out.rl_m / 1e-4).round() * 1e-4,
            trdtempi_c: temp_at(k) - 1.0,
            trdtempc_c: temp_at(k),
            trdtempo_c: temp_at(k) + 1.0,
            rig_mode: RigSetpoint::MODE_FREE_ROLLING,
            fault_flags: 0,
        };
        let enc = mcaplog::codec::encode(&s, &rs_ty).expect("encode");
        log.write(ch_sample, ns, ns, &enc).expect("write");
    }
    log.finish().expect("finish");
}

fn samples(path: &Path) -> Vec<RigSample> {
    LogReader::open(path)
        .expect("log reads")
        .typed::<RigSample>("/rig/sample")
        .expect("samples")
        .into_iter()
        .map(|(_, s)| s)
        .collect()
}

fn paths(dir: &tempfile::TempDir) -> (PathBuf, PathBuf) {
    (dir.path().join("in.mcap"), dir.path().join("out.mcap"))
}

/// A thermal effect on the surface reading with a quadratic μ(T) peaking at the median
/// temperature (60 °C), 10 % lateral grip lost at the hot end and 5 % at the cold end.
fn known_thermal(strength: f64) -> HiddenEffect {
    let HiddenEffect::Thermal(mut t) = HiddenEffect::draw(EffectKind::Thermal, 1, strength) else { unreachable!() };
    t.bulk_lag_s = 0.0;
    t.surface_weight = 1.0;
    t.grip_curve = GripCurve::AsymmetricQuadratic;
    t.grip_optimum_quantile = 0.5;
    t.grip_loss_cold = 0.05;
    t.grip_loss_hot = 0.10;
    HiddenEffect::Thermal(t)
}

#[test]
fn only_the_four_fields_change_and_everything_else_is_copied() {
    let dir = tempfile::tempdir().expect("tempdir");
    let (a, b) = paths(&dir);
    let tyre = tyre();
    write_log(&a, &tyre);
    let effects = [known_thermal(1.0), HiddenEffect::draw(EffectKind::Wear, 2, 1.0)];
    let report = inject(&a, &b, &tyre, &effects).expect("inject");
    assert_eq!(report.kinds(), vec![EffectKind::Thermal, EffectKind::Wear]);
    assert_eq!(report.logs[0].samples, SAMPLES as usize);
    assert!(report.logs[0].forces_changed > 1000 && report.logs[0].radius_changed > 100, "{:?}", report.logs[0]);

    let (ra, rb) = (LogReader::open(&a).expect("in"), LogReader::open(&b).expect("out"));
    assert_eq!(ra.metadata(), rb.metadata());
    assert_eq!(ra.topics(), rb.topics());
    for (ma, mb) in ra.messages().iter().zip(rb.messages()).filter(|(m, _)| m.topic != "/rig/sample") {
        assert_eq!((ma.log_time_ns, ma.publish_time_ns, &ma.data), (mb.log_time_ns, mb.publish_time_ns, &mb.data));
    }
    let (sa, sb) = (samples(&a), samples(&b));
    assert_eq!(sa.len(), sb.len());
    let mut changed = 0;
    for (x, y) in sa.iter().zip(&sb) {
        // Put the four fields back: the rest must be bit-identical.
        let mut z = y.clone();
        z.fx_n = x.fx_n;
        z.fyw_n = x.fyw_n;
        z.mzw_nm = x.mzw_nm;
        z.dstwowhc_m = x.dstwowhc_m;
        assert_eq!(&z, x);
        changed += usize::from(y.fyw_n != x.fyw_n);
        let steps = y.dstwowhc_m / 1e-4;
        assert!((steps - steps.round()).abs() < 1e-6, "DSTWOWHC off its 0.1 mm steps: {}", y.dstwowhc_m);
    }
    assert!(changed > 1000);
}

#[test]
fn zero_strength_changes_nothing() {
    let dir = tempfile::tempdir().expect("tempdir");
    let (a, b) = paths(&dir);
    let tyre = tyre();
    write_log(&a, &tyre);
    let effects: Vec<HiddenEffect> = EffectKind::ALL.iter().map(|&k| HiddenEffect::draw(k, 5, 0.0)).collect();
    let report = inject(&a, &b, &tyre, &effects).expect("inject");
    assert_eq!((report.logs[0].forces_changed, report.logs[0].radius_changed), (0, 0));
    assert_eq!(samples(&a), samples(&b));
    assert_eq!(report.combined.strength_noise_units, 0.0);
}

#[test]
fn thermal_grip_loss_has_the_expected_sign_and_size_at_a_known_temperature() {
    let dir = tempfile::tempdir().expect("tempdir");
    let (a, b) = paths(&dir);
    let tyre = tyre();
    write_log(&a, &tyre);
    let report = inject(&a, &b, &tyre, &[known_thermal(1.0)]).expect("inject");
    let r = &report.effects[0].resolved;
    assert!((r["grip_optimum_c"] - 60.0).abs() < 0.05, "{r:?}");
    let (sa, sb) = (samples(&a), samples(&b));
    // At the optimum (the median sample) nothing changes; at 98 % of the range the full hot loss.
    let mid = (SAMPLES / 2) as usize;
    assert!((sb[mid].fyw_n - sa[mid].fyw_n).abs() < 0.05 * 0.10 * sa[mid].fyw_n.abs());
    let hot = (0.98 * (SAMPLES - 1) as f64).round() as usize;
    let fy = sa[hot].fyw_n;
    let d = sb[hot].fyw_n - fy;
    // 6° is near the peak: |FY| falls by about the 10 % grip lost (more or less with the
    // stiffness change of the hot tyre).
    assert!(fy < 0.0, "a positive slip angle gives a negative FY: {fy}");
    assert!(d > 0.5 * 0.10 * fy.abs() && d < 1.25 * 0.10 * fy.abs(), "ΔFY {d} at FY {fy}");
    // The same change, computed straight from the tyre with λμy × 0.9, λμx × (1 − 0.1·ratio).
    let HiddenEffect::Thermal(t) = &report.effects[0].effect else { unreachable!() };
    let p = tyre.mf_params().expect("MF");
    let mut s = p.scaling;
    s.lmuy *= 0.90;
    s.lmux *= 1.0 - 0.10 * t.grip_x_ratio;
    let y = (temp_at(hot as u64) - r["stiffness_reference_c"]) / (r["hottest_c"] - r["coldest_c"]);
    let k = 1.0 - t.stiffness_slope * y - t.stiffness_curvature * y * y;
    s.lkx *= k;
    s.lky *= k;
    let with = mftyre::evaluate_scaled(p, &s, UseMode::M111, &input());
    let without = mftyre::evaluate(p, UseMode::M111, &input());
    let expected = with.fy_n - without.fy_n;
    assert!((d - expected).abs() < 0.02 * expected.abs() + 1e-6, "ΔFY {d}, expected {expected}");
    // The hot tyre's radius grew (pressure), never beyond a fraction of a millimetre.
    let dr = sb[hot].dstwowhc_m - sa[hot].dstwowhc_m;
    assert!((-1e-4..=6e-4).contains(&dr), "radius change {dr}");
    assert!(report.effects[0].size.strength_noise_units > 3.0, "{:?}", report.effects[0].size);
}

#[test]
fn the_radius_falls_by_the_wear_depth() {
    let dir = tempfile::tempdir().expect("tempdir");
    let (a, b) = paths(&dir);
    let tyre = tyre();
    write_log(&a, &tyre);
    let HiddenEffect::Wear(mut w) = HiddenEffect::draw(EffectKind::Wear, 3, 1.0) else { unreachable!() };
    w.depth_at_end_mm = 1.0;
    let report = inject(&a, &b, &tyre, &[HiddenEffect::Wear(w)]).expect("inject");
    let (sa, sb) = (samples(&a), samples(&b));
    // Constant sliding power: the depth grows linearly to 1 mm at the end.
    for k in [SAMPLES as usize / 2, SAMPLES as usize - 1] {
        let depth_mm = 1.0 * k as f64 / (SAMPLES - 1) as f64;
        let dr_mm = (sb[k].dstwowhc_m - sa[k].dstwowhc_m) * 1e3;
        assert!((dr_mm + depth_mm).abs() <= 0.1 + 1e-9, "sample {k}: radius change {dr_mm} mm, depth {depth_mm} mm");
    }
    assert_eq!(report.effects[0].size.main_channel, "DSTWOWHC");
}

//! Unit-level checks: Jacobian against finite differences, failure-mode detection, the MCAP
//! round trip, the written .tir reading back. (The file formats are `rigdata`'s, tested there.)

use mffit::engine::{Channel, ChannelProblem, Point};
use mffit::synth::{self, Noise, SynthOptions};
use mffit::{Dataset, FitOptions, fit};
use mftyre::{MfInput, TyreParams};
use nalgebra::{DMatrix, DVector};

fn truth() -> TyreParams {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../../launch-config/tyres/MagicFormula61_Paramerters.tir");
    TyreParams::read_tir(std::path::Path::new(path)).expect("default tyre")
}

fn grid_points(t: &TyreParams, channel: Channel) -> Vec<Point> {
    let mut v = Vec::new();
    for fz in [3000.0, 6000.0, 9000.0] {
        for a in [-10.0_f64, -4.0, -1.0, 0.5, 2.0, 8.0] {
            for (k, g) in [(0.0, 0.0_f64), (0.05, 2.0), (-0.1, -3.0)] {
                let input = MfInput {
                    fz_n: fz,
                    kappa: k,
                    alpha_rad: a.to_radians(),
                    gamma_rad: g.to_radians(),
                    phit_per_m: 0.0,
                    vx_mps: 16.6,
                    p_pa: 2.4e5,
                    omega_radps: 0.0,
                };
                v.push(Point { input, measured: channel.eval(t, &input) * 1.01 + 3.0 });
            }
        }
    }
    v
}

/// The fitter evaluates residuals with the batch kernel; each channel must read the same value
/// as the scalar model, including with the pressure and spin columns filled and at zero speed.
#[test]
fn batch_residual_channels_agree_with_the_scalar_model() {
    use mffit::engine::{BatchScratch, InputColumns};
    let t = truth();
    let all = [
        Channel::Fy0,
        Channel::Fx0,
        Channel::Mz0,
        Channel::Fx,
        Channel::Fy,
        Channel::Mz,
        Channel::Mx,
        Channel::Rl,
        Channel::Re,
        Channel::Cx,
        Channel::SigmaY,
    ];
    let mut pts = grid_points(&t, Channel::Fy);
    // A point with another pressure and a measured spin rate, and one at standstill.
    pts[3].input.p_pa = 1.9e5;
    pts[4].input.omega_radps = 50.0;
    pts[5].input.vx_mps = 0.0;
    let cols = InputColumns::of(&pts);
    let mut scratch = BatchScratch::default();
    for channel in all {
        let mut batch = vec![0.0; pts.len() - 1];
        // An odd range: a partial lane group at the end.
        channel.eval_batch(&t, &cols.batch(1..pts.len()), &mut scratch, &mut batch);
        for (i, b) in batch.iter().enumerate() {
            let scalar = channel.eval(&t, &pts[i + 1].input);
            let tol = 1e-12 * scalar.abs().max(1.0);
            assert!((b - scalar).abs() <= tol, "{channel:?} point {}: batch {b} vs scalar {scalar}", i + 1);
        }
    }
}

#[test]
fn numeric_jacobians_agree_with_lsq_finite_differences() {
    let t = truth();
    let cases: [(Channel, &[&'static str]); 4] = [
        (Channel::Fy0, &["PCY1", "PDY1", "PEY1", "PKY1", "PKY2", "PKY4", "PVY3", "PPY1"]),
        (Channel::Mz0, &["QBZ1", "QCZ1", "QDZ1", "QDZ6", "QEZ1", "QHZ1", "PPZ1"]),
        (Channel::Fy, &["RBY1", "RBY2", "RCY1", "RVY1", "RVY5", "RVY6"]),
        (Channel::Mx, &["QSX1", "QSX2", "QSX3", "QSX4", "QSX6", "QSX9"]),
    ];
    for (channel, keys) in cases {
        let pts = grid_points(&t, channel);
        let problem = ChannelProblem::new(&t, keys, &pts, channel, 10.0);
        let p = DVector::from_vec(mffit::engine::values_of(&t, keys));
        let check = lsq::check_jacobian(&problem, &p).expect("check");
        assert!(check.max_rel_error < 1e-4, "{channel:?}: {check:?}");
        // Forward differences (the optimiser's) agree to first order: per column within 1e-4 of
        // its size, whether the residuals at p are in hand or not (single small entries may be
        // off by more, relative to themselves).
        let mut forward = ChannelProblem::new(&t, keys, &pts, channel, 10.0);
        forward.differences = mffit::engine::Differences::Forward;
        let check = lsq::check_jacobian(&forward, &p).expect("check");
        assert!(check.max_rel_error < 1e-2, "{channel:?} forward: {check:?}");
        let mut r = DVector::zeros(lsq::Problem::num_residuals(&forward));
        lsq::Problem::residuals(&forward, &p, &mut r);
        let (mut central_j, mut forward_j) = (DMatrix::zeros(r.len(), keys.len()), DMatrix::zeros(r.len(), keys.len()));
        lsq::Problem::jacobian(&problem, &p, &mut central_j);
        lsq::Problem::jacobian(&forward, &p, &mut forward_j);
        for (c, key) in keys.iter().enumerate() {
            let gap = (central_j.column(c) - forward_j.column(c)).norm();
            let rel = gap / central_j.column(c).norm().max(1e-12);
            assert!(rel <= 1e-4, "{channel:?} {key}: relative gap {rel}");
        }
    }
}

#[test]
fn failure_modes_are_detected() {
    let t = truth();
    let range = mffit::ValidRange::of(&synth::gs2mf(
        &t,
        SynthOptions { rate_hz: 5.0, noise: Noise::OFF, ..Default::default() },
    ));
    // The true tyre is clean (apart from E, which it never pushes past 1 in range).
    let clean = mffit::checks::check_all(&t, &range);
    assert!(clean.iter().all(|w| !w.contains("square") && !w.contains("Dy")), "{clean:?}");
    // Square ellipse: lateral force no longer reduced by slip ratio.
    let mut sq = t.clone();
    sq.set("RBY1", 0.01).unwrap();
    sq.set("RBY2", 0.0).unwrap();
    assert!(mffit::checks::ellipse_squareness(&sq, 6752.0, 2.6e5) > mffit::checks::SQUARE_LIMIT);
    assert!(mffit::checks::check_all(&sq, &range).iter().any(|w| w.contains("square")));
    // Non-physical friction and shape.
    let mut bad = t.clone();
    bad.set("PCY1", -1.0).unwrap();
    let w = mffit::checks::check_all(&bad, &range);
    assert!(w.iter().any(|w| w.contains("Cy ≤ 0")), "{w:?}");
    // Friction that falls through zero with load: named by the stage's physical margins.
    let mut bad = t.clone();
    bad.set("PDY1", 0.3).unwrap();
    bad.set("PDY2", -0.5).unwrap();
    let w = mffit::checks::check_all(&bad, &range);
    assert!(w.iter().any(|w| w.contains("stage fy_pure") && w.contains("Dy")), "{w:?}");
    // Extrapolation: a curvature that turns the force over past the peak.
    let mut ex = t.clone();
    ex.set("PCY1", 3.0).unwrap();
    assert!(!mffit::checks::extrapolation(&ex, &range).is_empty());
}

fn small_dataset(noise: Noise) -> Dataset {
    let t = truth();
    synth::gs2mf(&t, SynthOptions { rate_hz: 10.0, noise, ..Default::default() })
}

#[test]
fn mcap_round_trip_keeps_segments() {
    let d = small_dataset(Noise::RIG);
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("x.mcap");
    mffit::logs::write_log(&p, &d).unwrap();
    let back = mffit::logs::read_log(&p).unwrap();
    assert_eq!(back.segments.len(), d.segments.len());
    assert_eq!(back.fnomin_n, d.fnomin_n);
    for (a, b) in d.segments.iter().zip(&back.segments) {
        assert_eq!((a.procedure, a.kind), (b.procedure, b.kind), "{} / {}", a.section, a.sweep);
        assert_eq!(a.samples.len(), b.samples.len());
        let (x, y) = (a.samples[1], b.samples[1]);
        assert!((x.fy_n - y.fy_n).abs() < 1e-9 && (x.alpha_rad - y.alpha_rad).abs() < 1e-12);
    }
}

#[test]
fn written_tir_reads_back_and_evaluates_the_same() {
    let d = small_dataset(Noise::RIG);
    let r = fit(&d, &FitOptions { max_points: 800, max_iterations: 30, ..FitOptions::default() }).unwrap();
    let text = r.params.to_tir_string();
    assert!(text.contains("FITTYP") && text.contains("61"));
    let back = TyreParams::from_tir_str(&text, "fitted.tir").unwrap();
    for a in [-0.2, -0.05, 0.0, 0.1] {
        for k in [-0.1, 0.0, 0.08] {
            let i = MfInput {
                fz_n: 7000.0,
                kappa: k,
                alpha_rad: a,
                gamma_rad: 0.01,
                phit_per_m: 0.0,
                vx_mps: 16.6,
                p_pa: 2.5e5,
                omega_radps: 0.0,
            };
            let (x, y) = (
                mftyre::evaluate(&r.params, mftyre::UseMode::M111, &i),
                mftyre::evaluate(&back, mftyre::UseMode::M111, &i),
            );
            for (u, v) in [(x.fx_n, y.fx_n), (x.fy_n, y.fy_n), (x.mz_nm, y.mz_nm), (x.mx_nm, y.mx_nm), (x.rl_m, y.rl_m)]
            {
                assert!((u - v).abs() <= 1e-8 * u.abs().max(1.0), "{u} vs {v}");
            }
        }
    }
    // Report files.
    let dir = tempfile::tempdir().unwrap();
    let files = mffit::report::write(dir.path(), &r, None).unwrap();
    assert!(files.iter().any(|f| f.ends_with("fit.json")));
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.path().join("fit.json")).unwrap()).unwrap();
    let st = json["stages"].as_array().unwrap();
    assert!(st.iter().any(|s| s["stage"] == "fy_pure" && s["nrmse_pct"].as_f64().unwrap() < 2.0));
    assert!(json["wall_time_s"].as_f64().unwrap() > 0.0);
    assert!(dir.path().join("friction_ellipse.png").exists());
}

#[test]
fn robust_loss_resists_outliers() {
    let t = truth();
    let mut pts = grid_points(&t, Channel::Fy0);
    for p in pts.iter_mut() {
        p.measured = Channel::Fy0.eval(&t, &p.input);
    }
    // Every 10th point is a gross outlier (a spike of 3 kN).
    for p in pts.iter_mut().step_by(10) {
        p.measured += 3000.0;
    }
    let keys: &[&'static str] = &["PDY1", "PKY1", "PCY1", "PEY1"];
    let scale = 100.0;
    let err = |robust: Option<f64>| {
        let mut p = t.clone();
        mffit::engine::apply(&mut p, keys, &[0.9, 20.0, 1.3, -0.5]);
        let s = mffit::fit::StepSettings { robust, max_iterations: 200, threads: 1, ..Default::default() };
        mffit::fit::fit_step("test", &mut p, keys, &pts, Channel::Fy0, scale, &s).unwrap();
        (p.get("PDY1").unwrap() - t.get("PDY1").unwrap()).abs()
    };
    let plain = err(None);
    let robust = err(Some(2.0));
    assert!(robust < 0.2 * plain, "robust {robust} vs plain {plain}");
}

/// The maps evaluate the grid in load-case order with the batch kernel; every value and σ must
/// still be the one the scalar model gives at that grid point.
#[test]
fn prediction_maps_match_the_scalar_delta_method_point_by_point() {
    use mffit::prediction::{ChannelCovariance, EnvelopeGrid, MapChannel, prediction_maps_since};
    let d = small_dataset(Noise::RIG);
    let result = fit(&d, &FitOptions { folds: 0, ..FitOptions::default() }).expect("fit");
    let n = &result.nominal;
    let grid = EnvelopeGrid::standard(n.fz0_n, n.p0_pa, n.v0_mps);
    let maps = prediction_maps_since(&result, &grid, None, 2);
    assert_eq!(maps.len(), MapChannel::ALL.len());
    for map in &maps {
        let cov = ChannelCovariance::of(&result, map.channel).expect("every stage fitted");
        let inputs = grid.inputs(map.channel, n.r0_m);
        for i in (0..inputs.len()).step_by(7) {
            let value = map.channel.channel().eval(&result.params, &inputs[i]);
            assert!((map.value[i] - value).abs() <= 1e-12 * value.abs().max(1.0), "{:?} #{i}", map.channel);
            let sd = cov.std_at(&result, map.channel, &inputs[i]);
            assert!(
                (map.std_param[i] - sd).abs() <= 1e-5 * sd.abs() + 1e-9,
                "{:?} #{i}: map σ {} vs scalar σ {sd}",
                map.channel,
                map.std_param[i]
            );
            let total = map.std_param[i].hypot(map.std_form[i]);
            assert_eq!(map.std[i].to_bits(), total.to_bits(), "{:?} #{i}: the total σ", map.channel);
        }
    }
}

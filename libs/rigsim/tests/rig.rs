//! Behaviour of the virtual rig: determinism, effects off = steady-state MF, envelope and bad
//! setpoints, and each effect's signature.

use std::path::PathBuf;

use mftyre::{MfInput, UseMode};
use rigsim::{Effects, RigConfig, RigSample, RigSetpoint, SetpointRefusal, TyreParams, VirtualRig};

fn config_path() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../launch-config/virtual_rig.toml")
}

fn config() -> RigConfig {
    RigConfig::load(&config_path()).expect("launch-config/virtual_rig.toml")
}

fn params(cfg: &RigConfig) -> TyreParams {
    TyreParams::read_tir(&cfg.tyre_file).expect("tyre file")
}

fn rig_with(effects: Effects, seed: u64) -> VirtualRig {
    let mut cfg = config();
    cfg.effects = effects;
    let p = params(&cfg);
    VirtualRig::new(cfg, p, seed).expect("rig")
}

fn sp(mode: u8, sa: f64, sr: f64, fz: f64) -> RigSetpoint {
    RigSetpoint {
        mode,
        slip_angle_deg: sa,
        slip_ratio: sr,
        fz_n: fz,
        pressure_pa: 260_000.0,
        speed_mps: 16.6,
        ..RigSetpoint::default()
    }
}

/// A short mixed programme: roll up, lateral sweep, coupled longitudinal sweep, camber.
fn programme(rig: &mut VirtualRig) -> Vec<RigSample> {
    let mut out = Vec::new();
    rig.apply_setpoint(&sp(RigSetpoint::MODE_FREE_ROLLING, 0.0, 0.0, 6000.0)).unwrap();
    rig.run_until(6.0, &mut |s| out.push(s.clone()));
    for k in 0..400 {
        let t = 6.0 + k as f64 * 0.01;
        let sa = 8.0 * (t - 6.0).sin() * 2.0;
        rig.apply_setpoint(&sp(RigSetpoint::MODE_FREE_ROLLING, sa, 0.0, 6000.0)).unwrap();
        rig.run_until(t + 0.01, &mut |s| out.push(s.clone()));
    }
    for k in 0..400 {
        let t = 10.0 + k as f64 * 0.01;
        let sr = 0.2 * (t - 10.0).sin();
        let mut s = sp(RigSetpoint::MODE_COUPLED, 2.0, sr, 5000.0);
        s.camber_deg = -2.0;
        rig.apply_setpoint(&s).unwrap();
        rig.run_until(t + 0.01, &mut |s| out.push(s.clone()));
    }
    out
}

#[test]
fn same_config_and_seed_give_identical_samples() {
    let a = programme(&mut rig_with(Effects::ALL, 42));
    let b = programme(&mut rig_with(Effects::ALL, 42));
    assert_eq!(a.len(), b.len());
    assert!(a.len() > 1000);
    // Debug prints every f64 in its shortest round-trip form: equal text = equal bits.
    for (x, y) in a.iter().zip(&b) {
        assert_eq!(format!("{x:?}"), format!("{y:?}"));
    }
    let c = programme(&mut rig_with(Effects::ALL, 43));
    assert!(a.iter().zip(&c).any(|(x, y)| x.fyw_n != y.fyw_n), "another seed gives other noise");
}

#[test]
fn samples_come_at_the_publish_rate_with_sequential_seq() {
    let mut rig = rig_with(Effects::ALL, 1);
    let mut v = Vec::new();
    rig.run_until(1.0, &mut |s| v.push(s.clone()));
    assert_eq!(v.len(), 100);
    for (i, s) in v.iter().enumerate() {
        assert_eq!(s.seq, i as u64);
        assert!((s.runtime_s - (i + 1) as f64 * 0.01).abs() < 1e-9);
        assert_eq!(s.header.stamp, tyre_msgs::builtin_interfaces::Time::from_secs_f64(s.runtime_s));
    }
    assert!((rig.time_s() - 1.0).abs() < 1e-12);

    let mut cfg = config();
    cfg.publish_rate_hz = 1000;
    let p = params(&cfg);
    let mut rig = VirtualRig::new(cfg, p, 1).unwrap();
    let mut n = 0;
    rig.run_until(0.5, &mut |_| n += 1);
    assert_eq!(n, 500);
}

fn mf_at(params: &TyreParams, s: &RigSample) -> mftyre::MfOutput {
    mftyre::evaluate(
        params,
        UseMode::M111,
        &MfInput {
            fz_n: s.fzw_n,
            kappa: s.longslip,
            alpha_rad: s.slipangl_deg.to_radians(),
            gamma_rad: s.inclangl_deg.to_radians(),
            phit_per_m: 0.0,
            vx_mps: s.trajvelw_mps,
            p_pa: s.inflpres_pa,
            omega_radps: s.wheel_speed_radps,
        },
    )
}

#[test]
fn with_every_effect_off_samples_are_the_steady_state_model() {
    let mut rig = rig_with(Effects::NONE, 5);
    let p = rig.params().expect("MF tyre").clone();
    let samples = programme(&mut rig);
    let mut checked = 0;
    for s in samples.iter().filter(|s| s.trajvelw_mps > 2.0 && s.fzw_n > 100.0) {
        let m = mf_at(&p, s);
        let tol = 1e-6 * s.fzw_n.max(1.0);
        assert!((s.fx_n - m.fx_n).abs() < tol, "t {} fx {} vs {}", s.runtime_s, s.fx_n, m.fx_n);
        assert!((s.fyw_n - m.fy_n).abs() < tol, "t {} fy {} vs {}", s.runtime_s, s.fyw_n, m.fy_n);
        assert!((s.mzw_nm - m.mz_nm).abs() < tol, "mz");
        assert!((s.mxw_nm - m.mx_nm).abs() < tol, "mx");
        assert!((s.myw_nm - m.my_nm).abs() < 1e-3 * s.fzw_n, "my");
        // Loaded radius at the rig's 0.1 mm resolution.
        assert!((s.dstwowhc_m - m.rl_m).abs() <= 0.5e-4 + 1e-9, "rl {} vs {}", s.dstwowhc_m, m.rl_m);
        assert_eq!(s.fault_flags, 0);
        checked += 1;
    }
    assert!(checked > 500);
    // No thermal effect: temperatures stay where they started.
    let t0 = rig.config().environment.initial_tyre_temp_c;
    assert!(samples.iter().all(|s| (s.trdtempc_c - t0).abs() < 1e-9));
}

#[test]
fn with_only_noise_on_samples_are_the_model_plus_configured_noise() {
    let mut rig = rig_with(Effects::parse("noise").unwrap(), 9);
    let p = rig.params().expect("MF tyre").clone();
    let n = rig.config().noise.clone();
    let samples = programme(&mut rig);
    // The slip channels are noisy too, so compare in a window where the model is nearly linear
    // in them: free rolling at small slip angles.
    let res: Vec<f64> = samples
        .iter()
        .filter(|s| s.rig_mode == RigSetpoint::MODE_FREE_ROLLING && s.trajvelw_mps > 16.0 && s.slipangl_deg.abs() < 1.0)
        .map(|s| {
            // Free rolling: the true slip ratio is 0; LONGSLIP only carries sensor noise.
            let mut x = s.clone();
            x.longslip = 0.0;
            let m = mf_at(&p, &x);
            s.fx_n - m.fx_n
        })
        .collect();
    assert!(res.len() > 50, "{}", res.len());
    let mean = res.iter().sum::<f64>() / res.len() as f64;
    let sd = (res.iter().map(|r| (r - mean).powi(2)).sum::<f64>() / res.len() as f64).sqrt();
    // FX noise plus the FX change the slip-angle noise causes (tiny at small slip).
    assert!(mean.abs() < 3.0 * n.fx_n / (res.len() as f64).sqrt() + 5.0, "mean {mean}");
    assert!(sd > 0.7 * n.fx_n && sd < 1.5 * n.fx_n, "sd {sd} vs {}", n.fx_n);
}

#[test]
fn out_of_envelope_setpoints_are_refused_and_the_rig_holds_safe() {
    let mut rig = rig_with(Effects::ALL, 3);
    rig.apply_setpoint(&sp(RigSetpoint::MODE_FREE_ROLLING, 2.0, 0.0, 6000.0)).unwrap();
    rig.run_until(6.0, &mut |_| {});
    // Load above the tyre's rating (3 × Fz0 of load index 110).
    let err = rig.apply_setpoint(&sp(RigSetpoint::MODE_FREE_ROLLING, 2.0, 0.0, 21_000.0)).unwrap_err();
    assert!(matches!(err, SetpointRefusal::OutOfEnvelope { field: "fz_n", .. }), "{err:?}");
    assert!(err.to_string().contains("fz_n"), "{err}");
    let mut last = None;
    rig.run_until(12.0, &mut |s| last = Some(s.clone()));
    let s = last.take().unwrap();
    assert_ne!(s.fault_flags & RigSample::FAULT_ENVELOPE, 0);
    assert_eq!(s.rig_mode, RigSetpoint::MODE_SAFE);
    assert!(s.fzw_n.abs() < 200.0 && s.slipangl_deg.abs() < 0.1 && s.trajvelw_mps.abs() < 0.1, "{s:?}");
    assert!(rig.truth().safe);
    // Slip angle beyond the rig's range, and an unknown mode.
    assert!(matches!(
        rig.apply_setpoint(&sp(RigSetpoint::MODE_FREE_ROLLING, 45.0, 0.0, 6000.0)),
        Err(SetpointRefusal::OutOfEnvelope { field: "slip_angle_deg", .. })
    ));
    assert!(matches!(rig.apply_setpoint(&sp(9, 0.0, 0.0, 6000.0)), Err(SetpointRefusal::UnknownMode(9))));
    // A valid setpoint clears the fault.
    rig.apply_setpoint(&sp(RigSetpoint::MODE_FREE_ROLLING, 0.0, 0.0, 6000.0)).unwrap();
    rig.run_until(20.0, &mut |s| last = Some(s.clone()));
    let s = last.take().unwrap();
    assert_eq!(s.fault_flags & RigSample::FAULT_ENVELOPE, 0);
    assert!((s.fzw_n - 6000.0).abs() < 200.0);
}

#[test]
fn nan_and_absurd_setpoints_never_reach_the_samples() {
    let mut rig = rig_with(Effects::ALL, 4);
    rig.apply_setpoint(&sp(RigSetpoint::MODE_COUPLED, 3.0, 0.05, 6000.0)).unwrap();
    rig.run_until(6.0, &mut |_| {});
    let bad = [f64::NAN, f64::INFINITY, f64::NEG_INFINITY, 1e300, -1e300, f64::MAX, -0.0];
    let mut all = Vec::new();
    for (i, &v) in bad.iter().enumerate() {
        for field in 0..7 {
            let mut s = sp(RigSetpoint::MODE_COUPLED, 3.0, 0.05, 6000.0);
            match field {
                0 => s.slip_angle_deg = v,
                1 => s.slip_ratio = v,
                2 => s.fz_n = v,
                3 => s.camber_deg = v,
                4 => s.pressure_pa = v,
                5 => s.speed_mps = v,
                _ => s.belt_displacement_m = v,
            }
            let r = rig.apply_setpoint(&s);
            if !v.is_finite() {
                assert!(matches!(r, Err(SetpointRefusal::NotFinite { .. })), "{v} in field {field}: {r:?}");
            }
            let t = rig.time_s() + 0.05 + 0.01 * i as f64;
            rig.run_until(t, &mut |s| all.push(s.clone()));
        }
    }
    for s in &all {
        for v in [
            s.fx_n,
            s.fyw_n,
            s.fzw_n,
            s.mxw_nm,
            s.myw_nm,
            s.mzw_nm,
            s.slipangl_deg,
            s.longslip,
            s.inclangl_deg,
            s.inflpres_pa,
            s.trajvelw_mps,
            s.wheel_speed_radps,
            s.dstwowhc_m,
            s.trdtempi_c,
            s.trdtempc_c,
            s.trdtempo_c,
        ] {
            assert!(v.is_finite(), "{s:?}");
        }
        assert!(s.fzw_n < 20_000.0 && s.slipangl_deg.abs() < 31.0);
    }
}

#[test]
fn safe_mode_is_always_accepted() {
    let mut rig = rig_with(Effects::ALL, 4);
    let mut s = sp(RigSetpoint::MODE_SAFE, f64::NAN, f64::NAN, f64::NAN);
    s.speed_mps = f64::INFINITY;
    rig.apply_setpoint(&s).unwrap();
    let mut last = None;
    rig.run_until(1.0, &mut |s| last = Some(s.clone()));
    let l = last.unwrap();
    assert_eq!(l.rig_mode, RigSetpoint::MODE_SAFE);
    assert!(rig.truth().safe);
    assert!(l.fzw_n.abs() < 100.0 && l.trajvelw_mps.abs() < 0.1);
}

#[test]
fn fast_sweeps_show_mechanical_hysteresis_only_with_transient() {
    use rigsim::calibration::{SweepKind, freerolling_setup, settle};
    for (effects, lo, hi) in [(Effects::parse("transient").unwrap(), 2000.0, 6000.0), (Effects::NONE, 0.0, 50.0)] {
        let mut rig = rig_with(effects, 1);
        let setup = freerolling_setup(SweepKind::ConstantHigh);
        settle(&mut rig, &setup, 8.0).unwrap();
        let o = rigsim::calibration::run_sweep(&mut rig, &setup, -100.0, 1.0).unwrap();
        assert!(o.hysteresis_n >= lo && o.hysteresis_n <= hi, "{effects}: {}", o.hysteresis_n);
    }
}

#[test]
fn step_steer_builds_up_over_the_relaxation_length() {
    let mut rig = rig_with(Effects::parse("transient").unwrap(), 1);
    rig.apply_setpoint(&sp(RigSetpoint::MODE_FREE_ROLLING, 0.0, 0.0, 5100.0)).unwrap();
    rig.run_until(8.0, &mut |_| {});
    // Stop, then steer at standstill (static mode: wheel locked).
    let mut s = sp(RigSetpoint::MODE_FREE_ROLLING, 0.0, 0.0, 5100.0);
    s.speed_mps = 0.0;
    rig.apply_setpoint(&s).unwrap();
    rig.run_until(16.0, &mut |_| {});
    let mut st = sp(RigSetpoint::MODE_STATIC, 1.0, 0.0, 5100.0);
    st.speed_mps = 0.0;
    rig.apply_setpoint(&st).unwrap();
    let mut during = Vec::new();
    rig.run_until(17.0, &mut |s| during.push(s.fyw_n));
    assert!(during.iter().all(|f| f.abs() < 300.0), "no lateral force builds up at standstill");
    // Roll at 1 m/s holding the slip angle: FY vs travelled distance.
    let mut r = sp(RigSetpoint::MODE_FREE_ROLLING, 1.0, 0.0, 5100.0);
    r.speed_mps = 1.0;
    rig.apply_setpoint(&r).unwrap();
    let mut trace = Vec::new();
    let mut dist = 0.0;
    rig.run_until(30.0, &mut |s| {
        dist += s.trajvelw_mps * 0.01;
        trace.push((dist, s.fyw_n));
    });
    let sat = trace.last().unwrap().1;
    assert!(sat < -1000.0, "{sat}");
    let d63 = trace.iter().find(|(_, f)| *f <= 0.632 * sat).unwrap().0;
    // Belt acceleration costs a few cm; σ(1°) at 5,100 N is ~0.5 m.
    assert!(d63 > 0.2 && d63 < 0.9, "63 % at {d63} m");
}

#[test]
fn static_longitudinal_force_is_linear_in_belt_displacement() {
    let mut rig = rig_with(Effects::NONE, 1);
    let mut s = sp(RigSetpoint::MODE_STATIC, 0.0, 0.0, 5000.0);
    s.speed_mps = 0.0;
    rig.apply_setpoint(&s).unwrap();
    rig.run_until(2.0, &mut |_| {});
    s.belt_displacement_m = 0.01;
    rig.apply_setpoint(&s).unwrap();
    let mut pts = Vec::new();
    rig.run_until(4.0, &mut |x| pts.push(x.fx_n));
    let f1 = *pts.last().unwrap();
    s.belt_displacement_m = 0.005;
    rig.apply_setpoint(&s).unwrap();
    let mut p2 = Vec::new();
    rig.run_until(6.0, &mut |x| p2.push(x.fx_n));
    let f2 = *p2.last().unwrap();
    assert!(f1 < -1000.0, "{f1}");
    assert!((f1 / f2 - 2.0).abs() < 0.05, "{f1} {f2}");
}

/// Static mode reports the belt's real, signed velocity (with noise), so integrating TRAJVELW
/// over a static drag (LONGDISP, as the channels node does: trapezoid) gives back the belt's
/// displacement, there and back again.
#[test]
fn static_drag_trajvelw_integrates_to_the_belt_displacement() {
    for seed in [1, 2, 3] {
        let mut rig = rig_with(Effects::ALL, seed);
        let belt_speed = rig.config().rig.static_belt_speed_mps;
        let mut s = sp(RigSetpoint::MODE_FREE_ROLLING, 0.0, 0.0, 5000.0);
        s.speed_mps = 1.0;
        rig.apply_setpoint(&s).unwrap();
        rig.run_until(6.0, &mut |_| {});
        s.speed_mps = 0.0;
        rig.apply_setpoint(&s).unwrap();
        rig.run_until(9.0, &mut |_| {});
        s.mode = RigSetpoint::MODE_STATIC;
        rig.apply_setpoint(&s).unwrap();
        let mut samples = Vec::new();
        rig.run_until(10.0, &mut |x| samples.push(x.clone()));
        s.belt_displacement_m = 0.1;
        rig.apply_setpoint(&s).unwrap();
        rig.run_until(16.0, &mut |x| samples.push(x.clone()));
        let n_out = samples.len();
        s.belt_displacement_m = 0.04;
        rig.apply_setpoint(&s).unwrap();
        rig.run_until(20.0, &mut |x| samples.push(x.clone()));
        assert!(samples.iter().all(|x| x.rig_mode == RigSetpoint::MODE_STATIC));
        let longdisp = |xs: &[RigSample]| -> f64 {
            xs.windows(2)
                .map(|w| 0.5 * (w[0].trajvelw_mps + w[1].trajvelw_mps) * (w[1].runtime_s - w[0].runtime_s))
                .sum()
        };
        let out = longdisp(&samples[..n_out]);
        let back = longdisp(&samples);
        assert!((out - 0.1).abs() < 0.002, "seed {seed}: LONGDISP {out} m after a 0.1 m drag");
        assert!((back - 0.04).abs() < 0.002, "seed {seed}: LONGDISP {back} m after moving back to 0.04 m");
        // While the belt moves, TRAJVELW reads its speed (mean over the drag), signed.
        let moving: Vec<f64> = samples[100..550].iter().map(|x| x.trajvelw_mps).collect();
        let mean = moving.iter().sum::<f64>() / moving.len() as f64;
        assert!((mean - belt_speed).abs() < 0.05 * belt_speed, "seed {seed}: mean TRAJVELW {mean}");
        let returning: Vec<f64> = samples[n_out + 50..n_out + 250].iter().map(|x| x.trajvelw_mps).collect();
        let mean_back = returning.iter().sum::<f64>() / returning.len() as f64;
        assert!((mean_back + belt_speed).abs() < 0.05 * belt_speed, "seed {seed}: mean TRAJVELW {mean_back}");
    }
}

#[test]
fn pressure_change_takes_about_twenty_seconds() {
    let mut rig = rig_with(Effects::NONE, 1);
    rig.apply_setpoint(&sp(RigSetpoint::MODE_FREE_ROLLING, 0.0, 0.0, 5000.0)).unwrap();
    rig.run_until(2.0, &mut |_| {});
    let mut s = sp(RigSetpoint::MODE_FREE_ROLLING, 0.0, 0.0, 5000.0);
    s.pressure_pa = 330_000.0;
    rig.apply_setpoint(&s).unwrap();
    let mut v = Vec::new();
    rig.run_until(40.0, &mut |x| v.push((x.runtime_s - 2.0, x.inflpres_pa)));
    let t99 = v.iter().find(|(_, p)| *p >= 330_000.0 - 700.0).unwrap().0;
    assert!(t99 > 15.0 && t99 < 25.0, "{t99}");
}

#[test]
fn wear_lowers_the_radius_in_tenth_millimetre_steps() {
    let mut cfg = config();
    cfg.tyre.wear_rate_multiplier = 5.0;
    let p = params(&cfg);
    let mut rig = VirtualRig::new(cfg, p, 1).unwrap();
    rig.apply_setpoint(&sp(RigSetpoint::MODE_FREE_ROLLING, 0.0, 0.0, 6000.0)).unwrap();
    let mut r0 = Vec::new();
    rig.run_until(8.0, &mut |s| r0.push(s.dstwowhc_m));
    for _ in 0..6 {
        rig.apply_setpoint(&sp(RigSetpoint::MODE_FREE_ROLLING, 12.0, 0.0, 6000.0)).unwrap();
        let t = rig.time_s() + 5.0;
        rig.run_until(t, &mut |_| {});
        rig.apply_setpoint(&sp(RigSetpoint::MODE_FREE_ROLLING, -12.0, 0.0, 6000.0)).unwrap();
        let t = rig.time_s() + 5.0;
        rig.run_until(t, &mut |_| {});
    }
    rig.apply_setpoint(&sp(RigSetpoint::MODE_FREE_ROLLING, 0.0, 0.0, 6000.0)).unwrap();
    let t = rig.time_s() + 60.0;
    rig.run_until(t, &mut |_| {});
    let mut r1 = Vec::new();
    let t = rig.time_s() + 2.0;
    rig.run_until(t, &mut |s| r1.push(s.dstwowhc_m));
    let truth = rig.truth();
    assert!(truth.tread_worn_mm > 0.2, "{truth:?}");
    for r in r0.iter().chain(&r1) {
        assert!(((r / 1e-4) - (r / 1e-4).round()).abs() < 1e-6, "quantised: {r}");
    }
    let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len() as f64;
    let drop_mm = (mean(&r0[r0.len() - 100..]) - mean(&r1)) * 1e3;
    assert!((drop_mm - truth.tread_worn_mm).abs() < 0.3, "radius drop {drop_mm} mm vs wear {}", truth.tread_worn_mm);
}

/// Peak |FYW| of a ±10° sweep at 6,000 N from the rig's present state.
fn peak_fy(rig: &mut VirtualRig) -> f64 {
    let mut peak: f64 = 0.0;
    for k in 0..=200 {
        let sa = -10.0 + 0.1 * k as f64;
        rig.apply_setpoint(&sp(RigSetpoint::MODE_FREE_ROLLING, sa, 0.0, 6000.0)).unwrap();
        let t = rig.time_s() + 0.01;
        rig.run_until(t, &mut |s| peak = peak.max(s.fyw_n.abs()));
    }
    peak
}

#[test]
fn hot_tyre_loses_grip_and_new_tyre_gains_it() {
    let mut rig = rig_with(Effects::parse("thermal_grip").unwrap(), 1);
    rig.apply_setpoint(&sp(RigSetpoint::MODE_FREE_ROLLING, 0.0, 0.0, 6000.0)).unwrap();
    rig.run_until(8.0, &mut |_| {});
    rig.soak(50.0);
    let warm = peak_fy(&mut rig);
    rig.soak(110.0);
    let hot = peak_fy(&mut rig);
    assert!(hot < 0.95 * warm, "hot {hot} warm {warm}");

    let mut rig = rig_with(Effects::parse("break_in").unwrap(), 1);
    rig.apply_setpoint(&sp(RigSetpoint::MODE_FREE_ROLLING, 0.0, 0.0, 6000.0)).unwrap();
    rig.run_until(8.0, &mut |_| {});
    let new = peak_fy(&mut rig);
    assert!(rig.truth().break_in_deficit > 0.05);
    // Severe sliding breaks it in.
    rig.apply_setpoint(&sp(RigSetpoint::MODE_FREE_ROLLING, 20.0, 0.0, 6000.0)).unwrap();
    let t = rig.time_s() + 60.0;
    rig.run_until(t, &mut |_| {});
    let broken_in = peak_fy(&mut rig);
    assert!(broken_in > 1.08 * new, "new {new} broken in {broken_in}");
    assert!(rig.truth().break_in_deficit < 0.01);
}

#[test]
fn coupled_drive_is_noisier_on_mx_than_free_rolling() {
    let mut rig = rig_with(Effects::parse("noise").unwrap(), 2);
    let sd = |v: &[f64]| {
        let m = v.iter().sum::<f64>() / v.len() as f64;
        (v.iter().map(|x| (x - m).powi(2)).sum::<f64>() / v.len() as f64).sqrt()
    };
    rig.apply_setpoint(&sp(RigSetpoint::MODE_FREE_ROLLING, 0.0, 0.0, 6000.0)).unwrap();
    rig.run_until(8.0, &mut |_| {});
    let mut free = Vec::new();
    rig.run_until(12.0, &mut |s| free.push(s.mxw_nm));
    rig.apply_setpoint(&sp(RigSetpoint::MODE_COUPLED, 0.0, 0.0, 6000.0)).unwrap();
    rig.run_until(14.0, &mut |_| {});
    let mut coupled = Vec::new();
    rig.run_until(18.0, &mut |s| coupled.push(s.mxw_nm));
    assert!(sd(&coupled) > 5.0 * sd(&free), "{} vs {}", sd(&coupled), sd(&free));
}

#[test]
fn slip_ratio_faster_than_the_bead_holds_slips_on_the_rim() {
    for (rate, expect) in [(0.4, false), (1.2, true)] {
        let mut rig = rig_with(Effects::parse("rim_slip").unwrap(), 2);
        rig.apply_setpoint(&sp(RigSetpoint::MODE_COUPLED, 0.0, 0.0, 6000.0)).unwrap();
        rig.run_until(8.0, &mut |_| {});
        let n = (0.25 / rate * 100.0) as usize;
        for k in 0..=n {
            let sr = (rate * k as f64 * 0.01).min(0.25);
            rig.apply_setpoint(&sp(RigSetpoint::MODE_COUPLED, 0.0, sr, 6000.0)).unwrap();
            let t = rig.time_s() + 0.01;
            rig.run_until(t, &mut |_| {});
        }
        assert_eq!(rig.truth().rim_slip_steps > 0, expect, "rate {rate}: {:?}", rig.truth());
    }
}

#[test]
fn chatter_appears_on_a_worn_tyre_at_high_load_and_slip() {
    let mut cfg = config();
    cfg.effects = Effects::parse("chatter,wear").unwrap();
    cfg.tyre.initial_tread_depth_mm = 2.5;
    let p = params(&cfg);
    let mut rig = VirtualRig::new(cfg, p, 1).unwrap();
    rig.apply_setpoint(&sp(RigSetpoint::MODE_FREE_ROLLING, 15.0, 0.0, 11_000.0)).unwrap();
    rig.run_until(8.0, &mut |_| {});
    let mut v = Vec::new();
    rig.run_until(9.0, &mut |s| v.push(s.fyw_n));
    let (lo, hi) = v.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &x| (a.min(x), b.max(x)));
    assert!(hi - lo > 500.0, "chatter range {}", hi - lo);
}

#[test]
fn camber_splits_inner_and_outer_tread_temperatures() {
    let mut rig = rig_with(Effects::parse("thermal").unwrap(), 1);
    let mut s = sp(RigSetpoint::MODE_FREE_ROLLING, 8.0, 0.0, 6000.0);
    s.camber_deg = -4.0;
    rig.apply_setpoint(&s).unwrap();
    let mut last = None;
    rig.run_until(20.0, &mut |x| last = Some(x.clone()));
    let l = last.unwrap();
    assert!(l.trdtempi_c > l.trdtempo_c + 1.0, "{l:?}");
}

#[test]
fn config_file_matches_the_calibrated_defaults() {
    let mut cfg = config();
    cfg.tyre_file = RigConfig::default().tyre_file;
    assert_eq!(cfg, RigConfig::default());
}

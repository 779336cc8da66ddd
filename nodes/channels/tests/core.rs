//! The channels core on synthetic sample streams.

use approx::assert_relative_eq;
use channels::{ChannelsConfig, ChannelsCore, ChannelsOutput};
use tyre_msgs::std_msgs::Header;
use tyre_msgs::{ProcedureState, RigSample, RigSetpoint};

fn state(t: f64, phase: u8, section: &str, sweep: &str, idx: u32) -> ProcedureState {
    ProcedureState {
        header: Header::iso_w(t),
        phase,
        procedure: "p".into(),
        section: section.into(),
        sweep_name: sweep.into(),
        sweep_index: idx,
        ..ProcedureState::default()
    }
}

fn sample(t: f64, seq: u64) -> RigSample {
    RigSample {
        header: Header::iso_w(t),
        seq,
        runtime_s: t,
        fzw_n: 6000.0,
        inflpres_pa: 2.6e5,
        trajvelw_mps: 16.6,
        wheel_speed_radps: 16.6 / 0.36,
        dstwowhc_m: 0.37,
        trdtempc_c: 45.0,
        rig_mode: RigSetpoint::MODE_COUPLED,
        ..RigSample::default()
    }
}

/// A longitudinal sweep after a free-rolling reference: the Calspan slip ratio uses VX1/W1 of
/// the reference; sliding energy is the trapezoid of P; segments zero runtime and LONGDISP; the
/// summary comes at the sweep's end and again with its cool-down.
#[test]
fn calspan_energy_segments_and_summary() {
    let mut c = ChannelsCore::new(ChannelsConfig::default()).unwrap();
    let dt = 0.01;
    let mut outs: Vec<ChannelsOutput> = Vec::new();
    let mut seq = 0;
    let mut t = 0.0;
    let mut feed = |c: &mut ChannelsCore, t: f64, s: RigSample| {
        let o = c.on_sample(&s);
        outs.push(o);
        let _ = t;
    };
    c.on_procedure_state(&state(0.0, ProcedureState::PHASE_FREE_ROLLING_REF, "long", "", 0));
    // Reference: free rolling at Re = 0.36 m.
    for _ in 0..100 {
        t += dt;
        seq += 1;
        feed(&mut c, t, sample(t, seq));
    }
    c.on_procedure_state(&state(t, ProcedureState::PHASE_SWEEP, "long", "Brk_sw1_X_1", 0));
    // Sweep: wheel 10 % faster (SR = 0.1), FX = 2,000 N for 1 s.
    let t_sweep0 = t + dt;
    for _ in 0..100 {
        t += dt;
        seq += 1;
        let mut s = sample(t, seq);
        s.wheel_speed_radps *= 1.1;
        s.fx_n = 2000.0;
        s.longslip = 0.1;
        feed(&mut c, t, s);
    }
    c.on_procedure_state(&state(t, ProcedureState::PHASE_THERMAL_PAUSE, "long", "Brk_sw1_X_1", 0));
    for _ in 0..300 {
        t += dt;
        seq += 1;
        feed(&mut c, t, sample(t, seq));
    }
    c.on_procedure_state(&state(t, ProcedureState::PHASE_SETTLE, "long", "", 0));
    t += dt;
    seq += 1;
    feed(&mut c, t, sample(t, seq));

    let live: Vec<_> = outs.iter().map(|o| &o.live).collect();
    let in_sweep: Vec<_> = live.iter().filter(|l| l.segment == "Brk_sw1_X_1").collect();
    assert_eq!(in_sweep.len(), 100);
    assert_relative_eq!(in_sweep[0].zeroed_runtime_s, 0.0);
    assert_relative_eq!(in_sweep[0].longdisp_m, 0.0);
    assert_relative_eq!(in_sweep[99].zeroed_runtime_s, 0.99, epsilon = 1e-9);
    assert_relative_eq!(in_sweep[99].longdisp_m, 16.6 * 0.99, epsilon = 1e-9);
    for l in &in_sweep {
        assert_relative_eq!(l.slip_ratio_calspan, 0.1, epsilon = 1e-9);
        assert_relative_eq!(l.px_w, 2000.0 * 0.1 * 16.6, epsilon = 1e-6);
    }
    // 99 trapezoids of constant power.
    assert_relative_eq!(in_sweep[99].acsldeny_j, 3320.0 * 0.99, epsilon = 1e-6);
    // Outside a sweep without a reference, no Calspan slip ratio.
    assert!(live.last().unwrap().slip_ratio_calspan.is_nan());
    // Effective radius model learnt from the reference hold: SR ≈ 0.1 in the sweep.
    assert_relative_eq!(in_sweep[50].slip_ratio_effective_radius, 0.1, epsilon = 1e-9);

    let sums: Vec<_> = outs.iter().flat_map(|o| o.sweep_summaries.clone()).collect();
    assert_eq!(sums.len(), 2, "{sums:?}");
    assert!(!sums[0].cool_down_complete && sums[1].cool_down_complete);
    let s = &sums[1];
    assert_eq!(s.sweep_name, "Brk_sw1_X_1");
    assert_relative_eq!(s.start_time_s, t_sweep0, epsilon = 1e-9);
    assert_relative_eq!(s.duration_s, 0.99, epsilon = 1e-9);
    assert_relative_eq!(s.sliding_energy_j, 3320.0 * 0.99, epsilon = 1e-6);
    assert_relative_eq!(s.cool_down_s, 3.0, epsilon = 0.011);
    assert_relative_eq!(s.slip_ratio_max, 0.1, epsilon = 1e-9);
    assert_relative_eq!(s.mean_fz_n, 6000.0);
    assert_relative_eq!(s.peak_fx_n, 2000.0);
}

/// States may arrive before or after the sample with the same stamp (live vs log order): the
/// outputs are the same.
#[test]
fn state_order_at_equal_stamps_does_not_matter() {
    let run = |state_first: bool| {
        let mut c = ChannelsCore::new(ChannelsConfig::default()).unwrap();
        let mut out = Vec::new();
        for i in 1..=600u64 {
            let t = i as f64 * 0.01;
            let mut s = sample(t, i);
            s.slipangl_deg = 5.0 * (t * 2.0).sin();
            s.fyw_n = -1000.0 * s.slipangl_deg;
            let st = match i {
                100 => Some(state(t, ProcedureState::PHASE_SWEEP, "a", "Free_sw1_1", 0)),
                400 => Some(state(t, ProcedureState::PHASE_THERMAL_PAUSE, "a", "Free_sw1_1", 0)),
                500 => Some(state(t, ProcedureState::PHASE_SWEEP, "b", "Free_sw2_1", 1)),
                _ => None,
            };
            if state_first && let Some(st) = &st {
                c.on_procedure_state(st);
            }
            out.push(c.on_sample(&s));
            if !state_first && let Some(st) = &st {
                c.on_procedure_state(st);
            }
        }
        out.push(c.finish());
        format!("{out:?}")
    };
    assert_eq!(run(true), run(false));
}

/// NaN channels and fault flags give NaN or skipped values, never a panic or a poisoned sum.
#[test]
fn bad_samples_do_not_poison() {
    let mut c = ChannelsCore::new(ChannelsConfig::default()).unwrap();
    c.on_procedure_state(&state(0.0, ProcedureState::PHASE_SWEEP, "a", "x", 0));
    let mut last = None;
    for i in 1..200u64 {
        let t = i as f64 * 0.01;
        let mut s = sample(t, i);
        s.slipangl_deg = 3.0;
        s.fyw_n = -3000.0;
        if i % 7 == 0 {
            s.fyw_n = f64::NAN;
            s.trajvelw_mps = f64::NAN;
            s.trdtempc_c = f64::NAN;
        }
        if i % 11 == 0 {
            s.fault_flags = RigSample::FAULT_FORCE;
        }
        last = Some(c.on_sample(&s));
    }
    let l = last.unwrap().live;
    assert!(l.acsldeny_j.is_finite() && l.acsldeny_j > 0.0);
    assert!(l.longdisp_m.is_finite());
    let f = c.finish();
    assert_eq!(f.sweep_summaries.len(), 2);
    assert!(f.sweep_summaries[0].peak_temp_c == 45.0);
}

/// Static drags (thesis §3.12.2): the wheel locked, the belt moved ~0.1 m; FX is a spring up to
/// the friction limit. The section's end gives the stiffness, averaged over the repeats.
#[test]
fn static_drags_give_the_longitudinal_stiffness_averaged_over_repeats() {
    let mut c = ChannelsCore::new(ChannelsConfig::default()).unwrap();
    let (cx, limit, v_belt) = (4.0e5, 5000.0, 0.05);
    let mut t = 0.0;
    let mut seq = 0;
    let mut derived = Vec::new();
    for rep in 0..4u32 {
        c.on_procedure_state(&state(
            t,
            ProcedureState::PHASE_SWEEP,
            "static_long_2.6bar",
            "Static_sw1_StaticDrag_D0.1_1",
            rep,
        ));
        let (mut x, mut v_prev) = (0.0, 0.0);
        for i in 0..400 {
            t += 0.01;
            seq += 1;
            let mut s = sample(t, seq);
            s.rig_mode = RigSetpoint::MODE_STATIC;
            s.wheel_speed_radps = 0.0;
            // Belt still for 0.5 s, then moving.
            s.trajvelw_mps = if i < 50 { 0.0 } else { v_belt };
            // The belt's displacement as the rig's belt integrates it (a ramp in speed).
            x += 0.5 * (v_prev + s.trajvelw_mps) * 0.01;
            v_prev = s.trajvelw_mps;
            s.fx_n = -(cx * x).min(limit) + if i % 2 == 0 { 20.0 } else { -20.0 };
            derived.extend(c.on_sample(&s).derived);
        }
        c.on_procedure_state(&state(t, ProcedureState::PHASE_SETTLE, "static_long_2.6bar", "", rep));
    }
    c.on_procedure_state(&state(t, ProcedureState::PHASE_COMPLETE, "static_long_2.6bar", "", 0));
    t += 0.01;
    derived.extend(c.on_sample(&sample(t, seq + 1)).derived);
    derived.extend(c.finish().derived);
    let k: Vec<_> = derived.iter().filter(|d| d.quantity == channels::Quantity::LongitudinalStiffness).collect();
    assert_eq!(k.len(), 1, "{derived:?}");
    assert_eq!(k[0].n_points, 4);
    assert_relative_eq!(k[0].value, cx, max_relative = 0.03);
}

/// Samples lost on the way (a jump in `RigSample.seq`) are a gap: the sliding energy and the
/// travelled distance are not integrated across it, even when the stamps are close together.
#[test]
fn a_gap_in_the_sample_counter_is_not_integrated_across() {
    let run = |lose: bool| {
        let mut c = ChannelsCore::new(ChannelsConfig::default()).unwrap();
        c.on_procedure_state(&state(0.0, ProcedureState::PHASE_SWEEP, "long", "Brk_sw1_X_1", 0));
        let mut last = None;
        for i in 1..=100u64 {
            // Samples 41..=60 never arrive; the stamps still advance by 10 ms per sample.
            if lose && (41..=60).contains(&i) {
                continue;
            }
            let t = i as f64 * 0.01;
            let mut s = sample(t, i);
            s.fx_n = 2000.0;
            s.longslip = 0.1;
            last = Some(c.on_sample(&s).live);
        }
        (last.expect("samples"), c.seq_gaps())
    };
    let (whole, gaps) = run(false);
    assert_eq!(gaps, 0);
    let (gappy, gaps) = run(true);
    assert_eq!(gaps, 1);
    // 99 intervals without loss; with 20 samples lost, 21 intervals are missing, not bridged.
    assert_relative_eq!(gappy.longdisp_m, whole.longdisp_m * 78.0 / 99.0, epsilon = 1e-9);
    assert_relative_eq!(gappy.acsldeny_j, whole.acsldeny_j * 78.0 / 99.0, epsilon = 1e-6);
}

//! Behaviour of the thermal gate, fail-safe cases first, all on synthetic data in rig time.

use thermal::{
    AlarmLevel, TempWeights, ThermalAlarm, ThermalCheck, ThermalConfig, ThermalGate, ThermalOutput, WarmUpStatus,
};
use tyre_msgs::{ProcedureState, RigSample, ThermalState};

const DT_S: f64 = 0.01; // 100 Hz, a typical rig sample rate

fn sample(seq: u64, inner_c: f64, centre_c: f64, outer_c: f64) -> RigSample {
    RigSample { seq, trdtempi_c: inner_c, trdtempc_c: centre_c, trdtempo_c: outer_c, ..RigSample::default() }
}

/// Deterministic zero-mean pseudo-noise in [−amp, amp] (xorshift), so tests need no RNG crate.
struct Noise(u64);

impl Noise {
    fn next(&mut self, amp: f64) -> f64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        amp * ((self.0 >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0)
    }
}

/// A small harness: feeds centre-channel samples at 100 Hz and keeps every alarm.
struct Rig {
    gate: ThermalGate,
    t_s: f64,
    seq: u64,
    alarms: Vec<ThermalAlarm>,
    noise: Noise,
}

impl Rig {
    fn new(config: ThermalConfig) -> Self {
        Self {
            gate: ThermalGate::new(config).unwrap(),
            t_s: 0.0,
            seq: 0,
            alarms: Vec::new(),
            noise: Noise(0x9E37_79B9_7F4A_7C15),
        }
    }

    fn default() -> Self {
        Self::new(ThermalConfig::default())
    }

    fn step(&mut self) -> ThermalOutput {
        let out = self.gate.step(self.t_s);
        self.alarms.extend(out.alarms.iter().cloned());
        out
    }

    /// One sample of the centre temperature (the default weighting), then a step.
    fn feed(&mut self, centre_c: f64) -> ThermalOutput {
        self.t_s += DT_S;
        self.seq += 1;
        let s = sample(self.seq, 20.0, centre_c, 20.0);
        self.gate.on_sample(self.t_s, &s);
        self.step()
    }

    /// Feeds `temp(t)` plus ±0.02 °C sensor flicker for `duration_s`; returns every output.
    fn run(&mut self, duration_s: f64, temp: impl Fn(f64) -> f64) -> Vec<ThermalOutput> {
        let n = (duration_s / DT_S).round() as usize;
        (0..n)
            .map(|_| {
                let t = self.t_s + DT_S;
                let flicker = self.noise.next(0.02);
                self.feed(temp(t) + flicker)
            })
            .collect()
    }

    /// Lets time pass with no samples, stepping at 10 Hz.
    fn silence(&mut self, duration_s: f64) -> ThermalOutput {
        let n = (duration_s / 0.1).round() as usize;
        let mut out = None;
        for _ in 0..n {
            self.t_s += 0.1;
            out = Some(self.step());
        }
        out.unwrap()
    }

    fn alarms_of(&self, check: ThermalCheck, level: AlarmLevel) -> usize {
        self.alarms.iter().filter(|a| a.check == check && a.level == level).count()
    }
}

fn cooling(t0_s: f64, start_c: f64, ambient_c: f64, tau_s: f64) -> impl Fn(f64) -> f64 {
    move |t| ambient_c + (start_c - ambient_c) * (-(t - t0_s) / tau_s).exp()
}

#[test]
fn idle_without_pause() {
    let mut rig = Rig::default();
    let out = rig.run(2.0, |_| 30.0).pop().unwrap();
    assert_eq!(out.state.status, ThermalState::STATUS_IDLE);
    assert!(!out.state.gate_open);
    assert!(rig.alarms.is_empty());
}

#[test]
fn releases_at_baseline() {
    let mut rig = Rig::default();
    rig.gate.begin_pause(0.0);
    // 70 °C cooling towards 25 °C with τ = 20 s crosses 45 °C at 20·ln(45/20) = 16.2 s.
    let outs = rig.run(20.0, cooling(0.0, 70.0, 25.0, 20.0));
    let first_open = outs.iter().position(|o| o.state.gate_open).unwrap();
    let t_open = (first_open + 1) as f64 * DT_S;
    assert!((16.2..16.7).contains(&t_open), "opened at {t_open} s");
    for o in &outs[..first_open] {
        assert_eq!(o.state.status, ThermalState::STATUS_WAITING);
        assert!(o.state.filtered_temp_c > 45.0);
    }
    let o = &outs[first_open];
    assert_eq!(o.state.status, ThermalState::STATUS_RELEASED);
    assert!(o.state.filtered_temp_c <= 45.0);
    assert_eq!(o.state.predicted_wait_s, 0.0);
    assert!(!o.next_sweep_started_hot);
    assert!(rig.alarms.is_empty(), "{:?}", rig.alarms);
    // The release latches for the rest of the pause, and the pause's end makes it idle.
    assert!(outs[first_open..].iter().all(|o| o.state.gate_open));
    rig.gate.end_pause(rig.t_s);
    assert_eq!(rig.step().state.status, ThermalState::STATUS_IDLE);
}

#[test]
fn holds_above_baseline() {
    let mut rig = Rig::default();
    rig.gate.begin_pause(0.0);
    let outs = rig.run(100.0, |_| 50.0);
    assert!(outs.iter().all(|o| !o.state.gate_open));
    assert!(outs.iter().all(|o| o.state.status == ThermalState::STATUS_WAITING));
    let last = outs.last().unwrap();
    assert!((last.state.pause_elapsed_s - 100.0).abs() < 1e-6);
    assert!(last.state.predicted_wait_s > 0.0 && last.state.predicted_wait_s <= 20.0 + 1e-9);
    assert!(rig.alarms.is_empty(), "{:?}", rig.alarms);
}

#[test]
fn nan_holds_and_alarms_then_recovers() {
    let mut rig = Rig::default();
    rig.gate.begin_pause(0.0);
    rig.run(2.0, |_| 50.0);
    // The tread has cooled below the baseline, but the sensor now returns NaN.
    let outs = rig.run(3.0, |_| f64::NAN);
    assert!(outs.iter().all(|o| !o.state.gate_open));
    assert!(outs.iter().all(|o| o.state.status == ThermalState::STATUS_FAULT));
    assert!(outs[0].state.fault.contains("TRDTEMPC"), "{}", outs[0].state.fault);
    assert_eq!(rig.alarms_of(ThermalCheck::Sensor, AlarmLevel::Error), 1);
    // Valid again at 44 °C: the gate waits `recovery_s` (1 s) of healthy data before releasing.
    let outs = rig.run(2.0, |_| 44.0);
    let first_open = outs.iter().position(|o| o.state.gate_open).unwrap();
    let held_s = (first_open + 1) as f64 * DT_S;
    assert!((1.0..1.1).contains(&held_s), "released {held_s} s after recovery");
    assert_eq!(outs[first_open].state.status, ThermalState::STATUS_RELEASED);
    assert_eq!(rig.alarms_of(ThermalCheck::Sensor, AlarmLevel::Warn), 1);
}

#[test]
fn nan_in_unweighted_channel_is_ignored() {
    let mut rig = Rig::default();
    rig.gate.begin_pause(0.0);
    for i in 0..100 {
        let t = (i + 1) as f64 * DT_S;
        rig.gate.on_sample(t, &sample(i, f64::NAN, 44.0 + 1e-3 * i as f64, 300.0));
    }
    let out = rig.gate.step(1.0);
    assert_eq!(out.state.status, ThermalState::STATUS_RELEASED);
    assert!(out.alarms.is_empty());
}

#[test]
fn absurd_and_flagged_readings_hold() {
    let mut rig = Rig::default();
    rig.gate.begin_pause(0.0);
    let outs = rig.run(1.0, |_| -50.0);
    assert!(outs.iter().all(|o| o.state.status == ThermalState::STATUS_FAULT));
    assert!(outs[0].state.fault.contains("absurd"), "{}", outs[0].state.fault);

    let mut rig = Rig::default();
    rig.gate.begin_pause(0.0);
    for i in 0..100 {
        let t = (i + 1) as f64 * DT_S;
        let mut s = sample(i, 40.0, 40.0 + 1e-3 * i as f64, 40.0);
        s.fault_flags = RigSample::FAULT_TEMPERATURE;
        rig.gate.on_sample(t, &s);
        let out = rig.gate.step(t);
        assert_eq!(out.state.status, ThermalState::STATUS_FAULT);
        assert!(!out.state.gate_open);
    }
}

#[test]
fn stuck_sensor_holds_and_alarms() {
    let mut rig = Rig::default();
    rig.gate.begin_pause(0.0);
    rig.run(3.0, cooling(0.0, 70.0, 25.0, 30.0));
    // The channel freezes at exactly 60.0 °C while the cooling model expects ~1 °C/s.
    let outs: Vec<_> = (0..1000).map(|_| rig.feed(60.0)).collect();
    let first_fault = outs.iter().position(|o| o.state.status == ThermalState::STATUS_FAULT).unwrap();
    let detect_s = (first_fault + 1) as f64 * DT_S;
    assert!((4.9..5.1).contains(&detect_s), "detected after {detect_s} s");
    assert!(outs[..first_fault].iter().all(|o| !o.state.gate_open));
    assert!(outs[first_fault..].iter().all(|o| !o.state.gate_open));
    assert!(outs[first_fault].state.fault.contains("stuck"));
    assert_eq!(rig.alarms_of(ThermalCheck::Stuck, AlarmLevel::Error), 1);
}

#[test]
fn constant_reading_while_idle_is_not_stuck() {
    let mut rig = Rig::default();
    let outs: Vec<_> = (0..2000).map(|_| rig.feed(25.0)).collect();
    assert!(outs.iter().all(|o| o.state.status == ThermalState::STATUS_IDLE));
    assert!(rig.alarms.is_empty());
}

#[test]
fn frozen_channel_during_a_sweep_is_stuck() {
    let mut rig = Rig::default();
    let sweep = ProcedureState { phase: ProcedureState::PHASE_SWEEP, ..ProcedureState::default() };
    rig.gate.on_procedure_state(0.0, &sweep);
    let outs: Vec<_> = (0..600).map(|_| rig.feed(40.0)).collect();
    assert_eq!(outs.last().unwrap().state.status, ThermalState::STATUS_FAULT);
    // The sequencer then enters the pause: the frozen 40 °C must not release it.
    let pause = ProcedureState { phase: ProcedureState::PHASE_THERMAL_PAUSE, ..ProcedureState::default() };
    rig.gate.on_procedure_state(rig.t_s, &pause);
    assert!(rig.gate.in_pause());
    let outs: Vec<_> = (0..200).map(|_| rig.feed(40.0)).collect();
    assert!(outs.iter().all(|o| !o.state.gate_open));
    assert_eq!(rig.alarms_of(ThermalCheck::Stuck, AlarmLevel::Error), 1);
}

#[test]
fn stale_stream_holds_and_alarms() {
    let mut rig = Rig::default();
    rig.gate.begin_pause(0.0);
    rig.run(2.0, |_| 50.0);
    let out = rig.silence(0.9);
    assert_eq!(out.state.status, ThermalState::STATUS_WAITING);
    let out = rig.silence(0.2);
    assert_eq!(out.state.status, ThermalState::STATUS_FAULT);
    assert!(out.state.fault.contains("stale"), "{}", out.state.fault);
    let out = rig.silence(5.0);
    assert_eq!(out.state.status, ThermalState::STATUS_FAULT);
    assert!(!out.state.gate_open);
    assert_eq!(rig.alarms_of(ThermalCheck::Stale, AlarmLevel::Error), 1);
    // Samples return below the baseline: release only after the recovery time.
    let outs = rig.run(2.0, |_| 44.0);
    let first_open = outs.iter().position(|o| o.state.gate_open).unwrap();
    assert!(first_open as f64 * DT_S >= 0.99);
}

#[test]
fn pause_without_any_sample_goes_stale() {
    let mut rig = Rig::default();
    rig.gate.begin_pause(0.0);
    let out = rig.silence(1.5);
    assert_eq!(out.state.status, ThermalState::STATUS_FAULT);
    assert!(!out.state.gate_open);
    let out = rig.silence(150.0);
    assert_eq!(out.state.status, ThermalState::STATUS_FAULT);
    assert!(!out.state.gate_open, "the time-out must not release a faulty gate");
    assert_eq!(rig.alarms_of(ThermalCheck::Timeout, AlarmLevel::Error), 1);
}

#[test]
fn flash_spike_is_filtered() {
    let mut rig = Rig::default();
    rig.gate.begin_pause(0.0);
    rig.run(2.0, |_| 47.0);
    // A 150 °C flash for 50 ms (5 samples) does not move the filtered temperature …
    let outs = rig.run(0.05, |_| 150.0);
    let after = rig.run(1.0, |_| 47.0);
    for o in outs.iter().chain(&after) {
        assert!(o.state.filtered_temp_c < 47.1, "{}", o.state.filtered_temp_c);
        assert_eq!(o.state.status, ThermalState::STATUS_WAITING);
    }
    assert!(outs.iter().any(|o| o.state.weighted_temp_c > 140.0));
    // … and a 50 ms drop-out to 20 °C does not release the gate early.
    let outs = rig.run(0.05, |_| 20.0);
    let after = rig.run(1.0, |_| 47.0);
    assert!(outs.iter().chain(&after).all(|o| !o.state.gate_open));
    // Once released, a flash does not disturb the filtered temperature either.
    rig.run(1.0, |_| 44.0);
    let outs = rig.run(0.05, |_| 150.0);
    assert!(outs.iter().all(|o| o.state.gate_open && o.state.filtered_temp_c < 44.1));
    assert!(rig.alarms.is_empty(), "{:?}", rig.alarms);
}

#[test]
fn timeout_releases_with_alarm_and_marks_started_hot() {
    let mut rig = Rig::default();
    rig.gate.begin_pause(0.0);
    let outs = rig.run(125.0, |_| 60.0);
    let first_open = outs.iter().position(|o| o.state.gate_open).unwrap();
    let t_open = (first_open + 1) as f64 * DT_S;
    assert!((119.99..120.02).contains(&t_open), "opened at {t_open} s");
    let o = &outs[first_open];
    assert_eq!(o.state.status, ThermalState::STATUS_TIMED_OUT);
    assert!(o.next_sweep_started_hot);
    assert_eq!(o.alarms.len(), 1);
    assert_eq!(o.alarms[0].check, ThermalCheck::Timeout);
    assert_eq!(o.alarms[0].check.as_str(), "thermal_timeout");
    assert_eq!(o.alarms[0].level, AlarmLevel::Warn);
    assert!(outs[first_open..].iter().all(|o| o.state.gate_open));
    assert_eq!(rig.alarms_of(ThermalCheck::Timeout, AlarmLevel::Warn), 1);
    // The mark survives the pause's end (the sweep starts then) and clears with the next pause.
    rig.gate.end_pause(rig.t_s);
    assert!(rig.step().next_sweep_started_hot);
    rig.gate.begin_pause(rig.t_s);
    assert!(!rig.step().next_sweep_started_hot);
}

#[test]
fn fault_at_timeout_still_holds() {
    let mut rig = Rig::default();
    rig.gate.begin_pause(0.0);
    rig.run(100.0, |_| 60.0);
    let outs = rig.run(30.0, |_| 300.0);
    assert!(outs.iter().all(|o| !o.state.gate_open));
    assert!(outs.iter().all(|o| o.state.status == ThermalState::STATUS_FAULT));
    assert!(!outs.last().unwrap().next_sweep_started_hot);
    assert_eq!(rig.alarms_of(ThermalCheck::Timeout, AlarmLevel::Error), 1);
    assert_eq!(rig.alarms_of(ThermalCheck::Timeout, AlarmLevel::Warn), 0);
    // Healthy again past the time-out but still hot: now the time-out releases, marked hot.
    let outs = rig.run(2.0, |_| 60.0);
    let o = outs.iter().find(|o| o.state.gate_open).unwrap();
    assert_eq!(o.state.status, ThermalState::STATUS_TIMED_OUT);
    assert!(o.next_sweep_started_hot);
}

#[test]
fn weighted_temperature() {
    let config =
        ThermalConfig { weights: TempWeights { inner: 1.0, centre: 2.0, outer: 1.0 }, ..ThermalConfig::default() };
    let mut gate = ThermalGate::new(config).unwrap();
    gate.begin_pause(0.0);
    gate.on_sample(0.01, &sample(1, 40.0, 50.0, 60.0));
    let out = gate.step(0.01);
    assert_eq!(out.state.weighted_temp_c, 50.0);
    assert_eq!(out.state.trdtempi_c, 40.0);
    assert_eq!(out.state.trdtempo_c, 60.0);
    // Centre 44 alone would release; the hot shoulders keep the weighted 47 °C above baseline.
    for i in 2..100 {
        let t = i as f64 * DT_S;
        gate.on_sample(t, &sample(i, 50.0, 44.0 + 1e-3 * i as f64, 50.0));
    }
    let out = gate.step(1.0);
    assert!((out.state.filtered_temp_c - 47.05).abs() < 0.1);
    assert_eq!(out.state.status, ThermalState::STATUS_WAITING);
}

/// Feeds a noisy exponential cool-down and returns the predicted wait after `data_s` of it,
/// with the true remaining time.
fn prediction_after(data_s: f64, ambient_c: f64, tau_s: f64, config: ThermalConfig) -> (f64, f64, f64) {
    let mut rig = Rig::new(config);
    rig.gate.begin_pause(0.0);
    let start_c = 70.0;
    let f = cooling(0.0, start_c, ambient_c, tau_s);
    let mut noise = Noise(7);
    let mut out = None;
    for _ in 0..(data_s / DT_S).round() as usize {
        let t = rig.t_s + DT_S;
        out = Some(rig.feed(f(t) + noise.next(0.2)));
    }
    let out = out.unwrap();
    let total_s = tau_s * ((start_c - ambient_c) / (45.0 - ambient_c)).ln();
    (out.state.predicted_wait_s, total_s - rig.t_s, out.state.cooling_time_constant_s)
}

#[test]
fn cooling_model_predicts_the_wait() {
    // Priors (τ 40 s, ambient 25 °C) against a tyre with τ 30 s: within 10 % after 5 s.
    let (predicted_s, true_s, tau_s) = prediction_after(5.0, 25.0, 30.0, ThermalConfig::default());
    let rel = (predicted_s - true_s).abs() / true_s;
    assert!(rel < 0.10, "predicted {predicted_s:.2} s, true {true_s:.2} s, tau {tau_s:.1}");

    // Ambient off by 5 °C and τ by a factor of 2 (τ 80 s): still within 10 % after 5 s.
    let (predicted_s, true_s, tau_s) = prediction_after(5.0, 30.0, 80.0, ThermalConfig::default());
    let rel = (predicted_s - true_s).abs() / true_s;
    assert!(rel < 0.10, "predicted {predicted_s:.2} s, true {true_s:.2} s, tau {tau_s:.1}");

    // Given long enough, the data override the priors: τ within 5 % after 30 s.
    let (predicted_s, true_s, tau_s) = prediction_after(30.0, 30.0, 60.0, ThermalConfig::default());
    assert!((tau_s - 60.0).abs() / 60.0 < 0.05, "tau {tau_s:.1}");
    assert!((predicted_s - true_s).abs() / true_s < 0.05);
}

#[test]
fn next_pause_is_seeded_with_the_fitted_time_constant() {
    let mut rig = Rig::default();
    rig.gate.begin_pause(0.0);
    rig.run(15.0, cooling(0.0, 70.0, 25.0, 20.0));
    let fitted = rig.gate.cooling_model();
    assert!((fitted.tau_s - 20.0).abs() < 1.0, "{fitted:?}");
    rig.gate.end_pause(rig.t_s);
    let prior = rig.gate.cooling_model();
    assert_eq!(prior.tau_s, fitted.tau_s);
    assert_eq!(prior.data_s, 0.0);
    assert_eq!(rig.step().state.cooling_time_constant_s, fitted.tau_s);
    // The sequencer's ETA for a pause after a sweep that ends at 70 °C: about 20·ln(45/20).
    let predicted_s = rig.gate.predict_pause_s(70.0);
    assert!((predicted_s - 16.2).abs() < 1.0, "{predicted_s}");
    assert_eq!(rig.gate.predict_pause_s(40.0), 0.0);
    assert_eq!(rig.gate.predict_pause_s(f64::NAN), 120.0);
}

#[test]
fn warm_up_completion() {
    let mut rig = Rig::default();
    assert_eq!(rig.gate.warm_up_status(), WarmUpStatus::Unknown);
    rig.run(5.0, |t| 20.0 + 4.0 * t);
    assert!(!rig.gate.warm_up_reached());
    assert_eq!(rig.gate.warm_up_status(), WarmUpStatus::Below);
    rig.run(0.6, |_| 42.0);
    assert!(rig.gate.warm_up_reached());
    assert_eq!(rig.gate.warm_up_status(), WarmUpStatus::InRange);
    rig.run(0.6, |_| 50.0);
    assert_eq!(rig.gate.warm_up_status(), WarmUpStatus::Above);
    rig.gate.reset_warm_up();
    assert!(!rig.gate.warm_up_reached());
}

#[test]
fn out_of_order_sample_is_dropped_with_a_warning() {
    let mut gate = ThermalGate::new(ThermalConfig::default()).unwrap();
    gate.on_sample(1.0, &sample(1, 20.0, 50.0, 20.0));
    gate.on_sample(0.5, &sample(2, 20.0, 10.0, 20.0));
    let out = gate.step(1.0);
    assert_eq!(out.state.trdtempc_c, 50.0);
    assert_eq!(out.alarms.len(), 1);
    assert_eq!(out.alarms[0].level, AlarmLevel::Warn);
    assert_eq!(out.alarms[0].check, ThermalCheck::Sensor);
}

/// Samples lost on the way (a jump in `RigSample.seq`) are a gap: the spike median restarts
/// instead of mixing readings from before and after it.
#[test]
fn a_gap_in_the_sample_counter_restarts_the_median() {
    let filtered_after = |jump: u64| {
        let mut gate = ThermalGate::new(ThermalConfig::default()).unwrap();
        let mut t = 0.0;
        for seq in 1..=20 {
            t += DT_S;
            gate.on_sample(t, &sample(seq, 20.0, 40.0, 20.0));
        }
        // Three samples later (30 ms, well inside the 0.5 s median window) the tyre reads 60 °C.
        t += 3.0 * DT_S;
        gate.on_sample(t, &sample(20 + jump, 20.0, 60.0, 20.0));
        (gate.step(t).state.filtered_temp_c, gate.seq_gaps())
    };
    // Consecutive numbers: one 60 °C reading among twenty at 40 °C is a spike the median rejects.
    assert_eq!(filtered_after(1), (40.0, 0));
    // Two samples lost: the median starts again from the first reading after the gap.
    assert_eq!(filtered_after(3), (60.0, 1));
}

//! Property: whatever the sensor does, the gate opens only on a trustworthy temperature.

use proptest::prelude::*;
use thermal::{ThermalConfig, ThermalGate};
use tyre_msgs::{RigSample, ThermalState};

#[derive(Debug, Clone)]
enum Event {
    /// `count` samples `dt_s` apart at this centre temperature (with a flicker, as a real laser
    /// has, unless `frozen`).
    Run { count: usize, dt_s: f64, temp_c: f64, frozen: bool },
    /// Time passes without samples, then the gate is stepped.
    Silence { dt_s: f64 },
    /// The sequencer starts or ends a pause.
    Pause(bool),
}

fn temperature() -> impl Strategy<Value = f64> {
    prop_oneof![
        8 => 20.0..80.0f64,
        1 => Just(f64::NAN),
        1 => Just(f64::INFINITY),
        1 => prop_oneof![-100.0..-41.0f64, 251.0..500.0f64],
        1 => 140.0..200.0f64,
        2 => Just(44.0),
    ]
}

fn event() -> impl Strategy<Value = Event> {
    prop_oneof![
        6 => (1..400usize, 0.005..0.1f64, temperature(), prop::bool::weighted(0.1))
            .prop_map(|(count, dt_s, temp_c, frozen)| Event::Run { count, dt_s, temp_c, frozen }),
        1 => (0.1..30.0f64).prop_map(|dt_s| Event::Silence { dt_s }),
        2 => any::<bool>().prop_map(Event::Pause),
    ]
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(200))]

    #[test]
    fn gate_opens_only_on_trustworthy_temperature(events in prop::collection::vec(event(), 1..60)) {
        let config = ThermalConfig::default();
        let mut gate = ThermalGate::new(config.clone()).unwrap();
        let mut now_s = 0.0;
        let mut last_sample_s: Option<f64> = None;
        let mut last_bad_s: Option<f64> = None;
        let mut seq = 0;
        let mut was_open = false;
        let mut check = |gate: &mut ThermalGate,
                         now_s: f64,
                         last_sample_s: Option<f64>,
                         last_bad_s: Option<f64>|
         -> Result<(), TestCaseError> {
            let out = gate.step(now_s);
            let s = &out.state;
            prop_assert_eq!(
                s.gate_open,
                s.status == ThermalState::STATUS_RELEASED || s.status == ThermalState::STATUS_TIMED_OUT
            );
            if s.gate_open {
                prop_assert!(gate.in_pause());
                prop_assert!(s.fault.is_empty());
                // No invalid reading within the recovery time …
                if let Some(bad_s) = last_bad_s {
                    prop_assert!(now_s - bad_s >= config.recovery_s, "opened {} s after a bad reading", now_s - bad_s);
                }
                // … and the stream is live.
                let last = last_sample_s.expect("opened without any sample");
                prop_assert!(now_s - last < config.stale_after_s);
                // A release happens at or below the baseline (it then latches for the pause).
                if !was_open && s.status == ThermalState::STATUS_RELEASED {
                    prop_assert!(s.filtered_temp_c <= config.baseline_c);
                }
                if s.status == ThermalState::STATUS_TIMED_OUT {
                    prop_assert!(out.next_sweep_started_hot);
                    prop_assert!(s.pause_elapsed_s >= config.timeout_s);
                }
            }
            was_open = s.gate_open;
            if s.status == ThermalState::STATUS_FAULT {
                prop_assert!(!s.fault.is_empty());
            }
            prop_assert!(s.predicted_wait_s.is_finite() && s.predicted_wait_s >= 0.0);
            Ok(())
        };
        for event in events {
            match event {
                Event::Run { count, dt_s, temp_c, frozen } => {
                    for k in 0..count {
                        now_s += dt_s;
                        seq += 1;
                        let flicker = if frozen { 0.0 } else { 0.01 * (k % 3) as f64 };
                        let sample = RigSample { seq, trdtempc_c: temp_c + flicker, ..RigSample::default() };
                        gate.on_sample(now_s, &sample);
                        last_sample_s = Some(now_s);
                        if !(config.absurd_min_c..=config.absurd_max_c).contains(&temp_c) {
                            last_bad_s = Some(now_s);
                        }
                        check(&mut gate, now_s, last_sample_s, last_bad_s)?;
                    }
                }
                Event::Silence { dt_s } => {
                    now_s += dt_s;
                    check(&mut gate, now_s, last_sample_s, last_bad_s)?;
                }
                Event::Pause(true) => gate.begin_pause(now_s),
                Event::Pause(false) => gate.end_pause(now_s),
            }
        }
    }
}

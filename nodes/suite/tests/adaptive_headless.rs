//! The adaptive plan end to end, headless: virtual rig, thermal gate, sequencer, live fit. A
//! small procedure keeps it short: a warm-up, a heating sweep and a rolling-radius hold (fixed),
//! then four force & moment candidates at two pressures. The slot follows the hold directly (no
//! thermal pause between): the plan must still decide with a model that has seen the hold.

use std::path::Path;
use suite::sink::{MessageSink, Outgoing};
use suite::{Headless, ProcedureChoice, RunSpec, RunSummary};

const MINI: &str = r#"
[procedure]
name = "mini_adaptive"
title = "Mini adaptive"
config_tag = "FreeRoll"
mode = "free_rolling"

[[section]]
name = "warmup"
pressure = "mid"

[[section.step]]
kind = "warm_up"
blocks = 1
loads = [0.9]
peak_deg = 8.0
rate_dps = 4.0
roll_s = 5.0

[[section]]
name = "heating_sweep"
pressure = "mid"

[[section.step]]
kind = "sweep"
peak_deg = 12.0
low_rate_dps = 2.0
high_rate_dps = 30.0
threshold_deg = 4.0
loads = [1.0]

[[section]]
name = "rolling_radius"
pressure = "mid"

[[section.step]]
kind = "rolling_radius"
loads = [0.6, 1.4]
speeds_mps = [16.6]
hold_s = 4.0

[[section]]
name = "force_moment"
pressures = ["low", "high"]

[[section.step]]
kind = "sweep"
peak_deg = 12.0
low_rate_dps = 2.0
high_rate_dps = 30.0
threshold_deg = 4.0
loads = [0.6, 1.4]
"#;

#[derive(Default)]
struct Capture {
    decisions: Vec<String>,
    /// `sweep_index` of the newest data step (not a warm-up) the sequencer has run.
    newest_data_sweep: Option<u32>,
    /// Per decision: the newest data sweep run before it, and the sweep its model's data reach.
    reach: Vec<(Option<u32>, Option<u32>)>,
    /// The sweep running now (empty outside sweeps), and the rig time of the last sample.
    sweep: String,
    last_sample_s: Option<f64>,
    /// Per sweep: sliding energy from the measured forces and slips \[J\], as the planner's
    /// model predicts it (|FX|·|κ|·V + |FY|·|tan α|·V).
    measured_sliding_j: std::collections::HashMap<String, f64>,
}

impl MessageSink for Capture {
    fn put(&mut self, _t: f64, msg: Outgoing<'_>) -> Result<(), mcaplog::LogWriteError> {
        match msg {
            Outgoing::Procedure(st) => {
                let sweeping = st.phase == tyre_msgs::ProcedureState::PHASE_SWEEP;
                if sweeping && st.section != "warmup" {
                    self.newest_data_sweep = Some(st.sweep_index);
                }
                self.sweep = if sweeping { st.sweep_name.clone() } else { String::new() };
            }
            Outgoing::Sample(x) => {
                if let Some(t0) = self.last_sample_s.filter(|_| !self.sweep.is_empty()) {
                    let slip_w = x.trajvelw_mps.abs()
                        * (x.fx_n.abs() * x.longslip.abs() + x.fyw_n.abs() * x.slipangl_deg.to_radians().tan().abs());
                    *self.measured_sliding_j.entry(self.sweep.clone()).or_default() += slip_w * (x.runtime_s - t0);
                }
                self.last_sample_s = Some(x.runtime_s);
            }
            Outgoing::Diagnostics(d) => {
                for s in d.status.iter().filter(|s| s.name == "sequencer: adaptive") {
                    self.decisions.push(s.message.clone());
                    let model = s.values.iter().find(|kv| kv.key == "model_last_sweep_index");
                    self.reach.push((self.newest_data_sweep, model.map(|kv| kv.value.parse().unwrap())));
                }
            }
            _ => {}
        }
        Ok(())
    }
}

fn headless(dir: &Path) -> (Headless, RunSpec) {
    let file = dir.join("mini_adaptive.toml");
    std::fs::write(&file, MINI).unwrap();
    let mut spec =
        RunSpec::new(&Path::new(env!("CARGO_MANIFEST_DIR")).join("../../launch-config"), ProcedureChoice::Gs2mf);
    spec.procedure_file = file;
    spec.seed = 1;
    let cfg = sequencer::SequencerConfig { plan: sequencer::PlanKind::Adaptive, ..Default::default() };
    let h = Headless::new(&spec, thermal::ThermalConfig::default(), cfg)
        .expect("adaptive suite builds")
        .with_live_fit(livefit::LiveFitConfig::default());
    (h, spec)
}

fn run(dir: &Path) -> (RunSummary, Capture, Vec<String>) {
    let (mut h, _) = headless(dir);
    // The fixed plan holds no force & moment sweep: those are the candidates.
    assert!(!h.plan().sections.is_empty());
    let fm = h.plan().sections.iter().position(|s| s.name.starts_with("force_moment")).unwrap();
    assert!(!h.plan().steps.iter().any(|s| s.section_index == fm && s.kind == procedure::StepKind::Sweep));
    let mut cap = Capture::default();
    let summary = h.run(&mut cap, &mut |_, _| {}).expect("run");
    let ran: Vec<String> = h.plan().steps.iter().filter(|s| s.sweep_index.is_some()).map(|s| s.name.clone()).collect();
    (summary, cap, ran)
}

#[test]
fn adaptive_plan_chooses_runs_logs_and_repeats_its_decisions() {
    let dir = tempfile::tempdir().unwrap();
    let (a, cap, ran) = run(dir.path());
    println!("{}", a.table());
    for c in &a.adaptive {
        println!("{:>7.0} s slot {} {}: {}", c.rig_time_s, c.slot, c.sweep, c.reason);
    }
    assert!(a.completed, "{a:?}");
    assert!(!a.alarms.iter().any(|x| x.check == "envelope"), "{:?}", a.alarms);
    // At least one choice, and the slot closed at the end with a reason.
    let chosen: Vec<&str> = a.adaptive.iter().filter(|c| !c.sweep.is_empty()).map(|c| c.sweep.as_str()).collect();
    assert!(!chosen.is_empty());
    let last = a.adaptive.last().unwrap();
    assert!(last.sweep.is_empty() && !last.reason.is_empty(), "{last:?}");
    assert!(chosen.len() <= 4);
    // Every choice ran (it is in the plan the sequencer ran) and was logged on /diagnostics.
    for c in &chosen {
        assert!(ran.iter().any(|r| r == c), "{c} chosen, not run: {ran:?}");
    }
    assert_eq!(cap.decisions.len(), a.adaptive.len());
    assert!(cap.decisions.iter().any(|m| m.contains("chose ")));
    // Each choice after the first model counts the tread it wears, predicted by the live model:
    // a sweep of a few seconds slides some kJ (µm of tread at the thesis's 0.208 mm/MJ), and the
    // reason says what it costs.
    for c in a.adaptive.iter().filter(|c| !c.sweep.is_empty() && c.value.is_finite()) {
        assert!(c.wear_mm > 1e-5 && c.wear_mm < 0.2, "{c:?}");
        assert!(c.reason.contains("of tread"), "{}", c.reason);
        // The live model's sliding energy against what the rig's measured forces and slips give.
        let measured_mm = c.wear_rate_mm_per_mj * 1e-6 * cap.measured_sliding_j[&c.sweep];
        println!("{}: wear predicted {:.5} mm, from the measurements {measured_mm:.5} mm", c.sweep, c.wear_mm);
        assert!((c.wear_mm / measured_mm - 1.0).abs() < 0.25, "{c:?}: measured {measured_mm} mm");
    }
    // Every decision with a model was made with one that had seen every data step before it,
    // the first too (it follows the rolling-radius hold without a pause).
    let first_hold = ran.iter().position(|r| r.contains("RollingRadius")).expect("the hold ran") as u32;
    assert!(cap.reach[0].0 >= Some(first_hold), "{:?}", cap.reach);
    for (i, (newest, model)) in cap.reach.iter().enumerate() {
        if let Some(model) = model {
            assert!(
                Some(*model) >= *newest,
                "decision {i} made with a model of data to sweep {model}: {:?}",
                cap.reach
            );
        }
    }
    assert!(cap.reach[0].1.is_some(), "the heating sweep gives a model before the first decision");
    // Same config and seed: the same decisions.
    let (b, _, _) = run(dir.path());
    let names = |s: &RunSummary| s.adaptive.iter().map(|c| c.sweep.clone()).collect::<Vec<_>>();
    assert_eq!(names(&a), names(&b));
    assert_eq!(a.total_rig_time_s, b.total_rig_time_s);
}

/// The summary of a recorded adaptive run (what a DDS run's summary is built from) lists the
/// same decisions as the live one, from their `/diagnostics` records.
#[test]
fn the_summary_of_an_adaptive_log_lists_its_decisions() {
    let dir = tempfile::tempdir().unwrap();
    let (mut h, spec) = headless(dir.path());
    let path = dir.path().join("adaptive.mcap");
    let mut sink = suite::McapSink::create(&path, "/rig", &h.metadata(&spec)).expect("log");
    let live = h.run(&mut sink, &mut |_, _| {}).expect("run");
    sink.finish().expect("finish");
    let log = mcaplog::LogReader::open(&path).expect("read back");
    let from_log = suite::summary_from_log(&log, "/rig").expect("summary");
    assert!(!live.adaptive.is_empty());
    assert_eq!(from_log.adaptive.len(), live.adaptive.len(), "{:?}", from_log.adaptive);
    let close = |a: f64, b: f64, tol: f64| (a.is_nan() && b.is_nan()) || (a - b).abs() <= tol * b.abs().max(1.0);
    for (l, d) in from_log.adaptive.iter().zip(&live.adaptive) {
        assert_eq!((l.slot, &l.sweep, &l.reason), (d.slot, &d.sweep, &d.reason));
        assert!(close(l.rig_time_s, d.rig_time_s, 1e-3), "{l:?} vs {d:?}");
        // The record carries 4-6 decimals.
        assert!(close(l.value, d.value, 1e-5) && close(l.cost_s, d.cost_s, 1e-2), "{l:?} vs {d:?}");
        assert!(close(l.wear_mm, d.wear_mm, 1e-4), "{l:?} vs {d:?}");
        assert!(close(l.error_pct, d.error_pct, 1e-4) && close(l.error_after_pct, d.error_after_pct, 1e-4));
        assert!(close(l.target_pct, d.target_pct, 1e-4), "{l:?} vs {d:?}");
    }
}

/// A tyre that wears four times as fast as the configured rate (the virtual rig's wear
/// multiplier): once the monitor has measured the rate from the rolling radius, the plan prices
/// the tread of its choices at that rate, read from the monitor's `/diagnostics` record.
/// BrkDrv alone (its reference holds repeat load cases, so the rate is measured early).
#[test]
fn the_plan_prices_wear_at_the_rate_the_monitor_measures_on_the_tyre() {
    let mut spec =
        RunSpec::new(&Path::new(env!("CARGO_MANIFEST_DIR")).join("../../launch-config"), ProcedureChoice::BrkDrv);
    spec.seed = 2;
    spec.wear_multiplier = Some(4.0);
    let cfg = sequencer::SequencerConfig { plan: sequencer::PlanKind::Adaptive, ..Default::default() };
    let configured = cfg.adaptive.wear_mm_per_mj;
    let mut h = Headless::new(&spec, thermal::ThermalConfig::default(), cfg)
        .expect("adaptive suite builds")
        .with_live_fit(livefit::LiveFitConfig::default());
    let a = h.run(&mut Capture::default(), &mut |_, _| {}).expect("run");
    let choices: Vec<_> = a.adaptive.iter().filter(|c| !c.sweep.is_empty()).collect();
    for c in &choices {
        println!("{:>7.0} s {}: {:.3} mm/MJ, {:.4} mm", c.rig_time_s, c.sweep, c.wear_rate_mm_per_mj, c.wear_mm);
    }
    assert!(a.completed && choices.len() >= 10, "{a:?}");
    // Before the monitor can measure (two holds of one load case), the configured rate.
    assert_eq!(choices[0].wear_rate_mm_per_mj, configured);
    // The rig's own rate: its true tread loss over the sliding energy it counts is
    // `configured` × 4 by construction; the monitor measures it from the radius.
    let true_rate = 4.0 * configured;
    let last = choices.last().unwrap();
    assert!(
        (last.wear_rate_mm_per_mj / true_rate - 1.0).abs() < 0.15,
        "last choice priced at {} mm/MJ, the tyre wears {true_rate} mm/MJ",
        last.wear_rate_mm_per_mj
    );
    assert!(last.reason.contains("mm/MJ, measured"), "{}", last.reason);
    // Most of the run is priced at the measured rate, not the configured one.
    let measured = choices.iter().filter(|c| c.wear_rate_mm_per_mj > 2.0 * configured).count();
    assert!(
        2 * measured > choices.len(),
        "{measured} of {} choices priced above twice the configured rate",
        choices.len()
    );
}

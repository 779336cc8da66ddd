//! The live fit on the virtual rig (MF tyre, sensor noise): the FreeRolling procedure run
//! headless with the live fit in the loop, then checked against the offline fit of the same
//! log, the rig's true tyre and a second run (another seed) the fit never saw. Not timed: speed
//! is `tyrerig bench live-fit`'s business. ~1–2 min in release on 2 cores.

use std::path::Path;

use livefit::LiveFitConfig;
use livefit::replay::{feed, inputs_of_log};
use mffit::accuracy::{Support, compare};
use suite::{Headless, McapSink, ProcedureChoice, RunSpec};
use tyre_msgs::{ModelStage, ModelState, RosMessage};

fn spec(seed: u64) -> RunSpec {
    let launch = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../launch-config");
    let mut spec = RunSpec::new(&launch, ProcedureChoice::FreeRolling);
    spec.effects = Some("noise".into());
    spec.seed = seed;
    spec
}

/// Runs `spec` headless into `log`, with the live fit when `live` is set; returns the run.
fn run(spec: &RunSpec, log: &Path, live: bool) -> Headless {
    let mut h = Headless::new(spec, thermal::ThermalConfig::default(), sequencer::SequencerConfig::default()).unwrap();
    if live {
        h = h.with_live_fit(LiveFitConfig::default());
    }
    let md = h.metadata(spec);
    let mut sink = McapSink::create(log, "/rig", &md).unwrap();
    let summary = h.run(&mut sink, &mut |_, _| {}).unwrap();
    sink.finish().unwrap();
    assert!(summary.completed);
    h
}

fn stage<'a>(st: &'a ModelState, name: &str) -> &'a ModelStage {
    st.stages.iter().find(|s| s.stage == name).unwrap_or_else(|| panic!("no stage {name}"))
}

#[test]
fn live_fit_on_a_freerolling_run_matches_the_offline_fit_and_its_bands_hold() {
    let dir = tempfile::tempdir().unwrap();
    let (log, other_log) = (dir.path().join("fr1.mcap"), dir.path().join("fr2.mcap"));
    let h = run(&spec(1), &log, true);
    run(&spec(2), &other_log, false);
    let (_, truth) = suite::headless::rig_config(&spec(1)).unwrap();

    // The log holds a model state per update, the last one final, the stages' status honest.
    let reader = mcaplog::LogReader::open(&log).unwrap();
    let topic = reader.topics().into_iter().find(|t| t.ros_type == ModelState::ros_type_name()).unwrap().topic;
    assert_eq!(topic, "/rig/model/state");
    let states: Vec<ModelState> = reader.typed::<ModelState>(&topic).unwrap().into_iter().map(|(_, s)| s).collect();
    assert!(states.len() > 10, "{} model states", states.len());
    let last = states.last().unwrap();
    assert!(last.final_update && states[..states.len() - 1].iter().all(|s| !s.final_update));
    assert_eq!(last.update_index as usize, states.len());
    assert!(states.windows(2).all(|w| w[0].segments_used <= w[1].segments_used));
    for name in ["fy_pure", "mz_pure"] {
        let s = stage(last, name);
        assert_eq!(s.status, ModelStage::IDENTIFIED, "{name}: {}", s.status_reason);
        assert!(!s.coefficients.is_empty() && s.coefficients.iter().all(|c| c.std.is_finite() && c.std > 0.0));
    }
    // FreeRolling has no drive/brake data: the longitudinal stages wait, and say so.
    let fx = stage(last, "fx_pure");
    assert_eq!(fx.status, ModelStage::WAITING);
    assert!(fx.status_reason.contains("not enough data"), "{}", fx.status_reason);
    // Before the sweeps at other cambers, FY pure cannot be identified yet.
    let first_fit = states.iter().find(|s| stage(s, "fy_pure").status != ModelStage::WAITING).unwrap();
    assert!(first_fit.update_index < last.update_index);
    // The maps cover the documented grid, FY and MZ with finite uncertainty, FX not yet fitted.
    assert_eq!(last.grid_fz_n.len() * 11 * 5 * 3, 660);
    let map = |c: &str| last.maps.iter().find(|m| m.channel == c).unwrap();
    assert_eq!(map("FYW").value.len(), 660);
    assert!(map("FYW").std.iter().all(|s| s.is_finite() && *s >= 0.0));
    assert!(map("MZW").std.iter().all(|s| s.is_finite()));
    assert!(map("FX").std.iter().all(|s| s.is_nan()));
    // Each map says where it is extrapolated: the run holds one pressure of the grid's three.
    let k_fy = last.maps.iter().position(|m| m.channel == "FYW").unwrap();
    let fy_extrapolated = (0..660).filter(|&i| last.extrapolated(k_fy, i)).count();
    assert_eq!(last.maps_extrapolated.len(), 660 * last.maps.len());
    assert!(fy_extrapolated > 0 && fy_extrapolated < 660, "{fy_extrapolated} of 660 extrapolated");
    // Each map carries the band for a repeat measurement: finite where its stage is fitted.
    assert_eq!(last.maps_repeat_band.len(), last.maps.len());
    assert!(last.repeat_band(k_fy) > 0.0 && last.repeat_band(k_fy).is_finite(), "{:?}", last.maps_repeat_band);
    let k_fx = last.maps.iter().position(|m| m.channel == "FX").unwrap();
    assert!(last.repeat_band(k_fx).is_nan(), "FX is not fitted yet: {:?}", last.maps_repeat_band);

    // The same log replayed into a fresh core gives the same model states (the log reproduces it).
    let mut core = livefit::LiveFit::new(LiveFitConfig { fz0_n: Some(h.plan().fz0_n), ..LiveFitConfig::default() });
    let mut replayed = Vec::new();
    for input in inputs_of_log(&reader).unwrap() {
        if feed(&mut core, &input) == livefit::Trigger::Update {
            replayed.push(core.update());
        }
    }
    assert_eq!(replayed.len() + 1, states.len());
    for (a, b) in replayed.iter().zip(&states) {
        assert_eq!(a.segments_used, b.segments_used);
        assert_eq!(a.last_sweep, b.last_sweep);
        for (x, y) in a.stages.iter().zip(&b.stages) {
            assert_eq!((x.status, x.points), (y.status, y.points), "{}", x.stage);
        }
    }

    // End of run: the live model against the truth is as good as the offline fit (within 10 %).
    let live = h.live_fit_result().unwrap();
    let data = mffit::logs::read_log(&log).unwrap();
    let offline = mffit::fit(&data, &mffit::FitOptions { folds: 0, ..mffit::FitOptions::default() }).unwrap();
    let acc = |r: &mffit::FitResult| compare(&truth, &r.params, &r.range, &Support::of_fit(r));
    let (live_acc, off_acc) = (acc(live), acc(&offline));
    for (l, o) in live_acc.iter().zip(&off_acc) {
        eprintln!("{:<12} live {:.3} % offline {:.3} %", l.channel, l.rms_pct_of_peak, o.rms_pct_of_peak);
        if ["FY pure", "MZ pure", "MX pure"].contains(&l.channel.as_str()) {
            assert!(l.rms_pct_of_peak <= 1.1 * o.rms_pct_of_peak, "{}: live {l:?} offline {o:?}", l.channel);
        }
    }

    // Calibration on the other run: the 95 % band for a new measurement holds 90–98 % of them.
    let other = mffit::logs::read_log(&other_log).unwrap();
    let reference = |mode: mftyre::UseMode, x: &mftyre::MfInput| mftyre::evaluate(&truth, mode, x);
    let cov = mffit::prediction::coverage(live, &other, &LiveFitConfig::default().fit_options(), Some(&reference));
    for c in &cov {
        eprintln!("{c:?}");
    }
    for ch in ["FYW", "MZW"] {
        let c = cov.iter().find(|c| c.channel == ch).unwrap();
        assert!(c.points > 500, "{c:?}");
        assert!((90.0..=98.0).contains(&c.measured_in_band_pct), "{c:?}");
    }
}

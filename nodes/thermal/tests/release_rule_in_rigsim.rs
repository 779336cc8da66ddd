//! The virtual rig's calibration (`rigsim::calibration`) times cool-downs with this gate's
//! release rule, restated there because `libs/` do not depend on `nodes/`. This test fails when
//! the gate's defaults change and the restatement does not.

use rigsim::calibration::{BASELINE_C, GATE_MEDIAN_WINDOW_S, GATE_MIN_SAMPLES};
use thermal::ThermalConfig;

#[test]
fn rigsim_times_cool_downs_with_the_gate_s_default_rule() {
    let gate = ThermalConfig::default();
    assert_eq!(GATE_MEDIAN_WINDOW_S, gate.spike_filter.window_s, "median window");
    assert_eq!(GATE_MIN_SAMPLES, gate.spike_filter.min_samples as usize, "fewest samples");
    assert_eq!(BASELINE_C, gate.baseline_c, "baseline");
    // The calibration reads TRDTEMPC alone: the gate's default weights must be centre only.
    let w = gate.weights;
    assert_eq!((w.inner, w.centre, w.outer), (0.0, 1.0, 0.0), "temperature weights");
}

//! The force-over-slip trace of one sweep, bounded in size for a browser.
//!
//! A GS2MF sweep at 1 kHz has up to ~30,000 samples; a plot needs a few thousand. Points are
//! kept at a stride that doubles whenever the trace is full (every other point is dropped), so
//! any sweep is drawn evenly from its first to its latest point with at most `max_points`.

use serde::Serialize;
use tyre_msgs::RigSample;

/// One sweep's points, column-wise (Foxglove plots `…fyw_n[:]` against `…slip_angle_deg[:]`).
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct SweepTrace {
    pub sweep_name: String,
    pub sweep_index: u32,
    /// Samples of the sweep seen so far (before decimation).
    pub samples: u64,
    pub slip_angle_deg: Vec<f64>,
    pub slip_ratio: Vec<f64>,
    pub fyw_n: Vec<f64>,
    pub fx_n: Vec<f64>,
    pub mzw_nm: Vec<f64>,
    pub fzw_n: Vec<f64>,
}

/// Builds a [`SweepTrace`] from samples.
#[derive(Debug, Clone)]
pub struct TraceBuilder {
    trace: SweepTrace,
    max_points: usize,
    stride: u64,
}

impl TraceBuilder {
    pub fn new(sweep_name: &str, sweep_index: u32, max_points: usize) -> Self {
        let trace = SweepTrace { sweep_name: sweep_name.to_owned(), sweep_index, ..SweepTrace::default() };
        Self { trace, max_points: max_points.max(2), stride: 1 }
    }

    pub fn push(&mut self, s: &RigSample) {
        let n = self.trace.samples;
        self.trace.samples += 1;
        if !n.is_multiple_of(self.stride) {
            return;
        }
        if self.trace.fyw_n.len() >= self.max_points {
            self.halve();
            if !n.is_multiple_of(self.stride) {
                return;
            }
        }
        let t = &mut self.trace;
        t.slip_angle_deg.push(s.slipangl_deg);
        t.slip_ratio.push(s.longslip);
        t.fyw_n.push(s.fyw_n);
        t.fx_n.push(s.fx_n);
        t.mzw_nm.push(s.mzw_nm);
        t.fzw_n.push(s.fzw_n);
    }

    /// Keeps every other point (those at multiples of the doubled stride).
    fn halve(&mut self) {
        fn keep_even(v: &mut Vec<f64>) {
            let mut i = 0;
            v.retain(|_| {
                i += 1;
                i % 2 == 1
            });
        }
        let t = &mut self.trace;
        for v in [&mut t.slip_angle_deg, &mut t.slip_ratio, &mut t.fyw_n, &mut t.fx_n, &mut t.mzw_nm, &mut t.fzw_n] {
            keep_even(v);
        }
        self.stride *= 2;
    }

    pub fn trace(&self) -> &SweepTrace {
        &self.trace
    }

    pub fn into_trace(self) -> SweepTrace {
        self.trace
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample(i: u64) -> RigSample {
        RigSample { seq: i, slipangl_deg: i as f64, fyw_n: -(i as f64), ..RigSample::default() }
    }

    #[test]
    fn a_short_sweep_keeps_every_point() {
        let mut b = TraceBuilder::new("s", 3, 100);
        (0..50).for_each(|i| b.push(&sample(i)));
        assert_eq!(b.trace().fyw_n.len(), 50);
        assert_eq!(b.trace().slip_angle_deg[49], 49.0);
    }

    #[test]
    fn a_long_sweep_is_decimated_evenly_and_bounded() {
        let mut b = TraceBuilder::new("s", 0, 100);
        (0..10_000).for_each(|i| b.push(&sample(i)));
        let t = b.trace();
        assert!(t.fyw_n.len() <= 100 && t.fyw_n.len() >= 50, "{}", t.fyw_n.len());
        assert_eq!(t.samples, 10_000);
        // Even spacing from the first sample on: every kept x is a multiple of one stride.
        let step = t.slip_angle_deg[1] - t.slip_angle_deg[0];
        assert_eq!(t.slip_angle_deg[0], 0.0);
        assert!(t.slip_angle_deg.windows(2).all(|w| w[1] - w[0] == step), "{:?}", &t.slip_angle_deg[..5]);
        // The pairs stay together (fyw = -slip for every kept point).
        assert!(t.slip_angle_deg.iter().zip(&t.fyw_n).all(|(x, y)| *y == -x));
        // It reaches close to the latest sample.
        assert!(*t.slip_angle_deg.last().expect("points") > 10_000.0 - 2.0 * step);
    }
}

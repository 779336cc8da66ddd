//! Where and when each of a stage's points was measured: tread temperature and test time, for
//! the report's residual plots (a fit that drifts with temperature or along the test shows in
//! them, and a point does not carry either).

use crate::engine::Point;
use crate::stages::context::{Ctx, StagePoints};

/// The state of the tyre at one point.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PointState {
    /// Test time: the segments in the order read, each from where the one before ended (the
    /// gaps between them left out), s.
    pub test_time_s: f64,
    /// Tread temperature: the centre reading, else the mean of inner and outer, °C (NaN when
    /// none was recorded).
    pub temp_c: f64,
}

impl PointState {
    const UNKNOWN: PointState = PointState { test_time_s: f64::NAN, temp_c: f64::NAN };
}

/// The states of `sel`'s points: each found in its segment's resampled samples by its load and
/// slip angle (bit for bit: the points were made from those samples).
pub fn of(ctx: &Ctx, sel: &StagePoints) -> Vec<PointState> {
    let segments = &ctx.data.segments;
    let mut start_s = Vec::with_capacity(segments.len());
    let mut t = 0.0;
    for seg in segments {
        start_s.push(t);
        if let (Some(a), Some(b)) = (seg.samples.first(), seg.samples.last()) {
            let d = b.time_s - a.time_s;
            t += if d.is_finite() { d.max(0.0) } else { 0.0 };
        }
    }
    let mut cached: Option<(usize, std::borrow::Cow<'_, [crate::data::Sample]>)> = None;
    sel.points
        .iter()
        .zip(&sel.groups)
        .map(|(p, &g)| {
            if g >= segments.len() {
                return PointState::UNKNOWN;
            }
            if cached.as_ref().is_none_or(|(at, _)| *at != g) {
                cached = Some((g, ctx.resampled(g)));
            }
            let Some((_, samples)) = cached.as_ref() else { return PointState::UNKNOWN };
            let origin = segments[g].samples.first().map_or(0.0, |s| s.time_s);
            samples.iter().find(|s| same(p, s)).map_or(PointState::UNKNOWN, |s| PointState {
                test_time_s: start_s[g] + (s.time_s - origin),
                temp_c: if s.temp_c.is_finite() { s.temp_c } else { 0.5 * (s.temp_inner_c + s.temp_outer_c) },
            })
        })
        .collect()
}

fn same(p: &Point, s: &crate::data::Sample) -> bool {
    p.input.fz_n.to_bits() == s.fz_n.to_bits() && p.input.alpha_rad.to_bits() == s.alpha_rad.to_bits()
}

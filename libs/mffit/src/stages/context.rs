//! What every stage works with: the data, the options, the nominal values, and the selection of
//! a stage's points (resampled per segment, decimated evenly, each tagged with its segment so
//! k-fold validation can hold out whole sweeps).

use mftyre::MfInput;

use crate::data::{DataKind, Dataset, Procedure, Sample, Segment, ValidRange, resample};
use crate::engine::Point;
use crate::fit::StepSettings;
use crate::physics::Grid;
use crate::stages::{FitOptions, Nominal};

/// A stage's context.
#[derive(Debug)]
pub struct Ctx<'a> {
    /// All data of the fit.
    pub data: &'a Dataset,
    /// Options.
    pub opts: &'a FitOptions,
    /// Stage 0's nominal values.
    pub nominal: Nominal,
    /// Optimiser settings.
    pub settings: StepSettings,
    /// The tested range's grid, where physical margins are checked.
    pub grid: Grid,
    /// Each segment resampled, computed once per fit (every stage selects from them).
    pub resampled: Resampled,
}

/// Each segment of a dataset resampled at its period, computed on first use: the stages select
/// their points from the same resampled segments, and resampling all data once per stage was a
/// large part of a live update. Cloning shares the cells; a live fit's next update takes over the
/// cells of the segments it already had ([`Resampled::continuing`]), so each segment is
/// resampled once per run rather than once per update.
#[derive(Clone, Default)]
pub struct Resampled {
    cells: Vec<std::sync::Arc<SegmentCell>>,
}

/// What is computed once per segment, each with the number of raw samples it was computed from.
#[derive(Default)]
struct SegmentCell {
    /// The period and the resampled samples.
    resampled: std::sync::OnceLock<(f64, usize, Vec<Sample>)>,
    /// The segment's part of the tested range.
    range: std::sync::OnceLock<(usize, ValidRange)>,
}

impl Resampled {
    /// An empty cache for the segments of `data`.
    pub fn of(data: &Dataset) -> Self {
        Resampled { cells: (0..data.segments.len()).map(|_| Default::default()).collect() }
    }

    /// The cache for `data`, a dataset that grew from the one `previous` served by appending
    /// segments (a live fit's): the cells of the segments both hold are shared. A cell whose
    /// segment changed after all (another sample count) is not used ([`Ctx::resampled`]).
    pub fn continuing(previous: &Resampled, data: &Dataset) -> Self {
        let cells = (0..data.segments.len()).map(|i| previous.cells.get(i).cloned().unwrap_or_default()).collect();
        Resampled { cells }
    }

    /// [`ValidRange::of`] `data`, from the segments' ranges computed once per segment.
    pub fn valid_range(&self, data: &Dataset) -> ValidRange {
        ValidRange::merged(data.segments.iter().enumerate().map(|(i, seg)| match self.cells.get(i) {
            Some(cell) => {
                let (raw, r) = cell.range.get_or_init(|| (seg.samples.len(), ValidRange::of_segment(seg)));
                if *raw == seg.samples.len() { *r } else { ValidRange::of_segment(seg) }
            }
            None => ValidRange::of_segment(seg),
        }))
    }
}

impl std::fmt::Debug for Resampled {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let done = self.cells.iter().filter(|c| c.resampled.get().is_some()).count();
        write!(f, "Resampled({done} of {} segments)", self.cells.len())
    }
}

/// A stage's points and the segment (index into the dataset) each came from.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct StagePoints {
    /// Points.
    pub points: Vec<Point>,
    /// `groups[i]` = the segment of `points[i]`.
    pub groups: Vec<usize>,
}

impl StagePoints {
    /// Number of points.
    pub fn len(&self) -> usize {
        self.points.len()
    }

    /// True without points.
    pub fn is_empty(&self) -> bool {
        self.points.is_empty()
    }

    /// The points satisfying `keep`, with their groups.
    pub fn filter(&self, keep: impl Fn(&Point) -> bool) -> StagePoints {
        let mut out = StagePoints::default();
        for (p, g) in self.points.iter().zip(&self.groups) {
            if keep(p) {
                out.points.push(*p);
                out.groups.push(*g);
            }
        }
        out
    }

    /// The points whose group satisfies `keep`.
    pub fn by_group(&self, keep: impl Fn(usize) -> bool) -> StagePoints {
        let mut out = StagePoints::default();
        for (p, g) in self.points.iter().zip(&self.groups) {
            if keep(*g) {
                out.points.push(*p);
                out.groups.push(*g);
            }
        }
        out
    }

    /// Appends another selection.
    pub fn extend(&mut self, other: StagePoints) {
        self.points.extend(other.points);
        self.groups.extend(other.groups);
    }

    /// Evenly decimated to at most `max` points (groups kept aligned).
    pub fn decimated(self, max: usize) -> StagePoints {
        let n = self.points.len();
        if n <= max || max == 0 {
            return self;
        }
        let step = n as f64 / max as f64;
        let idx: Vec<usize> = (0..max).map(|i| ((i as f64 * step) as usize).min(n - 1)).collect();
        StagePoints {
            points: idx.iter().map(|&i| self.points[i]).collect(),
            groups: idx.iter().map(|&i| self.groups[i]).collect(),
        }
    }

    /// Distinct groups, in order of first appearance.
    pub fn distinct_groups(&self) -> Vec<usize> {
        let mut seen = Vec::new();
        for g in &self.groups {
            if !seen.contains(g) {
                seen.push(*g);
            }
        }
        seen
    }
}

/// True for force & moment data: sweeps and on-centre clumps (graph sweeps only when asked).
pub fn is_fm(seg: &Segment, opts: &FitOptions) -> bool {
    matches!(seg.kind, DataKind::Sweep | DataKind::OnCentre)
        || (opts.include_graph_sweeps && seg.kind == DataKind::GraphSweep)
}

/// The model input of a sample. Free rolling: the wheel is not driven, the slip ratio is zero by
/// construction (the rig's reported value is noise around it).
pub fn input_of(s: &Sample, free_rolling: bool) -> MfInput {
    MfInput {
        fz_n: s.fz_n,
        kappa: if free_rolling { 0.0 } else { s.kappa },
        alpha_rad: s.alpha_rad,
        gamma_rad: s.gamma_rad,
        phit_per_m: 0.0,
        vx_mps: s.vx_mps,
        p_pa: s.p_pa,
        omega_radps: s.omega_radps,
    }
}

impl Ctx<'_> {
    /// The previous solution `stage` starts from, when the fit is warm-started and that
    /// solution fitted the stage.
    pub fn warm(&self, stage: &str) -> Option<&mftyre::TyreParams> {
        self.opts.warm_start.as_ref().filter(|w| w.stages.iter().any(|(s, _)| s == stage)).map(|w| &w.params)
    }

    /// The keys the warm start's solution held by the Jacobian's verdict in `stage` (empty when
    /// the stage starts cold).
    pub fn warm_held(&self, stage: &str) -> &[crate::identify::Held] {
        match (self.warm(stage), self.opts.warm_start.as_ref()) {
            (Some(_), Some(w)) => w.jacobian_held(stage),
            _ => &[],
        }
    }

    /// True when a stage stuck above its noise floor may try other starts
    /// ([`FitOptions::restarts`]).
    pub fn restarts(&self) -> bool {
        self.opts.restarts
    }

    /// Resampling period of a segment: 10 Hz for free rolling (the thesis's rate); finer for
    /// BrkDrv, whose slip-ratio sweeps cross the peak in a fraction of a second.
    pub fn period_of(&self, seg: &Segment) -> f64 {
        if seg.procedure == Procedure::BrkDrv { self.opts.brkdrv_period_s } else { self.opts.resample_period_s }
    }

    /// Segment `i` of the data, resampled at its period ([`resample`]).
    pub fn resampled(&self, i: usize) -> std::borrow::Cow<'_, [Sample]> {
        let seg = &self.data.segments[i];
        let period = self.period_of(seg);
        match self.resampled.cells.get(i) {
            Some(cell) => {
                let (at, raw, samples) =
                    cell.resampled.get_or_init(|| (period, seg.samples.len(), resample(&seg.samples, period)));
                if at.to_bits() == period.to_bits() && *raw == seg.samples.len() {
                    std::borrow::Cow::Borrowed(samples)
                } else {
                    std::borrow::Cow::Owned(resample(&seg.samples, period))
                }
            }
            None => std::borrow::Cow::Owned(resample(&seg.samples, period)),
        }
    }

    /// Samples of the segments matching `keep_seg` that satisfy `keep`, resampled per segment,
    /// as points measuring `measured`, evenly decimated to `max`.
    pub fn points(
        &self,
        keep_seg: impl Fn(&Segment) -> bool,
        keep: impl Fn(&Sample) -> bool,
        measured: impl Fn(&Sample) -> f64,
        max: usize,
    ) -> StagePoints {
        let mut out = StagePoints::default();
        for (i, seg) in self.data.segments.iter().enumerate().filter(|(_, s)| keep_seg(s)) {
            let free = seg.procedure == Procedure::FreeRolling;
            for s in self.resampled(i).iter().filter(|s| keep(s) && s.fz_n > 50.0) {
                let m = measured(s);
                if m.is_finite() && s.fz_n.is_finite() && s.alpha_rad.is_finite() && s.kappa.is_finite() {
                    out.points.push(Point { input: input_of(s, free), measured: m });
                    out.groups.push(i);
                }
            }
        }
        out.decimated(max)
    }

    /// Per segment matching `keep_seg`, its resampled points (for starting values: peaks,
    /// crossings).
    pub fn segment_points(&self, keep_seg: impl Fn(&Segment) -> bool, measured: fn(&Sample) -> f64) -> Vec<Vec<Point>> {
        self.data
            .segments
            .iter()
            .enumerate()
            .filter(|(_, s)| keep_seg(s))
            .map(|(i, seg)| {
                let free = seg.procedure == Procedure::FreeRolling;
                self.resampled(i)
                    .iter()
                    .filter(|s| s.fz_n > 50.0)
                    .map(|s| Point { input: input_of(s, free), measured: measured(s) })
                    .collect()
            })
            .collect()
    }

    /// Noise floor of a channel from consecutive resampled samples at (nearly) the same
    /// operating point: σ ≈ median|Δ| / (0.6745·√2).
    pub fn noise_floor(&self, keep_seg: impl Fn(&Segment) -> bool, measured: fn(&Sample) -> f64) -> f64 {
        let mut d = Vec::new();
        for (i, _) in self.data.segments.iter().enumerate().filter(|(_, s)| keep_seg(s)) {
            let rs = self.resampled(i);
            for w in rs.windows(2) {
                if (w[1].alpha_rad - w[0].alpha_rad).abs() < 0.05f64.to_radians()
                    && (w[1].kappa - w[0].kappa).abs() < 0.002
                    && (w[1].fz_n - w[0].fz_n).abs() < 0.015 * self.nominal.fz0_n
                {
                    d.push((measured(&w[1]) - measured(&w[0])).abs());
                }
            }
        }
        crate::starts::median(d).map(|m| m / (0.6745 * std::f64::consts::SQRT_2)).unwrap_or(0.0)
    }
}

/// Largest |measured| of a set of points (a channel's peak), never zero.
pub fn peak_abs(points: &[Point]) -> f64 {
    points.iter().map(|p| p.measured.abs()).fold(0.0, f64::max).max(1e-9)
}

/// Within 0.4° of zero camber.
pub fn near_nominal_camber(p: &Point) -> bool {
    p.input.gamma_rad.abs() < 0.4f64.to_radians()
}

/// Within 5 kPa of the nominal pressure.
pub fn near_p0(p: &Point, p0: f64) -> bool {
    (p.input.p_pa - p0).abs() < 5e3
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::synth::{self, Noise, SynthOptions};

    fn data() -> Dataset {
        let tyre =
            mftyre::TyreParams::from_tir_str(crate::stages::TEMPLATE_TIR, "template").expect("the template parses");
        synth::gs2mf(&tyre, SynthOptions { rate_hz: 5.0, noise: Noise::OFF, ..Default::default() })
    }

    fn ctx<'a>(data: &'a Dataset, opts: &'a FitOptions, resampled: Resampled) -> Ctx<'a> {
        let nominal = crate::stages::nominal::nominal_values(data, opts).expect("nominal values");
        let params = mftyre::TyreParams::from_tir_str(crate::stages::TEMPLATE_TIR, "template").expect("parses");
        let grid = Grid::of_range(&params, &ValidRange::of(data));
        Ctx { data, opts, nominal, settings: StepSettings::default(), grid, resampled }
    }

    #[test]
    fn a_continuing_cache_serves_the_segments_it_had_and_computes_the_new_ones() {
        let all = data();
        let opts = FitOptions::default();
        let mut first = all.clone();
        first.segments.truncate(all.segments.len() / 2);
        let earlier = Resampled::of(&first);
        let c = ctx(&first, &opts, earlier.clone());
        let fy = |c: &Ctx| c.points(|s| s.kind == DataKind::Sweep, |_| true, |s| s.fy_n, usize::MAX);
        let before = fy(&c);
        assert_eq!(earlier.valid_range(&first), ValidRange::of(&first));

        let later = Resampled::continuing(&earlier, &all);
        // The cells of the first half are shared, so nothing in them is resampled again.
        assert!(matches!(ctx(&all, &opts, later.clone()).resampled(0), std::borrow::Cow::Borrowed(_)));
        assert_eq!(later.valid_range(&all), ValidRange::of(&all));
        let c = ctx(&all, &opts, later);
        let after = fy(&c);
        assert_eq!(after, fy(&ctx(&all, &opts, Resampled::of(&all))));
        assert!(after.len() > before.len());

        // A segment that changed under a shared cell (another sample count) is not served from it.
        let mut changed = all.clone();
        let longest = (0..changed.segments.len()).max_by_key(|&i| changed.segments[i].samples.len()).expect("segments");
        changed.segments[longest].samples.truncate(3);
        let stale = Resampled::continuing(&Resampled::continuing(&earlier, &all), &changed);
        let c = ctx(&changed, &opts, stale.clone());
        // Fill the shared cells from the unchanged data first.
        let filler = Resampled::continuing(&stale, &all);
        let _ = fy(&ctx(&all, &opts, filler.clone()));
        let _ = filler.valid_range(&all);
        assert!(matches!(ctx(&all, &opts, filler).resampled(longest), std::borrow::Cow::Borrowed(_)));
        assert!(matches!(c.resampled(longest), std::borrow::Cow::Owned(_)));
        assert_eq!(fy(&c), fy(&ctx(&changed, &opts, Resampled::of(&changed))));
        assert_eq!(stale.valid_range(&changed), ValidRange::of(&changed));
    }
}

//! The fitter's view of test data: segments (one sweep, clump or static test each) of samples in
//! ISO-W axes and SI units, tagged with the procedure and the kind of test they come from.
//!
//! Logs, TYDEX files, TTC files and the synthetic generator all produce a [`Dataset`]; the
//! stages only ever select from it.

use serde::{Deserialize, Serialize};

/// Which GS2MF procedure a segment was recorded in.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum Procedure {
    /// Drive un-coupled: cornering, on-centre, rolling radius, step-steer.
    FreeRolling,
    /// Drive coupled, slip ratio controlled: pure longitudinal and combined.
    BrkDrv,
    /// Locked wheel, belt moved: longitudinal carcass stiffness.
    StaticLong,
}

impl Procedure {
    /// Classifies a procedure name from a log (`gs2mf_freerolling`, `FreeRoll`, …).
    pub fn from_name(name: &str) -> Option<Self> {
        let n = name.to_ascii_lowercase();
        if n.contains("static") {
            Some(Procedure::StaticLong)
        } else if n.contains("brk") || n.contains("drv") || n.contains("drive") || n.contains("long") {
            Some(Procedure::BrkDrv)
        } else if n.contains("free") || n.contains("corner") || n.contains("lat") {
            Some(Procedure::FreeRolling)
        } else {
            None
        }
    }

    /// Short name used in reports.
    pub fn name(self) -> &'static str {
        match self {
            Procedure::FreeRolling => "FreeRolling",
            Procedure::BrkDrv => "BrkDrv",
            Procedure::StaticLong => "StaticLong",
        }
    }
}

/// What kind of test a segment is; decides which stages may use it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum DataKind {
    /// Warm-up sweeps: never fitted (the tyre is not at its baseline temperature).
    WarmUp,
    /// Graph sweeps: drift/wear checks; fitted only when asked to.
    GraphSweep,
    /// Force & moment sweeps (slip angle or slip ratio), the bulk of the data.
    Sweep,
    /// On-centre clumps: constant small slip angle at several loads.
    OnCentre,
    /// Rolling-radius holds: zero slip, several loads and speeds.
    RollingRadius,
    /// Step-steer: roll at 1 m/s holding a slip angle (lateral relaxation length).
    StepSteer,
    /// Static longitudinal: locked wheel, belt moved (longitudinal stiffness).
    StaticLong,
}

impl DataKind {
    /// Classifies a step from its section and sweep names. The sweep name decides first (the
    /// procedure library names steps `<tag>_sw<n>_<Type>_<repeat>`: `OnCentre_SA1`,
    /// `RollingRadius_V16.6`, `StepSteer_SA1.5`, `StaticDrag_D0.1`, `WarmUp_…`,
    /// `GraphSweep_…`), the section name second.
    pub fn from_names(section: &str, sweep: &str) -> Self {
        let w = sweep.to_ascii_lowercase();
        let sec = section.to_ascii_lowercase();
        let has = |t: &str| w.contains(t) || sec.contains(t);
        if has("warmup") || has("warm_up") {
            DataKind::WarmUp
        } else if has("graphsweep") || has("graph_sweep") {
            DataKind::GraphSweep
        } else if has("stepsteer") || has("step_steer") {
            DataKind::StepSteer
        } else if has("staticdrag") || has("static") {
            DataKind::StaticLong
        } else if w.contains("oncentre") || w.contains("oncenter") {
            DataKind::OnCentre
        } else if w.contains("rollingradius")
            || w.contains("rolling_radius")
            || (sec.contains("rolling_radius") && !w.contains("centre"))
        {
            DataKind::RollingRadius
        } else if has("centre") || has("center") {
            DataKind::OnCentre
        } else {
            DataKind::Sweep
        }
    }
}

/// One (resampled) sample. ISO-W axes, SI units, angles in radians. The default is all zeros
/// with the temperatures not recorded (NaN).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Sample {
    /// Time since the segment started, s.
    pub time_s: f64,
    /// FZW, N (positive loaded).
    pub fz_n: f64,
    /// LONGSLIP.
    pub kappa: f64,
    /// SLIPANGL, rad.
    pub alpha_rad: f64,
    /// INCLANGL, rad.
    pub gamma_rad: f64,
    /// INFLPRES, Pa.
    pub p_pa: f64,
    /// TRAJVELW, m/s.
    pub vx_mps: f64,
    /// Wheel rotational speed, rad/s.
    pub omega_radps: f64,
    /// FX, N.
    pub fx_n: f64,
    /// FYW, N.
    pub fy_n: f64,
    /// MXW, N·m.
    pub mx_nm: f64,
    /// MYW, N·m.
    pub my_nm: f64,
    /// MZW, N·m.
    pub mz_nm: f64,
    /// DSTWOWHC (loaded radius), m.
    pub rl_m: f64,
    /// Centre tread temperature (TRDTEMPC, TTC `TSTC`), °C (NaN when not recorded).
    pub temp_c: f64,
    /// Inner tread temperature (TRDTEMPI, TTC `TSTI`), °C (NaN when not recorded).
    pub temp_inner_c: f64,
    /// Outer tread temperature (TRDTEMPO, TTC `TSTO`), °C (NaN when not recorded).
    pub temp_outer_c: f64,
    /// Road (belt) surface temperature (TTC `RST`), °C (NaN when not recorded).
    pub road_temp_c: f64,
    /// Distance rolled (or belt travel) since the segment started, m (LONGDISP).
    pub dist_m: f64,
}

impl Default for Sample {
    fn default() -> Self {
        Sample {
            time_s: 0.0,
            fz_n: 0.0,
            kappa: 0.0,
            alpha_rad: 0.0,
            gamma_rad: 0.0,
            p_pa: 0.0,
            vx_mps: 0.0,
            omega_radps: 0.0,
            fx_n: 0.0,
            fy_n: 0.0,
            mx_nm: 0.0,
            my_nm: 0.0,
            mz_nm: 0.0,
            rl_m: 0.0,
            temp_c: f64::NAN,
            temp_inner_c: f64::NAN,
            temp_outer_c: f64::NAN,
            road_temp_c: f64::NAN,
            dist_m: 0.0,
        }
    }
}

/// What a sweep of measured data is, judged from the channel that moves.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum SweepKind {
    /// Slip-angle sweep, free rolling (slip ratio zero).
    Cornering,
    /// Slip-ratio sweep at (nearly) zero slip angle.
    DriveBrake,
    /// Slip-ratio sweep at a held non-zero slip angle.
    Combined,
}

impl SweepKind {
    /// Name in reports (`cornering`, `drive/brake`, `combined`).
    pub fn name(self) -> &'static str {
        match self {
            SweepKind::Cornering => "cornering",
            SweepKind::DriveBrake => "drive/brake",
            SweepKind::Combined => "combined",
        }
    }
}

/// The test cell a sweep of measured data was run at: the conditions held while the slip moved.
/// Values are medians over the sweep, ISO-W, SI.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Cell {
    /// Kind of sweep.
    pub kind: SweepKind,
    /// Vertical load FZW, N.
    pub fz_n: f64,
    /// Inflation pressure, Pa.
    pub p_pa: f64,
    /// Inclination angle, rad.
    pub gamma_rad: f64,
    /// Held slip angle of a slip-ratio sweep, rad (0 for cornering sweeps).
    pub alpha_rad: f64,
    /// Held slip ratio of a slip-angle sweep (0 for free rolling).
    pub kappa: f64,
    /// Road speed, m/s.
    pub vx_mps: f64,
    /// Largest |slip| reached: slip angle in rad for cornering, slip ratio otherwise.
    pub slip_reach: f64,
}

/// Where a segment came from in its source file, for messages a person can follow.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct Origin {
    /// Source file.
    pub file: String,
    /// First row of the segment (1-based line number of a text file, row index of a `.mat`).
    pub first_row: usize,
    /// Last row of the segment, inclusive.
    pub last_row: usize,
}

/// A contiguous piece of one test: a sweep, a clump, a static test.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Segment {
    /// Procedure it was recorded in.
    pub procedure: Procedure,
    /// Kind of test.
    pub kind: DataKind,
    /// Section name (e.g. `force_moment_2.6bar`).
    pub section: String,
    /// Sweep name (thesis naming) or a generated label.
    pub sweep: String,
    /// Samples in time order.
    pub samples: Vec<Sample>,
    /// The test cell, when the segment comes from measured files whose cells were found from the
    /// data (TTC, foreign TYDEX); `None` for GS2MF logs, whose procedure names say it.
    #[serde(default)]
    pub cell: Option<Cell>,
    /// Where the segment sits in its source file, when it was read from one.
    #[serde(default)]
    pub origin: Option<Origin>,
}

/// Everything the fitter may use, plus what is known about the test.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct Dataset {
    /// The segments, in recording order.
    pub segments: Vec<Segment>,
    /// Nominal load Fz0 if the log says it (metadata), N.
    pub fnomin_n: Option<f64>,
    /// Sources (file names) the data came from.
    pub sources: Vec<String>,
}

impl Dataset {
    /// Adds another dataset's segments (several logs feed one fit).
    pub fn extend(&mut self, other: Dataset) {
        self.segments.extend(other.segments);
        if self.fnomin_n.is_none() {
            self.fnomin_n = other.fnomin_n;
        }
        self.sources.extend(other.sources);
    }

    /// Samples of every segment matching `keep`, with their segment.
    pub fn select<'a>(
        &'a self,
        keep: impl Fn(&Segment) -> bool + 'a,
    ) -> impl Iterator<Item = (&'a Segment, &'a Sample)> + 'a {
        self.segments.iter().filter(move |s| keep(s)).flat_map(|seg| seg.samples.iter().map(move |s| (seg, s)))
    }

    /// Number of samples over all segments.
    pub fn len(&self) -> usize {
        self.segments.iter().map(|s| s.samples.len()).sum()
    }

    /// True when there are no samples.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

/// Averages samples into bins of `period_s` (the thesis fits at 10 Hz: `0.1`). Averaging rather
/// than picking every n-th sample lowers the noise by √n; a bin's time is its samples' mean.
pub fn resample(samples: &[Sample], period_s: f64) -> Vec<Sample> {
    let mut out = Vec::new();
    if samples.is_empty() || period_s.is_nan() || period_s <= 0.0 {
        return samples.to_vec();
    }
    let t0 = samples[0].time_s;
    let mut bin = 0_i64;
    let mut acc: Vec<Sample> = Vec::new();
    let flush = |acc: &mut Vec<Sample>, out: &mut Vec<Sample>| {
        if acc.is_empty() {
            return;
        }
        let n = acc.len() as f64;
        // Temperatures too start from zero: a bin's mean is NaN only if a sample's is.
        let mut m = Sample { temp_c: 0.0, temp_inner_c: 0.0, temp_outer_c: 0.0, road_temp_c: 0.0, ..Sample::default() };
        for s in acc.iter() {
            m.time_s += s.time_s / n;
            m.fz_n += s.fz_n / n;
            m.kappa += s.kappa / n;
            m.alpha_rad += s.alpha_rad / n;
            m.gamma_rad += s.gamma_rad / n;
            m.p_pa += s.p_pa / n;
            m.vx_mps += s.vx_mps / n;
            m.omega_radps += s.omega_radps / n;
            m.fx_n += s.fx_n / n;
            m.fy_n += s.fy_n / n;
            m.mx_nm += s.mx_nm / n;
            m.my_nm += s.my_nm / n;
            m.mz_nm += s.mz_nm / n;
            m.rl_m += s.rl_m / n;
            m.temp_c += s.temp_c / n;
            m.temp_inner_c += s.temp_inner_c / n;
            m.temp_outer_c += s.temp_outer_c / n;
            m.road_temp_c += s.road_temp_c / n;
            m.dist_m += s.dist_m / n;
        }
        out.push(m);
        acc.clear();
    };
    for s in samples {
        let b = ((s.time_s - t0) / period_s).floor() as i64;
        if b != bin {
            flush(&mut acc, &mut out);
            bin = b;
        }
        acc.push(*s);
    }
    flush(&mut acc, &mut out);
    out
}

/// Ranges of the operating conditions a set of samples covers (the model's valid range).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Range {
    /// Smallest value.
    pub min: f64,
    /// Largest value.
    pub max: f64,
}

impl Range {
    /// An empty range that any value widens.
    pub const EMPTY: Range = Range { min: f64::INFINITY, max: f64::NEG_INFINITY };

    /// Widens the range to include `v` (non-finite values are ignored).
    pub fn add(&mut self, v: f64) {
        if v.is_finite() {
            self.min = self.min.min(v);
            self.max = self.max.max(v);
        }
    }

    /// True when no value was added.
    pub fn is_empty(&self) -> bool {
        self.min > self.max
    }
}

/// The tested range (thesis Table 5.1.3-A style).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct ValidRange {
    /// Vertical load, N.
    pub fz_n: Range,
    /// Slip angle, rad.
    pub alpha_rad: Range,
    /// Slip ratio.
    pub kappa: Range,
    /// Camber, rad.
    pub gamma_rad: Range,
    /// Inflation pressure, Pa.
    pub p_pa: Range,
    /// Speed, m/s.
    pub vx_mps: Range,
}

impl ValidRange {
    const EMPTY: ValidRange = ValidRange {
        fz_n: Range::EMPTY,
        alpha_rad: Range::EMPTY,
        kappa: Range::EMPTY,
        gamma_rad: Range::EMPTY,
        p_pa: Range::EMPTY,
        vx_mps: Range::EMPTY,
    };

    /// The range covered by the force & moment data (sweeps, on-centre, graph sweeps) of a dataset.
    pub fn of(data: &Dataset) -> Self {
        Self::merged(data.segments.iter().map(Self::of_segment))
    }

    /// The range one segment adds to [`ValidRange::of`] (empty for segments it ignores; the
    /// slip-ratio range only from BrkDrv segments).
    pub fn of_segment(seg: &Segment) -> Self {
        let mut r = Self::EMPTY;
        if !matches!(seg.kind, DataKind::Sweep | DataKind::OnCentre | DataKind::GraphSweep) {
            return r;
        }
        for s in &seg.samples {
            r.fz_n.add(s.fz_n);
            r.alpha_rad.add(s.alpha_rad);
            r.gamma_rad.add(s.gamma_rad);
            r.p_pa.add(s.p_pa);
            r.vx_mps.add(s.vx_mps);
            if seg.procedure == Procedure::BrkDrv {
                r.kappa.add(s.kappa);
            }
        }
        r
    }

    /// The range of segments' ranges ([`ValidRange::of_segment`]): what [`ValidRange::of`] gives
    /// for their dataset.
    pub fn merged(parts: impl IntoIterator<Item = ValidRange>) -> Self {
        let mut r = Self::EMPTY;
        for p in parts {
            for (all, one) in [
                (&mut r.fz_n, p.fz_n),
                (&mut r.alpha_rad, p.alpha_rad),
                (&mut r.kappa, p.kappa),
                (&mut r.gamma_rad, p.gamma_rad),
                (&mut r.p_pa, p.p_pa),
                (&mut r.vx_mps, p.vx_mps),
            ] {
                if !one.is_empty() {
                    all.add(one.min);
                    all.add(one.max);
                }
            }
        }
        if r.kappa.is_empty() {
            r.kappa = Range { min: 0.0, max: 0.0 };
        }
        r
    }
}

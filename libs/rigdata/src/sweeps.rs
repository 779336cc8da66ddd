//! Finding the sweeps in a measured run, the way an engineer reads the plot: drop what is not a
//! test (standstill, unloaded, load and pressure ramps, camber and speed changes), then, within
//! each stretch where load, pressure, camber and speed are held, follow the slip channel that
//! actually moves — the slip angle where it sweeps, else the slip ratio — and cut a sweep each
//! time it has gone out and come back to zero. Short sweeps to a few degrees are the rig's
//! conditioning (warm-up) sweeps, kept apart so the fitter does not use them. Every row ends
//! up either in a sweep or excluded with a reason, and the reasons are counted.

use serde::Serialize;

use mffit::{Cell, SweepKind};

use crate::interpret::{KappaSource, Signals};

/// Thresholds of the segmentation. The defaults suit TTC-like runs (50–100 Hz, sweeps of a few
/// seconds or more to ±13° or ±0.2 slip ratio).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct SweepOptions {
    /// Below this road speed the rig is standing still, m/s.
    pub standstill_mps: f64,
    /// Rows below this fraction of the run's high load (98th percentile) are unloaded.
    pub unloaded_fraction: f64,
    /// Half width of the window over which a held quantity must stay put, s.
    pub hold_window_s: f64,
    /// Load held within max(this, `fz_tol_fraction` × load), N.
    pub fz_tol_n: f64,
    /// Relative load tolerance.
    pub fz_tol_fraction: f64,
    /// Pressure held within max(this, 3 % of the pressure), Pa.
    pub p_tol_pa: f64,
    /// Camber held within, rad.
    pub gamma_tol_rad: f64,
    /// Speed held within max(this, 5 % of the speed), m/s.
    pub v_tol_mps: f64,
    /// A slip angle moving more than this over the hold window is sweeping, deg.
    pub sa_moving_deg: f64,
    /// Slip angle counted as zero (sweeps start and end here), deg.
    pub sa_zero_deg: f64,
    /// A slip-angle excursion beyond this is a sweep, deg.
    pub sa_on_deg: f64,
    /// Slip ratio counted as zero (`SL`).
    pub kappa_zero: f64,
    /// A slip-ratio excursion beyond this is a sweep (`SL`).
    pub kappa_on: f64,
    /// The same two for `SR`, which is noisy and offset even when free rolling.
    pub sr_zero: f64,
    /// See `sr_zero`.
    pub sr_on: f64,
    /// Quiet this long after an excursion ends a sweep, s.
    pub idle_split_s: f64,
    /// Shortest sweep kept, s.
    pub min_sweep_s: f64,
    /// A sweep reaching less than this fraction of its kind's typical reach is a conditioning
    /// (warm-up) sweep.
    pub conditioning_fraction: f64,
    /// Mark the sweeps a run opens with on a cold tyre as conditioning where their cell is swept
    /// again (`conditioning::mark_cold_start`).
    pub cold_start: bool,
    /// `SR` (no `SL` in the file) moving is a slip-ratio sweep only where the wheel is driven or
    /// braked: |FX| above this fraction of FZ in at least a tenth of the rows.
    pub sr_driven_fx_fraction: f64,
    /// A camber sweep spans at least this much camber, deg.
    pub camber_sweep_min_deg: f64,
    /// Load wandering around its setpoint while the slip angle sweeps stays one cell when it
    /// comes back to the level it left and strays at most this fraction of it.
    pub fz_wander_fraction: f64,
}

impl Default for SweepOptions {
    fn default() -> Self {
        Self {
            standstill_mps: 0.5,
            unloaded_fraction: 0.05,
            hold_window_s: 0.5,
            fz_tol_n: 60.0,
            fz_tol_fraction: 0.06,
            p_tol_pa: 3_000.0,
            gamma_tol_rad: 0.25_f64.to_radians(),
            v_tol_mps: 0.3,
            sa_moving_deg: 0.3,
            sa_zero_deg: 0.5,
            sa_on_deg: 1.0,
            kappa_zero: 0.005,
            kappa_on: 0.02,
            sr_zero: 0.02,
            sr_on: 0.05,
            idle_split_s: 2.0,
            min_sweep_s: 1.0,
            conditioning_fraction: 0.5,
            cold_start: true,
            sr_driven_fx_fraction: 0.15,
            camber_sweep_min_deg: 1.5,
            fz_wander_fraction: 0.3,
        }
    }
}

/// Why a row is not in any sweep.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, PartialOrd, Ord)]
pub enum Exclusion {
    /// A needed value is NaN or missing.
    NonFinite,
    /// Road speed about zero (start and end of a run).
    Standstill,
    /// Wheel off the road or barely loaded.
    Unloaded,
    /// Load changing between cells.
    LoadRamp,
    /// Pressure changing between cells.
    PressureRamp,
    /// Camber changing between cells.
    CamberChange,
    /// Speed changing.
    SpeedChange,
    /// Slip angle moving without forming a sweep (set between slip-ratio sweeps).
    SlipAngleChange,
    /// Rolling at a held cell with no slip sweep.
    Idle,
    /// A sweep cut off before it came back to zero.
    IncompleteSweep,
    /// A sweep shorter than the shortest kept.
    ShortSweep,
    /// `SR` moving while the wheel rolls free (FX small): not a slip ratio.
    SrFreeRolling,
}

impl Exclusion {
    /// Reason in reports.
    pub fn name(self) -> &'static str {
        match self {
            Exclusion::NonFinite => "NaN or missing value",
            Exclusion::Standstill => "standstill (V ≈ 0)",
            Exclusion::Unloaded => "unloaded",
            Exclusion::LoadRamp => "load ramp",
            Exclusion::PressureRamp => "pressure ramp",
            Exclusion::CamberChange => "camber change",
            Exclusion::SpeedChange => "speed change",
            Exclusion::SlipAngleChange => "slip angle set between sweeps",
            Exclusion::Idle => "rolling between sweeps",
            Exclusion::IncompleteSweep => "incomplete sweep",
            Exclusion::ShortSweep => "sweep too short",
            Exclusion::SrFreeRolling => "SR moving while the wheel rolls free (not a slip ratio)",
        }
    }
}

/// What a sweep moves.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub enum Swept {
    /// The slip angle (a cornering sweep).
    SlipAngle,
    /// The slip ratio (drive/brake or combined).
    SlipRatio,
    /// The camber, stepped at a held slip angle: free-rolling data at several cambers, which
    /// the fitter takes as cornering data (its camber terms); its cell's `alpha_rad` is the
    /// held slip angle and its `gamma_rad` the median camber.
    Camber,
}

impl Swept {
    /// Name in reports.
    pub fn name(self) -> &'static str {
        match self {
            Swept::SlipAngle => "slip angle",
            Swept::SlipRatio => "slip ratio",
            Swept::Camber => "camber",
        }
    }
}

/// Why a sweep is a conditioning (warm-up) sweep, left out of the fit.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub enum Conditioning {
    /// It reaches less than [`SweepOptions::conditioning_fraction`] of its kind's typical reach.
    ShortReach,
    /// One of several sweeps opening a run (or a pressure) at one cell that is swept again
    /// later: the tyre being brought to temperature.
    LeadingRepeat,
    /// Begun before the tread temperature settled (a cold tyre at the start of a run), at a
    /// cell swept again later on the settled tyre.
    ColdStart,
}

impl Conditioning {
    /// Reason in reports.
    pub const fn name(self) -> &'static str {
        match self {
            Conditioning::ShortReach => "short reach",
            Conditioning::LeadingRepeat => "leading sweeps at a cell swept again later",
            Conditioning::ColdStart => "begun before the tread temperature settled, cell swept again later",
        }
    }

    /// Kept as conditioning whatever its reach: the run's plan, not the sweep's size, says so.
    pub fn by_plan(self) -> bool {
        matches!(self, Conditioning::LeadingRepeat | Conditioning::ColdStart)
    }
}

/// One sweep found.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct FoundSweep {
    /// Its cell and kind.
    pub cell: Cell,
    /// What it sweeps.
    pub swept: Swept,
    /// Why it is a conditioning (warm-up) sweep, if it is one.
    pub conditioning: Option<Conditioning>,
    /// Largest |camber| change from the sweep's lowest camber (camber sweeps), deg.
    pub camber_span_deg: f64,
    /// First row (0-based index into the table).
    pub first: usize,
    /// Last row, inclusive.
    pub last: usize,
    /// The tread temperature as it begins, °C (NaN without tread temperatures).
    pub tread_start_c: f64,
}

/// The outcome of [`find_sweeps`].
#[derive(Debug, Clone, Default)]
pub struct Segmentation {
    /// Sweeps in row order.
    pub sweeps: Vec<FoundSweep>,
    /// Rows excluded, per reason (reasons with no rows left out).
    pub excluded: Vec<(Exclusion, usize)>,
    /// Rows of cornering sweeps whose `SR` slip ratio was set to zero (free rolling).
    pub sr_zeroed: usize,
    /// Slip-ratio sweeps not looked for because `SR` is meaningless in a cornering test.
    pub kappa_ignored: bool,
}

/// What a file says its test is (`testid`, title, TYDEX constants).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub enum TestKind {
    /// Cornering (free rolling, slip-angle sweeps).
    Cornering,
    /// Drive/brake and/or combined (slip-ratio sweeps).
    DriveBrake,
}

impl TestKind {
    /// Reads a test id (`Cornering, Various pressures`, `Drive/Brake/Combined, 12psi`).
    pub fn from_id(id: &str) -> Option<Self> {
        let l = id.to_ascii_lowercase();
        if l.contains("drive") || l.contains("brake") || l.contains("combined") || l.contains("longitudinal") {
            Some(TestKind::DriveBrake)
        } else if l.contains("cornering") || l.contains("lateral") || l.contains("free rolling") || l.contains("camber")
        {
            Some(TestKind::Cornering)
        } else {
            None
        }
    }

    /// Name in reports.
    pub fn name(self) -> &'static str {
        match self {
            TestKind::Cornering => "cornering",
            TestKind::DriveBrake => "drive/brake/combined",
        }
    }
}

pub(crate) fn median_of(it: impl Iterator<Item = f64>) -> f64 {
    let mut v: Vec<f64> = it.filter(|x| x.is_finite()).collect();
    if v.is_empty() {
        return f64::NAN;
    }
    let mid = v.len() / 2;
    let (_, m, _) = v.select_nth_unstable_by(mid, f64::total_cmp);
    *m
}

/// Rows where `x` does not stay put: its moving average over ±`w` rows spans more than `tol`
/// (of the local level) within ±`w` rows.
fn unsteady(x: &[f64], w: usize, tol: impl Fn(f64) -> f64) -> Vec<bool> {
    let n = x.len();
    // Prefix sums over finite values for the moving average.
    let mut sum = vec![0.0; n + 1];
    let mut cnt = vec![0usize; n + 1];
    for i in 0..n {
        let ok = x[i].is_finite();
        sum[i + 1] = sum[i] + if ok { x[i] } else { 0.0 };
        cnt[i + 1] = cnt[i] + usize::from(ok);
    }
    let smooth: Vec<f64> = (0..n)
        .map(|i| {
            let (a, b) = (i.saturating_sub(w), (i + w + 1).min(n));
            let c = cnt[b] - cnt[a];
            if c == 0 { f64::NAN } else { (sum[b] - sum[a]) / c as f64 }
        })
        .collect();
    let mut flag: Vec<bool> = (0..n)
        .map(|i| {
            let (a, b) = (i.saturating_sub(w), (i + w + 1).min(n));
            let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
            for &s in &smooth[a..b] {
                if s.is_finite() {
                    lo = lo.min(s);
                    hi = hi.max(s);
                }
            }
            hi > lo && hi - lo > tol(smooth[i].abs())
        })
        .collect();
    // The window flags up to `w` rows on each side of a change that are still at the level
    // before (or already at the level after) it: give back the edge rows whose lightly smoothed
    // value sits within half the tolerance of the neighbouring held level. Real runs change the
    // load right as a sweep comes back to zero; without this the sweep's last half second
    // would be lost to the ramp.
    let short = (w / 10).max(2);
    let near = |i: usize| {
        let (a, b) = (i.saturating_sub(short), (i + short + 1).min(n));
        let c = cnt[b] - cnt[a];
        if c == 0 { f64::NAN } else { (sum[b] - sum[a]) / c as f64 }
    };
    let mut i = 0;
    while i < n {
        if !flag[i] {
            i += 1;
            continue;
        }
        let (s, mut e) = (i, i);
        while e < n && flag[e] {
            e += 1;
        }
        i = e;
        if s > 0 {
            let level = smooth[s - 1];
            let mut k = s;
            while k < e && level.is_finite() && (near(k) - level).abs() <= 0.5 * tol(level.abs()) {
                flag[k] = false;
                k += 1;
            }
        }
        if e < n {
            let level = smooth[e];
            let mut k = e;
            while k > s && level.is_finite() && flag[k - 1] && (near(k - 1) - level).abs() <= 0.5 * tol(level.abs()) {
                flag[k - 1] = false;
                k -= 1;
            }
        }
    }
    flag
}

/// Sweeps of one signal over rows `a..b`: each starts where the signal leaves zero and ends
/// where it is back at zero having been to both sides, or has stayed quiet for `idle` rows
/// after going to one side. Returns inclusive row ranges.
fn excursions(x: &[f64], a: usize, b: usize, zero: f64, on: f64, idle: usize) -> Vec<(usize, usize)> {
    let mut out = Vec::new();
    let mut open: Option<usize> = None;
    let (mut pos, mut neg) = (false, false);
    let mut quiet_since: Option<usize> = None;
    let mut last_zero: Option<usize> = None;
    for i in a..b {
        let v = x[i];
        let quiet = v.abs() <= on;
        let at_zero = v.abs() <= zero;
        match open {
            None => {
                if quiet {
                    quiet_since.get_or_insert(i);
                    if at_zero {
                        last_zero = Some(i);
                    }
                } else {
                    if let Some(q) = quiet_since {
                        let start = last_zero.filter(|&z| z >= q).unwrap_or(q);
                        open = Some(start);
                        pos = v > on;
                        neg = v < -on;
                    }
                    quiet_since = None;
                }
            }
            Some(s) => {
                pos |= v > on;
                neg |= v < -on;
                if quiet {
                    let q = *quiet_since.get_or_insert(i);
                    let close = if pos && neg && at_zero {
                        Some(i)
                    } else if i - q >= idle {
                        Some(q)
                    } else {
                        None
                    };
                    if let Some(e) = close {
                        out.push((s, e));
                        open = None;
                        pos = false;
                        neg = false;
                        quiet_since = Some(e);
                        last_zero = (x[e].abs() <= zero).then_some(e);
                        if at_zero {
                            last_zero = Some(i);
                        }
                    }
                } else {
                    quiet_since = None;
                }
            }
        }
    }
    if let Some(s) = open {
        if let Some(q) = quiet_since {
            out.push((s, q));
        } else if pos && neg && b > s {
            // Cut off by the end of the held stretch after it had been to both sides (real runs
            // change the load or slip angle as a sweep comes back towards zero): the rows are
            // valid measurements at the held cell, and both sides of the curve are there.
            out.push((s, b - 1));
        }
    }
    out
}

/// Peak ratio between neighbouring lobes (stretches on one side of zero) beyond which they
/// belong to different sweeps: a sweep's two sides reach about alike; a conditioning sweep to
/// 4° running straight into a 13° sweep does not.
const LOBE_PEAK_RATIO: f64 = 2.5;

/// Splits an excursion `(s, e)` of `x` where the slip reach changes from one lobe to the next
/// by more than [`LOBE_PEAK_RATIO`] — back-to-back sweeps of different reach with no rest at
/// zero between them, which a sweep that starts while a ramp is excluded (the first sweep
/// after the rig comes up to speed) otherwise merges with its successor. The split is at the
/// zero crossing between the two lobes.
fn split_at_reach_changes(x: &[f64], (s, e): (usize, usize), on: f64) -> Vec<(usize, usize)> {
    // Lobes: (first row, last row, peak |x|), a new one where the sign flips beyond `on`.
    let mut lobes: Vec<(usize, usize, f64)> = Vec::new();
    let mut sign = 0.0;
    let mut last_small = s;
    for (i, &v) in x.iter().enumerate().take(e + 1).skip(s) {
        if v.abs() <= on {
            last_small = i;
            continue;
        }
        if v.signum() != sign {
            let cut = if sign == 0.0 { s } else { last_small };
            if let Some(l) = lobes.last_mut() {
                l.1 = cut;
            }
            lobes.push((cut, e, 0.0));
            sign = v.signum();
        }
        if let Some(l) = lobes.last_mut() {
            l.2 = l.2.max(v.abs());
        }
    }
    let mut out = Vec::new();
    let mut start = s;
    for w in lobes.windows(2) {
        let (a, b) = (w[0].2, w[1].2);
        if a.max(b) > LOBE_PEAK_RATIO * a.min(b).max(f64::MIN_POSITIVE) {
            out.push((start, w[1].0));
            start = w[1].0;
        }
    }
    out.push((start, e));
    out
}

/// Largest gap [s] between two one-sided halves that are one sweep (in seconds: files come at
/// 50 or 100 Hz).
const HALF_SWEEP_GAP_S: f64 = 1.0;

/// Joins back-to-back one-sided pieces of opposite sign and like reach (within
/// [`LOBE_PEAK_RATIO`], at most `max_gap_rows` apart: [`HALF_SWEEP_GAP_S`]) into one sweep: a
/// sweep whose first half was counted with the tail of a different sweep before it (and split
/// off again by [`split_at_reach_changes`]) comes back whole.
fn join_halves(x: &[f64], pieces: Vec<(usize, usize)>, on: f64, max_gap_rows: usize) -> Vec<(usize, usize)> {
    let sides = |(a, b): (usize, usize)| {
        let w = &x[a..=b.min(x.len().saturating_sub(1))];
        let reach = w.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        (w.iter().any(|v| *v > on), w.iter().any(|v| *v < -on), reach)
    };
    let mut out: Vec<(usize, usize)> = Vec::new();
    let mut last_one_sided = false;
    for p in pieces {
        if let Some(prev) = out.last_mut()
            && last_one_sided
        {
            let (pp, pn, pr) = sides(*prev);
            let (cp, cn, cr) = sides(p);
            let opposite = (pp && !pn && cn && !cp) || (pn && !pp && cp && !cn);
            let alike = pr.max(cr) <= LOBE_PEAK_RATIO * pr.min(cr);
            if opposite && alike && p.0 <= prev.1 + max_gap_rows {
                prev.1 = p.1;
                last_one_sided = false;
                continue;
            }
        }
        let (cp, cn, _) = sides(p);
        last_one_sided = cp != cn;
        out.push(p);
    }
    out
}

/// A held quantity, the reason its rows are excluded when it moves, and its tolerance.
type HeldCheck<'a> = (&'a [f64], Exclusion, Box<dyn Fn(f64) -> f64 + 'a>);

/// `flag` with gaps shorter than `fill` rows between flagged rows filled in: a sweep's
/// turn-arounds, where the slip angle pauses, belong to the sweep.
fn fill_short_gaps(flag: &[bool], fill: usize) -> Vec<bool> {
    let mut out = flag.to_vec();
    let mut k = 0;
    while k < out.len() {
        if out[k] {
            k += 1;
            continue;
        }
        let s = k;
        while k < out.len() && !out[k] {
            k += 1;
        }
        if s > 0 && k < out.len() && k - s < fill {
            out[s..k].iter_mut().for_each(|m| *m = true);
        }
    }
    out
}

/// Load flagged as moving while the slip angle sweeps is the rig's load control wandering, not a
/// change of cell, up to the last row where the load is back at the level it had before the
/// sweep (within the load tolerance) — all of it when the level after the sweep is that level
/// too — provided it never strays more than `max_fraction` of that level: those rows are given
/// back (the sweep stays one sweep, each point with its measured load). Real rigs of some rounds
/// swing ±10–20 % at the sweep's ends, and often change the load for the next cell right as the
/// sweep comes back to zero: the rows of that ramp stay a load ramp.
fn forgive_wander(
    fz: &[f64],
    bad: &mut [bool],
    sweeping: &[bool],
    w: usize,
    max_fraction: f64,
    tol: &dyn Fn(f64) -> f64,
) {
    let n = fz.len();
    let level = |rows: std::ops::Range<usize>, bad: &[bool]| median_of(rows.filter(|&i| !bad[i]).map(|i| fz[i]));
    let mut i = 0;
    while i < n {
        if !sweeping[i] {
            i += 1;
            continue;
        }
        let s = i;
        while i < n && sweeping[i] {
            i += 1;
        }
        let e = i;
        if !bad[s..e].iter().any(|b| *b) {
            continue;
        }
        let before = level(s.saturating_sub(2 * w)..s, bad);
        if !before.is_finite() {
            continue;
        }
        let home = |x: f64| (x - before).abs() <= tol(before.abs());
        let after = level(e..(e + 2 * w).min(n), bad);
        // Up to where the wander ends: the stretch's end when the load after it is home,
        // else its last row at home.
        let end = if after.is_finite() && home(after) {
            e
        } else {
            match (s..e).rev().find(|&r| fz[r].is_finite() && home(fz[r])) {
                Some(r) => r + 1,
                None => continue,
            }
        };
        let stray = fz[s..end].iter().filter(|x| x.is_finite()).fold(0.0_f64, |m, x| m.max((x - before).abs()));
        if stray <= max_fraction * before.abs() {
            bad[s..end].iter_mut().for_each(|b| *b = false);
        }
    }
}

/// Where `SR` is the only slip ratio, a slip-ratio excursion is a sweep only if the wheel is
/// driven or braked over it: `SR` also moves with slip angle and load while the wheel rolls free.
fn driven(sig: &Signals, (f, l): (usize, usize), fx_fraction: f64) -> bool {
    let rows = l + 1 - f;
    let hard = (f..=l).filter(|&r| sig.fx_n[r].abs() > fx_fraction * sig.fz_n[r].abs()).count();
    hard * 10 >= rows
}

/// Finds the sweeps of a run. `test` is what the file says its test is, if it says.
pub fn find_sweeps(
    sig: &Signals,
    kappa_source: KappaSource,
    test: Option<TestKind>,
    opt: &SweepOptions,
) -> Segmentation {
    let n = sig.fz_n.len();
    let mut why: Vec<Option<Exclusion>> = vec![None; n];
    let dt = {
        let d = median_of(sig.time_s.windows(2).map(|w| w[1] - w[0]).filter(|d| *d > 0.0));
        if d.is_finite() && d > 0.0 { d } else { 0.01 }
    };
    let rows_of = |s: f64| ((s / dt).round() as usize).clamp(1, 100_000);
    let w = rows_of(opt.hold_window_s);
    let uses_kappa = kappa_source != KappaSource::Absent;
    let fz_high = {
        let mut a: Vec<f64> = sig.fz_n.iter().copied().filter(|x| x.is_finite()).collect();
        if a.is_empty() {
            0.0
        } else {
            let k = ((a.len() - 1) as f64 * 0.98) as usize;
            *a.select_nth_unstable_by(k, f64::total_cmp).1
        }
    };
    for i in 0..n {
        let v = sig.v_mps.as_ref().map(|v| v[i]);
        why[i] = if !sig.fz_n[i].is_finite()
            || !sig.alpha_rad[i].is_finite()
            || (uses_kappa && !sig.kappa[i].is_finite())
            || v.is_some_and(|v| !v.is_finite())
        {
            Some(Exclusion::NonFinite)
        } else if v.is_some_and(|v| v.abs() < opt.standstill_mps) {
            Some(Exclusion::Standstill)
        } else if sig.fz_n[i] < (opt.unloaded_fraction * fz_high).max(50.0) {
            Some(Exclusion::Unloaded)
        } else {
            None
        };
    }
    let sa_deg: Vec<f64> = sig.alpha_rad.iter().map(|a| a.to_degrees()).collect();
    let sa_moving = unsteady(&sa_deg, w, |_| opt.sa_moving_deg);
    let fill = rows_of(1.0);
    let sa_sweeping = fill_short_gaps(&sa_moving, fill);
    let fz_tol = |l: f64| (opt.fz_tol_fraction * l).max(opt.fz_tol_n);
    let held: [HeldCheck; 3] = [
        (&sig.fz_n, Exclusion::LoadRamp, Box::new(fz_tol)),
        (&sig.p_pa, Exclusion::PressureRamp, Box::new(|l| (0.03 * l).max(opt.p_tol_pa))),
        (sig.v_mps.as_deref().unwrap_or(&[]), Exclusion::SpeedChange, Box::new(|l| (0.05 * l).max(opt.v_tol_mps))),
    ];
    for (x, reason, tol) in held.iter() {
        if x.len() != n {
            continue;
        }
        let mut bad = unsteady(x, w, tol);
        if *reason == Exclusion::LoadRamp {
            forgive_wander(x, &mut bad, &sa_sweeping, w, opt.fz_wander_fraction, tol);
        }
        for i in 0..n {
            if why[i].is_none() && bad[i] {
                why[i] = Some(*reason);
            }
        }
    }
    // Camber stepped at a held slip angle is a sweep of its own; elsewhere a camber change is a
    // change of cell.
    let gamma_deg: Vec<f64> = sig.gamma_rad.iter().map(|g| g.to_degrees()).collect();
    let camber_moving = unsteady(&gamma_deg, w, |_| opt.gamma_tol_rad.to_degrees());
    let camber_sweeps =
        crate::camber::find_camber_sweeps(sig, &why, &sa_sweeping, &camber_moving, kappa_source, w, opt);
    let mut taken = vec![false; n];
    for &(f, l) in &camber_sweeps {
        taken[f..=l].iter_mut().for_each(|t| *t = true);
    }
    for i in 0..n {
        if why[i].is_none() && camber_moving[i] && !taken[i] {
            why[i] = Some(Exclusion::CamberChange);
        }
    }
    let (kz, kon) = match kappa_source {
        KappaSource::EffectiveRadius => (opt.sr_zero, opt.sr_on),
        _ => (opt.kappa_zero, opt.kappa_on),
    };
    // SR is meaningless where the wheel rolls free: a cornering test has no slip-ratio sweeps.
    let kappa_ignored = kappa_source == KappaSource::EffectiveRadius && test == Some(TestKind::Cornering);
    let look_for_kappa = uses_kappa && !kappa_ignored;
    let idle = rows_of(opt.idle_split_s);
    let mut raw: Vec<(Swept, usize, usize)> = Vec::new();
    let mut sr_free = Vec::new();
    let mut i = 0;
    while i < n {
        if why[i].is_some() || taken[i] {
            i += 1;
            continue;
        }
        let a = i;
        while i < n && why[i].is_none() && !taken[i] {
            i += 1;
        }
        let b = i;
        // Moving and held pieces of the slip angle; held gaps shorter than 1 s between moving
        // rows (turn-arounds) belong to the sweep.
        let moving = fill_short_gaps(&sa_moving[a..b], fill);
        let mut k = 0;
        while k < moving.len() {
            let s = k;
            let m = moving[k];
            while k < moving.len() && moving[k] == m {
                k += 1;
            }
            let (pa, pb) = (a + s, a + k);
            if m {
                let pieces: Vec<(usize, usize)> = excursions(&sa_deg, pa, pb, opt.sa_zero_deg, opt.sa_on_deg, idle)
                    .into_iter()
                    .flat_map(|ex| split_at_reach_changes(&sa_deg, ex, opt.sa_on_deg))
                    .collect();
                for (f, l) in join_halves(&sa_deg, pieces, opt.sa_on_deg, rows_of(HALF_SWEEP_GAP_S)) {
                    raw.push((Swept::SlipAngle, f, l));
                }
                why[pa..pb].iter_mut().for_each(|w| *w = Some(Exclusion::SlipAngleChange));
            } else {
                why[pa..pb].iter_mut().for_each(|w| *w = Some(Exclusion::Idle));
                if look_for_kappa {
                    let pieces: Vec<(usize, usize)> = excursions(&sig.kappa, pa, pb, kz, kon, idle)
                        .into_iter()
                        .flat_map(|ex| split_at_reach_changes(&sig.kappa, ex, kon))
                        .collect();
                    for p in join_halves(&sig.kappa, pieces, kon, rows_of(HALF_SWEEP_GAP_S)) {
                        if kappa_source == KappaSource::EffectiveRadius && !driven(sig, p, opt.sr_driven_fx_fraction) {
                            sr_free.push(p);
                        } else {
                            raw.push((Swept::SlipRatio, p.0, p.1));
                        }
                    }
                }
            }
        }
    }
    for (f, l) in sr_free {
        why[f..=l].iter_mut().for_each(|w| *w = Some(Exclusion::SrFreeRolling));
    }
    raw.extend(camber_sweeps.iter().map(|&(f, l)| (Swept::Camber, f, l)));
    let min_rows = rows_of(opt.min_sweep_s).max(10);
    let mut sweeps = Vec::new();
    let mut sr_zeroed = 0;
    for (swept, f, l) in raw {
        if l + 1 - f < min_rows {
            why[f..=l].iter_mut().for_each(|w| *w = Some(Exclusion::ShortSweep));
            continue;
        }
        let rows = f..=l;
        let med = |x: &[f64]| median_of(x[rows.clone()].iter().copied());
        let alpha = med(&sig.alpha_rad);
        let max_abs = |x: &[f64]| x[rows.clone()].iter().fold(0.0_f64, |m, a| m.max(a.abs()));
        let (kind, reach) = match swept {
            Swept::SlipAngle => (SweepKind::Cornering, max_abs(&sig.alpha_rad)),
            // A camber sweep's slip is its held slip angle.
            Swept::Camber => (SweepKind::Cornering, alpha.abs()),
            Swept::SlipRatio => {
                let k = if alpha.abs() < 1.0_f64.to_radians() { SweepKind::DriveBrake } else { SweepKind::Combined };
                (k, max_abs(&sig.kappa))
            }
        };
        let free = swept != Swept::SlipRatio;
        let kappa = if free && kappa_source == KappaSource::EffectiveRadius {
            sr_zeroed += l + 1 - f;
            0.0
        } else if free {
            med(&sig.kappa)
        } else {
            0.0
        };
        let camber_span_deg = if swept == Swept::Camber {
            let (lo, hi) = sig.gamma_rad[rows.clone()]
                .iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), g| (lo.min(*g), hi.max(*g)));
            (hi - lo).to_degrees()
        } else {
            0.0
        };
        let cell = Cell {
            kind,
            fz_n: med(&sig.fz_n),
            p_pa: med(&sig.p_pa),
            gamma_rad: med(&sig.gamma_rad),
            alpha_rad: if swept == Swept::SlipAngle { 0.0 } else { alpha },
            kappa,
            // 0 when the file has no speed channel (a JSON-safe "unknown").
            vx_mps: sig.v_mps.as_ref().map(|v| med(v)).filter(|v| v.is_finite()).unwrap_or(0.0),
            slip_reach: reach,
        };
        why[f..=l].iter_mut().for_each(|w| *w = None);
        sweeps.push(FoundSweep {
            cell,
            swept,
            conditioning: None,
            camber_span_deg,
            first: f,
            last: l,
            tread_start_c: f64::NAN,
        });
    }
    // Rows of moving pieces outside any sweep: a sweep cut off, or a slip angle being set.
    mark_incomplete(&mut why, &sa_deg, opt.sa_zero_deg);
    sweeps.sort_by_key(|s| s.first);
    crate::conditioning::mark_short_reach(&mut sweeps, opt.conditioning_fraction);
    let mut sweeps = crate::conditioning::merge_conditioning(sweeps, &why);
    crate::conditioning::mark_leading_repeats(&mut sweeps);
    let starts = crate::conditioning::start_tread_temps(sig, &sweeps);
    for (s, t) in sweeps.iter_mut().zip(starts) {
        s.tread_start_c = t;
    }
    if opt.cold_start {
        crate::conditioning::mark_cold_start(&mut sweeps);
    }
    // Back-to-back sweeps share their boundary row: give it to the first.
    for k in 1..sweeps.len() {
        let prev_last = sweeps[k - 1].last;
        if sweeps[k].first <= prev_last {
            sweeps[k].first = prev_last + 1;
        }
    }
    sweeps.retain(|s| s.first <= s.last);
    for s in &sweeps {
        why[s.first..=s.last].iter_mut().for_each(|w| *w = None);
    }
    let mut excluded: Vec<(Exclusion, usize)> = Vec::new();
    for r in why.into_iter().flatten() {
        match excluded.iter_mut().find(|(e, _)| *e == r) {
            Some((_, c)) => *c += 1,
            None => excluded.push((r, 1)),
        }
    }
    excluded.sort();
    Segmentation { sweeps, excluded, sr_zeroed, kappa_ignored }
}

/// A slip-angle stretch that leaves zero and never returns is a sweep cut off by a ramp or the
/// end of the data, unless it only moved to a held angle (set between slip-ratio sweeps).
fn mark_incomplete(why: &mut [Option<Exclusion>], sa_deg: &[f64], zero: f64) {
    let n = why.len();
    let mut i = 0;
    while i < n {
        if why[i] != Some(Exclusion::SlipAngleChange) {
            i += 1;
            continue;
        }
        let s = i;
        while i < n && why[i] == Some(Exclusion::SlipAngleChange) {
            i += 1;
        }
        // A sweep crosses zero; setting a held angle goes from one level to another; the edges
        // of a sweep's window at zero slip are just rolling.
        let crosses = sa_deg[s..i].iter().any(|v| *v > zero) && sa_deg[s..i].iter().any(|v| *v < -zero);
        let at_zero = sa_deg[s..i].iter().all(|v| v.abs() <= 2.0 * zero);
        let reason = if at_zero {
            Exclusion::Idle
        } else if crosses {
            Exclusion::IncompleteSweep
        } else {
            Exclusion::SlipAngleChange
        };
        why[s..i].iter_mut().for_each(|w| *w = Some(reason));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn excursions_split_full_and_one_sided_sweeps() {
        // 0 → -5 → +5 → 0, twice, then one-sided 0 → 3 → 0 and a long rest.
        let mut x = Vec::new();
        for _ in 0..2 {
            x.extend((0..50).map(|i| -(i as f64) / 10.0));
            x.extend((0..100).map(|i| -5.0 + i as f64 / 10.0));
            x.extend((0..50).map(|i| 5.0 - i as f64 / 10.0));
        }
        x.extend((0..30).map(|i| i as f64 / 10.0));
        x.extend((0..30).map(|i| 3.0 - i as f64 / 10.0));
        x.extend(std::iter::repeat_n(0.0, 300));
        let s = excursions(&x, 0, x.len(), 0.5, 1.0, 100);
        assert_eq!(s.len(), 3, "{s:?}");
        assert!(s[0].0 <= 5 && (194..=200).contains(&s[0].1), "{s:?}");
        // Back to back: the next starts where the signal last sat at zero.
        assert!((s[0].1..=s[0].1 + 10).contains(&s[1].0), "{s:?}");
        assert!(s[2].0 >= 395 && s[2].1 >= 450 && s[2].1 < 470, "{s:?}");
    }

    #[test]
    fn a_short_sweep_running_into_a_long_one_is_split_at_the_zero_crossing() {
        // The tail of a ±4° conditioning sweep (its start lost to a speed ramp) straight into a
        // ±13° sweep: one excursion, two sweeps.
        let mut x: Vec<f64> = (0..40).map(|i| -(i as f64) / 10.0).collect(); // 0 → −4
        x.extend((0..40).map(|i| -4.0 + i as f64 / 10.0)); // → 0 at row 80
        x.extend((0..130).map(|i| i as f64 / 10.0)); // → 13
        x.extend((0..260).map(|i| 13.0 - i as f64 / 10.0)); // → −13
        x.extend((0..131).map(|i| -13.0 + i as f64 / 10.0)); // → 0
        let parts = split_at_reach_changes(&x, (0, x.len() - 1), 1.0);
        assert_eq!(parts.len(), 2, "{parts:?}");
        assert!((75..=90).contains(&parts[0].1), "{parts:?}");
        assert_eq!(parts[0].1, parts[1].0);
        // The excursion logic closed the first piece at the 13° sweep's mid-way zero (it had
        // seen both sides by then): split, then the two halves of the 13° sweep are one again.
        let pieces = [(0, 340), (340, x.len() - 1)]
            .into_iter()
            .flat_map(|p| split_at_reach_changes(&x, p, 1.0))
            .collect::<Vec<_>>();
        let joined = join_halves(&x, pieces, 1.0, 50);
        assert_eq!(joined.len(), 2, "{joined:?}");
        assert!((75..=90).contains(&joined[0].1) && joined[1].1 == x.len() - 1, "{joined:?}");
        // A sweep whose sides reach alike (and noise near zero) stays whole.
        let y: Vec<f64> = x[80..].iter().enumerate().map(|(i, v)| v + if i % 2 == 0 { 0.3 } else { -0.3 }).collect();
        assert_eq!(split_at_reach_changes(&y, (0, y.len() - 1), 1.0).len(), 1);
    }

    /// 60 s at 50 Hz rolling at 40 kph, 2 kN, slip angle held at `sa_deg`, with `SR` going
    /// 0 → −0.08 → +0.08 → 0 over 8 s in the middle and FX = `fx_per_sr` × FZ × SR.
    fn held_run(sa_deg: f64, fx_per_sr: f64) -> Signals {
        let n = 3000;
        let sr: Vec<f64> = (0..n)
            .map(|i| {
                let t = (i as f64 - 1200.0) / 400.0; // 0..1 over the 8 s excursion
                if (0.0..1.0).contains(&t) { -0.08 * (std::f64::consts::TAU * t).sin() } else { -0.01 }
            })
            .collect();
        Signals {
            time_s: (0..n).map(|i| i as f64 * 0.02).collect(),
            v_mps: Some(vec![11.1; n]),
            omega_radps: vec![43.0; n],
            alpha_rad: vec![sa_deg.to_radians(); n],
            gamma_rad: vec![0.0; n],
            rl_m: vec![0.25; n],
            p_pa: vec![83_000.0; n],
            fx_n: sr.iter().map(|k| fx_per_sr * 2000.0 * k).collect(),
            fy_n: vec![-3000.0; n],
            fz_n: vec![2000.0; n],
            mx_nm: vec![0.0; n],
            my_nm: vec![0.0; n],
            mz_nm: vec![0.0; n],
            kappa: sr,
            temp_inner_c: vec![50.0; n],
            temp_centre_c: vec![50.0; n],
            temp_outer_c: vec![50.0; n],
            road_temp_c: vec![30.0; n],
            ambient_c: None,
        }
    }

    #[test]
    fn sr_moving_is_a_slip_ratio_sweep_only_where_the_wheel_is_driven_or_braked() {
        // Free rolling at 12°: SR swings (it grows with slip angle and load) with FX about 0.
        let free = find_sweeps(&held_run(12.0, 0.2), KappaSource::EffectiveRadius, None, &SweepOptions::default());
        assert!(free.sweeps.is_empty(), "{:?}", free.sweeps);
        let sr_rows = free.excluded.iter().find(|e| e.0 == Exclusion::SrFreeRolling).map(|e| e.1).unwrap_or(0);
        assert!(sr_rows > 300, "{:?}", free.excluded);
        // Driven and braked (FX up to 1.6 FZ at SR 0.08): a combined sweep at 12°.
        let driven = find_sweeps(&held_run(12.0, 20.0), KappaSource::EffectiveRadius, None, &SweepOptions::default());
        assert_eq!(driven.sweeps.len(), 1, "{:?}", driven.excluded);
        assert_eq!((driven.sweeps[0].swept, driven.sweeps[0].cell.kind), (Swept::SlipRatio, SweepKind::Combined));
        // With SL the rule does not apply: SL moves only when the rig drives the wheel.
        let sl = find_sweeps(&held_run(0.0, 0.2), KappaSource::LoadedRadius, None, &SweepOptions::default());
        assert_eq!(sl.sweeps.len(), 1);
    }

    #[test]
    fn unsteady_flags_a_ramp_not_noise() {
        let x: Vec<f64> = (0..600)
            .map(|i| if i < 250 { 1000.0 } else if i < 300 { 1000.0 + (i - 250) as f64 * 10.0 } else { 1500.0 } + if i % 2 == 0 { 15.0 } else { -15.0 })
            .collect();
        let bad = unsteady(&x, 25, |l| (0.06 * l).max(60.0));
        assert!(!bad[100] && !bad[500]);
        assert!(bad[275]);
        assert!(bad.iter().filter(|b| **b).count() < 120);
    }
}

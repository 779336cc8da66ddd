//! Sweep primitives: slip paths with rate laws, load and camber couplings, keyframe trajectories.
//!
//! Every primitive is a pure generator: given the time since its start it yields a [`Setpoint`],
//! and it knows its duration. Nothing here reads a clock.

use crate::setpoint::{RigMode, Setpoint};
use serde::{Deserialize, Serialize};

/// Which slip a sweep moves.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum SlipAxis {
    /// Slip angle \[deg\] (free rolling).
    SlipAngle,
    /// Slip ratio \[-\] (coupled drive).
    SlipRatio,
}

/// How fast the slip moves as a function of |slip| (units: the axis's unit per second).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case", tag = "law")]
pub enum RateLaw {
    /// One rate throughout.
    Constant {
        /// Rate \[deg/s or 1/s\].
        rate: f64,
    },
    /// The thesis's "shark tooth": `low_rate` while |slip| < `threshold`, `high_rate` beyond.
    Variable {
        /// Rate below the threshold.
        low_rate: f64,
        /// Rate at and beyond the threshold.
        high_rate: f64,
        /// |slip| where the rate switches.
        threshold: f64,
    },
    /// Continually variable rate (the thesis's future work): the rate rises smoothly from its
    /// zero-slip value, flat at zero slip, to the rig's maximum:
    /// `r(s) = min(max_rate, rate_at_zero · (1 + (s / knee)²))`.
    ///
    /// Why quadratic: mechanical hysteresis is the lag of the tyre's force behind the slip as it
    /// crosses zero, and the lag there reflects the rate over the last relaxation length of
    /// travel, not only the rate at zero. A law flat at zero (zero slope) keeps that recent rate
    /// at the variable sweep's low rate, so the data near zero are as good, and then rises
    /// smoothly (no step) and faster than a linear law. Measured on the full GS2MF suite (see
    /// `docs/procedures.md`): the linear law `1 + |s|/knee` with the same knee gave 12 % more
    /// FreeRolling hysteresis than the variable-rate sweeps; the quadratic law gives the same.
    Continuous {
        /// Rate at zero slip (the "near zero" rate).
        rate_at_zero: f64,
        /// Rate cap (the rig's fastest).
        max_rate: f64,
        /// |slip| at which the rate has doubled.
        knee: f64,
    },
}

/// Knee of the continually variable law as a fraction of the variable sweep's threshold, per
/// axis. Chosen by measurement on the full GS2MF suite on the virtual rig (docs/procedures.md):
/// - slip angle 1/3: FreeRolling hysteresis equal to the variable sweeps' (436 vs 436 N), sweeps
///   half as long, cool-downs 21 % shorter (1/2 and 2/3 gave less time saved, same hysteresis);
/// - slip ratio 1: BrkDrv's 2 % threshold leaves little low-rate travel to save, and a knee of
///   1/3 raised the hysteresis by a third (1,909 vs 1,431 N); at 1 it stays within 5 %.
pub fn continuous_knee_fraction(axis: SlipAxis) -> f64 {
    match axis {
        SlipAxis::SlipAngle => 1.0 / 3.0,
        SlipAxis::SlipRatio => 1.0,
    }
}

impl RateLaw {
    /// The continually variable law that replaces a variable-rate sweep on `axis`: same rate at
    /// zero, same top rate, knee = threshold × [`continuous_knee_fraction`].
    pub fn continuous_from_variable(low_rate: f64, high_rate: f64, threshold: f64, axis: SlipAxis) -> Self {
        Self::Continuous {
            rate_at_zero: low_rate,
            max_rate: high_rate,
            knee: threshold * continuous_knee_fraction(axis),
        }
    }

    /// Slip rate at `|slip|` = `s_abs`.
    pub fn rate_at(&self, s_abs: f64) -> f64 {
        let s = s_abs.abs();
        match *self {
            Self::Constant { rate } => rate,
            Self::Variable { low_rate, high_rate, threshold } => {
                if s < threshold {
                    low_rate
                } else {
                    high_rate
                }
            }
            Self::Continuous { rate_at_zero, max_rate, knee } => {
                (rate_at_zero * (1.0 + (s / knee).powi(2))).min(max_rate.max(rate_at_zero))
            }
        }
    }

    /// The fastest rate the law ever asks for.
    pub fn max_rate(&self) -> f64 {
        match *self {
            Self::Constant { rate } => rate,
            Self::Variable { low_rate, high_rate, .. } => low_rate.max(high_rate),
            Self::Continuous { rate_at_zero, max_rate, .. } => rate_at_zero.max(max_rate),
        }
    }

    /// Whether every parameter is finite and positive.
    pub fn is_valid(&self) -> bool {
        let p = |x: f64| x.is_finite() && x > 0.0;
        match *self {
            Self::Constant { rate } => p(rate),
            Self::Variable { low_rate, high_rate, threshold } => {
                p(low_rate) && p(high_rate) && threshold.is_finite() && threshold >= 0.0
            }
            Self::Continuous { rate_at_zero, max_rate, knee } => p(rate_at_zero) && p(max_rate) && p(knee),
        }
    }

    /// Time to move outward from |slip| = 0 to |slip| = `s` (`F(s) = ∫₀ˢ du / r(u)`).
    pub fn time_from_zero(&self, s: f64) -> f64 {
        let s = s.abs();
        match *self {
            Self::Constant { rate } => s / rate,
            Self::Variable { low_rate, high_rate, threshold } => {
                if s <= threshold {
                    s / low_rate
                } else {
                    threshold / low_rate + (s - threshold) / high_rate
                }
            }
            Self::Continuous { rate_at_zero, max_rate, knee } => {
                let s_cap = self.continuous_cap_slip();
                if s <= s_cap {
                    knee / rate_at_zero * (s / knee).atan()
                } else {
                    knee / rate_at_zero * (s_cap / knee).atan() + (s - s_cap) / max_rate
                }
            }
        }
    }

    /// Inverse of [`Self::time_from_zero`]: the |slip| reached `t` seconds after leaving zero.
    pub fn slip_at_time_from_zero(&self, t: f64) -> f64 {
        let t = t.max(0.0);
        match *self {
            Self::Constant { rate } => t * rate,
            Self::Variable { low_rate, high_rate, threshold } => {
                let t_th = threshold / low_rate;
                if t <= t_th { t * low_rate } else { threshold + (t - t_th) * high_rate }
            }
            Self::Continuous { rate_at_zero, max_rate, knee } => {
                let s_cap = self.continuous_cap_slip();
                let t_cap = knee / rate_at_zero * (s_cap / knee).atan();
                if t <= t_cap { knee * (t * rate_at_zero / knee).tan() } else { s_cap + (t - t_cap) * max_rate }
            }
        }
    }

    /// Continuous law: |slip| where the rate reaches its cap (0 for other laws).
    fn continuous_cap_slip(&self) -> f64 {
        match *self {
            Self::Continuous { rate_at_zero, max_rate, knee } => knee * (max_rate / rate_at_zero - 1.0).max(0.0).sqrt(),
            _ => 0.0,
        }
    }
}

/// One monotone-magnitude piece of a slip path (never crosses zero inside).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
struct Piece {
    t0_s: f64,
    duration_s: f64,
    sign: f64,
    from_abs: f64,
    to_abs: f64,
}

/// A slip path: straight legs between waypoints, each run under a [`RateLaw`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SlipPath {
    /// Waypoints in the axis's unit (deg or slip ratio); starts and usually ends at 0.
    pub waypoints: Vec<f64>,
    /// The rate law.
    pub law: RateLaw,
    pieces: Vec<Piece>,
    duration_s: f64,
}

impl SlipPath {
    /// Build a path. Waypoints must be finite and the law valid (checked by the caller's
    /// validation; bad values give a zero-length path rather than a panic).
    pub fn new(waypoints: Vec<f64>, law: RateLaw) -> Self {
        let mut pieces = Vec::new();
        let mut t = 0.0;
        let ok = law.is_valid() && waypoints.iter().all(|w| w.is_finite());
        if ok {
            for leg in waypoints.windows(2) {
                let (a, b) = (leg[0], leg[1]);
                // Split a leg crossing zero into an inward and an outward piece.
                let parts: Vec<(f64, f64)> = if a * b < 0.0 { vec![(a, 0.0), (0.0, b)] } else { vec![(a, b)] };
                for (x, y) in parts {
                    if x == y {
                        continue;
                    }
                    let sign = if x + y > 0.0 { 1.0 } else { -1.0 };
                    let d = (law.time_from_zero(y) - law.time_from_zero(x)).abs();
                    pieces.push(Piece { t0_s: t, duration_s: d, sign, from_abs: x.abs(), to_abs: y.abs() });
                    t += d;
                }
            }
        }
        Self { waypoints, law, pieces, duration_s: t }
    }

    /// A full sweep to ±`peak`: 0 → −peak → +peak → 0 (negative first: the right-side tyre's
    /// high-load side, while the tread is coolest).
    pub fn full_cycle(peak: f64, law: RateLaw) -> Self {
        Self::new(vec![0.0, -peak, peak, 0.0], law)
    }

    /// Total time of the path \[s\].
    pub fn duration_s(&self) -> f64 {
        self.duration_s
    }

    /// Slip at `t_s` seconds (clamped to the path).
    pub fn at(&self, t_s: f64) -> f64 {
        let t = t_s.clamp(0.0, self.duration_s);
        let Some(p) = self.pieces.iter().rev().find(|p| p.t0_s <= t).or(self.pieces.first()) else {
            return self.waypoints.first().copied().unwrap_or(0.0);
        };
        let dt = (t - p.t0_s).min(p.duration_s);
        let abs = if p.to_abs >= p.from_abs {
            let t_from = self.law.time_from_zero(p.from_abs);
            self.law.slip_at_time_from_zero(t_from + dt).min(p.to_abs)
        } else {
            let t_from = self.law.time_from_zero(p.from_abs);
            self.law.slip_at_time_from_zero(t_from - dt).max(p.to_abs)
        };
        p.sign * abs
    }

    /// Largest |slip| on the path.
    pub fn peak_abs(&self) -> f64 {
        self.waypoints.iter().fold(0.0_f64, |m, w| m.max(w.abs()))
    }

    /// ∫|slip| dt over the path (a wear and heat proxy used by time estimates) \[unit·s\].
    pub fn slip_time_integral(&self) -> f64 {
        let n = 400;
        let dt = self.duration_s / n as f64;
        (0..n).map(|i| self.at((i as f64 + 0.5) * dt).abs() * dt).sum()
    }
}

/// Thesis asymmetric-load presets (Table 3.7-A): factors of Fz0 at negative / positive slip angle.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum AsymLevel {
    /// 1.8 / 0.6.
    High,
    /// 1.6 / 0.4.
    Medium,
    /// 1.4 / 0.2.
    Low,
}

impl AsymLevel {
    /// (factor at negative slip angle, factor at positive slip angle).
    pub fn factors(self) -> (f64, f64) {
        match self {
            Self::High => (1.8, 0.6),
            Self::Medium => (1.6, 0.4),
            Self::Low => (1.4, 0.2),
        }
    }
}

/// Slip angle beyond which the vehicle's weight transfer has saturated (§3.7: ≈ 5°).
pub const ASYM_SATURATION_DEG: f64 = 5.0;

/// How the vertical load follows the slip angle.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case", tag = "coupling")]
pub enum LoadCoupling {
    /// Constant load.
    Constant {
        /// Load \[N\].
        fz_n: f64,
    },
    /// Lateral weight transfer: linear in slip angle between the mean load at 0° and
    /// `neg_n` / `pos_n` at ∓`saturation_deg`, constant beyond.
    Asymmetric {
        /// Load at slip angle ≤ −saturation \[N\].
        neg_n: f64,
        /// Load at slip angle ≥ +saturation \[N\].
        pos_n: f64,
        /// Saturation slip angle \[deg\].
        saturation_deg: f64,
    },
}

impl LoadCoupling {
    /// An asymmetric coupling from thesis factors; `adverse` swaps the sides (load rises at
    /// positive slip: rollover, adverse road camber).
    pub fn asymmetric(fz0_n: f64, neg_factor: f64, pos_factor: f64, adverse: bool) -> Self {
        let (n, p) = if adverse { (pos_factor, neg_factor) } else { (neg_factor, pos_factor) };
        Self::Asymmetric { neg_n: n * fz0_n, pos_n: p * fz0_n, saturation_deg: ASYM_SATURATION_DEG }
    }

    /// Load at slip angle `sa_deg` \[N\].
    pub fn at(&self, sa_deg: f64) -> f64 {
        match *self {
            Self::Constant { fz_n } => fz_n,
            Self::Asymmetric { neg_n, pos_n, saturation_deg } => {
                let mean = 0.5 * (neg_n + pos_n);
                let half = 0.5 * (neg_n - pos_n);
                let x = if saturation_deg > 0.0 { (sa_deg / saturation_deg).clamp(-1.0, 1.0) } else { sa_deg.signum() };
                mean - half * x
            }
        }
    }
}

/// How camber follows the slip angle.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case", tag = "coupling")]
pub enum CamberCoupling {
    /// Constant camber \[deg\].
    Constant {
        /// Camber \[deg\].
        camber_deg: f64,
    },
    /// `camber = gain_deg · clamp(SA / saturation_deg, −1, 1)`: positive gain acts with the slip
    /// angle (everyday cornering), negative gain against it (adverse).
    Coupled {
        /// Camber reached at and beyond the saturation slip angle \[deg\].
        gain_deg: f64,
        /// Slip angle where camber stops following \[deg\].
        saturation_deg: f64,
    },
}

impl CamberCoupling {
    /// Camber at slip angle `sa_deg` \[deg\].
    pub fn at(&self, sa_deg: f64) -> f64 {
        match *self {
            Self::Constant { camber_deg } => camber_deg,
            Self::Coupled { gain_deg, saturation_deg } => {
                let x = if saturation_deg > 0.0 { (sa_deg / saturation_deg).clamp(-1.0, 1.0) } else { sa_deg.signum() };
                gain_deg * x
            }
        }
    }
}

/// A slip sweep: a [`SlipPath`] on one axis, the other axes fixed or coupled to slip angle.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SlipSweep {
    /// Swept axis.
    pub axis: SlipAxis,
    /// The path.
    pub path: SlipPath,
    /// Mode, pressure, speed and (for slip-ratio sweeps) the held slip angle.
    pub base: Setpoint,
    /// Load coupling (evaluated on the slip angle).
    pub load: LoadCoupling,
    /// Camber coupling (evaluated on the slip angle).
    pub camber: CamberCoupling,
}

impl SlipSweep {
    /// Setpoint at `t_s` since the sweep's start.
    pub fn at(&self, t_s: f64) -> Setpoint {
        let s = self.path.at(t_s);
        let mut sp = self.base;
        match self.axis {
            SlipAxis::SlipAngle => sp.slip_angle_deg = s,
            SlipAxis::SlipRatio => sp.slip_ratio = s,
        }
        sp.fz_n = self.load.at(sp.slip_angle_deg);
        sp.camber_deg = self.camber.at(sp.slip_angle_deg);
        sp
    }
}

/// One keyframe: the setpoint at `t_s`; axes interpolate linearly to the next frame, the mode
/// is this frame's until the next one.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Keyframe {
    /// Time since the trajectory's start \[s\].
    pub t_s: f64,
    /// Setpoint at that time.
    pub sp: Setpoint,
}

/// A piecewise-linear trajectory through keyframes (holds, ramps, step-steer, static drags…).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, Default)]
pub struct Keyframes {
    frames: Vec<Keyframe>,
}

impl Keyframes {
    /// Start at `sp`.
    pub fn start(sp: Setpoint) -> Self {
        Self { frames: vec![Keyframe { t_s: 0.0, sp }] }
    }

    /// The last setpoint.
    pub fn last(&self) -> Setpoint {
        self.frames.last().map(|k| k.sp).unwrap_or_default()
    }

    /// Duration so far \[s\].
    pub fn duration_s(&self) -> f64 {
        self.frames.last().map_or(0.0, |k| k.t_s)
    }

    /// Move linearly to `sp` over `dt_s` seconds (a mode change takes effect at the end).
    pub fn to(mut self, dt_s: f64, sp: Setpoint) -> Self {
        let t = self.duration_s() + dt_s.max(0.0);
        self.frames.push(Keyframe { t_s: t, sp });
        self
    }

    /// Switch mode at once (zero-length step).
    pub fn mode(self, mode: RigMode) -> Self {
        let mut sp = self.last();
        sp.mode = mode;
        self.to(0.0, sp)
    }

    /// Hold the last setpoint for `dt_s`.
    pub fn hold(self, dt_s: f64) -> Self {
        let sp = self.last();
        self.to(dt_s, sp)
    }

    /// Change the last setpoint with `f` over `dt_s`.
    pub fn then(self, dt_s: f64, f: impl FnOnce(&mut Setpoint)) -> Self {
        let mut sp = self.last();
        f(&mut sp);
        self.to(dt_s, sp)
    }

    /// The keyframes.
    pub fn frames(&self) -> &[Keyframe] {
        &self.frames
    }

    /// Setpoint at `t_s` (clamped).
    pub fn at(&self, t_s: f64) -> Setpoint {
        let Some(first) = self.frames.first() else {
            return Setpoint::default();
        };
        if t_s <= first.t_s {
            return first.sp;
        }
        for w in self.frames.windows(2) {
            let (a, b) = (&w[0], &w[1]);
            if t_s < b.t_s {
                let f = (t_s - a.t_s) / (b.t_s - a.t_s);
                return Setpoint::lerp(&a.sp, &b.sp, f);
            }
        }
        self.last()
    }
}

/// A trajectory: what a plan step streams.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case", tag = "type")]
pub enum Trajectory {
    /// A slip sweep.
    Sweep(SlipSweep),
    /// Keyframes.
    Keyframes(Keyframes),
}

impl Trajectory {
    /// Duration \[s\].
    pub fn duration_s(&self) -> f64 {
        match self {
            Self::Sweep(s) => s.path.duration_s(),
            Self::Keyframes(k) => k.duration_s(),
        }
    }

    /// Setpoint at `t_s` since the start (clamped to the trajectory).
    pub fn at(&self, t_s: f64) -> Setpoint {
        match self {
            Self::Sweep(s) => s.at(t_s),
            Self::Keyframes(k) => k.at(t_s),
        }
    }

    /// First setpoint.
    pub fn start(&self) -> Setpoint {
        self.at(0.0)
    }

    /// Last setpoint.
    pub fn end(&self) -> Setpoint {
        match self {
            Self::Sweep(s) => s.at(s.path.duration_s()),
            Self::Keyframes(k) => k.last(),
        }
    }

    /// Fastest slip-angle \[deg/s\] and slip-ratio \[1/s\] rates the trajectory asks for.
    pub fn max_slip_rates(&self) -> (f64, f64) {
        match self {
            Self::Sweep(s) => {
                let r = if s.path.duration_s() > 0.0 { s.path.law.max_rate() } else { 0.0 };
                match s.axis {
                    SlipAxis::SlipAngle => (r, 0.0),
                    SlipAxis::SlipRatio => (0.0, r),
                }
            }
            Self::Keyframes(k) => k.frames().windows(2).fold((0.0, 0.0), |(a, r), w| {
                let dt = w[1].t_s - w[0].t_s;
                let da = (w[1].sp.slip_angle_deg - w[0].sp.slip_angle_deg).abs();
                let dr = (w[1].sp.slip_ratio - w[0].sp.slip_ratio).abs();
                if dt > 0.0 {
                    (f64::max(a, da / dt), f64::max(r, dr / dt))
                } else if da > 0.0 || dr > 0.0 {
                    // A jump in slip: an infinite rate.
                    (if da > 0.0 { f64::INFINITY } else { a }, if dr > 0.0 { f64::INFINITY } else { r })
                } else {
                    (a, r)
                }
            }),
        }
    }

    /// Every setpoint the envelope check must see: keyframe vertices (the envelope is a box, so
    /// straight lines between vertices inside it stay inside), or a sweep sampled at its
    /// waypoints and densely between them.
    pub fn check_points(&self) -> Vec<Setpoint> {
        match self {
            Self::Keyframes(k) => k.frames().iter().map(|f| f.sp).collect(),
            Self::Sweep(s) => {
                let d = s.path.duration_s();
                let n = ((d / 0.05).ceil() as usize).clamp(2, 20_000);
                (0..=n).map(|i| s.at(d * i as f64 / n as f64)).collect()
            }
        }
    }
}

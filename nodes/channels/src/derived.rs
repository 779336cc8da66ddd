//! Derived measurements (thesis §3.6.2, §3.10–§3.12): pure functions over collected data, each
//! tested against the thesis's worked example.
//!
//! | quantity | from | thesis |
//! |---|---|---|
//! | cornering stiffness, RSAT, RCF | on-centre clumps at −1/0/+1° per load and pressure | §3.11: 2,750 N/° at 8,750 N, RSAT −8 N·m, RCF −222 N |
//! | loaded radius, vertical stiffness, unloaded radius | rolling-radius load steps | §3.10: extrapolation to Fz = 0 per pressure, averaged (0.3938 m) |
//! | lateral relaxation length | step-steer FY vs LONGDISP | §3.12.1: 0.475 − 0.05 = 0.425 m |
//! | longitudinal stiffness | static drags FX vs displacement | §3.12.2 |
//! | mechanical hysteresis | force at zero-slip crossings | §3.6.1: +1,730 − (−2,220) = 3,950 N |

use serde::{Deserialize, Serialize};

/// What a [`DerivedMeasurement`] measures.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Quantity {
    /// |dFY/dSA| on centre [N/deg].
    CorneringStiffness,
    /// Residual self-aligning torque: MZ where FY = 0 [N·m].
    Rsat,
    /// Residual cornering force: FY where MZ = 0 [N].
    Rcf,
    /// DSTWOWHC at a load step [m].
    LoadedRadius,
    /// −dFz/dDSTWOWHC per pressure [N/m].
    VerticalStiffness,
    /// DSTWOWHC extrapolated to Fz = 0: per pressure, and (pressure_pa NaN) the average [m].
    UnloadedRadius,
    /// Lateral relaxation length from a step-steer (or, with slip_angle_deg NaN, the ± pair's
    /// mean) [m].
    LateralRelaxationLength,
    /// Longitudinal (static) stiffness of the carcass, averaged over repeats [N/m].
    LongitudinalStiffness,
}

impl Quantity {
    /// Snake-case name (as serialised).
    pub fn name(self) -> &'static str {
        match self {
            Self::CorneringStiffness => "cornering_stiffness",
            Self::Rsat => "rsat",
            Self::Rcf => "rcf",
            Self::LoadedRadius => "loaded_radius",
            Self::VerticalStiffness => "vertical_stiffness",
            Self::UnloadedRadius => "unloaded_radius",
            Self::LateralRelaxationLength => "lateral_relaxation_length",
            Self::LongitudinalStiffness => "longitudinal_stiffness",
        }
    }

    /// Unit of the value.
    pub fn unit(self) -> &'static str {
        match self {
            Self::CorneringStiffness => "N/deg",
            Self::Rsat => "N*m",
            Self::Rcf => "N",
            Self::LoadedRadius | Self::UnloadedRadius | Self::LateralRelaxationLength => "m",
            Self::VerticalStiffness | Self::LongitudinalStiffness => "N/m",
        }
    }
}

/// One derived measurement with the conditions it was taken at (NaN where not applicable).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct DerivedMeasurement {
    /// What it is.
    pub quantity: Quantity,
    /// The value, in [`Quantity::unit`].
    pub value: f64,
    /// Section it came from.
    pub section: String,
    /// Mean vertical load [N].
    pub fz_n: f64,
    /// Mean inflation pressure [Pa].
    pub pressure_pa: f64,
    /// Mean forward speed [m/s].
    pub speed_mps: f64,
    /// Slip angle the test held [deg].
    pub slip_angle_deg: f64,
    /// How many points (clumps, samples, tests) went into it.
    pub n_points: usize,
    /// RUNTIME when it was derived [s].
    pub rig_time_s: f64,
    /// Procedure it came from (set by the core when it publishes).
    #[serde(default)]
    pub procedure: String,
}

impl DerivedMeasurement {
    /// A measurement with every condition NaN.
    pub fn new(quantity: Quantity, value: f64, section: &str, rig_time_s: f64) -> Self {
        Self {
            quantity,
            value,
            section: section.to_owned(),
            fz_n: f64::NAN,
            pressure_pa: f64::NAN,
            speed_mps: f64::NAN,
            slip_angle_deg: f64::NAN,
            n_points: 0,
            rig_time_s,
            procedure: String::new(),
        }
    }

    /// As the `channels/derived` message.
    pub fn to_msg(&self) -> tyre_msgs::DerivedMeasurement {
        tyre_msgs::DerivedMeasurement {
            header: tyre_msgs::std_msgs::Header::iso_w(self.rig_time_s),
            quantity: self.quantity.name().to_owned(),
            value: self.value,
            unit: self.quantity.unit().to_owned(),
            procedure: self.procedure.clone(),
            section: self.section.clone(),
            fz_n: self.fz_n,
            pressure_pa: self.pressure_pa,
            speed_mps: self.speed_mps,
            slip_angle_deg: self.slip_angle_deg,
            n_points: u32::try_from(self.n_points).unwrap_or(u32::MAX),
        }
    }
}

/// A least-squares straight line y = slope·x + intercept.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LineFit {
    /// dy/dx.
    pub slope: f64,
    /// y at x = 0.
    pub intercept: f64,
    /// Number of points.
    pub n: usize,
}

impl LineFit {
    /// y at `x`.
    pub fn at(&self, x: f64) -> f64 {
        self.intercept + self.slope * x
    }

    /// x where y = 0 (NaN for a flat line).
    pub fn root(&self) -> f64 {
        if self.slope == 0.0 { f64::NAN } else { -self.intercept / self.slope }
    }
}

/// Ordinary least-squares line through the finite (x, y) pairs; `None` with fewer than two
/// distinct x.
pub fn fit_line(xs: &[f64], ys: &[f64]) -> Option<LineFit> {
    let pts: Vec<(f64, f64)> =
        xs.iter().zip(ys).filter(|(x, y)| x.is_finite() && y.is_finite()).map(|(x, y)| (*x, *y)).collect();
    let n = pts.len();
    if n < 2 {
        return None;
    }
    let nf = n as f64;
    let mx = pts.iter().map(|p| p.0).sum::<f64>() / nf;
    let my = pts.iter().map(|p| p.1).sum::<f64>() / nf;
    let sxx: f64 = pts.iter().map(|p| (p.0 - mx).powi(2)).sum();
    let sxy: f64 = pts.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
    // Distinct x are needed; compare with the scale of x so tiny jitter does not pass.
    if sxx.is_nan() || sxx <= 1e-18 * (1.0 + mx * mx) * nf {
        return None;
    }
    let slope = sxy / sxx;
    Some(LineFit { slope, intercept: my - slope * mx, n })
}

/// One on-centre clump: the mean of a hold at one slip angle, load and pressure.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OnCentreClump {
    /// Measured (not target) mean slip angle [deg]: the thesis's targets were ~0.05° off.
    pub slip_angle_deg: f64,
    /// Mean FYW [N].
    pub fy_n: f64,
    /// Mean MZW [N·m].
    pub mz_nm: f64,
}

/// Cornering stiffness, RSAT and RCF of one load case.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OnCentreResult {
    /// |dFY/dSA| [N/deg] (the rig's FY falls with SA; the stiffness is reported positive).
    pub cornering_stiffness_n_per_deg: f64,
    /// MZ at the slip angle where FY = 0 [N·m].
    pub rsat_nm: f64,
    /// FY at the slip angle where MZ = 0 [N].
    pub rcf_n: f64,
    /// SA where FY = 0 [deg].
    pub fy_zero_slip_angle_deg: f64,
    /// SA where MZ = 0 [deg].
    pub mz_zero_slip_angle_deg: f64,
}

/// Fits one straight line through the clumps for FY and one for MZ (thesis §3.11) and reads
/// cornering stiffness (slope), RSAT (MZ at FY = 0) and RCF (FY at MZ = 0).
pub fn on_centre(clumps: &[OnCentreClump]) -> Option<OnCentreResult> {
    let sa: Vec<f64> = clumps.iter().map(|c| c.slip_angle_deg).collect();
    let fy: Vec<f64> = clumps.iter().map(|c| c.fy_n).collect();
    let mz: Vec<f64> = clumps.iter().map(|c| c.mz_nm).collect();
    let lf = fit_line(&sa, &fy)?;
    let lm = fit_line(&sa, &mz)?;
    let a_fy0 = lf.root();
    let a_mz0 = lm.root();
    Some(OnCentreResult {
        cornering_stiffness_n_per_deg: lf.slope.abs(),
        rsat_nm: lm.at(a_fy0),
        rcf_n: lf.at(a_mz0),
        fy_zero_slip_angle_deg: a_fy0,
        mz_zero_slip_angle_deg: a_mz0,
    })
}

/// Vertical stiffness and unloaded radius of one pressure from rolling-radius steps.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RadiusFit {
    /// −dFz/dR [N/m].
    pub vertical_stiffness_npm: f64,
    /// R at Fz = 0 (linear extrapolation) [m].
    pub unloaded_radius_m: f64,
    /// Load steps used.
    pub n: usize,
}

/// Fits DSTWOWHC = R0 − Fz/Cz through (load, loaded radius) points (thesis §3.10).
pub fn rolling_radius(fz_n: &[f64], radius_m: &[f64]) -> Option<RadiusFit> {
    let l = fit_line(fz_n, radius_m)?;
    if l.slope.is_nan() || l.slope >= 0.0 {
        return None;
    }
    Some(RadiusFit { vertical_stiffness_npm: -1.0 / l.slope, unloaded_radius_m: l.intercept, n: l.n })
}

/// Lateral relaxation length from one step-steer test.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RelaxationResult {
    /// d63 − d0 [m].
    pub length_m: f64,
    /// Distance where FY first reaches 63.2 % of the saturated FY [m].
    pub d63_m: f64,
    /// Distance where FY last crosses zero before that [m] (0 if it starts with the right sign).
    pub d0_m: f64,
    /// Saturated FY: mean over the final `saturated_frac` of the distance [N].
    pub saturated_fy_n: f64,
}

/// Samples each side of the centred moving average of the step-steer force.
const SMOOTH_HALF_WIDTH: usize = 3;

/// Relaxation length from FY vs LONGDISP of a step-steer (thesis §3.12.1): the distance to
/// 63.2 % of the saturated FY minus the distance where FY crosses zero. `disp_m` must rise.
pub fn relaxation_length(disp_m: &[f64], fy_n: &[f64], saturated_frac: f64) -> Option<RelaxationResult> {
    let pts: Vec<(f64, f64)> =
        disp_m.iter().zip(fy_n).filter(|(x, y)| x.is_finite() && y.is_finite()).map(|(x, y)| (*x, *y)).collect();
    if pts.len() < 5 {
        return None;
    }
    let x0 = pts[0].0;
    let x_end = pts[pts.len() - 1].0;
    if x_end.is_nan() || x_end <= x0 {
        return None;
    }
    let x_sat = x_end - saturated_frac * (x_end - x0);
    let tail: Vec<f64> = pts.iter().filter(|p| p.0 >= x_sat).map(|p| p.1).collect();
    if tail.is_empty() {
        return None;
    }
    let sat = tail.iter().sum::<f64>() / tail.len() as f64;
    if sat == 0.0 || !sat.is_finite() {
        return None;
    }
    // Work in the saturated force's sign so one code path serves ± slip angles. A centred
    // moving average over SMOOTH_HALF_WIDTH samples each side keeps force noise from making
    // early threshold crossings (it leaves a straight flank unchanged).
    let s = sat.signum();
    let target = 0.632 * sat.abs();
    let n = pts.len();
    let smooth: Vec<(f64, f64)> = (0..n)
        .map(|i| {
            // Symmetric, narrowing at the ends, so the average stays centred on x.
            let w = SMOOTH_HALF_WIDTH.min(i).min(n - 1 - i);
            let (a, b) = (i - w, i + w);
            let m = pts[a..=b].iter().map(|p| p.1).sum::<f64>() / (b - a + 1) as f64;
            (pts[i].0, s * m)
        })
        .collect();
    if smooth[0].1 >= target {
        return None;
    }
    let mut d63 = None;
    // FY starting on the wrong side crosses zero first; starting on the right side, d0 is the
    // start.
    let mut d0 = if smooth[0].1 > 0.0 { Some(x0) } else { None };
    for w in smooth.windows(2) {
        let ((xa, ya), (xb, yb)) = (w[0], w[1]);
        if d0.is_none() && ya <= 0.0 && yb > 0.0 {
            d0 = Some(xa + (xb - xa) * (-ya) / (yb - ya));
        }
        if ya < target && yb >= target {
            d63 = Some(xa + (xb - xa) * (target - ya) / (yb - ya));
            break;
        }
    }
    let d0 = d0.unwrap_or(x0);
    let d63 = d63?;
    Some(RelaxationResult { length_m: d63 - d0, d63_m: d63 - x0, d0_m: d0 - x0, saturated_fy_n: sat })
}

/// A static drag's linear part must span at least this displacement [m].
const MIN_DRAG_DISPLACEMENT_M: f64 = 0.002;
/// …move one way: net displacement at least this fraction of the path…
const MIN_DRAG_MONOTONY: f64 = 0.8;
/// …and be a line: coefficient of determination at least this.
const MIN_DRAG_R2: f64 = 0.9;

/// Longitudinal stiffness from one static drag (thesis §3.12.2): the slope of FX vs belt
/// displacement, fitted where |FX| is below `linear_frac` of the drag's peak |FX| (beyond, the
/// patch slides). Returned positive [N/m].
pub fn longitudinal_stiffness(disp_m: &[f64], fx_n: &[f64], linear_frac: f64) -> Option<f64> {
    let peak = fx_n.iter().filter(|v| v.is_finite()).fold(0.0_f64, |m, v| m.max(v.abs()));
    if peak <= 0.0 {
        return None;
    }
    let (xs, ys): (Vec<f64>, Vec<f64>) = disp_m
        .iter()
        .zip(fx_n)
        .filter(|(x, f)| x.is_finite() && f.abs() <= linear_frac * peak)
        .map(|(x, f)| (*x, *f))
        .unzip();
    // A drag the displacement channel did not see (e.g. a belt speed that reads zero with the
    // wheel locked) gives a cloud, not a line: refuse it rather than report noise.
    let span = xs.iter().copied().fold(f64::NEG_INFINITY, f64::max) - xs.iter().copied().fold(f64::INFINITY, f64::min);
    if span.is_nan() || span < MIN_DRAG_DISPLACEMENT_M {
        return None;
    }
    // The belt moves one way: a displacement that wanders (integrated noise) is not a drag.
    let path: f64 = xs.windows(2).map(|w| (w[1] - w[0]).abs()).sum();
    let net = (xs[xs.len() - 1] - xs[0]).abs();
    if path <= 0.0 || net < MIN_DRAG_MONOTONY * path {
        return None;
    }
    let l = fit_line(&xs, &ys)?;
    let my = ys.iter().sum::<f64>() / ys.len() as f64;
    let ss_tot: f64 = ys.iter().map(|y| (y - my).powi(2)).sum();
    let ss_res: f64 = xs.iter().zip(&ys).map(|(x, y)| (y - l.at(*x)).powi(2)).sum();
    if ss_tot <= 0.0 || 1.0 - ss_res / ss_tot < MIN_DRAG_R2 {
        return None;
    }
    let k = l.slope.abs();
    (k.is_finite() && k > 0.0).then_some(k)
}

/// Mechanical hysteresis from the forces at zero-slip crossings (thesis §3.6.1): max − min;
/// NaN with fewer than two crossings.
pub fn mechanical_hysteresis(crossing_forces_n: &[f64]) -> f64 {
    let f: Vec<f64> = crossing_forces_n.iter().copied().filter(|v| v.is_finite()).collect();
    if f.len() < 2 {
        return f64::NAN;
    }
    let max = f.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let min = f.iter().copied().fold(f64::INFINITY, f64::min);
    max - min
}

/// Within this fraction of the arming threshold the slip counts as at zero.
const TOUCH_FRACTION: f64 = 0.05;
/// Half-width of the window around zero slip whose samples give the force at zero, as a
/// fraction of the arming threshold (chosen: 0.5° of slip angle, 0.5 % of slip ratio with the
/// default arms: inside the linear range, wide enough for ~10 samples at 100 Hz and 10 %/s).
const WINDOW_FRACTION: f64 = 0.5;

/// Finds zero-slip crossings in a stream of (slip, force) and records the force at each.
///
/// The force at zero slip is read the way an engineer reads it off the plot: a straight line
/// fitted (least squares) to the pass's samples within a small window around zero slip, plus
/// the sample on each side of it, evaluated at slip = 0. One sample's noise (a single noisy
/// force or slip reading interpolated across zero) would otherwise set the figure; the fit
/// averages over the pass. A crossing counts only after the slip has been beyond `arm` since the
/// previous one, so noise around zero does not make crossings; returning to zero (within a
/// twentieth of `arm`: a sweep that ends at zero may stop a hair short) counts as a crossing too.
#[derive(Debug, Clone)]
pub struct ZeroCrossings {
    arm: f64,
    window: f64,
    armed: bool,
    prev: Option<(f64, f64)>,
    /// The near-zero pass in progress: the sample before it and those inside the window.
    pass: Vec<(f64, f64)>,
    pass_armed: bool,
    pass_at_zero: bool,
    /// Forces at the completed crossings so far [N].
    pub forces_n: Vec<f64>,
}

impl ZeroCrossings {
    /// A tracker arming at |slip| > `arm`.
    pub fn new(arm: f64) -> Self {
        Self {
            arm,
            window: WINDOW_FRACTION * arm,
            armed: false,
            prev: None,
            pass: Vec::new(),
            pass_armed: false,
            pass_at_zero: false,
            forces_n: Vec::new(),
        }
    }

    /// Feeds one (slip, force) pair; NaN pairs are skipped.
    pub fn push(&mut self, slip: f64, force: f64) {
        if !(slip.is_finite() && force.is_finite()) {
            return;
        }
        if slip.abs() > self.arm {
            self.armed = true;
        }
        let crossed = self.prev.is_some_and(|(ps, _)| (ps > 0.0 && slip <= 0.0) || (ps < 0.0 && slip >= 0.0));
        if slip.abs() <= self.window {
            if self.pass.is_empty() {
                self.pass_armed = self.armed;
                self.pass_at_zero = false;
                self.pass.extend(self.prev);
            }
            self.pass.push((slip, force));
            self.pass_at_zero |= crossed || slip.abs() <= TOUCH_FRACTION * self.arm;
        } else if !self.pass.is_empty() {
            self.pass.push((slip, force));
            if self.pass_counts() {
                self.forces_n.push(force_at_zero(&self.pass));
                self.armed = false;
            }
            self.pass.clear();
        } else if crossed && self.armed {
            // Across the whole window between two samples (a very fast sweep): interpolate.
            self.forces_n.push(force_at_zero(&[self.prev.unwrap_or((slip, force)), (slip, force)]));
            self.armed = false;
        }
        self.prev = Some((slip, force));
    }

    fn pass_counts(&self) -> bool {
        self.pass_armed && self.pass_at_zero
    }

    /// Forces at every crossing so far, the pass still near zero included (a sweep that ends
    /// at zero slip ends inside the window) [N].
    pub fn crossing_forces_n(&self) -> Vec<f64> {
        let mut f = self.forces_n.clone();
        if !self.pass.is_empty() && self.pass_counts() {
            f.push(force_at_zero(&self.pass));
        }
        f
    }

    /// max − min of the crossing forces (NaN with fewer than two).
    pub fn hysteresis_n(&self) -> f64 {
        mechanical_hysteresis(&self.crossing_forces_n())
    }
}

/// The least-squares line through (slip, force) evaluated at slip = 0; the mean force when the
/// slips do not spread.
fn force_at_zero(pts: &[(f64, f64)]) -> f64 {
    let n = pts.len() as f64;
    let mx = pts.iter().map(|p| p.0).sum::<f64>() / n;
    let my = pts.iter().map(|p| p.1).sum::<f64>() / n;
    let sxx: f64 = pts.iter().map(|p| (p.0 - mx).powi(2)).sum();
    let sxy: f64 = pts.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
    if sxx <= 1e-12 * (1.0 + mx * mx) {
        return my;
    }
    my - sxy / sxx * mx
}

/// Calspan slip ratio (thesis §3.6.2): SR = (VX1/W1)·(W/VX) − 1, with VX1 and W1 taken free
/// rolling at the sweep's load case just before it. NaN when a divisor is not usable.
pub fn slip_ratio_calspan(vx1_mps: f64, w1_radps: f64, w_radps: f64, vx_mps: f64) -> f64 {
    if w1_radps.abs() < 1e-9 || vx_mps.abs() < 1e-9 {
        return f64::NAN;
    }
    (vx1_mps / w1_radps) * (w_radps / vx_mps) - 1.0
}

/// Effective-radius slip ratio: SR = (W·Re − VX)/VX. NaN when VX is ~0.
pub fn slip_ratio_effective_radius(w_radps: f64, re_m: f64, vx_mps: f64) -> f64 {
    if vx_mps.abs() < 1e-9 {
        return f64::NAN;
    }
    (w_radps * re_m - vx_mps) / vx_mps
}

/// Sliding powers (PX, PY, P) [W] (thesis §Nomenclature): PY = FY·VX·sin(SA),
/// PX = FX·SR·VX·cos(SA), P = √(PX² + PY²).
pub fn sliding_power_w(fx_n: f64, fy_n: f64, slip_ratio: f64, slip_angle_deg: f64, vx_mps: f64) -> (f64, f64, f64) {
    let sa = slip_angle_deg.to_radians();
    let py = fy_n * vx_mps * sa.sin();
    let px = fx_n * slip_ratio * vx_mps * sa.cos();
    (px, py, px.hypot(py))
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    /// Thesis §3.11, middle load 8,750 N: +2,600 N at −1°, −2,900 N at +1° → 2,750 N/°; FY = 0 at
    /// −0.09° where MZ = −8 N·m (RSAT); MZ = 0 at −0.01° where FY = −222 N (RCF).
    #[test]
    fn on_centre_worked_example() {
        // The cornering stiffness from the thesis's two clumps as they are.
        let two = [(-1.0, 2600.0), (1.0, -2900.0)].map(|(a, fy)| OnCentreClump {
            slip_angle_deg: a,
            fy_n: fy,
            mz_nm: 100.0 * (a + 0.01),
        });
        assert_relative_eq!(on_centre(&two).unwrap().cornering_stiffness_n_per_deg, 2750.0, epsilon = 1e-9);
        // The thesis reads its figures to ~100 N and ~0.01°: the line with slope −2,750 N/° whose
        // zero is at −0.0907° (read: −0.09°) gives −222 N at −0.01°; MZ is zero at −0.01° and
        // −8 N·m at −0.09° (slope 100 N·m/°).
        let fy = |a: f64| -2750.0 * (a + 0.0907);
        let mz = |a: f64| 100.0 * (a + 0.01);
        let clumps: Vec<OnCentreClump> =
            [-1.0, 0.0, 1.0].iter().map(|&a| OnCentreClump { slip_angle_deg: a, fy_n: fy(a), mz_nm: mz(a) }).collect();
        let r = on_centre(&clumps).unwrap();
        assert_relative_eq!(r.cornering_stiffness_n_per_deg, 2750.0, epsilon = 1e-9);
        assert_eq!((r.fy_zero_slip_angle_deg * 100.0).round() / 100.0, -0.09);
        assert_eq!(r.rsat_nm.round(), -8.0);
        assert_relative_eq!(r.mz_zero_slip_angle_deg, -0.01, epsilon = 1e-12);
        assert_eq!(r.rcf_n.round(), -222.0);
    }

    /// Thesis §3.12.1: saturated FY 3,201 N at 5,100 N; 63.2 % (2,023 N) reached at 0.475 m, FY
    /// crossing zero at 0.05 m → 0.425 m.
    #[test]
    fn relaxation_worked_example() {
        let knots = [(0.0, -150.0), (0.05, 0.0), (0.475, 2023.0), (0.9, 3100.0), (1.1, 3201.0), (1.5, 3201.0)];
        let interp = |x: f64| {
            for w in knots.windows(2) {
                if x <= w[1].0 {
                    return w[0].1 + (w[1].1 - w[0].1) * (x - w[0].0) / (w[1].0 - w[0].0);
                }
            }
            knots[knots.len() - 1].1
        };
        let xs: Vec<f64> = (0..=1500).map(|i| i as f64 * 1e-3).collect();
        let fy: Vec<f64> = xs.iter().map(|&x| interp(x)).collect();
        let r = relaxation_length(&xs, &fy, 0.2).unwrap();
        assert_relative_eq!(r.saturated_fy_n, 3201.0, epsilon = 1e-9);
        assert_relative_eq!(r.d63_m, 0.475, epsilon = 1e-3);
        assert_relative_eq!(r.d0_m, 0.05, epsilon = 1e-3);
        assert_relative_eq!(r.length_m, 0.425, epsilon = 1e-3);
        // Negative slip angle: mirrored force, same length.
        let neg: Vec<f64> = fy.iter().map(|v| -v).collect();
        assert_relative_eq!(relaxation_length(&xs, &neg, 0.2).unwrap().length_m, 0.425, epsilon = 1e-3);
        // An exponential from zero: the length is its distance constant.
        let e: Vec<f64> = xs.iter().map(|&x| 3000.0 * (1.0 - (-x / 0.3_f64).exp())).collect();
        assert_relative_eq!(relaxation_length(&xs, &e, 0.05).unwrap().length_m, 0.3, epsilon = 5e-3);
    }

    /// Thesis §3.6.1: a 30 °/s sweep 0 → +2 → −28 → +28 → 0 crossed zero at +1,730 N and at
    /// −2,220 N → 3,950 N.
    #[test]
    fn hysteresis_worked_example() {
        let mut z = ZeroCrossings::new(1.0);
        // Lag model: FY = −k·(SA − lag·direction), crossings give ±forces.
        let path = [0.0, 2.0, -28.0, 28.0, 0.0];
        let mut last_dir = 0.0;
        for w in path.windows(2) {
            let n = 200;
            for i in 0..=n {
                let sa = w[0] + (w[1] - w[0]) * f64::from(i) / f64::from(n);
                let dir = (w[1] - w[0]).signum();
                last_dir = dir;
                let off = if dir > 0.0 { 1730.0 } else { -2220.0 };
                let fy = -100.0 * sa + if sa.abs() < 3.0 { off } else { 0.0 };
                z.push(sa, fy);
            }
        }
        assert!(last_dir < 0.0);
        assert_relative_eq!(z.hysteresis_n(), 3950.0, epsilon = 1e-6);
        assert_relative_eq!(mechanical_hysteresis(&[1730.0, -2220.0]), 3950.0);
        assert!(mechanical_hysteresis(&[1.0]).is_nan());
    }

    /// Force noise on one sample moves a two-point interpolation by its full size; the pass's
    /// line fit moves far less.
    #[test]
    fn one_noisy_sample_barely_moves_the_fitted_crossing() {
        let run = |spike: f64| {
            let mut z = ZeroCrossings::new(1.0);
            // 5 → −5 → 5 at 0.02° per sample (2 °/s at 100 Hz): FY = −2750·SA ± 150 lag.
            let mut sa: f64 = 0.0;
            let mut dir = 1.0;
            for i in 0..1500 {
                sa += dir * 0.02;
                if sa.abs() >= 5.0 {
                    dir = -dir;
                }
                let mut fy = -2750.0 * sa + 150.0 * dir;
                if i == 1000 {
                    fy += spike; // the sample nearest a crossing
                }
                z.push(sa, fy);
            }
            z.hysteresis_n()
        };
        assert_relative_eq!(run(0.0), 300.0, epsilon = 1e-6);
        let moved = (run(500.0) - 300.0).abs();
        assert!(moved < 50.0, "a 500 N spike moved the hysteresis by {moved} N");
    }

    #[test]
    fn noise_around_zero_makes_no_crossings() {
        let mut z = ZeroCrossings::new(1.0);
        for i in 0..1000 {
            z.push(if i % 2 == 0 { 0.01 } else { -0.01 }, 5.0);
        }
        assert!(z.forces_n.is_empty());
        z.push(f64::NAN, 1.0);
        assert!(z.hysteresis_n().is_nan());
    }

    #[test]
    fn rolling_radius_extrapolates_to_zero_load() {
        // R = 0.3938 − Fz / 250 kN/m at three pressures with slightly different R0.
        let fz = [2700.0, 4400.0, 6100.0, 8100.0, 10100.0, 11800.0, 13500.0];
        let mut r0s = Vec::new();
        for (r0, cz) in [(0.3930, 230e3), (0.3938, 250e3), (0.3946, 280e3)] {
            let r: Vec<f64> = fz.iter().map(|f| r0 - f / cz).collect();
            let fit = rolling_radius(&fz, &r).unwrap();
            assert_relative_eq!(fit.vertical_stiffness_npm, cz, max_relative = 1e-9);
            r0s.push(fit.unloaded_radius_m);
        }
        assert_relative_eq!(r0s.iter().sum::<f64>() / 3.0, 0.3938, epsilon = 1e-9);
        assert!(rolling_radius(&[1.0], &[0.3]).is_none());
        assert!(rolling_radius(&[1.0, 2.0], &[0.3, 0.31]).is_none(), "radius rising with load is refused");
    }

    #[test]
    fn static_drag_fits_the_linear_part() {
        let xs: Vec<f64> = (0..=100).map(|i| f64::from(i) * 1e-3).collect();
        let fx: Vec<f64> = xs.iter().map(|x| -(4.0e5 * x).min(6000.0)).collect();
        assert_relative_eq!(longitudinal_stiffness(&xs, &fx, 0.5).unwrap(), 4.0e5, max_relative = 1e-9);
        assert!(longitudinal_stiffness(&xs, &vec![0.0; xs.len()], 0.5).is_none());
        // Displacement not seen (noise around zero): refused.
        let noise: Vec<f64> = (0..=100).map(|i| 1e-4 * f64::from(i % 7) - 3e-4).collect();
        assert!(longitudinal_stiffness(&noise, &fx, 0.5).is_none());
    }

    #[test]
    fn slip_ratios_and_power() {
        // Free rolling at the reference gives zero; 10 % more wheel speed gives +0.1.
        assert_relative_eq!(slip_ratio_calspan(16.6, 45.0, 45.0, 16.6), 0.0);
        assert_relative_eq!(slip_ratio_calspan(16.6, 45.0, 49.5, 16.6), 0.1, epsilon = 1e-12);
        assert!(slip_ratio_calspan(16.6, 0.0, 45.0, 16.6).is_nan());
        assert_relative_eq!(slip_ratio_effective_radius(50.0, 0.36, 16.6), (18.0 - 16.6) / 16.6);
        let (px, py, p) = sliding_power_w(1000.0, -3000.0, 0.1, 5.0, 16.6);
        assert_relative_eq!(px, 1000.0 * 0.1 * 16.6 * 5f64.to_radians().cos());
        assert_relative_eq!(py, -3000.0 * 16.6 * 5f64.to_radians().sin());
        assert_relative_eq!(p, px.hypot(py));
    }
}

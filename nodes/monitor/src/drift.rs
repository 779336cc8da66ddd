//! Graph-sweep drift (thesis §3.9): graph sweep 2 against graph sweep 1, sweep by sweep — the
//! curve's shape (RMS difference of force vs slip), peak force and its slip position, cornering
//! or slip stiffness, and the temperature profile.

use std::collections::BTreeMap;

/// Force and temperature of one graph sweep, as it ran.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct SweepCurve {
    /// (slip angle [deg], slip ratio [-], FYW [N], FX [N], TRDTEMPC [°C], RUNTIME [s]).
    pts: Vec<[f64; 6]>,
}

/// The figures of one graph sweep.
#[derive(Debug, Clone, PartialEq)]
pub struct CurveFigures {
    /// FX vs slip ratio (true) or FYW vs slip angle (false).
    pub longitudinal: bool,
    /// Peak |force| on the positive-slip side and its slip (deg or %: the centroid of the slips
    /// within 2 % of the peak).
    pub peak_pos: (f64, f64),
    /// Peak |force| on the negative-slip side and its slip.
    pub peak_neg: (f64, f64),
    /// |dF/dslip| near zero slip [N/deg or N/%].
    pub stiffness: f64,
    /// Mean force per (direction, slip bin).
    pub bins: BTreeMap<(i8, i64), f64>,
    /// Mean TRDTEMPC per 0.5 s since the sweep's start.
    pub temp: BTreeMap<i64, f64>,
    /// Peak TRDTEMPC [°C].
    pub peak_temp_c: f64,
}

/// Graph sweep 2 against 1.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Drift {
    /// RMS of the force difference over common bins, % of sweep 1's peak |force|.
    pub rms_pct: f64,
    /// Peak |force| change, % (the side that changed most, signed).
    pub peak_pct: f64,
    /// Peak position shift (deg or % slip), the side that moved most, absolute.
    pub peak_shift: f64,
    /// Stiffness change, % (signed).
    pub stiffness_pct: f64,
    /// Largest |ΔTRDTEMPC| at the same time into the sweep, % of sweep 1's peak temperature.
    pub temp_pct: f64,
    /// Lateral or longitudinal.
    pub longitudinal: bool,
}

impl SweepCurve {
    /// Adds one sample (NaN values are skipped).
    pub fn push(&mut self, slip_angle_deg: f64, slip_ratio: f64, fy_n: f64, fx_n: f64, temp_c: f64, t_s: f64) {
        if t_s.is_finite() {
            self.pts.push([slip_angle_deg, slip_ratio, fy_n, fx_n, temp_c, t_s]);
        }
    }

    /// Number of samples.
    pub fn len(&self) -> usize {
        self.pts.len()
    }

    /// Whether there are no samples.
    pub fn is_empty(&self) -> bool {
        self.pts.is_empty()
    }

    /// The figures, with slip bins of `bin_deg` (lateral) or `bin_sr` (longitudinal).
    pub fn figures(&self, bin_deg: f64, bin_sr: f64) -> Option<CurveFigures> {
        let sr: Vec<f64> = self.pts.iter().map(|p| p[1]).filter(|v| v.is_finite()).collect();
        let sr_range =
            sr.iter().copied().fold(f64::NEG_INFINITY, f64::max) - sr.iter().copied().fold(f64::INFINITY, f64::min);
        let longitudinal = sr_range.is_finite() && sr_range > 0.02;
        // Slip in deg (lateral) or % (longitudinal), force FYW or FX.
        let series: Vec<(f64, f64, f64, f64)> = self
            .pts
            .iter()
            .map(|p| if longitudinal { (p[1] * 100.0, p[3], p[4], p[5]) } else { (p[0], p[2], p[4], p[5]) })
            .filter(|(s, f, _, _)| s.is_finite() && f.is_finite())
            .collect();
        if series.len() < 10 {
            return None;
        }
        let bin = if longitudinal { bin_sr * 100.0 } else { bin_deg };
        let mut sums: BTreeMap<(i8, i64), (f64, f64)> = BTreeMap::new();
        let (mut peak_pos, mut peak_neg) = ((0.0_f64, f64::NAN), (0.0_f64, f64::NAN));
        let (mut xs, mut ys) = (Vec::new(), Vec::new());
        let lin = if longitudinal { 2.0 } else { 1.0 };
        for (i, &(s, f, _, _)) in series.iter().enumerate() {
            let prev = if i > 0 { series[i - 1].0 } else { s };
            let dir: i8 = if s >= prev { 1 } else { -1 };
            let e = sums.entry((dir, (s / bin).round() as i64)).or_insert((0.0, 0.0));
            e.0 += f;
            e.1 += 1.0;
            if s > 0.0 && f.abs() > peak_pos.0 {
                peak_pos = (f.abs(), s);
            }
            if s < 0.0 && f.abs() > peak_neg.0 {
                peak_neg = (f.abs(), s);
            }
            if s.abs() < lin {
                xs.push(s);
                ys.push(f);
            }
        }
        // A tyre's peak is flat: its position is the centroid of the slips within 2 % of the
        // peak force, not the noisy arg-max.
        let centroid = |pos_side: bool, peak: f64| {
            let sel: Vec<f64> = series
                .iter()
                .filter(|(s, f, _, _)| (*s > 0.0) == pos_side && *s != 0.0 && f.abs() >= 0.98 * peak)
                .map(|(s, _, _, _)| *s)
                .collect();
            if sel.is_empty() { f64::NAN } else { sel.iter().sum::<f64>() / sel.len() as f64 }
        };
        peak_pos.1 = centroid(true, peak_pos.0);
        peak_neg.1 = centroid(false, peak_neg.0);
        let stiffness = channels::derived::fit_line(&xs, &ys).map_or(f64::NAN, |l| l.slope.abs());
        let t0 = series[0].3;
        let mut tsum: BTreeMap<i64, (f64, f64)> = BTreeMap::new();
        let mut peak_temp_c = f64::NAN;
        for &(_, _, temp, t) in &series {
            if temp.is_finite() {
                let e = tsum.entry(((t - t0) / 0.5).floor() as i64).or_insert((0.0, 0.0));
                e.0 += temp;
                e.1 += 1.0;
                if peak_temp_c.is_nan() || temp > peak_temp_c {
                    peak_temp_c = temp;
                }
            }
        }
        Some(CurveFigures {
            longitudinal,
            peak_pos,
            peak_neg,
            stiffness,
            bins: sums.into_iter().map(|(k, (s, n))| (k, s / n)).collect(),
            temp: tsum.into_iter().map(|(k, (s, n))| (k, s / n)).collect(),
            peak_temp_c,
        })
    }
}

/// Compares graph sweep 2 (`b`) with graph sweep 1 (`a`).
pub fn compare(a: &CurveFigures, b: &CurveFigures) -> Drift {
    let peak = a.peak_pos.0.max(a.peak_neg.0);
    let diffs: Vec<f64> = a.bins.iter().filter_map(|(k, fa)| b.bins.get(k).map(|fb| fb - fa)).collect();
    let rms = if diffs.is_empty() {
        f64::NAN
    } else {
        (diffs.iter().map(|d| d * d).sum::<f64>() / diffs.len() as f64).sqrt()
    };
    let side = |pa: (f64, f64), pb: (f64, f64)| {
        if pa.0 > 0.0 && pb.0 > 0.0 {
            ((pb.0 - pa.0) / pa.0 * 100.0, (pb.1 - pa.1).abs())
        } else {
            (f64::NAN, f64::NAN)
        }
    };
    let (pp, sp) = side(a.peak_pos, b.peak_pos);
    let (pn, sn) = side(a.peak_neg, b.peak_neg);
    let peak_pct = if pp.abs() >= pn.abs() || pn.is_nan() { pp } else { pn };
    let peak_shift = sp.max(sn);
    let temp_diffs: Vec<f64> = a.temp.iter().filter_map(|(k, ta)| b.temp.get(k).map(|tb| (tb - ta).abs())).collect();
    let temp_pct = if temp_diffs.is_empty() || a.peak_temp_c.is_nan() || a.peak_temp_c <= 0.0 {
        f64::NAN
    } else {
        temp_diffs.iter().copied().fold(0.0, f64::max) / a.peak_temp_c * 100.0
    };
    Drift {
        rms_pct: if peak > 0.0 { rms / peak * 100.0 } else { f64::NAN },
        peak_pct,
        peak_shift,
        stiffness_pct: if a.stiffness > 0.0 { (b.stiffness - a.stiffness) / a.stiffness * 100.0 } else { f64::NAN },
        temp_pct,
        longitudinal: a.longitudinal,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    fn sweep(mu: f64, stiff: f64, temp_gain: f64) -> SweepCurve {
        let mut c = SweepCurve::default();
        // 0 → +10 → −10 → 0 deg over 4 s at 100 Hz; FY = −mu·Fz·tanh(stiff·SA/(mu·Fz)).
        let fz = 6000.0;
        for i in 0..=400 {
            let t = f64::from(i) * 0.01;
            let sa = if t < 1.0 {
                10.0 * t
            } else if t < 3.0 {
                10.0 - 10.0 * (t - 1.0)
            } else {
                -10.0 + 10.0 * (t - 3.0)
            };
            let fy = -mu * fz * (stiff * sa / (mu * fz)).tanh();
            c.push(sa, 0.0, fy, 0.0, 45.0 + temp_gain * sa.abs(), t);
        }
        c
    }

    #[test]
    fn identical_sweeps_do_not_drift_and_changes_show() {
        let a = sweep(1.0, 2000.0, 2.0).figures(0.5, 0.005).unwrap();
        let d = compare(&a, &a);
        assert_eq!(d.rms_pct, 0.0);
        assert_eq!(d.peak_pct, 0.0);
        assert_eq!(d.temp_pct, 0.0);
        assert!(!d.longitudinal);
        // The thesis's −4.4 % peak (11,400 → 10,900 N).
        let b = sweep(10_900.0 / 11_400.0, 2000.0, 2.0).figures(0.5, 0.005).unwrap();
        let d = compare(&a, &b);
        assert_relative_eq!(d.peak_pct, -4.386, epsilon = 0.1);
        assert!(d.rms_pct > 0.5 && d.rms_pct < 5.0, "{}", d.rms_pct);
        let c = sweep(1.0, 2400.0, 2.0).figures(0.5, 0.005).unwrap();
        let d = compare(&a, &c);
        assert!(d.stiffness_pct > 15.0 && d.stiffness_pct < 21.0, "{}", d.stiffness_pct);
        let h = sweep(1.0, 2000.0, 2.5).figures(0.5, 0.005).unwrap();
        let d = compare(&a, &h);
        // 0.5 °C/deg more at up to 10°, averaged in 0.5 s bins, against a 65 °C peak.
        assert!(d.temp_pct > 5.0 && d.temp_pct < 7.7, "{}", d.temp_pct);
    }
}

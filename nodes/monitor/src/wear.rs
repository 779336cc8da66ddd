//! Tread wear from the loaded radius (DSTWOWHC), continuously.
//!
//! The thesis compared DSTWOWHC at matching points of graph sweeps 1 and 2 (§3.9, §5.1.2); its
//! rig resolves 0.1 mm, and 32 sweeps wore only 1.4 mm, too little per sweep to resolve. Here
//! every zero-slip thermal-pause hold is averaged (≥ 100 samples: far below the resolution, the
//! noise dithers the quantisation) and keyed by its load case (load, pressure, speed, camber).
//! Holds of the same case differ only by the tread worn between them; the thesis names sliding
//! energy as the wear indicator, so the model is
//!
//! `R_i = c_case(i) − k · E_i`
//!
//! with one radius per case `c` and one wear rate `k` [m/J] shared by all cases, fitted by
//! least squares within cases (the cases' offsets drop out).
//!
//! Holds of one case are not at exactly one load: the match tolerance admits neighbouring load
//! setpoints (GS2MF's BrkDrv holds at 1.6·Fz0 and at 9,000 N: 73 N apart on a 5,579 N tyre),
//! and a tyre's radius moves 2–4 mm per kN, more than it wears between two holds. So each hold's
//! radius is first moved to its case's mean load along the tyre's own radius–load slope, taken
//! from the nearest other load case at the same pressure, speed and camber (where there is
//! none, the radius is used as measured). The wear so far is `k · E_now`
//! (including the wear before the first hold, which the energy records), and its forecast is
//! `k · (E_now + E_still_to_come)`.

/// One averaged zero-slip hold.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Hold {
    /// Mean DSTWOWHC [m].
    pub radius_m: f64,
    /// Mean load [N].
    pub fz_n: f64,
    /// Mean pressure [Pa].
    pub pressure_pa: f64,
    /// Mean speed [m/s].
    pub speed_mps: f64,
    /// Mean camber [deg].
    pub camber_deg: f64,
    /// Specimen's accumulated sliding energy at the hold [J].
    pub energy_j: f64,
    /// RUNTIME at the hold's end [s].
    pub time_s: f64,
    /// Samples averaged.
    pub n: usize,
}

/// The wear-rate fit.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WearFit {
    /// Wear per sliding energy [m/J].
    pub rate_m_per_j: f64,
    /// Its standard error [m/J].
    pub rate_se_m_per_j: f64,
    /// Holds that share a case with another hold.
    pub n_matched: usize,
    /// Load cases with ≥ 2 holds.
    pub n_cases: usize,
}

/// Matching tolerances of load cases.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MatchTol {
    /// Load [N].
    pub load_n: f64,
    /// Pressure [Pa].
    pub pressure_pa: f64,
    /// Speed [m/s].
    pub speed_mps: f64,
    /// Camber [deg].
    pub camber_deg: f64,
}

/// Groups holds into load cases (each hold joins the first case whose first hold matches).
pub fn cases(holds: &[Hold], tol: &MatchTol) -> Vec<Vec<Hold>> {
    let mut out: Vec<Vec<Hold>> = Vec::new();
    for h in holds {
        let found = out.iter_mut().find(|c| {
            let r = &c[0];
            (r.fz_n - h.fz_n).abs() < tol.load_n
                && (r.pressure_pa - h.pressure_pa).abs() < tol.pressure_pa
                && (r.speed_mps - h.speed_mps).abs() < tol.speed_mps
                && (r.camber_deg - h.camber_deg).abs() < tol.camber_deg
        });
        match found {
            Some(c) => c.push(*h),
            None => out.push(vec![*h]),
        }
    }
    out
}

/// Mean load [N] and radius [m] of a group of holds.
fn mean_load_and_radius(holds: &[Hold]) -> (f64, f64) {
    let m = holds.len() as f64;
    (holds.iter().map(|h| h.fz_n).sum::<f64>() / m, holds.iter().map(|h| h.radius_m).sum::<f64>() / m)
}

/// The slope of loaded radius against load [m/N] at `case`: the secant to the case (of `all`)
/// with the nearest other mean load at the same pressure, speed and camber. `None` if there is
/// no such case or the secant does not fall with load (not a radius–load relation).
pub fn radius_load_slope(case: &[Hold], all: &[Vec<Hold>], tol: &MatchTol) -> Option<f64> {
    let r = case.first()?;
    let (fz, radius) = mean_load_and_radius(case);
    let same_conditions = |h: &Hold| {
        (r.pressure_pa - h.pressure_pa).abs() < tol.pressure_pa
            && (r.speed_mps - h.speed_mps).abs() < tol.speed_mps
            && (r.camber_deg - h.camber_deg).abs() < tol.camber_deg
    };
    let (other_fz, other_radius) = all
        .iter()
        .filter(|c| c.first().is_some_and(|h| same_conditions(h) && (h.fz_n - r.fz_n).abs() >= tol.load_n))
        .map(|c| mean_load_and_radius(c))
        .min_by(|a, b| (a.0 - fz).abs().total_cmp(&(b.0 - fz).abs()))?;
    let slope = (other_radius - radius) / (other_fz - fz);
    (slope.is_finite() && slope < 0.0).then_some(slope)
}

/// Holds grouped into load cases, each hold's radius moved to its case's mean load
/// ([`radius_load_slope`]). The slopes are taken on radii with the wear `rate_m_per_j · E`
/// added back: two cases' mean radii also differ by the wear between their mean energies.
pub fn load_corrected_cases(holds: &[Hold], tol: &MatchTol, rate_m_per_j: f64) -> Vec<Vec<Hold>> {
    let all = cases(holds, tol);
    let unworn: Vec<Vec<Hold>> = all
        .iter()
        .map(|c| c.iter().map(|h| Hold { radius_m: h.radius_m + rate_m_per_j * h.energy_j, ..*h }).collect())
        .collect();
    all.iter()
        .zip(&unworn)
        .map(|(case, unworn_case)| {
            let (fz, _) = mean_load_and_radius(case);
            let slope = if case.len() >= 2 { radius_load_slope(unworn_case, &unworn, tol).unwrap_or(0.0) } else { 0.0 };
            case.iter().map(|h| Hold { radius_m: h.radius_m - slope * (h.fz_n - fz), ..*h }).collect()
        })
        .collect()
}

/// Fits the shared wear rate. `None` until two holds of one case lie at different energies.
pub fn fit(holds: &[Hold], tol: &MatchTol) -> Option<WearFit> {
    // The load correction's slopes need the wear rate and the rate needs the correction: a few
    // rounds settle it (the slopes' wear term is small, so each round gains an order).
    let mut fit = fit_corrected(holds, tol, 0.0)?;
    for _ in 0..3 {
        fit = fit_corrected(holds, tol, fit.rate_m_per_j)?;
    }
    Some(fit)
}

/// One round of [`fit`], the load correction's slopes taken with the wear rate `rate_m_per_j`.
fn fit_corrected(holds: &[Hold], tol: &MatchTol, rate_m_per_j: f64) -> Option<WearFit> {
    let groups: Vec<Vec<Hold>> =
        load_corrected_cases(holds, tol, rate_m_per_j).into_iter().filter(|c| c.len() >= 2).collect();
    let (mut sxx, mut sxy) = (0.0, 0.0);
    let mut n = 0;
    for g in &groups {
        let m = g.len() as f64;
        let me = g.iter().map(|h| h.energy_j).sum::<f64>() / m;
        let mr = g.iter().map(|h| h.radius_m).sum::<f64>() / m;
        for h in g {
            sxx += (h.energy_j - me).powi(2);
            sxy += (h.energy_j - me) * (h.radius_m - mr);
        }
        n += g.len();
    }
    if sxx <= 0.0 || groups.is_empty() {
        return None;
    }
    let rate = -sxy / sxx;
    // Residual variance with one offset per case and the rate as parameters.
    let mut ss = 0.0;
    for g in &groups {
        let m = g.len() as f64;
        let c = g.iter().map(|h| h.radius_m + rate * h.energy_j).sum::<f64>() / m;
        ss += g.iter().map(|h| (h.radius_m - (c - rate * h.energy_j)).powi(2)).sum::<f64>();
    }
    let dof = n as f64 - groups.len() as f64 - 1.0;
    // With no degrees of freedom left, fall back to the rig's resolution (0.1 mm) as the scatter.
    let var = if dof >= 1.0 { ss / dof } else { 1e-8 };
    Some(WearFit { rate_m_per_j: rate, rate_se_m_per_j: (var / sxx).sqrt(), n_matched: n, n_cases: groups.len() })
}

/// Accumulates one hold's samples.
#[derive(Debug, Clone, Copy, Default)]
pub struct HoldAcc {
    n: f64,
    r: f64,
    fz: f64,
    p: f64,
    v: f64,
    c: f64,
    /// Energy at the hold's start [J].
    pub energy_j: f64,
    /// RUNTIME of the pause's start [s].
    pub t0_s: f64,
    /// RUNTIME of the last sample [s].
    pub t_last_s: f64,
    first_t_s: f64,
}

impl HoldAcc {
    /// A hold starting at `t0_s` with the specimen's energy `energy_j`.
    pub fn new(t0_s: f64, energy_j: f64) -> Self {
        Self { t0_s, energy_j, first_t_s: f64::NAN, t_last_s: t0_s, ..Self::default() }
    }

    /// Adds one sample's values.
    pub fn push(&mut self, t_s: f64, radius_m: f64, fz_n: f64, pressure_pa: f64, speed_mps: f64, camber_deg: f64) {
        if self.first_t_s.is_nan() {
            self.first_t_s = t_s;
        }
        self.t_last_s = t_s;
        self.n += 1.0;
        self.r += radius_m;
        self.fz += fz_n;
        self.p += pressure_pa;
        self.v += speed_mps;
        self.c += camber_deg;
    }

    /// The hold, if it lasted `min_s`.
    pub fn finish(&self, min_s: f64) -> Option<Hold> {
        if self.n < 2.0 || self.t_last_s - self.first_t_s < min_s {
            return None;
        }
        Some(Hold {
            radius_m: self.r / self.n,
            fz_n: self.fz / self.n,
            pressure_pa: self.p / self.n,
            speed_mps: self.v / self.n,
            camber_deg: self.c / self.n,
            energy_j: self.energy_j,
            time_s: self.t_last_s,
            n: self.n as usize,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    const TOL: MatchTol = MatchTol { load_n: 100.0, pressure_pa: 1e4, speed_mps: 1.0, camber_deg: 0.5 };

    fn hold(fz: f64, r0: f64, e: f64, k: f64) -> Hold {
        Hold {
            radius_m: r0 - k * e,
            fz_n: fz,
            pressure_pa: 2.6e5,
            speed_mps: 16.6,
            camber_deg: 0.0,
            energy_j: e,
            time_s: e / 1000.0,
            n: 100,
        }
    }

    #[test]
    fn shared_rate_across_load_cases() {
        // 0.18 mm/MJ; three load cases with different radii, interleaved.
        let k = 0.18e-3 / 1e6;
        let mut hs = Vec::new();
        for i in 0..10 {
            let e = 1e5 + 2e5 * f64::from(i);
            hs.push(hold([3000.0, 6000.0, 9000.0][i as usize % 3], [0.383, 0.373, 0.363][i as usize % 3], e, k));
        }
        let f = fit(&hs, &TOL).unwrap();
        assert_relative_eq!(f.rate_m_per_j, k, max_relative = 1e-9);
        assert_eq!(f.n_cases, 3);
        // A single hold per case says nothing.
        assert!(fit(&hs[..3], &TOL).is_none());
    }

    /// A loaded radius falling ever less steeply with load (≈ 3.8 mm/kN at 1 kN, 2.6 mm/kN at
    /// 9 kN: the brush road tyre's), minus the wear `k·e`.
    fn curved_hold(fz: f64, e: f64, k: f64) -> Hold {
        let r = 0.335 - 4.0e-6 * fz + 7.5e-11 * fz * fz;
        Hold { radius_m: r - k * e, fz_n: fz, ..hold(fz, 0.0, e, 0.0) }
    }

    #[test]
    fn neighbouring_load_setpoints_do_not_pass_for_wear() {
        // GS2MF's BrkDrv holds at 1.6·Fz0 = 8,927 N early and at 9,003 N late: one case within
        // 100 N, whose 76 N step alone lowers the radius by ~0.2 mm, as much as 1 MJ of wear.
        let k = 0.208e-3 / 1e6;
        let hs = [
            curved_hold(8372.0, 0.2e6, k),
            curved_hold(8927.0, 0.4e6, k),
            curved_hold(3348.0, 0.6e6, k),
            curved_hold(8371.0, 0.9e6, k),
            curved_hold(3347.0, 1.1e6, k),
            curved_hold(9003.0, 1.4e6, k),
        ];
        let f = fit(&hs, &TOL).unwrap();
        assert_eq!(f.n_cases, 3);
        // Within 2 %: the secant to the next load case is not the slope at the case (1 % here).
        assert_relative_eq!(f.rate_m_per_j, k, max_relative = 0.02);
        // Taken as measured, the load step reads as 60 % more wear.
        let cases = cases(&hs, &TOL);
        let step = cases.iter().find(|c| c[0].fz_n == 8927.0).expect("the 9 kN case");
        let as_measured = (step[0].radius_m - step[1].radius_m) / (step[1].energy_j - step[0].energy_j);
        assert!(as_measured > 1.5 * k, "the uncorrected rate {as_measured:e} should be far off");
    }

    #[test]
    fn no_slope_without_another_load_case_at_the_same_conditions() {
        let k = 0.208e-3 / 1e6;
        let hs = [curved_hold(8927.0, 0.4e6, k), curved_hold(9003.0, 1.4e6, k)];
        let all = cases(&hs, &TOL);
        assert_eq!(all.len(), 1);
        assert!(radius_load_slope(&all[0], &all, &TOL).is_none());
        // Another pressure is another tyre stiffness: not a neighbour either.
        let other_pressure = Hold { pressure_pa: 2.1e5, ..curved_hold(6000.0, 0.5e6, k) };
        let all = cases(&[hs[0], hs[1], other_pressure], &TOL);
        assert!(radius_load_slope(&all[0], &all, &TOL).is_none());
    }
}

//! What "physical" means for a fitted MF-Tyre 6.1 model, as margins that must stay ≥ 0 over the
//! tested range: friction D > 0, curvature E ≤ 1, stiffnesses keeping their sign, pneumatic
//! trail > 0 at small slip, and combined-slip weights G in [0, 1] with the pure force's sign.
//!
//! One source for two uses: the stages add the margins' shortfalls as penalty residuals to their
//! least-squares problems, so a fit is pulled back inside the physical region *during* the
//! optimisation (by construction rather than by a check afterwards); [`crate::checks`] reports
//! any margin still negative on the final model, naming the stage that owns it.
//!
//! The margins are dimensionless (friction coefficient, curvature, weight), so one penalty
//! weight serves them all.

use mftyre::{MfInput, TyreParams, UseMode};

use crate::data::ValidRange;

/// The operating grid the margins are checked on: the tested range of load, camber and pressure
/// (slips are chosen per margin).
#[derive(Debug, Clone, PartialEq)]
pub struct Grid {
    /// Loads, N.
    pub fz_n: Vec<f64>,
    /// Cambers, rad.
    pub gamma_rad: Vec<f64>,
    /// Pressures, Pa.
    pub p_pa: Vec<f64>,
    /// Largest |slip angle| tested, rad (the combined checks go 1.3× beyond).
    pub alpha_max_rad: f64,
    /// Largest |slip ratio| tested.
    pub kappa_max: f64,
    /// Speed, m/s.
    pub vx_mps: f64,
}

fn spread(min: f64, max: f64, n: usize) -> Vec<f64> {
    if !(min.is_finite() && max.is_finite()) || max <= min || n < 2 {
        return vec![if min.is_finite() { min } else { 0.0 }];
    }
    (0..n).map(|i| min + (max - min) * i as f64 / (n - 1) as f64).collect()
}

impl Grid {
    /// The grid over a tested range (5 loads, 3 cambers, 3 pressures at most), falling back to
    /// the model's nominal conditions where the range is empty.
    pub fn of_range(params: &TyreParams, range: &ValidRange) -> Self {
        let fz0 = params.fnomin_n();
        let p0 = params.nominal_pressure_pa();
        let (fz_lo, fz_hi) = if range.fz_n.is_empty() {
            (0.4 * fz0, 2.0 * fz0)
        } else {
            (range.fz_n.min.max(0.05 * fz0), range.fz_n.max)
        };
        let gamma =
            if range.gamma_rad.is_empty() { vec![0.0] } else { spread(range.gamma_rad.min, range.gamma_rad.max, 3) };
        let p = if range.p_pa.is_empty() { vec![p0] } else { spread(range.p_pa.min, range.p_pa.max, 3) };
        let a = if range.alpha_rad.is_empty() { 0.2 } else { range.alpha_rad.max.max(-range.alpha_rad.min) };
        let k = if range.kappa.is_empty() { 0.2 } else { range.kappa.max.max(-range.kappa.min) };
        Grid {
            fz_n: spread(fz_lo, fz_hi, 5),
            gamma_rad: gamma,
            p_pa: p,
            alpha_max_rad: a.max(1f64.to_radians()),
            kappa_max: k.max(0.02),
            vx_mps: params.longvl_mps(),
        }
    }

    fn conditions(&self) -> impl Iterator<Item = (f64, f64, f64)> + '_ {
        self.fz_n
            .iter()
            .flat_map(move |&fz| self.gamma_rad.iter().flat_map(move |&g| self.p_pa.iter().map(move |&p| (fz, g, p))))
    }

    fn input(&self, fz: f64, kappa: f64, alpha: f64, gamma: f64, p: f64) -> MfInput {
        MfInput {
            fz_n: fz,
            kappa,
            alpha_rad: alpha,
            gamma_rad: gamma,
            phit_per_m: 0.0,
            vx_mps: self.vx_mps,
            p_pa: p,
            omega_radps: 0.0,
        }
    }
}

/// Which group of margins (each belongs to the stage that fits the coefficients behind it).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MarginSet {
    /// Lateral friction, curvature and cornering stiffness sign (stage `fy_pure`).
    FyPure,
    /// Longitudinal friction, curvature and slip stiffness sign (stage `fx_pure`).
    FxPure,
    /// Pneumatic trail and its shape at small slip (stage `mz_pure`).
    MzPure,
    /// Gxα in [0, 1]: combined FX never exceeds nor reverses the pure FX (stage `fx_combined`).
    FxCombined,
    /// Gyκ in [0, 1] beyond 1° of slip angle (stage `fy_combined`).
    FyCombined,
    /// Both FY sets: `fy_combined` fitting the pure FY terms too, when no cornering data did.
    FyPureAndCombined,
}

impl MarginSet {
    /// The stage that owns the margins.
    pub fn stage(self) -> &'static str {
        match self {
            MarginSet::FyPure => "fy_pure",
            MarginSet::FxPure => "fx_pure",
            MarginSet::MzPure => "mz_pure",
            MarginSet::FxCombined => "fx_combined",
            MarginSet::FyCombined | MarginSet::FyPureAndCombined => "fy_combined",
        }
    }
}

/// One margin with what it means, for findings.
#[derive(Debug, Clone, PartialEq)]
pub struct Margin {
    /// ≥ 0 when physical.
    pub value: f64,
    /// What was checked where, e.g. `Dy/Fz at Fz 220 N, IA 4.0 deg, P 83 kPa`.
    pub what: String,
}

/// Slip stiffness of the pure curve from the model itself: a small-slip secant through zero
/// (signs and sizes matter, not the last digit).
fn slip_stiffness(params: &TyreParams, grid: &Grid, fz: f64, g: f64, p: f64, lateral: bool) -> f64 {
    let small = if lateral { 0.2f64.to_radians() } else { 0.002 };
    let f = |s: f64| {
        if lateral {
            mftyre::pure_fy(params, UseMode::M211, &grid.input(fz, 0.0, s, g, p))
        } else {
            mftyre::pure_fx(params, UseMode::M211, &grid.input(fz, s, 0.0, g, p))
        }
    };
    (f(small) - f(-small)) / (2.0 * small)
}

/// Combined-slip and pure force (FY when `lateral`, else FX) at every input, by the batch kernel.
fn combined_and_pure(params: &TyreParams, inputs: &[mftyre::MfInput], lateral: bool) -> (Vec<f64>, Vec<f64>) {
    use crate::engine::{BatchScratch, Channel, InputColumns};
    let cols = InputColumns::of_inputs(inputs);
    let batch = cols.batch(0..inputs.len());
    let mut scratch = BatchScratch::default();
    let (mut combined, mut pure) = (vec![0.0; inputs.len()], vec![0.0; inputs.len()]);
    let (c, p) = if lateral { (Channel::Fy, Channel::Fy0) } else { (Channel::Fx, Channel::Fx0) };
    c.eval_batch(params, &batch, &mut scratch, &mut combined);
    p.eval_batch(params, &batch, &mut scratch, &mut pure);
    (combined, pure)
}

/// The margins of one set; `described` = with descriptions (for findings), else values only
/// (for penalties, evaluated thousands of times per fit).
fn margins_of(params: &TyreParams, set: MarginSet, grid: &Grid, described: bool) -> Vec<Margin> {
    if set == MarginSet::FyPureAndCombined {
        let mut both = margins_of(params, MarginSet::FyPure, grid, described);
        both.extend(margins_of(params, MarginSet::FyCombined, grid, described));
        return both;
    }
    let g = |k: &str| params.get(k).unwrap_or(0.0);
    let fz0 = params.fnomin_n();
    let p0 = params.nominal_pressure_pa();
    let mut out = Vec::new();
    // Only failing margins are described: a grid has hundreds that hold, and formatting them
    // all was a visible part of every live update.
    let mut push = |value: f64, what: &dyn Fn() -> String| {
        let failing = value.is_nan() || value < TOLERANCE;
        out.push(Margin { value, what: if described && failing { what() } else { String::new() } });
    };
    let at = |fz: f64, gam: f64, p: f64| format!("Fz {fz:.0} N, IA {:.1} deg, P {:.0} kPa", gam.to_degrees(), p / 1e3);
    match set {
        MarginSet::FyPure | MarginSet::FxPure => {
            let lateral = set == MarginSet::FyPure;
            // The nominal sign of the cornering stiffness is the model's own at Fz0, IA 0, P0
            // (PKY1's sign alone does not say it: a negative PKY4 flips it, as in MFeval's
            // example file); a longitudinal slip stiffness is positive in ISO-W.
            let kp = if lateral {
                let k0 = slip_stiffness(params, grid, fz0, 0.0, p0, true);
                if k0 < 0.0 { -1.0 } else { 1.0 }
            } else {
                1.0
            };
            for (fz, gam, p) in grid.conditions() {
                let df = (fz - fz0) / fz0;
                let dp = (p - p0) / p0;
                let mu = if lateral {
                    (g("PDY1") + g("PDY2") * df)
                        * (1.0 + g("PPY3") * dp + g("PPY4") * dp * dp)
                        * (1.0 - g("PDY3") * gam * gam)
                } else {
                    (g("PDX1") + g("PDX2") * df)
                        * (1.0 + g("PPX3") * dp + g("PPX4") * dp * dp)
                        * (1.0 - g("PDX3") * gam * gam)
                };
                // A friction coefficient below 0.05 is as useless as a negative one.
                push(mu - 0.05, &|| {
                    format!("{}/Fz = {mu:.3} at {}", if lateral { "Dy" } else { "Dx" }, at(fz, gam, p))
                });
                for sgn in [-1.0, 1.0] {
                    let e = if lateral {
                        (g("PEY1") + g("PEY2") * df)
                            * (1.0 + g("PEY5") * gam * gam - (g("PEY3") + g("PEY4") * gam) * sgn)
                    } else {
                        (g("PEX1") + g("PEX2") * df + g("PEX3") * df * df) * (1.0 - g("PEX4") * sgn)
                    };
                    push(1.0 - e, &|| {
                        format!(
                            "{} = {e:.3} (> 1) at {}, slip sign {sgn:+}",
                            if lateral { "Ey" } else { "Ex" },
                            at(fz, gam, p)
                        )
                    });
                }
                let k = slip_stiffness(params, grid, fz, gam, p, lateral);
                // The slip stiffness keeps its nominal sign: in units of Fz per rad (or per unit
                // slip), at least 1 (a real tyre has 10–60).
                let kn = kp * k / fz;
                push(kn - 1.0, &|| {
                    format!(
                        "{} = {:.2}·Fz (sign or size wrong) at {}",
                        if lateral { "Kya" } else { "Kxk" },
                        kp * kn,
                        at(fz, gam, p)
                    )
                });
            }
        }
        MarginSet::MzPure => {
            let r0 = params.unloaded_radius_m();
            for (fz, gam, p) in grid.conditions() {
                let df = (fz - fz0) / fz0;
                let dp = (p - p0) / p0;
                // Peak trail Dt (MF 6.1 eq. 4.E42) at small slip: must be positive.
                let dt = fz
                    * (g("QDZ1") + g("QDZ2") * df)
                    * (1.0 - g("PPZ1") * dp)
                    * (1.0 + g("QDZ3") * gam.abs() + g("QDZ4") * gam * gam)
                    * r0
                    / fz0;
                push(dt / (fz * r0 / fz0).max(1e-9) - 1e-3, &|| {
                    format!("trail Dt = {dt:.4} m (≤ 0) at {}", at(fz, gam, p))
                });
                let bt = (g("QBZ1") + g("QBZ2") * df + g("QBZ3") * df * df)
                    * (1.0 + g("QBZ5") * gam.abs() + g("QBZ6") * gam * gam);
                push(bt - 0.1, &|| format!("trail Bt = {bt:.3} (≤ 0) at {}", at(fz, gam, p)));
            }
        }
        // Expanded into its two sets above.
        MarginSet::FyPureAndCombined => {}
        MarginSet::FxCombined | MarginSet::FyCombined => {
            let lateral = set == MarginSet::FyCombined;
            let a_max = 1.3 * grid.alpha_max_rad;
            let k_max = 1.3 * grid.kappa_max;
            // Lightest, middle and heaviest load: G's load terms are linear in dfz, so the ends
            // and the middle bound it; every camber and pressure.
            let n = grid.fz_n.len();
            let loads = [grid.fz_n[0], grid.fz_n[n / 2], grid.fz_n[n - 1]];
            let conditions = loads
                .iter()
                .flat_map(|&fz| grid.gamma_rad.iter().flat_map(move |&g| grid.p_pa.iter().map(move |&p| (fz, g, p))));
            // Every check point first, in load-case runs, so the batch kernel evaluates them
            // together (these margins are penalty residuals: every Jacobian column pays them).
            let mut points = Vec::new();
            for (fz, gam, p) in conditions {
                for ia in 1..=3 {
                    let a = a_max * ia as f64 / 3.0;
                    for ik in -3..=3 {
                        if ik == 0 {
                            continue;
                        }
                        let k = k_max * ik as f64 / 3.0;
                        for sa in [-a, a] {
                            points.push((fz, gam, p, k, sa));
                        }
                    }
                }
            }
            let inputs: Vec<_> = points.iter().map(|&(fz, gam, p, k, sa)| grid.input(fz, k, sa, gam, p)).collect();
            let (combined, pure) = combined_and_pure(params, &inputs, lateral);
            for (((fz, gam, p, k, sa), f), f0) in points.into_iter().zip(combined).zip(pure) {
                // The pure force must be clearly there to judge a ratio; where it is not,
                // the two margins count as held (the number of margins stays fixed, as
                // penalty residuals need).
                if !f0.is_finite() || f0.abs() < 0.05 * fz {
                    push(1.0, &|| String::new());
                    push(1.0, &|| String::new());
                    continue;
                }
                let ratio = if f.is_finite() { f / f0 } else { -1.0 };
                let what = |kind: &str| {
                    format!(
                        "{kind}: combined {} {f:.0} N vs pure {f0:.0} N at SA {:.1} deg, SR {k:.3}, {}",
                        if lateral { "FY" } else { "FX" },
                        sa.to_degrees(),
                        at(fz, gam, p)
                    )
                };
                // G ≤ 1 (2 % tolerance for the shifts), and G ≥ 0: combined slip
                // weakens a force, never strengthens or reverses it.
                push(1.02 - ratio, &|| what("G > 1"));
                push(ratio, &|| what("G < 0"));
            }
        }
    }
    out
}

/// Every margin of `set`, for findings: the failing ones ([`fails`]) described, the others with
/// an empty description.
pub fn margins(params: &TyreParams, set: MarginSet, grid: &Grid) -> Vec<Margin> {
    margins_of(params, set, grid, true)
}

/// The shortfalls of `set` (0 where a margin holds, −margin where it fails), in a fixed order
/// and number for a given grid: penalty residuals for the least-squares problem.
pub fn shortfalls(params: &TyreParams, set: MarginSet, grid: &Grid, out: &mut Vec<f64>) {
    out.clear();
    out.extend(
        margins_of(params, set, grid, false)
            .into_iter()
            .map(|m| if m.value.is_finite() { (-m.value).max(0.0) } else { 10.0 }),
    );
}

/// A margin counts as failing below this: E = 1 exactly is the model's own clamp, and the
/// penalties leave margins a rounding error short of zero.
pub const TOLERANCE: f64 = -1e-3;

/// True when a margin fails (below [`TOLERANCE`], or not a number).
pub fn fails(m: &Margin) -> bool {
    m.value.is_nan() || m.value < TOLERANCE
}

/// The worst (most negative) margin of `set`, if any fails.
pub fn worst(params: &TyreParams, set: MarginSet, grid: &Grid) -> Option<Margin> {
    margins(params, set, grid).into_iter().filter(fails).min_by(|a, b| a.value.total_cmp(&b.value))
}

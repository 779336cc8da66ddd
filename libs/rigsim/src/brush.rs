//! A physical brush tyre: the virtual rig's second tyre model, one the Magic Formula cannot
//! represent exactly (equations and parameter meanings: `docs/brush-tyre.md`).
//!
//! The tread is a row of elastic bristles on a compliant carcass, pressed onto the road by a
//! parabolic pressure distribution over a contact patch whose length follows the vertical
//! deflection. Each bristle sticks to the road until its stress reaches the static friction
//! limit, then slides at a kinetic friction that falls with the sliding speed. Everything is
//! closed form except the carcass compliance, a small fixed-point problem solved by a secant
//! iteration, so one evaluation costs about as much as one MF-Tyre 6.1 evaluation.
//!
//! Axes and units: ISO-W, SI, exactly as [`mftyre::MfOutput`] reports them (the rig consumes
//! both models through that struct): a positive slip angle gives a negative FY and a positive
//! (aligning) MZ at small slip, a positive slip ratio a positive FX, rolling forwards a negative
//! MY.

use std::path::Path;

use mftyre::MfOutput;
use serde::{Deserialize, Serialize};

/// Errors reading or checking a brush-tyre parameter file.
#[derive(Debug, thiserror::Error)]
pub enum BrushError {
    /// The file could not be read.
    #[error("{path}: cannot read: {source}")]
    Io {
        /// The file.
        path: String,
        /// The cause.
        #[source]
        source: std::io::Error,
    },
    /// The TOML did not parse or did not match the schema.
    #[error("{path}:{line}:{column}: {message}")]
    Parse {
        /// The file.
        path: String,
        /// 1-based line (0 when unknown).
        line: usize,
        /// 1-based column (0 when unknown).
        column: usize,
        /// What toml/serde reported.
        message: String,
    },
    /// A value is out of its physical range.
    #[error("{path}: invalid `{key}`: {reason}")]
    Invalid {
        /// The file.
        path: String,
        /// Dotted key.
        key: String,
        /// Why.
        reason: String,
    },
}

/// Size and nominal operating point of the tyre.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BrushNominal {
    /// Nominal (reference) vertical load Fz0 [N]; procedures scale their loads from it.
    pub load_n: f64,
    /// Nominal inflation pressure p0 (gauge) [Pa].
    pub pressure_pa: f64,
    /// Reference speed V0 for the speed terms [m/s].
    pub speed_mps: f64,
    /// The three test pressures a run uses for its low, middle and high slots [bar].
    pub test_pressures_bar: [f64; 3],
}

/// Size.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BrushDimensions {
    /// Unloaded radius R0 [m].
    pub unloaded_radius_m: f64,
    /// Section width [m].
    pub width_m: f64,
    /// Rim width [in] (as a TTC title line writes it).
    pub rim_width_in: f64,
}

/// Vertical behaviour: nonlinear stiffness, loaded and effective rolling radius, contact length.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BrushVertical {
    /// Linear vertical stiffness cz1 at p0: Fz = (cz1·ρ + cz2·ρ²)·(1 + p_cz·dp) [N/m].
    pub stiffness_n_per_m: f64,
    /// Progressive (quadratic) vertical stiffness cz2 [N/m²].
    pub stiffness_quadratic_n_per_m2: f64,
    /// Pressure gain p_cz of the vertical stiffness per unit relative pressure dp = (p − p0)/p0 [-].
    pub pressure_gain: f64,
    /// Contact half-length a = q_a·√(2·R0·ρ) [-] (1 would be the geometric chord).
    pub contact_length_factor: f64,
    /// Effective rolling radius Re = RΩ − k_re·ρ [-] (a belted tyre rolls on ~R − ρ/3).
    pub effective_radius_factor: f64,
    /// Centrifugal growth RΩ = R0·(1 + q_v·(Vx/V0)²) [-].
    pub radius_speed_growth: f64,
}

/// Tread bristles.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BrushTread {
    /// Longitudinal bristle stiffness per unit contact length cpx at p0 [N/m²].
    pub longitudinal_stiffness_n_per_m2: f64,
    /// Lateral bristle stiffness per unit contact length cpy at p0 [N/m²].
    pub lateral_stiffness_n_per_m2: f64,
    /// Pressure gain of the bristle stiffness per unit relative pressure [-].
    pub pressure_gain: f64,
}

/// Carcass compliance between rim and tread base.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BrushCarcass {
    /// Lateral stiffness ccy [N/m]: the patch shifts by v = FY/ccy (arms of MZ and MX).
    pub lateral_stiffness_n_per_m: f64,
    /// Longitudinal stiffness ccx [N/m] (static drag, with the tread in series).
    pub longitudinal_stiffness_n_per_m: f64,
    /// Yaw stiffness cψ [N·m/rad]: MZ twists the patch towards the direction of travel, so the
    /// effective slip angle is α − MZ/cψ.
    pub torsional_stiffness_nm_per_rad: f64,
    /// Belt extension stiffness EA [N]: FX stretches the tread band in the patch, so the
    /// effective slip ratio is κ − FX/EA.
    pub belt_extension_stiffness_n: f64,
}

/// Friction.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BrushFriction {
    /// Static longitudinal friction μx0 at Fz0, p0, zero camber [-].
    pub mu_x: f64,
    /// Static lateral friction μy0 at Fz0, p0, zero camber [-].
    pub mu_y: f64,
    /// Load sensitivity: μ = μ0·(Fz/Fz0)^(−n) [-] (a power law; MF writes it linear in dfz).
    pub load_exponent: f64,
    /// Smallest Fz/Fz0 the power law is evaluated at (it diverges at zero load) [-].
    pub min_load_ratio: f64,
    /// Kinetic/static ratio r at high sliding speed: μk = μs·(r + (1 − r)/(1 + Vs/Vμ)) [-].
    pub kinetic_ratio: f64,
    /// Sliding speed Vμ at which half the static excess is lost [m/s].
    pub sliding_speed_mps: f64,
    /// Pressure gain of friction per unit relative pressure [-].
    pub pressure_gain: f64,
    /// Friction loss with camber: factor 1 − c·sin²γ [-].
    pub camber_loss: f64,
}

/// Camber.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BrushCamber {
    /// Share εγ of the ideal brush camber deflection ½·(sinγ/R0)·(a² − x²) the tread takes
    /// (the rest is absorbed by the tread's width and the carcass) [-].
    pub thrust_factor: f64,
    /// Overturning moment from camber: MX_γ = −Fz·RL·k·sinγ [-].
    pub overturning_factor: f64,
}

/// Rolling resistance.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BrushRolling {
    /// Rolling resistance coefficient f0 at V0 → 0 and p0 [-].
    pub coefficient: f64,
    /// Speed term: f = f0 + fv·(Vx/V0)² [-].
    pub speed_coefficient: f64,
    /// Pressure exponent: f ∝ (p/p0)^e [-] (harder tyres roll easier: e < 0).
    pub pressure_exponent: f64,
}

/// A brush tyre's parameter file (TOML; `launch-config/tyres/brush_*.toml`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BrushParams {
    /// Tyre name, as a TTC title line's `Tire_Name` carries it.
    pub name: String,
    /// ETRTO load index the tyre declares, when its Fz0 is one (road tyres); race tyres have none.
    #[serde(default)]
    pub load_index: Option<u32>,
    /// Nominal operating point.
    pub nominal: BrushNominal,
    /// Size.
    pub dimensions: BrushDimensions,
    /// Vertical behaviour.
    pub vertical: BrushVertical,
    /// Tread bristles.
    pub tread: BrushTread,
    /// Carcass.
    pub carcass: BrushCarcass,
    /// Friction.
    pub friction: BrushFriction,
    /// Camber.
    pub camber: BrushCamber,
    /// Rolling resistance.
    pub rolling: BrushRolling,
}

/// One operating point of the brush tyre.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BrushInput {
    /// Vertical load [N] (negative is taken as 0).
    pub fz_n: f64,
    /// Longitudinal slip ratio κ = −Vsx/Vx [-].
    pub kappa: f64,
    /// Slip angle α [rad] (ISO-W).
    pub alpha_rad: f64,
    /// Inclination (camber) γ [rad].
    pub gamma_rad: f64,
    /// Forward speed of the wheel centre Vx [m/s].
    pub vx_mps: f64,
    /// Inflation pressure (gauge) [Pa]; ≤ 0 means the nominal pressure.
    pub p_pa: f64,
    /// Multiplies both friction coefficients (the rig's thermal grip and break-in) [-].
    pub grip_factor: f64,
    /// Multiplies both bristle stiffnesses (the rig's thermal and wear stiffness) [-].
    pub stiffness_factor: f64,
}

impl BrushInput {
    /// A point at `fz_n`, `kappa`, `alpha_rad`, nominal everything else (tests and examples).
    pub fn new(fz_n: f64, kappa: f64, alpha_rad: f64, vx_mps: f64) -> Self {
        Self { fz_n, kappa, alpha_rad, gamma_rad: 0.0, vx_mps, p_pa: 0.0, grip_factor: 1.0, stiffness_factor: 1.0 }
    }
}

/// What the contact patch looks like at one load and pressure (no slip needed).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PatchState {
    /// Vertical deflection ρ [m].
    pub rho_m: f64,
    /// Contact half-length a [m].
    pub half_length_m: f64,
    /// Brush slip stiffness Cx = 2·cpx·a² [N] (before carcass compliance).
    pub cx_n: f64,
    /// Brush cornering stiffness Cy = 2·cpy·a² [N/rad] (before carcass compliance).
    pub cy_n_per_rad: f64,
    /// Static friction μx, μy at this load, pressure and camber [-].
    pub mu_x: f64,
    /// Static lateral friction [-].
    pub mu_y: f64,
}

/// Most secant iterations of the carcass-compliance solve (it converges in 3–5).
const MAX_COMPLIANCE_ITERATIONS: usize = 12;
/// Converged when both residuals (slip ratio, slip angle in rad) are below this.
const COMPLIANCE_TOLERANCE: f64 = 1e-12;
/// Smallest 1 + κ the theoretical slips divide by (κ = −1 is a locked wheel).
const MIN_ONE_PLUS_KAPPA: f64 = 1e-3;

impl BrushParams {
    /// Parses a brush-tyre file from TOML text; `path` labels errors.
    pub fn from_toml_str(text: &str, path: &str) -> Result<BrushParams, BrushError> {
        let p: BrushParams = toml::from_str(text).map_err(|e| {
            let (line, column) = e.span().map(|s| line_col(text, s.start)).unwrap_or((0, 0));
            BrushError::Parse { path: path.to_owned(), line, column, message: e.message().to_owned() }
        })?;
        p.validate().map_err(|(key, reason)| BrushError::Invalid { path: path.to_owned(), key, reason })?;
        Ok(p)
    }

    /// Reads and checks a brush-tyre file.
    pub fn load(path: &Path) -> Result<BrushParams, BrushError> {
        let text = std::fs::read_to_string(path)
            .map_err(|source| BrushError::Io { path: path.display().to_string(), source })?;
        BrushParams::from_toml_str(&text, &path.display().to_string())
    }

    /// Checks every value's physical range; on failure (dotted key, reason).
    pub fn validate(&self) -> Result<(), (String, String)> {
        let positive = [
            ("nominal.load_n", self.nominal.load_n),
            ("nominal.pressure_pa", self.nominal.pressure_pa),
            ("nominal.speed_mps", self.nominal.speed_mps),
            ("dimensions.unloaded_radius_m", self.dimensions.unloaded_radius_m),
            ("dimensions.width_m", self.dimensions.width_m),
            ("dimensions.rim_width_in", self.dimensions.rim_width_in),
            ("vertical.stiffness_n_per_m", self.vertical.stiffness_n_per_m),
            ("vertical.contact_length_factor", self.vertical.contact_length_factor),
            ("tread.longitudinal_stiffness_n_per_m2", self.tread.longitudinal_stiffness_n_per_m2),
            ("tread.lateral_stiffness_n_per_m2", self.tread.lateral_stiffness_n_per_m2),
            ("carcass.lateral_stiffness_n_per_m", self.carcass.lateral_stiffness_n_per_m),
            ("carcass.longitudinal_stiffness_n_per_m", self.carcass.longitudinal_stiffness_n_per_m),
            ("carcass.torsional_stiffness_nm_per_rad", self.carcass.torsional_stiffness_nm_per_rad),
            ("carcass.belt_extension_stiffness_n", self.carcass.belt_extension_stiffness_n),
            ("friction.mu_x", self.friction.mu_x),
            ("friction.mu_y", self.friction.mu_y),
            ("friction.min_load_ratio", self.friction.min_load_ratio),
            ("friction.sliding_speed_mps", self.friction.sliding_speed_mps),
        ];
        for (k, v) in positive {
            if !(v.is_finite() && v > 0.0) {
                return Err((k.to_owned(), format!("must be finite and > 0, got {v}")));
            }
        }
        let non_negative = [
            ("vertical.stiffness_quadratic_n_per_m2", self.vertical.stiffness_quadratic_n_per_m2),
            ("vertical.effective_radius_factor", self.vertical.effective_radius_factor),
            ("vertical.radius_speed_growth", self.vertical.radius_speed_growth),
            ("friction.load_exponent", self.friction.load_exponent),
            ("friction.camber_loss", self.friction.camber_loss),
            ("camber.thrust_factor", self.camber.thrust_factor),
            ("rolling.coefficient", self.rolling.coefficient),
            ("rolling.speed_coefficient", self.rolling.speed_coefficient),
        ];
        for (k, v) in non_negative {
            if !(v.is_finite() && v >= 0.0) {
                return Err((k.to_owned(), format!("must be finite and ≥ 0, got {v}")));
            }
        }
        let bounded = [
            ("friction.kinetic_ratio", self.friction.kinetic_ratio, 0.05, 1.0),
            ("friction.load_exponent", self.friction.load_exponent, 0.0, 0.9),
            ("friction.min_load_ratio", self.friction.min_load_ratio, 0.0, 1.0),
            ("vertical.pressure_gain", self.vertical.pressure_gain, -3.0, 3.0),
            ("vertical.effective_radius_factor", self.vertical.effective_radius_factor, 0.0, 1.0),
            ("tread.pressure_gain", self.tread.pressure_gain, -3.0, 3.0),
            ("friction.pressure_gain", self.friction.pressure_gain, -3.0, 3.0),
            ("camber.thrust_factor", self.camber.thrust_factor, 0.0, 3.0),
            ("camber.overturning_factor", self.camber.overturning_factor, -5.0, 5.0),
            ("rolling.pressure_exponent", self.rolling.pressure_exponent, -3.0, 3.0),
        ];
        for (k, v, lo, hi) in bounded {
            if !(v.is_finite() && v >= lo && v <= hi) {
                return Err((k.to_owned(), format!("must be in [{lo}, {hi}], got {v}")));
            }
        }
        if self.nominal.test_pressures_bar.iter().any(|p| !(p.is_finite() && *p > 0.0)) {
            return Err((
                "nominal.test_pressures_bar".to_owned(),
                format!("expected three positive pressures, got {:?}", self.nominal.test_pressures_bar),
            ));
        }
        if self.name.trim().is_empty() {
            return Err(("name".to_owned(), "must not be empty".to_owned()));
        }
        Ok(())
    }

    /// Relative pressure dp = (p − p0)/p0 (p ≤ 0 or non-finite → nominal).
    fn dp(&self, p_pa: f64) -> f64 {
        if p_pa.is_finite() && p_pa > 0.0 { (p_pa - self.nominal.pressure_pa) / self.nominal.pressure_pa } else { 0.0 }
    }

    /// Vertical deflection ρ [m] at load `fz_n` and relative pressure `dp`: the positive root
    /// of cz2·ρ² + cz1·ρ = Fz/(1 + p_cz·dp), in cancellation-free form.
    pub fn deflection_m(&self, fz_n: f64, dp: f64) -> f64 {
        let v = &self.vertical;
        let fz = fz_n.max(0.0) / (1.0 + v.pressure_gain * dp).max(0.1);
        let c1 = v.stiffness_n_per_m;
        let c2 = v.stiffness_quadratic_n_per_m2;
        2.0 * fz / (c1 + (c1 * c1 + 4.0 * c2 * fz).sqrt())
    }

    /// The contact patch at `fz_n`, pressure `p_pa` (≤ 0: nominal), camber `gamma_rad`, with the
    /// rig's grip and stiffness factors.
    pub fn patch(&self, fz_n: f64, p_pa: f64, gamma_rad: f64, grip_factor: f64, stiffness_factor: f64) -> PatchState {
        let dp = self.dp(p_pa);
        let rho = self.deflection_m(fz_n, dp);
        let r0 = self.dimensions.unloaded_radius_m;
        let a = self.vertical.contact_length_factor * (2.0 * r0 * rho).sqrt();
        let k = (1.0 + self.tread.pressure_gain * dp).max(0.1) * stiffness_factor;
        let f = &self.friction;
        let fz_ratio = (fz_n.max(0.0) / self.nominal.load_n).max(f.min_load_ratio);
        let sg = gamma_rad.sin();
        let mu_scale = fz_ratio.powf(-f.load_exponent)
            * (1.0 + f.pressure_gain * dp).max(0.1)
            * (1.0 - f.camber_loss * sg * sg).max(0.1)
            * grip_factor.max(0.0);
        PatchState {
            rho_m: rho,
            half_length_m: a,
            cx_n: 2.0 * self.tread.longitudinal_stiffness_n_per_m2 * k * a * a,
            cy_n_per_rad: 2.0 * self.tread.lateral_stiffness_n_per_m2 * k * a * a,
            mu_x: f.mu_x * mu_scale,
            mu_y: f.mu_y * mu_scale,
        }
    }

    /// Evaluates the tyre at one operating point (ISO-W, SI). Never panics; a zero load gives
    /// zero forces and the free radius.
    pub fn evaluate(&self, input: &BrushInput) -> MfOutput {
        let fz = if input.fz_n.is_finite() { input.fz_n.max(0.0) } else { 0.0 };
        let vx = if input.vx_mps.is_finite() { input.vx_mps } else { 0.0 };
        let r0 = self.dimensions.unloaded_radius_m;
        let v0 = self.nominal.speed_mps;
        let r_omega = r0 * (1.0 + self.vertical.radius_speed_growth * (vx / v0) * (vx / v0));
        let patch = self.patch(fz, input.p_pa, input.gamma_rad, input.grip_factor, input.stiffness_factor);
        let rho = patch.rho_m;
        let rl = r_omega - rho;
        let re = r_omega - self.vertical.effective_radius_factor * rho;
        let mut out = MfOutput {
            fz_n: fz,
            kappa: input.kappa,
            alpha_rad: input.alpha_rad,
            gamma_rad: input.gamma_rad,
            vx_mps: vx,
            p_pa: if input.p_pa > 0.0 { input.p_pa } else { self.nominal.pressure_pa },
            re_m: re,
            rl_m: rl,
            rho_m: rho,
            omega_radps: if re > 0.0 { vx * (1.0 + input.kappa) / re } else { 0.0 },
            contact_width_m: self.dimensions.width_m,
            cy_npm: self.carcass.lateral_stiffness_n_per_m,
            ..MfOutput::default()
        };
        if fz <= 0.0 || patch.half_length_m <= 0.0 || !(input.kappa.is_finite() && input.alpha_rad.is_finite()) {
            out.cx_npm = self.carcass.longitudinal_stiffness_n_per_m;
            out.cz_npm = self.vertical.stiffness_n_per_m;
            return out;
        }
        let a = patch.half_length_m;
        let c = &self.carcass;
        // Equivalent lateral slip of the camber deflection: ½·εγ·(sinγ/R0)·(a² − x²) carries the
        // force of a uniform slip εγ·a·sinγ/(3·R0).
        let sigma_camber = self.camber.thrust_factor * a * input.gamma_rad.sin() / (3.0 * r0);
        let point = |kappa_e: f64, alpha_e: f64| {
            let b = brush_forces(&patch, fz, kappa_e, alpha_e, sigma_camber, vx, &self.friction);
            // The carcass shifts the patch sideways by v = FY/ccy: FX then acts off the wheel
            // plane (MZ = x·FY − y·FX).
            let mz = b.mz_nm - b.fx_n * b.fy_n / c.lateral_stiffness_n_per_m;
            (b, mz)
        };
        // Carcass compliance: κe = κ − FX(κe, αe)/EA, αe = α − MZ(κe, αe)/cψ. Start from the
        // linear answer and polish each residual with secant steps (chord steps until two
        // points exist).
        let chord_x = 1.0 + patch.cx_n / c.belt_extension_stiffness_n;
        let chord_y = 1.0 + patch.cy_n_per_rad * a / (3.0 * c.torsional_stiffness_nm_per_rad);
        let (kappa, alpha) = (input.kappa, input.alpha_rad);
        let mut ke = kappa / chord_x;
        let mut ae = alpha / chord_y;
        let mut prev: Option<(f64, f64, f64, f64)> = None;
        let (mut b, mut mz) = point(ke, ae);
        for _ in 0..MAX_COMPLIANCE_ITERATIONS {
            let gk = ke + b.fx_n / c.belt_extension_stiffness_n - kappa;
            let ga = ae + mz / c.torsional_stiffness_nm_per_rad - alpha;
            if gk.abs() < COMPLIANCE_TOLERANCE && ga.abs() < COMPLIANCE_TOLERANCE {
                break;
            }
            let (sk, sa) = match prev {
                Some((pk, pgk, pa, pga)) => {
                    let dk = ke - pk;
                    let da = ae - pa;
                    let slope_k = if dk.abs() > 1e-15 { (gk - pgk) / dk } else { chord_x };
                    let slope_a = if da.abs() > 1e-15 { (ga - pga) / da } else { chord_y };
                    // Each residual's slope is 1 + (a stiffness ratio that may be negative past
                    // the peak); keep it in a sane band so a noisy secant cannot throw far.
                    (slope_k.clamp(0.2, 3.0 * chord_x), slope_a.clamp(0.2, 3.0 * chord_y))
                }
                None => (chord_x, chord_y),
            };
            prev = Some((ke, gk, ae, ga));
            ke -= gk / sk;
            ae -= ga / sa;
            (b, mz) = point(ke, ae);
        }

        let sg = input.gamma_rad.sin();
        // MX: the load acts at the patch's sideways shift v = FY/ccy, and camber moves the
        // centre of pressure towards the lower shoulder.
        let mx = fz * b.fy_n / c.lateral_stiffness_n_per_m - fz * rl * self.camber.overturning_factor * sg;
        let ro = &self.rolling;
        let dp = self.dp(input.p_pa);
        let p_ratio = (1.0 + dp).max(0.1);
        let f_roll =
            (ro.coefficient + ro.speed_coefficient * (vx / v0) * (vx / v0)) * p_ratio.powf(ro.pressure_exponent);
        // Rolling resistance resists the rolling direction; blended through zero at standstill.
        let my = -fz * r0 * f_roll * (vx / 0.5).tanh();

        // Linear (small-slip) stiffnesses with the carcass in series.
        let cx_eff = patch.cx_n / chord_x;
        let cy_eff = patch.cy_n_per_rad / chord_y;
        // Longitudinal stiffness of the standing tyre: carcass and tread (2a·cpx) in series.
        let tread_x = patch.cx_n / a;
        let cx_static = 1.0 / (1.0 / c.longitudinal_stiffness_n_per_m + 1.0 / tread_x);

        out.fx_n = b.fx_n;
        out.fy_n = b.fy_n;
        out.mz_nm = mz;
        out.mx_nm = mx;
        out.my_nm = my;
        out.mzr_nm = 0.0;
        out.trail_m = if b.fy_n.abs() > 1e-9 { -b.mz_nm / b.fy_n } else { a / 3.0 };
        out.contact_length_m = 2.0 * a;
        out.mux = patch.mu_x;
        out.muy = patch.mu_y;
        out.cx_npm = cx_static;
        out.cz_npm = fz / rho.max(1e-9);
        // ISO-W sign of the MF: FY = Kyα·α at small slip, Kyα < 0.
        out.kya_nprad = -cy_eff;
        out.kxk_n = cx_eff;
        out.sigmax_m = cx_eff / c.longitudinal_stiffness_n_per_m;
        out.sigmay_m = cy_eff / c.lateral_stiffness_n_per_m;
        out
    }
}

/// Forces of the bristles alone (no carcass), ISO-W.
#[derive(Debug, Clone, Copy, PartialEq)]
struct BristleForces {
    fx_n: f64,
    fy_n: f64,
    mz_nm: f64,
}

/// The brush with a parabolic pressure q(x) = 3Fz/(4a)·(1 − x²/a²) over −a ≤ x ≤ a (leading
/// edge at +a) at effective slips κe, αe (plus the camber's equivalent lateral slip).
///
/// Computed in a frame whose lateral axis is ISO-W's mirrored, so a positive slip gives a
/// positive force there: theoretical slips σx = κ/(1+κ), σy = tanα/(1+κ) + σγ. Adhesion holds
/// from the leading edge back to x_s = a·(2λ − 1), λ = |(Cx·σx/μx, Cy·σy/μy)|/(3Fz); behind it
/// the bristles slide at the kinetic friction along the slip direction. Closed forms:
/// F_adh = C·σ·(1 − λ)², F_slide = μk·Fz·λ²(3 − 2λ)·ŝ,
/// MZ_adh = −(a/3)·Cy·σy·(1 − λ)²(1 − 4λ), MZ_slide = −3·μk,y·Fz·a·λ²(1 − λ)²·ŝy.
fn brush_forces(
    patch: &PatchState,
    fz: f64,
    kappa_e: f64,
    alpha_e: f64,
    sigma_camber: f64,
    vx: f64,
    fr: &BrushFriction,
) -> BristleForces {
    let one_k = (1.0 + kappa_e).max(MIN_ONE_PLUS_KAPPA);
    let tan_a = alpha_e.tan();
    let sx = kappa_e / one_k;
    // Mirrored lateral axis: positive α (ISO-W) is a positive slip here.
    let sy = tan_a / one_k + sigma_camber;
    let (mux, muy) = (patch.mu_x, patch.mu_y);
    let tx = patch.cx_n * sx / mux;
    let ty = patch.cy_n_per_rad * sy / muy;
    let lambda = (tx * tx + ty * ty).sqrt() / (3.0 * fz);
    // Sliding speed of the tips: the slip velocity |Vs| = Vx·√(κ² + tan²α).
    let vs = vx.abs() * (kappa_e * kappa_e + tan_a * tan_a).sqrt();
    let k_kin = fr.kinetic_ratio + (1.0 - fr.kinetic_ratio) / (1.0 + vs / fr.sliding_speed_mps);
    let s_norm = (sx * sx + sy * sy).sqrt();
    let (ux, uy) = if s_norm > 0.0 { (sx / s_norm, sy / s_norm) } else { (0.0, 0.0) };
    let a = patch.half_length_m;
    let (fx, fy_m, mz_m) = if lambda < 1.0 {
        let one_l = 1.0 - lambda;
        let adh = one_l * one_l;
        let slide = k_kin * fz * lambda * lambda * (3.0 - 2.0 * lambda);
        let fx = patch.cx_n * sx * adh + slide * mux * ux;
        let fy = patch.cy_n_per_rad * sy * adh + slide * muy * uy;
        let mz = -(a / 3.0) * patch.cy_n_per_rad * sy * adh * (1.0 - 4.0 * lambda)
            - 3.0 * k_kin * muy * fz * a * lambda * lambda * adh * uy;
        (fx, fy, mz)
    } else {
        (k_kin * mux * fz * ux, k_kin * muy * fz * uy, 0.0)
    };
    // Back to ISO-W: the lateral axis and the yaw moment change sign.
    BristleForces { fx_n: fx, fy_n: -fy_m, mz_nm: -mz_m }
}

/// 1-based (line, column) of a byte offset.
fn line_col(text: &str, offset: usize) -> (usize, usize) {
    let before = &text[..offset.min(text.len())];
    let line = before.matches('\n').count() + 1;
    let col = before.rsplit('\n').next().map_or(0, |l| l.chars().count()) + 1;
    (line, col)
}

//! MF-Tyre 6.1 steady-state evaluation (ISO-W axes, SI units), turn slip excluded.
//!
//! Equation numbers refer to Pacejka, *Tire and Vehicle Dynamics*, 3rd ed. (2012), ch. 4
//! ("4.Exx"), and to Besselink, Schmeitz & Pacejka (2010), "An improved Magic Formula/Swift
//! tyre model that can handle inflation pressure changes" ("Axx", "eq. n"). Where the TNO
//! MF-Tyre 6.1.2 solver differs from the book, this follows the choices MFeval documents as
//! TNO-compatible (A_mu = 1, LMUV = 0, signed ε = 1e-6, My per A48, Mz per A54–A60, t × LFZO,
//! F'y = Gyκ(γ)·Fy0(γ = 0), Re/ρ/Cz from Besselink eqs. 1–7).

use std::f64::consts::{FRAC_2_PI, PI};

use crate::params::{ScalingFactors, TyreParams};

/// Small number that keeps divisions finite (4.E6a); signed like the quantity it protects.
const EPS: f64 = 1e-6;

/// How the model is evaluated: MFeval's three-digit `useMode` without turn slip.
///
/// Hundreds: 1 = limit checks (inputs clamped to the `.tir` ranges, low-speed model),
/// 2 = none. Tens: 1 = α and γ used directly (TNO), 2 = α* = tan α·sgn Vx, γ* = sin γ (book).
/// Units: 1 = combined slip, 2 = pure slip (Fx = Fx0, Fy = Fy0, Mz = Mz0).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum UseMode {
    /// Limit checks, no α*, combined slip: what TNO MF-Tyre does.
    #[default]
    M111,
    /// Limit checks, no α*, pure slip.
    M112,
    /// Limit checks, α* = tan α·sgn Vx and γ* = sin γ, combined slip (the book's form).
    M121,
    /// Limit checks, α*/γ*, pure slip.
    M122,
    /// No limit checks, no α*, combined slip.
    M211,
    /// No limit checks, no α*, pure slip.
    M212,
    /// No limit checks, α*/γ*, combined slip.
    M221,
    /// No limit checks, α*/γ*, pure slip.
    M222,
}

/// A `useMode` this crate does not implement.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error(
    "use mode `{given}` is not supported: expected 111, 112, 121, 122, 211, 212, 221 or 222 (turn-slip modes 1x3/1x4 are not implemented)"
)]
pub struct UseModeError {
    /// The text given.
    pub given: String,
}

impl std::str::FromStr for UseMode {
    type Err = UseModeError;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        Ok(match s.trim() {
            "111" => UseMode::M111,
            "112" => UseMode::M112,
            "121" => UseMode::M121,
            "122" => UseMode::M122,
            "211" => UseMode::M211,
            "212" => UseMode::M212,
            "221" => UseMode::M221,
            "222" => UseMode::M222,
            other => {
                return Err(UseModeError { given: other.to_owned() });
            }
        })
    }
}

impl std::fmt::Display for UseMode {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let s = match self {
            UseMode::M111 => "111",
            UseMode::M112 => "112",
            UseMode::M121 => "121",
            UseMode::M122 => "122",
            UseMode::M211 => "211",
            UseMode::M212 => "212",
            UseMode::M221 => "221",
            UseMode::M222 => "222",
        };
        f.write_str(s)
    }
}

impl UseMode {
    /// Inputs are clamped to the `.tir` ranges and the low-speed model applies.
    pub fn limits_check(self) -> bool {
        matches!(self, UseMode::M111 | UseMode::M112 | UseMode::M121 | UseMode::M122)
    }

    /// α* = tan α·sgn Vx and γ* = sin γ instead of α and γ.
    pub fn alpha_star(self) -> bool {
        matches!(self, UseMode::M121 | UseMode::M122 | UseMode::M221 | UseMode::M222)
    }

    /// The same mode with pure-slip output (units digit 2).
    pub fn pure(self) -> UseMode {
        match self {
            UseMode::M111 | UseMode::M112 => UseMode::M112,
            UseMode::M121 | UseMode::M122 => UseMode::M122,
            UseMode::M211 | UseMode::M212 => UseMode::M212,
            UseMode::M221 | UseMode::M222 => UseMode::M222,
        }
    }

    /// Combined-slip weighting applies (otherwise pure-slip forces and moments).
    pub fn combined(self) -> bool {
        matches!(self, UseMode::M111 | UseMode::M121 | UseMode::M211 | UseMode::M221)
    }
}

/// Which inputs the limit checks changed (a small bit set).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Hash)]
pub struct Clamped {
    bits: u8,
}

impl Clamped {
    /// Fz was negative (set to 0), above FZMAX, or below FZMIN (Mz and ρ then use FZMIN).
    pub const FZ: Clamped = Clamped { bits: 1 };
    /// κ outside KPUMIN..KPUMAX.
    pub const KAPPA: Clamped = Clamped { bits: 2 };
    /// α outside ALPMIN..ALPMAX.
    pub const ALPHA: Clamped = Clamped { bits: 4 };
    /// γ outside CAMMIN..CAMMAX.
    pub const GAMMA: Clamped = Clamped { bits: 8 };
    /// Pressure outside PRESMIN..PRESMAX.
    pub const PRESSURE: Clamped = Clamped { bits: 16 };
    /// |Vx| ≤ VXLOW: low-speed reductions were applied.
    pub const LOW_SPEED: Clamped = Clamped { bits: 32 };
    /// Nonzero turn slip was given and ignored (turn slip is not modelled).
    pub const PHIT_IGNORED: Clamped = Clamped { bits: 64 };

    /// No flag set.
    pub const fn empty() -> Self {
        Clamped { bits: 0 }
    }

    /// From raw bits (the batch kernel builds flags per lane).
    pub(crate) const fn from_bits(bits: u8) -> Self {
        Clamped { bits }
    }

    /// The raw bits.
    pub const fn bits(self) -> u8 {
        self.bits
    }

    /// True when no flag is set.
    pub const fn is_empty(self) -> bool {
        self.bits == 0
    }

    /// True when every flag of `other` is set in `self`.
    pub const fn contains(self, other: Clamped) -> bool {
        self.bits & other.bits == other.bits
    }

    /// Sets the flags of `other`.
    pub fn insert(&mut self, other: Clamped) {
        self.bits |= other.bits;
    }
}

impl std::ops::BitOr for Clamped {
    type Output = Clamped;
    fn bitor(self, rhs: Clamped) -> Clamped {
        Clamped { bits: self.bits | rhs.bits }
    }
}

/// One operating point (ISO-W, SI).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct MfInput {
    /// Vertical load, N (positive in compression).
    pub fz_n: f64,
    /// Longitudinal slip κ, – (positive when driving).
    pub kappa: f64,
    /// Slip angle α, rad.
    pub alpha_rad: f64,
    /// Inclination (camber) angle γ, rad.
    pub gamma_rad: f64,
    /// Turn slip φt, 1/m. Not modelled: ignored (flagged in [`MfOutput::clamped`]).
    pub phit_per_m: f64,
    /// Longitudinal speed of the wheel centre Vx, m/s.
    pub vx_mps: f64,
    /// Inflation pressure, Pa; 0 means the file's INFLPRES.
    pub p_pa: f64,
    /// Wheel spin rate, rad/s; 0 means "estimate from Vx and κ".
    pub omega_radps: f64,
}

/// Everything MFeval reports for one operating point (ISO-W, SI).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct MfOutput {
    /// Longitudinal force, N.
    pub fx_n: f64,
    /// Lateral force, N.
    pub fy_n: f64,
    /// Vertical load as given (negative values set to 0), N.
    pub fz_n: f64,
    /// Overturning moment, N·m.
    pub mx_nm: f64,
    /// Rolling resistance moment, N·m.
    pub my_nm: f64,
    /// Aligning moment, N·m.
    pub mz_nm: f64,
    /// κ as used (after the low-speed reduction, before clamping), –.
    pub kappa: f64,
    /// α as given, rad.
    pub alpha_rad: f64,
    /// γ as given, rad.
    pub gamma_rad: f64,
    /// φt as given, 1/m.
    pub phit_per_m: f64,
    /// Vx as given, m/s.
    pub vx_mps: f64,
    /// Pressure as used (INFLPRES when 0 was given, clamped with limit checks), Pa.
    pub p_pa: f64,
    /// Effective rolling radius Re, m.
    pub re_m: f64,
    /// Vertical deflection ρ, m.
    pub rho_m: f64,
    /// Contact length 2a, m.
    pub contact_length_m: f64,
    /// Pneumatic trail t, m.
    pub trail_m: f64,
    /// Longitudinal friction coefficient μx, –.
    pub mux: f64,
    /// Lateral friction coefficient μy, –.
    pub muy: f64,
    /// Wheel spin rate (given or estimated), rad/s.
    pub omega_radps: f64,
    /// Loaded radius Rl, m.
    pub rl_m: f64,
    /// Contact width 2b, m.
    pub contact_width_m: f64,
    /// Residual aligning moment Mzr, N·m.
    pub mzr_nm: f64,
    /// Longitudinal carcass stiffness Cx, N/m.
    pub cx_npm: f64,
    /// Lateral carcass stiffness Cy, N/m.
    pub cy_npm: f64,
    /// Vertical stiffness Cz = Fz/ρ, N/m.
    pub cz_npm: f64,
    /// Cornering stiffness Kyα, N/rad.
    pub kya_nprad: f64,
    /// Longitudinal relaxation length σx, m.
    pub sigmax_m: f64,
    /// Lateral relaxation length σy, m.
    pub sigmay_m: f64,
    /// Longitudinal slip stiffness Kxκ, N.
    pub kxk_n: f64,
    /// Which inputs the limit checks changed.
    pub clamped: Clamped,
}

/// MATLAB-style sign: 0 at 0. Used where the equations use sgn() of a slip quantity.
#[inline(always)]
fn sgn(x: f64) -> f64 {
    if x > 0.0 {
        1.0
    } else if x < 0.0 {
        -1.0
    } else {
        0.0
    }
}

/// Sign that is +1 at 0, for ε terms: keeps `K/(C·D + ε)` finite when D = 0.
#[inline(always)]
fn sgn1(x: f64) -> f64 {
    if x < 0.0 { -1.0 } else { 1.0 }
}

/// cos(atan(x)) without trigonometry.
#[inline(always)]
fn cos_atan(x: f64) -> f64 {
    1.0 / (1.0 + x * x).sqrt()
}

/// The Magic Formula kernel's inner argument: B·x − E·(B·x − atan(B·x)).
#[inline(always)]
fn mf_arg(b: f64, x: f64, e: f64) -> f64 {
    let bx = b * x;
    bx - e * (bx - bx.atan())
}

/// Operating point after limit checks and low-speed handling.
#[derive(Clone, Copy)]
struct Prepared {
    /// Fz used by forces (≥ 0, ≤ FZMAX with limit checks).
    fz: f64,
    /// Fz used by Mz and deflection (raised to FZMIN with limit checks).
    fz_low: f64,
    /// Fz as given (negatives set to 0).
    u_fz: f64,
    kappa: f64,
    kappa_out: f64,
    alpha: f64,
    gamma: f64,
    vcx: f64,
    press: f64,
    /// 1 normally; the cosine ramp below VXLOW with limit checks.
    reduction_smooth: f64,
    clamped: Clamped,
}

#[inline(always)]
fn clamp_flag(v: f64, lo: f64, hi: f64, flag: Clamped, clamped: &mut Clamped) -> f64 {
    if v < lo {
        clamped.insert(flag);
        lo
    } else if v > hi {
        clamped.insert(flag);
        hi
    } else {
        v
    }
}

#[inline(always)]
fn prepare(p: &TyreParams, mode: UseMode, input: &MfInput) -> Prepared {
    let mut clamped = Clamped::empty();
    let u_fz = if input.fz_n < 0.0 {
        clamped.insert(Clamped::FZ);
        0.0
    } else {
        input.fz_n
    };
    if input.phit_per_m != 0.0 {
        clamped.insert(Clamped::PHIT_IGNORED);
    }
    let vcx = input.vx_mps;
    let mut kappa = input.kappa;
    let mut kappa_out = kappa;
    let mut alpha = input.alpha_rad;
    let mut gamma = input.gamma_rad;
    let mut press = if input.p_pa == 0.0 { p.operating.inflpres } else { input.p_pa };
    let mut fz = u_fz;
    let mut fz_low = u_fz;
    let mut reduction_smooth = 1.0;

    if mode.limits_check() {
        let vxlow = p.model.vxlow;
        if vxlow > 0.0 {
            if vcx.abs() <= vxlow {
                clamped.insert(Clamped::LOW_SPEED);
                let ratio = vcx / vxlow;
                // Shifts fade in with a cosine ramp and slip with a linear one, so forces go
                // smoothly to zero at standstill instead of through the 0/0 of slip.
                reduction_smooth = 1.0 - 0.5 * (1.0 + (PI * ratio).cos());
                kappa *= ratio.abs();
                kappa_out *= ratio.abs();
            }
            // The side-slip speed only matters when the forward speed is already below VXLOW.
            if vcx.abs() < vxlow {
                let speed_sum = vcx.abs() + (alpha.tan() * vcx).abs();
                if speed_sum < vxlow {
                    alpha *= speed_sum / vxlow;
                }
            }
        }
        let l = &p.limits;
        alpha = clamp_flag(alpha, l.alpmin, l.alpmax, Clamped::ALPHA, &mut clamped);
        gamma = clamp_flag(gamma, l.cammin, l.cammax, Clamped::GAMMA, &mut clamped);
        press = clamp_flag(press, l.presmin, l.presmax, Clamped::PRESSURE, &mut clamped);
        kappa = clamp_flag(kappa, l.kpumin, l.kpumax, Clamped::KAPPA, &mut clamped);
        if fz > l.fzmax {
            clamped.insert(Clamped::FZ);
            fz = l.fzmax;
        }
        fz_low = if fz < l.fzmin {
            clamped.insert(Clamped::FZ);
            l.fzmin
        } else {
            fz
        };
        if u_fz <= 0.0 {
            fz_low = 0.0;
        }
    }
    Prepared { fz, fz_low, u_fz, kappa, kappa_out, alpha, gamma, vcx, press, reduction_smooth, clamped }
}

/// Pure longitudinal force terms that depend on the load case only (4.E10–4.E18).
#[derive(Clone, Copy, Default)]
struct FxLoad {
    cx: f64,
    mux: f64,
    dx: f64,
    kxk: f64,
    bx: f64,
    shx: f64,
    svx: f64,
    /// Ex = ex_a·(1 − pex4·sgn κx).
    ex_a: f64,
    pex4: f64,
}

#[inline(always)]
fn fx_load(p: &TyreParams, s: &ScalingFactors, x: &Prepared, dfz: f64, dpi: f64) -> FxLoad {
    let c = &p.pure_fx;
    let pr = &p.pressure;
    let (fz, g) = (x.fz, x.gamma);
    let cx = c.pcx1 * s.lcx;
    let mut mux =
        (c.pdx1 + c.pdx2 * dfz) * (1.0 + pr.ppx3 * dpi + pr.ppx4 * dpi * dpi) * (1.0 - c.pdx3 * g * g) * s.lmux;
    if fz == 0.0 {
        mux = 0.0;
    }
    let dx = mux * fz;
    let kxk = fz * (c.pkx1 + c.pkx2 * dfz) * (c.pkx3 * dfz).exp() * (1.0 + pr.ppx1 * dpi + pr.ppx2 * dpi * dpi) * s.lkx;
    FxLoad {
        cx,
        mux,
        dx,
        kxk,
        bx: kxk / (cx * dx + EPS * sgn1(dx)),
        shx: (c.phx1 + c.phx2 * dfz) * s.lhx * x.reduction_smooth,
        svx: fz * (c.pvx1 + c.pvx2 * dfz) * s.lvx * s.lmux * x.reduction_smooth,
        ex_a: (c.pex1 + c.pex2 * dfz + c.pex3 * dfz * dfz) * s.lex,
        pex4: c.pex4,
    }
}

/// Pure longitudinal force (4.E9) at slip κ from its load-case terms.
#[inline(always)]
fn fx_kernel(f: &FxLoad, mode: UseMode, kappa: f64, vcx: f64) -> f64 {
    let kx = kappa + f.shx;
    let mut ex = f.ex_a * (1.0 - f.pex4 * sgn(kx));
    if mode.limits_check() && ex > 1.0 {
        ex = 1.0;
    }
    let fx0 = f.dx * (f.cx * mf_arg(f.bx, kx, ex).atan()).sin() + f.svx;
    if vcx < 0.0 { -fx0 } else { fx0 }
}

/// Pure lateral force terms that depend on the load case only (4.E20–4.E30).
#[derive(Clone, Copy, Default)]
struct FyLoad {
    kya: f64,
    shy: f64,
    svy: f64,
    cy: f64,
    muy: f64,
    dy: f64,
    by: f64,
    /// Ey = ey_a·(ey_b − ey_c·sgn αy).
    ey_a: f64,
    ey_b: f64,
    ey_c: f64,
}

/// Everything that depends only on the load case — Fz, pressure, camber and the low-speed
/// factor — for one parameter set, scaling and mode. A sweep shares one load case across all its
/// points, so batches compute this once per run of equal load cases.
#[derive(Clone, Copy, Default)]
struct LoadTerms {
    fz0: f64,
    gamma_s: f64,
    // Pure Fx (4.E9–4.E18).
    fx: FxLoad,
    // Pure Fy at γ* and at γ = 0 (the latter for Mz's F'y).
    fy: FyLoad,
    fy_g0: FyLoad,
    // Combined slip (4.E50–4.E67).
    exa: f64,
    bxa_a: f64,
    shyk: f64,
    eyk: f64,
    byk_a: f64,
    dvyk_a: f64,
    // Aligning moment (A54–A60, 4.E31–4.E47).
    kya_p: f64,
    shf: f64,
    sht: f64,
    bt: f64,
    ct: f64,
    dt: f64,
    et_a: f64,
    et_b: f64,
    br: f64,
    dr_a: f64,
    s_a: f64,
    s_fy: f64,
    // Overturning moment: R0·Fz·λMx, the Fy-free part and the QSX4 cosine factor.
    mx_fz_lmx: f64,
    mx_const: f64,
    mx_q4: f64,
    mx_fy_lin: f64,
    // Rolling resistance: −R0·Fz0·λMy·(Fz/Fz0)^QSY7·(p/p0)^QSY8 and the camber term.
    my_scale: f64,
    my_gamma: f64,
    // Radii and stiffnesses.
    deflection_term: f64,
    ext_scale: f64,
    q_fz1: f64,
    a_m: f64,
    b_m: f64,
    cx_carcass: f64,
    cy_carcass: f64,
}

/// Cornering stiffness Kyα (4.E25) at a given γ*.
#[inline(always)]
fn kya(p: &TyreParams, s: &ScalingFactors, fz0p: f64, dpi: f64, fz: f64, gamma_s: f64) -> f64 {
    let c = &p.pure_fy;
    let pr = &p.pressure;
    c.pky1
        * fz0p
        * (1.0 + pr.ppy1 * dpi)
        * (1.0 - c.pky3 * gamma_s.abs())
        * (c.pky4 * ((fz / fz0p) / ((c.pky2 + c.pky5 * gamma_s * gamma_s) * (1.0 + pr.ppy2 * dpi))).atan()).sin()
        * s.lky
}

/// Load-case part of pure Fy at γ* = `gamma_s`.
#[inline(always)]
fn fy_load(p: &TyreParams, s: &ScalingFactors, x: &Prepared, fz0p: f64, dfz: f64, dpi: f64, gamma_s: f64) -> FyLoad {
    let c = &p.pure_fy;
    let pr = &p.pressure;
    let fz = x.fz;
    let kya = kya(p, s, fz0p, dpi, fz, gamma_s);
    let svyg = fz * (c.pvy3 + c.pvy4 * dfz) * gamma_s * s.lkyc * s.lmuy;
    let kyg0 = fz * (c.pky6 + c.pky7 * dfz) * (1.0 + pr.ppy5 * dpi) * s.lkyc;
    let kya_p = kya + EPS * sgn1(kya);
    let shy = ((c.phy1 + c.phy2 * dfz) * s.lhy + (kyg0 * gamma_s - svyg) / kya_p) * x.reduction_smooth;
    let svy = (fz * (c.pvy1 + c.pvy2 * dfz) * s.lvy * s.lmuy + svyg) * x.reduction_smooth;
    let cy = c.pcy1 * s.lcy;
    let muy = (c.pdy1 + c.pdy2 * dfz)
        * (1.0 + pr.ppy3 * dpi + pr.ppy4 * dpi * dpi)
        * (1.0 - c.pdy3 * gamma_s * gamma_s)
        * s.lmuy;
    let dy = muy * fz;
    let by = kya / (cy * dy + EPS * sgn1(dy));
    FyLoad {
        kya,
        shy,
        svy,
        cy,
        muy,
        dy,
        by,
        ey_a: (c.pey1 + c.pey2 * dfz) * s.ley,
        ey_b: 1.0 + c.pey5 * gamma_s * gamma_s,
        ey_c: c.pey3 + c.pey4 * gamma_s,
    }
}

/// Pure lateral force (4.E19) at slip angle α* from its load-case terms.
#[inline(always)]
fn fy_kernel(f: &FyLoad, mode: UseMode, alpha_s: f64, vcx: f64) -> f64 {
    let alphay = alpha_s + f.shy;
    let mut ey = f.ey_a * (f.ey_b - f.ey_c * sgn(alphay));
    if mode.limits_check() && ey > 1.0 {
        ey = 1.0;
    }
    let fy0 = f.dy * (f.cy * mf_arg(f.by, alphay, ey).atan()).sin() + f.svy;
    if mode.alpha_star() && vcx < 0.0 { -fy0 } else { fy0 }
}

/// (Fz/Fz0)^QSY7 · (p/p0)^QSY8 with one exp instead of two powf calls.
#[inline(always)]
pub(crate) fn load_pressure_factor(fz_r: f64, p_r: f64, qsy7: f64, qsy8: f64) -> f64 {
    if fz_r > 0.0 && p_r > 0.0 { (qsy7 * fz_r.ln() + qsy8 * p_r.ln()).exp() } else { fz_r.powf(qsy7) * p_r.powf(qsy8) }
}

impl LoadTerms {
    #[inline(always)]
    fn new(p: &TyreParams, s: &ScalingFactors, mode: UseMode, x: &Prepared) -> Self {
        let fz0 = p.vertical.fnomin;
        let fz0p = fz0 * s.lfzo;
        let fz = x.fz;
        let dfz = (fz - fz0p) / fz0p;
        let nompres = p.operating.nompres;
        let dpi = (x.press - nompres) / nompres;
        let gamma_s = if mode.alpha_star() { x.gamma.sin() } else { x.gamma };
        let g = x.gamma;
        let r0 = p.dimension.unloaded_radius;

        // Pure Fx.
        let fxl = fx_load(p, s, x, dfz, dpi);
        let pr = &p.pressure;

        // Pure Fy; Mz's F'y needs it at γ = 0 as well (4.E32/4.E74).
        let fy = fy_load(p, s, x, fz0p, dfz, dpi, gamma_s);
        let fy_g0 = if gamma_s == 0.0 { fy } else { fy_load(p, s, x, fz0p, dfz, dpi, 0.0) };

        // Combined slip.
        let cb = &p.combined;
        let mut exa = cb.rex1 + cb.rex2 * dfz;
        let mut eyk = cb.rey1 + cb.rey2 * dfz;
        if mode.limits_check() {
            exa = exa.min(1.0);
            eyk = eyk.min(1.0);
        }
        let muy_out = if fz == 0.0 { 0.0 } else { fy.muy };

        // Aligning moment.
        let q = &p.aligning;
        let fz_mz = if fz <= 0.0 {
            0.0
        } else if mode.limits_check() {
            x.fz_low
        } else {
            fz
        };
        let kya_p = fy.kya + EPS * sgn1(fy.kya);
        let shf = fy.shy + fy.svy / kya_p;
        let sht = q.qhz1 + q.qhz2 * dfz + (q.qhz3 + q.qhz4 * dfz) * gamma_s;
        // A58: camber enters Bt through γ (QBZ4·γ + QBZ5·|γ|), not γ*.
        let bt = (q.qbz1 + q.qbz2 * dfz + q.qbz3 * dfz * dfz) * (1.0 + q.qbz4 * g + q.qbz5 * g.abs()) * s.lky / s.lmuy;
        let ct = q.qcz1;
        // A60: QDZ3·γ (signed), not QDZ3·|γ*| as in the book.
        let dt = (q.qdz1 + q.qdz2 * dfz)
            * (1.0 - pr.ppz1 * dpi)
            * (1.0 + q.qdz3 * g + q.qdz4 * g * g)
            * fz_mz
            * (r0 / fz0p)
            * s.ltr;
        let br = q.qbz9 * s.lky / s.lmuy + q.qbz10 * fy.by * fy.cy;
        let dr_a = fz_mz
            * r0
            * ((q.qdz6 + q.qdz7 * dfz) * s.lres
                + ((q.qdz8 + q.qdz9 * dfz) * (1.0 + pr.ppz2 * dpi) + (q.qdz10 + q.qdz11 * dfz) * gamma_s.abs())
                    * gamma_s
                    * s.lkzc)
            * s.lmuy;
        // A56: the moment arm uses the unscaled Fz0.
        let s_a = r0 * (q.ssz1 + (q.ssz3 + q.ssz4 * dfz) * g) * s.ls;
        let s_fy = r0 * q.ssz2 / fz0 * s.ls;

        // Overturning moment (TNO / Besselink form).
        let qx = &p.overturning;
        let mut fz_mx = fz;
        let fzmin = p.limits.fzmin;
        if fzmin > 0.0 && fz_mx < fzmin {
            // Below FZMIN MFeval fades Mx out with (Fz/FZMIN)² rather than clamping.
            fz_mx *= (fz_mx / fzmin) * (fz_mx / fzmin);
        }
        let fzr_mx = fz_mx / fz0;
        let mx_fz_lmx = r0 * fz_mx * s.lmx;
        let mx_const = mx_fz_lmx
            * (qx.qsx1 * s.lvmx - qx.qsx2 * g * (1.0 + pr.ppmx1 * dpi) + qx.qsx10 * (qx.qsx11 * fzr_mx).atan() * g)
            - r0 * s.lmx * fz_mx * qx.qsx12 * g * g.abs();
        let mx_q4 = qx.qsx4 * (qx.qsx5 * ((qx.qsx6 * fzr_mx) * (qx.qsx6 * fzr_mx)).atan()).cos();
        let mx_fy_lin = r0 * s.lmx * (qx.qsx13 + qx.qsx14 * g.abs());

        // Rolling resistance (A48); below FZMIN MFeval scales Fz by Fz/FZMIN.
        let qy = &p.rolling;
        let mut fz_my = x.u_fz;
        if fzmin > 0.0 && fz_my < fzmin {
            fz_my *= fz_my / fzmin;
        }
        let fzr_my = fz_my / fz0;
        let my_scale = -r0 * fz0 * s.lmy * load_pressure_factor(fzr_my, x.press / nompres, qy.qsy7, qy.qsy8);
        let my_gamma = (qy.qsy5 + qy.qsy6 * fzr_my) * g * g;

        // Effective rolling radius (Besselink eq. 7) and deflection coefficients (eq. 4).
        let v = &p.vertical;
        let cz_p = v.vertical_stiffness * (1.0 + v.pfz1 * dpi);
        let ufz_r = x.u_fz / fz0;
        let deflection_term = (fz0 / cz_p) * (v.dreff * (v.breff * ufz_r).atan() + v.freff * ufz_r);
        let q_fz1 = ((v.vertical_stiffness * r0 / fz0).powi(2) - 4.0 * v.q_fz2).max(0.0).sqrt();
        let ext_scale = (1.0 + v.pfz1 * dpi) * fz0;

        // Contact patch (Besselink eqs. 9, 10); with bottoming the rim carries the rest.
        let cp = &p.contact_patch;
        let rim = p.dimension.rim_radius + v.bottom_offst;
        let fz_cp = if r0 - x.u_fz / cz_p < rim { (r0 - rim) * cz_p } else { x.u_fz };
        let n = (fz_cp / (cz_p * r0)).max(0.0);
        let a_m = r0 * (cp.q_ra2 * n + cp.q_ra1 * n.sqrt());
        let b_m = p.dimension.width * (cp.q_rb2 * n + cp.q_rb1 * n.cbrt());

        // Carcass stiffnesses for the relaxation lengths (Besselink eqs. 17–19).
        let st = &p.structural;
        let cx_carcass =
            st.longitudinal_stiffness * (1.0 + st.pcfx1 * dfz + st.pcfx2 * dfz * dfz) * (1.0 + st.pcfx3 * dpi);
        let cy_carcass = st.lateral_stiffness * (1.0 + st.pcfy1 * dfz + st.pcfy2 * dfz * dfz) * (1.0 + st.pcfy3 * dpi);

        LoadTerms {
            fz0,
            gamma_s,
            fx: fxl,
            fy: FyLoad { muy: muy_out, ..fy },
            fy_g0,
            exa,
            bxa_a: (cb.rbx1 + cb.rbx3 * gamma_s * gamma_s) * s.lxal,
            shyk: cb.rhy1 + cb.rhy2 * dfz,
            eyk,
            byk_a: (cb.rby1 + cb.rby4 * gamma_s * gamma_s) * s.lyka,
            dvyk_a: muy_out * fz * (cb.rvy1 + cb.rvy2 * dfz + cb.rvy3 * gamma_s) * s.lvyka * x.reduction_smooth,
            kya_p,
            shf,
            sht,
            bt,
            ct,
            dt,
            et_a: q.qez1 + q.qez2 * dfz + q.qez3 * dfz * dfz,
            et_b: q.qez4 + q.qez5 * gamma_s,
            br,
            dr_a,
            s_a,
            s_fy,
            mx_fz_lmx,
            mx_const,
            mx_q4,
            mx_fy_lin,
            my_scale,
            my_gamma,
            deflection_term,
            ext_scale,
            q_fz1,
            a_m,
            b_m,
            cx_carcass,
            cy_carcass,
        }
    }
}

/// Rolling resistance moment, Besselink 2010 eq. A48, with MFeval's low-speed shaping.
#[inline(always)]
fn my(p: &TyreParams, lt: &LoadTerms, vcx: f64, input_kappa: f64, fx: f64) -> f64 {
    if vcx == 0.0 {
        return 0.0;
    }
    let q = &p.rolling;
    let vr = vcx / p.model.longvl;
    let vr2 = vr * vr;
    let mut m = lt.my_scale * (q.qsy1 + q.qsy2 * (fx / lt.fz0) + q.qsy3 * vr.abs() + q.qsy4 * vr2 * vr2 + lt.my_gamma);
    if vcx < 0.0 {
        m = -m;
    }
    // Near standstill the wheel may spin backwards relative to the road (κ < −1 + VXLOW/|Vx|);
    // MFeval blends My through zero there instead of flipping it abruptly.
    let vxlow = p.model.vxlow;
    let high = vxlow / vcx.abs() - 1.0;
    let low = -1.0 - vxlow - high;
    if input_kappa >= low && input_kappa <= high {
        let red = (std::f64::consts::FRAC_PI_2 * (input_kappa + 1.0)) / (high + 1.0);
        m *= red.sin();
    } else if input_kappa < low {
        m = -m;
    }
    m
}

/// Effective rolling radius and spin rate (Besselink eqs. 1 and 7) → (Re, RΩ, Ω).
#[inline(always)]
fn rolling_radius(p: &TyreParams, lt: &LoadTerms, vcx: f64, input: &MfInput) -> (f64, f64, f64) {
    let v = &p.vertical;
    let r0 = p.dimension.unloaded_radius;
    let k = v.q_v1 * (r0 / p.model.longvl).powi(2);
    let a = r0 * v.q_re0 - lt.deflection_term;
    if input.omega_radps != 0.0 {
        let omega = input.omega_radps;
        let ro = r0 * (v.q_re0 + k * omega * omega);
        return (ro - lt.deflection_term, ro, omega);
    }
    // Ω is unknown: Re = A + R0·k·Ω² with Ω = Vw/Re, Vw = Vx(1 + κ), i.e. the cubic
    // Re³ − A·Re² − R0·k·Vw² = 0. Start from the fixed-point step (Q_V1 is small, so that is
    // already close) and polish with Newton, which converges quadratically.
    let vw = vcx * (1.0 + input.kappa);
    let c = r0 * k * vw * vw;
    let mut re = a;
    if re > 0.0 && c != 0.0 {
        re = a + c / (a * a);
        for _ in 0..3 {
            let f = re * re * re - a * re * re - c;
            let df = 3.0 * re * re - 2.0 * a * re;
            if df == 0.0 {
                break;
            }
            let step = f / df;
            re -= step;
            if step.abs() <= 1e-15 * re.abs() {
                break;
            }
        }
    }
    let omega = if re > 0.0 { vw / re } else { 0.0 };
    let ro = r0 * (v.q_re0 + k * omega * omega);
    (ro - lt.deflection_term, ro, omega)
}

/// Deflection, loaded radius and vertical stiffness (Besselink eq. 4 solved for ρ).
#[inline(always)]
fn deflection(
    p: &TyreParams,
    x: &Prepared,
    lt: &LoadTerms,
    omega: f64,
    r_omega: f64,
    fx: f64,
    fy: f64,
) -> (f64, f64, f64) {
    let v = &p.vertical;
    let r0 = p.dimension.unloaded_radius;
    let fcx = v.q_fcx * fx / lt.fz0;
    let fcy = v.q_fcy * fy / lt.fz0;
    let ext = ((1.0 + v.q_v2 * (r0 / p.model.longvl) * omega.abs() - fcx * fcx - fcy * fcy) * lt.ext_scale)
        .max(f64::MIN_POSITIVE);
    let fz = x.fz_low;
    // Q_FZ2·x² + Q_FZ1·x = Fz/ext with x = ρ/R0; the root in cancellation-free form.
    let c = fz / ext;
    let disc = (lt.q_fz1 * lt.q_fz1 + 4.0 * v.q_fz2 * c).max(0.0);
    let denom = lt.q_fz1 + disc.sqrt();
    let xr = if denom > 0.0 { 2.0 * c / denom } else { 0.0 };
    let mut rho = (xr * r0).max(0.0);
    let rl = (r_omega - rho).max(0.0);
    if fz == 0.0 {
        rho = 1e-6;
    }
    (rho, rl, fz / rho)
}

/// The slip-dependent part of the model for one point, given its load-case terms.
#[inline(always)]
fn eval_point(
    p: &TyreParams,
    s: &ScalingFactors,
    mode: UseMode,
    input: &MfInput,
    x: &Prepared,
    lt: &LoadTerms,
) -> MfOutput {
    let vcx = x.vcx;
    let kappa = x.kappa;
    // One sin/cos pair serves tan α (for V'c and α*) and cos α* (for Dr) in the TNO mode.
    let (sin_alpha, cos_alpha) = x.alpha.sin_cos();
    let tan_alpha = sin_alpha / cos_alpha;
    let (alpha_s, cos_alpha_s) = if mode.alpha_star() {
        let a = tan_alpha * sgn1(vcx);
        (a, a.cos())
    } else {
        (x.alpha, cos_alpha)
    };
    // cos α' = Vcx/V'c (4.E6), V'c = |Vc| + ε.
    let vsy = tan_alpha * vcx.abs();
    let vc = (vcx * vcx + vsy * vsy).sqrt();
    let cos_alpha_p = (vcx / (vc + EPS)).clamp(-1.0, 1.0);

    let fx0 = fx_kernel(&lt.fx, mode, kappa, vcx);

    // Pure Fy at γ* and, for the trail term, at γ = 0.
    let fy0 = fy_kernel(&lt.fy, mode, alpha_s, vcx);
    let fy0_g0 = if lt.gamma_s == 0.0 { fy0 } else { fy_kernel(&lt.fy_g0, mode, alpha_s, vcx) };

    // Aligning-moment slip angles and curvature.
    let alphar = alpha_s + lt.shf;
    let alphat = alpha_s + lt.sht;
    let mut et = lt.et_a * (1.0 + lt.et_b * FRAC_2_PI * (lt.bt * lt.ct * alphat).atan());
    if mode.limits_check() && et > 1.0 {
        et = 1.0;
    }
    let dr = lt.dr_a * sgn(vcx) * cos_alpha_s;

    let (fx, fy, mz, trail, mzr) = if mode.combined() {
        let cb = &p.combined;
        // Gxα = 1 exactly at α* = 0 (numerator and denominator coincide): skip the work.
        let gx = if alpha_s == 0.0 {
            1.0
        } else {
            let bxa = lt.bxa_a * cos_atan(cb.rbx2 * kappa);
            let shxa = cb.rhx1;
            let g0 = (cb.rcx1 * mf_arg(bxa, shxa, lt.exa).atan()).cos();
            (cb.rcx1 * mf_arg(bxa, alpha_s + shxa, lt.exa).atan()).cos() / g0
        };
        // Likewise Gyκ = 1 and SVyκ = 0 at κ = 0.
        let (gy, svyk) = if kappa == 0.0 {
            (1.0, 0.0)
        } else {
            let byk = lt.byk_a * cos_atan(cb.rby2 * (alpha_s - cb.rby3));
            let g0 = (cb.rcy1 * mf_arg(byk, lt.shyk, lt.eyk).atan()).cos();
            let g = (cb.rcy1 * mf_arg(byk, kappa + lt.shyk, lt.eyk).atan()).cos() / g0;
            let svyk = lt.dvyk_a * cos_atan(cb.rvy4 * alpha_s) * (cb.rvy5 * (cb.rvy6 * kappa).atan()).sin();
            (g, svyk)
        };
        let fx = gx * fx0;
        let fy = gy * fy0 + svyk;
        // A54/A55: equivalent slip angles combine α and κ through the slip stiffnesses
        // (identical to αr, αt when κ = 0).
        let (alphar_eq, alphat_eq) = if kappa == 0.0 {
            (alphar, alphat)
        } else {
            let k_ratio = lt.fx.kxk / lt.kya_p * kappa;
            let k2 = k_ratio * k_ratio;
            let tr = alphar.tan();
            let tt = alphat.tan();
            ((tr * tr + k2).sqrt().atan() * sgn(alphar), (tt * tt + k2).sqrt().atan() * sgn(alphat))
        };
        let s_arm = lt.s_a + lt.s_fy * fy;
        let mzr = dr * cos_atan(lt.br * alphar_eq) * x.reduction_smooth;
        let t = lt.dt * (lt.ct * mf_arg(lt.bt, alphat_eq, et).atan()).cos() * cos_alpha_p * s.lfzo * x.reduction_smooth;
        let mz = -t * (gy * fy0_g0) + mzr + s_arm * fx;
        (fx, fy, mz, t, mzr)
    } else {
        let t0 = lt.dt * (lt.ct * mf_arg(lt.bt, alphat, et).atan()).cos() * cos_alpha_p * x.reduction_smooth;
        let mzr0 = dr * cos_atan(lt.br * alphar) * cos_alpha_p * x.reduction_smooth;
        (fx0, fy0, -t0 * fy0_g0 + mzr0, t0, mzr0)
    };

    let qx = &p.overturning;
    let fy_r = fy / lt.fz0;
    let g = x.gamma;
    let mx_nm = lt.mx_const
        + lt.mx_fz_lmx * (qx.qsx3 * fy_r + lt.mx_q4 * (qx.qsx7 * g + qx.qsx8 * (qx.qsx9 * fy_r).atan()).sin())
        + lt.mx_fy_lin * fy;
    let my_nm = my(p, lt, vcx, input.kappa, fx);

    let (re, r_omega, omega) = rolling_radius(p, lt, vcx, input);
    let (rho, rl, cz) = deflection(p, x, lt, omega, r_omega, fx, fy);

    MfOutput {
        fx_n: fx,
        fy_n: fy,
        fz_n: x.u_fz,
        mx_nm,
        my_nm,
        mz_nm: mz,
        kappa: x.kappa_out,
        alpha_rad: input.alpha_rad,
        gamma_rad: input.gamma_rad,
        phit_per_m: input.phit_per_m,
        vx_mps: input.vx_mps,
        p_pa: x.press,
        re_m: re,
        rho_m: rho,
        contact_length_m: 2.0 * lt.a_m,
        trail_m: trail,
        mux: lt.fx.mux,
        muy: lt.fy.muy,
        omega_radps: omega,
        rl_m: rl,
        contact_width_m: 2.0 * lt.b_m,
        mzr_nm: mzr,
        cx_npm: lt.cx_carcass,
        cy_npm: lt.cy_carcass,
        cz_npm: cz,
        kya_nprad: lt.fy.kya,
        sigmax_m: (lt.fx.kxk / lt.cx_carcass).abs(),
        sigmay_m: (lt.fy.kya / lt.cy_carcass).abs(),
        kxk_n: lt.fx.kxk,
        clamped: x.clamped,
    }
}

/// Evaluates the model at one operating point with the file's own scaling factors.
pub fn evaluate(params: &TyreParams, mode: UseMode, input: &MfInput) -> MfOutput {
    evaluate_scaled(params, &params.scaling, mode, input)
}

/// Evaluates the model with `scaling` in place of `params.scaling`, so a simulation can vary
/// grip and stiffness λs per step without copying the parameter set.
pub fn evaluate_scaled(params: &TyreParams, scaling: &ScalingFactors, mode: UseMode, input: &MfInput) -> MfOutput {
    let x = prepare(params, mode, input);
    let lt = LoadTerms::new(params, scaling, mode, &x);
    eval_point(params, scaling, mode, input, &x, &lt)
}

/// Pure lateral force Fy0 only (no combined slip, no moments): the cheapest useful call,
/// for fitting pure-cornering data and for benchmarks.
pub fn pure_fy(params: &TyreParams, mode: UseMode, input: &MfInput) -> f64 {
    let s = &params.scaling;
    let x = prepare(params, mode, input);
    let fz0p = params.vertical.fnomin * s.lfzo;
    let dfz = (x.fz - fz0p) / fz0p;
    let dpi = (x.press - params.operating.nompres) / params.operating.nompres;
    let (alpha_s, gamma_s) = if mode.alpha_star() {
        // tan α as sin/cos, exactly as the full evaluation forms it.
        let (sin_alpha, cos_alpha) = x.alpha.sin_cos();
        (sin_alpha / cos_alpha * sgn1(x.vcx), x.gamma.sin())
    } else {
        (x.alpha, x.gamma)
    };
    let f = fy_load(params, s, &x, fz0p, dfz, dpi, gamma_s);
    fy_kernel(&f, mode, alpha_s, x.vcx)
}

/// Pure longitudinal force Fx0 only.
pub fn pure_fx(params: &TyreParams, mode: UseMode, input: &MfInput) -> f64 {
    let s = &params.scaling;
    let x = prepare(params, mode, input);
    let fz0p = params.vertical.fnomin * s.lfzo;
    let dfz = (x.fz - fz0p) / fz0p;
    let dpi = (x.press - params.operating.nompres) / params.operating.nompres;
    fx_kernel(&fx_load(params, s, &x, dfz, dpi), mode, x.kappa, x.vcx)
}

//! MF-Tyre 6.1 steady-state evaluation (ISO-W axes, SI units), turn slip excluded.
//!
//! Equation numbers refer to Pacejka, *Tire and Vehicle Dynamics*, 3rd ed. (2012), ch. 4
//! ("4.Exx"), and to Besselink, Schmeitz & Pacejka (2010), "An improved Magic Formula/Swift
//! tyre model that can handle inflation pressure changes" ("Axx", "eq. n"). Where the TNO
//! MF-Tyre 6.1.2 solver differs from the book, this follows the choices MFeval documents as
//! TNO-compatible (A_mu = 1, LMUV = 0, signed ε = 1e-6, My per A48, Mz per A54–A60, t × LFZO,
//! F'y = Gyκ(γ)·Fy0(γ = 0), Re/ρ/Cz from Besselink eqs. 1–7).

use std::f64::consts::{FRAC_2_PI, PI};

use crate::fastmath::{Fast, sin_cos};
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
    bx - e * (bx - bx.fatan())
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
                reduction_smooth = 1.0 - 0.5 * (1.0 + (PI * ratio).fcos());
                kappa *= ratio.abs();
                kappa_out *= ratio.abs();
            }
            // The side-slip speed only matters when the forward speed is already below VXLOW.
            if vcx.abs() < vxlow {
                let speed_sum = vcx.abs() + (alpha.ftan() * vcx).abs();
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

/// Quantities shared by all force and moment equations.
#[derive(Clone, Copy)]
struct Basic {
    fz0: f64,
    fz0p: f64,
    dfz: f64,
    dpi: f64,
    alpha_s: f64,
    gamma_s: f64,
    /// cos α' = Vcx/V'c (4.E6).
    cos_alpha_p: f64,
    /// cos α*, for the residual moment's Dr (4.E47).
    cos_alpha_s: f64,
}

#[inline(always)]
fn basic(p: &TyreParams, s: &ScalingFactors, mode: UseMode, x: &Prepared) -> Basic {
    let fz0 = p.vertical.fnomin;
    let fz0p = fz0 * s.lfzo;
    let dfz = (x.fz - fz0p) / fz0p;
    let nompres = p.operating.nompres;
    let dpi = (x.press - nompres) / nompres;
    // One sin/cos pair serves tan α (for V'c and α*) and cos α* (for Dr) in the TNO mode.
    let (sin_alpha, cos_alpha) = sin_cos(x.alpha);
    let tan_alpha = sin_alpha / cos_alpha;
    let (alpha_s, gamma_s, cos_alpha_s) = if mode.alpha_star() {
        let a = tan_alpha * sgn1(x.vcx);
        (a, x.gamma.fsin(), a.fcos())
    } else {
        (x.alpha, x.gamma, cos_alpha)
    };
    let vsy = tan_alpha * x.vcx.abs();
    let vc = (x.vcx * x.vcx + vsy * vsy).sqrt();
    let vc_p = vc + EPS;
    let cos_alpha_p = (x.vcx / vc_p).clamp(-1.0, 1.0);
    Basic { fz0, fz0p, dfz, dpi, alpha_s, gamma_s, cos_alpha_p, cos_alpha_s }
}

/// Pure longitudinal force (4.E9–4.E18) → (Fx0, μx, Kxκ).
#[inline(always)]
fn fx0(p: &TyreParams, s: &ScalingFactors, mode: UseMode, x: &Prepared, b: &Basic) -> (f64, f64, f64) {
    let c = &p.pure_fx;
    let pr = &p.pressure;
    let (dfz, dpi, fz) = (b.dfz, b.dpi, x.fz);
    let cx = c.pcx1 * s.lcx;
    let mut mux = (c.pdx1 + c.pdx2 * dfz)
        * (1.0 + pr.ppx3 * dpi + pr.ppx4 * dpi * dpi)
        * (1.0 - c.pdx3 * x.gamma * x.gamma)
        * s.lmux;
    if fz == 0.0 {
        mux = 0.0;
    }
    let dx = mux * fz;
    let kxk = fz * (c.pkx1 + c.pkx2 * dfz) * (c.pkx3 * dfz).exp() * (1.0 + pr.ppx1 * dpi + pr.ppx2 * dpi * dpi) * s.lkx;
    let bx = kxk / (cx * dx + EPS * sgn1(dx));
    let shx = (c.phx1 + c.phx2 * dfz) * s.lhx * x.reduction_smooth;
    let svx = fz * (c.pvx1 + c.pvx2 * dfz) * s.lvx * s.lmux * x.reduction_smooth;
    let kx = x.kappa + shx;
    let mut ex = (c.pex1 + c.pex2 * dfz + c.pex3 * dfz * dfz) * (1.0 - c.pex4 * sgn(kx)) * s.lex;
    if mode.limits_check() && ex > 1.0 {
        ex = 1.0;
    }
    let mut f = dx * (cx * mf_arg(bx, kx, ex).fatan()).fsin() + svx;
    if x.vcx < 0.0 {
        f = -f;
    }
    (f, mux, kxk)
}

/// Pure lateral force terms (4.E19–4.E30).
#[derive(Clone, Copy)]
struct Fy0Terms {
    fy0: f64,
    muy: f64,
    kya: f64,
    shy: f64,
    svy: f64,
    by: f64,
    cy: f64,
}

/// Cornering stiffness Kyα (4.E25) at a given γ*.
#[inline(always)]
fn kya(p: &TyreParams, s: &ScalingFactors, b: &Basic, fz: f64, gamma_s: f64) -> f64 {
    let c = &p.pure_fy;
    let pr = &p.pressure;
    c.pky1
        * b.fz0p
        * (1.0 + pr.ppy1 * b.dpi)
        * (1.0 - c.pky3 * gamma_s.abs())
        * (c.pky4 * ((fz / b.fz0p) / ((c.pky2 + c.pky5 * gamma_s * gamma_s) * (1.0 + pr.ppy2 * b.dpi))).fatan()).fsin()
        * s.lky
}

/// Pure lateral force at γ* = `gamma_s` with cornering stiffness `kya` already computed.
#[inline(always)]
fn fy0_with(
    p: &TyreParams,
    s: &ScalingFactors,
    mode: UseMode,
    x: &Prepared,
    b: &Basic,
    gamma_s: f64,
    kya: f64,
) -> Fy0Terms {
    let c = &p.pure_fy;
    let pr = &p.pressure;
    let (dfz, dpi, fz) = (b.dfz, b.dpi, x.fz);
    let svyg = fz * (c.pvy3 + c.pvy4 * dfz) * gamma_s * s.lkyc * s.lmuy;
    let kyg0 = fz * (c.pky6 + c.pky7 * dfz) * (1.0 + pr.ppy5 * dpi) * s.lkyc;
    let kya_p = kya + EPS * sgn1(kya);
    let shy = ((c.phy1 + c.phy2 * dfz) * s.lhy + (kyg0 * gamma_s - svyg) / kya_p) * x.reduction_smooth;
    let svy = (fz * (c.pvy1 + c.pvy2 * dfz) * s.lvy * s.lmuy + svyg) * x.reduction_smooth;
    let alphay = b.alpha_s + shy;
    let cy = c.pcy1 * s.lcy;
    let mut muy = (c.pdy1 + c.pdy2 * dfz)
        * (1.0 + pr.ppy3 * dpi + pr.ppy4 * dpi * dpi)
        * (1.0 - c.pdy3 * gamma_s * gamma_s)
        * s.lmuy;
    let dy = muy * fz;
    let mut ey = (c.pey1 + c.pey2 * dfz)
        * (1.0 + c.pey5 * gamma_s * gamma_s - (c.pey3 + c.pey4 * gamma_s) * sgn(alphay))
        * s.ley;
    if mode.limits_check() && ey > 1.0 {
        ey = 1.0;
    }
    let by = kya / (cy * dy + EPS * sgn1(dy));
    let mut fy0 = dy * (cy * mf_arg(by, alphay, ey).fatan()).fsin() + svy;
    if mode.alpha_star() && x.vcx < 0.0 {
        fy0 = -fy0;
    }
    if fz == 0.0 {
        muy = 0.0;
    }
    Fy0Terms { fy0, muy, kya, shy, svy, by, cy }
}

/// Gxα (4.E51–4.E57).
#[inline(always)]
fn gxa(p: &TyreParams, s: &ScalingFactors, mode: UseMode, x: &Prepared, b: &Basic) -> f64 {
    let c = &p.combined;
    let cxa = c.rcx1;
    let mut exa = c.rex1 + c.rex2 * b.dfz;
    if mode.limits_check() && exa > 1.0 {
        exa = 1.0;
    }
    let shxa = c.rhx1;
    let bxa = (c.rbx1 + c.rbx3 * b.gamma_s * b.gamma_s) * cos_atan(c.rbx2 * x.kappa) * s.lxal;
    let alphas = b.alpha_s + shxa;
    let g0 = (cxa * mf_arg(bxa, shxa, exa).fatan()).fcos();
    (cxa * mf_arg(bxa, alphas, exa).fatan()).fcos() / g0
}

/// Gyκ and SVyκ (4.E58–4.E67).
#[inline(always)]
fn gyk(p: &TyreParams, s: &ScalingFactors, mode: UseMode, x: &Prepared, b: &Basic, muy: f64) -> (f64, f64) {
    let c = &p.combined;
    let (dfz, gs, as_) = (b.dfz, b.gamma_s, b.alpha_s);
    let dvyk = muy * x.fz * (c.rvy1 + c.rvy2 * dfz + c.rvy3 * gs) * cos_atan(c.rvy4 * as_);
    let svyk = dvyk * (c.rvy5 * (c.rvy6 * x.kappa).fatan()).fsin() * s.lvyka * x.reduction_smooth;
    let shyk = c.rhy1 + c.rhy2 * dfz;
    let mut eyk = c.rey1 + c.rey2 * dfz;
    if mode.limits_check() && eyk > 1.0 {
        eyk = 1.0;
    }
    let cyk = c.rcy1;
    let byk = (c.rby1 + c.rby4 * gs * gs) * cos_atan(c.rby2 * (as_ - c.rby3)) * s.lyka;
    let kappas = x.kappa + shyk;
    let g0 = (cyk * mf_arg(byk, shyk, eyk).fatan()).fcos();
    let g = (cyk * mf_arg(byk, kappas, eyk).fatan()).fcos() / g0;
    (g, svyk)
}

/// Overturning moment, TNO/Besselink form (includes QSX12–14).
#[inline(always)]
fn mx(p: &TyreParams, s: &ScalingFactors, x: &Prepared, b: &Basic, fy: f64) -> f64 {
    let q = &p.overturning;
    let r0 = p.dimension.unloaded_radius;
    let fz0 = b.fz0;
    let g = x.gamma;
    let mut fz = x.fz;
    let fzmin = p.limits.fzmin;
    if fzmin > 0.0 && fz < fzmin {
        // Below FZMIN MFeval fades Mx out with (Fz/FZMIN)² rather than clamping.
        fz *= (fz / fzmin) * (fz / fzmin);
    }
    let fz_r = fz / fz0;
    let fy_r = fy / fz0;
    r0 * fz
        * s.lmx
        * (q.qsx1 * s.lvmx - q.qsx2 * g * (1.0 + p.pressure.ppmx1 * b.dpi)
            + q.qsx3 * fy_r
            + q.qsx4
                * (q.qsx5 * ((q.qsx6 * fz_r) * (q.qsx6 * fz_r)).fatan()).fcos()
                * (q.qsx7 * g + q.qsx8 * (q.qsx9 * fy_r).fatan()).fsin()
            + q.qsx10 * (q.qsx11 * fz_r).fatan() * g)
        + r0 * s.lmx * (fy * (q.qsx13 + q.qsx14 * g.abs()) - fz * q.qsx12 * g * g.abs())
}

/// (Fz/Fz0)^QSY7 · (p/p0)^QSY8 with one exp instead of two powf calls.
#[inline(always)]
fn load_pressure_factor(fz_r: f64, p_r: f64, qsy7: f64, qsy8: f64) -> f64 {
    if fz_r > 0.0 && p_r > 0.0 {
        (qsy7 * fz_r.ln() + qsy8 * p_r.ln()).exp()
    } else {
        fz_r.powf(qsy7) * p_r.powf(qsy8)
    }
}

/// Rolling resistance moment, Besselink 2010 eq. A48, with MFeval's low-speed shaping.
#[inline(always)]
fn my(p: &TyreParams, s: &ScalingFactors, x: &Prepared, input_kappa: f64, fx: f64) -> f64 {
    let q = &p.rolling;
    let vcx = x.vcx;
    if vcx == 0.0 {
        return 0.0;
    }
    let r0 = p.dimension.unloaded_radius;
    let fz0 = p.vertical.fnomin;
    let v0 = p.model.longvl;
    let mut fz = x.u_fz;
    let fzmin = p.limits.fzmin;
    if fzmin > 0.0 && fz < fzmin {
        fz *= fz / fzmin;
    }
    let vr = vcx / v0;
    let vr2 = vr * vr;
    let g2 = x.gamma * x.gamma;
    let fz_r = fz / fz0;
    let mut m = -r0
        * fz0
        * s.lmy
        * (q.qsy1 + q.qsy2 * (fx / fz0) + q.qsy3 * vr.abs() + q.qsy4 * vr2 * vr2 + (q.qsy5 + q.qsy6 * fz_r) * g2)
        * load_pressure_factor(fz_r, x.press / p.operating.nompres, q.qsy7, q.qsy8);
    if vcx < 0.0 {
        m = -m;
    }
    // Near standstill the wheel may spin backwards relative to the road (κ < −1 + VXLOW/|Vx|);
    // MFeval blends My through zero there instead of flipping it abruptly.
    let vxlow = p.model.vxlow;
    let high = vxlow / vcx.abs() - 1.0;
    let low = -1.0 - vxlow - high;
    if input_kappa >= low && input_kappa <= high {
        let x0 = -1.0;
        let red = (std::f64::consts::FRAC_PI_2 * (input_kappa - x0)) / (high - x0);
        m *= red.fsin();
    } else if input_kappa < low {
        m = -m;
    }
    m
}

/// Aligning-moment terms shared by pure and combined Mz.
#[derive(Clone, Copy)]
struct MzTerms {
    alphar: f64,
    alphat: f64,
    bt: f64,
    ct: f64,
    dt: f64,
    et: f64,
    br: f64,
    dr: f64,
    kya_p: f64,
}

#[inline(always)]
fn mz_terms(p: &TyreParams, s: &ScalingFactors, mode: UseMode, x: &Prepared, b: &Basic, f: &Fy0Terms) -> MzTerms {
    let q = &p.aligning;
    let pr = &p.pressure;
    let r0 = p.dimension.unloaded_radius;
    let (dfz, dpi, gs, as_) = (b.dfz, b.dpi, b.gamma_s, b.alpha_s);
    let g = x.gamma;
    let fz = if x.fz <= 0.0 {
        0.0
    } else if mode.limits_check() {
        x.fz_low
    } else {
        x.fz
    };
    let kya_p = f.kya + EPS * sgn1(f.kya);
    let shf = f.shy + f.svy / kya_p;
    let alphar = as_ + shf;
    let sht = q.qhz1 + q.qhz2 * dfz + (q.qhz3 + q.qhz4 * dfz) * gs;
    let alphat = as_ + sht;
    // A58: camber enters Bt through γ (QBZ4·γ + QBZ5·|γ|), not γ*.
    let bt = (q.qbz1 + q.qbz2 * dfz + q.qbz3 * dfz * dfz) * (1.0 + q.qbz4 * g + q.qbz5 * g.abs()) * s.lky / s.lmuy;
    let ct = q.qcz1;
    // A60: QDZ3·γ (signed), not QDZ3·|γ*| as in the book.
    let dt = (q.qdz1 + q.qdz2 * dfz)
        * (1.0 - pr.ppz1 * dpi)
        * (1.0 + q.qdz3 * g + q.qdz4 * g * g)
        * fz
        * (r0 / b.fz0p)
        * s.ltr;
    let mut et = (q.qez1 + q.qez2 * dfz + q.qez3 * dfz * dfz)
        * (1.0 + (q.qez4 + q.qez5 * gs) * FRAC_2_PI * (bt * ct * alphat).fatan());
    if mode.limits_check() && et > 1.0 {
        et = 1.0;
    }
    let br = q.qbz9 * s.lky / s.lmuy + q.qbz10 * f.by * f.cy;
    let dr = fz
        * r0
        * ((q.qdz6 + q.qdz7 * dfz) * s.lres
            + ((q.qdz8 + q.qdz9 * dfz) * (1.0 + pr.ppz2 * dpi) + (q.qdz10 + q.qdz11 * dfz) * gs.abs()) * gs * s.lkzc)
        * s.lmuy
        * sgn(x.vcx)
        * b.cos_alpha_s;
    MzTerms { alphar, alphat, bt, ct, dt, et, br, dr, kya_p }
}

/// Effective rolling radius and spin rate (Besselink eqs. 1 and 7) → (Re, RΩ, Ω).
#[inline(always)]
fn rolling_radius(p: &TyreParams, x: &Prepared, b: &Basic, input: &MfInput) -> (f64, f64, f64) {
    let v = &p.vertical;
    let r0 = p.dimension.unloaded_radius;
    let v0 = p.model.longvl;
    let fz0 = v.fnomin;
    let cz = v.vertical_stiffness * (1.0 + v.pfz1 * b.dpi);
    let fz_r = x.u_fz / fz0;
    let deflection_term = (fz0 / cz) * (v.dreff * (v.breff * fz_r).fatan() + v.freff * fz_r);
    let r_omega = |omega: f64| {
        let w = omega * r0 / v0;
        r0 * (v.q_re0 + v.q_v1 * w * w)
    };
    if input.omega_radps != 0.0 {
        let omega = input.omega_radps;
        let ro = r_omega(omega);
        return (ro - deflection_term, ro, omega);
    }
    // Ω is unknown: solve Ω = Vx(1 + κ)/Re(Ω) by fixed-point iteration (Re depends on Ω only
    // through the small Q_V1 term, so this converges in a few steps).
    let vx_wheel = x.vcx * (1.0 + input.kappa);
    let mut re = r0 * v.q_re0 - deflection_term;
    let mut omega = 0.0;
    let mut ro = r0 * v.q_re0;
    for _ in 0..30 {
        if re <= 0.0 {
            break;
        }
        omega = vx_wheel / re;
        ro = r_omega(omega);
        let next = ro - deflection_term;
        let done = (next - re).abs() <= 1e-13 * r0;
        re = next;
        if done {
            break;
        }
    }
    (re, ro, omega)
}

/// Deflection, loaded radius and vertical stiffness (Besselink eq. 4 solved for ρ).
#[inline(always)]
fn deflection(p: &TyreParams, x: &Prepared, b: &Basic, omega: f64, r_omega: f64, fx: f64, fy: f64) -> (f64, f64, f64) {
    let v = &p.vertical;
    let r0 = p.dimension.unloaded_radius;
    let fz0 = v.fnomin;
    let cz0 = v.vertical_stiffness;
    let q_fz1 = ((cz0 * r0 / fz0).powi(2) - 4.0 * v.q_fz2).max(0.0).sqrt();
    let fcx = v.q_fcx * fx / fz0;
    let fcy = v.q_fcy * fy / fz0;
    let ext =
        ((1.0 + v.q_v2 * (r0 / p.model.longvl) * omega.abs() - fcx * fcx - fcy * fcy) * (1.0 + v.pfz1 * b.dpi) * fz0)
            .max(f64::MIN_POSITIVE);
    let fz = x.fz_low;
    // Q_FZ2·x² + Q_FZ1·x = Fz/ext with x = ρ/R0; the root in cancellation-free form.
    let c = fz / ext;
    let disc = (q_fz1 * q_fz1 + 4.0 * v.q_fz2 * c).max(0.0);
    let denom = q_fz1 + disc.sqrt();
    let xr = if denom > 0.0 { 2.0 * c / denom } else { 0.0 };
    let mut rho = (xr * r0).max(0.0);
    let rl = (r_omega - rho).max(0.0);
    if fz == 0.0 {
        rho = 1e-6;
    }
    (rho, rl, fz / rho)
}

/// Contact patch half length a and half width b (Besselink eqs. 9, 10).
#[inline(always)]
fn contact_patch(p: &TyreParams, x: &Prepared, b: &Basic) -> (f64, f64) {
    let v = &p.vertical;
    let cp = &p.contact_patch;
    let r0 = p.dimension.unloaded_radius;
    let ncz = v.vertical_stiffness * (1.0 + v.pfz1 * b.dpi);
    // With bottoming the rim carries the load beyond this deflection.
    let room = r0 - p.dimension.rim_radius - v.bottom_offst;
    let fz = if r0 - x.u_fz / ncz < p.dimension.rim_radius + v.bottom_offst { room * ncz } else { x.u_fz };
    let n = (fz / (ncz * r0)).max(0.0);
    let a = r0 * (cp.q_ra2 * n + cp.q_ra1 * n.sqrt());
    let bw = p.dimension.width * (cp.q_rb2 * n + cp.q_rb1 * n.cbrt());
    (a, bw)
}

/// Evaluates the model at one operating point with the file's own scaling factors.
pub fn evaluate(params: &TyreParams, mode: UseMode, input: &MfInput) -> MfOutput {
    evaluate_scaled(params, &params.scaling, mode, input)
}

/// Evaluates the model with `scaling` in place of `params.scaling`, so a simulation can vary
/// grip and stiffness λs per step without copying the parameter set.
pub fn evaluate_scaled(params: &TyreParams, scaling: &ScalingFactors, mode: UseMode, input: &MfInput) -> MfOutput {
    let p = params;
    let s = scaling;
    let x = prepare(p, mode, input);
    let b = basic(p, s, mode, &x);

    let (fx0, mux, kxk) = fx0(p, s, mode, &x, &b);
    let kya_full = kya(p, s, &b, x.fz, b.gamma_s);
    let fy0 = fy0_with(p, s, mode, &x, &b, b.gamma_s, kya_full);
    // Mz's pneumatic-trail term uses Fy0 at γ = 0 (4.E32/4.E74); reuse when γ* is 0 already.
    let fy0_g0 = if b.gamma_s == 0.0 {
        fy0.fy0
    } else {
        let k0 = kya(p, s, &b, x.fz, 0.0);
        fy0_with(p, s, mode, &x, &b, 0.0, k0).fy0
    };
    let mzt = mz_terms(p, s, mode, &x, &b, &fy0);

    let (fx, fy, mz, trail, mzr) = if mode.combined() {
        let gx = gxa(p, s, mode, &x, &b);
        let (gy, svyk) = gyk(p, s, mode, &x, &b, fy0.muy);
        let fx = gx * fx0;
        let fy = gy * fy0.fy0 + svyk;
        // A54/A55: equivalent slip angles combine α and κ through the slip stiffnesses.
        let k_ratio = kxk / mzt.kya_p * x.kappa;
        let k2 = k_ratio * k_ratio;
        let tr = mzt.alphar.ftan();
        let tt = mzt.alphat.ftan();
        let alphar_eq = (tr * tr + k2).sqrt().fatan() * sgn(mzt.alphar);
        let alphat_eq = (tt * tt + k2).sqrt().fatan() * sgn(mzt.alphat);
        let q = &p.aligning;
        let r0 = p.dimension.unloaded_radius;
        // A56: s uses the unscaled Fz0.
        let s_arm = r0 * (q.ssz1 + q.ssz2 * (fy / b.fz0) + (q.ssz3 + q.ssz4 * b.dfz) * x.gamma) * s.ls;
        let mzr = mzt.dr * cos_atan(mzt.br * alphar_eq) * x.reduction_smooth;
        let fy_p = gy * fy0_g0;
        let t = mzt.dt
            * (mzt.ct * mf_arg(mzt.bt, alphat_eq, mzt.et).fatan()).fcos()
            * b.cos_alpha_p
            * s.lfzo
            * x.reduction_smooth;
        let mz = -t * fy_p + mzr + s_arm * fx;
        (fx, fy, mz, t, mzr)
    } else {
        let t0 =
            mzt.dt * (mzt.ct * mf_arg(mzt.bt, mzt.alphat, mzt.et).fatan()).fcos() * b.cos_alpha_p * x.reduction_smooth;
        let mzr0 = mzt.dr * cos_atan(mzt.br * mzt.alphar) * b.cos_alpha_p * x.reduction_smooth;
        let mz0 = -t0 * fy0_g0 + mzr0;
        (fx0, fy0.fy0, mz0, t0, mzr0)
    };

    let mx_nm = mx(p, s, &x, &b, fy);
    let my_nm = my(p, s, &x, input.kappa, fx);

    let (re, r_omega, omega) = rolling_radius(p, &x, &b, input);
    let (rho, rl, cz) = deflection(p, &x, &b, omega, r_omega, fx, fy);
    let (a, bw) = contact_patch(p, &x, &b);

    let st = &p.structural;
    let cx = st.longitudinal_stiffness * (1.0 + st.pcfx1 * b.dfz + st.pcfx2 * b.dfz * b.dfz) * (1.0 + st.pcfx3 * b.dpi);
    let cy = st.lateral_stiffness * (1.0 + st.pcfy1 * b.dfz + st.pcfy2 * b.dfz * b.dfz) * (1.0 + st.pcfy3 * b.dpi);

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
        contact_length_m: 2.0 * a,
        trail_m: trail,
        mux,
        muy: fy0.muy,
        omega_radps: omega,
        rl_m: rl,
        contact_width_m: 2.0 * bw,
        mzr_nm: mzr,
        cx_npm: cx,
        cy_npm: cy,
        cz_npm: cz,
        kya_nprad: fy0.kya,
        sigmax_m: (kxk / cx).abs(),
        sigmay_m: (fy0.kya / cy).abs(),
        kxk_n: kxk,
        clamped: x.clamped,
    }
}

/// Pure lateral force Fy0 only (no combined slip, no moments): the cheapest useful call,
/// for fitting pure-cornering data and for benchmarks.
pub fn pure_fy(params: &TyreParams, mode: UseMode, input: &MfInput) -> f64 {
    let s = &params.scaling;
    let x = prepare(params, mode, input);
    let b = basic(params, s, mode, &x);
    let k = kya(params, s, &b, x.fz, b.gamma_s);
    fy0_with(params, s, mode, &x, &b, b.gamma_s, k).fy0
}

/// Pure longitudinal force Fx0 only.
pub fn pure_fx(params: &TyreParams, mode: UseMode, input: &MfInput) -> f64 {
    let s = &params.scaling;
    let x = prepare(params, mode, input);
    let b = basic(params, s, mode, &x);
    fx0(params, s, mode, &x, &b).0
}

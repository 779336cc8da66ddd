//! The lane-wise batch kernel: the model of `model.rs` evaluated for [`L`] points at once.
//!
//! Every function here is a line-by-line transcription of its scalar counterpart in `model.rs`
//! (same names, same order of operations), with branches on the point's values turned into
//! per-lane selects and libm calls replaced by the lane functions of `lanes.rs`. Branches that
//! only skip work whose result the scalar code also skips (κ = 0, α* = 0, γ* = 0, low speed) are
//! taken per chunk, when every lane agrees. Divisions by parameter constants become
//! multiplications by reciprocals computed once per batch ([`Kernel`]). Results therefore match
//! [`crate::evaluate`] to a few ulp (`tests/batch.rs` checks ≤ 1e-13 relative in all eight modes;
//! measured ≤ 2.2e-14); the scalar model remains the readable reference. A chunk in which some
//! lane leaves the lane functions' fast ranges is evaluated by the scalar model.

use std::f64::consts::{FRAC_2_PI, FRAC_PI_2, PI};

use crate::lanes::{Guard, L, M, V, sel};
use crate::model::{Clamped, MfInput, MfOutput, UseMode, evaluate_scaled, load_pressure_factor, pure_fy};
use crate::params::{ScalingFactors, TyreParams};

const EPS: f64 = 1e-6;

/// Which outputs a kernel instance computes: a bit mask, a const parameter of [`eval_points`],
/// so each variant compiles to only the work its outputs need (a fit of one channel calls the
/// model thousands of times and needs one column). Outputs outside the mask read as 0.
pub(crate) mod want {
    /// Fx (combined Fx in combined modes).
    pub const FX: u32 = 1;
    /// Fy.
    pub const FY: u32 = 2;
    /// Mz, trail and Mzr.
    pub const MZ: u32 = 4;
    /// Mx.
    pub const MX: u32 = 8;
    /// My.
    pub const MY: u32 = 16;
    /// Re, Ω, loaded radius, deflection and vertical stiffness (the deflection needs Fx and Fy).
    pub const RADII: u32 = 32;
    /// Re and Ω only (the rolling radius needs no forces).
    pub const RE: u32 = 64;
    /// Every output: the full evaluation.
    pub const ALL: u32 = FX | FY | MZ | MX | MY | RADII | RE;
    /// Only the terms that depend on the load case (Cx, Cy, σx, σy, Kxκ, Kyα, μ, contact patch).
    pub const LOAD_ONLY: u32 = 0;
}

/// One chunk of inputs, one lane per point.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Inputs {
    pub fz: V,
    pub kappa: V,
    pub alpha: V,
    pub gamma: V,
    pub phit: V,
    pub vx: V,
    pub p: V,
    pub omega: V,
}

impl Inputs {
    /// Lane `i` as a scalar input (for the scalar fallbacks).
    fn point(&self, i: usize) -> MfInput {
        MfInput {
            fz_n: self.fz.0[i],
            kappa: self.kappa.0[i],
            alpha_rad: self.alpha.0[i],
            gamma_rad: self.gamma.0[i],
            phit_per_m: self.phit.0[i],
            vx_mps: self.vx.0[i],
            p_pa: self.p.0[i],
            omega_radps: self.omega.0[i],
        }
    }
}

/// One chunk of outputs (the fields of `MfOutput`, one lane per point).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Outputs {
    pub fx_n: V,
    pub fy_n: V,
    pub fz_n: V,
    pub mx_nm: V,
    pub my_nm: V,
    pub mz_nm: V,
    pub kappa: V,
    pub alpha_rad: V,
    pub gamma_rad: V,
    pub phit_per_m: V,
    pub vx_mps: V,
    pub p_pa: V,
    pub re_m: V,
    pub rho_m: V,
    pub contact_length_m: V,
    pub trail_m: V,
    pub mux: V,
    pub muy: V,
    pub omega_radps: V,
    pub rl_m: V,
    pub contact_width_m: V,
    pub mzr_nm: V,
    pub cx_npm: V,
    pub cy_npm: V,
    pub cz_npm: V,
    pub kya_nprad: V,
    pub sigmax_m: V,
    pub sigmay_m: V,
    pub kxk_n: V,
    pub clamped: [Clamped; L],
}

/// The parameter set, scaling, mode and everything that depends on them only, computed once
/// per batch.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Kernel<'a> {
    p: &'a TyreParams,
    s: &'a ScalingFactors,
    mode: UseMode,
    limits: bool,
    star: bool,
    combined: bool,
    fz0: f64,
    fz0p: f64,
    nompres: f64,
    r0: f64,
    /// R0·k with k = Q_V1·(R0/LONGVL)² (rolling radius).
    k_omega: f64,
    /// Q_V2·R0/LONGVL (deflection).
    qv2_r0_v: f64,
    q_fz1: f64,
    fzmin: f64,
    // Reciprocals of parameter constants: the kernel multiplies where the scalar model divides
    // (one extra rounding, well inside the 1e-13 agreement; divisions are the slowest lane op).
    inv_fz0: f64,
    inv_fz0p: f64,
    inv_nompres: f64,
    inv_fzmin: f64,
    inv_longvl: f64,
    /// λKy/λμy (Bt).
    lky_lmuy: f64,
}

impl<'a> Kernel<'a> {
    pub(crate) fn new(p: &'a TyreParams, s: &'a ScalingFactors, mode: UseMode) -> Self {
        let v = &p.vertical;
        let r0 = p.dimension.unloaded_radius;
        let fz0 = v.fnomin;
        Kernel {
            p,
            s,
            mode,
            limits: mode.limits_check(),
            star: mode.alpha_star(),
            combined: mode.combined(),
            fz0,
            fz0p: fz0 * s.lfzo,
            nompres: p.operating.nompres,
            r0,
            k_omega: v.q_v1 * (r0 / p.model.longvl).powi(2),
            qv2_r0_v: v.q_v2 * (r0 / p.model.longvl),
            q_fz1: ((v.vertical_stiffness * r0 / fz0).powi(2) - 4.0 * v.q_fz2).max(0.0).sqrt(),
            fzmin: p.limits.fzmin,
            inv_fz0: 1.0 / fz0,
            inv_fz0p: 1.0 / (fz0 * s.lfzo),
            inv_nompres: 1.0 / p.operating.nompres,
            inv_fzmin: 1.0 / p.limits.fzmin,
            inv_longvl: 1.0 / p.model.longvl,
            lky_lmuy: s.lky / s.lmuy,
        }
    }
}

#[inline(always)]
fn sgn(x: V) -> V {
    sel(x.gt(0.0), 1.0, sel(x.lt(0.0), -1.0, 0.0))
}

#[inline(always)]
fn sgn1(x: V) -> V {
    sel(x.lt(0.0), -1.0, 1.0)
}

#[inline(always)]
fn cos_atan(x: V) -> V {
    1.0 / (1.0 + x * x).sqrt()
}

#[inline(always)]
fn mf_arg<const F: bool>(gd: &Guard<F>, b: V, x: V, e: V) -> V {
    let bx = b * x;
    bx - e * (bx - gd.atan(bx))
}

/// Flags per lane.
#[derive(Clone, Copy)]
struct Flags([u8; L]);

impl Flags {
    #[inline(always)]
    fn set(&mut self, m: M, f: Clamped) {
        for i in 0..L {
            self.0[i] |= if m.0[i] { f.bits() } else { 0 };
        }
    }
}

/// `clamp_flag` of model.rs per lane.
#[inline(always)]
fn clamp_flag(v: V, lo: f64, hi: f64, flag: Clamped, flags: &mut Flags) -> V {
    let below = v.lt(lo);
    let above = v.gt(hi);
    flags.set(below | above, flag);
    sel(below, lo, sel(above, hi, v))
}

#[derive(Clone, Copy)]
struct Prepared {
    fz: V,
    fz_low: V,
    u_fz: V,
    kappa: V,
    kappa_out: V,
    alpha: V,
    gamma: V,
    vcx: V,
    press: V,
    reduction_smooth: V,
    flags: Flags,
}

#[inline(always)]
fn prepare<const F: bool>(k: &Kernel<'_>, gd: &Guard<F>, input: &Inputs) -> Prepared {
    let p = k.p;
    let mut flags = Flags([0; L]);
    let neg = input.fz.lt(0.0);
    flags.set(neg, Clamped::FZ);
    let u_fz = sel(neg, 0.0, input.fz);
    flags.set(input.phit.ne(0.0), Clamped::PHIT_IGNORED);
    let vcx = input.vx;
    let mut kappa = input.kappa;
    let mut kappa_out = kappa;
    let mut alpha = input.alpha;
    let mut gamma = input.gamma;
    let mut press = sel(input.p.eq(0.0), p.operating.inflpres, input.p);
    let mut fz = u_fz;
    let mut fz_low = u_fz;
    let mut reduction_smooth = V::splat(1.0);

    if k.limits {
        let vxlow = p.model.vxlow;
        if vxlow > 0.0 {
            let low = vcx.abs().le(vxlow);
            if low.any() {
                flags.set(low, Clamped::LOW_SPEED);
                let ratio = vcx / vxlow;
                reduction_smooth = sel(low, 1.0 - 0.5 * (1.0 + gd.cos(PI * ratio)), 1.0);
                kappa = sel(low, kappa * ratio.abs(), kappa);
                kappa_out = sel(low, kappa_out * ratio.abs(), kappa_out);
            }
            let below = vcx.abs().lt(vxlow);
            if below.any() {
                let (sa, ca) = gd.sin_cos(alpha);
                let speed_sum = vcx.abs() + ((sa / ca) * vcx).abs();
                alpha = sel(below & speed_sum.lt(vxlow), alpha * speed_sum / vxlow, alpha);
            }
        }
        let l = &p.limits;
        alpha = clamp_flag(alpha, l.alpmin, l.alpmax, Clamped::ALPHA, &mut flags);
        gamma = clamp_flag(gamma, l.cammin, l.cammax, Clamped::GAMMA, &mut flags);
        press = clamp_flag(press, l.presmin, l.presmax, Clamped::PRESSURE, &mut flags);
        kappa = clamp_flag(kappa, l.kpumin, l.kpumax, Clamped::KAPPA, &mut flags);
        let over = fz.gt(l.fzmax);
        flags.set(over, Clamped::FZ);
        fz = sel(over, l.fzmax, fz);
        let under = fz.lt(l.fzmin);
        flags.set(under, Clamped::FZ);
        fz_low = sel(under, l.fzmin, fz);
        fz_low = sel(u_fz.le(0.0), 0.0, fz_low);
    }
    Prepared { fz, fz_low, u_fz, kappa, kappa_out, alpha, gamma, vcx, press, reduction_smooth, flags }
}

#[derive(Clone, Copy)]
struct FxLoad {
    cx: f64,
    mux: V,
    dx: V,
    kxk: V,
    bx: V,
    shx: V,
    svx: V,
    ex_a: V,
    pex4: f64,
}

#[inline(always)]
fn fx_load<const F: bool>(k: &Kernel<'_>, gd: &Guard<F>, x: &Prepared, dfz: V, dpi: V) -> FxLoad {
    let (p, s) = (k.p, k.s);
    let c = &p.pure_fx;
    let pr = &p.pressure;
    let (fz, g) = (x.fz, x.gamma);
    let cx = c.pcx1 * s.lcx;
    let mux = (c.pdx2 * dfz + c.pdx1) * (1.0 + pr.ppx3 * dpi + pr.ppx4 * dpi * dpi) * (1.0 - c.pdx3 * g * g) * s.lmux;
    let mux = sel(fz.eq(0.0), 0.0, mux);
    let dx = mux * fz;
    let kxk = fz * (c.pkx2 * dfz + c.pkx1) * gd.exp(c.pkx3 * dfz) * (1.0 + pr.ppx1 * dpi + pr.ppx2 * dpi * dpi) * s.lkx;
    FxLoad {
        cx,
        mux,
        dx,
        kxk,
        bx: kxk / (cx * dx + EPS * sgn1(dx)),
        shx: (c.phx2 * dfz + c.phx1) * s.lhx * x.reduction_smooth,
        svx: fz * (c.pvx2 * dfz + c.pvx1) * s.lvx * s.lmux * x.reduction_smooth,
        ex_a: (c.pex1 + c.pex2 * dfz + c.pex3 * dfz * dfz) * s.lex,
        pex4: c.pex4,
    }
}

#[inline(always)]
fn fx_kernel<const F: bool>(k: &Kernel<'_>, gd: &Guard<F>, f: &FxLoad, kappa: V, vcx: V) -> V {
    let kx = kappa + f.shx;
    let mut ex = f.ex_a * (1.0 - f.pex4 * sgn(kx));
    if k.limits {
        ex = sel(ex.gt(1.0), 1.0, ex);
    }
    let fx0 = f.dx * gd.sin(f.cx * gd.atan(mf_arg(gd, f.bx, kx, ex))) + f.svx;
    sel(vcx.lt(0.0), -fx0, fx0)
}

#[derive(Clone, Copy)]
struct FyLoad {
    kya: V,
    shy: V,
    svy: V,
    cy: f64,
    muy: V,
    dy: V,
    by: V,
    ey_a: V,
    ey_b: V,
    ey_c: V,
}

#[inline(always)]
fn kya<const F: bool>(k: &Kernel<'_>, gd: &Guard<F>, dpi: V, fz: V, gamma_s: V) -> V {
    let (p, s) = (k.p, k.s);
    let c = &p.pure_fy;
    let pr = &p.pressure;
    c.pky1
        * k.fz0p
        * (1.0 + pr.ppy1 * dpi)
        * (1.0 - c.pky3 * gamma_s.abs())
        * gd.sin(c.pky4 * gd.atan((fz * k.inv_fz0p) / ((c.pky2 + c.pky5 * gamma_s * gamma_s) * (1.0 + pr.ppy2 * dpi))))
        * s.lky
}

#[inline(always)]
fn fy_load<const F: bool>(k: &Kernel<'_>, gd: &Guard<F>, x: &Prepared, dfz: V, dpi: V, gamma_s: V) -> FyLoad {
    let (p, s) = (k.p, k.s);
    let c = &p.pure_fy;
    let pr = &p.pressure;
    let fz = x.fz;
    let kya = kya(k, gd, dpi, fz, gamma_s);
    let svyg = fz * (c.pvy4 * dfz + c.pvy3) * gamma_s * s.lkyc * s.lmuy;
    let kyg0 = fz * (c.pky7 * dfz + c.pky6) * (1.0 + pr.ppy5 * dpi) * s.lkyc;
    let kya_p = kya + EPS * sgn1(kya);
    let shy = ((c.phy2 * dfz + c.phy1) * s.lhy + (kyg0 * gamma_s - svyg) / kya_p) * x.reduction_smooth;
    let svy = (fz * (c.pvy2 * dfz + c.pvy1) * s.lvy * s.lmuy + svyg) * x.reduction_smooth;
    let cy = c.pcy1 * s.lcy;
    let muy = (c.pdy2 * dfz + c.pdy1)
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
        ey_a: (c.pey2 * dfz + c.pey1) * s.ley,
        ey_b: 1.0 + c.pey5 * gamma_s * gamma_s,
        ey_c: c.pey4 * gamma_s + c.pey3,
    }
}

#[inline(always)]
fn fy_kernel<const F: bool>(k: &Kernel<'_>, gd: &Guard<F>, f: &FyLoad, alpha_s: V, vcx: V) -> V {
    let alphay = alpha_s + f.shy;
    let mut ey = f.ey_a * (f.ey_b - f.ey_c * sgn(alphay));
    if k.limits {
        ey = sel(ey.gt(1.0), 1.0, ey);
    }
    let fy0 = f.dy * gd.sin(f.cy * gd.atan(mf_arg(gd, f.by, alphay, ey))) + f.svy;
    if k.star { sel(vcx.lt(0.0), -fy0, fy0) } else { fy0 }
}

/// Load-case terms per lane (`LoadTerms` of model.rs).
#[derive(Clone, Copy)]
pub(crate) struct LoadTerms {
    /// (Fz, Fz_low, uFz, p, γ, low-speed factor) these were computed for.
    key: [V; 6],
    gamma_s: V,
    gamma_s_zero: bool,
    fx: FxLoad,
    fy: FyLoad,
    fy_g0: FyLoad,
    exa: V,
    bxa_a: V,
    shyk: V,
    eyk: V,
    byk_a: V,
    dvyk_a: V,
    kya_p: V,
    shf: V,
    sht: V,
    bt: V,
    ct: f64,
    dt: V,
    et_a: V,
    et_b: V,
    br: V,
    dr_a: V,
    s_a: V,
    s_fy: f64,
    mx_fz_lmx: V,
    mx_const: V,
    mx_q4: V,
    mx_fy_lin: V,
    my_scale: V,
    my_gamma: V,
    deflection_term: V,
    ext_scale: V,
    a_m: V,
    b_m: V,
    cx_carcass: V,
    cy_carcass: V,
}

#[inline(always)]
fn load_key(x: &Prepared) -> [V; 6] {
    [x.fz, x.fz_low, x.u_fz, x.press, x.gamma, x.reduction_smooth]
}

/// True when every lane of `x` has the load case `lt` was computed for.
#[inline(always)]
fn same_load(x: &Prepared, lt: &LoadTerms) -> bool {
    let key = load_key(x);
    (0..6).all(|j| key[j].same_bits(lt.key[j]))
}

#[inline(always)]
fn load_terms<const F: bool>(k: &Kernel<'_>, gd: &Guard<F>, x: &Prepared) -> LoadTerms {
    let (p, s) = (k.p, k.s);
    let fz0 = k.fz0;
    let fz0p = k.fz0p;
    let fz = x.fz;
    let dfz = (fz - fz0p) * k.inv_fz0p;
    let nompres = k.nompres;
    let dpi = (x.press - nompres) * k.inv_nompres;
    let gamma_s = if k.star { gd.sin(x.gamma) } else { x.gamma };
    let g = x.gamma;
    let r0 = k.r0;

    let fxl = fx_load(k, gd, x, dfz, dpi);
    let pr = &p.pressure;

    let fy = fy_load(k, gd, x, dfz, dpi, gamma_s);
    let gamma_s_zero = gamma_s.eq(0.0).all();
    let fy_g0 = if gamma_s_zero { fy } else { fy_load(k, gd, x, dfz, dpi, V::splat(0.0)) };

    let cb = &p.combined;
    let mut exa = cb.rex2 * dfz + cb.rex1;
    let mut eyk = cb.rey2 * dfz + cb.rey1;
    if k.limits {
        exa = exa.min(1.0);
        eyk = eyk.min(1.0);
    }
    let muy_out = sel(fz.eq(0.0), 0.0, fy.muy);

    let q = &p.aligning;
    let fz_mz = sel(fz.le(0.0), 0.0, if k.limits { x.fz_low } else { fz });
    let kya_p = fy.kya + EPS * sgn1(fy.kya);
    let shf = fy.shy + fy.svy / kya_p;
    let sht = q.qhz2 * dfz + q.qhz1 + (q.qhz4 * dfz + q.qhz3) * gamma_s;
    let bt = (q.qbz1 + q.qbz2 * dfz + q.qbz3 * dfz * dfz) * (1.0 + q.qbz4 * g + q.qbz5 * g.abs()) * k.lky_lmuy;
    let ct = q.qcz1;
    let dt = (q.qdz2 * dfz + q.qdz1)
        * (1.0 - pr.ppz1 * dpi)
        * (1.0 + q.qdz3 * g + q.qdz4 * g * g)
        * fz_mz
        * (r0 / fz0p)
        * s.ltr;
    let br = q.qbz10 * fy.by * fy.cy + q.qbz9 * s.lky / s.lmuy;
    let dr_a = fz_mz
        * r0
        * ((q.qdz7 * dfz + q.qdz6) * s.lres
            + ((q.qdz9 * dfz + q.qdz8) * (1.0 + pr.ppz2 * dpi) + (q.qdz11 * dfz + q.qdz10) * gamma_s.abs())
                * gamma_s
                * s.lkzc)
        * s.lmuy;
    let s_a = r0 * ((q.ssz4 * dfz + q.ssz3) * g + q.ssz1) * s.ls;
    let s_fy = r0 * q.ssz2 / fz0 * s.ls;

    let qx = &p.overturning;
    let fzmin = k.fzmin;
    let fz_mx = if fzmin > 0.0 { sel(fz.lt(fzmin), fz * ((fz * k.inv_fzmin) * (fz * k.inv_fzmin)), fz) } else { fz };
    let fzr_mx = fz_mx * k.inv_fz0;
    let mx_fz_lmx = r0 * fz_mx * s.lmx;
    let mx_const = mx_fz_lmx
        * (qx.qsx1 * s.lvmx - qx.qsx2 * g * (1.0 + pr.ppmx1 * dpi) + qx.qsx10 * gd.atan(qx.qsx11 * fzr_mx) * g)
        - r0 * s.lmx * fz_mx * qx.qsx12 * g * g.abs();
    let mx_q4 = qx.qsx4 * gd.cos(qx.qsx5 * gd.atan((qx.qsx6 * fzr_mx) * (qx.qsx6 * fzr_mx)));
    let mx_fy_lin = r0 * s.lmx * (qx.qsx14 * g.abs() + qx.qsx13);

    let qy = &p.rolling;
    let u = x.u_fz;
    let fz_my = if fzmin > 0.0 { sel(u.lt(fzmin), u * (u * k.inv_fzmin), u) } else { u };
    let fzr_my = fz_my * k.inv_fz0;
    let p_r = x.press * k.inv_nompres;
    // (Fz/Fz0)^QSY7·(p/p0)^QSY8 = exp(QSY7·ln + QSY8·ln) where both ratios are positive (every
    // lane in practice); the other lanes take the scalar function's powf branch.
    let pos = fzr_my.gt(0.0) & p_r.gt(0.0);
    let mut lpf = gd.exp(qy.qsy7 * gd.ln(sel(pos, fzr_my, 1.0)) + qy.qsy8 * gd.ln(sel(pos, p_r, 1.0)));
    if !pos.all() {
        for i in 0..L {
            if !pos.0[i] {
                lpf.0[i] = load_pressure_factor(fzr_my.0[i], p_r.0[i], qy.qsy7, qy.qsy8);
            }
        }
    }
    let my_scale = -r0 * fz0 * s.lmy * lpf;
    let my_gamma = (qy.qsy6 * fzr_my + qy.qsy5) * g * g;

    let v = &p.vertical;
    let cz_p = v.vertical_stiffness * (1.0 + v.pfz1 * dpi);
    let ufz_r = x.u_fz * k.inv_fz0;
    let deflection_term = (fz0 / cz_p) * (v.dreff * gd.atan(v.breff * ufz_r) + v.freff * ufz_r);
    let ext_scale = (1.0 + v.pfz1 * dpi) * fz0;

    let cp = &p.contact_patch;
    let rim = p.dimension.rim_radius + v.bottom_offst;
    let fz_cp = sel((r0 - x.u_fz / cz_p).lt(rim), (r0 - rim) * cz_p, x.u_fz);
    let n = (fz_cp / (cz_p * r0)).max(0.0);
    let a_m = r0 * (cp.q_ra2 * n + cp.q_ra1 * n.sqrt());
    let b_m = p.dimension.width * (cp.q_rb2 * n + cp.q_rb1 * gd.cbrt(n));

    let st = &p.structural;
    let cx_carcass = st.longitudinal_stiffness * (1.0 + st.pcfx1 * dfz + st.pcfx2 * dfz * dfz) * (1.0 + st.pcfx3 * dpi);
    let cy_carcass = st.lateral_stiffness * (1.0 + st.pcfy1 * dfz + st.pcfy2 * dfz * dfz) * (1.0 + st.pcfy3 * dpi);

    LoadTerms {
        key: load_key(x),
        gamma_s,
        gamma_s_zero,
        fx: fxl,
        fy: FyLoad { muy: muy_out, ..fy },
        fy_g0,
        exa,
        bxa_a: (cb.rbx3 * gamma_s * gamma_s + cb.rbx1) * s.lxal,
        shyk: cb.rhy2 * dfz + cb.rhy1,
        eyk,
        byk_a: (cb.rby4 * gamma_s * gamma_s + cb.rby1) * s.lyka,
        dvyk_a: muy_out * fz * (cb.rvy1 + cb.rvy2 * dfz + cb.rvy3 * gamma_s) * s.lvyka * x.reduction_smooth,
        kya_p,
        shf,
        sht,
        bt,
        ct,
        dt,
        et_a: q.qez1 + q.qez2 * dfz + q.qez3 * dfz * dfz,
        et_b: q.qez5 * gamma_s + q.qez4,
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
        a_m,
        b_m,
        cx_carcass,
        cy_carcass,
    }
}

#[inline(always)]
fn my<const F: bool>(k: &Kernel<'_>, gd: &Guard<F>, lt: &LoadTerms, vcx: V, input_kappa: V, fx: V) -> V {
    let p = k.p;
    let q = &p.rolling;
    let vr = vcx * k.inv_longvl;
    let vr2 = vr * vr;
    let m = lt.my_scale * (q.qsy1 + q.qsy2 * (fx * k.inv_fz0) + q.qsy3 * vr.abs() + q.qsy4 * vr2 * vr2 + lt.my_gamma);
    let mut m = sel(vcx.lt(0.0), -m, m);
    let vxlow = p.model.vxlow;
    let high = vxlow / vcx.abs() - 1.0;
    let low = -1.0 - vxlow - high;
    let blend = input_kappa.ge(low) & input_kappa.le(high);
    if blend.any() {
        let red = (FRAC_PI_2 * (input_kappa + 1.0)) / (high + 1.0);
        m = sel(blend, m * gd.sin(red), m);
    }
    m = sel(input_kappa.lt(low), -m, m);
    sel(vcx.eq(0.0), 0.0, m)
}

#[inline(always)]
fn rolling_radius(k: &Kernel<'_>, lt: &LoadTerms, vcx: V, input: &Inputs) -> (V, V, V) {
    let v = &k.p.vertical;
    let r0 = k.r0;
    let kk = k.k_omega;
    let a = r0 * v.q_re0 - lt.deflection_term;
    let vw = vcx * (1.0 + input.kappa);
    let c = r0 * kk * vw * vw;
    let mut active = a.gt(0.0) & c.ne(0.0);
    let mut re = sel(active, a + c / (a * a), a);
    for _ in 0..3 {
        if !active.any() {
            break;
        }
        let f = re * re * re - a * re * re - c;
        let df = 3.0 * re * re - 2.0 * a * re;
        active = active & df.ne(0.0);
        let step = f / df;
        re = sel(active, re - step, re);
        active = active & !step.abs().le(1e-15 * re.abs());
    }
    let omega = sel(re.gt(0.0), vw / re, 0.0);
    let omega = sel(input.omega.ne(0.0), input.omega, omega);
    let ro = r0 * (v.q_re0 + kk * omega * omega);
    (ro - lt.deflection_term, ro, omega)
}

#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn deflection(k: &Kernel<'_>, x: &Prepared, lt: &LoadTerms, omega: V, r_omega: V, fx: V, fy: V) -> (V, V, V) {
    let v = &k.p.vertical;
    let r0 = k.r0;
    let fcx = v.q_fcx * fx * k.inv_fz0;
    let fcy = v.q_fcy * fy * k.inv_fz0;
    let ext = ((1.0 + k.qv2_r0_v * omega.abs() - fcx * fcx - fcy * fcy) * lt.ext_scale).max(f64::MIN_POSITIVE);
    let fz = x.fz_low;
    let c = fz / ext;
    let disc = (k.q_fz1 * k.q_fz1 + 4.0 * v.q_fz2 * c).max(0.0);
    let denom = k.q_fz1 + disc.sqrt();
    let xr = sel(denom.gt(0.0), 2.0 * c / denom, 0.0);
    let rho = (xr * r0).max(0.0);
    let rl = (r_omega - rho).max(0.0);
    let rho = sel(fz.eq(0.0), 1e-6, rho);
    (rho, rl, fz / rho)
}

/// The evaluation of one chunk, of the outputs in the mask `W` ([`want`]). `cache` holds the load-case terms of the previous chunk
/// and is reused when every lane has the same load case (sweeps). A chunk in which some lane
/// left the lane functions' fast ranges (huge or non-finite arguments) is evaluated by the
/// scalar model instead.
#[inline(always)]
pub(crate) fn eval_chunk<const F: bool, const W: u32>(
    k: &Kernel<'_>,
    input: &Inputs,
    cache: &mut Option<LoadTerms>,
) -> Outputs {
    let gd = Guard::<F>::default();
    let x = prepare(k, &gd, input);
    let lt = match cache {
        Some(lt) if same_load(&x, lt) => lt,
        _ => cache.insert(load_terms(k, &gd, &x)),
    };
    let out = eval_points::<F, W>(k, &gd, input, &x, lt);
    if gd.any() {
        *cache = None;
        return scalar_chunk(k, input);
    }
    out
}

/// The scalar reference model, lane by lane.
#[cold]
#[inline(never)]
fn scalar_chunk(k: &Kernel<'_>, input: &Inputs) -> Outputs {
    let o: [MfOutput; L] = std::array::from_fn(|i| {
        let x = input.point(i);
        evaluate_scaled(k.p, k.s, k.mode, &x)
    });
    macro_rules! lanes_of {
        ($($f:ident),*) => {
            Outputs { $( $f: V(std::array::from_fn(|i| o[i].$f)), )* clamped: std::array::from_fn(|i| o[i].clamped) }
        };
    }
    crate::batch::for_each_value_column!(lanes_of)
}

/// The aligning-moment terms shared by the pure and the combined branch of [`eval_points`]:
/// (cos α′, αr, αt, Et, Dr). A function, not a closure: closures are not inlined reliably, and
/// an outlined one loses the AVX2/FMA target of the kernel that calls it.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn mz_terms<const F: bool>(
    k: &Kernel<'_>,
    gd: &Guard<F>,
    x: &Prepared,
    lt: &LoadTerms,
    alpha_s: V,
    cos_alpha_s: V,
    tan_alpha: V,
) -> (V, V, V, V, V) {
    let vcx = x.vcx;
    let vsy = tan_alpha * vcx.abs();
    let vc = (vcx * vcx + vsy * vsy).sqrt();
    let cos_alpha_p = (vcx / (vc + EPS)).clamp(-1.0, 1.0);
    let alphar = alpha_s + lt.shf;
    let alphat = alpha_s + lt.sht;
    let mut et = lt.et_a * (1.0 + lt.et_b * FRAC_2_PI * gd.atan(lt.bt * lt.ct * alphat));
    if k.limits {
        et = sel(et.gt(1.0), 1.0, et);
    }
    let dr = lt.dr_a * sgn(vcx) * cos_alpha_s;
    (cos_alpha_p, alphar, alphat, et, dr)
}

#[inline(always)]
fn eval_points<const F: bool, const W: u32>(
    k: &Kernel<'_>,
    gd: &Guard<F>,
    input: &Inputs,
    x: &Prepared,
    lt: &LoadTerms,
) -> Outputs {
    // What the mask needs, following the model's data flow: Mz uses Fx, Fy and Fy(γ = 0); Mx
    // uses Fy; My uses Fx; the loaded radius uses Fx, Fy and the rolling radius.
    let want_mz = W & want::MZ != 0;
    let want_fx = W & (want::FX | want::MZ | want::MY | want::RADII) != 0;
    let want_fy = W & (want::FY | want::MZ | want::MX | want::RADII) != 0;
    let zero = V::splat(0.0);
    let p = k.p;
    let s = k.s;
    let vcx = x.vcx;
    let kappa = x.kappa;
    let (sin_alpha, cos_alpha) = gd.sin_cos(x.alpha);
    let tan_alpha = sin_alpha / cos_alpha;
    let (alpha_s, cos_alpha_s) = if k.star {
        let a = tan_alpha * sgn1(vcx);
        (a, gd.cos(a))
    } else {
        (x.alpha, cos_alpha)
    };

    let fx0 = if want_fx { fx_kernel(k, gd, &lt.fx, kappa, vcx) } else { zero };
    let fy0 = if want_fy { fy_kernel(k, gd, &lt.fy, alpha_s, vcx) } else { zero };
    let fy0_g0 = if !want_mz || lt.gamma_s_zero {
        fy0
    } else {
        sel(lt.gamma_s.eq(0.0), fy0, fy_kernel(k, gd, &lt.fy_g0, alpha_s, vcx))
    };

    let (fx, fy, mz, trail, mzr) = if k.combined {
        let cb = &p.combined;
        let alpha_zero = alpha_s.eq(0.0);
        let gx = if !want_fx || alpha_zero.all() {
            V::splat(1.0)
        } else {
            let bxa = lt.bxa_a * cos_atan(cb.rbx2 * kappa);
            let shxa = V::splat(cb.rhx1);
            let g0 = gd.cos(cb.rcx1 * gd.atan(mf_arg(gd, bxa, shxa, lt.exa)));
            let g = gd.cos(cb.rcx1 * gd.atan(mf_arg(gd, bxa, alpha_s + shxa, lt.exa))) / g0;
            sel(alpha_zero, 1.0, g)
        };
        let kappa_zero = kappa.eq(0.0);
        let all_kappa_zero = kappa_zero.all();
        let (gy, svyk) = if !want_fy || all_kappa_zero {
            (V::splat(1.0), V::splat(0.0))
        } else {
            let byk = lt.byk_a * cos_atan(cb.rby2 * (alpha_s - cb.rby3));
            let g0 = gd.cos(cb.rcy1 * gd.atan(mf_arg(gd, byk, lt.shyk, lt.eyk)));
            let g = gd.cos(cb.rcy1 * gd.atan(mf_arg(gd, byk, kappa + lt.shyk, lt.eyk))) / g0;
            let svyk = lt.dvyk_a * cos_atan(cb.rvy4 * alpha_s) * gd.sin(cb.rvy5 * gd.atan(cb.rvy6 * kappa));
            (sel(kappa_zero, 1.0, g), sel(kappa_zero, 0.0, svyk))
        };
        let fx = gx * fx0;
        let fy = gy * fy0 + svyk;
        if want_mz {
            let (cos_alpha_p, alphar, alphat, et, dr) = mz_terms(k, gd, x, lt, alpha_s, cos_alpha_s, tan_alpha);
            let (alphar_eq, alphat_eq) = if all_kappa_zero {
                (alphar, alphat)
            } else {
                let k_ratio = lt.fx.kxk / lt.kya_p * kappa;
                let k2 = k_ratio * k_ratio;
                let (sr, cr) = gd.sin_cos(alphar);
                let (st, ct) = gd.sin_cos(alphat);
                let tr = sr / cr;
                let tt = st / ct;
                let ar = gd.atan((tr * tr + k2).sqrt()) * sgn(alphar);
                let at = gd.atan((tt * tt + k2).sqrt()) * sgn(alphat);
                (sel(kappa_zero, alphar, ar), sel(kappa_zero, alphat, at))
            };
            let s_arm = lt.s_a + lt.s_fy * fy;
            let mzr = dr * cos_atan(lt.br * alphar_eq) * x.reduction_smooth;
            let t = lt.dt
                * gd.cos(lt.ct * gd.atan(mf_arg(gd, lt.bt, alphat_eq, et)))
                * cos_alpha_p
                * s.lfzo
                * x.reduction_smooth;
            let mz = -t * (gy * fy0_g0) + mzr + s_arm * fx;
            (fx, fy, mz, t, mzr)
        } else {
            (fx, fy, zero, zero, zero)
        }
    } else if want_mz {
        let (cos_alpha_p, alphar, alphat, et, dr) = mz_terms(k, gd, x, lt, alpha_s, cos_alpha_s, tan_alpha);
        let t0 = lt.dt * gd.cos(lt.ct * gd.atan(mf_arg(gd, lt.bt, alphat, et))) * cos_alpha_p * x.reduction_smooth;
        let mzr0 = dr * cos_atan(lt.br * alphar) * cos_alpha_p * x.reduction_smooth;
        (fx0, fy0, -t0 * fy0_g0 + mzr0, t0, mzr0)
    } else {
        (fx0, fy0, zero, zero, zero)
    };

    let mx_nm = if W & want::MX != 0 {
        let qx = &p.overturning;
        let fy_r = fy * k.inv_fz0;
        let g = x.gamma;
        lt.mx_const
            + lt.mx_fz_lmx * (qx.qsx3 * fy_r + lt.mx_q4 * gd.sin(qx.qsx7 * g + qx.qsx8 * gd.atan(qx.qsx9 * fy_r)))
            + lt.mx_fy_lin * fy
    } else {
        zero
    };
    let my_nm = if W & want::MY != 0 { my(k, gd, lt, vcx, input.kappa, fx) } else { zero };

    let (re, r_omega, omega) =
        if W & (want::RADII | want::RE) != 0 { rolling_radius(k, lt, vcx, input) } else { (zero, zero, zero) };
    let (rho, rl, cz) =
        if W & want::RADII != 0 { deflection(k, x, lt, omega, r_omega, fx, fy) } else { (zero, zero, zero) };

    Outputs {
        fx_n: fx,
        fy_n: fy,
        fz_n: x.u_fz,
        mx_nm,
        my_nm,
        mz_nm: mz,
        kappa: x.kappa_out,
        alpha_rad: input.alpha,
        gamma_rad: input.gamma,
        phit_per_m: input.phit,
        vx_mps: input.vx,
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
        clamped: x.flags.0.map(Clamped::from_bits),
    }
}

/// Pure lateral force of one chunk (`pure_fy` of model.rs); as [`eval_chunk`], a chunk that
/// leaves the fast ranges is redone by the scalar function.
#[inline(always)]
pub(crate) fn pure_fy_chunk<const F: bool>(k: &Kernel<'_>, input: &Inputs) -> V {
    let gd = Guard::<F>::default();
    let x = prepare(k, &gd, input);
    let fz0p = k.fz0p;
    let dfz = (x.fz - fz0p) * k.inv_fz0p;
    let dpi = (x.press - k.nompres) * k.inv_nompres;
    let (alpha_s, gamma_s) = if k.star {
        let (sin_alpha, cos_alpha) = gd.sin_cos(x.alpha);
        (sin_alpha / cos_alpha * sgn1(x.vcx), gd.sin(x.gamma))
    } else {
        (x.alpha, x.gamma)
    };
    let f = fy_load(k, &gd, &x, dfz, dpi, gamma_s);
    let fy = fy_kernel(k, &gd, &f, alpha_s, x.vcx);
    if gd.any() {
        return scalar_pure_fy(k, input);
    }
    fy
}

#[cold]
#[inline(never)]
fn scalar_pure_fy(k: &Kernel<'_>, input: &Inputs) -> V {
    V(std::array::from_fn(|i| {
        let x = input.point(i);
        pure_fy(k.p, k.mode, &x)
    }))
}

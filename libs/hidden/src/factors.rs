//! What an effect does to the tyre at one instant — MF scaling factors and a loaded-radius
//! change — and the true tyre evaluated with them.

use mftyre::{MfInput, ScalingFactors, UseMode};
use rigsim::{BrushInput, VirtualTyre};

/// Multiplicative scaling factors (1 = unchanged) and an additive loaded-radius change.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Factors {
    /// λμx.
    pub mux: f64,
    /// λμy.
    pub muy: f64,
    /// λKx.
    pub kx: f64,
    /// λKy.
    pub ky: f64,
    /// λCx.
    pub cx: f64,
    /// λCy.
    pub cy: f64,
    /// LTR and LRES (pneumatic trail and residual aligning moment).
    pub trail: f64,
    /// Loaded radius change [m].
    pub radius_m: f64,
}

impl Factors {
    /// No change.
    pub const NEUTRAL: Factors =
        Factors { mux: 1.0, muy: 1.0, kx: 1.0, ky: 1.0, cx: 1.0, cy: 1.0, trail: 1.0, radius_m: 0.0 };

    /// Two effects at once: factors multiply, radius changes add.
    pub fn and(self, o: Factors) -> Factors {
        Factors {
            mux: self.mux * o.mux,
            muy: self.muy * o.muy,
            kx: self.kx * o.kx,
            ky: self.ky * o.ky,
            cx: self.cx * o.cx,
            cy: self.cy * o.cy,
            trail: self.trail * o.trail,
            radius_m: self.radius_m + o.radius_m,
        }
    }

    /// Leaves the forces alone (only the radius may change).
    pub fn changes_forces(&self) -> bool {
        [self.mux, self.muy, self.kx, self.ky, self.cx, self.cy, self.trail].iter().any(|&f| f != 1.0)
    }
}

/// The run's true tyre: the rig's [`VirtualTyre`] with its file's own scaling.
#[derive(Debug, Clone, Copy)]
pub struct TrueTyre<'a> {
    tyre: &'a VirtualTyre,
}

impl<'a> TrueTyre<'a> {
    /// Wraps the rig's tyre.
    pub fn new(tyre: &'a VirtualTyre) -> Self {
        Self { tyre }
    }

    /// FX, FYW, MZW [N, N, N·m] and the loaded radius [m] at `x` with the effect's factors
    /// applied (ISO-W, use mode 111). An MF tyre takes every factor; the brush tyre has one grip
    /// and one stiffness factor (the means of the longitudinal and lateral ones) and no shape or
    /// trail factor. The radius is the tyre's own: MF-Tyre 6.1's loaded radius follows FX and
    /// FY, so a grip change moves it — the rig measures that, and so must a hidden effect.
    pub fn forces(&self, f: &Factors, x: &MfInput) -> [f64; 4] {
        match self.tyre {
            VirtualTyre::Mf(p) => {
                let s = scaled(&p.scaling, f);
                let o = mftyre::evaluate_scaled(p, &s, UseMode::M111, x);
                [o.fx_n, o.fy_n, o.mz_nm, o.rl_m]
            }
            VirtualTyre::Brush(b) => {
                let o = b.evaluate(&BrushInput {
                    fz_n: x.fz_n,
                    kappa: x.kappa,
                    alpha_rad: x.alpha_rad,
                    gamma_rad: x.gamma_rad,
                    vx_mps: x.vx_mps,
                    p_pa: x.p_pa,
                    grip_factor: 0.5 * (f.mux + f.muy),
                    stiffness_factor: 0.5 * (f.kx + f.ky),
                });
                [o.fx_n, o.fy_n, o.mz_nm, o.rl_m]
            }
        }
    }
}

fn scaled(base: &ScalingFactors, f: &Factors) -> ScalingFactors {
    let mut s = *base;
    s.lmux *= f.mux;
    s.lmuy *= f.muy;
    s.lkx *= f.kx;
    s.lky *= f.ky;
    s.lcx *= f.cx;
    s.lcy *= f.cy;
    s.ltr *= f.trail;
    s.lres *= f.trail;
    s
}

#[cfg(test)]
mod tests {
    use super::*;
    use mftyre::TyreParams;
    use std::path::Path;

    /// MF-Tyre 6.1's loaded radius follows the forces: a hidden grip loss at a large slip angle
    /// must move the radius the rig reports, or the injected log is one no tyre could produce.
    #[test]
    fn a_grip_change_moves_the_mf_tyres_loaded_radius() {
        let tir =
            Path::new(env!("CARGO_MANIFEST_DIR")).join("../../launch-config/tyres/MagicFormula61_Paramerters.tir");
        let tyre = VirtualTyre::from(TyreParams::read_tir(&tir).expect("the shipped MF tyre reads"));
        let truth = TrueTyre::new(&tyre);
        let x = MfInput { fz_n: 4000.0, alpha_rad: 8f64.to_radians(), vx_mps: 16.7, ..MfInput::default() };
        let less_grip = Factors { muy: 0.8, ..Factors::NEUTRAL };
        let (with, without) = (truth.forces(&less_grip, &x), truth.forces(&Factors::NEUTRAL, &x));
        assert!(with[1].abs() < 0.9 * without[1].abs(), "FYW {} vs {}", with[1], without[1]);
        let drl_mm = (with[3] - without[3]) * 1e3;
        assert!(drl_mm.abs() > 0.01, "loaded radius moved by {drl_mm} mm");
    }
}

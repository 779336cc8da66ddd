//! The virtual tyre on the rig: an MF-Tyre 6.1 property file (the default) or a physical brush
//! tyre ([`crate::brush`]), chosen by the rig config's `[tyre] model`.

use mftyre::{MfInput, MfOutput, ScalingFactors, TyreParams, UseMode};

use crate::brush::{BrushInput, BrushParams};
use crate::config::{RigConfig, TyreModel};
use crate::rig::RigError;

/// The tyre model the rig evaluates.
#[derive(Debug, Clone, PartialEq)]
pub enum VirtualTyre {
    /// MF-Tyre 6.1 (use mode 111), from a `.tir` file.
    Mf(Box<TyreParams>),
    /// The physical brush tyre, from a brush parameter file.
    Brush(Box<BrushParams>),
}

impl From<TyreParams> for VirtualTyre {
    fn from(p: TyreParams) -> Self {
        VirtualTyre::Mf(Box::new(p))
    }
}

impl From<BrushParams> for VirtualTyre {
    fn from(p: BrushParams) -> Self {
        VirtualTyre::Brush(Box::new(p))
    }
}

/// One evaluation's inputs, common to both models (ISO-W, SI).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct TyreState {
    pub fz_n: f64,
    pub kappa: f64,
    pub alpha_rad: f64,
    pub gamma_rad: f64,
    pub vx_mps: f64,
    pub p_pa: f64,
    /// Wheel spin rate the MF uses for its speed-dependent radius [rad/s].
    pub omega_radps: f64,
}

/// The rig's effects on the tyre at one instant, as scaling factors.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct TyreScaling {
    /// Friction factor (thermal grip × break-in).
    pub grip: f64,
    /// Stiffness factor (thermal × wear).
    pub stiffness: f64,
    /// MF shape factor λC (wear); the brush tyre has no equivalent.
    pub shape: f64,
}

impl VirtualTyre {
    /// Reads the tyre the config names (`tyre_file`, a `.tir` or a brush file per `[tyre] model`).
    pub fn load(cfg: &RigConfig) -> Result<VirtualTyre, RigError> {
        let path = &cfg.tyre_file;
        match cfg.tyre.model {
            TyreModel::Mf61 => TyreParams::read_tir(path)
                .map(VirtualTyre::from)
                .map_err(|source| RigError::Tyre { path: path.display().to_string(), source }),
            TyreModel::Brush => BrushParams::load(path).map(VirtualTyre::from).map_err(RigError::Brush),
        }
    }

    /// Which model this is.
    pub fn model(&self) -> TyreModel {
        match self {
            VirtualTyre::Mf(_) => TyreModel::Mf61,
            VirtualTyre::Brush(_) => TyreModel::Brush,
        }
    }

    /// Nominal load Fz0 (FNOMIN) [N].
    pub fn fnomin_n(&self) -> f64 {
        match self {
            VirtualTyre::Mf(p) => p.fnomin_n(),
            VirtualTyre::Brush(b) => b.nominal.load_n,
        }
    }

    /// Free radius R0 (UNLOADED_RADIUS) [m].
    pub fn unloaded_radius_m(&self) -> f64 {
        match self {
            VirtualTyre::Mf(p) => p.unloaded_radius_m(),
            VirtualTyre::Brush(b) => b.dimensions.unloaded_radius_m,
        }
    }

    /// Nominal inflation pressure (NOMPRES) [Pa].
    pub fn nominal_pressure_pa(&self) -> f64 {
        match self {
            VirtualTyre::Mf(p) => p.nominal_pressure_pa(),
            VirtualTyre::Brush(b) => b.nominal.pressure_pa,
        }
    }

    /// A name for logs and exports (the `.tir`'s source, the brush file's `name`).
    pub fn name(&self) -> String {
        match self {
            VirtualTyre::Mf(p) => p.source.clone(),
            VirtualTyre::Brush(b) => b.name.clone(),
        }
    }

    /// The MF parameters, when this is an MF tyre.
    pub fn mf_params(&self) -> Option<&TyreParams> {
        match self {
            VirtualTyre::Mf(p) => Some(p),
            VirtualTyre::Brush(_) => None,
        }
    }

    /// The brush parameters, when this is a brush tyre.
    pub fn brush_params(&self) -> Option<&BrushParams> {
        match self {
            VirtualTyre::Mf(_) => None,
            VirtualTyre::Brush(b) => Some(b),
        }
    }

    /// The tyre itself, steady state and without the rig's effects (heat, wear, break-in): the
    /// truth a fitted model is scored against. The brush tyre has one behaviour for every use
    /// mode.
    pub fn reference(&self, mode: UseMode, input: &MfInput) -> MfOutput {
        match self {
            VirtualTyre::Mf(p) => mftyre::evaluate(p, mode, input),
            VirtualTyre::Brush(b) => b.evaluate(&BrushInput {
                fz_n: input.fz_n,
                kappa: input.kappa,
                alpha_rad: input.alpha_rad,
                gamma_rad: input.gamma_rad,
                vx_mps: input.vx_mps,
                p_pa: input.p_pa,
                grip_factor: 1.0,
                stiffness_factor: 1.0,
            }),
        }
    }

    /// The scaling factors of the file (MF) or neutral ones (brush).
    pub(crate) fn base_scaling(&self) -> ScalingFactors {
        match self {
            VirtualTyre::Mf(p) => p.scaling,
            VirtualTyre::Brush(_) => ScalingFactors::default(),
        }
    }

    /// Evaluates the tyre. `base` is the MF file's own scaling (the rig keeps a copy).
    pub(crate) fn evaluate(&self, base: &ScalingFactors, f: TyreScaling, x: &TyreState) -> MfOutput {
        match self {
            VirtualTyre::Mf(p) => {
                let mut s = *base;
                s.lmux *= f.grip;
                s.lmuy *= f.grip;
                s.lkx *= f.stiffness;
                s.lky *= f.stiffness;
                s.lcx *= f.shape;
                s.lcy *= f.shape;
                let input = MfInput {
                    fz_n: x.fz_n,
                    kappa: x.kappa,
                    alpha_rad: x.alpha_rad,
                    gamma_rad: x.gamma_rad,
                    phit_per_m: 0.0,
                    vx_mps: x.vx_mps,
                    p_pa: x.p_pa,
                    omega_radps: x.omega_radps,
                };
                mftyre::evaluate_scaled(p, &s, UseMode::M111, &input)
            }
            VirtualTyre::Brush(b) => b.evaluate(&BrushInput {
                fz_n: x.fz_n,
                kappa: x.kappa,
                alpha_rad: x.alpha_rad,
                gamma_rad: x.gamma_rad,
                vx_mps: x.vx_mps,
                p_pa: x.p_pa,
                grip_factor: f.grip,
                stiffness_factor: f.stiffness,
            }),
        }
    }

    /// Static longitudinal friction coefficient the rig's static mode (locked wheel, belt
    /// moved) slides at, before the grip factor: MF's PDX1, the brush's μx at the load.
    pub(crate) fn static_friction(&self, out: &MfOutput, grip_factor: f64) -> f64 {
        match self {
            VirtualTyre::Mf(p) => p.get("PDX1").unwrap_or(1.0).abs() * grip_factor,
            // The brush output's μx already carries the grip factor.
            VirtualTyre::Brush(_) => out.mux,
        }
    }
}

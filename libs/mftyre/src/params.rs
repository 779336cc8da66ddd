//! Typed MF-Tyre 6.1 parameter set, grouped the way fitting code addresses coefficients.
//!
//! Every numeric `.tir` key the model knows lives in exactly one typed group struct (pure Fx,
//! pure Fy, combined, Mz, Mx, My, vertical, pressure, scaling, …). Each group also carries a
//! static key table so coefficients can be listed, read and written by their `.tir` name
//! (`params.get("PKY1")`, `params.set("PKY1", v)`, `CoefGroup::PureFy.keys()`).

use std::collections::BTreeMap;

use crate::tir::{ExtraSection, TirError, TirValue};

/// Where a typed key lives and what it defaults to when a file omits it.
#[derive(Debug, Clone, Copy)]
pub(crate) struct KeySpec {
    /// The `.tir` key name (upper case).
    pub key: &'static str,
    /// The section the writer puts the key in.
    pub section: &'static str,
    /// `None`: the key is required (the model uses it); `Some(v)`: default when absent.
    pub default: Option<f64>,
}

macro_rules! opt_default {
    () => {
        None
    };
    ($d:expr) => {
        Some($d)
    };
}

macro_rules! zero_or {
    () => {
        0.0
    };
    ($d:expr) => {
        $d
    };
}

/// Declares one coefficient group: a `Copy` struct of `f64` fields plus its key table.
macro_rules! coef_group {
    (
        $(#[$meta:meta])*
        $name:ident {
            $( $(#[$fmeta:meta])* $field:ident : $key:literal @ $sec:literal $(= $def:expr)? ),* $(,)?
        }
    ) => {
        $(#[$meta])*
        #[derive(Debug, Clone, Copy, PartialEq)]
        pub struct $name {
            $( $(#[$fmeta])* #[doc = concat!("`.tir` key `", $key, "`.")] pub $field: f64, )*
        }

        impl Default for $name {
            /// Defaults as documented for optional keys; required keys start at 0.
            fn default() -> Self {
                Self { $( $field: zero_or!($($def)?), )* }
            }
        }

        impl $name {
            /// The `.tir` key names of this group, in writing order.
            pub const KEYS: &'static [&'static str] = &[$($key),*];

            pub(crate) const SPECS: &'static [KeySpec] = &[
                $( KeySpec { key: $key, section: $sec, default: opt_default!($($def)?) }, )*
            ];

            /// The value of `key` (upper-case `.tir` name), if it belongs to this group.
            pub fn get(&self, key: &str) -> Option<f64> {
                match key {
                    $( $key => Some(self.$field), )*
                    _ => None,
                }
            }

            /// Mutable access to the value of `key`, if it belongs to this group.
            pub fn get_mut(&mut self, key: &str) -> Option<&mut f64> {
                match key {
                    $( $key => Some(&mut self.$field), )*
                    _ => None,
                }
            }
        }
    };
}

coef_group! {
    /// `[MODEL]` numeric values the model uses.
    ModelParams {
        /// Reference speed LONGVL, m/s.
        longvl: "LONGVL" @ "MODEL",
        /// Speed below which the low-speed model applies, m/s.
        vxlow: "VXLOW" @ "MODEL" = 1.0,
    }
}

coef_group! {
    /// `[DIMENSION]`: tyre geometry, m.
    Dimension {
        unloaded_radius: "UNLOADED_RADIUS" @ "DIMENSION",
        width: "WIDTH" @ "DIMENSION",
        aspect_ratio: "ASPECT_RATIO" @ "DIMENSION" = 0.0,
        rim_radius: "RIM_RADIUS" @ "DIMENSION",
        rim_width: "RIM_WIDTH" @ "DIMENSION" = 0.0,
    }
}

coef_group! {
    /// `[OPERATING_CONDITIONS]`: pressures, Pa.
    OperatingConditions {
        inflpres: "INFLPRES" @ "OPERATING_CONDITIONS",
        nompres: "NOMPRES" @ "OPERATING_CONDITIONS",
    }
}

coef_group! {
    /// `[INERTIA]`: masses (kg) and inertias (kg·m²); not used by the steady-state model.
    Inertia {
        mass: "MASS" @ "INERTIA" = 0.0,
        ixx: "IXX" @ "INERTIA" = 0.0,
        iyy: "IYY" @ "INERTIA" = 0.0,
        belt_mass: "BELT_MASS" @ "INERTIA" = 0.0,
        belt_ixx: "BELT_IXX" @ "INERTIA" = 0.0,
        belt_iyy: "BELT_IYY" @ "INERTIA" = 0.0,
        gravity: "GRAVITY" @ "INERTIA" = -9.81,
    }
}

coef_group! {
    /// `[VERTICAL]`: nominal load, vertical stiffness and the radius/deflection coefficients.
    Vertical {
        fnomin: "FNOMIN" @ "VERTICAL",
        vertical_stiffness: "VERTICAL_STIFFNESS" @ "VERTICAL",
        vertical_damping: "VERTICAL_DAMPING" @ "VERTICAL" = 0.0,
        mc_contour_a: "MC_CONTOUR_A" @ "VERTICAL" = 0.0,
        mc_contour_b: "MC_CONTOUR_B" @ "VERTICAL" = 0.0,
        breff: "BREFF" @ "VERTICAL",
        dreff: "DREFF" @ "VERTICAL",
        freff: "FREFF" @ "VERTICAL",
        q_re0: "Q_RE0" @ "VERTICAL",
        q_v1: "Q_V1" @ "VERTICAL",
        q_v2: "Q_V2" @ "VERTICAL",
        q_fz2: "Q_FZ2" @ "VERTICAL",
        q_fcx: "Q_FCX" @ "VERTICAL",
        q_fcy: "Q_FCY" @ "VERTICAL",
        q_cam: "Q_CAM" @ "VERTICAL" = 0.0,
        pfz1: "PFZ1" @ "VERTICAL",
        bottom_offst: "BOTTOM_OFFST" @ "VERTICAL" = 0.0,
        bottom_stiff: "BOTTOM_STIFF" @ "VERTICAL" = 0.0,
    }
}

coef_group! {
    /// `[STRUCTURAL]`: carcass stiffnesses (for relaxation lengths) and dynamic-mode data.
    Structural {
        longitudinal_stiffness: "LONGITUDINAL_STIFFNESS" @ "STRUCTURAL",
        lateral_stiffness: "LATERAL_STIFFNESS" @ "STRUCTURAL",
        yaw_stiffness: "YAW_STIFFNESS" @ "STRUCTURAL" = 0.0,
        freq_long: "FREQ_LONG" @ "STRUCTURAL" = 0.0,
        freq_lat: "FREQ_LAT" @ "STRUCTURAL" = 0.0,
        freq_yaw: "FREQ_YAW" @ "STRUCTURAL" = 0.0,
        freq_windup: "FREQ_WINDUP" @ "STRUCTURAL" = 0.0,
        damp_long: "DAMP_LONG" @ "STRUCTURAL" = 0.0,
        damp_lat: "DAMP_LAT" @ "STRUCTURAL" = 0.0,
        damp_yaw: "DAMP_YAW" @ "STRUCTURAL" = 0.0,
        damp_windup: "DAMP_WINDUP" @ "STRUCTURAL" = 0.0,
        damp_residual: "DAMP_RESIDUAL" @ "STRUCTURAL" = 0.0,
        damp_vlow: "DAMP_VLOW" @ "STRUCTURAL" = 0.0,
        q_bvx: "Q_BVX" @ "STRUCTURAL" = 0.0,
        q_bvt: "Q_BVT" @ "STRUCTURAL" = 0.0,
        pcfx1: "PCFX1" @ "STRUCTURAL" = 0.0,
        pcfx2: "PCFX2" @ "STRUCTURAL" = 0.0,
        pcfx3: "PCFX3" @ "STRUCTURAL" = 0.0,
        pcfy1: "PCFY1" @ "STRUCTURAL" = 0.0,
        pcfy2: "PCFY2" @ "STRUCTURAL" = 0.0,
        pcfy3: "PCFY3" @ "STRUCTURAL" = 0.0,
        pcmz1: "PCMZ1" @ "STRUCTURAL" = 0.0,
    }
}

coef_group! {
    /// `[CONTACT_PATCH]`: contact length/width coefficients and the (unused) ellipsoid data.
    ContactPatch {
        q_ra1: "Q_RA1" @ "CONTACT_PATCH",
        q_ra2: "Q_RA2" @ "CONTACT_PATCH",
        q_rb1: "Q_RB1" @ "CONTACT_PATCH",
        q_rb2: "Q_RB2" @ "CONTACT_PATCH",
        ellips_shift: "ELLIPS_SHIFT" @ "CONTACT_PATCH" = 0.0,
        ellips_length: "ELLIPS_LENGTH" @ "CONTACT_PATCH" = 0.0,
        ellips_height: "ELLIPS_HEIGHT" @ "CONTACT_PATCH" = 0.0,
        ellips_order: "ELLIPS_ORDER" @ "CONTACT_PATCH" = 0.0,
        ellips_max_step: "ELLIPS_MAX_STEP" @ "CONTACT_PATCH" = 0.0,
        ellips_nwidth: "ELLIPS_NWIDTH" @ "CONTACT_PATCH" = 0.0,
        ellips_nlength: "ELLIPS_NLENGTH" @ "CONTACT_PATCH" = 0.0,
    }
}

coef_group! {
    /// The validity ranges (`*_RANGE` sections) that limit checks clamp inputs to.
    Limits {
        presmin: "PRESMIN" @ "INFLATION_PRESSURE_RANGE",
        presmax: "PRESMAX" @ "INFLATION_PRESSURE_RANGE",
        fzmin: "FZMIN" @ "VERTICAL_FORCE_RANGE",
        fzmax: "FZMAX" @ "VERTICAL_FORCE_RANGE",
        kpumin: "KPUMIN" @ "LONG_SLIP_RANGE",
        kpumax: "KPUMAX" @ "LONG_SLIP_RANGE",
        alpmin: "ALPMIN" @ "SLIP_ANGLE_RANGE",
        alpmax: "ALPMAX" @ "SLIP_ANGLE_RANGE",
        cammin: "CAMMIN" @ "INCLINATION_ANGLE_RANGE",
        cammax: "CAMMAX" @ "INCLINATION_ANGLE_RANGE",
    }
}

coef_group! {
    /// User scaling factors λ (`[SCALING_COEFFICIENTS]`); all default to 1.
    ScalingFactors {
        /// Nominal load.
        lfzo: "LFZO" @ "SCALING_COEFFICIENTS" = 1.0,
        lcx: "LCX" @ "SCALING_COEFFICIENTS" = 1.0,
        lmux: "LMUX" @ "SCALING_COEFFICIENTS" = 1.0,
        lex: "LEX" @ "SCALING_COEFFICIENTS" = 1.0,
        lkx: "LKX" @ "SCALING_COEFFICIENTS" = 1.0,
        lhx: "LHX" @ "SCALING_COEFFICIENTS" = 1.0,
        lvx: "LVX" @ "SCALING_COEFFICIENTS" = 1.0,
        lcy: "LCY" @ "SCALING_COEFFICIENTS" = 1.0,
        lmuy: "LMUY" @ "SCALING_COEFFICIENTS" = 1.0,
        ley: "LEY" @ "SCALING_COEFFICIENTS" = 1.0,
        lky: "LKY" @ "SCALING_COEFFICIENTS" = 1.0,
        lhy: "LHY" @ "SCALING_COEFFICIENTS" = 1.0,
        lvy: "LVY" @ "SCALING_COEFFICIENTS" = 1.0,
        ltr: "LTR" @ "SCALING_COEFFICIENTS" = 1.0,
        lres: "LRES" @ "SCALING_COEFFICIENTS" = 1.0,
        lxal: "LXAL" @ "SCALING_COEFFICIENTS" = 1.0,
        lyka: "LYKA" @ "SCALING_COEFFICIENTS" = 1.0,
        lvyka: "LVYKA" @ "SCALING_COEFFICIENTS" = 1.0,
        ls: "LS" @ "SCALING_COEFFICIENTS" = 1.0,
        lkyc: "LKYC" @ "SCALING_COEFFICIENTS" = 1.0,
        lkzc: "LKZC" @ "SCALING_COEFFICIENTS" = 1.0,
        lvmx: "LVMX" @ "SCALING_COEFFICIENTS" = 1.0,
        lmx: "LMX" @ "SCALING_COEFFICIENTS" = 1.0,
        lmy: "LMY" @ "SCALING_COEFFICIENTS" = 1.0,
        lmp: "LMP" @ "SCALING_COEFFICIENTS" = 1.0,
    }
}

coef_group! {
    /// Pure longitudinal force Fx0 (Pacejka 2012 eqs. 4.E9–4.E18), pressure terms excluded.
    PureFx {
        pcx1: "PCX1" @ "LONGITUDINAL_COEFFICIENTS",
        pdx1: "PDX1" @ "LONGITUDINAL_COEFFICIENTS",
        pdx2: "PDX2" @ "LONGITUDINAL_COEFFICIENTS",
        pdx3: "PDX3" @ "LONGITUDINAL_COEFFICIENTS",
        pex1: "PEX1" @ "LONGITUDINAL_COEFFICIENTS",
        pex2: "PEX2" @ "LONGITUDINAL_COEFFICIENTS",
        pex3: "PEX3" @ "LONGITUDINAL_COEFFICIENTS",
        pex4: "PEX4" @ "LONGITUDINAL_COEFFICIENTS",
        pkx1: "PKX1" @ "LONGITUDINAL_COEFFICIENTS",
        pkx2: "PKX2" @ "LONGITUDINAL_COEFFICIENTS",
        pkx3: "PKX3" @ "LONGITUDINAL_COEFFICIENTS",
        phx1: "PHX1" @ "LONGITUDINAL_COEFFICIENTS",
        phx2: "PHX2" @ "LONGITUDINAL_COEFFICIENTS",
        pvx1: "PVX1" @ "LONGITUDINAL_COEFFICIENTS",
        pvx2: "PVX2" @ "LONGITUDINAL_COEFFICIENTS",
    }
}

coef_group! {
    /// Pure lateral force Fy0 (eqs. 4.E19–4.E30), pressure terms excluded.
    PureFy {
        pcy1: "PCY1" @ "LATERAL_COEFFICIENTS",
        pdy1: "PDY1" @ "LATERAL_COEFFICIENTS",
        pdy2: "PDY2" @ "LATERAL_COEFFICIENTS",
        pdy3: "PDY3" @ "LATERAL_COEFFICIENTS",
        pey1: "PEY1" @ "LATERAL_COEFFICIENTS",
        pey2: "PEY2" @ "LATERAL_COEFFICIENTS",
        pey3: "PEY3" @ "LATERAL_COEFFICIENTS",
        pey4: "PEY4" @ "LATERAL_COEFFICIENTS",
        pey5: "PEY5" @ "LATERAL_COEFFICIENTS",
        pky1: "PKY1" @ "LATERAL_COEFFICIENTS",
        pky2: "PKY2" @ "LATERAL_COEFFICIENTS",
        pky3: "PKY3" @ "LATERAL_COEFFICIENTS",
        pky4: "PKY4" @ "LATERAL_COEFFICIENTS",
        pky5: "PKY5" @ "LATERAL_COEFFICIENTS",
        pky6: "PKY6" @ "LATERAL_COEFFICIENTS",
        pky7: "PKY7" @ "LATERAL_COEFFICIENTS",
        phy1: "PHY1" @ "LATERAL_COEFFICIENTS",
        phy2: "PHY2" @ "LATERAL_COEFFICIENTS",
        pvy1: "PVY1" @ "LATERAL_COEFFICIENTS",
        pvy2: "PVY2" @ "LATERAL_COEFFICIENTS",
        pvy3: "PVY3" @ "LATERAL_COEFFICIENTS",
        pvy4: "PVY4" @ "LATERAL_COEFFICIENTS",
    }
}

coef_group! {
    /// Combined-slip weighting functions Gxα, Gyκ and κ-induced side force (4.E50–4.E67).
    Combined {
        rbx1: "RBX1" @ "LONGITUDINAL_COEFFICIENTS",
        rbx2: "RBX2" @ "LONGITUDINAL_COEFFICIENTS",
        rbx3: "RBX3" @ "LONGITUDINAL_COEFFICIENTS",
        rcx1: "RCX1" @ "LONGITUDINAL_COEFFICIENTS",
        rex1: "REX1" @ "LONGITUDINAL_COEFFICIENTS",
        rex2: "REX2" @ "LONGITUDINAL_COEFFICIENTS",
        rhx1: "RHX1" @ "LONGITUDINAL_COEFFICIENTS",
        rby1: "RBY1" @ "LATERAL_COEFFICIENTS",
        rby2: "RBY2" @ "LATERAL_COEFFICIENTS",
        rby3: "RBY3" @ "LATERAL_COEFFICIENTS",
        rby4: "RBY4" @ "LATERAL_COEFFICIENTS",
        rcy1: "RCY1" @ "LATERAL_COEFFICIENTS",
        rey1: "REY1" @ "LATERAL_COEFFICIENTS",
        rey2: "REY2" @ "LATERAL_COEFFICIENTS",
        rhy1: "RHY1" @ "LATERAL_COEFFICIENTS",
        rhy2: "RHY2" @ "LATERAL_COEFFICIENTS",
        rvy1: "RVY1" @ "LATERAL_COEFFICIENTS",
        rvy2: "RVY2" @ "LATERAL_COEFFICIENTS",
        rvy3: "RVY3" @ "LATERAL_COEFFICIENTS",
        rvy4: "RVY4" @ "LATERAL_COEFFICIENTS",
        rvy5: "RVY5" @ "LATERAL_COEFFICIENTS",
        rvy6: "RVY6" @ "LATERAL_COEFFICIENTS",
    }
}

coef_group! {
    /// Overturning moment Mx (TNO / Besselink 2010 form with QSX12–14), pressure term excluded.
    Overturning {
        qsx1: "QSX1" @ "OVERTURNING_COEFFICIENTS",
        qsx2: "QSX2" @ "OVERTURNING_COEFFICIENTS",
        qsx3: "QSX3" @ "OVERTURNING_COEFFICIENTS",
        qsx4: "QSX4" @ "OVERTURNING_COEFFICIENTS" = 0.0,
        qsx5: "QSX5" @ "OVERTURNING_COEFFICIENTS" = 0.0,
        qsx6: "QSX6" @ "OVERTURNING_COEFFICIENTS" = 0.0,
        qsx7: "QSX7" @ "OVERTURNING_COEFFICIENTS" = 0.0,
        qsx8: "QSX8" @ "OVERTURNING_COEFFICIENTS" = 0.0,
        qsx9: "QSX9" @ "OVERTURNING_COEFFICIENTS" = 0.0,
        qsx10: "QSX10" @ "OVERTURNING_COEFFICIENTS" = 0.0,
        qsx11: "QSX11" @ "OVERTURNING_COEFFICIENTS" = 0.0,
        qsx12: "QSX12" @ "OVERTURNING_COEFFICIENTS" = 0.0,
        qsx13: "QSX13" @ "OVERTURNING_COEFFICIENTS" = 0.0,
        qsx14: "QSX14" @ "OVERTURNING_COEFFICIENTS" = 0.0,
    }
}

coef_group! {
    /// Rolling resistance moment My (Besselink 2010 eq. A48).
    Rolling {
        qsy1: "QSY1" @ "ROLLING_COEFFICIENTS",
        qsy2: "QSY2" @ "ROLLING_COEFFICIENTS",
        qsy3: "QSY3" @ "ROLLING_COEFFICIENTS",
        qsy4: "QSY4" @ "ROLLING_COEFFICIENTS",
        qsy5: "QSY5" @ "ROLLING_COEFFICIENTS" = 0.0,
        qsy6: "QSY6" @ "ROLLING_COEFFICIENTS" = 0.0,
        qsy7: "QSY7" @ "ROLLING_COEFFICIENTS",
        qsy8: "QSY8" @ "ROLLING_COEFFICIENTS",
    }
}

coef_group! {
    /// Aligning moment Mz: pneumatic trail, residual moment and Fx moment arm s.
    Aligning {
        qbz1: "QBZ1" @ "ALIGNING_COEFFICIENTS",
        qbz2: "QBZ2" @ "ALIGNING_COEFFICIENTS",
        qbz3: "QBZ3" @ "ALIGNING_COEFFICIENTS",
        qbz4: "QBZ4" @ "ALIGNING_COEFFICIENTS",
        qbz5: "QBZ5" @ "ALIGNING_COEFFICIENTS",
        qbz9: "QBZ9" @ "ALIGNING_COEFFICIENTS",
        qbz10: "QBZ10" @ "ALIGNING_COEFFICIENTS",
        qcz1: "QCZ1" @ "ALIGNING_COEFFICIENTS",
        qdz1: "QDZ1" @ "ALIGNING_COEFFICIENTS",
        qdz2: "QDZ2" @ "ALIGNING_COEFFICIENTS",
        qdz3: "QDZ3" @ "ALIGNING_COEFFICIENTS",
        qdz4: "QDZ4" @ "ALIGNING_COEFFICIENTS",
        qdz6: "QDZ6" @ "ALIGNING_COEFFICIENTS",
        qdz7: "QDZ7" @ "ALIGNING_COEFFICIENTS",
        qdz8: "QDZ8" @ "ALIGNING_COEFFICIENTS",
        qdz9: "QDZ9" @ "ALIGNING_COEFFICIENTS",
        qdz10: "QDZ10" @ "ALIGNING_COEFFICIENTS",
        qdz11: "QDZ11" @ "ALIGNING_COEFFICIENTS",
        qez1: "QEZ1" @ "ALIGNING_COEFFICIENTS",
        qez2: "QEZ2" @ "ALIGNING_COEFFICIENTS",
        qez3: "QEZ3" @ "ALIGNING_COEFFICIENTS",
        qez4: "QEZ4" @ "ALIGNING_COEFFICIENTS",
        qez5: "QEZ5" @ "ALIGNING_COEFFICIENTS",
        qhz1: "QHZ1" @ "ALIGNING_COEFFICIENTS",
        qhz2: "QHZ2" @ "ALIGNING_COEFFICIENTS",
        qhz3: "QHZ3" @ "ALIGNING_COEFFICIENTS",
        qhz4: "QHZ4" @ "ALIGNING_COEFFICIENTS",
        ssz1: "SSZ1" @ "ALIGNING_COEFFICIENTS",
        ssz2: "SSZ2" @ "ALIGNING_COEFFICIENTS",
        ssz3: "SSZ3" @ "ALIGNING_COEFFICIENTS",
        ssz4: "SSZ4" @ "ALIGNING_COEFFICIENTS",
    }
}

coef_group! {
    /// Inflation-pressure coefficients of Fx, Fy, Mz and Mx (MF 6.1 additions).
    Pressure {
        ppx1: "PPX1" @ "LONGITUDINAL_COEFFICIENTS",
        ppx2: "PPX2" @ "LONGITUDINAL_COEFFICIENTS",
        ppx3: "PPX3" @ "LONGITUDINAL_COEFFICIENTS",
        ppx4: "PPX4" @ "LONGITUDINAL_COEFFICIENTS",
        ppy1: "PPY1" @ "LATERAL_COEFFICIENTS",
        ppy2: "PPY2" @ "LATERAL_COEFFICIENTS",
        ppy3: "PPY3" @ "LATERAL_COEFFICIENTS",
        ppy4: "PPY4" @ "LATERAL_COEFFICIENTS",
        ppy5: "PPY5" @ "LATERAL_COEFFICIENTS",
        ppz1: "PPZ1" @ "ALIGNING_COEFFICIENTS",
        ppz2: "PPZ2" @ "ALIGNING_COEFFICIENTS",
        ppmx1: "PPMX1" @ "OVERTURNING_COEFFICIENTS",
    }
}

coef_group! {
    /// Turn-slip coefficients: read and written, not used (this crate evaluates phit = 0 only).
    TurnSlip {
        pdxp1: "PDXP1" @ "TURNSLIP_COEFFICIENTS" = 0.0,
        pdxp2: "PDXP2" @ "TURNSLIP_COEFFICIENTS" = 0.0,
        pdxp3: "PDXP3" @ "TURNSLIP_COEFFICIENTS" = 0.0,
        pkyp1: "PKYP1" @ "TURNSLIP_COEFFICIENTS" = 0.0,
        pdyp1: "PDYP1" @ "TURNSLIP_COEFFICIENTS" = 0.0,
        pdyp2: "PDYP2" @ "TURNSLIP_COEFFICIENTS" = 0.0,
        pdyp3: "PDYP3" @ "TURNSLIP_COEFFICIENTS" = 0.0,
        pdyp4: "PDYP4" @ "TURNSLIP_COEFFICIENTS" = 0.0,
        phyp1: "PHYP1" @ "TURNSLIP_COEFFICIENTS" = 0.0,
        phyp2: "PHYP2" @ "TURNSLIP_COEFFICIENTS" = 0.0,
        phyp3: "PHYP3" @ "TURNSLIP_COEFFICIENTS" = 0.0,
        phyp4: "PHYP4" @ "TURNSLIP_COEFFICIENTS" = 0.0,
        pecp1: "PECP1" @ "TURNSLIP_COEFFICIENTS" = 0.0,
        pecp2: "PECP2" @ "TURNSLIP_COEFFICIENTS" = 0.0,
        qdtp1: "QDTP1" @ "TURNSLIP_COEFFICIENTS" = 0.0,
        qcrp1: "QCRP1" @ "TURNSLIP_COEFFICIENTS" = 0.0,
        qcrp2: "QCRP2" @ "TURNSLIP_COEFFICIENTS" = 0.0,
        qbrp1: "QBRP1" @ "TURNSLIP_COEFFICIENTS" = 0.0,
        qdrp1: "QDRP1" @ "TURNSLIP_COEFFICIENTS" = 0.0,
    }
}

/// A named group of coefficients, for fitting code that works group by group.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum CoefGroup {
    /// LONGVL, VXLOW.
    Model,
    /// Tyre dimensions.
    Dimension,
    /// INFLPRES, NOMPRES.
    OperatingConditions,
    /// Masses and inertias.
    Inertia,
    /// Radius, vertical stiffness and deflection.
    Vertical,
    /// Carcass stiffnesses (relaxation lengths).
    Structural,
    /// Contact patch size.
    ContactPatch,
    /// Validity ranges.
    Limits,
    /// Scaling factors λ.
    Scaling,
    /// Pure longitudinal force.
    PureFx,
    /// Pure lateral force.
    PureFy,
    /// Combined-slip weighting.
    Combined,
    /// Overturning moment Mx.
    Mx,
    /// Rolling resistance moment My.
    My,
    /// Aligning moment Mz.
    Mz,
    /// Inflation-pressure terms.
    Pressure,
    /// Turn slip (stored only).
    TurnSlip,
}

impl CoefGroup {
    /// Every group, in `.tir` writing order.
    pub const ALL: [CoefGroup; 17] = [
        CoefGroup::Model,
        CoefGroup::Dimension,
        CoefGroup::OperatingConditions,
        CoefGroup::Inertia,
        CoefGroup::Vertical,
        CoefGroup::Structural,
        CoefGroup::ContactPatch,
        CoefGroup::Limits,
        CoefGroup::Scaling,
        CoefGroup::PureFx,
        CoefGroup::Combined,
        CoefGroup::Pressure,
        CoefGroup::Mx,
        CoefGroup::PureFy,
        CoefGroup::My,
        CoefGroup::Mz,
        CoefGroup::TurnSlip,
    ];

    /// The `.tir` key names in this group.
    pub fn keys(self) -> &'static [&'static str] {
        match self {
            CoefGroup::Model => ModelParams::KEYS,
            CoefGroup::Dimension => Dimension::KEYS,
            CoefGroup::OperatingConditions => OperatingConditions::KEYS,
            CoefGroup::Inertia => Inertia::KEYS,
            CoefGroup::Vertical => Vertical::KEYS,
            CoefGroup::Structural => Structural::KEYS,
            CoefGroup::ContactPatch => ContactPatch::KEYS,
            CoefGroup::Limits => Limits::KEYS,
            CoefGroup::Scaling => ScalingFactors::KEYS,
            CoefGroup::PureFx => PureFx::KEYS,
            CoefGroup::PureFy => PureFy::KEYS,
            CoefGroup::Combined => Combined::KEYS,
            CoefGroup::Mx => Overturning::KEYS,
            CoefGroup::My => Rolling::KEYS,
            CoefGroup::Mz => Aligning::KEYS,
            CoefGroup::Pressure => Pressure::KEYS,
            CoefGroup::TurnSlip => TurnSlip::KEYS,
        }
    }

    pub(crate) fn specs(self) -> &'static [KeySpec] {
        match self {
            CoefGroup::Model => ModelParams::SPECS,
            CoefGroup::Dimension => Dimension::SPECS,
            CoefGroup::OperatingConditions => OperatingConditions::SPECS,
            CoefGroup::Inertia => Inertia::SPECS,
            CoefGroup::Vertical => Vertical::SPECS,
            CoefGroup::Structural => Structural::SPECS,
            CoefGroup::ContactPatch => ContactPatch::SPECS,
            CoefGroup::Limits => Limits::SPECS,
            CoefGroup::Scaling => ScalingFactors::SPECS,
            CoefGroup::PureFx => PureFx::SPECS,
            CoefGroup::PureFy => PureFy::SPECS,
            CoefGroup::Combined => Combined::SPECS,
            CoefGroup::Mx => Overturning::SPECS,
            CoefGroup::My => Rolling::SPECS,
            CoefGroup::Mz => Aligning::SPECS,
            CoefGroup::Pressure => Pressure::SPECS,
            CoefGroup::TurnSlip => TurnSlip::SPECS,
        }
    }

    /// The group a `.tir` key belongs to, if it is a typed coefficient.
    pub fn of_key(key: &str) -> Option<CoefGroup> {
        CoefGroup::ALL.into_iter().find(|g| g.keys().contains(&key))
    }
}

/// A `.tir` entry the model does not use, kept so files round-trip (header, units, …).
#[derive(Debug, Clone, PartialEq)]
pub struct OtherEntry {
    /// Section name without brackets, upper case.
    pub section: String,
    /// Key as written in the file.
    pub key: String,
    /// Its value.
    pub value: TirValue,
}

/// A complete MF-Tyre 6.1 parameter set (one `.tir` file), SI units.
#[derive(Debug, Clone, PartialEq)]
pub struct TyreParams {
    /// Where the parameters came from (file name), for messages.
    pub source: String,
    /// FITTYP (always 61 for a set this crate accepts).
    pub fittyp: u32,
    /// LONGVL, VXLOW.
    pub model: ModelParams,
    /// Tyre dimensions.
    pub dimension: Dimension,
    /// INFLPRES, NOMPRES.
    pub operating: OperatingConditions,
    /// Masses and inertias.
    pub inertia: Inertia,
    /// Vertical: FNOMIN, Cz, radius coefficients.
    pub vertical: Vertical,
    /// Carcass stiffnesses.
    pub structural: Structural,
    /// Contact patch.
    pub contact_patch: ContactPatch,
    /// Validity ranges.
    pub limits: Limits,
    /// Scaling factors λ.
    pub scaling: ScalingFactors,
    /// Pure Fx.
    pub pure_fx: PureFx,
    /// Pure Fy.
    pub pure_fy: PureFy,
    /// Combined slip.
    pub combined: Combined,
    /// Mx.
    pub overturning: Overturning,
    /// My.
    pub rolling: Rolling,
    /// Mz.
    pub aligning: Aligning,
    /// Pressure terms.
    pub pressure: Pressure,
    /// Turn slip (stored, not evaluated).
    pub turn_slip: TurnSlip,
    /// Non-model entries of known sections, in file order.
    pub other: Vec<OtherEntry>,
    /// Sections this crate does not know (e.g. a doctor's additions, MF 5.2 `[SHAPE]`),
    /// kept line by line so they survive a read/write cycle.
    pub extra_sections: BTreeMap<String, ExtraSection>,
}

impl TyreParams {
    /// An all-default set (required coefficients 0); the starting point of the reader.
    pub(crate) fn empty(source: &str) -> Self {
        Self {
            source: source.to_owned(),
            fittyp: 61,
            model: ModelParams::default(),
            dimension: Dimension::default(),
            operating: OperatingConditions::default(),
            inertia: Inertia::default(),
            vertical: Vertical::default(),
            structural: Structural::default(),
            contact_patch: ContactPatch::default(),
            limits: Limits::default(),
            scaling: ScalingFactors::default(),
            pure_fx: PureFx::default(),
            pure_fy: PureFy::default(),
            combined: Combined::default(),
            overturning: Overturning::default(),
            rolling: Rolling::default(),
            aligning: Aligning::default(),
            pressure: Pressure::default(),
            turn_slip: TurnSlip::default(),
            other: Vec::new(),
            extra_sections: BTreeMap::new(),
        }
    }

    /// The value of a typed coefficient by `.tir` key (case-insensitive), e.g. `"PKY1"`.
    pub fn get(&self, key: &str) -> Option<f64> {
        let key = key.to_ascii_uppercase();
        let k = key.as_str();
        self.model
            .get(k)
            .or_else(|| self.dimension.get(k))
            .or_else(|| self.operating.get(k))
            .or_else(|| self.inertia.get(k))
            .or_else(|| self.vertical.get(k))
            .or_else(|| self.structural.get(k))
            .or_else(|| self.contact_patch.get(k))
            .or_else(|| self.limits.get(k))
            .or_else(|| self.scaling.get(k))
            .or_else(|| self.pure_fx.get(k))
            .or_else(|| self.pure_fy.get(k))
            .or_else(|| self.combined.get(k))
            .or_else(|| self.overturning.get(k))
            .or_else(|| self.rolling.get(k))
            .or_else(|| self.aligning.get(k))
            .or_else(|| self.pressure.get(k))
            .or_else(|| self.turn_slip.get(k))
    }

    pub(crate) fn slot_mut(&mut self, key: &str) -> Option<&mut f64> {
        // One group at a time: the borrow checker cannot see through an `or_else` chain of
        // mutable borrows, so test membership first.
        match CoefGroup::of_key(key)? {
            CoefGroup::Model => self.model.get_mut(key),
            CoefGroup::Dimension => self.dimension.get_mut(key),
            CoefGroup::OperatingConditions => self.operating.get_mut(key),
            CoefGroup::Inertia => self.inertia.get_mut(key),
            CoefGroup::Vertical => self.vertical.get_mut(key),
            CoefGroup::Structural => self.structural.get_mut(key),
            CoefGroup::ContactPatch => self.contact_patch.get_mut(key),
            CoefGroup::Limits => self.limits.get_mut(key),
            CoefGroup::Scaling => self.scaling.get_mut(key),
            CoefGroup::PureFx => self.pure_fx.get_mut(key),
            CoefGroup::PureFy => self.pure_fy.get_mut(key),
            CoefGroup::Combined => self.combined.get_mut(key),
            CoefGroup::Mx => self.overturning.get_mut(key),
            CoefGroup::My => self.rolling.get_mut(key),
            CoefGroup::Mz => self.aligning.get_mut(key),
            CoefGroup::Pressure => self.pressure.get_mut(key),
            CoefGroup::TurnSlip => self.turn_slip.get_mut(key),
        }
    }

    /// Sets a typed coefficient by `.tir` key (case-insensitive).
    ///
    /// Errors: [`TirError::UnknownKey`] for a key that is not a typed coefficient,
    /// [`TirError::InvalidValue`] for a non-finite value.
    pub fn set(&mut self, key: &str, v: f64) -> Result<(), TirError> {
        let upper = key.to_ascii_uppercase();
        if !v.is_finite() {
            return Err(TirError::InvalidValue {
                file: self.source.clone(),
                line: 0,
                key: upper,
                value: v,
                reason: "not a finite number",
            });
        }
        match self.slot_mut(&upper) {
            Some(slot) => {
                *slot = v;
                Ok(())
            }
            None => Err(TirError::UnknownKey { key: key.to_owned() }),
        }
    }

    /// The coefficients of one group as `(key, value)` pairs, in writing order.
    pub fn group_values(&self, group: CoefGroup) -> Vec<(&'static str, f64)> {
        group.keys().iter().filter_map(|k| self.get(k).map(|v| (*k, v))).collect()
    }

    /// Nominal (rated) wheel load FNOMIN, N (unscaled).
    pub fn fnomin_n(&self) -> f64 {
        self.vertical.fnomin
    }

    /// Free tyre radius UNLOADED_RADIUS, m.
    pub fn unloaded_radius_m(&self) -> f64 {
        self.dimension.unloaded_radius
    }

    /// Nominal inflation pressure NOMPRES, Pa.
    pub fn nominal_pressure_pa(&self) -> f64 {
        self.operating.nompres
    }

    /// The file's inflation pressure INFLPRES (used when an input gives P = 0), Pa.
    pub fn inflation_pressure_pa(&self) -> f64 {
        self.operating.inflpres
    }

    /// Reference speed LONGVL, m/s.
    pub fn longvl_mps(&self) -> f64 {
        self.model.longvl
    }

    /// Low-speed threshold VXLOW, m/s.
    pub fn vxlow_mps(&self) -> f64 {
        self.model.vxlow
    }

    /// Nominal section width WIDTH, m.
    pub fn width_m(&self) -> f64 {
        self.dimension.width
    }

    /// Rim radius RIM_RADIUS, m.
    pub fn rim_radius_m(&self) -> f64 {
        self.dimension.rim_radius
    }

    /// Vertical stiffness VERTICAL_STIFFNESS at nominal pressure, N/m.
    pub fn vertical_stiffness_npm(&self) -> f64 {
        self.vertical.vertical_stiffness
    }

    /// Vertical damping VERTICAL_DAMPING, N·s/m.
    pub fn vertical_damping_nspm(&self) -> f64 {
        self.vertical.vertical_damping
    }

    /// Tyre mass MASS from `[INERTIA]`, kg.
    pub fn mass_kg(&self) -> f64 {
        self.inertia.mass
    }

    /// Polar moment of inertia IYY, kg·m².
    pub fn iyy_kgm2(&self) -> f64 {
        self.inertia.iyy
    }

    /// A non-model entry (e.g. `("MODEL", "TYRESIDE")`), if present.
    pub fn other_value(&self, section: &str, key: &str) -> Option<&TirValue> {
        self.other
            .iter()
            .find(|e| e.section.eq_ignore_ascii_case(section) && e.key.eq_ignore_ascii_case(key))
            .map(|e| &e.value)
    }

    /// A copy with every coefficient that makes the pure-slip curves asymmetric set to zero
    /// (shifts, camber and sign-dependent curvature terms), useful for symmetry checks.
    pub fn symmetric_copy(&self) -> Self {
        let mut p = self.clone();
        p.pure_fx.phx1 = 0.0;
        p.pure_fx.phx2 = 0.0;
        p.pure_fx.pvx1 = 0.0;
        p.pure_fx.pvx2 = 0.0;
        p.pure_fx.pex4 = 0.0;
        p.pure_fy.phy1 = 0.0;
        p.pure_fy.phy2 = 0.0;
        p.pure_fy.pvy1 = 0.0;
        p.pure_fy.pvy2 = 0.0;
        p.pure_fy.pvy3 = 0.0;
        p.pure_fy.pvy4 = 0.0;
        p.pure_fy.pey3 = 0.0;
        p.pure_fy.pey4 = 0.0;
        p.pure_fy.pky6 = 0.0;
        p.pure_fy.pky7 = 0.0;
        p.overturning.qsx1 = 0.0;
        p.aligning.qhz1 = 0.0;
        p.aligning.qhz2 = 0.0;
        p.aligning.qhz3 = 0.0;
        p.aligning.qhz4 = 0.0;
        p.aligning.qez4 = 0.0;
        p.aligning.qez5 = 0.0;
        p.aligning.qdz6 = 0.0;
        p.aligning.qdz7 = 0.0;
        p.aligning.ssz1 = 0.0;
        p.aligning.ssz2 = 0.0;
        p.combined.rhx1 = 0.0;
        p.combined.rhy1 = 0.0;
        p.combined.rhy2 = 0.0;
        p.combined.rby3 = 0.0;
        p.combined.rvy1 = 0.0;
        p.combined.rvy2 = 0.0;
        p.combined.rvy3 = 0.0;
        p
    }
}

//! Struct-of-arrays evaluation for fitting and simulation.

use crate::model::{Clamped, MfInput, MfOutput, SweepEvaluator, UseMode};
use crate::params::{ScalingFactors, TyreParams};

/// Inputs as parallel slices. `fz_n` sets the batch length; every other slice is either empty
/// (meaning 0 for every point: P = INFLPRES, Ω estimated, no slip, …) or exactly as long.
#[derive(Debug, Clone, Copy, Default)]
pub struct BatchInput<'a> {
    /// Vertical load, N.
    pub fz_n: &'a [f64],
    /// Longitudinal slip, –.
    pub kappa: &'a [f64],
    /// Slip angle, rad.
    pub alpha_rad: &'a [f64],
    /// Inclination angle, rad.
    pub gamma_rad: &'a [f64],
    /// Turn slip, 1/m (ignored: not modelled).
    pub phit_per_m: &'a [f64],
    /// Forward speed, m/s.
    pub vx_mps: &'a [f64],
    /// Inflation pressure, Pa (0 or empty = INFLPRES).
    pub p_pa: &'a [f64],
    /// Wheel spin rate, rad/s (0 or empty = estimate).
    pub omega_radps: &'a [f64],
}

/// A batch whose slices disagree in length.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("batch input `{column}` has {len} values but `fz_n` has {expected} (give the same count or none)")]
pub struct BatchLengthError {
    /// The offending column.
    pub column: &'static str,
    /// Its length.
    pub len: usize,
    /// The length of `fz_n`.
    pub expected: usize,
}

impl BatchInput<'_> {
    /// Number of points (the length of `fz_n`).
    pub fn len(&self) -> usize {
        self.fz_n.len()
    }

    /// True for an empty batch.
    pub fn is_empty(&self) -> bool {
        self.fz_n.is_empty()
    }

    /// Checks that every slice is empty or as long as `fz_n`.
    pub fn validate(&self) -> Result<usize, BatchLengthError> {
        let n = self.fz_n.len();
        let cols: [(&'static str, &[f64]); 7] = [
            ("kappa", self.kappa),
            ("alpha_rad", self.alpha_rad),
            ("gamma_rad", self.gamma_rad),
            ("phit_per_m", self.phit_per_m),
            ("vx_mps", self.vx_mps),
            ("p_pa", self.p_pa),
            ("omega_radps", self.omega_radps),
        ];
        for (column, s) in cols {
            if !s.is_empty() && s.len() != n {
                return Err(BatchLengthError { column, len: s.len(), expected: n });
            }
        }
        Ok(n)
    }

    /// Point `i` as an [`MfInput`] (empty columns read as 0). `i` must be below `len()`.
    #[inline(always)]
    pub fn point(&self, i: usize) -> MfInput {
        let at = |s: &[f64]| s.get(i).copied().unwrap_or(0.0);
        MfInput {
            fz_n: at(self.fz_n),
            kappa: at(self.kappa),
            alpha_rad: at(self.alpha_rad),
            gamma_rad: at(self.gamma_rad),
            phit_per_m: at(self.phit_per_m),
            vx_mps: at(self.vx_mps),
            p_pa: at(self.p_pa),
            omega_radps: at(self.omega_radps),
        }
    }
}

/// Outputs as parallel vectors (one per [`MfOutput`] field).
#[derive(Debug, Clone, Default, PartialEq)]
#[allow(missing_docs)] // Each field mirrors the MfOutput field of the same name.
pub struct BatchOutput {
    pub fx_n: Vec<f64>,
    pub fy_n: Vec<f64>,
    pub fz_n: Vec<f64>,
    pub mx_nm: Vec<f64>,
    pub my_nm: Vec<f64>,
    pub mz_nm: Vec<f64>,
    pub kappa: Vec<f64>,
    pub alpha_rad: Vec<f64>,
    pub gamma_rad: Vec<f64>,
    pub phit_per_m: Vec<f64>,
    pub vx_mps: Vec<f64>,
    pub p_pa: Vec<f64>,
    pub re_m: Vec<f64>,
    pub rho_m: Vec<f64>,
    pub contact_length_m: Vec<f64>,
    pub trail_m: Vec<f64>,
    pub mux: Vec<f64>,
    pub muy: Vec<f64>,
    pub omega_radps: Vec<f64>,
    pub rl_m: Vec<f64>,
    pub contact_width_m: Vec<f64>,
    pub mzr_nm: Vec<f64>,
    pub cx_npm: Vec<f64>,
    pub cy_npm: Vec<f64>,
    pub cz_npm: Vec<f64>,
    pub kya_nprad: Vec<f64>,
    pub sigmax_m: Vec<f64>,
    pub sigmay_m: Vec<f64>,
    pub kxk_n: Vec<f64>,
    pub clamped: Vec<Clamped>,
}

macro_rules! for_each_column {
    ($m:ident) => {
        $m!(
            fx_n,
            fy_n,
            fz_n,
            mx_nm,
            my_nm,
            mz_nm,
            kappa,
            alpha_rad,
            gamma_rad,
            phit_per_m,
            vx_mps,
            p_pa,
            re_m,
            rho_m,
            contact_length_m,
            trail_m,
            mux,
            muy,
            omega_radps,
            rl_m,
            contact_width_m,
            mzr_nm,
            cx_npm,
            cy_npm,
            cz_npm,
            kya_nprad,
            sigmax_m,
            sigmay_m,
            kxk_n,
            clamped
        )
    };
}

impl BatchOutput {
    /// Number of points held.
    pub fn len(&self) -> usize {
        self.fx_n.len()
    }

    /// True when empty.
    pub fn is_empty(&self) -> bool {
        self.fx_n.is_empty()
    }

    /// Removes all points, keeping the allocations.
    pub fn clear(&mut self) {
        macro_rules! clear {
            ($($f:ident),*) => { $( self.$f.clear(); )* };
        }
        for_each_column!(clear);
    }

    fn reserve(&mut self, n: usize) {
        macro_rules! reserve {
            ($($f:ident),*) => { $( self.$f.reserve(n); )* };
        }
        for_each_column!(reserve);
    }

    /// Appends one point.
    pub fn push(&mut self, o: &MfOutput) {
        macro_rules! push {
            ($($f:ident),*) => { $( self.$f.push(o.$f); )* };
        }
        for_each_column!(push);
    }

    /// Point `i` as an [`MfOutput`], if present.
    pub fn get(&self, i: usize) -> Option<MfOutput> {
        if i >= self.len() {
            return None;
        }
        macro_rules! get {
            ($($f:ident),*) => { MfOutput { $( $f: self.$f[i], )* } };
        }
        Some(for_each_column!(get))
    }
}

/// Evaluates every point of `inputs` into `out` (cleared first; allocations reused). Runs of
/// points that share Fz, pressure and camber (sweeps) reuse the load-dependent terms; the
/// results are identical to [`crate::evaluate`] point by point.
pub fn evaluate_batch(
    params: &TyreParams,
    mode: UseMode,
    inputs: &BatchInput<'_>,
    out: &mut BatchOutput,
) -> Result<(), BatchLengthError> {
    evaluate_batch_scaled(params, &params.scaling, mode, inputs, out)
}

/// [`evaluate_batch`] with `scaling` in place of `params.scaling`.
pub fn evaluate_batch_scaled(
    params: &TyreParams,
    scaling: &ScalingFactors,
    mode: UseMode,
    inputs: &BatchInput<'_>,
    out: &mut BatchOutput,
) -> Result<(), BatchLengthError> {
    let n = inputs.validate()?;
    out.clear();
    out.reserve(n);
    // Consecutive points with the same load case (a sweep) share the load-dependent terms.
    let mut ev = SweepEvaluator::new(params, scaling, mode);
    for i in 0..n {
        let o = ev.eval(&inputs.point(i));
        out.push(&o);
    }
    Ok(())
}

/// Pure lateral force for every point into `fy_n` (cleared first).
pub fn pure_fy_batch(
    params: &TyreParams,
    mode: UseMode,
    inputs: &BatchInput<'_>,
    fy_n: &mut Vec<f64>,
) -> Result<(), BatchLengthError> {
    let n = inputs.validate()?;
    fy_n.clear();
    fy_n.reserve(n);
    for i in 0..n {
        fy_n.push(crate::model::pure_fy(params, mode, &inputs.point(i)));
    }
    Ok(())
}

//! Struct-of-arrays evaluation for fitting and simulation.

use crate::kernel::{Inputs, Kernel, Outputs, eval_chunk, pure_fy_chunk, want};
use crate::lanes::{L, V};
use crate::model::{Clamped, MfInput, MfOutput, UseMode};
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

/// Calls `$m!(fx_n, fy_n, …, kxk_n $(, extra)*)`: the `f64` columns (every column but
/// `clamped`), then any extra names. The one list of output columns; the kernel uses it too.
macro_rules! for_each_value_column {
    ($m:ident $(, $extra:ident)*) => {
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
            kxk_n
            $(, $extra)*
        )
    };
}
pub(crate) use for_each_value_column;

/// Every column, `clamped` last.
macro_rules! for_each_column {
    ($m:ident) => {
        for_each_value_column!($m, clamped)
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

/// Evaluates every point of `inputs` into `out` (cleared first; allocations reused).
///
/// Points are evaluated four at a time by the lane-wise kernel (`kernel.rs`),
/// whose results agree with [`crate::evaluate`] point by point to a few ulp (≤ 1e-13 relative,
/// tested); runs of points that share Fz, pressure and camber (sweeps) reuse the load-dependent
/// terms.
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
    let k = Kernel::new(params, scaling, mode);
    full_dispatch(&k, inputs, out);
    Ok(())
}

/// Pure lateral force for every point into `fy_n` (cleared first), by the lane-wise kernel.
pub fn pure_fy_batch(
    params: &TyreParams,
    mode: UseMode,
    inputs: &BatchInput<'_>,
    fy_n: &mut Vec<f64>,
) -> Result<(), BatchLengthError> {
    let n = inputs.validate()?;
    fy_n.clear();
    fy_n.reserve(n);
    let k = Kernel::new(params, &params.scaling, mode);
    pure_fy_dispatch(&k, inputs, fy_n);
    Ok(())
}

/// One output of the model, for [`evaluate_column`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum BatchColumn {
    /// Fx, N (combined slip in combined modes).
    FxN,
    /// Fy, N.
    FyN,
    /// Mz, N·m.
    MzNm,
    /// Mx, N·m.
    MxNm,
    /// My, N·m.
    MyNm,
    /// Effective rolling radius, m.
    ReM,
    /// Loaded radius, m.
    RlM,
    /// Longitudinal carcass stiffness, N/m.
    CxNpm,
    /// Lateral relaxation length, m.
    SigmayM,
}

impl BatchColumn {
    /// This column of a chunk's outputs.
    #[inline(always)]
    fn of(self, o: &Outputs) -> V {
        match self {
            BatchColumn::FxN => o.fx_n,
            BatchColumn::FyN => o.fy_n,
            BatchColumn::MzNm => o.mz_nm,
            BatchColumn::MxNm => o.mx_nm,
            BatchColumn::MyNm => o.my_nm,
            BatchColumn::ReM => o.re_m,
            BatchColumn::RlM => o.rl_m,
            BatchColumn::CxNpm => o.cx_npm,
            BatchColumn::SigmayM => o.sigmay_m,
        }
    }
}

/// One output column for every point into `out` (cleared first): the values of
/// [`evaluate_batch`]'s column of the same name, computing only the terms that column needs.
///
/// This is what a fit calls in its inner loop (residuals and Jacobian columns of one channel):
/// Mx, for example, needs the lateral force but no aligning moment, rolling resistance or radii.
/// The values are those of the full evaluation, bit for bit, except in a chunk where the full
/// evaluation fell back to the scalar model because of an output this column does not use
/// (then they agree to a few ulp); `tests/batch.rs` checks every column in every mode.
pub fn evaluate_column(
    params: &TyreParams,
    mode: UseMode,
    inputs: &BatchInput<'_>,
    column: BatchColumn,
    out: &mut Vec<f64>,
) -> Result<(), BatchLengthError> {
    let n = inputs.validate()?;
    out.clear();
    out.reserve(n);
    let k = Kernel::new(params, &params.scaling, mode);
    column_dispatch(&k, inputs, column, out);
    Ok(())
}

/// Chunk `start..start + L` of `inputs` (lanes past the end repeat the last point).
#[inline(always)]
fn chunk(inputs: &BatchInput<'_>, start: usize, n: usize) -> Inputs {
    let col = |s: &[f64]| -> V {
        if s.is_empty() {
            V::splat(0.0)
        } else if start + L <= n {
            let mut a = [0.0; L];
            a.copy_from_slice(&s[start..start + L]);
            V(a)
        } else {
            V(std::array::from_fn(|i| s[(start + i).min(n - 1)]))
        }
    };
    Inputs {
        fz: col(inputs.fz_n),
        kappa: col(inputs.kappa),
        alpha: col(inputs.alpha_rad),
        gamma: col(inputs.gamma_rad),
        phit: col(inputs.phit_per_m),
        vx: col(inputs.vx_mps),
        p: col(inputs.p_pa),
        omega: col(inputs.omega_radps),
    }
}

/// The batch loop over the kernel; inlined into each instruction-set variant below.
#[inline(always)]
fn full_generic<const F: bool>(k: &Kernel<'_>, inputs: &BatchInput<'_>, out: &mut BatchOutput) {
    let n = inputs.len();
    let mut cache = None;
    let mut start = 0;
    while start < n {
        let m = L.min(n - start);
        let o = eval_chunk::<F, { want::ALL }>(k, &chunk(inputs, start, n), &mut cache);
        if m == L {
            // Fixed-length copies compile to plain vector stores.
            macro_rules! store {
                ($($f:ident),*) => { $( out.$f.extend_from_slice(&o.$f.0); )* };
            }
            for_each_value_column!(store);
            out.clamped.extend_from_slice(&o.clamped);
        } else {
            macro_rules! store {
                ($($f:ident),*) => { $( out.$f.extend_from_slice(&o.$f.0[..m]); )* };
            }
            for_each_value_column!(store);
            out.clamped.extend_from_slice(&o.clamped[..m]);
        }
        start += L;
    }
}

#[inline(always)]
fn column_generic<const F: bool, const W: u32>(
    k: &Kernel<'_>,
    inputs: &BatchInput<'_>,
    column: BatchColumn,
    out: &mut Vec<f64>,
) {
    let n = inputs.len();
    let mut cache = None;
    let mut start = 0;
    while start < n {
        let m = L.min(n - start);
        let o = eval_chunk::<F, W>(k, &chunk(inputs, start, n), &mut cache);
        let v = column.of(&o);
        if m == L {
            out.extend_from_slice(&v.0);
        } else {
            out.extend_from_slice(&v.0[..m]);
        }
        start += L;
    }
}

/// [`column_generic`] for `column`, with the mask its output needs.
#[inline(always)]
fn column_masked<const F: bool>(k: &Kernel<'_>, inputs: &BatchInput<'_>, column: BatchColumn, out: &mut Vec<f64>) {
    match column {
        BatchColumn::FxN => column_generic::<F, { want::FX }>(k, inputs, column, out),
        BatchColumn::FyN => column_generic::<F, { want::FY }>(k, inputs, column, out),
        BatchColumn::MzNm => column_generic::<F, { want::MZ }>(k, inputs, column, out),
        BatchColumn::MxNm => column_generic::<F, { want::MX }>(k, inputs, column, out),
        BatchColumn::MyNm => column_generic::<F, { want::MY }>(k, inputs, column, out),
        BatchColumn::ReM => column_generic::<F, { want::RE }>(k, inputs, column, out),
        BatchColumn::RlM => column_generic::<F, { want::RADII }>(k, inputs, column, out),
        BatchColumn::CxNpm | BatchColumn::SigmayM => column_generic::<F, { want::LOAD_ONLY }>(k, inputs, column, out),
    }
}

#[inline(always)]
fn pure_fy_generic<const F: bool>(k: &Kernel<'_>, inputs: &BatchInput<'_>, fy_n: &mut Vec<f64>) {
    let n = inputs.len();
    let mut start = 0;
    while start < n {
        let m = L.min(n - start);
        let fy = pure_fy_chunk::<F>(k, &chunk(inputs, start, n));
        if m == L {
            fy_n.extend_from_slice(&fy.0);
        } else {
            fy_n.extend_from_slice(&fy.0[..m]);
        }
        start += L;
    }
}

fn full_portable(k: &Kernel<'_>, inputs: &BatchInput<'_>, out: &mut BatchOutput) {
    full_generic::<false>(k, inputs, out);
}

fn pure_fy_portable(k: &Kernel<'_>, inputs: &BatchInput<'_>, fy_n: &mut Vec<f64>) {
    pure_fy_generic::<false>(k, inputs, fy_n);
}

fn column_portable(k: &Kernel<'_>, inputs: &BatchInput<'_>, column: BatchColumn, out: &mut Vec<f64>) {
    column_masked::<false>(k, inputs, column, out);
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
fn column_avx2(k: &Kernel<'_>, inputs: &BatchInput<'_>, column: BatchColumn, out: &mut Vec<f64>) {
    column_masked::<true>(k, inputs, column, out);
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
fn full_avx2(k: &Kernel<'_>, inputs: &BatchInput<'_>, out: &mut BatchOutput) {
    full_generic::<true>(k, inputs, out);
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
fn pure_fy_avx2(k: &Kernel<'_>, inputs: &BatchInput<'_>, fy_n: &mut Vec<f64>) {
    pure_fy_generic::<true>(k, inputs, fy_n);
}

/// True when the CPU runs the AVX2 build of the kernel.
pub(crate) fn have_avx2() -> bool {
    #[cfg(target_arch = "x86_64")]
    {
        std::is_x86_feature_detected!("avx2") && std::is_x86_feature_detected!("fma")
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        false
    }
}

fn full_dispatch(k: &Kernel<'_>, inputs: &BatchInput<'_>, out: &mut BatchOutput) {
    #[cfg(target_arch = "x86_64")]
    if have_avx2() {
        // SAFETY: `full_avx2` only requires the CPU features AVX2 and FMA, checked just above
        // by `have_avx2` (std's runtime CPUID detection); it has no other preconditions.
        #[allow(unsafe_code)]
        unsafe {
            full_avx2(k, inputs, out)
        };
        return;
    }
    full_portable(k, inputs, out);
}

fn column_dispatch(k: &Kernel<'_>, inputs: &BatchInput<'_>, column: BatchColumn, out: &mut Vec<f64>) {
    #[cfg(target_arch = "x86_64")]
    if have_avx2() {
        // SAFETY: as in `full_dispatch`: AVX2 and FMA were detected at run time.
        #[allow(unsafe_code)]
        unsafe {
            column_avx2(k, inputs, column, out)
        };
        return;
    }
    column_portable(k, inputs, column, out);
}

fn pure_fy_dispatch(k: &Kernel<'_>, inputs: &BatchInput<'_>, fy_n: &mut Vec<f64>) {
    #[cfg(target_arch = "x86_64")]
    if have_avx2() {
        // SAFETY: as in `full_dispatch`: AVX2 and FMA were detected at run time.
        #[allow(unsafe_code)]
        unsafe {
            pure_fy_avx2(k, inputs, fy_n)
        };
        return;
    }
    pure_fy_portable(k, inputs, fy_n);
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The AVX2+FMA build of the kernel (what `evaluate_batch` runs on this CPU when available)
    /// and the portable build agree to ~1e-15: they differ only in vector width and in the lane
    /// functions' polynomials using fused multiply-add.
    #[test]
    fn dispatched_and_portable_kernels_agree() {
        let text = std::fs::read_to_string(
            std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
                .join("../../launch-config/tyres/MagicFormula61_Paramerters.tir"),
        )
        .expect("sample tyre");
        let params = TyreParams::from_tir_str(&text, "MagicFormula61_Paramerters.tir").expect("parses");
        let mut seed = 99_u64;
        let mut rnd = |lo: f64, hi: f64| {
            seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            lo + (hi - lo) * ((seed >> 11) as f64 / (1u64 << 53) as f64)
        };
        let n = 4099;
        let mut cols: [Vec<f64>; 7] = Default::default();
        for _ in 0..n {
            let r = [
                rnd(-100.0, 20000.0),
                rnd(-1.0, 1.0),
                rnd(-1.0, 1.0),
                rnd(-0.12, 0.12),
                rnd(-40.0, 40.0),
                rnd(1e5, 4e5),
                if rnd(0.0, 1.0) < 0.5 { 0.0 } else { rnd(0.0, 150.0) },
            ];
            for (c, v) in cols.iter_mut().zip(r) {
                c.push(v);
            }
        }
        let inputs = BatchInput {
            fz_n: &cols[0],
            kappa: &cols[1],
            alpha_rad: &cols[2],
            gamma_rad: &cols[3],
            vx_mps: &cols[4],
            p_pa: &cols[5],
            omega_radps: &cols[6],
            ..Default::default()
        };
        for mode in [UseMode::M111, UseMode::M121, UseMode::M212] {
            let k = Kernel::new(&params, &params.scaling, mode);
            let mut portable = BatchOutput::default();
            full_portable(&k, &inputs, &mut portable);
            let mut dispatched = BatchOutput::default();
            full_dispatch(&k, &inputs, &mut dispatched);
            assert_eq!(portable.len(), n);
            let close = |a: f64, b: f64, scale: f64| {
                a.to_bits() == b.to_bits() || (a - b).abs() <= 1e-13 * b.abs().max(scale) || (a.is_nan() && b.is_nan())
            };
            macro_rules! cmp {
                ($($f:ident),*) => { $(
                    let scale = portable.$f.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
                    for (i, (a, b)) in dispatched.$f.iter().zip(&portable.$f).enumerate() {
                        assert!(close(*a, *b, scale), "{mode} point {i} {}: {a:e} vs {b:e}", stringify!($f));
                    }
                )* };
            }
            for_each_value_column!(cmp);
            assert_eq!(portable.clamped, dispatched.clamped);
            let (mut fa, mut fb) = (Vec::new(), Vec::new());
            pure_fy_portable(&k, &inputs, &mut fa);
            pure_fy_dispatch(&k, &inputs, &mut fb);
            let scale = fa.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
            assert!(fa.iter().zip(&fb).all(|(a, b)| close(*b, *a, scale)), "{mode} pure Fy");
        }
        println!("AVX2+FMA available: {}", have_avx2());
    }
}

//! Scalar atan, sin, cos and tan that are several times faster than the platform libm and
//! accurate to a few ulp over the arguments a tyre model produces.
//!
//! The model spends most of its time in some 45 transcendental calls per operating point;
//! glibc's correctly-rounded-ish versions cost 10–15 ns each. These use Cody–Waite range
//! reduction and the published Cephes minimax polynomials (Moshier, *Methods and Programs for
//! Mathematical Functions*), whose stated peak relative errors are below 1e-16 on the reduced
//! range, so results stay within ~2 ulp of libm — far inside the 1e-9 agreement the model is
//! tested to. Arguments beyond the range where the three-part π/4 reduction is exact fall back
//! to the standard library.

// The constants are quoted with the digits they are published with; rounding them by hand
// would only add a chance of a typo.
#![allow(clippy::excessive_precision)]

use std::f64::consts::{FRAC_PI_2, FRAC_PI_4};

/// Beyond this |x| the reduction constants lose accuracy; defer to libm.
const REDUCTION_LIMIT: f64 = 1.0e8;

const FOUR_OVER_PI: f64 = 1.273_239_544_735_162_7;
// π/4 split in three parts so that j·DP1 and j·DP2 are exact for the j we allow.
const DP1: f64 = 7.853_981_256_484_985_351_56e-1;
const DP2: f64 = 3.774_894_707_930_798_176_68e-8;
const DP3: f64 = 2.695_151_429_079_059_526_45e-15;

const SIN_C: [f64; 6] = [
    1.589_623_015_765_465_680_60e-10,
    -2.505_074_776_285_780_728_66e-8,
    2.755_731_362_138_572_452_13e-6,
    -1.984_126_982_958_953_859_96e-4,
    8.333_333_333_322_118_588_78e-3,
    -1.666_666_666_666_663_072_95e-1,
];

const COS_C: [f64; 6] = [
    -1.135_853_652_138_768_173_00e-11,
    2.087_570_084_197_473_167_78e-9,
    -2.755_731_417_929_673_881_12e-7,
    2.480_158_728_885_170_453_48e-5,
    -1.388_888_888_887_305_641_16e-3,
    4.166_666_666_666_659_292_18e-2,
];

const ATAN_P: [f64; 5] = [
    -8.750_608_600_031_904_122_785e-1,
    -1.615_753_718_733_365_076_637e1,
    -7.500_855_792_314_704_667_340e1,
    -1.228_866_684_490_136_173_410e2,
    -6.485_021_904_942_025_371_773e1,
];

const ATAN_Q: [f64; 5] = [
    2.485_846_490_142_306_297_962e1,
    1.650_270_098_316_988_542_046e2,
    4.328_810_604_912_902_668_951e2,
    4.853_903_996_359_136_964_868e2,
    1.945_506_571_482_613_964_425e2,
];

/// tan(3π/8).
const T3P8: f64 = 2.414_213_562_373_095_048_80;
/// The part of π/2 that the f64 constant misses.
const MOREBITS: f64 = 6.123_233_995_736_766e-17;

#[inline(always)]
fn sin_poly(z: f64, zz: f64) -> f64 {
    let p = ((((SIN_C[0] * zz + SIN_C[1]) * zz + SIN_C[2]) * zz + SIN_C[3]) * zz + SIN_C[4]) * zz + SIN_C[5];
    z + z * zz * p
}

#[inline(always)]
fn cos_poly(zz: f64) -> f64 {
    let p = ((((COS_C[0] * zz + COS_C[1]) * zz + COS_C[2]) * zz + COS_C[3]) * zz + COS_C[4]) * zz + COS_C[5];
    1.0 - 0.5 * zz + zz * zz * p
}

/// Reduces |x| to z in [−π/4, π/4] and the even octant j ∈ {0, 2, 4, 6} with |x| = z + j·π/4.
#[inline(always)]
fn reduce(ax: f64) -> (f64, u32) {
    let mut j = (ax * FOUR_OVER_PI) as u64;
    j += j & 1;
    let y = j as f64;
    let z = ((ax - y * DP1) - y * DP2) - y * DP3;
    (z, (j & 7) as u32)
}

/// sin(x).
#[inline(always)]
pub(crate) fn sin(x: f64) -> f64 {
    let ax = x.abs();
    if ax >= REDUCTION_LIMIT || ax.is_nan() {
        return x.sin();
    }
    let (z, j) = reduce(ax);
    let zz = z * z;
    // sin(z + jπ/4): j = 0 → sin z, 2 → cos z, 4 → −sin z, 6 → −cos z.
    let r = if j & 2 == 0 { sin_poly(z, zz) } else { cos_poly(zz) };
    let r = if j >= 4 { -r } else { r };
    if x < 0.0 { -r } else { r }
}

/// cos(x).
#[inline(always)]
pub(crate) fn cos(x: f64) -> f64 {
    let ax = x.abs();
    if ax >= REDUCTION_LIMIT || ax.is_nan() {
        return x.cos();
    }
    let (z, j) = reduce(ax);
    let zz = z * z;
    // cos(z + jπ/4): j = 0 → cos z, 2 → −sin z, 4 → −cos z, 6 → sin z.
    let r = if j & 2 == 0 { cos_poly(zz) } else { -sin_poly(z, zz) };
    if j >= 4 { -r } else { r }
}

/// (sin x, cos x) with one range reduction.
#[inline(always)]
pub(crate) fn sin_cos(x: f64) -> (f64, f64) {
    let ax = x.abs();
    if ax >= REDUCTION_LIMIT || ax.is_nan() {
        return x.sin_cos();
    }
    let (z, j) = reduce(ax);
    let zz = z * z;
    let sp = sin_poly(z, zz);
    let cp = cos_poly(zz);
    let (s, c) = match j {
        0 => (sp, cp),
        2 => (cp, -sp),
        4 => (-sp, -cp),
        _ => (-cp, sp),
    };
    (if x < 0.0 { -s } else { s }, c)
}

/// tan(x) as sin/cos (±inf-free except exactly at the poles, which f64 cannot represent).
#[inline(always)]
pub(crate) fn tan(x: f64) -> f64 {
    let (s, c) = sin_cos(x);
    s / c
}

/// atan(x).
#[inline(always)]
pub(crate) fn atan(x: f64) -> f64 {
    let ax = x.abs();
    if ax.is_nan() {
        return x;
    }
    // Three ranges: [0, 0.66], (0.66, tan 3π/8] via atan((x−1)/(x+1)) + π/4, and beyond via
    // π/2 − atan(1/x); the polynomial is accurate on [0, 0.66].
    let (y, t, extra) = if ax > T3P8 {
        (FRAC_PI_2, -1.0 / ax, MOREBITS)
    } else if ax <= 0.66 {
        (0.0, ax, 0.0)
    } else {
        (FRAC_PI_4, (ax - 1.0) / (ax + 1.0), 0.5 * MOREBITS)
    };
    let z = t * t;
    let p = (((ATAN_P[0] * z + ATAN_P[1]) * z + ATAN_P[2]) * z + ATAN_P[3]) * z + ATAN_P[4];
    let q = ((((z + ATAN_Q[0]) * z + ATAN_Q[1]) * z + ATAN_Q[2]) * z + ATAN_Q[3]) * z + ATAN_Q[4];
    let r = y + (t * (z * p / q) + t + extra);
    if x < 0.0 { -r } else { r }
}

/// Method-call spelling of the fast functions, so equations read like the book.
pub(crate) trait Fast {
    /// Fast atan.
    fn fatan(self) -> Self;
    /// Fast sin.
    fn fsin(self) -> Self;
    /// Fast cos.
    fn fcos(self) -> Self;
    /// Fast tan.
    fn ftan(self) -> Self;
}

impl Fast for f64 {
    #[inline(always)]
    fn fatan(self) -> f64 {
        atan(self)
    }
    #[inline(always)]
    fn fsin(self) -> f64 {
        sin(self)
    }
    #[inline(always)]
    fn fcos(self) -> f64 {
        cos(self)
    }
    #[inline(always)]
    fn ftan(self) -> f64 {
        tan(self)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ulps(a: f64, b: f64) -> f64 {
        if a == b {
            return 0.0;
        }
        let scale = b.abs().max(f64::MIN_POSITIVE);
        (a - b).abs() / (scale * f64::EPSILON)
    }

    fn grid() -> impl Iterator<Item = f64> {
        // Dense near zero, then out to the large arguments slip stiffness can create.
        let small = (0..20_000).map(|i| (i as f64 - 10_000.0) * 1e-4);
        let wide = (0..20_000).map(|i| (i as f64 - 10_000.0) * 7.3e-3);
        let huge = (0..2_000).map(|i| (i as f64 - 1_000.0) * 3.7e3);
        let tiny = (0..200).map(|i| (i as f64 - 100.0) * 1e-12);
        small.chain(wide).chain(huge).chain(tiny).chain([0.0, -0.0, 1e-300, 1e300, -1e300])
    }

    #[test]
    fn atan_matches_libm() {
        let worst = grid().map(|x| ulps(atan(x), x.atan())).fold(0.0, f64::max);
        assert!(worst <= 2.0, "atan worst {worst} ulp");
    }

    #[test]
    fn sin_cos_match_libm_in_absolute_terms() {
        // Near the zeros relative error is meaningless; compare against the magnitude 1.
        for x in grid() {
            let (s, c) = sin_cos(x);
            assert!((s - x.sin()).abs() <= 4.0 * f64::EPSILON, "sin({x})");
            assert!((c - x.cos()).abs() <= 4.0 * f64::EPSILON, "cos({x})");
            assert_eq!(s.to_bits(), sin(x).to_bits());
            assert_eq!(c.to_bits(), cos(x).to_bits());
        }
    }

    #[test]
    fn sin_cos_relative_accuracy_on_small_arguments() {
        for i in 1..10_000 {
            let x = i as f64 * 1.5e-4;
            assert!(ulps(sin(x), x.sin()) <= 2.0, "sin({x})");
            assert!(ulps(cos(x), x.cos()) <= 2.0, "cos({x})");
            assert!(ulps(tan(x), x.tan()) <= 4.0, "tan({x})");
        }
    }

    #[test]
    fn special_values() {
        assert!(atan(f64::NAN).is_nan());
        assert_eq!(atan(f64::INFINITY), FRAC_PI_2);
        assert!(sin(f64::NAN).is_nan());
        assert!(cos(f64::INFINITY).is_nan());
        assert_eq!(sin(0.0), 0.0);
        assert_eq!(cos(0.0), 1.0);
    }
}

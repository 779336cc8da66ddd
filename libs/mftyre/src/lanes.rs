//! Lane-wise arithmetic for the batch kernel: [`V`] holds [`L`] `f64` values (one per point),
//! [`M`] a per-lane condition, and the transcendental functions below work on all lanes at once
//! without branches, so that LLVM turns them into SIMD code (SSE2 on the baseline target, AVX2
//! and FMA through the runtime dispatch in `batch.rs`).
//!
//! The functions are written from the textbook method: Cody–Waite argument reduction (the
//! reduction constant split so that `k·C_hi` is exact), then a polynomial on the reduced range.
//! The polynomial coefficients are Chebyshev fits computed for this crate with mpmath
//! (`mpmath.chebyfit` at 60 digits; the fitted function and range are given at each table) —
//! they agree with the Taylor coefficients in their leading digits. Polynomials are evaluated by
//! Estrin's scheme (the kernel is latency-bound, and Estrin's chains are log₂ N long). Accuracy
//! against `std` (tests below): ≤ 2 ulp for atan, sin, cos, exp, ln and cbrt over wide ranges,
//! with and without FMA.
//!
//! The functions are reached through [`Guard`], which records the lanes whose argument is outside
//! a fast path's range (|x| > 1e5 for sin/cos, |x| > 708 for exp, non-normal x for ln/cbrt); the
//! kernel then redoes that chunk with the scalar model, so the fast paths stay branch-free.
//! `Guard<F>`: with `F` (the AVX2+FMA build) multiply-adds are fused; without, they are a plain
//! `a * b + c` (`mul_add` without hardware FMA would be a slow library call).

use std::ops::{Add, BitAnd, BitOr, Div, Mul, Neg, Not, Sub};

/// Points evaluated together.
pub(crate) const L: usize = 4;

/// One `f64` per lane.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct V(pub [f64; L]);

/// One condition per lane.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct M(pub [bool; L]);

#[inline(always)]
fn vf(f: impl FnMut(usize) -> f64) -> V {
    V(std::array::from_fn(f))
}

#[inline(always)]
fn mf(f: impl FnMut(usize) -> bool) -> M {
    M(std::array::from_fn(f))
}

impl V {
    #[inline(always)]
    pub(crate) fn splat(x: f64) -> V {
        V([x; L])
    }
    #[inline(always)]
    pub(crate) fn map(self, f: impl Fn(f64) -> f64) -> V {
        vf(|i| f(self.0[i]))
    }
    #[inline(always)]
    pub(crate) fn abs(self) -> V {
        self.map(f64::abs)
    }
    #[inline(always)]
    pub(crate) fn sqrt(self) -> V {
        self.map(f64::sqrt)
    }
    /// `f64::max` per lane (a NaN lane gives the other operand).
    #[inline(always)]
    pub(crate) fn max(self, o: impl Into<V>) -> V {
        let o = o.into();
        vf(|i| self.0[i].max(o.0[i]))
    }
    /// `f64::min` per lane.
    #[inline(always)]
    pub(crate) fn min(self, o: impl Into<V>) -> V {
        let o = o.into();
        vf(|i| self.0[i].min(o.0[i]))
    }
    #[inline(always)]
    pub(crate) fn clamp(self, lo: f64, hi: f64) -> V {
        self.map(|x| x.clamp(lo, hi))
    }
    #[inline(always)]
    pub(crate) fn copysign(self, sign: V) -> V {
        vf(|i| self.0[i].copysign(sign.0[i]))
    }
    #[inline(always)]
    pub(crate) fn lt(self, o: impl Into<V>) -> M {
        let o = o.into();
        mf(|i| self.0[i] < o.0[i])
    }
    #[inline(always)]
    pub(crate) fn le(self, o: impl Into<V>) -> M {
        let o = o.into();
        mf(|i| self.0[i] <= o.0[i])
    }
    #[inline(always)]
    pub(crate) fn gt(self, o: impl Into<V>) -> M {
        let o = o.into();
        mf(|i| self.0[i] > o.0[i])
    }
    #[inline(always)]
    pub(crate) fn ge(self, o: impl Into<V>) -> M {
        let o = o.into();
        mf(|i| self.0[i] >= o.0[i])
    }
    #[inline(always)]
    pub(crate) fn eq(self, o: impl Into<V>) -> M {
        let o = o.into();
        mf(|i| self.0[i] == o.0[i])
    }
    #[inline(always)]
    pub(crate) fn ne(self, o: impl Into<V>) -> M {
        let o = o.into();
        mf(|i| self.0[i] != o.0[i])
    }
    /// Bitwise equality of every lane (the load-case cache key).
    #[inline(always)]
    pub(crate) fn same_bits(self, o: V) -> bool {
        (0..L).all(|i| self.0[i].to_bits() == o.0[i].to_bits())
    }
}

impl From<f64> for V {
    #[inline(always)]
    fn from(x: f64) -> V {
        V::splat(x)
    }
}

/// `if m { a } else { b }` per lane.
#[inline(always)]
pub(crate) fn sel(m: M, a: impl Into<V>, b: impl Into<V>) -> V {
    let (a, b) = (a.into(), b.into());
    vf(|i| if m.0[i] { a.0[i] } else { b.0[i] })
}

impl M {
    #[inline(always)]
    pub(crate) fn any(self) -> bool {
        self.0.iter().fold(false, |a, &b| a | b)
    }
    #[inline(always)]
    pub(crate) fn all(self) -> bool {
        self.0.iter().fold(true, |a, &b| a & b)
    }
}

impl BitAnd for M {
    type Output = M;
    #[inline(always)]
    fn bitand(self, o: M) -> M {
        mf(|i| self.0[i] & o.0[i])
    }
}

impl BitOr for M {
    type Output = M;
    #[inline(always)]
    fn bitor(self, o: M) -> M {
        mf(|i| self.0[i] | o.0[i])
    }
}

impl Not for M {
    type Output = M;
    #[inline(always)]
    fn not(self) -> M {
        mf(|i| !self.0[i])
    }
}

macro_rules! binop {
    ($tr:ident, $f:ident, $op:tt) => {
        impl $tr for V {
            type Output = V;
            #[inline(always)]
            fn $f(self, o: V) -> V {
                vf(|i| self.0[i] $op o.0[i])
            }
        }
        impl $tr<f64> for V {
            type Output = V;
            #[inline(always)]
            fn $f(self, o: f64) -> V {
                vf(|i| self.0[i] $op o)
            }
        }
        impl $tr<V> for f64 {
            type Output = V;
            #[inline(always)]
            fn $f(self, o: V) -> V {
                vf(|i| self $op o.0[i])
            }
        }
    };
}
binop!(Add, add, +);
binop!(Sub, sub, -);
binop!(Mul, mul, *);
binop!(Div, div, /);

impl Neg for V {
    type Output = V;
    #[inline(always)]
    fn neg(self) -> V {
        vf(|i| -self.0[i])
    }
}

/// Polynomial with coefficients lowest degree first, by Estrin's scheme: pairs c₂ᵢ + c₂ᵢ₊₁·x,
/// then pairs of those with x², x⁴, … The dependency chain is log₂ N steps long instead of N
/// (Horner), which matters more here than the operation count: the kernel is latency-bound.
#[inline(always)]
fn poly<const F: bool, const N: usize>(x: V, c: &[f64; N]) -> V {
    let mut t: [V; N] = std::array::from_fn(|i| V::splat(c[i]));
    let mut n = N;
    let mut p = x;
    while n > 1 {
        let m = n.div_ceil(2);
        for i in 0..m {
            t[i] = if 2 * i + 1 < n { mla::<F>(t[2 * i + 1], p, t[2 * i]) } else { t[2 * i] };
        }
        n = m;
        p = p * p;
    }
    t[0]
}

/// a·b + c: fused (one rounding) when `F`, the build having FMA; otherwise multiply then add.
#[inline(always)]
fn mla<const F: bool>(a: V, b: impl Into<V>, c: impl Into<V>) -> V {
    let (b, c) = (b.into(), c.into());
    if F { vf(|i| a.0[i].mul_add(b.0[i], c.0[i])) } else { a * b + c }
}

/// Adding then subtracting 1.5·2⁵² rounds to the nearest integer (|x| < 2⁵¹) and leaves the
/// integer in the low bits of the intermediate sum.
const SHIFTER: f64 = 6755399441055744.0;

/// π/2 and π/4 as a double plus the rounding remainder.
const PIO2_HI: f64 = std::f64::consts::FRAC_PI_2;
const PIO2_LO: f64 = 6.123233995736766e-17;
const PIO4_HI: f64 = std::f64::consts::FRAC_PI_4;
const PIO4_LO: f64 = 3.061616997868383e-17;
/// tan(π/8) and tan(3π/8): the atan reduction thresholds.
const TAN_PI_8: f64 = 0.41421356237309503;
const TAN_3PI_8: f64 = 2.414213562373095;
/// (atan(√z)/√z − 1)/z on z ∈ [0, tan²(π/8)], degree 10; fit error 3.2e-17.
const ATAN_P: [f64; 11] = [
    -0.3333333333333333,
    0.1999999999999552,
    -0.14285714284666542,
    0.11111111015256361,
    -0.09090904578123903,
    0.07692183190826087,
    -0.06664511447381948,
    0.0585814891280221,
    -0.0508544973794026,
    0.03923165829558719,
    -0.01917688711906226,
];

/// atan per lane. |x| is reduced to |y| ≤ tan(π/8) by atan x = π/4 + atan((x−1)/(x+1)) or
/// π/2 + atan(−1/x); one division serves all three ranges.
#[inline(always)]
pub(crate) fn atan<const F: bool>(x: V) -> V {
    let a = x.abs();
    let big = a.gt(TAN_3PI_8);
    let mid = a.gt(TAN_PI_8);
    let num = sel(big, -1.0, sel(mid, a - 1.0, a));
    let den = sel(big, a, sel(mid, a + 1.0, 1.0));
    let y = num / den;
    let base = sel(big, PIO2_HI, sel(mid, PIO4_HI, 0.0));
    let base_lo = sel(big, PIO2_LO, sel(mid, PIO4_LO, 0.0));
    let z = y * y;
    let r = base + (y + mla::<F>(y * z, poly::<F, 11>(z, &ATAN_P), base_lo));
    r.copysign(x)
}

/// π/2 in three parts, the first two with 33 significant bits so that k·part is exact for
/// |k| < 2²⁰.
const PIO2_1: f64 = 1.5707963267341256;
const PIO2_2: f64 = 6.077100506303966e-11;
const PIO2_3: f64 = 2.0222662487959506e-21;
/// Largest |x| for the fast sin/cos path (beyond it std is used).
const TRIG_MAX: f64 = 1.0e5;
/// (sin √z/√z − 1)/z on z ∈ [0, (π/4)²], degree 5; fit error 2.0e-17.
const SIN_S: [f64; 6] = [
    -0.16666666666666666,
    0.008333333333330948,
    -0.00019841269836758574,
    2.755731610255244e-06,
    -2.5051131845003624e-08,
    1.5918129294866608e-10,
];
/// (cos √z − 1 + z/2)/z² on z ∈ [0, (π/4)²], degree 5; fit error 1.3e-18.
const COS_C: [f64; 6] = [
    0.041666666666666664,
    -0.0013888888888887398,
    2.480158729876569e-05,
    -2.7557317271729793e-07,
    2.08761462684032e-09,
    -1.1382632425521717e-11,
];

/// Sign bit mask per lane from the quadrant bits (bit 1 of q → sign).
#[inline(always)]
fn flip(v: V, q: [u64; L]) -> V {
    vf(|i| f64::from_bits(v.0[i].to_bits() ^ ((q[i] & 2) << 62)))
}

/// (sin x, cos x) per lane: x = k·π/2 + r, |r| ≤ π/4, then the quadrant k mod 4 picks and
/// signs; also says which lanes were in the fast path's range (|x| ≤ 1e5).
#[inline(always)]
fn sin_cos_raw<const F: bool>(x: V) -> (V, V, M) {
    let t = x * std::f64::consts::FRAC_2_PI + SHIFTER;
    let k = t - SHIFTER;
    let q: [u64; L] = std::array::from_fn(|i| t.0[i].to_bits());
    let r = mla::<F>(-k, PIO2_3, mla::<F>(-k, PIO2_2, mla::<F>(-k, PIO2_1, x)));
    let z = r * r;
    // sin(−0) = −0: the polynomial term would add +0.
    let s = sel(z.eq(0.0), r, mla::<F>(r * z, poly::<F, 6>(z, &SIN_S), r));
    let c = 1.0 - mla::<F>(-(z * z), poly::<F, 6>(z, &COS_C), 0.5 * z);
    let odd = M(std::array::from_fn(|i| q[i] & 1 != 0));
    let sin = flip(sel(odd, c, s), q);
    let q1: [u64; L] = std::array::from_fn(|i| q[i].wrapping_add(1));
    let cos = flip(sel(odd, s, c), q1);
    (sin, cos, x.abs().le(TRIG_MAX))
}

/// ln 2 with 32 significant bits (k·LN2_HI exact for |k| < 2²¹) and the remainder.
const LN2_HI: f64 = 0.6931471803691238;
const LN2_LO: f64 = 1.9082149292705877e-10;
/// (eʳ − 1 − r)/r² on r ∈ [−ln2/2, ln2/2], degree 10; fit error 1.4e-18.
const EXP_E: [f64; 11] = [
    0.5,
    0.1666666666666667,
    0.04166666666666667,
    0.008333333333326141,
    0.0013888888888883752,
    0.00019841269874800493,
    2.4801587325533363e-05,
    2.7557255425746435e-06,
    2.7557273661348637e-07,
    2.510520637395701e-08,
    2.0914679376583935e-09,
];

/// exp per lane: x = k·ln2 + r, |r| ≤ ln2/2, eˣ = 2ᵏ·eʳ (fast path for |x| ≤ 708).
#[inline(always)]
fn exp_raw<const F: bool>(x: V) -> (V, M) {
    let t = x * std::f64::consts::LOG2_E + SHIFTER;
    let k = t - SHIFTER;
    let r = mla::<F>(-k, LN2_LO, mla::<F>(-k, LN2_HI, x));
    let e = 1.0 + mla::<F>(r * r, poly::<F, 11>(r, &EXP_E), r);
    // 2^k built from its bits: k sits in the low bits of t (two's complement for k < 0).
    let scale = vf(|i| f64::from_bits((t.0[i].to_bits().wrapping_add(1023) & 0x7ff) << 52));
    (e * scale, x.abs().le(708.0))
}

/// 2·atanh(√w)/√w − 2)/w on w ∈ [0, ((√2−1)/(√2+1))²], degree 7; fit error 2.1e-18.
const LN_L: [f64; 8] = [
    0.6666666666666666,
    0.4000000000000088,
    0.28571428570803614,
    0.22222222391713917,
    0.18181795640132906,
    0.15386239702814658,
    0.13268773138656886,
    0.13086626147840102,
];

/// Natural logarithm per lane: x = 2ᵉ·m with m ∈ [√½, √2), ln m = 2·atanh s, s = (m−1)/(m+1).
/// Fast path for positive normal finite x.
#[inline(always)]
fn ln_raw<const F: bool>(x: V) -> (V, M) {
    const MANT: u64 = (1 << 52) - 1;
    let m1 = vf(|i| f64::from_bits((x.0[i].to_bits() & MANT) | 0x3ff0_0000_0000_0000));
    // The biased exponent as a double without an integer conversion: 2⁵² + e_b − (2⁵² + 1023).
    let e1 = vf(|i| f64::from_bits(0x4330_0000_0000_0000 | (x.0[i].to_bits() >> 52))) - (4503599627370496.0 + 1023.0);
    let hi = m1.gt(std::f64::consts::SQRT_2);
    let m = sel(hi, m1 * 0.5, m1);
    let e = sel(hi, e1 + 1.0, e1);
    let s = (m - 1.0) / (m + 1.0);
    let w = s * s;
    let lnm = mla::<F>(s * w, poly::<F, 8>(w, &LN_L), 2.0 * s);
    let r = mla::<F>(e, LN2_HI, mla::<F>(e, LN2_LO, lnm));
    (r, x.ge(f64::MIN_POSITIVE) & x.lt(f64::INFINITY))
}

/// Cube root per lane: exp(ln|x|/3) polished by one Newton step, sign restored (fast path
/// for normal finite x; 0 is not in it).
#[inline(always)]
fn cbrt_raw<const F: bool>(x: V) -> (V, M) {
    let a = x.abs();
    let ok = a.ge(f64::MIN_POSITIVE) & a.lt(f64::INFINITY);
    let a1 = sel(ok, a, 1.0);
    // ln and exp cannot leave their ranges here (a1 is normal, ln a1/3 ≤ 237).
    let y = exp_raw::<F>(ln_raw::<F>(a1).0 * (1.0 / 3.0)).0;
    let y = y - (y - a1 / (y * y)) * (1.0 / 3.0);
    (y.copysign(x), ok)
}

/// Collects which lanes of a chunk left the fast paths' ranges, so that the kernel can run
/// branch-free and redo the (rare) chunks that need it with the scalar model.
#[derive(Debug, Default)]
/// `F`: the build has FMA (see [`mla`]).
pub(crate) struct Guard<const F: bool>(std::cell::Cell<[bool; L]>);

impl<const F: bool> Guard<F> {
    #[inline(always)]
    fn note(&self, ok: M) {
        let b = self.0.get();
        self.0.set(std::array::from_fn(|i| b[i] | !ok.0[i]));
    }

    /// atan (no range limits).
    #[inline(always)]
    pub(crate) fn atan(&self, x: V) -> V {
        atan::<F>(x)
    }

    /// True when some lane needs the slow path.
    #[inline(always)]
    pub(crate) fn any(&self) -> bool {
        M(self.0.get()).any()
    }

    #[inline(always)]
    pub(crate) fn sin_cos(&self, x: V) -> (V, V) {
        let (s, c, ok) = sin_cos_raw::<F>(x);
        self.note(ok);
        (s, c)
    }

    #[inline(always)]
    pub(crate) fn sin(&self, x: V) -> V {
        self.sin_cos(x).0
    }

    #[inline(always)]
    pub(crate) fn cos(&self, x: V) -> V {
        self.sin_cos(x).1
    }

    #[inline(always)]
    pub(crate) fn exp(&self, x: V) -> V {
        let (r, ok) = exp_raw::<F>(x);
        self.note(ok);
        r
    }

    #[inline(always)]
    pub(crate) fn ln(&self, x: V) -> V {
        let (r, ok) = ln_raw::<F>(x);
        self.note(ok);
        r
    }

    #[inline(always)]
    pub(crate) fn cbrt(&self, x: V) -> V {
        let (r, ok) = cbrt_raw::<F>(x);
        self.note(ok);
        r
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Lanes where `ok` is false recomputed with std, as the kernel's chunk fallback does.
    fn patch(mut r: V, x: V, ok: M, f: impl Fn(f64) -> f64) -> V {
        for i in 0..L {
            if !ok.0[i] {
                r.0[i] = f(x.0[i]);
            }
        }
        r
    }

    // The functions under test, without (F = false) and with (F = true) fused multiply-add.
    fn sin_cos_f<const F: bool>(x: V) -> (V, V) {
        let (s, c, ok) = sin_cos_raw::<F>(x);
        (patch(s, x, ok, f64::sin), patch(c, x, ok, f64::cos))
    }
    fn sin_f<const F: bool>(x: V) -> V {
        sin_cos_f::<F>(x).0
    }
    fn cos_f<const F: bool>(x: V) -> V {
        sin_cos_f::<F>(x).1
    }
    fn exp_f<const F: bool>(x: V) -> V {
        let (r, ok) = exp_raw::<F>(x);
        patch(r, x, ok, f64::exp)
    }
    fn ln_f<const F: bool>(x: V) -> V {
        let (r, ok) = ln_raw::<F>(x);
        patch(r, x, ok, f64::ln)
    }
    fn cbrt_f<const F: bool>(x: V) -> V {
        let (r, ok) = cbrt_raw::<F>(x);
        patch(r, x, ok, f64::cbrt)
    }

    /// Distance in units in the last place (same-sign finite values).
    fn ulps(a: f64, b: f64) -> u64 {
        if a == b || (a.is_nan() && b.is_nan()) {
            return 0;
        }
        if a.is_nan() != b.is_nan() || a.is_sign_negative() != b.is_sign_negative() {
            // Only acceptable across zero for tiny values.
            return if (a - b).abs() < 1e-300 { 0 } else { u64::MAX };
        }
        a.to_bits().abs_diff(b.to_bits())
    }

    fn xs(lo: f64, hi: f64, n: usize, log: bool) -> Vec<f64> {
        let mut seed = 0x1234_5678_9abc_def0_u64;
        (0..n)
            .map(|_| {
                seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
                let u = (seed >> 11) as f64 / (1u64 << 53) as f64;
                if log { (lo.ln() + (hi.ln() - lo.ln()) * u).exp() } else { lo + (hi - lo) * u }
            })
            .collect()
    }

    fn max_ulp(f: impl Fn(V) -> V, g: impl Fn(f64) -> f64, x: &[f64]) -> (u64, f64) {
        let mut worst = (0, 0.0);
        for c in x.chunks_exact(L) {
            let v = f(V(c.try_into().unwrap_or([0.0; L])));
            for (&got, &x) in v.0.iter().zip(c) {
                let u = ulps(got, g(x));
                if u > worst.0 {
                    worst = (u, x);
                }
            }
        }
        worst
    }

    fn check(name: &str, f: impl Fn(V) -> V + Copy, g: impl Fn(f64) -> f64 + Copy, ranges: &[(f64, f64, bool)]) {
        for &(lo, hi, log) in ranges {
            let (u, at) = max_ulp(f, g, &xs(lo, hi, 200_000, log));
            println!("{name} on [{lo:e}, {hi:e}]: max {u} ulp at {at:e}");
            assert!(u <= 2, "{name}: {u} ulp at {at:e}");
        }
    }

    fn atan_checks<const F: bool>() {
        check(
            "atan",
            atan::<F>,
            f64::atan,
            &[(-3.0, 3.0, false), (-0.5, 0.5, false), (1e-300, 1e300, true), (-50.0, -1e-8, false)],
        );
        let specials = [0.0, -0.0, 1.0, -1.0, TAN_PI_8, TAN_3PI_8, f64::INFINITY, f64::NEG_INFINITY, 1e-310];
        for x in specials {
            let v = atan::<F>(V::splat(x)).0[0];
            assert!(ulps(v, x.atan()) <= 1, "atan({x}) = {v}");
        }
        assert!(atan::<F>(V::splat(f64::NAN)).0[0].is_nan());
    }

    fn sin_cos_checks<const F: bool>() {
        let ranges = [(-4.0, 4.0, false), (-0.8, 0.8, false), (-1e5, 1e5, false), (1e-300, 1e-3, true)];
        check("sin", sin_f::<F>, f64::sin, &ranges[..2]);
        check("cos", cos_f::<F>, f64::cos, &ranges[..3]);
        check("sin tiny", sin_f::<F>, f64::sin, &ranges[3..]);
        // Near multiples of π the result is tiny: compare absolutely there (≤ 3 ulp of 1; the
        // reduction of large arguments adds up to an ulp of the reduced angle).
        for x in xs(-1e5, 1e5, 200_000, false) {
            let (s, c) = sin_cos_f::<F>(V::splat(x));
            assert!((s.0[0] - x.sin()).abs() <= 3.5e-16, "sin({x})");
            assert!((c.0[0] - x.cos()).abs() <= 3.5e-16, "cos({x})");
        }
        for x in [1e6, -3e10, 1e300, f64::INFINITY, f64::NAN, 0.0, -0.0] {
            let (s, c) = sin_cos_f::<F>(V::splat(x));
            assert_eq!(s.0[0].to_bits(), x.sin().to_bits(), "sin({x})");
            assert_eq!(c.0[0].to_bits(), x.cos().to_bits(), "cos({x})");
        }
    }

    fn exp_ln_cbrt_checks<const F: bool>() {
        check("exp", exp_f::<F>, f64::exp, &[(-708.0, 708.0, false), (-1.0, 1.0, false), (-1e-10, 1e-10, false)]);
        check("ln", ln_f::<F>, f64::ln, &[(1e-300, 1e300, true), (0.5, 2.0, false), (0.999, 1.001, false)]);
        check("cbrt", cbrt_f::<F>, f64::cbrt, &[(1e-300, 1e300, true), (0.0, 1.0, false), (-1e3, -1e-3, false)]);
        for x in [0.0, -0.0, 1e-310, -1.0, 800.0, -800.0, f64::INFINITY, f64::NAN, f64::MAX] {
            let (e, l, c) = (exp_f::<F>(V::splat(x)).0[0], ln_f::<F>(V::splat(x)).0[0], cbrt_f::<F>(V::splat(x)).0[0]);
            assert!(ulps(e, x.exp()) <= 1, "exp({x}) = {e}");
            assert!(ulps(l, x.ln()) <= 1, "ln({x}) = {l}");
            assert!(ulps(c, x.cbrt()) <= 1, "cbrt({x}) = {c}");
        }
    }

    #[test]
    fn atan_within_2_ulp() {
        atan_checks::<false>();
        atan_checks::<true>();
    }

    #[test]
    fn sin_cos_within_2_ulp() {
        sin_cos_checks::<false>();
        sin_cos_checks::<true>();
    }

    #[test]
    fn exp_ln_cbrt_within_2_ulp() {
        exp_ln_cbrt_checks::<false>();
        exp_ln_cbrt_checks::<true>();
    }
}

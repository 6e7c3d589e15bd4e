//! Branch-free f32 transcendentals for the structure-of-arrays kernels ([`super::soa`]).
//!
//! `f32::exp`, `powf` and `acos` are calls into the C library, which stops the compiler from
//! vectorising a loop over lanes. These versions use only arithmetic, `sqrt`, comparisons
//! with selects and bit casts, so a loop that calls them on every lane compiles to SIMD code
//! (SSE2 on a baseline x86-64 build, AVX-512 with `target-cpu=native`). Range reduction and
//! polynomials follow the classic Cephes single-precision routines (Moshier), which are
//! accurate to one or two ulp over the ranges used here; the scalar leaves keep the standard
//! library, and the kernels' tests compare the two (relative 1e-5).
//!
//! No fused multiply-add is used (`mul_add` is a library call on baseline x86-64, and it
//! would make results differ between builds).

/// `a` where `c` holds, else `b`, as a bit-mask blend: a plain `if` may be turned back into
/// a branch around the computation of `a`, which stops the loop vectoriser on baseline
/// x86-64 (SSE2).
#[inline(always)]
pub fn select(c: bool, a: f32, b: f32) -> f32 {
    let m = u32::from(c).wrapping_neg();
    f32::from_bits((a.to_bits() & m) | (b.to_bits() & !m))
}

/// [`select`] per component of a vector.
#[inline(always)]
pub(crate) fn select3(c: bool, a: glam::Vec3, b: glam::Vec3) -> glam::Vec3 {
    glam::Vec3::new(
        select(c, a.x, b.x),
        select(c, a.y, b.y),
        select(c, a.z, b.z),
    )
}

/// 1.5·2²³: adding it to |x| < 2²² rounds x to the nearest integer (ties to even) in the
/// low mantissa bits.
const ROUND_MAGIC: f32 = 12_582_912.0;

/// Round to the nearest integer (|x| < 2²²): the rounded value and the same as an i32.
#[inline(always)]
fn round_i(x: f32) -> (f32, i32) {
    let t = x + ROUND_MAGIC;
    (
        t - ROUND_MAGIC,
        t.to_bits() as i32 - ROUND_MAGIC.to_bits() as i32,
    )
}

/// `2ⁿ` for an integer n in [−126, 127].
#[inline(always)]
fn pow2i(n: i32) -> f32 {
    f32::from_bits(((n + 127) as u32) << 23)
}

/// `eˣ`; 0 below −87 (where the result is near the subnormal range), `e⁸⁸` above 88.
#[inline(always)]
pub fn exp(x: f32) -> f32 {
    const LOG2_E: f32 = std::f32::consts::LOG2_E;
    // ln 2 split so that n·LN2_HI is exact for |n| < 2⁸ (Cody–Waite).
    const LN2_HI: f32 = 0.693_359_4;
    const LN2_LO: f32 = -2.121_944_4e-4;
    let xc = x.clamp(-87.0, 88.0);
    let (n, ni) = round_i(xc * LOG2_E);
    let r = xc - n * LN2_HI - n * LN2_LO;
    let p = 1.987_569_2e-4;
    let p = p * r + 1.398_2e-3;
    let p = p * r + 8.333_452e-3;
    let p = p * r + 4.166_579_6e-2;
    let p = p * r + 1.666_666_5e-1;
    let p = p * r + 0.5;
    let e = p * (r * r) + r + 1.0;
    let y = e * pow2i(ni);
    select(x < -87.0, 0.0, y)
}

/// `2ˣ`; 0 below −126, `2¹²⁷` above 127.
#[inline(always)]
pub fn exp2(x: f32) -> f32 {
    let xc = x.clamp(-126.0, 127.0);
    let (n, ni) = round_i(xc);
    let r = xc - n;
    let p = 1.535_336_2e-4;
    let p = p * r + 1.339_887_4e-3;
    let p = p * r + 9.618_437e-3;
    let p = p * r + 5.550_332_5e-2;
    let p = p * r + 2.402_264_8e-1;
    let p = p * r + 6.931_472e-1;
    let e = p * r + 1.0;
    let y = e * pow2i(ni);
    select(x < -126.0, 0.0, y)
}

/// `log₂ x` for normal positive x (subnormals, 0 and negatives give garbage: callers
/// select those lanes away).
#[inline(always)]
pub fn log2(x: f32) -> f32 {
    const SQRT_HALF: f32 = std::f32::consts::FRAC_1_SQRT_2;
    let bits = x.to_bits() as i32;
    let mut e = ((bits >> 23) & 0xff) - 127;
    let m = f32::from_bits(((bits & 0x007f_ffff) | 0x3f00_0000) as u32); // [0.5, 1)
    // x = m·2^(e+1): use 2m (in [1, √2)) when m < 1/√2, else m (in [1/√2, 1)).
    let low = m < SQRT_HALF;
    let f = select(low, m + m - 1.0, m - 1.0);
    e += i32::from(!low);
    let z = f * f;
    let p = 7.037_683_6e-2;
    let p = p * f - 1.151_461e-1;
    let p = p * f + 1.167_699_9e-1;
    let p = p * f - 1.242_014_1e-1;
    let p = p * f + 1.424_932_3e-1;
    let p = p * f - 1.666_805_8e-1;
    let p = p * f + 2.000_071_4e-1;
    let p = p * f - 2.499_999_4e-1;
    let p = p * f + 3.333_333e-1;
    let ln1p = f + (f * z * p - 0.5 * z);
    ln1p * std::f32::consts::LOG2_E + e as f32
}

/// `xʸ` for x ≥ 0 and y > 0 (0 for x below the normal range).
#[inline(always)]
#[cfg_attr(feature = "testkit", visibility::make(pub))]
pub(crate) fn pow_pos(x: f32, y: f32) -> f32 {
    let r = exp2(y * log2(x.max(f32::MIN_POSITIVE)));
    select(x < f32::MIN_POSITIVE, 0.0, r)
}

/// `acos x` for x in [−1, 1] (clamped).
#[inline(always)]
pub fn acos(x: f32) -> f32 {
    use std::f32::consts::{FRAC_PI_2, PI};
    let x = x.clamp(-1.0, 1.0);
    let a = x.abs();
    // |x| > 1/2: acos|x| = 2 asin √((1 − |x|)/2); else acos x = π/2 − asin x.
    let far = a > 0.5;
    let z = select(far, 0.5 * (1.0 - a), a * a);
    let s = select(far, z.sqrt(), a);
    let p = 4.216_32e-2;
    let p = p * z + 2.418_131e-2;
    let p = p * z + 4.547_002_6e-2;
    let p = p * z + 7.495_300_3e-2;
    let p = p * z + 1.666_675_2e-1;
    let asin_s = s + s * z * p;
    let acos_a = select(far, 2.0 * asin_s, FRAC_PI_2 - asin_s);
    select(x < 0.0, PI - acos_a, acos_a)
}

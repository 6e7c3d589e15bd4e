//! Small shared helpers of the leaves: colour reductions, hemisphere tests, sampling maps.

use glam::Vec3;
use std::f32::consts::{FRAC_1_PI, PI};

/// Linear RGB colour (Rec.709 primaries).
pub type Rgb = Vec3;

/// Smallest |μ| used in denominators.
pub(crate) const MU_EPS: f32 = 1e-7;

/// Rec.709 luminance `0.2126 r + 0.7152 g + 0.0722 b`.
#[inline]
pub fn lum(c: Rgb) -> f32 {
    0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z
}

/// Mean of the three channels.
#[inline]
#[cfg(feature = "testkit")]
pub fn mean(c: Rgb) -> f32 {
    (c.x + c.y + c.z) * (1.0 / 3.0)
}

/// `max(|μ|, 1e-7)`, the guarded denominator of the spec.
#[inline]
pub(crate) fn safe_mu(mu: f32) -> f32 {
    mu.abs().max(MU_EPS)
}

/// `x⁵` by multiplications.
#[inline]
pub(crate) fn pow5(x: f32) -> f32 {
    let x2 = x * x;
    x2 * x2 * x
}

/// `x^q`, with a multiplication-only path for the common `q = 5`.
#[inline]
pub(crate) fn pow_q(x: f32, q: f32) -> f32 {
    if q == 5.0 {
        pow5(x)
    } else {
        x.max(0.0).powf(q)
    }
}

/// Mirror reflection of `v` about the unit vector `h`: `2(v·h)h − v`.
#[inline]
pub fn reflect(v: Vec3, h: Vec3) -> Vec3 {
    2.0 * v.dot(h) * h - v
}

/// Refraction of `v` (pointing away from the surface on `h`'s side, `v·h > 0`) into a medium
/// of relative index `eta` (transmitted over incident); `None` on total internal reflection.
#[inline]
pub fn refract(v: Vec3, h: Vec3, eta: f32) -> Option<Vec3> {
    let c = v.dot(h);
    let inv = 1.0 / eta;
    let s2t = (1.0 - c * c) * inv * inv;
    if s2t >= 1.0 {
        return None;
    }
    let ct = (1.0 - s2t).sqrt();
    Some(-v * inv + (c * inv - ct) * h)
}

/// The frame flip of two-sided lobes (`z → −z`, `y → −y`; a rotation by π about `x`).
#[inline]
pub fn flip(v: Vec3) -> Vec3 {
    Vec3::new(v.x, -v.y, -v.z)
}

/// Cosine-distributed direction on the upper hemisphere from `(u1, u2)`; `None` when the
/// sample falls exactly on the horizon (zero density).
#[inline]
pub fn sample_cosine(u1: f32, u2: f32) -> Option<Vec3> {
    let r = u1.clamp(0.0, 1.0).sqrt();
    let (s, c) = (2.0 * PI * u2).sin_cos();
    let z = (1.0 - u1).max(0.0).sqrt();
    if z <= 0.0 {
        return None;
    }
    Some(Vec3::new(r * c, r * s, z))
}

/// Density of [`sample_cosine`] (per solid angle) at a direction with `z = mu`.
#[inline]
pub(crate) fn pdf_cosine(mu: f32) -> f32 {
    mu.max(0.0) * FRAC_1_PI
}

/// Uniform direction on the upper hemisphere from `(u1, u2)`.
#[inline]
pub(crate) fn sample_uniform_hemisphere(u1: f32, u2: f32) -> Vec3 {
    let z = 1.0 - u1.clamp(0.0, 1.0);
    let r = (1.0 - z * z).max(0.0).sqrt();
    let (s, c) = (2.0 * PI * u2).sin_cos();
    Vec3::new(r * c, r * s, z)
}

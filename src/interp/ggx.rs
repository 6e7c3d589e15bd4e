//! The GGX microfacet distribution (spec closures.md §3.6): NDF, Smith masking per variant,
//! visible-normal sampling, the delta cut-off, and the roughness/anisotropy mapping (§0).

use glam::Vec3;
use std::f32::consts::PI;

/// Below this `max(α_x, α_y)` a GGX lobe is a specular delta (pbrt-v4's rule).
pub const DELTA_ALPHA: f32 = 1e-3;
/// Smallest width used by a non-delta lobe on either axis (keeps `D` finite in f32).
pub const MIN_ALPHA: f32 = 1e-4;

/// Smith masking–shadowing variant, named per lobe.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Masking {
    /// `G2 = 1/(1 + Λ(V) + Λ(L))` (Heitz 2014; MaterialX, pbrt-v4, OSL testrender).
    #[default]
    HeightCorrelated,
    /// `G2 = G1(V)·G1(L)` (Adobe's OpenPBR BSDF and its tables).
    Separable,
}

/// A GGX distribution with widths `α_x` (tangent) and `α_y` (bitangent).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Ggx {
    /// Width along the tangent.
    pub ax: f32,
    /// Width along the bitangent.
    pub ay: f32,
}

impl Ggx {
    /// Widths clamped to [0, 1]; a non-delta lobe also raises each width to ≥ `MIN_ALPHA`.
    pub fn new(ax: f32, ay: f32) -> Ggx {
        let ax = if ax.is_nan() { 1.0 } else { ax.clamp(0.0, 1.0) };
        let ay = if ay.is_nan() { 1.0 } else { ay.clamp(0.0, 1.0) };
        if ax.max(ay) < DELTA_ALPHA {
            Ggx { ax, ay }
        } else {
            Ggx {
                ax: ax.max(MIN_ALPHA),
                ay: ay.max(MIN_ALPHA),
            }
        }
    }

    /// Isotropic distribution.
    pub fn isotropic(alpha: f32) -> Ggx {
        Ggx::new(alpha, alpha)
    }

    /// True when the lobe is a specular delta.
    #[inline]
    pub fn is_delta(&self) -> bool {
        self.ax.max(self.ay) < DELTA_ALPHA
    }

    /// The isotropic width used for table lookups: `√(α_x α_y)`.
    #[inline]
    pub fn lookup_alpha(&self) -> f32 {
        (self.ax * self.ay).sqrt()
    }

    /// NDF `D(h)` for a unit `h` with `h_z > 0`.
    #[inline]
    pub fn d(&self, h: Vec3) -> f32 {
        let x = h.x / self.ax;
        let y = h.y / self.ay;
        let t = x * x + y * y + h.z * h.z;
        1.0 / (PI * self.ax * self.ay * t * t)
    }

    /// Smith `Λ(ω)`, written as `x / (2(1 + √(1 + x)))` to avoid cancellation.
    #[inline]
    pub fn lambda(&self, w: Vec3) -> f32 {
        let z2 = (w.z * w.z).max(1e-14);
        let x = (self.ax * self.ax * w.x * w.x + self.ay * self.ay * w.y * w.y) / z2;
        x / (2.0 * (1.0 + (1.0 + x).sqrt()))
    }

    /// `G1(ω) = 1/(1 + Λ(ω))`.
    #[inline]
    pub fn g1(&self, w: Vec3) -> f32 {
        1.0 / (1.0 + self.lambda(w))
    }

    /// Visible-normal sample for `v` (`v_z > 0`) by spherical caps (Dupuy & Benyoub 2023).
    #[inline]
    pub fn sample_vndf(&self, v: Vec3, u1: f32, u2: f32) -> Vec3 {
        let vh = Vec3::new(self.ax * v.x, self.ay * v.y, v.z).normalize();
        let (s, c) = (2.0 * PI * u1).sin_cos();
        let z = (1.0 - u2) * (1.0 + vh.z) - vh.z;
        let r = (1.0 - z * z).max(0.0).sqrt();
        let m = Vec3::new(r * c, r * s, z) + vh;
        Vec3::new(self.ax * m.x, self.ay * m.y, m.z.max(0.0)).normalize_or(Vec3::Z)
    }
}

/// `G2` from the two Smith `Λ` values, per masking variant.
#[inline]
pub fn g2(masking: Masking, lambda_v: f32, lambda_l: f32) -> f32 {
    match masking {
        Masking::HeightCorrelated => 1.0 / (1.0 + lambda_v + lambda_l),
        Masking::Separable => 1.0 / ((1.0 + lambda_v) * (1.0 + lambda_l)),
    }
}

/// The shared roughness/anisotropy mapping of spec §0 (MaterialX `roughness_anisotropy`):
/// `α = clamp(r², 1e-6, 1)`, `s = √(1 − min(|a|, 0.98))`, `α_x = min(α/s, 1)`, `α_y = α s`;
/// negative `a` swaps the axes. Returns `(α_x, α_y)`.
pub fn roughness_to_alpha(r: f32, a: f32) -> (f32, f32) {
    let alpha = (r * r).clamp(1e-6, 1.0);
    let s = (1.0 - a.abs().min(0.98)).sqrt();
    let (along, across) = ((alpha / s).min(1.0), alpha * s);
    if a >= 0.0 {
        (along, across)
    } else {
        (across, along)
    }
}

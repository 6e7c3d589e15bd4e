//! The GGX microfacet distribution: NDF, Smith masking per variant,
//! visible-normal sampling, the delta cut-off, and the roughness/anisotropy mapping.

use glam::Vec3;
use std::f32::consts::PI;

/// Below this `max(α_x, α_y)` a GGX lobe is a specular delta (pbrt-v4's rule).
pub(crate) const DELTA_ALPHA: f32 = 1e-3;
/// Smallest width used by a non-delta lobe on either axis (keeps `D` finite in f32).
pub const MIN_ALPHA: f32 = 1e-4;

pub use crate::ir::closure::Masking;

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
    #[cfg(feature = "testkit")]
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
        lambda_squared(self.ax * self.ax, self.ay * self.ay, w)
    }

    /// `G1(ω) = 1/(1 + Λ(ω))`.
    #[inline]
    #[cfg(feature = "testkit")]
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

/// [`Ggx::lambda`] from the squared widths `α_x²`, `α_y²`.
#[inline(always)]
fn lambda_squared(ax2: f32, ay2: f32, w: Vec3) -> f32 {
    let z2 = (w.z * w.z).max(1e-14);
    let x = (ax2 * w.x * w.x + ay2 * w.y * w.y) / z2;
    x / (2.0 * (1.0 + (1.0 + x).sqrt()))
}

/// GGX reflection with the view fixed, in the division-light form shared by the scalar
/// leaves and the batched kernels ([`super::soa`]), so that the two agree to rounding.
///
/// With `H = V + L` unnormalised, `T = (Hx/αx)² + (Hy/αy)² + Hz² = |H|² t`, so
/// `D = |H|⁴/(π αx αy T²)`; `Λl = (S/l_z − 1)/2` with `S = √(l_z² + αx² lx² + αy² ly²)`
/// (`l_z` clamped at 1e-7, as [`Ggx::lambda`] clamps `l_z²` at 1e-14), so
/// `G2 = 2 l_z/(c_z l_z + c_s S)` for either masking (height-correlated: `c_z = 1 + 2Λv`,
/// `c_s = 1`; separable: both `1 + Λv`). With `P = π αx αy T² (c_z l_z + c_s S)`,
/// `D = |H|⁴ (c_z l_z + c_s S)/P` and `D G2 = |H|⁴ 2 l_z/P`: one square root and one
/// division where [`Ggx::d`], [`Ggx::lambda`] and [`g2`] take two and five.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GgxView {
    /// `1/α_x`.
    pub inv_ax: f32,
    /// `1/α_y`.
    pub inv_ay: f32,
    /// `α_x²`.
    pub ax2: f32,
    /// `α_y²`.
    pub ay2: f32,
    /// `π α_x α_y`.
    pub pi_axay: f32,
    /// The masking's coefficient of `l_z`.
    pub c_z: f32,
    /// The masking's coefficient of `S`.
    pub c_s: f32,
}

/// The shared intermediate values of [`GgxView::core`].
#[derive(Debug, Clone, Copy)]
pub struct GgxCore {
    /// `V·H` (clamped at 0).
    pub vh: f32,
    /// `|H|²`.
    pub hh: f32,
    /// `P = π αx αy T² (c_z l_z + c_s S)`.
    pub p: f32,
    /// `c_z l_z + c_s S`.
    pub den_g: f32,
    /// `l_z` clamped at 1e-7.
    pub lz: f32,
}

/// What every GGX lobe's prepare computes at view `v`: `Λ(V)`, the [`GgxView`] and
/// `G1(V) = 1/(1 + Λ(V))` (the scalar leaves and the lane-parallel prepare share it).
#[derive(Debug, Clone, Copy)]
pub struct ViewTerms {
    /// `Λ(V)`.
    pub lambda_v: f32,
    /// The view-fixed constants of `D` and `D·G2`.
    pub view: GgxView,
    /// `G1(V)`.
    pub g1_v: f32,
}

impl ViewTerms {
    /// The terms with `masking` at `v` (local frame, `v.z > 0`), from the distribution's
    /// [`GgxView::constants`], computed once per lobe by its bind: the two divisions and
    /// three products that do not depend on the view are not repeated per prepare.
    #[inline(always)]
    pub fn from_constants(c: &GgxView, masking: Masking, v: Vec3) -> ViewTerms {
        let lambda_v = lambda_squared(c.ax2, c.ay2, v);
        ViewTerms {
            lambda_v,
            view: c.with_lambda(masking, lambda_v),
            g1_v: 1.0 / (1.0 + lambda_v),
        }
    }
}

impl GgxView {
    /// The view-independent constants of a (non-delta) distribution (`c_z = c_s = 1` until
    /// [`ViewTerms::from_constants`] sets them for a view).
    pub fn constants(ggx: &Ggx) -> GgxView {
        GgxView {
            inv_ax: 1.0 / ggx.ax,
            inv_ay: 1.0 / ggx.ay,
            ax2: ggx.ax * ggx.ax,
            ay2: ggx.ay * ggx.ay,
            pi_axay: PI * ggx.ax * ggx.ay,
            c_z: 1.0,
            c_s: 1.0,
        }
    }

    /// These constants with the masking's coefficients at `Λ(V) = lambda_v`.
    #[inline(always)]
    fn with_lambda(&self, masking: Masking, lambda_v: f32) -> GgxView {
        let (c_z, c_s) = match masking {
            Masking::HeightCorrelated => (1.0 + 2.0 * lambda_v, 1.0),
            Masking::Separable => (1.0 + lambda_v, 1.0 + lambda_v),
        };
        GgxView { c_z, c_s, ..*self }
    }

    /// The intermediate values at view `v` and light `l` (`l_z > 0`). `H` is `V + L` times
    /// a power of two that brings `|H|²` into [1, 4): the outputs of [`GgxView::reflect`]
    /// and [`GgxView::reflect_squared`] are homogeneous of degree 0 in `H` (the dielectric
    /// Fresnel term takes `V·H` and `|H|²` together), so the scaling, exact in binary, changes
    /// no bit of them, and it keeps `T²|H|²` in range when `V ≈ −L` near the horizon (where
    /// `|H|²` is tiny and its cube underflows).
    #[inline(always)]
    pub fn core(&self, v: Vec3, l: Vec3) -> GgxCore {
        let (hx, hy, hz) = (v.x + l.x, v.y + l.y, v.z + l.z);
        let sc = inv_sqrt_pow2(hx * hx + hy * hy + hz * hz);
        let (hx, hy, hz) = (hx * sc, hy * sc, hz * sc);
        let hh = hx * hx + hy * hy + hz * hz;
        let (tx, ty) = (hx * self.inv_ax, hy * self.inv_ay);
        let t = tx * tx + ty * ty + hz * hz;
        let lz = l.z.max(1e-7);
        let s = (lz * lz + self.ax2 * l.x * l.x + self.ay2 * l.y * l.y).sqrt();
        let den_g = self.c_z * lz + self.c_s * s;
        GgxCore {
            vh: (v.x * hx + v.y * hy + v.z * hz).max(0.0),
            hh,
            p: self.pi_axay * t * t * den_g,
            den_g,
            lz,
        }
    }

    /// `(V·H, |H|², D(h), D(h)·G2)` at view `v` and light `l` (`l_z > 0`), `H = V + L`
    /// unnormalised: the form for the exact dielectric Fresnel term, which takes `V·H` and
    /// `|H|²` as they are ([`super::fresnel::dielectric_half`]).
    #[inline(always)]
    pub fn reflect(&self, v: Vec3, l: Vec3) -> (f32, f32, f32, f32) {
        let c = self.core(v, l);
        let hh2_r = c.hh * c.hh / c.p;
        (c.vh, c.hh, hh2_r * c.den_g, hh2_r * (2.0 * c.lz))
    }

    /// `((V·h)², |H|², D(h), D(h)·G2)` with the unit half vector's `(V·h)² =
    /// min((V·H)²/|H|², 1)` taken from the same reciprocal as `D`: the form for Fresnel
    /// terms of the cosine ([`super::fresnel::Fresnel::eval_squared`]).
    #[inline(always)]
    pub fn reflect_squared(&self, v: Vec3, l: Vec3) -> (f32, f32, f32, f32) {
        let c = self.core(v, l);
        let r = 1.0 / (c.p * c.hh);
        let hh3_r = c.hh * c.hh * c.hh * r;
        let vh2 = (c.vh * c.vh * c.p * r).min(1.0);
        (vh2, c.hh, hh3_r * c.den_g, hh3_r * (2.0 * c.lz))
    }
}

/// `2^−⌊e/2⌋` for the binary exponent `e` of `x ≥ 0` (subnormals count as `e = −127`), so
/// `x` times its square is in [1, 4) for normal `x`. Integer operations only.
#[inline(always)]
fn inv_sqrt_pow2(x: f32) -> f32 {
    let e = ((x.to_bits() >> 23) & 0xff) as i32 - 127;
    f32::from_bits(((127 - (e >> 1)) as u32) << 23)
}

/// `G2` from the two Smith `Λ` values, per masking variant.
#[inline]
pub fn g2(masking: Masking, lambda_v: f32, lambda_l: f32) -> f32 {
    match masking {
        Masking::HeightCorrelated => 1.0 / (1.0 + lambda_v + lambda_l),
        Masking::Separable => 1.0 / ((1.0 + lambda_v) * (1.0 + lambda_l)),
    }
}

/// The shared roughness/anisotropy mapping (MaterialX `roughness_anisotropy`):
/// `α = clamp(r², 1e-6, 1)`, `s = √(1 − min(|a|, 0.98))`, `α_x = min(α/s, 1)`, `α_y = α s`;
/// negative `a` swaps the axes. Returns `(α_x, α_y)`.
#[cfg(feature = "testkit")]
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

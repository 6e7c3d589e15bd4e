//! The records every layer of the folder passes around: a shading point, the options, a
//! weighted lobe of a prepared material and the results of `eval`, `sample` and `albedo`.
//! Plain data at the bottom of the folder, importing no file of it.

use crate::interp::lobe::{LobeAlbedo, PreparedLobe, Sides};
use crate::interp::math::Rgb;
use glam::{Vec2, Vec3};

/// Default of [`PrepareOptions::drop_threshold`].
pub(crate) const DEFAULT_DROP_THRESHOLD: f32 = 1e-6;

/// One shading point as the interpreter sees it. Directions are world-space unit
/// vectors.
#[derive(Debug, Clone, Copy)]
pub struct ShadingPoint<'a> {
    /// Shading normal.
    pub n: Vec3,
    /// Surface tangent (the anisotropy direction unless a lobe's frame says otherwise).
    pub t: Vec3,
    /// Direction toward the viewer.
    pub v: Vec3,
    /// External input slots, packed (see
    /// [`Material::input_layout`](super::Material::input_layout)); slots beyond the end take
    /// their fallbacks.
    pub inputs: &'a [f32],
    /// Surface position (the program's `P` global).
    pub p: Vec3,
    /// Surface parameters (the program's `u`, `v` globals).
    pub uv: Vec2,
}

impl<'a> ShadingPoint<'a> {
    /// A point with normal `n`, tangent `t` and view `v`; no inputs, `P = 0`, `uv = 0`.
    pub fn new(n: Vec3, t: Vec3, v: Vec3) -> ShadingPoint<'static> {
        ShadingPoint {
            n,
            t,
            v,
            inputs: &[],
            p: Vec3::ZERO,
            uv: Vec2::ZERO,
        }
    }

    /// The same point with these packed inputs.
    pub fn with_inputs<'b>(self, inputs: &'b [f32]) -> ShadingPoint<'b> {
        ShadingPoint {
            n: self.n,
            t: self.t,
            v: self.v,
            inputs,
            p: self.p,
            uv: self.uv,
        }
    }

    /// The same point with these surface parameters.
    pub fn with_uv(self, uv: Vec2) -> Self {
        ShadingPoint { uv, ..self }
    }

    /// The same point at this position.
    pub fn with_position(self, p: Vec3) -> Self {
        ShadingPoint { p, ..self }
    }
}

/// Result of [`Prepared::eval`](super::Prepared::eval).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Eval {
    /// `Σ_k w_k ⊙ f_k(V, L)·|μ_i|` (RGB).
    pub f_cos: Rgb,
    /// Mixture density `Σ_k p_k pdf_k(L)` per unit solid angle.
    pub pdf: f32,
}

/// Result of [`Prepared::sample`](super::Prepared::sample).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sample {
    /// Sampled direction (world space, unit).
    pub l: Vec3,
    /// `f_cos / pdf` over the mixture (one-sample balance heuristic); for delta lobes
    /// `w_k ⊙ R_k / p_k`.
    pub weight: Rgb,
    /// Mixture density; for delta lobes the discrete probability of the choice.
    pub pdf: f32,
    /// True for a delta direction (specular, straight transmission).
    pub delta: bool,
    /// Index of the chosen lobe in [`Prepared::lobes`](super::Prepared::lobes), or
    /// [`Sample::TRANSPARENCY_LOBE`].
    pub lobe: u8,
}

impl Sample {
    /// The lobe index [`Sample::lobe`] reports for straight transmission through
    /// `Transparent` leaves.
    pub const TRANSPARENCY_LOBE: u8 = u8::MAX;
}

/// Directional albedo of a prepared material or lobe, split by hemisphere.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Albedo {
    /// Reflected part.
    pub reflect: Rgb,
    /// Transmitted part as energy (`η'² E_T`): a lossless interface reports
    /// `reflect + transmit = 1`.
    pub transmit: Rgb,
    /// Transmitted part in the radiance convention (what sample weights average to).
    pub transmit_radiance: Rgb,
}

impl Albedo {
    /// `reflect + transmit` (energy).
    pub fn total(&self) -> Rgb {
        self.reflect + self.transmit
    }

    pub(super) fn scaled(a: &LobeAlbedo, w: Rgb) -> Albedo {
        Albedo {
            reflect: w * a.reflect,
            transmit: w * a.transmit_energy,
            transmit_radiance: w * a.transmit,
        }
    }

    pub(super) fn add(&mut self, o: &Albedo) {
        self.reflect += o.reflect;
        self.transmit += o.transmit;
        self.transmit_radiance += o.transmit_radiance;
    }
}

/// Options of [`Material`](super::Material).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PrepareOptions {
    /// Drop lobes with `maxc(A_k)` at or below this; 0 disables dropping.
    pub drop_threshold: f32,
    /// Whether reflection lobes also respond when seen from below (transmission lobes are
    /// always two-sided).
    pub sides: Sides,
    /// Whether [`Prepared::eval`](super::Prepared::eval) runs same-family lobes together, one
    /// per SIMD lane (the batched path's kernels; equal to the lobe-by-lobe sum to relative
    /// 1e-5). Off, every lobe is evaluated alone with its scalar leaf.
    pub pack_lobes: bool,
}

impl Default for PrepareOptions {
    fn default() -> Self {
        PrepareOptions {
            drop_threshold: DEFAULT_DROP_THRESHOLD,
            sides: Sides::Front,
            pack_lobes: true,
        }
    }
}

/// A lobe of a prepared material: the leaf's prepared state with its weight, albedo and
/// selection probability (the leaf-level
/// `PreparedLobe` is the `lobe` field).
#[derive(Debug, Clone, Copy)]
pub struct ActiveLobe {
    /// The leaf with its view-only terms, in its own frame.
    pub lobe: PreparedLobe,
    /// Weight `w_k` (includes the leaf's tint), summed over all paths.
    pub weight: Rgb,
    /// `A_k = w_k ⊙ E_k(μ_o)`.
    pub albedo: Albedo,
    /// Selection probability `p_k`.
    pub prob: f32,
    /// Index of the frame in the prepared frame list.
    pub frame: u8,
    /// Index of the leaf in [`Material::leaves`](super::Material::leaves).
    pub leaf: u8,
}

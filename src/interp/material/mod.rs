//! The interpreter API over a whole material: compile a
//! [`MaterialIr`](crate::ir::MaterialIr) once into a [`Material`], then [`Material::prepare`] per (point, view) and
//! [`Prepared::eval`] / [`Prepared::sample`] / [`Prepared::albedo`] per light direction.
//!
//! # The compile step
//! [`Material::new`] checks the IR (child order, register and frame indices, lobe count) and
//! turns it into a flat, interpreter-friendly form: the closure nodes with their children as
//! plain indices, the leaves in node order with their compact frame slot, and, per node, the
//! set of tint modes in which its throughput is ever read (a node outside every layer top
//! needs none, so the throughput pass skips it). Everything that does not depend on the
//! point is decided there, once.
//!
//! # Prepare, without heap allocation
//! `prepare` follows seven steps in order: (1) run the program, (2) build the frames and
//! `μ_o`, (3) throughput bottom-up, (4) weights top-down, (5) view-only terms and albedos of
//! the weighted lobes, (6) drop negligible lobes, (7) selection probabilities. The register file
//! and the per-node throughput and weight arrays have the IR's (unbounded) sizes, so they live in a
//! reusable [`Scratch`]: [`Material::prepare_with`] takes one from the caller,
//! [`Material::prepare`] uses a per-thread scratch (allocated on a thread's first call, reused
//! afterwards). The result, [`Prepared`], is a fixed array of `MAX_LOBES` [`ActiveLobe`]s and never
//! allocates; `eval` and `sample` neither. A uniform material seen from above its surface is
//! prepared by a fused form of the same steps over fixed arrays (`material/uniform.rs`), with the
//! same results as the general form, [`Material::prepare_general_into`].
//!
//! # Choices where the spec is silent
//! * Frames whose normal comes from a register: the program runs once with every frame's
//!   `μ_o` taken from the shading normal; when a frame's own normal gives a different `μ_o`
//!   and the program reads `ViewMu`, it runs a second time with the corrected values (a
//!   normal that depends on `μ_o` would be circular anyway).
//! * Lobe weights are clamped to be non-negative and finite (a negative tint from a program
//!   would otherwise produce a negative response).
//! * Step 6 drops a lobe when `maxc(A_k) ≤ threshold` where the transmitted part of `A_k` is
//!   the larger of its radiance and energy forms (so that a transmission lobe is dropped
//!   only when it is negligible in both conventions).
//! * Step 7's selection uses `lum(A_k)` with transmission in the radiance convention: that is
//!   what the lobe's sample weights average to, so it is the choice with the least variance.
//! * `Transparent` leaves are not lobes (they do not count toward `MAX_LOBES`, and are not in
//!   [`Prepared::lobes`] or [`Prepared::albedo`]), but `sample` does choose straight
//!   transmission (`L = −V`, weight `τ/p`) with probability `lum(τ)/Σ`, reported with
//!   lobe index [`Sample::TRANSPARENCY_LOBE`]. The mean of sample weights is therefore
//!   `albedo().reflect + albedo().transmit_radiance + transparency()`.
//! * External inputs are packed 3 floats per colour/vector slot and 1 per scalar slot, in
//!   slot order ([`Material::input_layout`]); a slot that lies (even partly) beyond the end of
//!   [`ShadingPoint::inputs`] takes its fallback.
//!
//! # Layout
//! `compile.rs` checks and flattens the IR into a [`Material`]; `leaf.rs` turns an IR leaf
//! into its lobe; `plan.rs` compiles the weight pass of a material with constant registers;
//! `prepare.rs` is the general prepare and its [`Scratch`]; `prepared.rs` is [`Prepared`]
//! (eval, sample, albedo). The fast paths, same bits as the general prepare: `uniform.rs`
//! (fused prepare of a uniform material), `lanes.rs` (lane-parallel prepare), `packs.rs`
//! (same-family lobes evaluated as lanes of one kernel).

use super::lobe::{LobeAlbedo, Sides};
use super::math::Rgb;
use crate::ir::MAX_LOBES;
use glam::{Vec2, Vec3};

mod compile;
mod lanes;
// The lobe packs: public under `testkit` for their unit tests.
testkit_mods!(packs);
mod leaf;
mod plan;
mod prepare;
mod prepared;
mod uniform;

use compile::ThrOp;
pub use compile::{LeafInfo, Material};
pub use leaf::TableAlbedo;
use plan::{Target, WeightPlan};
pub use prepare::Scratch;
use prepare::{clean, sat};
pub use prepared::{ActiveLobe, Prepared};


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
    /// External input slots, packed (see [`Material::input_layout`]); slots beyond the end
    /// take their fallbacks.
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

/// Result of [`Prepared::eval`].
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Eval {
    /// `Σ_k w_k ⊙ f_k(V, L)·|μ_i|` (RGB).
    pub f_cos: Rgb,
    /// Mixture density `Σ_k p_k pdf_k(L)` per unit solid angle.
    pub pdf: f32,
}

/// Result of [`Prepared::sample`].
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
    /// Index of the chosen lobe in [`Prepared::lobes`], or [`Sample::TRANSPARENCY_LOBE`].
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

    fn scaled(a: &LobeAlbedo, w: Rgb) -> Albedo {
        Albedo {
            reflect: w * a.reflect,
            transmit: w * a.transmit_energy,
            transmit_radiance: w * a.transmit,
        }
    }

    fn add(&mut self, o: &Albedo) {
        self.reflect += o.reflect;
        self.transmit += o.transmit;
        self.transmit_radiance += o.transmit_radiance;
    }
}

/// Options of [`Material`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PrepareOptions {
    /// Drop lobes with `maxc(A_k)` at or below this; 0 disables dropping.
    pub drop_threshold: f32,
    /// Whether reflection lobes also respond when seen from below (transmission lobes are
    /// always two-sided).
    pub sides: Sides,
    /// Whether [`Prepared::eval`] runs same-family lobes together, one per SIMD lane (the
    /// batched path's kernels; equal to the lobe-by-lobe sum to relative 1e-5). Off, every
    /// lobe is evaluated alone with its scalar leaf.
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

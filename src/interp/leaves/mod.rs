//! The BSDF leaf families, one folder each: its parameters, its scalar prepare, eval, sample
//! and albedo in the lobe's local frame, its bound form (the view-independent work of a
//! constant leaf done once) and its structure-of-arrays kernel for the batched and
//! lane-parallel paths (`soa.rs`). Here: the interface every family implements ([`Leaf`]
//! for the parameters, [`PreparedLeaf`] for the leaf prepared at a view) and the results
//! it returns ([`LobeEval`], [`LobeSample`], [`LobeAlbedo`]), so that the families import
//! this module and not the enum over them. `interp::lobe` dispatches over the families
//! with a `match` whose arms call these traits on their variant's type: static calls, no
//! trait objects. Emission and transparency are not BSDF leaves and implement neither.

pub mod diffuse;
pub mod emission;
pub mod microfacet;
pub mod sheen;
pub mod ward;

use crate::interp::math::Rgb;
use glam::Vec3;

/// A BSDF leaf family's parameters: what the interpreter prepares at a view.
///
/// Every method works in the lobe's local frame (normal `+z`) with a view above the
/// surface (`v.z > 0`, finite); the caller has already flipped the frame of a view from
/// below (`flipped` says it did, for families whose two sides differ: the dielectric).
pub trait Leaf {
    /// The leaf with its view-only terms computed.
    type Prepared: PreparedLeaf;
    /// The view-independent part of [`Leaf::prepare`], computed once for a constant leaf
    /// (`()` for families with none).
    type Bound;

    /// Precomputes every view-only term for the local view `v`.
    fn prepare(&self, v: Vec3, flipped: bool) -> Self::Prepared;

    /// The view-independent precomputation of [`Leaf::prepare`].
    fn bind(&self) -> Self::Bound;

    /// [`Leaf::prepare`] with the view-independent part read from `bound` (this leaf's
    /// [`Leaf::bind`]).
    fn prepare_bound(&self, v: Vec3, flipped: bool, bound: &Self::Bound) -> Self::Prepared;

    /// Brings `p`, a record [`Leaf::prepare_bound`] made of this leaf with `bound` and the
    /// same `flipped` at some other view, to the view `v`: afterwards it holds the bits of
    /// `prepare_bound(v, flipped, bound)`. The refresh of a record kept from an earlier
    /// point; families whose view-independent fields are worth keeping write only the
    /// view-dependent ones, the others (this default) prepare the record whole.
    #[inline(always)]
    fn set_view(&self, p: &mut Self::Prepared, v: Vec3, flipped: bool, bound: &Self::Bound) {
        *p = self.prepare_bound(v, flipped, bound);
    }
}

/// A BSDF leaf prepared at a view ([`Leaf::prepare`]): what eval and sample run on.
pub trait PreparedLeaf {
    /// `f(V, L)·|μ_i|` (RGB) and the density of [`PreparedLeaf::sample`] at `l`.
    fn eval(&self, l: Vec3) -> LobeEval;

    /// Density of [`PreparedLeaf::sample`] at `l` (0 for delta lobes).
    fn pdf(&self, l: Vec3) -> f32;

    /// Samples a direction from `u ∈ [0, 1)³`; `None` when the sample carries no energy.
    fn sample(&self, u: [f32; 3]) -> Option<LobeSample>;

    /// Directional albedo at the prepared view.
    fn albedo(&self) -> LobeAlbedo;
}

/// Result of [`PreparedLobe::eval`](crate::interp::lobe::PreparedLobe::eval): cosine-weighted
/// response and sampling density.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct LobeEval {
    /// `f(V, L)·|μ_i|`, RGB.
    pub f_cos: Rgb,
    /// Density of the lobe's sampling routine at L, per unit solid angle.
    pub pdf: f32,
}

impl LobeEval {
    /// No response, zero density.
    pub const ZERO: LobeEval = LobeEval {
        f_cos: Vec3::ZERO,
        pdf: 0.0,
    };
}

/// Result of [`PreparedLobe::sample`](crate::interp::lobe::PreparedLobe::sample).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LobeSample {
    /// Sampled direction (local frame, unit).
    pub l: Vec3,
    /// `f_cos / pdf` (for delta samples: reflectance or transmittance over the discrete
    /// probability).
    pub weight: Rgb,
    /// Density per solid angle; for delta samples the discrete probability of the choice.
    pub pdf: f32,
    /// True for a specular (delta) direction.
    pub delta: bool,
}

/// Directional albedo `∫ f |μ_i| dω` at the prepared view, split by hemisphere.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct LobeAlbedo {
    /// Reflected part.
    pub reflect: Rgb,
    /// Transmitted part as sampling weights average it (radiance convention).
    pub transmit: Rgb,
    /// Transmitted part as energy (`η'² E_T`; equal to `transmit` without an index change).
    pub transmit_energy: Rgb,
}

impl LobeAlbedo {
    /// A reflection-only albedo.
    pub fn reflect(reflect: Rgb) -> LobeAlbedo {
        LobeAlbedo {
            reflect,
            ..LobeAlbedo::default()
        }
    }
}

//! The BSDF leaf families, one folder each: its parameters, its scalar prepare, eval, sample
//! and albedo in the lobe's local frame, its bound form (the view-independent work of a
//! constant leaf done once) and its structure-of-arrays kernel for the batched and
//! lane-parallel paths (`soa.rs`). Here: the results every family returns ([`LobeEval`],
//! [`LobeSample`], [`LobeAlbedo`]), so that the families import this module and not the
//! enum over them (`interp::lobe`, which the interpreter dispatches on with a `match`, no
//! trait objects).

pub mod diffuse;
pub mod emission;
pub mod microfacet;
pub mod sheen;
pub mod ward;

use crate::interp::math::Rgb;
use glam::Vec3;

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

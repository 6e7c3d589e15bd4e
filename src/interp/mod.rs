//! The embedded CPU interpreter: compile a material once, then prepare it per point and
//! view, and evaluate, sample and integrate it per light direction.
//!
//! [`Material`] compiles a [`crate::ir::MaterialIr`] once (options in [`PrepareOptions`]);
//! [`Material::prepare`] runs its program and the closure algebra for one [`ShadingPoint`]
//! and returns a [`Prepared`] (at most `MAX_LOBES` weighted lobes, no heap allocation) with
//! `eval` ([`Eval`]), `sample` ([`Sample`]), `albedo` ([`Albedo`]), `emission` and
//! `transparency`. [`Material::prepare_batch`] prepares 8 or 16 points at once
//! ([`ShadingBatch`], [`PreparedBatch`]) with the same results; [`preview`] renders the
//! material ball and contact sheets. Directions are world-space; colours are [`Rgb`].
//!
//! Inside, each BSDF leaf family is evaluated in f32 in a local frame ([`Frame`]), with
//! directional albedos from committed tables; the fast paths (fused and lane-parallel
//! prepares of uniform materials, lobe packs, structure-of-arrays kernels, run-time choice of
//! SIMD level) compute the same bits as the general prepare and are chosen internally.
//! (With the `testkit` feature the internal modules are public for the crate's tests and
//! benches: leaves, tables and kernels; the reference materials, the statistical harness
//! and the table generator are in the `vstructc-testkit` crate.)

/// An associated function that is `pub` under the `testkit` feature (the crate's tests and
/// benches compare the internal paths it opens) and `pub(crate)` otherwise.
macro_rules! testkit_pub {
    ($(#[$meta:meta])* fn $($rest:tt)*) => {
        #[cfg(feature = "testkit")]
        $(#[$meta])*
        pub fn $($rest)*
        #[cfg(not(feature = "testkit"))]
        $(#[$meta])*
        pub(crate) fn $($rest)*
    };
}

// Internal modules: public only under the `testkit` feature, for the crate's own tests and
// benches (the cross-path comparisons reach leaves, kernels and SIMD levels directly). A
// program using the library sees the items re-exported below and `preview`.
testkit_mods!(
    frame, fresnel, ggx, leaves, lobe, material, math, simd, soa, tables, vmath,
);

// The leaf families under their own names (`interp::ward`, ...).
#[cfg(feature = "testkit")]
pub use leaves::{diffuse, emission, microfacet, sheen, ward};
#[cfg(not(feature = "testkit"))]
use leaves::{diffuse, emission, microfacet, sheen, ward};

pub mod preview;

pub use frame::Frame;
pub use lobe::Sides;
pub use material::{
    ActiveLobe, Albedo, Eval, LeafInfo, Material, PrepareOptions, Prepared, PreparedBatch, Sample,
    Scratch, ShadingBatch, ShadingPoint, TableAlbedo,
};
pub use math::Rgb;

/// Leaf families, their parameters and prepared forms, for the crate's tests and benches.
#[cfg(feature = "testkit")]
pub use self::{
    diffuse::{Burley, Lambert, MiaDiffuse, OrenNayar, OrenNayarVariant},
    emission::{Emission, Transparent},
    fresnel::Fresnel,
    ggx::{Ggx, Masking},
    lobe::{
        BoundLobe, Lobe, LobeAlbedo, LobeClass, LobeEval, LobeKind, LobeSample, PreparedLobe,
        Reciprocity,
    },
    microfacet::{Compensation, Dielectric, DielectricMode, MicrofacetR},
    sheen::{SheenCK, SheenLTC, SheenMasking},
    ward::{MiaHighlight3, Ward, WardVariant},
};

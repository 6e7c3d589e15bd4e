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
//! The files read top-down, compile → plan → prepare → eval: each imports only files below
//! it in this list, so no two import each other (`tests/resolve/layers.rs` checks it).
//! * `compile.rs` checks and flattens the IR into a [`Material`] and builds its plans;
//! * `plan.rs` compiles the weight pass of a material with constant registers;
//! * `lanes.rs`, the batched prepares: each lane by the scalar steps, or the lane-parallel
//!   prepare of a uniform material;
//! * `batch.rs`, [`ShadingBatch`] and [`PreparedBatch`]: the lanes' records side by side and
//!   the batched `eval`;
//! * `prepare.rs`, the general prepare and its [`Scratch`];
//! * `uniform.rs`, the fused prepare of a uniform material (same bits as the general one);
//! * `prepared.rs`, [`Prepared`]: eval, sample, albedo;
//! * `form.rs`, the compiled form: [`Material`]'s data and its plans' (types only, with the
//!   clamps every pass applies), shared by the compile step and the prepares;
//! * `packs.rs`, same-family lobes evaluated as lanes of one kernel;
//! * `leaf.rs`, an IR leaf turned into its lobe;
//! * `record.rs`, the records every layer passes: [`ShadingPoint`], [`PrepareOptions`],
//!   [`ActiveLobe`], [`Eval`], [`Sample`], [`Albedo`].
//!
//! `Material`'s methods sit in the file of their step, and a step calls only steps below it.

mod compile;
mod plan;
mod lanes;
mod batch;
mod prepare;
mod uniform;
mod prepared;
mod form;
// The lobe packs: public under `testkit` for their unit tests.
testkit_mods!(packs);
mod leaf;
mod record;

pub use batch::{PreparedBatch, ShadingBatch};
pub use form::{LeafInfo, Material};
pub use leaf::TableAlbedo;
pub use prepare::Scratch;
pub use prepared::Prepared;
pub use record::{ActiveLobe, Albedo, Eval, PrepareOptions, Sample, ShadingPoint};



//! The interpreter: each leaf's API, reference points, reciprocity, robustness and tables,
//! and the material paths (scalar, SoA kernels, lanes, packs, uniform plans, SIMD levels,
//! batches), which must agree bit for bit or to the stated tolerance.

#[macro_use]
#[path = "../common/mod.rs"]
mod common;

mod alloc;
mod batch_lanes;
mod batch_ref10;
mod batch_reuse;
mod bound;
mod lanes;
mod leaves_api;
mod leaves_points;
mod leaves_reciprocity;
mod leaves_robust;
mod leaves_tables;
mod levels;
mod material;
mod packs;
mod sheet_labels;
mod soa;
mod soa_kernels;
mod uniform;
mod uniform_materials;
mod unit;

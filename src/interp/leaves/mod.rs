//! The BSDF leaf families, one folder each: its parameters, its scalar prepare, eval, sample
//! and albedo in the lobe's local frame, its bound form (the view-independent work of a
//! constant leaf done once) and its structure-of-arrays kernel for the batched and
//! lane-parallel paths (`soa.rs`). [`crate::interp::lobe`] is the enum over the families that
//! the interpreter dispatches on (a `match`, no trait objects).

pub mod diffuse;
pub mod emission;
pub mod microfacet;
pub mod sheen;
pub mod ward;

//! Test and benchmark support of vstructc, kept out of the library: the generators of
//! scenes and definitions the tests, the benchmarks and `examples/scale_scene.rs` share.
//! Not published; not a stable API.

#![warn(missing_docs)]

pub mod testgen;

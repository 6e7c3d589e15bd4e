//! Test and benchmark support of vstructc, kept out of the library: the generators of
//! scenes and definitions the tests, the benchmarks and `examples/scale_scene.rs` share
//! ([`testgen`], and [`scene`]: the same layered scene built for the lowering directly),
//! reference materials built with the library's IR builder ([`mod@reference`]),
//! the statistical harness of the interpreter's verification ([`verify`]) and the generator
//! of the interpreter's albedo tables ([`lutgen`]). Not published; not a stable API.

#![warn(missing_docs)]

pub mod lutgen;
pub mod reference;
pub mod scene;
pub mod testgen;
pub mod verify;

//! Test and benchmark support of vstructc, kept out of the library: the generators of
//! scenes and definitions the tests, the benchmarks and `examples/scale_scene.rs` share
//! ([`testgen`]), reference materials built with the library's IR builder ([`mod@reference`])
//! and the statistical harness of the interpreter's verification ([`verify`]). Not
//! published; not a stable API.

#![warn(missing_docs)]

pub mod reference;
pub mod testgen;
pub mod verify;

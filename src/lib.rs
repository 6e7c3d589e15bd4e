//! # vstructc
//!
//! A shader-network compiler for RenderMan-style renderers. It reads shader definitions
//! (`.args` XML and compiled OSL `.oso`) into a [`registry::Registry`], parses the
//! `vstructConditionalExpr` language ([`cond`]), reads shader networks (RIB, JSON) into a
//! [`network::Network`], expands vstruct connections exactly as OpenUSD's hdPrman does
//! ([`resolve`]), and writes the resolved network back ([`back`]).
//!
//! Stages, in the order data flows (see `ARCHITECTURE.md`):
//!
//! 1. [`front`]: readers for `.args`, `.oso`, RIB and JSON;
//! 2. [`registry`]: definitions, lookup, per-type vstruct tables;
//! 3. [`cond`]: the conditional language (lexer, parser, AST, evaluator);
//! 4. [`network`]: the shader-network graph;
//! 5. [`resolve`]: vstruct expansion;
//! 6. [`ir`], `lower`, [`interp`]: the closure IR, its lowering per material model, and the
//!    CPU interpreter;
//! 7. [`back`]: writers for RIB, JSON, Graphviz dot and images.
//!
//! [`pipeline`] chains them: a network's text in, closure IR or interpreter materials out.
//! [`model`] holds the definition model the readers produce and the registry holds;
//! [`raster`] the image type the preview renderer and the image writers share.
//!
//! Features: `cli` (default; the `vstructc` binary's dependencies), `png` (PNG encoding of
//! previews, on with `cli`), `parallel` (default; rayon), `testkit` (the internals the
//! tests and benchmarks reach, made public; not a stable API). A crate embedding vstructc
//! can turn the defaults off: `vstructc = { version = "0.1", default-features = false }`.
//!
//! Problems are reported as [`diag::Diagnostic`]s with stable codes and positions; conditions
//! that stop processing are [`diag::Error`]s.

#![warn(missing_docs)]

/// Declares modules that are public under the `testkit` feature (the crate's own tests and
/// benches reach into them) and crate-private otherwise. Items that only those tests use
/// compile only with `testkit`.
macro_rules! testkit_mods {
    ($($name:ident),+ $(,)?) => {$(
        #[cfg(feature = "testkit")]
        pub mod $name;
        #[cfg(not(feature = "testkit"))]
        pub(crate) mod $name;
    )+};
}

pub mod diag;
pub mod limits;
pub mod types;

pub mod front;
pub mod model;
pub mod registry;

pub mod cond;

pub mod network;
pub mod resolve;

pub mod interp;
pub mod ir;
// Lowering is reached through `pipeline`; its recipes and graph traits are internals.
testkit_mods!(lower);

pub mod back;
pub mod raster;

// How the readers and writers share rayon's pool; the tests reach `make_in_order`.
testkit_mods!(schedule);

pub mod pipeline;

pub use diag::{Code, Diagnostic, Diagnostics, Error, Location, Result, Severity};

/// The vector types of the interpreter's signatures (`glam::Vec3` directions and colours):
/// use `vstructc::glam` to get the same version.
pub use glam;
/// The graph library under [`network::Network`] (its node and edge ids are petgraph's
/// indices): use `vstructc::petgraph` to get the same version.
pub use petgraph;
pub use types::{ArraySpec, BaseType, Type, Value};

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
//! 6. [`ir`], [`lower`], [`interp`]: the closure IR, its lowering per material model, and the
//!    CPU interpreter;
//! 7. [`back`]: writers for RIB, JSON, Graphviz dot and images.
//!
//! Problems are reported as [`diag::Diagnostic`]s with stable codes and positions; conditions
//! that stop processing are [`diag::Error`]s.

#![warn(missing_docs)]

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
pub mod lower;

pub mod back;
pub mod raster;

pub mod pipeline;

pub use diag::{Diagnostic, Diagnostics, Error, Location, Result, Severity};
pub use types::{ArraySpec, BaseType, Type, Value};

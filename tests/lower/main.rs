//! Lowering: the closure IR's algebra and the recipes that lower each material model and a
//! resolved network to it.

#[macro_use]
#[path = "../common/mod.rs"]
mod common;

mod args;
mod ir_algebra;
mod models;
mod network;
mod pxr;
mod snapshot;
mod unit;

//! The conditional language: grammar, parser, printed forms, evaluation, the spec's vectors
//! and every conditional of the fixtures.

#[macro_use]
#[path = "../common/mod.rs"]
mod common;

mod check;
mod fixtures;
mod grammar;
mod props;
mod snapshot;
mod unit;
mod vectors;

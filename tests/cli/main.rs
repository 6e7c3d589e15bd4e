//! The `vstructc` command line: each subcommand's output, exit codes and determinism.

#[macro_use]
#[path = "../common/mod.rs"]
mod common;

mod commands;
mod cond;
mod determinism;
mod diagnostics;
mod eval;
mod info;
mod render;
mod snippets;

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
mod unit;

/// The binary's source snippets, compiled here for their unit tests (`unit::snippet`): the
/// binary is not built as a test target, so its helpers are checked from this one.
#[path = "../../src/bin/vstructc/cli/snippet.rs"]
#[allow(
    dead_code,
    reason = "the rendering entry points are the binary's; the unit tests reach only the helpers"
)]
mod snippet;

/// The binary's grouping of human diagnostics, compiled here for its unit tests
/// (`unit::group`).
#[path = "../../src/bin/vstructc/cli/group.rs"]
mod group;

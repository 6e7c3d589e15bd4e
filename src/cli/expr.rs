//! `vstructc expr` (in progress).

use super::CommonOptions;
use std::process::ExitCode;

/// Arguments of `vstructc expr`.
#[derive(Debug, clap::Args)]
pub struct ExprArgs {}

/// Run `vstructc expr`.
pub fn run(_args: &ExprArgs, _common: &CommonOptions) -> ExitCode {
    eprintln!("vstructc expr: not implemented yet");
    ExitCode::from(2)
}

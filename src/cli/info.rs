//! `vstructc info` (in progress).

use super::CommonOptions;
use std::process::ExitCode;

/// Arguments of `vstructc info`.
#[derive(Debug, clap::Args)]
pub struct InfoArgs {}

/// Run `vstructc info`.
pub fn run(_args: &InfoArgs, _common: &CommonOptions) -> ExitCode {
    eprintln!("vstructc info: not implemented yet");
    ExitCode::from(2)
}

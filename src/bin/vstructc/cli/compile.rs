//! `vstructc compile [--args DIR]... [--emit ir|lobes|dot] [--material NAME] INPUT`: read a
//! RIB or JSON network, resolve it (a no-op when it holds no placeholders), lower each
//! material (or only `--material`) and print its IR, flat lobe list or closure tree.
//!
//! The lobe list's numeric weights use the interpreter's albedo tables
//! ([`TableAlbedo`]); the snapshot tests print with `SimpleAlbedo` (smooth-surface estimates)
//! so that their numbers can be checked by hand.

use super::CommonOptions;
use super::input::{print_stdout, run_pipeline};
use clap::ValueEnum;
use std::path::PathBuf;
use std::process::ExitCode;
use vstructc::interp::TableAlbedo;
use vstructc::ir::{MaterialIr, print};
use vstructc::pipeline::Lowering;

/// What `compile` prints.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, ValueEnum)]
pub enum Emit {
    /// The IR: inputs, frames, program, closure nodes.
    #[default]
    Ir,
    /// The flat lobe list with symbolic and numeric weights.
    Lobes,
    /// Graphviz dot of the closure tree.
    Dot,
}

/// Arguments of `vstructc compile`.
#[derive(Debug, clap::Args)]
pub struct CompileArgs {
    /// The network: a RIB or JSON file, or `-` for standard input.
    pub input: PathBuf,
    /// What to print.
    #[arg(long, value_enum, default_value_t = Emit::Ir)]
    pub emit: Emit,
    /// Lower only this material (material name or terminal node handle).
    #[arg(long, value_name = "NAME")]
    pub material: Option<String>,
    /// Resolve without evaluating conditionals.
    #[arg(long)]
    pub no_conditions: bool,
    /// Single-quoted RIB strings are an error instead of an info (RB011).
    #[arg(long)]
    pub strict_rib: bool,
}

/// Render one lowered material.
pub fn render(ir: &MaterialIr, emit: Emit) -> String {
    match emit {
        Emit::Ir => print::ir_text(ir),
        Emit::Lobes => print::lobes_text(ir, &TableAlbedo),
        Emit::Dot => vstructc::back::dot::to_dot(ir),
    }
}

/// Run `vstructc compile`.
pub fn run(args: &CompileArgs, common: &CommonOptions) -> ExitCode {
    let lowering = match &args.material {
        Some(name) => Lowering::Only(name.clone()),
        None => Lowering::All,
    };
    let ran = match run_pipeline(
        &args.input,
        args.no_conditions,
        args.strict_rib,
        false,
        lowering,
        common,
    ) {
        Ok(ran) => ran,
        Err(status) => return status,
    };
    let out: String = ran
        .output
        .materials
        .iter()
        .map(|ir| render(ir, args.emit) + "\n")
        .collect();
    if let Err(failed) = print_stdout(&out, common) {
        super::report(&ran.diags, common);
        return failed;
    }
    super::report(&ran.diags, common)
}

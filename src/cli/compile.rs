//! `vstructc compile [--args DIR]... [--emit ir|lobes|dot] [--material NAME] INPUT`: read a
//! RIB or JSON network, resolve it (a no-op when it holds no placeholders), lower each
//! material and print its IR, flat lobe list or closure tree.
//!
//! (Enabled once `network`, `registry` and `resolve` are on main: add `pub mod compile;` and
//! the `Compile` variant to `src/cli/mod.rs`.)

use super::CommonOptions;
use crate::diag::{Diagnostics, Error};
use crate::ir::{print, SimpleAlbedo};
use crate::lower::network::{lower_terminal, report_placeholders, terminals};
use crate::registry::{Registry, RegistryOptions};
use crate::resolve::{resolve, ResolveOptions};
use clap::ValueEnum;
use std::path::PathBuf;
use std::process::ExitCode;

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
    /// What to print.
    #[arg(long, value_enum, default_value_t = Emit::Ir)]
    pub emit: Emit,
    /// Lower only this material (material name or terminal node handle).
    #[arg(long, value_name = "NAME")]
    pub material: Option<String>,
    /// Resolve without evaluating conditionals.
    #[arg(long)]
    pub no_conditions: bool,
    /// The network (`.rib` or `.json`).
    pub input: PathBuf,
}

/// Render one lowered material.
pub fn render(ir: &crate::ir::MaterialIr, emit: Emit) -> String {
    match emit {
        Emit::Ir => print::ir_text(ir),
        Emit::Lobes => print::lobes_text(ir, &SimpleAlbedo),
        Emit::Dot => crate::back::dot::to_dot(ir),
    }
}

/// Run `vstructc compile`.
pub fn run(args: &CompileArgs, common: &CommonOptions) -> ExitCode {
    let mut diags = Diagnostics::new();
    match compile(args, common, &mut diags) {
        Ok(text) => {
            print!("{text}");
            super::report(&diags, common)
        }
        Err(Error::Usage(msg)) => {
            let _ = super::report(&diags, common);
            eprintln!("error: {msg}");
            ExitCode::from(2)
        }
        Err(e) => {
            if let Some(d) = e.diagnostic() {
                diags.push(d.clone());
            } else {
                eprintln!("error: {e}");
            }
            let _ = super::report(&diags, common);
            ExitCode::from(1)
        }
    }
}

fn compile(args: &CompileArgs, common: &CommonOptions, diags: &mut Diagnostics) -> Result<String, Error> {
    let registry = Registry::new(RegistryOptions {
        paths: common.args.clone(),
        ..RegistryOptions::default()
    });
    let bytes = std::fs::read(&args.input).map_err(|source| Error::Io {
        path: args.input.clone(),
        source,
    })?;
    let path = args.input.display().to_string();
    let mut net = if path.ends_with(".json") {
        crate::front::json::parse_json(&bytes, &path, &registry, diags)?
    } else {
        crate::front::rib::parse_rib(&bytes, &path, &registry, &Default::default(), diags)?
    };
    let options = ResolveOptions {
        conditions: !args.no_conditions,
        verbose: common.verbose,
        ..ResolveOptions::default()
    };
    let resolution = resolve(&mut net, &registry, &options);
    diags.extend(resolution.diagnostics);
    report_placeholders(&net, &registry, diags);
    let mut out = String::new();
    for (name, node) in terminals(&net, args.material.as_deref())? {
        match lower_terminal(&net, &registry, node, &name, diags) {
            Ok(ir) => {
                out.push_str(&render(&ir, args.emit));
                out.push('\n');
            }
            Err(Error::Input(d)) => diags.push(*d),
            Err(e) => return Err(e),
        }
    }
    Ok(out)
}

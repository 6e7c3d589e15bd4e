//! `vstructc resolve`: expand the vstruct connections of a network and write it back.

use super::CommonOptions;
use super::input::{NetFormat, Prepared, prepare, report_error, stream_output};
use vstructc::back::json::write_json_to;
use vstructc::back::rib::write_rib;
use vstructc::cond::Extensions;
use vstructc::diag::Error;
use vstructc::network::Network;
use vstructc::registry::Registry;
use vstructc::resolve::{ResolveOptions, resolve, unsupported_extensions};
use std::path::PathBuf;
use std::process::ExitCode;

/// Arguments of `vstructc resolve`.
#[derive(Debug, clap::Args)]
pub struct ResolveArgs {
    /// The network to resolve: a RIB or JSON file, or `-` for standard input.
    pub input: PathBuf,
    /// Connect every matched member without evaluating conditionals (the reference's
    /// `enableConditions = false`).
    #[arg(long)]
    pub no_conditions: bool,
    /// Output format (default: the input's).
    #[arg(long, value_enum)]
    pub format: Option<NetFormat>,
    /// Write to FILE (atomically) instead of standard output.
    #[arg(short = 'o', long = "output", value_name = "FILE")]
    pub output: Option<PathBuf>,
    /// Single-quoted RIB strings are an error instead of an info (RB011).
    #[arg(long)]
    pub strict_rib: bool,
    /// Delete placeholder connections that could not be resolved (VS010) instead of writing
    /// them unchanged.
    #[arg(long)]
    pub drop_unresolved: bool,
}

/// Resolution options from the command line; unknown or unsupported extensions are usage
/// errors.
pub fn resolve_options(
    no_conditions: bool,
    common: &CommonOptions,
) -> Result<ResolveOptions, Error> {
    let extensions =
        Extensions::from_names(&common.ext).map_err(|e| Error::Usage(e.to_string()))?;
    let missing = unsupported_extensions(&extensions);
    if !missing.is_empty() {
        return Err(Error::Usage(format!(
            "extension(s) {} are not implemented in resolution yet",
            missing.join(", ")
        )));
    }
    Ok(ResolveOptions {
        conditions: !no_conditions,
        extensions,
        verbose: common.verbose,
        record_events: false,
        limits: Default::default(),
    })
}

/// Delete every connection still on an input head after resolution (the VS010 placeholders).
pub fn drop_unresolved(net: &mut Network, registry: &Registry) {
    for node in net.nodes_sorted() {
        let Some(tables) = registry.tables(net[node].shader()) else {
            continue;
        };
        for input in net.connected_inputs(node) {
            if tables.is_input_head(&input) {
                net.clear_connections(node, &input);
            }
        }
    }
}

/// Run `vstructc resolve`.
pub fn run(args: &ResolveArgs, common: &CommonOptions) -> ExitCode {
    let Prepared {
        options,
        registry,
        mut loaded,
        mut diags,
    } = match prepare(&args.input, args.no_conditions, args.strict_rib, common) {
        Ok(p) => p,
        Err(status) => return status,
    };
    let res = resolve(&mut loaded.network, &registry, &options);
    if args.drop_unresolved {
        drop_unresolved(&mut loaded.network, &registry);
    }
    diags.extend(registry.diagnostics());
    diags.extend(res.diagnostics);
    diags.sort();
    let status = super::report(&diags, common);
    if status != ExitCode::SUCCESS {
        return status;
    }
    let output = args.output.as_deref();
    let written = match args.format.unwrap_or(loaded.format) {
        NetFormat::Json => stream_output(output, |out| write_json_to(&loaded.network, out)),
        NetFormat::Rib => {
            // Streamed: the untouched parts of a large scene are copied from the source
            // straight into the output file.
            let source = match loaded.format {
                NetFormat::Rib => loaded.bytes.as_slice(),
                NetFormat::Json => &[],
            };
            stream_output(output, |out| {
                write_rib(source, &loaded.network, &registry, out)
            })
        }
    };
    match written {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => report_error(&e, common),
    }
}

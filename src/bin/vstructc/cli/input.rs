//! What the commands share: the registry and resolution options of the common options,
//! reading a network input (RIB, JSON or USD, a file or `-` for standard input) and running the
//! library's pipeline on it, and writing output (files by [`vstructc::back::output`]'s
//! rules, or standard output).

use super::CommonOptions;
use std::io::{Read, Write};
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use vstructc::back::output;
use vstructc::cond::Extensions;
use vstructc::diag::{Diagnostics, Error, Location};
use vstructc::front::args::ArgsOptions;
use vstructc::front::source::{ReadError, read_stream};
use vstructc::front::{NetFormat, ReadOptions, read_network};
use vstructc::limits::{Limit, LimitExceeded, Limits};
use vstructc::network::Network;
use vstructc::pipeline::{self, Lowering, PipelineOptions, PipelineOutput};
use vstructc::registry::{Registry, RegistryOptions};
use vstructc::resolve::ResolveOptions;

/// `--format`'s values, mapped onto the library's [`NetFormat`].
pub fn format_parser() -> impl clap::builder::TypedValueParser<Value = NetFormat> {
    use clap::builder::{PossibleValue, PossibleValuesParser, TypedValueParser};
    PossibleValuesParser::new([
        PossibleValue::new("rib").help("RenderMan RIB"),
        PossibleValue::new("json").help("The JSON network form (see docs/inputs-and-outputs.md)"),
        PossibleValue::new("usda").help("A USD text layer of Material and Shader prims"),
    ])
    .map(|s| match s.as_str() {
        "json" => NetFormat::Json,
        "usda" => NetFormat::Usd,
        _ => NetFormat::Rib,
    })
}

/// Registry options implied by the common command-line options (`--args`, `--prefer`,
/// `--ext args-child-meta`); the environment and the embedded definitions are searched too.
pub fn registry_options(common: &CommonOptions) -> RegistryOptions {
    let ext = |name: &str| common.ext.iter().any(|e| e == name || e == "all");
    RegistryOptions {
        paths: common.args.clone(),
        prefer: common.prefer,
        args: ArgsOptions {
            child_meta: ext("args-child-meta"),
        },
        ..RegistryOptions::default()
    }
}

/// The registry for a command line (see [`registry_options`]).
pub fn registry_for(common: &CommonOptions) -> Registry {
    Registry::new(registry_options(common))
}

/// Resolution options from the command line; unknown or unsupported extensions are usage
/// errors.
pub fn resolve_options(
    no_conditions: bool,
    common: &CommonOptions,
) -> Result<ResolveOptions, Error> {
    let extensions =
        Extensions::from_names(&common.ext).map_err(|e| Error::Usage(e.to_string()))?;
    let missing = extensions.unsupported_by_resolver();
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
        ..ResolveOptions::default()
    })
}

/// An input's bytes, with the name used in diagnostics (`<stdin>` for `-`) and its format
/// (the RIB writer passes everything outside the network through unchanged).
pub struct LoadedInput {
    /// The name used in diagnostics.
    pub name: String,
    /// The input bytes.
    pub bytes: Vec<u8>,
    /// The detected format.
    pub format: NetFormat,
}

/// Read `path` (`-`: standard input); the format is detected by extension, else by the
/// first non-blank byte; USD and MaterialX are recognised and refused (IO003).
pub fn load_input(path: &Path) -> Result<LoadedInput, Error> {
    let (name, bytes) = read_bytes(path)?;
    let format = NetFormat::detect(&name, &bytes)?;
    Ok(LoadedInput {
        name,
        bytes,
        format,
    })
}

/// The input's bytes, at most [`Limits::network_file_bytes`] of them (LM001 beyond): a
/// regular file is refused by its size before it is read; standard input, a FIFO or a device
/// is read until the limit is passed.
fn read_bytes(path: &Path) -> Result<(String, Vec<u8>), Error> {
    let max = Limits::default().network_file_bytes;
    if path.as_os_str() == "-" {
        let name = "<stdin>".to_string();
        let bytes = stream_bytes(std::io::stdin().lock(), &name, max)?;
        super::snippet::remember(&name, &bytes);
        return Ok((name, bytes));
    }
    let name = path.display().to_string();
    let io = |source| Error::Io {
        path: path.to_path_buf(),
        source,
    };
    let meta = std::fs::metadata(path).map_err(io)?;
    if meta.is_dir() {
        return Err(io(std::io::Error::new(
            std::io::ErrorKind::IsADirectory,
            "is a folder, not a network file",
        )));
    }
    let bytes = if meta.is_file() {
        if meta.len() > max {
            return Err(too_large(meta.len(), max, &name));
        }
        std::fs::read(path).map_err(io)?
    } else {
        stream_bytes(std::fs::File::open(path).map_err(io)?, &name, max)?
    };
    Ok((name, bytes))
}

/// A stream input, read until more than `max` bytes arrive.
fn stream_bytes(reader: impl Read, name: &str, max: u64) -> Result<Vec<u8>, Error> {
    read_stream(reader, max).map_err(|e| match e {
        ReadError::Io(source) => Error::Io {
            path: PathBuf::from(name),
            source,
        },
        // A stream's size is unknown: it had at least one byte more than the limit.
        _ => too_large(max.saturating_add(1), max, name),
    })
}

/// LM001: a network input of `size` bytes is above `max`.
fn too_large(size: u64, max: u64, name: &str) -> Error {
    LimitExceeded {
        limit: Limit::NetworkFileBytes,
        value: size,
        max,
        location: Some(Location::file(name)),
    }
    .into()
}

/// Write the output `produce` writes to `path` (`None` or `-`: standard output) by the rules
/// of [`vstructc::back::output`]: a regular file is replaced atomically (a failure never
/// leaves a partial file, and reading and writing the same path is safe since the input was
/// read completely before), a device or FIFO is written in place, a symlink is written
/// through. The destination is buffered, so a large scene is never held in memory a second
/// time.
pub fn stream_output(
    path: Option<&Path>,
    produce: impl FnOnce(&mut dyn Write) -> std::io::Result<()>,
) -> Result<(), Error> {
    match path.filter(|p| p.as_os_str() != "-") {
        Some(path) => output::write_file(path, produce),
        None => output::write_stdout(produce),
    }
}

/// Print `text` on standard output; a write error (a full disk) is reported as IO001 and
/// gives exit status 1.
pub fn print_stdout(text: &str, common: &CommonOptions) -> Result<(), std::process::ExitCode> {
    output::write_stdout(|out| out.write_all(text.as_bytes())).map_err(|e| report_error(&e, common))
}

/// Print an error (I/O or input) as a diagnostic according to the common options; returns
/// exit status 1.
pub fn report_error(err: &Error, common: &CommonOptions) -> std::process::ExitCode {
    let mut diags = Diagnostics::new();
    diags.push(err.to_diagnostic());
    super::report(&diags, common)
}

/// The common start of the network commands, on failure already reported: the exit status
/// to return (2 for usage errors, 1 for input errors).
fn start(
    input: &Path,
    no_conditions: bool,
    common: &CommonOptions,
) -> Result<(ResolveOptions, Registry, LoadedInput), ExitCode> {
    let options = resolve_options(no_conditions, common).map_err(|e| {
        eprintln_quiet!("error: {e}");
        ExitCode::from(2)
    })?;
    let registry = registry_for(common);
    let loaded = load_input(input).map_err(|e| report_error(&e, common))?;
    Ok((options, registry, loaded))
}

/// A network read but not resolved, for `explain`.
pub struct ReadInput {
    /// Resolution options from the command line.
    pub options: ResolveOptions,
    /// The registry of the common options.
    pub registry: Registry,
    /// The input's name.
    pub name: String,
    /// The network.
    pub network: Network,
}

/// Read the input's network with the registry and options of the command line. On failure
/// the diagnostics are printed and the exit status to return is given.
pub fn read(
    input: &Path,
    no_conditions: bool,
    common: &CommonOptions,
) -> Result<ReadInput, ExitCode> {
    let (options, registry, loaded) = start(input, no_conditions, common)?;
    let mut diags = Diagnostics::new();
    let read = ReadOptions::default();
    match read_network(
        &loaded.name,
        &loaded.bytes,
        loaded.format,
        &registry,
        &read,
        &mut diags,
    ) {
        Ok(network) => Ok(ReadInput {
            options,
            registry,
            name: loaded.name,
            network,
        }),
        Err(e) => {
            super::report(&diags, common);
            Err(report_error(&e, common))
        }
    }
}

/// What the library's pipeline made of one input.
pub struct Ran {
    /// The input read.
    pub loaded: LoadedInput,
    /// The registry of the common options.
    pub registry: Registry,
    /// The resolved network and lowered materials.
    pub output: PipelineOutput,
    /// Every diagnostic so far, sorted.
    pub diags: Diagnostics,
}

/// What the network commands share: read `input` and run [`pipeline::run`] on it. On
/// failure the diagnostics are printed and the exit status to return is given (2 for usage
/// errors, among them a `--material` no material has, 1 for input errors).
pub fn run_pipeline(
    input: &Path,
    no_conditions: bool,
    strict_rib: bool,
    drop_unresolved: bool,
    lowering: Lowering,
    common: &CommonOptions,
) -> Result<Ran, ExitCode> {
    let (mut resolve, registry, loaded) = start(input, no_conditions, common)?;
    resolve.drop_unresolved = drop_unresolved;
    let options = PipelineOptions {
        resolve,
        strict_rib,
        lowering,
    };
    let mut diags = Diagnostics::new();
    let ran = pipeline::run(
        &loaded.name,
        &loaded.bytes,
        loaded.format,
        &registry,
        &options,
        &mut diags,
    );
    match ran {
        Ok(output) => Ok(Ran {
            loaded,
            registry,
            output,
            diags,
        }),
        Err(Error::Usage(msg)) => {
            diags.sort();
            super::report(&diags, common);
            eprintln_quiet!("error: {msg}");
            Err(ExitCode::from(2))
        }
        Err(e) => {
            diags.sort();
            super::report(&diags, common);
            Err(report_error(&e, common))
        }
    }
}

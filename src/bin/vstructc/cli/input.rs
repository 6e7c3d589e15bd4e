//! Reading a network input (RIB or JSON, a file or `-` for standard input) and writing output
//! (files by [`vstructc::back::output`]'s rules, or standard output). Shared by every command.

use super::CommonOptions;
use vstructc::back::output;
use vstructc::diag::{Diagnostics, Error, Location};
use vstructc::front::json::parse_json;
use vstructc::front::rib::{RibOptions, parse_rib};
use vstructc::front::source::{ReadError, read_stream};
use vstructc::limits::{Limit, LimitExceeded, Limits};
use vstructc::network::Network;
use vstructc::registry::Registry;
use std::io::{Read, Write};
use std::path::{Path, PathBuf};

/// The format of a network file.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum NetFormat {
    /// RenderMan RIB.
    Rib,
    /// The JSON network form (see docs/file-formats.md).
    Json,
}

/// A network read from an input, with the bytes it came from (the RIB writer passes
/// everything outside the network through unchanged).
pub struct LoadedInput {
    /// The name used in diagnostics (`<stdin>` for `-`).
    pub name: String,
    /// The input bytes.
    pub bytes: Vec<u8>,
    /// The detected format.
    pub format: NetFormat,
    /// The network.
    pub network: Network,
}

/// Read `path` (`-`: standard input) and parse it as RIB or JSON (by extension, else by the
/// first non-blank byte). Reader warnings go to `diags`.
pub fn load_network(
    path: &Path,
    registry: &Registry,
    strict_rib: bool,
    diags: &mut Diagnostics,
) -> Result<LoadedInput, Error> {
    let (name, bytes) = read_bytes(path)?;
    let format = detect_format(path, &bytes);
    let network = match format {
        NetFormat::Json => parse_json(&bytes, &name, registry, diags)?,
        NetFormat::Rib => parse_rib(
            &bytes,
            &name,
            registry,
            &RibOptions {
                strict: strict_rib,
                ..RibOptions::default()
            },
            diags,
        )?,
    };
    Ok(LoadedInput {
        name,
        bytes,
        format,
        network,
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

fn detect_format(path: &Path, bytes: &[u8]) -> NetFormat {
    match path.extension().and_then(|e| e.to_str()) {
        Some("json") => NetFormat::Json,
        Some("rib") => NetFormat::Rib,
        _ => match bytes.iter().find(|b| !b.is_ascii_whitespace()) {
            Some(b'{') => NetFormat::Json,
            _ => NetFormat::Rib,
        },
    }
}

/// Write `data` to `path` (`None` or `-`: standard output) by the rules of
/// [`vstructc::back::output`]: a regular file is replaced atomically (a failure never leaves a
/// partial file, and reading and writing the same path is safe since the input was read
/// completely before), a device or FIFO is written in place, a symlink is written through.
pub fn write_output(path: Option<&Path>, data: &[u8]) -> Result<(), Error> {
    stream_output(path, |out| out.write_all(data))
}

/// [`write_output`] for output produced piece by piece: `produce` writes into the destination
/// (buffered), so a large scene is never held in memory a second time.
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

/// What every network command starts from: resolution options, the registry, the network
/// read from the input, and the diagnostics so far.
pub struct Prepared {
    /// Resolution options from the command line.
    pub options: vstructc::resolve::ResolveOptions,
    /// The registry of the common options.
    pub registry: Registry,
    /// The input and its network.
    pub loaded: LoadedInput,
    /// Reader diagnostics.
    pub diags: Diagnostics,
}

/// The shared start of `resolve`, `explain` and `compile`: check the options, build the
/// registry and read the input. On failure the diagnostics are printed and the exit status to
/// return is given (2 for usage errors, 1 for input errors).
pub fn prepare(
    input: &Path,
    no_conditions: bool,
    strict_rib: bool,
    common: &CommonOptions,
) -> Result<Prepared, std::process::ExitCode> {
    let options = super::resolve::resolve_options(no_conditions, common).map_err(|e| {
        eprintln_quiet!("error: {e}");
        std::process::ExitCode::from(2)
    })?;
    let registry = super::info::registry_for(common);
    let mut diags = Diagnostics::new();
    match load_network(input, &registry, strict_rib, &mut diags) {
        Ok(loaded) => Ok(Prepared {
            options,
            registry,
            loaded,
            diags,
        }),
        Err(e) => {
            super::report(&diags, common);
            Err(report_error(&e, common))
        }
    }
}

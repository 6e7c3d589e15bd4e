//! Reading a network input (RIB or JSON, a file or `-` for standard input) and writing an
//! output file atomically. Shared by `resolve`, `explain` and the later stages.

use super::CommonOptions;
use crate::diag::{Diagnostics, Error};
use crate::front::json::parse_json;
use crate::front::rib::{RibOptions, parse_rib};
use crate::network::Network;
use crate::registry::Registry;
use std::io::{Read, Write};
use std::path::{Path, PathBuf};

/// The format of a network file.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum NetFormat {
    /// RenderMan RIB.
    Rib,
    /// The JSON network form (formats.md §5).
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
            &RibOptions { strict: strict_rib },
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

fn read_bytes(path: &Path) -> Result<(String, Vec<u8>), Error> {
    if path.as_os_str() == "-" {
        let mut bytes = Vec::new();
        std::io::stdin()
            .read_to_end(&mut bytes)
            .map_err(|source| Error::Io {
                path: PathBuf::from("<stdin>"),
                source,
            })?;
        return Ok(("<stdin>".to_string(), bytes));
    }
    let bytes = std::fs::read(path).map_err(|source| Error::Io {
        path: path.to_path_buf(),
        source,
    })?;
    Ok((path.display().to_string(), bytes))
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

/// Write `data` to `path` atomically: into a temporary file beside it, then rename, so that a
/// failure never leaves a partial file (and reading and writing the same path is safe, since
/// the input was read completely before). `-` writes to standard output.
pub fn write_output(path: Option<&Path>, data: &[u8]) -> Result<(), Error> {
    stream_output(path, |out| out.write_all(data))
}

/// [`write_output`] for output produced piece by piece: `produce` writes into the destination
/// (a buffered temporary file renamed into place only when everything succeeded, or stdout),
/// so a large scene is never held in memory a second time.
pub fn stream_output(
    path: Option<&Path>,
    produce: impl FnOnce(&mut dyn Write) -> std::io::Result<()>,
) -> Result<(), Error> {
    let Some(path) = path.filter(|p| p.as_os_str() != "-") else {
        let mut out = std::io::BufWriter::new(std::io::stdout().lock());
        return produce(&mut out)
            .and_then(|_| out.flush())
            .map_err(|source| Error::Io {
                path: PathBuf::from("<stdout>"),
                source,
            });
    };
    let io = |source| Error::Io {
        path: path.to_path_buf(),
        source,
    };
    let dir = path
        .parent()
        .filter(|d| !d.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    let file_name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| "output".to_string());
    let tmp = dir.join(format!(".{file_name}.vstructc-{}.tmp", std::process::id()));
    let result = std::fs::File::create(&tmp)
        .and_then(|f| {
            let mut out = std::io::BufWriter::with_capacity(1 << 16, f);
            produce(&mut out)?;
            out.into_inner().map_err(|e| e.into_error())?.sync_all()
        })
        .and_then(|_| std::fs::rename(&tmp, path));
    if let Err(e) = result {
        let _ = std::fs::remove_file(&tmp);
        return Err(io(e));
    }
    Ok(())
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
    pub options: crate::resolve::ResolveOptions,
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
        eprintln!("error: {e}");
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

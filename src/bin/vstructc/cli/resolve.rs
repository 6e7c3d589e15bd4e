//! `vstructc resolve`: expand the vstruct connections of a network and write it back.

use super::CommonOptions;
use super::input::{format_parser, report_error, run_pipeline, stream_output};
use std::path::{Component, Path, PathBuf};
use std::process::ExitCode;
use vstructc::back::json::write_json_to;
use vstructc::back::rib::write_rib;
use vstructc::back::usd::{UsdMode, write_usd};
use vstructc::front::NetFormat;
use vstructc::pipeline::Lowering;

/// Arguments of `vstructc resolve`.
#[derive(Debug, clap::Args)]
pub struct ResolveArgs {
    /// The network to resolve: a RIB, JSON or USD (`.usda`, `.usdc`, `.usdz`) file, or `-`
    /// for standard input.
    pub input: PathBuf,
    /// Connect every matched member without evaluating conditionals (the reference's
    /// `enableConditions = false`).
    #[arg(long)]
    pub no_conditions: bool,
    /// Output format (default: the extension of `-o` when it is `.rib`, `.json`, `.usda`,
    /// `.usdc` or `.usdz`, else the input's: USD input gives usda text). `-o` with `.usdc` or
    /// `.usdz` writes binary USD (a crate file, or a package holding one); a `-o` extension
    /// naming another format is a usage error.
    #[arg(long, value_parser = format_parser())]
    pub format: Option<NetFormat>,
    /// The resolved network as JSON (the JSON network form): the same as `--format json`,
    /// the machine-output flag every command that prints data has.
    #[arg(long, conflicts_with = "format")]
    pub json: bool,
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
    /// How USD output is written: `flatten`, one layer holding every material and shader at
    /// the input's prim paths, or `over`, a small layer that sublayers the USD input file (by
    /// a path relative to the output's folder) and overrides only what resolution changed.
    #[arg(long, value_enum, default_value_t = UsdModeArg::Flatten)]
    pub usd_mode: UsdModeArg,
}

/// The values of `--usd-mode`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, clap::ValueEnum)]
pub enum UsdModeArg {
    /// A flattened layer of every material and shader.
    #[default]
    Flatten,
    /// An override layer over the input: only what resolution changed.
    Over,
}

/// Why `--usd-mode over` cannot be honoured before the input is read, if it cannot: it
/// writes a USD layer (`.usda` or `.usdc`; not a `.usdz` package, inside which the input's
/// relative path would be looked for), and it sublayers an input file.
fn check_over(args: &ResolveArgs, format: Option<NetFormat>) -> Result<(), String> {
    if args.usd_mode != UsdModeArg::Over {
        return Ok(());
    }
    if args.json || format.is_some_and(|f| f != NetFormat::Usd) {
        let asked = if args.json {
            "--json".to_string()
        } else {
            format!(
                "the {} output asked for",
                format_name(format.unwrap_or(NetFormat::Rib))
            )
        };
        return Err(format!(
            "--usd-mode over writes a usda override layer; {asked} is not usda"
        ));
    }
    if encoding(args.output.as_deref()) == "usdz" {
        return Err(
            "--usd-mode over writes a layer that sublayers the input by a relative path; a \
             `.usdz` package would look for the input inside itself (use .usda or .usdc)"
                .into(),
        );
    }
    if args.input.as_os_str() == "-" {
        return Err(
            "--usd-mode over sublayers the input file; standard input cannot be sublayered".into(),
        );
    }
    Ok(())
}

/// The USD encoding output file `output` asks for by its extension: `usdc` or `usdz`
/// (binary, only to a file), else `usda` text.
fn encoding(output: Option<&Path>) -> &'static str {
    let ext = output
        .and_then(|p| p.extension())
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    match ext.as_deref() {
        Some("usdc") => "usdc",
        Some("usdz") => "usdz",
        _ => "usda",
    }
}

/// The name `--format` gives format `f`.
fn format_name(f: NetFormat) -> &'static str {
    match f {
        NetFormat::Rib => "rib",
        NetFormat::Json => "json",
        NetFormat::Usd => "usda",
    }
}

/// The asset path by which a layer written to `output` (standard output: the current
/// folder) refers to `input`: relative to the output's folder, `/`-separated; absolute when
/// no relative path exists.
fn sublayer_path(input: &Path, output: Option<&Path>) -> String {
    let absolute = |p: &Path| {
        p.canonicalize()
            .or_else(|_| std::path::absolute(p))
            .unwrap_or_else(|_| p.to_path_buf())
    };
    let folder = match output.filter(|o| o.as_os_str() != "-") {
        Some(o) => match o.parent() {
            Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
            _ => PathBuf::from("."),
        },
        None => PathBuf::from("."),
    };
    let (from, to) = (absolute(&folder), absolute(input));
    let text = |c: Component<'_>| c.as_os_str().to_string_lossy().into_owned();
    let (f, t): (Vec<Component<'_>>, Vec<Component<'_>>) =
        (from.components().collect(), to.components().collect());
    // Different roots (another drive): no relative path.
    if f.first() != t.first() {
        return to.to_string_lossy().replace('\\', "/");
    }
    let common = f.iter().zip(&t).take_while(|(a, b)| a == b).count();
    let mut parts: Vec<String> = vec!["..".to_string(); f.len() - common];
    parts.extend(t[common..].iter().map(|&c| text(c)));
    parts.join("/")
}

/// The output format `--format` and the extension of `-o` ask for (`None`: the input's), or
/// why they cannot be honoured.
pub fn output_format(
    format: Option<NetFormat>,
    output: Option<&std::path::Path>,
) -> Result<Option<NetFormat>, String> {
    let ext = output
        .and_then(|p| p.extension())
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    let by_ext = match ext.as_deref() {
        Some("rib") => Some(NetFormat::Rib),
        Some("json") => Some(NetFormat::Json),
        Some("usda" | "usd" | "usdc" | "usdz") => Some(NetFormat::Usd),
        Some("mtlx") => {
            return Err(
                "`.mtlx` output: MaterialX output is not supported (use .rib, .json or .usda)"
                    .into(),
            );
        }
        _ => None,
    };
    match (format, by_ext) {
        (Some(f), Some(e)) if f != e => Err(format!(
            "--format {} conflicts with the output file's extension `.{}`",
            format_name(f),
            ext.as_deref().unwrap_or(format_name(e))
        )),
        (Some(f), _) => Ok(Some(f)),
        (None, e) => Ok(e),
    }
}

/// Run `vstructc resolve`.
pub fn run(args: &ResolveArgs, common: &CommonOptions) -> ExitCode {
    let asked = if args.json {
        Some(NetFormat::Json)
    } else {
        args.format
    };
    let format = match output_format(asked, args.output.as_deref()) {
        Ok(f) => f,
        Err(msg) => {
            let msg = if args.json {
                msg.replace("--format json", "--json")
            } else {
                msg
            };
            eprintln_quiet!("error: {msg}");
            return ExitCode::from(2);
        }
    };
    if let Err(msg) = check_over(args, format) {
        eprintln_quiet!("error: {msg}");
        return ExitCode::from(2);
    }
    let ran = match run_pipeline(
        &args.input,
        args.no_conditions,
        args.strict_rib,
        args.drop_unresolved,
        Lowering::None,
        common,
    ) {
        Ok(ran) => ran,
        Err(status) => return status,
    };
    // The override layer sublayers the input: found before the run's diagnostics are shown.
    let over = args.usd_mode == UsdModeArg::Over;
    if over && ran.loaded.format != NetFormat::Usd {
        eprintln_quiet!(
            "error: --usd-mode over needs a USD input, which the override layer sublayers; \
             `{}` is {}",
            ran.loaded.name,
            match ran.loaded.format {
                NetFormat::Rib => "RIB",
                NetFormat::Json => "JSON",
                NetFormat::Usd => "USD",
            }
        );
        std::mem::forget(ran);
        return ExitCode::from(2);
    }
    let status = super::report(&ran.diags, common);
    if status != ExitCode::SUCCESS {
        return status;
    }
    let (loaded, network) = (&ran.loaded, &ran.output.network);
    let output = args.output.as_deref();
    let sublayer = if over {
        sublayer_path(&args.input, output)
    } else {
        String::new()
    };
    let mode = match (over, loaded.format) {
        (true, _) => UsdMode::Over {
            sublayer: &sublayer,
        },
        (false, NetFormat::Usd) => UsdMode::FlattenFrom {
            name: &loaded.name,
            bytes: &loaded.bytes,
        },
        (false, _) => UsdMode::Flatten,
    };
    let written = match format.unwrap_or(loaded.format) {
        NetFormat::Json => stream_output(output, |out| write_json_to(network, out)),
        NetFormat::Usd => {
            let encoding = encoding(output);
            stream_output(output, |out| {
                write_usd(network, &ran.registry, mode, encoding, out)
            })
        }
        NetFormat::Rib => {
            // Streamed: the untouched parts of a large scene are copied from the source
            // straight into the output file.
            let source = match loaded.format {
                NetFormat::Rib => loaded.bytes.as_slice(),
                NetFormat::Json | NetFormat::Usd => &[],
            };
            stream_output(output, |out| write_rib(source, network, &ran.registry, out))
        }
    };
    let status = match written {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => report_error(&e, common),
    };
    // The process ends here: the operating system takes back the input, the network and the
    // registry at once. Dropping a resolved scene's millions of parameters one by one took
    // a tenth of the command's time.
    std::mem::forget(ran);
    status
}

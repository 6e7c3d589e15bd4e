//! `vstructc render INPUT [-o ball.png] [--size N] [--furnace] [--pfm] [--aov lobe:NAME]
//! [--input NAME=VALUE]... [--material HANDLE]`: the material-ball preview (docs/preview.md).
//!
//! The input is read, resolved and lowered as by `compile`; each material is compiled for
//! the interpreter and rendered ([`vstructc::interp::preview`]). With several materials and no
//! `--material`, the balls are arranged in a contact sheet (a grid, `⌈√n⌉` columns, row-major
//! in material order).
//!
//! Output: `-o PATH` (`-` for standard output); without `-o`, `<input stem>.png` (`.pfm`
//! with `--pfm`) in the current directory, `preview.png` for standard input. A path ending
//! in `.pfm` selects PFM. The file is written atomically (temporary file, then rename).
//!
//! Memory does not grow with the number of materials: the sheet is rendered a band of pixel
//! rows at a time and each row is encoded into the output as it is finished
//! ([`vstructc::interp::preview::ContactSheet`]). `--size` is checked by the library
//! ([`PreviewOptions::validate`], at most [`vstructc::limits::Limits::preview_pixels`] pixels); a
//! size outside it is a usage error.
//!
//! `--input NAME=VALUE` sets an external input slot (its name as `compile --emit ir` lists
//! it, `node.output`); VALUE is one number or three separated by commas or spaces.
//! `--aov lobe:NAME` renders one lobe's contribution; NAME is the lobe's label (`diffuse`,
//! `specular`, ...), its kind (`lambert`, ...), or its node id (`#3`).
//!
//! Exit status: 0, 1 on input errors (positioned diagnostics), 2 on usage errors.

use super::CommonOptions;
use super::input::{Prepared as Loaded, prepare, report_error, stream_output};
use vstructc::back::png::{ImageFormat, write_rows};
use vstructc::diag::{Diagnostics, Error};
use vstructc::interp::Material;
use vstructc::interp::preview::{Ball, ContactSheet, PreviewOptions};
use vstructc::ir::MaterialIr;
use vstructc::lower::network::{lower_terminal, report_placeholders, terminals};
use vstructc::resolve::resolve;
use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

/// Options shared by `render` and `eval`: which input and material, and external inputs.
#[derive(Debug, Clone, clap::Args)]
pub struct MaterialArgs {
    /// The network: a RIB or JSON file, or `-` for standard input.
    pub input: PathBuf,
    /// Only this material (material name or terminal node handle).
    #[arg(long, value_name = "HANDLE")]
    pub material: Option<String>,
    /// Set an external input slot: `NAME=VALUE` (VALUE: `x` or `r,g,b`); repeatable.
    #[arg(long = "input", value_name = "NAME=VALUE")]
    pub inputs: Vec<String>,
    /// Resolve without evaluating conditionals.
    #[arg(long)]
    pub no_conditions: bool,
    /// Single-quoted RIB strings are an error instead of an info (RB011).
    #[arg(long)]
    pub strict_rib: bool,
}

/// Arguments of `vstructc render`.
#[derive(Debug, clap::Args)]
pub struct RenderArgs {
    /// Input, material and external inputs.
    #[command(flatten)]
    pub source: MaterialArgs,
    /// Output file (`-`: standard output). Default: `<input stem>.png` (or `.pfm`).
    #[arg(short, long, value_name = "PATH")]
    pub output: Option<PathBuf>,
    /// Side of one ball in pixels (1 to 8192).
    #[arg(long, default_value_t = 256)]
    pub size: usize,
    /// White furnace: no light, environment 1.
    #[arg(long)]
    pub furnace: bool,
    /// Write linear PFM instead of sRGB PNG.
    #[arg(long)]
    pub pfm: bool,
    /// Render one lobe's contribution: `lobe:NAME`.
    #[arg(long, value_name = "lobe:NAME")]
    pub aov: Option<String>,
    /// Use the batched (16-lane) interpreter.
    #[arg(long)]
    pub batched: bool,
}

/// A lowered, compiled material.
pub struct Compiled {
    /// Material name.
    pub name: String,
    /// Its interpreter form.
    pub material: Material,
}

/// Read, resolve and lower the input; compile every selected material. On failure the
/// diagnostics are printed and the exit status is returned. Diagnostics of a successful
/// load are returned for the caller to report.
pub fn load_materials(
    args: &MaterialArgs,
    common: &CommonOptions,
) -> Result<(Vec<Compiled>, Diagnostics), ExitCode> {
    let Loaded {
        options,
        registry,
        mut loaded,
        mut diags,
    } = prepare(&args.input, args.no_conditions, args.strict_rib, common)?;
    let res = resolve(&mut loaded.network, &registry, &options);
    diags.extend(registry.diagnostics());
    diags.extend(res.diagnostics);
    report_placeholders(&loaded.network, &registry, &mut diags);
    let net = &loaded.network;
    let list = match terminals(net, args.material.as_deref()) {
        Ok(l) => l,
        Err(Error::Usage(msg)) => {
            super::report(&diags, common);
            eprintln_quiet!("error: {msg}");
            return Err(ExitCode::from(2));
        }
        Err(e) => return Err(report_error(&e, common)),
    };
    let mut irs: Vec<MaterialIr> = Vec::new();
    for (name, node) in list {
        match lower_terminal(net, &registry, node, &name, &mut diags) {
            Ok(ir) => irs.push(ir),
            Err(Error::Input(d)) => diags.push(*d),
            Err(e) => return Err(report_error(&e, common)),
        }
    }
    let mut out = Vec::new();
    for ir in &irs {
        match Material::new(ir) {
            Ok(material) => out.push(Compiled {
                name: ir.name.clone(),
                material,
            }),
            Err(Error::Input(d)) => diags.push(*d),
            Err(e) => return Err(report_error(&e, common)),
        }
    }
    diags.sort();
    if diags.has_errors() {
        super::report(&diags, common);
        return Err(ExitCode::from(1));
    }
    if out.is_empty() {
        super::report(&diags, common);
        eprintln_quiet!("error: the input has no material with a lowering recipe");
        return Err(ExitCode::from(1));
    }
    Ok((out, diags))
}

/// Parse `--input NAME=VALUE` settings into packed inputs for `m` (fallbacks elsewhere).
/// Unknown names and malformed values are usage errors.
pub fn packed_inputs(m: &Material, settings: &[String]) -> Result<Vec<f32>, String> {
    let mut packed = m.fallback_inputs();
    for s in settings {
        let (name, value) = s
            .split_once('=')
            .ok_or_else(|| format!("--input `{s}`: expected NAME=VALUE"))?;
        let nums: Vec<f32> = value
            .split(|c: char| c == ',' || c.is_whitespace())
            .filter(|t| !t.is_empty())
            .map(|t| t.parse::<f32>())
            .collect::<Result<_, _>>()
            .map_err(|_| format!("--input `{s}`: `{value}` is not one or three numbers"))?;
        let Some(slot) = m.ir().input_index(name) else {
            // A setting for another material of the input is not an error.
            continue;
        };
        let (o, w) = m.input_layout()[slot];
        match (nums.len(), w) {
            (1, _) => packed[o..o + w].fill(nums[0]),
            (3, 3) => packed[o..o + 3].copy_from_slice(&nums),
            _ => {
                return Err(format!(
                    "--input `{s}`: slot `{name}` takes {w} number(s), got {}",
                    nums.len()
                ));
            }
        }
    }
    Ok(packed)
}

/// Check that every `--input` name exists in some material.
pub fn check_input_names(materials: &[Compiled], settings: &[String]) -> Result<(), String> {
    for s in settings {
        let name = s.split_once('=').map_or(s.as_str(), |(n, _)| n);
        if !materials
            .iter()
            .any(|c| c.material.ir().input_index(name).is_some())
        {
            let known: Vec<&str> = materials
                .iter()
                .flat_map(|c| c.material.ir().inputs.iter().map(|i| i.name.as_str()))
                .collect();
            return Err(format!(
                "--input `{name}`: no such external input (known: {})",
                if known.is_empty() {
                    "none".to_string()
                } else {
                    known.join(", ")
                }
            ));
        }
    }
    Ok(())
}

/// The leaf a `lobe:NAME` AOV designates in `m`: by label, then kind name, then `#node`.
pub fn find_leaf(m: &Material, name: &str) -> Option<usize> {
    let leaves = m.leaves();
    leaves
        .iter()
        .position(|l| l.leaf.label == name)
        .or_else(|| leaves.iter().position(|l| l.leaf.kind.name() == name))
        .or_else(|| {
            let id: u32 = name.strip_prefix('#')?.parse().ok()?;
            leaves.iter().position(|l| l.node.0 == id)
        })
}

fn default_output(input: &Path, pfm: bool) -> PathBuf {
    let ext = if pfm { "pfm" } else { "png" };
    match input.file_stem().filter(|_| input.as_os_str() != "-") {
        Some(stem) => PathBuf::from(format!("{}.{ext}", stem.to_string_lossy())),
        None => PathBuf::from(format!("preview.{ext}")),
    }
}

/// Render `sheet` into `out` row by row in `format`, with a progress bar on a terminal once
/// the render has taken more than a moment.
fn write_sheet(
    sheet: &ContactSheet<'_>,
    format: ImageFormat,
    out: &mut dyn std::io::Write,
    show: bool,
) -> std::io::Result<()> {
    let bar = indicatif::ProgressBar::hidden();
    bar.set_length(sheet.height() as u64);
    let start = Instant::now();
    let shown = AtomicBool::new(false);
    let progress = |rows: usize| {
        bar.set_position(rows as u64);
        if show
            && start.elapsed() > Duration::from_millis(300)
            && shown
                .compare_exchange(false, true, Ordering::Relaxed, Ordering::Relaxed)
                .is_ok()
        {
            bar.set_draw_target(indicatif::ProgressDrawTarget::stderr());
        }
    };
    let result = write_rows(format, out, sheet.width(), sheet.height(), |sink| {
        sheet.render_rows(format.order(), &progress, |row| sink.write_row(row))
    });
    bar.finish_and_clear();
    result
}

/// Run `vstructc render`.
pub fn run(args: &RenderArgs, common: &CommonOptions) -> ExitCode {
    let (materials, diags) = match load_materials(&args.source, common) {
        Ok(x) => x,
        Err(status) => return status,
    };
    let status = super::report(&diags, common);
    if status != ExitCode::SUCCESS {
        return status;
    }
    let usage = |msg: String| {
        eprintln_quiet!("error: {msg}");
        ExitCode::from(2)
    };
    if let Err(msg) = check_input_names(&materials, &args.source.inputs) {
        return usage(msg);
    }
    let aov = match args.aov.as_deref() {
        None => None,
        Some(a) => match a.strip_prefix("lobe:") {
            Some(name) if !name.is_empty() => Some(name),
            _ => return usage(format!("--aov `{a}`: expected `lobe:NAME`")),
        },
    };
    if let Some(name) = aov {
        if !materials
            .iter()
            .any(|c| find_leaf(&c.material, name).is_some())
        {
            let mut known: Vec<String> = materials
                .iter()
                .flat_map(|c| c.material.leaves().iter().map(|l| l.leaf.label.clone()))
                .collect();
            known.sort();
            known.dedup();
            return usage(format!(
                "--aov lobe:{name}: no lobe with this label, kind or node id (lobes: {})",
                known.join(", ")
            ));
        }
    }
    let base = PreviewOptions {
        size: args.size,
        batched: args.batched,
        ..PreviewOptions::default()
    };
    let base = if args.furnace { base.furnace() } else { base };
    let mut balls = Vec::with_capacity(materials.len());
    for c in &materials {
        let inputs = match packed_inputs(&c.material, &args.source.inputs) {
            Ok(i) => i,
            Err(msg) => return usage(msg),
        };
        // A material without the AOV's lobe renders its sphere black (usize::MAX matches
        // no leaf).
        let options = PreviewOptions {
            inputs,
            aov_leaf: aov.map(|n| find_leaf(&c.material, n).unwrap_or(usize::MAX)),
            ..base.clone()
        };
        balls.push(Ball {
            material: &c.material,
            options,
        });
    }
    let sheet = match ContactSheet::new(balls, base.env) {
        Ok(s) => s,
        Err(e) => return usage(e.to_string()),
    };
    let out = args
        .output
        .clone()
        .unwrap_or_else(|| default_output(&args.source.input, args.pfm));
    let pfm = args.pfm
        || out
            .extension()
            .is_some_and(|e| e.eq_ignore_ascii_case("pfm"));
    let format = if pfm {
        ImageFormat::Pfm
    } else {
        ImageFormat::Png
    };
    let show = std::io::stderr().is_terminal();
    if let Err(e) = stream_output(Some(&out), |w| write_sheet(&sheet, format, w, show)) {
        return report_error(&e, common);
    }
    ExitCode::SUCCESS
}

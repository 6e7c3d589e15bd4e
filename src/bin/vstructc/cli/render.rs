//! `vstructc render INPUT [-o ball.png] [--size N] [--furnace] [--pfm] [--aov lobe:NAME]
//! [--input NAME=VALUE]... [--material HANDLE] [--no-labels]`: the material-ball preview
//! (docs/preview.md).
//!
//! The input is read, resolved and lowered as by `compile`; each material is compiled for
//! the interpreter and rendered ([`vstructc::interp::preview`]). With several materials and no
//! `--material`, the balls are arranged in a contact sheet (a grid, `⌈√n⌉` columns, row-major
//! in material order); in PNG each ball has its material's name under it unless
//! `--no-labels` (PFM and EXR hold rendered values only).
//!
//! Output: `-o PATH` (`-` for standard output); without `-o`, `<input stem>.png` (`.pfm`
//! with `--pfm`) in the current directory, `preview.png` for standard input. The extension
//! picks the format: `.png` sRGB PNG, `.pfm` linear PFM, `.exr` linear OpenEXR (32-bit
//! float); `--pfm` selects PFM whatever the extension. Another extension (`.jpg`, …), or
//! `--pfm` with `.png` or `.exr`, is a usage error found before any work. The file is
//! written atomically (temporary file, then rename).
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
use super::input::{report_error, stream_output};
use super::material::{
    MaterialArgs, check_input_names, check_input_syntax, load_materials, packed_inputs,
};
use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};
use vstructc::back::png::{ImageFormat, write_rows};
use vstructc::interp::Material;
use vstructc::interp::preview::{Ball, ContactSheet, PreviewOptions};

/// Arguments of `vstructc render`.
#[derive(Debug, clap::Args)]
pub struct RenderArgs {
    /// Input, material and external inputs.
    #[command(flatten)]
    pub source: MaterialArgs,
    /// Output file (`-`: standard output); the extension picks the format: `.png` (sRGB),
    /// `.pfm` or `.exr` (linear float). Default: `<input stem>.png` (or `.pfm`).
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
    /// No material names under the balls of a PNG contact sheet (PFM and EXR never have
    /// them).
    #[arg(long)]
    pub no_labels: bool,
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

/// The image format of the output file `out`, by its extension (ASCII case ignored): `.png`
/// or none PNG, `.pfm` PFM, `.exr` EXR; `--pfm` selects PFM whatever the name, except that
/// it conflicts with `.png` and `.exr`. Another extension is a usage error.
fn image_format(out: &Path, pfm: bool) -> Result<ImageFormat, String> {
    let ext = out
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    match (ext.as_deref(), pfm) {
        (Some(e @ ("png" | "exr")), true) => Err(format!(
            "--pfm conflicts with the output file's extension `.{e}`"
        )),
        (Some("pfm"), _) | (_, true) => Ok(ImageFormat::Pfm),
        (Some("png") | None, false) => Ok(ImageFormat::Png),
        (Some("exr"), false) => Ok(ImageFormat::Exr),
        (Some(e), false) => Err(format!(
            "`.{e}` output is not supported: `render` writes PNG (`.png`), linear PFM (`.pfm`, \
             or any name with `--pfm`) or linear OpenEXR (`.exr`)"
        )),
    }
}

/// Run `vstructc render`.
pub fn run(args: &RenderArgs, common: &CommonOptions) -> ExitCode {
    let out = args
        .output
        .clone()
        .unwrap_or_else(|| default_output(&args.source.input, args.pfm));
    let format = if out.as_os_str() == "-" {
        Ok(if args.pfm {
            ImageFormat::Pfm
        } else {
            ImageFormat::Png
        })
    } else {
        image_format(&out, args.pfm)
    };
    let usage = |msg: String| {
        eprintln_quiet!("error: {msg}");
        ExitCode::from(2)
    };
    // Every flag is checked before the input is read: a usage error prints nothing else.
    let format = match format {
        Ok(f) => f,
        Err(msg) => return usage(msg),
    };
    let aov = match args.aov.as_deref() {
        None => None,
        Some(a) => match a.strip_prefix("lobe:") {
            Some(name) if !name.is_empty() => Some(name),
            _ => return usage(format!("--aov `{a}`: expected `lobe:NAME`")),
        },
    };
    if let Err(msg) = check_input_syntax(&args.source.inputs) {
        return usage(msg);
    }
    let size_check = PreviewOptions {
        size: args.size,
        ..PreviewOptions::default()
    };
    if let Err(e) = size_check.validate() {
        return usage(e.to_string());
    }
    let (materials, diags) = match load_materials(&args.source, common) {
        Ok(x) => x,
        Err(status) => return status,
    };
    let status = super::report(&diags, common);
    if status != ExitCode::SUCCESS {
        return status;
    }
    if let Err(msg) = check_input_names(&materials, &args.source.inputs) {
        return usage(msg);
    }
    if let Some(name) = aov
        && !materials
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
    let base = PreviewOptions {
        size: args.size,
        batched: args.batched,
        ..PreviewOptions::default()
    };
    let base = if args.furnace { base.furnace() } else { base };
    // A contact sheet names its balls in PNG; linear images keep only rendered values.
    let labels = materials.len() > 1 && !format.is_linear() && !args.no_labels;
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
            label: labels.then(|| c.name.clone()),
        });
    }
    let sheet = match ContactSheet::new(balls, base.env) {
        Ok(s) => s,
        Err(e) => return usage(e.to_string()),
    };
    let show = std::io::stderr().is_terminal();
    if let Err(e) = stream_output(Some(&out), |w| write_sheet(&sheet, format, w, show)) {
        return report_error(&e, common);
    }
    ExitCode::SUCCESS
}

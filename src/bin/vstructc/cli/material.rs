//! What `render` and `eval` share: which input and material, external inputs, and the
//! materials compiled for the interpreter.

use super::CommonOptions;
use super::input::{Ran, report_error, run_pipeline};
use std::path::PathBuf;
use std::process::ExitCode;
use vstructc::diag::{Diagnostics, Error};
use vstructc::interp::Material;
use vstructc::pipeline::Lowering;

/// Options shared by `render` and `eval`: which input and material, and external inputs.
#[derive(Debug, Clone, clap::Args)]
pub struct MaterialArgs {
    /// The network: a RIB, JSON or USD file, or `-` for standard input.
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

/// The message of exit status 1 when the input has no material to act on (`compile`,
/// `render`, `eval`).
pub const NO_MATERIAL: &str = "the input has no material with a lowering recipe";

/// A lowered, compiled material.
pub struct Compiled {
    /// Material name.
    pub name: String,
    /// Its interpreter form.
    pub material: Material,
}

/// Read, resolve and lower the input (the library's pipeline); compile every selected
/// material. On failure the diagnostics are printed and the exit status is returned.
/// Diagnostics of a successful load are returned for the caller to report.
pub fn load_materials(
    args: &MaterialArgs,
    common: &CommonOptions,
) -> Result<(Vec<Compiled>, Diagnostics), ExitCode> {
    let lowering = match &args.material {
        Some(name) => Lowering::Only(name.clone()),
        None => Lowering::All,
    };
    let Ran {
        output, mut diags, ..
    } = run_pipeline(
        &args.input,
        args.no_conditions,
        args.strict_rib,
        false,
        lowering,
        common,
    )?;
    let mut out = Vec::new();
    for ir in &output.materials {
        match Material::new(ir) {
            Ok(material) => out.push(Compiled {
                name: ir.name.clone(),
                material,
            }),
            Err(Error::Input(d)) => diags.push(*d),
            Err(e) => {
                super::report(&diags, common);
                return Err(report_error(&e, common));
            }
        }
    }
    diags.sort();
    if diags.has_errors() {
        super::report(&diags, common);
        return Err(ExitCode::from(1));
    }
    if out.is_empty() {
        super::report(&diags, common);
        eprintln_quiet!("error: {NO_MATERIAL}");
        return Err(ExitCode::from(1));
    }
    Ok((out, diags))
}

/// Check the form of every `--input NAME=VALUE` setting (a name, `=`, one or three
/// numbers) before any work; whether a material has the slot is checked once the materials
/// are loaded ([`check_input_names`]).
pub fn check_input_syntax(settings: &[String]) -> Result<(), String> {
    for s in settings {
        let (_, value) = s
            .split_once('=')
            .filter(|(name, _)| !name.is_empty())
            .ok_or_else(|| format!("--input `{s}`: expected NAME=VALUE"))?;
        parse_numbers(s, value)?;
    }
    Ok(())
}

/// The numbers of an `--input` value: one, or three separated by commas or spaces.
fn parse_numbers(setting: &str, value: &str) -> Result<Vec<f32>, String> {
    let nums: Vec<f32> = value
        .split(|c: char| c == ',' || c.is_whitespace())
        .filter(|t| !t.is_empty())
        .map(|t| t.parse::<f32>())
        .collect::<Result<_, _>>()
        .map_err(|_| format!("--input `{setting}`: `{value}` is not one or three numbers"))?;
    if !matches!(nums.len(), 1 | 3) {
        return Err(format!(
            "--input `{setting}`: `{value}` is not one or three numbers"
        ));
    }
    Ok(nums)
}

/// Parse `--input NAME=VALUE` settings into packed inputs for `m` (fallbacks elsewhere).
/// Unknown names and malformed values are usage errors.
pub fn packed_inputs(m: &Material, settings: &[String]) -> Result<Vec<f32>, String> {
    let mut packed = m.fallback_inputs();
    for s in settings {
        let (name, value) = s
            .split_once('=')
            .ok_or_else(|| format!("--input `{s}`: expected NAME=VALUE"))?;
        let nums = parse_numbers(s, value)?;
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

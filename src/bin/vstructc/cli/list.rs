//! `vstructc list [--json]`: every shader the registry knows (from `--args`,
//! `VSTRUCTC_ARGS_PATH` and the embedded definitions), its kind, and the file its
//! definition is read from.
//!
//! Exit status: 0 (definition files that could not be read are reported, and their shaders
//! listed with kind `unreadable`), 1 when an error was reported (a rejected definition file,
//! a missing `--args` path), 2 on usage errors.

use super::input::registry_for;
use super::json::{self, format_word, origin};
use super::{CommonOptions, report};
use serde::Serialize;
use std::fmt::Write as _;
use std::process::ExitCode;

/// Arguments of `vstructc list`.
#[derive(Debug, clap::Args)]
pub struct ListArgs {
    /// Print a JSON document on standard output instead of the table (docs/json.md).
    #[arg(long)]
    pub json: bool,
}

/// The `--json` document.
#[derive(Debug, Serialize)]
pub struct ListDoc {
    /// Every known shader, sorted by id.
    pub shaders: Vec<ShaderDoc>,
}

/// One known shader.
#[derive(Debug, Serialize)]
pub struct ShaderDoc {
    /// Shader id.
    pub id: String,
    /// Kind (`bxdf`, `pattern`, …; `unknown` when the file does not say, `unreadable` when
    /// the file was rejected).
    pub kind: String,
    /// `args` or `oso`: the format of the definition used.
    pub format: &'static str,
    /// The file the definition is read from (`<embedded>/X.args` for an embedded one).
    pub path: String,
    /// `embedded`, `args-option` (under an `--args` path) or `environment`
    /// (`VSTRUCTC_ARGS_PATH`).
    pub origin: &'static str,
    /// Other files defining the same id, not used (the winner is chosen by `--prefer` and
    /// the search order).
    pub shadowed: Vec<String>,
}

/// The rows of `list`, sorted by id.
pub fn shaders(common: &CommonOptions) -> (Vec<ShaderDoc>, vstructc::diag::Diagnostics) {
    let registry = registry_for(common);
    let mut ids: Vec<String> = registry.ids().into_iter().map(str::to_string).collect();
    ids.sort();
    let mut rows = Vec::with_capacity(ids.len());
    for id in ids {
        let sources = registry.sources(&id);
        let row = match registry.definition(&id) {
            Some(def) => ShaderDoc {
                kind: def.kind.clone(),
                format: format_word(def.source),
                origin: origin(&def.path, common),
                shadowed: sources
                    .iter()
                    .filter(|(_, p)| **p != *def.path)
                    .map(|(_, p)| p.to_string())
                    .collect(),
                path: def.path.to_string(),
                id,
            },
            None => {
                // The file was rejected (its errors are reported): name the first candidate.
                let Some((kind, path)) = sources.first() else {
                    continue;
                };
                ShaderDoc {
                    kind: "unreadable".into(),
                    format: format_word(*kind),
                    origin: origin(path, common),
                    shadowed: sources.iter().skip(1).map(|(_, p)| p.to_string()).collect(),
                    path: path.to_string(),
                    id,
                }
            }
        };
        rows.push(row);
    }
    (rows, registry.diagnostics())
}

/// The human table: a header, then id, kind, format, origin and path, aligned; other files
/// defining the same id below their row.
pub fn render_human(rows: &[ShaderDoc]) -> String {
    let width = |f: &dyn Fn(&ShaderDoc) -> usize, header: &str| {
        rows.iter().map(f).max().unwrap_or(0).max(header.len())
    };
    let w_id = width(&|r| r.id.chars().count(), "SHADER");
    let w_kind = width(&|r| r.kind.chars().count(), "KIND");
    let w_origin = width(&|r| r.origin.len(), "ORIGIN");
    let mut out = String::new();
    let mut line = |id: &str, kind: &str, format: &str, origin: &str, path: &str| {
        let l = format!("{id:w_id$}  {kind:w_kind$}  {format:6}  {origin:w_origin$}  {path}");
        let _ = writeln!(out, "{}", l.trim_end());
    };
    line("SHADER", "KIND", "FORMAT", "ORIGIN", "PATH");
    for r in rows {
        line(&r.id, &r.kind, r.format, r.origin, &r.path);
        for s in &r.shadowed {
            line("", "", "", "", &format!("also {s} (not used)"));
        }
    }
    out
}

/// Run `vstructc list`.
pub fn run(args: &ListArgs, common: &CommonOptions) -> ExitCode {
    let (rows, diags) = shaders(common);
    let status = report(&diags, common);
    let printed = if args.json {
        json::print(&ListDoc { shaders: rows }, common)
    } else {
        match super::input::print_stdout(&render_human(&rows), common) {
            Ok(()) => ExitCode::SUCCESS,
            Err(failed) => failed,
        }
    };
    if printed == ExitCode::SUCCESS {
        status
    } else {
        printed
    }
}

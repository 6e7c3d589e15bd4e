//! `vstructc info SHADER`: a readable summary of one shader definition (kind, source, params
//! grouped by page, outputs, vstruct heads with member counts, conditional expressions), or
//! `--json` for tools.
//!
//! Exit status: 0 on success, 1 when an input error was reported (a rejected definition file,
//! a missing `--args` path), 2 when the shader id is unknown.

use super::input::registry_for;
use super::{CommonOptions, report};
use std::fmt::Write as _;
use std::process::ExitCode;
use vstructc::diag::{closest_names, did_you_mean};
use vstructc::registry::{Definition, Property, Registry, VstructTables};

/// Arguments of `vstructc info`.
#[derive(Debug, clap::Args)]
pub struct InfoArgs {
    /// The shader id (e.g. `PxrLayerMixer`).
    #[arg(value_name = "SHADER")]
    pub shader: String,
    /// Print a JSON document instead of the readable summary.
    #[arg(long)]
    pub json: bool,
}

/// Run `vstructc info`.
pub fn run(args: &InfoArgs, common: &CommonOptions) -> ExitCode {
    let registry = registry_for(common);
    let def = registry.definition(&args.shader);
    let tables = registry.tables(&args.shader);
    let diags = registry.diagnostics();
    let status = report(&diags, common);
    if diags.has_errors() {
        return status;
    }
    let Some(def) = def else {
        let ids = registry.ids();
        let hint = did_you_mean(&closest_names(&args.shader, ids.iter().copied()));
        eprintln_quiet!("error: unknown shader `{}`{hint}", args.shader);
        if !ids.is_empty() && ids.len() <= 50 {
            eprintln_quiet!("  known shaders: {}", ids.join(", "));
        }
        return ExitCode::from(2);
    };
    let tables = tables.unwrap_or_default();
    let text = if args.json {
        render_json(&def, &tables, &registry)
    } else {
        render_human(&def, &tables, &registry, common.verbose)
    };
    match super::input::print_stdout(&text, common) {
        Ok(()) => status,
        Err(failed) => failed,
    }
}

/// The human summary of `def`; `verbose` also lists the other files that define the id.
pub fn render_human(
    def: &Definition,
    tables: &VstructTables,
    registry: &Registry,
    verbose: bool,
) -> String {
    let mut out = String::new();
    let _ = writeln!(out, "{}: {}", def.id, def.kind);
    let source = match def.source {
        vstructc::registry::SourceKind::Args => ".args",
        vstructc::registry::SourceKind::Oso => ".oso",
    };
    let _ = writeln!(out, "  defined in {} ({source})", def.path);
    for (_, other) in registry.sources(&def.id) {
        if verbose && other != def.path {
            let _ = writeln!(out, "  also found: {other} (not used)");
        }
    }
    if let Some((_, help)) = def.metadata.iter().find(|(k, _)| *k == "help")
        && let Some(first) = help.lines().map(str::trim).find(|l| !l.is_empty())
    {
        let _ = writeln!(out, "  help: {first}");
    }

    let _ = writeln!(out, "\nInputs ({})", def.inputs.len());
    for (page, props) in group_by_page(&def.inputs) {
        let _ = writeln!(
            out,
            "  {}",
            page.map_or("(no page)".to_string(), |p| format!("page {p}"))
        );
        write_rows(&mut out, &props, tables, true);
    }

    let _ = writeln!(out, "\nOutputs ({})", def.outputs.len());
    let outputs: Vec<&Property> = def.outputs.iter().collect();
    write_rows(&mut out, &outputs, tables, false);

    write_heads(&mut out, tables);
    write_conditionals(&mut out, def);
    out
}

/// Properties grouped by page path, pages in order of first appearance.
fn group_by_page(props: &[Property]) -> Vec<(Option<&str>, Vec<&Property>)> {
    let mut groups: Vec<(Option<&str>, Vec<&Property>)> = Vec::new();
    for p in props {
        let page = p.page.as_deref();
        match groups.iter_mut().find(|(g, _)| *g == page) {
            Some((_, v)) => v.push(p),
            None => groups.push((page, vec![p])),
        }
    }
    groups
}

/// One aligned row per property: name, type, default (inputs only), flags.
fn write_rows(out: &mut String, props: &[&Property], tables: &VstructTables, inputs: bool) {
    let rows: Vec<[String; 4]> = props
        .iter()
        .map(|p| {
            let default = p
                .default
                .as_ref()
                .map_or("-".to_string(), |v| v.to_string());
            [
                p.name.clone(),
                p.ty.to_string(),
                default,
                flags(p, tables, inputs),
            ]
        })
        .collect();
    // Column widths are capped: `format!` panics on a width above u16::MAX, and a 1 MB
    // property name or default must not crash `info` (longer cells just overflow the column).
    let width = |i: usize| {
        rows.iter()
            .map(|r: &[String; 4]| r[i].chars().count())
            .max()
            .unwrap_or(0)
            .min(MAX_COLUMN)
    };
    let (w0, w1, w2) = (width(0), width(1), width(2));
    for r in rows {
        let line = if inputs {
            format!("    {:w0$}  {:w1$}  {:w2$}  {}", r[0], r[1], r[2], r[3])
        } else {
            format!("    {:w0$}  {:w1$}  {}", r[0], r[1], r[3])
        };
        let _ = writeln!(out, "{}", line.trim_end());
    }
}

/// Widest padded column in the human summary.
const MAX_COLUMN: usize = 120;

/// Short flags: head / member, hidden, not connectable, declared type when it differs.
fn flags(p: &Property, tables: &VstructTables, input: bool) -> String {
    let mut f: Vec<String> = Vec::new();
    let head_members = if input {
        tables.members_in(&p.name).len()
    } else {
        tables.members_out(&p.name).len()
    };
    if head_members > 0 {
        f.push(format!("head ({head_members} members)"));
    }
    if let Some(m) = &p.vstruct {
        let mut s = format!("member {}.{}", m.head, m.member);
        if let Some(a) = &m.alias {
            let _ = write!(s, " alias {a:?}");
        }
        if m.cond.is_some() {
            s.push_str(", conditional");
        }
        f.push(s);
    }
    if p.widget
        .as_deref()
        .is_some_and(|w| w.eq_ignore_ascii_case("null"))
    {
        f.push("hidden".into());
    }
    if input && !p.connectable {
        f.push("not connectable".into());
    }
    let shown = p.ty.to_string();
    if !p.declared_type.is_empty()
        && p.declared_type != shown
        && p.ty.base.word() != p.declared_type
    {
        f.push(format!("declared {}", p.declared_type));
    }
    f.join(", ")
}

fn write_heads(out: &mut String, tables: &VstructTables) {
    if tables.is_empty() {
        return;
    }
    let _ = writeln!(out, "\nVstruct heads");
    let mut rows: Vec<(String, String, String)> = Vec::new();
    for h in tables.input_heads() {
        let n = tables.members_in(h).len();
        rows.push(("input".into(), h.to_string(), format!("{n} members")));
    }
    for h in tables.output_heads() {
        let members = tables.members_out(h);
        let conditional = members.iter().filter(|m| m.cond.is_some()).count();
        rows.push((
            "output".into(),
            h.to_string(),
            format!("{} members, {conditional} conditional", members.len()),
        ));
    }
    let w = rows.iter().map(|r| r.1.chars().count()).max().unwrap_or(0);
    for (dir, name, count) in rows {
        let _ = writeln!(out, "  {dir:6}  {name:w$}  {count}");
    }
}

fn write_conditionals(out: &mut String, def: &Definition) {
    let conds: Vec<(&str, &str)> = def
        .properties_in_order()
        .into_iter()
        .filter_map(|p| {
            let c = p.vstruct.as_ref()?.cond.as_ref()?;
            Some((p.name.as_str(), c.text.as_str()))
        })
        .collect();
    if conds.is_empty() {
        return;
    }
    let _ = writeln!(out, "\nConditional expressions ({})", conds.len());
    let w = conds.iter().map(|c| c.0.chars().count()).max().unwrap_or(0);
    for (name, text) in conds {
        let _ = writeln!(out, "  {name:w$}  {}", text.trim());
    }
}

/// The `--json` document: the definition (every field of the model) plus its vstruct tables.
pub fn render_json(def: &Definition, tables: &VstructTables, registry: &Registry) -> String {
    use serde_json::json;
    let input_heads: Vec<_> = tables
        .input_heads()
        .map(|h| {
            let members: Vec<_> = tables
                .members_in(h)
                .iter()
                .map(|m| json!({ "property": m.property, "names": m.names }))
                .collect();
            json!({ "name": h, "members": members })
        })
        .collect();
    let output_heads: Vec<_> = tables
        .output_heads()
        .map(|h| {
            let members: Vec<_> = tables
                .members_out(h)
                .iter()
                .map(|m| {
                    let cond = m.cond.as_ref().map(|c| {
                        json!({
                            "text": c.source.text,
                            "location": c.source.location,
                            "parses": c.statement().is_some(),
                        })
                    });
                    json!({ "property": m.property, "names": m.names, "cond": cond })
                })
                .collect();
            json!({ "name": h, "members": members })
        })
        .collect();
    let sources: Vec<_> = registry
        .sources(&def.id)
        .into_iter()
        .map(|(kind, path)| json!({ "kind": kind, "path": path, "used": path == def.path }))
        .collect();
    let doc = json!({
        "definition": def,
        "sources": sources,
        "vstruct": { "inputHeads": input_heads, "outputHeads": output_heads },
    });
    let mut s = serde_json::to_string_pretty(&doc).unwrap_or_else(|_| "{}".into());
    s.push('\n');
    s
}

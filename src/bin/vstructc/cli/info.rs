//! `vstructc info SHADER`: a readable summary of one shader definition (kind, source, params
//! grouped by page, outputs, vstruct heads with member counts, conditional expressions), or
//! `--json` for tools: plain fields, values as `{"type", "value"}` (docs/json.md).
//!
//! Exit status: 0 on success, 1 when an input error was reported (a rejected definition file,
//! a missing `--args` path), 2 when the shader id is unknown.

use super::input::registry_for;
use super::json::{self, LocationDoc, TypedValue, format_word, origin, type_word};
use super::{CommonOptions, report};
use serde::Serialize;
use std::fmt::Write as _;
use std::process::ExitCode;
use vstructc::diag::did_you_mean;
use vstructc::registry::{Definition, Property, Registry, VstructTables};

/// Arguments of `vstructc info`.
#[derive(Debug, clap::Args)]
pub struct InfoArgs {
    /// The shader id (e.g. `PxrLayerMixer`).
    #[arg(value_name = "SHADER")]
    pub shader: String,
    /// Print a JSON document on standard output instead of the readable summary
    /// (docs/json.md).
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
        let hint = did_you_mean(&args.shader, ids.iter().copied());
        eprintln_quiet!("error: unknown shader `{}`{hint}", args.shader);
        if !ids.is_empty() && ids.len() <= 50 {
            eprintln_quiet!("  known shaders: {}", ids.join(", "));
        }
        return ExitCode::from(2);
    };
    let tables = tables.unwrap_or_default();
    if args.json {
        let printed = json::print(&info_doc(&def, &tables, &registry, common), common);
        return if printed == ExitCode::SUCCESS {
            status
        } else {
            printed
        };
    }
    let text = render_human(&def, &tables, &registry, common.verbose);
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
    // A definition may put each of its many parameters on a page of its own: find a page's
    // group by name, not by a scan of the groups.
    let mut index: std::collections::HashMap<Option<&str>, usize> =
        std::collections::HashMap::new();
    for p in props {
        let page = p.page.as_deref();
        let next = groups.len();
        let i = *index.entry(page).or_insert(next);
        if i == next {
            groups.push((page, Vec::new()));
        }
        groups[i].1.push(p);
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

/// The `--json` document (docs/json.md, `info`): the definition in plain JSON, the files
/// that define the id, and the vstruct tables.
#[derive(Debug, Serialize)]
#[serde(rename_all = "camelCase")]
pub struct InfoDoc {
    /// The definition used.
    pub definition: DefinitionDoc,
    /// Every file that defines the id, the one used marked.
    pub sources: Vec<SourceDoc>,
    /// Vstruct heads and their members.
    pub vstruct: VstructDoc,
}

/// One definition.
#[derive(Debug, Serialize)]
#[serde(rename_all = "camelCase")]
pub struct DefinitionDoc {
    /// Shader id.
    pub id: String,
    /// Shader kind (`bxdf`, `pattern`, …; `unknown` when the file does not say).
    pub kind: String,
    /// `args` or `oso`.
    pub format: &'static str,
    /// The file read (`<embedded>/X.args` for a definition compiled into vstructc).
    pub path: String,
    /// Where the definition came from: `embedded`, `args-option`, `environment`.
    pub origin: &'static str,
    /// Input parameters in declaration order.
    pub inputs: Vec<PropertyDoc>,
    /// Outputs in declaration order.
    pub outputs: Vec<PropertyDoc>,
    /// Node-level metadata, `[key, value]` pairs in document order.
    pub metadata: Vec<[String; 2]>,
}

/// One input or output.
#[derive(Debug, Serialize)]
#[serde(rename_all = "camelCase")]
pub struct PropertyDoc {
    /// Name.
    pub name: String,
    /// Interpreted type word (`float`, `color`, `vstruct`, `float[2]`, `struct Name`, …).
    #[serde(rename = "type")]
    pub ty: String,
    /// The type text as declared in the file.
    pub declared_type: String,
    /// Default value (`{"type", "value"}`), or null.
    pub default: Option<TypedValue>,
    /// Page path (`:`-joined), or null.
    pub page: Option<String>,
    /// UI label, or null.
    pub label: Option<String>,
    /// Help text, or null.
    pub help: Option<String>,
    /// Widget name, or null.
    pub widget: Option<String>,
    /// Whether it accepts connections.
    pub connectable: bool,
    /// Connection types (tags).
    pub connection_types: Vec<String>,
    /// Options: `{"label", "value"}` pairs.
    pub options: Vec<OptionDoc>,
    /// Member declaration, or null.
    pub vstruct: Option<MemberDoc>,
    /// Where it is declared.
    pub location: LocationDoc,
    /// Every attribute verbatim, `[key, value]` pairs in document order.
    pub metadata: Vec<[String; 2]>,
}

/// One option of a property's options list.
#[derive(Debug, Serialize)]
pub struct OptionDoc {
    /// Shown label.
    pub label: String,
    /// Value.
    pub value: String,
}

/// A property's vstruct member declaration.
#[derive(Debug, Serialize)]
pub struct MemberDoc {
    /// Head name.
    pub head: String,
    /// Member name.
    pub member: String,
    /// `vstructmemberaliases`, or null.
    pub alias: Option<String>,
    /// The conditional expression's text, or null.
    pub conditional: Option<String>,
}

/// A file that defines the id.
#[derive(Debug, Serialize)]
pub struct SourceDoc {
    /// `args` or `oso`.
    pub format: &'static str,
    /// The file.
    pub path: String,
    /// True for the file whose definition is used.
    pub used: bool,
}

/// The vstruct tables.
#[derive(Debug, Serialize)]
#[serde(rename_all = "camelCase")]
pub struct VstructDoc {
    /// Input heads.
    pub input_heads: Vec<HeadDoc>,
    /// Output heads.
    pub output_heads: Vec<HeadDoc>,
}

/// One head and its members.
#[derive(Debug, Serialize)]
pub struct HeadDoc {
    /// Head name.
    pub name: String,
    /// Members in declaration order.
    pub members: Vec<HeadMemberDoc>,
}

/// One member of a head.
#[derive(Debug, Serialize)]
pub struct HeadMemberDoc {
    /// The member property.
    pub property: String,
    /// The names it matches by (member name, then aliases).
    pub names: Vec<String>,
    /// Output members: the conditional, or null. Absent on input members.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub cond: Option<Option<CondDoc>>,
}

/// An output member's conditional.
#[derive(Debug, Serialize)]
pub struct CondDoc {
    /// The expression text.
    pub text: String,
    /// Where its value starts in the definition file.
    pub location: LocationDoc,
    /// Whether it parses.
    pub parses: bool,
}

fn pairs(m: &vstructc::registry::Metadata) -> Vec<[String; 2]> {
    m.iter()
        .map(|(k, v)| [k.to_string(), v.to_string()])
        .collect()
}

fn property_doc(p: &Property) -> PropertyDoc {
    PropertyDoc {
        name: p.name.clone(),
        ty: type_word(&p.ty),
        declared_type: p.declared_type.clone(),
        default: p.default.as_ref().map(TypedValue::of),
        page: p.page.clone(),
        label: p.label.clone(),
        help: p.help.clone(),
        widget: p.widget.clone(),
        connectable: p.connectable,
        connection_types: p.connection_types.clone(),
        options: p
            .options
            .iter()
            .map(|(label, value)| OptionDoc {
                label: label.clone(),
                value: value.clone(),
            })
            .collect(),
        vstruct: p.vstruct.as_ref().map(|m| MemberDoc {
            head: m.head.clone(),
            member: m.member.clone(),
            alias: m.alias.clone(),
            conditional: m.cond.as_ref().map(|c| c.text.clone()),
        }),
        location: LocationDoc::of(&p.location),
        metadata: pairs(&p.metadata),
    }
}

/// The `--json` document of `def`.
pub fn info_doc(
    def: &Definition,
    tables: &VstructTables,
    registry: &Registry,
    common: &CommonOptions,
) -> InfoDoc {
    let input_heads = tables
        .input_heads()
        .map(|h| HeadDoc {
            name: h.to_string(),
            members: tables
                .members_in(h)
                .iter()
                .map(|m| HeadMemberDoc {
                    property: m.property.to_string(),
                    names: m.names.iter().map(|n| n.to_string()).collect(),
                    cond: None,
                })
                .collect(),
        })
        .collect();
    let output_heads = tables
        .output_heads()
        .map(|h| HeadDoc {
            name: h.to_string(),
            members: tables
                .members_out(h)
                .iter()
                .map(|m| HeadMemberDoc {
                    property: m.property.to_string(),
                    names: m.names.iter().map(|n| n.to_string()).collect(),
                    cond: Some(m.cond.as_ref().map(|c| CondDoc {
                        text: c.source.text.clone(),
                        location: LocationDoc::of(&c.source.location),
                        parses: c.statement().is_some(),
                    })),
                })
                .collect(),
        })
        .collect();
    InfoDoc {
        definition: DefinitionDoc {
            id: def.id.clone(),
            kind: def.kind.clone(),
            format: format_word(def.source),
            path: def.path.to_string(),
            origin: origin(&def.path, common),
            inputs: def.inputs.iter().map(property_doc).collect(),
            outputs: def.outputs.iter().map(property_doc).collect(),
            metadata: pairs(&def.metadata),
        },
        sources: registry
            .sources(&def.id)
            .into_iter()
            .map(|(kind, path)| SourceDoc {
                format: format_word(kind),
                used: path == def.path,
                path: path.to_string(),
            })
            .collect(),
        vstruct: VstructDoc {
            input_heads,
            output_heads,
        },
    }
}

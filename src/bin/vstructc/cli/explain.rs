//! `vstructc explain HANDLE.INPUT INPUT [--json]`: the story of one input's value.
//!
//! The story says where the value comes from: authored in the file, the definition's
//! default, or written by resolution (a vstruct `set`/`copy`, or a connection it made), and
//! follows it upstream to its origin. A conditional's read of a value that resolution wrote
//! tells that value's story in turn; a connection to an upstream member output tells the
//! story of the upstream inputs that member carries (the inputs of the same member name).
//! Each input's story is told once; a later mention says it was told above.
//!
//! Exit status: 0, 1 on input errors, 2 on usage errors (a malformed target, a node the
//! input does not have, an input its definition does not declare).

use super::CommonOptions;
use super::input::{ReadInput, read};
use super::json::{self, LocationDoc, TypedValue};
use serde::Serialize;
use std::fmt::Write as _;
use std::path::PathBuf;
use std::process::ExitCode;
use vstructc::diag::did_you_mean;
use vstructc::resolve::{Outcome, StoryEvent, resolve};

/// Arguments of `vstructc explain`.
#[derive(Debug, clap::Args)]
pub struct ExplainArgs {
    /// The input to explain, as `HANDLE.INPUT` (the handle may contain dots; the input is
    /// the text after the last dot).
    pub target: String,
    /// The network: a RIB, JSON or USD file, or `-` for standard input.
    pub input: PathBuf,
    /// Explain as if `--no-conditions` were given.
    #[arg(long)]
    pub no_conditions: bool,
    /// Print the story as a JSON document on standard output (docs/json.md).
    #[arg(long)]
    pub json: bool,
}

/// The story of one input (the `--json` document, and nested in it).
#[derive(Debug, Serialize)]
#[serde(rename_all = "camelCase")]
pub struct Story {
    /// The node's handle.
    pub node: String,
    /// The node's shader id.
    pub shader: String,
    /// The input.
    pub input: String,
    /// Where the value comes from: `authored` (a value in the file), `connected` (a
    /// connection in the file), `default` (the definition's default), `written` (a value a
    /// vstruct `set` or `copy` wrote), `resolved` (a connection resolution made), `none`
    /// (declared without value or default).
    pub origin: &'static str,
    /// The value (null when connected or without value).
    pub value: Option<TypedValue>,
    /// The connections, upstream node and output.
    pub connections: Vec<LinkDoc>,
    /// Where an authored value or connection is written in the input.
    pub location: Option<LocationDoc>,
    /// The resolution decisions about this input, in order.
    pub events: Vec<EventDoc>,
    /// For a connection to an upstream member output: the stories of the upstream inputs
    /// the output carries (inputs of the same member name that have a value or connection).
    pub upstream: Vec<Story>,
    /// True when this input's story was already told earlier in the document: `events` and
    /// `upstream` are then empty.
    pub told_above: bool,
    /// True when the story is more than 16 steps upstream of the input explained and stops
    /// here: `events` and `upstream` are then empty.
    pub truncated: bool,
}

/// A connection.
#[derive(Debug, Serialize)]
pub struct LinkDoc {
    /// Upstream node handle.
    pub node: String,
    /// Upstream output (null: a whole-node reference).
    pub output: Option<String>,
}

/// One resolution decision about a member input.
#[derive(Debug, Serialize)]
#[serde(rename_all = "camelCase")]
pub struct EventDoc {
    /// The input head it was expanded from.
    pub head: String,
    /// The upstream node the head is connected to.
    pub upstream_node: String,
    /// The upstream output head.
    pub upstream_head: String,
    /// The upstream member output that matched, or null.
    pub matched_output: Option<String>,
    /// The name it matched by, or null.
    pub matched_name: Option<String>,
    /// The conditional evaluated, or null.
    pub conditional: Option<String>,
    /// The chosen action as written (`connect`, `set 1`, …), or null.
    pub action: Option<String>,
    /// Each parameter the conditional read on the upstream node.
    pub reads: Vec<ReadDoc>,
    /// What happened: `connected`, `ignored`, `written`, `not-applied`,
    /// `direct-connection-wins`, `unparsable`, `no-counterpart`.
    pub outcome: &'static str,
    /// `written`: the value written.
    pub written: Option<TypedValue>,
    /// `not-applied`: why.
    pub reason: Option<String>,
}

/// One parameter a conditional read.
#[derive(Debug, Serialize)]
#[serde(rename_all = "camelCase")]
pub struct ReadDoc {
    /// The upstream node.
    pub node: String,
    /// The parameter.
    pub param: String,
    /// `authored`, `written` (by resolution, earlier), `default`, `none` (declared, no
    /// value), `undeclared` (not an input of the upstream type).
    pub origin: &'static str,
    /// The value read, or null.
    pub value: Option<TypedValue>,
    /// Whether the parameter was connected when read.
    pub connected: bool,
    /// Where an authored value is written in the input.
    pub location: Option<LocationDoc>,
    /// `written`: the story of the value read.
    pub story: Option<Box<Story>>,
}

impl Story {
    /// The document of the library's story.
    fn of(s: &vstructc::resolve::Story) -> Story {
        Story {
            node: s.node.clone(),
            shader: s.shader.clone(),
            input: s.input.clone(),
            origin: s.origin,
            value: s.value.as_ref().map(TypedValue::of),
            connections: s
                .connections
                .iter()
                .map(|(node, output)| LinkDoc {
                    node: node.clone(),
                    output: output.clone(),
                })
                .collect(),
            location: s.location.as_ref().map(LocationDoc::of),
            events: s.events.iter().map(EventDoc::of).collect(),
            upstream: s.upstream.iter().map(Story::of).collect(),
            told_above: s.told_above,
            truncated: s.truncated,
        }
    }
}

impl EventDoc {
    fn of(se: &StoryEvent) -> EventDoc {
        let e = &se.event;
        let (written, reason) = match &e.outcome {
            Outcome::Written(v) => (Some(TypedValue::of(v)), None),
            Outcome::NotApplied(why) => (None, Some(why.clone())),
            _ => (None, None),
        };
        EventDoc {
            head: e.head.clone(),
            upstream_node: se.upstream_node.clone(),
            upstream_head: e.upstream_head.clone(),
            matched_output: e.matched.as_ref().map(|m| m.0.clone()),
            matched_name: e.matched.as_ref().map(|m| m.1.clone()),
            conditional: e.expression.clone(),
            action: e.action.clone(),
            reads: se
                .reads
                .iter()
                .map(|r| ReadDoc {
                    node: se.upstream_node.clone(),
                    param: r.param.clone(),
                    origin: r.origin,
                    value: r.value.as_ref().map(TypedValue::of),
                    connected: r.connected,
                    location: r.location.as_ref().map(LocationDoc::of),
                    story: r.story.as_deref().map(|s| Box::new(Story::of(s))),
                })
                .collect(),
            outcome: e.outcome.word(),
            written,
            reason,
        }
    }
}

/// Run `vstructc explain`.
pub fn run(args: &ExplainArgs, common: &CommonOptions) -> ExitCode {
    let usage = |msg: String| {
        eprintln_quiet!("error: {msg}");
        ExitCode::from(2)
    };
    let Some((handle, input)) = args
        .target
        .rsplit_once('.')
        .filter(|(h, i)| !h.is_empty() && !i.is_empty())
    else {
        return usage(format!("expected HANDLE.INPUT, got `{}`", args.target));
    };
    let ReadInput {
        mut options,
        registry,
        name,
        mut network,
    } = match read(&args.input, args.no_conditions, common) {
        Ok(p) => p,
        Err(status) => return status,
    };
    options.record_events = true;
    let Some(node) = network.find(handle) else {
        let handles: Vec<&str> = network.node_ids().map(|n| network[n].handle()).collect();
        let hint = did_you_mean(handle, handles.iter().copied());
        return usage(format!("no node `{handle}` in {name}{hint}"));
    };
    if let Some(def) = registry.definition(network[node].shader())
        && def.input(input).is_none()
        && network[node].param(input).is_none()
    {
        let hint = did_you_mean(input, def.inputs.iter().map(|p| p.name.as_str()));
        return usage(format!(
            "`{}` ({}) has no input `{input}`{hint}",
            handle, def.id
        ));
    }
    let res = resolve(&mut network, &registry, &options);
    let story = Story::of(&res.story(&network, &registry, node, input));
    if args.json {
        return json::print(&story, common);
    }
    let mut text = String::new();
    render_story(&mut text, &story, 0);
    match super::input::print_stdout(&text, common) {
        Ok(()) => ExitCode::SUCCESS,
        Err(failed) => failed,
    }
}

fn value_text(v: &Option<TypedValue>) -> String {
    match v {
        Some(t) => plain_text(&t.value),
        None => "(no value)".to_string(),
    }
}

/// A plain JSON value as the readable output prints values: numbers space-separated,
/// strings quoted.
fn plain_text(v: &serde_json::Value) -> String {
    use serde_json::Value as J;
    // Numbers as the library prints them: `1`, `0.2` (serde_json would print `1.0`).
    let number = |n: &serde_json::Number| match (n.as_i64(), n.as_f64()) {
        (Some(i), _) => i.to_string(),
        (None, Some(x)) => format!("{x}"),
        _ => n.to_string(),
    };
    match v {
        J::Number(n) => number(n),
        J::Array(items) if items.iter().all(J::is_number) => items
            .iter()
            .filter_map(|i| match i {
                J::Number(n) => Some(number(n)),
                _ => None,
            })
            .collect::<Vec<_>>()
            .join(" "),
        other => other.to_string(),
    }
}

fn links_text(links: &[LinkDoc]) -> String {
    links
        .iter()
        .map(|l| match &l.output {
            Some(o) => format!("{}.{o}", l.node),
            None => l.node.clone(),
        })
        .collect::<Vec<_>>()
        .join(", ")
}

fn at(location: &Option<LocationDoc>) -> String {
    match location {
        Some(l) if l.line > 0 => format!(" at {}:{}:{}", l.file, l.line, l.column),
        Some(l) => format!(" in {}", l.file),
        None => String::new(),
    }
}

/// The readable story, indented by `indent` spaces.
pub fn render_story(s: &mut String, story: &Story, indent: usize) {
    let pad = " ".repeat(indent);
    let who = format!("{}.{}", story.node, story.input);
    let summary = match story.origin {
        "authored" => format!(
            "{who} = {} (authored{})",
            value_text(&story.value),
            at(&story.location)
        ),
        "connected" => format!(
            "{who} <- {} (connection authored{})",
            links_text(&story.connections),
            at(&story.location)
        ),
        "resolved" => format!(
            "{who} <- {} (connected by resolution)",
            links_text(&story.connections)
        ),
        "written" => format!(
            "{who} = {} (written by resolution)",
            value_text(&story.value)
        ),
        "default" => format!(
            "{who} = {} (the default of {})",
            value_text(&story.value),
            story.shader
        ),
        _ => format!("{who} has no value (no default in {})", story.shader),
    };
    if story.told_above {
        let _ = writeln!(s, "{pad}{summary}: told above");
        return;
    }
    if story.truncated {
        let _ = writeln!(
            s,
            "{pad}{summary}: the story goes on upstream (more than {} steps)",
            vstructc::resolve::Story::MAX_DEPTH
        );
        return;
    }
    let _ = writeln!(s, "{pad}{summary}");
    if story.events.is_empty() && indent == 0 {
        let _ = writeln!(
            s,
            "  not expanded from any vstruct connection: it is not a member of a connected \
             input head of `{}`",
            story.shader
        );
    }
    for e in &story.events {
        render_event(s, story, e, indent);
    }
    if !story.upstream.is_empty() {
        let _ = writeln!(s, "{pad}  the upstream output carries:");
        for u in &story.upstream {
            render_story(s, u, indent + 4);
        }
    }
}

/// One decision about a member, as readable text.
fn render_event(s: &mut String, story: &Story, e: &EventDoc, indent: usize) {
    let pad = " ".repeat(indent);
    let _ = writeln!(
        s,
        "{pad}{}.{}: member of head `{}`, connected to {}.{}",
        story.node, story.input, e.head, e.upstream_node, e.upstream_head
    );
    match (&e.matched_output, &e.matched_name) {
        (Some(output), Some(by)) => {
            let _ = writeln!(
                s,
                "{pad}  matches upstream member output `{output}` (by name `{by}`)"
            );
        }
        _ if e.outcome == "direct-connection-wins" => {}
        _ => {
            let _ = writeln!(s, "{pad}  no upstream member has any of its names");
        }
    }
    if let Some(expr) = &e.conditional {
        let _ = writeln!(s, "{pad}  conditional: {expr}");
        for r in &e.reads {
            let value = match r.origin {
                "authored" => format!("authored {}{}", value_text(&r.value), at(&r.location)),
                "written" => format!("{}, written by resolution", value_text(&r.value)),
                "default" => format!("default {}", value_text(&r.value)),
                "none" => "declared, no value".to_string(),
                _ => "not an input of the upstream type".to_string(),
            };
            let conn = if r.connected { ", connected" } else { "" };
            let _ = writeln!(s, "{pad}    reads {}.{} = {value}{conn}", r.node, r.param);
            if let Some(story) = &r.story {
                render_story(s, story, indent + 6);
            }
        }
        if let Some(a) = &e.action {
            let _ = writeln!(s, "{pad}  chosen action: {a}");
        }
    }
    let outcome = match e.outcome {
        "connected" => format!(
            "connected to {}.{}",
            e.upstream_node,
            e.matched_output.as_deref().unwrap_or("?")
        ),
        "ignored" => "ignored: keeps its authored value or default".to_string(),
        "written" => format!("value {} written", value_text(&e.written)),
        "not-applied" => format!("unchanged: {}", e.reason.as_deref().unwrap_or("")),
        "direct-connection-wins" => {
            "unchanged: already connected, the direct connection wins".to_string()
        }
        "unparsable" => "never connected: its conditional does not parse".to_string(),
        _ => "untouched".to_string(),
    };
    let _ = writeln!(s, "{pad}  result: {outcome}");
}

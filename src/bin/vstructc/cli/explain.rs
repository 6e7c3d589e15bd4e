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
use std::collections::{HashMap, HashSet};
use std::fmt::Write as _;
use std::path::PathBuf;
use std::process::ExitCode;
use vstructc::diag::did_you_mean;
use vstructc::network::{Network, NodeId};
use vstructc::registry::Registry;
use vstructc::resolve::{MemberEvent, Outcome, ReadSource, resolve};

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

/// How deep a story follows values upstream before it stops.
const MAX_DEPTH: usize = 16;

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

/// Builds stories over one resolved network.
struct Teller<'a> {
    net: &'a Network,
    registry: &'a Registry,
    events: &'a [MemberEvent],
    /// The indexes of the events about each `(node, member)`, in order.
    by_member: HashMap<(NodeId, &'a str), Vec<usize>>,
    told: HashSet<(NodeId, String)>,
}

impl Teller<'_> {
    fn name(&self, n: NodeId) -> String {
        self.net[n].display_name()
    }

    /// Indexes of the events about `node.input` before `before`.
    fn events_of(&self, node: NodeId, input: &str, before: usize) -> Vec<usize> {
        self.by_member
            .get(&(node, input))
            .map(|v| v.iter().copied().take_while(|&i| i < before).collect())
            .unwrap_or_default()
    }

    /// The story of `node.input` as it stood after the events before `before`.
    fn story(&mut self, node: NodeId, input: &str, before: usize, depth: usize) -> Story {
        let n = &self.net[node];
        let param = n.param(input);
        let mine = self.events_of(node, input, before);
        let written = mine
            .iter()
            .rev()
            .find_map(|&i| match &self.events[i].outcome {
                Outcome::Written(v) => Some(v.clone()),
                _ => None,
            });
        let resolved = mine
            .iter()
            .any(|&i| self.events[i].outcome == Outcome::Connected);
        let connections: Vec<LinkDoc> = param
            .map(|p| p.connections())
            .unwrap_or_default()
            .iter()
            .map(|l| LinkDoc {
                node: l
                    .upstream_node()
                    .map(|u| self.name(u))
                    .or_else(|| l.missing_handle().map(str::to_string))
                    .unwrap_or_default(),
                output: l.output().map(str::to_string),
            })
            .collect();
        let default = || {
            self.registry
                .definition(n.shader())
                .and_then(|d| d.input(input).and_then(|p| p.default.clone()))
        };
        let location = param
            .and_then(|p| n.param_location(p))
            .map(|l| LocationDoc::of(&l));
        let (origin, value, location) = if resolved && !connections.is_empty() {
            ("resolved", None, None)
        } else if let Some(v) = written {
            ("written", Some(v), None)
        } else if !connections.is_empty() {
            ("connected", None, location)
        } else if let Some(v) = param.and_then(|p| p.value()) {
            ("authored", Some(v.clone()), location)
        } else if let Some(v) = default() {
            ("default", Some(v), None)
        } else {
            ("none", None, None)
        };
        let mut story = Story {
            node: self.name(node),
            shader: n.shader().to_string(),
            input: input.to_string(),
            origin,
            value: value.as_ref().map(TypedValue::of),
            connections,
            location,
            events: Vec::new(),
            upstream: Vec::new(),
            told_above: false,
            truncated: false,
        };
        if depth > MAX_DEPTH {
            story.truncated = true;
            return story;
        }
        if !self.told.insert((node, input.to_string())) {
            story.told_above = true;
            return story;
        }
        story.events = mine.iter().map(|&i| self.event(i, depth)).collect();
        if matches!(origin, "resolved" | "connected") {
            story.upstream = self.carried(node, input, before, depth);
        }
        story
    }

    /// The stories of the upstream inputs carried by the member outputs `node.input` is
    /// connected to: inputs of the same member name that have a value or connection.
    fn carried(&mut self, node: NodeId, input: &str, before: usize, depth: usize) -> Vec<Story> {
        let links: Vec<(NodeId, String)> = self
            .net
            .connections(node, input)
            .iter()
            .filter_map(|l| Some((l.upstream_node()?, l.output()?.to_string())))
            .collect();
        let mut out = Vec::new();
        for (up, output) in links {
            let shader = self.net[up].shader().to_string();
            let Some(tables) = self.registry.tables(&shader) else {
                continue;
            };
            let names: Vec<String> = tables
                .output_heads()
                .flat_map(|h| tables.members_out(h).iter())
                .filter(|m| *m.property == *output)
                .flat_map(|m| m.names.iter().cloned())
                .collect();
            let mut inputs: Vec<String> = Vec::new();
            for name in &names {
                if self
                    .registry
                    .definition(&shader)
                    .is_some_and(|d| d.input(name).is_some())
                {
                    inputs.push(name.clone());
                }
                for h in tables.input_heads() {
                    for m in tables.members_in(h) {
                        if m.names.iter().any(|n| n == name) {
                            inputs.push(m.property.to_string());
                        }
                    }
                }
            }
            let mut seen = HashSet::new();
            inputs.retain(|i| seen.insert(i.clone()));
            for i in inputs {
                let s = self.story(up, &i, before, depth + 1);
                if s.told_above || !s.events.is_empty() || !matches!(s.origin, "default" | "none") {
                    out.push(s);
                } else {
                    // A default the output merely carries is no part of the story.
                    self.told.remove(&(up, i));
                }
            }
        }
        out
    }

    fn event(&mut self, i: usize, depth: usize) -> EventDoc {
        let e = &self.events[i];
        let reads = e
            .reads
            .iter()
            .map(|r| {
                let (origin, value) = match &r.source {
                    ReadSource::Authored(v) => ("authored", Some(v.clone())),
                    ReadSource::Default(v) => ("default", Some(v.clone())),
                    ReadSource::NoValue => ("none", None),
                    ReadSource::Undeclared => ("undeclared", None),
                };
                // A value resolution wrote earlier reads as authored: tell its story.
                let wrote = origin == "authored"
                    && self
                        .events_of(e.upstream, &r.param, i)
                        .iter()
                        .any(|&j| matches!(self.events[j].outcome, Outcome::Written(_)));
                let (origin, location, story) = if wrote {
                    let s = self.story(e.upstream, &r.param, i, depth + 1);
                    ("written", None, Some(Box::new(s)))
                } else {
                    let location = (origin == "authored")
                        .then(|| {
                            let up = &self.net[e.upstream];
                            up.param_location(up.param(&r.param)?)
                        })
                        .flatten()
                        .map(|l| LocationDoc::of(&l));
                    (origin, location, None)
                };
                ReadDoc {
                    node: self.name(e.upstream),
                    param: r.param.clone(),
                    origin,
                    value: value.as_ref().map(TypedValue::of),
                    connected: r.connected,
                    location,
                    story,
                }
            })
            .collect();
        let (outcome, written, reason) = match &e.outcome {
            Outcome::Connected => ("connected", None, None),
            Outcome::Ignored => ("ignored", None, None),
            Outcome::Written(v) => ("written", Some(TypedValue::of(v)), None),
            Outcome::NotApplied(why) => ("not-applied", None, Some(why.clone())),
            Outcome::DirectConnectionWins => ("direct-connection-wins", None, None),
            Outcome::Unparsable => ("unparsable", None, None),
            Outcome::NoCounterpart => ("no-counterpart", None, None),
        };
        EventDoc {
            head: e.head.clone(),
            upstream_node: self.name(e.upstream),
            upstream_head: e.upstream_head.clone(),
            matched_output: e.matched.as_ref().map(|m| m.0.clone()),
            matched_name: e.matched.as_ref().map(|m| m.1.clone()),
            conditional: e.expression.clone(),
            action: e.action.clone(),
            reads,
            outcome,
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
    let mut by_member: HashMap<(NodeId, &str), Vec<usize>> = HashMap::new();
    for (i, e) in res.events.iter().enumerate() {
        by_member
            .entry((e.node, e.member.as_str()))
            .or_default()
            .push(i);
    }
    let mut teller = Teller {
        net: &network,
        registry: &registry,
        events: &res.events,
        by_member,
        told: HashSet::new(),
    };
    let story = teller.story(node, input, usize::MAX, 0);
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
            "{pad}{summary}: the story goes on upstream (more than {MAX_DEPTH} steps)"
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

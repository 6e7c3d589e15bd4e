//! The story of one input's value after resolution: where the value comes from (authored,
//! a default, written by a vstruct `set`/`copy`, or a connection resolution made) and, from
//! there, upstream to its origin. `vstructc explain` prints it; bridges get it from
//! [`Resolution::story`].
//!
//! Built from the member events a run records ([`ResolveOptions::record_events`]): a
//! conditional's read of a value resolution wrote tells that value's story in turn, and a
//! connection to an upstream member output tells the stories of the upstream inputs that
//! member carries (the inputs of the same member name). Each input's story is told once; a
//! later mention says it was told above.

#[cfg(doc)]
use super::ResolveOptions;
use super::{MemberEvent, Outcome, ReadSource, Resolution};
use crate::diag::Location;
use crate::network::{Network, NodeId};
use crate::registry::Registry;
use crate::types::Value;
use std::collections::{HashMap, HashSet};

/// The story of one input (see [`Resolution::story`]).
#[derive(Debug, Clone, PartialEq)]
pub struct Story {
    /// The node's handle.
    pub node: String,
    /// The node's shader id.
    pub shader: String,
    /// The input.
    pub input: String,
    /// Where the value comes from: `authored` (a value in the input), `connected` (a
    /// connection in the input), `default` (the definition's default), `written` (a value a
    /// vstruct `set` or `copy` wrote), `resolved` (a connection resolution made), `none`
    /// (declared without value or default).
    pub origin: &'static str,
    /// The value (none when connected or without value).
    pub value: Option<Value>,
    /// The connections: upstream node handle and output (none for a whole-node reference).
    pub connections: Vec<(String, Option<String>)>,
    /// Where an authored value or connection is written in the input.
    pub location: Option<Location>,
    /// The resolution decisions about this input, in order.
    pub events: Vec<StoryEvent>,
    /// For a connection to an upstream member output: the stories of the upstream inputs
    /// the output carries (inputs of the same member name that have a value or connection).
    pub upstream: Vec<Story>,
    /// The story was told earlier in the same story: `events` and `upstream` are empty.
    pub told_above: bool,
    /// The story is more than 16 steps upstream of the input explained and stops here:
    /// `events` and `upstream` are empty.
    pub truncated: bool,
}

/// One resolution decision about a member input, with the stories of the values its
/// conditional read.
#[derive(Debug, Clone, PartialEq)]
pub struct StoryEvent {
    /// The decision as resolution recorded it.
    pub event: MemberEvent,
    /// Handle of the upstream node (the event's `upstream`).
    pub upstream_node: String,
    /// Each parameter the conditional read on the upstream node, in the event's order.
    pub reads: Vec<StoryRead>,
}

/// One parameter a conditional read.
#[derive(Debug, Clone, PartialEq)]
pub struct StoryRead {
    /// The parameter.
    pub param: String,
    /// `authored`, `written` (by resolution, earlier in the run), `default`, `none`
    /// (declared, no value) or `undeclared` (not an input of the upstream type).
    pub origin: &'static str,
    /// The value read.
    pub value: Option<Value>,
    /// Whether the parameter was connected when read.
    pub connected: bool,
    /// Where an authored value is written in the input.
    pub location: Option<Location>,
    /// `written`: the story of the value read.
    pub story: Option<Box<Story>>,
}

impl Story {
    /// How many steps upstream of the input explained a story follows before it stops.
    pub const MAX_DEPTH: usize = 16;
}

impl Resolution {
    /// The story of `node.input` in `net` after this resolution of it. Without
    /// [`ResolveOptions::record_events`] the run recorded no decisions, and the story tells
    /// only the value's final origin.
    pub fn story(&self, net: &Network, registry: &Registry, node: NodeId, input: &str) -> Story {
        let mut by_member: HashMap<(NodeId, &str), Vec<usize>> = HashMap::new();
        for (i, e) in self.events.iter().enumerate() {
            by_member
                .entry((e.node, e.member.as_str()))
                .or_default()
                .push(i);
        }
        let mut teller = Teller {
            net,
            registry,
            events: &self.events,
            by_member,
            told: HashSet::new(),
        };
        teller.story(node, input, usize::MAX, 0)
    }
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
        let connections: Vec<(String, Option<String>)> = param
            .map(|p| p.connections())
            .unwrap_or_default()
            .iter()
            .map(|l| {
                let up = l
                    .upstream_node()
                    .map(|u| self.name(u))
                    .or_else(|| l.missing_handle().map(str::to_string))
                    .unwrap_or_default();
                (up, l.output().map(str::to_string))
            })
            .collect();
        let default = || {
            self.registry
                .definition(n.shader())
                .and_then(|d| d.input(input).and_then(|p| p.default.clone()))
        };
        let location = param.and_then(|p| n.param_location(p));
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
            value,
            connections,
            location,
            events: Vec::new(),
            upstream: Vec::new(),
            told_above: false,
            truncated: false,
        };
        if depth > Story::MAX_DEPTH {
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

    /// The upstream inputs that carry the member output `output` of `up`: inputs of the
    /// same member name, in the definition's order, each once.
    fn carrier_inputs(&self, up: NodeId, output: &str) -> Vec<String> {
        let shader = self.net[up].shader();
        let Some(tables) = self.registry.tables(shader) else {
            return Vec::new();
        };
        let names: Vec<&String> = tables
            .output_heads()
            .flat_map(|h| tables.members_out(h).iter())
            .filter(|m| *m.property == *output)
            .flat_map(|m| m.names.iter())
            .collect();
        let declared = |name: &str| {
            self.registry
                .definition(shader)
                .is_some_and(|d| d.input(name).is_some())
        };
        let mut inputs: Vec<String> = Vec::new();
        for name in names {
            if declared(name) {
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
        inputs
    }

    /// The stories of the upstream inputs carried by the member outputs `node.input` is
    /// connected to.
    fn carried(&mut self, node: NodeId, input: &str, before: usize, depth: usize) -> Vec<Story> {
        let links: Vec<(NodeId, String)> = self
            .net
            .connections(node, input)
            .iter()
            .filter_map(|l| Some((l.upstream_node()?, l.output()?.to_string())))
            .collect();
        let mut out = Vec::new();
        for (up, output) in links {
            for i in self.carrier_inputs(up, &output) {
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

    fn event(&mut self, i: usize, depth: usize) -> StoryEvent {
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
                        .flatten();
                    (origin, location, None)
                };
                StoryRead {
                    param: r.param.clone(),
                    origin,
                    value,
                    connected: r.connected,
                    location,
                    story,
                }
            })
            .collect();
        StoryEvent {
            event: e.clone(),
            upstream_node: self.name(e.upstream),
            reads,
        }
    }
}

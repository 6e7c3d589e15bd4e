//! `vstructc.explain`: the story of one input's value, as the `vstructc explain --json`
//! document (docs/json.md) with the same fields, built from the member events resolution
//! records ([`vstructc::resolve::MemberEvent`]).

use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};
use std::collections::{HashMap, HashSet};
use vstructc::Value;
use vstructc::diag::Location;
use vstructc::network::{Network, NodeId};
use vstructc::registry::Registry;
use vstructc::resolve::{MemberEvent, Outcome, ReadSource};

/// How deep a story follows values upstream before it stops (as the command does).
const MAX_DEPTH: usize = 16;

/// A value as the JSON documents write it: `{"type": word, "value": plain value}`.
pub(crate) fn typed_value<'py>(py: Python<'py>, v: &Value) -> PyResult<Bound<'py, PyDict>> {
    let ty = match v {
        Value::Array(b, items) => {
            let word = items.first().map_or_else(
                || b.word().to_string(),
                |i| i.base_type().word().to_string(),
            );
            format!("{word}[{}]", items.len())
        }
        other => other.base_type().word().to_string(),
    };
    let d = PyDict::new(py);
    d.set_item("type", ty)?;
    d.set_item("value", crate::value_to_py(py, v)?)?;
    Ok(d)
}

fn location<'py>(py: Python<'py>, l: &Location) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("file", &*l.file)?;
    d.set_item("line", l.line)?;
    d.set_item("column", l.column)?;
    Ok(d)
}

/// Builds stories over one resolved network (the command's teller, with dicts).
pub(crate) struct Teller<'a> {
    pub net: &'a Network,
    pub registry: &'a Registry,
    pub events: &'a [MemberEvent],
    by_member: HashMap<(NodeId, &'a str), Vec<usize>>,
    told: HashSet<(NodeId, String)>,
}

impl<'a> Teller<'a> {
    pub fn new(net: &'a Network, registry: &'a Registry, events: &'a [MemberEvent]) -> Self {
        let mut by_member: HashMap<(NodeId, &str), Vec<usize>> = HashMap::new();
        for (i, e) in events.iter().enumerate() {
            by_member
                .entry((e.node, e.member.as_str()))
                .or_default()
                .push(i);
        }
        Teller {
            net,
            registry,
            events,
            by_member,
            told: HashSet::new(),
        }
    }

    fn name(&self, n: NodeId) -> String {
        self.net[n].display_name()
    }

    fn events_of(&self, node: NodeId, input: &str, before: usize) -> Vec<usize> {
        self.by_member
            .get(&(node, input))
            .map(|v| v.iter().copied().take_while(|&i| i < before).collect())
            .unwrap_or_default()
    }

    /// The story of `node.input` as it stood after the events before `before`.
    pub fn story<'py>(
        &mut self,
        py: Python<'py>,
        node: NodeId,
        input: &str,
        before: usize,
        depth: usize,
    ) -> PyResult<(Bound<'py, PyDict>, bool, bool, &'static str)> {
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
        let links = param.map(|p| p.connections()).unwrap_or_default();
        let connections = PyList::empty(py);
        for l in links {
            let c = PyDict::new(py);
            let up = l
                .upstream_node()
                .map(|u| self.name(u))
                .or_else(|| l.missing_handle().map(str::to_string))
                .unwrap_or_default();
            c.set_item("node", up)?;
            c.set_item("output", l.output())?;
            connections.append(c)?;
        }
        let default = || {
            self.registry
                .definition(n.shader())
                .and_then(|d| d.input(input).and_then(|p| p.default.clone()))
        };
        let at = param.and_then(|p| n.param_location(p));
        let (origin, value, at) = if resolved && !links.is_empty() {
            ("resolved", None, None)
        } else if let Some(v) = written {
            ("written", Some(v), None)
        } else if !links.is_empty() {
            ("connected", None, at)
        } else if let Some(v) = param.and_then(|p| p.value()) {
            ("authored", Some(v.clone()), at)
        } else if let Some(v) = default() {
            ("default", Some(v), None)
        } else {
            ("none", None, None)
        };
        let d = PyDict::new(py);
        d.set_item("node", self.name(node))?;
        d.set_item("shader", n.shader())?;
        d.set_item("input", input)?;
        d.set_item("origin", origin)?;
        d.set_item(
            "value",
            value.as_ref().map(|v| typed_value(py, v)).transpose()?,
        )?;
        d.set_item("connections", connections)?;
        d.set_item(
            "location",
            at.as_ref().map(|l| location(py, l)).transpose()?,
        )?;
        let events = PyList::empty(py);
        let upstream = PyList::empty(py);
        let mut told_above = false;
        let mut truncated = false;
        if depth > MAX_DEPTH {
            truncated = true;
        } else if !self.told.insert((node, input.to_string())) {
            told_above = true;
        } else {
            for i in &mine {
                events.append(self.event(py, *i, depth)?)?;
            }
            if matches!(origin, "resolved" | "connected") {
                for s in self.carried(py, node, input, before, depth)? {
                    upstream.append(s)?;
                }
            }
        }
        let has_events = !events.is_empty();
        d.set_item("events", events)?;
        d.set_item("upstream", upstream)?;
        d.set_item("toldAbove", told_above)?;
        d.set_item("truncated", truncated)?;
        Ok((d, told_above, has_events, origin))
    }

    /// The stories of the upstream inputs carried by the member outputs `node.input` is
    /// connected to: inputs of the same member name that have a value or connection.
    fn carried<'py>(
        &mut self,
        py: Python<'py>,
        node: NodeId,
        input: &str,
        before: usize,
        depth: usize,
    ) -> PyResult<Vec<Bound<'py, PyDict>>> {
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
                let (s, told_above, has_events, origin) =
                    self.story(py, up, &i, before, depth + 1)?;
                if told_above || has_events || !matches!(origin, "default" | "none") {
                    out.push(s);
                } else {
                    // A default the output merely carries is no part of the story.
                    self.told.remove(&(up, i));
                }
            }
        }
        Ok(out)
    }

    fn event<'py>(
        &mut self,
        py: Python<'py>,
        i: usize,
        depth: usize,
    ) -> PyResult<Bound<'py, PyDict>> {
        let e = &self.events[i];
        let reads = PyList::empty(py);
        for r in &e.reads {
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
            let d = PyDict::new(py);
            d.set_item("node", self.name(e.upstream))?;
            d.set_item("param", &r.param)?;
            let (origin, at, story) = if wrote {
                let (s, ..) = self.story(py, e.upstream, &r.param, i, depth + 1)?;
                ("written", None, Some(s))
            } else {
                let at = (origin == "authored")
                    .then(|| {
                        let up = &self.net[e.upstream];
                        up.param_location(up.param(&r.param)?)
                    })
                    .flatten();
                (origin, at, None)
            };
            d.set_item("origin", origin)?;
            d.set_item(
                "value",
                value.as_ref().map(|v| typed_value(py, v)).transpose()?,
            )?;
            d.set_item("connected", r.connected)?;
            d.set_item(
                "location",
                at.as_ref().map(|l| location(py, l)).transpose()?,
            )?;
            d.set_item("story", story)?;
            reads.append(d)?;
        }
        let (outcome, written, reason) = match &e.outcome {
            Outcome::Connected => ("connected", None, None),
            Outcome::Ignored => ("ignored", None, None),
            Outcome::Written(v) => ("written", Some(v.clone()), None),
            Outcome::NotApplied(why) => ("not-applied", None, Some(why.clone())),
            Outcome::DirectConnectionWins => ("direct-connection-wins", None, None),
            Outcome::Unparsable => ("unparsable", None, None),
            Outcome::NoCounterpart => ("no-counterpart", None, None),
        };
        let d = PyDict::new(py);
        d.set_item("head", &e.head)?;
        d.set_item("upstreamNode", self.name(e.upstream))?;
        d.set_item("upstreamHead", &e.upstream_head)?;
        d.set_item("matchedOutput", e.matched.as_ref().map(|m| &m.0))?;
        d.set_item("matchedName", e.matched.as_ref().map(|m| &m.1))?;
        d.set_item("conditional", &e.expression)?;
        d.set_item("action", &e.action)?;
        d.set_item("reads", reads)?;
        d.set_item("outcome", outcome)?;
        d.set_item(
            "written",
            written.as_ref().map(|v| typed_value(py, v)).transpose()?,
        )?;
        d.set_item("reason", reason)?;
        Ok(d)
    }
}

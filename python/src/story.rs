//! `vstructc.explain`: the library's story of one input's value
//! ([`vstructc::resolve::Story`]) as the dicts of the `vstructc explain --json` document
//! (docs/json.md), with the same fields.

use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};
use vstructc::Value;
use vstructc::diag::Location;
use vstructc::resolve::{Outcome, Story, StoryEvent, StoryRead};

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

/// The dict of a story.
pub(crate) fn story_dict<'py>(py: Python<'py>, s: &Story) -> PyResult<Bound<'py, PyDict>> {
    let connections = PyList::empty(py);
    for (node, output) in &s.connections {
        let c = PyDict::new(py);
        c.set_item("node", node)?;
        c.set_item("output", output)?;
        connections.append(c)?;
    }
    let events = PyList::empty(py);
    for e in &s.events {
        events.append(event_dict(py, e)?)?;
    }
    let upstream = PyList::empty(py);
    for u in &s.upstream {
        upstream.append(story_dict(py, u)?)?;
    }
    let d = PyDict::new(py);
    d.set_item("node", &s.node)?;
    d.set_item("shader", &s.shader)?;
    d.set_item("input", &s.input)?;
    d.set_item("origin", s.origin)?;
    d.set_item("value", optional_value(py, s.value.as_ref())?)?;
    d.set_item("connections", connections)?;
    d.set_item("location", optional_location(py, s.location.as_ref())?)?;
    d.set_item("events", events)?;
    d.set_item("upstream", upstream)?;
    d.set_item("toldAbove", s.told_above)?;
    d.set_item("truncated", s.truncated)?;
    Ok(d)
}

fn event_dict<'py>(py: Python<'py>, se: &StoryEvent) -> PyResult<Bound<'py, PyDict>> {
    let e = &se.event;
    let reads = PyList::empty(py);
    for r in &se.reads {
        reads.append(read_dict(py, &se.upstream_node, r)?)?;
    }
    let (written, reason) = match &e.outcome {
        Outcome::Written(v) => (Some(v), None),
        Outcome::NotApplied(why) => (None, Some(why)),
        _ => (None, None),
    };
    let d = PyDict::new(py);
    d.set_item("head", &e.head)?;
    d.set_item("upstreamNode", &se.upstream_node)?;
    d.set_item("upstreamHead", &e.upstream_head)?;
    d.set_item("matchedOutput", e.matched.as_ref().map(|m| &m.0))?;
    d.set_item("matchedName", e.matched.as_ref().map(|m| &m.1))?;
    d.set_item("conditional", &e.expression)?;
    d.set_item("action", &e.action)?;
    d.set_item("reads", reads)?;
    d.set_item("outcome", e.outcome.word())?;
    d.set_item("written", optional_value(py, written)?)?;
    d.set_item("reason", reason)?;
    Ok(d)
}

fn read_dict<'py>(py: Python<'py>, node: &str, r: &StoryRead) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("node", node)?;
    d.set_item("param", &r.param)?;
    d.set_item("origin", r.origin)?;
    d.set_item("value", optional_value(py, r.value.as_ref())?)?;
    d.set_item("connected", r.connected)?;
    d.set_item("location", optional_location(py, r.location.as_ref())?)?;
    d.set_item(
        "story",
        r.story.as_deref().map(|s| story_dict(py, s)).transpose()?,
    )?;
    Ok(d)
}

fn optional_value<'py>(py: Python<'py>, v: Option<&Value>) -> PyResult<Option<Bound<'py, PyDict>>> {
    v.map(|v| typed_value(py, v)).transpose()
}

fn optional_location<'py>(
    py: Python<'py>,
    l: Option<&Location>,
) -> PyResult<Option<Bound<'py, PyDict>>> {
    l.map(|l| location(py, l)).transpose()
}

//! Graphviz dot for the closure tree of a [`MaterialIr`] (`vstructc compile --emit dot`).
//!
//! One `digraph` per material; node `n<i>` is closure node `#i`; edges point from a parent
//! to its children and are labelled with the factor they carry (`top`, `base · T`, `1 − m`,
//! `m`, `c`). Leaves are boxes with their kind, label and parameters.

use crate::ir::print::{node_text, operand};
use crate::ir::{MaterialIr, Node, NodeId};
use std::fmt::Write;

fn escape(s: &str) -> String {
    s.replace('\\', "\\\\").replace('"', "\\\"")
}

/// The closure tree of `ir` as a Graphviz digraph.
pub fn to_dot(ir: &MaterialIr) -> String {
    let mut s = String::new();
    let _ = writeln!(s, "digraph \"{}\" {{", escape(&ir.name));
    let _ = writeln!(s, "  rankdir=TB;");
    let _ = writeln!(s, "  node [fontname=\"Helvetica\", fontsize=10];");
    if ir.nodes.is_empty() {
        let _ = writeln!(s, "  empty [label=\"(no closure)\", shape=plaintext];");
    }
    for (i, node) in ir.nodes.iter().enumerate() {
        let text = node_text(ir, NodeId(i as u32));
        let shape = match node {
            Node::Leaf(_) => "box",
            Node::Emission { .. } | Node::Transparent { .. } => "note",
            _ => "ellipse",
        };
        let _ = writeln!(
            s,
            "  n{i} [shape={shape}, label=\"#{i} {}\"];",
            escape(&text)
        );
    }
    let op = |r| operand(&ir.program, r);
    for (i, node) in ir.nodes.iter().enumerate() {
        let edges: Vec<(NodeId, String)> = match node {
            Node::Layer { top, base, mode } => vec![
                (*top, "top".into()),
                (*base, format!("base · T[{}](#{})", mode.name(), top.0)),
            ],
            Node::Mix { a, b, m } => {
                let m = op(*m);
                vec![(*a, format!("1 − {m}")), (*b, m)]
            }
            Node::Add { a, b } => vec![(*a, String::new()), (*b, String::new())],
            Node::Multiply { f, c } => vec![(*f, op(*c))],
            _ => vec![],
        };
        for (c, label) in edges {
            let _ = writeln!(s, "  n{i} -> n{} [label=\"{}\"];", c.0, escape(&label));
        }
    }
    s.push_str("}\n");
    s
}

//! JSON network writer (spec formats.md §5.4).
//!
//! [`write_json`] writes every material of a network in the form [`crate::front::json`] reads:
//! object keys sorted byte-wise, arrays in model order (connections in connection order,
//! primvars as given), values in canonical `{ "type", "value" }` form, floats in the shortest
//! text that reads back to the same `f32` (plain or exponent form, whichever is shorter), two-space indentation, `\n` line ends and a final
//! newline. Arrays of scalars are written on one line (`[0.5, 1, 0]`).
//!
//! For a network read from RIB, materials are those of [`crate::front::rib::parse_rib`]: one
//! per `Bxdf` (named by `__materialid` or handle) with the transitive upstream closure as node
//! set, and separate materials for `Displace`, `Light` and `LightFilter` nodes. Nodes outside
//! every material are not written.
//!
//! Choices where the spec is silent:
//!
//! * Node names are handles; when two nodes of one material share a handle (RIB versions),
//!   those nodes are named by their keys (`Curvature#1`).
//! * A connection to a node outside the material, or a dangling one, names the handle.
//! * Two materials with the same name: the later ones get `#1`, `#2`, … suffixes.
//! * A parameter with both a value and connections is written in both `parameters` and
//!   `inputConnections` (formats.md §5.3).
//! * Non-finite floats (only possible in networks built in code) are written as `null`.

use crate::network::{Link, Network, NodeId, Upstream};
use crate::types::{Value, format_f32};
use std::collections::{BTreeMap, HashMap, HashSet};

/// An output tree: objects are sorted maps, numbers are pre-formatted text.
enum Out {
    Obj(BTreeMap<String, Out>),
    Arr(Vec<Out>),
    Str(String),
    Raw(String),
}

impl Out {
    fn obj() -> BTreeMap<String, Out> {
        BTreeMap::new()
    }

    fn is_container(&self) -> bool {
        matches!(self, Out::Obj(_) | Out::Arr(_))
    }

    fn write(&self, out: &mut String, indent: usize) {
        match self {
            Out::Raw(s) => out.push_str(s),
            Out::Str(s) => {
                out.push_str(&serde_json::to_string(s).unwrap_or_else(|_| "\"\"".into()))
            }
            Out::Arr(items) if items.is_empty() => out.push_str("[]"),
            Out::Arr(items) if !items.iter().any(Out::is_container) => {
                out.push('[');
                for (i, item) in items.iter().enumerate() {
                    if i > 0 {
                        out.push_str(", ");
                    }
                    item.write(out, indent);
                }
                out.push(']');
            }
            Out::Arr(items) => {
                out.push('[');
                for (i, item) in items.iter().enumerate() {
                    out.push_str(if i > 0 { ",\n" } else { "\n" });
                    push_indent(out, indent + 1);
                    item.write(out, indent + 1);
                }
                out.push('\n');
                push_indent(out, indent);
                out.push(']');
            }
            Out::Obj(map) if map.is_empty() => out.push_str("{}"),
            Out::Obj(map) => {
                out.push('{');
                for (i, (k, v)) in map.iter().enumerate() {
                    out.push_str(if i > 0 { ",\n" } else { "\n" });
                    push_indent(out, indent + 1);
                    out.push_str(&serde_json::to_string(k).unwrap_or_else(|_| "\"\"".into()));
                    out.push_str(": ");
                    v.write(out, indent + 1);
                }
                out.push('\n');
                push_indent(out, indent);
                out.push('}');
            }
        }
    }
}

fn push_indent(out: &mut String, level: usize) {
    for _ in 0..level {
        out.push_str("  ");
    }
}

/// Write the network's materials as a JSON network document.
///
/// ```
/// use vstructc::back::json::write_json;
/// use vstructc::network::{Network, RequestKind};
/// use vstructc::{BaseType, Value};
///
/// let mut net = Network::new();
/// let layer = net.add_node("PxrLayer1", "PxrLayer");
/// let surface = net.add_node_of_kind("S", "PxrLayerSurface", RequestKind::Bxdf);
/// net.set_param(layer, "diffuseColor", Value::Triple(BaseType::Color, [0.1, 0.5, 1.0]));
/// net.connect(surface, "inputMaterial", layer, "pxrMaterialOut");
/// let m = net.add_material("SG");
/// net.set_terminal(m, "surface", surface, None);
///
/// let json = write_json(&net);
/// assert!(json.starts_with("{\n  \"materials\": {\n    \"SG\": {\n"));
/// assert!(json.contains("\"value\": [0.1, 0.5, 1]"));
/// assert!(json.ends_with("\"vstructcNetwork\": 1\n}\n"));
/// ```
pub fn write_json(net: &Network) -> String {
    let mut materials = Out::obj();
    let mut taken: HashSet<String> = HashSet::new();
    // Where the search for a free `name#n` of each name resumes (names only become taken,
    // so N materials of one name cost N probes in all, not N² / 2).
    let mut suffixes: HashMap<&str, usize> = HashMap::new();
    for (k, m) in net.materials().iter().enumerate() {
        let mut name = m.name.clone();
        if taken.contains(&name) {
            let n = suffixes.entry(m.name.as_str()).or_insert(1);
            while taken.contains(&name) {
                name = format!("{}#{n}", m.name);
                *n += 1;
            }
        }
        taken.insert(name.clone());
        materials.insert(name, material(net, k));
    }
    let mut top = Out::obj();
    top.insert("vstructcNetwork".into(), Out::Raw("1".into()));
    top.insert("materials".into(), Out::Obj(materials));
    let mut out = String::new();
    Out::Obj(top).write(&mut out, 0);
    out.push('\n');
    out
}

fn material(net: &Network, index: usize) -> Out {
    let m = &net.materials()[index];
    let ids = net.material_nodes(index);
    let names = local_names(net, &ids);
    let mut nodes = Out::obj();
    for &id in &ids {
        let node = &net[id];
        let mut parameters = Out::obj();
        let mut inputs = Out::obj();
        for p in node.params() {
            if let Some(v) = p.value() {
                parameters.insert(p.name().to_string(), canonical(v));
            }
            if p.is_connected() {
                let list = p
                    .connections()
                    .iter()
                    .map(|l| connection(net, l, &names))
                    .collect();
                inputs.insert(p.name().to_string(), Out::Arr(list));
            }
        }
        let mut n = Out::obj();
        n.insert("nodeTypeId".into(), Out::Str(node.shader().to_string()));
        n.insert("parameters".into(), Out::Obj(parameters));
        n.insert("inputConnections".into(), Out::Obj(inputs));
        if let Some(name) = names.get(&id) {
            nodes.insert(name.clone(), Out::Obj(n));
        }
    }
    let mut terminals = Out::obj();
    for t in &m.terminals {
        terminals.insert(t.name.clone(), connection(net, &t.link, &names));
    }
    let mut out = Out::obj();
    out.insert("nodes".into(), Out::Obj(nodes));
    out.insert("terminals".into(), Out::Obj(terminals));
    out.insert(
        "primvars".into(),
        Out::Arr(m.primvars.iter().map(|p| Out::Str(p.clone())).collect()),
    );
    Out::Obj(out)
}

/// Names of the material's nodes: handles, or keys for handles used twice in the material.
fn local_names(net: &Network, ids: &[NodeId]) -> HashMap<NodeId, String> {
    let mut count: HashMap<&str, usize> = HashMap::new();
    for &id in ids {
        *count.entry(net[id].handle()).or_default() += 1;
    }
    ids.iter()
        .map(|&id| {
            let n = &net[id];
            let name = if count[n.handle()] > 1 {
                n.key().to_string()
            } else {
                n.handle().to_string()
            };
            (id, name)
        })
        .collect()
}

fn connection(net: &Network, link: &Link, names: &HashMap<NodeId, String>) -> Out {
    let node = match &link.upstream {
        Upstream::Node(id) => names.get(id).cloned().unwrap_or_else(|| {
            net.get(*id)
                .map_or_else(String::new, |n| n.handle().to_string())
        }),
        Upstream::Missing(h) => h.clone(),
    };
    let mut c = Out::obj();
    c.insert("upstreamNode".into(), Out::Str(node));
    c.insert(
        "upstreamOutputName".into(),
        Out::Str(link.output().unwrap_or("").to_string()),
    );
    Out::Obj(c)
}

/// `{ "type": T, "value": V }`.
fn canonical(v: &Value) -> Out {
    let ty = match v {
        Value::Array(b, items) => format!("{}[{}]", b.word(), items.len()),
        other => other.base_type().word().to_string(),
    };
    let mut o = Out::obj();
    o.insert("type".into(), Out::Str(ty));
    o.insert("value".into(), json_value(v));
    Out::Obj(o)
}

/// The shortest JSON text that reads back to `x`: the shorter of the plain decimal
/// (`0.0000001`) and the exponent form (`1e-7`), plain on ties; `-0.0` keeps its sign.
fn num(x: f32) -> Out {
    if !x.is_finite() {
        return Out::Raw("null".into());
    }
    if x == 0.0 && x.is_sign_negative() {
        return Out::Raw("-0.0".into());
    }
    let plain = format_f32(x);
    let exp = format!("{x:e}");
    Out::Raw(if exp.len() < plain.len() { exp } else { plain })
}

fn json_value(v: &Value) -> Out {
    match v {
        Value::Int(i) => Out::Raw(i.to_string()),
        Value::Float(x) => num(*x),
        Value::Str(s) | Value::Token(s) | Value::Asset(s) => Out::Str(s.clone()),
        Value::Bool(b) => Out::Raw(b.to_string()),
        Value::Triple(_, xs) => Out::Arr(xs.iter().map(|x| num(*x)).collect()),
        Value::HPoint(xs) => Out::Arr(xs.iter().map(|x| num(*x)).collect()),
        Value::Matrix(xs) => Out::Arr(xs.iter().map(|x| num(*x)).collect()),
        Value::Array(_, items) => Out::Arr(items.iter().map(json_value).collect()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::types::BaseType;

    fn text(o: Out) -> String {
        let mut s = String::new();
        o.write(&mut s, 0);
        s
    }

    #[test]
    fn canonical_values() {
        assert_eq!(
            text(canonical(&Value::Float(0.1))),
            "{\n  \"type\": \"float\",\n  \"value\": 0.1\n}"
        );
        assert_eq!(
            text(json_value(&Value::Array(
                BaseType::Color,
                vec![Value::Triple(BaseType::Color, [1.0, 0.0, 0.5])]
            ))),
            "[\n  [1, 0, 0.5]\n]"
        );
        assert_eq!(text(json_value(&Value::Float(f32::NAN))), "null");
        assert_eq!(text(json_value(&Value::Str("a\"b".into()))), "\"a\\\"b\"");
        let t = text(canonical(&Value::Array(BaseType::Int, vec![Value::Int(0)])));
        assert!(t.contains("\"int[1]\""));
    }
}

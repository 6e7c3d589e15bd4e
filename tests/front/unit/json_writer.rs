//! Unit tests of `back::json` (`src/back/json.rs`).

use std::collections::{BTreeMap, HashMap};
use vstructc::back::json::*;
use vstructc::network::{Link, Network, NodeId, Upstream};
use vstructc::types::{format_f32, saturate_f32};
use vstructc::{BaseType, Value};

/// An output tree: objects are sorted maps, numbers are pre-formatted text. The tree the
/// writer used to build before writing, kept as the reference the streaming writer is
/// compared with.
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

/// The tree writer [`write_json`] replaced, kept as the reference of its output.
fn write_json_tree(net: &Network) -> String {
    let mut materials = Out::obj();
    for (k, name) in material_names(net).into_iter().enumerate() {
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

fn connection(net: &Network, link: &Link, names: &HashMap<NodeId, String>) -> Out {
    let node = match link.upstream() {
        Upstream::Node(id) => names.get(&id).cloned().unwrap_or_else(|| {
            net.get(id)
                .map_or_else(String::new, |n| n.handle().to_string())
        }),
        Upstream::Missing(h) => h.to_string(),
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
        Value::Array(b, items) => format!("{}[{}]", element_type(b, items).word(), items.len()),
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
    let x = saturate_f32(x);
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

fn text(o: Out) -> String {
    let mut s = String::new();
    o.write(&mut s, 0);
    s
}

/// A network with every kind of value, shared handles, dangling and whole-node links,
/// materials sharing a name and an empty one.
fn assorted() -> Network {
    use vstructc::network::{Link, RequestKind};
    let mut net = Network::new();
    let a = net.add_node("a", "PxrFractal");
    let a1 = net.add_node("a", "PxrFractal");
    let s = net.add_node_of_kind("s\"q", "PxrSurface", RequestKind::Bxdf);
    let values = [
        Value::Int(-3),
        Value::Float(1e-7),
        Value::Float(-0.0),
        Value::Float(f32::NAN),
        Value::Float(123456789.0),
        Value::Str("t\u{1}\"é".into()),
        Value::Token("tok".into()),
        Value::Bool(true),
        Value::Triple(BaseType::Color, [0.5, 1.0, 0.1]),
        Value::Matrix([0.25; 16]),
        Value::Array(BaseType::Int, vec![]),
        Value::Array(BaseType::Float, vec![Value::Float(2.0), Value::Float(0.3)]),
        Value::Array(
            BaseType::Color,
            vec![
                Value::Triple(BaseType::Color, [1.0, 0.0, 0.5]),
                Value::Triple(BaseType::Color, [0.0; 3]),
            ],
        ),
    ];
    for (i, v) in values.into_iter().enumerate() {
        net.set_param(a, &format!("p{i}"), v);
    }
    net.connect(s, "diffuseGain", a, "resultF");
    net.connect(s, "diffuseGain", a1, "resultF");
    net.connect_node(s, "whole", a1);
    net.push_link(s, "ghost", Link::missing("nobody", Some("out")));
    net.set_param(s, "diffuseGain", Value::Float(0.5));
    for name in ["M", "M", "M#1", "Z"] {
        let m = net.add_material(name);
        net.set_terminal(m, "surface", s, None);
        net.set_terminal(m, "displacement", a, Some("resultF"));
    }
    net.materials_mut()[0].primvars = vec!["st".into(), "x\ny".into()];
    net.add_material("empty");
    net
}

#[test]
fn streaming_writes_what_the_tree_wrote() {
    use vstructc::front::rib::{RibOptions, parse_rib};
    use vstructc::registry::Registry;
    use vstructc::resolve::{ResolveOptions, resolve};
    let net = assorted();
    assert_eq!(write_json(&net).unwrap(), write_json_tree(&net));
    assert_eq!(
        write_json(&Network::new()).unwrap(),
        write_json_tree(&Network::new())
    );
    let reg = Registry::embedded();
    let rib = vstructc_testkit::testgen::layered_scene(3);
    let mut diags = vstructc::Diagnostics::new();
    let mut net = parse_rib(
        rib.as_bytes(),
        "s.rib",
        &reg,
        &RibOptions::default(),
        &mut diags,
    )
    .unwrap();
    assert_eq!(write_json(&net).unwrap(), write_json_tree(&net));
    resolve(&mut net, &reg, &ResolveOptions::default());
    assert_eq!(write_json(&net).unwrap(), write_json_tree(&net));
}

#[test]
fn exponent_form_is_rusts() {
    let check = |x: f32| {
        let x = saturate_f32(x);
        let mut exp = NumBuf::new();
        exponent_form(format!("{x}").as_bytes(), &mut exp);
        assert_eq!(exp.as_bytes(), format!("{x:e}").as_bytes(), "{x:?}");
    };
    for x in [
        0.0,
        1.0,
        -1.0,
        0.1,
        1e-7,
        123456789.0,
        100.0,
        1e-45,
        f32::MAX,
        -0.5,
    ] {
        check(x);
    }
    // A spread of bit patterns over every exponent.
    let mut bits = 0x9e37_79b9u32;
    for _ in 0..200_000 {
        bits ^= bits << 13;
        bits ^= bits >> 17;
        bits ^= bits << 5;
        check(f32::from_bits(bits));
    }
}

#[test]
fn unescaped_strings_are_serdes() {
    let mut cases: Vec<String> = ["", "plain", "é ü", "a\"b", "a\\b", "x\ny", "\u{7f}", "~ "]
        .iter()
        .map(|s| s.to_string())
        .collect();
    // Each escaped byte and its neighbours at every position of a long string (the
    // scan reads eight bytes at a time).
    for special in [
        '"', '\\', '\0', '\n', '\u{1f}', ' ', '!', '#', '[', ']', '\u{80}', 'ÿ',
    ] {
        for at in 0..20 {
            let mut s: String = "abcdefghijklmnopqrst".chars().take(at).collect();
            s.push(special);
            s.push_str(&"0123456789abcdefgh"[..(at % 9)]);
            cases.push(s);
        }
    }
    for s in &cases {
        let mut w = Stream { out: Vec::new() };
        w.string(s);
        assert_eq!(w.out, serde_json::to_vec(s).unwrap(), "{s:?}");
    }
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
    assert_eq!(text(json_value(&Value::Float(f32::NAN))), "0");
    assert_eq!(
        text(json_value(&Value::Float(f32::NEG_INFINITY))),
        "-3.4028235e38"
    );
    assert_eq!(text(json_value(&Value::Str("a\"b".into()))), "\"a\\\"b\"");
    let t = text(canonical(&Value::Array(BaseType::Int, vec![Value::Int(0)])));
    assert!(t.contains("\"int[1]\""));
}

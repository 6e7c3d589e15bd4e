//! USD writer: a network as one flattened `usda` layer of `Material` and `Shader` prims.
//!
//! Prim paths: a network read from USD keeps its prim paths (a node's handle and a
//! material's name are prim paths). Any other network (RIB, JSON, built in code) gets one
//! `/Materials/<material>` Material per material with its nodes beneath it, each named after
//! its handle (its key, `handle#k`, for a redefined RIB handle); a node in several materials
//! sits under the first, a node in none directly under `/Materials`. A name is made a USD
//! identifier by replacing every character other than ASCII letters, digits and `_` with
//! `_` and prefixing `_` to a leading digit; a name already taken gets `_2`, `_3`, ….
//! Prims between a Material and its shaders are written as `NodeGraph`s, other ancestors as
//! `Scope`s.
//!
//! Inputs: every parameter with a value (typed as the definition declares it, by Sdr's
//! mapping: `color` → `color3f`, `vstruct` → `token`, `float[2]` → `float2`, …; the value's
//! own type when the definition is unknown or the value does not fit) and every connection
//! (`.connect` to the upstream prim's `outputs:NAME`, which the upstream prim declares).
//! Terminals connect the Material's `outputs:ri:surface` (`ri:displacement`, `ri:volume`)
//! to the terminal node's `outputs:out`, or to the output the terminal names.

use crate::network::{Link, Network, NodeId, ParamTypes};
use crate::types::{ArraySpec, BaseType, Type, Value, format_f32, saturate_f32};
use rustc_hash::{FxHashMap, FxHashSet};
use std::fmt::Write as _;
use std::io::{self, Write};

/// `name` as a USD prim name.
fn identifier(name: &str) -> String {
    let mut out: String = name
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '_' {
                c
            } else {
                '_'
            }
        })
        .collect();
    if out.is_empty() || out.starts_with(|c: char| c.is_ascii_digit()) {
        out.insert(0, '_');
    }
    out
}

/// A prim of the layer being written.
#[derive(Default)]
struct Prim {
    name: String,
    children: Vec<usize>,
    by_name: FxHashMap<String, usize>,
    node: Option<NodeId>,
    material: Option<usize>,
}

/// The prim tree: index 0 is the pseudo-root.
struct Tree {
    prims: Vec<Prim>,
}

impl Tree {
    fn child(&mut self, parent: usize, name: &str) -> usize {
        if let Some(&i) = self.prims[parent].by_name.get(name) {
            return i;
        }
        let i = self.prims.len();
        self.prims.push(Prim {
            name: name.to_string(),
            ..Prim::default()
        });
        self.prims[parent].children.push(i);
        self.prims[parent].by_name.insert(name.to_string(), i);
        i
    }

    /// The prim at absolute path `path`, created with its ancestors.
    fn at(&mut self, path: &str) -> usize {
        let mut cur = 0;
        for part in path.split('/').filter(|p| !p.is_empty()) {
            cur = self.child(cur, part);
        }
        cur
    }
}

/// The prim path of every node and material.
struct Paths {
    nodes: FxHashMap<NodeId, String>,
    materials: Vec<String>,
}

/// A valid absolute prim path: `/`-separated identifiers.
fn is_prim_path(p: &str) -> bool {
    p.starts_with('/')
        && p[1..]
            .split('/')
            .all(|s| !s.is_empty() && identifier(s) == s)
}

/// A node's name: its handle, or its key (`handle#k`) for a later version of a RIB handle.
fn node_name(net: &Network, id: NodeId) -> String {
    let node = &net[id];
    if node.version() == 0 {
        node.handle().to_string()
    } else {
        node.key().to_string()
    }
}

fn paths(net: &Network) -> Paths {
    let ids = net.nodes_sorted();
    let from_usd = (!ids.is_empty() || !net.materials().is_empty())
        && ids
            .iter()
            .all(|&id| net[id].version() == 0 && is_prim_path(net[id].handle()))
        && net.materials().iter().all(|m| is_prim_path(&m.name));
    let mut nodes = FxHashMap::default();
    let mut materials = Vec::new();
    if from_usd {
        for &id in &ids {
            nodes.insert(id, net[id].handle().to_string());
        }
        materials = net.materials().iter().map(|m| m.name.clone()).collect();
        return Paths { nodes, materials };
    }
    let mut taken: FxHashSet<String> = FxHashSet::default();
    let mut unique = |base: String| -> String {
        let mut p = base.clone();
        let mut n = 2;
        while !taken.insert(p.clone()) {
            p = format!("{base}_{n}");
            n += 1;
        }
        p
    };
    for (i, m) in net.materials().iter().enumerate() {
        let mp = unique(format!("/Materials/{}", identifier(&m.name)));
        for id in net.material_nodes(i) {
            nodes
                .entry(id)
                .or_insert_with(|| unique(format!("{mp}/{}", identifier(&node_name(net, id)))));
        }
        materials.push(mp);
    }
    for &id in &ids {
        nodes
            .entry(id)
            .or_insert_with(|| unique(format!("/Materials/{}", identifier(&node_name(net, id)))));
    }
    Paths { nodes, materials }
}

/// The USD type name of a vstructc type (Sdr's mapping).
fn usd_type(t: &Type) -> String {
    let scalar = match &t.base {
        BaseType::Int => "int",
        BaseType::Float => match t.array {
            ArraySpec::Fixed(2) => return "float2".into(),
            ArraySpec::Fixed(3) => return "float3".into(),
            ArraySpec::Fixed(4) => return "float4".into(),
            _ => "float",
        },
        BaseType::String => "string",
        BaseType::Color => "color3f",
        BaseType::Point => "point3f",
        BaseType::Vector => "vector3f",
        BaseType::Normal => "normal3f",
        BaseType::Matrix => "matrix4d",
        BaseType::HPoint => "float4",
        BaseType::Asset => "asset",
        BaseType::Bool => "bool",
        _ => "token",
    };
    if t.is_array() {
        format!("{scalar}[]")
    } else {
        scalar.to_string()
    }
}

/// The type a value is written with: the declared one when the value fits it, else the
/// value's own.
fn value_type(v: &Value, declared: Option<&Type>) -> Type {
    let own = |v: &Value| -> Type {
        match v {
            Value::Array(b, items) => Type {
                base: b.clone(),
                array: ArraySpec::Fixed(items.len()),
            },
            other => Type::scalar(other.base_type()),
        }
    };
    let Some(d) = declared else {
        let mut t = own(v);
        if let (BaseType::Float, ArraySpec::Fixed(n)) = (&t.base, t.array)
            && !(2..=4).contains(&n)
        {
            t.array = ArraySpec::Dynamic;
        } else if t.is_array() && t.base != BaseType::Float {
            t.array = ArraySpec::Dynamic;
        }
        return t;
    };
    let fits = match (v, &d.base) {
        (Value::Array(b, items), base) => {
            d.is_array()
                && (b == base
                    || (*base == BaseType::Float && *b == BaseType::Int)
                    || (b.is_triple() && base.is_triple()))
                && match d.array {
                    ArraySpec::Fixed(n) => n == items.len() || !(2..=4).contains(&n),
                    _ => true,
                }
        }
        (_, _) if d.is_array() => false,
        (Value::Int(_), BaseType::Int | BaseType::Float | BaseType::Bool) => true,
        (Value::Float(_), BaseType::Float) => true,
        (Value::Bool(_), BaseType::Bool | BaseType::Int) => true,
        (Value::Str(_) | Value::Token(_) | Value::Asset(_), b) => {
            matches!(b, BaseType::String | BaseType::Token | BaseType::Asset)
        }
        (Value::Triple(..), b) => b.is_triple(),
        (Value::HPoint(_), BaseType::HPoint) => true,
        (Value::Matrix(_), BaseType::Matrix) => true,
        _ => false,
    };
    if fits { d.clone() } else { value_type(v, None) }
}

/// `(x, y, …)`: a USD tuple of floats.
fn float_tuple(out: &mut String, f: &[f32]) {
    out.push('(');
    for (i, x) in f.iter().enumerate() {
        if i > 0 {
            out.push_str(", ");
        }
        float(out, *x);
    }
    out.push(')');
}

/// `x` as its shortest text; a non-finite value (possible in a network built in code) is
/// written saturated ([`saturate_f32`]), as every writer writes it.
fn float(out: &mut String, x: f32) {
    out.push_str(&format_f32(saturate_f32(x)));
}

fn string(out: &mut String, s: &str) {
    out.push('"');
    for c in s.chars() {
        match c {
            '"' => out.push_str("\\\""),
            '\\' => out.push_str("\\\\"),
            '\n' => out.push_str("\\n"),
            '\r' => out.push_str("\\r"),
            '\t' => out.push_str("\\t"),
            c => out.push(c),
        }
    }
    out.push('"');
}

/// One scalar value as USD text of base type `base`.
fn scalar(out: &mut String, v: &Value, base: &BaseType) {
    match v {
        Value::Int(i) => match base {
            BaseType::Float => float(out, *i as f32),
            BaseType::Bool => out.push_str(if *i != 0 { "true" } else { "false" }),
            _ => {
                let _ = write!(out, "{i}");
            }
        },
        Value::Float(x) => float(out, *x),
        Value::Bool(b) => match base {
            BaseType::Int => out.push_str(if *b { "1" } else { "0" }),
            _ => out.push_str(if *b { "true" } else { "false" }),
        },
        Value::Str(s) | Value::Token(s) => string(out, s),
        Value::Asset(s) => {
            out.push('@');
            out.push_str(&s.replace('@', "\\@"));
            out.push('@');
        }
        Value::Triple(_, f) => float_tuple(out, f),
        Value::HPoint(f) => float_tuple(out, f),
        Value::Matrix(m) => {
            out.push('(');
            for r in 0..4 {
                if r > 0 {
                    out.push_str(", ");
                }
                out.push('(');
                for c in 0..4 {
                    if c > 0 {
                        out.push_str(", ");
                    }
                    float(out, m[r * 4 + c]);
                }
                out.push(')');
            }
            out.push(')');
        }
        Value::Array(..) => value(out, v, &Type::scalar(base.clone())),
    }
}

/// A value as USD text of type `t`.
fn value(out: &mut String, v: &Value, t: &Type) {
    match v {
        Value::Array(_, items) => {
            let tuple = t.base == BaseType::Float && matches!(t.array, ArraySpec::Fixed(2..=4));
            out.push(if tuple { '(' } else { '[' });
            for (i, item) in items.iter().enumerate() {
                if i > 0 {
                    out.push_str(", ");
                }
                scalar(out, item, &t.base);
            }
            out.push(if tuple { ')' } else { ']' });
        }
        other => scalar(out, other, &t.base),
    }
}

/// A connection target: `<prim.outputs:NAME>`; a dangling link keeps its handle as a path.
fn target(out: &mut String, link: &Link, paths: &Paths) -> Option<(NodeId, String)> {
    let output = link.output().unwrap_or("out").to_string();
    let (path, up) = match link.upstream_node() {
        Some(up) => (paths.nodes[&up].clone(), Some(up)),
        None => {
            let h = link.missing_handle().unwrap_or("missing");
            let p = if is_prim_path(h) {
                h.to_string()
            } else {
                format!("/Materials/{}", identifier(h))
            };
            (p, None)
        }
    };
    let _ = write!(out, "<{path}.outputs:{output}>");
    up.map(|u| (u, output))
}

/// Records that upstream node `up`'s output `o` is connected to, so its prim declares it.
fn declare_output(outputs: &mut FxHashMap<NodeId, Vec<String>>, up: NodeId, o: String) {
    let list = outputs.entry(up).or_default();
    if !list.contains(&o) {
        list.push(o);
    }
}

/// The lines of node `id`'s Shader prim: its `info:id`, its values and its connections
/// (the upstream outputs they use are recorded in `outputs`).
fn node_body(
    net: &Network,
    types: &dyn ParamTypes,
    paths: &Paths,
    id: NodeId,
    outputs: &mut FxHashMap<NodeId, Vec<String>>,
) -> String {
    let node = &net[id];
    let shader = node.shader();
    let mut body = String::new();
    body.push_str("uniform token info:id = ");
    string(&mut body, shader);
    body.push('\n');
    for p in node.params_by_name() {
        let declared = types.input_type(shader, p.name());
        if let Some(v) = p.value() {
            let t = value_type(v, declared.as_ref());
            let _ = write!(body, "{} inputs:{} = ", usd_type(&t), p.name());
            value(&mut body, v, &t);
            body.push('\n');
        }
        let links = p.connections();
        if links.is_empty() {
            continue;
        }
        let t = declared.unwrap_or_else(|| Type::scalar(BaseType::Token));
        let _ = write!(body, "{} inputs:{}.connect = ", usd_type(&t), p.name());
        if links.len() > 1 {
            body.push('[');
        }
        for (i, l) in links.iter().enumerate() {
            if i > 0 {
                body.push_str(", ");
            }
            if let Some((up, o)) = target(&mut body, l, paths) {
                declare_output(outputs, up, o);
            }
        }
        if links.len() > 1 {
            body.push(']');
        }
        body.push('\n');
    }
    body
}

/// [`write_usda`], then the layer in `openusd`'s binary encoding `format` (`usdc`, or `usdz`:
/// a zip package holding one `usdc` layer). For the crate's tests and benchmarks only
/// (`testkit`): Pixar's USD rejects the crate files `openusd` 0.6 writes ("invalid children in
/// primChildren"), so the command line does not offer binary output.
#[cfg(all(feature = "usd", feature = "testkit"))]
#[cfg_attr(feature = "testkit", visibility::make(pub))]
fn write_binary(
    net: &Network,
    types: &dyn ParamTypes,
    format: &str,
    out: &mut dyn Write,
) -> io::Result<()> {
    let mut text = Vec::new();
    write_usda(net, types, &mut text)?;
    let stage = crate::front::usd::open_stage("<written>.usda", &text)
        .map_err(|why| io::Error::other(format!("the written layer does not read back: {why}")))?;
    let encoder = openusd::sdf::LayerRegistry::find_by_id(format)
        .ok_or_else(|| io::Error::other(format!("no `{format}` encoder")))?;
    let mut bytes = io::Cursor::new(Vec::new());
    encoder
        .write(stage.root_layer().data(), &mut bytes)
        .map_err(|e| io::Error::other(format!("{e:#}")))?;
    out.write_all(bytes.get_ref())
}

/// Write the resolved network `net` as a `usda` layer (see the module documentation), with
/// the declared types of `types` (a [`crate::registry::Registry`]).
///
/// ```
/// use vstructc::back::usd::write_usda;
/// use vstructc::network::{Network, RequestKind};
/// use vstructc::registry::Registry;
/// use vstructc::{BaseType, Value};
///
/// let mut net = Network::new();
/// let s = net.add_node_of_kind("ball", "PxrSurface", RequestKind::Bxdf);
/// net.set_param(s, "diffuseColor", Value::Triple(BaseType::Color, [0.8, 0.2, 0.2]));
/// let m = net.add_material("red ball");
/// net.set_terminal(m, "surface", s, None);
/// let mut out = Vec::new();
/// write_usda(&net, &Registry::embedded(), &mut out).unwrap();
/// let text = String::from_utf8(out).unwrap();
/// assert!(text.contains("def Material \"red_ball\""), "{text}");
/// assert!(text.contains("color3f inputs:diffuseColor = (0.8, 0.2, 0.2)"), "{text}");
/// assert!(text.contains("outputs:ri:surface.connect = </Materials/red_ball/ball.outputs:out>"));
/// ```
pub fn write_usda(net: &Network, types: &dyn ParamTypes, out: &mut dyn Write) -> io::Result<()> {
    let paths = paths(net);
    let mut tree = Tree {
        prims: vec![Prim::default()],
    };
    for (i, p) in paths.materials.iter().enumerate() {
        let at = tree.at(p);
        tree.prims[at].material = Some(i);
    }
    for id in net.nodes_sorted() {
        let at = tree.at(&paths.nodes[&id]);
        tree.prims[at].node = Some(id);
    }
    // Node bodies first: they tell which outputs each upstream prim must declare.
    let mut outputs: FxHashMap<NodeId, Vec<String>> = FxHashMap::default();
    let bodies: FxHashMap<NodeId, String> = net
        .nodes_sorted()
        .into_iter()
        .map(|id| (id, node_body(net, types, &paths, id, &mut outputs)))
        .collect();
    let mut material_bodies = Vec::new();
    for m in net.materials() {
        let mut body = String::new();
        for t in &m.terminals {
            let _ = write!(body, "token outputs:ri:{}.connect = ", t.name);
            if let Some((up, o)) = target(&mut body, &t.link, &paths) {
                declare_output(&mut outputs, up, o);
            }
            body.push('\n');
        }
        material_bodies.push(body);
    }
    let mut text = String::with_capacity(1 << 16);
    text.push_str("#usda 1.0\n(\n    doc = \"Written by vstructc\"\n)\n");
    struct Frame {
        prim: usize,
        next: usize,
        in_material: bool,
        has_lines: bool,
    }
    let mut stack = vec![Frame {
        prim: 0,
        next: 0,
        in_material: false,
        has_lines: true,
    }];
    while !stack.is_empty() {
        let depth = stack.len() - 1;
        let top = &mut stack[depth];
        let top_prim = top.prim;
        if top.next == tree.prims[top_prim].children.len() {
            stack.pop();
            if depth > 0 {
                let indent = "    ".repeat(depth - 1);
                let _ = writeln!(text, "{indent}}}");
            }
            continue;
        }
        let c = tree.prims[top_prim].children[top.next];
        if top.next > 0 || top.has_lines {
            text.push('\n');
        }
        top.next += 1;
        let in_material = top.in_material;
        let indent = "    ".repeat(depth);
        let prim = &tree.prims[c];
        let kind = if prim.material.is_some() {
            "Material"
        } else if prim.node.is_some() {
            "Shader"
        } else if in_material {
            "NodeGraph"
        } else {
            "Scope"
        };
        let _ = writeln!(text, "{indent}def {kind} \"{}\"\n{indent}{{", prim.name);
        let inner = "    ".repeat(depth + 1);
        let mut lines = String::new();
        if let Some(m) = prim.material {
            lines.push_str(&material_bodies[m]);
        }
        if let Some(id) = prim.node {
            lines.push_str(&bodies[&id]);
            let shader = net[id].shader();
            for o in outputs.get(&id).map_or(&[][..], Vec::as_slice) {
                let t = types
                    .output_type(shader, o)
                    .unwrap_or_else(|| Type::scalar(BaseType::Token));
                let _ = writeln!(lines, "{} outputs:{o}", usd_type(&t));
            }
        }
        for l in lines.lines() {
            let _ = writeln!(text, "{inner}{l}");
        }
        stack.push(Frame {
            prim: c,
            next: 0,
            in_material: in_material || prim.material.is_some(),
            has_lines: !lines.is_empty(),
        });
    }
    out.write_all(text.as_bytes())
}

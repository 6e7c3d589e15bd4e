//! USD writer: a network as one flattened `usda` layer of `Material` and `Shader` prims, or,
//! for a network read from USD, as an override layer over its input holding only what
//! resolution changed ([`UsdMode`]).
//!
//! Prim paths: a network read from USD keeps its prim paths (a node's handle and a
//! material's name are prim paths). Any other network (RIB, JSON, built in code) gets one
//! `/Materials/<material>` Material per material with its nodes beneath it, each named after
//! its handle (its key, `handle#k`, for a redefined RIB handle); a node in several materials
//! sits under the first, a node in none directly under `/Materials`. A name is made a USD
//! identifier by replacing every character other than ASCII letters, digits and `_` with
//! `_` and prefixing `_` to a leading digit; a name already taken gets `_2`, `_3`, ….
//! Prims between a Material and its shaders are written as `NodeGraph`s, other ancestors as
//! `Scope`s, unless [`UsdMode::FlattenFrom`] gives the stage whose types they keep.
//!
//! Inputs: every parameter with a value (typed as the definition declares it, by Sdr's
//! mapping: `color` → `color3f`, `vstruct` → `token`, `float[2]` → `float2`, …; the value's
//! own type when the definition is unknown or the value does not fit) and every connection
//! (`.connect` to the upstream prim's `outputs:NAME`, which the upstream prim declares).
//! Terminals connect the Material's `outputs:ri:surface` (`ri:displacement`, `ri:volume`)
//! to the terminal node's `outputs:out`, or to the output the terminal names.

use crate::network::{Link, Network, NodeId, ParamChange, ParamTypes};
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
    /// The absolute prim path.
    path: String,
    children: Vec<usize>,
    by_name: FxHashMap<String, usize>,
    node: Option<NodeId>,
    material: Option<usize>,
    /// The prim's properties, one per line, unindented.
    lines: String,
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
        let path = format!("{}/{name}", self.prims[parent].path);
        self.prims.push(Prim {
            name: name.to_string(),
            path,
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
    /// The network was read from USD: its handles and material names are the prim paths.
    from_usd: bool,
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
        return Paths {
            nodes,
            materials,
            from_usd,
        };
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
    Paths {
        nodes,
        materials,
        from_usd,
    }
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

/// `s` as a usda string Pixar's USD reads back as `s`: quotes, backslashes and line ends
/// escaped, other control characters as `\xHH` (two digits, so a hex digit after one is
/// not taken into it).
fn string(out: &mut String, s: &str) {
    out.push('"');
    for c in s.chars() {
        match c {
            '"' => out.push_str("\\\""),
            '\\' => out.push_str("\\\\"),
            '\n' => out.push_str("\\n"),
            '\r' => out.push_str("\\r"),
            '\t' => out.push_str("\\t"),
            c if c.is_ascii_control() => {
                let _ = write!(out, "\\x{:02x}", c as u32);
            }
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
        Value::Asset(s) => asset(out, s),
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

/// `T inputs:NAME = VALUE`: value `v` of input `name`, typed as `declared` says when it fits.
fn value_line(body: &mut String, declared: Option<&Type>, name: &str, v: &Value) {
    let t = value_type(v, declared);
    let _ = write!(body, "{} inputs:{name} = ", usd_type(&t));
    value(body, v, &t);
    body.push('\n');
}

/// The type an input's connection (or its removal) is declared with: the declared one, else
/// `token`.
fn connect_type(declared: Option<&Type>) -> String {
    usd_type(declared.unwrap_or(&Type::scalar(BaseType::Token)))
}

/// `T inputs:NAME.connect = <…>` (a list for several links); the upstream outputs used are
/// recorded in `outputs`.
fn connect_line(
    body: &mut String,
    declared: Option<&Type>,
    name: &str,
    links: &[Link],
    paths: &Paths,
    outputs: &mut FxHashMap<NodeId, Vec<String>>,
) {
    let _ = write!(body, "{} inputs:{name}.connect = ", connect_type(declared));
    if links.len() > 1 {
        body.push('[');
    }
    for (i, l) in links.iter().enumerate() {
        if i > 0 {
            body.push_str(", ");
        }
        if let Some((up, o)) = target(body, l, paths) {
            declare_output(outputs, up, o);
        }
    }
    if links.len() > 1 {
        body.push(']');
    }
    body.push('\n');
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
    // The USD reader names a shader that has no `info:id` after what it has instead
    // (`(no info:id)`, `(sourceAsset)`): such a node gets no `info:id` back, not the name.
    let unknown = shader.starts_with('(') && shader.ends_with(')');
    if !unknown {
        body.push_str("uniform token info:id = ");
        string(&mut body, shader);
        body.push('\n');
    }
    for p in node.params_by_name() {
        let declared = types.input_type(shader, p.name());
        input_lines(&mut body, declared.as_ref(), p, paths, outputs);
    }
    body
}

/// Input `p` whole: its value line and its connection line, each when it has one.
fn input_lines(
    body: &mut String,
    declared: Option<&Type>,
    p: &crate::network::Param,
    paths: &Paths,
    outputs: &mut FxHashMap<NodeId, Vec<String>>,
) {
    if let Some(v) = p.value() {
        value_line(body, declared, p.name(), v);
    }
    if p.is_connected() {
        connect_line(body, declared, p.name(), p.connections(), paths, outputs);
    }
}

/// The lines of node `id`'s `over` in an override layer: only the inputs resolution changed
/// ([`ParamChange`]). A value set is written typed as in the flattened layer; a connection
/// set or changed as an explicit list; a value that replaced an authored value or connection
/// with an empty connection list (`.connect = None`) beside it, since [`ParamChange`] does
/// not tell which it replaced; a parameter read from the input and
/// removed (a vstruct head) as a blocked value (`= None`) and an empty connection list, which
/// compose to no value and no connection.
fn over_body(
    net: &Network,
    types: &dyn ParamTypes,
    paths: &Paths,
    id: NodeId,
    outputs: &mut FxHashMap<NodeId, Vec<String>>,
) -> String {
    let node = &net[id];
    let shader = node.shader();
    let mut params: Vec<&crate::network::Param> = node.all_params().iter().collect();
    params.sort_by(|a, b| a.name().cmp(b.name()));
    let mut body = String::new();
    for p in params {
        let name = p.name();
        let change = p.change();
        if change == ParamChange::Unchanged {
            continue;
        }
        let declared = types.input_type(shader, name);
        let declared = declared.as_ref();
        match change {
            ParamChange::Unchanged => {}
            ParamChange::Removed => {
                if p.source_item().is_some() {
                    let t = connect_type(declared);
                    let _ = writeln!(body, "{t} inputs:{name} = None");
                    let _ = writeln!(body, "{t} inputs:{name}.connect = None");
                }
            }
            ParamChange::ValueReplaced => {
                if let Some(v) = p.value() {
                    value_line(&mut body, declared, name, v);
                }
                let _ = writeln!(
                    body,
                    "{} inputs:{name}.connect = None",
                    connect_type(declared)
                );
            }
            ParamChange::Connected => {
                connect_line(&mut body, declared, name, p.connections(), paths, outputs);
            }
            ParamChange::Added => input_lines(&mut body, declared, p, paths, outputs),
        }
    }
    body
}

/// The usda layer `text` in the binary crate encoding (`usdc`), or as a `usdz` package
/// holding it as its one layer, `layer.usdc`, when `package`.
///
/// `openusd`'s crate writer tags the values of the `primChildren` and `properties` fields
/// (and `subLayers`) as token (string) arrays, where Pixar's USD stores, and requires, its
/// token (string) vector type: the same bytes under another type tag. Pixar's USD rejects
/// a file whose `primChildren` value is not a token vector ("Invalid children found in
/// primChildren field"), so the tags are rewritten ([`retag_children`]).
#[cfg(feature = "usd")]
fn binary(text: &[u8], package: bool) -> io::Result<Vec<u8>> {
    let fail = |what: &str, e: String| io::Error::other(format!("{what}: {e}"));
    let data = crate::front::usd::read_usda_layer(text)
        .map_err(|e| fail("the written layer does not read back", e))?;
    let mut crate_file = io::Cursor::new(Vec::new());
    std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        openusd::usdc::CrateWriter::write(data.as_ref(), &mut crate_file)
    }))
    .map_err(|_| fail("usdc encoding", "the USD library failed".into()))?
    .map_err(|e| fail("usdc encoding", format!("{e:#}")))?;
    let bytes = retag_children(crate_file.into_inner())?;
    if !package {
        return Ok(bytes);
    }
    let mut zip = openusd::usdz::ArchiveWriter::new(io::Cursor::new(Vec::new()));
    zip.add_layer("layer.usdc", &bytes)
        .map_err(|e| fail("usdz packaging", format!("{e:#}")))?;
    let archive = zip
        .finish()
        .map_err(|e| fail("usdz packaging", format!("{e:#}")))?;
    Ok(archive.into_inner())
}

/// Crate value type tags (the high byte of a value representation).
#[cfg(feature = "usd")]
mod crate_type {
    pub const STRING: u64 = 10;
    pub const TOKEN: u64 = 11;
    pub const TOKEN_VECTOR: u64 = 41;
    pub const STRING_VECTOR: u64 = 50;
}

/// Crate file `bytes` with the values of its `primChildren` and `properties` fields tagged
/// as token vectors, and those of `subLayers` as string vectors, where they are tagged as
/// token (string) arrays. Both forms store a 64-bit count and 32-bit token (string)
/// indices, so only the `FIELDS` section's value representations change: the section is
/// rewritten with them stored uncompressed (a literal-only LZ4 block), the sections after
/// it move, and the table of contents and the header follow.
#[cfg(feature = "usd")]
fn retag_children(bytes: Vec<u8>) -> io::Result<Vec<u8>> {
    use crate_type::{STRING, STRING_VECTOR, TOKEN, TOKEN_VECTOR};
    let bad = |why: &str| io::Error::other(format!("usdc encoding: {why}"));
    let u64_at = |at: usize| -> io::Result<u64> {
        bytes
            .get(at..at + 8)
            .map(|b| u64::from_le_bytes(b.try_into().unwrap_or([0; 8])))
            .ok_or_else(|| bad("truncated crate file"))
    };
    let file = openusd::usdc::CrateFile::open(io::Cursor::new(bytes.as_slice()))
        .map_err(|e| bad(&format!("{e:#}")))?;
    const TYPE_BITS: u64 = 0xff << 48;
    const ARRAY_BIT: u64 = 1 << 63;
    let mut reps: Vec<u64> = file.fields.iter().map(|f| f.value_rep.0).collect();
    for (rep, field) in reps.iter_mut().zip(&file.fields) {
        let name = file.tokens.get(field.token_index).map(String::as_str);
        let (ty, array) = ((*rep & TYPE_BITS) >> 48, *rep & ARRAY_BIT != 0);
        let to = match (name, ty) {
            (Some("primChildren" | "properties"), TOKEN) if array => TOKEN_VECTOR,
            (Some("subLayers"), STRING) if array => STRING_VECTOR,
            _ => continue,
        };
        *rep = (*rep & !(TYPE_BITS | ARRAY_BIT)) | (to << 48);
    }
    // The table of contents: (name bytes, start, size) per section.
    let toc = usize::try_from(u64_at(16)?).map_err(|_| bad("table of contents"))?;
    let count = u64_at(toc)? as usize;
    let mut sections = Vec::with_capacity(count);
    for i in 0..count.min(64) {
        let at = toc + 8 + i * 32;
        let name = bytes
            .get(at..at + 16)
            .ok_or_else(|| bad("table of contents"))?;
        sections.push((name.to_vec(), u64_at(at + 16)?, u64_at(at + 24)?));
    }
    let is = |n: &[u8], want: &str| n.split(|&b| b == 0).next() == Some(want.as_bytes());
    let (_, start, size) = sections
        .iter()
        .find(|(n, ..)| is(n, "FIELDS"))
        .cloned()
        .ok_or_else(|| bad("no FIELDS section"))?;
    let (start, end) = (start as usize, (start + size) as usize);
    // FIELDS: field count, compressed token indices, compressed value representations.
    let reps_size_at = start + 16 + u64_at(start + 8)? as usize;
    if reps_size_at + 8 + u64_at(reps_size_at)? as usize != end || end > toc {
        return Err(bad("unexpected FIELDS section layout"));
    }
    let raw: Vec<u8> = reps.iter().flat_map(|r| r.to_le_bytes()).collect();
    let block = lz4_literals(&raw);
    let mut out = Vec::with_capacity(bytes.len() + raw.len());
    out.extend_from_slice(&bytes[..reps_size_at]);
    out.extend_from_slice(&(block.len() as u64).to_le_bytes());
    out.extend_from_slice(&block);
    let new_end = out.len();
    out.extend_from_slice(&bytes[end..toc]);
    let shift = |at: u64| (at as i64 + new_end as i64 - end as i64) as u64;
    let new_toc = out.len() as u64;
    out.extend_from_slice(&(sections.len() as u64).to_le_bytes());
    for (name, s, len) in &sections {
        let (s, len) = if *s as usize == start {
            (*s, (new_end - start) as u64)
        } else if *s as usize >= end {
            (shift(*s), *len)
        } else {
            (*s, *len)
        };
        out.extend_from_slice(name);
        out.extend_from_slice(&s.to_le_bytes());
        out.extend_from_slice(&len.to_le_bytes());
    }
    out[16..24].copy_from_slice(&new_toc.to_le_bytes());
    Ok(out)
}

/// `data` as Pixar's compressed form of one chunk (a zero chunk count), holding one LZ4
/// block made of a single literal run: valid LZ4 that any decoder expands to `data`.
#[cfg(feature = "usd")]
fn lz4_literals(data: &[u8]) -> Vec<u8> {
    let mut out = Vec::with_capacity(data.len() + data.len() / 255 + 3);
    out.push(0);
    let n = data.len();
    if n < 15 {
        out.push((n as u8) << 4);
    } else {
        out.push(0xf0);
        let mut rest = n - 15;
        while rest >= 255 {
            out.push(255);
            rest -= 255;
        }
        out.push(rest as u8);
    }
    out.extend_from_slice(data);
    out
}

/// What [`write_usd`] writes.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub enum UsdMode<'a> {
    /// One flattened layer holding every material and shader (see the module
    /// documentation); prims between a Material and its shaders are `NodeGraph`s, other
    /// ancestors `Scope`s.
    #[default]
    Flatten,
    /// [`UsdMode::Flatten`] for a network read from USD, whose prims other than materials
    /// and shaders (node graphs, scopes, transforms, …) keep the types they have on the
    /// stage it was read from: the root layer `bytes`, named `name` as it was for the reader
    /// (its references and sublayers are found relative to it). A prim the stage does not
    /// hold, or a library built without the `usd` feature, gets the types of
    /// [`UsdMode::Flatten`].
    FlattenFrom {
        /// The root layer's name (a path).
        name: &'a str,
        /// The root layer's bytes.
        bytes: &'a [u8],
    },
    /// An override layer for a network read from USD: its layer metadata sublayers the
    /// input by the asset path `sublayer` (as written into the layer: relative to the
    /// written layer's folder, or absolute), and it holds `over` prims only for what
    /// resolution changed (see [`ParamChange`]): inputs set or connected, typed as in the
    /// flattened layer, the upstream outputs they connect to, and parameters resolution
    /// removed (vstruct heads) written as a blocked value and an empty connection list. A
    /// node the input does not hold (one added in code) is a `def Shader` with all its
    /// inputs. Nothing else is written: a network resolution did not change gives a layer
    /// without prims. Resolution does not change terminals, so none are written. A network
    /// whose handles are not prim paths (not read from USD) is an
    /// [`io::ErrorKind::InvalidInput`] error.
    Over {
        /// The input's asset path.
        sublayer: &'a str,
    },
}

/// Write the resolved network `net` as a USD layer as `mode` asks (see the module
/// documentation), with the declared types of `types` (a [`crate::registry::Registry`]), in
/// the encoding `encoding` names as USD's file extensions do: `"usda"` text, `"usdc"` the
/// binary crate form, or `"usdz"` a package holding the layer as its one file,
/// `layer.usdc`. The binary encodings need the `usd` feature ([`io::ErrorKind::Unsupported`]
/// without it); another name is an [`io::ErrorKind::InvalidInput`] error.
///
/// ```
/// use vstructc::back::usd::{UsdMode, write_usd};
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
/// write_usd(&net, &Registry::embedded(), UsdMode::Flatten, "usda", &mut out).unwrap();
/// let text = String::from_utf8(out).unwrap();
/// assert!(text.contains("def Material \"red_ball\""), "{text}");
/// assert!(text.contains("color3f inputs:diffuseColor = (0.8, 0.2, 0.2)"), "{text}");
/// assert!(text.contains("outputs:ri:surface.connect = </Materials/red_ball/ball.outputs:out>"));
/// ```
pub fn write_usd(
    net: &Network,
    types: &dyn ParamTypes,
    mode: UsdMode<'_>,
    encoding: &str,
    out: &mut dyn Write,
) -> io::Result<()> {
    let package = match encoding {
        "usda" => return write_usda(net, types, mode, out),
        "usdc" => false,
        "usdz" => true,
        other => {
            return Err(io::Error::new(
                io::ErrorKind::InvalidInput,
                format!("`{other}` is not a USD encoding (usda, usdc, usdz)"),
            ));
        }
    };
    if let Some((node, input)) = text_with_nul(net) {
        return Err(io::Error::new(
            io::ErrorKind::InvalidData,
            format!(
                "input `{input}` of node `{node}` holds a NUL character, which a crate file \
                 cannot store (its tokens and strings are NUL-separated): write usda instead"
            ),
        ));
    }
    #[cfg(feature = "usd")]
    {
        let mut text = Vec::new();
        write_usda(net, types, mode, &mut text)?;
        out.write_all(&binary(&text, package)?)
    }
    #[cfg(not(feature = "usd"))]
    {
        let _ = package;
        Err(io::Error::new(
            io::ErrorKind::Unsupported,
            format!("`{encoding}` output needs the `usd` feature"),
        ))
    }
}

/// The node handle and input name of the first text value of `net` that holds a NUL
/// character, which no crate file can store.
fn text_with_nul(net: &Network) -> Option<(String, String)> {
    fn has_nul(v: &Value) -> bool {
        match v {
            Value::Str(s) | Value::Token(s) | Value::Asset(s) => s.contains('\0'),
            Value::Array(_, items) => items.iter().any(has_nul),
            _ => false,
        }
    }
    net.node_ids().find_map(|id| {
        let node = &net[id];
        node.params()
            .find(|p| p.value().is_some_and(has_nul))
            .map(|p| (node.handle().to_string(), p.name().to_string()))
    })
}

/// [`write_usd`] as `usda` text.
fn write_usda(
    net: &Network,
    types: &dyn ParamTypes,
    mode: UsdMode<'_>,
    out: &mut dyn Write,
) -> io::Result<()> {
    let paths = paths(net);
    let mut tree = Tree {
        prims: vec![Prim::default()],
    };
    let mut outputs: FxHashMap<NodeId, Vec<String>> = FxHashMap::default();
    let mut text = String::with_capacity(1 << 16);
    text.push_str("#usda 1.0\n(\n");
    let kinds: Vec<String>;
    if let UsdMode::Over { sublayer } = mode {
        if !paths.from_usd {
            return Err(io::Error::new(
                io::ErrorKind::InvalidInput,
                "an override layer needs a network read from USD (its handles are the prim \
                 paths it overrides)",
            ));
        }
        text.push_str(
            "    doc = \"Written by vstructc: what resolution changed in the layer below\"\n",
        );
        text.push_str("    subLayers = [\n        ");
        asset(&mut text, sublayer);
        text.push_str("\n    ]\n)\n");
        // Nodes the input holds get their changes; nodes it does not hold, everything.
        let mut fresh = FxHashSet::default();
        for id in net.nodes_sorted() {
            let read = net[id].location().is_some();
            let body = if read {
                over_body(net, types, &paths, id, &mut outputs)
            } else {
                fresh.insert(id);
                node_body(net, types, &paths, id, &mut outputs)
            };
            if !body.is_empty() {
                let at = tree.at(&paths.nodes[&id]);
                tree.prims[at].node = Some(id);
                tree.prims[at].lines = body;
            }
        }
        for &id in outputs.keys() {
            let at = tree.at(&paths.nodes[&id]);
            tree.prims[at].node = Some(id);
        }
        declare_outputs(net, types, &mut tree, &outputs);
        kinds = tree
            .prims
            .iter()
            .map(|prim| match prim.node {
                Some(id) if fresh.contains(&id) => "def Shader".to_string(),
                _ => "over".to_string(),
            })
            .collect();
    } else {
        text.push_str("    doc = \"Written by vstructc\"\n)\n");
        for (i, p) in paths.materials.iter().enumerate() {
            let at = tree.at(p);
            tree.prims[at].material = Some(i);
        }
        for id in net.nodes_sorted() {
            let at = tree.at(&paths.nodes[&id]);
            tree.prims[at].node = Some(id);
            tree.prims[at].lines = node_body(net, types, &paths, id, &mut outputs);
        }
        for (i, m) in net.materials().iter().enumerate() {
            let at = tree.at(&paths.materials[i]);
            let mut body = String::new();
            for t in &m.terminals {
                let _ = write!(body, "token outputs:ri:{}.connect = ", t.name);
                if let Some((up, o)) = target(&mut body, &t.link, &paths) {
                    declare_output(&mut outputs, up, o);
                }
                body.push('\n');
            }
            body.push_str(&tree.prims[at].lines);
            tree.prims[at].lines = body;
        }
        declare_outputs(net, types, &mut tree, &outputs);
        let source_types = match mode {
            UsdMode::FlattenFrom { name, bytes } if paths.from_usd => {
                let others: Vec<String> = tree.prims[1..]
                    .iter()
                    .filter(|p| p.material.is_none() && p.node.is_none())
                    .map(|p| p.path.clone())
                    .collect();
                prim_types(name, bytes, &others)
            }
            _ => FxHashMap::default(),
        };
        kinds = flat_kinds(&tree, &source_types);
    }
    emit(&tree, &kinds, &mut text);
    out.write_all(text.as_bytes())
}

/// `@path@`: a USD asset path, read by Pixar's USD as it stands (no escapes, so a Windows
/// path keeps its backslashes). A path holding `@` goes between `@@@`, where `\@@@` is
/// the one escape.
fn asset(out: &mut String, path: &str) {
    if path.contains('@') {
        out.push_str("@@@");
        out.push_str(&path.replace("@@@", "\\@@@"));
        out.push_str("@@@");
    } else {
        out.push('@');
        out.push_str(path);
        out.push('@');
    }
}

/// Adds to each upstream prim in `outputs` the declarations of the outputs connected to.
fn declare_outputs(
    net: &Network,
    types: &dyn ParamTypes,
    tree: &mut Tree,
    outputs: &FxHashMap<NodeId, Vec<String>>,
) {
    for prim in &mut tree.prims {
        let Some(id) = prim.node else { continue };
        let shader = net[id].shader();
        for o in outputs.get(&id).map_or(&[][..], Vec::as_slice) {
            let t = types
                .output_type(shader, o)
                .unwrap_or_else(|| Type::scalar(BaseType::Token));
            let _ = writeln!(prim.lines, "{} outputs:{o}", usd_type(&t));
        }
    }
}

/// The types of the prims `paths` on the stage whose root layer is `bytes`, named `name`
/// (`""` for an untyped prim; a prim the stage does not hold is left out).
#[cfg(feature = "usd")]
fn prim_types(name: &str, bytes: &[u8], paths: &[String]) -> FxHashMap<String, String> {
    crate::front::usd::prim_types(name, bytes, paths)
}

#[cfg(not(feature = "usd"))]
fn prim_types(_: &str, _: &[u8], _: &[String]) -> FxHashMap<String, String> {
    FxHashMap::default()
}

/// Each prim's `def` line head in a flattened layer: `def Material`, `def Shader`, the type
/// the source stage gives (`def Xform`, or `def` for an untyped prim), else `def NodeGraph`
/// inside a Material and `def Scope` outside.
fn flat_kinds(tree: &Tree, source: &FxHashMap<String, String>) -> Vec<String> {
    let mut kinds = vec![String::new(); tree.prims.len()];
    let mut stack = vec![(0usize, false)];
    while let Some((i, in_material)) = stack.pop() {
        let prim = &tree.prims[i];
        let head = if prim.material.is_some() {
            "def Material".to_string()
        } else if prim.node.is_some() {
            "def Shader".to_string()
        } else if let Some(t) = source.get(&prim.path) {
            if t.is_empty() {
                "def".to_string()
            } else {
                format!("def {t}")
            }
        } else if in_material {
            "def NodeGraph".to_string()
        } else {
            "def Scope".to_string()
        };
        kinds[i] = head;
        let inner = in_material || prim.material.is_some();
        stack.extend(prim.children.iter().map(|&c| (c, inner)));
    }
    kinds
}

/// The prims of `tree` as usda text: each child of the pseudo-root with its `kinds` head,
/// its lines, and its children, depth first.
fn emit(tree: &Tree, kinds: &[String], text: &mut String) {
    struct Frame {
        prim: usize,
        next: usize,
        has_lines: bool,
    }
    let mut stack = vec![Frame {
        prim: 0,
        next: 0,
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
        let indent = "    ".repeat(depth);
        let prim = &tree.prims[c];
        let _ = writeln!(text, "{indent}{} \"{}\"\n{indent}{{", kinds[c], prim.name);
        let inner = "    ".repeat(depth + 1);
        for l in prim.lines.lines() {
            let _ = writeln!(text, "{inner}{l}");
        }
        stack.push(Frame {
            prim: c,
            next: 0,
            has_lines: !prim.lines.is_empty(),
        });
    }
}

//! JSON network writer.
//!
//! [`write_json`] writes every material of a network in the form [`crate::front::json`] reads:
//! object keys sorted byte-wise, arrays in model order (connections in connection order,
//! primvars as given), values in canonical `{ "type", "value" }` form, floats in the shortest
//! text that reads back to the same `f32` (plain or exponent form, whichever is shorter), two-space indentation, `\n` line ends and a final
//! newline. Arrays of scalars are written on one line (`[0.5, 1, 0]`).
//!
//! The document is written as the network is walked, each object's keys sorted as it is
//! written: no tree of the document is built (a resolved scene's JSON has millions of
//! members).
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
//!   `inputConnections`.
//! * An array whose elements are not of its declared type (a RIB value kept as written after
//!   RB014, such as `"color c" [0]`) is written with its elements' type (`float[1]`): the
//!   reader would reject `color[1]` holding a number.
//! * Non-finite floats (only possible in networks built in code) are written saturated to the
//!   largest finite `f32` of their sign, NaN as 0: the reader
//!   takes finite numbers only, and what this writer writes must read back.

use crate::network::{Link, Network, NodeId, Upstream};
use crate::types::{BaseType, Value, saturate_f32};
use std::collections::{HashMap, HashSet};
use std::io::{self, Write};

/// The JSON form holds materials only: a network with nodes but no material would be
/// written as `{"materials": {}}`, losing every node. The writers refuse it with this error.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error(
    "the network has {nodes} node(s) but no material, so its JSON form would hold none of \
     them; add a material with a terminal (`Network::add_material`, `Network::set_terminal`)"
)]
pub struct NoMaterials {
    /// The number of nodes the output would have lost.
    pub nodes: usize,
}

/// Write the network's materials as a JSON network document. Fails with [`NoMaterials`]
/// when the network has nodes but no material (an empty network is written as an empty
/// document).
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
/// let json = write_json(&net).unwrap();
/// assert!(json.starts_with("{\n  \"materials\": {\n    \"SG\": {\n"));
/// assert!(json.contains("\"value\": [0.1, 0.5, 1]"));
/// assert!(json.ends_with("\"vstructcNetwork\": 1\n}\n"));
///
/// let mut loose = Network::new();
/// loose.add_node("PxrLayer1", "PxrLayer");
/// assert_eq!(write_json(&loose).unwrap_err().nodes, 1);
/// ```
pub fn write_json(net: &Network) -> Result<String, NoMaterials> {
    check_materials(net)?;
    let mut out = Vec::new();
    // Writing into a Vec cannot fail.
    let _ = write_json_to(net, &mut out);
    // Every piece written is a `str` or serde_json's escaping of one.
    Ok(String::from_utf8(out).unwrap_or_default())
}

fn check_materials(net: &Network) -> Result<(), NoMaterials> {
    match net.node_count() {
        nodes if nodes > 0 && net.materials().is_empty() => Err(NoMaterials { nodes }),
        _ => Ok(()),
    }
}

/// [`write_json`] into `out`, material by material (the text of a large scene is never
/// held in memory whole); fails with the error of `out`, or with an
/// [`io::ErrorKind::InvalidInput`] error wrapping [`NoMaterials`] (nothing written) when
/// the network has nodes but no material.
///
/// ```
/// use vstructc::back::json::{write_json, write_json_to};
/// use vstructc::network::Network;
/// let mut net = Network::new();
/// let s = net.add_node("s", "PxrSurface");
/// let m = net.add_material("SG");
/// net.set_terminal(m, "surface", s, None);
/// let mut out = Vec::new();
/// write_json_to(&net, &mut out).unwrap();
/// assert_eq!(out, write_json(&net).unwrap().into_bytes());
/// ```
pub fn write_json_to(net: &Network, out: &mut dyn Write) -> io::Result<()> {
    write_json_chunked(net, out, PIECE_MATERIALS, true)
}

/// Materials per piece of the document formatted on one thread: tens of kilobytes of text
/// for the bench scene's materials, so that handing pieces to the pool costs little.
const PIECE_MATERIALS: usize = 64;

/// Pieces formatted ahead of the writing, per thread of the pool: enough to keep every
/// thread busy while the calling thread writes, few enough that the text waiting in memory
/// stays a few megabytes.
#[cfg(feature = "parallel")]
const WINDOW_PER_THREAD: usize = 4;

/// [`write_json_to`] with its materials formatted in pieces of `chunk_materials` (at least
/// one). With `parallel` (and the `parallel` feature, more than one thread in rayon's pool,
/// and a caller outside the pool) a window of pieces is formatted on the pool's threads
/// while the calling thread writes the window before it; otherwise each piece is written as
/// it is formatted. Every way gives the same bytes: a piece's text depends only on the
/// network and on whether it holds the first material.
#[cfg_attr(feature = "testkit", visibility::make(pub))]
fn write_json_chunked(
    net: &Network,
    out: &mut dyn Write,
    chunk_materials: usize,
    parallel: bool,
) -> io::Result<()> {
    check_materials(net).map_err(|e| io::Error::new(io::ErrorKind::InvalidInput, e))?;
    let mut named: Vec<(String, usize)> = material_names(net).into_iter().zip(0..).collect();
    named.sort_unstable();
    let pieces: Vec<&[(String, usize)]> = named.chunks(chunk_materials.max(1)).collect();
    out.write_all(b"{\n  \"materials\": ")?;
    write_pieces(net, &pieces, out, parallel)?;
    let mut tail = Stream { out: Vec::new() };
    tail.end(named.is_empty(), 1, b'}');
    tail.out
        .extend_from_slice(b",\n  \"vstructcNetwork\": 1\n}\n");
    out.write_all(&tail.out)
}

/// The text of one piece of the materials object: its materials, each after the `{` that
/// opens the object (the first material of the document) or the `,` that separates it from
/// the one before. Formatted into `out`, emptied first (its room is reused).
fn format_piece(net: &Network, piece: &[(String, usize)], starts: bool, out: Vec<u8>) -> Vec<u8> {
    let mut w = Stream { out };
    w.out.clear();
    let mut first = starts;
    for (name, k) in piece {
        w.entry(&mut first, 1, name);
        w.material(net, *k, 2);
    }
    w.out
}

/// Writes the pieces in order: formatted on the calling thread, or on rayon's pool a window
/// ahead of the writing (see [`write_json_chunked`]).
fn write_pieces(
    net: &Network,
    pieces: &[&[(String, usize)]],
    out: &mut dyn Write,
    parallel: bool,
) -> io::Result<()> {
    #[cfg(feature = "parallel")]
    if parallel && pieces.len() > 1 && crate::schedule::pool_can_help() {
        return write_pieces_parallel(net, pieces, out);
    }
    let _ = parallel;
    let mut buffer = Vec::with_capacity(1 << 16);
    for (i, piece) in pieces.iter().enumerate() {
        buffer = format_piece(net, piece, i == 0, std::mem::take(&mut buffer));
        out.write_all(&buffer)?;
    }
    Ok(())
}

/// One window of pieces at a time is formatted on the pool (its pieces in parallel) while
/// the calling thread writes the window formatted before it.
#[cfg(feature = "parallel")]
fn write_pieces_parallel(
    net: &Network,
    pieces: &[&[(String, usize)]],
    out: &mut dyn Write,
) -> io::Result<()> {
    use rayon::prelude::*;
    let window = WINDOW_PER_THREAD * rayon::current_num_threads();
    let format = |start: usize, mut buffers: Vec<Vec<u8>>| -> Vec<Vec<u8>> {
        let end = (start + window).min(pieces.len());
        buffers.resize_with(end - start, Vec::new);
        (start..end)
            .into_par_iter()
            .zip(buffers)
            .map(|(i, buffer)| format_piece(net, pieces[i], i == 0, buffer))
            .collect()
    };
    let mut ready = format(0, Vec::new());
    let mut start = ready.len();
    // The buffers of the window written last, formatted into again: fresh memory costs a
    // page fault per page.
    let mut spare = Vec::new();
    while !ready.is_empty() {
        let mut next = Vec::new();
        let mut written = Ok(());
        rayon::in_place_scope(|scope| {
            if start < pieces.len() {
                let (next, spare) = (&mut next, std::mem::take(&mut spare));
                scope.spawn(move |_| *next = format(start, spare));
            }
            written = ready.iter().try_for_each(|text| out.write_all(text));
        });
        written?;
        start += next.len();
        spare = std::mem::replace(&mut ready, next);
    }
    Ok(())
}

/// The JSON name of each material, in material order: its name, with `#1`, `#2`, … added
/// to the later ones of a name already taken.
#[cfg_attr(feature = "testkit", visibility::make(pub))]
fn material_names(net: &Network) -> Vec<String> {
    let mut taken: HashSet<String> = HashSet::new();
    // Where the search for a free `name#n` of each name resumes (names only become taken,
    // so N materials of one name cost N probes in all, not N² / 2).
    let mut suffixes: HashMap<&str, usize> = HashMap::new();
    let mut names = Vec::with_capacity(net.materials().len());
    for m in net.materials() {
        let mut name = m.name.clone();
        if taken.contains(&name) {
            let n = suffixes.entry(m.name.as_str()).or_insert(1);
            while taken.contains(&name) {
                name = format!("{}#{n}", m.name);
                *n += 1;
            }
        }
        taken.insert(name.clone());
        names.push(name);
    }
    names
}

/// The streaming writer: appends to one buffer in the layout the module documents, keys
/// sorted as they are written (no tree of the document is built).
#[cfg_attr(feature = "testkit", visibility::make(pub))]
struct Stream {
    /// The document written so far.
    pub out: Vec<u8>,
}

impl Stream {
    fn indent(&mut self, level: usize) {
        for _ in 0..level {
            self.out.extend_from_slice(b"  ");
        }
    }

    /// A JSON string, escaped as serde_json escapes it.
    #[cfg_attr(feature = "testkit", visibility::make(pub))]
    fn string(&mut self, s: &str) {
        // serde_json escapes quotes, backslashes and control characters only; a string without them
        // (nearly every name and value) is copied as it is.
        if !needs_escape(s.as_bytes()) {
            self.out.reserve(s.len() + 2);
            self.out.push(b'"');
            self.out.extend_from_slice(s.as_bytes());
            self.out.push(b'"');
            return;
        }
        let mut ser = serde_json::Serializer::new(&mut self.out);
        // Writing into a Vec cannot fail.
        let _ = serde::Serialize::serialize(s, &mut ser);
    }

    /// Starts an element of a multi-line object or array at `level` (`{`/`[` first).
    fn item(&mut self, first: &mut bool, level: usize, open: u8) {
        if *first {
            self.out.push(open);
            self.out.push(b'\n');
        } else {
            self.out.extend_from_slice(b",\n");
        }
        *first = false;
        self.indent(level + 1);
    }

    /// Starts the member `key` of a multi-line object at `level`.
    fn entry(&mut self, first: &mut bool, level: usize, key: &str) {
        self.item(first, level, b'{');
        self.string(key);
        self.out.extend_from_slice(b": ");
    }

    /// Ends a multi-line object or array at `level` (`{}` / `[]` if it had no element).
    fn end(&mut self, first: bool, level: usize, close: u8) {
        if first {
            self.out.push(if close == b'}' { b'{' } else { b'[' });
        } else {
            self.out.push(b'\n');
            self.indent(level);
        }
        self.out.push(close);
    }

    fn material(&mut self, net: &Network, index: usize, level: usize) {
        let m = &net.materials()[index];
        let ids = net.material_nodes(index);
        let names = local_names(net, &ids);
        // Sorted by name; of nodes that share a name the last one is written.
        let mut nodes: Vec<(&str, usize, NodeId)> = ids
            .iter()
            .enumerate()
            .filter_map(|(k, id)| Some((names.get(id)?.as_str(), k, *id)))
            .collect();
        nodes.sort_unstable();
        let mut first = true;
        self.entry(&mut first, level, "nodes");
        let mut first_node = true;
        for (i, &(name, _, id)) in nodes.iter().enumerate() {
            if nodes.get(i + 1).is_some_and(|next| next.0 == name) {
                continue;
            }
            self.entry(&mut first_node, level + 1, name);
            self.node(net, id, &names, level + 2);
        }
        self.end(first_node, level + 1, b'}');
        self.entry(&mut first, level, "primvars");
        if m.primvars.is_empty() {
            self.out.extend_from_slice(b"[]");
        } else {
            self.out.push(b'[');
            for (i, p) in m.primvars.iter().enumerate() {
                if i > 0 {
                    self.out.extend_from_slice(b", ");
                }
                self.string(p);
            }
            self.out.push(b']');
        }
        self.entry(&mut first, level, "terminals");
        let mut terminals: Vec<(&str, usize)> = m
            .terminals
            .iter()
            .enumerate()
            .map(|(k, t)| (t.name.as_str(), k))
            .collect();
        terminals.sort_unstable();
        let mut first_terminal = true;
        for (i, &(name, k)) in terminals.iter().enumerate() {
            if terminals.get(i + 1).is_some_and(|next| next.0 == name) {
                continue;
            }
            self.entry(&mut first_terminal, level + 1, name);
            self.connection(net, &m.terminals[k].link, &names, level + 2);
        }
        self.end(first_terminal, level + 1, b'}');
        self.end(first, level, b'}');
    }

    fn node(&mut self, net: &Network, id: NodeId, names: &HashMap<NodeId, String>, level: usize) {
        let node = &net[id];
        let mut first = true;
        self.entry(&mut first, level, "inputConnections");
        let mut params: Vec<&crate::network::Param> = node.params_by_name().collect();
        let mut first_input = true;
        for p in params.iter().filter(|p| p.is_connected()) {
            self.entry(&mut first_input, level + 1, p.name());
            let mut first_link = true;
            for l in p.connections() {
                self.item(&mut first_link, level + 2, b'[');
                self.connection(net, l, names, level + 3);
            }
            self.end(first_link, level + 2, b']');
        }
        self.end(first_input, level + 1, b'}');
        self.entry(&mut first, level, "nodeTypeId");
        self.string(node.shader());
        self.entry(&mut first, level, "parameters");
        params.retain(|p| p.value().is_some());
        let mut first_param = true;
        for p in params {
            if let Some(v) = p.value() {
                self.entry(&mut first_param, level + 1, p.name());
                self.canonical(v, level + 2);
            }
        }
        self.end(first_param, level + 1, b'}');
        self.end(first, level, b'}');
    }

    fn connection(
        &mut self,
        net: &Network,
        link: &Link,
        names: &HashMap<NodeId, String>,
        level: usize,
    ) {
        let node = match link.upstream() {
            Upstream::Node(id) => names
                .get(&id)
                .map(String::as_str)
                .or_else(|| net.get(id).map(|n| n.handle()))
                .unwrap_or(""),
            Upstream::Missing(h) => h,
        };
        let mut first = true;
        self.entry(&mut first, level, "upstreamNode");
        self.string(node);
        self.entry(&mut first, level, "upstreamOutputName");
        self.string(link.output().unwrap_or(""));
        self.end(first, level, b'}');
    }

    fn canonical(&mut self, v: &Value, level: usize) {
        let mut first = true;
        self.entry(&mut first, level, "type");
        match v {
            Value::Array(b, items) => {
                // Type words need no escaping.
                self.out.push(b'"');
                self.out
                    .extend_from_slice(element_type(b, items).word().as_bytes());
                // Writing into a Vec cannot fail.
                let _ = write!(self.out, "[{}]\"", items.len());
            }
            other => self.string(other.base_type().word()),
        }
        self.entry(&mut first, level, "value");
        self.value(v, level + 1);
        self.end(first, level, b'}');
    }

    /// The shortest JSON text that reads back to `x` (see [`saturate_f32`] for non-finite
    /// values).
    fn num(&mut self, x: f32) {
        let x = saturate_f32(x);
        if x == 0.0 && x.is_sign_negative() {
            self.out.extend_from_slice(b"-0.0");
        } else {
            let mut plain = NumBuf::new();
            // Writing into a NumBuf cannot fail: an f32's plain form has at most 48 bytes.
            let _ = write!(plain, "{x}");
            let plain = plain.as_bytes();
            let mut exp = NumBuf::new();
            exponent_form(plain, &mut exp);
            let exp = exp.as_bytes();
            self.out
                .extend_from_slice(if exp.len() < plain.len() { exp } else { plain });
        }
    }

    fn nums(&mut self, xs: &[f32]) {
        self.out.push(b'[');
        for (i, x) in xs.iter().enumerate() {
            if i > 0 {
                self.out.extend_from_slice(b", ");
            }
            self.num(*x);
        }
        self.out.push(b']');
    }

    fn value(&mut self, v: &Value, level: usize) {
        match v {
            // Writing into a Vec cannot fail.
            Value::Int(i) => {
                let _ = write!(self.out, "{i}");
            }
            Value::Float(x) => self.num(*x),
            Value::Str(s) | Value::Token(s) | Value::Asset(s) => self.string(s),
            Value::Bool(b) => self
                .out
                .extend_from_slice(if *b { b"true" } else { b"false" }),
            Value::Triple(_, xs) => self.nums(xs),
            Value::HPoint(xs) => self.nums(xs),
            Value::Matrix(xs) => self.nums(xs),
            Value::Array(_, items) if items.is_empty() => self.out.extend_from_slice(b"[]"),
            Value::Array(_, items) if !items.iter().any(is_container) => {
                self.out.push(b'[');
                for (i, item) in items.iter().enumerate() {
                    if i > 0 {
                        self.out.extend_from_slice(b", ");
                    }
                    self.value(item, level);
                }
                self.out.push(b']');
            }
            Value::Array(_, items) => {
                let mut first = true;
                for item in items {
                    self.item(&mut first, level, b'[');
                    self.value(item, level + 1);
                }
                self.end(first, level, b']');
            }
        }
    }
}

/// True when `bytes` holds a quote, a backslash or a control character (below 0x20), the
/// bytes serde_json escapes; eight bytes at a time.
fn needs_escape(bytes: &[u8]) -> bool {
    const ONES: u64 = u64::from_ne_bytes([0x01; 8]);
    const HIGH: u64 = u64::from_ne_bytes([0x80; 8]);
    // A byte of `v` below `n` (n ≤ 0x80) sets its high bit in the result; no other does.
    let below = |v: u64, n: u8| v.wrapping_sub(ONES * u64::from(n)) & !v & HIGH;
    let mut chunks = bytes.chunks_exact(8);
    for chunk in &mut chunks {
        let mut word = [0u8; 8];
        word.copy_from_slice(chunk);
        let v = u64::from_ne_bytes(word);
        let quote = v ^ (ONES * u64::from(b'"'));
        let backslash = v ^ (ONES * u64::from(b'\\'));
        if below(v, 0x20) | below(quote, 1) | below(backslash, 1) != 0 {
            return true;
        }
    }
    chunks
        .remainder()
        .iter()
        .any(|&b| b < 0x20 || b == b'"' || b == b'\\')
}

/// A fixed buffer a number is formatted into (no allocation per number).
#[cfg_attr(feature = "testkit", visibility::make(pub))]
struct NumBuf {
    bytes: [u8; 64],
    len: usize,
}

impl Default for NumBuf {
    fn default() -> Self {
        Self::new()
    }
}

impl NumBuf {
    /// An empty buffer.
    #[cfg_attr(feature = "testkit", visibility::make(pub))]
    fn new() -> Self {
        NumBuf {
            bytes: [0; 64],
            len: 0,
        }
    }

    /// The text formatted so far.
    #[cfg_attr(feature = "testkit", visibility::make(pub))]
    fn as_bytes(&self) -> &[u8] {
        &self.bytes[..self.len]
    }

    fn push(&mut self, b: u8) {
        if let Some(slot) = self.bytes.get_mut(self.len) {
            *slot = b;
            self.len += 1;
        }
    }
}

impl Write for NumBuf {
    fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
        let room = self.bytes.len() - self.len;
        if buf.len() > room {
            return Err(io::ErrorKind::WriteZero.into());
        }
        self.bytes[self.len..self.len + buf.len()].copy_from_slice(buf);
        self.len += buf.len();
        Ok(buf.len())
    }

    fn flush(&mut self) -> io::Result<()> {
        Ok(())
    }
}

/// The exponent form (`{:e}`: `1.2345679e8`, `1e-7`) of a finite number from its plain
/// shortest form (`{}`: `123456790`, `0.0000001`); both hold the same shortest digits.
#[cfg_attr(feature = "testkit", visibility::make(pub))]
fn exponent_form(plain: &[u8], out: &mut NumBuf) {
    let (negative, body) = match plain.split_first() {
        Some((b'-', rest)) => (true, rest),
        _ => (false, plain),
    };
    let point = body.iter().position(|&b| b == b'.').unwrap_or(body.len());
    let digits = body.iter().filter(|b| b.is_ascii_digit());
    // The significant digits: leading and trailing zeros dropped.
    let mut sig = NumBuf::new();
    let mut leading = 0usize;
    for &d in digits {
        if sig.len == 0 && d == b'0' {
            leading += 1;
            continue;
        }
        sig.push(d);
    }
    while sig.len > 1 && sig.bytes[sig.len - 1] == b'0' {
        sig.len -= 1;
    }
    if negative {
        out.push(b'-');
    }
    if sig.len == 0 {
        // Zero.
        out.push(b'0');
        let _ = write!(out, "e0");
        return;
    }
    // The first significant digit sits `leading` digits into the number, whose integer part
    // has `point` digits.
    let exponent = point as isize - leading as isize - 1;
    let sig = sig.as_bytes();
    out.push(sig[0]);
    if sig.len() > 1 {
        out.push(b'.');
        for &d in &sig[1..] {
            out.push(d);
        }
    }
    let _ = write!(out, "e{exponent}");
}

/// True for values written as JSON arrays (which put the array holding them on several
/// lines).
fn is_container(v: &Value) -> bool {
    matches!(
        v,
        Value::Triple(..) | Value::HPoint(..) | Value::Matrix(..) | Value::Array(..)
    )
}

/// Names of the material's nodes: handles, or keys for handles used twice in the material.
#[cfg_attr(feature = "testkit", visibility::make(pub))]
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

/// The element type an array is written with: its declared base type when every element is
/// of it; otherwise (a RIB value kept as written after RB014, e.g. one number for a `color`)
/// the type of its elements, numbers as `float` (or `int` when all are), so that the reader
/// takes what is written.
#[cfg_attr(feature = "testkit", visibility::make(pub))]
fn element_type(declared: &BaseType, items: &[Value]) -> BaseType {
    if items.iter().all(|v| v.base_type() == *declared) {
        return declared.clone();
    }
    if items.iter().all(|v| matches!(v, Value::Int(_))) {
        BaseType::Int
    } else if items
        .iter()
        .all(|v| matches!(v, Value::Int(_) | Value::Float(_)))
    {
        BaseType::Float
    } else if items.iter().all(|v| matches!(v, Value::Str(_))) {
        BaseType::String
    } else {
        declared.clone()
    }
}

//! JSON network reader (spec formats.md §5.1–§5.3, error policy §5.5).
//!
//! The JSON form mirrors Hydra's `HdMaterialNetwork2`: materials, each with nodes (shader id,
//! parameter values, per-input connection lists), terminals and primvars. [`parse_json`]
//! builds a [`Network`] with one node per (material, node name); a node name that occurs in
//! several materials gives several nodes (keys `name#0`, `name#1`, … in file order), since
//! each material is resolved on its own node set.
//!
//! Duplicate object keys are an error (JS002): the text is read with a custom serde visitor
//! that sees every key (serde_json's own maps keep only the last). Diagnostics carry a JSON
//! Pointer (RFC 6901); syntax errors (JS001) and duplicate keys also carry line and column.
//!
//! Choices where the spec is silent:
//!
//! * `terminals` and `primvars` are optional; `upstreamOutputName` is required (use `""` for a
//!   whole-node reference).
//! * Unknown keys are reported (JS011) at every level, not only at the top.
//! * A parameter given as a JSON object must be the canonical `{ "type", "value" }` form
//!   (JS002 otherwise); an unknown type string is JS002.
//! * `int` accepts any integral JSON number in the `i32` range (`1.0` included); `float`
//!   accepts any number that is finite as `f32`.
//! * A node's request kind comes from the terminals naming it (`surface`/`volume` → `Bxdf`,
//!   `displacement` → `Displace`, `light`, `lightFilter`); other nodes are `Pattern`s.

use crate::diag::{Diagnostic, Diagnostics, Error, Location};
use crate::limits::{Limit, Limits};
use crate::network::{
    Decl, Link, Material, MaterialNodes, Network, Node, NodeId, Param, ParamTypes, RequestKind,
    Terminal,
};
use crate::types::{ArraySpec, BaseType, Type, Value};
use serde::de::{self, DeserializeSeed, MapAccess, SeqAccess, Visitor};
use std::cell::RefCell;
use std::collections::{HashMap, HashSet};
use std::fmt;
use std::sync::Arc;

/// A JSON number as read.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Num {
    I(i64),
    U(u64),
    F(f64),
}

impl Num {
    fn as_f64(self) -> f64 {
        match self {
            Num::I(i) => i as f64,
            Num::U(u) => u as f64,
            Num::F(f) => f,
        }
    }
}

/// A JSON value with object members in document order.
#[derive(Debug, Clone, PartialEq)]
enum J {
    Null,
    Bool(bool),
    Num(Num),
    Str(String),
    Arr(Vec<J>),
    Obj(Vec<(String, J)>),
}

impl J {
    fn kind(&self) -> &'static str {
        match self {
            J::Null => "null",
            J::Bool(_) => "a boolean",
            J::Num(_) => "a number",
            J::Str(_) => "a string",
            J::Arr(_) => "an array",
            J::Obj(_) => "an object",
        }
    }
}

/// Shared state of the tree builder: the current path (for the pointer of a duplicate key).
#[derive(Default)]
struct Ctx {
    path: RefCell<Vec<String>>,
    duplicate: RefCell<Option<String>>,
}

impl Ctx {
    fn pointer_with(&self, last: &str) -> String {
        let mut p = String::new();
        for seg in self.path.borrow().iter() {
            p.push('/');
            p.push_str(&escape_pointer(seg));
        }
        p.push('/');
        p.push_str(&escape_pointer(last));
        p
    }
}

/// RFC 6901 escaping of one pointer segment.
fn escape_pointer(s: &str) -> String {
    s.replace('~', "~0").replace('/', "~1")
}

struct Seed<'c>(&'c Ctx);

impl<'de> DeserializeSeed<'de> for Seed<'_> {
    type Value = J;
    fn deserialize<D: de::Deserializer<'de>>(self, d: D) -> Result<J, D::Error> {
        d.deserialize_any(self)
    }
}

impl<'de> Visitor<'de> for Seed<'_> {
    type Value = J;
    fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str("a JSON value")
    }
    fn visit_bool<E>(self, v: bool) -> Result<J, E> {
        Ok(J::Bool(v))
    }
    fn visit_i64<E>(self, v: i64) -> Result<J, E> {
        Ok(J::Num(Num::I(v)))
    }
    fn visit_u64<E>(self, v: u64) -> Result<J, E> {
        Ok(J::Num(Num::U(v)))
    }
    fn visit_f64<E>(self, v: f64) -> Result<J, E> {
        Ok(J::Num(Num::F(v)))
    }
    fn visit_str<E>(self, v: &str) -> Result<J, E> {
        Ok(J::Str(v.to_string()))
    }
    fn visit_string<E>(self, v: String) -> Result<J, E> {
        Ok(J::Str(v))
    }
    fn visit_unit<E>(self) -> Result<J, E> {
        Ok(J::Null)
    }
    fn visit_none<E>(self) -> Result<J, E> {
        Ok(J::Null)
    }
    fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<J, A::Error> {
        let mut items = Vec::new();
        loop {
            self.0.path.borrow_mut().push(items.len().to_string());
            let next = seq.next_element_seed(Seed(self.0));
            self.0.path.borrow_mut().pop();
            match next? {
                Some(v) => items.push(v),
                None => return Ok(J::Arr(items)),
            }
        }
    }
    fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> Result<J, A::Error> {
        let mut members: Vec<(String, J)> = Vec::new();
        let mut seen: HashSet<String> = HashSet::new();
        while let Some(key) = map.next_key::<String>()? {
            if !seen.insert(key.clone()) {
                let pointer = self.0.pointer_with(&key);
                *self.0.duplicate.borrow_mut() = Some(pointer);
                return Err(de::Error::custom(format!("duplicate key `{key}`")));
            }
            self.0.path.borrow_mut().push(key.clone());
            let value = map.next_value_seed(Seed(self.0));
            self.0.path.borrow_mut().pop();
            members.push((key, value?));
        }
        Ok(J::Obj(members))
    }
}

/// Read a JSON network.
///
/// `path` names the input in diagnostics; `types` supplies declared types for shorthand
/// values (JS006 when a parameter is not declared). Warnings go to `diags`; the first error is
/// returned.
///
/// ```
/// use vstructc::front::json::parse_json;
/// use vstructc::network::{NoDefinitions, RequestKind};
/// use vstructc::{Diagnostics, Value};
///
/// let text = br#"{
///   "vstructcNetwork": 1,
///   "materials": { "RedSG": {
///     "nodes": {
///       "noise": { "nodeTypeId": "PxrFractal",
///                  "parameters": { "layers": { "type": "int", "value": 4 } } },
///       "surf": { "nodeTypeId": "PxrSurface",
///                 "inputConnections": { "diffuseGain": [
///                   { "upstreamNode": "noise", "upstreamOutputName": "resultF" } ] } }
///     },
///     "terminals": { "surface": { "upstreamNode": "surf", "upstreamOutputName": "" } }
///   } }
/// }"#;
/// let mut diags = Diagnostics::new();
/// let net = parse_json(text, "net.json", &NoDefinitions, &mut diags).unwrap();
/// let noise = net.find("noise").unwrap();
/// let surf = net.find("surf").unwrap();
/// assert_eq!(net.value(noise, "layers"), Some(&Value::Int(4)));
/// assert_eq!(net.connections(surf, "diffuseGain")[0].upstream_node(), Some(noise));
/// assert_eq!(net[surf].kind(), RequestKind::Bxdf);
/// assert_eq!(net.materials()[0].name, "RedSG");
/// ```
pub fn parse_json(
    bytes: &[u8],
    path: &str,
    types: &dyn ParamTypes,
    diags: &mut Diagnostics,
) -> Result<Network, Error> {
    parse_json_limited(bytes, path, types, &Limits::default(), diags)
}

/// [`parse_json`] within `limits`: the input's size, its nodes, each node's parameters and
/// each input's connections ([`Network::check_limits`]); exceeding one is [`Error::Limit`].
pub fn parse_json_limited(
    bytes: &[u8],
    path: &str,
    types: &dyn ParamTypes,
    limits: &Limits,
    diags: &mut Diagnostics,
) -> Result<Network, Error> {
    let file: Arc<str> = Arc::from(path);
    limits
        .check(Limit::NetworkFileBytes, bytes.len() as u64)
        .map_err(|e| e.at(Location::file(file.clone())))?;
    let root = parse_tree(bytes, &file)?;
    let mut r = Reader {
        file,
        types,
        diags,
        net: Network::new(),
    };
    r.document(&root)?;
    r.net.check_limits(limits)?;
    Ok(r.net)
}

/// Parse the text into a tree; JS001 (syntax) and JS002 (duplicate key) with line/column.
fn parse_tree(bytes: &[u8], file: &Arc<str>) -> Result<J, Error> {
    let ctx = Ctx::default();
    let mut de = serde_json::Deserializer::from_slice(bytes);
    let result = Seed(&ctx)
        .deserialize(&mut de)
        .and_then(|j| de.end().map(|()| j));
    result.map_err(|e| {
        let mut loc = Location::new(
            file.clone(),
            e.line() as u32,
            char_column(bytes, e.line(), e.column()),
        );
        let duplicate = ctx.duplicate.borrow_mut().take();
        let d = match (e.classify(), duplicate) {
            (serde_json::error::Category::Data, Some(pointer)) => {
                loc.pointer = Some(pointer);
                Diagnostic::error("JS002", strip_position(&e))
            }
            _ => Diagnostic::error("JS001", format!("not valid JSON: {}", strip_position(&e))),
        };
        d.at(loc).into()
    })
}

/// serde_json's message without its " at line L column C" suffix (the location says it).
fn strip_position(e: &serde_json::Error) -> String {
    let s = e.to_string();
    match s.rfind(" at line ") {
        Some(k) => s[..k].to_string(),
        None => s,
    }
}

/// serde_json columns count bytes; diagnostics count characters.
fn char_column(bytes: &[u8], line: usize, byte_col: usize) -> u32 {
    if line == 0 {
        return 0;
    }
    let start = bytes
        .split(|&b| b == b'\n')
        .take(line - 1)
        .map(|l| l.len() + 1)
        .sum::<usize>()
        .min(bytes.len());
    let end = (start + byte_col).min(bytes.len());
    let text = String::from_utf8_lossy(&bytes[start..end]);
    text.chars().count().max(1) as u32
}

/// The connections of one node, per parameter index, waiting to be bound.
type NodeConns = Vec<(usize, Vec<Conn>)>;

/// A parsed connection object.
struct Conn {
    node: String,
    output: Option<String>,
    pointer: String,
}

struct Reader<'d, 't> {
    file: Arc<str>,
    types: &'t dyn ParamTypes,
    diags: &'d mut Diagnostics,
    net: Network,
}

fn ptr(base: &str, seg: &str) -> String {
    format!("{base}/{}", escape_pointer(seg))
}

impl Reader<'_, '_> {
    fn loc(&self, pointer: &str) -> Location {
        Location {
            file: self.file.clone(),
            line: 0,
            column: 0,
            pointer: Some(pointer.to_string()),
        }
    }

    fn error(&self, code: &'static str, pointer: &str, msg: impl Into<String>) -> Error {
        Diagnostic::error(code, msg).at(self.loc(pointer)).into()
    }

    fn object<'j>(&self, j: &'j J, pointer: &str, what: &str) -> Result<&'j [(String, J)], Error> {
        match j {
            J::Obj(m) => Ok(m),
            other => Err(self.error(
                "JS002",
                pointer,
                format!("{what} must be an object, found {}", other.kind()),
            )),
        }
    }

    fn string<'j>(&self, j: &'j J, pointer: &str, what: &str) -> Result<&'j str, Error> {
        match j {
            J::Str(s) => Ok(s),
            other => Err(self.error(
                "JS002",
                pointer,
                format!("{what} must be a string, found {}", other.kind()),
            )),
        }
    }

    fn unknown_key(&mut self, pointer: &str, key: &str, where_: &str) {
        let d = Diagnostic::warning("JS011", format!("unknown key `{key}` in {where_}; ignored"))
            .at(self.loc(pointer));
        self.diags.push(d);
    }

    fn document(&mut self, root: &J) -> Result<(), Error> {
        let top = self.object(root, "", "the document")?;
        let get = |k: &str| top.iter().find(|(key, _)| key == k).map(|(_, v)| v);
        match get("vstructcNetwork") {
            None => return Err(self.error("JS002", "", "missing `vstructcNetwork`")),
            Some(J::Num(n)) if n.as_f64() == 1.0 => {}
            Some(J::Num(n)) => {
                return Err(self.error(
                    "JS003",
                    "/vstructcNetwork",
                    format!(
                        "unsupported vstructcNetwork version {}; only 1 is supported",
                        n.as_f64()
                    ),
                ));
            }
            Some(other) => {
                return Err(self.error(
                    "JS002",
                    "/vstructcNetwork",
                    format!(
                        "`vstructcNetwork` must be the integer 1, found {}",
                        other.kind()
                    ),
                ));
            }
        }
        for (k, _) in top {
            if k != "vstructcNetwork" && k != "materials" {
                self.unknown_key(&ptr("", k), k, "the document");
            }
        }
        let Some(materials) = get("materials") else {
            return Err(self.error("JS002", "", "missing `materials`"));
        };
        let materials = self.object(materials, "/materials", "`materials`")?;
        for (name, m) in materials {
            self.material(name, m, &ptr("/materials", name))?;
        }
        Ok(())
    }

    fn material(&mut self, name: &str, j: &J, pointer: &str) -> Result<(), Error> {
        let members = self.object(j, pointer, "a material")?;
        let mut nodes = None;
        let mut terminals: &[(String, J)] = &[];
        let mut primvars = Vec::new();
        for (k, v) in members {
            let p = ptr(pointer, k);
            match k.as_str() {
                "nodes" => nodes = Some(self.object(v, &p, "`nodes`")?),
                "terminals" => terminals = self.object(v, &p, "`terminals`")?,
                "primvars" => primvars = self.primvars(v, &p)?,
                _ => self.unknown_key(&p, k, "a material"),
            }
        }
        let Some(nodes) = nodes else {
            return Err(self.error(
                "JS002",
                pointer,
                format!("material `{name}` has no `nodes`"),
            ));
        };
        let tpointer = ptr(pointer, "terminals");
        let terms: Vec<(String, Conn)> = terminals
            .iter()
            .map(|(t, c)| Ok((t.clone(), self.connection(c, &ptr(&tpointer, t))?)))
            .collect::<Result<_, Error>>()?;
        // A node's kind comes from the first terminal naming it.
        let mut kinds: HashMap<&str, RequestKind> = HashMap::new();
        for (t, c) in &terms {
            kinds
                .entry(c.node.as_str())
                .or_insert(RequestKind::from_terminal_name(t));
        }
        let npointer = ptr(pointer, "nodes");
        let mut ids: Vec<NodeId> = Vec::with_capacity(nodes.len());
        let mut by_name: HashMap<&str, NodeId> = HashMap::new();
        let mut pending: Vec<(NodeId, NodeConns)> = Vec::new();
        for (node_name, nj) in nodes {
            let kind = kinds
                .get(node_name.as_str())
                .copied()
                .unwrap_or(RequestKind::Pattern);
            let (id, conns) = self.node(node_name, nj, kind, &ptr(&npointer, node_name))?;
            ids.push(id);
            by_name.insert(node_name, id);
            pending.push((id, conns));
        }
        for (id, conns) in pending {
            for (param, list) in conns {
                let links = list.iter().map(|c| self.bind(c, &by_name, name)).collect();
                self.net.push_source_links(id, param, links);
            }
        }
        let terminals = terms
            .iter()
            .map(|(t, c)| Terminal {
                name: t.clone(),
                link: self.bind(c, &by_name, name),
            })
            .collect();
        let location = Some(self.loc(pointer));
        self.net.materials_mut().push(Material {
            name: name.to_string(),
            terminals,
            nodes: MaterialNodes::Explicit(ids),
            primvars,
            location,
        });
        Ok(())
    }

    fn primvars(&self, j: &J, pointer: &str) -> Result<Vec<String>, Error> {
        match j {
            J::Arr(items) => items
                .iter()
                .enumerate()
                .map(|(i, v)| {
                    self.string(v, &ptr(pointer, &i.to_string()), "a primvar")
                        .map(str::to_string)
                })
                .collect(),
            other => Err(self.error(
                "JS002",
                pointer,
                format!("`primvars` must be an array, found {}", other.kind()),
            )),
        }
    }

    /// Bind a connection to a node of the material, or keep it dangling (JS010).
    fn bind(&mut self, c: &Conn, by_name: &HashMap<&str, NodeId>, material: &str) -> Link {
        match by_name.get(c.node.as_str()) {
            Some(&id) => Link::node(id, c.output.as_deref()),
            None => {
                let d = Diagnostic::warning(
                    "JS010",
                    format!(
                        "connection to `{}`, which is not a node of material `{material}`; kept",
                        c.node
                    ),
                )
                .at(self.loc(&c.pointer));
                self.diags.push(d);
                Link::missing(&c.node, c.output.as_deref())
            }
        }
    }

    fn connection(&mut self, j: &J, pointer: &str) -> Result<Conn, Error> {
        let members = self.object(j, pointer, "a connection")?;
        let mut node = None;
        let mut output = None;
        for (k, v) in members {
            let p = ptr(pointer, k);
            match k.as_str() {
                "upstreamNode" => node = Some(self.string(v, &p, "`upstreamNode`")?.to_string()),
                "upstreamOutputName" => {
                    output = Some(self.string(v, &p, "`upstreamOutputName`")?.to_string())
                }
                _ => self.unknown_key(&p, k, "a connection"),
            }
        }
        let Some(node) = node else {
            return Err(self.error("JS002", pointer, "connection without `upstreamNode`"));
        };
        let Some(output) = output else {
            return Err(self.error(
                "JS002",
                pointer,
                "connection without `upstreamOutputName` (use \"\" for a whole-node reference)",
            ));
        };
        Ok(Conn {
            node,
            output: (!output.is_empty()).then_some(output),
            pointer: pointer.to_string(),
        })
    }

    /// Read one node; returns its id and its connections (per parameter index), to bind once
    /// every node of the material exists.
    fn node(
        &mut self,
        name: &str,
        j: &J,
        kind: RequestKind,
        pointer: &str,
    ) -> Result<(NodeId, NodeConns), Error> {
        let members = self.object(j, pointer, "a node")?;
        let mut shader = None;
        let mut parameters: &[(String, J)] = &[];
        let mut inputs: &[(String, J)] = &[];
        for (k, v) in members {
            let p = ptr(pointer, k);
            match k.as_str() {
                "nodeTypeId" => shader = Some(self.string(v, &p, "`nodeTypeId`")?),
                "parameters" => parameters = self.object(v, &p, "`parameters`")?,
                "inputConnections" => inputs = self.object(v, &p, "`inputConnections`")?,
                _ => self.unknown_key(&p, k, "a node"),
            }
        }
        let Some(shader) = shader else {
            return Err(self.error(
                "JS002",
                pointer,
                format!("node `{name}` has no `nodeTypeId`"),
            ));
        };
        let mut params: Vec<Param> = Vec::new();
        let mut index: HashMap<&str, usize> = HashMap::new();
        let ppointer = ptr(pointer, "parameters");
        for (pname, pj) in parameters {
            let p = ptr(&ppointer, pname);
            let (value, decl) = self.parameter(shader, pname, pj, &p)?;
            index.insert(pname, params.len());
            params.push(Param::from_source(
                pname.clone(),
                Some(value),
                Some(decl),
                Some(self.loc(&p)),
                None,
            ));
        }
        let ipointer = ptr(pointer, "inputConnections");
        let mut conns: NodeConns = Vec::new();
        for (input, list) in inputs {
            let p = ptr(&ipointer, input);
            let J::Arr(items) = list else {
                return Err(self.error(
                    "JS002",
                    &p,
                    format!(
                        "connections of `{input}` must be an array, found {}",
                        list.kind()
                    ),
                ));
            };
            let list: Vec<Conn> = items
                .iter()
                .enumerate()
                .map(|(i, c)| self.connection(c, &ptr(&p, &i.to_string())))
                .collect::<Result<_, Error>>()?;
            let k = *index.entry(input).or_insert_with(|| {
                params.push(Param::from_source(input.clone(), None, None, None, None));
                params.len() - 1
            });
            conns.push((k, list));
        }
        let mut node = Node::new_raw(name, shader, kind);
        node.set_raw_params(params);
        node.set_origin(Some(self.loc(pointer)), None);
        Ok((self.net.insert_node(node), conns))
    }

    /// A parameter value: canonical `{ "type", "value" }`, or a shorthand bare value typed by
    /// the definition.
    fn parameter(
        &mut self,
        shader: &str,
        name: &str,
        j: &J,
        pointer: &str,
    ) -> Result<(Value, Decl), Error> {
        if let J::Obj(members) = j {
            let mut ty = None;
            let mut value = None;
            for (k, v) in members {
                let p = ptr(pointer, k);
                match k.as_str() {
                    "type" => ty = Some(self.string(v, &p, "`type`")?),
                    "value" => value = Some(v),
                    _ => self.unknown_key(&p, k, "a parameter"),
                }
            }
            let (Some(text), Some(v)) = (ty, value) else {
                return Err(self.error(
                    "JS002",
                    pointer,
                    format!(
                        "parameter `{name}` must be {{ \"type\": T, \"value\": V }} or a bare value"
                    ),
                ));
            };
            let Some(t) = parse_type(text) else {
                return Err(self.error(
                    "JS002",
                    &ptr(pointer, "type"),
                    format!("unknown type `{text}` of `{name}`"),
                ));
            };
            let value = to_value(&t, v).map_err(|why| {
                self.error(
                    "JS004",
                    &ptr(pointer, "value"),
                    format!("value of `{name}` does not match its type `{text}`: {why}"),
                )
            })?;
            let decl = Decl {
                text: text.to_string(),
                class: None,
                reference: false,
                ty: t,
                inline_type: true,
            };
            return Ok((value, decl));
        }
        let Some(t) = self.types.input_type(shader, name) else {
            return Err(self.error(
                "JS006",
                pointer,
                format!("shorthand value for `{name}`, which `{shader}` does not declare; write {{ \"type\": T, \"value\": V }}"),
            ));
        };
        let value = to_value(&t, j).map_err(|why| {
            self.error(
                "JS004",
                pointer,
                format!("value of `{name}` does not match its declared type `{t}`: {why}"),
            )
        })?;
        let decl = Decl {
            text: String::new(),
            class: None,
            reference: false,
            ty: t,
            inline_type: false,
        };
        Ok((value, decl))
    }
}

/// A JSON type string: `int | float | string | color | point | vector | normal | matrix |
/// hpoint | token | asset | bool`, optionally with `[N]` or `[]`.
fn parse_type(text: &str) -> Option<Type> {
    let (word, array) = match text.find('[') {
        None => (text, ArraySpec::None),
        Some(k) => {
            let inner = text[k + 1..].strip_suffix(']')?;
            let array = if inner.is_empty() {
                ArraySpec::Dynamic
            } else {
                ArraySpec::Fixed(inner.parse().ok()?)
            };
            (&text[..k], array)
        }
    };
    let base = match word {
        "int" | "float" | "string" | "color" | "point" | "vector" | "normal" | "matrix"
        | "hpoint" | "token" | "asset" | "bool" => BaseType::from_word(word),
        _ => return None,
    };
    Some(Type { base, array })
}

/// Convert a JSON value to a typed value of type `t`.
fn to_value(t: &Type, j: &J) -> Result<Value, String> {
    let items = |j: &J| -> Result<Vec<Value>, String> {
        match j {
            J::Arr(items) => items.iter().map(|i| scalar(&t.base, i)).collect(),
            other => Err(format!("expected an array, found {}", other.kind())),
        }
    };
    match t.array {
        ArraySpec::None => scalar(&t.base, j),
        ArraySpec::Fixed(n) => {
            let v = items(j)?;
            if v.len() != n {
                return Err(format!("expected {n} elements, found {}", v.len()));
            }
            Ok(Value::Array(t.base.clone(), v))
        }
        ArraySpec::Dynamic => Ok(Value::Array(t.base.clone(), items(j)?)),
    }
}

fn number(j: &J) -> Result<Num, String> {
    match j {
        J::Num(n) => Ok(*n),
        other => Err(format!("expected a number, found {}", other.kind())),
    }
}

fn float(j: &J) -> Result<f32, String> {
    let x = number(j)?.as_f64() as f32;
    if x.is_finite() {
        Ok(x)
    } else {
        Err("number outside the f32 range".into())
    }
}

fn floats<const N: usize>(j: &J) -> Result<[f32; N], String> {
    let J::Arr(items) = j else {
        return Err(format!(
            "expected an array of {N} numbers, found {}",
            j.kind()
        ));
    };
    if items.len() != N {
        return Err(format!("expected {N} numbers, found {}", items.len()));
    }
    let mut out = [0.0f32; N];
    for (o, i) in out.iter_mut().zip(items) {
        *o = float(i)?;
    }
    Ok(out)
}

fn scalar(base: &BaseType, j: &J) -> Result<Value, String> {
    let string = |j: &J| match j {
        J::Str(s) => Ok(s.clone()),
        other => Err(format!("expected a string, found {}", other.kind())),
    };
    Ok(match base {
        BaseType::Int => {
            let n = number(j)?;
            let v = match n {
                Num::I(i) => i32::try_from(i).ok(),
                Num::U(u) => i32::try_from(u).ok(),
                Num::F(f)
                    if f.fract() == 0.0 && f >= f64::from(i32::MIN) && f <= f64::from(i32::MAX) =>
                {
                    Some(f as i32)
                }
                Num::F(_) => None,
            };
            Value::Int(
                v.ok_or_else(|| format!("{} is not an integer in the int range", n.as_f64()))?,
            )
        }
        BaseType::Float => Value::Float(float(j)?),
        BaseType::String => Value::Str(string(j)?),
        BaseType::Token => Value::Token(string(j)?),
        BaseType::Asset => Value::Asset(string(j)?),
        BaseType::Bool => match j {
            J::Bool(b) => Value::Bool(*b),
            other => return Err(format!("expected a boolean, found {}", other.kind())),
        },
        b if b.is_triple() => Value::Triple(b.clone(), floats::<3>(j)?),
        BaseType::HPoint => Value::HPoint(floats::<4>(j)?),
        BaseType::Matrix => Value::Matrix(floats::<16>(j)?),
        other => return Err(format!("type `{other}` has no value form")),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tree(s: &str) -> Result<J, Error> {
        parse_tree(s.as_bytes(), &Arc::from("t.json"))
    }

    #[test]
    fn duplicate_keys_are_js002_with_pointer_and_position() {
        let e = tree("{\"a\": {\"b\": 1,\n \"b\": 2}}").unwrap_err();
        let d = e.diagnostic().unwrap();
        assert_eq!(d.code, "JS002");
        let loc = d.location.as_ref().unwrap();
        assert_eq!(loc.pointer.as_deref(), Some("/a/b"));
        assert_eq!(loc.line, 2);
    }

    #[test]
    fn syntax_errors_are_js001_with_position() {
        let e = tree("{\n  \"a\": ,\n}").unwrap_err();
        let d = e.diagnostic().unwrap();
        assert_eq!(d.code, "JS001");
        let loc = d.location.as_ref().unwrap();
        assert_eq!((loc.line, loc.column), (2, 8));
        assert_eq!(tree("[1] x").unwrap_err().code(), Some("JS001"));
        assert_eq!(tree("").unwrap_err().code(), Some("JS001"));
    }

    #[test]
    fn pointer_escaping() {
        assert_eq!(escape_pointer("a/b~c"), "a~1b~0c");
        let e = tree("{\"x/y\": {\"~\": 1, \"~\": 2}}").unwrap_err();
        let loc = e.diagnostic().unwrap().location.clone().unwrap();
        assert_eq!(loc.pointer.as_deref(), Some("/x~1y/~0"));
    }

    #[test]
    fn types_and_values() {
        assert_eq!(
            parse_type("float[2]"),
            Some(Type {
                base: BaseType::Float,
                array: ArraySpec::Fixed(2)
            })
        );
        assert_eq!(
            parse_type("int[]").map(|t| t.array),
            Some(ArraySpec::Dynamic)
        );
        assert_eq!(parse_type("vstruct"), None);
        assert_eq!(parse_type("float[x]"), None);
        let t = Type::scalar(BaseType::Int);
        assert_eq!(to_value(&t, &J::Num(Num::F(2.0))), Ok(Value::Int(2)));
        assert!(to_value(&t, &J::Num(Num::F(2.5))).is_err());
        assert!(to_value(&t, &J::Num(Num::I(1 << 40))).is_err());
        let c = Type::scalar(BaseType::Color);
        let arr = J::Arr(vec![
            J::Num(Num::I(1)),
            J::Num(Num::F(0.5)),
            J::Num(Num::U(0)),
        ]);
        assert_eq!(
            to_value(&c, &arr),
            Ok(Value::Triple(BaseType::Color, [1.0, 0.5, 0.0]))
        );
        assert!(to_value(&Type::scalar(BaseType::Float), &J::Num(Num::F(1e39))).is_err());
    }
}

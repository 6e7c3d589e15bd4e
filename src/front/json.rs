//! JSON network reader (see `docs/inputs-and-outputs.md`).
//!
//! The JSON form mirrors Hydra's `HdMaterialNetwork2`: materials, each with nodes (shader id,
//! parameter values, per-input connection lists), terminals and primvars. [`parse_json`]
//! builds a [`Network`] with one node per (material, node name); a node name that occurs in
//! several materials gives several nodes (keys `name#0`, `name#1`, … in file order), since
//! each material is resolved on its own node set.
//!
//! The network is built while serde reads the text: custom `DeserializeSeed`s for the
//! document, `materials`, each material, its `nodes`, each node, its parameters (a value whose
//! `type` came first is converted as it is read) and its connections build each node as it
//! comes; a material's nodes and connections enter the network when the material closes
//! (`MaterialOut`). Only a material's `terminals` and `primvars`, a value read before its
//! `type` and unknown members are held as small trees. Keys and strings borrow from the text
//! unless they hold escapes, and a JSON Pointer is composed only when a diagnostic needs one.
//! A scene repeats its parameters: a parameter's value is taken as text (a `RawValue`) and,
//! when the same name and text were read before without a finding, its declaration and value
//! are shared and not read again; parameters with the same value share one block. Where
//! reading a value alone could differ from reading it in the document (an error of
//! serde_json, whose position must be the document's, or a deep tree), the document is read
//! again without remembering.
//! Duplicate object keys are an error (JS002): the visitors see every key (serde_json's own
//! maps keep only the last). Diagnostics carry a JSON Pointer (RFC 6901); syntax errors (JS001)
//! and duplicate keys also carry line and column.
//!
//! Diagnostics do not depend on the order of the keys: findings are collected with the place
//! of their check and reported once the whole text is valid JSON, in this order: any syntax
//! error or duplicate key first (nothing else is then reported); the version; unknown
//! top-level keys; `materials`; then per material, in document order, its own keys and
//! `primvars`, a missing `nodes`, its terminals, its nodes, and its dangling connections
//! (JS010); within a node, its own keys, a missing `nodeTypeId`, each parameter, each input
//! (a node's findings wait for the node to close). The first error ends the report; warnings
//! before it are kept. So within one of these steps, document order still counts: a warning
//! for an unknown key of a node is reported when the key comes before an error in the
//! node's own keys (a `nodeTypeId` that is not a string), not when it comes after. A node's kind is set when its material's terminals are read (they may
//! follow the nodes, as in the order the JSON writer uses).
//!
//! With the `parallel` feature, an input of 1 MiB or more is read with its materials on
//! rayon's pool (`read_on_pool`): the document is read with each material's value taken
//! unread (a `RawValue`), the pool's threads read the materials in batches with the same
//! visitors, and the materials enter the network in document order. Any error of serde_json
//! (a syntax error, a duplicate key) or a deep tree sends the document to the reading on the
//! calling thread, which reports it with its line and column, so the network, the diagnostics
//! and the errors are the same either way.
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
use crate::front::remembered::{MAX_REMEMBERED_PARAMS, Remembered, text_hash};
use crate::limits::{Limit, Limits};
use crate::network::{
    Decl, Link, Material, MaterialNodes, Network, Node, NodeId, Param, ParamAt, ParamTypes,
    RequestKind, Sym, Terminal,
};
use crate::types::{ArraySpec, BaseType, Type, Value};
use rustc_hash::{FxHashMap, FxHashSet, FxHasher};
use serde::de::{self, DeserializeSeed, MapAccess, SeqAccess, Visitor};
use serde_json::value::RawValue;
use std::borrow::Cow;
use std::cell::{Cell, RefCell};
use std::fmt;
use std::hash::Hasher;
use std::sync::Arc;
#[cfg(feature = "parallel")]
use std::sync::Mutex;

/// A JSON number as read.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "testkit", visibility::make(pub))]
enum Num {
    /// A negative integer.
    I(i64),
    /// A non-negative integer.
    U(u64),
    /// A number with a fraction or an exponent.
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

/// A JSON value with object members in document order; strings borrow from the text unless
/// they hold escapes.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "testkit", visibility::make(pub))]
enum J<'de> {
    /// `null`.
    Null,
    /// `true` or `false`.
    Bool(bool),
    /// A number.
    Num(Num),
    /// A string.
    Str(Cow<'de, str>),
    /// An array.
    Arr(Vec<J<'de>>),
    /// An object, members in document order.
    Obj(Vec<(Cow<'de, str>, J<'de>)>),
}

impl J<'_> {
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

/// Where a duplicate key was found. The pointer is collected as the duplicate's error
/// travels up the readers (each adds its own segment), so no path is kept while reading.
#[derive(Default)]
struct Ctx {
    /// The duplicate key's pointer segments, innermost first.
    duplicate: RefCell<Option<Vec<String>>>,
    /// How deep the value trees being read are nested now, and at most (a material read on
    /// its own must stay well within serde_json's nesting limit, which it meets shallower
    /// within the document).
    depth: Cell<u32>,
    deepest: Cell<u32>,
}

impl Ctx {
    /// One level deeper into a value tree.
    fn enter(&self) {
        let d = self.depth.get() + 1;
        self.depth.set(d);
        self.deepest.set(self.deepest.get().max(d));
    }

    /// Out of a level entered with [`Ctx::enter`].
    fn leave(&self) {
        self.depth.set(self.depth.get().saturating_sub(1));
    }

    /// The error for a duplicate `key` (a serde error: JS002 with line and column).
    fn duplicate_key<E: de::Error>(&self, key: &str) -> E {
        *self.duplicate.borrow_mut() = Some(vec![key.to_string()]);
        E::custom(format!("duplicate key `{key}`"))
    }

    /// `read`, the value under `segment`: a duplicate inside it gets `segment` in its pointer.
    #[inline]
    fn within<T, E>(&self, segment: impl FnOnce() -> String, read: Result<T, E>) -> Result<T, E> {
        if read.is_err()
            && let Some(segments) = self.duplicate.borrow_mut().as_mut()
        {
            segments.push(segment());
        }
        read
    }

    /// The duplicate key's pointer, if the error was a duplicate key.
    fn take_pointer(&self) -> Option<String> {
        let segments = self.duplicate.borrow_mut().take()?;
        let mut p = String::new();
        for seg in segments.iter().rev() {
            p.push('/');
            p.push_str(&escape_pointer(seg));
        }
        Some(p)
    }
}

/// Keys seen in one object: a scan while the object is small, a hash set beyond.
#[derive(Default)]
struct SeenKeys<'de> {
    few: Vec<Cow<'de, str>>,
    many: FxHashSet<Cow<'de, str>>,
}

impl<'de> SeenKeys<'de> {
    const SCAN: usize = 16;

    /// Record `key`; false if it was already there.
    fn insert(&mut self, key: Cow<'de, str>) -> bool {
        if self.few.len() < Self::SCAN {
            if self.few.contains(&key) {
                return false;
            }
            self.few.push(key);
            if self.few.len() == Self::SCAN {
                self.many.extend(self.few.iter().cloned());
            }
            return true;
        }
        self.many.insert(key)
    }
}

/// An object key, borrowed from the text unless it holds escapes.
struct Key;

impl<'de> DeserializeSeed<'de> for Key {
    type Value = Cow<'de, str>;
    fn deserialize<D: de::Deserializer<'de>>(self, d: D) -> Result<Cow<'de, str>, D::Error> {
        d.deserialize_str(self)
    }
}

impl<'de> Visitor<'de> for Key {
    type Value = Cow<'de, str>;
    fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str("a string")
    }
    fn visit_borrowed_str<E>(self, v: &'de str) -> Result<Cow<'de, str>, E> {
        Ok(Cow::Borrowed(v))
    }
    fn visit_str<E>(self, v: &str) -> Result<Cow<'de, str>, E> {
        Ok(Cow::Owned(v.to_string()))
    }
    fn visit_string<E>(self, v: String) -> Result<Cow<'de, str>, E> {
        Ok(Cow::Owned(v))
    }
}

/// A JSON Pointer built only when a diagnostic needs it: a rendered base and the segments
/// below it, each borrowed from the caller's frame.
#[derive(Clone, Copy)]
enum P<'a> {
    /// A pointer already rendered.
    Root(&'a str),
    /// The member `key` of the object at the base.
    Key(&'a P<'a>, &'a str),
    /// The element `index` of the array at the base.
    Index(&'a P<'a>, usize),
}

impl P<'_> {
    fn render(&self) -> String {
        let mut s = String::with_capacity(self.len_hint());
        self.write(&mut s);
        s
    }

    /// The rendered length when no segment needs escaping (one block for the text).
    fn len_hint(&self) -> usize {
        match *self {
            P::Root(r) => r.len(),
            P::Key(base, key) => base.len_hint() + 1 + key.len(),
            P::Index(base, _) => base.len_hint() + 21,
        }
    }

    fn write(&self, s: &mut String) {
        match *self {
            P::Root(r) => s.push_str(r),
            P::Key(base, key) => {
                base.write(s);
                s.push('/');
                s.push_str(&escape_pointer(key));
            }
            P::Index(base, i) => {
                base.write(s);
                s.push('/');
                s.push_str(itoa::Buffer::new().format(i));
            }
        }
    }
}

/// RFC 6901 escaping of one pointer segment.
#[cfg_attr(feature = "testkit", visibility::make(pub))]
fn escape_pointer(s: &str) -> Cow<'_, str> {
    if !s.contains(['~', '/']) {
        return Cow::Borrowed(s);
    }
    Cow::Owned(s.replace('~', "~0").replace('/', "~1"))
}

struct Seed<'c>(&'c Ctx);

impl<'de> Visitor<'de> for Seed<'_> {
    type Value = J<'de>;
    fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str("a JSON value")
    }
    fn visit_bool<E>(self, v: bool) -> Result<J<'de>, E> {
        Ok(J::Bool(v))
    }
    fn visit_i64<E>(self, v: i64) -> Result<J<'de>, E> {
        Ok(J::Num(Num::I(v)))
    }
    fn visit_u64<E>(self, v: u64) -> Result<J<'de>, E> {
        Ok(J::Num(Num::U(v)))
    }
    fn visit_f64<E>(self, v: f64) -> Result<J<'de>, E> {
        Ok(J::Num(Num::F(v)))
    }
    fn visit_borrowed_str<E>(self, v: &'de str) -> Result<J<'de>, E> {
        Ok(J::Str(Cow::Borrowed(v)))
    }
    fn visit_str<E>(self, v: &str) -> Result<J<'de>, E> {
        Ok(J::Str(Cow::Owned(v.to_string())))
    }
    fn visit_string<E>(self, v: String) -> Result<J<'de>, E> {
        Ok(J::Str(Cow::Owned(v)))
    }
    fn visit_unit<E>(self) -> Result<J<'de>, E> {
        Ok(J::Null)
    }
    fn visit_none<E>(self) -> Result<J<'de>, E> {
        Ok(J::Null)
    }
    fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<J<'de>, A::Error> {
        let mut items = Vec::new();
        self.0.enter();
        loop {
            let next = seq.next_element_seed(Seed(self.0));
            match self.0.within(|| items.len().to_string(), next)? {
                Some(v) => items.push(v),
                None => {
                    self.0.leave();
                    return Ok(J::Arr(items));
                }
            }
        }
    }
    fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> Result<J<'de>, A::Error> {
        self.0.enter();
        let mut members: Vec<(Cow<'de, str>, J<'de>)> = Vec::new();
        // Duplicates: a scan of the members while the object is small, a set beyond (built
        // from the members when first needed), so a small object allocates nothing for it.
        let mut many: FxHashSet<Cow<'de, str>> = FxHashSet::default();
        while let Some(key) = map.next_key_seed(Key)? {
            let fresh = if members.len() < SeenKeys::SCAN {
                !members.iter().any(|(k, _)| *k == key)
            } else {
                if many.is_empty() {
                    many.extend(members.iter().map(|(k, _)| k.clone()));
                }
                many.insert(key.clone())
            };
            if !fresh {
                return Err(self.0.duplicate_key(&key));
            }
            let value = map.next_value_seed(Seed(self.0));
            let value = self.0.within(|| key.to_string(), value)?;
            members.push((key, value));
        }
        self.0.leave();
        Ok(J::Obj(members))
    }
}

/// Nodes of one material by name (their index in [`MaterialState::nodes`]); `None` for a
/// node whose reading failed.
type NodesByName<'de> = FxHashMap<Cow<'de, str>, Option<u32>>;

/// One material while its members are read.
struct MaterialState<'de> {
    name: String,
    pointer: String,
    has_nodes: bool,
    /// Its nodes in document order, inserted into the network when the material closes.
    nodes: Vec<Node>,
    by_name: NodesByName<'de>,
    /// Each node read (its index in `nodes`), its name and its connections.
    pending: Vec<(u32, Cow<'de, str>, NodeConns<'de>)>,
    terminals: Option<J<'de>>,
    primvars: Vec<String>,
}

/// A duplicate key of the object at the current path is a serde error (JS002 with position).
fn check_duplicate<'de, E: de::Error>(
    ctx: &Ctx,
    seen: &mut SeenKeys<'de>,
    key: Cow<'de, str>,
) -> Result<(), E> {
    if seen.insert(key.clone()) {
        Ok(())
    } else {
        Err(ctx.duplicate_key(&key))
    }
}

/// Read the value of the current key as a tree (small subtrees only), under `key` in the path.
fn value_tree<'de, A: MapAccess<'de>>(
    ctx: &Ctx,
    map: &mut A,
    key: &str,
) -> Result<J<'de>, A::Error> {
    let value = map.next_value_seed(Seed(ctx));
    ctx.within(|| key.to_string(), value)
}

/// Consume an array where an object is needed (its members are still checked for duplicates).
fn skip_seq<'de, A: SeqAccess<'de>>(ctx: &Ctx, mut seq: A) -> Result<(), A::Error> {
    let mut i = 0usize;
    loop {
        let next = seq.next_element_seed(Seed(ctx));
        if ctx.within(|| i.to_string(), next)?.is_none() {
            return Ok(());
        }
        i += 1;
    }
}

/// `DeserializeSeed` for each visitor listed: it reads any JSON value (and reports the
/// kinds it did not expect itself).
macro_rules! seed_reads_any {
    ($($seed:ty),+ $(,)?) => {$(
        impl<'de> DeserializeSeed<'de> for $seed {
            type Value = <Self as Visitor<'de>>::Value;
            fn deserialize<D: de::Deserializer<'de>>(self, d: D) -> Result<Self::Value, D::Error> {
                d.deserialize_any(self)
            }
        }
    )+};
}

seed_reads_any!(
    Seed<'_>,
    DocSeed<'_, '_, '_, 'de>,
    MaterialsSeed<'_, '_, '_, 'de>,
    MaterialSeed<'_, '_, 'de>,
    NodesSeed<'_, '_, '_, 'de>,
    NodeSeed<'_, '_, '_, 'de, '_>,
    ParamsSeed<'_, '_, '_, 'de, '_>,
    InputsSeed<'_, '_, '_, 'de, '_>,
    ConnsSeed<'_, '_, '_, 'de, '_>,
    ConnSeed<'_, '_, '_, 'de, '_>,
    TypedSeed<'_, '_>,
    ParamSeed<'_, '_, '_, 'de, '_>,
);

/// The visitor methods of a streamed object for every value that is not an object: the
/// visitor's `not_object` records the error, and the value is consumed.
macro_rules! needs_object {
    () => {
        fn visit_bool<E: de::Error>(mut self, _: bool) -> Result<(), E> {
            self.not_object("a boolean");
            Ok(())
        }
        fn visit_i64<E: de::Error>(mut self, _: i64) -> Result<(), E> {
            self.not_object("a number");
            Ok(())
        }
        fn visit_u64<E: de::Error>(mut self, _: u64) -> Result<(), E> {
            self.not_object("a number");
            Ok(())
        }
        fn visit_f64<E: de::Error>(mut self, _: f64) -> Result<(), E> {
            self.not_object("a number");
            Ok(())
        }
        fn visit_str<E: de::Error>(mut self, _: &str) -> Result<(), E> {
            self.not_object("a string");
            Ok(())
        }
        fn visit_unit<E: de::Error>(mut self) -> Result<(), E> {
            self.not_object("null");
            Ok(())
        }
        fn visit_none<E: de::Error>(mut self) -> Result<(), E> {
            self.not_object("null");
            Ok(())
        }
        fn visit_seq<A: SeqAccess<'de>>(mut self, seq: A) -> Result<(), A::Error> {
            self.not_object("an array");
            skip_seq(self.ctx(), seq)
        }
        fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
            f.write_str("a JSON value")
        }
    };
}

/// The document object.
struct DocSeed<'r, 't, 's, 'de>(&'r mut Reader<'t>, Option<&'s mut dyn Split<'de>>);

/// Takes each material's value, unread, in place of the readers of [`MaterialSeed`] (the
/// materials are then read on rayon's pool).
trait Split<'de> {
    /// The `group`-th material (1 for the first), its name and the text of its value.
    fn material(&mut self, group: u32, name: Cow<'de, str>, value: &'de str);
}

impl DocSeed<'_, '_, '_, '_> {
    fn ctx(&self) -> &Ctx {
        &self.0.ctx
    }
    fn not_object(&mut self, kind: &str) {
        self.0.at(0, DOC_VERSION);
        let e = self.0.error(
            "JS002",
            "",
            format!("the document must be an object, found {kind}"),
        );
        self.0.fail(e);
    }
}

impl<'de> Visitor<'de> for DocSeed<'_, '_, '_, 'de> {
    type Value = ();
    needs_object!();
    fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> Result<(), A::Error> {
        let (r, mut split) = (self.0, self.1);
        let mut seen = SeenKeys::default();
        let mut version = None;
        let mut has_materials = false;
        while let Some(key) = map.next_key_seed(Key)? {
            check_duplicate(&r.ctx, &mut seen, key.clone())?;
            match &*key {
                "vstructcNetwork" => version = Some(value_tree(&r.ctx, &mut map, &key)?),
                "materials" => {
                    has_materials = true;
                    let read = map.next_value_seed(MaterialsSeed(&mut *r, split.take()));
                    r.ctx.within(|| key.to_string(), read)?;
                }
                _ => {
                    r.at(0, DOC_KEYS);
                    r.unknown_key(&P::Key(&P::Root(""), &key), &key, "the document");
                    value_tree(&r.ctx, &mut map, &key)?;
                }
            }
        }
        r.at(0, DOC_VERSION);
        r.check_version(version.as_ref());
        if !has_materials {
            r.at(0, DOC_MATERIALS);
            let e = r.error("JS002", "", "missing `materials`");
            r.fail(e);
        }
        Ok(())
    }
}

/// The `materials` object: each material is read and closed in turn.
struct MaterialsSeed<'r, 't, 's, 'de>(&'r mut Reader<'t>, Option<&'s mut dyn Split<'de>>);

impl MaterialsSeed<'_, '_, '_, '_> {
    fn ctx(&self) -> &Ctx {
        &self.0.ctx
    }
    fn not_object(&mut self, kind: &str) {
        self.0.at(0, DOC_MATERIALS);
        let e = self.0.error(
            "JS002",
            "/materials",
            format!("`materials` must be an object, found {kind}"),
        );
        self.0.fail(e);
    }
}

impl<'de> Visitor<'de> for MaterialsSeed<'_, '_, '_, 'de> {
    type Value = ();
    needs_object!();
    fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> Result<(), A::Error> {
        let (r, mut split) = (self.0, self.1);
        let mut seen = SeenKeys::default();
        while let Some(name) = map.next_key_seed(Key)? {
            check_duplicate(&r.ctx, &mut seen, name.clone())?;
            r.materials += 1;
            let group = r.materials;
            if let Some(split) = split.as_deref_mut() {
                let value: &'de RawValue = map.next_value()?;
                split.material(group, name, value.get());
                continue;
            }
            let m = MaterialState::new(&name);
            let read = map.next_value_seed(MaterialSeed {
                r: &mut *r,
                m: Some(m),
                group,
            });
            r.ctx.within(|| name.to_string(), read)?;
        }
        Ok(())
    }
}

impl MaterialState<'_> {
    /// The material `name`, before its members.
    fn new(name: &str) -> Self {
        MaterialState {
            pointer: P::Key(&P::Root("/materials"), name).render(),
            has_nodes: false,
            // Room for a material's usual few nodes without growing.
            nodes: Vec::with_capacity(8),
            by_name: FxHashMap::with_capacity_and_hasher(8, Default::default()),
            pending: Vec::with_capacity(8),
            terminals: None,
            primvars: Vec::new(),
            name: name.to_string(),
        }
    }
}

/// One material object.
struct MaterialSeed<'r, 't, 'de> {
    r: &'r mut Reader<'t>,
    m: Option<MaterialState<'de>>,
    group: u32,
}

impl MaterialSeed<'_, '_, '_> {
    fn ctx(&self) -> &Ctx {
        &self.r.ctx
    }
    fn not_object(&mut self, kind: &str) {
        self.r.at(self.group, MAT_KEYS);
        let pointer = self.m.as_ref().map_or("", |m| m.pointer.as_str());
        let e = self.r.error(
            "JS002",
            pointer,
            format!("a material must be an object, found {kind}"),
        );
        self.r.fail(e);
    }
}

impl<'de> Visitor<'de> for MaterialSeed<'_, '_, 'de> {
    type Value = ();
    needs_object!();
    fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> Result<(), A::Error> {
        let (r, group) = (self.r, self.group);
        let Some(mut m) = self.m else {
            return Ok(());
        };
        let mut seen = SeenKeys::default();
        while let Some(key) = map.next_key_seed(Key)? {
            check_duplicate(&r.ctx, &mut seen, key.clone())?;
            let root = m.pointer.clone();
            let p = P::Key(&P::Root(&root), &key);
            r.at(group, MAT_KEYS);
            match &*key {
                "nodes" => {
                    m.has_nodes = true;
                    let read = map.next_value_seed(NodesSeed {
                        r: &mut *r,
                        m: &mut m,
                        pointer: p.render(),
                        group,
                    });
                    r.ctx.within(|| key.to_string(), read)?;
                }
                "terminals" => {
                    let j = value_tree(&r.ctx, &mut map, &key)?;
                    match r.object(&j, &p, "`terminals`") {
                        Ok(_) => m.terminals = Some(j),
                        Err(e) => r.fail(e),
                    }
                }
                "primvars" => {
                    let j = value_tree(&r.ctx, &mut map, &key)?;
                    match r.primvars(&j, &p) {
                        Ok(v) => m.primvars = v,
                        Err(e) => r.fail(e),
                    }
                }
                _ => {
                    r.unknown_key(&p, &key, "a material");
                    value_tree(&r.ctx, &mut map, &key)?;
                }
            }
        }
        r.finish_material(m, group);
        Ok(())
    }
}

/// The `nodes` object of a material: each node is read (as a small tree) and inserted in turn;
/// its kind is set when the material's terminals are known.
struct NodesSeed<'r, 't, 'm, 'de> {
    r: &'r mut Reader<'t>,
    m: &'m mut MaterialState<'de>,
    pointer: String,
    group: u32,
}

impl NodesSeed<'_, '_, '_, '_> {
    fn ctx(&self) -> &Ctx {
        &self.r.ctx
    }
    fn not_object(&mut self, kind: &str) {
        self.r.at(self.group, MAT_KEYS);
        let e = self.r.error(
            "JS002",
            &self.pointer,
            format!("`nodes` must be an object, found {kind}"),
        );
        self.r.fail(e);
        self.m.has_nodes = false;
    }
}

impl<'de> Visitor<'de> for NodesSeed<'_, '_, '_, 'de> {
    type Value = ();
    needs_object!();
    fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> Result<(), A::Error> {
        let (r, m) = (self.r, self.m);
        // One node's scratch state, reused by the next.
        let mut n = NodeState::default();
        while let Some(name) = map.next_key_seed(Key)? {
            if m.by_name.contains_key(&name) {
                return Err(r.ctx.duplicate_key(&name));
            }
            let nodes = P::Root(&self.pointer);
            let pointer = P::Key(&nodes, &name);
            n.reset();
            let read = map.next_value_seed(NodeSeed {
                r: &mut *r,
                n: &mut n,
                pointer: &pointer,
            });
            r.ctx.within(|| name.to_string(), read)?;
            r.at(self.group, MAT_NODES);
            match r.close_node(&name, &mut n, RequestKind::Pattern, &pointer) {
                Ok((node, conns)) => {
                    let id = m.nodes.len() as u32;
                    m.nodes.push(node);
                    m.pending.push((id, name.clone(), conns));
                    m.by_name.insert(name, Some(id));
                }
                Err(e) => {
                    r.fail(e);
                    m.by_name.insert(name, None);
                }
            }
        }
        Ok(())
    }
}

/// The stages of one node's checks, in the order their findings are reported: the node's own
/// keys, a missing `nodeTypeId`, each parameter (in document order), each input.
const NODE_KEYS: u8 = 0;
const NODE_SHADER: u8 = 1;
const NODE_PARAMS: u8 = 2;
const NODE_INPUTS: u8 = 3;

/// A parameter value read and typed, with its declaration (both may be shared with other
/// parameters).
type Typed = (Arc<Value>, Arc<Decl>);

/// One node while its members stream in. Its findings are kept with their stage (and the
/// parameter's index) and reported when the node closes, in the order of the checks, up to
/// the first error: the same report whatever the order of the keys.
#[derive(Default)]
struct NodeState<'de> {
    shader: Option<Cow<'de, str>>,
    /// The `parameters` keys in document order, and their values once read.
    names: Vec<Sym>,
    values: Vec<Option<Typed>>,
    /// Parameter index by name, once the node has more than [`SCAN_PARAMS`] parameters.
    index: FxHashMap<Sym, usize>,
    /// Shorthand values read before `nodeTypeId` (their type comes from the shader).
    deferred: Vec<(usize, Cow<'de, str>, J<'de>)>,
    /// The `inputConnections` keys in document order, each with its connections.
    inputs: Vec<(Cow<'de, str>, Vec<Conn<'de>>)>,
    /// The input names, once the node has more than [`SCAN_PARAMS`] inputs.
    input_names: FxHashSet<Cow<'de, str>>,
    found: Vec<(u8, usize, Found)>,
}

impl<'de> NodeState<'de> {
    /// Ready for the next node (keeping the buffers).
    fn reset(&mut self) {
        self.shader = None;
        self.names.clear();
        self.values.clear();
        self.index.clear();
        self.deferred.clear();
        self.inputs.clear();
        self.input_names.clear();
        self.found.clear();
    }

    fn push(&mut self, stage: u8, index: usize, found: Found) {
        self.found.push((stage, index, found));
    }

    /// A key's first sighting among the node's parameters (false if a duplicate).
    fn add_parameter(&mut self, name: Sym) -> bool {
        let fresh = if self.names.len() <= SCAN_PARAMS {
            !self.names.contains(&name)
        } else {
            !self.index.contains_key(&name)
        };
        if fresh {
            self.names.push(name);
            self.values.push(None);
            if self.names.len() > SCAN_PARAMS {
                if self.index.is_empty() {
                    self.index = self
                        .names
                        .iter()
                        .enumerate()
                        .map(|(i, &n)| (n, i))
                        .collect();
                } else {
                    self.index.insert(name, self.names.len() - 1);
                }
            }
        }
        fresh
    }

    /// A key's first sighting among the node's `inputConnections`: its index, with no
    /// connections yet (none if a duplicate).
    fn add_input(&mut self, input: Cow<'de, str>) -> Option<usize> {
        let fresh = if self.inputs.len() < SeenKeys::SCAN {
            !self.inputs.iter().any(|(k, _)| *k == input)
        } else {
            if self.input_names.is_empty() {
                self.input_names = self.inputs.iter().map(|(k, _)| k.clone()).collect();
            }
            self.input_names.insert(input.clone())
        };
        fresh.then(|| {
            self.inputs.push((input, Vec::new()));
            self.inputs.len() - 1
        })
    }

    /// The index of the parameter `name`, if `parameters` gives it.
    fn parameter_index(&self, name: Sym) -> Option<usize> {
        if self.names.len() > SCAN_PARAMS {
            self.index.get(&name).copied()
        } else {
            self.names.iter().position(|&n| n == name)
        }
    }
}

/// Keys of a small object whose expected keys are a known few: a flag per expected key and
/// a scan of the others (rare).
#[derive(Default)]
struct FewKeys {
    known: u8,
    others: Vec<Box<str>>,
}

impl FewKeys {
    /// Record `key` (`slot`: the expected key's index, if it is one); false if seen before.
    #[inline]
    fn insert(&mut self, slot: Option<u8>, key: &str) -> bool {
        match slot {
            Some(i) => {
                let bit = 1u8 << i;
                let fresh = self.known & bit == 0;
                self.known |= bit;
                fresh
            }
            None => {
                if self.others.iter().any(|k| &**k == key) {
                    return false;
                }
                self.others.push(key.into());
                true
            }
        }
    }
}

/// One node object, read straight into a [`NodeState`].
struct NodeSeed<'r, 't, 'n, 'de, 'p> {
    r: &'r mut Reader<'t>,
    n: &'n mut NodeState<'de>,
    pointer: &'p P<'p>,
}

impl NodeSeed<'_, '_, '_, '_, '_> {
    fn ctx(&self) -> &Ctx {
        &self.r.ctx
    }
    fn not_object(&mut self, kind: &str) {
        let e = self.r.error(
            "JS002",
            &self.pointer.render(),
            format!("a node must be an object, found {kind}"),
        );
        self.n.push(NODE_KEYS, 0, Found::Error(e));
    }
}

impl<'de> Visitor<'de> for NodeSeed<'_, '_, '_, 'de, '_> {
    type Value = ();
    needs_object!();
    fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> Result<(), A::Error> {
        let (r, n, pointer) = (self.r, self.n, self.pointer);
        let mut seen = FewKeys::default();
        while let Some(key) = map.next_key_seed(Key)? {
            let slot = match &*key {
                "nodeTypeId" => Some(0),
                "parameters" => Some(1),
                "inputConnections" => Some(2),
                _ => None,
            };
            if !seen.insert(slot, &key) {
                return Err(r.ctx.duplicate_key(&key));
            }
            let p = P::Key(pointer, &key);
            match slot {
                Some(0) => match value_tree(&r.ctx, &mut map, &key)? {
                    J::Str(s) => n.shader = Some(s),
                    other => {
                        let e = r.error(
                            "JS002",
                            &p.render(),
                            format!("`nodeTypeId` must be a string, found {}", other.kind()),
                        );
                        n.push(NODE_KEYS, 0, Found::Error(e));
                    }
                },
                Some(1) => {
                    let read = map.next_value_seed(ParamsSeed {
                        r: &mut *r,
                        n: &mut *n,
                        pointer: &p,
                    });
                    r.ctx.within(|| key.to_string(), read)?;
                }
                Some(_) => {
                    let read = map.next_value_seed(InputsSeed {
                        r: &mut *r,
                        n: &mut *n,
                        pointer: &p,
                    });
                    r.ctx.within(|| key.to_string(), read)?;
                }
                None => {
                    let d = r.unknown_key_warning(&p, &key, "a node");
                    n.push(NODE_KEYS, 0, Found::Warning(d));
                    value_tree(&r.ctx, &mut map, &key)?;
                }
            }
        }
        Ok(())
    }
}

/// The `parameters` object of a node: each parameter is typed as it is read.
struct ParamsSeed<'r, 't, 'n, 'de, 'p> {
    r: &'r mut Reader<'t>,
    n: &'n mut NodeState<'de>,
    pointer: &'p P<'p>,
}

impl ParamsSeed<'_, '_, '_, '_, '_> {
    fn ctx(&self) -> &Ctx {
        &self.r.ctx
    }
    fn not_object(&mut self, kind: &str) {
        not_an_object(self.r, self.n, self.pointer, "parameters", kind);
    }
}

impl<'de> Visitor<'de> for ParamsSeed<'_, '_, '_, 'de, '_> {
    type Value = ();
    needs_object!();
    fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> Result<(), A::Error> {
        let (r, n, pointer) = (self.r, self.n, self.pointer);
        while let Some(name) = map.next_key_seed(Key)? {
            let sym = Sym::new(&name);
            if !n.add_parameter(sym) {
                return Err(r.ctx.duplicate_key(&name));
            }
            let p = P::Key(pointer, &name);
            let index = n.names.len() - 1;
            if r.remember {
                let value: &'de RawValue = map.next_value()?;
                let seed = ParamSeed {
                    r: &mut *r,
                    n: &mut *n,
                    index,
                    name: &name,
                    pointer: &p,
                };
                seed.remembered(sym, value.get())
                    .map_err(de::Error::custom)?;
                continue;
            }
            let read = map.next_value_seed(ParamSeed {
                r: &mut *r,
                n: &mut *n,
                index,
                name: &name,
                pointer: &p,
            });
            r.ctx.within(|| name.to_string(), read)?;
        }
        Ok(())
    }
}

/// One parameter: the canonical `{ "type", "value" }` object, or a bare (shorthand) value.
struct ParamSeed<'r, 't, 'n, 'de, 'p> {
    r: &'r mut Reader<'t>,
    n: &'n mut NodeState<'de>,
    index: usize,
    name: &'p Cow<'de, str>,
    pointer: &'p P<'p>,
}

impl<'de> ParamSeed<'_, '_, '_, 'de, '_> {
    /// The parameter `sym` whose value's text is `text`: what a parameter of that name and
    /// text gave before if it was read without a finding, else `text` read alone (and
    /// remembered if it is the canonical form and gave no finding). Reading `text` alone
    /// fails where reading it in the document may report an error of serde_json or might
    /// (a deep tree): the document is then read again without remembering.
    fn remembered(self, sym: Sym, text: &'de str) -> Result<(), &'static str> {
        let key = sym.as_str().as_ptr() as usize;
        let hash = text_hash(text.as_bytes());
        if let Some(typed) = self.r.memo.params.recall(key, text.as_bytes(), hash) {
            self.n.values[self.index] = Some(typed.clone());
            return Ok(());
        }
        let (r, n, index) = (&mut *self.r, &mut *self.n, self.index);
        let (found, deferred) = (n.found.len(), n.deferred.len());
        let mut de = serde_json::Deserializer::from_str(text);
        let seed = ParamSeed {
            r: &mut *r,
            n: &mut *n,
            index,
            name: self.name,
            pointer: self.pointer,
        };
        let read = seed.deserialize(&mut de).and_then(|()| de.end());
        if read.is_err() || r.ctx.deepest.get() > MAX_TREE_DEPTH {
            return Err("a parameter read alone needs the document");
        }
        if text.starts_with('{')
            && n.found.len() == found
            && n.deferred.len() == deferred
            && r.memo.params.len() < MAX_REMEMBERED_PARAMS
            && let Some(typed) = &n.values[index]
        {
            r.memo
                .params
                .remember(key, text.as_bytes(), hash, typed.clone());
        }
        Ok(())
    }

    /// A shorthand value: typed now if the shader is known, else when the node closes.
    fn bare<E>(self, j: J<'de>) -> Result<(), E> {
        match &self.n.shader {
            Some(shader) => {
                let read = self.r.shorthand(shader, self.name, &j, self.pointer);
                self.n.settle(self.index, read);
            }
            None => self.n.deferred.push((self.index, self.name.clone(), j)),
        }
        Ok(())
    }
}

impl<'de> NodeState<'de> {
    /// Keep parameter `index`'s value, or its error.
    #[inline]
    fn settle(&mut self, index: usize, read: Result<Typed, Error>) {
        match read {
            Ok(typed) => self.values[index] = Some(typed),
            Err(e) => self.push(NODE_PARAMS, index, Found::Error(e)),
        }
    }
}

/// The `inputConnections` object of a node: each input's connections as they are read.
struct InputsSeed<'r, 't, 'n, 'de, 'p> {
    r: &'r mut Reader<'t>,
    n: &'n mut NodeState<'de>,
    pointer: &'p P<'p>,
}

impl InputsSeed<'_, '_, '_, '_, '_> {
    fn ctx(&self) -> &Ctx {
        &self.r.ctx
    }
    fn not_object(&mut self, kind: &str) {
        not_an_object(self.r, self.n, self.pointer, "inputConnections", kind);
    }
}

/// JS002 for a node's `key` (at `pointer`) holding `kind` instead of an object: an error of
/// the node's own keys.
fn not_an_object(
    r: &mut Reader<'_>,
    n: &mut NodeState<'_>,
    pointer: &P<'_>,
    key: &str,
    kind: &str,
) {
    let e = r.error(
        "JS002",
        &pointer.render(),
        format!("`{key}` must be an object, found {kind}"),
    );
    n.push(NODE_KEYS, 0, Found::Error(e));
}

impl<'de> Visitor<'de> for InputsSeed<'_, '_, '_, 'de, '_> {
    type Value = ();
    needs_object!();
    fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> Result<(), A::Error> {
        let (r, n, pointer) = (self.r, self.n, self.pointer);
        while let Some(input) = map.next_key_seed(Key)? {
            let Some(index) = n.add_input(input.clone()) else {
                return Err(r.ctx.duplicate_key(&input));
            };
            let p = P::Key(pointer, &input);
            let read = map.next_value_seed(ConnsSeed {
                r: &mut *r,
                n: &mut *n,
                index,
                input: &input,
                pointer: &p,
            });
            r.ctx.within(|| input.to_string(), read)?;
        }
        Ok(())
    }
}

/// The connection list of one input.
struct ConnsSeed<'r, 't, 'n, 'de, 'p> {
    r: &'r mut Reader<'t>,
    n: &'n mut NodeState<'de>,
    index: usize,
    input: &'p str,
    pointer: &'p P<'p>,
}

impl ConnsSeed<'_, '_, '_, '_, '_> {
    fn not_array<E>(self, kind: &str) -> Result<(), E> {
        let e = self.r.error(
            "JS002",
            &self.pointer.render(),
            format!(
                "connections of `{}` must be an array, found {kind}",
                self.input
            ),
        );
        self.n.push(NODE_INPUTS, self.index, Found::Error(e));
        Ok(())
    }
}

impl<'de> Visitor<'de> for ConnsSeed<'_, '_, '_, 'de, '_> {
    type Value = ();
    fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str("a JSON value")
    }
    fn visit_bool<E>(self, _: bool) -> Result<(), E> {
        self.not_array("a boolean")
    }
    fn visit_i64<E>(self, _: i64) -> Result<(), E> {
        self.not_array("a number")
    }
    fn visit_u64<E>(self, _: u64) -> Result<(), E> {
        self.not_array("a number")
    }
    fn visit_f64<E>(self, _: f64) -> Result<(), E> {
        self.not_array("a number")
    }
    fn visit_str<E>(self, _: &str) -> Result<(), E> {
        self.not_array("a string")
    }
    fn visit_unit<E>(self) -> Result<(), E> {
        self.not_array("null")
    }
    fn visit_none<E>(self) -> Result<(), E> {
        self.not_array("null")
    }
    fn visit_map<A: MapAccess<'de>>(self, map: A) -> Result<(), A::Error> {
        Seed(&self.r.ctx).visit_map(map)?;
        self.not_array("an object")
    }
    fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<(), A::Error> {
        let (r, n, index, pointer) = (self.r, self.n, self.index, self.pointer);
        let mut i = 0usize;
        loop {
            let p = P::Index(pointer, i);
            let next = seq.next_element_seed(ConnSeed {
                r: &mut *r,
                n: &mut *n,
                index,
                pointer: &p,
            });
            match r.ctx.within(|| i.to_string(), next)? {
                Some(Some(conn)) => n.inputs[index].1.push(conn),
                Some(None) => {}
                None => return Ok(()),
            }
            i += 1;
        }
    }
}

/// One connection of an input (`None` when it has an error, kept in the node's findings).
struct ConnSeed<'r, 't, 'n, 'de, 'p> {
    r: &'r mut Reader<'t>,
    n: &'n mut NodeState<'de>,
    index: usize,
    pointer: &'p P<'p>,
}

impl ConnSeed<'_, '_, '_, '_, '_> {
    fn fail<'de, E>(self, kind: &str) -> Result<Option<Conn<'de>>, E> {
        let e = self.r.error(
            "JS002",
            &self.pointer.render(),
            format!("a connection must be an object, found {kind}"),
        );
        self.n.push(NODE_INPUTS, self.index, Found::Error(e));
        Ok(None)
    }
}

impl<'de> Visitor<'de> for ConnSeed<'_, '_, '_, 'de, '_> {
    type Value = Option<Conn<'de>>;
    fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str("a JSON value")
    }
    fn visit_bool<E>(self, _: bool) -> Result<Self::Value, E> {
        self.fail("a boolean")
    }
    fn visit_i64<E>(self, _: i64) -> Result<Self::Value, E> {
        self.fail("a number")
    }
    fn visit_u64<E>(self, _: u64) -> Result<Self::Value, E> {
        self.fail("a number")
    }
    fn visit_f64<E>(self, _: f64) -> Result<Self::Value, E> {
        self.fail("a number")
    }
    fn visit_str<E>(self, _: &str) -> Result<Self::Value, E> {
        self.fail("a string")
    }
    fn visit_unit<E>(self) -> Result<Self::Value, E> {
        self.fail("null")
    }
    fn visit_none<E>(self) -> Result<Self::Value, E> {
        self.fail("null")
    }
    fn visit_seq<A: SeqAccess<'de>>(self, seq: A) -> Result<Self::Value, A::Error> {
        skip_seq(&self.r.ctx, seq)?;
        self.fail("an array")
    }
    fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> Result<Self::Value, A::Error> {
        let (r, n, index, pointer) = (self.r, self.n, self.index, self.pointer);
        let mut seen = FewKeys::default();
        let mut node = None;
        let mut output = None;
        let mut failed = false;
        while let Some(key) = map.next_key_seed(Key)? {
            let slot = match &*key {
                "upstreamNode" => Some(0),
                "upstreamOutputName" => Some(1),
                _ => None,
            };
            if !seen.insert(slot, &key) {
                return Err(r.ctx.duplicate_key(&key));
            }
            let j = value_tree(&r.ctx, &mut map, &key)?;
            let p = P::Key(pointer, &key);
            match (slot, j) {
                (Some(0), J::Str(s)) => node = Some(s),
                (Some(_), J::Str(s)) => output = Some(s),
                (Some(_), other) => {
                    let what = if slot == Some(0) {
                        "`upstreamNode`"
                    } else {
                        "`upstreamOutputName`"
                    };
                    let e = r.error(
                        "JS002",
                        &p.render(),
                        format!("{what} must be a string, found {}", other.kind()),
                    );
                    n.push(NODE_INPUTS, index, Found::Error(e));
                    failed = true;
                }
                (None, _) => {
                    let d = r.unknown_key_warning(&p, &key, "a connection");
                    n.push(NODE_INPUTS, index, Found::Warning(d));
                }
            }
        }
        if failed {
            return Ok(None);
        }
        let Some(node) = node else {
            let e = r.error(
                "JS002",
                &pointer.render(),
                "connection without `upstreamNode`",
            );
            n.push(NODE_INPUTS, index, Found::Error(e));
            return Ok(None);
        };
        let Some(output) = output else {
            let e = r.error(
                "JS002",
                &pointer.render(),
                "connection without `upstreamOutputName` (use \"\" for a whole-node reference)",
            );
            n.push(NODE_INPUTS, index, Found::Error(e));
            return Ok(None);
        };
        Ok(Some(Conn {
            node,
            output: (!output.is_empty()).then_some(output),
        }))
    }
}

/// A canonical parameter's value, typed as it is read when its `type` came first, else
/// kept as a tree until the `type` is known.
enum ValueRead<'de> {
    Tree(J<'de>),
    Typed(Result<Value, String>),
}

/// A value of a known type, converted as it is read ([`to_value`]'s result, without a tree
/// for an array of numbers).
struct TypedSeed<'c, 't>(&'c Ctx, &'t Type);

impl<'de> Visitor<'de> for TypedSeed<'_, '_> {
    type Value = Result<Value, String>;
    fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str("a JSON value")
    }
    fn visit_bool<E>(self, v: bool) -> Result<Self::Value, E> {
        Ok(to_value(self.1, &J::Bool(v)))
    }
    fn visit_i64<E>(self, v: i64) -> Result<Self::Value, E> {
        Ok(to_value(self.1, &J::Num(Num::I(v))))
    }
    fn visit_u64<E>(self, v: u64) -> Result<Self::Value, E> {
        Ok(to_value(self.1, &J::Num(Num::U(v))))
    }
    fn visit_f64<E>(self, v: f64) -> Result<Self::Value, E> {
        Ok(to_value(self.1, &J::Num(Num::F(v))))
    }
    fn visit_borrowed_str<E>(self, v: &'de str) -> Result<Self::Value, E> {
        Ok(to_value(self.1, &J::Str(Cow::Borrowed(v))))
    }
    fn visit_str<E>(self, v: &str) -> Result<Self::Value, E> {
        Ok(to_value(self.1, &J::Str(Cow::Borrowed(v))))
    }
    fn visit_unit<E>(self) -> Result<Self::Value, E> {
        Ok(to_value(self.1, &J::Null))
    }
    fn visit_none<E>(self) -> Result<Self::Value, E> {
        Ok(to_value(self.1, &J::Null))
    }
    fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<Self::Value, A::Error> {
        // Up to a matrix's sixteen items without a heap block.
        let mut items: smallvec::SmallVec<[J<'de>; 16]> = smallvec::SmallVec::new();
        loop {
            let next = seq.next_element_seed(Seed(self.0));
            match self.0.within(|| items.len().to_string(), next)? {
                Some(v) => items.push(v),
                None => return Ok(to_value_seq(self.1, &items)),
            }
        }
    }
    fn visit_map<A: MapAccess<'de>>(self, map: A) -> Result<Self::Value, A::Error> {
        let j = Seed(self.0).visit_map(map)?;
        Ok(to_value(self.1, &j))
    }
}

impl<'de> Visitor<'de> for ParamSeed<'_, '_, '_, 'de, '_> {
    type Value = ();
    fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str("a JSON value")
    }
    fn visit_bool<E>(self, v: bool) -> Result<(), E> {
        self.bare(J::Bool(v))
    }
    fn visit_i64<E>(self, v: i64) -> Result<(), E> {
        self.bare(J::Num(Num::I(v)))
    }
    fn visit_u64<E>(self, v: u64) -> Result<(), E> {
        self.bare(J::Num(Num::U(v)))
    }
    fn visit_f64<E>(self, v: f64) -> Result<(), E> {
        self.bare(J::Num(Num::F(v)))
    }
    fn visit_borrowed_str<E>(self, v: &'de str) -> Result<(), E> {
        self.bare(J::Str(Cow::Borrowed(v)))
    }
    fn visit_str<E>(self, v: &str) -> Result<(), E> {
        self.bare(J::Str(Cow::Owned(v.to_string())))
    }
    fn visit_string<E>(self, v: String) -> Result<(), E> {
        self.bare(J::Str(Cow::Owned(v)))
    }
    fn visit_unit<E>(self) -> Result<(), E> {
        self.bare(J::Null)
    }
    fn visit_none<E>(self) -> Result<(), E> {
        self.bare(J::Null)
    }
    fn visit_seq<A: SeqAccess<'de>>(self, seq: A) -> Result<(), A::Error> {
        let j = Seed(&self.r.ctx).visit_seq(seq)?;
        self.bare(j)
    }
    fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> Result<(), A::Error> {
        let (r, n, index, pointer) = (self.r, self.n, self.index, self.pointer);
        let mut seen = FewKeys::default();
        let mut ty = None;
        let mut decl = None;
        let mut value = None;
        while let Some(key) = map.next_key_seed(Key)? {
            let slot = match &*key {
                "type" => Some(0),
                "value" => Some(1),
                _ => None,
            };
            if !seen.insert(slot, &key) {
                return Err(r.ctx.duplicate_key(&key));
            }
            if slot == Some(1) {
                value = Some(match &decl {
                    Some(d) => {
                        let d: &Arc<Decl> = d;
                        let read = map.next_value_seed(TypedSeed(&r.ctx, &d.ty));
                        ValueRead::Typed(r.ctx.within(|| key.to_string(), read)?)
                    }
                    None => ValueRead::Tree(value_tree(&r.ctx, &mut map, &key)?),
                });
                continue;
            }
            let j = value_tree(&r.ctx, &mut map, &key)?;
            match slot {
                Some(_) => match j {
                    J::Str(s) => {
                        decl = r.inline_decl(&s);
                        ty = Some(s);
                    }
                    other => {
                        let e = r.error(
                            "JS002",
                            &P::Key(pointer, &key).render(),
                            format!("`type` must be a string, found {}", other.kind()),
                        );
                        n.push(NODE_PARAMS, index, Found::Error(e));
                    }
                },
                None => {
                    let d = r.unknown_key_warning(&P::Key(pointer, &key), &key, "a parameter");
                    n.push(NODE_PARAMS, index, Found::Warning(d));
                }
            }
        }
        let read = r.canonical(self.name, ty.as_deref(), decl, value, pointer);
        n.settle(index, read);
        Ok(())
    }
}

/// Read a JSON network.
///
/// `path` names the input in diagnostics; `types` supplies declared types for shorthand
/// values (JS006 when a parameter is not declared; `Sync`, as the materials of a large input
/// are read on rayon's pool). Warnings go to `diags`; the first error is returned.
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
    types: &(dyn ParamTypes + Sync),
    diags: &mut Diagnostics,
) -> Result<Network, Error> {
    parse_json_limited(bytes, path, types, &Limits::default(), diags)
}

/// [`parse_json`] within `limits`: the input's size, its nodes, each node's parameters and
/// each input's connections ([`Network::check_limits`]); exceeding one is [`Error::Limit`].
#[cfg_attr(feature = "testkit", visibility::make(pub))]
pub(crate) fn parse_json_limited(
    bytes: &[u8],
    path: &str,
    types: &(dyn ParamTypes + Sync),
    limits: &Limits,
    diags: &mut Diagnostics,
) -> Result<Network, Error> {
    let file: Arc<str> = Arc::from(path);
    limits
        .check(Limit::NetworkFileBytes, bytes.len() as u64)
        .map_err(|e| e.at(Location::file(file.clone())))?;
    // Valid UTF-8 (checked once, in bulk) is read as text, which spares serde_json a check
    // per string; other input goes through the byte reader, which reports where it breaks.
    let text = std::str::from_utf8(bytes).ok();
    #[cfg(feature = "parallel")]
    if let Some(text) = text
        && bytes.len() >= POOL_MIN_BYTES
        && crate::schedule::pool_can_help()
        && let Some((net, found)) = read_on_pool(text, &file, types, limits)
    {
        return report(net, found, limits, diags);
    }
    let read = |remember: bool| {
        let mut net = Network::new();
        net.reserve_for_input(bytes.len(), BYTES_PER_NODE, limits.nodes);
        let mut r = Reader::new(file.clone(), types, Some(net));
        r.remember = remember;
        let read = match text {
            Some(text) => {
                let mut de = serde_json::Deserializer::from_str(text);
                DocSeed(&mut r, None)
                    .deserialize(&mut de)
                    .and_then(|()| de.end())
            }
            None => {
                let mut de = serde_json::Deserializer::from_slice(bytes);
                DocSeed(&mut r, None)
                    .deserialize(&mut de)
                    .and_then(|()| de.end())
            }
        };
        (read, r)
    };
    // Remembering parameters reads some alone: an error is reported as the document gives it.
    let (read, r) = match read(true) {
        (Ok(()), r) => (Ok(()), r),
        (Err(_), _) => read(false),
    };
    if let Err(e) = read {
        return Err(syntax_error(&e, bytes, &file, &r.ctx));
    }
    report(r.net.unwrap_or_default(), r.found, limits, diags)
}

/// Inputs from this size on are read on rayon's pool (with the `parallel` feature and more
/// than one thread): below, handing materials to the pool costs about what it saves.
#[cfg(feature = "parallel")]
const POOL_MIN_BYTES: usize = 1 << 20;

/// Materials per task on the pool.
#[cfg(feature = "parallel")]
const POOL_BATCH: usize = 64;

/// Value trees nested deeper than this within a material or a parameter read alone send the
/// document to the reading without either: serde_json's nesting limit counts the levels above
/// them too, and a value taken unread is not held to it.
const MAX_TREE_DEPTH: u32 = 64;

/// The materials of one task on the pool: what the network receives and their findings, or
/// `None` when one of them needs the reading on the calling thread.
#[cfg(feature = "parallel")]
type Batch = Option<(Vec<MaterialOut>, Vec<(Order, Found)>)>;

/// Reads `text` with its materials on rayon's pool: one task reads the document, taking each
/// material's value unread ([`Split`]), and hands the materials in batches to the pool, whose
/// threads read them with the visitors of the one-thread reading; that task then adds the
/// batches to the network in document order as they come. `None` when the one-thread reading
/// must decide: any error of serde_json (its line and column are the whole text's) or a deep
/// value tree.
#[cfg(feature = "parallel")]
fn read_on_pool(
    text: &str,
    file: &Arc<str>,
    types: &(dyn ParamTypes + Sync),
    limits: &Limits,
) -> Option<(Network, Vec<(Order, Found)>)> {
    struct Spawner<'a, 's, 'de> {
        scope: &'a rayon::Scope<'s>,
        batch: Vec<(u32, Cow<'de, str>, &'de str)>,
        /// Batches spawned so far.
        spawned: usize,
        /// The batches read, by their number.
        done: &'s Mutex<FxHashMap<usize, Batch>>,
        memos: &'s Mutex<Vec<Memo>>,
        file: &'s Arc<str>,
        types: &'s (dyn ParamTypes + Sync),
    }
    impl<'de: 's, 's> Spawner<'_, 's, 'de> {
        fn flush(&mut self) {
            let batch = std::mem::replace(&mut self.batch, Vec::with_capacity(POOL_BATCH));
            if batch.is_empty() {
                return;
            }
            let k = self.spawned;
            self.spawned += 1;
            let (done, memos, file, types) = (self.done, self.memos, self.file, self.types);
            self.scope.spawn(move |_| {
                let read = read_batch(batch, memos, file, types);
                lock(done).insert(k, read);
            });
        }
    }
    impl<'de: 's, 's> Split<'de> for Spawner<'_, 's, 'de> {
        fn material(&mut self, group: u32, name: Cow<'de, str>, value: &'de str) {
            self.batch.push((group, name, value));
            if self.batch.len() == POOL_BATCH {
                self.flush();
            }
        }
    }
    let done = Mutex::new(FxHashMap::default());
    let memos = Mutex::new(Vec::new());
    let mut doc = Reader::new(file.clone(), types, None);
    let mut net = Network::new();
    net.reserve_for_input(text.len(), BYTES_PER_NODE, limits.nodes);
    let mut found = Vec::new();
    let read = rayon::scope(|scope| {
        let mut spawner = Spawner {
            scope,
            batch: Vec::with_capacity(POOL_BATCH),
            spawned: 0,
            done: &done,
            memos: &memos,
            file,
            types,
        };
        let mut de = serde_json::Deserializer::from_str(text);
        let read = DocSeed(&mut doc, Some(&mut spawner))
            .deserialize(&mut de)
            .and_then(|()| de.end());
        spawner.flush();
        read.ok()?;
        // The batches enter the network in order while the pool reads the next ones; this
        // thread reads one of those while the batch it needs is not there yet.
        for k in 0..spawner.spawned {
            let batch = loop {
                if let Some(batch) = lock(&done).remove(&k) {
                    break batch;
                }
                if rayon::yield_now() != Some(rayon::Yield::Executed) {
                    std::thread::yield_now();
                }
            };
            let (outs, batch_found) = batch?;
            for out in outs {
                out.add_to(&mut net);
            }
            found.extend(batch_found);
        }
        Some(())
    });
    read?;
    doc.found.extend(found);
    Some((net, doc.found))
}

/// `mutex`, locked (a panic while it was locked panics the pool's scope anyway).
#[cfg(feature = "parallel")]
fn lock<T>(mutex: &Mutex<T>) -> std::sync::MutexGuard<'_, T> {
    mutex.lock().unwrap_or_else(|e| e.into_inner())
}

/// Reads the materials of `batch` (each its group, its name and its value's text) on a
/// thread of the pool ([`read_on_pool`]).
#[cfg(feature = "parallel")]
fn read_batch(
    batch: Vec<(u32, Cow<'_, str>, &str)>,
    memos: &Mutex<Vec<Memo>>,
    file: &Arc<str>,
    types: &(dyn ParamTypes + Sync),
) -> Batch {
    let mut r = Reader::new(file.clone(), types, None);
    // What an earlier task remembered (as many memos as tasks ever ran at once).
    r.memo = lock(memos).pop().unwrap_or_default();
    let read = || {
        for (group, name, value) in batch {
            let mut de = serde_json::Deserializer::from_str(value);
            let m = Some(MaterialState::new(&name));
            let seed = MaterialSeed {
                r: &mut r,
                m,
                group,
            };
            seed.deserialize(&mut de).and_then(|()| de.end()).ok()?;
        }
        Some(())
    };
    let read = read();
    lock(memos).push(std::mem::take(&mut r.memo));
    read?;
    (r.ctx.deepest.get() <= MAX_TREE_DEPTH).then_some((r.done, r.found))
}

/// Bytes of JSON per node assumed when room for the nodes is reserved: a node of the bench
/// scene takes about 1 KB as the writer lays it out, and a terser file outgrows the room only
/// by a doubling or two.
const BYTES_PER_NODE: usize = 512;

/// The end of a read whose text is valid JSON: the findings in the order of the checks, not
/// of the document (a material's terminals are checked before its nodes, the version before
/// the materials; module docs), warnings up to the first error, then the limits.
fn report(
    net: Network,
    mut found: Vec<(Order, Found)>,
    limits: &Limits,
    diags: &mut Diagnostics,
) -> Result<Network, Error> {
    found.sort_by_key(|(order, _)| *order);
    for (_, found) in found {
        match found {
            Found::Warning(d) => diags.push(d),
            Found::Error(e) => return Err(e),
        }
    }
    net.check_limits(limits)?;
    Ok(net)
}

/// A syntax error (JS001) or a duplicate key (JS002), with line and column.
fn syntax_error(e: &serde_json::Error, bytes: &[u8], file: &Arc<str>, ctx: &Ctx) -> Error {
    let mut loc = Location::new(
        file.clone(),
        e.line() as u32,
        char_column(bytes, e.line(), e.column()),
    );
    let duplicate = ctx.take_pointer();
    let d = match (e.classify(), duplicate) {
        (serde_json::error::Category::Data, Some(pointer)) => {
            loc.pointer = Some(pointer);
            Diagnostic::error("JS002", strip_position(e))
        }
        _ => Diagnostic::error("JS001", format!("not valid JSON: {}", strip_position(e))),
    };
    d.at(loc).into()
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

/// Up to this many parameters, an input finds its parameter by a scan rather than a map.
const SCAN_PARAMS: usize = 16;

/// The connections of one node, per parameter index (with the input's name, for the
/// pointer of a diagnostic), waiting to be bound.
type NodeConns<'de> = Vec<(usize, Cow<'de, str>, Vec<Conn<'de>>)>;

/// A parsed connection object.
struct Conn<'de> {
    node: Cow<'de, str>,
    output: Option<Cow<'de, str>>,
}

/// Where a diagnostic falls in the order of the checks: the document's checks (group 0) come
/// before its materials' (group 1 + the material's index); within a group, `phase` orders the
/// kinds of check and `seq` is the document order.
#[derive(Debug, Default, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
struct Order {
    group: u32,
    phase: u8,
    seq: u32,
}

/// Phases of the document's checks.
const DOC_VERSION: u8 = 0;
const DOC_KEYS: u8 = 1;
const DOC_MATERIALS: u8 = 2;
/// Phases of a material's checks.
const MAT_KEYS: u8 = 0;
const MAT_NO_NODES: u8 = 1;
const MAT_TERMINALS: u8 = 2;
const MAT_NODES: u8 = 3;
const MAT_BIND: u8 = 4;

/// A diagnostic found while reading, reported once the whole text is known to be valid JSON.
enum Found {
    Warning(Diagnostic),
    Error(Error),
}

/// A material read: its nodes, the connections between them (by their index among its nodes),
/// its terminals; what the network receives when the material closes ([`MaterialOut::add_to`]).
struct MaterialOut {
    /// Its nodes in document order.
    nodes: Vec<Node>,
    /// Node kinds set by its terminals.
    kinds: Vec<(u32, RequestKind)>,
    /// Each input's connections: the node, the parameter's index, the links.
    links: Vec<(u32, usize, Vec<LocalLink>)>,
    terminals: Vec<(String, LocalLink)>,
    name: String,
    primvars: Vec<String>,
    location: Option<Location>,
}

/// A connection of a material not yet in a network: to one of its nodes (by index) or
/// dangling.
enum LocalLink {
    Node(u32, Option<Sym>),
    Missing(Link),
}

impl LocalLink {
    /// The link, the material's nodes having received the ids `ids`.
    fn link(self, ids: &[NodeId]) -> Link {
        match self {
            LocalLink::Node(k, output) => Link::node_sym(ids[k as usize], output),
            LocalLink::Missing(link) => link,
        }
    }
}

impl MaterialOut {
    /// Inserts the material's nodes, connections and the material into `net`: the same calls
    /// in the same order on the calling thread and on rayon's pool.
    fn add_to(self, net: &mut Network) {
        let ids: Vec<NodeId> = self.nodes.into_iter().map(|n| net.insert_node(n)).collect();
        for (k, kind) in self.kinds {
            net.set_node_kind(ids[k as usize], kind);
        }
        for (k, param, links) in self.links {
            let links = links.into_iter().map(|l| l.link(&ids)).collect();
            net.push_source_links(ids[k as usize], param, links);
        }
        let terminals = self
            .terminals
            .into_iter()
            .map(|(name, l)| Terminal {
                name,
                link: l.link(&ids),
            })
            .collect();
        net.materials_mut().push(Material {
            name: self.name,
            terminals,
            nodes: MaterialNodes::Explicit(ids),
            primvars: self.primvars,
            location: self.location,
        });
    }
}

/// Type strings of the canonical form whose declarations a reader finds by a scan.
const FEW_DECLS: usize = 8;

/// The network being built while serde reads the text.
struct Reader<'t> {
    file: Arc<str>,
    /// Declared types for shorthand values.
    types: &'t (dyn ParamTypes + Sync),
    /// Where closed materials go: into the network, or (`None`, on rayon's pool) to `done`.
    net: Option<Network>,
    done: Vec<MaterialOut>,
    /// Whether parameters are read through [`Memo::params`].
    remember: bool,
    /// What it remembers of what it read.
    memo: Memo,
    /// The key path, for the pointer of a duplicate key.
    ctx: Ctx,
    found: Vec<(Order, Found)>,
    /// The group and phase of the check running now; `seq` counts every finding.
    order: Order,
    /// Materials read so far.
    materials: u32,
}

/// What a [`Reader`] remembers of what it read.
#[derive(Default)]
struct Memo {
    /// One declaration per type string of the canonical form, shared by its parameters: the
    /// first [`FEW_DECLS`] found by a scan (a document uses a few), the others by a map.
    few_decls: Vec<Arc<Decl>>,
    inline_decls: FxHashMap<Box<str>, Arc<Decl>>,
    /// One declaration per declared type of the shorthand form, shared likewise.
    declared_decls: FxHashMap<Type, Arc<Decl>>,
    /// Values read before (arrays aside), one per slot of their hash: parameters with the
    /// same value, bit for bit, mostly share one block.
    values: Vec<Option<Arc<Value>>>,
    /// One copy of each shader id.
    shaders: FxHashSet<Arc<str>>,
    /// Parameters of the canonical form read without a finding, under their name, by the
    /// text of their value: the parameters that repeat both share their declaration and
    /// value, and skip reading them.
    params: Remembered<Typed>,
}

/// Slots of [`Memo::values`].
const VALUE_SLOTS: usize = 1 << 12;

impl Memo {
    /// `value` in a block shared with the parameter read last with the same hash, if its
    /// value is the same.
    fn share(&mut self, value: Value) -> Arc<Value> {
        let Some(hash) = value_hash(&value) else {
            return Arc::new(value);
        };
        if self.values.is_empty() {
            self.values.resize(VALUE_SLOTS, None);
        }
        let slot = &mut self.values[(hash >> 52) as usize % VALUE_SLOTS];
        match slot {
            Some(shared) if same_bits(shared, &value) => shared.clone(),
            _ => slot.insert(Arc::new(value)).clone(),
        }
    }
}

/// The hash of a value that is not an array, over its bits (`None` for an array).
fn value_hash(value: &Value) -> Option<u64> {
    let words = |v: &[f32]| {
        v.iter().fold(v.len() as u64, |h, x| {
            (h ^ u64::from(x.to_bits())).wrapping_mul(0x9e37_79b9_7f4a_7c15)
        })
    };
    Some(match value {
        Value::Int(i) => words(&[f32::from_bits(*i as u32), 0.0]),
        Value::Float(x) => words(&[*x]),
        Value::Triple(_, v) => words(v),
        Value::HPoint(v) => words(v),
        Value::Matrix(v) => words(v),
        Value::Bool(b) => words(&[f32::from_bits(u32::from(*b)), 0.0, 0.0, 0.0, 0.0]),
        Value::Str(s) | Value::Token(s) | Value::Asset(s) => {
            let mut h = FxHasher::default();
            h.write(s.as_bytes());
            h.finish().wrapping_mul(0x9e37_79b9_7f4a_7c15)
        }
        Value::Array(..) => return None,
    })
}

/// Whether two values are the same bit for bit (`0.0` and `-0.0` differ).
fn same_bits(a: &Value, b: &Value) -> bool {
    let bits = |a: &[f32], b: &[f32]| {
        a.iter()
            .map(|x| x.to_bits())
            .eq(b.iter().map(|x| x.to_bits()))
    };
    match (a, b) {
        (Value::Float(x), Value::Float(y)) => x.to_bits() == y.to_bits(),
        (Value::Triple(s, x), Value::Triple(t, y)) => s == t && bits(x, y),
        (Value::HPoint(x), Value::HPoint(y)) => bits(x, y),
        (Value::Matrix(x), Value::Matrix(y)) => bits(x, y),
        (Value::Array(..), _) => false,
        _ => a == b,
    }
}

impl<'t> Reader<'t> {
    fn new(file: Arc<str>, types: &'t (dyn ParamTypes + Sync), net: Option<Network>) -> Self {
        Reader {
            file,
            types,
            net,
            done: Vec::new(),
            remember: true,
            memo: Memo::default(),
            ctx: Ctx::default(),
            found: Vec::new(),
            order: Order::default(),
            materials: 0,
        }
    }

    fn loc(&self, pointer: &str) -> Location {
        self.loc_owned(pointer.to_string())
    }

    /// [`Reader::loc`] of a pointer already rendered.
    fn loc_owned(&self, pointer: String) -> Location {
        Location {
            file: self.file.clone(),
            line: 0,
            column: 0,
            pointer: Some(pointer),
        }
    }

    fn error(&self, code: &'static str, pointer: &str, msg: impl Into<String>) -> Error {
        Diagnostic::error(code, msg).at(self.loc(pointer)).into()
    }

    /// Checks from now on belong to `group` and `phase`.
    fn at(&mut self, group: u32, phase: u8) {
        self.order.group = group;
        self.order.phase = phase;
    }

    fn record(&mut self, found: Found) {
        self.found.push((self.order, found));
        self.order.seq += 1;
    }

    fn warn(&mut self, d: Diagnostic) {
        self.record(Found::Warning(d));
    }

    fn fail(&mut self, e: Error) {
        self.record(Found::Error(e));
    }

    fn object<'j, 'de>(
        &self,
        j: &'j J<'de>,
        pointer: &P,
        what: &str,
    ) -> Result<&'j [(Cow<'de, str>, J<'de>)], Error> {
        match j {
            J::Obj(m) => Ok(m),
            other => Err(self.error(
                "JS002",
                &pointer.render(),
                format!("{what} must be an object, found {}", other.kind()),
            )),
        }
    }

    fn string<'j, 'de>(
        &self,
        j: &'j J<'de>,
        pointer: &P,
        what: &str,
    ) -> Result<&'j Cow<'de, str>, Error> {
        match j {
            J::Str(s) => Ok(s),
            other => Err(self.error(
                "JS002",
                &pointer.render(),
                format!("{what} must be a string, found {}", other.kind()),
            )),
        }
    }

    fn unknown_key(&mut self, pointer: &P, key: &str, where_: &str) {
        let d = self.unknown_key_warning(pointer, key, where_);
        self.warn(d);
    }

    fn unknown_key_warning(&self, pointer: &P, key: &str, where_: &str) -> Diagnostic {
        Diagnostic::warning("JS011", format!("unknown key `{key}` in {where_}; ignored"))
            .at(self.loc(&pointer.render()))
    }

    /// The `vstructcNetwork` member (`None` when missing).
    fn check_version(&mut self, version: Option<&J>) {
        let e = match version {
            None => self.error("JS002", "", "missing `vstructcNetwork`"),
            Some(J::Num(n)) if n.as_f64() == 1.0 => return,
            Some(J::Num(n)) => self.error(
                "JS003",
                "/vstructcNetwork",
                format!(
                    "unsupported vstructcNetwork version {}; only 1 is supported",
                    n.as_f64()
                ),
            ),
            Some(other) => self.error(
                "JS002",
                "/vstructcNetwork",
                format!(
                    "`vstructcNetwork` must be the integer 1, found {}",
                    other.kind()
                ),
            ),
        };
        self.fail(e);
    }

    /// Close a material once all its members are read: terminals, node kinds, bindings.
    fn finish_material(&mut self, m: MaterialState<'_>, group: u32) {
        let pointer = m.pointer;
        if !m.has_nodes {
            self.at(group, MAT_NO_NODES);
            let e = self.error(
                "JS002",
                &pointer,
                format!("material `{}` has no `nodes`", m.name),
            );
            self.fail(e);
        }
        self.at(group, MAT_TERMINALS);
        let root = P::Root(&pointer);
        let tpointer = P::Key(&root, "terminals");
        let members = m.terminals.as_ref().map_or(&[][..], |j| match j {
            J::Obj(members) => members.as_slice(),
            _ => &[],
        });
        let mut terms: Vec<(&str, Conn)> = Vec::with_capacity(members.len());
        for (t, c) in members {
            match self.connection(c, &P::Key(&tpointer, t)) {
                Ok(conn) => terms.push((&**t, conn)),
                Err(e) => self.fail(e),
            }
        }
        // A node's kind comes from the first terminal naming it (the earlier ones scanned
        // while they are few).
        let mut named = SeenKeys::default();
        let mut kinds = Vec::with_capacity(terms.len());
        for (t, c) in &terms {
            if named.insert(Cow::Borrowed(&c.node))
                && let Some(&Some(id)) = m.by_name.get(&*c.node)
            {
                kinds.push((id, RequestKind::from_terminal_name(t)));
            }
        }
        self.at(group, MAT_BIND);
        let nodes = P::Key(&root, "nodes");
        let mut links = Vec::with_capacity(m.pending.iter().map(|(_, _, c)| c.len()).sum());
        for (id, name, conns) in &m.pending {
            let node = P::Key(&nodes, name);
            let inputs = P::Key(&node, "inputConnections");
            for (param, input, list) in conns {
                let input = P::Key(&inputs, input);
                let bound = list
                    .iter()
                    .enumerate()
                    .map(|(i, c)| self.bind(c, &P::Index(&input, i), &m.by_name, &m.name))
                    .collect();
                links.push((*id, *param, bound));
            }
        }
        let terminals = terms
            .iter()
            .map(|(t, c)| {
                let link = self.bind(c, &P::Key(&tpointer, t), &m.by_name, &m.name);
                (t.to_string(), link)
            })
            .collect();
        let location = Some(self.loc_owned(pointer));
        let out = MaterialOut {
            nodes: m.nodes,
            kinds,
            links,
            terminals,
            name: m.name,
            primvars: m.primvars,
            location,
        };
        match &mut self.net {
            Some(net) => out.add_to(net),
            None => self.done.push(out),
        }
    }

    fn primvars(&self, j: &J, pointer: &P) -> Result<Vec<String>, Error> {
        match j {
            J::Arr(items) => items
                .iter()
                .enumerate()
                .map(|(i, v)| {
                    self.string(v, &P::Index(pointer, i), "a primvar")
                        .map(|s| s.to_string())
                })
                .collect(),
            other => Err(self.error(
                "JS002",
                &pointer.render(),
                format!("`primvars` must be an array, found {}", other.kind()),
            )),
        }
    }

    /// Bind a connection to a node of the material, or keep it dangling (JS010).
    fn bind(&mut self, c: &Conn, pointer: &P, by_name: &NodesByName, material: &str) -> LocalLink {
        match by_name.get(&*c.node) {
            Some(&Some(id)) => LocalLink::Node(id, c.output.as_deref().map(Sym::new)),
            _ => {
                let d = Diagnostic::warning(
                    "JS010",
                    format!(
                        "connection to `{}`, which is not a node of material `{material}`; kept",
                        c.node
                    ),
                )
                .at(self.loc(&pointer.render()));
                self.warn(d);
                LocalLink::Missing(Link::missing(&c.node, c.output.as_deref()))
            }
        }
    }

    fn connection<'de>(&mut self, j: &J<'de>, pointer: &P) -> Result<Conn<'de>, Error> {
        let members = self.object(j, pointer, "a connection")?;
        let mut node = None;
        let mut output = None;
        for (k, v) in members {
            let p = P::Key(pointer, k);
            match &**k {
                "upstreamNode" => node = Some(self.string(v, &p, "`upstreamNode`")?.clone()),
                "upstreamOutputName" => {
                    output = Some(self.string(v, &p, "`upstreamOutputName`")?.clone())
                }
                _ => self.unknown_key(&p, k, "a connection"),
            }
        }
        let Some(node) = node else {
            return Err(self.error(
                "JS002",
                &pointer.render(),
                "connection without `upstreamNode`",
            ));
        };
        let Some(output) = output else {
            return Err(self.error(
                "JS002",
                &pointer.render(),
                "connection without `upstreamOutputName` (use \"\" for a whole-node reference)",
            ));
        };
        Ok(Conn {
            node,
            output: (!output.is_empty()).then_some(output),
        })
    }

    /// Close a node once all its members are read: report its findings (module docs) and bind
    /// its inputs to its parameters. Returns the node and its connections (per parameter
    /// index), to bind once every node of the material exists.
    fn close_node<'de>(
        &mut self,
        name: &str,
        n: &mut NodeState<'de>,
        kind: RequestKind,
        pointer: &P,
    ) -> Result<(Node, NodeConns<'de>), Error> {
        match n.shader.clone() {
            Some(shader) => {
                let ppointer = P::Key(pointer, "parameters");
                for (index, pname, j) in std::mem::take(&mut n.deferred) {
                    let read = self.shorthand(&shader, &pname, &j, &P::Key(&ppointer, &pname));
                    n.settle(index, read);
                }
            }
            None => {
                let e = self.error(
                    "JS002",
                    &pointer.render(),
                    format!("node `{name}` has no `nodeTypeId`"),
                );
                n.push(NODE_SHADER, 0, Found::Error(e));
            }
        }
        if !n.found.is_empty() {
            n.found.sort_by_key(|&(stage, index, _)| (stage, index));
            for (_, _, found) in n.found.drain(..) {
                match found {
                    Found::Warning(d) => self.warn(d),
                    Found::Error(e) => return Err(e),
                }
            }
        }
        let Some(shader) = n.shader.take() else {
            return Err(self.error("JS002", &pointer.render(), "node without `nodeTypeId`"));
        };
        let mut params: Vec<Param> = Vec::with_capacity(n.names.len() + n.inputs.len());
        for (&pname, typed) in n.names.iter().zip(n.values.drain(..)) {
            let Some((value, decl)) = typed else { continue };
            params.push(Param::from_shared(
                pname,
                Some(value),
                Some(decl),
                ParamAt::JsonParameter,
                None,
            ));
        }
        // Inputs name parameters given above, or add their own.
        let mut conns: NodeConns<'de> = Vec::with_capacity(n.inputs.len());
        for (input, list) in std::mem::take(&mut n.inputs) {
            let sym = Sym::new(&input);
            let k = n.parameter_index(sym).unwrap_or_else(|| {
                params.push(Param::from_shared(sym, None, None, ParamAt::Unknown, None));
                params.len() - 1
            });
            conns.push((k, input, list));
        }
        let shader = match self.memo.shaders.get(&*shader) {
            Some(shared) => shared.clone(),
            None => {
                let shared: Arc<str> = Arc::from(&*shader);
                self.memo.shaders.insert(shared.clone());
                shared
            }
        };
        let mut node = Node::new_shared(name, shader, kind);
        node.set_raw_params(params);
        node.set_origin(Some(self.loc_owned(pointer.render())), None);
        Ok((node, conns))
    }

    /// A parameter in the canonical `{ "type", "value" }` form (`ty` and `value`: its members,
    /// if given and, for `type`, a string; `decl`: the type's declaration if it is a type).
    fn canonical(
        &mut self,
        name: &str,
        ty: Option<&str>,
        decl: Option<Arc<Decl>>,
        value: Option<ValueRead>,
        pointer: &P,
    ) -> Result<Typed, Error> {
        let (Some(text), Some(v)) = (ty, value) else {
            return Err(self.error(
                "JS002",
                &pointer.render(),
                format!(
                    "parameter `{name}` must be {{ \"type\": T, \"value\": V }} or a bare value"
                ),
            ));
        };
        let Some(decl) = decl else {
            return Err(self.error(
                "JS002",
                &P::Key(pointer, "type").render(),
                format!("unknown type `{text}` of `{name}`"),
            ));
        };
        let value = match v {
            ValueRead::Tree(j) => to_value(&decl.ty, &j),
            ValueRead::Typed(read) => read,
        };
        let value = value.map_err(|why| {
            self.error(
                "JS004",
                &P::Key(pointer, "value").render(),
                format!("value of `{name}` does not match its type `{text}`: {why}"),
            )
        })?;
        Ok((self.memo.share(value), decl))
    }

    /// The declaration shared by the parameters whose `type` is `text` (`None` if `text` is
    /// not a type).
    fn inline_decl(&mut self, text: &str) -> Option<Arc<Decl>> {
        if let Some(decl) = self.memo.few_decls.iter().find(|d| d.text == text) {
            return Some(decl.clone());
        }
        if let Some(decl) = self.memo.inline_decls.get(text) {
            return Some(decl.clone());
        }
        let decl = Arc::new(Decl {
            text: text.to_string(),
            class: None,
            reference: false,
            ty: parse_type(text)?,
            inline_type: true,
        });
        if self.memo.few_decls.len() < FEW_DECLS {
            self.memo.few_decls.push(decl.clone());
        } else {
            self.memo.inline_decls.insert(Box::from(text), decl.clone());
        }
        Some(decl)
    }

    /// A shorthand (bare) parameter value, typed by the shader's definition.
    fn shorthand(&mut self, shader: &str, name: &str, j: &J, pointer: &P) -> Result<Typed, Error> {
        let Some(t) = self.types.input_type(shader, name) else {
            return Err(self.error(
                "JS006",
                &pointer.render(),
                format!("shorthand value for `{name}`, which `{shader}` does not declare; write {{ \"type\": T, \"value\": V }}"),
            ));
        };
        let value = to_value(&t, j).map_err(|why| {
            self.error(
                "JS004",
                &pointer.render(),
                format!("value of `{name}` does not match its declared type `{t}`: {why}"),
            )
        })?;
        let decl = match self.memo.declared_decls.get(&t) {
            Some(decl) => decl.clone(),
            None => {
                let decl = Arc::new(Decl {
                    text: String::new(),
                    class: None,
                    reference: false,
                    ty: t.clone(),
                    inline_type: false,
                });
                self.memo.declared_decls.insert(t, decl.clone());
                decl
            }
        };
        Ok((self.memo.share(value), decl))
    }
}

/// A JSON type string: `int | float | string | color | point | vector | normal | matrix |
/// hpoint | token | asset | bool`, optionally with `[N]` or `[]`.
#[cfg_attr(feature = "testkit", visibility::make(pub))]
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
#[cfg_attr(feature = "testkit", visibility::make(pub))]
fn to_value(t: &Type, j: &J) -> Result<Value, String> {
    match (j, &t.array) {
        (J::Arr(items), _) => to_value_seq(t, items),
        (_, ArraySpec::None) => scalar(&t.base, j),
        (other, _) => Err(format!("expected an array, found {}", other.kind())),
    }
}

/// [`to_value`] of a JSON array, given as its items.
fn to_value_seq(t: &Type, items: &[J]) -> Result<Value, String> {
    let values =
        || -> Result<Vec<Value>, String> { items.iter().map(|i| scalar(&t.base, i)).collect() };
    match t.array {
        ArraySpec::None => match &t.base {
            b if b.is_triple() => Ok(Value::Triple(b.clone(), floats_seq::<3>(items)?)),
            BaseType::HPoint => Ok(Value::HPoint(floats_seq::<4>(items)?)),
            BaseType::Matrix => Ok(Value::Matrix(floats_seq::<16>(items)?)),
            // The other types take no array, whatever its items.
            b => scalar(b, &J::Arr(Vec::new())),
        },
        ArraySpec::Fixed(n) => {
            let v = values()?;
            if v.len() != n {
                return Err(format!("expected {n} elements, found {}", v.len()));
            }
            Ok(Value::Array(t.base.clone(), v))
        }
        ArraySpec::Dynamic => Ok(Value::Array(t.base.clone(), values()?)),
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
    floats_seq(items)
}

fn floats_seq<const N: usize>(items: &[J]) -> Result<[f32; N], String> {
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
        J::Str(s) => Ok(s.to_string()),
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

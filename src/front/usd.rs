//! USD reader (feature `usd`): the RenderMan materials of a USD stage (`.usda`, `.usdc`,
//! `.usdz`) as a [`Network`], read through the pure-Rust `openusd` crate with composition
//! (sublayers, references, payloads, variant selections, inherits).
//!
//! Every `Shader` prim becomes a node whose handle is its prim path and whose type is its
//! `info:id`; every `Material` prim becomes a material whose nodes are the shaders beneath
//! it (nested node graphs included), reached by a terminal or not. Authored `inputs:NAME`
//! values become parameters, typed as the definition declares them when the value fits
//! (else as USD typed them); `inputs:NAME.connect` targets become connections, followed
//! through the inputs and outputs of `NodeGraph` and `Material` prims to the shader output
//! that feeds them. The Material's `outputs:ri:surface`, `outputs:ri:displacement` and
//! `outputs:ri:volume` (or, when it has no `ri:` output, `outputs:surface` and
//! `outputs:displacement`) are its terminals. Order does not matter: a connection binds to
//! its prim wherever the prim is.
//!
//! The inputs read are the parameters' source: resolution's edits to them are changes
//! ([`crate::network::ParamChange`]), which is what the USD writer's override layer writes.
//!
//! A `.usda` or `.usdc` root layer in which nothing composes is read from its specs
//! directly, without composing a stage; the result is the same, and it is much faster. A
//! crate file is then indexed once from its tables (each spec's type and field set by path,
//! each field name's token), and an attribute's fields are found in one walk of its field
//! set. The reader decodes a crate file's tables and its usual values itself
//! (`crate_file`) when the file is laid out as USD's writers lay it out, and leaves anything
//! else to `openusd`, which reads (or refuses) it as it would alone.
//!
//! usda text is lexed first as Pixar's USD lexes it (`usda`): `openusd` keeps what stands
//! between quotes as the value, so each string is decoded and handed over in a quoting
//! `openusd` reads word for word.
//!
//! Diagnostics name the file and the prim or property path (in [`Location::pointer`]);
//! `openusd` keeps no line numbers, so USD diagnostics have none, except for a usda layer
//! that does not read: US001 at the line and column where it stops.

use crate::diag::{Diagnostic, Diagnostics, Error, Location};
use crate::limits::{Limit, Limits};
use crate::network::{
    Link, Material, MaterialNodes, Network, Node, NodeId, Param, ParamAt, ParamTypes, RequestKind,
    Sym, Terminal,
};
use crate::types::{BaseType, Type, Value, saturate_f32};
use openusd::{ar, sdf, usd};
use rustc_hash::FxHashMap;
use std::borrow::Cow;
use std::io::{self, Read};
use std::sync::Arc;

mod crate_file;
mod usda;
use crate_file::CrateLayer;

/// How many NodeGraph or Material inputs and outputs a connection is followed through
/// before it is reported as a cycle (US005).
const MAX_HOPS: usize = 64;

/// Serves the root layer from the bytes already read (so standard input works and the file
/// is read once) and everything it refers to from the file system, anchored at the root's
/// folder.
struct MemResolver {
    inner: ar::DefaultResolver,
    root: String,
    /// The root layer as `openusd` is to read it ([`openusd_form`], done once here however
    /// often the layer is opened), or why it cannot be.
    bytes: Result<Vec<u8>, String>,
    /// How many of the root's values went in encoded ([`usda::decoded`] gives them back).
    encoded: usize,
}

impl MemResolver {
    /// The packaged path inside the root, when `path` is `root[inner]`.
    fn in_root_package<'a>(&self, path: &'a str) -> Option<&'a str> {
        path.strip_prefix(self.root.as_str())?
            .strip_prefix('[')?
            .strip_suffix(']')
    }

    /// The root layer's bytes as `openusd` is to read them.
    fn root_bytes(&self) -> io::Result<&[u8]> {
        self.bytes
            .as_deref()
            .map_err(|why| io::Error::other(why.clone()))
    }

    fn root_entry(&self, inner: &str) -> io::Result<Vec<u8>> {
        let mut archive =
            zip::ZipArchive::new(io::Cursor::new(self.root_bytes()?)).map_err(io::Error::other)?;
        let mut entry = archive.by_name(inner).map_err(io::Error::other)?;
        let mut out = Vec::new();
        entry.read_to_end(&mut out)?;
        layer_form(out)
    }
}

/// Layer `bytes` as `openusd` is to read them, and how many values went in encoded: usda
/// text in the form in which `openusd` reads what Pixar's USD reads ([`usda::normalise`]);
/// a crate file or package as it is. Text Pixar's USD would not lex is refused, with the
/// reason, so that `openusd` (which is more lenient) does not read it.
fn openusd_form(bytes: Cow<'_, [u8]>) -> Result<(Vec<u8>, usize), String> {
    if flavour(&bytes) != "usda" {
        return Ok((bytes.into_owned(), 0));
    }
    let normalised = usda::normalise(&bytes).map_err(|e| e.message)?;
    let encoded = normalised.encoded;
    let rewritten = match normalised.text {
        Cow::Owned(text) => Some(text),
        Cow::Borrowed(_) => None,
    };
    Ok((rewritten.unwrap_or_else(|| bytes.into_owned()), encoded))
}

/// [`openusd_form`] of a layer other than the root. The reader decodes encoded values as
/// it takes them; only the writer, which reads back its own root alone, needs their count.
fn layer_form(bytes: Vec<u8>) -> io::Result<Vec<u8>> {
    openusd_form(Cow::Owned(bytes))
        .map(|(bytes, _)| bytes)
        .map_err(io::Error::other)
}

impl ar::Resolver for MemResolver {
    fn create_identifier(&self, asset_path: &str, anchor: Option<&ar::ResolvedPath>) -> String {
        self.inner.create_identifier(asset_path, anchor)
    }

    fn resolve(&self, asset_path: &str) -> Option<ar::ResolvedPath> {
        if asset_path == self.root {
            return Some(ar::ResolvedPath::new(asset_path));
        }
        if let Some(inner) = self.in_root_package(asset_path) {
            return self
                .root_entry(inner)
                .ok()
                .map(|_| ar::ResolvedPath::new(asset_path));
        }
        self.inner.resolve(asset_path)
    }

    fn resolve_for_new_asset(&self, asset_path: &str) -> Option<ar::ResolvedPath> {
        self.inner.resolve_for_new_asset(asset_path)
    }

    fn open_asset(&self, resolved: &ar::ResolvedPath) -> io::Result<Box<dyn ar::Asset>> {
        let path = resolved.to_string_lossy();
        if path == self.root {
            return Ok(Box::new(io::Cursor::new(self.root_bytes()?.to_vec())));
        }
        if let Some(inner) = self.in_root_package(&path) {
            return Ok(Box::new(io::Cursor::new(self.root_entry(inner)?)));
        }
        let mut bytes = Vec::new();
        self.inner.open_asset(resolved)?.read_to_end(&mut bytes)?;
        Ok(Box::new(io::Cursor::new(layer_form(bytes)?)))
    }

    fn get_modification_timestamp(
        &self,
        asset_path: &str,
        resolved: &ar::ResolvedPath,
    ) -> Option<std::time::SystemTime> {
        if resolved.to_string_lossy().starts_with(self.root.as_str()) {
            return None;
        }
        self.inner.get_modification_timestamp(asset_path, resolved)
    }
}

/// The USD flavour of `bytes` by signature: `usda`, `usdc` or `usdz`.
fn flavour(bytes: &[u8]) -> &'static str {
    if bytes.starts_with(b"PXR-USDC") {
        "usdc"
    } else if bytes.starts_with(b"PK\x03\x04") {
        "usdz"
    } else {
        "usda"
    }
}

/// The root layer's name for `openusd`: `name` when its extension is a USD one, else `name`
/// with the extension its content calls for (standard input, or a file named otherwise).
fn root_name(name: &str, bytes: &[u8]) -> String {
    let ext = std::path::Path::new(name)
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    match ext.as_deref() {
        Some("usda" | "usdc" | "usdz") => name.to_string(),
        // `.usd` is either encoding: name it by its signature.
        _ => format!("{name}.{}", flavour(bytes)),
    }
}

/// The prim kinds the reader cares about.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum PrimKind {
    Material,
    NodeGraph,
    Shader,
}

/// The kind of a prim whose `typeName` is `t`.
fn prim_kind(t: &sdf::Value) -> Option<PrimKind> {
    let sdf::Value::Token(t) = t else {
        return None;
    };
    match t.as_str() {
        "Material" => Some(PrimKind::Material),
        "NodeGraph" => Some(PrimKind::NodeGraph),
        "Shader" => Some(PrimKind::Shader),
        _ => None,
    }
}

/// Reading state: the stage, the prims it holds and where findings go.
struct Reader<'a> {
    /// The composed stage, or nothing when `flat` is read instead.
    stage: Option<&'a usd::Stage>,
    /// The root layer's specs, when nothing in that layer composes (see [`flat_prims`]):
    /// read directly, they are what the composed stage would give, without composing
    /// each prim.
    flat: Option<&'a dyn Specs>,
    /// The crate file read alone, when its prims were walked by path index
    /// ([`CrateLayer::flat_prims_by_index`]): prims and attributes are then found by index.
    indexed: Option<&'a CrateLayer>,
    file: Arc<str>,
    types: &'a dyn ParamTypes,
    diags: &'a mut Diagnostics,
    kinds: FxHashMap<String, PrimKind>,
    nodes: FxHashMap<String, NodeId>,
    net: Network,
    /// Attributes with time samples (reported once, US004).
    sampled: Vec<String>,
    /// The declared type of each input looked up so far, by shader type and input name.
    declared: FxHashMap<(Sym, Sym), Option<Type>>,
}

impl<'a> Reader<'a> {
    fn at(&self, path: &str) -> Location {
        Location {
            file: self.file.clone(),
            line: 0,
            column: 0,
            pointer: Some(path.to_string()),
        }
    }

    /// The type `shader`'s definition declares for input `input` (looked up once per
    /// shader type and input).
    fn declared_type(&mut self, shader: Sym, input: Sym) -> Option<Type> {
        if let Some(t) = self.declared.get(&(shader, input)) {
            return t.clone();
        }
        let t = self.types.input_type(&shader, &input);
        self.declared.insert((shader, input), t.clone());
        t
    }

    fn warn(&mut self, code: &'static str, path: &str, message: String) {
        let d = Diagnostic::warning(code, message).at(self.at(path));
        self.diags.push(d);
    }

    /// US002: the attribute `apath` is connected to `prim`, which is not a Shader; the
    /// connection is kept dangling (`what`: a connection or a terminal).
    fn warn_not_a_shader(&mut self, apath: &str, prim: &str, what: &str) {
        self.warn(
            "US002",
            apath,
            format!(
                "`{apath}` is connected to `{prim}`, which is not a Shader on the stage; kept \
                 as a dangling {what}"
            ),
        );
    }

    /// The kind of prim `prim` (at path index `index` of a crate file walked by index).
    fn kind_of(&self, prim: &sdf::Path, index: Option<usize>) -> Option<PrimKind> {
        if let (Some(layer), Some(index)) = (self.indexed, index) {
            return layer.kind_at(index);
        }
        match self.flat {
            Some(data) => prim_kind(
                data.try_field(prim, sdf::FieldKey::TypeName.as_str())
                    .ok()??
                    .as_ref(),
            ),
            None => prim_kind(&sdf::Value::Token(
                self.stage?.prim(prim.clone()).type_name().ok()??,
            )),
        }
    }

    /// Attribute `path`'s default value, as the stage composes it.
    fn default_value(&self, path: &sdf::Path) -> Result<Option<sdf::Value>, String> {
        if let Some(data) = self.flat {
            return default_of(data.try_field(path, sdf::FieldKey::Default.as_str()));
        }
        match self.stage {
            Some(stage) => stage
                .attribute(path.clone())
                .get::<sdf::Value>()
                .map_err(|e| e.to_string()),
            None => Ok(None),
        }
    }

    /// The targets of attribute `path`'s connections, as the stage composes them.
    fn connections(&self, path: &sdf::Path) -> Vec<sdf::Path> {
        match self.flat {
            Some(data) => targets_of(data.try_field(path, sdf::FieldKey::ConnectionPaths.as_str())),
            None => self
                .stage
                .and_then(|stage| stage.attribute(path.clone()).connections().ok())
                .unwrap_or_default(),
        }
    }

    /// How many time samples attribute `path` has on the stage (a layer read alone answers
    /// through [`Specs::attribute`]).
    fn time_samples(&self, path: &sdf::Path) -> usize {
        self.stage
            .and_then(|stage| stage.attribute(path.clone()).num_time_samples().ok())
            .unwrap_or(0)
    }

    /// Attribute `path`'s USD type name on the stage, or nothing (a layer read alone answers
    /// through [`Specs::attribute`]).
    fn value_type(&self, path: &sdf::Path) -> openusd::tf::Token {
        self.stage
            .and_then(|stage| stage.attribute(path.clone()).type_name().ok().flatten())
            .unwrap_or_default()
    }

    /// What the reader reads of attribute `path`, or nothing when the layer read alone
    /// has no attribute there. Through the stage, the type name and the default value are
    /// looked up only for an attribute without connections, the only one that uses them.
    /// (A crate file walked by index is read through its own [`ShaderSource`].)
    fn attr_fields(&self, path: &sdf::Path) -> Option<AttrFields> {
        if let Some(data) = self.flat {
            return data.attribute(path);
        }
        let targets = self.connections(path);
        let samples = self.time_samples(path);
        let (type_name, default) = if targets.is_empty() {
            (self.value_type(path), self.default_value(path))
        } else {
            (openusd::tf::Token::default(), Ok(None))
        };
        Some(AttrFields {
            type_name,
            default,
            targets,
            samples,
        })
    }

    /// The `inputs:` attributes of prim `path` in composed order: each one's path and
    /// input name (read alone, every property so named: [`Reader::attr_fields`] leaves out
    /// those that are not attributes).
    fn inputs(&self, path: &sdf::Path) -> Vec<InputAt<'a>> {
        match self.flat {
            Some(data) => {
                let names = tokens_of(data.try_field(path, "propertyChildren"));
                let names: Vec<&str> = names.iter().map(|t| t.as_str()).collect();
                distinct_inputs(&names)
                    .filter_map(|(name, input)| {
                        let path = property_path(path, name)?;
                        Some((Cow::Owned(path), Cow::Owned(input.to_string()), None))
                    })
                    .collect()
            }
            None => self
                .stage
                .and_then(|stage| stage.prim(path.clone()).attributes().ok())
                .unwrap_or_default()
                .into_iter()
                .filter_map(|a| {
                    let input = a.path().split_property()?.1.strip_prefix("inputs:")?;
                    let input = Cow::Owned(input.to_string());
                    Some((Cow::Owned(a.path().clone()), input, None))
                })
                .collect(),
        }
    }

    /// A token or string attribute's default value.
    fn text_attr(&self, prim: &sdf::Path, name: &str) -> Option<String> {
        text_of(self.default_value(&property_path(prim, name)?))
    }

    /// The node type of shader `path` from its texts read before ([`ShaderRead`]): its
    /// `info:id`, or a marker of what it has instead (US003).
    fn shader_id(&mut self, path: &str, source: Option<String>, id: Option<String>) -> String {
        match source.as_deref() {
            None | Some("id") => match id {
                Some(id) if !id.is_empty() => id,
                _ => {
                    self.warn(
                        "US003",
                        path,
                        format!("Shader `{path}` has no `info:id`; kept as a node of unknown type"),
                    );
                    "(no info:id)".to_string()
                }
            },
            Some(other) => {
                self.warn(
                    "US003",
                    path,
                    format!(
                        "Shader `{path}` is implemented by `{other}`, not by an `info:id`; \
                         kept as a node of unknown type"
                    ),
                );
                format!("({other})")
            }
        }
    }

    /// What feeds connection target `target`: shader outputs (prim path, output name),
    /// values authored on NodeGraph or Material inputs, or targets that are not a shader's.
    fn sources(&mut self, target: &sdf::Path, from: &str, out: &mut Vec<Source>, hops: usize) {
        let Some((prim, prop)) = split_property(target) else {
            out.push(Source::Missing(target.as_str().to_string(), None));
            return;
        };
        let prim_path = prim.into_owned();
        let base = prop
            .strip_prefix("outputs:")
            .or_else(|| prop.strip_prefix("inputs:"))
            .unwrap_or(prop)
            .to_string();
        match self.kinds.get(&prim_path).copied() {
            Some(PrimKind::Shader) => out.push(Source::Output(prim_path, base)),
            Some(PrimKind::NodeGraph | PrimKind::Material) => {
                if hops >= MAX_HOPS {
                    self.warn(
                        "US005",
                        from,
                        format!(
                            "connection through `{target}` passes {MAX_HOPS} node-graph ports \
                             (a cycle?); left out"
                        ),
                    );
                    return;
                }
                let targets = self.connections(target);
                if targets.is_empty() {
                    match self.default_value(target) {
                        Ok(Some(v)) => out.push(Source::Value(v, target.as_str().to_string())),
                        _ => self.warn(
                            "US005",
                            from,
                            format!(
                                "connection to `{target}`, a node-graph port that is neither \
                                 connected nor given a value; left out"
                            ),
                        ),
                    }
                }
                for t in targets {
                    self.sources(&t, from, out, hops + 1);
                }
            }
            None => out.push(Source::Missing(prim_path, Some(base))),
        }
    }

    /// The inputs of a shader of type `shader`, read before ([`ShaderRead`]), as
    /// parameters read from the source, with the connections to bind once every node
    /// exists: (parameter index, sources).
    fn read_inputs(
        &mut self,
        inputs: Vec<(Cow<'_, sdf::Path>, Sym, AttrFields)>,
        shader: Sym,
    ) -> (Vec<Param>, PendingLinks) {
        let mut params: Vec<Param> = Vec::with_capacity(inputs.len());
        let mut pending: PendingLinks = Vec::new();
        for (attr, input, fields) in inputs {
            let apath = attr.as_str();
            if fields.samples > 0 {
                self.sampled.push(apath.to_string());
            }
            // The declared type, looked up only for a value.
            let mut declared: Option<Option<Type>> = None;
            let targets = fields.targets;
            let mut value = None;
            let mut links = Vec::new();
            if targets.is_empty() {
                let usd_type = fields.type_name;
                match fields.default {
                    Ok(Some(v)) => {
                        let declared = self.declared_type(shader, input);
                        value = self.value(&v, declared.as_ref(), usd_type.as_str(), apath);
                    }
                    Ok(None) => {}
                    Err(e) => self.warn(
                        "US006",
                        apath,
                        format!("the value of `{apath}` cannot be read: {e}; left out"),
                    ),
                }
            } else {
                let mut sources = Vec::new();
                for t in &targets {
                    self.sources(t, apath, &mut sources, 0);
                }
                for s in sources {
                    match s {
                        Source::Output(prim, output) => links.push((prim, Some(output), false)),
                        Source::Value(v, from) => {
                            if declared.is_none() {
                                declared = Some(self.declared_type(shader, input));
                            }
                            let declared = declared.as_ref().and_then(Option::as_ref);
                            if let Some(v) = self.value(&v, declared, "", &from) {
                                value = Some(v);
                            }
                        }
                        Source::Missing(prim, output) => {
                            self.warn_not_a_shader(apath, &prim, "connection");
                            links.push((prim, output, true));
                        }
                    }
                }
            }
            if value.is_none() && links.is_empty() {
                continue;
            }
            // A position as the source item: the parameter was read, so resolution's edits
            // to it are changes ([`crate::network::ParamChange`]).
            let index = params.len();
            params.push(Param::from_shared(
                input,
                value.map(Arc::new),
                None,
                ParamAt::Unknown,
                Some(index as u32),
            ));
            if !links.is_empty() {
                pending.push((index, links));
            }
        }
        (params, pending)
    }

    /// USD value `v` as a vstructc value, or a warning (US006) when its type is not read.
    fn value(
        &mut self,
        v: &sdf::Value,
        declared: Option<&Type>,
        usd_type: &str,
        at: &str,
    ) -> Option<Value> {
        let value = to_value(v, declared, usd_type);
        if value.is_none() {
            self.warn(
                "US006",
                at,
                format!(
                    "`{at}` has a value of a type vstructc does not read ({}); left out",
                    if usd_type.is_empty() {
                        value_kind(v)
                    } else {
                        usd_type
                    }
                ),
            );
        }
        value
    }

    /// The terminals of Material `path`: `outputs:ri:*`, else the universal outputs.
    /// (`index`: its path index in a crate file walked by index.)
    fn terminals(&mut self, path: &str, index: Option<usize>) -> Vec<Terminal> {
        let prim = sdf::Path::from(path);
        let read = |this: &mut Self, names: &[(&str, &str)]| -> Vec<Terminal> {
            let mut out = Vec::new();
            for &(attr_name, terminal) in names {
                let targets = match (this.indexed, index) {
                    (Some(layer), Some(index)) => layer.property_targets(index, attr_name),
                    _ => match property_path(&prim, attr_name) {
                        Some(attr) => this.connections(&attr),
                        None => Vec::new(),
                    },
                };
                if targets.is_empty() {
                    continue;
                }
                let apath = format!("{path}.{attr_name}");
                let mut sources = Vec::new();
                for t in &targets {
                    this.sources(t, &apath, &mut sources, 0);
                }
                if let Some(s) = sources.into_iter().next() {
                    let link = match s {
                        Source::Output(prim, _) => Link::node(this.nodes[&prim], None),
                        Source::Missing(prim, _) => {
                            this.warn_not_a_shader(&apath, &prim, "terminal");
                            Link::missing(&prim, None)
                        }
                        Source::Value(..) => continue,
                    };
                    out.push(Terminal {
                        name: terminal.to_string(),
                        link,
                    });
                }
            }
            out
        };
        let ri = read(
            self,
            &[
                ("outputs:ri:surface", "surface"),
                ("outputs:ri:displacement", "displacement"),
                ("outputs:ri:volume", "volume"),
            ],
        );
        if !ri.is_empty() {
            return ri;
        }
        read(
            self,
            &[
                ("outputs:surface", "surface"),
                ("outputs:displacement", "displacement"),
                ("outputs:volume", "volume"),
            ],
        )
    }
}

/// Property path `path` split into its prim's path and the property's name, exactly as
/// `openusd`'s `Path::split_property` splits it; the usual `/…/prim.name` (no variant
/// selection, target or second dot in its last element) is split here without copying.
#[cfg_attr(feature = "testkit", visibility::make(pub))]
pub(crate) fn split_property(path: &sdf::Path) -> Option<(Cow<'_, str>, &str)> {
    let text = path.as_str();
    let bytes = text.as_bytes();
    let slash = bytes.iter().rposition(|&b| b == b'/');
    let last = &bytes[slash.map_or(0, |s| s + 1)..];
    let mut dots = last.iter().enumerate().filter(|&(_, &b)| b == b'.');
    if let (Some(slash), Some((dot, _)), None) = (slash, dots.next(), dots.next())
        && dot > 0
        && !last.iter().any(|b| b"{}[]".contains(b))
    {
        let property = &text[slash + 1 + dot + 1..];
        // As `openusd` tells a property path: a name of alphanumerics, `_` and `:`.
        let named = !property.is_empty()
            && if property.is_ascii() {
                property
                    .bytes()
                    .all(|b| b.is_ascii_alphanumeric() || b == b'_' || b == b':')
            } else {
                property
                    .chars()
                    .all(|c| c.is_alphanumeric() || c == '_' || c == ':')
            };
        let prim = &text[..slash + 1 + dot];
        return named.then_some((Cow::Borrowed(prim), property));
    }
    let (prim, property) = path.split_property()?;
    Some((Cow::Owned(prim.as_str().to_string()), property))
}

/// A token or string value as text; nothing for another value, none or an error.
fn text_of(value: Result<Option<sdf::Value>, String>) -> Option<String> {
    match value.ok()?? {
        sdf::Value::Token(t) => Some(usda::decoded(t.as_str()).into_owned()),
        sdf::Value::String(s) => Some(usda::decoded(&s).into_owned()),
        _ => None,
    }
}

/// An `inputs:` attribute of a prim: its path, the input's name and its path index in a
/// crate file walked by index (borrowed from that file when read from it).
type InputAt<'a> = (Cow<'a, sdf::Path>, Cow<'a, str>, Option<usize>);

/// Where shader prims are read from ([`ShaderRead`]): the reader (any layer or stage), or
/// a crate file walked by index, which several threads may read at once.
trait ShaderSource<'a> {
    /// The text of property `name` of prim `prim` ([`Reader::text_attr`]).
    fn shader_text(&self, prim: &sdf::Path, index: Option<usize>, name: &str) -> Option<String>;
    /// The `inputs:` attributes of prim `prim` ([`Reader::inputs`]).
    fn shader_inputs(&self, prim: &sdf::Path, index: Option<usize>) -> Vec<InputAt<'a>>;
    /// What is read of attribute `path` ([`Reader::attr_fields`]).
    fn input_fields(&self, path: &sdf::Path, index: Option<usize>) -> Option<AttrFields>;
}

/// Any layer or stage but a crate file walked by index: found by path.
impl<'a> ShaderSource<'a> for Reader<'a> {
    fn shader_text(&self, prim: &sdf::Path, _: Option<usize>, name: &str) -> Option<String> {
        self.text_attr(prim, name)
    }
    fn shader_inputs(&self, prim: &sdf::Path, _: Option<usize>) -> Vec<InputAt<'a>> {
        self.inputs(prim)
    }
    fn input_fields(&self, path: &sdf::Path, _: Option<usize>) -> Option<AttrFields> {
        self.attr_fields(path)
    }
}

/// The walk by index: what [`Reader`] reads through the layer when it was walked by index.
impl<'a> ShaderSource<'a> for &'a CrateLayer {
    fn shader_text(&self, _: &sdf::Path, index: Option<usize>, name: &str) -> Option<String> {
        text_of(self.property_default(index?, name))
    }
    fn shader_inputs(&self, _: &sdf::Path, index: Option<usize>) -> Vec<InputAt<'a>> {
        let layer: &'a CrateLayer = self;
        index.map(|i| layer.inputs_at(i)).unwrap_or_default()
    }
    fn input_fields(&self, _: &sdf::Path, index: Option<usize>) -> Option<AttrFields> {
        self.attribute_at(index?)
    }
}

/// A panic of the USD library caught while reading, raised again where the reading in
/// order reaches it (so that what was reported before it is what the one-by-one reading
/// reports).
type Panic = Box<dyn std::any::Any + Send>;

/// What is read of a shader prim before its node is built: its `info:implementationSource`
/// and (when that is none or `id`) its `info:id`, then its `inputs:` attributes that are
/// attributes, each with its path and input name. Reading stops at a panic of the USD
/// library, kept to be raised where the walk in order reaches it. Being pure reads, these
/// can be read for many shaders at once ([`read_shaders`]).
struct ShaderRead<'a> {
    texts: Result<(Option<String>, Option<String>), Panic>,
    /// Each input's attribute path, name (made a symbol here, off the thread that builds
    /// the network) and fields.
    inputs: Vec<(Cow<'a, sdf::Path>, Sym, AttrFields)>,
    /// The panic that stopped the reading of the inputs, if one did.
    stop: Option<Panic>,
}

impl<'a> ShaderRead<'a> {
    /// Reads shader prim `prim` (at path index `index` of a crate file walked by index).
    fn of(source: &impl ShaderSource<'a>, prim: &sdf::Path, index: Option<usize>) -> Self {
        use std::panic::{AssertUnwindSafe, catch_unwind};
        let texts = catch_unwind(AssertUnwindSafe(|| {
            let impl_source = source.shader_text(prim, index, "info:implementationSource");
            let id = match impl_source.as_deref() {
                None | Some("id") => source.shader_text(prim, index, "info:id"),
                Some(_) => None,
            };
            (impl_source, id)
        }));
        let mut read = ShaderRead {
            texts,
            inputs: Vec::new(),
            stop: None,
        };
        if read.texts.is_err() {
            return read;
        }
        let inputs = &mut read.inputs;
        let walked = catch_unwind(AssertUnwindSafe(|| {
            let listed = source.shader_inputs(prim, index);
            inputs.reserve_exact(listed.len());
            for (attr, input, at) in listed {
                if let Some(fields) = source.input_fields(&attr, at) {
                    inputs.push((attr, Sym::new(&input), fields));
                }
            }
        }));
        read.stop = walked.err();
        read
    }
}

/// Shaders `shaders`, each read ([`ShaderRead`]) and handed to `take` in order. A crate
/// file walked by index is read through its own [`ShaderSource`], on rayon's pool when it
/// can help (feature `parallel`), in pieces of consecutive shaders, while the calling
/// thread takes the ones read; anything else is read on the calling thread through the
/// reader.
fn read_shaders<'a>(
    r: &mut Reader<'a>,
    shaders: &[(sdf::Path, Option<usize>)],
    mut take: impl FnMut(&mut Reader<'a>, usize, ShaderRead<'a>),
) {
    let Some(layer) = r.indexed else {
        for (n, (p, index)) in shaders.iter().enumerate() {
            let read = ShaderRead::of(&*r, p, *index);
            take(r, n, read);
        }
        return;
    };
    #[cfg(feature = "parallel")]
    if crate::schedule::pool_can_help() {
        let mut n = 0;
        crate::schedule::make_in_order(
            shaders.len(),
            SHADERS_PER_PIECE,
            |i| ShaderRead::of(&layer, &shaders[i].0, shaders[i].1),
            |read| {
                take(r, n, read);
                n += 1;
            },
        );
        return;
    }
    for (n, (p, index)) in shaders.iter().enumerate() {
        take(r, n, ShaderRead::of(&layer, p, *index));
    }
}

/// How many shaders a piece read on rayon's pool holds ([`read_shaders`]): enough that
/// handing a piece over costs little against reading it.
#[cfg(feature = "parallel")]
const SHADERS_PER_PIECE: usize = 64;

/// The connections of a shader's parameters, bound once every node exists: each
/// parameter's index and its sources (prim path, output, whether the prim is not a shader).
type PendingLinks = Vec<(usize, Vec<(String, Option<String>, bool)>)>;

/// What feeds a connection.
enum Source {
    /// A shader's output: prim path, output name.
    Output(String, String),
    /// A value authored on a node-graph input, and that input's path.
    Value(sdf::Value, String),
    /// A prim that is not a shader on the stage, and the output named.
    Missing(String, Option<String>),
}

/// A short name for the variant of `v`, for messages.
fn value_kind(v: &sdf::Value) -> &'static str {
    match v {
        sdf::Value::Quath(_) | sdf::Value::Quatf(_) | sdf::Value::Quatd(_) => "quaternion",
        sdf::Value::Dictionary(_) => "dictionary",
        sdf::Value::Matrix2d(_) | sdf::Value::Matrix3d(_) => "matrix2d/matrix3d",
        _ => "unsupported",
    }
}

/// `x` as an `f32`, saturated to the finite range ([`saturate_f32`]).
fn sat(x: f64) -> f32 {
    saturate_f32(x as f32)
}

/// The triple type a USD type name asks for.
fn triple_base(usd_type: &str) -> BaseType {
    let t = usd_type.trim_end_matches("[]");
    if t.starts_with("normal") {
        BaseType::Normal
    } else if t.starts_with("point") {
        BaseType::Point
    } else if t.starts_with("vector") {
        BaseType::Vector
    } else {
        BaseType::Color
    }
}

/// A USD value as a vstructc value, typed as `declared` says when it fits.
#[cfg_attr(feature = "testkit", visibility::make(pub))]
fn to_value(v: &sdf::Value, declared: Option<&Type>, usd_type: &str) -> Option<Value> {
    use sdf::Value as V;
    let base = declared.map(|t| &t.base);
    let int = |i: i64| -> Value {
        match base {
            Some(BaseType::Float) => Value::Float(i as f32),
            Some(BaseType::Bool) => Value::Bool(i != 0),
            _ => Value::Int(i.clamp(i32::MIN as i64, i32::MAX as i64) as i32),
        }
    };
    let float = |x: f64| -> Value {
        match base {
            Some(BaseType::Int) if x.fract() == 0.0 && x.abs() <= i32::MAX as f64 => {
                Value::Int(x as i32)
            }
            _ => Value::Float(sat(x)),
        }
    };
    let text = |s: &str, usd: BaseType| -> Value {
        let s = usda::decoded(s);
        match base.unwrap_or(&usd) {
            BaseType::Token => Value::Token(s.to_string()),
            BaseType::Asset => Value::Asset(s.to_string()),
            _ => Value::Str(s.to_string()),
        }
    };
    // The triple type: the declared one when it is a triple, else the one USD names.
    let triple_type = || match base {
        Some(b) if b.is_triple() => b.clone(),
        _ => triple_base(usd_type),
    };
    let triple = |f: [f32; 3]| -> Value {
        let b = triple_type();
        match declared {
            Some(t) if t.base == BaseType::Float && t.is_array() => Value::Array(
                BaseType::Float,
                f.iter().map(|&x| Value::Float(x)).collect(),
            ),
            _ => Value::Triple(b, f),
        }
    };
    let floats = |xs: Vec<f64>| -> Value {
        Value::Array(
            BaseType::Float,
            xs.into_iter().map(|x| Value::Float(sat(x))).collect(),
        )
    };
    let d3 = |x: [f64; 3]| x.map(sat);
    let arr = |b: BaseType, items: Vec<Value>| Value::Array(b, items);
    Some(match v {
        V::Bool(b) => match base {
            Some(BaseType::Bool) | None => Value::Bool(*b),
            _ => int(i64::from(*b)),
        },
        V::Int(i) => int(i64::from(*i)),
        V::Uint(i) => int(i64::from(*i)),
        V::Uchar(i) => int(i64::from(*i)),
        V::Int64(i) => int(*i),
        V::Uint64(i) => int(i64::try_from(*i).unwrap_or(i64::MAX)),
        V::Float(x) => float(f64::from(*x)),
        V::Double(x) => float(*x),
        V::Half(x) => float(f64::from(x.to_f32())),
        V::String(s) => text(s, BaseType::String),
        V::Token(t) => text(t.as_str(), BaseType::Token),
        V::AssetPath(a) => text(&a.authored_path, BaseType::Asset),
        V::Vec3f(x) => triple([x.x, x.y, x.z]),
        V::Vec3d(x) => triple(d3([x.x, x.y, x.z])),
        V::Vec3h(x) => triple([x.x.to_f32(), x.y.to_f32(), x.z.to_f32()]),
        V::Vec2f(x) => floats(vec![f64::from(x.x), f64::from(x.y)]),
        V::Vec2d(x) => floats(vec![x.x, x.y]),
        V::Vec4f(x) => match base {
            Some(BaseType::HPoint) => Value::HPoint([x.x, x.y, x.z, x.w]),
            _ => floats(
                vec![x.x, x.y, x.z, x.w]
                    .into_iter()
                    .map(f64::from)
                    .collect(),
            ),
        },
        V::Vec4d(x) => match base {
            Some(BaseType::HPoint) => Value::HPoint([x.x, x.y, x.z, x.w].map(sat)),
            _ => floats(vec![x.x, x.y, x.z, x.w]),
        },
        V::Matrix4d(m) => {
            let mut out = [0.0f32; 16];
            for (o, x) in out.iter_mut().zip(m.0.iter()) {
                *o = sat(*x);
            }
            Value::Matrix(out)
        }
        V::BoolVec(xs) => arr(
            BaseType::Int,
            xs.iter().map(|&b| Value::Int(i32::from(b))).collect(),
        ),
        V::IntVec(xs) => match base {
            Some(BaseType::Float) => arr(
                BaseType::Float,
                xs.iter().map(|&i| Value::Float(i as f32)).collect(),
            ),
            _ => arr(BaseType::Int, xs.iter().map(|&i| Value::Int(i)).collect()),
        },
        V::FloatVec(xs) => floats(xs.iter().map(|&x| f64::from(x)).collect()),
        V::DoubleVec(xs) => floats(xs.clone()),
        V::StringVec(xs) => {
            let b = base.cloned().unwrap_or(BaseType::String);
            arr(b.clone(), xs.iter().map(|s| text(s, b.clone())).collect())
        }
        V::TokenVec(xs) => {
            let b = base.cloned().unwrap_or(BaseType::Token);
            arr(
                b.clone(),
                xs.iter().map(|s| text(s.as_str(), b.clone())).collect(),
            )
        }
        V::AssetPathVec(xs) => arr(
            BaseType::Asset,
            xs.iter()
                .map(|a| text(&a.authored_path, BaseType::Asset))
                .collect(),
        ),
        V::Vec3fVec(xs) => {
            let b = triple_type();
            arr(
                b.clone(),
                xs.iter()
                    .map(|x| Value::Triple(b.clone(), [x.x, x.y, x.z]))
                    .collect(),
            )
        }
        V::Vec3dVec(xs) => {
            let b = triple_type();
            arr(
                b.clone(),
                xs.iter()
                    .map(|x| Value::Triple(b.clone(), d3([x.x, x.y, x.z])))
                    .collect(),
            )
        }
        V::Vec2fVec(xs) => arr(
            BaseType::Float,
            xs.iter()
                .flat_map(|x| [Value::Float(x.x), Value::Float(x.y)])
                .collect(),
        ),
        _ => return None,
    })
}

/// Open the stage whose root layer is `bytes`; an `openusd` failure or panic is the reason
/// as text.
pub(crate) fn open_stage(name: &str, bytes: &[u8]) -> Result<usd::Stage, String> {
    let (resolver, root) = mem_resolver(name, bytes);
    let opened = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        usd::Stage::builder().resolver(resolver).open(&root)
    }));
    match opened {
        Ok(Ok(stage)) => Ok(stage),
        Ok(Err(e)) => Err(format!("{e:#}")),
        Err(_) => Err("the USD library failed on this input".to_string()),
    }
}

/// The types of the prims `paths` on the stage whose root layer is `bytes`, named `name` as
/// for [`parse_usd`]: `""` for an untyped prim; a prim the stage does not hold, or a stage
/// that does not open, gives nothing (crate-internal: the USD writer keeps these types).
pub(crate) fn prim_types(name: &str, bytes: &[u8], paths: &[String]) -> FxHashMap<String, String> {
    let mut out = FxHashMap::default();
    if paths.is_empty() {
        return out;
    }
    let looked_up = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        let flat = (!(flavour(bytes) == "usda" && may_compose(bytes)))
            .then(|| open_flat(name, bytes))
            .flatten();
        if let Some((data, ..)) = &flat {
            for p in paths {
                let path = sdf::Path::from(p.as_str());
                if data.spec_type(&path) != Some(sdf::SpecType::Prim) {
                    continue;
                }
                let t = match data.try_field(&path, sdf::FieldKey::TypeName.as_str()) {
                    Ok(Some(v)) => match v.as_ref() {
                        sdf::Value::Token(t) => t.as_str().to_string(),
                        _ => String::new(),
                    },
                    _ => String::new(),
                };
                out.insert(p.clone(), t);
            }
            return;
        }
        let Ok(stage) = open_stage(name, bytes) else {
            return;
        };
        for p in paths {
            let prim = stage.prim(sdf::Path::from(p.as_str()));
            if !matches!(prim.specifier(), Ok(Some(_))) {
                continue;
            }
            let t = prim.type_name().ok().flatten();
            out.insert(
                p.clone(),
                t.map(|t| t.as_str().to_string()).unwrap_or_default(),
            );
        }
    }));
    if looked_up.is_err() {
        out.clear();
    }
    out
}

/// The resolver that serves root layer `bytes` named `name`, and the root's identifier.
fn mem_resolver(name: &str, bytes: &[u8]) -> (MemResolver, String) {
    let root_path = root_name(name, bytes);
    let inner = ar::DefaultResolver::new();
    let root = ar::Resolver::create_identifier(&inner, &root_path, None);
    let (bytes, encoded) = match openusd_form(Cow::Borrowed(bytes)) {
        Ok((bytes, encoded)) => (Ok(bytes), encoded),
        Err(why) => (Err(why), 0),
    };
    let resolver = MemResolver {
        inner,
        root: root.clone(),
        bytes,
        encoded,
    };
    (resolver, root)
}

/// Whether usda text `bytes` may hold something that composes, so that reading it alone
/// would be parsing it twice: a word that only composition arcs, variants, prim states and
/// layer metadata use, `over "` or `class `. A false alarm only means the stage is
/// composed; a miss, that the text is parsed twice.
fn may_compose(bytes: &[u8]) -> bool {
    const WORDS: [&[u8]; 10] = [
        b"subLayers",
        b"references",
        b"payload",
        b"inherits",
        b"specializes",
        b"variant",
        b"active",
        b"instanceable",
        b"relocates",
        b"Order",
    ];
    WORDS
        .iter()
        .chain([b"over \"".as_slice(), b"class "].iter())
        .any(|w| memchr::memmem::find(bytes, w).is_some())
}

/// The path of property `name` of prim `prim` (a prim path, never a property path), or
/// nothing for an empty name or `.`, which name no property.
fn property_path(prim: &sdf::Path, name: &str) -> Option<sdf::Path> {
    if name.is_empty() || name == "." {
        return None;
    }
    let mut p = String::with_capacity(prim.as_str().len() + 1 + name.len());
    p.push_str(prim.as_str());
    p.push('.');
    p.push_str(name);
    Some(sdf::Path::from(p))
}

/// Whether no name in `names` is given twice.
fn all_differ(names: &[openusd::tf::Token]) -> bool {
    if names.len() <= 8 {
        return names
            .iter()
            .enumerate()
            .all(|(i, a)| names[..i].iter().all(|b| a.as_str() != b.as_str()));
    }
    let mut seen = rustc_hash::FxHashSet::default();
    names.iter().all(|n| seen.insert(n.as_str()))
}

/// The path of child `name` of prim `prim` (the root or a prim path that is no variant
/// selection), as [`sdf::Path::append_path`] makes it: a name that is an identifier is
/// appended directly, any other through `append_path`, which refuses what is no prim name.
fn child_path(prim: &sdf::Path, name: &str) -> Option<sdf::Path> {
    if !sdf::Path::is_valid_identifier(name) {
        return prim.append_path(name).ok();
    }
    let parent = prim.as_str();
    let mut p = String::with_capacity(parent.len() + 1 + name.len());
    p.push_str(parent);
    if parent != "/" {
        p.push('/');
    }
    p.push_str(name);
    Some(sdf::Path::from(p))
}

/// A field read from a layer alone.
type FieldRead<'a> = Result<Option<std::borrow::Cow<'a, sdf::Value>>, sdf::DataError>;

/// An attribute's default value from its `default` field: a blocked value is none. (The
/// stage would resolve asset paths too; the reader keeps only the authored path, which
/// resolution leaves as it is.)
fn default_of(field: FieldRead<'_>) -> Result<Option<sdf::Value>, String> {
    match field.map_err(|e| e.to_string())? {
        None => Ok(None),
        Some(v) => match v.as_ref() {
            sdf::Value::ValueBlock => Ok(None),
            _ => Ok(Some(v.into_owned())),
        },
    }
}

/// A token list field's tokens (`propertyChildren`), or none when it is missing, unreadable
/// or of another type.
fn tokens_of(field: FieldRead<'_>) -> Vec<openusd::tf::Token> {
    match field {
        Ok(Some(v)) => match v.into_owned() {
            sdf::Value::TokenVec(names) => names,
            _ => Vec::new(),
        },
        _ => Vec::new(),
    }
}

/// The `inputs:` properties among `names`, each input once (its first), in order: the
/// property's name and the input's.
fn distinct_inputs<'n>(names: &[&'n str]) -> impl Iterator<Item = (&'n str, &'n str)> {
    let mut seen = rustc_hash::FxHashSet::default();
    names.iter().filter_map(move |&n| {
        let input = n.strip_prefix("inputs:")?;
        seen.insert(input).then_some((n, input))
    })
}

/// An attribute's connection targets from its `connectionPaths` field.
fn targets_of(field: FieldRead<'_>) -> Vec<sdf::Path> {
    match field {
        Ok(Some(v)) => match v.as_ref() {
            sdf::Value::PathListOp(op) => op.compose_over(&[]),
            _ => Vec::new(),
        },
        _ => Vec::new(),
    }
}

/// An attribute's number of time samples from its `timeSamples` field.
fn samples_of(field: FieldRead<'_>) -> usize {
    match field {
        Ok(Some(v)) => match v.as_ref() {
            sdf::Value::TimeSamples(t) => t.len(),
            _ => 0,
        },
        _ => 0,
    }
}

/// An attribute's USD type name from its `typeName` field, or nothing (a token read from
/// a crate file is shared, not copied).
fn type_name_of(field: FieldRead<'_>) -> openusd::tf::Token {
    match field {
        Ok(Some(v)) => match v {
            std::borrow::Cow::Owned(sdf::Value::Token(t)) => t,
            std::borrow::Cow::Borrowed(sdf::Value::Token(t)) => t.clone(),
            _ => match v.as_ref() {
                sdf::Value::String(t) => openusd::tf::Token::from(t.as_str()),
                _ => openusd::tf::Token::default(),
            },
        },
        _ => openusd::tf::Token::default(),
    }
}

/// What the reader reads of an attribute ([`Reader::attr_fields`]).
struct AttrFields {
    /// Its USD type name, or nothing.
    type_name: openusd::tf::Token,
    /// Its default value (a blocked value is none), or why it cannot be read.
    default: Result<Option<sdf::Value>, String>,
    /// Its connection targets.
    targets: Vec<sdf::Path>,
    /// Its number of time samples.
    samples: usize,
}

/// What the reader of a layer read alone asks of its specs (see [`open_flat`]): the read
/// side of `openusd`'s [`sdf::AbstractData`], which a usda layer's data answers, and
/// [`CrateLayer`] for a crate file.
trait Specs {
    /// The type of the spec at `path`, if there is one.
    fn spec_type(&self, path: &sdf::Path) -> Option<sdf::SpecType>;
    /// Field `field` of the spec at `path`, if both exist.
    fn try_field(
        &self,
        path: &sdf::Path,
        field: &str,
    ) -> Result<Option<std::borrow::Cow<'_, sdf::Value>>, sdf::DataError>;
    /// The names of the fields of the spec at `path`.
    fn list_fields(&self, path: &sdf::Path) -> Option<Vec<String>>;
    /// The crate file these specs are, if they are one.
    fn as_crate(&self) -> Option<&CrateLayer> {
        None
    }
    /// Drops these specs (a crate file's, which hold a string per path, on rayon's pool
    /// when it can help, so that the reader returns without freeing them).
    fn drop_soon(self: Box<Self>) {}
    /// Whether every field of the spec at `path` is named in `allowed`; nothing when there
    /// is no spec there.
    fn fields_within(&self, path: &sdf::Path, allowed: &[&str]) -> Option<bool> {
        Some(
            self.list_fields(path)?
                .iter()
                .all(|f| allowed.contains(&f.as_str())),
        )
    }
    /// What the reader reads of the attribute at `path`, or nothing when there is no
    /// attribute spec there.
    fn attribute(&self, path: &sdf::Path) -> Option<AttrFields> {
        if self.spec_type(path) != Some(sdf::SpecType::Attribute) {
            return None;
        }
        Some(AttrFields {
            type_name: type_name_of(self.try_field(path, sdf::FieldKey::TypeName.as_str())),
            default: default_of(self.try_field(path, sdf::FieldKey::Default.as_str())),
            targets: targets_of(self.try_field(path, sdf::FieldKey::ConnectionPaths.as_str())),
            samples: samples_of(self.try_field(path, sdf::FieldKey::TimeSamples.as_str())),
        })
    }
}

impl Specs for sdf::LayerData {
    fn spec_type(&self, path: &sdf::Path) -> Option<sdf::SpecType> {
        self.as_ref().spec_type(path)
    }

    fn try_field(
        &self,
        path: &sdf::Path,
        field: &str,
    ) -> Result<Option<std::borrow::Cow<'_, sdf::Value>>, sdf::DataError> {
        self.as_ref().try_field(path, field)
    }

    fn list_fields(&self, path: &sdf::Path) -> Option<Vec<String>> {
        self.as_ref().list_fields(path)
    }
}

/// A layer read alone: its specs, its prims in traversal order and, for a crate file
/// walked by index, each prim's path index.
type FlatLayer = (Box<dyn Specs>, Vec<sdf::Path>, Vec<usize>);

/// The root layer `bytes` (a `.usda` or `.usdc`, named so and holding that encoding) read
/// alone, with its prims in traversal order, when nothing in it composes
/// ([`flat_prims`]); else nothing, and the stage is composed instead.
/// A crate file's prims come with their path indices when walked by index
/// ([`CrateLayer::flat_prims_by_index`]); else the indices are empty.
fn open_flat(name: &str, bytes: &[u8]) -> Option<FlatLayer> {
    let (resolver, root) = mem_resolver(name, bytes);
    let ext = root.rsplit('.').next()?.to_ascii_lowercase();
    if ext != flavour(bytes) {
        return None;
    }
    let resolved = ar::ResolvedPath::new(&root);
    let read = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        let data: Box<dyn Specs> = match ext.as_str() {
            "usdc" => {
                let layer = CrateLayer::open(bytes)?;
                if let Some(walked) = layer.flat_prims_by_index() {
                    let (prims, indices) = walked?;
                    return Some((Box::new(layer) as Box<dyn Specs>, prims, indices));
                }
                Box::new(layer)
            }
            "usda" => Box::new(
                sdf::FileFormat::read(&openusd::usda::UsdaFileFormat, &resolver, &resolved).ok()?,
            ),
            _ => return None,
        };
        let prims = flat_prims(data.as_ref())?;
        Some((data, prims, Vec::new()))
    }));
    read.ok().flatten()
}

/// The usda text `bytes` read as one layer, without composing anything (crate-internal:
/// the USD writer encodes its text layers in the binary form from it).
pub(crate) fn read_usda_layer(bytes: &[u8]) -> Result<sdf::LayerData, String> {
    let (resolver, root) = mem_resolver("<written>.usda", bytes);
    let resolved = ar::ResolvedPath::new(&root);
    let read = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        sdf::FileFormat::read(&openusd::usda::UsdaFileFormat, &resolver, &resolved)
    }));
    match read {
        Ok(Ok(mut data)) => {
            if resolver.encoded > 0 {
                decode_values(data.as_mut());
            }
            Ok(data)
        }
        Ok(Err(e)) => Err(format!("{e:#}")),
        Err(_) => Err("the USD library failed on this layer".to_string()),
    }
}

/// Every encoded value of `data` decoded ([`usda::decoded`]): the layer then holds what
/// its text does, as the crate writer is to write it.
fn decode_values(data: &mut dyn sdf::AbstractData) {
    fn text(s: &mut String) -> bool {
        match usda::decoded(s) {
            Cow::Owned(v) => {
                *s = v;
                true
            }
            Cow::Borrowed(_) => false,
        }
    }
    fn token(t: &mut openusd::tf::Token) -> bool {
        match usda::decoded(t.as_str()) {
            Cow::Owned(v) => {
                *t = openusd::tf::Token::from(v.as_str());
                true
            }
            Cow::Borrowed(_) => false,
        }
    }
    for path in data.spec_paths() {
        for field in data.list_fields(&path).unwrap_or_default() {
            let Ok(Some(value)) = data.try_field(&path, &field) else {
                continue;
            };
            let mut value = value.into_owned();
            let changed = match &mut value {
                sdf::Value::String(s) => text(s),
                sdf::Value::Token(t) => token(t),
                sdf::Value::AssetPath(a) => text(&mut a.authored_path),
                sdf::Value::StringVec(xs) => xs.iter_mut().fold(false, |c, s| text(s) | c),
                sdf::Value::TokenVec(xs) => xs.iter_mut().fold(false, |c, t| token(t) | c),
                sdf::Value::AssetPathVec(xs) => xs
                    .iter_mut()
                    .fold(false, |c, a| text(&mut a.authored_path) | c),
                _ => false,
            };
            if changed {
                data.set_field(&path, &field, value);
            }
        }
    }
}

/// Read the materials of the USD stage whose root layer is `bytes` (named `name` in
/// diagnostics; references and sublayers are found relative to it), with the parameter
/// types of `types`. A stage that cannot be opened is an error (US001); composition
/// problems (an unresolvable reference or sublayer, US002), shaders without `info:id`
/// (US003), ignored time samples (US004), dangling or cyclic connections (US002, US005)
/// and values of types vstructc does not read (US006) are warnings in `diags`.
///
/// ```
/// use vstructc::Diagnostics;
/// use vstructc::front::usd::parse_usd;
/// use vstructc::limits::Limits;
/// use vstructc::registry::Registry;
///
/// let text = br#"#usda 1.0
/// def Material "M" {
///     token outputs:ri:surface.connect = </M/S.outputs:out>
///     def Shader "S" {
///         uniform token info:id = "PxrSurface"
///         color3f inputs:diffuseColor = (0.8, 0.2, 0.2)
///         token outputs:out
///     }
/// }
/// "#;
/// let mut diags = Diagnostics::new();
/// let net = parse_usd(text, "look.usda", &Registry::embedded(), &Limits::default(), &mut diags)
///     .unwrap();
/// let s = net.find("/M/S").unwrap();
/// assert_eq!(net[s].shader(), "PxrSurface");
/// assert_eq!(net.materials()[0].name, "/M");
/// ```
pub fn parse_usd(
    bytes: &[u8],
    name: &str,
    types: &dyn ParamTypes,
    limits: &Limits,
    diags: &mut Diagnostics,
) -> Result<Network, Error> {
    read_usd(bytes, name, types, limits, diags, true)
}

/// [`parse_usd`] through the composed stage always, never reading the root layer alone:
/// what the direct reading of a layer that does not compose must equal.
#[cfg(feature = "testkit")]
pub fn parse_usd_composed(
    bytes: &[u8],
    name: &str,
    types: &dyn ParamTypes,
    limits: &Limits,
    diags: &mut Diagnostics,
) -> Result<Network, Error> {
    read_usd(bytes, name, types, limits, diags, false)
}

/// Whether nothing in root layer `bytes` named `name` composes, so that [`parse_usd`] may
/// read it alone, without composing a stage (a `.usda` whose text suggests composition
/// is composed without asking).
#[cfg(feature = "testkit")]
pub fn reads_layer_alone(bytes: &[u8], name: &str) -> bool {
    open_flat(name, bytes).is_some()
}

#[cfg(feature = "testkit")]
pub use crate_file::crate_values_agree;

/// [`parse_usd`], reading the root layer alone when `direct` and nothing in it composes.
fn read_usd(
    bytes: &[u8],
    name: &str,
    types: &dyn ParamTypes,
    limits: &Limits,
    diags: &mut Diagnostics,
    direct: bool,
) -> Result<Network, Error> {
    let file: Arc<str> = Arc::from(name);
    limits
        .check(Limit::NetworkFileBytes, bytes.len() as u64)
        .map_err(|e| e.at(Location::file(file.clone())))?;
    let flat_layer = (direct && !(flavour(bytes) == "usda" && may_compose(bytes)))
        .then(|| open_flat(name, bytes))
        .flatten();
    let stage = match flat_layer {
        Some(_) => None,
        None => Some(open_stage(name, bytes).map_err(|why| cannot_open(&file, bytes, &why))?),
    };
    let (flat, prims, indices) = match &flat_layer {
        Some((data, prims, indices)) => (
            Some(data.as_ref()),
            Some(prims.as_slice()),
            indices.as_slice(),
        ),
        None => (None, None, &[][..]),
    };
    let indexed = flat
        .and_then(|f| f.as_crate())
        .filter(|_| !indices.is_empty());
    let mut reader = Reader {
        stage: stage.as_ref(),
        flat,
        indexed,
        file: file.clone(),
        types,
        diags,
        kinds: FxHashMap::default(),
        nodes: FxHashMap::default(),
        net: Network::new(),
        sampled: Vec::new(),
        declared: FxHashMap::default(),
    };
    let walked = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        read_stage(&mut reader, prims, indices)
    }));
    let outcome = match walked {
        Ok(r) => r,
        Err(_) => Err(Error::from(
            Diagnostic::error("US001", "the USD library failed while composing the stage")
                .at(Location::file(file.clone())),
        )),
    };
    outcome?;
    let net = reader.net;
    net.check_limits(limits)?;
    if let Some((data, ..)) = flat_layer {
        data.drop_soon();
    }
    Ok(net)
}

/// US001 for a stage that does not open for reason `why`: at the place in root layer
/// `bytes` where the text stops reading, when the root is the usda text at fault.
fn cannot_open(file: &Arc<str>, bytes: &[u8], why: &str) -> Error {
    let at = (flavour(bytes) == "usda")
        .then(|| usda_failure_at(bytes))
        .flatten()
        .and_then(|offset| {
            Some(Location::from_offset(
                file.clone(),
                std::str::from_utf8(bytes).ok()?,
                offset,
            ))
        })
        .unwrap_or_else(|| Location::file(file.clone()));
    Diagnostic::error("US001", format!("cannot open the USD stage: {why}"))
        .at(at)
        .into()
}

/// The byte offset where usda text `bytes` stops reading, as Pixar's USD lexes it and as
/// `openusd` parses it; nothing when it reads (the fault is elsewhere).
fn usda_failure_at(bytes: &[u8]) -> Option<usize> {
    let normalised = match usda::normalise(bytes) {
        Ok(n) => n,
        Err(e) => return Some(e.offset),
    };
    let text = std::str::from_utf8(&normalised.text).ok()?;
    let mut parser = openusd::usda::parser::Parser::new(text);
    let failed = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| parser.parse().is_err()));
    if !matches!(failed, Ok(true)) {
        return None;
    }
    let place = parser.last_error_highlight()?;
    Some(normalised.original_offset(usda::offset_of(text, place.line, place.column)))
}

/// The walk: prims, nodes, materials, inputs, composition errors.
/// `prims` are the prims of the flat layer, in traversal order, when it is read.
/// `indices`: their path indices when the crate file was walked by index, else empty.
fn read_stage(
    r: &mut Reader<'_>,
    prims: Option<&[sdf::Path]>,
    indices: &[usize],
) -> Result<(), Error> {
    let traversed;
    let paths = match (prims, r.stage) {
        (Some(paths), _) => paths,
        (None, None) => &[],
        (None, Some(stage)) => {
            let mut paths = Vec::new();
            stage
                .traverse(usd::PrimPredicate::DEFAULT, |p| paths.push(p.clone()))
                .map_err(|e| {
                    Error::from(
                        Diagnostic::error("US001", format!("cannot traverse the USD stage: {e:#}"))
                            .at(Location::file(r.file.clone())),
                    )
                })?;
            traversed = paths;
            &traversed
        }
    };
    // Depth-first order: a material comes before its shaders.
    let mut shaders = Vec::new();
    let mut materials: Vec<(String, Option<usize>, Vec<NodeId>)> = Vec::new();
    // Each material's place in `materials`, by prim path.
    let mut material_at: FxHashMap<String, usize> = FxHashMap::default();
    for (n, p) in paths.iter().enumerate() {
        let index = indices.get(n).copied();
        let Some(kind) = r.kind_of(p, index) else {
            continue;
        };
        r.kinds.insert(p.as_str().to_string(), kind);
        match kind {
            PrimKind::Material => {
                material_at.insert(p.as_str().to_string(), materials.len());
                materials.push((p.as_str().to_string(), index, Vec::new()));
            }
            PrimKind::Shader => shaders.push((p.clone(), index)),
            PrimKind::NodeGraph => {}
        }
    }
    let mut pending = Vec::with_capacity(shaders.len());
    // Each shader type's kind, asked of the definitions once.
    let mut kind_of_type: FxHashMap<String, RequestKind> = FxHashMap::default();
    read_shaders(r, &shaders, |r, n, read| {
        let path = shaders[n].0.as_str().to_string();
        let (source, id) = read.texts.unwrap_or_else(|p| std::panic::resume_unwind(p));
        let shader = r.shader_id(&path, source, id);
        let kind = match kind_of_type.get(&shader) {
            Some(&kind) => kind,
            None => {
                let kind = r.types.shader_kind(&shader).unwrap_or(RequestKind::Pattern);
                kind_of_type.insert(shader.clone(), kind);
                kind
            }
        };
        let (params, links) = r.read_inputs(read.inputs, Sym::new(&shader));
        if let Some(panic) = read.stop {
            std::panic::resume_unwind(panic);
        }
        let mut node = Node::new_raw(&path, &shader, kind);
        node.set_raw_params(params);
        let id = r.net.insert_node(node);
        r.net.set_node_location(id, r.at(&path));
        r.nodes.insert(path.clone(), id);
        pending.push((id, links));
        // The nearest enclosing Material owns the shader (a prim path's ancestors are its
        // prefixes up to each `/`).
        let mut owner = path.as_str();
        while let Some(cut) = owner.rfind('/') {
            owner = &owner[..cut];
            if r.kinds.get(owner) == Some(&PrimKind::Material) {
                if let Some(&m) = material_at.get(owner) {
                    materials[m].2.push(id);
                }
                break;
            }
        }
    });
    // Connections bind to their prims wherever they are: once every node exists.
    for (id, links) in pending {
        for (param, sources) in links {
            let links = sources
                .into_iter()
                .map(|(prim, output, missing)| {
                    if missing {
                        Link::missing(&prim, output.as_deref())
                    } else {
                        Link::node(r.nodes[&prim], output.as_deref())
                    }
                })
                .collect();
            r.net.push_source_links(id, param, links);
        }
    }
    for (name, index, ids) in materials {
        let terminals = r.terminals(&name, index);
        for t in &terminals {
            if let Some(id) = t.link.upstream_node()
                && r.types.shader_kind(r.net[id].shader()).is_none()
            {
                r.net
                    .set_node_kind(id, RequestKind::from_terminal_name(&t.name));
            }
        }
        let location = Some(r.at(&name));
        r.net.materials_mut().push(Material {
            name,
            terminals,
            nodes: MaterialNodes::Explicit(ids),
            primvars: Vec::new(),
            location,
        });
    }
    if !r.sampled.is_empty() {
        let first = r.sampled[0].clone();
        let n = r.sampled.len();
        r.warn(
            "US004",
            &first,
            format!(
                "time samples ignored on {n} input(s) (first: `{first}`); the default values \
                 are used"
            ),
        );
    }
    for e in r
        .stage
        .map(usd::Stage::composition_errors)
        .unwrap_or_default()
    {
        let d = Diagnostic::warning("US002", format!("composition: {e}"))
            .at(Location::file(r.file.clone()));
        r.diags.push(d);
    }
    Ok(())
}

/// The layer fields that change what a layer read alone gives ([`flat_prims`]).
const ROOT_CHANGES: [&str; 5] = [
    "subLayers",
    "subLayerOffsets",
    "layerRelocates",
    "relocates",
    "expressionVariables",
];

/// The only fields a prim of a layer read alone may have ([`flat_prims`]).
const PRIM_KEEPS: [&str; 10] = [
    "specifier",
    "typeName",
    "primChildren",
    "propertyChildren",
    "kind",
    "documentation",
    "comment",
    "customData",
    "displayName",
    "hidden",
];

/// The prims of a stage whose only layer is `data`, in the stage's traversal order, when
/// nothing in the layer composes: every prim is a `def` whose only fields are its type,
/// children, properties and metadata that changes nothing the reader reads. Anything else
/// (an arc, a variant set, an `over` or `class`, `active`, `instanceable`, child or
/// property reordering, sublayers or relocates on the layer) gives nothing, and the
/// composed stage is read instead.
fn flat_prims(data: &dyn Specs) -> Option<Vec<sdf::Path>> {
    let root = sdf::Path::abs_root();
    let fields = data.list_fields(&root)?;
    if fields.iter().any(|f| ROOT_CHANGES.contains(&f.as_str())) {
        return None;
    }
    let children = |path: &sdf::Path| -> Option<Vec<sdf::Path>> {
        match data.try_field(path, "primChildren").ok()? {
            None => Some(Vec::new()),
            Some(v) => match v.as_ref() {
                // A name given twice is for the composed stage to settle.
                sdf::Value::TokenVec(names) if all_differ(names) => {
                    names.iter().map(|n| child_path(path, n.as_str())).collect()
                }
                _ => None,
            },
        }
    };
    let mut out = Vec::new();
    let mut stack: Vec<sdf::Path> = children(&root)?;
    stack.reverse();
    while let Some(path) = stack.pop() {
        if data.spec_type(&path) != Some(sdf::SpecType::Prim) {
            return None;
        }
        if !data.fields_within(&path, &PRIM_KEEPS)? {
            return None;
        }
        match data.try_field(&path, "specifier").ok()?.as_deref() {
            Some(sdf::Value::Specifier(sdf::Specifier::Def)) => {}
            _ => return None,
        }
        let mut kids = children(&path)?;
        kids.reverse();
        stack.extend(kids);
        out.push(path);
    }
    Some(out)
}

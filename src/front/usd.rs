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
//! set. The reader decodes a crate file's tables (`crate_tables`) and its usual values
//! itself when the file is laid out as USD's writers lay it out, and leaves anything else
//! to `openusd`, which reads (or refuses) it as it would alone.
//!
//! Diagnostics name the file and the prim or property path (in [`Location::pointer`]);
//! `openusd` keeps no line numbers, so USD diagnostics have none.

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

mod crate_tables;
mod usda;
use crate_tables::{
    CRATE_BOOL, CRATE_DOUBLE, CRATE_FLOAT, CRATE_INT, CRATE_PATH_LIST_OP, CRATE_SPECIFIER,
    CRATE_STRING, CRATE_TOKEN, CRATE_TOKEN_VECTOR, CRATE_VEC3F, CrateTables, NO_PATH, PathTree,
    Rep, le_size,
};

/// How many NodeGraph or Material inputs and outputs a connection is followed through
/// before it is reported as a cycle (US005).
const MAX_HOPS: usize = 64;

/// Serves the root layer from the bytes already read (so standard input works and the file
/// is read once) and everything it refers to from the file system, anchored at the root's
/// folder.
struct MemResolver {
    inner: ar::DefaultResolver,
    root: String,
    bytes: Arc<Vec<u8>>,
}

impl MemResolver {
    /// The packaged path inside the root, when `path` is `root[inner]`.
    fn in_root_package<'a>(&self, path: &'a str) -> Option<&'a str> {
        path.strip_prefix(self.root.as_str())?
            .strip_prefix('[')?
            .strip_suffix(']')
    }

    fn root_entry(&self, inner: &str) -> io::Result<Vec<u8>> {
        let mut archive = zip::ZipArchive::new(io::Cursor::new(self.bytes.as_slice()))
            .map_err(io::Error::other)?;
        let mut entry = archive.by_name(inner).map_err(io::Error::other)?;
        let mut out = Vec::new();
        entry.read_to_end(&mut out)?;
        openusd_form(out)
    }
}

/// Layer `bytes` as `openusd` is to read them: usda text in the form in which `openusd`
/// reads what Pixar's USD reads ([`usda::normalise`]); a crate file as it is. Text Pixar's
/// USD would not lex is refused here, with the reason, so that `openusd` (which is more
/// lenient) does not read it.
fn openusd_form(bytes: Vec<u8>) -> io::Result<Vec<u8>> {
    if flavour(&bytes) != "usda" {
        return Ok(bytes);
    }
    match usda::normalise(&bytes) {
        Ok(n) => Ok(match n.text {
            Cow::Borrowed(_) => bytes,
            Cow::Owned(text) => text,
        }),
        Err(e) => Err(io::Error::other(e.message)),
    }
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
            return Ok(Box::new(io::Cursor::new(openusd_form(
                self.bytes.as_ref().clone(),
            )?)));
        }
        if let Some(inner) = self.in_root_package(&path) {
            return Ok(Box::new(io::Cursor::new(self.root_entry(inner)?)));
        }
        let mut bytes = Vec::new();
        self.inner.open_asset(resolved)?.read_to_end(&mut bytes)?;
        Ok(Box::new(io::Cursor::new(openusd_form(bytes)?)))
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
    let resolver = MemResolver {
        inner,
        root: root.clone(),
        bytes: Arc::new(bytes.to_vec()),
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

/// The crate file type [`CrateLayer`] reads values through when it does not decode them.
type CrateFile = openusd::usdc::CrateFile<io::Cursor<Arc<[u8]>>>;

/// The hash [`CrateLayer`] finds a spec by: its path's text, hashed with FxHash.
fn path_hash(path: &sdf::Path) -> u64 {
    use std::hash::BuildHasher;
    rustc_hash::FxBuildHasher.hash_one(path.as_str())
}

/// A crate file's specs, indexed once: each spec's type and fields by path, each field
/// name's token, so that a field is found by comparing token indices in the spec's field
/// set (`openusd`'s own crate data compares names and hashes paths with SipHash). The
/// tables are decoded here ([`CrateTables`]) when the file is laid out as writers lay it
/// out, else by `openusd`; the values the reader reads most (tokens, token arrays and
/// vectors, specifiers, booleans, ints, floats, doubles, 3-vectors of floats, path list
/// operations) are decoded here, any other by `openusd`, which then reads the file once.
struct CrateLayer {
    /// `openusd`'s reading of the file: at once when the tables are not decoded here, else
    /// when a value not decoded here is first asked for.
    file: std::sync::Mutex<Option<CrateFile>>,
    /// The file's bytes (shared with `file`'s reader), for the values decoded here.
    bytes: Arc<[u8]>,
    /// The file's version: whether it is at least 0.5.0, and at least 0.7.0 (the layout of
    /// array headers).
    v05: bool,
    v07: bool,
    /// The file's tokens, each made a token once (values that are tokens, or arrays of
    /// tokens, are answered with clones of these).
    tokens: Vec<openusd::tf::Token>,
    /// The token index of each string.
    strings: Vec<usize>,
    /// Each field: its name's token index and its value representation.
    fields: Vec<(usize, u64)>,
    /// Field indices, each field set ended by nothing.
    fieldsets: Vec<Option<usize>>,
    paths: Vec<sdf::Path>,
    /// Each spec: its path's index in `paths`, its type and the start of its field set in
    /// `fieldsets`, found by the hash of its path (so the paths are not copied): made
    /// from `specs_in` when a spec is first looked up by path.
    specs: std::sync::OnceLock<hashbrown::HashTable<(usize, sdf::SpecType, usize)>>,
    /// Each spec: its path index, its field set's start and its type.
    specs_in: Vec<(usize, usize, sdf::SpecType)>,
    /// The path tree, when the tables are decoded here and no two paths are the same.
    tree: Option<PathTree>,
    /// Whether values not decoded here are read as none rather than by `openusd` (set
    /// only to compare the walks by index and by text on damaged files, where `openusd`
    /// may fail).
    decoded_only: std::sync::atomic::AtomicBool,
    /// With the tree: the type and field set start of the spec of each path index.
    spec_at: Vec<Option<(sdf::SpecType, usize)>>,
    /// The token index of each field name (under the names `openusd`'s layers use:
    /// `propertyChildren` for the crate's `properties`).
    names: FxHashMap<String, usize>,
    /// The field name of each token index that names a field.
    field_names: FxHashMap<usize, String>,
    /// The token indices of the fields [`Specs::attribute`] reads: `typeName`, `default`,
    /// `connectionPaths`, `timeSamples`.
    attribute_fields: [Option<usize>; 4],
    /// The token indices of the prim fields the walk by path index reads: `specifier`,
    /// `primChildren`, `propertyChildren`.
    prim_fields: [Option<usize>; 3],
}

impl CrateLayer {
    /// The crate file `bytes`, or nothing when it does not read or is not sound (then the
    /// stage is composed, and reports why).
    fn open(bytes: &[u8]) -> Option<Self> {
        let bytes: Arc<[u8]> = Arc::from(bytes);
        let (tables, file) = match CrateTables::decode(&bytes) {
            Some(tables) => (tables, None),
            None => {
                let mut file = CrateFile::open(io::Cursor::new(bytes.clone())).ok()?;
                file.validate().ok()?;
                let v = file.version();
                let tables = CrateTables {
                    version: [v.major, v.minor, v.patch],
                    tokens: file
                        .tokens
                        .iter()
                        .map(|t| openusd::tf::Token::from(t.as_str()))
                        .collect(),
                    strings: file.strings.clone(),
                    fields: file
                        .fields
                        .iter()
                        .map(|f| (f.token_index, f.value_rep.0))
                        .collect(),
                    fieldsets: std::mem::take(&mut file.fieldsets),
                    paths: std::mem::take(&mut file.paths),
                    tree: None,
                    specs: std::mem::take(&mut file.specs)
                        .into_iter()
                        .map(|s| (s.path_index, s.fieldset_index, s.spec_type))
                        .collect(),
                };
                (tables, Some(file))
            }
        };
        let CrateTables {
            version,
            tokens,
            strings,
            fields,
            fieldsets,
            paths,
            tree,
            specs: specs_in,
        } = tables;
        let mut spec_at = vec![None; if tree.is_some() { paths.len() } else { 0 }];
        for &(path_index, fieldset_index, spec_type) in &specs_in {
            paths.get(path_index)?;
            fieldsets.get(fieldset_index)?;
            // Paths all differ here: the last spec of a path index is its path's.
            if let Some(slot) = spec_at.get_mut(path_index) {
                *slot = Some((spec_type, fieldset_index));
            }
        }
        // Each token that names a field once (fields repeat their name, once per value): a
        // name given by two tokens keeps the token of its last field, as in file order.
        let mut names = FxHashMap::default();
        let mut field_names = FxHashMap::default();
        let mut seen = vec![false; tokens.len()];
        for &(token_index, _) in fields.iter().rev() {
            let (Some(token), Some(seen)) = (tokens.get(token_index), seen.get_mut(token_index))
            else {
                return None;
            };
            if std::mem::replace(seen, true) {
                continue;
            }
            let name = match token.as_str() {
                "properties" => "propertyChildren",
                t => t,
            };
            names.entry(name.to_string()).or_insert(token_index);
            field_names.insert(token_index, name.to_string());
        }
        let attribute_fields = [
            sdf::FieldKey::TypeName,
            sdf::FieldKey::Default,
            sdf::FieldKey::ConnectionPaths,
            sdf::FieldKey::TimeSamples,
        ]
        .map(|k| names.get(k.as_str()).copied());
        let prim_fields =
            ["specifier", "primChildren", "propertyChildren"].map(|k| names.get(k).copied());
        Some(CrateLayer {
            file: std::sync::Mutex::new(file),
            bytes,
            v05: version[1] >= 5,
            v07: version[1] >= 7,
            tokens,
            strings,
            fields,
            fieldsets,
            paths,
            tree,
            decoded_only: std::sync::atomic::AtomicBool::new(false),
            spec_at,
            specs_in,
            specs: std::sync::OnceLock::new(),
            names,
            field_names,
            attribute_fields,
            prim_fields,
        })
    }

    /// The type and the field set start of the spec at `path`.
    fn spec(&self, path: &sdf::Path) -> Option<(sdf::SpecType, usize)> {
        self.specs
            .get_or_init(|| {
                let paths = &self.paths;
                let mut specs = hashbrown::HashTable::with_capacity(self.specs_in.len());
                for &(path_index, fieldset_index, spec_type) in &self.specs_in {
                    let path = &paths[path_index];
                    let entry = (path_index, spec_type, fieldset_index);
                    // A path given twice keeps its last spec, as a map would.
                    match specs.entry(
                        path_hash(path),
                        |&(i, ..): &(usize, _, _)| paths[i] == *path,
                        |&(i, ..)| path_hash(&paths[i]),
                    ) {
                        hashbrown::hash_table::Entry::Occupied(mut e) => *e.get_mut() = entry,
                        hashbrown::hash_table::Entry::Vacant(e) => {
                            e.insert(entry);
                        }
                    }
                }
                specs
            })
            .find(path_hash(path), |&(i, ..)| self.paths[i] == *path)
            .map(|&(_, ty, start)| (ty, start))
    }

    /// The value representation of field `field` when it may be decoded here: any but a
    /// compressed one (`openusd` decodes those).
    fn own_rep(&self, field: usize) -> Option<Rep> {
        let rep = Rep(self.fields.get(field)?.1);
        (!rep.is_compressed()).then_some(rep)
    }

    /// The token of field `field` when it is an inlined token (as `typeName` is), without
    /// the 160-byte value [`CrateLayer::own_value`] would build and move.
    fn own_token(&self, field: usize) -> Option<openusd::tf::Token> {
        let rep = self.own_rep(field)?;
        match rep.layout() {
            (CRATE_TOKEN, false, true) => self.tokens.get(rep.low() as usize).cloned(),
            _ => None,
        }
    }

    /// The targets of field `field` when it is a path list operation decoded here (as
    /// `connectionPaths` is), without the value [`CrateLayer::own_value`] would build.
    fn own_targets(&self, field: usize) -> Option<Vec<sdf::Path>> {
        let rep = self.own_rep(field)?;
        match rep.layout() {
            (CRATE_PATH_LIST_OP, false, false) => {
                let at = usize::try_from(rep.payload()).ok()?;
                Some(self.path_list_op(at)?.compose_over(&[]))
            }
            _ => None,
        }
    }

    /// The value of field `field` when it is of a type decoded here (see [`CrateLayer`])
    /// and laid out as writers lay it out; nothing for any other, which `openusd` decodes.
    fn own_value(&self, field: usize) -> Option<sdf::Value> {
        let rep = self.own_rep(field)?;
        let at = usize::try_from(rep.payload()).ok()?;
        match rep.layout() {
            (CRATE_TOKEN, false, true) => self
                .tokens
                .get(rep.low() as usize)
                .map(|t| sdf::Value::Token(t.clone())),
            (CRATE_TOKEN, true, false) | (CRATE_TOKEN_VECTOR, false, false) => {
                let tokens = self.token_list(rep)?.map(|t| t.cloned());
                tokens.collect::<Option<_>>().map(sdf::Value::TokenVec)
            }
            (CRATE_STRING, false, true) => {
                let token = self.strings.get(rep.low() as usize)?;
                Some(sdf::Value::String(
                    self.tokens.get(*token)?.as_str().to_string(),
                ))
            }
            (CRATE_SPECIFIER, false, true) => {
                sdf::Specifier::from_repr(rep.low() as i32).map(sdf::Value::Specifier)
            }
            (CRATE_BOOL, false, true) => Some(sdf::Value::Bool(rep.low() != 0)),
            (CRATE_INT, false, true) => Some(sdf::Value::Int(rep.low() as i32)),
            (CRATE_FLOAT, false, true) => Some(sdf::Value::Float(f32::from_bits(rep.low()))),
            // An inlined double is kept as a float.
            (CRATE_DOUBLE, false, true) => {
                Some(sdf::Value::Double(f64::from(f32::from_bits(rep.low()))))
            }
            // Inlined, each component is a signed byte.
            (CRATE_VEC3F, false, true) => {
                let [x, y, z, _] = rep.low().to_le_bytes().map(|b| f32::from(b as i8));
                Some(sdf::Value::Vec3f(openusd::gf::vec3f(x, y, z)))
            }
            (CRATE_VEC3F, false, false) => {
                let b = self.bytes.get(at..at.checked_add(12)?)?;
                let f = |i: usize| f32::from_le_bytes([b[i], b[i + 1], b[i + 2], b[i + 3]]);
                Some(sdf::Value::Vec3f(openusd::gf::vec3f(f(0), f(4), f(8))))
            }
            (CRATE_PATH_LIST_OP, false, false) => self.path_list_op(at).map(sdf::Value::PathListOp),
            _ => None,
        }
    }

    /// The list operation on paths at `at`: a header byte saying which lists follow (and
    /// whether the operation is explicit), then each list present (explicit, added,
    /// prepended, appended, deleted, ordered) as a 64-bit count and 32-bit path indices.
    fn path_list_op(&self, at: usize) -> Option<sdf::ListOp<sdf::Path>> {
        let header = *self.bytes.get(at)?;
        let mut pos = at + 1;
        let mut list = |bit: u8| -> Option<Vec<sdf::Path>> {
            if header & bit == 0 {
                return Some(Vec::new());
            }
            let count = le_size(&self.bytes, pos)?;
            let start = pos.checked_add(8)?;
            let end = start.checked_add(count.checked_mul(4)?)?;
            let items = self.bytes.get(start..end)?;
            pos = end;
            items
                .chunks_exact(4)
                .map(|c| {
                    let i = u32::from_le_bytes([c[0], c[1], c[2], c[3]]) as usize;
                    self.paths.get(i).cloned()
                })
                .collect()
        };
        let mut op = sdf::ListOp::<sdf::Path> {
            explicit: header & 1 != 0,
            ..Default::default()
        };
        op.explicit_items = list(1 << 1)?;
        op.added_items = list(1 << 2)?;
        op.prepended_items = list(1 << 5)?;
        op.appended_items = list(1 << 6)?;
        op.deleted_items = list(1 << 3)?;
        op.ordered_items = list(1 << 4)?;
        Some(op)
    }

    /// The tokens of a list of tokens at `rep`, an array of tokens (its header: before
    /// 0.5.0 a 32-bit shape, then the count, 32-bit before 0.7.0, else 64-bit) or a token
    /// vector (a 64-bit count), each from its 32-bit index (none for an index that names no
    /// token); nothing for another value or when the indices lie outside the file.
    fn token_list(
        &self,
        rep: Rep,
    ) -> Option<impl Iterator<Item = Option<&openusd::tf::Token>> + '_> {
        let at = usize::try_from(rep.payload()).ok()?;
        let (pos, count) = match rep.layout() {
            (CRATE_TOKEN, true, false) if at == 0 => (0, 0),
            (CRATE_TOKEN, true, false) => self.token_array_span(at)?,
            (CRATE_TOKEN_VECTOR, false, false) => (at.checked_add(8)?, le_size(&self.bytes, at)?),
            _ => return None,
        };
        let items = self
            .bytes
            .get(pos..pos.checked_add(count.checked_mul(4)?)?)?;
        Some(items.chunks_exact(4).map(|c| {
            let i = u32::from_le_bytes([c[0], c[1], c[2], c[3]]) as usize;
            self.tokens.get(i)
        }))
    }

    /// Where the token indices of the array of tokens at `at` (not 0) start, and how many
    /// there are (see [`CrateLayer::token_list`]).
    fn token_array_span(&self, at: usize) -> Option<(usize, usize)> {
        let mut pos = at;
        if !self.v05 {
            pos = pos.checked_add(4)?;
        }
        let count = if self.v07 {
            let count = le_size(&self.bytes, pos)?;
            pos += 8;
            count
        } else {
            let b = self.bytes.get(pos..pos.checked_add(4)?)?;
            pos += 4;
            u32::from_le_bytes(b.try_into().ok()?) as usize
        };
        Some((pos, count))
    }

    /// The texts of the tokens of field `field` when [`CrateLayer::own_value`] decodes it
    /// as a list of tokens, borrowed from the file's tokens; nothing for anything else
    /// (then the field is read as a value).
    fn own_token_texts(&self, field: usize) -> Option<Vec<&str>> {
        let texts = self.token_list(self.own_rep(field)?)?;
        let texts = texts.map(|t| t.map(|t| t.as_str()));
        texts.collect()
    }

    /// The value of field `field` (the field `name` of the spec at `path`): decoded here,
    /// or by `openusd` (which reads the file the first time).
    fn read_field(&self, field: usize, path: &sdf::Path, name: &str) -> FieldRead<'static> {
        if let Some(v) = self.own_value(field) {
            return Ok(Some(std::borrow::Cow::Owned(v)));
        }
        if self.decoded_only.load(std::sync::atomic::Ordering::Relaxed) {
            return Ok(None);
        }
        let failed = |source: Box<dyn std::error::Error + Send + Sync>| sdf::DataError::Decode {
            path: path.clone(),
            field: name.to_string(),
            source,
        };
        // A poisoned lock is taken as it is: a panic of `openusd` is raised again where
        // the walk reaches the read that panicked ([`ShaderRead`]), which ends the reading.
        let mut slot = self
            .file
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner);
        if slot.is_none() {
            let opened = CrateFile::open(io::Cursor::new(self.bytes.clone()));
            *slot = Some(opened.map_err(|e| failed(e.into()))?);
        }
        let Some(file) = slot.as_mut() else {
            return Ok(None);
        };
        let Some(rep) = file.fields.get(field).map(|f| f.value_rep) else {
            return Ok(None);
        };
        match file.value(rep) {
            Ok(v) => Ok(Some(std::borrow::Cow::Owned(v))),
            Err(e) => Err(failed(e.into())),
        }
    }

    /// The field indices of the field set starting at `start`.
    fn field_set(&self, start: usize) -> &[Option<usize>] {
        let rest = self.fieldsets.get(start..).unwrap_or(&[]);
        let end = rest.iter().position(Option::is_none).unwrap_or(rest.len());
        &rest[..end]
    }

    /// The token indices of the fields of the field set starting at `start`, with each
    /// field's index.
    fn set_fields(&self, start: usize) -> impl Iterator<Item = (usize, usize)> + '_ {
        self.field_set(start)
            .iter()
            .flatten()
            .filter_map(|&i| self.fields.get(i).map(|&(token, _)| (i, token)))
    }
    /// The first field of the field set at `start` named by token `token`, read (`path`
    /// and `name`: the spec's path and the field's name, for errors).
    fn field_in(
        &self,
        start: usize,
        token: Option<usize>,
        path: &sdf::Path,
        name: &str,
    ) -> FieldRead<'static> {
        match self.field_index(start, token) {
            Some(i) => self.read_field(i, path, name),
            None => Ok(None),
        }
    }

    /// The index of the first field of the field set at `start` named by token `token`.
    fn field_index(&self, start: usize, token: Option<usize>) -> Option<usize> {
        let token = token?;
        self.set_fields(start)
            .find(|&(_, t)| t == token)
            .map(|(i, _)| i)
    }

    /// What the reader reads of the attribute spec at `path` whose field set starts at
    /// `start`: one walk of the field set for the four fields.
    fn attribute_fields_of(&self, start: usize, path: &sdf::Path) -> AttrFields {
        let mut found = [None; 4];
        for (i, token) in self.set_fields(start) {
            if let Some(k) = self.attribute_fields.iter().position(|&t| t == Some(token))
                && found[k].is_none()
            {
                found[k] = Some(i);
            }
        }
        let keys = [
            sdf::FieldKey::TypeName,
            sdf::FieldKey::Default,
            sdf::FieldKey::ConnectionPaths,
            sdf::FieldKey::TimeSamples,
        ];
        let read = |k: usize| -> FieldRead<'static> {
            match found[k] {
                Some(i) => self.read_field(i, path, keys[k].as_str()),
                None => Ok(None),
            }
        };
        // The usual type name and targets straight from the file; any other form through a
        // value, as every other field.
        let type_name = found[0].and_then(|i| self.own_token(i));
        let targets = found[2].and_then(|i| self.own_targets(i));
        AttrFields {
            type_name: type_name.unwrap_or_else(|| type_name_of(read(0))),
            default: default_of(read(1)),
            targets: targets.unwrap_or_else(|| targets_of(read(2))),
            samples: samples_of(read(3)),
        }
    }

    /// The type and field set start of the spec of path index `index` (with the tree).
    fn spec_of(&self, index: usize) -> Option<(sdf::SpecType, usize)> {
        self.spec_at.get(index).copied().flatten()
    }

    /// The path index of child `name` of path index `parent` (a property when
    /// `property`), trying `hint` first (the sibling after the child found before).
    fn child_named(
        &self,
        parent: usize,
        name: &str,
        property: bool,
        hint: Option<usize>,
    ) -> Option<usize> {
        let tree = self.tree.as_ref()?;
        let is = |c: usize| {
            let e = tree.element[c];
            (e < 0) == property
                && self
                    .tokens
                    .get(e.unsigned_abs() as usize)
                    .is_some_and(|t| t.as_str() == name)
        };
        // From the hint to the last child, then from the first: children are mostly
        // listed in the order their paths are.
        let from_hint = std::iter::successors(hint, |&c| match tree.next_sibling.get(c) {
            Some(&n) if n != NO_PATH => Some(n as usize),
            _ => None,
        });
        from_hint
            .chain(tree.children(parent).take_while(|&c| Some(c) != hint))
            .find(|&c| is(c))
    }

    /// The sibling after path index `index` (a hint for [`CrateLayer::child_named`]).
    fn next_of(&self, index: usize) -> Option<usize> {
        let n = *self.tree.as_ref()?.next_sibling.get(index)?;
        (n != NO_PATH).then_some(n as usize)
    }

    /// The kind of the prim at path index `index`, as [`Reader::kind_of`] reads it.
    fn kind_at(&self, index: usize) -> Option<PrimKind> {
        let (_, start) = self.spec_of(index)?;
        let path = self.paths.get(index)?;
        let t = self
            .field_in(
                start,
                self.attribute_fields[0],
                path,
                sdf::FieldKey::TypeName.as_str(),
            )
            .ok()??;
        prim_kind(t.as_ref())
    }

    /// The `default` of property `name` of the prim at path index `prim`.
    fn property_default(&self, prim: usize, name: &str) -> Result<Option<sdf::Value>, String> {
        let Some(index) = self.child_named(prim, name, true, None) else {
            return Ok(None);
        };
        let (Some((_, start)), Some(path)) = (self.spec_of(index), self.paths.get(index)) else {
            return Ok(None);
        };
        default_of(self.field_in(
            start,
            self.attribute_fields[1],
            path,
            sdf::FieldKey::Default.as_str(),
        ))
    }

    /// The connection targets of property `name` of the prim at path index `prim`.
    fn property_targets(&self, prim: usize, name: &str) -> Vec<sdf::Path> {
        let Some(index) = self.child_named(prim, name, true, None) else {
            return Vec::new();
        };
        let (Some((_, start)), Some(path)) = (self.spec_of(index), self.paths.get(index)) else {
            return Vec::new();
        };
        targets_of(self.field_in(
            start,
            self.attribute_fields[2],
            path,
            sdf::FieldKey::ConnectionPaths.as_str(),
        ))
    }

    /// The `inputs:` attributes of the prim at path index `prim`, as [`Reader::inputs`]
    /// gives them, each with its path index; those without a spec are left out, as
    /// [`Reader::attr_fields`] would leave them.
    fn inputs_at(&self, prim: usize) -> Vec<InputAt<'_>> {
        let (Some((_, start)), Some(path)) = (self.spec_of(prim), self.paths.get(prim)) else {
            return Vec::new();
        };
        // The property names, borrowed from the file's tokens when decoded here.
        let field = self.field_index(start, self.prim_fields[2]);
        let read;
        let names: Vec<&str> = match field.and_then(|i| self.own_token_texts(i)) {
            Some(names) => names,
            None => {
                let value =
                    field.map_or(Ok(None), |i| self.read_field(i, path, "propertyChildren"));
                read = tokens_of(value);
                read.iter().map(|t| t.as_str()).collect()
            }
        };
        let mut out = Vec::with_capacity(names.len());
        let mut hint = None;
        for (name, input) in distinct_inputs(&names) {
            let Some(index) = self.child_named(prim, name, true, hint) else {
                continue;
            };
            hint = self.next_of(index);
            // The input's name from the file's own token (the child's element), so that
            // it is not copied.
            let input = self
                .tree
                .as_ref()
                .and_then(|tree| tree.element.get(index))
                .and_then(|&e| self.tokens.get(e.unsigned_abs() as usize))
                .and_then(|t| t.as_str().strip_prefix("inputs:"))
                .filter(|own| *own == input)
                .map_or_else(|| Cow::Owned(input.to_string()), Cow::Borrowed);
            if let Some(p) = self.paths.get(index) {
                out.push((Cow::Borrowed(p), input, Some(index)));
            }
        }
        out
    }

    /// What the reader reads of the attribute at path index `index`, or nothing when its
    /// spec is not an attribute's.
    fn attribute_at(&self, index: usize) -> Option<AttrFields> {
        let (ty, start) = self.spec_of(index)?;
        if ty != sdf::SpecType::Attribute {
            return None;
        }
        Some(self.attribute_fields_of(start, self.paths.get(index)?))
    }

    /// [`flat_prims`] by path index, each prim with its path index: one spec found per
    /// prim, its children found among its path's children. Nothing when there is no tree
    /// or a child's name is no identifier (then [`flat_prims`] decides); `Some(None)` when
    /// something composes.
    fn flat_prims_by_index(&self) -> Option<Option<(Vec<sdf::Path>, Vec<usize>)>> {
        let tree = self.tree.as_ref()?;
        let Some((_, start)) = self.spec_of(tree.root) else {
            return Some(None);
        };
        if self
            .set_fields(start)
            .filter_map(|(_, token)| self.field_names.get(&token))
            .any(|name| ROOT_CHANGES.contains(&name.as_str()))
        {
            return Some(None);
        }
        // A prim's children by path index; `Err` when a name is no identifier.
        let children = |index: usize, start: usize| -> Result<Option<Vec<usize>>, ()> {
            let path = &self.paths[index];
            let names = match self.field_in(start, self.prim_fields[1], path, "primChildren") {
                Err(_) => return Ok(None),
                Ok(None) => return Ok(Some(Vec::new())),
                Ok(Some(v)) => match v.into_owned() {
                    sdf::Value::TokenVec(names) if all_differ(&names) => names,
                    _ => return Ok(None),
                },
            };
            let mut out = Vec::with_capacity(names.len());
            let mut hint = None;
            for n in &names {
                if !sdf::Path::is_valid_identifier(n.as_str()) {
                    return Err(());
                }
                match self.child_named(index, n.as_str(), false, hint) {
                    Some(c) => {
                        hint = self.next_of(c);
                        out.push(c);
                    }
                    // No path of that text, so no spec: not a flat prim.
                    None => return Ok(None),
                }
            }
            Ok(Some(out))
        };
        let Some(mut stack) = children(tree.root, start).ok()? else {
            return Some(None);
        };
        stack.reverse();
        let mut paths = Vec::new();
        let mut indices = Vec::new();
        while let Some(index) = stack.pop() {
            let Some((sdf::SpecType::Prim, start)) = self.spec_of(index) else {
                return Some(None);
            };
            let within = self
                .set_fields(start)
                .filter_map(|(_, token)| self.field_names.get(&token))
                .all(|name| PRIM_KEEPS.contains(&name.as_str()));
            if !within {
                return Some(None);
            }
            let path = &self.paths[index];
            match self
                .field_in(start, self.prim_fields[0], path, "specifier")
                .ok()
                .flatten()
                .as_deref()
            {
                Some(sdf::Value::Specifier(sdf::Specifier::Def)) => {}
                _ => return Some(None),
            }
            let Some(mut kids) = children(index, start).ok()? else {
                return Some(None);
            };
            kids.reverse();
            stack.extend(kids);
            paths.push(path.clone());
            indices.push(index);
        }
        Some(Some((paths, indices)))
    }
}

impl Specs for CrateLayer {
    fn as_crate(&self) -> Option<&CrateLayer> {
        Some(self)
    }

    fn drop_soon(self: Box<Self>) {
        #[cfg(feature = "parallel")]
        if crate::schedule::pool_can_help() {
            rayon::spawn(move || drop(self));
        }
    }

    fn spec_type(&self, path: &sdf::Path) -> Option<sdf::SpecType> {
        self.spec(path).map(|s| s.0)
    }

    fn try_field(
        &self,
        path: &sdf::Path,
        field: &str,
    ) -> Result<Option<std::borrow::Cow<'_, sdf::Value>>, sdf::DataError> {
        let Some((_, start)) = self.spec(path) else {
            return Ok(None);
        };
        self.field_in(start, self.names.get(field).copied(), path, field)
    }

    /// One look-up and one walk of the spec's field set for the four fields.
    fn attribute(&self, path: &sdf::Path) -> Option<AttrFields> {
        let (ty, start) = self.spec(path)?;
        (ty == sdf::SpecType::Attribute).then(|| self.attribute_fields_of(start, path))
    }

    /// One look-up and one walk of the spec's field set, comparing names without copying
    /// them.
    fn fields_within(&self, path: &sdf::Path, allowed: &[&str]) -> Option<bool> {
        let (_, start) = self.spec(path)?;
        Some(
            self.set_fields(start)
                .filter_map(|(_, token)| self.field_names.get(&token))
                .all(|name| allowed.contains(&name.as_str())),
        )
    }

    fn list_fields(&self, path: &sdf::Path) -> Option<Vec<String>> {
        let (_, start) = self.spec(path)?;
        Some(
            self.set_fields(start)
                .filter_map(|(_, token)| self.field_names.get(&token).cloned())
                .collect(),
        )
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
            if usda::normalise(bytes).is_ok_and(|n| n.encoded > 0) {
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

/// Checks the crate file tables and values the reader decodes itself against `openusd`'s
/// reading of the same file: every table equal, and every value decoded here (tokens,
/// strings, numbers, 3-vectors of floats, specifiers, path list operations) equal to
/// `openusd`'s decoding of that field; and the prims and attributes found by path index
/// as found by path text. The number of values
/// compared, or the first difference (or a file whose tables are not decoded here, or that
/// `openusd` does not read).
#[cfg(feature = "testkit")]
pub fn crate_values_agree(bytes: &[u8]) -> Result<usize, String> {
    let ours = CrateTables::decode(bytes).ok_or("the tables are not decoded here")?;
    let layer = CrateLayer::open(bytes).ok_or("the crate file does not open")?;
    let compared = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        let mut file =
            CrateFile::open(io::Cursor::new(Arc::from(bytes))).map_err(|e| format!("{e:#}"))?;
        file.validate().map_err(|e| format!("{e:#}"))?;
        let v = file.version();
        if ours.version != [v.major, v.minor, v.patch] {
            return Err("versions differ".to_string());
        }
        let tokens: Vec<&str> = ours.tokens.iter().map(|t| t.as_str()).collect();
        if tokens != file.tokens || ours.strings != file.strings {
            return Err("tokens or strings differ".to_string());
        }
        let fields: Vec<(usize, u64)> = file
            .fields
            .iter()
            .map(|f| (f.token_index, f.value_rep.0))
            .collect();
        if ours.fields != fields {
            return Err("fields differ".to_string());
        }
        if ours.fieldsets != file.fieldsets {
            return Err("field sets differ".to_string());
        }
        if ours.paths != file.paths {
            return Err("paths differ".to_string());
        }
        let specs: Vec<(usize, usize, sdf::SpecType)> = file
            .specs
            .iter()
            .map(|s| (s.path_index, s.fieldset_index, s.spec_type))
            .collect();
        if ours.specs != specs {
            return Err("specs differ".to_string());
        }
        let mut checked = 0;
        for i in 0..file.fields.len() {
            let Some(own) = layer.own_value(i) else {
                continue;
            };
            let rep = file.fields[i].value_rep;
            let theirs = file.value(rep).map_err(|e| format!("field {i}: {e:#}"))?;
            if own != theirs {
                return Err(format!("field {i}: {own:?} against {theirs:?}"));
            }
            checked += 1;
        }
        walks_agree(&layer)?;
        Ok(checked)
    }));
    compared.unwrap_or_else(|_| Err("openusd failed on this file".to_string()))
}

/// Whether crate file `layer`, walked by path index, gives what it gives looked up by
/// path text: the same prims, kinds, inputs and what is read of them, `info:` texts and
/// terminal connections (nothing to compare when there is no path tree). Only values
/// decoded here are read (`openusd` may fail on a damaged file's); each side is read on
/// its own.
#[cfg(feature = "testkit")]
fn walks_agree(layer: &CrateLayer) -> Result<(), String> {
    fn caught<T>(f: impl FnOnce() -> T) -> Option<T> {
        std::panic::catch_unwind(std::panic::AssertUnwindSafe(f)).ok()
    }
    layer
        .decoded_only
        .store(true, std::sync::atomic::Ordering::Relaxed);
    let walked = caught(|| layer.flat_prims_by_index());
    if walked.as_ref().is_some_and(Option::is_none) {
        return Ok(());
    }
    let walked = walked.flatten();
    if caught(|| flat_prims(layer)) != walked.as_ref().map(|w| w.as_ref().map(|(p, _)| p.clone())) {
        return Err("the prims walked by index differ".to_string());
    }
    let Some(Some((prims, indices))) = walked else {
        return Ok(());
    };
    let seen = |a: &AttrFields| {
        format!(
            "{} {:?} {:?} {}",
            a.type_name, a.default, a.targets, a.samples
        )
    };
    for (prim, &index) in prims.iter().zip(&indices) {
        let kind = caught(|| {
            layer
                .try_field(prim, sdf::FieldKey::TypeName.as_str())
                .ok()
                .flatten()
                .and_then(|t| prim_kind(t.as_ref()))
        });
        if caught(|| layer.kind_at(index)) != kind {
            return Err(format!("`{prim}`: kinds differ"));
        }
        for name in [
            "info:id",
            "info:implementationSource",
            "outputs:surface",
            "outputs:ri:surface",
        ] {
            let Some(path) = property_path(prim, name) else {
                continue;
            };
            let by_text = caught(|| {
                (
                    default_of(layer.try_field(&path, sdf::FieldKey::Default.as_str())),
                    targets_of(layer.try_field(&path, sdf::FieldKey::ConnectionPaths.as_str())),
                )
            });
            let by_index = caught(|| {
                (
                    layer.property_default(index, name),
                    layer.property_targets(index, name),
                )
            });
            if by_text != by_index {
                return Err(format!("`{path}`: read by index, it differs"));
            }
        }
        let by_text = caught(|| {
            let names = tokens_of(layer.try_field(prim, "propertyChildren"));
            let mut unique = rustc_hash::FxHashSet::default();
            names
                .iter()
                .filter_map(|n| {
                    let input = n.as_str().strip_prefix("inputs:")?;
                    unique.insert(input).then_some(())?;
                    let path = property_path(prim, n.as_str())?;
                    let a = layer.attribute(&path)?;
                    Some(format!("{path} {input} {}", seen(&a)))
                })
                .collect::<Vec<String>>()
        });
        let by_index = caught(|| {
            layer
                .inputs_at(index)
                .into_iter()
                .filter_map(|(path, input, at)| {
                    let a = layer.attribute_at(at?)?;
                    Some(format!("{path} {input} {}", seen(&a)))
                })
                .collect::<Vec<String>>()
        });
        if by_text != by_index {
            return Err(format!("`{prim}`: the inputs read by index differ"));
        }
    }
    Ok(())
}

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

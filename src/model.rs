//! The definition model: what the `.args` and `.oso` readers ([`crate::front`]) produce and
//! the [`crate::registry::Registry`] holds.

use crate::diag::Location;
use crate::types::{Type, Value};
use std::sync::Arc;

/// Which reader produced a definition.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum SourceKind {
    /// A RenderMan `.args` XML file.
    Args,
    /// A compiled OSL `.oso` file.
    Oso,
}

/// A metadata key. Keys of the attribute vocabulary are static strings, so
/// reading a definition does not allocate one string per attribute; any other key is owned.
pub(crate) type MetaKey = std::borrow::Cow<'static, str>;

/// Metadata keys that occur on most properties of real `.args` / `.oso` files.
const KNOWN_META_KEYS: &[&str] = &[
    "name",
    "type",
    "default",
    "label",
    "widget",
    "connectable",
    "min",
    "max",
    "slider",
    "slidermin",
    "slidermax",
    "digits",
    "sensitivity",
    "vstructmember",
    "vstructConditionalExpr",
    "vstructmemberaliases",
    "options",
    "isDynamicArray",
    "arraySize",
    "help",
    "page",
    "readOnly",
    "tag",
    "renderType",
    "sdrDefinitionName",
    "conditionalVisOp",
    "conditionalVisPath",
    "conditionalVisValue",
    "input",
    "hidden",
    "format",
];

/// The [`MetaKey`] for `key`: static when it is a known vocabulary word, owned otherwise.
pub(crate) fn meta_key(key: &str) -> MetaKey {
    match KNOWN_META_KEYS.iter().find(|k| **k == key) {
        Some(k) => MetaKey::Borrowed(k),
        None => MetaKey::Owned(key.to_string()),
    }
}

/// Key/value metadata in document order (a key may repeat).
///
/// Stored compactly: the values share one string buffer, so a property with eight attributes
/// costs two allocations instead of sixteen (definitions are read for every shader a scene
/// uses). Serialises as a list of `[key, value]` pairs.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Metadata {
    /// Every value, concatenated.
    text: String,
    /// Each entry's key and the end of its value in `text` (it starts where the previous ends).
    entries: Vec<(MetaKey, usize)>,
}

impl Metadata {
    /// Empty metadata.
    pub fn new() -> Self {
        Self::default()
    }

    /// Empty metadata with room for `entries` entries and `bytes` bytes of values.
    pub fn with_capacity(entries: usize, bytes: usize) -> Self {
        Metadata {
            text: String::with_capacity(bytes),
            entries: Vec::with_capacity(entries),
        }
    }

    /// Appends an entry.
    pub fn push(&mut self, key: impl Into<MetaKey>, value: &str) {
        self.text.push_str(value);
        self.entries.push((key.into(), self.text.len()));
    }

    /// Number of entries.
    pub fn len(&self) -> usize {
        self.entries.len()
    }

    /// True when there are no entries.
    pub fn is_empty(&self) -> bool {
        self.entries.is_empty()
    }

    /// The `index`-th entry in document order.
    pub fn entry(&self, index: usize) -> Option<(&str, &str)> {
        let (key, end) = self.entries.get(index)?;
        let start = match index {
            0 => 0,
            i => self.entries[i - 1].1,
        };
        Some((key.as_ref(), &self.text[start..*end]))
    }

    /// Entries in document order.
    pub fn iter(&self) -> impl Iterator<Item = (&str, &str)> + '_ {
        let mut start = 0;
        self.entries.iter().map(move |(key, end)| {
            let value = &self.text[start..*end];
            start = *end;
            (key.as_ref(), value)
        })
    }

    /// The first value stored under `key`.
    pub fn get(&self, key: &str) -> Option<&str> {
        self.iter().find(|(k, _)| *k == key).map(|(_, v)| v)
    }

    /// Appends every entry of `other`.
    pub fn extend_from(&mut self, other: &Metadata) {
        for (k, v) in other.iter() {
            self.push(meta_key(k), v);
        }
    }
}

impl serde::Serialize for Metadata {
    fn serialize<S: serde::Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        serializer.collect_seq(self.iter())
    }
}

/// Direction of a property: inputs and outputs have separate namespaces.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Direction {
    /// An input parameter.
    In,
    /// An output.
    Out,
}

/// The raw text of a `vstructConditionalExpr` and where its value starts in the source.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct CondSource {
    /// The decoded expression string (after XML entity decoding / C unescaping).
    pub text: String,
    /// Where the value starts in the source file (just after the opening quote for `.args`,
    /// the `%meta` hint for `.oso`).
    pub location: Location,
}

/// A property's vstruct member declaration.
///
/// Readers fill this only when `vstructmember` splits into a non-empty head and member;
/// otherwise the raw attributes stay in [`Property::metadata`] and the registry reports VS003.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct MemberDecl {
    /// Head name: the text before the first `.`.
    pub head: String,
    /// Member name: the text after the first `.` (may itself contain dots).
    pub member: String,
    /// The whole `vstructmemberaliases` value (one alias in compat mode), if non-empty.
    pub alias: Option<String>,
    /// The conditional, if the attribute is present and non-empty.
    pub cond: Option<CondSource>,
}

/// One input parameter or output of a shader definition.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Property {
    /// Property name.
    pub name: String,
    /// Input or output.
    pub direction: Direction,
    /// Interpreted type (after head normalisation by the registry: `Vstruct` for heads).
    pub ty: Type,
    /// The type text as declared (`float`, `vstruct`, `color vector normal point` tags, …).
    pub declared_type: String,
    /// Typed default value, if any.
    pub default: Option<Value>,
    /// Every attribute / `%meta` entry verbatim, in document order.
    pub metadata: Metadata,
    /// Typed `%meta` values of `.oso` properties (`int`, `float`, `string` and their arrays),
    /// in document order, under the same keys as [`Property::metadata`]. Empty for `.args`.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub typed_metadata: Vec<(String, Value)>,
    /// Connection types: `<tags>` values, the deprecated `tag` attribute, OSL `tag` metas.
    pub connection_types: Vec<String>,
    /// `:`-joined page path.
    pub page: Option<String>,
    /// Label shown in UIs.
    pub label: Option<String>,
    /// Help text (raw inner markup for `.args`).
    pub help: Option<String>,
    /// Widget name.
    pub widget: Option<String>,
    /// Options list: `(label, value)` pairs (label = value when the source gives only values).
    pub options: Vec<(String, String)>,
    /// Whether the property accepts connections (outputs are always connectable).
    pub connectable: bool,
    /// vstruct member declaration, if the property is a member.
    pub vstruct: Option<MemberDecl>,
    /// Where the property is declared (the element / line).
    pub location: Location,
}

impl Property {
    /// A property with the given name, direction and type and every other field empty.
    pub fn new(
        name: impl Into<String>,
        direction: Direction,
        ty: Type,
        location: Location,
    ) -> Self {
        Property {
            name: name.into(),
            direction,
            declared_type: ty.to_string(),
            ty,
            default: None,
            metadata: Metadata::new(),
            typed_metadata: Vec::new(),
            connection_types: Vec::new(),
            page: None,
            label: None,
            help: None,
            widget: None,
            options: Vec::new(),
            connectable: true,
            vstruct: None,
            location,
        }
    }

    /// The first metadata value stored under `key`.
    pub fn meta(&self, key: &str) -> Option<&str> {
        self.metadata.get(key)
    }

    /// True if the property has a connection type (tag) equal to `tag`.
    pub fn has_tag(&self, tag: &str) -> bool {
        self.connection_types.iter().any(|t| t == tag)
    }
}

/// One shader definition read from an `.args` or `.oso` file.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Definition {
    /// Shader id: the `.args` file stem, or the `.oso` shader name.
    pub id: String,
    /// Shader kind: `pattern`, `bxdf`, `light`, … (`unknown` when missing).
    pub kind: String,
    /// Which reader produced it.
    pub source: SourceKind,
    /// The file it was read from (as given, or `<embedded>/X.args`).
    pub path: Arc<str>,
    /// Input parameters in declaration order.
    pub inputs: Vec<Property>,
    /// Outputs in declaration order.
    pub outputs: Vec<Property>,
    /// Node-level metadata (help, rfmdata, …) in document order.
    pub metadata: Metadata,
}

impl Definition {
    /// The input named `name`.
    pub fn input(&self, name: &str) -> Option<&Property> {
        self.inputs.iter().find(|p| p.name == name)
    }
    /// The output named `name`.
    pub fn output(&self, name: &str) -> Option<&Property> {
        self.outputs.iter().find(|p| p.name == name)
    }
    /// Inputs and outputs interleaved in declaration (document / line) order.
    pub fn properties_in_order(&self) -> Vec<&Property> {
        let mut all: Vec<&Property> = self.inputs.iter().chain(self.outputs.iter()).collect();
        all.sort_by_key(|p| (p.location.line, p.location.column));
        all
    }
}

/// A definition with a name index over its inputs. `Definition::input` scans the inputs;
/// definitions such as PxrLayerMixer declare hundreds of them, and resolution and lowering
/// look several up for every member or parameter binding.
#[derive(Debug, Clone)]
pub(crate) struct IndexedDefinition {
    def: Arc<Definition>,
    inputs: rustc_hash::FxHashMap<String, usize>,
    /// Output name → position in `def.outputs` (the first of duplicates).
    outputs: rustc_hash::FxHashMap<String, usize>,
    /// Per input (same order as `def.inputs`): the documented `min` / `max`, parsed once.
    ranges: Vec<NumericRange>,
}

/// A parameter's documented numeric range (`min` / `max` metadata); either end may be open.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub(crate) struct NumericRange {
    /// Lower bound, if documented.
    pub min: Option<f32>,
    /// Upper bound, if documented.
    pub max: Option<f32>,
}

impl NumericRange {
    fn of(p: &Property) -> Self {
        let bound = |key: &str| p.meta(key).and_then(|t| t.trim().parse::<f32>().ok());
        NumericRange {
            min: bound("min"),
            max: bound("max"),
        }
    }

    /// True when neither end is documented.
    pub fn is_open(&self) -> bool {
        self.min.is_none() && self.max.is_none()
    }
}

impl IndexedDefinition {
    /// Indexes `def`'s inputs (the first of duplicate names wins, as `Definition::input`).
    pub fn new(def: Arc<Definition>) -> Self {
        let mut inputs = rustc_hash::FxHashMap::default();
        for (i, p) in def.inputs.iter().enumerate() {
            inputs.entry(p.name.clone()).or_insert(i);
        }
        let mut outputs = rustc_hash::FxHashMap::default();
        for (i, p) in def.outputs.iter().enumerate() {
            outputs.entry(p.name.clone()).or_insert(i);
        }
        let ranges = def.inputs.iter().map(NumericRange::of).collect();
        IndexedDefinition {
            def,
            inputs,
            outputs,
            ranges,
        }
    }

    /// The input named `name`.
    pub fn input(&self, name: &str) -> Option<&Property> {
        self.inputs.get(name).map(|&i| &self.def.inputs[i])
    }

    /// The output named `name`.
    pub fn output(&self, name: &str) -> Option<&Property> {
        self.outputs.get(name).map(|&i| &self.def.outputs[i])
    }

    /// The position of the input named `name` among the definition's inputs.
    pub fn input_position(&self, name: &str) -> Option<usize> {
        self.inputs.get(name).copied()
    }

    /// The input named `name` with its documented range.
    pub(crate) fn input_with_range(&self, name: &str) -> Option<(&Property, NumericRange)> {
        self.inputs
            .get(name)
            .map(|&i| (&self.def.inputs[i], self.ranges[i]))
    }

    /// The definition.
    pub fn definition(&self) -> &Arc<Definition> {
        &self.def
    }
}

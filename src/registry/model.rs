//! The definition model that the `.args` and `.oso` readers produce (spec formats.md §1.3).

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

/// A property's vstruct member declaration (spec vstruct.md §2.2–§2.4).
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
    pub metadata: Vec<(String, String)>,
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
            metadata: Vec::new(),
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
        self.metadata
            .iter()
            .find(|(k, _)| k == key)
            .map(|(_, v)| v.as_str())
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
    pub metadata: Vec<(String, String)>,
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

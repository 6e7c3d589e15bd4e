//! The value model shared by definitions and networks.
//!
//! Floats are `f32` everywhere in networks and definitions (RIB's precision); the conditional
//! evaluator widens them to `f64`.

use std::fmt;

/// The base type of a parameter, output or value.
#[derive(Debug, Clone, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
pub enum BaseType {
    /// 32-bit integer.
    Int,
    /// 32-bit float.
    Float,
    /// String.
    String,
    /// RGB colour (3 floats).
    Color,
    /// Point (3 floats).
    Point,
    /// Vector (3 floats).
    Vector,
    /// Normal (3 floats).
    Normal,
    /// 4×4 matrix (16 floats, row-major as written in RIB).
    Matrix,
    /// Homogeneous point (4 floats).
    HPoint,
    /// OSL struct or RenderMan `struct X` connection type, with its name when known.
    Struct(Option<String>),
    /// A vstruct head, after registry normalisation.
    Vstruct,
    /// A terminal connection type: `bxdf`, `lightfilter`, `samplefilter`, `displayfilter`,
    /// `integrator`.
    Terminal(String),
    /// An OSL closure output.
    Closure,
    /// USD token (JSON/USD networks only).
    Token,
    /// USD asset path (JSON/USD networks only).
    Asset,
    /// Boolean (JSON/USD networks only).
    Bool,
    /// Anything else, kept verbatim and reported by the reader.
    Unknown(String),
}

impl BaseType {
    /// Number of scalar components of one element (0 for types without a value form).
    pub fn components(&self) -> usize {
        match self {
            BaseType::Int
            | BaseType::Float
            | BaseType::String
            | BaseType::Token
            | BaseType::Asset
            | BaseType::Bool => 1,
            BaseType::Color | BaseType::Point | BaseType::Vector | BaseType::Normal => 3,
            BaseType::HPoint => 4,
            BaseType::Matrix => 16,
            _ => 0,
        }
    }

    /// True for the four three-float types.
    pub fn is_triple(&self) -> bool {
        matches!(
            self,
            BaseType::Color | BaseType::Point | BaseType::Vector | BaseType::Normal
        )
    }

    /// True for types whose components are numbers (int, float, triples, hpoint, matrix).
    pub fn is_numeric(&self) -> bool {
        matches!(
            self,
            BaseType::Int | BaseType::Float | BaseType::HPoint | BaseType::Matrix
        ) || self.is_triple()
    }

    /// Parse a declared type word (`float`, `color`, `struct`, `bxdf`, …). `float2`/`float3`
    /// are not handled here (they carry an array size); see [`Type::parse_decl`].
    pub fn from_word(word: &str) -> BaseType {
        match word {
            "int" => BaseType::Int,
            "float" => BaseType::Float,
            "string" => BaseType::String,
            "color" => BaseType::Color,
            "point" => BaseType::Point,
            "vector" => BaseType::Vector,
            "normal" => BaseType::Normal,
            "matrix" => BaseType::Matrix,
            "hpoint" => BaseType::HPoint,
            "struct" => BaseType::Struct(None),
            "vstruct" => BaseType::Vstruct,
            "bxdf" | "lightfilter" | "samplefilter" | "displayfilter" | "integrator" => {
                BaseType::Terminal(word.to_string())
            }
            "closure" => BaseType::Closure,
            "token" => BaseType::Token,
            "asset" => BaseType::Asset,
            "bool" => BaseType::Bool,
            other => BaseType::Unknown(other.to_string()),
        }
    }

    /// The canonical type word (inverse of [`BaseType::from_word`]).
    pub fn word(&self) -> &str {
        match self {
            BaseType::Int => "int",
            BaseType::Float => "float",
            BaseType::String => "string",
            BaseType::Color => "color",
            BaseType::Point => "point",
            BaseType::Vector => "vector",
            BaseType::Normal => "normal",
            BaseType::Matrix => "matrix",
            BaseType::HPoint => "hpoint",
            BaseType::Struct(_) => "struct",
            BaseType::Vstruct => "vstruct",
            BaseType::Terminal(k) => k,
            BaseType::Closure => "closure",
            BaseType::Token => "token",
            BaseType::Asset => "asset",
            BaseType::Bool => "bool",
            BaseType::Unknown(w) => w,
        }
    }
}

impl fmt::Display for BaseType {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            BaseType::Struct(Some(name)) => write!(f, "struct {name}"),
            other => f.write_str(other.word()),
        }
    }
}

/// Array shape of a type.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
pub enum ArraySpec {
    /// A scalar (one element).
    None,
    /// A fixed-size array of `n` elements.
    Fixed(usize),
    /// A dynamic array.
    Dynamic,
}

/// A full type: base type plus array shape.
#[derive(Debug, Clone, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
pub struct Type {
    /// Base type.
    pub base: BaseType,
    /// Array shape.
    pub array: ArraySpec,
}

impl Type {
    /// A scalar of `base`.
    pub fn scalar(base: BaseType) -> Self {
        Type {
            base,
            array: ArraySpec::None,
        }
    }

    /// True if this is an array (fixed or dynamic).
    pub fn is_array(&self) -> bool {
        !matches!(self.array, ArraySpec::None)
    }

    /// Parse a declaration type word that may be `float2`/`float3` (a fixed float array).
    /// Other words go through [`BaseType::from_word`] as scalars.
    pub fn parse_decl(word: &str) -> Type {
        match word {
            "float2" => Type {
                base: BaseType::Float,
                array: ArraySpec::Fixed(2),
            },
            "float3" => Type {
                base: BaseType::Float,
                array: ArraySpec::Fixed(3),
            },
            w => Type::scalar(BaseType::from_word(w)),
        }
    }
}

impl fmt::Display for Type {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", self.base)?;
        match self.array {
            ArraySpec::None => Ok(()),
            ArraySpec::Fixed(n) => write!(f, "[{n}]"),
            ArraySpec::Dynamic => f.write_str("[]"),
        }
    }
}

/// A typed value.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub enum Value {
    /// `int`.
    Int(i32),
    /// `float`.
    Float(f32),
    /// `string`.
    Str(String),
    /// `color`, `point`, `vector` or `normal`.
    Triple(BaseType, [f32; 3]),
    /// `hpoint`.
    HPoint([f32; 4]),
    /// `matrix`, row-major as written.
    Matrix([f32; 16]),
    /// USD token.
    Token(String),
    /// USD asset path.
    Asset(String),
    /// Boolean.
    Bool(bool),
    /// Homogeneous array of elements of the given base type.
    Array(BaseType, Vec<Value>),
}

impl Value {
    /// The base type of this value (for arrays, of their elements).
    pub fn base_type(&self) -> BaseType {
        match self {
            Value::Int(_) => BaseType::Int,
            Value::Float(_) => BaseType::Float,
            Value::Str(_) => BaseType::String,
            Value::Triple(b, _) => b.clone(),
            Value::HPoint(_) => BaseType::HPoint,
            Value::Matrix(_) => BaseType::Matrix,
            Value::Token(_) => BaseType::Token,
            Value::Asset(_) => BaseType::Asset,
            Value::Bool(_) => BaseType::Bool,
            Value::Array(b, _) => b.clone(),
        }
    }

    /// The value as an `f64` if it is a scalar number or bool (bool as 0/1), exactly widened.
    /// This is the comparison operand rule of the conditional language.
    pub fn as_f64(&self) -> Option<f64> {
        match self {
            Value::Int(i) => Some(f64::from(*i)),
            Value::Float(x) => Some(f64::from(*x)),
            Value::Bool(b) => Some(if *b { 1.0 } else { 0.0 }),
            _ => None,
        }
    }

    /// The zero value of a scalar type, if it has one (0, 0.0, empty string, zero triple).
    pub fn zero_of(base: &BaseType) -> Option<Value> {
        Some(match base {
            BaseType::Int => Value::Int(0),
            BaseType::Float => Value::Float(0.0),
            BaseType::String => Value::Str(String::new()),
            b if b.is_triple() => Value::Triple(b.clone(), [0.0; 3]),
            BaseType::HPoint => Value::HPoint([0.0; 4]),
            BaseType::Bool => Value::Bool(false),
            _ => return None,
        })
    }

    /// All numeric components flattened in order (empty for strings/tokens/assets).
    pub fn numbers(&self) -> Vec<f32> {
        match self {
            Value::Int(i) => vec![*i as f32],
            Value::Float(x) => vec![*x],
            Value::Triple(_, v) => v.to_vec(),
            Value::HPoint(v) => v.to_vec(),
            Value::Matrix(v) => v.to_vec(),
            Value::Bool(b) => vec![if *b { 1.0 } else { 0.0 }],
            Value::Array(_, items) => items.iter().flat_map(Value::numbers).collect(),
            Value::Str(_) | Value::Token(_) | Value::Asset(_) => Vec::new(),
        }
    }
}

/// `x` if it is finite; otherwise the largest finite `f32` of its sign (`f32::MAX` for +∞,
/// `f32::MIN` for −∞) and 0 for NaN, which has no sign to keep. What the writers can emit
/// and the readers accept is finite floats only; this is how a value that is not gets there.
#[cfg_attr(feature = "testkit", visibility::make(pub))]
pub(crate) fn saturate_f32(x: f32) -> f32 {
    if x.is_finite() {
        x
    } else if x.is_nan() {
        0.0
    } else if x > 0.0 {
        f32::MAX
    } else {
        f32::MIN
    }
}

impl Value {
    /// Replace every non-finite float in the value (components and array elements included)
    /// by the largest finite `f32` of their sign (NaN by 0); true if any was replaced.
    pub fn saturate_floats(&mut self) -> bool {
        fn fix(xs: &mut [f32]) -> bool {
            let mut changed = false;
            for x in xs.iter_mut().filter(|x| !x.is_finite()) {
                *x = saturate_f32(*x);
                changed = true;
            }
            changed
        }
        match self {
            Value::Float(x) => fix(std::slice::from_mut(x)),
            Value::Triple(_, xs) => fix(xs),
            Value::HPoint(xs) => fix(xs),
            Value::Matrix(xs) => fix(xs),
            Value::Array(_, items) => items
                .iter_mut()
                .fold(false, |changed, v| v.saturate_floats() | changed),
            Value::Int(_) | Value::Bool(_) | Value::Str(_) | Value::Token(_) | Value::Asset(_) => {
                false
            }
        }
    }

    /// True if every float in the value is finite.
    pub fn is_finite(&self) -> bool {
        match self {
            Value::Float(x) => x.is_finite(),
            Value::Triple(_, xs) => xs.iter().all(|x| x.is_finite()),
            Value::HPoint(xs) => xs.iter().all(|x| x.is_finite()),
            Value::Matrix(xs) => xs.iter().all(|x| x.is_finite()),
            Value::Array(_, items) => items.iter().all(Value::is_finite),
            Value::Int(_) | Value::Bool(_) | Value::Str(_) | Value::Token(_) | Value::Asset(_) => {
                true
            }
        }
    }
}

/// Formats a float with the shortest decimal text that reads back to the same `f32`.
#[cfg_attr(feature = "testkit", visibility::make(pub))]
pub(crate) fn format_f32(x: f32) -> String {
    format!("{x}")
}

impl fmt::Display for Value {
    /// A compact, readable rendering (numbers space-separated, strings quoted).
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        fn join(f: &mut fmt::Formatter<'_>, xs: &[f32]) -> fmt::Result {
            for (i, x) in xs.iter().enumerate() {
                if i > 0 {
                    f.write_str(" ")?;
                }
                f.write_str(&format_f32(*x))?;
            }
            Ok(())
        }
        match self {
            Value::Int(i) => write!(f, "{i}"),
            Value::Float(x) => f.write_str(&format_f32(*x)),
            Value::Str(s) | Value::Token(s) | Value::Asset(s) => write!(f, "{s:?}"),
            Value::Triple(_, v) => join(f, v),
            Value::HPoint(v) => join(f, v),
            Value::Matrix(v) => join(f, v),
            Value::Bool(b) => write!(f, "{b}"),
            Value::Array(_, items) => {
                f.write_str("[")?;
                for (i, v) in items.iter().enumerate() {
                    if i > 0 {
                        f.write_str(", ")?;
                    }
                    write!(f, "{v}")?;
                }
                f.write_str("]")
            }
        }
    }
}

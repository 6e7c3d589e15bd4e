//! Typing of the `set` and `copy` actions (with the extensions `set-tuples` and
//! `copy-convert`; see `docs/conditional-language.md`). Pure functions over [`Type`] and
//! [`Value`]; the resolver looks up the declared types and writes the result.

use super::ast::{Literal, LiteralKind};
use super::ext::{Extension, Extensions};
use crate::types::{ArraySpec, BaseType, Type, Value, saturate_f32};
use std::fmt;

/// A value `set` writes, with the VS023 flag.
#[derive(Debug, Clone, PartialEq)]
pub struct SetValue {
    /// The value to author on D.M.
    pub value: Value,
    /// True if the number was outside the range of the destination type (`i32`, or the
    /// finite `f32` range) and was saturated (VS023).
    pub saturated: bool,
}

/// Why a `set` writes nothing (VS013).
#[derive(Debug, Clone, PartialEq)]
pub enum SetRejection {
    /// D has no definition, or declares no input M.
    NoDestination,
    /// A NUMBER cannot be written to this type.
    Number(Type),
    /// A STRING can only be written to a `string`.
    String(Type),
}

impl SetRejection {
    /// The stable code.
    pub const CODE: &'static str = "VS013";
}

impl fmt::Display for SetRejection {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            SetRejection::NoDestination => f.write_str(
                "`set` not applied: the downstream node's definition declares no such input",
            ),
            SetRejection::Number(t) if t.base.is_triple() && !t.is_array() => write!(
                f,
                "`set` not applied: a NUMBER cannot be written to a {t} input \
                 (see --ext set-tuples)"
            ),
            SetRejection::Number(t) => {
                write!(
                    f,
                    "`set` not applied: a NUMBER cannot be written to a {t} input"
                )
            }
            SetRejection::String(t) => write!(
                f,
                "`set` not applied: a STRING can only be written to a string input, not {t}"
            ),
        }
    }
}

/// Truncation toward zero into `i32`, saturating; returns `(value, saturated)`.
#[cfg_attr(feature = "testkit", visibility::make(pub))]
pub(crate) fn truncate_to_i32(x: f64) -> (i32, bool) {
    let t = x.trunc();
    if t > f64::from(i32::MAX) {
        (i32::MAX, true)
    } else if t < f64::from(i32::MIN) {
        (i32::MIN, true)
    } else if t.is_nan() {
        (0, true)
    } else {
        (t as i32, false)
    }
}

/// The value `set LITERAL` writes to an input of declared type `dest` (`None`: D has no
/// definition or no input M).
///
/// | literal | destination | written |
/// |---|---|---|
/// | NUMBER | `int` | truncation toward zero; saturated outside `i32` (flag for VS023) |
/// | NUMBER | `float` | the f64 rounded to the nearest f32; beyond the finite f32 range: the largest finite f32 of its sign (flag for VS023) |
/// | NUMBER | `color`/`point`/`vector`/`normal` with `set-tuples` | that f32 in all three components |
/// | NUMBER | anything else (arrays, string, matrix, …) | rejected (VS013) |
/// | STRING | `string` | the verbatim content |
/// | STRING | anything else | rejected (VS013) |
///
/// A float is never written as an infinity: the RIB and JSON readers reject non-finite
/// numbers, so a resolved network that held one could not be read back.
pub fn set_value(
    literal: &Literal,
    dest: Option<&Type>,
    ext: &Extensions,
) -> Result<SetValue, SetRejection> {
    let ty = dest.ok_or(SetRejection::NoDestination)?;
    let plain = |value| {
        Ok(SetValue {
            value,
            saturated: false,
        })
    };
    match &literal.kind {
        LiteralKind::Number { value, .. } => match (&ty.base, ty.array) {
            (BaseType::Int, ArraySpec::None) => {
                let (i, saturated) = truncate_to_i32(*value);
                Ok(SetValue {
                    value: Value::Int(i),
                    saturated,
                })
            }
            (BaseType::Float, ArraySpec::None) => Ok(saturated_float(*value, Value::Float)),
            (b, ArraySpec::None) if b.is_triple() && ext.contains(Extension::SetTuples) => {
                Ok(saturated_float(*value, |x| {
                    Value::Triple(b.clone(), [x; 3])
                }))
            }
            _ => Err(SetRejection::Number(ty.clone())),
        },
        LiteralKind::Str { value } => match (&ty.base, ty.array) {
            (BaseType::String, ArraySpec::None) => plain(Value::Str(value.clone())),
            _ => Err(SetRejection::String(ty.clone())),
        },
    }
}

/// The f64 `x` rounded to f32 and saturated to the finite range ([`saturate_f32`]), as the
/// value `make` builds from it.
fn saturated_float(x: f64, make: impl FnOnce(f32) -> Value) -> SetValue {
    let rounded = x as f32;
    SetValue {
        value: make(saturate_f32(rounded)),
        saturated: !rounded.is_finite(),
    }
}

/// How `copy` moves a value between two declared types.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CopyPlan {
    /// Identical base types: the value is copied as is.
    Same,
    /// `copy-convert`: int → float.
    IntToFloat,
    /// `copy-convert`: float → int, truncation toward zero.
    FloatToInt,
    /// `copy-convert`: an int or float scalar broadcast to a three-component type.
    Broadcast,
}

/// Why a `copy` writes nothing (VS014).
#[derive(Debug, Clone, PartialEq)]
pub enum CopyRejection {
    /// D has no definition, or declares no input M.
    NoDestination,
    /// U has no definition, or declares no input `p`.
    NoSource,
    /// The base types differ (and `copy-convert` does not cover them).
    TypeMismatch {
        /// U.p's declared type.
        source: Type,
        /// D.M's declared type.
        dest: Type,
    },
}

impl CopyRejection {
    /// The stable code.
    pub const CODE: &'static str = "VS014";
}

impl fmt::Display for CopyRejection {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            CopyRejection::NoDestination => f.write_str(
                "`copy` not applied: the downstream node's definition declares no such input",
            ),
            CopyRejection::NoSource => f.write_str(
                "`copy` not applied: the upstream node's definition declares no such input",
            ),
            CopyRejection::TypeMismatch { source, dest } => {
                let hint = if convertible(source, dest) {
                    " (see --ext copy-convert)"
                } else {
                    ""
                };
                write!(
                    f,
                    "`copy` not applied: source type {source} differs from destination type \
                     {dest}{hint}"
                )
            }
        }
    }
}

/// True if `copy-convert` would accept the pair.
fn convertible(source: &Type, dest: &Type) -> bool {
    let scalar_number =
        |t: &Type| matches!(t.base, BaseType::Int | BaseType::Float) && t.array == ArraySpec::None;
    matches!(
        (&source.base, &dest.base),
        (BaseType::Int, BaseType::Float) | (BaseType::Float, BaseType::Int)
    ) || (scalar_number(source) && dest.base.is_triple() && !dest.is_array())
}

/// Whether `copy` can move a value from declared type `source` (U.p) to `dest` (D.M).
/// Compat: identical base types only (array-ness is ignored, as in the reference). With
/// `copy-convert`: int↔float, and an int/float scalar to a color/point/vector/normal.
pub fn copy_plan(source: &Type, dest: &Type, ext: &Extensions) -> Result<CopyPlan, CopyRejection> {
    if source.base == dest.base {
        return Ok(CopyPlan::Same);
    }
    if ext.contains(Extension::CopyConvert) && convertible(source, dest) {
        return Ok(match (&source.base, &dest.base) {
            (BaseType::Int, BaseType::Float) => CopyPlan::IntToFloat,
            (BaseType::Float, BaseType::Int) => CopyPlan::FloatToInt,
            _ => CopyPlan::Broadcast,
        });
    }
    Err(CopyRejection::TypeMismatch {
        source: source.clone(),
        dest: dest.clone(),
    })
}

/// What `copy` writes.
#[derive(Debug, Clone, PartialEq)]
pub enum CopyOutcome {
    /// Author `value` on D.M.
    Write {
        /// The value.
        value: Value,
        /// The two declared types differ in array shape (scalar vs array, or different
        /// sizes): the value is copied as the reference does, and VS014 is reported as a
        /// warning about the shape.
        shape_mismatch: bool,
        /// `copy-convert` converted the value.
        converted: bool,
        /// The source held a non-finite float (an infinity or NaN, possible only in a
        /// definition default or a network built in code): it was replaced by
        /// [`saturate_f32`] (VS023).
        saturated: bool,
    },
    /// U.p is unauthored and has no default: nothing is written (no diagnostic).
    NoValue,
}

/// The `copy p` action: `value` is U.p's authored value, else its definition default
/// (`None` if neither exists); `source`/`dest` are the declared types of U's input `p` and
/// D's input M (`None` when the definition or input is missing).
///
/// vstructc reports the shape warning whenever the declared array shapes differ (the
/// specification names the scalar/array case; two arrays of different fixed sizes, or fixed
/// vs dynamic, are treated alike). A non-finite float in the value (an infinity or NaN, which
/// the readers never produce but a definition default or a network built in code can hold) is
/// written saturated ([`saturate_f32`]) and flagged for VS023, so that every written value
/// reads back.
pub fn copy_value(
    value: Option<&Value>,
    source: Option<&Type>,
    dest: Option<&Type>,
    ext: &Extensions,
) -> Result<CopyOutcome, CopyRejection> {
    let dest = dest.ok_or(CopyRejection::NoDestination)?;
    let source = source.ok_or(CopyRejection::NoSource)?;
    let plan = copy_plan(source, dest, ext)?;
    let Some(value) = value else {
        return Ok(CopyOutcome::NoValue);
    };
    let shape_mismatch = source.array != dest.array;
    let (mut value, converted) = match plan {
        CopyPlan::Same => (value.clone(), false),
        CopyPlan::IntToFloat | CopyPlan::FloatToInt => (convert(value, &dest.base), true),
        CopyPlan::Broadcast => match value.as_f64() {
            Some(x) => (Value::Triple(dest.base.clone(), [x as f32; 3]), true),
            None => (value.clone(), false),
        },
    };
    let saturated = value.saturate_floats();
    Ok(CopyOutcome::Write {
        value,
        shape_mismatch,
        converted,
        saturated,
    })
}

/// int → float (nearest f32) and float → int (truncation toward zero, saturating), element
/// by element for arrays; other values unchanged.
#[cfg_attr(feature = "testkit", visibility::make(pub))]
fn convert(value: &Value, to: &BaseType) -> Value {
    match (value, to) {
        (Value::Int(i), BaseType::Float) => Value::Float(*i as f32),
        (Value::Float(x), BaseType::Int) => Value::Int(truncate_to_i32(f64::from(*x)).0),
        (Value::Array(_, items), _) => {
            Value::Array(to.clone(), items.iter().map(|v| convert(v, to)).collect())
        }
        (other, _) => other.clone(),
    }
}

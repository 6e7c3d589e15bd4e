//! What the commands' `--json` output shares: values and types in one plain shape, and
//! printing a document. The schemas are documented in docs/json.md; every document is
//! built from the hand-shaped structs of the commands (never from the library's own serde
//! derives, whose enum shapes are internal).

use super::CommonOptions;
use serde::Serialize;
use serde_json::Value as Json;
use std::process::ExitCode;
use vstructc::diag::Location;
use vstructc::registry::SourceKind;
use vstructc::types::{Type, Value};

/// A typed value as `{"type": T, "value": V}`, the form of the JSON network format: T a type
/// word (`int`, `float`, `string`, `color`, …, `float[3]` for arrays), V a number, string,
/// boolean, or an array of numbers (tuples) or of elements (arrays).
#[derive(Debug, Serialize)]
pub struct TypedValue {
    /// The type word.
    #[serde(rename = "type")]
    pub ty: String,
    /// The value in plain JSON.
    pub value: Json,
}

impl TypedValue {
    /// The plain form of `v`.
    pub fn of(v: &Value) -> TypedValue {
        let ty = match v {
            Value::Array(_, items) => format!("{}[{}]", element_word(v), items.len()),
            other => other.base_type().word().to_string(),
        };
        TypedValue {
            ty,
            value: plain(v),
        }
    }
}

/// The element type word of an array value (its first element's, else the declared base).
fn element_word(v: &Value) -> String {
    match v {
        Value::Array(b, items) => items.first().map_or_else(
            || b.word().to_string(),
            |i| i.base_type().word().to_string(),
        ),
        other => other.base_type().word().to_string(),
    }
}

/// A type as its word: `float`, `color`, `struct Name`, `vstruct`, `bxdf`, `float[3]`, `int[]`.
pub fn type_word(t: &Type) -> String {
    t.to_string()
}

/// A number as the shortest decimal that reads back to the same `f32` (serde_json would
/// widen `0.2f32` to `0.20000000298023224`); non-finite numbers are `null`.
pub fn num(x: f32) -> Json {
    if !x.is_finite() {
        return Json::Null;
    }
    format!("{x}")
        .parse::<f64>()
        .ok()
        .and_then(serde_json::Number::from_f64)
        .map_or(Json::Null, Json::Number)
}

/// Numbers as a JSON array (see [`num`]).
pub fn nums(xs: &[f32]) -> Json {
    Json::Array(xs.iter().map(|x| num(*x)).collect())
}

/// The value part of [`TypedValue`].
pub fn plain(v: &Value) -> Json {
    match v {
        Value::Int(i) => Json::from(*i),
        Value::Float(x) => num(*x),
        Value::Str(s) | Value::Token(s) | Value::Asset(s) => Json::String(s.clone()),
        Value::Bool(b) => Json::Bool(*b),
        Value::Triple(_, xs) => nums(xs),
        Value::HPoint(xs) => nums(xs),
        Value::Matrix(xs) => nums(xs),
        Value::Array(_, items) => Json::Array(items.iter().map(plain).collect()),
    }
}

/// Print `doc` as pretty JSON with a final newline on standard output; 0, or 1 when the
/// write fails (IO001, reported).
pub fn print(doc: &impl Serialize, common: &CommonOptions) -> ExitCode {
    match to_text(doc) {
        Ok(text) => match super::input::print_stdout(&text, common) {
            Ok(()) => ExitCode::SUCCESS,
            Err(failed) => failed,
        },
        Err(e) => {
            eprintln_quiet!("error: {e}");
            ExitCode::from(1)
        }
    }
}

/// `doc` as pretty JSON with a final newline.
pub fn to_text(doc: &impl Serialize) -> serde_json::Result<String> {
    serde_json::to_string_pretty(doc).map(|s| s + "\n")
}

/// `args` or `oso`.
pub fn format_word(kind: SourceKind) -> &'static str {
    match kind {
        SourceKind::Args => "args",
        SourceKind::Oso => "oso",
    }
}

/// Where the definition file `path` came from: `embedded` (compiled into vstructc),
/// `args-option` (under an `--args` path), `environment` (a `VSTRUCTC_ARGS_PATH` folder).
pub fn origin(path: &str, common: &CommonOptions) -> &'static str {
    if path.starts_with("<embedded>") {
        "embedded"
    } else if common
        .args
        .iter()
        .any(|a| std::path::Path::new(path).starts_with(a))
    {
        "args-option"
    } else {
        "environment"
    }
}

/// A place in a file.
#[derive(Debug, Serialize)]
pub struct LocationDoc {
    /// File name.
    pub file: String,
    /// 1-based line (0: unknown).
    pub line: u32,
    /// 1-based column (0: unknown).
    pub column: u32,
}

impl LocationDoc {
    /// The plain form of `l`.
    pub fn of(l: &Location) -> Self {
        LocationDoc {
            file: l.file.to_string(),
            line: l.line,
            column: l.column,
        }
    }
}

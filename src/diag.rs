//! Diagnostics: positioned messages with stable codes, shared by every stage.
//!
//! Every stage of the pipeline reports problems as [`Diagnostic`] values collected into a
//! [`Diagnostics`] list that is returned to the caller (never only printed). Codes are the
//! stable identifiers of the specification (`AR…` args, `OS…` oso, `RG…` registry, `RB…` RIB,
//! `JS…` JSON, `VS…` vstruct, `LW…` lowering), plus `IO…` for files and streams (IO001: the
//! system refused a read or write; IO002: a stream input above its cap) and the registry's
//! own RG003 (symlink loop in a definitions folder), RG004 (not a regular file) and RG005
//! (definition file too large). Conditions that stop processing are returned as
//! [`Error`], which wraps the same positioned [`Diagnostic`].

use std::fmt;
use std::ops::Range;
use std::path::PathBuf;
use std::sync::Arc;

/// How serious a diagnostic is. Ordered from most to least severe.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Severity {
    /// Processing of the affected input stopped.
    Error,
    /// A likely mistake; processing continued.
    Warning,
    /// Something the user may want to know; shown by default.
    Info,
    /// Detail shown only with `--verbose`.
    Note,
}

impl Severity {
    /// Lower-case name as used in rendered messages (`error`, `warning`, ...).
    pub fn as_str(self) -> &'static str {
        match self {
            Severity::Error => "error",
            Severity::Warning => "warning",
            Severity::Info => "info",
            Severity::Note => "note",
        }
    }
}

impl fmt::Display for Severity {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.as_str())
    }
}

/// Where a diagnostic points: a file (or `<input>`), a 1-based line and column, and
/// optionally a JSON Pointer for JSON inputs.
#[derive(Debug, Clone, PartialEq, Eq, PartialOrd, Ord, Hash, Default, serde::Serialize)]
pub struct Location {
    /// File path as given by the user, or a pseudo-name such as `<expr>` or `<embedded>/X.args`.
    pub file: Arc<str>,
    /// 1-based line; 0 when unknown.
    pub line: u32,
    /// 1-based column (in characters); 0 when unknown.
    pub column: u32,
    /// RFC 6901 JSON Pointer, for JSON inputs.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub pointer: Option<String>,
}

impl Location {
    /// A location at `line:column` of `file`.
    pub fn new(file: impl Into<Arc<str>>, line: u32, column: u32) -> Self {
        Location {
            file: file.into(),
            line,
            column,
            pointer: None,
        }
    }

    /// A location naming only a file.
    pub fn file(file: impl Into<Arc<str>>) -> Self {
        Location::new(file, 0, 0)
    }

    /// The location `line:column` in `text` for byte offset `offset`, in `file`.
    /// Columns count characters, not bytes.
    pub fn from_offset(file: impl Into<Arc<str>>, text: &str, offset: usize) -> Self {
        let (line, column) = line_column(text, offset);
        Location::new(file, line, column)
    }
}

impl fmt::Display for Location {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", self.file)?;
        if self.line > 0 {
            write!(f, ":{}", self.line)?;
            if self.column > 0 {
                write!(f, ":{}", self.column)?;
            }
        }
        if let Some(p) = &self.pointer {
            write!(f, "#{p}")?;
        }
        Ok(())
    }
}

/// 1-based (line, column) of byte `offset` in `text`; columns count characters.
/// Offsets past the end map to the position just after the last character.
pub fn line_column(text: &str, offset: usize) -> (u32, u32) {
    let mut offset = offset.min(text.len());
    while !text.is_char_boundary(offset) {
        offset -= 1;
    }
    let before = &text[..offset];
    let line = before.bytes().filter(|&b| b == b'\n').count() as u32 + 1;
    let line_start = before.rfind('\n').map_or(0, |i| i + 1);
    let column = before[line_start..].chars().count() as u32 + 1;
    (line, column)
}

/// One positioned message with a stable code.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Diagnostic {
    /// Severity.
    pub severity: Severity,
    /// Stable code such as `VS001` or `AR004`.
    pub code: &'static str,
    /// One-line message.
    pub message: String,
    /// Primary location, if known.
    pub location: Option<Location>,
    /// Byte span inside an expression or value the message is about (e.g. a conditional).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub span: Option<Range<usize>>,
    /// Extra lines of explanation (caret renderings, expected tokens, cycle paths, ...).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub notes: Vec<String>,
    /// Related locations with a short label each.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub related: Vec<(String, Location)>,
}

impl Diagnostic {
    /// A diagnostic without location.
    pub fn new(severity: Severity, code: &'static str, message: impl Into<String>) -> Self {
        Diagnostic {
            severity,
            code,
            message: message.into(),
            location: None,
            span: None,
            notes: Vec::new(),
            related: Vec::new(),
        }
    }
    /// An error diagnostic.
    pub fn error(code: &'static str, message: impl Into<String>) -> Self {
        Self::new(Severity::Error, code, message)
    }
    /// A warning diagnostic.
    pub fn warning(code: &'static str, message: impl Into<String>) -> Self {
        Self::new(Severity::Warning, code, message)
    }
    /// An info diagnostic.
    pub fn info(code: &'static str, message: impl Into<String>) -> Self {
        Self::new(Severity::Info, code, message)
    }
    /// A note diagnostic (shown only with `--verbose`).
    pub fn note(code: &'static str, message: impl Into<String>) -> Self {
        Self::new(Severity::Note, code, message)
    }
    /// Builder: set the primary location.
    pub fn at(mut self, location: Location) -> Self {
        self.location = Some(location);
        self
    }
    /// Builder: set the byte span inside an expression or value.
    pub fn with_span(mut self, span: Range<usize>) -> Self {
        self.span = Some(span);
        self
    }
    /// Builder: add a line of explanation.
    pub fn with_note(mut self, note: impl Into<String>) -> Self {
        self.notes.push(note.into());
        self
    }
    /// Builder: add a related location.
    pub fn with_related(mut self, label: impl Into<String>, location: Location) -> Self {
        self.related.push((label.into(), location));
        self
    }

    /// Human rendering: `severity[CODE]: message`, then `  --> file:line:col`, then notes.
    pub fn render_human(&self) -> String {
        let mut out = format!("{}[{}]: {}", self.severity, self.code, self.message);
        if let Some(loc) = &self.location {
            out.push_str(&format!("\n  --> {loc}"));
        }
        for (label, loc) in &self.related {
            out.push_str(&format!("\n  note: {label}: {loc}"));
        }
        for note in &self.notes {
            for line in note.lines() {
                out.push_str("\n  ");
                out.push_str(line);
            }
        }
        out
    }

    /// JSON rendering: one object with `severity`, `code`, `message`, `location`, `related`.
    pub fn render_json(&self) -> String {
        serde_json::to_string(self).unwrap_or_else(|_| String::from("{}"))
    }
}

impl fmt::Display for Diagnostic {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.render_human())
    }
}

/// An ordered collection of diagnostics returned by every stage.
#[derive(Debug, Clone, Default, PartialEq, serde::Serialize)]
#[serde(transparent)]
pub struct Diagnostics {
    items: Vec<Diagnostic>,
}

impl Diagnostics {
    /// An empty list.
    pub fn new() -> Self {
        Self::default()
    }
    /// Append one diagnostic.
    pub fn push(&mut self, d: Diagnostic) {
        self.items.push(d);
    }
    /// Append all diagnostics of `other`.
    pub fn extend(&mut self, other: impl IntoIterator<Item = Diagnostic>) {
        self.items.extend(other);
    }
    /// All diagnostics in insertion order.
    pub fn items(&self) -> &[Diagnostic] {
        &self.items
    }
    /// Number of diagnostics.
    pub fn len(&self) -> usize {
        self.items.len()
    }
    /// True if there are none.
    pub fn is_empty(&self) -> bool {
        self.items.is_empty()
    }
    /// Iterate in insertion order.
    pub fn iter(&self) -> std::slice::Iter<'_, Diagnostic> {
        self.items.iter()
    }
    /// True if any diagnostic is an error.
    pub fn has_errors(&self) -> bool {
        self.items.iter().any(|d| d.severity == Severity::Error)
    }
    /// True if any diagnostic is a warning or error.
    pub fn has_warnings(&self) -> bool {
        self.items.iter().any(|d| d.severity <= Severity::Warning)
    }
    /// Diagnostics with the given code.
    pub fn with_code<'a>(&'a self, code: &'a str) -> impl Iterator<Item = &'a Diagnostic> + 'a {
        self.items.iter().filter(move |d| d.code == code)
    }
    /// Number of diagnostics with the given code.
    pub fn count(&self, code: &str) -> usize {
        self.with_code(code).count()
    }
    /// Sort into the deterministic emission order: by file, then position, then code.
    /// Diagnostics without location keep their relative order after located ones.
    pub fn sort(&mut self) {
        self.items.sort_by(|a, b| {
            let ka = a.location.as_ref().map(|l| (&*l.file, l.line, l.column));
            let kb = b.location.as_ref().map(|l| (&*l.file, l.line, l.column));
            match (ka, kb) {
                (Some(x), Some(y)) => x.cmp(&y).then(a.code.cmp(b.code)),
                (Some(_), None) => std::cmp::Ordering::Less,
                (None, Some(_)) => std::cmp::Ordering::Greater,
                (None, None) => std::cmp::Ordering::Equal,
            }
        });
    }
    /// Consume into the underlying vector.
    pub fn into_vec(self) -> Vec<Diagnostic> {
        self.items
    }
}

impl IntoIterator for Diagnostics {
    type Item = Diagnostic;
    type IntoIter = std::vec::IntoIter<Diagnostic>;
    fn into_iter(self) -> Self::IntoIter {
        self.items.into_iter()
    }
}

impl<'a> IntoIterator for &'a Diagnostics {
    type Item = &'a Diagnostic;
    type IntoIter = std::slice::Iter<'a, Diagnostic>;
    fn into_iter(self) -> Self::IntoIter {
        self.items.iter()
    }
}

impl From<Vec<Diagnostic>> for Diagnostics {
    fn from(items: Vec<Diagnostic>) -> Self {
        Diagnostics { items }
    }
}

/// Errors that stop processing of one input. Input errors carry a positioned diagnostic
/// (file, line, column, code).
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// Malformed input: the diagnostic says where and why.
    #[error("{0}")]
    Input(Box<Diagnostic>),
    /// A file could not be read or written.
    #[error("{path}: {source}")]
    Io {
        /// The path that failed.
        path: PathBuf,
        /// The underlying I/O error.
        #[source]
        source: std::io::Error,
    },
    /// Wrong use of an API or command (bad option value, unknown shader name, ...).
    #[error("{0}")]
    Usage(String),
    /// A bound of [`crate::limits::Limits`] was exceeded.
    #[error("{0}")]
    Limit(Box<crate::limits::LimitExceeded>),
}

impl Error {
    /// The positioned diagnostic of an input error.
    pub fn diagnostic(&self) -> Option<&Diagnostic> {
        match self {
            Error::Input(d) => Some(d),
            _ => None,
        }
    }
    /// The stable code of an input error (`LM001` for an exceeded limit).
    pub fn code(&self) -> Option<&'static str> {
        match self {
            Error::Limit(_) => Some("LM001"),
            _ => self.diagnostic().map(|d| d.code),
        }
    }

    /// The error as one diagnostic, as the command line prints it (`IO001` for I/O,
    /// `USAGE` for usage errors).
    pub fn to_diagnostic(&self) -> Diagnostic {
        match self {
            Error::Input(d) => (**d).clone(),
            Error::Io { path, source } => Diagnostic::error("IO001", format!("{source}"))
                .at(Location::file(path.display().to_string())),
            Error::Usage(msg) => Diagnostic::error("USAGE", msg.clone()),
            Error::Limit(e) => e.to_diagnostic(),
        }
    }
}

impl From<crate::limits::LimitExceeded> for Error {
    fn from(e: crate::limits::LimitExceeded) -> Self {
        Error::Limit(Box::new(e))
    }
}

impl From<Diagnostic> for Error {
    fn from(d: Diagnostic) -> Self {
        Error::Input(Box::new(d))
    }
}

/// Result type of the crate.
pub type Result<T, E = Error> = std::result::Result<T, E>;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn line_column_counts_characters() {
        let text = "ab\ncé\nx";
        assert_eq!(line_column(text, 0), (1, 1));
        assert_eq!(line_column(text, 3), (2, 1));
        // 'é' is two bytes; offset 6 is after it.
        assert_eq!(line_column(text, 6), (2, 3));
        assert_eq!(line_column(text, 100), (3, 2));
    }

    #[test]
    fn sort_orders_by_file_position_code() {
        let mut d = Diagnostics::new();
        d.push(Diagnostic::warning("VS002", "b").at(Location::new("f", 2, 1)));
        d.push(Diagnostic::warning("VS001", "a").at(Location::new("f", 2, 1)));
        d.push(Diagnostic::warning("VS009", "none"));
        d.push(Diagnostic::warning("VS003", "c").at(Location::new("f", 1, 9)));
        d.sort();
        let codes: Vec<_> = d.iter().map(|x| x.code).collect();
        assert_eq!(codes, ["VS003", "VS001", "VS002", "VS009"]);
    }

    #[test]
    fn human_rendering_has_code_and_location() {
        let d =
            Diagnostic::error("AR004", "duplicate parameter `x`").at(Location::new("a.args", 3, 5));
        assert_eq!(
            d.render_human(),
            "error[AR004]: duplicate parameter `x`\n  --> a.args:3:5"
        );
        assert!(d.render_json().contains("\"code\":\"AR004\""));
    }
}

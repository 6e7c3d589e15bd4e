//! Diagnostics: positioned messages with stable codes, shared by every stage.
//!
//! Every stage of the pipeline reports problems as [`Diagnostic`] values collected into a
//! [`Diagnostics`] list that is returned to the caller (never only printed). Codes are the
//! stable identifiers of the specification (`AR…` args, `OS…` oso, `RG…` registry, `RB…` RIB,
//! `JS…` JSON, `VS…` vstruct, `LW…` lowering), plus `IO…` for files and streams (IO001: the
//! system refused a read or write; IO002: the PNG encoder failed; IO003: a recognised input
//! format that is not read, USD or MaterialX), `LM001` for a bound of
//! [`crate::limits::Limits`] exceeded (file sizes, nodes, fan-in, parameters, expression
//! terms and depth, preview pixels), and the registry's own RG003 (symlink loop in a
//! definitions folder) and RG004 (not a regular file). Conditions that stop processing are returned as
//! [`Error`], which wraps the same positioned [`Diagnostic`].

use std::fmt;
use std::ops::{Deref, Range};
use std::path::PathBuf;
use std::sync::Arc;

/// How serious a diagnostic is. Ordered from least to most severe, so that
/// `d.severity >= Severity::Warning` reads "a warning or an error".
///
/// ```
/// use vstructc::Severity;
/// assert!(Severity::Error > Severity::Warning);
/// assert!(Severity::Warning > Severity::Info && Severity::Info > Severity::Note);
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Severity {
    /// Detail shown only with `--verbose`.
    Note,
    /// Something the user may want to know; shown by default.
    Info,
    /// A likely mistake; processing continued.
    Warning,
    /// Processing of the affected input stopped.
    Error,
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

mod codes;
// Below `limits`, which re-exports its types: `Error::Limit` needs them here.
pub(crate) mod limit;

/// A diagnostic's stable code (`VS009`, `AR004`, …): two letters naming the stage and three
/// digits. [`Code::meaning`] gives its documented meaning. A `Code` compares equal to its text
/// (`d.code == "VS009"`) and dereferences to it.
///
/// ```
/// use vstructc::diag::Code;
/// let c = Code::new("VS009");
/// assert_eq!(c, "VS009");
/// assert!(c.meaning().unwrap().contains("not an input"));
/// assert_eq!(Code::new("XX999").meaning(), None);
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct Code(&'static str);

impl Code {
    /// The code with this text.
    pub const fn new(code: &'static str) -> Code {
        Code(code)
    }
    /// The code's text.
    pub fn as_str(self) -> &'static str {
        self.0
    }
    /// The code's documented meaning (one line, as in the tables of the user documentation),
    /// or `None` for a code vstructc does not report.
    pub fn meaning(self) -> Option<&'static str> {
        codes::CODES
            .binary_search_by(|(c, _)| (*c).cmp(self.0))
            .ok()
            .map(|i| codes::CODES[i].1)
    }
    /// Every code vstructc reports, in order, with its meaning.
    pub fn all() -> impl Iterator<Item = (Code, &'static str)> {
        codes::CODES.iter().map(|(c, m)| (Code(c), *m))
    }
}

impl Deref for Code {
    type Target = str;
    fn deref(&self) -> &str {
        self.0
    }
}

impl std::borrow::Borrow<str> for Code {
    fn borrow(&self) -> &str {
        self.0
    }
}

impl From<&'static str> for Code {
    fn from(code: &'static str) -> Code {
        Code(code)
    }
}

impl PartialEq<str> for Code {
    fn eq(&self, other: &str) -> bool {
        self.0 == other
    }
}

impl PartialEq<&str> for Code {
    fn eq(&self, other: &&str) -> bool {
        self.0 == *other
    }
}

impl PartialEq<Code> for &str {
    fn eq(&self, other: &Code) -> bool {
        *self == other.0
    }
}

impl fmt::Display for Code {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.0)
    }
}

impl serde::Serialize for Code {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_str(self.0)
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
    /// RFC 6901 JSON Pointer, for JSON inputs; the prim or property path, for USD inputs.
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
#[cfg_attr(feature = "testkit", visibility::make(pub))]
pub(crate) fn line_column(text: &str, offset: usize) -> (u32, u32) {
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
    /// Stable code such as `VS001` or `AR004`, with its documented meaning.
    pub code: Code,
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
    /// The handle of the network node the diagnostic is about, if it is about one (set by
    /// resolution and lowering, also for networks built in memory, which have no
    /// [`Location`]).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub node: Option<String>,
    /// The parameter (input or output) of [`Diagnostic::node`] the diagnostic is about, if
    /// any.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub param: Option<String>,
}

impl Diagnostic {
    /// The longest line, in characters, of a diagnostic in a human report; a longer line keeps
    /// its beginning and end and says how many characters were left out.
    pub const MAX_HUMAN_LINE: usize = 2000;

    /// `line` shortened to at most about `max` characters: its beginning and end, and between
    /// them how many characters were left out. Shorter lines are returned unchanged.
    ///
    /// ```
    /// use vstructc::diag::Diagnostic;
    /// let long = "x".repeat(10_000);
    /// let short = Diagnostic::bound_line(&long, 100);
    /// assert!(short.chars().count() < 160);
    /// assert!(short.contains("9900 characters left out"));
    /// ```
    pub fn bound_line(line: &str, max: usize) -> std::borrow::Cow<'_, str> {
        let count = line.chars().count();
        if count <= max {
            return std::borrow::Cow::Borrowed(line);
        }
        let head = max / 2;
        let tail = max - head;
        let start_tail = line
            .char_indices()
            .nth(count - tail)
            .map_or(line.len(), |(i, _)| i);
        let end_head = line.char_indices().nth(head).map_or(0, |(i, _)| i);
        std::borrow::Cow::Owned(format!(
            "{} … [{} characters left out] … {}",
            &line[..end_head],
            count - max,
            &line[start_tail..]
        ))
    }

    /// A diagnostic without location.
    pub fn new(severity: Severity, code: impl Into<Code>, message: impl Into<String>) -> Self {
        Diagnostic {
            severity,
            code: code.into(),
            message: message.into(),
            location: None,
            span: None,
            notes: Vec::new(),
            related: Vec::new(),
            node: None,
            param: None,
        }
    }
    /// An error diagnostic.
    pub fn error(code: impl Into<Code>, message: impl Into<String>) -> Self {
        Self::new(Severity::Error, code, message)
    }
    /// A warning diagnostic.
    pub fn warning(code: impl Into<Code>, message: impl Into<String>) -> Self {
        Self::new(Severity::Warning, code, message)
    }
    /// An info diagnostic.
    pub fn info(code: impl Into<Code>, message: impl Into<String>) -> Self {
        Self::new(Severity::Info, code, message)
    }
    /// A note diagnostic (shown only with `--verbose`).
    pub fn note(code: impl Into<Code>, message: impl Into<String>) -> Self {
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
    /// Builder: the handle of the node the diagnostic is about.
    pub fn with_node(mut self, handle: impl Into<String>) -> Self {
        self.node = Some(handle.into());
        self
    }
    /// Builder: the parameter of the node the diagnostic is about.
    pub fn with_param(mut self, name: impl Into<String>) -> Self {
        self.param = Some(name.into());
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
    /// How many diagnostics of one code a human report shows before it summarises the rest
    /// (`--max-diagnostics`, whose 0 means no limit).
    pub const DEFAULT_MAX_PER_CODE: usize = 20;

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
        self.items.iter().any(|d| d.severity >= Severity::Warning)
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
                (Some(x), Some(y)) => x.cmp(&y).then(a.code.cmp(&b.code)),
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
    /// Keep one of each set of identical diagnostics (same severity, code, location,
    /// message, node and parameter; notes and related locations are not compared): the
    /// first, in place. Linear in the number of diagnostics.
    ///
    /// ```
    /// use vstructc::{Diagnostic, Diagnostics};
    /// let mut d = Diagnostics::new();
    /// for _ in 0..3 {
    ///     d.push(Diagnostic::info("LW020", "`specularModelType` is 0").with_node("ball"));
    /// }
    /// d.push(Diagnostic::info("LW020", "`specularModelType` is 0").with_node("other"));
    /// d.dedup();
    /// assert_eq!(d.len(), 2);
    /// ```
    pub fn dedup(&mut self) {
        type Key<'k> = (
            Severity,
            &'k str,
            Option<&'k Location>,
            &'k str,
            Option<&'k str>,
            Option<&'k str>,
        );
        let keep: Vec<bool> = {
            let mut seen: std::collections::HashSet<Key<'_>> = std::collections::HashSet::new();
            self.items
                .iter()
                .map(|d| {
                    seen.insert((
                        d.severity,
                        d.code.as_str(),
                        d.location.as_ref(),
                        d.message.as_str(),
                        d.node.as_deref(),
                        d.param.as_deref(),
                    ))
                })
                .collect()
        };
        let mut keep = keep.into_iter();
        self.items.retain(|_| keep.next().unwrap_or(true));
    }
}

/// The names among `candidates` that `name` is most likely a misspelling of, best first, at
/// most three of them, all of the best kind found: names equal but for letter
/// case, else names within an edit
/// distance (insertions, deletions, substitutions and swaps of neighbours, ignoring case) of
/// a quarter of `name`'s length (at least 1, at most 3), else names that begin with `name`
/// when it has at least 3 characters. Ties keep the candidates' order.
///
pub(crate) fn closest_names<'a>(
    name: &str,
    candidates: impl IntoIterator<Item = &'a str>,
) -> Vec<&'a str> {
    let lower = name.to_lowercase();
    let len = lower.chars().count();
    let max = (len / 4).clamp(1, 3);
    // (rank, distance, order): rank 0 equal but for case, 1 within the distance, 2 a prefix.
    let mut found: Vec<(u8, usize, usize, &'a str)> = Vec::new();
    for (i, c) in candidates.into_iter().enumerate() {
        if c == name {
            continue;
        }
        let cl = c.to_lowercase();
        if cl == lower {
            found.push((0, 0, i, c));
            continue;
        }
        // Lengths differing by more than the bound cannot be within it.
        let clen = cl.chars().count();
        if clen.abs_diff(len) <= max {
            let d = strsim::osa_distance(&lower, &cl);
            if d <= max {
                found.push((1, d, i, c));
                continue;
            }
        }
        if len >= 3 && cl.starts_with(&lower) {
            found.push((2, clen - len, i, c));
        }
    }
    found.sort_unstable();
    // Only the best kind of match: a name equal but for case hides near ones, a near one
    // hides longer names it begins.
    if let Some(&(best, ..)) = found.first() {
        found.retain(|f| f.0 == best);
    }
    found.truncate(SUGGESTIONS);
    found.into_iter().map(|(.., c)| c).collect()
}

/// How many names [`closest_names`] suggests at most.
const SUGGESTIONS: usize = 3;

/// A "did you mean" hint for an unknown `name` among `candidates`, as the end of a
/// message: `"; did you mean `a`?"`, `"; did you mean `a` or `b`?"`, or nothing when no
/// candidate is close. Close candidates are those equal but for case, else within an edit
/// distance (insertions, deletions, substitutions and swaps of neighbours, ignoring case) of
/// a quarter of `name`'s length (at least 1, at most 3), else those that begin with `name`
/// when it has at least 3 characters; at most three, best first.
///
/// ```
/// use vstructc::diag::did_you_mean;
/// let names = ["diffuseColor", "diffuseGain", "specularColor"];
/// assert_eq!(did_you_mean("diffuseColour", names), "; did you mean `diffuseColor`?");
/// assert_eq!(did_you_mean("DIFFUSEGAIN", names), "; did you mean `diffuseGain`?");
/// assert_eq!(
///     did_you_mean("pxrlayer", ["PxrLayerMixer", "PxrLayer"]),
///     "; did you mean `PxrLayer`?"
/// );
/// assert_eq!(
///     did_you_mean("diffuse", names),
///     "; did you mean `diffuseGain` or `diffuseColor`?"
/// );
/// assert_eq!(did_you_mean("roughness", names), "");
/// ```
pub fn did_you_mean<'a>(name: &str, candidates: impl IntoIterator<Item = &'a str>) -> String {
    hint_text(&closest_names(name, candidates))
}

/// `names` as the end of a message (see [`did_you_mean`]).
pub(crate) fn hint_text(names: &[&str]) -> String {
    match names {
        [] => String::new(),
        [one] => format!("; did you mean `{one}`?"),
        [init @ .., last] => {
            let init: Vec<String> = init.iter().map(|n| format!("`{n}`")).collect();
            format!("; did you mean {} or `{last}`?", init.join(", "))
        }
    }
}

/// What a report prints out of a [`Diagnostics`] list: see [`Diagnostics::volume_limited`].
#[derive(Debug, Clone, PartialEq)]
pub struct Shown<'a> {
    /// The diagnostics to print, in list order.
    pub items: Vec<&'a Diagnostic>,
    /// Per code (in the order the first one was left out): how many distinct diagnostics of
    /// that code were left out by the per-code limit.
    pub suppressed: Vec<(&'static str, usize)>,
}

impl Diagnostics {
    /// The diagnostics a report prints: those `keep` accepts, with `dedup` identical ones
    /// (same severity, code, location and message; notes and related locations are not
    /// compared) once, and at most `max_per_code` distinct ones of each code (0: no limit).
    /// The rest of each code is counted in [`Shown::suppressed`]. Linear in the number of
    /// diagnostics.
    ///
    /// ```
    /// use vstructc::{Diagnostic, Diagnostics};
    /// let mut d = Diagnostics::new();
    /// for i in 0..5 {
    ///     d.push(Diagnostic::warning("RB018", format!("reference {i}")));
    ///     d.push(Diagnostic::warning("RB018", format!("reference {i}")));
    /// }
    /// let shown = d.volume_limited(3, true, |_| true);
    /// assert_eq!(shown.items.len(), 3);
    /// assert_eq!(shown.suppressed, [("RB018", 2)]);
    /// assert_eq!(d.volume_limited(0, false, |_| true).items.len(), 10);
    /// ```
    pub fn volume_limited(
        &self,
        max_per_code: usize,
        dedup: bool,
        keep: impl Fn(&Diagnostic) -> bool,
    ) -> Shown<'_> {
        type Key<'k> = (Severity, &'static str, Option<&'k Location>, &'k str);
        let mut seen: std::collections::HashSet<Key<'_>> = std::collections::HashSet::new();
        let mut per_code: std::collections::HashMap<&'static str, usize> =
            std::collections::HashMap::new();
        let mut shown = Shown {
            items: Vec::new(),
            suppressed: Vec::new(),
        };
        for d in self.items.iter().filter(|d| keep(d)) {
            if dedup
                && !seen.insert((
                    d.severity,
                    d.code.as_str(),
                    d.location.as_ref(),
                    d.message.as_str(),
                ))
            {
                continue;
            }
            let count = per_code.entry(d.code.as_str()).or_insert(0);
            *count += 1;
            if max_per_code == 0 || *count <= max_per_code {
                shown.items.push(d);
            } else if let Some(s) = shown.suppressed.iter_mut().find(|(c, _)| *c == d.code) {
                s.1 += 1;
            } else {
                shown.suppressed.push((d.code.as_str(), 1));
            }
        }
        shown
    }
}

/// How many items [`join_bounded`] names at each end of a long list.
pub(crate) const LIST_ENDS: usize = 3;

/// The items of a list of `len` joined with `, `, naming at most `LIST_ENDS` (3) at each end
/// of a longer list and the number left out between them; `item(i)` is called only for the
/// items named, so a message about a list of 100,000 nodes costs what one about 6 does.
#[cfg_attr(feature = "testkit", visibility::make(pub))]
pub(crate) fn join_bounded(len: usize, mut item: impl FnMut(usize) -> String) -> String {
    if len <= 2 * LIST_ENDS + 1 {
        return (0..len).map(item).collect::<Vec<_>>().join(", ");
    }
    let head: Vec<String> = (0..LIST_ENDS).map(&mut item).collect();
    let tail: Vec<String> = (len - LIST_ENDS..len).map(&mut item).collect();
    format!(
        "{}, … {} more …, {}",
        head.join(", "),
        len - 2 * LIST_ENDS,
        tail.join(", ")
    )
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
    Limit(Box<limit::LimitExceeded>),
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
            _ => self.diagnostic().map(|d| d.code.as_str()),
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

impl From<limit::LimitExceeded> for Error {
    fn from(e: limit::LimitExceeded) -> Self {
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

//! Parse errors (VS001) and caret rendering.

use crate::diag::{Diagnostic, Severity};
use std::fmt;
use std::ops::Range;

/// A syntax error in a conditional expression (VS001).
///
/// The message names the expected set and the offending token with the token names, in
/// the form `expected NUMBER or STRING, found PARAM "y"` (for a predicate's operator slot the
/// expected set is summarised as `a comparison operator (==, !=, <, >, <=, >=)`; the full set,
/// which also holds `IS` and `IS_NOT`, is in [`ParseError::expected`]).
/// [`ParseError::in_words`] says the same in the language's words, for readers.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ParseError {
    /// Byte span of the offending token (empty at end of input).
    pub span: Range<usize>,
    /// Message naming the expected set and the unexpected token.
    pub message: String,
    /// Every token that would have been accepted at this point (token names, operators as
    /// spelled, `end of input`).
    pub expected: Vec<String>,
    /// The offending token as described in the message (`'='`, `PARAM "y"`, `end of input`).
    pub found: String,
    /// Hints about the likely mistake (`use '==' to compare`, …).
    pub notes: Vec<String>,
    /// Set when the expression exceeded a bound of [`crate::limits::Limits`]
    /// ([`Limits::expr_terms`](crate::limits::Limits::expr_terms) or
    /// [`Limits::expr_depth`](crate::limits::Limits::expr_depth)); `span` is where.
    pub limit: Option<Box<crate::limits::LimitExceeded>>,
}

impl ParseError {
    /// The stable code of a conditional syntax error.
    pub const CODE: &'static str = "VS001";

    /// 1-based `(line, column)` of the offending token in `text` (columns count characters).
    pub fn line_column(&self, text: &str) -> (u32, u32) {
        crate::diag::line_column(text, self.span.start)
    }

    /// 1-based column of the offending token in `text` on its line.
    pub fn column(&self, text: &str) -> u32 {
        self.line_column(text).1
    }

    /// Human rendering: the message, the expression with a caret line under the offending
    /// token, and the notes.
    pub fn render(&self, text: &str) -> String {
        let (line, column) = self.line_column(text);
        let mut out = format!("{} (at line {line}, column {column})\n", self.message);
        for l in render_caret(text, self.span.clone()).lines() {
            out.push_str("  ");
            out.push_str(l);
            out.push('\n');
        }
        for n in &self.notes {
            out.push_str("  note: ");
            out.push_str(n);
            out.push('\n');
        }
        out
    }

    /// What was expected and what was found, in one sentence in the language's words rather
    /// than token names: `expected a number or a quoted string, found the end of the
    /// expression`. An error that is not about an unexpected token (a bound of
    /// [`crate::limits::Limits`] exceeded) is said by its [`ParseError::message`] as it is.
    ///
    /// ```
    /// let err = vstructc::cond::parse("set 1 if x is").unwrap_err();
    /// assert_eq!(
    ///     err.in_words(),
    ///     "expected `connected` or `set`, found the end of the expression"
    /// );
    /// ```
    pub fn in_words(&self) -> String {
        if self.limit.is_some() || self.expected.is_empty() {
            return self.message.clone();
        }
        let mut items: Vec<String> = Vec::new();
        let cmp = ["==", "!=", "<", ">", "<=", ">="];
        let all_cmp = cmp.iter().all(|c| self.expected.iter().any(|e| e == c));
        let mut pushed_cmp = false;
        for e in &self.expected {
            let e = e.as_str();
            if all_cmp && cmp.contains(&e) {
                if !pushed_cmp {
                    items.push("a comparison (`==`, `!=`, `<`, `>`, `<=` or `>=`)".into());
                    pushed_cmp = true;
                }
                continue;
            }
            let word = expected_word(e);
            if !items.contains(&word) {
                items.push(word);
            }
        }
        let expected = match items.as_slice() {
            [] => String::from("something else"),
            [one] => one.clone(),
            [init @ .., last] => format!("{} or {last}", init.join(", ")),
        };
        format!("expected {expected}, found {}", found_words(&self.found))
    }

    /// A VS001 diagnostic (warning, as in definitions) with the span, the caret rendering,
    /// the expected set and the notes. The caller adds the location.
    pub fn to_diagnostic(&self, text: &str) -> Diagnostic {
        self.to_diagnostic_with(text, Severity::Warning)
    }

    /// [`ParseError::to_diagnostic`] with a chosen severity (`vstructc expr` reports the
    /// error of its only input as an error).
    pub fn to_diagnostic_with(&self, text: &str, severity: Severity) -> Diagnostic {
        let column = self.column(text);
        let mut d = Diagnostic::new(
            severity,
            Self::CODE,
            format!("conditional expression: {}", self.message),
        )
        .with_span(self.span.clone())
        .with_note(format!(
            "at byte {} (column {column}) of the expression:",
            self.span.start
        ))
        .with_note(indent(&render_caret(text, self.span.clone())));
        if !self.expected.is_empty() {
            d = d.with_note(format!("expected one of: {}", self.expected.join(" ")));
        }
        for n in &self.notes {
            d = d.with_note(format!("note: {n}"));
        }
        d
    }
}

impl fmt::Display for ParseError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{} (bytes {}..{})",
            self.message, self.span.start, self.span.end
        )
    }
}

impl std::error::Error for ParseError {}

/// One expected token in words: keywords as written, literals and names described.
fn expected_word(token: &str) -> String {
    match token {
        "NUMBER" => "a number".into(),
        "STRING" => "a quoted string".into(),
        "PARAM" => "a parameter name".into(),
        "end of input" => "the end of the expression".into(),
        t if !t.is_empty() && t.chars().all(|c| c.is_ascii_uppercase() || c == '_') => {
            format!("`{}`", t.to_ascii_lowercase().replace('_', " "))
        }
        t => format!("`{t}`"),
    }
}

/// The offending token as found (see [`ParseError::found`]) in words.
fn found_words(found: &str) -> String {
    if found == "end of input" {
        return "the end of the expression".into();
    }
    if let Some(n) = found.strip_prefix("NUMBER ") {
        return format!("the number {n}");
    }
    if let Some(s) = found.strip_prefix("STRING ") {
        return format!("the string {s}");
    }
    if let Some(p) = found.strip_prefix("PARAM ") {
        return format!("the name {p}");
    }
    if let Some(t) = found
        .strip_prefix('\'')
        .and_then(|f| f.strip_suffix('\''))
        .filter(|t| !t.is_empty())
    {
        return format!("`{t}`");
    }
    if !found.is_empty() && found.chars().all(|c| c.is_ascii_uppercase() || c == '_') {
        return format!("`{}`", found.to_ascii_lowercase().replace('_', " "));
    }
    found.to_string()
}

fn indent(text: &str) -> String {
    text.lines()
        .map(|l| format!("  {l}"))
        .collect::<Vec<_>>()
        .join("\n")
}

/// How one character of the expression is shown: tabs stay tabs (so the caret line lines up
/// in a terminal), other whitespace and control characters become visible escapes.
fn shown(c: char) -> String {
    match c {
        '\t' => "\t".into(),
        ' ' => " ".into(),
        c if c.is_control() => super::lexer::escape_char(c),
        c => c.to_string(),
    }
}

/// Padding under a shown character: a tab under a tab, else one space per shown column.
fn pad_for(c: char) -> String {
    if c == '\t' {
        "\t".into()
    } else {
        " ".repeat(shown(c).chars().count())
    }
}

/// Characters of a long line shown before a marked span, and after it.
const CARET_CONTEXT: usize = 200;

/// Characters of a long span marked under it.
const CARET_SPAN: usize = 200;

/// The line of `text` that contains byte `span.start`, and under it a caret line marking the
/// span (`^` under its first character, `~` under the rest of it on that line; a single `^`
/// just past the end for an empty span). Control characters such as `\r` are shown escaped
/// and the caret line accounts for their width.
///
/// A line longer than the window (200 characters before the span, 200 of the span, 200
/// after it) is cut to that window, with `…` where it was cut: the rendering costs the same
/// for a one-line expression of 10 MB, which may report a diagnostic per predicate.
///
/// For `connect if x = 1` and the span `13..14`:
///
/// ```text
/// connect if x = 1
///              ^
/// ```
pub fn render_caret(text: &str, span: Range<usize>) -> String {
    let mut start = span.start.min(text.len());
    while !text.is_char_boundary(start) {
        start -= 1;
    }
    // Only the window is scanned, never the whole line.
    let from = walk_back(text, start, CARET_CONTEXT);
    let span_end = walk_forward(text, start, CARET_SPAN);
    let end = span.end.clamp(start, span_end);
    let to = walk_forward(text, end, CARET_CONTEXT);
    let cut_before = from > 0 && text.as_bytes()[from - 1] != b'\n';
    let cut_after = to < text.len() && text.as_bytes()[to] != b'\n';
    let mut shown_line = String::new();
    let mut carets = String::new();
    if cut_before {
        shown_line.push('…');
        carets.push(' ');
    }
    for (i, c) in text[from..to].char_indices() {
        let at = from + i;
        shown_line.push_str(&shown(c));
        if at < start {
            carets.push_str(&pad_for(c));
        } else if at < end {
            let mark = if at == start { '^' } else { '~' };
            let width = shown(c).chars().count().max(1);
            carets.push(mark);
            carets.push_str(&"~".repeat(width - 1));
        }
    }
    if cut_after {
        shown_line.push('…');
    }
    if end == start {
        carets.push('^');
    }
    format!("{}\n{}", shown_line.trim_end_matches(' '), carets)
}

/// The byte offset up to `max` characters before `at`, stopping after a newline.
fn walk_back(text: &str, at: usize, max: usize) -> usize {
    let mut from = at;
    for (i, c) in text[..at].char_indices().rev().take(max) {
        if c == '\n' {
            break;
        }
        from = i;
    }
    from
}

/// The byte offset up to `max` characters after `at`, stopping before a newline.
fn walk_forward(text: &str, at: usize, max: usize) -> usize {
    let mut to = at;
    for (i, c) in text[at..].char_indices().take(max) {
        if c == '\n' {
            return at + i;
        }
        to = at + i + c.len_utf8();
    }
    to
}

/// The source location of byte `offset` of an expression whose first character is at
/// `start` (the position the definition readers record for a `vstructConditionalExpr` value).
/// Walks the decoded text: a newline advances the line, any other character one column. This
/// is the "value start plus decoded offset" mapping.
#[cfg(any(test, feature = "testkit"))]
pub fn location_in(
    start: &crate::diag::Location,
    text: &str,
    offset: usize,
) -> crate::diag::Location {
    let (dl, dc) = crate::diag::line_column(text, offset);
    let mut loc = start.clone();
    if start.line == 0 {
        return loc;
    }
    if dl == 1 {
        loc.column = start.column.max(1) + dc - 1;
    } else {
        loc.line = start.line + dl - 1;
        loc.column = dc;
    }
    loc
}

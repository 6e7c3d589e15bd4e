//! Compiled OSL `.oso` reader.
//!
//! [`parse_oso`] reads one file's bytes into a [`Definition`] whose id is the shader name.
//! Only the header, the shader line and the `param`/`oparam` lines are read; the property
//! section ends at the first `local`, `temp`, `global`, `const` or `code` line, and nothing
//! after it is looked at. No OSL installation is needed.
//!
//! The lexical rules follow OSL's own `.oso` scanner (`osolex.l`): `#` comments, a backslash
//! before a newline continues the line, double-quoted strings with C escapes that cannot span
//! a line, and hints (`%name{item,item,…}`) that are one lexical unit, so braces and commas
//! inside their quoted strings do not end them.
//!
//! Choices where the spec is silent (documented here so they are visible to users):
//!
//! * Bytes that are not valid UTF-8 are decoded lossily (U+FFFD); `.oso` is ASCII in practice.
//!   A leading UTF-8 byte-order mark is skipped.
//! * Blank lines and comment lines may appear anywhere before the code section.
//! * Spaces and tabs are accepted between the items of a hint (`%meta{int, x, 1}`).
//! * A `%meta` entry that is not `TYPE,NAME,VALUE…`, whose values do not match TYPE, or whose
//!   scalar TYPE has several values is reported like an unknown TYPE (OS011) and ignored. The
//!   number of values of an array TYPE is not checked against its length.
//! * A default whose literals have the wrong kind (a string for a `float`, a float for an
//!   `int`) or do not fit an `i32` or a finite `f32` (`1e39`: no writer could write an infinity
//!   back) is reported like a count mismatch (OS010): no default.
//! * Array lengths must be positive; `T[]` and `T[-1]` are dynamic; `T[0]` is malformed (OS002).
//! * The shader type must be one of `shader surface displacement volume light` (OS001 if not).
//! * A repeated `%meta` key keeps every entry in the metadata; the typed fields and the vstruct
//!   declaration take the last one.
//! * `%meta{string,options,"a|b"}` is also parsed into the options list, like `.args` options
//!   (`label:value` pairs or plain values).

use crate::diag::{Diagnostic, Diagnostics, Error, Location};
use crate::model::{
    CondSource, Definition, Direction, MemberDecl, Metadata, Property, SourceKind, meta_key,
};
use crate::types::{ArraySpec, BaseType, Type, Value};
use std::collections::HashMap;
use std::sync::Arc;

/// The newest `.oso` format version the reader was tested with (`OpenShadingLanguage 1.00`).
const NEWEST_TESTED_VERSION: (i64, i64) = (1, 0);

/// Shader-line keywords and the `kind` each one is recorded as.
const SHADER_TYPES: [(&str, &str); 5] = [
    ("shader", "pattern"),
    ("surface", "surface"),
    ("displacement", "displacement"),
    ("volume", "volume"),
    ("light", "light"),
];

/// Symbol types that end the property section.
const NON_PROPERTY_SYMTYPES: [&str; 5] = ["local", "temp", "global", "const", "code"];

/// The three `%meta` keys that carry vstruct metadata.
const VSTRUCT_KEYS: [&str; 3] = [
    "vstructmember",
    "vstructConditionalExpr",
    "vstructmemberaliases",
];

/// Parse an `.oso` document.
///
/// `path` names the file in diagnostics and in [`Definition::path`]. Warnings and infos
/// (OS010–OS013) go to `diags`; errors (OS001–OS004) reject the file and are returned with
/// their line and column.
pub fn parse_oso(bytes: &[u8], path: &str, diags: &mut Diagnostics) -> Result<Definition, Error> {
    let text = String::from_utf8_lossy(bytes);
    // A UTF-8 byte-order mark is not part of the header line.
    let text = text.strip_prefix('\u{feff}').unwrap_or(&text);
    Reader {
        lexer: Lexer::new(text),
        path: Arc::from(path),
    }
    .read(diags)
}

// ------------------------------------------------------------------------------------------
// Lexer
// ------------------------------------------------------------------------------------------

/// A 1-based line and column (columns count characters).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct Pos {
    line: u32,
    column: u32,
}

/// One token of a logical line.
#[derive(Debug, Clone)]
struct Token {
    kind: TokenKind,
    pos: Pos,
}

#[derive(Debug, Clone)]
enum TokenKind {
    Ident(String),
    /// A numeric literal: its text and whether it is a float (has `.` or an exponent).
    Number(String, bool),
    /// A decoded string literal.
    Str(String),
    Open,
    Close,
    Hint(Hint),
}

/// A hint such as `%meta{string,label,"Gain"}` or `%initexpr`.
#[derive(Debug, Clone)]
struct Hint {
    name: String,
    /// `None` when the hint has no braces.
    items: Option<Vec<Item>>,
}

/// One item inside a hint's braces.
#[derive(Debug, Clone)]
enum Item {
    Number(String, bool),
    Str(String),
    /// An identifier with an optional array suffix (`string[2]`, `int[]`).
    Ident(String, Option<ArraySpec>),
}

/// Why the lexer stopped.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum LexErrorKind {
    /// A string or hint not closed before the end of its line (OS003).
    Unterminated,
    /// Any other character or literal that does not fit the grammar.
    Malformed,
}

#[derive(Debug)]
struct LexError {
    kind: LexErrorKind,
    message: String,
    pos: Pos,
}

/// A logical line: its tokens (comments and continuations removed).
struct Line {
    tokens: Vec<Token>,
}

/// Reads the tokens of one line in order.
struct Cursor {
    tokens: std::collections::VecDeque<Token>,
    /// Position of the line's last token (for "expected …" at the end of a line).
    last: Pos,
}

impl Cursor {
    /// The tokens of `line` after its first (the symbol type).
    fn after_first(line: Line) -> Self {
        let last = line
            .tokens
            .last()
            .map_or(Pos { line: 1, column: 1 }, |t| t.pos);
        let mut tokens: std::collections::VecDeque<Token> = line.tokens.into();
        tokens.pop_front();
        Cursor { tokens, last }
    }

    fn peek(&self) -> Option<&TokenKind> {
        self.tokens.front().map(|t| &t.kind)
    }

    fn take(&mut self) -> Option<Token> {
        self.tokens.pop_front()
    }

    fn last_pos(&self) -> Pos {
        self.last
    }
}

/// Splits the text into logical lines of tokens.
struct Lexer<'a> {
    src: &'a str,
    bytes: &'a [u8],
    i: usize,
    line: u32,
    line_start: usize,
    /// Set after `%preprocessed_source`: everything that follows is ignored.
    stopped: bool,
    /// The last (offset, 0-based column) computed by [`Lexer::pos_at`].
    column_cache: std::cell::Cell<(usize, usize)>,
}

fn is_ident_start(b: u8) -> bool {
    b.is_ascii_alphabetic() || b == b'_' || b == b'$'
}

fn is_ident_char(b: u8) -> bool {
    b.is_ascii_alphanumeric() || b == b'_' || b == b'$' || b == b'.'
}

fn is_number_start(b: u8) -> bool {
    b.is_ascii_digit() || b == b'+' || b == b'-' || b == b'.'
}

impl<'a> Lexer<'a> {
    fn new(src: &'a str) -> Self {
        Lexer {
            src,
            bytes: src.as_bytes(),
            i: 0,
            line: 1,
            line_start: 0,
            stopped: false,
            column_cache: std::cell::Cell::new((0, 0)),
        }
    }

    /// The position of `offset` on the current line. Columns are counted incrementally from
    /// the last position asked for, so that long lines are not rescanned for every token.
    fn pos_at(&self, offset: usize) -> Pos {
        let (mut from, mut column) = self.column_cache.get();
        if from < self.line_start || from > offset {
            (from, column) = (self.line_start, 0);
        }
        column += self.src.get(from..offset).map_or(0, |s| s.chars().count());
        self.column_cache.set((offset, column));
        Pos {
            line: self.line,
            column: column as u32 + 1,
        }
    }

    fn pos(&self) -> Pos {
        self.pos_at(self.i)
    }

    fn peek(&self) -> Option<u8> {
        self.bytes.get(self.i).copied()
    }

    fn peek_at(&self, k: usize) -> Option<u8> {
        self.bytes.get(self.i + k).copied()
    }

    fn error(&self, kind: LexErrorKind, message: impl Into<String>, pos: Pos) -> LexError {
        LexError {
            kind,
            message: message.into(),
            pos,
        }
    }

    /// Consume a `\n` and start a new physical line.
    fn newline(&mut self) {
        self.i += 1;
        self.line += 1;
        self.line_start = self.i;
    }

    /// Skip spaces, tabs, `\r`, `\v`, `\f` and backslash-newline continuations.
    fn skip_blank(&mut self) {
        while let Some(b) = self.peek() {
            match b {
                b' ' | b'\t' | b'\r' | 0x0b | 0x0c => self.i += 1,
                b'\\' if self.peek_at(1) == Some(b'\n') => {
                    self.i += 1;
                    self.newline();
                }
                b'\\' if self.peek_at(1) == Some(b'\r') && self.peek_at(2) == Some(b'\n') => {
                    self.i += 2;
                    self.newline();
                }
                _ => break,
            }
        }
    }

    /// The next logical line, `None` at the end of the input (or after
    /// `%preprocessed_source`).
    fn next_line(&mut self) -> Option<Result<Line, LexError>> {
        if self.stopped || self.i >= self.bytes.len() {
            return None;
        }
        let mut tokens = Vec::new();
        loop {
            self.skip_blank();
            let Some(b) = self.peek() else { break };
            let pos = self.pos();
            let kind = match b {
                b'\n' => {
                    self.newline();
                    break;
                }
                b'#' => {
                    self.skip_comment();
                    continue;
                }
                b'[' | b']' => {
                    self.i += 1;
                    if b == b'[' {
                        TokenKind::Open
                    } else {
                        TokenKind::Close
                    }
                }
                b'"' => match self.string() {
                    Ok(s) => TokenKind::Str(s),
                    Err(e) => return Some(Err(e)),
                },
                b'%' => match self.hint() {
                    Ok(h) if h.name == "preprocessed_source" => {
                        self.stopped = true;
                        break;
                    }
                    Ok(h) => TokenKind::Hint(h),
                    Err(e) => return Some(Err(e)),
                },
                b if is_ident_start(b) => TokenKind::Ident(self.ident().to_string()),
                b if is_number_start(b) => match self.number() {
                    Ok((text, float)) => TokenKind::Number(text, float),
                    Err(e) => return Some(Err(e)),
                },
                _ => {
                    let c = self.src[self.i..].chars().next().unwrap_or('?');
                    return Some(Err(self.error(
                        LexErrorKind::Malformed,
                        format!("unexpected character `{}`", c.escape_default()),
                        pos,
                    )));
                }
            };
            tokens.push(Token { kind, pos });
        }
        Some(Ok(Line { tokens }))
    }

    /// Skip a `#` comment up to (not including) the newline.
    fn skip_comment(&mut self) {
        while let Some(b) = self.peek() {
            if b == b'\n' {
                break;
            }
            self.i += 1;
        }
    }

    fn ident(&mut self) -> &'a str {
        let start = self.i;
        self.i += 1;
        while self.peek().is_some_and(is_ident_char) {
            self.i += 1;
        }
        &self.src[start..self.i]
    }

    fn digits(&mut self) -> usize {
        let start = self.i;
        while self.peek().is_some_and(|b| b.is_ascii_digit()) {
            self.i += 1;
        }
        self.i - start
    }

    /// `[-+]? (D+ (. D*)? | . D+) ([eE] [-+]? D+)?`; returns the text and whether it is a
    /// float.
    fn number(&mut self) -> Result<(String, bool), LexError> {
        let start = self.i;
        let pos = self.pos();
        if matches!(self.peek(), Some(b'+' | b'-')) {
            self.i += 1;
        }
        let mut n_digits = self.digits();
        let mut float = false;
        if self.peek() == Some(b'.') {
            self.i += 1;
            float = true;
            n_digits += self.digits();
        }
        if n_digits > 0 && matches!(self.peek(), Some(b'e' | b'E')) {
            let sign = usize::from(matches!(self.peek_at(1), Some(b'+' | b'-')));
            if self.peek_at(1 + sign).is_some_and(|b| b.is_ascii_digit()) {
                self.i += 1 + sign;
                self.digits();
                float = true;
            }
        }
        if n_digits == 0 || self.peek().is_some_and(is_ident_char) {
            while self.peek().is_some_and(is_ident_char) {
                self.i += 1;
            }
            let text = &self.src[start..self.i];
            return Err(self.error(
                LexErrorKind::Malformed,
                format!("malformed number `{text}`"),
                pos,
            ));
        }
        Ok((self.src[start..self.i].to_string(), float))
    }

    /// A double-quoted string, decoded. It may not span a line.
    fn string(&mut self) -> Result<String, LexError> {
        let pos = self.pos();
        let start = self.i + 1;
        self.i += 1;
        loop {
            match self.peek() {
                None | Some(b'\n') => {
                    return Err(self.error(LexErrorKind::Unterminated, "unterminated string", pos));
                }
                Some(b'\\') => {
                    if matches!(self.peek_at(1), None | Some(b'\n')) {
                        self.i += 1;
                        continue;
                    }
                    self.i += 2;
                }
                Some(b'"') => break,
                Some(_) => self.i += 1,
            }
        }
        let raw = &self.bytes[start..self.i];
        self.i += 1;
        Ok(unescape(raw))
    }

    /// A hint: `%NAME` optionally followed by `{item, item, …}`.
    fn hint(&mut self) -> Result<Hint, LexError> {
        let pos = self.pos();
        self.i += 1;
        if !self.peek().is_some_and(is_ident_start) {
            return Err(self.error(
                LexErrorKind::Malformed,
                "expected a hint name after `%`",
                pos,
            ));
        }
        let name = self.ident().to_string();
        if self.peek() != Some(b'{') {
            return Ok(Hint { name, items: None });
        }
        self.i += 1;
        let mut items = Vec::new();
        self.skip_blank();
        if self.peek() == Some(b'}') {
            self.i += 1;
            return Ok(Hint {
                name,
                items: Some(items),
            });
        }
        loop {
            self.skip_blank();
            items.push(self.hint_item(pos)?);
            self.skip_blank();
            match self.peek() {
                Some(b',') => self.i += 1,
                Some(b'}') => {
                    self.i += 1;
                    break;
                }
                None | Some(b'\n') => return Err(self.unterminated_hint(&name, pos)),
                Some(_) => {
                    return Err(self.error(
                        LexErrorKind::Malformed,
                        format!("malformed hint `%{name}`: expected `,` or `}}`"),
                        self.pos(),
                    ));
                }
            }
        }
        Ok(Hint {
            name,
            items: Some(items),
        })
    }

    fn unterminated_hint(&self, name: &str, pos: Pos) -> LexError {
        self.error(
            LexErrorKind::Unterminated,
            format!("unterminated hint `%{name}{{`: no closing `}}` on its line"),
            pos,
        )
    }

    /// One hint item: a number, a string, or an identifier with an optional `[N]`/`[]`.
    fn hint_item(&mut self, hint_pos: Pos) -> Result<Item, LexError> {
        match self.peek() {
            Some(b'"') => self.string().map(Item::Str),
            Some(b) if is_ident_start(b) => {
                let word = self.ident().to_string();
                let array = if self.peek() == Some(b'[') {
                    Some(self.item_array_suffix()?)
                } else {
                    None
                };
                Ok(Item::Ident(word, array))
            }
            Some(b) if is_number_start(b) => {
                self.number().map(|(text, float)| Item::Number(text, float))
            }
            None | Some(b'\n') => Err(self.error(
                LexErrorKind::Unterminated,
                "unterminated hint: no closing `}` on its line",
                hint_pos,
            )),
            Some(_) => Err(self.error(
                LexErrorKind::Malformed,
                "malformed hint item: expected a number, a string or a name",
                self.pos(),
            )),
        }
    }

    /// `[N]` or `[]` after an identifier inside a hint (the `[` is next).
    fn item_array_suffix(&mut self) -> Result<ArraySpec, LexError> {
        let pos = self.pos();
        self.i += 1;
        let spec = if self.peek() == Some(b']') {
            ArraySpec::Dynamic
        } else {
            let (text, float) = self.number()?;
            array_spec(&text, float).ok_or_else(|| {
                self.error(
                    LexErrorKind::Malformed,
                    format!("invalid array length `{text}`"),
                    pos,
                )
            })?
        };
        if self.peek() != Some(b']') {
            return Err(self.error(LexErrorKind::Malformed, "expected `]`", self.pos()));
        }
        self.i += 1;
        Ok(spec)
    }
}

/// The array shape for a length literal: `N > 0` fixed, `-1` dynamic, anything else invalid.
#[cfg_attr(feature = "testkit", visibility::make(pub))]
fn array_spec(text: &str, float: bool) -> Option<ArraySpec> {
    if float {
        return None;
    }
    match text.parse::<i64>().ok()? {
        -1 => Some(ArraySpec::Dynamic),
        n if n > 0 => usize::try_from(n).ok().map(ArraySpec::Fixed),
        _ => None,
    }
}

/// Decode C escapes as OSL does: `\n \t \v \b \r \f \a \\ \" \' \?` and 1–3 octal digits.
/// Other escapes are kept verbatim (backslash included).
#[cfg_attr(feature = "testkit", visibility::make(pub))]
fn unescape(raw: &[u8]) -> String {
    let mut out = Vec::with_capacity(raw.len());
    let mut i = 0;
    while i < raw.len() {
        let b = raw[i];
        if b != b'\\' || i + 1 >= raw.len() {
            out.push(b);
            i += 1;
            continue;
        }
        let e = raw[i + 1];
        let simple = match e {
            b'n' => Some(b'\n'),
            b't' => Some(b'\t'),
            b'v' => Some(0x0b),
            b'b' => Some(0x08),
            b'r' => Some(b'\r'),
            b'f' => Some(0x0c),
            b'a' => Some(0x07),
            b'\\' | b'"' | b'\'' | b'?' => Some(e),
            _ => None,
        };
        if let Some(c) = simple {
            out.push(c);
            i += 2;
        } else if (b'0'..=b'7').contains(&e) {
            let mut value: u32 = 0;
            let mut j = i + 1;
            while j < raw.len() && j < i + 4 && (b'0'..=b'7').contains(&raw[j]) {
                value = value * 8 + u32::from(raw[j] - b'0');
                j += 1;
            }
            out.push((value & 0xff) as u8);
            i = j;
        } else {
            out.push(b);
            i += 1;
        }
    }
    String::from_utf8_lossy(&out).into_owned()
}

// ------------------------------------------------------------------------------------------
// Parser
// ------------------------------------------------------------------------------------------

/// Which part of the file is being read; decides the code of lexical errors.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Phase {
    Header,
    Shader,
    Symbols,
}

/// One `param`/`oparam` line, parsed but not yet interpreted.
struct SymbolLine {
    direction: Direction,
    ty: Type,
    declared_type: String,
    name: String,
    name_pos: Pos,
    start: Pos,
    values: Vec<Token>,
    hints: Vec<(Hint, Pos)>,
}

/// A decoded `%meta` entry.
struct Meta {
    name: String,
    /// The TYPE item as written (`string`, `float[2]`).
    type_text: String,
    /// True for the scalar `string` TYPE (required by the vstruct keys).
    is_scalar_string: bool,
    value: Value,
    /// Scalars as their decoded text; arrays joined with `,`.
    text: String,
}

struct Reader<'a> {
    lexer: Lexer<'a>,
    path: Arc<str>,
}

impl Reader<'_> {
    fn loc(&self, pos: Pos) -> Location {
        Location::new(self.path.clone(), pos.line, pos.column)
    }

    fn fail(&self, code: &'static str, message: impl Into<String>, pos: Pos) -> Error {
        Diagnostic::error(code, message).at(self.loc(pos)).into()
    }

    fn read(mut self, diags: &mut Diagnostics) -> Result<Definition, Error> {
        self.read_header(diags)?;
        let mut def = self.read_shader_line(diags)?;
        self.read_properties(&mut def, diags)?;
        Ok(def)
    }

    /// The next line with at least one token; lexical errors become the phase's code.
    fn next_line(&mut self, phase: Phase) -> Result<Option<Line>, Error> {
        while let Some(line) = self.lexer.next_line() {
            match line {
                Ok(line) if line.tokens.is_empty() => continue,
                Ok(line) => return Ok(Some(line)),
                Err(e) => {
                    let code = match (phase, e.kind) {
                        (Phase::Header, _) => "OS001",
                        (_, LexErrorKind::Unterminated) => "OS003",
                        (Phase::Shader, LexErrorKind::Malformed) => "OS001",
                        (Phase::Symbols, LexErrorKind::Malformed) => "OS002",
                    };
                    let message = if phase == Phase::Header {
                        format!(
                            "not an .oso file: expected `OpenShadingLanguage VERSION` ({})",
                            e.message
                        )
                    } else {
                        e.message
                    };
                    return Err(self.fail(code, message, e.pos));
                }
            }
        }
        Ok(None)
    }

    fn end_pos(&self) -> Pos {
        self.lexer.pos()
    }

    /// `OpenShadingLanguage VERSION`; a version newer than the newest tested is OS013.
    fn read_header(&mut self, diags: &mut Diagnostics) -> Result<(), Error> {
        let not_oso = "not an .oso file: expected `OpenShadingLanguage VERSION` as the first line";
        let Some(line) = self.next_line(Phase::Header)? else {
            return Err(self.fail("OS001", not_oso, Pos { line: 1, column: 1 }));
        };
        let toks = &line.tokens;
        let is_magic = matches!(&toks[0].kind, TokenKind::Ident(w) if w == "OpenShadingLanguage");
        if !is_magic {
            return Err(self.fail("OS001", not_oso, toks[0].pos));
        }
        let Some(Token {
            kind: TokenKind::Number(text, _),
            pos,
        }) = toks.get(1)
        else {
            let pos = toks.get(1).map_or(toks[0].pos, |t| t.pos);
            return Err(self.fail("OS001", "missing or malformed .oso version number", pos));
        };
        if let Some(extra) = toks.get(2) {
            return Err(self.fail("OS001", "unexpected text after the .oso version", extra.pos));
        }
        let version: f64 = text.parse().unwrap_or(0.0);
        let major = version.trunc() as i64;
        let minor = (100.0 * (version - version.trunc()) + 0.5) as i64;
        if (major, minor) > NEWEST_TESTED_VERSION {
            diags.push(
                Diagnostic::info(
                    "OS013",
                    format!("`.oso` version {text} is newer than the newest tested (1.00); parsed anyway"),
                )
                .at(self.loc(*pos)),
            );
        }
        Ok(())
    }

    /// `SHADERTYPE NAME hint*` → an empty definition with kind, id and node metadata.
    fn read_shader_line(&mut self, diags: &mut Diagnostics) -> Result<Definition, Error> {
        let Some(line) = self.next_line(Phase::Shader)? else {
            return Err(self.fail(
                "OS001",
                "no shader line (`shader NAME`) after the header",
                self.end_pos(),
            ));
        };
        let toks = &line.tokens;
        let kind = match &toks[0].kind {
            TokenKind::Ident(w) => SHADER_TYPES.iter().find(|(k, _)| k == w).map(|(_, v)| *v),
            _ => None,
        };
        let Some(kind) = kind else {
            return Err(self.fail(
                "OS001",
                "expected a shader line: `shader`, `surface`, `displacement`, `volume` or `light` and a name",
                toks[0].pos,
            ));
        };
        let Some(TokenKind::Ident(id)) = toks.get(1).map(|t| &t.kind) else {
            let pos = toks.get(1).map_or(toks[0].pos, |t| t.pos);
            return Err(self.fail("OS001", "expected the shader name", pos));
        };
        let mut def = Definition {
            id: id.clone(),
            kind: kind.to_string(),
            source: SourceKind::Oso,
            path: self.path.clone(),
            inputs: Vec::new(),
            outputs: Vec::new(),
            metadata: Metadata::new(),
        };
        for tok in &toks[2..] {
            let TokenKind::Hint(hint) = &tok.kind else {
                return Err(self.fail("OS001", "unexpected text on the shader line", tok.pos));
            };
            if let Some(meta) = self.meta(hint, tok.pos, diags) {
                def.metadata.push(meta_key(&meta.name), &meta.text);
            }
        }
        Ok(def)
    }

    /// Every `param`/`oparam` line up to the first line of another symbol type.
    fn read_properties(
        &mut self,
        def: &mut Definition,
        diags: &mut Diagnostics,
    ) -> Result<(), Error> {
        let mut seen: HashMap<String, Pos> = HashMap::new();
        while let Some(line) = self.next_line(Phase::Symbols)? {
            let first = &line.tokens[0];
            let direction = match &first.kind {
                TokenKind::Ident(w) if w == "param" => Direction::In,
                TokenKind::Ident(w) if w == "oparam" => Direction::Out,
                TokenKind::Ident(w) if NON_PROPERTY_SYMTYPES.contains(&w.as_str()) => break,
                _ => {
                    return Err(self.fail(
                        "OS002",
                        "malformed symbol line: expected `param`, `oparam`, `local`, `temp`, `global`, `const` or `code`",
                        first.pos,
                    ));
                }
            };
            let sym = self.symbol_line(line, direction)?;
            if let Some(first) = seen.get(&sym.name) {
                let d =
                    Diagnostic::error("OS004", format!("duplicate property name `{}`", sym.name))
                        .at(self.loc(sym.name_pos))
                        .with_related("first declared here", self.loc(*first));
                return Err(d.into());
            }
            seen.insert(sym.name.clone(), sym.name_pos);
            if sym.name.contains('.') {
                continue; // a struct field: its struct parameter stands for it
            }
            let prop = self.property(sym, diags);
            match prop.direction {
                Direction::In => def.inputs.push(prop),
                Direction::Out => def.outputs.push(prop),
            }
        }
        Ok(())
    }

    /// `SYMTYPE typespec NAME initval* hint*` (the SYMTYPE is `line.tokens[0]`).
    fn symbol_line(&self, line: Line, direction: Direction) -> Result<SymbolLine, Error> {
        let start = line.tokens[0].pos;
        let mut toks = Cursor::after_first(line);
        let (word, word_pos) = self.expect_ident(&mut toks, "a type")?;
        let (base, mut declared_type) = match word.as_str() {
            "closure" => {
                let (inner, pos) = self.expect_ident(&mut toks, "a type after `closure`")?;
                if !is_simple_type(&inner) {
                    return Err(self.fail("OS002", format!("unknown type `{inner}`"), pos));
                }
                (BaseType::Closure, format!("closure {inner}"))
            }
            "struct" => {
                let (name, _) = self.expect_ident(&mut toks, "a struct name")?;
                (
                    BaseType::Struct(Some(name.clone())),
                    format!("struct {name}"),
                )
            }
            w if is_simple_type(w) => (BaseType::from_word(w), w.to_string()),
            w => return Err(self.fail("OS002", format!("unknown type `{w}`"), word_pos)),
        };
        let array = self.array_suffix(&mut toks)?;
        match array {
            ArraySpec::None => {}
            ArraySpec::Fixed(n) => declared_type.push_str(&format!("[{n}]")),
            ArraySpec::Dynamic => declared_type.push_str("[]"),
        }
        let (name, name_pos) = self.expect_ident(&mut toks, "a parameter name")?;
        let mut values = Vec::new();
        let mut hints = Vec::new();
        while let Some(tok) = toks.take() {
            match tok.kind {
                TokenKind::Number(..) | TokenKind::Str(_) if hints.is_empty() => values.push(tok),
                TokenKind::Hint(h) => hints.push((h, tok.pos)),
                _ => {
                    return Err(self.fail(
                        "OS002",
                        "malformed symbol line: expected default values, then hints",
                        tok.pos,
                    ));
                }
            }
        }
        Ok(SymbolLine {
            direction,
            ty: Type { base, array },
            declared_type,
            name,
            name_pos,
            start,
            values,
            hints,
        })
    }

    /// The next token as an identifier, or OS002 naming `what` was expected.
    fn expect_ident(&self, toks: &mut Cursor, what: &str) -> Result<(String, Pos), Error> {
        let end = toks.last_pos();
        match toks.take() {
            Some(Token {
                kind: TokenKind::Ident(w),
                pos,
            }) => Ok((w, pos)),
            other => Err(self.fail(
                "OS002",
                format!("malformed symbol line: expected {what}"),
                other.map_or(end, |t| t.pos),
            )),
        }
    }

    /// An optional `[N]` or `[]` after the type.
    fn array_suffix(&self, toks: &mut Cursor) -> Result<ArraySpec, Error> {
        if !matches!(toks.peek(), Some(TokenKind::Open)) {
            return Ok(ArraySpec::None);
        }
        let end = toks.last_pos();
        toks.take();
        let spec = match toks.take() {
            Some(Token {
                kind: TokenKind::Close,
                ..
            }) => return Ok(ArraySpec::Dynamic),
            Some(Token {
                kind: TokenKind::Number(text, float),
                pos,
            }) => array_spec(&text, float)
                .ok_or_else(|| self.fail("OS002", format!("invalid array length `{text}`"), pos))?,
            other => {
                return Err(self.fail(
                    "OS002",
                    "malformed array type: expected a length or `]`",
                    other.map_or(end, |t| t.pos),
                ));
            }
        };
        match toks.take() {
            Some(Token {
                kind: TokenKind::Close,
                ..
            }) => Ok(spec),
            other => Err(self.fail(
                "OS002",
                "malformed array type: expected `]`",
                other.map_or(toks.last_pos(), |t| t.pos),
            )),
        }
    }

    /// Interpret a parsed symbol line: default, `%meta` entries, vstruct declaration.
    fn property(&self, sym: SymbolLine, diags: &mut Diagnostics) -> Property {
        let mut prop = Property::new(
            sym.name.clone(),
            sym.direction,
            sym.ty.clone(),
            self.loc(sym.start),
        );
        prop.declared_type = sym.declared_type.clone();
        let has_initexpr = sym.hints.iter().any(|(h, _)| h.name == "initexpr");
        if !has_initexpr {
            prop.default = self.default_value(&sym, diags);
        }
        let mut vstruct: HashMap<&'static str, (String, Pos)> = HashMap::new();
        for (hint, pos) in &sym.hints {
            let Some(meta) = self.meta(hint, *pos, diags) else {
                continue;
            };
            if let Some(key) = VSTRUCT_KEYS.iter().find(|k| **k == meta.name) {
                if !meta.is_scalar_string {
                    diags.push(
                        Diagnostic::warning(
                            "OS012",
                            format!(
                                "`%meta` `{key}` has type `{}`, not `string`; ignored",
                                meta.type_text
                            ),
                        )
                        .at(self.loc(*pos)),
                    );
                    continue;
                }
                vstruct.insert(key, (meta.text.clone(), *pos));
            }
            apply_meta(&mut prop, meta);
        }
        prop.vstruct = self.member_decl(&vstruct);
        prop
    }

    /// The vstruct member declaration, if `vstructmember` splits into a non-empty head and
    /// member; otherwise the raw entries stay only in the metadata.
    fn member_decl(&self, keys: &HashMap<&'static str, (String, Pos)>) -> Option<MemberDecl> {
        let (value, _) = keys.get("vstructmember")?;
        let (head, member) = value.split_once('.')?;
        if head.is_empty() || member.is_empty() {
            return None;
        }
        let non_empty = |k: &str| keys.get(k).filter(|(v, _)| !v.is_empty());
        Some(MemberDecl {
            head: head.to_string(),
            member: member.to_string(),
            alias: non_empty("vstructmemberaliases").map(|(v, _)| v.clone()),
            cond: non_empty("vstructConditionalExpr").map(|(v, pos)| CondSource {
                text: v.clone(),
                location: self.loc(*pos),
            }),
        })
    }

    /// The typed default from the initial values, or `None` with OS010 when they do not fit.
    fn default_value(&self, sym: &SymbolLine, diags: &mut Diagnostics) -> Option<Value> {
        let base = &sym.ty.base;
        let comps = base.components();
        if comps == 0 {
            return None; // struct and closure parameters have no default
        }
        let count = sym.values.len();
        let expected = match sym.ty.array {
            ArraySpec::None => comps,
            // Saturating: a declared length near usize::MAX must not overflow (it simply never matches).
            ArraySpec::Fixed(n) => comps.saturating_mul(n),
            ArraySpec::Dynamic if count.is_multiple_of(comps) => count,
            ArraySpec::Dynamic => count.next_multiple_of(comps),
        };
        let pos = sym.values.first().map_or(sym.name_pos, |t| t.pos);
        let warn = |diags: &mut Diagnostics, why: String| {
            diags.push(
                Diagnostic::warning(
                    "OS010",
                    format!("default of `{}` ({}): {why}; no default", sym.name, sym.ty),
                )
                .at(self.loc(pos)),
            );
        };
        if count != expected {
            warn(diags, format!("{count} values given, {expected} expected"));
            return None;
        }
        let scalars: Result<Vec<Value>, String> = sym
            .values
            .iter()
            .map(|t| scalar_literal(base, &t.kind))
            .collect();
        let scalars = match scalars {
            Ok(s) => s,
            Err(why) => {
                warn(diags, why);
                return None;
            }
        };
        let elements: Vec<Value> = scalars.chunks(comps).map(|c| element(base, c)).collect();
        match sym.ty.array {
            ArraySpec::None => elements.into_iter().next(),
            _ => Some(Value::Array(base.clone(), elements)),
        }
    }

    /// Decode a `%meta{TYPE,NAME,VALUE…}` hint; other hints and bad entries give `None`
    /// (bad entries with OS011).
    fn meta(&self, hint: &Hint, pos: Pos, diags: &mut Diagnostics) -> Option<Meta> {
        if hint.name != "meta" {
            return None;
        }
        match decode_meta(hint) {
            Ok(meta) => Some(meta),
            Err(why) => {
                diags.push(
                    Diagnostic::warning("OS011", format!("`%meta` entry ignored: {why}"))
                        .at(self.loc(pos)),
                );
                None
            }
        }
    }
}

fn is_simple_type(word: &str) -> bool {
    matches!(
        word,
        "int" | "float" | "string" | "color" | "point" | "vector" | "normal" | "matrix"
    )
}

/// One default literal as a scalar of the element type's component kind.
fn scalar_literal(base: &BaseType, tok: &TokenKind) -> Result<Value, String> {
    match (base, tok) {
        (BaseType::Int, TokenKind::Number(text, false)) => text
            .parse::<i32>()
            .map(Value::Int)
            .map_err(|_| format!("`{text}` does not fit an int")),
        (BaseType::String, TokenKind::Str(s)) => Ok(Value::Str(s.clone())),
        (b, TokenKind::Number(text, _)) if b.is_numeric() && *b != BaseType::Int => text
            .parse::<f32>()
            .ok()
            .filter(|x| x.is_finite())
            .map(Value::Float)
            .ok_or_else(|| format!("`{text}` is not a finite float")),
        (_, TokenKind::Number(text, _)) => Err(format!("value `{text}` has the wrong kind")),
        (_, TokenKind::Str(s)) => Err(format!("value {s:?} has the wrong kind")),
        _ => Err(String::from("unexpected default token")),
    }
}

/// Group one element's scalar components into its value.
fn element(base: &BaseType, comps: &[Value]) -> Value {
    let floats: Vec<f32> = comps.iter().flat_map(Value::numbers).collect();
    match base {
        b if b.is_triple() => Value::Triple(b.clone(), [floats[0], floats[1], floats[2]]),
        BaseType::Matrix => {
            let mut m = [0.0; 16];
            m.copy_from_slice(&floats[..16]);
            Value::Matrix(m)
        }
        _ => comps[0].clone(),
    }
}

/// Decode the items of a `%meta` hint.
fn decode_meta(hint: &Hint) -> Result<Meta, String> {
    let items = hint.items.as_deref().unwrap_or(&[]);
    let (Some(Item::Ident(type_word, array)), Some(Item::Ident(name, None))) =
        (items.first(), items.get(1))
    else {
        return Err(String::from("expected `%meta{TYPE,NAME,VALUE…}`"));
    };
    let base = match type_word.as_str() {
        "int" => BaseType::Int,
        "float" => BaseType::Float,
        "string" => BaseType::String,
        _ => return Err(format!("unknown TYPE `{type_word}`")),
    };
    let type_text = match array {
        None => type_word.clone(),
        Some(ArraySpec::Fixed(n)) => format!("{type_word}[{n}]"),
        Some(_) => format!("{type_word}[]"),
    };
    let raw = &items[2..];
    if raw.is_empty() {
        return Err(format!("`{name}` has no value"));
    }
    if array.is_none() && raw.len() > 1 {
        return Err(format!(
            "scalar `{type_text}` `{name}` has {} values",
            raw.len()
        ));
    }
    let mut values = Vec::with_capacity(raw.len());
    let mut texts = Vec::with_capacity(raw.len());
    for item in raw {
        let (value, text) = meta_value(&base, item)
            .ok_or_else(|| format!("a value of `{name}` is not a `{type_word}`"))?;
        values.push(value);
        texts.push(text);
    }
    let value = match array {
        None => values.remove(0),
        Some(_) => Value::Array(base.clone(), values),
    };
    Ok(Meta {
        name: name.clone(),
        is_scalar_string: base == BaseType::String && array.is_none(),
        type_text,
        value,
        text: texts.join(","),
    })
}

/// One `%meta` value and its text; `None` if it does not match the TYPE.
fn meta_value(base: &BaseType, item: &Item) -> Option<(Value, String)> {
    match (base, item) {
        (BaseType::Int, Item::Number(t, false)) => Some((Value::Int(t.parse().ok()?), t.clone())),
        (BaseType::Float, Item::Number(t, _)) => Some((Value::Float(t.parse().ok()?), t.clone())),
        (BaseType::String, Item::Str(s)) => Some((Value::Str(s.clone()), s.clone())),
        _ => None,
    }
}

/// Store a `%meta` entry and fill the typed fields it drives.
fn apply_meta(prop: &mut Property, meta: Meta) {
    match meta.name.as_str() {
        "tag" => prop.connection_types.extend(string_values(&meta.value)),
        "connectable" if prop.direction == Direction::In => prop.connectable = truthy(&meta.value),
        "widget" => prop.widget = Some(meta.text.clone()),
        "label" => prop.label = Some(meta.text.clone()),
        "help" => prop.help = Some(meta.text.clone()),
        "page" => prop.page = Some(meta.text.replace('.', ":")),
        "options" if matches!(meta.value, Value::Str(_)) => {
            prop.options = parse_options(&meta.text)
        }
        _ => {}
    }
    prop.metadata.push(meta_key(&meta.name), &meta.text);
    prop.typed_metadata.push((meta.name, meta.value));
}

/// The strings of a string value or string array (numbers as text).
fn string_values(value: &Value) -> Vec<String> {
    match value {
        Value::Array(_, items) => items.iter().flat_map(string_values).collect(),
        Value::Str(s) => vec![s.clone()],
        other => vec![other.to_string()],
    }
}

/// Boolean reading of a `connectable` value: non-zero numbers are true; strings are true
/// unless `0`, `false` or `f` (any case), as for `.args` attributes.
fn truthy(value: &Value) -> bool {
    match value {
        Value::Int(i) => *i != 0,
        Value::Float(x) => *x != 0.0,
        Value::Str(s) => !matches!(s.to_ascii_lowercase().as_str(), "0" | "false" | "f"),
        Value::Array(_, items) => items.first().is_none_or(truthy),
        _ => true,
    }
}

/// `a|b|c` or `Label:value|…` → `(label, value)` pairs (label = value for plain values).
#[cfg_attr(feature = "testkit", visibility::make(pub))]
fn parse_options(text: &str) -> Vec<(String, String)> {
    text.split('|')
        .filter(|s| !s.is_empty())
        .map(|s| match s.split_once(':') {
            Some((label, value)) => (label.to_string(), value.to_string()),
            None => (s.to_string(), s.to_string()),
        })
        .collect()
}

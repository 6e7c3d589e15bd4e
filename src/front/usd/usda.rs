//! usda text lexed as Pixar's USD lexes it, rewritten into the form `openusd` reads word
//! for word.
//!
//! `openusd`'s text reader keeps the characters between a string's quotes as they stand,
//! where Pixar's USD decodes backslash escapes (`"tab\there"` holds a TAB); it knows
//! neither the legacy type names (`PointFloat[]`), nor the `config` variability, nor `//`
//! comments, all of which Pixar's USD still reads. [`normalise`] lexes the text the way
//! Pixar's USD does, decodes each string and asset path that needs it and writes the
//! decoded value back in a quoting `openusd` reads as that value; a legacy type name
//! becomes the name Pixar's USD reads it as, `config` becomes `uniform` (Pixar's USD
//! reads it so), and `//` becomes `#/`. Everything else is copied byte for byte, so a
//! position in the rewritten text maps back to the original one
//! ([`Normalised::original_offset`]).
//!
//! A value no quoting carries through `openusd` (one holding both `"""` and `'''`, say), or
//! one that begins as an encoded value does, is written as an encoded value instead: the
//! hex digits of its UTF-8 bytes between [`ENCODED_OPEN`] and [`ENCODED_CLOSE`], which
//! [`decoded`] turns back into the value wherever the reader takes a string from `openusd`.
//!
//! Pixar's escapes (those of `TfEscapeString`): `\a \b \f \n \r \t \v`, `\\`, `\x` with up
//! to two hex digits, `\0`–`\7` starting up to three octal digits; a backslash before any
//! other character stands for that character (`\'` is `'`, `\q` is `q`). A string in
//! single quotes ends at its line; one in triple quotes may span lines. Asset paths
//! between single `@` are raw; between `@@@` only `\@@@` is an escape.

use std::borrow::Cow;
use std::ops::Range;

/// Legacy type names Pixar's USD still reads, and the names it reads them as.
const LEGACY_TYPES: [(&str, &str); 28] = [
    ("Color", "color3d"),
    ("ColorFloat", "color3f"),
    ("Frame", "frame4d"),
    ("Matrix2d", "matrix2d"),
    ("Matrix3d", "matrix3d"),
    ("Matrix4d", "matrix4d"),
    ("Normal", "normal3d"),
    ("NormalFloat", "normal3f"),
    ("Point", "point3d"),
    ("PointFloat", "point3f"),
    ("Quatd", "quatd"),
    ("Quatf", "quatf"),
    ("Quath", "quath"),
    ("Transform", "matrix4d"),
    ("Vec2d", "double2"),
    ("Vec2f", "float2"),
    ("Vec2h", "half2"),
    ("Vec2i", "int2"),
    ("Vec3d", "double3"),
    ("Vec3f", "float3"),
    ("Vec3h", "half3"),
    ("Vec3i", "int3"),
    ("Vec4d", "double4"),
    ("Vec4f", "float4"),
    ("Vec4h", "half4"),
    ("Vec4i", "int4"),
    ("Vector", "vector3d"),
    ("VectorFloat", "vector3f"),
];

/// Opens an encoded value: two private-use characters no USD text holds in practice.
pub(crate) const ENCODED_OPEN: &str = "\u{F8FF}\u{F8FE}";
/// Closes an encoded value.
pub(crate) const ENCODED_CLOSE: &str = "\u{F8FE}\u{F8FF}";

/// `value` encoded for `openusd`: the hex digits of its bytes between the two marks.
fn encoded(value: &str) -> String {
    let mut out = String::with_capacity(ENCODED_OPEN.len() * 2 + value.len() * 2);
    out.push_str(ENCODED_OPEN);
    for b in value.bytes() {
        out.push(char::from_digit(u32::from(b >> 4), 16).unwrap_or('0'));
        out.push(char::from_digit(u32::from(b & 15), 16).unwrap_or('0'));
    }
    out.push_str(ENCODED_CLOSE);
    out
}

/// The value `s` stands for: the decoded value when `s` is an encoded one ([`encoded`]),
/// else `s` itself.
pub(crate) fn decoded(s: &str) -> Cow<'_, str> {
    let Some(hex) = s
        .strip_prefix(ENCODED_OPEN)
        .and_then(|r| r.strip_suffix(ENCODED_CLOSE))
    else {
        return Cow::Borrowed(s);
    };
    let digits = hex.as_bytes();
    if digits.len() % 2 != 0 || !digits.iter().all(u8::is_ascii_hexdigit) {
        return Cow::Borrowed(s);
    }
    let bytes = digits
        .chunks(2)
        .map(|d| u8::from_str_radix(std::str::from_utf8(d).unwrap_or("0"), 16).unwrap_or(0))
        .collect();
    match String::from_utf8(bytes) {
        Ok(value) => Cow::Owned(value),
        Err(_) => Cow::Borrowed(s),
    }
}

/// Text Pixar's USD would not lex: where and why.
#[derive(Debug)]
pub(crate) struct SyntaxError {
    /// Byte offset in the original text.
    pub offset: usize,
    /// What is wrong there.
    pub message: String,
}

/// One rewritten span: `from` in the original text became `to` in the rewritten one.
#[derive(Debug)]
struct Edit {
    from: Range<usize>,
    to: Range<usize>,
}

/// usda text in the form `openusd` reads as Pixar's USD reads the original.
#[derive(Debug)]
pub(crate) struct Normalised<'a> {
    /// The rewritten text (the original when nothing needed rewriting).
    pub text: Cow<'a, [u8]>,
    /// How many values went in encoded ([`decoded`] gives them back).
    pub encoded: usize,
    edits: Vec<Edit>,
}

impl Normalised<'_> {
    /// The offset in the original text of offset `at` of the rewritten one (the start of
    /// the rewritten token it falls in).
    pub fn original_offset(&self, at: usize) -> usize {
        let i = self.edits.partition_point(|e| e.to.start <= at);
        match i.checked_sub(1).map(|i| &self.edits[i]) {
            None => at,
            Some(e) if at < e.to.end => e.from.start,
            Some(e) => e.from.end + (at - e.to.end),
        }
    }
}

/// `text` rewritten so that `openusd` reads in it what Pixar's USD reads in `text`.
pub(crate) fn normalise(text: &[u8]) -> Result<Normalised<'_>, SyntaxError> {
    let mut w = Rewriter {
        src: text,
        out: Vec::new(),
        copied: 0,
        edits: Vec::new(),
        encoded: 0,
    };
    let mut i = 0;
    while i < text.len() {
        i = match text[i] {
            b'#' => line_end(text, i),
            b'/' if text.get(i + 1) == Some(&b'*') => block_comment_end(text, i)?,
            b'/' if text.get(i + 1) == Some(&b'/') => {
                w.replace(i..i + 2, b"#/".to_vec());
                line_end(text, i)
            }
            b'"' | b'\'' => w.string(i)?,
            b'@' => w.asset(i)?,
            b'<' => path_end(text, i),
            b if b.is_ascii_alphabetic() || b == b'_' => w.word(i),
            b if b.is_ascii_digit() => word_end(text, i),
            _ => i + 1,
        };
    }
    Ok(w.finish())
}

/// The rewritten text, built lazily: nothing is copied until the first edit.
struct Rewriter<'a> {
    src: &'a [u8],
    out: Vec<u8>,
    /// How far `src` has been copied into `out`.
    copied: usize,
    edits: Vec<Edit>,
    encoded: usize,
}

impl<'a> Rewriter<'a> {
    fn replace(&mut self, from: Range<usize>, with: Vec<u8>) {
        if self.edits.is_empty() {
            self.out.reserve(self.src.len() + 64);
        }
        self.out
            .extend_from_slice(&self.src[self.copied..from.start]);
        let start = self.out.len();
        self.out.extend_from_slice(&with);
        self.edits.push(Edit {
            to: start..self.out.len(),
            from: from.clone(),
        });
        self.copied = from.end;
    }

    fn finish(mut self) -> Normalised<'a> {
        if self.edits.is_empty() {
            return Normalised {
                text: Cow::Borrowed(self.src),
                encoded: 0,
                edits: Vec::new(),
            };
        }
        self.out.extend_from_slice(&self.src[self.copied..]);
        Normalised {
            text: Cow::Owned(self.out),
            encoded: self.encoded,
            edits: self.edits,
        }
    }

    /// The string token at `start`; returns its end.
    fn string(&mut self, start: usize) -> Result<usize, SyntaxError> {
        let src = self.src;
        let q = src[start];
        let triple = src[start..].starts_with(&[q, q, q]);
        let (content, end) = if triple {
            triple_string(src, start)?
        } else {
            line_string(src, start)?
        };
        let raw = &src[content.clone()];
        if !raw.contains(&b'\\') && !raw.starts_with(ENCODED_OPEN.as_bytes()) {
            return Ok(end);
        }
        let value = unescape(raw);
        let quoted = match quoted_for_openusd(&value) {
            Some(q) if !value.starts_with(ENCODED_OPEN) => q,
            _ => {
                self.encoded += 1;
                format!("\"{}\"", encoded(&value))
            }
        };
        self.replace(start..end, quoted.into_bytes());
        Ok(end)
    }

    /// The asset path at `start`; returns its end.
    fn asset(&mut self, start: usize) -> Result<usize, SyntaxError> {
        let src = self.src;
        let triple = src[start..].starts_with(b"@@@");
        let (value, end) = if triple {
            triple_asset(src, start)?
        } else {
            line_asset(src, start)?
        };
        // `openusd` reads a path between single `@` as Pixar's USD does, and one between
        // `@@@` too unless it holds an escape or ends in `@`.
        let same = !triple || !(src[start..end].contains(&b'\\') || value.ends_with('@'));
        if same && !value.starts_with(ENCODED_OPEN) {
            return Ok(end);
        }
        let quoted = if value.starts_with(ENCODED_OPEN) {
            None
        } else if !value.contains('@') {
            Some(format!("@{value}@"))
        } else if !value.contains("@@@") && !value.ends_with('@') {
            Some(format!("@@@{value}@@@"))
        } else {
            None
        };
        let quoted = quoted.unwrap_or_else(|| {
            self.encoded += 1;
            format!("@{}@", encoded(&value))
        });
        self.replace(start..end, quoted.into_bytes());
        Ok(end)
    }

    /// The word at `start`: a legacy type name or `config` before a name is rewritten.
    fn word(&mut self, start: usize) -> usize {
        let end = word_end(self.src, start);
        let word = &self.src[start..end];
        let renamed = if word == b"config" {
            before_word(self.src, end).then_some("uniform")
        } else {
            LEGACY_TYPES
                .iter()
                .find(|(old, _)| old.as_bytes() == word)
                .filter(|_| before_name(self.src, end))
                .map(|(_, new)| *new)
        };
        if let Some(new) = renamed {
            self.replace(start..end, new.as_bytes().to_vec());
        }
        end
    }
}

fn line_end(src: &[u8], at: usize) -> usize {
    memchr::memchr(b'\n', &src[at..]).map_or(src.len(), |n| at + n)
}

fn block_comment_end(src: &[u8], at: usize) -> Result<usize, SyntaxError> {
    memchr::memmem::find(&src[at + 2..], b"*/")
        .map(|n| at + 2 + n + 2)
        .ok_or_else(|| SyntaxError {
            offset: at,
            message: "a `/*` comment is not closed".to_string(),
        })
}

/// The end of a path reference `<...>` (or just past `<` when it closes on no line).
fn path_end(src: &[u8], at: usize) -> usize {
    match memchr::memchr2(b'>', b'\n', &src[at + 1..]) {
        Some(n) if src[at + 1 + n] == b'>' => at + n + 2,
        _ => at + 1,
    }
}

fn is_word_byte(b: u8) -> bool {
    b.is_ascii_alphanumeric() || b == b'_' || b == b':'
}

fn word_end(src: &[u8], at: usize) -> usize {
    src[at..]
        .iter()
        .position(|&b| !is_word_byte(b))
        .map_or(src.len(), |n| at + n)
}

fn skip_blanks(src: &[u8], mut at: usize) -> usize {
    while src.get(at).is_some_and(|b| b.is_ascii_whitespace()) {
        at += 1;
    }
    at
}

/// Whether a word follows `at` after blanks: `config` is a variability only before a type.
fn before_word(src: &[u8], at: usize) -> bool {
    let next = skip_blanks(src, at);
    next > at
        && src
            .get(next)
            .is_some_and(|b| b.is_ascii_alphabetic() || *b == b'_')
}

/// Whether an attribute name follows `at` (after an optional `[]`): the word before it is
/// then a type name, not a prim type or a value.
fn before_name(src: &[u8], at: usize) -> bool {
    let open = skip_blanks(src, at);
    if src.get(open) != Some(&b'[') {
        return before_word(src, at);
    }
    let close = skip_blanks(src, open + 1);
    src.get(close) == Some(&b']') && before_word(src, close + 1)
}

/// A string in single quotes (`"` or `'`) at `start`: its content and its end. A backslash
/// takes the next character with it; the line must not end first.
fn line_string(src: &[u8], start: usize) -> Result<(Range<usize>, usize), SyntaxError> {
    let q = src[start];
    let mut i = start + 1;
    while let Some(&b) = src.get(i) {
        match b {
            b'\\' if src.get(i + 1).is_some_and(|&n| n != b'\n') => i += 2,
            b'\n' | b'\\' => break,
            b if b == q => return Ok((start + 1..i, i + 1)),
            _ => i += 1,
        }
    }
    Err(SyntaxError {
        offset: start,
        message: "a quoted string is not closed on its line".to_string(),
    })
}

/// A string in triple quotes at `start`: its content and its end.
fn triple_string(src: &[u8], start: usize) -> Result<(Range<usize>, usize), SyntaxError> {
    let q = src[start];
    let mut i = start + 3;
    while i < src.len() {
        if src[i] == b'\\' {
            i += 2;
        } else if src[i..].starts_with(&[q, q, q]) {
            return Ok((start + 3..i, i + 3));
        } else {
            i += 1;
        }
    }
    Err(SyntaxError {
        offset: start,
        message: "a triple-quoted string is not closed".to_string(),
    })
}

/// An asset path between single `@` at `start`: its value (raw) and its end.
fn line_asset(src: &[u8], start: usize) -> Result<(String, usize), SyntaxError> {
    match memchr::memchr2(b'@', b'\n', &src[start + 1..]) {
        Some(n) if src[start + 1 + n] == b'@' => Ok((
            String::from_utf8_lossy(&src[start + 1..start + 1 + n]).into_owned(),
            start + n + 2,
        )),
        _ => Err(SyntaxError {
            offset: start,
            message: "an asset path is not closed by `@` on its line".to_string(),
        }),
    }
}

/// An asset path between `@@@` at `start`: its value and its end. It closes at the last
/// `@` of the first run of three or more not escaped by a backslash.
fn triple_asset(src: &[u8], start: usize) -> Result<(String, usize), SyntaxError> {
    let mut value = Vec::new();
    let mut i = start + 3;
    while i < src.len() && src[i] != b'\n' {
        if src[i..].starts_with(b"\\@@@") {
            value.extend_from_slice(b"@@@");
            i += 4;
        } else if src[i..].starts_with(b"@@@") && src.get(i + 3) != Some(&b'@') {
            return Ok((String::from_utf8_lossy(&value).into_owned(), i + 3));
        } else {
            value.push(src[i]);
            i += 1;
        }
    }
    Err(SyntaxError {
        offset: start,
        message: "an asset path is not closed by `@@@` on its line".to_string(),
    })
}

/// The value Pixar's USD reads in string content `raw` (its escapes decoded). Bytes that
/// decode to no UTF-8 text become U+FFFD: a Rust string holds UTF-8 only.
pub(crate) fn unescape(raw: &[u8]) -> String {
    let mut out = Vec::with_capacity(raw.len());
    let mut i = 0;
    while i < raw.len() {
        if raw[i] != b'\\' || i + 1 == raw.len() {
            out.push(raw[i]);
            i += 1;
            continue;
        }
        let c = raw[i + 1];
        i += 2;
        let simple = match c {
            b'a' => Some(0x07),
            b'b' => Some(0x08),
            b'f' => Some(0x0c),
            b'n' => Some(b'\n'),
            b'r' => Some(b'\r'),
            b't' => Some(b'\t'),
            b'v' => Some(0x0b),
            b'x' | b'0'..=b'7' => None,
            other => Some(other),
        };
        if let Some(b) = simple {
            out.push(b);
            continue;
        }
        let (radix, first, max) = if c == b'x' { (16, i, 2) } else { (8, i - 1, 3) };
        let digits = raw[first..]
            .iter()
            .take(max)
            .take_while(|d| (**d as char).is_digit(radix))
            .count();
        let code = raw[first..first + digits].iter().fold(0u32, |n, d| {
            n * radix + (*d as char).to_digit(radix).unwrap_or(0)
        });
        out.push(code as u8);
        i = first + digits;
    }
    match String::from_utf8(out) {
        Ok(s) => s,
        Err(e) => String::from_utf8_lossy(e.as_bytes()).into_owned(),
    }
}

/// `value` quoted so that `openusd`'s reader, which keeps what stands between the quotes,
/// reads exactly `value`; nothing when no quoting can carry it.
pub(crate) fn quoted_for_openusd(value: &str) -> Option<String> {
    for q in ['"', '\''] {
        if single_quotes_carry(value, q) {
            return Some(format!("{q}{value}{q}"));
        }
    }
    for q in ["\"\"\"", "'''"] {
        let last = q.as_bytes()[0] as char;
        if !value.contains(q) && !value.ends_with(last) {
            return Some(format!("{q}{value}{q}"));
        }
    }
    None
}

/// Whether `"value"` (with `q` for `"`) is one whole string to `openusd`: no bare `q`, and
/// every backslash followed by a character other than a line end.
fn single_quotes_carry(value: &str, q: char) -> bool {
    let mut chars = value.chars();
    while let Some(c) = chars.next() {
        if c == q {
            return false;
        }
        if c == '\\' && !matches!(chars.next(), Some(n) if n != '\n') {
            return false;
        }
    }
    true
}

/// The byte offset in `text` of line `line`, column `column` (both from 1, the column
/// counted in characters), as `openusd` reports a parse error's place.
pub(crate) fn offset_of(text: &str, line: usize, column: usize) -> usize {
    let start = text
        .split_inclusive('\n')
        .take(line.saturating_sub(1))
        .map(str::len)
        .sum::<usize>();
    let rest = &text[start.min(text.len())..];
    start
        + rest
            .char_indices()
            .nth(column.saturating_sub(1))
            .map_or(rest.len(), |(i, _)| i)
}

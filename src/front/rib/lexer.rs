//! RIB tokenizer: byte spans, lines and columns, no copies.
//!
//! Tokens are produced one at a time; the parser keeps only the tokens of the shading request
//! it is reading, so pass-through requests (geometry with millions of numbers) cost no memory.
//! String contents are decoded on demand ([`decode_string`], `decode_str`). Short plain
//! strings (ASCII, no escape, no line break) and runs of digits are scanned eight bytes at a
//! time in a `u64` (one portable version, as fast here as the vector one it replaced);
//! comments and other strings are scanned with `memchr`. The usual array (one line, only numbers or only plain strings)
//! is read in one pass ([`Lexer::flat_array`]). A column is computed when a token starts, from
//! the offset of its line's start and the UTF-8 continuation bytes since (which only strings
//! and comments can hold), so only line breaks cost anything to track.

use crate::diag::{Diagnostic, Diagnostics, Error, Location};
use std::borrow::Cow;
use std::sync::Arc;

/// What a token is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "testkit", visibility::make(pub))]
pub(crate) enum TokKind {
    /// `[A-Za-z_][A-Za-z0-9_]*`: a request name.
    Ident,
    /// A number (integer or float syntax).
    Number,
    /// A double- or single-quoted string (quotes included in the span).
    Str,
    /// `[`
    Open,
    /// `]`
    Close,
    /// `#` to the end of the line (newline excluded).
    Comment,
}

/// One token: kind, byte span, position of its first character, and the line it ends on.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "testkit", visibility::make(pub))]
pub(crate) struct Token {
    /// What the token is.
    pub kind: TokKind,
    /// Byte offset of its first byte.
    pub start: usize,
    /// Byte offset past its last byte.
    pub end: usize,
    /// Line of its first character (from 1).
    pub line: u32,
    /// Column of its first character (from 1).
    pub col: u32,
    /// Line of its last character.
    pub end_line: u32,
    /// For strings: true if the content contains a backslash (needs decoding).
    pub escaped: bool,
}

/// The length of the RIB number at the start of `i`:
/// `[+-]?([0-9]+(\.[0-9]*)?|\.[0-9]+)([eE][+-]?[0-9]+)?`, or `None` if `i` does not start
/// with one.
#[inline]
fn number(i: &[u8]) -> Option<usize> {
    let digits = |n: usize| digits_end(i, n);
    let mut n = usize::from(matches!(i.first(), Some(b'+' | b'-')));
    let int_end = digits(n);
    let int = int_end - n;
    n = int_end;
    if i.get(n) == Some(&b'.') {
        let frac_end = digits(n + 1);
        if int == 0 && frac_end == n + 1 {
            return None;
        }
        n = frac_end;
    } else if int == 0 {
        return None;
    }
    // An exponent only when digits follow it (`1e` is the number `1` then an identifier).
    if matches!(i.get(n), Some(b'e' | b'E')) {
        let from = n + 1 + usize::from(matches!(i.get(n + 1), Some(b'+' | b'-')));
        let exp_end = digits(from);
        if exp_end > from {
            n = exp_end;
        }
    }
    Some(n)
}

/// The end of the run of ASCII digits in `i` from `n` on, looked at eight bytes at a time
/// (numbers in scenes are mostly several digits long).
#[inline]
fn digits_end(i: &[u8], mut n: usize) -> usize {
    const LOW7: u64 = 0x7f7f_7f7f_7f7f_7f7f;
    while let Some(chunk) = i.get(n..n + 8) {
        let w = u64::from_le_bytes(chunk.try_into().unwrap_or_default());
        // A digit `d` gives `x = d ^ 0x30` below 10: adding 0x76 to its low seven bits
        // leaves the high bit clear. Any other byte sets it (in `x` itself from 0x80 on).
        // No carry crosses bytes, so every flagged byte is a non-digit.
        let x = w ^ 0x3030_3030_3030_3030;
        let stop = ((x & LOW7).wrapping_add(0x7676_7676_7676_7676) | x) & !LOW7;
        if stop != 0 {
            return n + (stop.trailing_zeros() / 8) as usize;
        }
        n += 8;
    }
    while i.get(n).is_some_and(u8::is_ascii_digit) {
        n += 1;
    }
    n
}

/// The number of UTF-8 continuation bytes in `s` (bytes that start no character).
fn continuations(s: &[u8]) -> usize {
    s.iter().filter(|&&b| b & 0xC0 == 0x80).count()
}

/// True for the RIB whitespace bytes: space, `\t`, `\r`, `\n`, `\f`, `\v`.
#[inline]
pub(crate) fn is_space(b: u8) -> bool {
    CLASS[usize::from(b)] & SPACE != 0
}

/// [`CLASS`] bit: RIB whitespace.
const SPACE: u8 = 1;
/// [`CLASS`] bit: a byte of an identifier (`[A-Za-z0-9_]`).
const WORD: u8 = 2;

/// The class bits of each byte value (one table look-up per byte in the scanning loops).
static CLASS: [u8; 256] = {
    let mut t = [0u8; 256];
    let mut b = 0;
    while b < 256 {
        let c = b as u8;
        if matches!(c, b' ' | b'\t' | b'\r' | b'\n' | 0x0c | 0x0b) {
            t[b] = SPACE;
        }
        if c.is_ascii_alphanumeric() || c == b'_' {
            t[b] = WORD;
        }
        b += 1;
    }
    t
};

/// The tokenizer state: position and line of the next byte, and what its column (in
/// characters) is computed from. Only line breaks and the rare non-ASCII text inside strings
/// and comments update the column's parts; the bytes between them cost nothing.
#[cfg_attr(feature = "testkit", visibility::make(pub))]
pub(crate) struct Lexer<'a> {
    src: &'a [u8],
    pos: usize,
    line: u32,
    /// The offset of the first byte of the current line.
    line_start: usize,
    /// UTF-8 continuation bytes between `line_start` and `pos` (they start no character).
    continuations: usize,
    file: Arc<str>,
    strict: bool,
}

impl<'a> Lexer<'a> {
    /// A tokenizer over `src`; `strict` makes single-quoted strings an error.
    pub fn new(src: &'a [u8], file: Arc<str>, strict: bool) -> Self {
        Lexer {
            src,
            pos: 0,
            line: 1,
            line_start: 0,
            continuations: 0,
            file,
            strict,
        }
    }

    /// The location `line:col` in this file.
    pub fn loc(&self, line: u32, col: u32) -> Location {
        Location::new(self.file.clone(), line, col)
    }

    /// The file name of this source.
    pub fn file(&self) -> &Arc<str> {
        &self.file
    }

    /// The location of a token.
    pub fn tok_loc(&self, t: &Token) -> Location {
        self.loc(t.line, t.col)
    }

    /// The bytes of a token.
    pub fn bytes(&self, t: &Token) -> &'a [u8] {
        &self.src[t.start..t.end]
    }

    /// The column (in characters, from 1) of the next byte.
    #[inline(always)]
    fn col(&self) -> u32 {
        // Wrapping, as counting columns one by one in 32 bits did.
        ((self.pos - self.line_start - self.continuations) as u32).wrapping_add(1)
    }

    /// Advance over `src[pos..end]`, keeping line and column (characters) up to date.
    fn advance_to(&mut self, end: usize) {
        let s = &self.src[self.pos..end];
        match memchr::memrchr(b'\n', s) {
            None => self.continuations += continuations(s),
            Some(last) => {
                self.line += memchr::memchr_iter(b'\n', s).count() as u32;
                self.line_start = self.pos + last + 1;
                self.continuations = continuations(&s[last + 1..]);
            }
        }
        self.pos = end;
    }

    #[inline(always)]
    fn skip_space(&mut self) {
        let mut pos = self.pos;
        while let Some(&b) = self.src.get(pos) {
            if !is_space(b) {
                break;
            }
            pos += 1;
            if b == b'\n' {
                self.line += 1;
                self.line_start = pos;
                self.continuations = 0;
            }
        }
        self.pos = pos;
    }

    /// The next token, or `None` at the end of input. Errors: RB002, RB003, RB004 (and RB011
    /// under `strict`). Infos RB010, RB011 go to `diags`.
    // Inlined into the argument loop: a token returned through memory was read back before
    // its stores had landed, and that stall was the loop's largest cost.
    #[inline(always)]
    pub fn next_token(&mut self, diags: &mut Diagnostics) -> Result<Option<Token>, Error> {
        self.skip_space();
        let start = self.pos;
        let Some(&b) = self.src.get(start) else {
            return Ok(None);
        };
        let (line, col) = (self.line, self.col());
        let mut tok = Token {
            kind: TokKind::Comment,
            start,
            end: start,
            line,
            col,
            end_line: line,
            escaped: false,
        };
        match b {
            b'#' => {
                let end =
                    memchr::memchr(b'\n', &self.src[start..]).map_or(self.src.len(), |n| start + n);
                // No newline inside: only the column moves.
                self.continuations += continuations(&self.src[start..end]);
                self.pos = end;
                tok.kind = TokKind::Comment;
            }
            b'[' | b']' => {
                self.pos += 1;
                tok.kind = if b == b'[' {
                    TokKind::Open
                } else {
                    TokKind::Close
                };
            }
            b'"' | b'\'' => {
                let escaped = match plain_string_end(self.src, start, b) {
                    // One character per byte and no line break: only the position moves.
                    Some(end) => {
                        self.pos = end;
                        false
                    }
                    None => {
                        let (end, escaped) = self.scan_string(start, b, diags)?;
                        self.advance_to(end);
                        escaped
                    }
                };
                tok.kind = TokKind::Str;
                tok.escaped = escaped;
                if b == b'\'' {
                    let d = Diagnostic::info("RB011", "single-quoted string (non-standard RIB)")
                        .at(self.loc(line, col));
                    if self.strict {
                        return Err(Diagnostic::error(
                            "RB011",
                            "single-quoted string (not allowed with --strict-rib)",
                        )
                        .at(self.loc(line, col))
                        .into());
                    }
                    diags.push(d);
                }
            }
            c if c.is_ascii_alphabetic() || c == b'_' => {
                let len = self.src[start..]
                    .iter()
                    .position(|&c| CLASS[usize::from(c)] & WORD == 0)
                    .unwrap_or(self.src.len() - start);
                self.pos += len;
                tok.kind = TokKind::Ident;
            }
            c if c.is_ascii_digit() || matches!(c, b'+' | b'-' | b'.') => {
                match number(&self.src[start..]) {
                    Some(len) => {
                        self.pos += len;
                        tok.kind = TokKind::Number;
                    }
                    None => return Err(self.unexpected(start, line, col)),
                }
            }
            _ => return Err(self.unexpected(start, line, col)),
        }
        tok.end = self.pos;
        tok.end_line = self.line;
        Ok(Some(tok))
    }

    /// The elements and the `]` of an array whose `[` was just read, when they are the usual
    /// ones: on the `[`'s line, separated by spaces or tabs, all numbers or all plain strings
    /// (short printable ASCII without a backslash). Appends the elements to `items` and
    /// returns the `]`. Otherwise (a comment, a line break, a mixed array, an error to report, ...) returns
    /// `None` with nothing read and `items` as it was: [`Lexer::next_token`] then reads the
    /// array token by token and reports what it finds. The tokens are those `next_token`
    /// gives, found without its general dispatch: an array of a scene is read in one pass.
    pub fn flat_array(&mut self, items: &mut Vec<Token>) -> Option<Token> {
        let src = self.src;
        let line = self.line;
        // Nothing crossed here ends a line or holds a UTF-8 continuation byte, so a column
        // is the offset from the same base as [`Lexer::col`]'s.
        let base = self.line_start + self.continuations;
        let first = items.len();
        let mut kind = None;
        let mut pos = self.pos;
        loop {
            while matches!(src.get(pos), Some(b' ' | b'\t')) {
                pos += 1;
            }
            let Some(&b) = src.get(pos) else { break };
            let col = ((pos - base) as u32).wrapping_add(1);
            let (k, end) = match b {
                b']' => {
                    self.pos = pos + 1;
                    return Some(Token {
                        kind: TokKind::Close,
                        start: pos,
                        end: pos + 1,
                        line,
                        col,
                        end_line: line,
                        escaped: false,
                    });
                }
                b'"' => match plain_string_end(src, pos, b'"') {
                    Some(end) => (TokKind::Str, end),
                    None => break,
                },
                b'0'..=b'9' | b'+' | b'-' | b'.' => match number(&src[pos..]) {
                    Some(len) => (TokKind::Number, pos + len),
                    None => break,
                },
                _ => break,
            };
            if *kind.get_or_insert(k) != k {
                break;
            }
            items.push(Token {
                kind: k,
                start: pos,
                end,
                line,
                col,
                end_line: line,
                escaped: false,
            });
            pos = end;
        }
        items.truncate(first);
        None
    }

    fn unexpected(&self, at: usize, line: u32, col: u32) -> Error {
        let b = self.src[at];
        if b >= 0x80 {
            return Diagnostic::error(
                "RB002",
                format!(
                    "binary RIB is not supported (byte 0x{b:02X} at offset {at} outside a string or comment)"
                ),
            )
            .at(self.loc(line, col))
            .into();
        }
        let shown = if b.is_ascii_graphic() {
            format!("`{}`", b as char)
        } else {
            format!("byte 0x{b:02X}")
        };
        Diagnostic::error("RB004", format!("unexpected character {shown}"))
            .at(self.loc(line, col))
            .into()
    }

    /// Find the end of the string starting at `start` (quote `q`); report unknown escapes.
    /// Returns the end offset (after the closing quote) and whether a backslash occurs.
    fn scan_string(
        &self,
        start: usize,
        q: u8,
        diags: &mut Diagnostics,
    ) -> Result<(usize, bool), Error> {
        let mut i = start + 1;
        let mut escaped = false;
        loop {
            let Some(off) = memchr::memchr2(q, b'\\', &self.src[i..]) else {
                return Err(Diagnostic::error("RB003", "unterminated string")
                    .at(self.loc(self.line, self.col()))
                    .into());
            };
            i += off;
            if self.src[i] == q {
                return Ok((i + 1, escaped));
            }
            escaped = true;
            let Some(&e) = self.src.get(i + 1) else {
                return Err(Diagnostic::error("RB003", "unterminated string")
                    .at(self.loc(self.line, self.col()))
                    .into());
            };
            if !is_known_escape(e, q) {
                let (line, col) = self.position_of(i);
                let shown = if e.is_ascii_graphic() {
                    format!("\\{}", e as char)
                } else {
                    format!("\\ followed by byte 0x{e:02X}")
                };
                diags.push(
                    Diagnostic::info(
                        "RB010",
                        format!("unknown string escape `{shown}`, read as the character itself"),
                    )
                    .at(self.loc(line, col)),
                );
            }
            i += 2;
        }
    }

    /// Line and column of offset `at` inside the current token (at ≥ pos).
    fn position_of(&self, at: usize) -> (u32, u32) {
        let (mut line, mut col) = (self.line, self.col());
        for &b in &self.src[self.pos..at] {
            if b == b'\n' {
                line += 1;
                col = 1;
            } else if b & 0xC0 != 0x80 {
                col += 1;
            }
        }
        (line, col)
    }
}

/// Strings are looked at eight bytes at a time for at most this many bytes
/// ([`plain_string_end`]).
const SHORT_STRING: usize = 64;

/// The bytes of `w` equal to `b` (each such byte's high bit set, no other bit).
fn bytes_equal(w: u64, b: u8) -> u64 {
    const LOW7: u64 = 0x7f7f_7f7f_7f7f_7f7f;
    let x = w ^ (0x0101_0101_0101_0101 * u64::from(b));
    // A byte of `x` is zero exactly when adding 0x7f to its low seven bits leaves its high
    // bit clear and its own high bit is clear (no carry crosses bytes).
    !(((x & LOW7).wrapping_add(LOW7)) | x) & !LOW7
}

/// The end (after the closing quote `q`) of the string starting at `start`, when it is
/// plain: within [`SHORT_STRING`] bytes, printable ASCII, with no backslash. Then
/// its columns are its bytes and it needs no decoding. `None` otherwise (the caller scans it
/// in full). Nearly every string of a scene (decls, handles, connections) is plain, and a
/// vector search, a line count and a character count each cost more than such a string.
fn plain_string_end(src: &[u8], start: usize, q: u8) -> Option<usize> {
    let mut i = start + 1;
    while i - start <= SHORT_STRING {
        let chunk: [u8; 8] = src.get(i..i + 8)?.try_into().ok()?;
        let w = u64::from_le_bytes(chunk);
        // Control bytes (a line break among them) and non-ASCII bytes in one test: a byte
        // below 0x20 borrows when 0x20 is subtracted from it, a byte from 0x80 has its high
        // bit. A borrow can flag bytes above the first one flagged, never below it.
        let special = (w.wrapping_sub(0x2020_2020_2020_2020) | w) & 0x8080_8080_8080_8080;
        let stop = bytes_equal(w, q) | bytes_equal(w, b'\\') | special;
        if stop != 0 {
            let at = i + (stop.trailing_zeros() / 8) as usize;
            return (src[at] == q).then_some(at + 1);
        }
        i += 8;
    }
    None
}

/// Escapes that need no RB010: `\n \r \t \b \f \\ \"`, octal digits, backslash-newline, and
/// the quote character of a single-quoted string.
fn is_known_escape(e: u8, quote: u8) -> bool {
    matches!(
        e,
        b'n' | b'r' | b't' | b'b' | b'f' | b'\\' | b'"' | b'\n' | b'\r' | b'0'..=b'7'
    ) || e == quote
}

/// The decoded content of a string token (quotes removed, escapes applied). Invalid UTF-8 is
/// replaced by U+FFFD.
#[cfg_attr(feature = "testkit", visibility::make(pub))]
pub(crate) fn decode_string(src: &[u8], t: &Token) -> String {
    decode_str(src, t).into_owned()
}

/// [`decode_string`], borrowing from `src` when the string has no escape and is valid UTF-8
/// (as nearly every string of a scene is).
pub(crate) fn decode_str<'s>(src: &'s [u8], t: &Token) -> Cow<'s, str> {
    let inner = &src[t.start + 1..t.end - 1];
    if !t.escaped {
        if inner.is_ascii() {
            // SAFETY: ASCII bytes are valid UTF-8. (The short strings of a scene are nearly
            // all ASCII, and this check costs a fraction of the general validation's.)
            return Cow::Borrowed(unsafe { std::str::from_utf8_unchecked(inner) });
        }
        // Valid UTF-8 (nearly always) before the lossy decoder.
        return match std::str::from_utf8(inner) {
            Ok(s) => Cow::Borrowed(s),
            Err(_) => String::from_utf8_lossy(inner),
        };
    }
    let mut out: Vec<u8> = Vec::with_capacity(inner.len());
    let mut i = 0;
    while i < inner.len() {
        let c = inner[i];
        if c != b'\\' || i + 1 >= inner.len() {
            out.push(c);
            i += 1;
            continue;
        }
        let e = inner[i + 1];
        i += 2;
        match e {
            b'n' => out.push(b'\n'),
            b'r' => out.push(b'\r'),
            b't' => out.push(b'\t'),
            b'b' => out.push(0x08),
            b'f' => out.push(0x0c),
            // Backslash-newline is a continuation: both dropped (also for CR LF).
            b'\n' => {}
            b'\r' => {
                if inner.get(i) == Some(&b'\n') {
                    i += 1;
                }
            }
            b'0'..=b'7' => {
                let mut v = u32::from(e - b'0');
                let mut digits = 1;
                while digits < 3 {
                    match inner.get(i) {
                        Some(&d @ b'0'..=b'7') => {
                            v = v * 8 + u32::from(d - b'0');
                            i += 1;
                            digits += 1;
                        }
                        _ => break,
                    }
                }
                // `\400`–`\777` do not fit a byte; like C, keep the low eight bits.
                out.push((v & 0xFF) as u8);
            }
            other => out.push(other),
        }
    }
    Cow::Owned(String::from_utf8_lossy(&out).into_owned())
}

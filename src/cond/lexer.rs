//! The lexer of the conditional language, built on nom.
//!
//! Tokens (listed for users in `docs/conditional-language.md`) are recognised by longest
//! match; when a keyword and an identifier match the same text, the keyword wins. The
//! recognisers for the multi-character forms (numbers, strings, identifiers) are nom parsers;
//! [`next_token`] dispatches on the first character and applies the longest-match and tie
//! rules by hand, which for this token set comes down to a few local decisions:
//!
//! * an identifier `L(L|D)*` is extended by a glued array suffix `[D+]` when one follows
//!   (the longer match);
//! * `is` followed by exactly one U+0020 and `not` is the six-character `IS_NOT`,
//!   even when more identifier characters follow (`is notable` → `IS_NOT`, `PARAM able`);
//! * otherwise an identifier spelled exactly like a keyword is that keyword (the tie goes to
//!   the keyword), and anything longer is a `PARAM` (`connectif`, `island`);
//! * any character that starts no token is one `UNRECOGNIZED` token. The specification says
//!   "byte"; vstructc spans the whole UTF-8 character so that spans stay on character
//!   boundaries (the start offset, which is what positions report, is the same).
//!
//! Lexing never fails: unrecognised characters become tokens and the parser reports the first
//! one it reaches, like the reference (bison pulls tokens from flex on demand, so an earlier
//! syntax error wins over a later unrecognised character).

use nom::branch::alt;
use nom::bytes::complete::{tag, take_while};
use nom::character::complete::{char, digit0, digit1, none_of, one_of, satisfy};
use nom::combinator::opt;
use nom::multi::many0_count;
use nom::sequence::{pair, preceded};
use nom::{IResult, Parser};
use std::fmt;
use std::ops::Range;

/// A comparison operator.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, serde::Serialize)]
pub enum CmpOp {
    /// `==`
    #[serde(rename = "==")]
    Eq,
    /// `!=`
    #[serde(rename = "!=")]
    Ne,
    /// `<`
    #[serde(rename = "<")]
    Lt,
    /// `>`
    #[serde(rename = ">")]
    Gt,
    /// `<=`
    #[serde(rename = "<=")]
    Le,
    /// `>=`
    #[serde(rename = ">=")]
    Ge,
}

impl CmpOp {
    /// Every operator, in the order messages list them.
    pub const ALL: [CmpOp; 6] = [
        CmpOp::Eq,
        CmpOp::Ne,
        CmpOp::Lt,
        CmpOp::Gt,
        CmpOp::Le,
        CmpOp::Ge,
    ];

    /// The operator's spelling.
    pub fn as_str(self) -> &'static str {
        match self {
            CmpOp::Eq => "==",
            CmpOp::Ne => "!=",
            CmpOp::Lt => "<",
            CmpOp::Gt => ">",
            CmpOp::Le => "<=",
            CmpOp::Ge => ">=",
        }
    }
}

impl fmt::Display for CmpOp {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.as_str())
    }
}

/// The ten keywords that may also name a parameter in a predicate (spec `KW`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Keyword {
    /// `is`
    Is,
    /// `and`
    And,
    /// `or`
    Or,
    /// `if`
    If,
    /// `else`
    Else,
    /// `connected`
    Connected,
    /// `copy`
    Copy,
    /// `set`
    Set,
    /// `ignore`
    Ignore,
    /// `connect`
    Connect,
}

impl Keyword {
    /// All keywords, in a fixed order.
    pub const ALL: [Keyword; 10] = [
        Keyword::Is,
        Keyword::And,
        Keyword::Or,
        Keyword::If,
        Keyword::Else,
        Keyword::Connected,
        Keyword::Copy,
        Keyword::Set,
        Keyword::Ignore,
        Keyword::Connect,
    ];

    /// The keyword's spelling (lower case), which is also its parameter name.
    pub fn text(self) -> &'static str {
        match self {
            Keyword::Is => "is",
            Keyword::And => "and",
            Keyword::Or => "or",
            Keyword::If => "if",
            Keyword::Else => "else",
            Keyword::Connected => "connected",
            Keyword::Copy => "copy",
            Keyword::Set => "set",
            Keyword::Ignore => "ignore",
            Keyword::Connect => "connect",
        }
    }

    /// The token name used in messages: `IS`, `AND`, ….
    pub fn token_name(self) -> &'static str {
        match self {
            Keyword::Is => "IS",
            Keyword::And => "AND",
            Keyword::Or => "OR",
            Keyword::If => "IF",
            Keyword::Else => "ELSE",
            Keyword::Connected => "CONNECTED",
            Keyword::Copy => "COPY",
            Keyword::Set => "SET",
            Keyword::Ignore => "IGNORE",
            Keyword::Connect => "CONNECT",
        }
    }

    /// The keyword spelled exactly `word`, if any (case-sensitive).
    pub fn from_text(word: &str) -> Option<Keyword> {
        Keyword::ALL.into_iter().find(|k| k.text() == word)
    }
}

/// What a token is. Text-carrying variants borrow from the expression.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum TokenKind<'a> {
    /// One of the ten keywords.
    Kw(Keyword),
    /// `is not` (exactly one space).
    IsNot,
    /// A number literal, as written.
    Number(&'a str),
    /// A string literal: the text between the outer quotes, verbatim.
    Str {
        /// Content between the quotes (escapes not decoded).
        content: &'a str,
        /// The quote character used (`'` or `"`).
        quote: char,
    },
    /// A parameter name (possibly with an array suffix such as `arr[2]`).
    Param(&'a str),
    /// `(`
    LParen,
    /// `)`
    RParen,
    /// A comparison operator.
    Cmp(CmpOp),
    /// A character that starts no token.
    Unrecognized(char),
    /// End of input.
    Eof,
}

impl TokenKind<'_> {
    /// A description for "found …" in messages: the token name plus its text where that
    /// helps (`PARAM "y"`, `NUMBER 007`, `STRING 'x'`), quoted punctuation (`'('`, `'=='`),
    /// and unrecognised characters quoted and escaped (`'='`, `'\r'`).
    pub fn describe(&self) -> String {
        match self {
            TokenKind::Kw(k) => k.token_name().to_string(),
            TokenKind::IsNot => "IS_NOT".to_string(),
            TokenKind::Number(t) => format!("NUMBER {t}"),
            TokenKind::Str { content, quote } => format!("STRING {quote}{content}{quote}"),
            TokenKind::Param(p) => format!("PARAM \"{p}\""),
            TokenKind::LParen => "'('".to_string(),
            TokenKind::RParen => "')'".to_string(),
            TokenKind::Cmp(op) => format!("'{op}'"),
            TokenKind::Unrecognized('\'') => "\"'\"".to_string(),
            TokenKind::Unrecognized(c) => format!("'{}'", escape_char(*c)),
            TokenKind::Eof => "end of input".to_string(),
        }
    }
}

/// A character as shown in messages: printable characters as themselves, the whitespace and
/// control characters as C escapes (`\r`, `\v`, `\u{1b}`).
pub(crate) fn escape_char(c: char) -> String {
    match c {
        '\r' => "\\r".into(),
        '\n' => "\\n".into(),
        '\t' => "\\t".into(),
        '\u{0b}' => "\\v".into(),
        '\u{0c}' => "\\f".into(),
        '\0' => "\\0".into(),
        c if c.is_control() => format!("\\u{{{:x}}}", c as u32),
        c => c.to_string(),
    }
}

/// One token with its byte span in the expression.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Token<'a> {
    /// What the token is.
    pub kind: TokenKind<'a>,
    /// Byte offsets `start..end` in the expression.
    pub start: usize,
    /// End offset (exclusive).
    pub end: usize,
}

impl Token<'_> {
    /// The byte span.
    pub fn span(&self) -> Range<usize> {
        self.start..self.end
    }
}

/// The language's whitespace set: space, `\t`, `\v`, `\n`, `\f` — **not** `\r`.
pub(crate) fn is_space(c: char) -> bool {
    matches!(c, ' ' | '\t' | '\u{0b}' | '\n' | '\u{0c}')
}

fn is_letter(c: char) -> bool {
    c.is_ascii_alphabetic() || c == '_'
}

fn is_ident_char(c: char) -> bool {
    c.is_ascii_alphanumeric() || c == '_'
}

/// Run `parser` and return the slice of `i` it consumed, measured by **length**.
///
/// nom's own `recognize` measures by pointer offset, and nom 8.0's complete `digit0` returns
/// an empty remainder that points at the start of its input when it consumes everything, so
/// `recognize` would cut `0.0` at the end of an expression to `0.`. Lengths are always right.
fn consumed<'a, O, P>(mut parser: P) -> impl FnMut(&'a str) -> IResult<&'a str, &'a str>
where
    P: Parser<&'a str, Output = O, Error = nom::error::Error<&'a str>>,
{
    move |i: &'a str| {
        let (rest, _) = parser.parse(i)?;
        let used = i.len() - rest.len();
        Ok((&i[used..], &i[..used]))
    }
}

/// `NUMBER`: `-?D+`, `-?D+X`, `-?D*\.D+X?`, `-?D+\.D*X?` (longest match). An exponent
/// without digits is not part of the number (`1e` is `1`, then `e`).
fn number(i: &str) -> IResult<&str, &str> {
    let mantissa = alt((
        consumed(pair(digit1, opt(pair(char('.'), digit0)))),
        consumed(pair(char('.'), digit1)),
    ));
    let exponent = consumed((one_of("eE"), opt(one_of("+-")), digit1));
    consumed((opt(char('-')), mantissa, opt(exponent)))(i)
}

/// `STRING` delimited by `quote`: `q(\\.|[^\\q])*q`. The escape's `.` does not match a
/// newline (flex semantics); a raw newline is allowed as an ordinary character.
fn string(quote: char) -> impl Fn(&str) -> IResult<&str, &str> {
    move |i| {
        let stop: &str = if quote == '\'' { "\\'" } else { "\\\"" };
        let escape = preceded(char('\\'), none_of("\n"));
        let body = consumed(many0_count(alt((escape, none_of(stop)))));
        let (rest, (_, content, _)) = (char(quote), body, char(quote)).parse(i)?;
        Ok((rest, content))
    }
}

/// An identifier `L(L|D)*`, with a glued array suffix `[D+]` if one follows.
fn identifier(i: &str) -> IResult<&str, (&str, bool)> {
    let (rest, base) = consumed(pair(satisfy(is_letter), take_while(is_ident_char)))(i)?;
    let suffix = consumed((char('['), digit1, char(']')))(rest);
    match suffix {
        Ok((rest2, s)) => Ok((rest2, (&i[..base.len() + s.len()], true))),
        Err(_) => Ok((rest, (base, false))),
    }
}

/// The operators: `==`, `!=`, `<=`, `>=`, `<`, `>` (two-character forms first: longest match).
fn operator(i: &str) -> IResult<&str, CmpOp> {
    alt((
        tag("==").map(|_| CmpOp::Eq),
        tag("!=").map(|_| CmpOp::Ne),
        tag("<=").map(|_| CmpOp::Le),
        tag(">=").map(|_| CmpOp::Ge),
        tag("<").map(|_| CmpOp::Lt),
        tag(">").map(|_| CmpOp::Gt),
    ))
    .parse(i)
}

/// Recognise the token starting at byte `pos` of `text` (after whitespace was skipped).
/// Returns the token kind and its length in bytes. `pos` must be a character boundary
/// before the end of `text`.
fn token_at(text: &str, pos: usize) -> (TokenKind<'_>, usize) {
    let rest = &text[pos..];
    let Some(first) = rest.chars().next() else {
        return (TokenKind::Eof, 0);
    };
    let unrecognized = (TokenKind::Unrecognized(first), first.len_utf8());
    match first {
        c if is_letter(c) => match identifier(rest) {
            Ok((_, (word, true))) => (TokenKind::Param(word), word.len()),
            Ok((after, (word, false))) => {
                if word == "is" && after.starts_with(" not") {
                    (TokenKind::IsNot, "is not".len())
                } else if let Some(k) = Keyword::from_text(word) {
                    (TokenKind::Kw(k), word.len())
                } else {
                    (TokenKind::Param(word), word.len())
                }
            }
            Err(_) => unrecognized,
        },
        '0'..='9' | '.' | '-' => match number(rest) {
            Ok((_, n)) => (TokenKind::Number(n), n.len()),
            Err(_) => unrecognized,
        },
        '\'' | '"' => match string(first)(rest) {
            Ok((after, content)) => (
                TokenKind::Str {
                    content,
                    quote: first,
                },
                rest.len() - after.len(),
            ),
            Err(_) => unrecognized,
        },
        '(' => (TokenKind::LParen, 1),
        ')' => (TokenKind::RParen, 1),
        '=' | '!' | '<' | '>' => match operator(rest) {
            Ok((after, op)) => (TokenKind::Cmp(op), rest.len() - after.len()),
            Err(_) => unrecognized,
        },
        _ => unrecognized,
    }
}

/// The next token at or after byte `pos` (whitespace skipped). Returns an [`TokenKind::Eof`]
/// token with an empty span at the end of the text.
pub fn next_token(text: &str, pos: usize) -> Token<'_> {
    let skipped = text[pos..]
        .find(|c: char| !is_space(c))
        .map_or(text.len(), |n| pos + n);
    let (kind, len) = token_at(text, skipped);
    Token {
        kind,
        start: skipped,
        end: skipped + len,
    }
}

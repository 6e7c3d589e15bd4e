//! Unit tests of `cond::lexer` (`src/cond/lexer.rs`).

use vstructc::cond::internals::*;
use vstructc::cond::*;

/// Split `text` into tokens; the last token is always [`TokenKind::Eof`]. Never fails.
fn tokenize(text: &str) -> Vec<Token<'_>> {
    let mut tokens = Vec::with_capacity(text.len() / 3 + 2);
    let mut pos = 0;
    loop {
        let t = next_token(text, pos);
        tokens.push(t);
        if t.kind == TokenKind::Eof {
            return tokens;
        }
        pos = t.end;
    }
}

fn kinds(text: &str) -> Vec<TokenKind<'_>> {
    tokenize(text).into_iter().map(|t| t.kind).collect()
}

use TokenKind::*;

#[test]
fn keywords_are_whole_words_and_case_sensitive() {
    assert_eq!(kinds("connect"), [Kw(Keyword::Connect), Eof]);
    assert_eq!(kinds("connected"), [Kw(Keyword::Connected), Eof]);
    for word in [
        "CONNECT",
        "AND",
        "connectif",
        "isConnected",
        "island",
        "not",
        "Is",
    ] {
        assert_eq!(kinds(word), [Param(word), Eof], "{word}");
    }
}

#[test]
fn is_not_needs_exactly_one_space() {
    assert_eq!(kinds("is not"), [IsNot, Eof]);
    assert_eq!(kinds("is  not"), [Kw(Keyword::Is), Param("not"), Eof]);
    assert_eq!(kinds("is\tnot"), [Kw(Keyword::Is), Param("not"), Eof]);
    assert_eq!(kinds("is notable"), [IsNot, Param("able"), Eof]);
    assert_eq!(kinds("is no"), [Kw(Keyword::Is), Param("no"), Eof]);
    assert_eq!(kinds("isnot"), [Param("isnot"), Eof]);
}

#[test]
fn numbers_follow_the_four_forms() {
    for n in [
        "1", "-1", "007", "1e2", ".5", "5.", "-.5e-1", "1E+3", "5.e3", "-0",
    ] {
        assert_eq!(kinds(n), [Number(n), Eof], "{n}");
    }
    assert_eq!(kinds("0x10"), [Number("0"), Param("x10"), Eof]);
    // At the very end of the input (nom 8 `digit0` quirk, see `consumed`).
    assert_eq!(kinds("set 0.0"), [Kw(Keyword::Set), Number("0.0"), Eof]);
    assert_eq!(kinds("x 1.5"), [Param("x"), Number("1.5"), Eof]);
    assert_eq!(kinds("1.5.2"), [Number("1.5"), Number(".2"), Eof]);
    assert_eq!(kinds("1e"), [Number("1"), Param("e"), Eof]);
    assert_eq!(kinds("+1"), [Unrecognized('+'), Number("1"), Eof]);
    assert_eq!(kinds("- 1"), [Unrecognized('-'), Number("1"), Eof]);
    assert_eq!(kinds("."), [Unrecognized('.'), Eof]);
    assert_eq!(kinds("-."), [Unrecognized('-'), Unrecognized('.'), Eof]);
}

#[test]
fn strings_are_verbatim_and_escapes_only_delimit() {
    let t = tokenize(r"'a\'b'");
    assert_eq!(
        t[0].kind,
        Str {
            content: r"a\'b",
            quote: '\''
        }
    );
    assert_eq!(t[0].span(), 0..6);
    assert_eq!(
        kinds("\"it's\""),
        [
            Str {
                content: "it's",
                quote: '"'
            },
            Eof
        ]
    );
    assert_eq!(
        kinds("'a\nb'"),
        [
            Str {
                content: "a\nb",
                quote: '\''
            },
            Eof
        ]
    );
    // An unterminated string makes its opening quote unrecognised.
    assert_eq!(kinds("'abc"), [Unrecognized('\''), Param("abc"), Eof]);
    // A backslash cannot escape a newline (flex `.`), so this string never closes.
    assert_eq!(kinds("'\\\n'")[0], Unrecognized('\''));
}

#[test]
fn array_suffix_is_part_of_the_name() {
    assert_eq!(kinds("arr[2]"), [Param("arr[2]"), Eof]);
    assert_eq!(kinds("is[2]"), [Param("is[2]"), Eof]);
    assert_eq!(kinds("arr[ 2]")[1], Unrecognized('['));
    assert_eq!(kinds("arr[]")[1], Unrecognized('['));
    assert_eq!(kinds("arr[-1]")[1], Unrecognized('['));
}

#[test]
fn operators_by_longest_match() {
    assert_eq!(kinds(">="), [Cmp(CmpOp::Ge), Eof]);
    assert_eq!(kinds("> ="), [Cmp(CmpOp::Gt), Unrecognized('='), Eof]);
    assert_eq!(
        kinds("x==-1"),
        [Param("x"), Cmp(CmpOp::Eq), Number("-1"), Eof]
    );
    for bad in ['=', '!', '&', '|', ';', ':', '+', ',', '{', '\r', 'é'] {
        let s = bad.to_string();
        assert_eq!(kinds(&s), [Unrecognized(bad), Eof], "{bad:?}");
    }
}

#[test]
fn whitespace_set_excludes_carriage_return() {
    assert_eq!(
        kinds(" \t\u{b}\n\u{c}x"),
        [Param("x"), Eof],
        "all five whitespace characters are skipped"
    );
    assert_eq!(kinds("\rx")[0], Unrecognized('\r'));
}

#[test]
fn spans_are_byte_offsets() {
    let t = tokenize("connect if x = 1");
    let spans: Vec<_> = t.iter().map(Token::span).collect();
    assert_eq!(spans, [0..7, 8..10, 11..12, 13..14, 15..16, 16..16]);
    let t = tokenize("é x");
    assert_eq!(t[0].span(), 0..2);
    assert_eq!(t[1].span(), 3..4);
}

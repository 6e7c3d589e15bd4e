//! Unit tests of `front::rib::lexer` (`src/front/rib/lexer.rs`).

use vstructc::diag::Diagnostics;
use vstructc::front::rib::lexer::*;

fn lex(src: &str) -> (Vec<(TokKind, String)>, Diagnostics) {
    let mut d = Diagnostics::new();
    let mut lx = Lexer::new(src.as_bytes(), "t".into(), false);
    let mut out = Vec::new();
    while let Some(t) = lx.next_token(&mut d).unwrap() {
        let text = if t.kind == TokKind::Str {
            decode_string(src.as_bytes(), &t)
        } else {
            String::from_utf8_lossy(lx.bytes(&t)).into_owned()
        };
        out.push((t.kind, text));
    }
    (out, d)
}

#[test]
fn numbers_in_every_form() {
    for n in [
        "0.",
        "1.",
        "-0",
        "9.99999968e+37",
        "3.04999995",
        ".8",
        "+2",
        "1e5",
        "-1.5E-3",
    ] {
        let (toks, _) = lex(n);
        assert_eq!(toks, vec![(TokKind::Number, n.to_string())], "{n}");
    }
}

#[test]
fn number_then_identifier_splits() {
    let (toks, _) = lex("[1 2]Sphere");
    let kinds: Vec<_> = toks.iter().map(|t| t.0).collect();
    assert_eq!(
        kinds,
        [
            TokKind::Open,
            TokKind::Number,
            TokKind::Number,
            TokKind::Close,
            TokKind::Ident
        ]
    );
}

#[test]
fn string_escapes() {
    let (toks, d) = lex(r#""a\"b\\c\n\t\101\q" "x\
y""#);
    assert_eq!(toks[0].1, "a\"b\\c\n\tAq");
    assert_eq!(toks[1].1, "xy");
    assert_eq!(d.count("RB010"), 1);
    let rb010 = d.with_code("RB010").next().unwrap();
    assert_eq!(rb010.location.as_ref().map(|l| l.column), Some(17));
}

#[test]
fn single_quotes_are_info_or_strict_error() {
    let (toks, d) = lex("['object']");
    assert_eq!(toks[1], (TokKind::Str, "object".into()));
    assert_eq!(d.count("RB011"), 1);
    let mut d = Diagnostics::new();
    let mut lx = Lexer::new(b"'x'", "t".into(), true);
    let err = lx.next_token(&mut d).unwrap_err();
    assert_eq!(err.code(), Some("RB011"));
}

#[test]
fn positions_count_characters() {
    let src = "# é comment\n  Pattern \"é\" x";
    let mut d = Diagnostics::new();
    let mut lx = Lexer::new(src.as_bytes(), "t".into(), false);
    let c = lx.next_token(&mut d).unwrap().unwrap();
    assert_eq!((c.kind, c.line, c.col), (TokKind::Comment, 1, 1));
    let p = lx.next_token(&mut d).unwrap().unwrap();
    assert_eq!((p.line, p.col), (2, 3));
    let s = lx.next_token(&mut d).unwrap().unwrap();
    assert_eq!((s.line, s.col), (2, 11));
    let x = lx.next_token(&mut d).unwrap().unwrap();
    assert_eq!((x.line, x.col), (2, 15));
}

#[test]
fn errors() {
    let mut d = Diagnostics::new();
    let mut lx = Lexer::new(b"  \"abc", "t".into(), false);
    assert_eq!(lx.next_token(&mut d).unwrap_err().code(), Some("RB003"));
    let mut lx = Lexer::new(b"a {", "t".into(), false);
    lx.next_token(&mut d).unwrap();
    let e = lx.next_token(&mut d).unwrap_err();
    assert_eq!(e.code(), Some("RB004"));
    assert_eq!(e.diagnostic().unwrap().location.as_ref().unwrap().column, 3);
    let mut lx = Lexer::new(b"a \xff", "t".into(), false);
    lx.next_token(&mut d).unwrap();
    let e = lx.next_token(&mut d).unwrap_err();
    assert_eq!(e.code(), Some("RB002"));
    assert!(e.to_string().contains("offset 2"));
    // Bytes >= 0x80 inside strings and comments are fine.
    let mut lx = Lexer::new("\"\u{e9}\" # \u{e9}".as_bytes(), "t".into(), false);
    assert!(lx.next_token(&mut d).unwrap().is_some());
    assert!(lx.next_token(&mut d).unwrap().is_some());
    // A lone sign is not a number.
    let mut lx = Lexer::new(b"- 1", "t".into(), false);
    assert_eq!(lx.next_token(&mut d).unwrap_err().code(), Some("RB004"));
}

/// Line and column (characters, from 1) of byte offset `at` of `src`, counted naively.
fn naive_position(src: &str, at: usize) -> (u32, u32) {
    let before = &src[..at];
    let line = 1 + before.matches('\n').count() as u32;
    let line_start = before.rfind('\n').map_or(0, |i| i + 1);
    (line, 1 + src[line_start..at].chars().count() as u32)
}

#[test]
fn strings_of_every_length_and_content_keep_positions() {
    // Plain ASCII strings take a shortcut (eight bytes at a time, columns = bytes); a string
    // with a line break, a non-ASCII character or an escape anywhere, a long one, or one near
    // the end of the input does not. Every shape must give the same token ends and positions.
    for len in 0usize..80 {
        for special in [None, Some("é"), Some("\n"), Some("\\\""), Some("'")] {
            for at in [0, len / 2, len.saturating_sub(1)] {
                let mut body: String = "ab_:1".chars().cycle().take(len).collect();
                if let Some(s) = special {
                    body.insert_str(at.min(body.len()), s);
                }
                for (q, tail) in [('"', " x"), ('"', ""), ('\'', " x")] {
                    if q == '\'' && special == Some("'") {
                        continue;
                    }
                    let src = format!("  {q}{body}{q}{tail}");
                    let mut d = Diagnostics::new();
                    let mut lx = Lexer::new(src.as_bytes(), "t".into(), false);
                    let s = lx.next_token(&mut d).unwrap().unwrap();
                    assert_eq!((s.kind, s.start, s.end), (TokKind::Str, 2, 4 + body.len()));
                    assert_eq!((s.line, s.col), (1, 3));
                    assert_eq!(s.end_line, naive_position(&src, s.end - 1).0, "{src:?}");
                    assert_eq!(s.escaped, body.contains('\\'), "{src:?}");
                    match lx.next_token(&mut d).unwrap() {
                        Some(x) => {
                            assert_eq!(x.kind, TokKind::Ident);
                            let at = src.len() - 1;
                            assert_eq!((x.line, x.col), naive_position(&src, at), "{src:?}");
                        }
                        None => assert!(tail.is_empty()),
                    }
                }
            }
        }
    }
}

/// The tokens of `src` (kind, span, position) up to the first error, and that error's code
/// and position.
fn tokens(src: &str) -> (Vec<Token>, Option<String>) {
    let mut d = Diagnostics::new();
    let mut lx = Lexer::new(src.as_bytes(), "t".into(), false);
    let mut out = Vec::new();
    loop {
        match lx.next_token(&mut d) {
            Ok(Some(t)) => out.push(t),
            Ok(None) => return (out, None),
            Err(e) => return (out, Some(format!("{:?} {}", e.code(), e))),
        }
    }
}

#[test]
fn numbers_read_alike_with_and_without_room_after() {
    // A number with sixteen bytes after its start is classified in one step; nearer the end
    // of the input it is read byte by byte. Both must find the same tokens and errors.
    let alphabet = ['0', '7', '.', 'e', 'E', '+', '-', 'x'];
    let mut cases: Vec<String> = vec![String::new()];
    for _ in 0..4 {
        let longer: Vec<String> = cases
            .iter()
            .flat_map(|c| alphabet.iter().map(move |a| format!("{c}{a}")))
            .collect();
        cases.extend(longer);
    }
    for n in 13..19 {
        cases.push("1".repeat(n));
        cases.push(format!("0.{}", "5".repeat(n - 2)));
        cases.push(format!("-{}", "2".repeat(n)));
        cases.push(format!("{}e3", "3".repeat(n)));
    }
    for case in cases.iter().filter(|c| !c.is_empty()) {
        let (short, short_err) = tokens(case);
        let padded = format!("{case} 0 0 0 0 0 0 0 0 0 0 0");
        let (long, long_err) = tokens(&padded);
        let inside: Vec<Token> = long
            .iter()
            .copied()
            .filter(|t| t.start < case.len())
            .collect();
        assert_eq!(short, inside, "{case:?}");
        // An error inside the case is the same error; the padding itself reads cleanly.
        if short_err.is_some() {
            assert_eq!(short_err, long_err, "{case:?}");
        }
    }
}

#[test]
fn flat_arrays_read_as_token_by_token() {
    // `Lexer::flat_array` reads the usual arrays in one pass and leaves any other to
    // `next_token`: either way the same tokens and positions follow.
    let bodies = [
        "",
        "1 2 3",
        "0.5",
        "\t1\t-2 +.5 3e4  ",
        "\"a\" \"b:c\"",
        "\"a\"\"b\"",
        "1\"a\"",
        "1 \"a\"",
        "\"a\" 1",
        "1 # c\n 2",
        "1\n2",
        "1\r\n2",
        "'a'",
        "\"a\\\"b\"",
        "\"é\" 1",
        "\"x\ny\"",
        "1e",
        "1 x",
        "- 1",
        "[1]",
        "1 2 3 4 5 6 7 8 9 10 11 12 13 14 15 16 17",
        "\"a very long string that takes more than the sixty-four bytes looked at first\"",
    ];
    for body in bodies {
        for tail in ["] x", "]x", "", "]\n]"] {
            let src = format!("  [{body}{tail}");
            let mut d = Diagnostics::new();
            let (expected, _) = tokens(&src);
            let mut lx = Lexer::new(src.as_bytes(), "t".into(), false);
            let open = lx.next_token(&mut d).unwrap().unwrap();
            assert_eq!(open, expected[0], "{src:?}");
            let mut items = vec![open];
            let read = match lx.flat_array(&mut items) {
                Some(close) => {
                    items.push(close);
                    items.len()
                }
                None => {
                    assert_eq!(items.len(), 1, "{src:?}");
                    1
                }
            };
            assert_eq!(items[..], expected[..read], "{src:?}");
            // The lexer goes on from where the array ended, positions intact.
            let mut rest = items;
            while let Ok(Some(t)) = lx.next_token(&mut d) {
                rest.push(t);
            }
            assert_eq!(rest, expected, "{src:?}");
        }
    }
}

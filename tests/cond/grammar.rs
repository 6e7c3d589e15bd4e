//! Every example in `grammar/vstruct-conditional.ebnf` behaves as the file says.
//!
//! Example lines (documented at the top of the grammar file):
//! `(* example: TEXT *)`, `(* example: TEXT --> DESUGARED *)`, `(* example[EXT]: ... *)`,
//! `(* reject: TEXT *)`, `(* reject-at N: TEXT *)` (N = 1-based column of the offending token).

use vstructc::cond::{self, Extensions};

const GRAMMAR: &str = include_str!("../../grammar/vstruct-conditional.ebnf");

#[derive(Debug)]
enum Kind {
    Accept {
        ext: Extensions,
        desugared: Option<String>,
    },
    Reject {
        column: Option<u32>,
    },
}

#[derive(Debug)]
struct Example {
    line: usize,
    text: String,
    kind: Kind,
}

/// Pull every example out of the grammar file.
fn examples() -> Vec<Example> {
    let mut out = Vec::new();
    for (n, line) in GRAMMAR.lines().enumerate() {
        // An example is a comment that ends its line (the format description at the top of
        // the file has prose after its comments).
        let line = line.trim_end();
        if !line.ends_with(" *)") {
            continue;
        }
        let Some(open) = line.find("(* example").or_else(|| line.find("(* reject")) else {
            continue;
        };
        let rest = &line[open + 3..];
        let Some(colon) = rest.find(": ") else {
            panic!("line {}: example without ': '", n + 1);
        };
        let head = &rest[..colon];
        let body = &rest[colon + 2..];
        let body = body
            .strip_suffix(" *)")
            .unwrap_or_else(|| panic!("line {}: example must end with ' *)'", n + 1));
        let kind = if let Some(h) = head.strip_prefix("example") {
            let ext = match h.strip_prefix('[').and_then(|h| h.strip_suffix(']')) {
                Some(name) => Extensions::from_names([name]).expect("known extension"),
                None => {
                    assert!(h.is_empty(), "line {}: bad example head {head:?}", n + 1);
                    Extensions::none()
                }
            };
            let (text, desugared) = match body.split_once(" --> ") {
                Some((t, d)) => (t, Some(d.to_string())),
                None => (body, None),
            };
            out.push(Example {
                line: n + 1,
                text: text.to_string(),
                kind: Kind::Accept { ext, desugared },
            });
            continue;
        } else if head == "reject" {
            Kind::Reject { column: None }
        } else if let Some(col) = head.strip_prefix("reject-at ") {
            Kind::Reject {
                column: Some(col.parse().expect("column number")),
            }
        } else {
            panic!("line {}: unknown example kind {head:?}", n + 1);
        };
        out.push(Example {
            line: n + 1,
            text: body.to_string(),
            kind,
        });
    }
    out
}

#[test]
fn grammar_has_many_examples() {
    let ex = examples();
    let accepts = ex
        .iter()
        .filter(|e| matches!(e.kind, Kind::Accept { .. }))
        .count();
    let rejects = ex.len() - accepts;
    assert!(accepts >= 50, "only {accepts} accept examples");
    assert!(rejects >= 25, "only {rejects} reject examples");
}

#[test]
fn every_grammar_example_behaves_as_documented() {
    for ex in examples() {
        match &ex.kind {
            Kind::Accept { ext, desugared } => {
                let stmt = cond::parse_with(&ex.text, ext).unwrap_or_else(|e| {
                    panic!("line {}: {:?} should parse: {}", ex.line, ex.text, e)
                });
                if let Some(d) = desugared {
                    assert_eq!(&stmt.to_string(), d, "line {}: {:?}", ex.line, ex.text);
                }
                // The printed form parses back to the same statement.
                let again = cond::parse_with(&stmt.to_string(), ext).unwrap();
                assert!(again.same_as(&stmt), "line {}", ex.line);
            }
            Kind::Reject { column } => {
                let err = match cond::parse(&ex.text) {
                    Ok(s) => panic!(
                        "line {}: {:?} should be rejected, got {s}",
                        ex.line, ex.text
                    ),
                    Err(e) => e,
                };
                if let Some(c) = column {
                    assert_eq!(
                        err.column(&ex.text),
                        *c,
                        "line {}: {:?}: {}",
                        ex.line,
                        ex.text,
                        err.message
                    );
                }
            }
        }
    }
}

#[test]
fn else_if_examples_need_the_extension() {
    let gated: Vec<_> = examples()
        .into_iter()
        .filter(|e| matches!(&e.kind, Kind::Accept { ext, .. } if !ext.is_empty()))
        .collect();
    assert!(gated.len() >= 3);
    let mut chained = 0;
    for ex in gated {
        if let Ok(s) = cond::parse(&ex.text) {
            // Only the degenerate chain without links parses in compat mode too.
            assert!(s.else_ifs.is_empty(), "line {}", ex.line);
        } else {
            chained += 1;
        }
    }
    assert!(chained >= 3);
}

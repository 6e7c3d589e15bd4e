//! Property tests: random ASTs round-trip through print/parse; random input never panics.

use proptest::prelude::*;
use vstructc::cond::{
    self, Action, ActionKind, CmpOp, ElseIf, Expr, Extension, Extensions, IsTest, Literal,
    MapUpstream, Param, Statement, ast::quote_for,
};
use vstructc::types::Value;

const KEYWORDS: [&str; 10] = [
    "is",
    "and",
    "or",
    "if",
    "else",
    "connected",
    "copy",
    "set",
    "ignore",
    "connect",
];

/// A `PARAM`: an identifier that is not a keyword, maybe with an array suffix.
fn param_name() -> impl Strategy<Value = String> {
    (
        "[A-Za-z_][A-Za-z0-9_]{0,7}",
        proptest::option::of(0u32..1000),
    )
        .prop_filter("not a keyword", |(id, _)| !KEYWORDS.contains(&id.as_str()))
        .prop_map(|(id, idx)| match idx {
            Some(i) => format!("{id}[{i}]"),
            None => id,
        })
}

/// A predicate name: a `PARAM` or any keyword (§3.2 `name := PARAM | KW`).
fn pred_name() -> impl Strategy<Value = String> {
    prop_oneof![
        4 => param_name(),
        1 => proptest::sample::select(KEYWORDS.to_vec()).prop_map(str::to_string),
    ]
}

/// Number text in one of the four §3.1 forms.
fn number_text() -> impl Strategy<Value = String> {
    let exp = proptest::option::of(("[eE]", "[+-]?", "[0-9]{1,2}"))
        .prop_map(|e| e.map_or(String::new(), |(a, b, c)| format!("{a}{b}{c}")));
    (
        any::<bool>(),
        prop_oneof![
            "[0-9]{1,4}".prop_map(|d| d),
            ("[0-9]{0,3}", "[0-9]{1,3}").prop_map(|(a, b)| format!("{a}.{b}")),
            ("[0-9]{1,3}", "[0-9]{0,3}").prop_map(|(a, b)| format!("{a}.{b}")),
        ],
        exp,
    )
        .prop_map(|(neg, m, e)| format!("{}{m}{e}", if neg { "-" } else { "" }))
}

fn literal() -> impl Strategy<Value = Literal> {
    prop_oneof![
        number_text().prop_map(|t| Literal::number(&t, 0..0).expect("valid number text")),
        "[ab '\"\\\\\n\t]{0,6}"
            .prop_filter("delimitable", |s| quote_for(s).is_some())
            .prop_map(|s| Literal::string(s, 0..0)),
    ]
}

fn predicate() -> impl Strategy<Value = Expr> {
    let op = proptest::sample::select(CmpOp::ALL.to_vec());
    prop_oneof![
        (pred_name(), op, literal()).prop_map(|(n, op, lit)| Expr::cmp(
            Param::new(n, 0..0),
            op,
            lit,
            0..0
        )),
        (
            pred_name(),
            prop_oneof![Just(IsTest::Connected), Just(IsTest::Set)],
            any::<bool>()
        )
            .prop_map(|(n, t, neg)| Expr::is(Param::new(n, 0..0), t, neg, 0..0)),
    ]
}

fn expr() -> impl Strategy<Value = Expr> {
    predicate().prop_recursive(4, 24, 2, |inner| {
        prop_oneof![
            (inner.clone(), inner.clone()).prop_map(|(a, b)| Expr::and(a, b)),
            (inner.clone(), inner).prop_map(|(a, b)| Expr::or(a, b)),
        ]
    })
}

fn action() -> impl Strategy<Value = Action> {
    prop_oneof![
        Just(ActionKind::Connect),
        Just(ActionKind::Ignore),
        literal().prop_map(|literal| ActionKind::Set { literal }),
        param_name().prop_map(|n| ActionKind::Copy {
            param: Param::new(n, 0..0)
        }),
    ]
    .prop_map(|k| Action::new(k, 0..0))
}

/// A desugared statement: a bare action, or (action, condition, fallback), optionally with
/// `else-if` links.
fn statement(chains: bool) -> impl Strategy<Value = Statement> {
    let links = if chains { 0..3usize } else { 0..1usize };
    prop_oneof![
        action().prop_map(|a| Statement {
            action: a,
            condition: None,
            else_ifs: Vec::new(),
            fallback: None,
            span: 0..0,
        }),
        (
            action(),
            expr(),
            proptest::collection::vec((action(), expr()), links),
            action()
        )
            .prop_map(|(a, c, links, fb)| Statement {
                action: a,
                condition: Some(c),
                else_ifs: links
                    .into_iter()
                    .map(|(action, condition)| ElseIf { action, condition })
                    .collect(),
                fallback: Some(fb),
                span: 0..0,
            }),
    ]
}

fn else_if() -> Extensions {
    Extensions::none().with(Extension::ElseIf)
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(512))]

    #[test]
    fn random_statements_round_trip(stmt in statement(false)) {
        let text = stmt.to_string();
        let parsed = cond::parse(&text)
            .map_err(|e| TestCaseError::fail(format!("{text:?}: {}", e.render(&text))))?;
        prop_assert!(parsed.same_as(&stmt), "{:?}\n{:#?}\n{:#?}", text, parsed.without_spans(), stmt);
        // Spans of the parse lie inside the text and cover the printed pieces.
        prop_assert_eq!(parsed.span.clone(), 0..text.len());
    }

    #[test]
    fn random_chains_round_trip(stmt in statement(true)) {
        let text = stmt.to_string();
        let parsed = cond::parse_with(&text, &else_if())
            .map_err(|e| TestCaseError::fail(format!("{text:?}: {}", e.render(&text))))?;
        prop_assert!(parsed.same_as(&stmt), "{:?}", text);
        if !stmt.else_ifs.is_empty() {
            prop_assert!(cond::parse(&text).is_err(), "chain accepted without else-if: {:?}", text);
        }
    }

    #[test]
    fn random_bytes_never_panic(bytes in proptest::collection::vec(any::<u8>(), 0..48)) {
        let text = String::from_utf8_lossy(&bytes).into_owned();
        check_any_input(&text)?;
    }

    #[test]
    fn random_token_soup_never_panics(words in proptest::collection::vec(
        proptest::sample::select(vec![
            "connect", "ignore", "set", "copy", "if", "else", "is", "is not", "connected",
            "and", "or", "(", ")", "==", "!=", "<", ">=", "x", "y[1]", "1", "-.5", "'a'",
            "\"b\\\"\"", "=", "!", "'", "\r", "\t", "not", "é",
        ]), 0..12),
        glue in proptest::collection::vec(prop_oneof![Just(" "), Just(""), Just("  ")], 12)
    ) {
        let mut text = String::new();
        for (i, w) in words.iter().enumerate() {
            text.push_str(w);
            text.push_str(glue[i]);
        }
        check_any_input(&text)?;
    }
}

/// Whatever the input: no panic; errors point inside the text at a character boundary and
/// render; successes print to text that parses back to the same statement and evaluate.
fn check_any_input(text: &str) -> Result<(), TestCaseError> {
    for ext in [Extensions::none(), Extensions::all()] {
        match cond::parse_with(text, &ext) {
            Err(e) => {
                prop_assert!(e.span.start <= e.span.end && e.span.end <= text.len());
                prop_assert!(text.is_char_boundary(e.span.start));
                prop_assert!(text.is_char_boundary(e.span.end));
                prop_assert!(!e.message.is_empty() && !e.expected.is_empty());
                let _ = e.render(text);
                let _ = e.to_diagnostic(text).render_human();
            }
            Ok(stmt) => {
                let printed = stmt.to_string();
                let again = cond::parse_with(&printed, &ext)
                    .map_err(|e| TestCaseError::fail(format!("{printed:?}: {e}")))?;
                prop_assert!(again.same_as(&stmt), "{:?} -> {:?}", text, printed);
                let _ = cond::dump(&stmt);
                let up = MapUpstream::new()
                    .input("x", Some(Value::Int(1)))
                    .set("y", Value::Str("a".into()));
                let ev = cond::evaluate(&stmt, &up, &ext);
                for r in &ev.reports {
                    prop_assert!(r.span.end <= text.len());
                    let _ = r.to_diagnostic(text);
                }
            }
        }
    }
    Ok(())
}

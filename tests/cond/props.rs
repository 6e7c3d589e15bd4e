//! Property tests: random ASTs round-trip through print/parse; random input never panics.

use proptest::prelude::*;
use vstructc::cond::{
    self, Action, ActionKind, CmpOp, ComparisonReport, ElseIf, Expr, Extension, Extensions, IsTest,
    Literal, MapUpstream, Param, Statement, internals::quote_for,
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
                let _ = stmt.dump();
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

/// The binary tree of the grammar (`expr 'AND' expr`, left-associative), which is how the
/// parser stored chains before they became n-ary nodes: the reference that the n-ary form
/// must agree with, in evaluation (value, short-circuit and reports) and in printing.
#[derive(Debug, Clone)]
enum Tree {
    Pred(Expr),
    And(Box<Tree>, Box<Tree>),
    Or(Box<Tree>, Box<Tree>),
}

impl Tree {
    /// The n-ary expression, built with the public constructors.
    fn to_expr(&self) -> Expr {
        match self {
            Tree::Pred(e) => e.clone(),
            Tree::And(l, r) => Expr::and(l.to_expr(), r.to_expr()),
            Tree::Or(l, r) => Expr::or(l.to_expr(), r.to_expr()),
        }
    }

    /// Straightforward recursive evaluation; predicates go through the library one at a time.
    fn eval(
        &self,
        up: &MapUpstream,
        ext: &Extensions,
        reports: &mut Vec<ComparisonReport>,
    ) -> bool {
        match self {
            Tree::Pred(e) => cond::internals::evaluate_expr(e, up, ext, reports),
            Tree::And(l, r) => l.eval(up, ext, reports) && r.eval(up, ext, reports),
            Tree::Or(l, r) => l.eval(up, ext, reports) || r.eval(up, ext, reports),
        }
    }

    fn precedence(&self) -> u8 {
        match self {
            Tree::Or(..) => 1,
            Tree::And(..) => 2,
            Tree::Pred(_) => 3,
        }
    }

    /// The printing rule of spec §3.2 for a binary tree: a left operand may be the same
    /// operator unparenthesised, a right operand must bind strictly tighter.
    fn print(&self) -> String {
        let operand = |t: &Tree, min: u8| {
            if t.precedence() < min {
                format!("({})", t.print())
            } else {
                t.print()
            }
        };
        match self {
            Tree::Pred(e) => e.to_string(),
            Tree::And(l, r) => format!("{} and {}", operand(l, 2), operand(r, 3)),
            Tree::Or(l, r) => format!("{} or {}", operand(l, 1), operand(r, 2)),
        }
    }
}

/// Predicates over a small pool of names whose upstream states cover true, false and every
/// kind of VS015 report.
fn pooled_predicate() -> impl Strategy<Value = Expr> {
    let name = proptest::sample::select(vec!["p", "q", "r", "s", "missing"]);
    let lit = prop_oneof![
        Just(Literal::number("0", 0..0).unwrap()),
        Just(Literal::number("1", 0..0).unwrap()),
        Just(Literal::string("a", 0..0)),
    ];
    prop_oneof![
        (
            name.clone(),
            proptest::sample::select(CmpOp::ALL.to_vec()),
            lit
        )
            .prop_map(|(n, op, l)| Expr::cmp(Param::new(n, 0..0), op, l, 0..0)),
        (
            name,
            prop_oneof![Just(IsTest::Connected), Just(IsTest::Set)],
            any::<bool>()
        )
            .prop_map(|(n, t, neg)| Expr::is(Param::new(n, 0..0), t, neg, 0..0)),
    ]
}

fn tree() -> impl Strategy<Value = Tree> {
    let leaf = pooled_predicate().prop_map(Tree::Pred);
    let nested = leaf.prop_recursive(6, 64, 2, |inner| {
        prop_oneof![
            (inner.clone(), inner.clone()).prop_map(|(a, b)| Tree::And(Box::new(a), Box::new(b))),
            (inner.clone(), inner).prop_map(|(a, b)| Tree::Or(Box::new(a), Box::new(b))),
        ]
    });
    // Long left-associative chains of random subtrees and operators, as real text makes.
    let chains =
        proptest::collection::vec((any::<bool>(), nested.clone()), 1..40).prop_map(|items| {
            let mut it = items.into_iter();
            let (_, first) = it.next().expect("at least one item");
            it.fold(first, |acc, (is_and, t)| {
                if is_and {
                    Tree::And(Box::new(acc), Box::new(t))
                } else {
                    Tree::Or(Box::new(acc), Box::new(t))
                }
            })
        });
    prop_oneof![nested, chains]
}

fn pool_upstream() -> MapUpstream {
    MapUpstream::new()
        .input("p", Some(Value::Int(1)))
        .set("q", Value::Str("a".into()))
        .input("r", None)
        .input("s", Some(Value::Float(0.0)))
        .connect("s")
}

/// No `and` node starts with an `and` node (nor `or` with `or`), and every node has at
/// least two terms: a chain is one node.
fn chains_are_flat(e: &Expr) -> bool {
    use cond::ExprKind;
    let terms = e.terms();
    let first_same = matches!(
        (&e.kind, terms.first().map(|t| &t.kind)),
        (ExprKind::And { .. }, Some(ExprKind::And { .. }))
            | (ExprKind::Or { .. }, Some(ExprKind::Or { .. }))
    );
    let is_chain = matches!(e.kind, ExprKind::And { .. } | ExprKind::Or { .. });
    !first_same && (!is_chain || terms.len() >= 2) && terms.iter().all(chains_are_flat)
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(512))]

    #[test]
    fn n_ary_chains_agree_with_the_binary_reference(t in tree(), strict_ne in any::<bool>()) {
        let ext = if strict_ne {
            Extensions::none().with(Extension::StrictNe)
        } else {
            Extensions::none()
        };
        let up = pool_upstream();
        let mut want_reports = Vec::new();
        let want = t.eval(&up, &ext, &mut want_reports);
        let text = t.print();

        let built = t.to_expr();
        prop_assert!(chains_are_flat(&built));
        prop_assert_eq!(built.to_string(), text.clone());
        let mut got_reports = Vec::new();
        prop_assert_eq!(cond::internals::evaluate_expr(&built, &up, &ext, &mut got_reports), want);
        prop_assert_eq!(&got_reports, &want_reports);

        // The parsed text: the same tree (modulo spans), the same decision and reports
        // (report spans now point into the text, so compare the rest).
        let stmt = cond::parse(&format!("connect if {text}"))
            .map_err(|e| TestCaseError::fail(format!("{text:?}: {e}")))?;
        let parsed = stmt.condition.clone().expect("a condition");
        prop_assert!(chains_are_flat(&parsed));
        let rebuilt = Statement { condition: Some(built), ..stmt.clone() };
        prop_assert!(stmt.same_as(&rebuilt), "{:?}", text);
        let ev = cond::evaluate(&stmt, &up, &ext);
        prop_assert_eq!(ev.choice == cond::Choice::Condition, want);
        let strip = |r: &[ComparisonReport]| -> Vec<(String, CmpOp, String, bool)> {
            r.iter().map(|r| (r.param.clone(), r.op, r.literal.clone(), r.result)).collect()
        };
        prop_assert_eq!(strip(&ev.reports), strip(&want_reports));
        for r in &ev.reports {
            prop_assert_eq!(&text[r.span.start - "connect if ".len()..r.span.end - "connect if ".len()],
                format!("{} {} {}", r.param, r.op, r.literal));
        }
    }
}

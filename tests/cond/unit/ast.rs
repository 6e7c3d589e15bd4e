//! Unit tests of `cond::ast` (`src/cond/ast.rs`).

use vstructc::cond::internals::*;
use vstructc::cond::*;

#[test]
fn split_index_needs_a_whole_suffix() {
    assert_eq!(split_index("arr[2]"), Some(("arr", 2)));
    assert_eq!(split_index("arr"), None);
    assert_eq!(split_index("arr[x]"), None);
    assert_eq!(split_index("a[99999999999999999999999]"), None);
}

#[test]
fn quote_choice_keeps_content_verbatim() {
    assert_eq!(quote_for("abc"), Some('"'));
    assert_eq!(quote_for("a\"b"), Some('\''));
    assert_eq!(quote_for("a\\\"b"), Some('"'));
    assert_eq!(quote_for("it's \"x\""), None);
    assert_eq!(quote_for("a\\"), None);
    assert_eq!(quote_for("a\\\nb"), None);
}

fn p(name: &str) -> Param {
    Param::new(name, 0..0)
}

fn num(text: &str) -> Literal {
    Literal::number(text, 0..0).unwrap()
}

#[test]
fn display_parenthesises_minimally() {
    let a = Expr::cmp(p("a"), CmpOp::Eq, num("1"), 0..0);
    let b = Expr::is(p("b"), IsTest::Set, true, 0..0);
    let c = Expr::cmp(p("c"), CmpOp::Ge, Literal::string("x", 0..0), 0..0);
    let or_ab = Expr::or(a.clone(), b.clone());
    assert_eq!(
        Expr::and(or_ab.clone(), c.clone()).to_string(),
        "(a == 1 or b is not set) and c >= \"x\""
    );
    assert_eq!(
        Expr::or(a.clone(), Expr::and(b.clone(), c.clone())).to_string(),
        "a == 1 or b is not set and c >= \"x\""
    );
    assert_eq!(
        Expr::or(or_ab.clone(), c.clone()).to_string(),
        "a == 1 or b is not set or c >= \"x\""
    );
    assert_eq!(
        Expr::or(c.clone(), or_ab).to_string(),
        "c >= \"x\" or (a == 1 or b is not set)"
    );
    let and_ab = Expr::and(a, b);
    assert_eq!(
        Expr::and(c, and_ab).to_string(),
        "c >= \"x\" and (a == 1 and b is not set)"
    );
}

//! The AST of a desugared statement.
//!
//! Every node carries its byte span in the expression text. Actions that the desugaring table
//! supplies without them being written (the `ignore` of `connect if C`, the `connect` of
//! `ignore if C` and of `if C else B`, the final `ignore` of an `else-if` chain that ends in
//! `… if C`) have an **empty** span at the point where they are implied; see
//! [`Action::is_implied`].
//!
//! `Display` prints the canonical desugared form, which parses back to the same AST modulo
//! spans ([`Statement::same_as`]): conditional statements always with an explicit `else`,
//! expressions with the fewest parentheses that keep the tree (`and` binds tighter than `or`;
//! both are left-associative, so a right operand of the same operator is parenthesised),
//! numbers as originally written, strings between `"` unless their verbatim content needs `'`.
//!
//! `and`/`or` nodes are n-ary ([`ExprKind::And`]): a chain of a million terms is one node, so
//! the depth of a parsed expression grows only with its parentheses, which the parser bounds
//! ([`super::parser::MAX_PAREN_DEPTH`]); every walk over the tree (evaluation, printing,
//! `dump`, serialisation, dropping) therefore recurses at most about twice that deep,
//! whatever the length of the text.

use super::lexer::CmpOp;
use std::fmt;
use std::ops::Range;

/// A byte span in the expression text.
pub(crate) type Span = Range<usize>;

/// A parameter name as written, with its span. Names of predicates may be keywords
/// (`connect == 1`); names may carry an array suffix (`arr[2]`).
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Param {
    /// The name, verbatim (including an array suffix).
    pub name: String,
    /// Span of the name token.
    pub span: Span,
}

impl Param {
    /// A name with the given span.
    pub fn new(name: impl Into<String>, span: Span) -> Self {
        Param {
            name: name.into(),
            span,
        }
    }

    /// `(base, index)` if the name has an array suffix such as `arr[2]`. Indices too large
    /// for `usize` give `None`.
    pub fn array_index(&self) -> Option<(&str, usize)> {
        split_index(&self.name)
    }
}

/// `(base, index)` for a name of the form `base[digits]`.
#[cfg_attr(feature = "testkit", visibility::make(pub))]
pub(crate) fn split_index(name: &str) -> Option<(&str, usize)> {
    let inner = name.strip_suffix(']')?;
    let open = inner.find('[')?;
    let index = inner[open + 1..].parse().ok()?;
    Some((&inner[..open], index))
}

/// A literal: a number (value and original text) or a string (verbatim content).
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
#[serde(tag = "type", rename_all = "lowercase")]
pub enum LiteralKind {
    /// A `NUMBER`: its value (round-to-nearest decimal conversion) and its text as written.
    Number {
        /// The value.
        value: f64,
        /// The text as written (`-.5e-1`, `007`).
        text: String,
    },
    /// A `STRING`: the verbatim content between the quotes (escapes not decoded).
    #[serde(rename = "string")]
    Str {
        /// The content.
        value: String,
    },
}

/// A literal with its span (including quotes for strings).
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Literal {
    /// Number or string.
    #[serde(flatten)]
    pub kind: LiteralKind,
    /// Span of the literal token.
    pub span: Span,
}

impl Literal {
    /// A number literal from its text; `None` if `text` is not a valid decimal number.
    pub fn number(text: &str, span: Span) -> Option<Self> {
        let value = text.parse::<f64>().ok()?;
        Some(Literal {
            kind: LiteralKind::Number {
                value,
                text: text.to_string(),
            },
            span,
        })
    }

    /// A string literal with verbatim `content`.
    pub fn string(content: impl Into<String>, span: Span) -> Self {
        Literal {
            kind: LiteralKind::Str {
                value: content.into(),
            },
            span,
        }
    }

    /// The numeric value of a number literal.
    pub fn as_number(&self) -> Option<f64> {
        match &self.kind {
            LiteralKind::Number { value, .. } => Some(*value),
            LiteralKind::Str { .. } => None,
        }
    }

    /// The content of a string literal.
    pub fn as_str(&self) -> Option<&str> {
        match &self.kind {
            LiteralKind::Str { value } => Some(value),
            LiteralKind::Number { .. } => None,
        }
    }

    /// The token name used in messages: `NUMBER` or `STRING`.
    pub fn token_name(&self) -> &'static str {
        match self.kind {
            LiteralKind::Number { .. } => "NUMBER",
            LiteralKind::Str { .. } => "STRING",
        }
    }
}

/// Which of the quote characters can delimit `content` so that it lexes back verbatim:
/// `"` preferred, else `'`; `None` if neither can (not produced by the parser).
pub fn quote_for(content: &str) -> Option<char> {
    ['"', '\''].into_iter().find(|&q| delimits(content, q))
}

/// True if `q content q` is one `STRING` token whose content is `content`.
fn delimits(content: &str, q: char) -> bool {
    let mut chars = content.chars();
    while let Some(c) = chars.next() {
        if c == q {
            return false;
        }
        if c == '\\' {
            match chars.next() {
                Some('\n') | None => return false,
                Some(_) => {}
            }
        }
    }
    true
}

impl fmt::Display for Literal {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match &self.kind {
            LiteralKind::Number { text, .. } => f.write_str(text),
            LiteralKind::Str { value } => {
                let q = quote_for(value).unwrap_or('"');
                write!(f, "{q}{value}{q}")
            }
        }
    }
}

/// What an action does.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
#[serde(tag = "action", rename_all = "lowercase")]
pub enum ActionKind {
    /// Connect D.M to U.P.
    Connect,
    /// Leave D.M alone.
    Ignore,
    /// Write a literal to D.M (typed by D.M's declared type, the same rules as `set` in the language reference).
    Set {
        /// The literal (number with its text, or verbatim string).
        literal: Literal,
    },
    /// Copy U's input `param` to D.M (typed as the language reference's `copy` rules say).
    Copy {
        /// The parameter of U to copy.
        param: Param,
    },
}

/// An action with its span (empty when implied by desugaring).
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Action {
    /// What it does.
    #[serde(flatten)]
    pub kind: ActionKind,
    /// Span of the written action; empty (`n..n`) for an implied one.
    pub span: Span,
}

impl Action {
    /// An action with a span.
    pub fn new(kind: ActionKind, span: Span) -> Self {
        Action { kind, span }
    }

    /// True if the desugaring supplied this action (it is not written in the text).
    pub fn is_implied(&self) -> bool {
        self.span.is_empty()
    }

    /// The short name: `connect`, `ignore`, `set`, `copy`.
    pub fn name(&self) -> &'static str {
        match self.kind {
            ActionKind::Connect => "connect",
            ActionKind::Ignore => "ignore",
            ActionKind::Set { .. } => "set",
            ActionKind::Copy { .. } => "copy",
        }
    }
}

impl fmt::Display for Action {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match &self.kind {
            ActionKind::Connect => f.write_str("connect"),
            ActionKind::Ignore => f.write_str("ignore"),
            ActionKind::Set { literal } => write!(f, "set {literal}"),
            ActionKind::Copy { param } => write!(f, "copy {}", param.name),
        }
    }
}

/// Whether an `is` predicate tests connection or authored value.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum IsTest {
    /// `is [not] connected`
    Connected,
    /// `is [not] set`
    Set,
}

/// An expression node.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
#[serde(tag = "expr", rename_all = "lowercase")]
pub enum ExprKind {
    /// `param OP literal`
    Cmp {
        /// The parameter of U.
        param: Param,
        /// The operator.
        op: CmpOp,
        /// The literal on the right.
        value: Literal,
    },
    /// `param is [not] connected` / `param is [not] set`
    Is {
        /// The parameter of U.
        param: Param,
        /// Connected or set.
        test: IsTest,
        /// True for `is not`.
        negated: bool,
    },
    /// `t1 and t2 and … tn`: true when every term is, evaluated left to right.
    ///
    /// A left-associative chain is one node: `a and b and c` (and `(a and b) and c`, which
    /// means the same) has three terms. A term is an `and` node only when it was
    /// parenthesised on the right (`a and (b and c)`), never the first term. The parser
    /// always produces at least two terms; see [`Expr::and`].
    And {
        /// The operands, in evaluation order.
        terms: Vec<Expr>,
    },
    /// `t1 or t2 or … tn`: true when some term is, evaluated left to right (same shape
    /// rules as [`ExprKind::And`]).
    Or {
        /// The operands, in evaluation order.
        terms: Vec<Expr>,
    },
}

/// An expression with its span. The span of a predicate covers the predicate's tokens; the
/// span of `and`/`or` covers both operands including any parentheses around them.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Expr {
    /// The node.
    #[serde(flatten)]
    pub kind: ExprKind,
    /// Span in the expression text.
    pub span: Span,
}

impl Expr {
    /// `param OP literal`.
    pub fn cmp(param: Param, op: CmpOp, value: Literal, span: Span) -> Self {
        Expr {
            kind: ExprKind::Cmp { param, op, value },
            span,
        }
    }

    /// `param is [not] connected|set`.
    pub fn is(param: Param, test: IsTest, negated: bool, span: Span) -> Self {
        Expr {
            kind: ExprKind::Is {
                param,
                test,
                negated,
            },
            span,
        }
    }

    /// `left and right`, spanning both. A `left` that is itself an `and` node is extended
    /// (left associativity: `(a and b) and c` is the chain `a and b and c`), so a chain of n
    /// terms built from the left is one node with n terms, not a tree n levels deep.
    pub fn and(left: Expr, right: Expr) -> Self {
        Self::chain(left, right, true)
    }

    /// `left or right`, spanning both; extends a `left` that is an `or` node (see
    /// [`Expr::and`]).
    pub fn or(left: Expr, right: Expr) -> Self {
        Self::chain(left, right, false)
    }

    fn chain(left: Expr, right: Expr, is_and: bool) -> Self {
        let span = left.span.start..right.span.end;
        let kind = match (left.kind, is_and) {
            (ExprKind::And { mut terms }, true) => {
                terms.push(right);
                ExprKind::And { terms }
            }
            (ExprKind::Or { mut terms }, false) => {
                terms.push(right);
                ExprKind::Or { terms }
            }
            (kind, _) => {
                let left = Expr {
                    kind,
                    span: left.span,
                };
                if is_and {
                    ExprKind::And {
                        terms: vec![left, right],
                    }
                } else {
                    ExprKind::Or {
                        terms: vec![left, right],
                    }
                }
            }
        };
        Expr { kind, span }
    }

    /// The operands of an `and`/`or` node (empty for a predicate).
    pub fn terms(&self) -> &[Expr] {
        match &self.kind {
            ExprKind::And { terms } | ExprKind::Or { terms } => terms,
            ExprKind::Cmp { .. } | ExprKind::Is { .. } => &[],
        }
    }

    /// The parameter of a predicate (`None` for `and`/`or`).
    pub fn param(&self) -> Option<&Param> {
        match &self.kind {
            ExprKind::Cmp { param, .. } | ExprKind::Is { param, .. } => Some(param),
            _ => None,
        }
    }

    /// Every predicate's parameter, left to right.
    pub fn params(&self) -> Vec<&Param> {
        let mut out = Vec::new();
        self.collect_params(&mut out);
        out
    }

    fn collect_params<'a>(&'a self, out: &mut Vec<&'a Param>) {
        match &self.kind {
            ExprKind::Cmp { param, .. } | ExprKind::Is { param, .. } => out.push(param),
            ExprKind::And { terms } | ExprKind::Or { terms } => {
                for t in terms {
                    t.collect_params(out);
                }
            }
        }
    }

    /// Binding strength for printing: `or` 1, `and` 2, predicates 3.
    fn precedence(&self) -> u8 {
        match self.kind {
            ExprKind::Or { .. } => 1,
            ExprKind::And { .. } => 2,
            _ => 3,
        }
    }

    fn fmt_operand(&self, f: &mut fmt::Formatter<'_>, min: u8) -> fmt::Result {
        if self.precedence() < min {
            write!(f, "({self})")
        } else {
            write!(f, "{self}")
        }
    }
}

impl fmt::Display for Expr {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match &self.kind {
            ExprKind::Cmp { param, op, value } => write!(f, "{} {op} {value}", param.name),
            ExprKind::Is {
                param,
                test,
                negated,
            } => {
                let not = if *negated { " not" } else { "" };
                let what = match test {
                    IsTest::Connected => "connected",
                    IsTest::Set => "set",
                };
                write!(f, "{} is{not} {what}", param.name)
            }
            ExprKind::And { terms } => fmt_chain(f, terms, " and ", 2),
            ExprKind::Or { terms } => fmt_chain(f, terms, " or ", 1),
        }
    }
}

/// The terms of a chain of binding strength `prec`, joined by `sep`. Left-associative: the
/// first term may be the same operator unparenthesised (it never is in a parsed tree), later
/// terms must bind strictly tighter.
fn fmt_chain(f: &mut fmt::Formatter<'_>, terms: &[Expr], sep: &str, prec: u8) -> fmt::Result {
    for (i, t) in terms.iter().enumerate() {
        if i == 0 {
            t.fmt_operand(f, prec)?;
        } else {
            f.write_str(sep)?;
            t.fmt_operand(f, prec + 1)?;
        }
    }
    Ok(())
}

/// One `else B if C` link of an `else-if` chain (extension `else-if`).
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct ElseIf {
    /// The action chosen when `condition` is the first true condition.
    pub action: Action,
    /// The condition.
    pub condition: Expr,
}

/// A desugared statement `(action, condition?, fallback)`.
///
/// Invariant: `fallback` is `Some` exactly when `condition` is `Some`; `else_ifs` is empty
/// unless the statement was parsed with the `else-if` extension, and then `condition` is
/// `Some`. Evaluation: the first true condition among `condition`, `else_ifs[0].condition`, …
/// selects its action; if none is true, `fallback` applies.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Statement {
    /// The action chosen when there is no condition or the condition is true.
    pub action: Action,
    /// The condition, if any.
    pub condition: Option<Expr>,
    /// Further `else A if C` links (extension `else-if`; empty in compat mode).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub else_ifs: Vec<ElseIf>,
    /// The action chosen when every condition is false.
    pub fallback: Option<Action>,
    /// Span of the whole statement (first to last token).
    pub span: Span,
}

impl Statement {
    /// Every parameter name the statement reads, distinct, in source order (predicates and
    /// `copy`, including `else-if` links and the fallback).
    pub fn param_names(&self) -> Vec<&str> {
        // A set, not a scan of `names`: a chain may name a million distinct parameters.
        let mut seen = std::collections::HashSet::new();
        self.params()
            .into_iter()
            .map(|p| p.name.as_str())
            .filter(|name| seen.insert(*name))
            .collect()
    }

    /// Every parameter occurrence (predicates and `copy`), in source order.
    pub fn params(&self) -> Vec<&Param> {
        fn action_param(a: &Action) -> Option<&Param> {
            match &a.kind {
                ActionKind::Copy { param } => Some(param),
                _ => None,
            }
        }
        let mut out = Vec::new();
        out.extend(action_param(&self.action));
        if let Some(c) = &self.condition {
            out.extend(c.params());
        }
        for link in &self.else_ifs {
            out.extend(action_param(&link.action));
            out.extend(link.condition.params());
        }
        if let Some(fb) = &self.fallback {
            out.extend(action_param(fb));
        }
        out
    }

    /// Every action the statement can choose, in order: action, `else-if` actions, fallback.
    pub fn actions(&self) -> Vec<&Action> {
        let mut out = vec![&self.action];
        out.extend(self.else_ifs.iter().map(|l| &l.action));
        out.extend(self.fallback.iter());
        out
    }

    /// True if the statement has a condition (it is not a bare action).
    pub fn is_conditional(&self) -> bool {
        self.condition.is_some()
    }

    /// A copy with every span set to `0..0`.
    pub fn without_spans(&self) -> Statement {
        let mut s = self.clone();
        s.clear_spans();
        s
    }

    /// Structural equality ignoring spans (the round-trip equality of `parse(print(ast))`).
    pub fn same_as(&self, other: &Statement) -> bool {
        self.without_spans() == other.without_spans()
    }

    fn clear_spans(&mut self) {
        self.span = 0..0;
        clear_action(&mut self.action);
        if let Some(c) = &mut self.condition {
            clear_expr(c);
        }
        for link in &mut self.else_ifs {
            clear_action(&mut link.action);
            clear_expr(&mut link.condition);
        }
        if let Some(fb) = &mut self.fallback {
            clear_action(fb);
        }
    }
}

fn clear_action(a: &mut Action) {
    a.span = 0..0;
    match &mut a.kind {
        ActionKind::Set { literal } => literal.span = 0..0,
        ActionKind::Copy { param } => param.span = 0..0,
        ActionKind::Connect | ActionKind::Ignore => {}
    }
}

fn clear_expr(e: &mut Expr) {
    e.span = 0..0;
    match &mut e.kind {
        ExprKind::Cmp { param, value, .. } => {
            param.span = 0..0;
            value.span = 0..0;
        }
        ExprKind::Is { param, .. } => param.span = 0..0,
        ExprKind::And { terms } | ExprKind::Or { terms } => terms.iter_mut().for_each(clear_expr),
    }
}

impl fmt::Display for Statement {
    /// The canonical desugared form: `A`, or `A if C else F`, or with `else-if` links
    /// `A if C1 else B if C2 else F`.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", self.action)?;
        let Some(c) = &self.condition else {
            return Ok(());
        };
        write!(f, " if {c}")?;
        for link in &self.else_ifs {
            write!(f, " else {} if {}", link.action, link.condition)?;
        }
        if let Some(fb) = &self.fallback {
            write!(f, " else {fb}")?;
        }
        Ok(())
    }
}

impl Statement {
    /// An indented, line-per-node dump of the statement with spans, used by `vstructc expr`
    /// and the snapshot tests.
    pub fn dump(&self) -> String {
        dump(self)
    }
}

fn dump(stmt: &Statement) -> String {
    let mut out = String::new();
    line(&mut out, 0, &format!("Statement {}", span_text(&stmt.span)));
    dump_action(&mut out, 1, "action", &stmt.action);
    match &stmt.condition {
        Some(c) => {
            line(&mut out, 1, "condition:");
            dump_expr(&mut out, 2, c);
        }
        None => line(&mut out, 1, "condition: none (always the action)"),
    }
    for (i, link) in stmt.else_ifs.iter().enumerate() {
        line(&mut out, 1, &format!("else-if #{}:", i + 1));
        dump_action(&mut out, 2, "action", &link.action);
        line(&mut out, 2, "condition:");
        dump_expr(&mut out, 3, &link.condition);
    }
    match &stmt.fallback {
        Some(fb) => dump_action(&mut out, 1, "fallback", fb),
        None => line(&mut out, 1, "fallback: none"),
    }
    out
}

fn span_text(span: &Span) -> String {
    format!("@{}..{}", span.start, span.end)
}

fn line(out: &mut String, depth: usize, text: &str) {
    for _ in 0..depth {
        out.push_str("  ");
    }
    out.push_str(text);
    out.push('\n');
}

fn literal_text(lit: &Literal) -> String {
    match &lit.kind {
        LiteralKind::Number { value, text } => format!("NUMBER {value:?} (written {text})"),
        LiteralKind::Str { value } => {
            format!("STRING {value:?} ({} chars)", value.chars().count())
        }
    }
}

fn dump_action(out: &mut String, depth: usize, role: &str, a: &Action) {
    let where_ = if a.is_implied() {
        format!("(implied at {})", a.span.start)
    } else {
        span_text(&a.span)
    };
    let body = match &a.kind {
        ActionKind::Connect => "Connect".to_string(),
        ActionKind::Ignore => "Ignore".to_string(),
        ActionKind::Set { literal } => format!("Set {}", literal_text(literal)),
        ActionKind::Copy { param } => {
            format!("Copy {:?} (name {})", param.name, span_text(&param.span))
        }
    };
    line(out, depth, &format!("{role}: {body} {where_}"));
}

fn dump_expr(out: &mut String, depth: usize, e: &Expr) {
    let at = span_text(&e.span);
    match &e.kind {
        ExprKind::Cmp { param, op, value } => line(
            out,
            depth,
            &format!("Cmp {at}: {:?} {op} {}", param.name, literal_text(value)),
        ),
        ExprKind::Is {
            param,
            test,
            negated,
        } => {
            let name = match (test, negated) {
                (IsTest::Connected, false) => "IsConnected",
                (IsTest::Connected, true) => "IsNotConnected",
                (IsTest::Set, false) => "IsSet",
                (IsTest::Set, true) => "IsNotSet",
            };
            line(out, depth, &format!("{name} {at}: {:?}", param.name));
        }
        ExprKind::And { terms } | ExprKind::Or { terms } => {
            let name = if matches!(e.kind, ExprKind::And { .. }) {
                "And"
            } else {
                "Or"
            };
            line(out, depth, &format!("{name} {at}"));
            for t in terms {
                dump_expr(out, depth + 1, t);
            }
        }
    }
}

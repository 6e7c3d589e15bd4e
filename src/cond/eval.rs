//! Evaluation of a statement against the upstream node U.
//!
//! The evaluator only *decides*: it returns the chosen [`Action`] and the VS015 reports of
//! the comparisons that were false for a reason other than a genuine value mismatch. Writing
//! the result to D.M is the resolver's job (with [`super::action::set_value`] and
//! [`super::action::copy_value`] for the typing rules).

use super::ast::{
    Action, ActionKind, Expr, ExprKind, IsTest, Literal, LiteralKind, Param, Span, Statement,
};
use super::ext::{Extension, Extensions};
use super::lexer::CmpOp;
use crate::diag::Diagnostic;
use crate::types::Value;
use std::borrow::Cow;
use std::cmp::Ordering;
use std::fmt;

/// What the evaluator needs to know about the upstream node U, in its **current** state
/// (including values written and members connected earlier in the same resolution).
pub trait Upstream {
    /// U's authored value for `param`, if any (values written by `set`/`copy` count).
    fn authored(&self, param: &str) -> Option<&Value>;

    /// True if U's definition declares an **input** named `param` (outputs do not count).
    fn declares_input(&self, param: &str) -> bool;

    /// The definition default of U's input `param` (absent for struct/vstruct inputs, or
    /// when the input is not declared).
    fn default_value(&self, param: &str) -> Option<&Value>;

    /// True if U's input `param` has at least one incoming connection now.
    fn is_connected(&self, param: &str) -> bool;

    /// The comparison operand: the authored value, else the default of a declared
    /// input, else `None`. The default implementation combines [`Upstream::authored`],
    /// [`Upstream::declares_input`] and [`Upstream::default_value`]; implementations that can
    /// answer with fewer look-ups should override it.
    fn operand(&self, param: &str) -> Option<&Value> {
        self.authored(param).or_else(|| {
            if self.declares_input(param) {
                self.default_value(param)
            } else {
                None
            }
        })
    }

    /// Extension `array-index`: element `index` of the array parameter `param` — of its
    /// authored value, else of its default. `None` when there is no such array value or the
    /// index is out of range. The default implementation reads [`Value::Array`] values
    /// through [`Upstream::authored`] and [`Upstream::default_value`].
    fn element(&self, param: &str, index: usize) -> Option<Value> {
        match self.operand(param)? {
            Value::Array(_, items) => items.get(index).cloned(),
            _ => None,
        }
    }

    /// Extension `array-index`: true if element `index` of `param` has a connection. The
    /// default implementation answers for the whole parameter ([`Upstream::is_connected`]);
    /// implementations that track element connections should override it.
    fn is_element_connected(&self, param: &str, index: usize) -> bool {
        let _ = index;
        self.is_connected(param)
    }
}

/// Which part of the statement chose the action.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Choice {
    /// The statement has no condition.
    Unconditional,
    /// The (first) condition was true.
    Condition,
    /// The condition of `else_ifs[i]` was the first true one (extension `else-if`).
    ElseIf(usize),
    /// Every condition was false.
    Fallback,
}

/// Why a comparison was false without a genuine value mismatch (VS015).
#[derive(Debug, Clone, PartialEq, Eq, serde::Serialize)]
#[serde(tag = "reason", rename_all = "kebab-case")]
pub enum FalseReason {
    /// U has neither an authored value for the parameter nor an input of that name.
    NoInput,
    /// The input is declared but has no authored value and no default.
    NoValue,
    /// Extension `array-index`: the array has no element at this index.
    NoElement {
        /// The index asked for.
        index: usize,
    },
    /// The operand's type cannot be compared with this literal.
    TypeMismatch {
        /// The operand's type (`color`, `string`, `float[2]`, …).
        operand: String,
        /// The literal's token name (`NUMBER` or `STRING`).
        literal: &'static str,
    },
    /// A string literal against a token or asset operand (see extension `token-strings`).
    TokenOperand {
        /// `token` or `asset`.
        operand: &'static str,
    },
    /// `<`, `>`, `<=`, `>=` with a string literal.
    StringOrdering,
}

/// One VS015 report: a comparison decided by a "false" rule of the comparison table.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct ComparisonReport {
    /// Span of the predicate in the expression.
    pub span: Span,
    /// The parameter of U.
    pub param: String,
    /// The operator.
    pub op: CmpOp,
    /// The literal as printed (`1`, `"abc"`).
    pub literal: String,
    /// Why it was false.
    #[serde(flatten)]
    pub reason: FalseReason,
    /// The value the comparison produced: `false`, except `!=` under `strict-ne` (`true`).
    pub result: bool,
}

impl ComparisonReport {
    /// The stable code.
    pub const CODE: &'static str = "VS015";

    /// A one-line explanation (without node names; the resolver adds `D.M ← U.P`).
    pub fn message(&self) -> String {
        let cmp = format!("`{} {} {}`", self.param, self.op, self.literal);
        let verdict = if self.result {
            "is true (strict-ne)"
        } else {
            "is false"
        };
        let p = &self.param;
        let why = match &self.reason {
            FalseReason::NoInput => format!("the upstream node has no input `{p}`"),
            FalseReason::NoValue => {
                format!("`{p}` has no authored value and its definition gives no default")
            }
            FalseReason::NoElement { index } => {
                format!("the array has no element {index} (extension array-index)")
            }
            FalseReason::TypeMismatch { operand, literal } => {
                format!("`{p}` is a {operand}, which is never compared with a {literal}")
            }
            FalseReason::TokenOperand { operand } => format!(
                "`{p}` is a {operand}; string literals compare only with `string` parameters \
                 (see --ext token-strings)"
            ),
            FalseReason::StringOrdering => {
                "ordering operators are always false on strings".to_string()
            }
        };
        format!("comparison {cmp} {verdict} because {why}")
    }

    /// A VS015 warning with the predicate span and a caret rendering of `text` (the
    /// statement's expression text). The caller adds the location and node names.
    pub fn to_diagnostic(&self, text: &str) -> Diagnostic {
        Diagnostic::warning(Self::CODE, self.message())
            .with_span(self.span.clone())
            .with_note(super::error::render_caret(text, self.span.clone()))
    }
}

impl fmt::Display for ComparisonReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.message())
    }
}

/// The result of evaluating a statement.
#[derive(Debug, Clone, PartialEq)]
pub struct Evaluation<'s> {
    /// The chosen action (a reference into the statement).
    pub action: &'s Action,
    /// Which part of the statement chose it.
    pub choice: Choice,
    /// VS015 reports, in evaluation order (predicates not evaluated because of short-circuit
    /// produce none).
    pub reports: Vec<ComparisonReport>,
}

/// Evaluate `stmt` against `upstream`: the statement's action if there is
/// no condition or it is true; with `else-if`, the action of the first true link; otherwise
/// the fallback.
pub fn evaluate<'s, U: Upstream + ?Sized>(
    stmt: &'s Statement,
    upstream: &U,
    ext: &Extensions,
) -> Evaluation<'s> {
    let mut ev = Evaluator {
        u: upstream,
        ext,
        reports: Vec::new(),
    };
    let choice = match &stmt.condition {
        None => Choice::Unconditional,
        Some(c) if ev.expr(c) => Choice::Condition,
        Some(_) => match stmt.else_ifs.iter().position(|l| ev.expr(&l.condition)) {
            Some(i) => Choice::ElseIf(i),
            None => Choice::Fallback,
        },
    };
    Evaluation {
        action: chosen_action(stmt, choice),
        choice,
        reports: ev.reports,
    }
}

/// The action of `stmt` that `choice` names (so a caller may keep the choice, which is
/// `Copy`, instead of the action).
pub(crate) fn chosen_action(stmt: &Statement, choice: Choice) -> &Action {
    match choice {
        Choice::Unconditional | Choice::Condition => &stmt.action,
        Choice::ElseIf(i) => stmt.else_ifs.get(i).map_or(&stmt.action, |l| &l.action),
        Choice::Fallback => match &stmt.fallback {
            Some(fb) => fb,
            // Not produced by the parser (hand-built AST): apply the desugaring of `A if C`.
            None => implied_fallback(&stmt.action),
        },
    }
}

static IMPLIED_IGNORE: Action = Action {
    kind: ActionKind::Ignore,
    span: 0..0,
};
static IMPLIED_CONNECT: Action = Action {
    kind: ActionKind::Connect,
    span: 0..0,
};

/// The fallback the desugaring implies for `A if C`: `connect` for `ignore if C`, else `ignore`.
fn implied_fallback(action: &Action) -> &'static Action {
    match action.kind {
        ActionKind::Ignore => &IMPLIED_CONNECT,
        _ => &IMPLIED_IGNORE,
    }
}

/// Evaluate only an expression (useful to explain a decision); reports are appended to
/// `reports`.
#[cfg(any(test, feature = "testkit"))]
pub fn evaluate_expr<U: Upstream + ?Sized>(
    expr: &Expr,
    upstream: &U,
    ext: &Extensions,
    reports: &mut Vec<ComparisonReport>,
) -> bool {
    let mut ev = Evaluator {
        u: upstream,
        ext,
        reports: Vec::new(),
    };
    let r = ev.expr(expr);
    reports.append(&mut ev.reports);
    r
}

struct Evaluator<'e, U: ?Sized> {
    u: &'e U,
    ext: &'e Extensions,
    reports: Vec<ComparisonReport>,
}

impl<U: Upstream + ?Sized> Evaluator<'_, U> {
    fn expr(&mut self, e: &Expr) -> bool {
        match &e.kind {
            // Short-circuit left to right: the right operand is not evaluated (and reports
            // nothing) when the left decides.
            // A chain is a loop, not a recursion: nesting is bounded by parentheses.
            ExprKind::And { terms } => terms.iter().all(|t| self.expr(t)),
            ExprKind::Or { terms } => terms.iter().any(|t| self.expr(t)),
            ExprKind::Is {
                param,
                test,
                negated,
            } => {
                let yes = match test {
                    IsTest::Connected => self.is_connected(param),
                    IsTest::Set => self.is_set(param),
                };
                yes != *negated
            }
            ExprKind::Cmp { param, op, value } => self.comparison(e, param, *op, value),
        }
    }

    /// `(base, index)` when extension `array-index` applies to this name.
    fn indexed<'p>(&self, param: &'p Param) -> Option<(&'p str, usize)> {
        if self.ext.contains(Extension::ArrayIndex) {
            param.array_index()
        } else {
            None
        }
    }

    fn is_connected(&self, param: &Param) -> bool {
        match self.indexed(param) {
            Some((base, i)) => self.u.is_element_connected(base, i),
            None => self.u.is_connected(&param.name),
        }
    }

    /// `is set`: an authored value now; definition defaults do not count.
    fn is_set(&self, param: &Param) -> bool {
        match self.indexed(param) {
            Some((base, i)) => {
                matches!(self.u.authored(base), Some(Value::Array(_, items)) if i < items.len())
            }
            None => self.u.authored(&param.name).is_some(),
        }
    }

    fn operand(&self, param: &Param) -> Result<Cow<'_, Value>, FalseReason> {
        let missing = |name: &str| {
            if self.u.declares_input(name) || self.u.authored(name).is_some() {
                FalseReason::NoValue
            } else {
                FalseReason::NoInput
            }
        };
        match self.indexed(param) {
            Some((base, index)) => match self.u.element(base, index) {
                Some(v) => Ok(Cow::Owned(v)),
                None => match missing(base) {
                    FalseReason::NoInput => Err(FalseReason::NoInput),
                    _ => Err(FalseReason::NoElement { index }),
                },
            },
            None => self
                .u
                .operand(&param.name)
                .map(Cow::Borrowed)
                .ok_or_else(|| missing(&param.name)),
        }
    }

    fn comparison(&mut self, e: &Expr, param: &Param, op: CmpOp, lit: &Literal) -> bool {
        let decided = self
            .operand(param)
            .and_then(|v| compare(&v, op, lit, self.ext));
        match decided {
            Ok(b) => b,
            Err(reason) => {
                let result = op == CmpOp::Ne && self.ext.contains(Extension::StrictNe);
                self.reports.push(ComparisonReport {
                    span: e.span.clone(),
                    param: param.name.clone(),
                    op,
                    literal: lit.to_string(),
                    reason,
                    result,
                });
                result
            }
        }
    }
}

/// The type of a value as named in messages (`int`, `color`, `float[2]`).
fn type_text(v: &Value) -> String {
    match v {
        Value::Array(b, items) => format!("{}[{}]", b.word(), items.len()),
        other => other.base_type().word().to_string(),
    }
}

fn apply(op: CmpOp, ord: Option<Ordering>) -> bool {
    match op {
        CmpOp::Eq => ord == Some(Ordering::Equal),
        CmpOp::Ne => ord != Some(Ordering::Equal),
        CmpOp::Lt => ord == Some(Ordering::Less),
        CmpOp::Gt => ord == Some(Ordering::Greater),
        CmpOp::Le => matches!(ord, Some(Ordering::Less | Ordering::Equal)),
        CmpOp::Ge => matches!(ord, Some(Ordering::Greater | Ordering::Equal)),
    }
}

/// The comparison table (see `docs/conditional-language.md`): `Ok(result)` for a genuine
/// comparison, `Err(reason)` when a "false" rule decides. Numbers compare exactly in f64 (*operand
/// OP literal*); strings compare by verbatim content, and only for `==`/`!=`.
pub fn compare(
    operand: &Value,
    op: CmpOp,
    lit: &Literal,
    ext: &Extensions,
) -> Result<bool, FalseReason> {
    match &lit.kind {
        LiteralKind::Number { value, .. } => match operand.as_f64() {
            Some(a) => Ok(apply(op, a.partial_cmp(value))),
            None => Err(FalseReason::TypeMismatch {
                operand: type_text(operand),
                literal: "NUMBER",
            }),
        },
        LiteralKind::Str { value } => {
            let text = match operand {
                Value::Str(s) => s,
                Value::Token(s) | Value::Asset(s) if ext.contains(Extension::TokenStrings) => s,
                Value::Token(_) => return Err(FalseReason::TokenOperand { operand: "token" }),
                Value::Asset(_) => return Err(FalseReason::TokenOperand { operand: "asset" }),
                other => {
                    return Err(FalseReason::TypeMismatch {
                        operand: type_text(other),
                        literal: "STRING",
                    });
                }
            };
            match op {
                CmpOp::Eq => Ok(text == value),
                CmpOp::Ne => Ok(text != value),
                _ => Err(FalseReason::StringOrdering),
            }
        }
    }
}

/// A simple in-memory [`Upstream`]: declared inputs with optional defaults, authored values,
/// connected inputs. Used by tests and by `vstructc expr`.
#[derive(Debug, Clone, Default)]
pub struct MapUpstream {
    /// Declared inputs and their defaults.
    pub inputs: std::collections::BTreeMap<String, Option<Value>>,
    /// Authored values.
    pub authored: std::collections::BTreeMap<String, Value>,
    /// Inputs with at least one connection.
    pub connected: std::collections::BTreeSet<String>,
}

impl MapUpstream {
    /// An upstream node with nothing declared, authored or connected.
    pub fn new() -> Self {
        Self::default()
    }

    /// Builder: declare an input with an optional default.
    pub fn input(mut self, name: &str, default: Option<Value>) -> Self {
        self.inputs.insert(name.to_string(), default);
        self
    }

    /// Builder: author a value.
    pub fn set(mut self, name: &str, value: Value) -> Self {
        self.authored.insert(name.to_string(), value);
        self
    }

    /// Builder: mark an input connected.
    pub fn connect(mut self, name: &str) -> Self {
        self.connected.insert(name.to_string());
        self
    }
}

impl Upstream for MapUpstream {
    fn authored(&self, param: &str) -> Option<&Value> {
        self.authored.get(param)
    }
    fn declares_input(&self, param: &str) -> bool {
        self.inputs.contains_key(param)
    }
    fn default_value(&self, param: &str) -> Option<&Value> {
        self.inputs.get(param).and_then(Option::as_ref)
    }
    fn is_connected(&self, param: &str) -> bool {
        self.connected.contains(param)
    }
}

//! The `vstructConditionalExpr` language: lexer, parser,
//! AST, evaluator, `set`/`copy` typing and the opt-in extensions (the definition-time VS009
//! check of the names a conditional reads is the registry's, `registry::VstructTables`).
//!
//! The formal grammar users read is `grammar/vstruct-conditional.ebnf`.
//!
//! ```
//! use vstructc::cond::{self, ActionKind, Choice, MapUpstream};
//! use vstructc::types::Value;
//!
//! let stmt = cond::parse("set 1 if enableDiffuse == 1 else set 0").unwrap();
//! assert_eq!(stmt.to_string(), "set 1 if enableDiffuse == 1 else set 0");
//! assert_eq!(stmt.param_names(), ["enableDiffuse"]);
//!
//! let upstream = MapUpstream::new().input("enableDiffuse", Some(Value::Int(0)));
//! let ev = cond::evaluate(&stmt, &upstream, &cond::Extensions::none());
//! assert_eq!(ev.choice, Choice::Fallback);
//! assert!(matches!(&ev.action.kind, ActionKind::Set { literal } if literal.as_number() == Some(0.0)));
//!
//! let err = cond::parse("connect if x = 1").unwrap_err();
//! assert_eq!(err.message, "expected a comparison operator (==, !=, <, >, <=, >=), found '='");
//! assert_eq!(err.column("connect if x = 1"), 14);
//! ```
//!
//! Interface contract: [`parse`] (compat mode) returns a [`Statement`] or a [`ParseError`]
//! with the byte span of the offending token; [`Statement::param_names`] lists every
//! parameter name the statement reads (predicates and `copy`).

mod action;
mod ast;
mod error;
mod eval;
mod ext;
mod lexer;
mod parser;

pub(crate) use action::{CopyOutcome, CopyRejection, SetRejection, copy_value, set_value};
pub use ast::{
    Action, ActionKind, ElseIf, Expr, ExprKind, IsTest, Literal, LiteralKind, Param, Statement,
};
pub use error::ParseError;
pub(crate) use error::render_caret;
pub(crate) use eval::chosen_action;
pub use eval::{
    Choice, ComparisonReport, Evaluation, FalseReason, MapUpstream, Upstream, evaluate,
};
pub use ext::{Extension, Extensions, UnknownExtension};
pub use lexer::CmpOp;

/// The language's internals that the crate's own tests and fuzz targets check directly
/// (feature `testkit`; not a stable API): the lexer, the parser entry with its limits, the
/// `set`/`copy` typing rules, the AST dump and expression evaluation.
#[cfg(feature = "testkit")]
pub mod internals {
    pub use super::action::{
        CopyOutcome, CopyPlan, CopyRejection, SetRejection, SetValue, convert, copy_plan,
        copy_value, set_value, truncate_to_i32,
    };
    pub use super::ast::{quote_for, split_index};
    pub use super::error::{location_in, render_caret};
    pub use super::eval::evaluate_expr;
    pub use super::lexer::{Keyword, Token, TokenKind, next_token};
    pub use super::parser::{MAX_PAREN_DEPTH, parse_statement, parse_statement_limited};
}

/// Parse one conditional expression in compat mode (no extension).
pub fn parse(text: &str) -> Result<Statement, ParseError> {
    parser::parse_statement(text, &Extensions::none())
}

/// Parse one conditional expression with the given extensions (only `else-if` changes the
/// grammar).
pub fn parse_with(text: &str, ext: &Extensions) -> Result<Statement, ParseError> {
    parser::parse_statement(text, ext)
}

/// [`parse_with`] within `limits` (expression terms and parenthesis depth): the registry's
/// entry, which reads definitions within the caller's limits.
pub(crate) fn parse_limited(
    text: &str,
    ext: &Extensions,
    limits: &crate::limits::Limits,
) -> Result<Statement, ParseError> {
    parser::parse_statement_limited(text, ext, limits)
}

//! The `vstructConditionalExpr` language (spec vstruct.md §3): lexer, parser, AST, evaluator.
//!
//! Interface contract (kept by the full implementation): [`parse`] returns a [`Statement`] or a
//! [`ParseError`] with the byte span of the offending token; [`Statement::param_names`] lists
//! every parameter name the statement reads (predicates and `copy`).

use std::ops::Range;

/// A parsed, desugared statement.
#[derive(Debug, Clone, PartialEq)]
pub struct Statement {
    names: Vec<String>,
}

impl Statement {
    /// Every parameter name the statement reads, in source order (predicates and `copy`).
    pub fn param_names(&self) -> Vec<&str> {
        self.names.iter().map(String::as_str).collect()
    }
}

/// A syntax error (VS001).
#[derive(Debug, Clone, PartialEq)]
pub struct ParseError {
    /// Byte span of the offending token (empty at end of input).
    pub span: Range<usize>,
    /// Message naming the unexpected token and the expected set.
    pub message: String,
}

/// Parse one conditional expression in compat mode.
pub fn parse(text: &str) -> Result<Statement, ParseError> {
    Err(ParseError {
        span: text.len()..text.len(),
        message: "the conditional parser is not implemented yet".into(),
    })
}

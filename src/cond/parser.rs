//! Recursive-descent parser over tokens lexed on demand.
//!
//! The grammar is LR; this parser decides every choice with at most two tokens of
//! look-ahead using this deterministic rule:
//!
//! > At a position where a predicate may begin (start of statement, after `IF`, after `(`,
//! > after `AND`/`OR`), a keyword token is a parameter name if and only if the next token is
//! > a comparison operator, or the next token is `IS`/`IS_NOT` and the token after that is
//! > `CONNECTED` or `SET`. Otherwise it keeps its keyword role.
//!
//! Statements are desugared while parsing. The first offending token produces a
//! [`ParseError`] naming it and the set of tokens that were expected there.

use super::ast::{Action, ActionKind, ElseIf, Expr, IsTest, Literal, Param, Span, Statement};
use super::error::ParseError;
use super::ext::{Extension, Extensions};
use super::lexer::{CmpOp, Keyword, Token, TokenKind, next_token};
use crate::limits::{Limit, Limits};

/// What may follow at an error position; rendered into the message and the expected list.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Want {
    Kw(Keyword),
    IsNot,
    Number,
    Str,
    Param,
    LParen,
    RParen,
    /// The six comparison operators, summarised in the message.
    Cmp,
    End,
}

impl Want {
    fn message_text(self) -> String {
        match self {
            Want::Kw(k) => k.token_name().to_string(),
            Want::IsNot => "IS_NOT".into(),
            Want::Number => "NUMBER".into(),
            Want::Str => "STRING".into(),
            Want::Param => "PARAM".into(),
            Want::LParen => "'('".into(),
            Want::RParen => "')'".into(),
            Want::Cmp => "a comparison operator (==, !=, <, >, <=, >=)".into(),
            Want::End => "end of input".into(),
        }
    }

    fn list_items(self) -> Vec<String> {
        match self {
            Want::Cmp => CmpOp::ALL.iter().map(|o| o.as_str().to_string()).collect(),
            Want::LParen => vec!["(".into()],
            Want::RParen => vec![")".into()],
            other => vec![other.message_text()],
        }
    }
}

const ACTION_START: [Want; 4] = [
    Want::Kw(Keyword::Connect),
    Want::Kw(Keyword::Ignore),
    Want::Kw(Keyword::Set),
    Want::Kw(Keyword::Copy),
];

/// `a`, `a or b`, `a, b or c`.
fn join_or(items: &[String]) -> String {
    match items {
        [] => String::new(),
        [one] => one.clone(),
        [init @ .., last] => format!("{} or {last}", init.join(", ")),
    }
}

/// Parse `text` with the given extensions, within the default [`Limits`].
pub fn parse_statement(text: &str, ext: &Extensions) -> Result<Statement, ParseError> {
    parse_statement_limited(text, ext, &Limits::default())
}

/// Parse `text` with the given extensions, within `limits`: at most
/// [`Limits::expr_terms`] predicates and [`Limits::expr_depth`] levels of parentheses (each
/// level costs stack in the parser and in every pass over the tree, so keep it in the
/// hundreds). Exceeding one is a VS001 error at the term or parenthesis that exceeds it, with
/// [`ParseError::limit`] set.
pub fn parse_statement_limited(
    text: &str,
    ext: &Extensions,
    limits: &Limits,
) -> Result<Statement, ParseError> {
    let first = next_token(text, 0);
    let mut p = Parser {
        text,
        window: [first; LOOKAHEAD],
        previous: None,
        ext: *ext,
        depth: 0,
        terms: 0,
        limits: *limits,
    };
    for k in 1..LOOKAHEAD {
        p.window[k] = p.following(p.window[k - 1]);
    }
    p.statement()
}

/// Tokens of look-ahead the parser keeps (the current one and two more).
const LOOKAHEAD: usize = 3;

/// Tokens are lexed on demand into a window of [`LOOKAHEAD`] tokens rather than into a list
/// of the whole text, so a long expression costs no memory beyond its tree.
struct Parser<'a> {
    text: &'a str,
    /// The current token and the next ones; past the end, `Eof` repeats.
    window: [Token<'a>; LOOKAHEAD],
    /// The last consumed token.
    previous: Option<Token<'a>>,
    ext: Extensions,
    /// Open parentheses around the current position (bounded by [`Limits::expr_depth`]).
    depth: usize,
    /// Predicates parsed so far (bounded by [`Limits::expr_terms`]).
    terms: u64,
    limits: Limits,
}

/// Deepest parenthesis nesting accepted in a conditional by default
/// ([`Limits::expr_depth`]; robustness limit: the parser and every pass over the tree recurse
/// once per level, while `and`/`or` chains of any length are loops over n-ary nodes; real
/// expressions use 1–3 levels). Deeper nesting is a syntax error (VS001) at the parenthesis
/// that exceeds it.
#[cfg(any(test, feature = "testkit"))]
pub const MAX_PAREN_DEPTH: usize = crate::limits::DEFAULT_EXPR_DEPTH as usize;

impl<'a> Parser<'a> {
    /// The token `k` positions ahead, `k < LOOKAHEAD` (the final `Eof` repeats).
    fn peek_at(&self, k: usize) -> Token<'a> {
        self.window[k]
    }

    fn peek(&self) -> Token<'a> {
        self.peek_at(0)
    }

    /// The token after `t` (`Eof` after `Eof`).
    fn following(&self, t: Token<'a>) -> Token<'a> {
        if t.kind == TokenKind::Eof {
            t
        } else {
            next_token(self.text, t.end)
        }
    }

    fn bump(&mut self) -> Token<'a> {
        let t = self.peek();
        if t.kind != TokenKind::Eof {
            self.previous = Some(t);
            self.window.rotate_left(1);
            self.window[LOOKAHEAD - 1] = self.following(self.window[LOOKAHEAD - 2]);
        }
        t
    }

    /// End offset of the last consumed token.
    fn last_end(&self) -> usize {
        match self.previous {
            Some(t) => t.end,
            None => self.peek().start,
        }
    }

    fn at_kw(&self, k: Keyword) -> bool {
        self.peek().kind == TokenKind::Kw(k)
    }

    /// The deterministic rule of the module docs: does a predicate start at the current token?
    /// `PARAM` always names a parameter; a keyword does only when followed by a comparison
    /// operator, or by `IS`/`IS_NOT` and then `CONNECTED`/`SET`.
    fn name_here(&self) -> bool {
        match self.peek().kind {
            TokenKind::Param(_) => true,
            TokenKind::Kw(_) => match self.peek_at(1).kind {
                TokenKind::Cmp(_) => true,
                TokenKind::Kw(Keyword::Is) | TokenKind::IsNot => matches!(
                    self.peek_at(2).kind,
                    TokenKind::Kw(Keyword::Connected) | TokenKind::Kw(Keyword::Set)
                ),
                _ => false,
            },
            _ => false,
        }
    }

    fn error(&self, wants: &[Want]) -> ParseError {
        let t = self.peek();
        let texts: Vec<String> = wants.iter().map(|w| w.message_text()).collect();
        let expected: Vec<String> = wants.iter().flat_map(|w| w.list_items()).collect();
        let found = t.kind.describe();
        let message = format!("expected {}, found {found}", join_or(&texts));
        let notes = hints(&t, wants, self.previous(), &self.ext);
        ParseError {
            span: t.span(),
            message,
            expected,
            found,
            notes,
            limit: None,
        }
    }

    fn previous(&self) -> Option<Token<'a>> {
        self.previous
    }

    fn expect_end(&self, also: &[Want]) -> Result<(), ParseError> {
        if self.peek().kind == TokenKind::Eof {
            Ok(())
        } else {
            let mut wants = also.to_vec();
            wants.push(Want::End);
            Err(self.error(&wants))
        }
    }

    // statement := action 'IF' expr 'ELSE' action | action 'IF' expr
    //            | 'IF' expr 'ELSE' action | action | expr
    fn statement(&mut self) -> Result<Statement, ParseError> {
        let start = self.peek().start;
        if self.name_here() || self.peek().kind == TokenKind::LParen {
            // A bare expression: (connect, C, ignore).
            let cond = self.expr()?;
            self.expect_end(&[Want::Kw(Keyword::And), Want::Kw(Keyword::Or)])?;
            let at = self.last_end();
            return Ok(Statement {
                action: implied(ActionKind::Connect, start),
                condition: Some(cond),
                else_ifs: Vec::new(),
                fallback: Some(implied(ActionKind::Ignore, at)),
                span: start..at,
            });
        }
        match self.peek().kind {
            TokenKind::Kw(Keyword::If) => self.if_else_statement(start),
            TokenKind::Kw(Keyword::Connect | Keyword::Ignore | Keyword::Set | Keyword::Copy) => {
                self.action_statement(start)
            }
            _ => {
                let mut wants = ACTION_START.to_vec();
                wants.extend([Want::Kw(Keyword::If), Want::Param, Want::LParen]);
                Err(self.error(&wants))
            }
        }
    }

    // 'IF' expr 'ELSE' action  →  (connect, C, B)
    fn if_else_statement(&mut self, start: usize) -> Result<Statement, ParseError> {
        self.bump();
        let cond = self.expr()?;
        if !self.at_kw(Keyword::Else) {
            return Err(self.error(&[
                Want::Kw(Keyword::And),
                Want::Kw(Keyword::Or),
                Want::Kw(Keyword::Else),
            ]));
        }
        self.bump();
        let fallback = self.action()?;
        self.expect_end(&[])?;
        Ok(Statement {
            action: implied(ActionKind::Connect, start),
            condition: Some(cond),
            else_ifs: Vec::new(),
            fallback: Some(fallback),
            span: start..self.last_end(),
        })
    }

    // action [ 'IF' expr [ 'ELSE' tail ] ]
    fn action_statement(&mut self, start: usize) -> Result<Statement, ParseError> {
        let action = self.action()?;
        if !self.at_kw(Keyword::If) {
            self.expect_end(&[Want::Kw(Keyword::If)])?;
            return Ok(Statement {
                span: start..action.span.end,
                action,
                condition: None,
                else_ifs: Vec::new(),
                fallback: None,
            });
        }
        self.bump();
        let cond = self.expr()?;
        let mut stmt = Statement {
            action,
            condition: Some(cond),
            else_ifs: Vec::new(),
            fallback: None,
            span: 0..0,
        };
        if !self.at_kw(Keyword::Else) {
            self.expect_end(&[
                Want::Kw(Keyword::And),
                Want::Kw(Keyword::Or),
                Want::Kw(Keyword::Else),
            ])?;
            // `A if C`: fallback ignore, except `ignore if C` falls back to connect.
            let at = self.last_end();
            let fb = match stmt.action.kind {
                ActionKind::Ignore => ActionKind::Connect,
                _ => ActionKind::Ignore,
            };
            stmt.fallback = Some(implied(fb, at));
            stmt.span = start..at;
            return Ok(stmt);
        }
        self.bump();
        let fallback = self.tail(&mut stmt.else_ifs)?;
        stmt.fallback = Some(fallback);
        stmt.span = start..self.last_end();
        Ok(stmt)
    }

    /// After `ELSE`. Compat: `action` then end of input. With `else-if`:
    /// `tail := action | action 'IF' expr 'ELSE' tail | action 'IF' expr`; links are
    /// appended to `links` and the final fallback returned (`ignore` when the chain ends in
    /// `… if C`).
    fn tail(&mut self, links: &mut Vec<ElseIf>) -> Result<Action, ParseError> {
        loop {
            let action = self.action()?;
            let chained = self.ext.contains(Extension::ElseIf);
            if !chained || !self.at_kw(Keyword::If) {
                self.expect_end(if chained {
                    &[Want::Kw(Keyword::If)]
                } else {
                    &[]
                })?;
                return Ok(action);
            }
            self.bump();
            let condition = self.expr()?;
            links.push(ElseIf { action, condition });
            if self.at_kw(Keyword::Else) {
                self.bump();
                continue;
            }
            self.expect_end(&[
                Want::Kw(Keyword::And),
                Want::Kw(Keyword::Or),
                Want::Kw(Keyword::Else),
            ])?;
            return Ok(implied(ActionKind::Ignore, self.last_end()));
        }
    }

    // action := 'CONNECT' | 'IGNORE' | 'SET' ( NUMBER | STRING ) | 'COPY' PARAM
    fn action(&mut self) -> Result<Action, ParseError> {
        let t = self.peek();
        let kind = match t.kind {
            TokenKind::Kw(Keyword::Connect) => {
                self.bump();
                ActionKind::Connect
            }
            TokenKind::Kw(Keyword::Ignore) => {
                self.bump();
                ActionKind::Ignore
            }
            TokenKind::Kw(Keyword::Set) => {
                self.bump();
                let literal = self.literal()?;
                ActionKind::Set { literal }
            }
            TokenKind::Kw(Keyword::Copy) => {
                self.bump();
                let n = self.peek();
                let TokenKind::Param(name) = n.kind else {
                    return Err(self.error(&[Want::Param]));
                };
                self.bump();
                ActionKind::Copy {
                    param: Param::new(name, n.span()),
                }
            }
            _ => return Err(self.error(&ACTION_START)),
        };
        Ok(Action::new(kind, t.start..self.last_end()))
    }

    // value := NUMBER | STRING
    fn literal(&mut self) -> Result<Literal, ParseError> {
        let t = self.peek();
        let lit = match t.kind {
            TokenKind::Number(text) => Literal::number(text, t.span()),
            TokenKind::Str { content, .. } => Some(Literal::string(content, t.span())),
            _ => None,
        };
        match lit {
            Some(l) => {
                self.bump();
                Ok(l)
            }
            None => Err(self.error(&[Want::Number, Want::Str])),
        }
    }

    // expr := or ; or := and { 'OR' and } ; and := primary { 'AND' primary }
    fn expr(&mut self) -> Result<Expr, ParseError> {
        let (e, _) = self.or_expr()?;
        Ok(e)
    }

    /// Returns the expression and its outer span (including enclosing parentheses), so that
    /// `and`/`or` nodes span their parenthesised operands while predicates keep their own.
    fn or_expr(&mut self) -> Result<(Expr, Span), ParseError> {
        let (mut left, mut outer) = self.and_expr()?;
        while self.at_kw(Keyword::Or) {
            self.bump();
            let (right, right_outer) = self.and_expr()?;
            outer = outer.start..right_outer.end;
            left = Expr::or(left, right);
            left.span = outer.clone();
        }
        Ok((left, outer))
    }

    fn and_expr(&mut self) -> Result<(Expr, Span), ParseError> {
        let (mut left, mut outer) = self.primary()?;
        while self.at_kw(Keyword::And) {
            self.bump();
            let (right, right_outer) = self.primary()?;
            outer = outer.start..right_outer.end;
            left = Expr::and(left, right);
            left.span = outer.clone();
        }
        Ok((left, outer))
    }

    // primary := '(' expr ')' | pred
    fn primary(&mut self) -> Result<(Expr, Span), ParseError> {
        let t = self.peek();
        if t.kind == TokenKind::LParen {
            if let Err(exceeded) = self.limits.check(Limit::ExprDepth, self.depth as u64 + 1) {
                let mut e = self.error(&[Want::Param]);
                e.message = format!("parentheses nested deeper than {} levels", exceeded.max);
                e.limit = Some(Box::new(exceeded));
                return Err(e);
            }
            self.bump();
            self.depth += 1;
            let inner = self.or_expr();
            self.depth -= 1;
            let (inner, _) = inner?;
            if self.peek().kind != TokenKind::RParen {
                return Err(self.error(&[
                    Want::Kw(Keyword::And),
                    Want::Kw(Keyword::Or),
                    Want::RParen,
                ]));
            }
            let close = self.bump();
            return Ok((inner, t.start..close.end));
        }
        if self.name_here() {
            let e = self.predicate()?;
            let span = e.span.clone();
            return Ok((e, span));
        }
        Err(self.error(&[Want::Param, Want::LParen]))
    }

    // pred := name CMP value | name ('IS' | 'IS_NOT') ('CONNECTED' | 'SET')
    fn predicate(&mut self) -> Result<Expr, ParseError> {
        self.terms += 1;
        if let Err(exceeded) = self.limits.check(Limit::ExprTerms, self.terms) {
            let mut e = self.error(&[Want::Param]);
            e.message = format!("{exceeded}");
            e.limit = Some(Box::new(exceeded));
            return Err(e);
        }
        let n = self.bump();
        let name = match n.kind {
            TokenKind::Param(p) => p,
            TokenKind::Kw(k) => k.text(),
            // `name_here` admitted only names.
            _ => return Err(self.error(&[Want::Param])),
        };
        let param = Param::new(name, n.span());
        let t = self.peek();
        match t.kind {
            TokenKind::Cmp(op) => {
                self.bump();
                let value = self.literal()?;
                let span = n.start..value.span.end;
                Ok(Expr::cmp(param, op, value, span))
            }
            TokenKind::Kw(Keyword::Is) | TokenKind::IsNot => {
                self.bump();
                let negated = t.kind == TokenKind::IsNot;
                let test = match self.peek().kind {
                    TokenKind::Kw(Keyword::Connected) => IsTest::Connected,
                    TokenKind::Kw(Keyword::Set) => IsTest::Set,
                    _ => {
                        return Err(
                            self.error(&[Want::Kw(Keyword::Connected), Want::Kw(Keyword::Set)])
                        );
                    }
                };
                let last = self.bump();
                Ok(Expr::is(param, test, negated, n.start..last.end))
            }
            _ => Err(self
                .error(&[Want::Cmp, Want::Kw(Keyword::Is), Want::IsNot])
                .summarise_cmp()),
        }
    }
}

impl ParseError {
    /// After a name, the message mentions only the comparison operators (the common case);
    /// `IS`/`IS_NOT` stay in the expected list and get a note.
    fn summarise_cmp(mut self) -> Self {
        let cmp = Want::Cmp.message_text();
        self.message = format!("expected {cmp}, found {}", self.found);
        self.notes.push(
            "a parameter name is followed by a comparison operator and a number or a quoted string, \
             or by `is connected`, `is not connected`, `is set` or `is not set`"
                .into(),
        );
        self
    }
}

fn implied(kind: ActionKind, at: usize) -> Action {
    Action::new(kind, at..at)
}

/// Hints for the likely mistake behind an error at token `t` (`previous` is the token
/// before it, `wants` what the parser expected).
fn hints(
    t: &Token<'_>,
    wants: &[Want],
    previous: Option<Token<'_>>,
    ext: &Extensions,
) -> Vec<String> {
    let mut notes = Vec::new();
    let copy_slot = wants == [Want::Param];
    let predicate_start = wants.contains(&Want::LParen) && wants.contains(&Want::Param);
    let prev_kind = previous.map(|p| p.kind);
    // Mistakes visible in the previous token.
    if let Some(TokenKind::Param(p)) = prev_kind {
        if let Some(k) = Keyword::from_text(&p.to_ascii_lowercase()).filter(|k| k.text() != p) {
            notes.push(format!(
                "keywords are case-sensitive: `{p}` is read as a parameter name; \
                 did you mean `{}`?",
                k.text()
            ));
        }
        if p == "not" && wants.contains(&Want::Cmp) {
            notes.push(
                "there is no unary `not`; use `!=`, `is not connected` or `is not set`".into(),
            );
        }
    }
    match t.kind {
        TokenKind::Unrecognized(c) => {
            notes.push(format!(
                "{} is not a token of the conditional language",
                t.kind.describe()
            ));
            if let Some(h) = unrecognized_hint(c) {
                notes.push(h.to_string());
            }
        }
        TokenKind::Param(p) => {
            if let Some(k) = Keyword::from_text(&p.to_ascii_lowercase()).filter(|k| k.text() != p) {
                notes.push(format!(
                    "keywords are case-sensitive: `{p}` is a parameter name; did you mean `{}`?",
                    k.text()
                ));
            }
            if p == "not" && prev_kind == Some(TokenKind::Kw(Keyword::Is)) {
                notes.push("`is not` must be written with exactly one space".into());
            }
            if wants.contains(&Want::Number) {
                if prev_kind == Some(TokenKind::Kw(Keyword::Set)) {
                    notes.push(format!(
                        "`set` takes a number or a quoted string; to copy a parameter write \
                         `copy {p}`"
                    ));
                } else if matches!(p, "true" | "false") {
                    notes.push("there are no boolean literals; compare with 1 or 0".into());
                } else {
                    notes.push(
                        "a parameter can only be compared with a number or a quoted string".into(),
                    );
                }
            }
        }
        TokenKind::Number(_) | TokenKind::Str { .. } if copy_slot => {
            notes.push("`copy` takes a parameter name; to write a literal use `set`".into());
        }
        TokenKind::Number(_) | TokenKind::Str { .. } if predicate_start => {
            notes.push("the parameter name comes first: `x == 1`, not `1 == x`".into());
        }
        TokenKind::Kw(Keyword::If) if wants == [Want::End] => {
            notes.push(if ext.contains(Extension::ElseIf) {
                "with `--ext else-if`, a chain starts with an action: \
                 `connect if … else … if …`"
                    .into()
            } else {
                "chained `else … if` is not part of the reference language; \
                 `--ext else-if` accepts chains that start with an action"
                    .into()
            });
        }
        TokenKind::Kw(k) if copy_slot => {
            notes.push(format!(
                "`copy` takes a PARAM; a parameter named like the keyword `{}` cannot be copied",
                k.text()
            ));
        }
        TokenKind::Kw(k) if predicate_start => {
            notes.push(format!(
                "`{}` is a keyword here; a keyword names a parameter only when a comparison \
                 operator, `is [not] connected` or `is [not] set` follows it",
                k.text()
            ));
        }
        TokenKind::Eof if wants == ACTION_START => {
            notes.push("`else` must be followed by an action: connect, ignore, set or copy".into());
        }
        _ => {}
    }
    notes
}

fn unrecognized_hint(c: char) -> Option<&'static str> {
    Some(match c {
        '=' => "use '==' to compare",
        '!' => "'!=' is the inequality operator; there is no unary '!'",
        '&' => "use `and`",
        '|' => "use `or`",
        '+' => "numbers take no '+' sign",
        '-' => "a minus sign must be glued to the digits, as in `-1`",
        '.' | ':' => {
            "parameter names cannot contain '.' or ':' (dotted and namespaced names cannot be referenced)"
        }
        '[' | ']' => {
            "an array suffix must be glued to the name and hold only digits, as in `arr[2]`"
        }
        '\'' | '"' => "this string is never closed",
        '\r' => "a carriage return is not whitespace in conditionals",
        ';' | ',' => "an expression is exactly one statement",
        _ if !c.is_ascii() => "only ASCII characters can appear outside string literals",
        _ => return None,
    })
}

//! `vstructc expr 'TEXT' [--json]`: parse one conditional expression and print its
//! desugared form and AST, or the syntax error: what was expected, in the language's words,
//! and the expression with a caret under the offending token.
//!
//! The parse error is reported as `error[VS001]` here (in a definition the same problem is a
//! warning, because loading continues; here it is the command's only input). Exit status: 0
//! when the expression parses, 1 on a syntax error, 2 on a usage error (unknown `--ext`).

use super::CommonOptions;
use super::input::print_stdout;
use std::process::ExitCode;
use vstructc::cond::{self, Extensions};
use vstructc::diag::{Diagnostic, Diagnostics, Location};

/// Arguments of `vstructc expr`.
#[derive(Debug, clap::Args)]
pub struct ExprArgs {
    /// The expression, e.g. 'set 1 if enableDiffuse == 1 else set 0'.
    #[arg(value_name = "TEXT", allow_hyphen_values = true)]
    pub text: String,
    /// Print a JSON document on stdout instead of the readable form.
    ///
    /// On success: {"input", "extensions", "desugared", "statement"}. The statement is
    /// {"action", "condition", "else_ifs", "fallback", "span"} (condition and fallback are
    /// null for a bare action; else_ifs, links {"action", "condition"}, appears with
    /// `--ext else-if` only). An action is {"action": "connect" | "ignore" | "set" | "copy",
    /// "literal" (set) or "param" (copy), "span"}. An expression node is one of
    /// {"expr": "cmp", "param", "op", "value", "span"},
    /// {"expr": "is", "param", "test": "connected" | "set", "negated", "span"},
    /// {"expr": "and" | "or", "terms" (a list of nodes), "span"}: a chain `a and b and c` is one node
    /// with its terms in order; only a chain parenthesised as a later term is a nested node.
    /// A param is {"name", "span"}, a literal {"type": "number", "value", "text", "span"} or
    /// {"type": "string", "value", "span"}; spans are byte offsets {"start", "end"}.
    /// On a syntax error: {"input", "extensions", "error": {"code", "message", "span",
    /// "line", "column", "expected", "found", "notes"}}.
    #[arg(long)]
    pub json: bool,
}

/// Run `vstructc expr`.
pub fn run(args: &ExprArgs, common: &CommonOptions) -> ExitCode {
    let ext = match Extensions::from_names(&common.ext) {
        Ok(e) => e,
        Err(e) => {
            eprintln_quiet!("error: {e}");
            return ExitCode::from(2);
        }
    };
    let text = args.text.as_str();
    let print = |out: String| print_stdout(&out, common);
    match cond::parse_with(text, &ext) {
        Ok(stmt) => {
            let out = if args.json {
                let doc = serde_json::json!({
                    "input": text,
                    "extensions": ext.names(),
                    "desugared": stmt.to_string(),
                    "statement": stmt,
                });
                pretty(&doc) + "\n"
            } else {
                format!("{stmt}\n\n{}", stmt.dump())
            };
            match print(out) {
                Ok(()) => ExitCode::SUCCESS,
                Err(failed) => failed,
            }
        }
        Err(err) => {
            let (line, column) = err.line_column(text);
            if args.json {
                let doc = serde_json::json!({
                    "input": text,
                    "extensions": ext.names(),
                    "error": {
                        "code": cond::ParseError::CODE,
                        "message": err.message,
                        "span": [err.span.start, err.span.end],
                        "line": line,
                        "column": column,
                        "expected": err.expected,
                        "found": err.found,
                        "notes": err.notes,
                    },
                });
                if let Err(failed) = print(pretty(&doc) + "\n") {
                    return failed;
                }
            }
            // One sentence of what was expected, in the language's words, and the text with a
            // caret under the offending token; the notes say what the mistake likely is.
            let mut d = Diagnostic::error(
                cond::ParseError::CODE,
                format!("conditional expression: {}", err.in_words()),
            )
            .with_span(err.span.clone())
            .at(Location::new("<expr>", line, column));
            for n in err.notes.iter().filter(|n| !restates_expected(n)) {
                d = d.with_note(format!("note: {n}"));
            }
            super::snippet::remember("<expr>", text.as_bytes());
            let mut diags = Diagnostics::new();
            diags.push(d);
            super::report(&diags, common)
        }
    }
}

/// The parser's note that lists again what may follow a parameter name: the message says it.
fn restates_expected(note: &str) -> bool {
    note.starts_with("a parameter name is followed by")
}

fn pretty(v: &serde_json::Value) -> String {
    serde_json::to_string_pretty(v).unwrap_or_else(|_| v.to_string())
}

//! The definition-time check of parameter names (spec vstruct.md §5.6, VS009).

use super::ast::{Param, Statement, split_index};
use super::error::render_caret;
use super::ext::{Extension, Extensions};
use crate::diag::Diagnostic;
use crate::registry::Definition;

/// The stable code of an undeclared parameter in a conditional.
pub const VS009: &str = "VS009";

/// Warn (VS009) about every parameter name used in a predicate or in `copy` that `def` does
/// not declare as an **input** (outputs do not count; names with `[n]` are looked up
/// literally unless `array-index` is enabled, which checks the array's name). One warning per
/// distinct name, at its first occurrence, naming the shader, the member and the parameter.
///
/// `member` is how the caller names the member carrying the conditional (for example
/// `pxrMaterialOut.diffuseGain` or the property name); `text` is the expression, used for the
/// caret note. The caller adds the location (see [`super::location_in`]).
pub fn check_params(
    stmt: &Statement,
    text: &str,
    def: &Definition,
    member: &str,
    ext: &Extensions,
) -> Vec<Diagnostic> {
    let mut seen = std::collections::HashSet::new();
    let mut out = Vec::new();
    for p in stmt.params() {
        if !seen.insert(p.name.as_str()) {
            continue;
        }
        if let Some(d) = check_one(p, text, def, member, ext) {
            out.push(d);
        }
    }
    out
}

fn check_one(
    p: &Param,
    text: &str,
    def: &Definition,
    member: &str,
    ext: &Extensions,
) -> Option<Diagnostic> {
    let indexed = ext
        .contains(Extension::ArrayIndex)
        .then(|| split_index(&p.name))
        .flatten();
    let looked_up = indexed.map_or(p.name.as_str(), |(base, _)| base);
    if def.input(looked_up).is_some() {
        return None;
    }
    let mut d = Diagnostic::warning(
        VS009,
        format!(
            "conditional of `{}` member `{member}` names `{}`, which is not an input of `{}`",
            def.id, p.name, def.id
        ),
    )
    .with_span(p.span.clone())
    .with_note(render_caret(text, p.span.clone()));
    if def.output(looked_up).is_some() {
        d = d.with_note(format!(
            "`{looked_up}` is an output of `{}`; conditionals read inputs only",
            def.id
        ));
    }
    let literal_index = split_index(&p.name).filter(|_| indexed.is_none());
    if let Some((base, index)) = literal_index.filter(|(b, _)| def.input(b).is_some()) {
        d = d.with_note(format!(
            "the name is looked up literally; `--ext array-index` reads element {index} \
             of `{base}`"
        ));
    }
    d = d.with_note(
        "the predicate will always see no operand / not connected / not set, \
         and `copy` of it will always fail",
    );
    Some(d)
}

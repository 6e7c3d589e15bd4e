//! The conformance vectors of spec/vstruct.md §11.1 (parser) and §11.2 (evaluation), kept as
//! data in `tests/vectors/cond/*.json`.
//!
//! Expected statements are written as S-expressions built here from the AST structure, not
//! with the crate's `Display`, so that the vectors check the tree itself.

use serde_json::Value as Json;
use vstructc::cond::{
    self, Action, ActionKind, Expr, ExprKind, Extensions, IsTest, Literal, LiteralKind,
    MapUpstream, Statement, internals::CopyOutcome,
};
use vstructc::types::{ArraySpec, BaseType, Type, Value};

fn load(name: &str) -> Vec<Json> {
    let path = format!("{}/tests/vectors/cond/{name}", env!("CARGO_MANIFEST_DIR"));
    let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{path}: {e}"));
    let doc: Json = serde_json::from_str(&text).unwrap_or_else(|e| panic!("{path}: {e}"));
    doc["vectors"].as_array().expect("vectors array").clone()
}

fn ext_of(v: &Json) -> Extensions {
    let names: Vec<&str> = v["ext"]
        .as_array()
        .map(|a| a.iter().filter_map(Json::as_str).collect())
        .unwrap_or_default();
    Extensions::from_names(names).expect("known extensions")
}

fn sx_literal(l: &Literal) -> String {
    match &l.kind {
        LiteralKind::Number { value, .. } => format!("{value}"),
        LiteralKind::Str { value } => format!("\"{value}\""),
    }
}

fn sx_action(a: &Action) -> String {
    match &a.kind {
        ActionKind::Connect => "connect".into(),
        ActionKind::Ignore => "ignore".into(),
        ActionKind::Set { literal } => format!("(set {})", sx_literal(literal)),
        ActionKind::Copy { param } => format!("(copy {})", param.name),
    }
}

fn sx_expr(e: &Expr) -> String {
    match &e.kind {
        ExprKind::Cmp { param, op, value } => {
            format!("({} {} {})", op.as_str(), param.name, sx_literal(value))
        }
        ExprKind::Is {
            param,
            test,
            negated,
        } => {
            let not = if *negated { "not-" } else { "" };
            let what = match test {
                IsTest::Connected => "connected",
                IsTest::Set => "set",
            };
            format!("(is-{not}{what} {})", param.name)
        }
        ExprKind::And { terms } => sx_chain("and", terms),
        ExprKind::Or { terms } => sx_chain("or", terms),
    }
}

/// The vectors write `and`/`or` as the binary, left-associative nodes of the grammar: an
/// n-ary chain `a and b and c` is `(and (and a b) c)`.
fn sx_chain(op: &str, terms: &[Expr]) -> String {
    let mut it = terms.iter().map(sx_expr);
    let first = it.next().unwrap_or_default();
    it.fold(first, |acc, t| format!("({op} {acc} {t})"))
}

fn opt_str(v: &Json) -> Option<String> {
    v.as_str().map(str::to_string)
}

#[test]
fn parser_accept_vectors() {
    let vectors = load("parse_accept.json");
    assert!(vectors.len() >= 31 + 4);
    for v in vectors {
        let input = v["input"].as_str().expect("input");
        let ext = ext_of(&v);
        let stmt = cond::parse_with(input, &ext)
            .unwrap_or_else(|e| panic!("{input:?} should parse: {}", e.render(input)));
        assert_eq!(
            sx_action(&stmt.action),
            v["action"].as_str().unwrap(),
            "{input:?}"
        );
        assert_eq!(
            stmt.condition.as_ref().map(sx_expr),
            opt_str(&v["condition"]),
            "{input:?}"
        );
        assert_eq!(
            stmt.fallback.as_ref().map(sx_action),
            opt_str(&v["fallback"]),
            "{input:?}"
        );
        let chain: Vec<(String, String)> = stmt
            .else_ifs
            .iter()
            .map(|l| (sx_action(&l.action), sx_expr(&l.condition)))
            .collect();
        let want: Vec<(String, String)> = v["chain"]
            .as_array()
            .map(|links| {
                links
                    .iter()
                    .map(|l| (l[0].as_str().unwrap().into(), l[1].as_str().unwrap().into()))
                    .collect()
            })
            .unwrap_or_default();
        assert_eq!(chain, want, "{input:?}");
        if let Some(n) = v["string_chars"].as_u64() {
            let s = string_literals(&stmt);
            assert_eq!(s.len(), 1, "{input:?}");
            assert_eq!(s[0].chars().count() as u64, n, "{input:?}");
        }
        if ext.is_empty() {
            assert!(stmt.else_ifs.is_empty());
        }
        // The canonical print parses back to the same statement.
        let printed = stmt.to_string();
        let again = cond::parse_with(&printed, &ext).unwrap();
        assert!(again.same_as(&stmt), "{input:?} printed as {printed:?}");
    }
}

fn string_literals(stmt: &Statement) -> Vec<String> {
    fn from_expr(e: &Expr, out: &mut Vec<String>) {
        match &e.kind {
            ExprKind::Cmp { value, .. } => out.extend(value.as_str().map(str::to_string)),
            ExprKind::Is { .. } => {}
            ExprKind::And { terms } | ExprKind::Or { terms } => {
                terms.iter().for_each(|t| from_expr(t, out));
            }
        }
    }
    let mut out = Vec::new();
    for a in stmt.actions() {
        if let ActionKind::Set { literal } = &a.kind {
            out.extend(literal.as_str().map(str::to_string));
        }
    }
    if let Some(c) = &stmt.condition {
        from_expr(c, &mut out);
    }
    out
}

#[test]
fn parser_reject_vectors() {
    let vectors = load("parse_reject.json");
    assert!(vectors.len() >= 26);
    for v in vectors {
        let input = v["input"].as_str().expect("input");
        let err = match cond::parse_with(input, &ext_of(&v)) {
            Ok(s) => panic!("{input:?} should be rejected, parsed as {s}"),
            Err(e) => e,
        };
        let span: Vec<usize> = v["span"]
            .as_array()
            .unwrap()
            .iter()
            .map(|n| n.as_u64().unwrap() as usize)
            .collect();
        assert_eq!(err.span, span[0]..span[1], "{input:?}: {}", err.message);
        assert_eq!(err.found, v["found"].as_str().unwrap(), "{input:?}");
        assert!(
            err.message.contains(&err.found),
            "{input:?}: {}",
            err.message
        );
        for e in v["expected"].as_array().into_iter().flatten() {
            let e = e.as_str().unwrap();
            assert!(
                err.expected.iter().any(|x| x == e),
                "{input:?}: expected set {:?} lacks {e}",
                err.expected
            );
        }
        let d = err.to_diagnostic(input);
        assert_eq!(d.code, "VS001");
        assert_eq!(d.span, Some(err.span.clone()));
    }
}

/// `int`, `float[2]`, `int[]`, `color`, … (`none` is handled by the caller).
fn type_of(word: &str) -> Type {
    if let Some(base) = word.strip_suffix("[]") {
        return Type {
            base: BaseType::from_word(base),
            array: ArraySpec::Dynamic,
        };
    }
    if let Some((base, n)) = word.strip_suffix(']').and_then(|w| w.split_once('[')) {
        return Type {
            base: BaseType::from_word(base),
            array: ArraySpec::Fixed(n.parse().unwrap()),
        };
    }
    Type::scalar(BaseType::from_word(word))
}

fn value_of(v: &Json) -> Value {
    serde_json::from_value(v.clone()).unwrap_or_else(|e| panic!("bad value {v}: {e}"))
}

struct Upstream {
    map: MapUpstream,
    types: std::collections::BTreeMap<String, Type>,
}

fn upstream_of(v: &Json) -> Upstream {
    let mut map = MapUpstream::new();
    let mut types = std::collections::BTreeMap::new();
    if let Some(inputs) = v["inputs"].as_object() {
        for (name, decl) in inputs {
            let default = (!decl["default"].is_null()).then(|| value_of(&decl["default"]));
            map = map.input(name, default);
            types.insert(name.clone(), type_of(decl["type"].as_str().unwrap()));
        }
    }
    if let Some(authored) = v["authored"].as_object() {
        for (name, value) in authored {
            map = map.set(name, value_of(value));
        }
    }
    for name in v["connected"].as_array().into_iter().flatten() {
        map = map.connect(name.as_str().unwrap());
    }
    Upstream { map, types }
}

/// Apply the chosen `set`/`copy` to a destination of the vector's `dest` type and compare
/// with `effect`.
fn check_effect(id: &str, action: &Action, up: &Upstream, v: &Json, ext: &Extensions) {
    let dest_word = v["dest"].as_str().unwrap();
    let dest = (dest_word != "none").then(|| type_of(dest_word));
    let effect = &v["effect"];
    let (written, saturated, shape, rejected) = match &action.kind {
        ActionKind::Set { literal } => {
            match cond::internals::set_value(literal, dest.as_ref(), ext) {
                Ok(sv) => (Some(sv.value), sv.saturated, false, None),
                Err(_) => (
                    None,
                    false,
                    false,
                    Some(cond::internals::SetRejection::CODE),
                ),
            }
        }
        ActionKind::Copy { param } => {
            let value = up
                .map
                .authored
                .get(&param.name)
                .or_else(|| up.map.inputs.get(&param.name).and_then(Option::as_ref));
            let source = up.types.get(&param.name);
            match cond::internals::copy_value(value, source, dest.as_ref(), ext) {
                Ok(CopyOutcome::Write {
                    value,
                    shape_mismatch,
                    ..
                }) => (Some(value), false, shape_mismatch, None),
                Ok(CopyOutcome::NoValue) => (None, false, false, None),
                Err(_) => (
                    None,
                    false,
                    false,
                    Some(cond::internals::CopyRejection::CODE),
                ),
            }
        }
        _ => panic!("{id}: 'dest' given but the action is {}", action.name()),
    };
    if let Some(code) = effect["rejected"].as_str() {
        assert_eq!(rejected, Some(code), "{id}");
        assert_eq!(written, None, "{id}");
    } else if effect["nothing"].as_bool() == Some(true) {
        assert_eq!((written, rejected), (None, None), "{id}");
    } else {
        assert_eq!(rejected, None, "{id}");
        assert_eq!(written, Some(value_of(&effect["write"])), "{id}");
        assert_eq!(
            saturated,
            effect["saturated"].as_bool().unwrap_or(false),
            "{id}"
        );
        assert_eq!(
            shape,
            effect["shape_mismatch"].as_bool().unwrap_or(false),
            "{id}"
        );
    }
}

#[test]
fn evaluation_vectors() {
    let vectors = load("eval.json");
    let mut spec_ids = std::collections::BTreeSet::new();
    for v in vectors {
        let id = v["id"].as_str().unwrap();
        if let Some(n) = id.strip_prefix('E').and_then(|r| r.split('-').next()) {
            spec_ids.insert(n.parse::<u32>().unwrap());
        }
        if v["resolver_only"].is_string() {
            continue;
        }
        let expr = v["expr"].as_str().unwrap();
        let ext = ext_of(&v);
        if v["parse_error"].as_bool() == Some(true) {
            assert!(cond::parse_with(expr, &ext).is_err(), "{id}");
            continue;
        }
        let stmt = cond::parse_with(expr, &ext).unwrap_or_else(|e| panic!("{id}: {e}"));
        let up = upstream_of(&v["upstream"]);
        let ev = cond::evaluate(&stmt, &up.map, &ext);
        assert_eq!(sx_action(ev.action), v["action"].as_str().unwrap(), "{id}");
        assert_eq!(
            ev.reports.len() as u64,
            v["vs015"].as_u64().unwrap(),
            "{id}"
        );
        if let Some(reasons) = v["reasons"].as_array() {
            let got: Vec<String> = ev
                .reports
                .iter()
                .map(|r| serde_json::to_value(&r.reason).unwrap()["reason"].to_string())
                .map(|s| s.trim_matches('"').to_string())
                .collect();
            let want: Vec<&str> = reasons.iter().map(|r| r.as_str().unwrap()).collect();
            assert_eq!(got, want, "{id}");
        }
        for r in &ev.reports {
            // The report points at a whole predicate of this expression.
            assert!(
                r.span.end <= expr.len() && r.span.start < r.span.end,
                "{id}"
            );
            assert!(expr[r.span.clone()].starts_with(&r.param), "{id}");
            assert_eq!(r.to_diagnostic(expr).code, "VS015");
        }
        if !v["dest"].is_null() {
            check_effect(id, ev.action, &up, &v, &ext);
        }
    }
    // Every vector E1–E32 of §11.2 is present.
    assert_eq!(spec_ids, (1..=32).collect(), "missing §11.2 vectors");
}

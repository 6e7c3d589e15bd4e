//! The VS009 definition-time check (spec vstruct.md §5.6) and the diagnostics the evaluator
//! and the action helpers hand to the resolver.

use std::sync::Arc;
use vstructc::cond::{self, Extension, Extensions, MapUpstream};
use vstructc::registry::{
    CondSource, Definition, Direction, MemberDecl, Property, SourceKind, VstructTables,
};
use vstructc::types::{ArraySpec, BaseType, Type, Value};
use vstructc::{Location, Severity};

fn prop(name: &str, direction: Direction, ty: Type) -> Property {
    Property::new(name, direction, ty, Location::new("PxrTest.args", 1, 1))
}

fn definition() -> Definition {
    Definition {
        id: "PxrTest".into(),
        kind: "pattern".into(),
        source: SourceKind::Args,
        path: Arc::from("PxrTest.args"),
        inputs: vec![
            prop("enableDiffuse", Direction::In, Type::scalar(BaseType::Int)),
            prop("bumpNormal", Direction::In, Type::scalar(BaseType::Normal)),
            prop(
                "arr",
                Direction::In,
                Type {
                    base: BaseType::Int,
                    array: ArraySpec::Dynamic,
                },
            ),
            prop("set", Direction::In, Type::scalar(BaseType::Int)),
        ],
        outputs: vec![prop(
            "resultF",
            Direction::Out,
            Type::scalar(BaseType::Float),
        )],
        metadata: Default::default(),
    }
}

/// Where the conditional's value starts in `PxrTest.args`.
const COND_AT: (u32, u32) = (7, 20);

/// `def` with one more output, `outX`, member `x` of head `pxrMaterialOut` carrying the
/// conditional `text`.
fn with_member(mut def: Definition, text: &str) -> Definition {
    let mut out = prop("outX", Direction::Out, Type::scalar(BaseType::Float));
    out.vstruct = Some(MemberDecl {
        head: "pxrMaterialOut".into(),
        member: "x".into(),
        alias: None,
        cond: Some(CondSource {
            text: text.into(),
            location: Location::new("PxrTest.args", COND_AT.0, COND_AT.1),
        }),
    });
    def.outputs.push(out);
    def
}

/// The VS009 warnings the registry's tables report for `def`.
fn vs009(def: &Definition) -> Vec<vstructc::Diagnostic> {
    let mut diags = Vec::new();
    VstructTables::build(def, &mut diags);
    diags.retain(|d| d.code == "VS009");
    diags
}

fn check(text: &str) -> Vec<vstructc::Diagnostic> {
    vs009(&with_member(definition(), text))
}

#[test]
fn declared_inputs_pass() {
    assert!(check("connect if enableDiffuse == 1 and bumpNormal is connected").is_empty());
    assert!(check("set is set").is_empty(), "keyword-named input `set`");
    assert!(check("set 1 if enableDiffuse == 1 else set 0").is_empty());
}

#[test]
fn undeclared_names_warn_once_each_with_member_param_and_position() {
    let text = "copy gain if enableDiffuse == 1 or missing == 1 and missing is set else ignore";
    let d = check(text);
    assert_eq!(d.len(), 2, "{d:#?}");
    assert!(d.iter().all(|x| x.severity == Severity::Warning));
    // Source order: the copy first, then the predicate.
    assert_eq!(
        d[0].message,
        "conditional of `outX` reads `gain`, which is not an input of `PxrTest`"
    );
    assert_eq!(d[0].span, Some(5..9));
    let at = |d: &vstructc::Diagnostic| d.location.as_ref().map(|l| (l.line, l.column));
    assert_eq!(at(&d[0]), Some((COND_AT.0, COND_AT.1 + 5)));
    assert!(d[1].message.contains("reads `missing`"));
    assert_eq!(d[1].span, Some(35..42), "first occurrence");
    assert_eq!(at(&d[1]), Some((COND_AT.0, COND_AT.1 + 35)));
    assert!(d[1].notes[0].contains("^~~~~~~"), "{:?}", d[1].notes);
}

#[test]
fn e4_vs009_at_definition_time() {
    // E4: the upstream type lacks the input; the definition check warns.
    let mut def = definition();
    def.inputs.retain(|p| p.name != "enableDiffuse");
    let d = vs009(&with_member(def, "connect if enableDiffuse == 1"));
    assert_eq!(d.len(), 1);
    assert!(d[0].message.contains("`enableDiffuse`"));
    assert!(d[0].message.contains("conditional of `outX`"));
}

#[test]
fn outputs_do_not_count() {
    let d = check("connect if resultF == 1");
    assert_eq!(d.len(), 1);
    assert!(
        d[0].notes
            .iter()
            .any(|n| n.contains("is an output of `PxrTest`")),
        "{d:#?}"
    );
}

/// Definitions are read without extensions, so an index suffix is part of the name looked up.
#[test]
fn array_suffix_is_literal() {
    let d = check("connect if arr[1] == 1");
    assert_eq!(d.len(), 1);
    assert!(d[0].message.contains("reads `arr[1]`"), "{d:#?}");
    assert_eq!(check("connect if arr is connected").len(), 0);
}

#[test]
fn vs015_report_names_the_reason_and_the_predicate() {
    let text = "connect if enableDiffuse == 1 and c != 1";
    let stmt = cond::parse(text).unwrap();
    let up = MapUpstream::new()
        .input("enableDiffuse", Some(Value::Int(1)))
        .input("c", Some(Value::Triple(BaseType::Color, [1.0; 3])));
    let ev = cond::evaluate(&stmt, &up, &Extensions::none());
    assert_eq!(ev.action.name(), "ignore");
    assert_eq!(ev.choice, cond::Choice::Fallback);
    assert_eq!(ev.reports.len(), 1);
    let r = &ev.reports[0];
    assert_eq!(r.span, 34..40);
    assert_eq!(&text[r.span.clone()], "c != 1");
    assert_eq!(
        r.message(),
        "comparison `c != 1` is false because `c` is a color, which is never compared with a NUMBER"
    );
    let d = r.to_diagnostic(text);
    assert_eq!(
        (d.code.as_str(), d.severity, d.span.clone()),
        ("VS015", Severity::Warning, Some(34..40))
    );
    assert!(d.notes[0].ends_with("^~~~~~"), "{:?}", d.notes);

    let strict = Extensions::none().with(Extension::StrictNe);
    let ev = cond::evaluate(&stmt, &up, &strict);
    assert_eq!(ev.action.name(), "connect");
    assert!(ev.reports[0].result);
    assert!(ev.reports[0].message().contains("is true (strict-ne)"));
}

#[test]
fn evaluation_reads_only_the_upstream_trait() {
    // A custom Upstream: the evaluator must use authored, then the default of a declared
    // input, and never the default of an undeclared name.
    struct Odd;
    impl cond::Upstream for Odd {
        fn authored(&self, _: &str) -> Option<&Value> {
            None
        }
        fn declares_input(&self, p: &str) -> bool {
            p == "declared"
        }
        fn default_value(&self, _: &str) -> Option<&Value> {
            static ONE: Value = Value::Int(1);
            Some(&ONE)
        }
        fn is_connected(&self, p: &str) -> bool {
            p == "wired"
        }
    }
    let none = Extensions::none();
    let eval = |t: &str| {
        let s = cond::parse(t).unwrap();
        cond::evaluate(&s, &Odd, &none).action.name()
    };
    assert_eq!(eval("declared == 1"), "connect");
    assert_eq!(eval("undeclared == 1"), "ignore");
    assert_eq!(
        eval("declared is set"),
        "ignore",
        "defaults do not count for `is set`"
    );
    assert_eq!(eval("wired is connected"), "connect");
    assert_eq!(eval("wired is not connected"), "ignore");
}

#[test]
fn set_and_copy_rejections_explain_themselves() {
    let color = Type::scalar(BaseType::Color);
    let lit = cond::Literal::number("1.7", 0..3).unwrap();
    let r = cond::internals::set_value(&lit, Some(&color), &Extensions::none()).unwrap_err();
    assert_eq!(cond::internals::SetRejection::CODE, "VS013");
    assert!(r.to_string().contains("see --ext set-tuples"), "{r}");
    let f = Type::scalar(BaseType::Float);
    let i = Type::scalar(BaseType::Int);
    let r = cond::internals::copy_value(
        Some(&Value::Float(1.0)),
        Some(&f),
        Some(&i),
        &Extensions::none(),
    )
    .unwrap_err();
    assert_eq!(cond::internals::CopyRejection::CODE, "VS014");
    assert!(r.to_string().contains("see --ext copy-convert"), "{r}");
    let s = Type::scalar(BaseType::String);
    let r = cond::internals::copy_value(
        Some(&Value::Str("a".into())),
        Some(&s),
        Some(&i),
        &Extensions::all(),
    )
    .unwrap_err();
    assert!(!r.to_string().contains("copy-convert"), "{r}");
}

#[test]
fn copy_plans() {
    let t = |b| Type::scalar(b);
    let none = Extensions::none();
    let cc = Extensions::none().with(Extension::CopyConvert);
    assert_eq!(
        cond::internals::copy_plan(&t(BaseType::Color), &t(BaseType::Color), &none),
        Ok(cond::internals::CopyPlan::Same)
    );
    assert!(cond::internals::copy_plan(&t(BaseType::Int), &t(BaseType::Float), &none).is_err());
    assert_eq!(
        cond::internals::copy_plan(&t(BaseType::Int), &t(BaseType::Float), &cc),
        Ok(cond::internals::CopyPlan::IntToFloat)
    );
    assert_eq!(
        cond::internals::copy_plan(&t(BaseType::Float), &t(BaseType::Int), &cc),
        Ok(cond::internals::CopyPlan::FloatToInt)
    );
    assert_eq!(
        cond::internals::copy_plan(&t(BaseType::Int), &t(BaseType::Vector), &cc),
        Ok(cond::internals::CopyPlan::Broadcast)
    );
    assert!(cond::internals::copy_plan(&t(BaseType::Color), &t(BaseType::Float), &cc).is_err());
    assert!(cond::internals::copy_plan(&t(BaseType::Float), &t(BaseType::Matrix), &cc).is_err());
    // Arrays of the same base type: the reference ignores array-ness.
    let arr = Type {
        base: BaseType::Float,
        array: ArraySpec::Fixed(3),
    };
    assert_eq!(
        cond::internals::copy_plan(&arr, &t(BaseType::Float), &none),
        Ok(cond::internals::CopyPlan::Same)
    );
}

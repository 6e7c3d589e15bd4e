//! The VS009 definition-time check (spec vstruct.md §5.6) and the diagnostics the evaluator
//! and the action helpers hand to the resolver.

use std::sync::Arc;
use vstructc::cond::{self, Extension, Extensions, MapUpstream};
use vstructc::registry::{Definition, Direction, Property, SourceKind};
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

fn check(text: &str, ext: &Extensions) -> Vec<vstructc::Diagnostic> {
    let stmt = cond::parse_with(text, ext).unwrap();
    cond::check_params(&stmt, text, &definition(), "pxrMaterialOut.x", ext)
}

#[test]
fn declared_inputs_pass() {
    let none = Extensions::none();
    assert!(
        check(
            "connect if enableDiffuse == 1 and bumpNormal is connected",
            &none
        )
        .is_empty()
    );
    assert!(
        check("set is set", &none).is_empty(),
        "keyword-named input `set`"
    );
    assert!(check("set 1 if enableDiffuse == 1 else set 0", &none).is_empty());
}

#[test]
fn undeclared_names_warn_once_each_with_shader_member_and_param() {
    let text = "copy gain if enableDiffuse == 1 or missing == 1 and missing is set else ignore";
    let d = check(text, &Extensions::none());
    assert_eq!(d.len(), 2, "{d:#?}");
    assert!(
        d.iter()
            .all(|x| x.code == "VS009" && x.severity == Severity::Warning)
    );
    // Source order: the copy first, then the predicate.
    assert_eq!(
        d[0].message,
        "conditional of `PxrTest` member `pxrMaterialOut.x` names `gain`, which is not an input of `PxrTest`"
    );
    assert_eq!(d[0].span, Some(5..9));
    assert!(d[1].message.contains("names `missing`"));
    assert_eq!(d[1].span, Some(35..42), "first occurrence");
    assert!(d[1].notes[0].contains("^~~~~~~"), "{:?}", d[1].notes);
}

#[test]
fn e4_vs009_at_definition_time() {
    // §11.2 E4: the upstream type lacks the input; the definition check warns.
    let mut def = definition();
    def.inputs.retain(|p| p.name != "enableDiffuse");
    let text = "connect if enableDiffuse == 1";
    let stmt = cond::parse(text).unwrap();
    let d = cond::check_params(
        &stmt,
        text,
        &def,
        "pxrMaterialOut.diffuseGain",
        &Extensions::none(),
    );
    assert_eq!(d.len(), 1);
    assert!(d[0].message.contains("`enableDiffuse`"));
    assert!(d[0].message.contains("member `pxrMaterialOut.diffuseGain`"));
}

#[test]
fn outputs_do_not_count() {
    let d = check("connect if resultF == 1", &Extensions::none());
    assert_eq!(d.len(), 1);
    assert!(
        d[0].notes
            .iter()
            .any(|n| n.contains("is an output of `PxrTest`")),
        "{d:#?}"
    );
}

#[test]
fn array_suffix_is_literal_unless_array_index() {
    let d = check("connect if arr[1] == 1", &Extensions::none());
    assert_eq!(d.len(), 1);
    assert!(d[0].message.contains("names `arr[1]`"));
    assert!(
        d[0].notes.iter().any(|n| n.contains("--ext array-index")),
        "{d:#?}"
    );
    let ai = Extensions::none().with(Extension::ArrayIndex);
    assert!(check("connect if arr[1] == 1", &ai).is_empty());
    assert_eq!(check("connect if nope[1] == 1", &ai).len(), 1);
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
        (d.code, d.severity, d.span.clone()),
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
    let r = cond::set_value(&lit, Some(&color), &Extensions::none()).unwrap_err();
    assert_eq!(cond::SetRejection::CODE, "VS013");
    assert!(r.to_string().contains("see --ext set-tuples"), "{r}");
    let f = Type::scalar(BaseType::Float);
    let i = Type::scalar(BaseType::Int);
    let r = cond::copy_value(
        Some(&Value::Float(1.0)),
        Some(&f),
        Some(&i),
        &Extensions::none(),
    )
    .unwrap_err();
    assert_eq!(cond::CopyRejection::CODE, "VS014");
    assert!(r.to_string().contains("see --ext copy-convert"), "{r}");
    let s = Type::scalar(BaseType::String);
    let r = cond::copy_value(
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
        cond::copy_plan(&t(BaseType::Color), &t(BaseType::Color), &none),
        Ok(cond::CopyPlan::Same)
    );
    assert!(cond::copy_plan(&t(BaseType::Int), &t(BaseType::Float), &none).is_err());
    assert_eq!(
        cond::copy_plan(&t(BaseType::Int), &t(BaseType::Float), &cc),
        Ok(cond::CopyPlan::IntToFloat)
    );
    assert_eq!(
        cond::copy_plan(&t(BaseType::Float), &t(BaseType::Int), &cc),
        Ok(cond::CopyPlan::FloatToInt)
    );
    assert_eq!(
        cond::copy_plan(&t(BaseType::Int), &t(BaseType::Vector), &cc),
        Ok(cond::CopyPlan::Broadcast)
    );
    assert!(cond::copy_plan(&t(BaseType::Color), &t(BaseType::Float), &cc).is_err());
    assert!(cond::copy_plan(&t(BaseType::Float), &t(BaseType::Matrix), &cc).is_err());
    // Arrays of the same base type: the reference ignores array-ness.
    let arr = Type {
        base: BaseType::Float,
        array: ArraySpec::Fixed(3),
    };
    assert_eq!(
        cond::copy_plan(&arr, &t(BaseType::Float), &none),
        Ok(cond::CopyPlan::Same)
    );
}

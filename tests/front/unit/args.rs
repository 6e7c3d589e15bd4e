//! Unit tests of `front::args` (`src/front/args.rs`).

use proptest::prelude::*;
use quick_xml::XmlVersion;
use quick_xml::events::Event;
use quick_xml::reader::Reader;
use vstructc::diag::Severity;
use vstructc::front::args::*;
use vstructc::{ArraySpec, BaseType, Type, Value};

/// Attributes as quick-xml reads and normalises them: (key, value, value offset in `raw`).
fn quick_xml_attributes(raw: &str) -> Option<Vec<(String, String, usize)>> {
    let tag = format!("<p{raw}/>");
    let mut reader = Reader::from_str(&tag);
    let Ok(Event::Empty(e)) = reader.read_event() else {
        return None;
    };
    let mut out = Vec::new();
    for a in e.attributes() {
        let a = a.ok()?;
        let value = a.normalized_value(XmlVersion::Implicit1_0).ok()?;
        let offset = a.value.as_ptr() as usize - tag.as_ptr() as usize - 2;
        out.push((a.key.as_ref().to_string(), value.into_owned(), offset));
    }
    Some(out)
}

proptest! {
    /// Whenever the plain fast path accepts a tag, it reads exactly what quick-xml reads.
    #[test]
    fn plain_attributes_agree_with_quick_xml(raw in "( {1,2}[a-c_1:]{0,3} ?= ?[\"'][a-c &<\t\"']{0,4}[\"']){0,4} ?") {
        let mut fast = Vec::new();
        if plain_attributes(&raw, 0, &mut fast) {
            let fast: Vec<_> = fast
                .iter()
                .map(|a| (a.key.to_string(), a.value.to_string(), a.offset))
                .collect();
            prop_assert_eq!(Some(fast), quick_xml_attributes(&raw));
        }
    }
}

#[test]
fn plain_attributes_take_the_common_form_and_leave_the_rest() {
    let mut out = Vec::new();
    assert!(plain_attributes(r#" name="a" type='float'"#, 10, &mut out));
    assert_eq!(out.len(), 2);
    assert_eq!(
        (&*out[1].key, &*out[1].value, out[1].offset),
        ("type", "float", 26)
    );
    for other in [
        r#" name = "a""#,     // spaced `=`
        r#" name="a&amp;b""#, // entity
        r#" a="1"b="2""#,     // no whitespace between attributes
        r#" a="1" a="2""#,    // duplicate
        r#" help="x	y""#,     // tab to normalise
        r#" name="unterminated"#,
    ] {
        out.clear();
        assert!(!plain_attributes(other, 0, &mut out), "{other}");
    }
}

fn ty(b: BaseType) -> Type {
    Type::scalar(b)
}

#[test]
fn float_prefix_rules() {
    assert_eq!(float_prefix_len("1."), 2);
    assert_eq!(float_prefix_len(".5"), 2);
    assert_eq!(float_prefix_len("1e-3"), 4);
    assert_eq!(float_prefix_len("-0"), 2);
    assert_eq!(float_prefix_len("1e"), 1);
    assert_eq!(float_prefix_len("."), 0);
    assert_eq!(float_prefix_len("abc"), 0);
    assert_eq!(float_prefix_len("2.5x"), 3);
}

#[test]
fn int_defaults_like_atoi() {
    let d = parse_default(&ty(BaseType::Int), Some("1.0"));
    assert_eq!(d.value, Some(Value::Int(1)));
    let (sev, msg) = d.issue.unwrap();
    assert_eq!(sev, Severity::Warning);
    assert!(msg.contains("1 is used"), "{msg}");
    assert_eq!(
        parse_default(&ty(BaseType::Int), Some("1e3")).value,
        Some(Value::Int(1))
    );
    assert_eq!(
        parse_default(&ty(BaseType::Int), Some("x")).value,
        Some(Value::Int(0))
    );
    let ok = parse_default(&ty(BaseType::Int), Some(" -7 "));
    assert_eq!((ok.value, ok.issue), (Some(Value::Int(-7)), None));
}

#[test]
fn float_defaults() {
    let d = parse_default(&ty(BaseType::Float), Some("0.5f"));
    assert_eq!(d.value, Some(Value::Float(0.5)));
    assert_eq!(d.issue.unwrap().0, Severity::Info);
    let d = parse_default(&ty(BaseType::Float), Some("2.5x"));
    assert_eq!(d.value, Some(Value::Float(2.5)));
    assert_eq!(d.issue.unwrap().0, Severity::Warning);
    let d = parse_default(&ty(BaseType::Float), Some("abc"));
    assert_eq!(d.value, Some(Value::Float(0.0)));
    assert_eq!(d.issue.unwrap().0, Severity::Warning);
    let d = parse_default(&ty(BaseType::Float), Some(".5"));
    assert_eq!((d.value, d.issue), (Some(Value::Float(0.5)), None));
}

#[test]
fn absent_and_empty_defaults() {
    assert_eq!(
        parse_default(&ty(BaseType::Float), None).value,
        Some(Value::Float(0.0))
    );
    assert_eq!(
        parse_default(&ty(BaseType::String), None).value,
        Some(Value::Str(String::new()))
    );
    assert_eq!(
        parse_default(&ty(BaseType::Color), Some("")).value,
        Some(Value::Triple(BaseType::Color, [0.0; 3]))
    );
    assert_eq!(parse_default(&ty(BaseType::Matrix), None).value, None);
    assert_eq!(parse_default(&ty(BaseType::Vstruct), Some("1")).value, None);
    assert_eq!(
        parse_default(&ty(BaseType::Struct(None)), Some("1")).value,
        None
    );
    assert_eq!(
        parse_default(&ty(BaseType::Terminal("bxdf".into())), Some("1")).value,
        None
    );
}

#[test]
fn triples_need_three_numbers() {
    let d = parse_default(&ty(BaseType::Color), Some("0.18, 0.18 0.18"));
    assert_eq!(d.value, Some(Value::Triple(BaseType::Color, [0.18; 3])));
    assert!(d.issue.is_none());
    let d = parse_default(&ty(BaseType::Normal), Some("0 0"));
    assert_eq!(d.value, Some(Value::Triple(BaseType::Normal, [0.0; 3])));
    assert_eq!(d.issue.unwrap().0, Severity::Warning);
    let d = parse_default(&ty(BaseType::Matrix), Some("1 0 0"));
    assert_eq!(d.value, None);
    assert!(d.issue.is_some());
}

#[test]
fn string_scalar_is_verbatim() {
    let d = parse_default(&ty(BaseType::String), Some(" a, b "));
    assert_eq!(d.value, Some(Value::Str(" a, b ".into())));
}

#[test]
fn arrays() {
    let fixed = Type {
        base: BaseType::Float,
        array: ArraySpec::Fixed(3),
    };
    let d = parse_default(&fixed, Some("1 2"));
    assert_eq!(
        d.value,
        Some(Value::Array(
            BaseType::Float,
            vec![Value::Float(1.0), Value::Float(2.0), Value::Float(0.0)]
        ))
    );
    assert!(d.issue.is_some());
    let d = parse_default(&fixed, Some("1 2 3 4"));
    assert_eq!(
        d.value.as_ref().map(|v| v.numbers()),
        Some(vec![1.0, 2.0, 3.0])
    );
    let dynamic = Type {
        base: BaseType::Color,
        array: ArraySpec::Dynamic,
    };
    let d = parse_default(&dynamic, Some("1 1 1 2 2"));
    assert_eq!(
        d.value.as_ref().map(|v| v.numbers()),
        Some(vec![1.0, 1.0, 1.0])
    );
    assert!(d.issue.is_some());
    let d = parse_default(&dynamic, Some(""));
    assert_eq!(d.value, Some(Value::Array(BaseType::Color, vec![])));
    assert_eq!(parse_default(&dynamic, None).value, None);
    let strings = Type {
        base: BaseType::String,
        array: ArraySpec::Dynamic,
    };
    let d = parse_default(&strings, Some("a b,c"));
    assert_eq!(
        d.value.map(|v| v.to_string()),
        Some("[\"a\", \"b\", \"c\"]".into())
    );
}

#[test]
fn member_split() {
    assert_eq!(split_member("a.b.c"), Some(("a".into(), "b.c".into())));
    assert_eq!(split_member("ab"), None);
    assert_eq!(split_member(".x"), None);
    assert_eq!(split_member("x."), None);
    assert_eq!(split_member(""), None);
    assert_eq!(
        split_member("inputMaterial. diffuseGain"),
        Some(("inputMaterial".into(), " diffuseGain".into()))
    );
}

#[test]
fn booleans() {
    for f in ["0", "false", "False", "F", "f", "FALSE"] {
        assert!(!args_bool(f, true), "{f}");
    }
    for t in ["1", "true", "yes", "T"] {
        assert!(args_bool(t, false), "{t}");
    }
    assert!(args_bool("", true));
    assert!(!args_bool("", false));
}

#[test]
fn options_attribute() {
    assert_eq!(
        parse_options_attr("a|b"),
        vec![("a".into(), "a".into()), ("b".into(), "b".into())]
    );
    assert_eq!(
        parse_options_attr("Off:0|On:1")[1],
        ("On".into(), "1".into())
    );
}

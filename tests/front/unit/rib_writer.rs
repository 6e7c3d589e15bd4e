//! Unit tests of `back::rib` (`src/back/rib.rs`).

use vstructc::back::rib::*;
use vstructc::{BaseType, Type, Value};

#[test]
fn value_formatting() {
    assert_eq!(format_value(&Value::Float(0.1)), "[0.1]");
    assert_eq!(format_value(&Value::Float(1.0)), "[1]");
    assert_eq!(format_value(&Value::Int(-3)), "[-3]");
    assert_eq!(
        format_value(&Value::Triple(BaseType::Color, [0.5, 1.0, 0.25])),
        "[0.5 1 0.25]"
    );
    assert_eq!(
        format_value(&Value::Array(
            BaseType::String,
            vec![Value::Str("a".into()), Value::Str("b\\".into())]
        )),
        r#"["a" "b\\"]"#
    );
}

fn value_type_text(v: &Value) -> String {
    let mut t = Vec::new();
    push_value_type(&mut t, v);
    String::from_utf8(t).unwrap()
}

#[test]
fn pushed_values_are_formatted_values() {
    for v in [
        Value::Int(-7),
        Value::Int(0),
        Value::Int(9),
        Value::Int(10),
        Value::Int(-10),
        Value::Int(i32::MAX),
        Value::Int(i32::MIN),
        Value::Float(0.1),
        Value::Float(1.0),
        Value::Float(f32::INFINITY),
        Value::Float(f32::NAN),
        Value::Float(-3.0e-40),
        Value::Triple(BaseType::Color, [0.5, 1.0, 0.25]),
        Value::Str("a\"b".into()),
    ] {
        let mut t = Vec::new();
        push_value(&mut t, &v);
        assert_eq!(String::from_utf8(t).unwrap(), format_value(&v), "{v:?}");
    }
}

#[test]
fn value_type_texts() {
    assert_eq!(value_type_text(&Value::Int(1)), "int");
    assert_eq!(value_type_text(&Value::Bool(true)), "int");
    assert_eq!(value_type_text(&Value::Token("x".into())), "string");
    assert_eq!(
        value_type_text(&Value::Array(BaseType::Int, vec![Value::Int(0)])),
        "int[1]"
    );
    assert_eq!(
        value_type_text(&Value::Triple(BaseType::Normal, [0.0; 3])),
        "normal"
    );
}

#[test]
fn fits() {
    let f2 = Type::parse_decl("float2");
    assert!(value_fits(
        &f2,
        &Value::Array(BaseType::Float, vec![Value::Float(1.0), Value::Float(2.0)])
    ));
    assert!(!value_fits(&f2, &Value::Float(1.0)));
    assert!(value_fits(
        &Type::scalar(BaseType::Color),
        &Value::Triple(BaseType::Color, [0.0; 3])
    ));
    assert!(!value_fits(
        &Type::scalar(BaseType::Vector),
        &Value::Triple(BaseType::Color, [0.0; 3])
    ));
    assert!(!value_fits(&Type::scalar(BaseType::Float), &Value::Int(1)));
}

#[test]
fn escapes() {
    assert_eq!(escape("tab\there"), "tab\\there");
    assert_eq!(escape("\u{7f}é"), "\\177é");
}

#[test]
fn only_strings_with_a_special_byte_are_escaped() {
    // Every ASCII byte (and a two-byte character) at every position of strings up to 40
    // bytes (two whole vectors and a part): the vector check must agree with the
    // byte-by-byte rule.
    let special = |c: char| c < ' ' || c == '\u{7f}' || c == '"' || c == '\\';
    for len in 0usize..40 {
        for at in 0..len.max(1) {
            for c in (0u8..0x80).map(char::from).chain(['é']) {
                let mut s: String = "name_x".chars().cycle().take(len).collect();
                s.insert(at.min(s.len()), c);
                let borrowed = matches!(escape(&s), std::borrow::Cow::Borrowed(_));
                assert_eq!(borrowed, !special(c), "{s:?}");
            }
        }
    }
}

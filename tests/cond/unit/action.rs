//! Unit tests of `cond::action` (`src/cond/action.rs`).

use vstructc::cond::internals::*;
use vstructc::cond::*;
use vstructc::{BaseType, Type, Value};

#[test]
fn truncation_saturates() {
    assert_eq!(truncate_to_i32(1.9), (1, false));
    assert_eq!(truncate_to_i32(-0.5), (0, false));
    assert_eq!(truncate_to_i32(-1.9), (-1, false));
    assert_eq!(truncate_to_i32(2147483647.9), (i32::MAX, false));
    assert_eq!(truncate_to_i32(2147483648.0), (i32::MAX, true));
    assert_eq!(truncate_to_i32(-2147483648.5), (i32::MIN, false));
    assert_eq!(truncate_to_i32(-2147483649.0), (i32::MIN, true));
    assert_eq!(truncate_to_i32(f64::INFINITY), (i32::MAX, true));
}

fn number(text: &str) -> Literal {
    Literal::number(text, 0..text.len()).expect("a number")
}

#[test]
fn set_saturates_floats_beyond_the_f32_range() {
    let float = Type::scalar(BaseType::Float);
    let none = Extensions::none();
    let big = set_value(&number("1e39"), Some(&float), &none).unwrap();
    assert_eq!(big.value, Value::Float(f32::MAX));
    assert!(big.saturated);
    let small = set_value(&number("-1e39"), Some(&float), &none).unwrap();
    assert_eq!(small.value, Value::Float(f32::MIN));
    assert!(small.saturated);
    let inf = set_value(&number("1e400"), Some(&float), &none).unwrap();
    assert_eq!(inf.value, Value::Float(f32::MAX));
    let max = set_value(&number("3.4028235e38"), Some(&float), &none).unwrap();
    assert_eq!((max.value, max.saturated), (Value::Float(f32::MAX), false));
    let tiny = set_value(&number("1e-60"), Some(&float), &none).unwrap();
    assert_eq!((tiny.value, tiny.saturated), (Value::Float(0.0), false));
    let color = Type::scalar(BaseType::Color);
    let tuples = Extensions::none().with(Extension::SetTuples);
    let c = set_value(&number("-1e39"), Some(&color), &tuples).unwrap();
    assert_eq!(c.value, Value::Triple(BaseType::Color, [f32::MIN; 3]));
    assert!(c.saturated);
}

#[test]
fn copy_saturates_non_finite_sources() {
    let color = Type::scalar(BaseType::Color);
    let v = Value::Triple(BaseType::Color, [f32::INFINITY, f32::NAN, 0.5]);
    let Ok(CopyOutcome::Write {
        value, saturated, ..
    }) = copy_value(Some(&v), Some(&color), Some(&color), &Extensions::none())
    else {
        panic!("copy refused")
    };
    assert_eq!(value, Value::Triple(BaseType::Color, [f32::MAX, 0.0, 0.5]));
    assert!(saturated);
    let float = Type::scalar(BaseType::Float);
    let arr = Value::Array(BaseType::Float, vec![Value::Float(f32::NEG_INFINITY)]);
    let Ok(CopyOutcome::Write {
        value, saturated, ..
    }) = copy_value(Some(&arr), Some(&float), Some(&float), &Extensions::none())
    else {
        panic!("copy refused")
    };
    assert_eq!(
        value,
        Value::Array(BaseType::Float, vec![Value::Float(f32::MIN)])
    );
    assert!(saturated);
    let fine = Value::Float(1.0);
    let Ok(CopyOutcome::Write { saturated, .. }) =
        copy_value(Some(&fine), Some(&float), Some(&float), &Extensions::none())
    else {
        panic!("copy refused")
    };
    assert!(!saturated);
}

#[test]
fn convert_is_elementwise() {
    let v = Value::Array(BaseType::Int, vec![Value::Int(1), Value::Int(-2)]);
    assert_eq!(
        convert(&v, &BaseType::Float),
        Value::Array(BaseType::Float, vec![Value::Float(1.0), Value::Float(-2.0)])
    );
    assert_eq!(convert(&Value::Float(-2.7), &BaseType::Int), Value::Int(-2));
}

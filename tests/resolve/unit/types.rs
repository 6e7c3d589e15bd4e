//! Unit tests of `types` (`src/types.rs`).

use vstructc::types::*;

#[test]
fn type_words_round_trip() {
    for w in [
        "int", "float", "string", "color", "point", "vector", "normal", "matrix", "hpoint",
        "vstruct", "bxdf", "token", "asset", "bool",
    ] {
        assert_eq!(BaseType::from_word(w).word(), w);
    }
    assert_eq!(
        BaseType::from_word("message"),
        BaseType::Unknown("message".into())
    );
    assert_eq!(Type::parse_decl("float2").to_string(), "float[2]");
}

#[test]
fn component_counts() {
    assert_eq!(BaseType::Color.components(), 3);
    assert_eq!(BaseType::HPoint.components(), 4);
    assert_eq!(BaseType::Matrix.components(), 16);
    assert_eq!(BaseType::String.components(), 1);
    assert_eq!(BaseType::Vstruct.components(), 0);
}

#[test]
fn widening_is_exact() {
    assert_eq!(Value::Float(0.2).as_f64(), Some(f64::from(0.2f32)));
    assert_ne!(Value::Float(0.2).as_f64(), Some(0.2));
    assert_eq!(Value::Bool(true).as_f64(), Some(1.0));
    assert_eq!(Value::Str("1".into()).as_f64(), None);
}

#[test]
fn shortest_float_text_reads_back() {
    for x in [0.1f32, 0.009_674_47, 1.0, 3.05, 1e38] {
        assert_eq!(format_f32(x).parse::<f32>().unwrap(), x);
    }
}

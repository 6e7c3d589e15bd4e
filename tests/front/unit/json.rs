//! Unit tests of `front::json` (`src/front/json.rs`).

use vstructc::diag::{Diagnostics, Error};
use vstructc::front::json::*;
use vstructc::network::Network;
use vstructc::{ArraySpec, BaseType, Type, Value};

fn tree(s: &str) -> Result<Network, Error> {
    let mut diags = Diagnostics::new();
    parse_json(
        s.as_bytes(),
        "t.json",
        &vstructc::network::NoDefinitions,
        &mut diags,
    )
}

#[test]
fn duplicate_keys_are_js002_with_pointer_and_position() {
    let e = tree("{\"a\": {\"b\": 1,\n \"b\": 2}}").unwrap_err();
    let d = e.diagnostic().unwrap();
    assert_eq!(d.code, "JS002");
    let loc = d.location.as_ref().unwrap();
    assert_eq!(loc.pointer.as_deref(), Some("/a/b"));
    assert_eq!(loc.line, 2);
}

#[test]
fn syntax_errors_are_js001_with_position() {
    let e = tree("{\n  \"a\": ,\n}").unwrap_err();
    let d = e.diagnostic().unwrap();
    assert_eq!(d.code, "JS001");
    let loc = d.location.as_ref().unwrap();
    assert_eq!((loc.line, loc.column), (2, 8));
    assert_eq!(tree("[1] x").unwrap_err().code(), Some("JS001"));
    assert_eq!(tree("").unwrap_err().code(), Some("JS001"));
}

#[test]
fn duplicate_keys_are_found_in_large_objects() {
    // Objects beyond SeenKeys::SCAN keys switch to a hash set: duplicates of an early and
    // of a late key are both found, with their pointers.
    for dup in ["k3", "k19"] {
        let mut text = String::from("{\"x\": {");
        for i in 0..20 {
            text.push_str(&format!("\"k{i}\": {i}, "));
        }
        text.push_str(&format!("\"{dup}\": 0}}}}"));
        let e = tree(&text).unwrap_err();
        let d = e.diagnostic().unwrap();
        assert_eq!(d.code, "JS002");
        let pointer = d.location.as_ref().unwrap().pointer.clone();
        assert_eq!(pointer, Some(format!("/x/{dup}")));
    }
}

#[test]
fn pointer_escaping() {
    assert_eq!(escape_pointer("a/b~c"), "a~1b~0c");
    let e = tree("{\"x/y\": {\"~\": 1, \"~\": 2}}").unwrap_err();
    let loc = e.diagnostic().unwrap().location.clone().unwrap();
    assert_eq!(loc.pointer.as_deref(), Some("/x~1y/~0"));
}

#[test]
fn types_and_values() {
    assert_eq!(
        parse_type("float[2]"),
        Some(Type {
            base: BaseType::Float,
            array: ArraySpec::Fixed(2)
        })
    );
    assert_eq!(
        parse_type("int[]").map(|t| t.array),
        Some(ArraySpec::Dynamic)
    );
    assert_eq!(parse_type("vstruct"), None);
    assert_eq!(parse_type("float[x]"), None);
    let t = Type::scalar(BaseType::Int);
    assert_eq!(to_value(&t, &J::Num(Num::F(2.0))), Ok(Value::Int(2)));
    assert!(to_value(&t, &J::Num(Num::F(2.5))).is_err());
    assert!(to_value(&t, &J::Num(Num::I(1 << 40))).is_err());
    let c = Type::scalar(BaseType::Color);
    let arr = J::Arr(vec![
        J::Num(Num::I(1)),
        J::Num(Num::F(0.5)),
        J::Num(Num::U(0)),
    ]);
    assert_eq!(
        to_value(&c, &arr),
        Ok(Value::Triple(BaseType::Color, [1.0, 0.5, 0.0]))
    );
    assert!(to_value(&Type::scalar(BaseType::Float), &J::Num(Num::F(1e39))).is_err());
}

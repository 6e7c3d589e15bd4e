//! Unit tests of `front::rib` (`src/front/rib.rs`).

use vstructc::diag::Diagnostics;
use vstructc::front::rib::*;
use vstructc::network::Network;
use vstructc::network::NoDefinitions;
use vstructc::{ArraySpec, BaseType, Type, Value};

fn read(src: &str) -> (Network, Diagnostics) {
    let mut d = Diagnostics::new();
    let net = parse_rib(
        src.as_bytes(),
        "t.rib",
        &NoDefinitions,
        &RibOptions::default(),
        &mut d,
    )
    .unwrap();
    (net, d)
}

/// Declarations and values are shared between nodes only when reading them reported
/// nothing: a repeated declaration or value with a finding reports it at every place.
#[test]
fn repeated_findings_are_reported_each_time() {
    let (net, d) = read(
        "Pattern \"P\" \"a\" \"uniform bogus x\" [1] \"int n\" [1.5] \"float f\" [2] \"reference float r\" [1]\n\
         Pattern \"P\" \"b\" \"uniform bogus x\" [1] \"int n\" [1.5] \"float f\" [2] \"reference float r\" [1]\n",
    );
    assert_eq!(d.count("RB013"), 2, "{d:?}");
    assert_eq!(d.count("RB014"), 4, "{d:?}");
    let lines: Vec<u32> = d
        .with_code("RB014")
        .filter_map(|x| x.location.as_ref().map(|l| l.line))
        .collect();
    assert_eq!(lines, [1, 1, 2, 2]);
    // A parameter shared with an earlier node keeps its own position.
    let b = &net[net.find("b").unwrap()];
    let at = b.param_location(b.param("f").unwrap()).unwrap();
    assert_eq!((at.line, at.column), (2, 53));
}

/// Parameters of different nodes with the same declaration and value share them, and
/// read the same as when each is read alone.
#[test]
fn repeated_declarations_and_values_are_shared() {
    let (net, d) = read(
        "Pattern \"P\" \"a\" \"float f\" [2] \"color c\" [1 0 0]\n\
         Pattern \"P\" \"b\" \"float f\" [2] \"color c\" [1 0 1]\n\
         Pattern \"Q\" \"c\" \"float f\" [2]\n\
         Pattern \"R\" \"d\" \"reference float x\" [\"a:resultF\"]\n\
         Pattern \"R\" \"e\" \"reference float x\" [\"b:resultF\"]\n",
    );
    assert!(d.is_empty(), "{d:?}");
    let out = |h: &str| net.connections(net.find(h).unwrap(), "x")[0].output();
    let (d_out, e_out) = (out("d").unwrap(), out("e").unwrap());
    assert_eq!(d_out, "resultF");
    assert!(std::ptr::eq(d_out, e_out));
    assert_eq!(
        net.connections(net.find("e").unwrap(), "x")[0].upstream_node(),
        net.find("b")
    );
    let p = |h: &str, n: &str| net[net.find(h).unwrap()].param(n).unwrap();
    assert!(std::ptr::eq(
        p("a", "f").decl().unwrap(),
        p("b", "f").decl().unwrap()
    ));
    assert!(std::ptr::eq(
        p("a", "f").value().unwrap(),
        p("b", "f").value().unwrap()
    ));
    assert_eq!(p("c", "f").value(), Some(&Value::Float(2.0)));
    assert_eq!(
        p("b", "c").value(),
        Some(&Value::Triple(BaseType::Color, [1.0, 0.0, 1.0]))
    );
    assert_ne!(p("a", "c").value(), p("b", "c").value());
}

#[test]
fn decl_words() {
    let d = split_decl("reference struct manifold").unwrap();
    assert!(d.reference);
    assert_eq!((d.type_word, d.name), (Some("struct"), "manifold"));
    let d = split_decl("float[2] PixelFilterWidth").unwrap();
    assert_eq!((d.type_word, d.array), (Some("float"), Some("2")));
    let d = split_decl("uniform float [3]  x").unwrap();
    assert_eq!(
        (d.class, d.type_word, d.array),
        (Some("uniform"), Some("float"), Some("3"))
    );
    let d = split_decl("diffuseGain").unwrap();
    assert_eq!((d.type_word, d.name), (None, "diffuseGain"));
    let d = split_decl("reference x").unwrap();
    assert_eq!((d.reference, d.type_word), (true, None));
    let d = split_decl("foo bar float x").unwrap();
    assert_eq!(d.extra, vec!["foo", "bar"]);
    assert!(split_decl("  ").is_none());
}

#[test]
fn compatible_types() {
    let f = Type::scalar(BaseType::Float);
    let i = Type::scalar(BaseType::Int);
    let f2 = Type::parse_decl("float2");
    let int_dyn = Type {
        base: BaseType::Int,
        array: ArraySpec::Dynamic,
    };
    let int1 = Type {
        base: BaseType::Int,
        array: ArraySpec::Fixed(1),
    };
    assert!(types_compatible(&f, &f));
    assert!(!types_compatible(&f, &i));
    assert!(!types_compatible(&f, &f2));
    assert!(types_compatible(&int1, &int_dyn));
    assert!(types_compatible(&int1, &i));
    assert!(types_compatible(
        &Type::scalar(BaseType::Struct(None)),
        &Type::scalar(BaseType::Struct(Some("manifold".into())))
    ));
}

#[test]
fn int_parsing() {
    let mut notes = Vec::new();
    let mut note = |s: String| notes.push(s);
    assert_eq!(parse_int("7", &mut note), Some(7));
    assert_eq!(parse_int("1.", &mut note), Some(1));
    assert_eq!(parse_int("1e2", &mut note), Some(100));
    assert_eq!(parse_int("99999999999", &mut note), Some(i32::MAX));
    assert_eq!(parse_int("1.5", &mut note), None);
    assert_eq!(notes.len(), 2);
}

/// Source ranges are kept as 32-bit offsets from the request's start: a part of a request
/// more than 4 GiB from its start is refused (RB021), not truncated.
#[test]
fn request_offsets_fit_in_32_bits_or_are_refused() {
    let start = 5usize << 32;
    let max = u32::MAX as usize;
    assert_eq!(in_request(start, start + 3..start + 9), Some(3..9));
    assert_eq!(in_request(start, start..start + max), Some(0..u32::MAX));
    assert_eq!(in_request(start, start..start + max + 1), None);
    assert_eq!(in_request(start, start - 1..start), None);
}

//! RIB reader: every RB code on a small input (tests/data/rib), with its position; network
//! assembly rules (formats.md §3.3–§3.6); random input never panics.

use crate::common::network as network_common;

use network_common::{Table, codes};
use proptest::prelude::*;
use std::path::PathBuf;
use vstructc::front::rib::{RibOptions, parse_rib};
use vstructc::network::{Link, Network, NoDefinitions, ParamTypes, RequestKind, Upstream};
use vstructc::{ArraySpec, BaseType, Diagnostics, Error, Severity, Type, Value};

fn defs() -> Table {
    Table::new()
        .shader(
            "PxrFractal",
            &[("layers", "int"), ("frequency", "float")],
            &[("resultF", "float"), ("resultRGB", "color")],
        )
        .shader(
            "PxrSurface",
            &[("diffuseGain", "float"), ("diffuseColor", "color")],
            &[("bxdf_out", "bxdf")],
        )
}

fn data(name: &str) -> Vec<u8> {
    let p = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/rib")
        .join(name);
    std::fs::read(&p).unwrap_or_else(|e| panic!("{}: {e}", p.display()))
}

fn parse_with(
    src: &[u8],
    types: &(dyn ParamTypes + Sync),
) -> (Result<Network, Error>, Diagnostics) {
    let mut d = Diagnostics::new();
    let r = parse_rib(src, "t.rib", types, &RibOptions::default(), &mut d);
    (r, d)
}

fn parse(src: &str) -> (Network, Diagnostics) {
    let (r, d) = parse_with(src.as_bytes(), &NoDefinitions);
    (r.unwrap_or_else(|e| panic!("{e}")), d)
}

/// (file, code, severity, line, column, with definitions)
const CASES: &[(&str, &str, Severity, u32, u32, bool)] = &[
    ("rb001_gzip.rib", "RB001", Severity::Error, 1, 1, false),
    ("rb002_binary.rib", "RB002", Severity::Error, 4, 3, false),
    (
        "rb003_unterminated.rib",
        "RB003",
        Severity::Error,
        2,
        19,
        false,
    ),
    (
        "rb004_unexpected.rib",
        "RB004",
        Severity::Error,
        2,
        21,
        false,
    ),
    ("rb005_mixed.rib", "RB005", Severity::Error, 2, 24, false),
    ("rb006_no_type.rib", "RB006", Severity::Error, 2, 3, false),
    ("rb007_no_value.rib", "RB007", Severity::Error, 3, 3, false),
    (
        "rb008_empty_output.rib",
        "RB008",
        Severity::Error,
        3,
        3,
        false,
    ),
    ("rb010_escape.rib", "RB010", Severity::Info, 2, 25, false),
    (
        "rb011_single_quote.rib",
        "RB011",
        Severity::Info,
        2,
        22,
        false,
    ),
    (
        "rb012_type_from_definition.rib",
        "RB012",
        Severity::Warning,
        2,
        3,
        true,
    ),
    (
        "rb013_unknown_type.rib",
        "RB013",
        Severity::Warning,
        2,
        3,
        false,
    ),
    ("rb014_count.rib", "RB014", Severity::Warning, 2, 3, false),
    (
        "rb015_duplicate.rib",
        "RB015",
        Severity::Warning,
        3,
        3,
        false,
    ),
    (
        "rb016_type_mismatch.rib",
        "RB016",
        Severity::Warning,
        2,
        3,
        true,
    ),
    (
        "rb017_redefined.rib",
        "RB017",
        Severity::Warning,
        2,
        1,
        false,
    ),
    ("rb018_forward.rib", "RB018", Severity::Warning, 2, 3, false),
    (
        "rb019_unknown_shader.rib",
        "RB019",
        Severity::Warning,
        3,
        1,
        true,
    ),
    ("rb020_legacy.rib", "RB020", Severity::Info, 1, 1, false),
];

#[test]
fn every_rb_code_with_position() {
    let table = defs();
    for &(file, code, severity, line, column, with_defs) in CASES {
        let types: &(dyn ParamTypes + Sync) = if with_defs { &table } else { &NoDefinitions };
        let (r, d) = parse_with(&data(file), types);
        let diag = match (&r, severity) {
            (Err(e), Severity::Error) => e.diagnostic().unwrap().clone(),
            (Err(e), _) => panic!("{file}: unexpected error {e}"),
            (Ok(_), Severity::Error) => {
                panic!("{file}: expected error {code}, got {:?}", codes(&d))
            }
            (Ok(_), _) => d
                .with_code(code)
                .next()
                .unwrap_or_else(|| panic!("{file}: no {code} in {:?}", codes(&d)))
                .clone(),
        };
        assert_eq!(diag.code.as_str(), code, "{file}");
        assert_eq!(diag.severity, severity, "{file}");
        let loc = diag.location.as_ref().unwrap();
        assert_eq!(
            (&*loc.file, loc.line, loc.column),
            ("t.rib", line, column),
            "{file}: {diag}"
        );
    }
}

/// Each parameter's findings come in its turn, and a connection's (RB018) after its
/// declaration's (RB013): the order the parameters are written in.
#[test]
fn a_parameters_findings_come_in_its_turn() {
    let src = concat!(
        "Pattern \"PxrFractal\" \"e\" \"bogus float a\" [1]",
        " \"odd reference float b\" [\"nowhere:out\"] \"extra int c\" [2]\n",
    );
    let (r, d) = parse_with(src.as_bytes(), &NoDefinitions);
    assert!(r.is_ok(), "{r:?}");
    assert_eq!(codes(&d), ["RB013", "RB013", "RB018", "RB013"], "{d:?}");
    let columns: Vec<_> = d
        .iter()
        .map(|x| x.location.as_ref().map(|l| l.column))
        .collect();
    assert_eq!(columns, [Some(26), Some(46), Some(46), Some(86)]);
}

#[test]
fn error_details() {
    let (r, _) = parse_with(&data("rb002_binary.rib"), &NoDefinitions);
    assert!(r.unwrap_err().to_string().contains("offset 61"));
    // Two unknown escapes, each reported; the string reads the characters themselves.
    let (r, d) = parse_with(&data("rb010_escape.rib"), &NoDefinitions);
    assert_eq!(d.count("RB010"), 2);
    let net = r.unwrap();
    let tex = net.find("tex").unwrap();
    assert_eq!(
        net.value(tex, "filename"),
        Some(&Value::Str("C:mapswood.tex".into()))
    );
    // RB015: the later value wins.
    let (r, _) = parse_with(&data("rb015_duplicate.rib"), &NoDefinitions);
    let net = r.unwrap();
    assert_eq!(
        net.value(net.find("noise").unwrap(), "layers"),
        Some(&Value::Int(3))
    );
    // RB012: the type comes from the definition.
    let (r, _) = parse_with(&data("rb012_type_from_definition.rib"), &defs());
    let net = r.unwrap();
    let n = net.find("noise").unwrap();
    assert_eq!(net.value(n, "frequency"), Some(&Value::Float(2.0)));
    assert!(
        !net[n]
            .param("frequency")
            .unwrap()
            .decl()
            .unwrap()
            .inline_type
    );
    // RB014: kept as written.
    let (r, _) = parse_with(&data("rb014_count.rib"), &NoDefinitions);
    let net = r.unwrap();
    assert_eq!(
        net.value(net.find("surf").unwrap(), "diffuseColor"),
        Some(&Value::Array(
            BaseType::Color,
            vec![Value::Float(0.5), Value::Float(0.5)]
        ))
    );
    // RB013: unknown type kept raw.
    let (r, _) = parse_with(&data("rb013_unknown_type.rib"), &NoDefinitions);
    let net = r.unwrap();
    assert_eq!(
        net.value(net.find("noise").unwrap(), "note"),
        Some(&Value::Array(
            BaseType::Unknown("message".into()),
            vec![Value::Str("hi".into())]
        ))
    );
    // No RB019 without definitions.
    let (_, d) = parse_with(&data("rb019_unknown_shader.rib"), &NoDefinitions);
    assert_eq!(d.count("RB019"), 0);
    let (_, d) = parse_with(&data("rb019_unknown_shader.rib"), &defs());
    assert_eq!(d.count("RB019"), 1);
    // RB016 fires for connections too, but never on a placeholder head.
    let heads = Table::new()
        .shader("M", &[("baselayer", "vstruct"), ("mask", "float")], &[])
        .shader(
            "L",
            &[],
            &[("pxrMaterialOut", "vstruct"), ("resultRGB", "color")],
        );
    let src = br#"Pattern "L" "l"
Pattern "M" "m" "reference float baselayer" ["l:pxrMaterialOut"] "reference color mask" ["l:resultRGB"]"#;
    let (r, d) = parse_with(src, &heads);
    r.unwrap();
    assert_eq!(d.count("RB016"), 1);
    assert!(
        d.with_code("RB016")
            .next()
            .unwrap()
            .message
            .contains("mask")
    );
}

#[test]
fn strict_rib_rejects_single_quotes() {
    let mut d = Diagnostics::new();
    let e = parse_rib(
        &data("rb011_single_quote.rib"),
        "t.rib",
        &NoDefinitions,
        &RibOptions {
            strict: true,
            ..RibOptions::default()
        },
        &mut d,
    )
    .unwrap_err();
    assert_eq!(e.code(), Some("RB011"));
    assert_eq!(e.diagnostic().unwrap().severity, Severity::Error);
}

#[test]
fn more_errors() {
    for (src, code) in [
        ("Pattern \"A\" \"a\" \"float x\" [1 [2]]", "RB004"),
        ("Pattern \"A\" \"a\" \"float x\" 1 ]", "RB004"),
        ("Pattern \"A\" \"a\" \"float x\" [1 2", "RB004"),
        ("Pattern \"A\" \"a\" \"float x\" [1 Sphere", "RB004"),
        ("Pattern \"A\"", "RB004"),
        ("Pattern 1 \"a\"", "RB004"),
        ("Pattern \"A\" \"a\" [1] [2]", "RB004"),
        ("\"orphan\" Pattern \"A\" \"a\"", "RB004"),
        ("Pattern \"A\" \"a\" \"\" [1]", "RB006"),
        ("Option \"x\" \"float y\" [1 \"z\"]", "RB005"),
    ] {
        let (r, _) = parse_with(src.as_bytes(), &NoDefinitions);
        assert_eq!(r.err().and_then(|e| e.code()), Some(code), "{src}");
    }
}

#[test]
fn decl_forms_and_values() {
    let (net, d) = parse(
        r#"Pattern "P" "p"
    "float[2] a" [1 2]
    "float [3] b" [1 2 3]
    "uniform float c" [0.]
    "float2 d" [.5 -0]
    "point e" [1 2 3]
    "hpoint f" [1 2 3 4]
    "matrix g" [1 0 0 0 0 1 0 0 0 0 1 0 0 0 0 1]
    "string h" "bare"
    "int i" 7
    "float j" [9.99999968e+37]
    "normal[2] k" [0 0 1 0 1 0]
    "int l" [1.]
"#,
    );
    assert!(d.is_empty(), "{:?}", codes(&d));
    let p = net.find("p").unwrap();
    let arr = |b: BaseType, v: Vec<f32>| Value::Array(b, v.into_iter().map(Value::Float).collect());
    assert_eq!(
        net.value(p, "a"),
        Some(&arr(BaseType::Float, vec![1.0, 2.0]))
    );
    assert_eq!(
        net.value(p, "b"),
        Some(&arr(BaseType::Float, vec![1.0, 2.0, 3.0]))
    );
    assert_eq!(net.value(p, "c"), Some(&Value::Float(0.0)));
    assert_eq!(
        net[p].param("c").unwrap().decl().unwrap().class.as_deref(),
        Some("uniform")
    );
    assert_eq!(
        net.value(p, "d"),
        Some(&arr(BaseType::Float, vec![0.5, -0.0]))
    );
    assert_eq!(
        net.value(p, "e"),
        Some(&Value::Triple(BaseType::Point, [1.0, 2.0, 3.0]))
    );
    assert_eq!(
        net.value(p, "f"),
        Some(&Value::HPoint([1.0, 2.0, 3.0, 4.0]))
    );
    assert!(matches!(net.value(p, "g"), Some(Value::Matrix(m)) if m[0] == 1.0 && m[15] == 1.0));
    assert_eq!(net.value(p, "h"), Some(&Value::Str("bare".into())));
    assert_eq!(net.value(p, "i"), Some(&Value::Int(7)));
    assert_eq!(
        net.value(p, "j"),
        Some(&Value::Float("9.99999968e+37".parse().unwrap()))
    );
    assert_eq!(
        net.value(p, "k"),
        Some(&Value::Array(
            BaseType::Normal,
            vec![
                Value::Triple(BaseType::Normal, [0.0, 0.0, 1.0]),
                Value::Triple(BaseType::Normal, [0.0, 1.0, 0.0])
            ]
        ))
    );
    assert_eq!(net.value(p, "l"), Some(&Value::Int(1)));
    let decl_b = net[p].param("b").unwrap().decl().unwrap();
    assert_eq!(
        decl_b.ty,
        Type {
            base: BaseType::Float,
            array: ArraySpec::Fixed(3)
        }
    );
    // Order of parameters is the source order.
    let names: Vec<&str> = net[p].params().map(|p| p.name()).collect();
    assert_eq!(
        names,
        ["a", "b", "c", "d", "e", "f", "g", "h", "i", "j", "k", "l"]
    );
}

#[test]
fn value_problems_are_rb014() {
    for (decl, value) in [
        ("int x", "[1.5]"),
        ("float x", "[\"s\"]"),
        ("string x", "[1]"),
        ("color x", "[]"),
        ("struct x", "[1]"),
        ("float x", "[1e39]"),
        ("int x", "[99999999999]"),
    ] {
        let (_, d) = parse(&format!("Pattern \"P\" \"p\" \"{decl}\" {value}"));
        assert_eq!(codes(&d), ["RB014"], "{decl} {value}");
    }
    let (net, _) = parse("Pattern \"P\" \"p\" \"float x\" [1e39]");
    assert_eq!(
        net.value(net.find("p").unwrap(), "x"),
        Some(&Value::Float(f32::MAX))
    );
}

#[test]
fn connections_split_at_last_colon() {
    let (net, d) = parse(
        r#"Pattern "PxrFractal" "ns:sub:Fractal 1|x"
Pattern "PxrSurface" "plain|surf"
Pattern "PxrBlend" "b"
    "reference float[2] inputs" ["ns:sub:Fractal 1|x:resultF" "ns:sub:Fractal 1|x:resultG"]
    "reference bxdf shading" ["plain|surf"]
    "reference bxdf colonHandle" ["ns:sub:Fractal 1|x"]
"#,
    );
    // A handle containing `:` cannot be referenced as a whole node: the string is split at
    // its last `:` (formats.md §3.5), naming handle `ns:sub` (not defined).
    assert_eq!(codes(&d), ["RB018"]);
    let f = net.find("ns:sub:Fractal 1|x").unwrap();
    let surf = net.find("plain|surf").unwrap();
    let b = net.find("b").unwrap();
    assert_eq!(
        net.connections(b, "colonHandle"),
        &[Link::missing("ns:sub", Some("Fractal 1|x"))]
    );
    assert_eq!(
        net.connections(b, "inputs"),
        &[
            Link::node(f, Some("resultF")),
            Link::node(f, Some("resultG"))
        ]
    );
    // Whole-node reference: no output name.
    assert_eq!(net.connections(b, "shading"), &[Link::node(surf, None)]);
    // Edges carry output, input and element index.
    let mut edges: Vec<_> = net
        .graph()
        .edge_indices()
        .map(|e| {
            let (input, link) = net.edge_link(e).unwrap();
            (input.name(), net.graph()[e].index, link.output())
        })
        .collect();
    edges.sort();
    assert_eq!(
        edges,
        [
            ("inputs", 0, Some("resultF")),
            ("inputs", 1, Some("resultG")),
            ("shading", 0, None)
        ]
    );
}

#[test]
fn reuse_redefinition_and_binding() {
    let (net, d) = parse(
        r#"Pattern "PxrFractal" "noise" "int layers" [1]
Bxdf "PxrSurface" "surf" "reference float diffuseGain" ["noise:resultF"] "string __materialid" ["SurfSG"]
Pattern "PxrFractal" "noise" "int layers" [2]
Bxdf "PxrSurface" "surf" "string __materialid" ["SurfSG"]
Bxdf "PxrSurface" "surf"
Pattern "PxrWorley" "noise"
Bxdf "PxrSurface" "surf2" "reference float diffuseGain" ["noise:resultF"]
Bxdf "PxrSurface" "self" "reference float diffuseGain" ["self:resultF"]
"#,
    );
    // Re-uses: no new versions of `surf`.
    assert_eq!(net.versions("surf").len(), 1);
    // Redefinitions: noise#1 (new params), noise#2 (same handle, other shader, empty list).
    assert_eq!(net.versions("noise").len(), 3);
    assert_eq!(d.count("RB017"), 2);
    assert_eq!(net[net.by_key("noise#2").unwrap()].shader(), "PxrWorley");
    // `surf` bound to noise#0 (the only version before it); surf2 to the latest, noise#2.
    let surf = net.find("surf").unwrap();
    assert_eq!(
        net.connections(surf, "diffuseGain")[0].upstream(),
        Upstream::Node(net.by_key("noise#0").unwrap())
    );
    let surf2 = net.find("surf2").unwrap();
    assert_eq!(
        net.connections(surf2, "diffuseGain")[0].upstream(),
        Upstream::Node(net.by_key("noise#2").unwrap())
    );
    // A reference to its own handle, not defined before: dangling (RB018).
    let me = net.find("self").unwrap();
    assert_eq!(
        net.connections(me, "diffuseGain")[0].missing_handle(),
        Some("self")
    );
    assert_eq!(d.count("RB018"), 1);
    // RB017 points at the new request and names the previous one.
    let rb017 = d.with_code("RB017").next().unwrap();
    assert_eq!(rb017.location.as_ref().unwrap().line, 3);
    assert_eq!(rb017.related[0].1.line, 1);
    assert_eq!(
        net[net.by_key("noise#1").unwrap()].display_name(),
        "noise (line 3)"
    );
}

#[test]
fn forward_references_stay_dangling() {
    let (net, d) = parse(
        r#"Pattern "PxrLayerMixer" "mix" "reference vstruct baselayer" ["layer:pxrMaterialOut"]
Pattern "PxrLayer" "layer"
"#,
    );
    let mix = net.find("mix").unwrap();
    assert_eq!(
        net.connections(mix, "baselayer"),
        &[Link::missing("layer", Some("pxrMaterialOut"))]
    );
    assert_eq!(net.graph().edge_count(), 0);
    assert_eq!(codes(&d), ["RB018"]);
}

#[test]
fn placeholder_convention_any_type_word() {
    let (net, d) = parse(
        r#"Pattern "PxrLayer" "PxrLayer1"
Pattern "PxrLayerMixer" "PxrLayerMixer1"
    "reference vstruct baselayer" ["PxrLayer1:pxrMaterialOut"]
    "reference struct layer1" ["PxrLayer1:pxrMaterialOut"]
Bxdf "PxrLayerSurface" "PxrLayerSurface1"
    "reference float inputMaterial" ["PxrLayerMixer1:pxrMaterialOut"]
"#,
    );
    assert!(d.is_empty());
    let s = net.find("PxrLayerSurface1").unwrap();
    let m = net.find("PxrLayerMixer1").unwrap();
    assert_eq!(
        net.connections(s, "inputMaterial"),
        &[Link::node(m, Some("pxrMaterialOut"))]
    );
    assert_eq!(net.connected_inputs(m), ["baselayer", "layer1"]);
}

#[test]
fn pass_through_requests_are_not_nodes() {
    let (net, d) = parse(
        r#"##RenderMan RIB
version 3.04
Integrator "PxrPathTracer" "pt" "int maxPathLength" [10]
Projection "PxrPerspective" "float fov" [45]
DisplayFilter "PxrBackgroundDisplayFilter" "bg" "color backgroundColor" [1 1 1]
AttributeBegin
  Attribute "identifier" "string name" ["x"]
  Displace "PxrDisplace" "d" "float dispAmount" [0.1]
  LightFilter "PxrBlockerLightFilter" "blocker"
  Light "PxrDomeLight" "dome" "float intensity" [1]
  Sphere 1 -1 1 360
AttributeEnd
"#,
    );
    assert!(d.is_empty(), "{:?}", codes(&d));
    let kinds: Vec<RequestKind> = net.node_ids().map(|i| net[i].kind()).collect();
    assert_eq!(
        kinds,
        [
            RequestKind::Displace,
            RequestKind::LightFilter,
            RequestKind::Light
        ]
    );
    let terminals: Vec<(&str, &str)> = net
        .materials()
        .iter()
        .map(|m| (m.name.as_str(), m.terminals[0].name.as_str()))
        .collect();
    assert_eq!(
        terminals,
        [
            ("d", "displacement"),
            ("blocker", "lightFilter"),
            ("dome", "light")
        ]
    );
}

#[test]
fn comments_are_attached() {
    let src = r#"Pattern "PxrTexture" "tex" # header comment
    # before filename
    "string filename" ["a.tex"] # after filename
    #"int invertT" [0]
    "int linearize" [1]
# outside
WorldBegin
"#;
    let (net, _) = parse(src);
    let tex = net.find("tex").unwrap();
    let s = net[tex].source().unwrap();
    let text = |r: &std::ops::Range<usize>| &src[r.clone()];
    assert_eq!(s.items.len(), 2);
    let lead: Vec<&str> = s.leading_comments(0).iter().map(text).collect();
    assert_eq!(lead, ["# header comment", "# before filename"]);
    assert_eq!(s.trailing_comment(0).map(text), Some("# after filename"));
    let lead: Vec<&str> = s.leading_comments(1).iter().map(text).collect();
    assert_eq!(lead, ["#\"int invertT\" [0]"]);
    // The span ends with the last value: the comment after it is passed through.
    assert!(text(&s.span).ends_with("\"int linearize\" [1]"));
    assert!(s.end_comments().is_empty());
}

#[test]
fn positions_of_nodes_and_params() {
    let (net, _) = parse("\n\n    Pattern \"PxrFractal\" \"n\"\n\t\t\"int layers\" [1]\n");
    let n = net.find("n").unwrap();
    let loc = net[n].location().unwrap();
    assert_eq!((loc.line, loc.column), (3, 5));
    let p = net[n]
        .param_location(net[n].param("layers").unwrap())
        .unwrap();
    assert_eq!(&*p.file, "t.rib");
    assert_eq!((p.line, p.column), (4, 3));
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 512, ..ProptestConfig::default() })]

    #[test]
    fn random_bytes_never_panic(bytes in proptest::collection::vec(any::<u8>(), 0..400)) {
        let mut d = Diagnostics::new();
        let _ = parse_rib(&bytes, "r.rib", &NoDefinitions, &RibOptions::default(), &mut d);
        let _ = parse_rib(&bytes, "r.rib", &defs(), &RibOptions {
            strict: true,
            ..RibOptions::default()
        }, &mut d);
    }

    #[test]
    fn random_rib_like_text_never_panics(
        parts in proptest::collection::vec(
            prop_oneof![
                Just("Pattern".to_string()), Just("Bxdf".to_string()), Just("Option".to_string()),
                Just("\"PxrFractal\"".to_string()), Just("\"h\"".to_string()),
                Just("\"reference float x\"".to_string()), Just("\"float x\"".to_string()),
                Just("\"x\"".to_string()), Just("\"h:out\"".to_string()), Just("\"h:\"".to_string()),
                Just("[".to_string()), Just("]".to_string()), Just("1".to_string()),
                Just("-.5e3".to_string()), Just("# c\n".to_string()), Just("'q'".to_string()),
                Just("\"\\q\\\n\"".to_string()), Just("\"string __materialid\"".to_string()),
                "[a-z ]{0,6}".prop_map(|s| s),
            ],
            0..40,
        )
    ) {
        let text = parts.join(" ");
        let mut d = Diagnostics::new();
        if let Ok(net) = parse_rib(text.as_bytes(), "r.rib", &defs(), &RibOptions::default(), &mut d) {
            // Whatever was read can be written back unchanged.
            let out = vstructc::back::rib::write_rib_to_vec(text.as_bytes(), &net, &NoDefinitions).unwrap();
            prop_assert_eq!(out, text.as_bytes().to_vec());
        }
    }
}

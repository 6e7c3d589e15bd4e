//! JSON reader (formats.md §5): shape, schema, shorthand values, every JS code with its
//! pointer, random input never panics.

use crate::common::network as network_common;

use network_common::{Table, codes};
use proptest::prelude::*;
use vstructc::front::json::parse_json;
use vstructc::network::{Link, MaterialNodes, Network, NoDefinitions, ParamTypes, RequestKind};
use vstructc::{BaseType, Diagnostics, Error, Severity, Value};

fn read_with(text: &str, types: &(dyn ParamTypes + Sync)) -> (Result<Network, Error>, Diagnostics) {
    let mut d = Diagnostics::new();
    let r = parse_json(text.as_bytes(), "n.json", types, &mut d);
    (r, d)
}

fn read(text: &str) -> (Network, Diagnostics) {
    let (r, d) = read_with(text, &NoDefinitions);
    (r.unwrap_or_else(|e| panic!("{e}")), d)
}

/// A document with one material `M` whose nodes are `nodes` (a JSON object body).
fn doc(nodes: &str) -> String {
    format!(r#"{{"vstructcNetwork": 1, "materials": {{"M": {{"nodes": {{{nodes}}}}}}}}}"#)
}

const SPEC_EXAMPLE: &str = r#"{
  "vstructcNetwork": 1,
  "materials": {
    "PxrLayerSurface1SG": {
      "nodes": {
        "PxrLayer1": {
          "nodeTypeId": "PxrLayer",
          "parameters": {
            "enableDiffuse": { "type": "int", "value": 1 },
            "diffuseColor":  { "type": "color", "value": [0.00967447, 0.179702, 0.0572573] }
          },
          "inputConnections": {}
        },
        "PxrLayerMixer1": {
          "nodeTypeId": "PxrLayerMixer",
          "parameters": { "enableDiffuseAlways": { "type": "int", "value": 1 } },
          "inputConnections": {
            "baselayer":  [ { "upstreamNode": "PxrLayer1", "upstreamOutputName": "pxrMaterialOut" } ],
            "layer1Mask": [ { "upstreamNode": "PxrThreshold1", "upstreamOutputName": "resultR" } ]
          }
        },
        "PxrLayerSurface1": {
          "nodeTypeId": "PxrLayerSurface",
          "parameters": {},
          "inputConnections": {
            "inputMaterial": [ { "upstreamNode": "PxrLayerMixer1", "upstreamOutputName": "pxrMaterialOut" } ]
          }
        }
      },
      "terminals": {
        "surface": { "upstreamNode": "PxrLayerSurface1", "upstreamOutputName": "" }
      },
      "primvars": []
    }
  }
}"#;

#[test]
fn the_spec_example() {
    let (net, d) = read(SPEC_EXAMPLE);
    // PxrThreshold1 is not in the material: kept dangling, JS010.
    assert_eq!(codes(&d), ["JS010"]);
    let js010 = d.iter().next().unwrap();
    assert_eq!(
        js010.location.as_ref().unwrap().pointer.as_deref(),
        Some("/materials/PxrLayerSurface1SG/nodes/PxrLayerMixer1/inputConnections/layer1Mask/0")
    );
    let layer = net.find("PxrLayer1").unwrap();
    let mixer = net.find("PxrLayerMixer1").unwrap();
    let surface = net.find("PxrLayerSurface1").unwrap();
    assert_eq!(net.value(layer, "enableDiffuse"), Some(&Value::Int(1)));
    assert_eq!(
        net.value(layer, "diffuseColor"),
        Some(&Value::Triple(
            BaseType::Color,
            [0.00967447, 0.179702, 0.0572573]
        ))
    );
    assert_eq!(
        net.connections(mixer, "baselayer"),
        &[Link::node(layer, Some("pxrMaterialOut"))]
    );
    assert_eq!(
        net.connections(mixer, "layer1Mask"),
        &[Link::missing("PxrThreshold1", Some("resultR"))]
    );
    assert_eq!(net[surface].kind(), RequestKind::Bxdf);
    assert_eq!(net[layer].kind(), RequestKind::Pattern);
    let m = &net.materials()[0];
    assert_eq!(m.name, "PxrLayerSurface1SG");
    assert_eq!(m.terminals[0].name, "surface");
    assert_eq!(m.terminals[0].link, Link::node(surface, None));
    assert_eq!(
        m.nodes,
        MaterialNodes::Explicit(vec![layer, mixer, surface])
    );
    assert_eq!(
        net[mixer].location().unwrap().pointer.as_deref(),
        Some("/materials/PxrLayerSurface1SG/nodes/PxrLayerMixer1")
    );
}

#[test]
fn same_node_name_in_two_materials_gives_two_nodes() {
    let text = r#"{"vstructcNetwork": 1, "materials": {
      "A": {"nodes": {"n": {"nodeTypeId": "X"}, "s": {"nodeTypeId": "S", "inputConnections": {"i": [{"upstreamNode": "n", "upstreamOutputName": "o"}]}}}},
      "B": {"nodes": {"n": {"nodeTypeId": "Y"}, "s": {"nodeTypeId": "S", "inputConnections": {"i": [{"upstreamNode": "n", "upstreamOutputName": "o"}]}}}}
    }}"#;
    let (net, d) = read(text);
    assert!(d.is_empty());
    let n0 = net.by_key("n#0").unwrap();
    let n1 = net.by_key("n#1").unwrap();
    assert_eq!((net[n0].shader(), net[n1].shader()), ("X", "Y"));
    // Connections bind within their material.
    assert_eq!(
        net.connections(net.by_key("s#1").unwrap(), "i")[0].upstream_node(),
        Some(n1)
    );
    assert_eq!(
        net.connections(net.by_key("s#0").unwrap(), "i")[0].upstream_node(),
        Some(n0)
    );
}

#[test]
fn every_value_type() {
    let text = doc(r#""n": {"nodeTypeId": "X", "parameters": {
          "i": {"type": "int", "value": -3},
          "f": {"type": "float", "value": 0.1},
          "s": {"type": "string", "value": "a\"b"},
          "p": {"type": "point", "value": [1, 2, 3]},
          "v": {"type": "vector", "value": [0, 0, 1]},
          "nn": {"type": "normal", "value": [0, 1, 0]},
          "h": {"type": "hpoint", "value": [1, 2, 3, 1]},
          "m": {"type": "matrix", "value": [1,0,0,0, 0,1,0,0, 0,0,1,0, 0,0,0,1]},
          "t": {"type": "token", "value": "tok"},
          "a": {"type": "asset", "value": "@x.tex@"},
          "b": {"type": "bool", "value": true},
          "fa": {"type": "float[2]", "value": [1, 2.5]},
          "ca": {"type": "color[]", "value": [[1, 0, 0], [0, 1, 0]]}
        }}"#);
    let (net, d) = read(&text);
    assert!(d.is_empty());
    let n = net.find("n").unwrap();
    let v = |k: &str| net.value(n, k).cloned().unwrap();
    assert_eq!(v("i"), Value::Int(-3));
    assert_eq!(v("f"), Value::Float(0.1));
    assert_eq!(v("s"), Value::Str("a\"b".into()));
    assert_eq!(v("p"), Value::Triple(BaseType::Point, [1.0, 2.0, 3.0]));
    assert_eq!(v("v"), Value::Triple(BaseType::Vector, [0.0, 0.0, 1.0]));
    assert_eq!(v("nn"), Value::Triple(BaseType::Normal, [0.0, 1.0, 0.0]));
    assert_eq!(v("h"), Value::HPoint([1.0, 2.0, 3.0, 1.0]));
    assert!(matches!(v("m"), Value::Matrix(m) if m[5] == 1.0 && m[4] == 0.0));
    assert_eq!(v("t"), Value::Token("tok".into()));
    assert_eq!(v("a"), Value::Asset("@x.tex@".into()));
    assert_eq!(v("b"), Value::Bool(true));
    assert_eq!(
        v("fa"),
        Value::Array(BaseType::Float, vec![Value::Float(1.0), Value::Float(2.5)])
    );
    assert_eq!(
        v("ca"),
        Value::Array(
            BaseType::Color,
            vec![
                Value::Triple(BaseType::Color, [1.0, 0.0, 0.0]),
                Value::Triple(BaseType::Color, [0.0, 1.0, 0.0])
            ]
        )
    );
}

#[test]
fn shorthand_values_use_the_declared_type() {
    let types = Table::new().shader(
        "PxrSurface",
        &[
            ("diffuseGain", "float"),
            ("diffuseColor", "color"),
            ("on", "int"),
        ],
        &[],
    );
    let text = doc(
        r#""s": {"nodeTypeId": "PxrSurface", "parameters": {"diffuseGain": 1, "diffuseColor": [1, 0.5, 0], "on": 1}}"#,
    );
    let (r, d) = read_with(&text, &types);
    let net = r.unwrap();
    assert!(d.is_empty());
    let s = net.find("s").unwrap();
    assert_eq!(net.value(s, "diffuseGain"), Some(&Value::Float(1.0)));
    assert_eq!(
        net.value(s, "diffuseColor"),
        Some(&Value::Triple(BaseType::Color, [1.0, 0.5, 0.0]))
    );
    assert_eq!(net.value(s, "on"), Some(&Value::Int(1)));
    // Shorthand that does not fit the declared type: JS004.
    let bad = doc(r#""s": {"nodeTypeId": "PxrSurface", "parameters": {"diffuseColor": 0.5}}"#);
    let (r, _) = read_with(&bad, &types);
    assert_eq!(r.unwrap_err().code(), Some("JS004"));
}

/// (document, code, pointer)
fn error_cases() -> Vec<(String, &'static str, &'static str)> {
    vec![
        ("{\"vstructcNetwork\": 1,, }".into(), "JS001", ""),
        ("[1, 2]".into(), "JS002", ""),
        (r#"{"materials": {}}"#.into(), "JS002", ""),
        (
            r#"{"vstructcNetwork": "1", "materials": {}}"#.into(),
            "JS002",
            "/vstructcNetwork",
        ),
        (r#"{"vstructcNetwork": 1}"#.into(), "JS002", ""),
        (
            r#"{"vstructcNetwork": 1, "materials": []}"#.into(),
            "JS002",
            "/materials",
        ),
        (
            r#"{"vstructcNetwork": 1, "materials": {"M": {}}}"#.into(),
            "JS002",
            "/materials/M",
        ),
        (
            doc(r#""n": {"parameters": {}}"#),
            "JS002",
            "/materials/M/nodes/n",
        ),
        (
            doc(r#""n": {"nodeTypeId": 3}"#),
            "JS002",
            "/materials/M/nodes/n/nodeTypeId",
        ),
        (
            doc(r#""n": {"nodeTypeId": "X", "nodeTypeId": "Y"}"#),
            "JS002",
            "/materials/M/nodes/n/nodeTypeId",
        ),
        (
            doc(r#""n": {"nodeTypeId": "X"}, "n": {"nodeTypeId": "X"}"#),
            "JS002",
            "/materials/M/nodes/n",
        ),
        (
            doc(r#""n": {"nodeTypeId": "X", "inputConnections": {"i": {}}}"#),
            "JS002",
            "/materials/M/nodes/n/inputConnections/i",
        ),
        (
            doc(r#""n": {"nodeTypeId": "X", "inputConnections": {"i": [{"upstreamNode": "n"}]}}"#),
            "JS002",
            "/materials/M/nodes/n/inputConnections/i/0",
        ),
        (
            doc(
                r#""n": {"nodeTypeId": "X", "parameters": {"p": {"type": "vstruct", "value": 1}}}"#,
            ),
            "JS002",
            "/materials/M/nodes/n/parameters/p/type",
        ),
        (
            doc(r#""n": {"nodeTypeId": "X", "parameters": {"p": {"value": 1}}}"#),
            "JS002",
            "/materials/M/nodes/n/parameters/p",
        ),
        (
            r#"{"vstructcNetwork": 2, "materials": {}}"#.into(),
            "JS003",
            "/vstructcNetwork",
        ),
        (
            doc(r#""n": {"nodeTypeId": "X", "parameters": {"p": {"type": "int", "value": 1.5}}}"#),
            "JS004",
            "/materials/M/nodes/n/parameters/p/value",
        ),
        (
            doc(
                r#""n": {"nodeTypeId": "X", "parameters": {"p": {"type": "color", "value": [1, 2]}}}"#,
            ),
            "JS004",
            "/materials/M/nodes/n/parameters/p/value",
        ),
        (
            doc(
                r#""n": {"nodeTypeId": "X", "parameters": {"p": {"type": "float[3]", "value": [1, 2]}}}"#,
            ),
            "JS004",
            "/materials/M/nodes/n/parameters/p/value",
        ),
        (
            doc(r#""n": {"nodeTypeId": "X", "parameters": {"p": {"type": "string", "value": 1}}}"#),
            "JS004",
            "/materials/M/nodes/n/parameters/p/value",
        ),
        (
            doc(r#""n": {"nodeTypeId": "X", "parameters": {"p": 0.5}}"#),
            "JS006",
            "/materials/M/nodes/n/parameters/p",
        ),
    ]
}

#[test]
fn every_js_error_with_pointer() {
    for (text, code, pointer) in error_cases() {
        let (r, _) = read_with(&text, &NoDefinitions);
        let e = r.err().unwrap_or_else(|| panic!("no error for {text}"));
        let d = e.diagnostic().unwrap();
        assert_eq!(
            (d.code.as_str(), d.severity),
            (code, Severity::Error),
            "{text}: {d}"
        );
        let loc = d.location.as_ref().unwrap();
        assert_eq!(&*loc.file, "n.json");
        if code == "JS001" {
            assert_eq!((loc.line, loc.column), (1, 23), "{text}");
        } else {
            assert_eq!(loc.pointer.as_deref().unwrap_or(""), pointer, "{text}: {d}");
        }
    }
}

/// A node's `parameters` or `inputConnections` that is not an object is JS002 at its pointer,
/// naming the key and what it holds.
#[test]
fn node_objects_that_are_not_objects() {
    for (member, key, kind) in [
        (r#""parameters": 3"#, "parameters", "a number"),
        (r#""inputConnections": "x""#, "inputConnections", "a string"),
        (r#""parameters": [1]"#, "parameters", "an array"),
    ] {
        let text = doc(&format!(r#""n": {{"nodeTypeId": "X", {member}}}"#));
        let (r, _) = read_with(&text, &NoDefinitions);
        let e = r.err().unwrap_or_else(|| panic!("no error for {text}"));
        let d = e.diagnostic().unwrap();
        assert_eq!(d.code.as_str(), "JS002", "{text}: {d}");
        let pointer = d.location.as_ref().and_then(|l| l.pointer.as_deref());
        assert_eq!(
            pointer,
            Some(&*format!("/materials/M/nodes/n/{key}")),
            "{d}"
        );
        assert_eq!(
            d.message,
            format!("`{key}` must be an object, found {kind}"),
            "{text}"
        );
    }
}

#[test]
fn duplicate_key_has_line_and_column() {
    let text = "{\"vstructcNetwork\": 1,\n \"materials\": {},\n \"materials\": {}}";
    let (r, _) = read_with(text, &NoDefinitions);
    let e = r.unwrap_err();
    let loc = e.diagnostic().unwrap().location.clone().unwrap();
    assert_eq!(e.code(), Some("JS002"));
    assert_eq!(loc.line, 3);
    assert_eq!(loc.pointer.as_deref(), Some("/materials"));
}

#[test]
fn warnings_js010_js011() {
    let text = r#"{"vstructcNetwork": 1, "comment": "x", "materials": {"M": {
        "nodes": {"n": {"nodeTypeId": "X", "color": "red",
                        "parameters": {"p": {"type": "int", "value": 1, "doc": "?"}},
                        "inputConnections": {"i": [{"upstreamNode": "ghost", "upstreamOutputName": "o", "w": 1}]}}},
        "terminals": {"surface": {"upstreamNode": "elsewhere", "upstreamOutputName": ""}},
        "extra": 1}}}"#;
    let (net, d) = read(text);
    let got: Vec<(&str, Option<&str>)> = d
        .iter()
        .map(|x| {
            (
                x.code.as_str(),
                x.location.as_ref().and_then(|l| l.pointer.as_deref()),
            )
        })
        .collect();
    assert_eq!(
        got,
        [
            ("JS011", Some("/comment")),
            ("JS011", Some("/materials/M/extra")),
            ("JS011", Some("/materials/M/nodes/n/color")),
            ("JS011", Some("/materials/M/nodes/n/parameters/p/doc")),
            ("JS011", Some("/materials/M/nodes/n/inputConnections/i/0/w")),
            ("JS010", Some("/materials/M/nodes/n/inputConnections/i/0")),
            ("JS010", Some("/materials/M/terminals/surface")),
        ]
    );
    assert!(d.iter().all(|x| x.severity == Severity::Warning));
    let m = &net.materials()[0];
    assert_eq!(m.terminals[0].link, Link::missing("elsewhere", None));
}

#[test]
fn whole_node_references_and_connection_order() {
    let text = doc(r#""a": {"nodeTypeId": "A"}, "b": {"nodeTypeId": "B"},
           "m": {"nodeTypeId": "M", "parameters": {"x": {"type": "float", "value": 2}},
                 "inputConnections": {"x": [{"upstreamNode": "b", "upstreamOutputName": "o"},
                                            {"upstreamNode": "a", "upstreamOutputName": ""}]}}"#);
    let (net, _) = read(&text);
    let (a, b, m) = (
        net.find("a").unwrap(),
        net.find("b").unwrap(),
        net.find("m").unwrap(),
    );
    assert_eq!(
        net.connections(m, "x"),
        &[Link::node(b, Some("o")), Link::node(a, None)]
    );
    // Value and connection on the same input are both kept (formats.md §5.3).
    assert_eq!(net.value(m, "x"), Some(&Value::Float(2.0)));
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 512, ..ProptestConfig::default() })]

    #[test]
    fn random_bytes_never_panic(bytes in proptest::collection::vec(any::<u8>(), 0..300)) {
        let mut d = Diagnostics::new();
        let _ = parse_json(&bytes, "r.json", &NoDefinitions, &mut d);
    }

    #[test]
    fn random_json_like_text_never_panics(
        parts in proptest::collection::vec(
            prop_oneof![
                Just("{".to_string()), Just("}".to_string()), Just("[".to_string()), Just("]".to_string()),
                Just(",".to_string()), Just(":".to_string()), Just("\"vstructcNetwork\"".to_string()),
                Just("\"materials\"".to_string()), Just("\"nodes\"".to_string()), Just("\"nodeTypeId\"".to_string()),
                Just("\"parameters\"".to_string()), Just("\"type\"".to_string()), Just("\"value\"".to_string()),
                Just("\"int\"".to_string()), Just("\"color[2]\"".to_string()), Just("1".to_string()),
                Just("1.5e40".to_string()), Just("true".to_string()), Just("null".to_string()),
                Just("\"inputConnections\"".to_string()), Just("\"upstreamNode\"".to_string()),
            ],
            0..60,
        )
    ) {
        let text = parts.join("");
        let mut d = Diagnostics::new();
        let _ = parse_json(text.as_bytes(), "r.json", &NoDefinitions, &mut d);
    }
}

/// Every order of `members` (JSON object members, without braces), joined as an object.
fn orders(members: &[&str]) -> Vec<String> {
    if members.len() <= 1 {
        return vec![format!("{{{}}}", members.join(""))];
    }
    let mut out = Vec::new();
    for i in 0..members.len() {
        let mut rest = members.to_vec();
        let first = rest.remove(i);
        for tail in orders(&rest) {
            let tail = &tail[1..tail.len() - 1];
            out.push(format!("{{{first}, {tail}}}"));
        }
    }
    out
}

/// The report of `text`: the network as JSON, or the error's code and pointer, and the
/// warnings' codes and pointers.
fn report(text: &str, types: &(dyn ParamTypes + Sync)) -> (String, Vec<(String, String)>) {
    let (r, d) = read_with(text, types);
    let pointer = |d: &vstructc::Diagnostic| {
        d.location
            .as_ref()
            .and_then(|l| l.pointer.clone())
            .unwrap_or_default()
    };
    let result = match r {
        Ok(net) => vstructc::back::json::write_json(&net).unwrap(),
        Err(e) => {
            let d = e.diagnostic().unwrap();
            format!("{} {} {}", d.code, pointer(d), d.message)
        }
    };
    let warnings = d.iter().map(|w| (w.code.to_string(), pointer(w))).collect();
    (result, warnings)
}

#[test]
fn node_keys_in_any_order_read_alike() {
    let types = Table::new().shader("S", &[("g", "float"), ("c", "color")], &[]);
    let params = orders(&[
        r#""p": {"value": [1, 2, 3], "type": "color"}"#,
        r#""g": 0.5"#,
        r#""c": [0, 1, 0]"#,
    ]);
    let param = |members: &[&str]| orders(members);
    // A valid node (values before types, shorthand before `nodeTypeId`, inputs before the
    // parameters they name), then nodes with findings at several stages.
    let cases: Vec<Vec<String>> = vec![
        vec![
            r#""nodeTypeId": "S""#.to_string(),
            format!(r#""parameters": {}"#, params[3]),
            r#""inputConnections": {"p": [{"upstreamNode": "a", "upstreamOutputName": "o"}], "q": []}"#
                .to_string(),
        ],
        vec![
            r#""nodeTypeId": "S""#.to_string(),
            r#""other": 1"#.to_string(),
            format!(
                r#""parameters": {{"x": {}, "g": "no"}}"#,
                param(&[r#""doc": 1"#, r#""type": "int""#, r#""value": 1.5"#])[4]
            ),
        ],
        vec![
            r#""nodeTypeId": 3"#.to_string(),
            r#""parameters": {"x": {"type": "int", "value": 1.5}}"#.to_string(),
        ],
        vec![
            r#""parameters": {"g": 1, "y": {"value": 1}}"#.to_string(),
            r#""inputConnections": {"g": {}}"#.to_string(),
        ],
        vec![
            r#""nodeTypeId": "S""#.to_string(),
            r#""parameters": {"k": {"type": "bogus", "value": 1, "doc": 2}}"#.to_string(),
            r#""inputConnections": {"g": [{"upstreamNode": "a", "w": 1}]}"#.to_string(),
        ],
    ];
    for members in &cases {
        let members: Vec<&str> = members.iter().map(String::as_str).collect();
        let mut reports = Vec::new();
        for node in orders(&members) {
            let text = doc(&format!(r#""a": {{"nodeTypeId": "A"}}, "n": {node}"#));
            reports.push((report(&text, &types), text));
        }
        for (r, text) in &reports[1..] {
            assert_eq!(r, &reports[0].0, "{text}\nagainst\n{}", reports[0].1);
        }
    }
    // Each parameter form, in every order of its members, gives one network.
    for p in params {
        let text = doc(&format!(r#""n": {{"nodeTypeId": "S", "parameters": {p}}}"#));
        let (r, w) = report(&text, &types);
        assert!(w.is_empty() && r.contains("\"c\""), "{text}: {r}");
    }
}

/// A document of `n` materials, each on four lines, larger than 1 MiB for `n` = 3000 (the
/// reader then reads its materials on rayon's pool, with the `parallel` feature);
/// `edit(i, material)` may change the text of material `i`.
fn large_doc(n: usize, edit: impl Fn(usize, String) -> String) -> String {
    let mut text = String::from("{\n  \"vstructcNetwork\": 1,\n  \"materials\": {\n");
    for i in 0..n {
        let m = format!(
            "    \"m{i}\": {{\"nodes\": {{\n      \"a\": {{\"nodeTypeId\": \"PxrLayer\", \"parameters\": {{\"g\": {{\"type\": \"float\", \"value\": 0.5}}, \"z\": {{\"type\": \"float\", \"value\": -0.0}}, \"c\": {{\"type\": \"color\", \"value\": [0, 0.5, 1]}}}}}},\n      \"s\": {{\"nodeTypeId\": \"PxrSurface\", \"inputConnections\": {{\"x\": [{{\"upstreamNode\": \"a\", \"upstreamOutputName\": \"resultRGB\"}}]}}}}}},\n      \"terminals\": {{\"surface\": {{\"upstreamNode\": \"s\", \"upstreamOutputName\": \"\"}}}}}}{}\n",
            if i + 1 < n { "," } else { "" }
        );
        text.push_str(&edit(i, m));
    }
    text.push_str("  },\n  \"zzz\": 1\n}\n");
    text
}

/// The line (1-based) of the first occurrence of `what` in `text`.
fn line_of(text: &str, what: &str) -> u32 {
    let k = text.find(what).unwrap();
    1 + text[..k].matches('\n').count() as u32
}

#[test]
fn large_documents_keep_values_diagnostics_and_positions() {
    let n = 3000;
    let plain = large_doc(n, |_, m| m);
    assert!(plain.len() > 1 << 20, "{}", plain.len());
    let (net, d) = read(&plain);
    assert_eq!(codes(&d), ["JS011"]);
    assert_eq!(net.node_count(), 2 * n);
    assert_eq!(net.materials().len(), n);
    assert_eq!(net.materials()[n - 1].name, format!("m{}", n - 1));
    let MaterialNodes::Explicit(ids) = &net.materials()[n - 1].nodes else {
        panic!("explicit nodes");
    };
    let (a, s) = (ids[0], ids[1]);
    assert_eq!(net.value(a, "g"), Some(&Value::Float(0.5)));
    let Some(Value::Float(z)) = net.value(a, "z") else {
        panic!("z");
    };
    assert_eq!(z.to_bits(), (-0.0f32).to_bits());
    assert_eq!(
        net.value(a, "c"),
        Some(&Value::Triple(BaseType::Color, [0.0, 0.5, 1.0]))
    );
    assert_eq!(net[s].kind(), RequestKind::Bxdf);
    assert_eq!(net.connections(s, "x")[0].upstream_node(), Some(a));

    // Warnings in document order within the order of the checks: the document's own keys
    // (after `materials` in the text) first.
    let warned = large_doc(n, |i, m| match i {
        10 => m.replacen("{\"nodes\"", "{\"extra\": [1, {\"k\": 2}], \"nodes\"", 1),
        2500 => m.replacen("\"upstreamNode\": \"a\"", "\"upstreamNode\": \"ghost\"", 1),
        _ => m,
    });
    let (_, d) = read(&warned);
    let got: Vec<(&str, Option<&str>)> = d
        .iter()
        .map(|x| {
            let pointer = x.location.as_ref().and_then(|l| l.pointer.as_deref());
            (x.code.as_str(), pointer)
        })
        .collect();
    assert_eq!(
        got,
        [
            ("JS011", Some("/zzz")),
            ("JS011", Some("/materials/m10/extra")),
            (
                "JS010",
                Some("/materials/m2500/nodes/s/inputConnections/x/0")
            ),
        ]
    );

    // The first error, with the warnings before it.
    let wrong = large_doc(n, |i, m| match i {
        10 => m.replacen("{\"nodes\"", "{\"extra\": 1, \"nodes\"", 1),
        2999 => m.replacen("\"value\": 0.5", "\"value\": \"x\"", 1),
        _ => m,
    });
    let (r, d) = read_with(&wrong, &NoDefinitions);
    let e = r.unwrap_err();
    assert_eq!(e.code(), Some("JS004"));
    let loc = e.diagnostic().unwrap().location.clone().unwrap();
    assert_eq!(
        loc.pointer.as_deref(),
        Some("/materials/m2999/nodes/a/parameters/g/value")
    );
    assert_eq!(codes(&d), ["JS011", "JS011"]);

    // A duplicate key and a syntax error late in the text: line and column in the whole text.
    let dup = large_doc(n, |i, m| {
        if i == 2000 {
            m.replacen("\"z\": ", "\"g\": 1, \"z\": ", 1)
        } else {
            m
        }
    });
    let (r, _) = read_with(&dup, &NoDefinitions);
    let e = r.unwrap_err();
    let loc = e.diagnostic().unwrap().location.clone().unwrap();
    assert_eq!(e.code(), Some("JS002"));
    assert_eq!(
        loc.pointer.as_deref(),
        Some("/materials/m2000/nodes/a/parameters/g")
    );
    assert_eq!(loc.line, line_of(&dup, "\"g\": 1, \"z\""));
    let column = dup
        .lines()
        .nth(loc.line as usize - 1)
        .unwrap()
        .find("\"g\": 1")
        .unwrap();
    assert_eq!(loc.column as usize, column + "\"g\"".len());
    let broken = large_doc(n, |i, m| {
        if i == 2000 {
            m.replacen(
                "\"nodeTypeId\": \"PxrSurface\"",
                "\"nodeTypeId\" \"PxrSurface\"",
                1,
            )
        } else {
            m
        }
    });
    let (r, _) = read_with(&broken, &NoDefinitions);
    let e = r.unwrap_err();
    let loc = e.diagnostic().unwrap().location.clone().unwrap();
    assert_eq!(e.code(), Some("JS001"));
    assert_eq!(loc.line, line_of(&broken, "\"nodeTypeId\" \"PxrSurface\""));

    // Nesting within serde_json's limit, which counts the levels above a material.
    for (levels, ok) in [(100, true), (130, false)] {
        let deep = large_doc(n, |i, m| {
            if i == 1500 {
                let value = format!("{}1{}", "[".repeat(levels), "]".repeat(levels));
                m.replacen("{\"nodes\"", &format!("{{\"deep\": {value}, \"nodes\""), 1)
            } else {
                m
            }
        });
        let (r, d) = read_with(&deep, &NoDefinitions);
        match r {
            Ok(_) => {
                assert!(ok, "{levels}");
                assert_eq!(codes(&d), ["JS011", "JS011"]);
            }
            Err(e) => {
                assert!(!ok, "{levels}");
                assert_eq!(e.code(), Some("JS001"));
                let line = e.diagnostic().unwrap().location.as_ref().unwrap().line;
                assert_eq!(line, line_of(&deep, "\"deep\""));
            }
        }
    }
}

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

/// Everything a read gives, for comparing two ways of reading: the network (its JSON form
/// and its full debug form) or the error, and the diagnostics.
fn read_outcome(
    src: &[u8],
    reg: &vstructc::registry::Registry,
    limits: &vstructc::limits::Limits,
    piece: Option<usize>,
) -> String {
    let mut d = Diagnostics::new();
    let net = match parse_json_with(src, "t.json", reg, limits, &mut d, piece) {
        Ok(net) => format!(
            "{} nodes\n{:?}\n{net:?}",
            net.node_count(),
            vstructc::back::json::write_json(&net)
        ),
        Err(e) => format!("error {e:?}"),
    };
    format!("{net}\n{d:?}")
}

/// The JSON form of the layered scene of `materials` materials, as the writer lays it out.
fn scene_json(materials: usize, reg: &vstructc::registry::Registry) -> String {
    let rib = vstructc_testkit::testgen::layered_scene(materials);
    let mut d = Diagnostics::new();
    let options = vstructc::front::rib::RibOptions::default();
    let net =
        vstructc::front::rib::parse_rib(rib.as_bytes(), "s.rib", reg, &options, &mut d).unwrap();
    vstructc::back::json::write_json(&net).unwrap()
}

/// The position of the start of the material nearest after `frac` of `text` (its name's
/// quote), in the writer's layout.
fn material_at(text: &str, frac: f64) -> usize {
    let from = (text.len() as f64 * frac) as usize;
    from + text[from..].find(",\n    \"").unwrap() + 6
}

/// `text` with the first `what` at or after `at` replaced by `with`.
fn replace_after(text: &str, at: usize, what: &str, with: &str) -> String {
    let k = at + text[at..].find(what).unwrap();
    format!("{}{with}{}", &text[..k], &text[k + what.len()..])
}

/// `text` with a bare value in place of the first canonical `float` parameter after `at`.
fn shorthand_after(text: &str, at: usize) -> String {
    let ty = at + text[at..].find("\"type\": \"float\"").unwrap();
    let open = text[..ty].rfind('{').unwrap();
    let close = ty + text[ty..].find('}').unwrap();
    let v = ty + text[ty..].find("\"value\": ").unwrap() + 9;
    let value = text[v..].lines().next().unwrap().trim();
    format!("{}{value}{}", &text[..open], &text[close + 1..])
}

/// Inputs for comparing the two readers: a scene with findings of every kind placed early,
/// in the middle and late, errors of every kind there, and layouts the pieces leave to one
/// thread.
fn scenes_with_findings(reg: &vstructc::registry::Registry) -> Vec<(String, String)> {
    let scene = scene_json(40, reg);
    let spots = [0.02, 0.5, 0.9].map(|f| material_at(&scene, f));
    let mut out = vec![("scene".to_string(), scene.clone())];
    // Warnings: unknown keys of nodes and connections, dangling connections, shorthand
    // values (read again with the declared types), in every third of the scene.
    let mut warned = scene.clone();
    for &f in [0.9, 0.5, 0.02].iter() {
        let at = material_at(&warned, f);
        warned = replace_after(
            &warned,
            at,
            "\"nodeTypeId\": ",
            "\"bogus\": [1, {\"x\": null}],\n \"nodeTypeId\": ",
        );
        warned = replace_after(
            &warned,
            at,
            "\"upstreamNode\": \"",
            "\"upstreamNode\": \"ghost",
        );
        warned = replace_after(
            &warned,
            at,
            "\"upstreamOutputName\"",
            "\"extra\": 1, \"upstreamOutputName\"",
        );
        warned = shorthand_after(&warned, at);
    }
    out.push(("warnings".into(), warned.clone()));
    for (i, &at) in spots.iter().enumerate() {
        let at_w = material_at(&warned, [0.02, 0.5, 0.9][i]);
        let cases = [
            (
                "JS004",
                replace_after(&warned, at_w, "\"value\": 0.5\n", "\"value\": \"x\"\n"),
            ),
            (
                "JS006",
                replace_after(
                    &warned,
                    at_w,
                    "\"parameters\": {",
                    "\"parameters\": {\"bogus\": 1,",
                ),
            ),
            (
                "no nodeTypeId",
                replace_after(&warned, at_w, "\"nodeTypeId\": ", "\"nodeType\": "),
            ),
            ("syntax", replace_after(&scene, at, "\": ", "\" ")),
            ("stray ]", replace_after(&scene, at, "}", "}]")),
            (
                "duplicate key",
                replace_after(
                    &scene,
                    at,
                    "\"nodeTypeId\": ",
                    "\"nodeTypeId\": \"X\", \"nodeTypeId\": ",
                ),
            ),
            (
                "duplicate material",
                replace_after(&scene, at, "\"m", "\"m0_SG\": {\"nodes\": {}},\n    \"m"),
            ),
            (
                "escaped name",
                replace_after(&scene, at, "_SG\"", "\\u005fSG\""),
            ),
            (
                "deep",
                replace_after(
                    &scene,
                    at,
                    "\"nodes\": {",
                    &format!(
                        "\"deep\": {}1{},\n      \"nodes\": {{",
                        "[".repeat(40),
                        "]".repeat(40)
                    ),
                ),
            ),
            (
                "deeper",
                replace_after(
                    &scene,
                    at,
                    "\"nodes\": {",
                    &format!(
                        "\"deep\": {}1{},\n      \"nodes\": {{",
                        "[".repeat(100),
                        "]".repeat(100)
                    ),
                ),
            ),
            (
                "too deep",
                replace_after(
                    &scene,
                    at,
                    "\"nodes\": {",
                    &format!(
                        "\"deep\": {}1{},\n      \"nodes\": {{",
                        "[".repeat(127),
                        "]".repeat(127)
                    ),
                ),
            ),
            (
                "not an object",
                replace_after(
                    &scene,
                    at,
                    "{\n      \"nodes\"",
                    "[],\n \"x\": {\n      \"nodes\"",
                ),
            ),
            (
                "spaces",
                replace_after(&scene, at, "},\n    \"", "} \t,\n    \""),
            ),
        ];
        out.extend(
            cases
                .into_iter()
                .map(|(name, text)| (format!("{name} {i}"), text)),
        );
    }
    // The document's own members around `materials`, with a finding of their own.
    let doc = scene.replacen(
        "{\n  \"materials\"",
        "{\n  \"zzz\": {\"a\": [1, \"}\"]}, \"vstructcNetwork\": 2,\n  \"materials\"",
        1,
    );
    out.push((
        "document members".into(),
        doc.replacen("\"vstructcNetwork\": 1", "\"more\": null", 1),
    ));
    out.push(("CRLF".into(), warned.replace('\n', "\r\n")));
    let compact: serde_json::Value = serde_json::from_str(&scene).unwrap();
    out.push(("one line".into(), compact.to_string()));
    out.push((
        "no materials".into(),
        "{\n  \"materials\": {\n  },\n  \"vstructcNetwork\": 1\n}\n".into(),
    ));
    out.push(("truncated".into(), scene[..scene.len() / 2].to_string()));
    out
}

/// The reader in pieces on the pool, of any size, gives what it gives on one thread: the same
/// network, the same diagnostics in the same order with the same positions, the same error
/// (a syntax error or a duplicate key with its line and column, wherever it falls).
#[test]
fn reading_in_pieces_is_the_one_thread_reading() {
    let reg = vstructc::registry::Registry::embedded();
    let mut inputs: Vec<(String, Vec<u8>)> = Vec::new();
    // Every JSON file of the tests, and every RIB example written as JSON.
    for dir in [
        "tests",
        "tests/hostile/corpus",
        "tests/vectors/cond",
        "tests/data/rib",
        "examples",
    ] {
        for entry in std::fs::read_dir(dir).unwrap() {
            let path = entry.unwrap().path();
            let bytes = std::fs::read(&path).unwrap_or_default();
            if path.extension().is_some_and(|e| e == "json") {
                inputs.push((path.display().to_string(), bytes));
            } else if path.extension().is_some_and(|e| e == "rib") {
                let mut d = Diagnostics::new();
                let options = vstructc::front::rib::RibOptions::default();
                if let Ok(net) =
                    vstructc::front::rib::parse_rib(&bytes, "x.rib", &reg, &options, &mut d)
                    && let Ok(json) = vstructc::back::json::write_json(&net)
                {
                    inputs.push((path.display().to_string(), json.into_bytes()));
                }
            }
        }
    }
    assert!(inputs.len() > 10, "{}", inputs.len());
    let scenes = scenes_with_findings(&reg);
    // Text that is not UTF-8 in a material's name, in a value, and in the document's members.
    let scene = scenes[0].1.as_bytes();
    for (name, at) in [
        ("bad name", 0.3),
        ("bad value", 0.6),
        ("bad document", 0.999),
    ] {
        let mut bad = scene.to_vec();
        let at = (scene.len() as f64 * at) as usize;
        let k = match name {
            "bad name" => material_at(&scenes[0].1, 0.3) + 2,
            "bad document" => scenes[0].1.rfind("vstructcNetwork").unwrap() + 3,
            _ => at + scene[at..].iter().position(|&c| c == b'"').unwrap() + 1,
        };
        bad.insert(k, 0xff);
        inputs.push((name.into(), bad));
    }
    inputs.extend(scenes.into_iter().map(|(n, t)| (n, t.into_bytes())));
    let few_nodes = vstructc::limits::Limits {
        nodes: 60,
        ..Default::default()
    };
    let mut pieced = 0;
    for (name, src) in &inputs {
        for limits in [&vstructc::limits::Limits::default(), &few_nodes] {
            let serial = read_outcome(src, &reg, limits, None);
            for piece in [1, 100, 3000, 20_000, 1 << 20] {
                let pieces = read_outcome(src, &reg, limits, Some(piece));
                assert!(
                    serial == pieces,
                    "{name}, pieces of {piece} bytes, {limits:?}:\n{serial}\n---\n{pieces}"
                );
            }
        }
        if json_reads_in_pieces(src, &reg, 3000) {
            pieced += 1;
        }
    }
    // The scenes were read in pieces, not handed to the one-thread reader.
    for name in [
        "scene",
        "warnings",
        "CRLF",
        "document members",
        "JS004 1",
        "spaces 2",
        "deep 0",
    ] {
        let (_, src) = inputs.iter().find(|(n, _)| n == name).unwrap();
        assert!(json_reads_in_pieces(src, &reg, 3000), "{name}");
    }
    for name in [
        "one line",
        "syntax 1",
        "duplicate material 2",
        "escaped name 0",
        "deeper 2",
        "too deep 1",
        "bad name",
        "bad value",
        "bad document",
    ] {
        let (_, src) = inputs.iter().find(|(n, _)| n == name).unwrap();
        assert!(!json_reads_in_pieces(src, &reg, 3000), "{name}");
    }
    assert!(pieced > 20, "{pieced}");
}

/// The scanner of the pieces settles a material of the writer's layout and the forms it reads
/// exactly as serde_json does (numbers within its exact range, strings without escapes, any
/// whitespace, a value before its type), and leaves everything else to serde_json (escapes,
/// control characters, numbers it cannot read the same way, keys and shapes the format does
/// not define, duplicate keys, findings of a parameter, syntax errors): either way the pieces
/// give what one thread gives.
#[test]
fn the_pieces_scanner_reads_what_serde_json_reads() {
    let reg = vstructc::registry::Registry::embedded();
    let scene = scene_json(12, &reg);
    let at = material_at(&scene, 0.5);
    let open = at + scene[at..].find('{').unwrap();
    let close = open + scene[open..].find("\n    }").unwrap() + 6;
    let material = &scene[open..close];
    assert!(json_scans_material(material.as_bytes()), "{material}");
    let float = "\"value\": 0.5\n";
    let int = "\"value\": 1\n";
    let params = "\"parameters\": {";
    let cases: &[(&str, &str, bool)] = &[
        // Numbers the scanner reads as serde_json does.
        (float, "\"value\": 5e-1\n", true),
        (float, "\"value\": 0.05E1\n", true),
        (float, "\"value\": 0.3000000000000000444\n", false),
        (float, "\"value\": 0.30000000000000004\n", false),
        (float, "\"value\": 0.3000000000000001\n", true),
        (float, "\"value\": 9007199254740993\n", true),
        (float, "\"value\": 9007199254740993.0\n", false),
        (float, "\"value\": 12345678901234567890\n", false),
        (float, "\"value\": 1e-22\n", true),
        (float, "\"value\": 1e-23\n", false),
        (float, "\"value\": 3e22\n", true),
        (float, "\"value\": 1e400\n", false),
        (float, "\"value\": -0\n", true),
        (float, "\"value\": -0.0\n", true),
        (float, "\"value\": -1.25e+2\n", true),
        (float, "\"value\": 1e39\n", false),
        (int, "\"value\": 1.0\n", true),
        (int, "\"value\": -0\n", true),
        (int, "\"value\": -7\n", true),
        (int, "\"value\": -9223372036854775808\n", false),
        (int, "\"value\": 2147483648\n", false),
        (int, "\"value\": 2.5\n", false),
        // Not numbers: syntax errors.
        (float, "\"value\": 01\n", false),
        (float, "\"value\": 1.\n", false),
        (float, "\"value\": .5\n", false),
        (float, "\"value\": -\n", false),
        (float, "\"value\": +1\n", false),
        (float, "\"value\": 1e\n", false),
        (float, "\"value\": 1e+\n", false),
        (float, "\"value\": 1.5.5\n", false),
        (float, "\"value\": NaN\n", false),
        // Strings.
        ("\"PxrLayer\"", "\"PxrLay\u{e9}r\"", true),
        ("\"PxrLayer\"", "\"Pxr\\u004cayer\"", false),
        ("\"PxrLayer\"", "\"Pxr\\\"Layer\"", false),
        ("\"PxrLayer\"", "\"Pxr\tLayer\"", false),
        ("\"nodeTypeId\"", "\"node\\u0054ypeId\"", false),
        // Layout and shapes.
        ("\n", "\r\n\t ", true),
        (
            "\"type\": \"float\",\n              \"value\": 0.5\n",
            "\"value\": 0.5, \"type\": \"float\"\n",
            true,
        ),
        (
            params,
            "\"parameters\": {\"flag\": {\"type\": \"bool\", \"value\": true}, \"ns\": {\"type\": \"int[]\", \"value\": [1, -2, 3.0]}, \"t\": {\"type\": \"string\", \"value\": \"a b\"},",
            true,
        ),
        ("\"primvars\": []", "\"primvars\": [\"st\", \"P\"]", true),
        ("\"primvars\": []", "\"primvars\": [\"st\", 1]", true),
        ("\"primvars\": []", "\"primvars\": 7", true),
        ("\"nodes\"", "\"terminals\": {}, \"nodes\"", false),
        ("\"nodes\"", "\"doc\": {}, \"nodes\"", false),
        ("\"nodeTypeId\": ", "\"doc\": 1, \"nodeTypeId\": ", false),
        ("\"nodeTypeId\": \"PxrLayer\"", "\"nodeTypeId\": 5", false),
        ("\"nodeTypeId\": \"PxrLayer\",", "", true),
        (
            params,
            "\"parameters\": {\"flag\": {\"type\": \"bool\", \"value\": tru}, ",
            false,
        ),
        (
            params,
            "\"parameters\": {\"flag\": {\"type\": \"bool\", \"value\": 1}, ",
            false,
        ),
        (
            params,
            "\"parameters\": {\"flag\": {\"type\": \"vstruct\", \"value\": 1}, ",
            false,
        ),
        (
            params,
            "\"parameters\": {\"flag\": {\"type\": 3, \"value\": 1}, ",
            false,
        ),
        (
            params,
            "\"parameters\": {\"flag\": {\"type\": \"int\"}, ",
            false,
        ),
        (
            params,
            "\"parameters\": {\"flag\": {\"type\": \"int\", \"value\": 1, \"doc\": 0}, ",
            false,
        ),
        (params, "\"parameters\": {\"flag\": 1, ", false),
        (
            params,
            "\"parameters\": {\"flag\": {\"type\": \"float[2]\", \"value\": [1, 2, 3]}, ",
            false,
        ),
        (
            params,
            "\"parameters\": {\"diffuseGain\": {\"type\": \"int\", \"value\": 1}, ",
            false,
        ),
        (
            "\"upstreamOutputName\"",
            "\"doc\": 1, \"upstreamOutputName\"",
            false,
        ),
        ("\"upstreamNode\": \"", "\"upstreamNode\": \"ghost", true),
        (
            "\"upstreamNode\": \"",
            "\"upstreamNode\": 4, \"x\": \"",
            false,
        ),
        ("\"upstreamOutputName\": \"", "\"upstreamNode\": \"", false),
        ("[\n", "{\"a\": [\n", false),
        ("\"nodes\": {", "\"nodes\": [], \"x\": {", false),
    ];
    let few_nodes = vstructc::limits::Limits {
        nodes: 30,
        ..Default::default()
    };
    for &(what, with, scans) in cases {
        let Some(k) = material.find(what) else {
            panic!("{what:?} not in {material}");
        };
        let changed = format!("{}{with}{}", &material[..k], &material[k + what.len()..]);
        assert_eq!(
            json_scans_material(changed.as_bytes()),
            scans,
            "{what:?} -> {with:?}"
        );
        let doc = format!("{}{changed}{}", &scene[..open], &scene[close..]);
        for limits in [&vstructc::limits::Limits::default(), &few_nodes] {
            let serial = read_outcome(doc.as_bytes(), &reg, limits, None);
            for piece in [1, 3000] {
                let pieces = read_outcome(doc.as_bytes(), &reg, limits, Some(piece));
                assert!(
                    serial == pieces,
                    "{what:?} -> {with:?}, pieces of {piece}:\n{serial}\n---\n{pieces}"
                );
            }
        }
    }
    // Parameters whose text repeats, which the scanner reads again from memory: in every
    // node, with a `}` inside a string (its text up to the first `}` is not a parameter, so
    // it is never remembered), a remembered parameter given twice in a node (JS002), and
    // the same parameter in another layout.
    let gain = "\"gain\": {\"type\": \"float\", \"value\": 0.5}";
    for (extra, error) in [
        (
            format!("\"note\": {{\"type\": \"string\", \"value\": \"a}}b\"}}, {gain}"),
            false,
        ),
        (format!("{gain}, {gain}"), true),
        (
            format!("{gain} , \"gain2\": {{ \"type\":\"float\", \"value\" :0.5}}"),
            false,
        ),
    ] {
        let doc = scene.replace(
            "\"parameters\": {\n",
            &format!("\"parameters\": {{{extra},\n"),
        );
        assert!(doc.matches(&extra).count() > 20);
        let serial = read_outcome(doc.as_bytes(), &reg, &Default::default(), None);
        assert_eq!(serial.contains("JS002"), error, "{extra}: {serial}");
        for piece in [1, 3000, 1 << 20] {
            let pieces = read_outcome(doc.as_bytes(), &reg, &Default::default(), Some(piece));
            assert!(serial == pieces, "{extra}, pieces of {piece}");
        }
        assert_eq!(json_reads_in_pieces(doc.as_bytes(), &reg, 3000), !error);
    }
    // Bytes beyond ASCII in a string, at any place of its eight-byte steps: valid UTF-8 is
    // read by the scanner, anything else is left to serde_json (which reports it).
    let shader = "\"PxrLayer\"";
    for (with, scans) in [
        ("\"\u{1F600}PxrLayer\"".as_bytes(), true),
        ("\"PxrLayer\u{e9}\"".as_bytes(), true),
        ("\"PxrLa\u{20ac}yer\u{10FFFF}\"".as_bytes(), true),
        (b"\"Pxr\xffLayer\"", false),
        (b"\"PxrLayer\xc3\"", false),
        (b"\"Pxr\xe9\xe9\xe9\xe9\xe9\xe9\xe9\xe9\xe9Layer\"", false),
        (b"\"PxrLayer\xed\xa0\x80\"", false),
        (b"\"\xc3\xa9\x01\"", false),
    ] {
        let k = material.find(shader).unwrap();
        let mut changed = material.as_bytes()[..k].to_vec();
        changed.extend_from_slice(with);
        changed.extend_from_slice(&material.as_bytes()[k + shader.len()..]);
        assert_eq!(json_scans_material(&changed), scans, "{with:?}");
        assert_eq!(
            std::str::from_utf8(with).is_ok() && !with.contains(&1),
            scans
        );
    }
    // A material much longer than a piece, with a non-ASCII value: the scanner reads on
    // past the piece's end.
    let long = format!(
        "\"parameters\": {{\"note\": {{\"type\": \"string\", \"value\": \"{}\u{e9}\"}}, ",
        "x".repeat(200_000)
    );
    let changed = material.replacen(params, &long, 1);
    assert!(json_scans_material(changed.as_bytes()));
    let doc = format!("{}{changed}{}", &scene[..open], &scene[close..]);
    let serial = read_outcome(doc.as_bytes(), &reg, &Default::default(), None);
    for piece in [1, 3000, 100_000] {
        let pieces = read_outcome(doc.as_bytes(), &reg, &Default::default(), Some(piece));
        assert!(serial == pieces, "long material, pieces of {piece}");
        assert!(json_reads_in_pieces(doc.as_bytes(), &reg, piece));
    }
}

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

/// A parameter repeated within one request is read like any other: the occurrence after
/// the first shares what the first remembered, keeps its own position and source item, and
/// wins (RB015 once); a later request shares it too.
#[test]
fn a_parameter_repeated_within_a_request_is_shared() {
    let (net, d) = read(
        "Pattern \"P\" \"a\" \"float f\" [2] \"float g\" [3] \"float f\" [2]\n\
         Pattern \"P\" \"b\" \"float g\" [3] \"float f\" [2]\n",
    );
    assert_eq!(d.count("RB015"), 1, "{d:?}");
    assert_eq!(d.len(), 1, "{d:?}");
    let a = &net[net.find("a").unwrap()];
    let b = &net[net.find("b").unwrap()];
    let (af, bf) = (a.param("f").unwrap(), b.param("f").unwrap());
    assert_eq!(af.source_item(), Some(2));
    assert_eq!(bf.source_item(), Some(1));
    let at = a.param_location(af).unwrap();
    assert_eq!((at.line, at.column), (1, 45));
    let at = b.param_location(bf).unwrap();
    assert_eq!((at.line, at.column), (2, 31));
    assert_eq!(af.value(), Some(&Value::Float(2.0)));
    assert!(std::ptr::eq(af.value().unwrap(), bf.value().unwrap()));
    assert!(std::ptr::eq(af.decl().unwrap(), bf.decl().unwrap()));
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

/// Everything a read gives, for comparing two ways of reading: the written RIB and JSON of
/// the network (or the error) and the diagnostics.
fn read_outcome(src: &[u8], options: &RibOptions, batch: Option<usize>) -> String {
    use vstructc::back::json::write_json;
    use vstructc::back::rib::write_rib_to_vec;
    let reg = vstructc::registry::Registry::embedded();
    let mut d = Diagnostics::new();
    let read = parse_rib_with(src, "t.rib", &reg, options, &mut d, batch);
    let net = match read {
        Ok(net) => {
            let rib = write_rib_to_vec(src, &net, &reg).map(String::from_utf8);
            format!(
                "{} nodes\n{rib:?}\n{:?}",
                net.node_count(),
                write_json(&net)
            )
        }
        Err(e) => format!("error {:?}", e.diagnostic()),
    };
    format!("{net}\n{d:?}")
}

/// A scene of `materials` layered materials with findings of every stage of the reader
/// between them: the tokenizer's (RB011), the pass-through requests' (RB020), the
/// declarations' and values' (RB013, RB014), the connections' (RB018), the request's (RB015)
/// and the handles' (RB017), and comments inside and between requests.
fn scene_with_findings(materials: usize) -> String {
    let scene = vstructc_testkit::testgen::layered_scene(materials);
    let mut out = String::new();
    for (i, line) in scene.lines().enumerate() {
        out.push_str(line);
        out.push('\n');
        match i % 97 {
            5 => out.push_str("Pattern 'PxrFractal' 'q' \"float frequency\" [2] # note\n"),
            17 => out.push_str("Surface \"plastic\" \"reference float Kd\" [\"q:resultF\"]\n"),
            29 => out.push_str(
                "Pattern \"PxrFractal\" \"q\" \"uniform bogus float x\" [1] \"int n\" [1.5]\n",
            ),
            41 => out.push_str("Pattern \"PxrFractal\" \"d\" \"float a\" [1] \"float a\" [2]\n"),
            53 => out.push_str("# a comment between requests\nSphere 1 -1 1 360\n"),
            // The parameters' findings (RB013) on both sides of a connection's (RB018).
            71 => out.push_str(
                "Pattern \"PxrFractal\" \"e\" \"bogus float a\" [1] \"reference float b\" [\"nowhere:out\"] \"odd int c\" [2]\n",
            ),
            _ => {}
        }
    }
    out
}

/// The reader pipelined on two threads, in batches of any size, gives what it gives on one:
/// the same network, the same diagnostics in the same order with the same positions, the
/// same error (the tokenizer's, a parameter's or the assembler's, wherever it falls among
/// the batches). Here the tokenizer reads the parameters of every other batch and the
/// assembler those of the rest, so both threads' parameter reading is compared.
#[test]
fn pipelined_reading_is_the_one_thread_reading() {
    let mut inputs: Vec<(String, Vec<u8>)> = Vec::new();
    for dir in ["tests/data/rib", "examples"] {
        for entry in std::fs::read_dir(dir).unwrap() {
            let path = entry.unwrap().path();
            if path.extension().is_some_and(|e| e == "rib") {
                inputs.push((path.display().to_string(), std::fs::read(&path).unwrap()));
            }
        }
    }
    assert!(inputs.len() > 10);
    let scene = scene_with_findings(12);
    inputs.push(("findings".into(), scene.clone().into_bytes()));
    // A tokenizer's error near the end, after many batches.
    inputs.push(("late ]".into(), format!("{scene}]\n").into_bytes()));
    // An assembler's error in the middle.
    let half = scene.len() / 2;
    let cut = half + scene[half..].find("\n\tPattern").unwrap();
    let mut middle = scene.clone();
    middle.insert_str(cut + 1, "Pattern \"PxrFractal\"\n");
    inputs.push(("middle RB004".into(), middle.into_bytes()));
    // A parameter's error (RB006: no type, and the shader does not declare it) in the
    // middle, after findings of the same request.
    let mut middle = scene.clone();
    middle.insert_str(
        cut + 1,
        "Pattern \"PxrFractal\" \"f\" \"bogus float a\" [1] \"undeclared\" [1]\n",
    );
    inputs.push(("middle RB006".into(), middle.into_bytes()));
    let strict = RibOptions {
        strict: true,
        ..RibOptions::default()
    };
    let mut few_nodes = RibOptions::default();
    few_nodes.limits.nodes = 40;
    for (name, src) in &inputs {
        for options in [&RibOptions::default(), &strict, &few_nodes] {
            let serial = read_outcome(src, options, None);
            for batch in [1, 2, 3, 7, 256] {
                let pipelined = read_outcome(src, options, Some(batch));
                assert!(
                    serial == pipelined,
                    "{name}, batches of {batch}, {options:?}:\n{serial}\n---\n{pipelined}"
                );
            }
        }
    }
}

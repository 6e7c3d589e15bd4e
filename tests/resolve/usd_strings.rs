//! Strings through USD: read as Pixar's USD reads them (the escapes of the text format
//! decoded), written so that it reads them back, in `.usda` and `.usdc`, and kept through
//! RIB; Pixar's own test files open; text that does not read is US001 at its place.
//! (`tests/data/usd/pxr_check.py` has Pixar's USD itself judge the same strings in CI.)

use proptest::prelude::*;
use vstructc::back::rib::write_rib_to_vec;
use vstructc::back::usd::{UsdMode, write_usd};
use vstructc::front::rib::{RibOptions, parse_rib};
use vstructc::front::usd::parse_usd;
use vstructc::limits::Limits;
use vstructc::network::{Network, RequestKind};
use vstructc::registry::Registry;
use vstructc::resolve::{ResolveOptions, resolve};
use vstructc::types::Value;
use vstructc::{Diagnostics, Severity};

/// usda string literals and the values Pixar's USD (usd-core 0.26) reads in them.
const PIXAR_READS: &[(&str, &str)] = &[
    (r#""it\\'s""#, r"it\'s"),
    (r#""tab\there""#, "tab\there"),
    (r#""back\\slash""#, r"back\slash"),
    (r#""C:\\tex\\a.tex""#, r"C:\tex\a.tex"),
    (r#""C:\tex\a.tex""#, "C:\tex\x07.tex"),
    (r#""\a\b\f\n\r\t\v""#, "\x07\x08\x0c\n\r\t\x0b"),
    (r#""\\ \" \'""#, "\\ \" '"),
    (r"'\q\z\?'", "qz?"),
    (r#""\x41\x4g\x414\x""#, "A\x04gA4\0"),
    (r#""\101\0\08\1234\8\9""#, "A\0\08S489"),
    (r#""\u0041""#, "u0041"),
    (r#""\xc3\xa9 é""#, "é é"),
    ("\"\"\"a\\\nb\"\"\"", "a\nb"),
    (r#""""x"y""z""""#, r#"x"y""z"#),
    (r#""""a\"""b""""#, r#"a"""b"#),
    (r"'''a\''''", "a'"),
    (r#""""a\"""""#, "a\""),
    (r#""""""x""""#, r#"""x"#),
    (r#"'a"b'"#, r#"a"b"#),
    (r#""""\\""""#, "\\"),
    (r#""""\""" and '''""""#, r#"""" and '''"#),
    (r#""""#, ""),
    ("''''''", ""),
];

/// Asset path literals and what Pixar's USD reads in them.
const PIXAR_READS_ASSETS: &[(&str, &str)] = &[
    (r"@C:\tex\a.tex@", r"C:\tex\a.tex"),
    ("@@@a@b@@@", "a@b"),
    (r"@@@a\@@@b@@@", "a@@@b"),
    (r"@@@a\\b@@@", r"a\\b"),
    ("@@@a@@@@", "a@"),
];

fn read(text: &[u8], name: &str) -> Network {
    let mut diags = Diagnostics::new();
    let net = parse_usd(
        text,
        name,
        &Registry::embedded(),
        &Limits::default(),
        &mut diags,
    )
    .unwrap_or_else(|e| panic!("{name}: {e}"));
    assert!(
        !diags.iter().any(|d| d.severity >= Severity::Warning),
        "{name}: {diags:#?}"
    );
    net
}

/// One PxrSurface whose input `note` (of USD type `usd_type`) is `literal`.
fn stage_with(usd_type: &str, literal: &str) -> String {
    format!(
        "#usda 1.0\ndef Material \"M\" {{\n    token outputs:ri:surface.connect = </M/S.outputs:out>\n    \
         def Shader \"S\" {{\n        uniform token info:id = \"PxrSurface\"\n        \
         {usd_type} inputs:note = {literal}\n        token outputs:out\n    }}\n}}\n"
    )
}

fn note(net: &Network) -> Option<&Value> {
    let s = net.find("/M/S").expect("the shader");
    net[s].value("note")
}

#[test]
fn usda_strings_read_as_pixar_reads_them() {
    for &(literal, want) in PIXAR_READS {
        let net = read(stage_with("string", literal).as_bytes(), literal);
        assert_eq!(note(&net), Some(&Value::Str(want.to_string())), "{literal}");
    }
    for &(literal, want) in PIXAR_READS_ASSETS {
        let net = read(stage_with("asset", literal).as_bytes(), "look.usda");
        assert_eq!(
            note(&net),
            Some(&Value::Asset(want.to_string())),
            "{literal}"
        );
    }
}

/// The forms Pixar's USD still reads and `openusd` alone does not: `config`, a legacy type
/// name before an attribute name (not a prim type of the same name), `//` comments, and
/// strings and paths inside comments and paths that are not strings.
#[test]
fn legacy_forms_read_as_pixar_reads_them() {
    let text = "#usda 1.0\n// a comment with a \"quote\ndef Point \"P\" {\n    \
                def Material \"M\" {\n        token outputs:ri:surface.connect = \
                </P/M/S.outputs:out> # it's\n        def Shader \"S\" /* '@ */ {\n            \
                config token info:id = \"PxrSurface\"\n            \
                PointFloat[] inputs:p = [(1, 2, 3)]\n            \
                Color inputs:c = (0.5, 0.25, 1)\n            token outputs:out\n        }\n    }\n}\n";
    let reg = Registry::embedded();
    let net = read(text.as_bytes(), "legacy.usda");
    let s = net.find("/P/M/S").expect("the shader");
    assert_eq!(net[s].shader(), "PxrSurface");
    assert!(
        net[s].value("p").is_some(),
        "{:?}",
        net[s].params().collect::<Vec<_>>()
    );
    assert!(net[s].value("c").is_some());
    let mut out = Vec::new();
    let from = UsdMode::FlattenFrom {
        name: "legacy.usda",
        bytes: text.as_bytes(),
    };
    write_usd(&net, &reg, from, "usda", &mut out).unwrap();
    let written = String::from_utf8(out).unwrap();
    assert!(written.contains("def Point \"P\""), "{written}");
}

/// A network of one surface whose inputs `note0`, `note1`, … hold `values`.
fn network_of(values: &[Value]) -> Network {
    let mut net = Network::new();
    let s = net.add_node_of_kind("S", "PxrSurface", RequestKind::Bxdf);
    for (i, v) in values.iter().enumerate() {
        net.set_param(s, &format!("note{i}"), v.clone());
    }
    let m = net.add_material("M");
    net.set_terminal(m, "surface", s, None);
    net
}

fn notes(net: &Network) -> Vec<Option<Value>> {
    let s = net
        .nodes_sorted()
        .into_iter()
        .find(|&id| net[id].shader() == "PxrSurface")
        .expect("the surface");
    (0..)
        .map(|i| net[s].value(&format!("note{i}")).cloned())
        .take_while(Option::is_some)
        .collect()
}

/// `values` written to `encoding` and read back.
fn through_usd(values: &[Value], encoding: &str) -> Vec<Option<Value>> {
    let reg = Registry::embedded();
    let mut out = Vec::new();
    write_usd(
        &network_of(values),
        &reg,
        UsdMode::Flatten,
        encoding,
        &mut out,
    )
    .unwrap_or_else(|e| panic!("{encoding}: {e}"));
    notes(&read(&out, &format!("out.{encoding}")))
}

/// `values` through RIB, then USD `encoding`, then RIB again.
fn through_rib_and_usd(values: &[Value], encoding: &str) -> Vec<Option<Value>> {
    let reg = Registry::embedded();
    let rib_in = |bytes: &[u8]| {
        let mut diags = Diagnostics::new();
        parse_rib(bytes, "n.rib", &reg, &RibOptions::default(), &mut diags).expect("RIB reads")
    };
    let rib = write_rib_to_vec(b"", &network_of(values), &reg).unwrap();
    let mut usd = Vec::new();
    write_usd(&rib_in(&rib), &reg, UsdMode::Flatten, encoding, &mut usd).unwrap();
    let back = write_rib_to_vec(b"", &read(&usd, &format!("n.{encoding}")), &reg).unwrap();
    notes(&rib_in(&back))
}

fn strings_and_assets() -> Vec<Value> {
    let mut values: Vec<Value> = PIXAR_READS
        .iter()
        .map(|(_, v)| Value::Str(v.to_string()))
        .collect();
    values.extend(
        PIXAR_READS_ASSETS
            .iter()
            .map(|(_, v)| Value::Asset(v.to_string())),
    );
    values.push(Value::Str("\u{1}ctl\u{7f} 漢字 🎨".to_string()));
    values.push(Value::Str(r"end\".to_string()));
    values
}

fn has_nul(v: &Option<Value>) -> bool {
    matches!(v, Some(Value::Str(s) | Value::Asset(s)) if s.contains('\0'))
}

fn without_nul(values: &[Value]) -> Vec<Value> {
    values
        .iter()
        .filter(|v| !matches!(v, Value::Str(s) | Value::Asset(s) if s.contains('\0')))
        .cloned()
        .collect()
}

/// A crate file cannot hold a string with a NUL character: writing one is an error that
/// names the input, not a file that does not read.
#[test]
fn nul_characters_are_refused_for_crate_files() {
    let net = network_of(&[Value::Str("a\0b".to_string())]);
    let mut out = Vec::new();
    let e = write_usd(
        &net,
        &Registry::embedded(),
        UsdMode::Flatten,
        "usdc",
        &mut out,
    )
    .unwrap_err();
    assert!(
        e.to_string().contains("`note0` of node `S` holds a NUL"),
        "{e}"
    );
    assert!(out.is_empty());
}

#[test]
fn strings_survive_usda_and_usdc() {
    let values = strings_and_assets();
    let want: Vec<_> = values.iter().cloned().map(Some).collect();
    for encoding in ["usda", "usdc", "usdz"] {
        // A crate file keeps strings NUL-separated, as Pixar's USD does: none holds a NUL.
        let (values, want) = match encoding {
            "usda" => (values.clone(), want.clone()),
            _ => (
                without_nul(&values),
                want.iter().filter(|v| !has_nul(v)).cloned().collect(),
            ),
        };
        assert_eq!(through_usd(&values, encoding), want, "{encoding}");
        // RIB has no asset type: an asset path comes back as a string of the same text.
        let as_rib: Vec<_> = want
            .iter()
            .map(|v| match v {
                Some(Value::Asset(a)) => Some(Value::Str(a.clone())),
                v => v.clone(),
            })
            .collect();
        assert_eq!(
            through_rib_and_usd(&values, encoding),
            as_rib,
            "RIB and {encoding}"
        );
    }
}

/// The same look in RIB and in usda, its strings written with escapes in each, resolves
/// to the same network.
#[test]
fn escaped_strings_resolve_as_in_rib() {
    let reg = Registry::embedded();
    let rib = br#"Bxdf "PxrSurface" "S" "string note0" ["it\\'s"] "string note1" ["tab\there"]"#;
    let mut diags = Diagnostics::new();
    let mut from_rib =
        parse_rib(rib, "n.rib", &reg, &RibOptions::default(), &mut diags).expect("RIB reads");
    let usda = stage_with("string", r#""it\\'s""#).replace(
        "token outputs:out",
        "string inputs:note1 = \"tab\\there\"\n        token outputs:out",
    );
    let mut from_usd = read(
        usda.replace("inputs:note ", "inputs:note0 ").as_bytes(),
        "n.usda",
    );
    resolve(&mut from_rib, &reg, &ResolveOptions::default());
    resolve(&mut from_usd, &reg, &ResolveOptions::default());
    assert_eq!(notes(&from_usd), notes(&from_rib));
    assert_eq!(
        notes(&from_usd),
        vec![
            Some(Value::Str(r"it\'s".to_string())),
            Some(Value::Str("tab\there".to_string()))
        ]
    );
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(300))]

    /// Any string (quotes of both kinds in any run, backslashes, line ends, tabs, control
    /// and non-ASCII characters, empty) comes back from `.usda` and `.usdc` as it went in,
    /// and so does an asset path with backslashes or with `@` (the usda text has no
    /// form for a path holding `@` that ends in a backslash).
    #[test]
    fn generated_strings_survive_usda_and_usdc(
        s in "[\"'\\\\\n\r\t\u{1}a-c é漢@\u{F8FF}\u{F8FE}]{0,12}",
        windows in "[\\\\a-c:/. ]{0,10}",
        at in "[a-c@ ]{0,10}",
    ) {
        let values = [Value::Str(s.clone()), Value::Asset(windows.clone()), Value::Asset(at.clone())];
        let want: Vec<_> = values.iter().cloned().map(Some).collect();
        for encoding in ["usda", "usdc"] {
            prop_assert_eq!(&through_usd(&values, encoding), &want, "{:?} {}", values, encoding);
        }
    }
}

#[test]
fn pixar_test_suite_files_open_and_resolve() {
    let dir = fixtures_or_skip!().join("usd/openusd");
    let reg = Registry::embedded();
    let mut files: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "usda"))
        .collect();
    files.sort();
    assert_eq!(files.len(), 13, "{}", dir.display());
    for path in files {
        let name = path.to_str().unwrap();
        let mut diags = Diagnostics::new();
        let mut net = parse_usd(
            &std::fs::read(&path).unwrap(),
            name,
            &reg,
            &Limits::default(),
            &mut diags,
        )
        .unwrap_or_else(|e| panic!("{name}: {e}"));
        assert!(!diags.has_errors(), "{name}: {diags:#?}");
        assert!(net.node_count() > 0, "{name}: no shaders");
        resolve(&mut net, &reg, &ResolveOptions::default());
        let mut out = Vec::new();
        write_usd(&net, &reg, UsdMode::Flatten, "usdc", &mut out).unwrap();
    }
}

/// A layer Pixar's USD would not read is US001 at the line and column where it stops.
#[test]
fn unreadable_usda_is_us001_at_its_place() {
    let reg = Registry::embedded();
    for (text, line, column) in [
        (
            "#usda 1.0\ndef Shader \"S\" {\n    float inputs:x = }\n}\n",
            3,
            22,
        ),
        (
            "#usda 1.0\ndef Shader \"S\" {\n    string inputs:x = \"open\n}\n",
            3,
            23,
        ),
        (
            "#usda 1.0\ndef Shader \"S\" {\n    asset inputs:x = @a.tex\n}\n",
            3,
            22,
        ),
        (
            "#usda 1.0\ndef Shader \"S\" {\n    string a = \"\\t\"\n    float b = ]\n}\n",
            4,
            15,
        ),
    ] {
        let mut diags = Diagnostics::new();
        let e = parse_usd(
            text.as_bytes(),
            "bad.usda",
            &reg,
            &Limits::default(),
            &mut diags,
        )
        .unwrap_err();
        assert_eq!(e.code(), Some("US001"), "{e}");
        let at = e
            .diagnostic()
            .and_then(|d| d.location.clone())
            .expect("a place");
        assert_eq!((at.line, at.column), (line, column), "{text}: {e}");
    }
}

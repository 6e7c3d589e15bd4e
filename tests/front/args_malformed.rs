//! Malformed `.args` inputs (tests/data/args/malformed): each gives its specified code at the
//! right line:column (positions counted by hand from the files), the CLI exits 1 on a rejected
//! file, and nothing panics on arbitrary bytes.

use proptest::prelude::*;
use std::process::Command;
use vstructc::front::args::parse_args;
use vstructc::registry::{Registry, RegistryOptions};
use vstructc::{Diagnostic, Diagnostics, Severity};

const DIR: &str = "tests/data/args/malformed";

fn read(name: &str) -> (String, Vec<u8>) {
    let path = format!("{DIR}/{name}");
    let full = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join(&path);
    (path, std::fs::read(full).unwrap())
}

/// The rejecting error of a file that must not load.
fn rejected(name: &str) -> Diagnostic {
    let (path, bytes) = read(name);
    let mut diags = Diagnostics::new();
    match parse_args(&bytes, &path, "x", &mut diags) {
        Ok(_) => panic!("{name} should be rejected"),
        Err(e) => (*e.diagnostic().expect("input error")).clone(),
    }
}

/// The diagnostics of a file that must load.
fn accepted(name: &str) -> Diagnostics {
    let (path, bytes) = read(name);
    let mut diags = Diagnostics::new();
    parse_args(&bytes, &path, "x", &mut diags).unwrap_or_else(|e| panic!("{name}: {e}"));
    diags
}

fn assert_at(d: &Diagnostic, code: &str, severity: Severity, line: u32, column: u32) {
    assert_eq!(d.code.as_str(), code, "{}", d.render_human());
    assert_eq!(d.severity, severity, "{}", d.render_human());
    let loc = d.location.as_ref().expect("located");
    assert!(loc.file.starts_with(DIR), "{loc}");
    assert_eq!(
        (loc.line, loc.column),
        (line, column),
        "{}",
        d.render_human()
    );
}

fn only(diags: &Diagnostics, code: &str) -> Diagnostic {
    let found: Vec<_> = diags.with_code(code).collect();
    assert_eq!(found.len(), 1, "{diags:?}");
    found[0].clone()
}

#[test]
fn truncated_inside_a_tag_is_ar001_at_the_tag() {
    let d = rejected("truncated_in_tag.args");
    assert_at(&d, "AR001", Severity::Error, 3, 3);
}

#[test]
fn truncated_with_open_elements_is_ar001_at_end_of_file() {
    let d = rejected("truncated_unclosed.args");
    assert_at(&d, "AR001", Severity::Error, 5, 1);
    assert!(d.message.contains("<page>"), "{}", d.message);
    assert_eq!(d.related[0].1.line, 3);
}

#[test]
fn mismatched_end_tag_is_ar001() {
    assert_at(
        &rejected("mismatched_end.args"),
        "AR001",
        Severity::Error,
        5,
        3,
    );
}

#[test]
fn unknown_entity_is_ar001_at_the_ampersand() {
    let d = rejected("unknown_entity.args");
    assert_at(&d, "AR001", Severity::Error, 3, 46);
    assert!(d.message.contains("&nbsp;"), "{}", d.message);
}

#[test]
fn duplicate_attribute_is_ar001_at_the_second() {
    assert_at(
        &rejected("duplicate_attribute.args"),
        "AR001",
        Severity::Error,
        3,
        35,
    );
}

#[test]
fn second_root_and_empty_file_are_ar001() {
    assert_at(&rejected("two_roots.args"), "AR001", Severity::Error, 4, 1);
    assert_at(&rejected("empty.args"), "AR001", Severity::Error, 1, 1);
}

#[test]
fn wrong_root_is_ar002() {
    let d = rejected("wrong_root.args");
    assert_at(&d, "AR002", Severity::Error, 3, 1);
    assert!(d.message.contains("<shader>"));
}

#[test]
fn missing_name_is_ar003() {
    assert_at(
        &rejected("missing_name.args"),
        "AR003",
        Severity::Error,
        3,
        3,
    );
    assert_at(
        &rejected("missing_output_name.args"),
        "AR003",
        Severity::Error,
        3,
        3,
    );
}

#[test]
fn duplicate_names_are_ar004_with_the_first_declaration() {
    let d = rejected("duplicate_param.args");
    assert_at(&d, "AR004", Severity::Error, 5, 7);
    assert_eq!((d.related[0].1.line, d.related[0].1.column), (3, 3));
    // An input and an output may share a name; two outputs may not.
    let d = rejected("duplicate_output.args");
    assert_at(&d, "AR004", Severity::Error, 5, 3);
}

#[test]
fn invalid_utf8_is_ar005_at_the_byte() {
    let d = rejected("invalid_utf8.args");
    assert_at(&d, "AR005", Severity::Error, 4, 14);
}

#[test]
fn other_declared_encoding_is_ar005() {
    let d = rejected("latin1_declaration.args");
    assert_at(&d, "AR005", Severity::Error, 1, 31);
}

#[test]
fn missing_shader_type_and_format_are_warnings() {
    let diags = accepted("no_shader_type.args");
    assert_at(&only(&diags, "AR010"), "AR010", Severity::Warning, 1, 1);
    assert_at(&only(&diags, "AR014"), "AR014", Severity::Warning, 1, 1);
}

#[test]
fn unknown_type_is_ar011_at_the_value() {
    let diags = accepted("unknown_type.args");
    assert_at(&only(&diags, "AR011"), "AR011", Severity::Warning, 3, 29);
}

#[test]
fn bad_default_arity_is_ar012_at_the_value() {
    let diags = accepted("bad_default_arity.args");
    assert_at(&only(&diags, "AR012"), "AR012", Severity::Warning, 4, 19);
}

#[test]
fn non_integer_array_size_is_ar013() {
    let diags = accepted("bad_array_size.args");
    assert_at(&only(&diags, "AR013"), "AR013", Severity::Warning, 3, 49);
}

#[test]
fn bad_vstructmember_is_vs003_from_the_registry() {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join(DIR)
        .join("bad_vstructmember.args");
    let reg = Registry::new(RegistryOptions::only([&path]));
    let tables = reg.tables("bad_vstructmember").expect("loads");
    assert!(tables.is_empty(), "a malformed member declares no head");
    let diags = reg.diagnostics();
    let d = only(&diags, "VS003");
    assert_eq!(d.severity, Severity::Warning);
    let loc = d.location.unwrap();
    assert_eq!((loc.line, loc.column), (4, 3));
    assert!(d.message.contains("inputMaterialdiffuseGain"));
}

fn vstructc(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_vstructc"))
        .args(args)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .env_remove("VSTRUCTC_ARGS_PATH")
        .output()
        .unwrap()
}

#[test]
fn cli_exits_1_on_a_rejected_file() {
    for (id, code) in [
        ("missing_name", "AR003"),
        ("truncated_in_tag", "AR001"),
        ("invalid_utf8", "AR005"),
    ] {
        let file = format!("{DIR}/{id}.args");
        let out = vstructc(&["info", id, "--args", &file]);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(1), "{id}: {stderr}");
        assert!(stderr.contains(&format!("error[{code}]")), "{stderr}");
        assert!(stderr.contains(&format!("--> {file}:")), "{stderr}");
    }
}

#[test]
fn cli_warnings_exit_0_unless_denied() {
    let file = format!("{DIR}/unknown_type.args");
    let out = vstructc(&["info", "unknown_type", "--args", &file]);
    assert_eq!(out.status.code(), Some(0));
    assert!(String::from_utf8_lossy(&out.stderr).contains("warning[AR011]"));
    let out = vstructc(&["info", "unknown_type", "--args", &file, "--deny-warnings"]);
    assert_eq!(out.status.code(), Some(1));
}

#[test]
fn every_malformed_file_is_handled_without_panic() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join(DIR);
    let mut n = 0;
    for e in std::fs::read_dir(dir).unwrap() {
        let p = e.unwrap().path();
        let bytes = std::fs::read(&p).unwrap();
        let mut diags = Diagnostics::new();
        if let Err(e) = parse_args(&bytes, &p.to_string_lossy(), "x", &mut diags) {
            let d = e.diagnostic().expect("input errors are diagnostics");
            assert!(d.code.starts_with("AR"), "{d}");
            assert!(
                d.location
                    .as_ref()
                    .is_some_and(|l| l.line > 0 && l.column > 0),
                "{d}"
            );
        }
        for d in &diags {
            assert!(d.location.as_ref().is_some_and(|l| l.line > 0), "{d}");
        }
        n += 1;
    }
    assert!(n >= 12);
}

/// XML-ish fragments the generator assembles into documents.
fn xmlish() -> impl Strategy<Value = String> {
    let piece = prop_oneof![
        Just("<args format=\"1.0\">".to_string()),
        Just("</args>".to_string()),
        Just("<param name=\"a\" type=\"float\" default=\"1\">".to_string()),
        Just("<param name='b' type = 'color' default='1 2'/>".to_string()),
        Just("</param>".to_string()),
        Just("<output name=\"o\" vstructmember=\"h.m\" vstructConditionalExpr=\"connect if a == 1\">".to_string()),
        Just("</output>".to_string()),
        Just("<tags><tag value=\"vstruct\"/></tags>".to_string()),
        Just("<page name=\"P\">".to_string()),
        Just("</page>".to_string()),
        Just("<help>x <b>y</b></help>".to_string()),
        Just("<hintdict name=\"options\"><string name=\"A\" value=\"1\"/></hintdict>".to_string()),
        Just("<shaderType><tag value=\"pattern\"/></shaderType>".to_string()),
        Just("<!-- c -->".to_string()),
        Just("&amp;&#10;&bogus;".to_string()),
        Just("<?xml version=\"1.0\"?>".to_string()),
        "[ -~\n]{0,12}",
    ];
    prop::collection::vec(piece, 0..24).prop_map(|v| v.concat())
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]

    #[test]
    fn random_bytes_never_panic(bytes in prop::collection::vec(any::<u8>(), 0..512)) {
        let mut diags = Diagnostics::new();
        let _ = parse_args(&bytes, "fuzz.args", "fuzz", &mut diags);
    }

    #[test]
    fn random_xmlish_text_never_panics(text in xmlish()) {
        let mut diags = Diagnostics::new();
        match parse_args(text.as_bytes(), "fuzz.args", "fuzz", &mut diags) {
            Ok(def) => {
                // Tables build without panicking on whatever was accepted.
                let mut d = Vec::new();
                let _ = vstructc::registry::VstructTables::build(&def, &mut d);
            }
            Err(e) => prop_assert!(e.diagnostic().is_some()),
        }
    }
}

/// Positions far into one long line (a generated file written without line breaks) are
/// counted in characters, with multi-byte characters before them, as on a short line.
#[test]
fn positions_on_one_long_line_count_characters() {
    let mut text = String::from("<args format=\"1.0\">");
    for i in 0..3000 {
        // Labels of different lengths in two- and three-byte characters, so that positions
        // fall at every offset within the reader's blocks of bytes.
        let label: String = "é€".repeat(i % 7);
        text.push_str(&format!(
            "<param name=\"p{i}\" type=\"float\" default=\"0\" label=\"{label}\"/>"
        ));
    }
    text.push_str("</args>");
    let mut diags = Diagnostics::new();
    let def = parse_args(text.as_bytes(), "one_line.args", "x", &mut diags).unwrap();
    assert_eq!(def.inputs.len(), 3000);
    let (mut from, mut chars) = (0, 0);
    for (i, p) in def.inputs.iter().enumerate() {
        let at = from
            + text[from..]
                .find(&format!("<param name=\"p{i}\" "))
                .expect("declared");
        chars += text[from..at].chars().count();
        from = at;
        let loc = &p.location;
        assert_eq!((loc.line, loc.column), (1, chars as u32 + 1), "p{i}");
    }
    // The duplicate's error, after all of them, is at its tag too.
    let mut diags = Diagnostics::new();
    let text = text.replace("</args>", "<param name=\"p5\" type=\"float\"/></args>");
    let err = parse_args(text.as_bytes(), "one_line.args", "x", &mut diags).unwrap_err();
    let d = err.diagnostic().expect("input error");
    let at = text.rfind("<param name=\"p5\"").unwrap();
    let loc = d.location.as_ref().expect("located");
    assert_eq!(d.code.as_str(), "AR004");
    assert_eq!(loc.column, text[..at].chars().count() as u32 + 1);
}

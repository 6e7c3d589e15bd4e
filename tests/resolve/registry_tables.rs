//! vstruct table rules (vstruct.md §2.2–§2.7) on small hand-written definitions in
//! tests/data/args/tables: aliases, later-wins (VS004), mixed directions (VS005), aliases with
//! spaces (VS006), missing head properties (VS007), nested heads (VS008), conditionals (VS001,
//! VS002, VS009, AR022) and head normalisation.

use std::path::PathBuf;
use std::sync::Arc;
use vstructc::registry::{Definition, Registry, RegistryOptions, VstructTables};
use vstructc::types::{BaseType, Value};
use vstructc::{Diagnostic, Diagnostics, Severity};

fn data(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join(format!("tests/data/args/tables/{name}.args"))
}

fn load(name: &str) -> (Arc<Definition>, Arc<VstructTables>, Diagnostics) {
    let reg = Registry::new(RegistryOptions::only([data(name)]));
    let def = reg.definition(name).expect("definition");
    let tables = reg.tables(name).expect("tables");
    (def, tables, reg.diagnostics())
}

fn codes<'a>(diags: &'a Diagnostics, code: &'a str) -> Vec<&'a Diagnostic> {
    diags.with_code(code).collect()
}

fn line_col(d: &Diagnostic) -> (u32, u32) {
    let l = d.location.as_ref().expect("located");
    (l.line, l.column)
}

#[test]
fn aliases_extend_name_lists_on_both_sides() {
    let (_, t, _) = load("aliases");
    let members = t.members_in("in");
    let names: Vec<Vec<&str>> = members
        .iter()
        .map(|m| m.names.iter().map(String::as_str).collect())
        .collect();
    assert_eq!(names, [vec!["a", "alpha"], vec!["b"], vec!["c", "x y"]]);
    assert_eq!(&*members[0].property, "in_a");
    // The alias is entered in the reverse table like a primary name.
    assert_eq!(&*t.reverse_out("out", "alpha").unwrap().property, "out_a");
    assert_eq!(&*t.reverse_out("out", "a").unwrap().property, "out_a");
    assert!(t.reverse_out("out", "c").is_none());
}

#[test]
fn alias_with_whitespace_is_vs006_and_kept_whole() {
    let (_, _, diags) = load("aliases");
    let vs006 = codes(&diags, "VS006");
    assert_eq!(vs006.len(), 1, "{diags:?}");
    assert_eq!(vs006[0].severity, Severity::Warning);
    assert_eq!(line_col(vs006[0]), (8, 3));
}

#[test]
fn empty_conditional_means_unconditional() {
    let (_, t, _) = load("aliases");
    assert!(t.reverse_out("out", "b").unwrap().cond.is_none());
}

#[test]
fn heads_are_normalised_to_vstruct_without_default() {
    let (def, t, _) = load("aliases");
    // Encoding E1: a float param with a vstruct tag and a default.
    let head = def.input("in").unwrap();
    assert_eq!(head.ty.base, BaseType::Vstruct);
    assert_eq!(
        head.declared_type, "float",
        "declared type kept for diagnostics"
    );
    assert_eq!(head.default, None);
    // A vstruct tag without members pointing at it is not a head.
    let lonely = def.input("lonely").unwrap();
    assert!(!t.is_input_head("lonely"));
    assert_eq!(lonely.ty.base, BaseType::Float);
    assert_eq!(lonely.default, Some(Value::Float(1.0)));
    // The output head (E3) too; members keep their own types.
    assert_eq!(def.output("out").unwrap().ty.base, BaseType::Vstruct);
    assert_eq!(def.output("out_a").unwrap().ty.base, BaseType::Float);
    assert!(t.is_input_head("in") && !t.is_output_head("in"));
    assert!(t.is_output_head("out") && !t.is_input_head("out"));
}

#[test]
fn later_output_member_wins_with_vs004() {
    let (_, t, diags) = load("later_wins");
    assert_eq!(&*t.reverse_out("out", "x").unwrap().property, "out_x2");
    // An alias colliding with an earlier primary name also takes it over.
    assert_eq!(&*t.reverse_out("out", "p").unwrap().property, "out_q");
    assert_eq!(&*t.reverse_out("out", "q").unwrap().property, "out_q");
    // Every member stays in the declaration-order list.
    assert_eq!(t.members_out("out").len(), 4);
    let vs004 = codes(&diags, "VS004");
    assert_eq!(vs004.len(), 2, "{diags:?}");
    assert_eq!(line_col(vs004[0]), (5, 3));
    assert_eq!(line_col(vs004[1]), (7, 3));
    assert!(vs004[0].message.contains("out_x1") && vs004[0].message.contains("out_x2"));
    assert_eq!(vs004[0].related[0].1.line, 4);
    // The deprecated tag attribute made `out` a vstruct-tagged output (AR020 info).
    assert_eq!(codes(&diags, "AR020").len(), 1);
}

#[test]
fn head_with_input_and_output_members_is_vs005_and_split() {
    let (_, t, diags) = load("mixed_heads");
    assert!(t.is_input_head("h") && t.is_output_head("h"));
    assert_eq!(&*t.members_in("h")[0].property, "h_a");
    assert_eq!(&*t.reverse_out("h", "a").unwrap().property, "h_a_out");
    let vs005 = codes(&diags, "VS005");
    assert_eq!(vs005.len(), 1, "{diags:?}");
    assert_eq!(line_col(vs005[0]), (3, 3));
    // Neither an input nor an output named `h` exists: VS007 (info) once per direction.
    let vs007 = codes(&diags, "VS007");
    assert_eq!(vs007.len(), 2, "{diags:?}");
    assert!(vs007.iter().all(|d| d.severity == Severity::Info));
}

#[test]
fn nested_head_is_vs008_and_not_flattened() {
    let (def, t, diags) = load("nested");
    let outer: Vec<&str> = t.members_in("outer").iter().map(|m| &*m.property).collect();
    assert_eq!(outer, ["inner", "outer_y"]);
    assert_eq!(
        t.members_in("outer")[1].names,
        ["a.b.c"],
        "member names may contain dots"
    );
    assert_eq!(&*t.members_in("inner")[0].property, "inner_x");
    let vs008 = codes(&diags, "VS008");
    assert_eq!(vs008.len(), 1, "{diags:?}");
    assert_eq!(line_col(vs008[0]), (4, 3));
    // The nested head is normalised like any head.
    let inner = def.input("inner").unwrap();
    assert_eq!(inner.ty.base, BaseType::Vstruct);
    assert_eq!(inner.default, None);
    assert!(
        codes(&diags, "VS007").is_empty(),
        "both heads exist: {diags:?}"
    );
}

#[test]
fn conditionals_on_inputs_are_parsed_then_vs002() {
    let (_, _, diags) = load("conditionals");
    let vs002 = codes(&diags, "VS002");
    assert_eq!(vs002.len(), 1, "{diags:?}");
    assert_eq!(vs002[0].severity, Severity::Info);
    // Points at the attribute value of `h_in` (line 5).
    assert_eq!(vs002[0].location.as_ref().unwrap().line, 5);
    // A conditional on a non-member is AR022 from the reader.
    let ar022 = codes(&diags, "AR022");
    assert_eq!(ar022.len(), 1, "{diags:?}");
    assert_eq!(ar022[0].location.as_ref().unwrap().line, 6);
}

#[test]
fn identical_conditionals_are_parsed_once() {
    let (_, t, _) = load("conditionals");
    let ok = t.reverse_out("out", "ok").unwrap().cond.as_ref().unwrap();
    let same = t.reverse_out("out", "same").unwrap().cond.as_ref().unwrap();
    assert!(Arc::ptr_eq(&ok.parsed, &same.parsed));
    assert_eq!(ok.source.text, "connect if enable == 1 ");
    assert_eq!(
        (ok.source.location.line, ok.source.location.column),
        (8, 35)
    );
}

#[test]
fn unparsable_conditionals_are_vs001_at_value_start_plus_offset() {
    let (_, t, diags) = load("conditionals");
    let bad = t.reverse_out("out", "bad").unwrap().cond.as_ref().unwrap();
    assert!(bad.parsed.is_err(), "`== ==` does not parse");
    let blank = t
        .reverse_out("out", "blank")
        .unwrap()
        .cond
        .as_ref()
        .unwrap();
    assert!(
        blank.parsed.is_err(),
        "whitespace is not an empty conditional"
    );
    let vs001: Vec<_> = codes(&diags, "VS001")
        .into_iter()
        .filter(|d| d.message.contains("out_bad") || d.message.contains("out_blank"))
        .collect();
    assert_eq!(vs001.len(), 2, "{diags:?}");
    for (d, c) in vs001.iter().zip([bad, blank]) {
        let span = d.span.clone().expect("span");
        let err = c.parsed.as_ref().as_ref().unwrap_err();
        assert_eq!(span, err.span);
        let offset = c.source.text[..span.start].chars().count() as u32;
        let loc = d.location.as_ref().unwrap();
        assert_eq!(loc.line, c.source.location.line);
        assert_eq!(loc.column, c.source.location.column + offset);
        assert_eq!(d.severity, Severity::Warning);
    }
}

#[test]
fn conditional_naming_an_unknown_parameter_is_vs009() {
    let (_, t, diags) = load("conditionals");
    let c = t
        .reverse_out("out", "unknown")
        .unwrap()
        .cond
        .as_ref()
        .unwrap();
    let stmt = c.statement().expect("the conditional parses");
    assert!(stmt.param_names().contains(&"missingParam"));
    let vs009 = codes(&diags, "VS009");
    assert_eq!(vs009.len(), 1, "{diags:?}");
    assert!(vs009[0].message.contains("missingParam"));
    assert_eq!(vs009[0].location.as_ref().unwrap().line, 12);
}

#[test]
fn tables_build_directly_from_a_definition() {
    let (def, t, _) = load("aliases");
    let mut diags = Vec::new();
    let again = VstructTables::build(&def, &mut diags);
    assert_eq!(again.members_in("in"), t.members_in("in"));
    assert_eq!(again.input_heads().collect::<Vec<_>>(), ["in"]);
    assert_eq!(again.output_heads().collect::<Vec<_>>(), ["out"]);
}

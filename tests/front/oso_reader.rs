//! `.oso` reader: public fixtures, the test vectors of formats.md §4.3, and the error policy.

use crate::common;

use vstructc::front::oso::parse_oso;
use vstructc::registry::{Definition, Direction};
use vstructc::{ArraySpec, BaseType, Diagnostics, Error, Severity, Type, Value};

fn parse(text: &str) -> (Result<Definition, Error>, Diagnostics) {
    let mut diags = Diagnostics::new();
    let result = parse_oso(text.as_bytes(), "t.oso", &mut diags);
    (result, diags)
}

/// Parse text that must load; returns the definition and its diagnostics.
fn load(text: &str) -> (Definition, Diagnostics) {
    let (result, diags) = parse(text);
    match result {
        Ok(def) => (def, diags),
        Err(e) => panic!("unexpected error: {e}"),
    }
}

/// Parse text that must be rejected; returns (code, line, column).
fn reject(text: &str) -> (&'static str, u32, u32) {
    let (result, _) = parse(text);
    let err = result.expect_err("the input must be rejected");
    let d = err.diagnostic().expect("an input error with a diagnostic");
    assert_eq!(d.severity, Severity::Error);
    let loc = d.location.as_ref().expect("a location");
    assert_eq!(&*loc.file, "t.oso");
    (d.code.as_str(), loc.line, loc.column)
}

fn floats(xs: &[f32]) -> Value {
    Value::Array(
        BaseType::Float,
        xs.iter().map(|x| Value::Float(*x)).collect(),
    )
}

const HEAD: &str = "OpenShadingLanguage 1.00\nshader T\n";

// ---------------------------------------------------------------------------------------
// Public fixtures
// ---------------------------------------------------------------------------------------

#[test]
fn openusd_properties_fixture_loads_with_the_vstruct_member() {
    let dir = fixtures_or_skip!();
    let path = dir.join("oso/openusd/TestShaderPropertiesNodeOSL.oso");
    let bytes = std::fs::read(&path).expect("fixture readable");
    let mut diags = Diagnostics::new();
    let def = parse_oso(&bytes, "TestShaderPropertiesNodeOSL.oso", &mut diags).expect("loads");
    assert!(diags.is_empty(), "{diags:?}");
    assert_eq!(def.id, "TestShaderPropertiesNodeOSL");
    assert_eq!(def.kind, "pattern");
    assert_eq!(def.inputs.len(), 32);
    assert_eq!(def.outputs.len(), 1);
    assert_eq!(
        def.metadata.iter().collect::<Vec<_>>(),
        vec![(
            "help",
            "This node is used for testing shader property typecorrectness"
        )]
    );

    let member = def.input("inputVstruct_parameter").expect("member input");
    let decl = member.vstruct.as_ref().expect("member declaration");
    assert_eq!(decl.head, "inputVstruct");
    assert_eq!(decl.member, "parameter");
    assert_eq!(decl.alias, None);
    assert_eq!(decl.cond, None);
    assert_eq!(member.meta("vstructmember"), Some("inputVstruct.parameter"));
    assert!(def.input("inputVstruct").expect("head").vstruct.is_none());

    // The struct parameter is kept without default; its field is skipped.
    let st = def.input("inputStruct").expect("struct");
    assert_eq!(st.ty.base, BaseType::Struct(Some("TestStruct".into())));
    assert_eq!(st.declared_type, "struct TestStruct");
    assert_eq!(st.default, None);
    assert!(def.input("inputStruct.foo").is_none());

    // `%initexpr` parameters have no default even though initvals are written.
    for name in [
        "inputPointRoleNone",
        "inputNormalRoleNone",
        "inputVectorRoleNone",
    ] {
        assert_eq!(def.input(name).expect(name).default, None, "{name}");
    }
    assert_eq!(
        def.input("inputColorRoleNone").unwrap().default,
        Some(Value::Triple(BaseType::Color, [1.0, 2.0, 3.0]))
    );

    // Typed defaults of every shape.
    assert_eq!(def.input("inputInt").unwrap().default, Some(Value::Int(1)));
    assert_eq!(
        def.input("inputString").unwrap().default,
        Some(Value::Str("foo".into()))
    );
    assert_eq!(
        def.input("inputNormal").unwrap().default,
        Some(Value::Triple(BaseType::Normal, [1.0; 3]))
    );
    assert_eq!(
        def.input("inputMatrix").unwrap().default,
        Some(Value::Matrix([0.0; 16]))
    );
    let m2 = def.input("inputMatrixArray").unwrap();
    assert_eq!(
        m2.ty,
        Type {
            base: BaseType::Matrix,
            array: ArraySpec::Fixed(2)
        }
    );
    let mut identity = [0.0; 16];
    for i in 0..4 {
        identity[i * 5] = 1.0;
    }
    assert_eq!(
        m2.default,
        Some(Value::Array(
            BaseType::Matrix,
            vec![Value::Matrix([0.0; 16]), Value::Matrix(identity)]
        ))
    );
    assert_eq!(
        def.input("inputColorArray").unwrap().default,
        Some(Value::Array(
            BaseType::Color,
            vec![Value::Triple(BaseType::Color, [1.0; 3]); 2]
        ))
    );
    assert_eq!(
        def.input("inputFloat2").unwrap().default,
        Some(floats(&[1.0, 2.0]))
    );
    assert_eq!(def.input("inputFloat2").unwrap().declared_type, "float[2]");
    assert_eq!(
        def.input("inputStringArray").unwrap().default,
        Some(Value::Array(
            BaseType::String,
            ["foo", "bar", "baz", "moo"]
                .iter()
                .map(|s| Value::Str(s.to_string()))
                .collect()
        ))
    );

    let out = def.output("outputSurface").expect("output");
    assert_eq!(out.direction, Direction::Out);
    assert_eq!(out.meta("renderType"), Some("terminal surface"));
    // Declaration order and line positions (the first param is on line 5).
    assert_eq!(def.inputs[0].name, "inputInt");
    assert_eq!(
        (def.inputs[0].location.line, def.inputs[0].location.column),
        (5, 1)
    );
}

#[test]
fn openusd_test_node_fixture_loads_with_typed_fields() {
    let dir = fixtures_or_skip!();
    let bytes = std::fs::read(dir.join("oso/openusd/TestNodeOSL.oso")).expect("fixture readable");
    let mut diags = Diagnostics::new();
    let def = parse_oso(&bytes, "TestNodeOSL.oso", &mut diags).expect("loads");
    assert!(diags.is_empty(), "{diags:?}");
    assert_eq!(def.id, "TestNodeOSL");
    assert_eq!(def.kind, "pattern");
    assert_eq!(def.inputs.len(), 17);
    assert_eq!(def.outputs.len(), 8);
    let keys: Vec<&str> = def.metadata.iter().map(|(k, _)| k).collect();
    assert_eq!(
        keys,
        [
            "category",
            "departments",
            "help",
            "label",
            "primvars",
            "uncategorizedMetadata"
        ]
    );

    let a = def.input("inputA").unwrap();
    assert_eq!(a.widget.as_deref(), Some("number"));
    assert_eq!(a.label.as_deref(), Some("inputA label"));
    assert_eq!(a.page.as_deref(), Some("inputs1"));
    assert_eq!(a.help.as_deref(), Some("inputA help message"));
    assert!(a.connectable);
    assert_eq!(a.meta("uncategorized"), Some("1"));
    assert!(
        a.typed_metadata
            .contains(&("uncategorized".to_string(), Value::Int(1)))
    );

    assert!(!def.input("inputF2").unwrap().connectable);
    assert_eq!(def.input("inputD").unwrap().ty.array, ArraySpec::Fixed(1));
    assert_eq!(def.input("inputD").unwrap().meta("arraySize"), Some("-1"));
    assert_eq!(
        def.input("inputOptions").unwrap().options,
        vec![
            ("opt1".to_string(), "opt1val".to_string()),
            ("opt2".to_string(), "opt2val".to_string())
        ]
    );
    assert_eq!(def.input("inputInterp").unwrap().options.len(), 4);
    assert_eq!(
        def.output("resultF2").unwrap().default,
        Some(floats(&[1.0, 2.0]))
    );
    assert!(def.outputs.iter().all(|o| o.connectable));
}

// ---------------------------------------------------------------------------------------
// Test vectors (formats.md §4.3), in tests/data/oso/vectors.oso
// ---------------------------------------------------------------------------------------

fn vectors() -> (Definition, Diagnostics) {
    let path = common::repo_dir().join("tests/data/oso/vectors.oso");
    let bytes = std::fs::read(&path).expect("tests/data/oso/vectors.oso");
    let mut diags = Diagnostics::new();
    let def = parse_oso(&bytes, "vectors.oso", &mut diags).expect("vectors load");
    (def, diags)
}

#[test]
fn vectors_load_without_diagnostics_and_stop_at_local() {
    let (def, diags) = vectors();
    assert!(diags.is_empty(), "{diags:?}");
    assert_eq!(def.id, "VectorsNode");
    let names: Vec<&str> = def
        .properties_in_order()
        .iter()
        .map(|p| p.name.as_str())
        .collect();
    assert_eq!(
        names,
        [
            "metaBraces",
            "escaped",
            "continued",
            "st",
            "computed",
            "ranged",
            "dyn",
            "layer_diffuseGain",
            "out_diffuseGain",
            "out",
            "Ci"
        ]
    );
    assert!(def.input("notAProperty").is_none());
    assert_eq!(
        def.metadata.entry(0),
        Some(("help", "node help, with {braces}"))
    );
}

#[test]
fn vector_meta_string_with_brace_and_comma() {
    let (def, _) = vectors();
    let p = def.input("metaBraces").unwrap();
    assert_eq!(p.help.as_deref(), Some("a}b,c{d"));
    assert_eq!(
        p.label.as_deref(),
        Some("Braces"),
        "the hint after it is still read"
    );
}

#[test]
fn vector_escaped_quote_after_escaped_backslash() {
    let (def, _) = vectors();
    let p = def.input("escaped").unwrap();
    assert_eq!(p.help.as_deref(), Some(r#"a\"b"#));
    assert_eq!(p.default, Some(Value::Str(r#"a\"b"#.to_string())));
}

#[test]
fn vector_continued_line() {
    let (def, _) = vectors();
    let p = def.input("continued").unwrap();
    assert_eq!(
        p.default,
        Some(Value::Triple(BaseType::Color, [0.25, 0.5, 1.0]))
    );
    assert_eq!(
        p.page.as_deref(),
        Some("Basic:Advanced"),
        "OSL page `.` becomes `:`"
    );
    assert_eq!(
        p.meta("page"),
        Some("Basic.Advanced"),
        "metadata stays verbatim"
    );
    assert_eq!(p.location.line, 10);
    // Lines after the continuation keep their physical numbers.
    assert_eq!(def.input("st").unwrap().location.line, 13);
}

#[test]
fn vector_struct_parameter_with_fields() {
    let (def, _) = vectors();
    let st = def.input("st").unwrap();
    assert_eq!(st.ty, Type::scalar(BaseType::Struct(Some("S".into()))));
    assert_eq!(st.default, None);
    assert!(def.inputs.iter().all(|p| !p.name.contains('.')));
}

#[test]
fn vector_initexpr_parameter_has_no_default() {
    let (def, _) = vectors();
    assert_eq!(def.input("computed").unwrap().default, None);
}

#[test]
fn vector_float2_and_string2_meta() {
    let (def, _) = vectors();
    let p = def.input("ranged").unwrap();
    assert_eq!(p.meta("minmax"), Some("42,44"));
    assert_eq!(p.meta("s"), Some("foo,bar"));
    assert!(
        p.typed_metadata
            .contains(&("minmax".to_string(), floats(&[42.0, 44.0])))
    );
    assert!(p.typed_metadata.contains(&(
        "s".to_string(),
        Value::Array(
            BaseType::String,
            vec![Value::Str("foo".into()), Value::Str("bar".into())]
        )
    )));
    assert!(!p.connectable);
    assert_eq!(def.input("dyn").unwrap().ty.array, ArraySpec::Dynamic);
    assert_eq!(def.input("dyn").unwrap().declared_type, "float[]");
    assert_eq!(
        def.input("dyn").unwrap().default,
        Some(floats(&[1.0, 2.0, 3.0]))
    );
}

#[test]
fn vector_oparam_member_with_conditional() {
    let (def, _) = vectors();
    let out = def.output("out_diffuseGain").unwrap();
    let decl = out.vstruct.as_ref().expect("member");
    assert_eq!(
        (decl.head.as_str(), decl.member.as_str()),
        ("out", "diffuseGain")
    );
    let cond = decl.cond.as_ref().expect("conditional");
    assert_eq!(cond.text, r#"connect if s == "a" and enableDiffuse == 1"#);
    assert_eq!(&*cond.location.file, "vectors.oso");
    // The conditional's location is its `%meta` hint: line 23, after
    // "oparam\tfloat\tout_diffuseGain\t0\t\t" (32 characters) and the 45-character first hint
    // plus one space.
    assert_eq!((cond.location.line, cond.location.column), (23, 79));

    let input_member = def
        .input("layer_diffuseGain")
        .unwrap()
        .vstruct
        .as_ref()
        .unwrap();
    assert_eq!(
        (input_member.head.as_str(), input_member.member.as_str()),
        ("layer", "diffuseGain")
    );

    let head = def.output("out").unwrap();
    assert!(head.has_tag("vstruct"));
    assert_eq!(head.meta("tag"), Some("vstruct"));
    let ci = def.output("Ci").unwrap();
    assert_eq!(ci.ty.base, BaseType::Closure);
    assert_eq!(ci.declared_type, "closure color");
    assert_eq!(ci.default, None);
}

// ---------------------------------------------------------------------------------------
// Mapping rules on small inputs
// ---------------------------------------------------------------------------------------

#[test]
fn shader_keywords_map_to_kinds() {
    for (word, kind) in [
        ("shader", "pattern"),
        ("surface", "surface"),
        ("displacement", "displacement"),
    ] {
        let (def, _) = load(&format!("OpenShadingLanguage 1.00\n{word} N\n"));
        assert_eq!(def.kind, kind);
        assert_eq!(def.id, "N");
    }
}

#[test]
fn comments_blank_lines_and_crlf_are_accepted() {
    let text = "# leading comment\r\n\r\nOpenShadingLanguage 1.00\r\n# c\r\nshader T # trailing\r\n\r\nparam float x 0.5 # a comment\r\nparam int y 2\r\n";
    let (def, diags) = load(text);
    assert!(diags.is_empty(), "{diags:?}");
    assert_eq!(def.input("x").unwrap().default, Some(Value::Float(0.5)));
    assert_eq!(def.input("y").unwrap().default, Some(Value::Int(2)));
    assert_eq!(def.input("y").unwrap().location.line, 8);
}

#[test]
fn preprocessed_source_stops_reading() {
    let text = format!("{HEAD}param float a 1 %preprocessed_source\nthis is \"not oso at all\n");
    let (def, diags) = load(&text);
    assert!(diags.is_empty());
    assert_eq!(def.input("a").unwrap().default, Some(Value::Float(1.0)));
    assert_eq!(def.inputs.len(), 1);
}

#[test]
fn property_section_ends_at_code_and_const() {
    for stop in [
        "code ___main___",
        "const float $c 1",
        "temp int $t 0",
        "global point P",
    ] {
        let text = format!("{HEAD}param float a 1\n{stop}\nparam float b 0\n\"unterminated\n");
        let (def, _) = load(&text);
        assert_eq!(def.inputs.len(), 1, "{stop}");
    }
}

#[test]
fn count_mismatch_is_os010_without_default() {
    let (def, diags) = load(&format!(
        "{HEAD}param color c 1 1\nparam float[2] f 1 2 3\nparam float g\n"
    ));
    assert_eq!(diags.count("OS010"), 3, "{diags:?}");
    let d = diags.with_code("OS010").next().unwrap();
    assert_eq!(d.severity, Severity::Warning);
    let loc = d.location.as_ref().unwrap();
    assert_eq!(
        (loc.line, loc.column),
        (3, 15),
        "position of the first value"
    );
    assert!(def.inputs.iter().all(|p| p.default.is_none()));
}

#[test]
fn default_of_wrong_kind_is_os010() {
    let (def, diags) = load(&format!("{HEAD}param int i 1.5\nparam float f \"x\"\n"));
    assert_eq!(diags.count("OS010"), 2, "{diags:?}");
    assert!(def.inputs.iter().all(|p| p.default.is_none()));
}

#[test]
fn unknown_meta_type_is_os011() {
    let (def, diags) = load(&format!(
        "{HEAD}param float f 0 %meta{{color,c,1}} %meta{{string,label,\"ok\"}}\n"
    ));
    assert_eq!(diags.count("OS011"), 1);
    let d = diags.with_code("OS011").next().unwrap();
    assert_eq!(d.severity, Severity::Warning);
    let loc = d.location.as_ref().unwrap();
    assert_eq!((loc.line, loc.column), (3, 17));
    let f = def.input("f").unwrap();
    assert_eq!(f.meta("c"), None);
    assert_eq!(f.label.as_deref(), Some("ok"));
}

#[test]
fn vstruct_key_with_non_string_type_is_os012() {
    let text = format!(
        "{HEAD}param float m 0 %meta{{int,vstructmember,1}}\n\
         param float n 0 %meta{{string[1],vstructmember,\"h.n\"}}\n"
    );
    let (def, diags) = load(&text);
    assert_eq!(diags.count("OS012"), 2, "{diags:?}");
    assert!(
        def.inputs
            .iter()
            .all(|p| p.vstruct.is_none() && p.meta("vstructmember").is_none())
    );
}

#[test]
fn newer_version_is_os013_info() {
    let (_, diags) = load("OpenShadingLanguage 1.10\nshader T\n");
    assert_eq!(diags.count("OS013"), 1);
    let d = diags.with_code("OS013").next().unwrap();
    assert_eq!(d.severity, Severity::Info);
    assert_eq!(
        d.location.as_ref().map(|l| (l.line, l.column)),
        Some((1, 21))
    );
    let (_, diags) = load("OpenShadingLanguage 1.00\nshader T\n");
    assert!(diags.is_empty());
}

#[test]
fn member_split_rules() {
    let text = format!(
        "{HEAD}param float a 0 %meta{{string,vstructmember,\"h.m.x\"}} %meta{{string,vstructmemberaliases,\"alt\"}} %meta{{string,vstructConditionalExpr,\"\"}}\n\
         param float b 0 %meta{{string,vstructmember,\"nodot\"}}\n\
         param float c 0 %meta{{string,vstructmember,\".x\"}}\n\
         param float d 0 %meta{{string,vstructmember,\"x.\"}}\n"
    );
    let (def, _) = load(&text);
    let a = def.input("a").unwrap().vstruct.as_ref().unwrap();
    assert_eq!((a.head.as_str(), a.member.as_str()), ("h", "m.x"));
    assert_eq!(a.alias.as_deref(), Some("alt"));
    assert_eq!(a.cond, None, "an empty conditional is no conditional");
    for name in ["b", "c", "d"] {
        let p = def.input(name).unwrap();
        assert!(p.vstruct.is_none(), "{name}");
        assert!(
            p.meta("vstructmember").is_some(),
            "{name}: raw value kept for VS003"
        );
    }
}

#[test]
fn octal_and_other_escapes_decode() {
    let (def, _) = load(&format!(
        "{HEAD}param string s \"\\101\\tz\\n\" %meta{{string,help,\"q\\\\\"}}\n"
    ));
    let s = def.input("s").unwrap();
    assert_eq!(s.default, Some(Value::Str("A\tz\n".into())));
    assert_eq!(s.help.as_deref(), Some("q\\"));
}

// ---------------------------------------------------------------------------------------
// Errors (formats.md §4.3): code and line:column
// ---------------------------------------------------------------------------------------

#[test]
fn bad_header_is_os001() {
    assert_eq!(
        reject("OpenShadingLanguag 1.00\nshader T\n"),
        ("OS001", 1, 1)
    );
    assert_eq!(reject("# only a comment\n\n  shader T\n"), ("OS001", 3, 3));
    assert_eq!(reject("OpenShadingLanguage\nshader T\n"), ("OS001", 1, 1));
    assert_eq!(reject("OpenShadingLanguage x\n"), ("OS001", 1, 21));
    assert_eq!(reject(""), ("OS001", 1, 1));
}

#[test]
fn missing_or_bad_shader_line_is_os001() {
    assert_eq!(reject("OpenShadingLanguage 1.00\n# c\n"), ("OS001", 3, 1));
    assert_eq!(
        reject("OpenShadingLanguage 1.00\nparam float x 0\n"),
        ("OS001", 2, 1)
    );
    assert_eq!(
        reject("OpenShadingLanguage 1.00\nshader\n"),
        ("OS001", 2, 1)
    );
    assert_eq!(
        reject("OpenShadingLanguage 1.00\nshader T 1\n"),
        ("OS001", 2, 10)
    );
}

#[test]
fn malformed_symbol_line_is_os002() {
    assert_eq!(reject(&format!("{HEAD}param floot x 0\n")), ("OS002", 3, 7));
    assert_eq!(reject(&format!("{HEAD}param float\n")), ("OS002", 3, 7));
    assert_eq!(
        reject(&format!("{HEAD}param float x 0 %read{{1,2}} 1\n")),
        ("OS002", 3, 28)
    );
    assert_eq!(
        reject(&format!("{HEAD}param float[0] x 0\n")),
        ("OS002", 3, 13)
    );
    assert_eq!(
        reject(&format!("{HEAD}param float[2 x 0\n")),
        ("OS002", 3, 15)
    );
    assert_eq!(reject(&format!("{HEAD}parm float x 0\n")), ("OS002", 3, 1));
    assert_eq!(
        reject(&format!("{HEAD}param float x 0 @\n")),
        ("OS002", 3, 17)
    );
    assert_eq!(
        reject(&format!("{HEAD}param float x 1x\n")),
        ("OS002", 3, 15)
    );
    assert_eq!(
        reject(&format!("{HEAD}param float x 0 %meta{{string,a \"b\"}}\n")),
        ("OS002", 3, 32)
    );
}

#[test]
fn unterminated_string_or_hint_is_os003() {
    assert_eq!(
        reject(&format!("{HEAD}param string s \"abc\nparam float y 0\n")),
        ("OS003", 3, 16)
    );
    assert_eq!(
        reject(&format!("{HEAD}param string s \"abc\\\n\"\n")),
        ("OS003", 3, 16)
    );
    assert_eq!(
        reject(&format!("{HEAD}param float x 0 %meta{{string,a,\"b\"\n")),
        ("OS003", 3, 17)
    );
    assert_eq!(
        reject(&format!("{HEAD}param float x 0 %meta{{string,a,\"b}}\n")),
        ("OS003", 3, 32)
    );
    assert_eq!(
        reject("OpenShadingLanguage 1.00\nshader T %meta{string,help,\"x\n"),
        ("OS003", 2, 28)
    );
}

#[test]
fn duplicate_property_is_os004() {
    let text = format!("{HEAD}param float x 0\noparam  float  x 1\n");
    let (result, _) = parse(&text);
    let err = result.unwrap_err();
    let d = err.diagnostic().unwrap();
    assert_eq!(d.code, "OS004");
    let loc = d.location.as_ref().unwrap();
    assert_eq!((loc.line, loc.column), (4, 16));
    assert_eq!(d.related.len(), 1);
    assert_eq!((d.related[0].1.line, d.related[0].1.column), (3, 13));
    // Struct fields count too: a repeated field name is a duplicate.
    assert_eq!(
        reject(&format!(
            "{HEAD}param struct S s\nparam float s.a 0\nparam float s.a 0\n"
        )),
        ("OS004", 5, 13)
    );
}

#[test]
fn a_very_long_line_is_read_quickly() {
    // 20 000 hints on one line: column bookkeeping must not rescan the line per token.
    let hints = "%read{2147483647,-1} ".repeat(20_000);
    let text = format!("{HEAD}param float f 0 {hints}%meta{{string,label,\"end\"}}\n");
    let start = std::time::Instant::now();
    let (def, _) = load(&text);
    assert_eq!(def.input("f").unwrap().label.as_deref(), Some("end"));
    assert!(
        start.elapsed().as_secs_f64() < 2.0,
        "took {:?}",
        start.elapsed()
    );
}

#[test]
fn a_byte_order_mark_is_skipped() {
    let (def, diags) = load("\u{feff}OpenShadingLanguage 1.00\nshader T\n");
    assert!(diags.is_empty());
    assert_eq!(def.id, "T");
}

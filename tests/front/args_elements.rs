//! `.args` element and attribute rules (formats.md §2.1–§2.6) on small inline documents.

use vstructc::front::args::{ArgsOptions, parse_args, parse_args_with};
use vstructc::registry::Definition;
use vstructc::types::{ArraySpec, BaseType, Value};
use vstructc::{Diagnostics, Severity};

fn parse(text: &str) -> (Definition, Diagnostics) {
    let mut diags = Diagnostics::new();
    let def =
        parse_args(text.as_bytes(), "t.args", "T", &mut diags).unwrap_or_else(|e| panic!("{e}"));
    (def, diags)
}

fn wrap(body: &str) -> String {
    format!(
        "<args format=\"1.0\">\n<shaderType><tag value=\"pattern\"/></shaderType>\n{body}\n</args>\n"
    )
}

fn one(diags: &Diagnostics, code: &str) -> (Severity, u32, u32) {
    let found: Vec<_> = diags.with_code(code).collect();
    assert_eq!(found.len(), 1, "{code}: {diags:?}");
    let l = found[0].location.as_ref().unwrap();
    (found[0].severity, l.line, l.column)
}

#[test]
fn shader_kinds() {
    let (def, d) = parse(r#"<args format="1.0"><shaderType name="lightfilter"/></args>"#);
    assert_eq!(def.kind, "lightFilter");
    assert!(d.is_empty(), "{d:?}");
    let (def, d) =
        parse(r#"<args format="1.0"><shaderType><tag value="samplefilter"/></shaderType></args>"#);
    assert_eq!(def.kind, "sampleFilter");
    assert!(d.is_empty());
    let (def, d) = parse(r#"<args format="1.0"><shaderType name="pixelfilter"/></args>"#);
    assert_eq!(def.kind, "pixelFilter");
    assert_eq!(one(&d, "AR010").0, Severity::Info);
    let (def, d) = parse(r#"<args format="1.0"><shaderType name="gizmo"/></args>"#);
    assert_eq!(def.kind, "gizmo");
    assert_eq!(one(&d, "AR010"), (Severity::Info, 1, 38));
    let (def, d) =
        parse("<args format=\"1.0\">\n  <typeTag><tag value=\"bxdf\"/></typeTag></args>");
    assert_eq!(def.kind, "bxdf");
    assert_eq!(one(&d, "AR020"), (Severity::Info, 2, 3));
}

#[test]
fn format_attribute_other_than_1_0_is_ar014() {
    let (_, d) = parse(r#"<args format="2.0"><shaderType name="bxdf"/></args>"#);
    assert_eq!(one(&d, "AR014"), (Severity::Warning, 1, 15));
}

#[test]
fn declaration_bom_comments_single_quotes_and_spaced_equals() {
    let text = "\u{feff}<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<!-- c -->\n<args format = '1.0'>\n<!-- inside -->\n<shaderType name = 'bxdf'/>\n<param name = 'g' type = \"float\" default = '0.5'>\n<hintdict name=\"options\"><!-- x --><string name=\"Half\" value=\"0.5\"/></hintdict>\n</param>\n</args>\n<!-- after -->\n  ";
    let (def, d) = parse(text);
    assert!(d.is_empty(), "{d:?}");
    let g = def.input("g").unwrap();
    assert_eq!(g.default, Some(Value::Float(0.5)));
    assert_eq!(g.options, [("Half".to_string(), "0.5".to_string())]);
    // The BOM is not counted: `<param` is at 6:1.
    assert_eq!((g.location.line, g.location.column), (6, 1));
}

#[test]
fn node_level_elements() {
    let text = wrap(
        r#"<help>Top <b>level</b> help.</help>
<primvars><primvar name="st"/></primvars>
<rfmdata nodeid="1" classification="x"/>
<mystery a="1"><inner/></mystery>
<param name="a" type="float"/>"#,
    );
    let (def, d) = parse(&text);
    let keys: Vec<&str> = def.metadata.iter().map(|(k, _)| k).collect();
    assert_eq!(keys, ["help", "primvars", "rfmdata"]);
    assert_eq!(def.metadata.entry(0).unwrap().1, "Top <b>level</b> help.");
    assert_eq!(
        def.metadata.entry(1).unwrap().1,
        r#"<primvars><primvar name="st"/></primvars>"#
    );
    assert_eq!(one(&d, "AR021"), (Severity::Info, 6, 1));
    assert!(
        def.input("a").is_some(),
        "parsing goes on after an unknown element"
    );
}

#[test]
fn sdr_global_config_after_sdr_definition_name_is_ar015() {
    let text = wrap(
        r#"<param name="a" type="float" sdrDefinitionName="b"/>
<sdrGlobalConfig><x/></sdrGlobalConfig>
<param name="c" type="float"/>"#,
    );
    let (def, d) = parse(&text);
    assert_eq!(one(&d, "AR015"), (Severity::Warning, 4, 1));
    assert!(!def.metadata.iter().any(|(k, _)| k == "sdrGlobalConfig"));
    assert!(def.input("c").is_some());
    // The property keeps its args name (sdrDefinitionName is only metadata).
    assert_eq!(def.input("a").unwrap().meta("sdrDefinitionName"), Some("b"));
}

#[test]
fn deprecated_forms_are_ar020() {
    let text = wrap(
        r#"<param name="a" type="float" tag="float" input="True"/>
<output name="o" type="color"><tags><tag value="float"/></tags></output>"#,
    );
    let (def, d) = parse(&text);
    assert_eq!(d.count("AR020"), 3, "{d:?}");
    let a = def.input("a").unwrap();
    assert_eq!(a.connection_types, ["float"]);
    // `type` on an output wins over its tag.
    assert_eq!(def.output("o").unwrap().ty.base, BaseType::Color);
}

#[test]
fn types_from_tags_structs_terminals_and_unknowns() {
    let text = wrap(
        r#"<output name="m"><tags><tag value="struct manifold"/></tags></output>
<output name="b"><tags><tag value="bxdf"/></tags></output>
<output name="none"/>
<param name="f2" type="float2" default="1 2"/>
<param name="lf" type="lightfilter"/>
<param name="t" type="string" renderType="terminal lightfilter"/>
<param name="t2" type="bxdf" renderType="terminal"/>
<param name="s" type="struct" default="1"/>"#,
    );
    let (def, d) = parse(&text);
    assert_eq!(
        def.output("m").unwrap().ty.base,
        BaseType::Struct(Some("manifold".into()))
    );
    assert_eq!(
        def.output("b").unwrap().ty.base,
        BaseType::Terminal("bxdf".into())
    );
    let none = def.output("none").unwrap();
    assert_eq!(none.ty.base, BaseType::Unknown(String::new()));
    assert_eq!(one(&d, "AR011"), (Severity::Warning, 5, 1));
    let f2 = def.input("f2").unwrap();
    assert_eq!(f2.ty.array, ArraySpec::Fixed(2));
    assert_eq!(f2.default.as_ref().unwrap().numbers(), [1.0, 2.0]);
    assert_eq!(
        def.input("lf").unwrap().ty.base,
        BaseType::Terminal("lightfilter".into())
    );
    let t = def.input("t").unwrap();
    assert_eq!(t.ty.base, BaseType::Terminal("lightfilter".into()));
    assert_eq!(t.default, None, "terminals have no default");
    assert_eq!(
        def.input("t2").unwrap().ty.base,
        BaseType::Terminal("bxdf".into())
    );
    assert_eq!(def.input("s").unwrap().default, None);
}

#[test]
fn arrays_and_booleans() {
    let text = wrap(
        r#"<param name="fixed" type="float" arraySize="3" default="1 2 3"/>
<param name="dyn" type="color" arraySize="-1" default="1 1 1 0 0 0"/>
<param name="dyn2" type="int" isDynamicArray="1" default=""/>
<param name="dynEmptyFlag" type="int" isDynamicArray=""/>
<param name="notDyn" type="int" isDynamicArray="False"/>
<param name="c0" type="int" connectable="f"/>
<param name="c1" type="int" connectable="yes"/>"#,
    );
    let (def, d) = parse(&text);
    assert!(d.is_empty(), "{d:?}");
    let fixed = def.input("fixed").unwrap();
    assert_eq!(fixed.ty.array, ArraySpec::Fixed(3));
    assert_eq!(fixed.default.as_ref().unwrap().numbers(), [1.0, 2.0, 3.0]);
    let dynamic = def.input("dyn").unwrap();
    assert_eq!(dynamic.ty.array, ArraySpec::Dynamic);
    match dynamic.default.as_ref().unwrap() {
        Value::Array(BaseType::Color, items) => assert_eq!(items.len(), 2),
        other => panic!("{other:?}"),
    }
    assert_eq!(def.input("dyn2").unwrap().ty.array, ArraySpec::Dynamic);
    assert_eq!(
        def.input("dyn2").unwrap().default,
        Some(Value::Array(BaseType::Int, vec![]))
    );
    assert_eq!(
        def.input("dynEmptyFlag").unwrap().ty.array,
        ArraySpec::Dynamic
    );
    assert_eq!(def.input("notDyn").unwrap().ty.array, ArraySpec::None);
    assert!(!def.input("c0").unwrap().connectable);
    assert!(def.input("c1").unwrap().connectable);
}

#[test]
fn trailing_f_is_an_info_and_bad_numbers_warn() {
    let text = wrap(
        "<param name=\"a\" type=\"float\" default=\"0.5f\"/>\n<param name=\"b\" type=\"int\" default=\"2.5\"/>",
    );
    let (def, d) = parse(&text);
    assert_eq!(def.input("a").unwrap().default, Some(Value::Float(0.5)));
    assert_eq!(def.input("b").unwrap().default, Some(Value::Int(2)));
    let sev: Vec<_> = d.with_code("AR012").map(|x| x.severity).collect();
    assert_eq!(sev, [Severity::Info, Severity::Warning]);
    assert!(
        d.with_code("AR012")
            .nth(1)
            .unwrap()
            .message
            .contains("2 is used")
    );
}

#[test]
fn options_help_label_widget_and_pages() {
    let text = wrap(
        r#"<page name="Outer"><page name="Inner">
<param name="mode" type="int" widget="mapper" label="Mode" options="Off:0|On:1" help="attr help">
  <help>child <i>help</i></help>
  <hintlist name="options"><string value="extra"/></hintlist>
  <hintdict name="conditionalVisOps"><string name="conditionalVisOp" value="equalTo"/></hintdict>
</param>
</page></page>
<param name="free" type="float" page="Attr Page" help="only attr"/>"#,
    );
    let (def, d) = parse(&text);
    assert!(d.is_empty(), "{d:?}");
    let m = def.input("mode").unwrap();
    assert_eq!(m.page.as_deref(), Some("Outer:Inner"));
    assert_eq!(m.label.as_deref(), Some("Mode"));
    assert_eq!(m.widget.as_deref(), Some("mapper"));
    assert_eq!(m.help.as_deref(), Some("child <i>help</i>"));
    let opts: Vec<(&str, &str)> = m
        .options
        .iter()
        .map(|(a, b)| (a.as_str(), b.as_str()))
        .collect();
    assert_eq!(opts, [("Off", "0"), ("On", "1"), ("extra", "extra")]);
    // Attributes first, in document order, then raw hints that are not options.
    let keys: Vec<&str> = m.metadata.iter().map(|(k, _)| k).collect();
    assert_eq!(
        keys,
        [
            "name",
            "type",
            "widget",
            "label",
            "options",
            "help",
            "hintdict:conditionalVisOps"
        ]
    );
    let free = def.input("free").unwrap();
    assert_eq!(free.page.as_deref(), Some("Attr Page"));
    assert_eq!(free.help.as_deref(), Some("only attr"));
}

#[test]
fn vstruct_attributes_and_positions() {
    let text = wrap(
        "<output name=\"o\" vstructmember=\"h.m\"\n  vstructConditionalExpr=\"connect if a &amp;&amp; b\" vstructmemberaliases=\"\"/>\n<param name=\"p\" type=\"float\" vstructConditionalExpr=\"connect if x == 1\"/>\n<param name=\"q\" type=\"float\" vstructmember=\"nodot\" vstructConditionalExpr=\"\"/>",
    );
    let (def, d) = parse(&text);
    let o = def.output("o").unwrap();
    let m = o.vstruct.as_ref().unwrap();
    assert_eq!((m.head.as_str(), m.member.as_str()), ("h", "m"));
    assert_eq!(m.alias, None, "an empty alias is no alias");
    let c = m.cond.as_ref().unwrap();
    assert_eq!(c.text, "connect if a && b", "entities are decoded");
    assert_eq!((c.location.line, c.location.column), (4, 27));
    // A conditional on a non-member: AR022; an empty one on a malformed member: nothing.
    assert_eq!(one(&d, "AR022"), (Severity::Info, 5, 54));
    assert!(def.input("q").unwrap().vstruct.is_none());
    assert_eq!(def.input("q").unwrap().meta("vstructmember"), Some("nodot"));
}

#[test]
fn child_metadata_needs_the_extension() {
    let text = wrap(
        r#"<param name="a" type="float">
  <string name="vstructmember" value="h.a"/>
</param>
<param name="b" type="float" vstructmember="h.b">
  <string name="vstructmember" value="h.other"/>
</param>"#,
    );
    let (def, d) = parse(&text);
    assert!(def.input("a").unwrap().vstruct.is_none());
    assert_eq!(d.count("AR021"), 2, "{d:?}");

    let mut d = Diagnostics::new();
    let opts = ArgsOptions { child_meta: true };
    let def = parse_args_with(text.as_bytes(), "t.args", "T", &opts, &mut d).unwrap();
    assert_eq!(
        def.input("a").unwrap().vstruct.as_ref().unwrap().member,
        "a"
    );
    assert_eq!(def.input("a").unwrap().meta("vstructmember"), Some("h.a"));
    assert_eq!(
        def.input("b").unwrap().vstruct.as_ref().unwrap().member,
        "b",
        "attribute wins"
    );
    assert_eq!(one(&d, "AR023"), (Severity::Warning, 7, 39));
}

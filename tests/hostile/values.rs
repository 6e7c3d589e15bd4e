//! Every output reads back: no writer emits a value its own reader rejects. A `set` or
//! `copy` that would store an infinity is a VS023 warning and writes the largest finite float
//! of its sign; a float default beyond the `f32` range is saturated where it is read (AR012);
//! the writers saturate what a network built in code holds. The property test runs any
//! network the RIB reader accepts through resolve, both writers and both readers.

use crate::{run, scratch};
use proptest::prelude::*;
use std::path::{Path, PathBuf};
use vstructc::back::json::write_json;
use vstructc::back::rib::write_rib_to_vec;
use vstructc::cond::Extensions;
use vstructc::front::json::parse_json;
use vstructc::front::rib::{RibOptions, parse_rib};
use vstructc::network::{Network, NoDefinitions};
use vstructc::registry::{Registry, RegistryOptions};
use vstructc::resolve::{ResolveOptions, resolve};
use vstructc::{BaseType, Diagnostics, Value};

/// Upstream type: float inputs with huge defaults and an output head whose members `set`
/// and `copy` values beyond the f32 range.
const UP: &str = r#"<args format="1.0">
  <shaderType><tag value="pattern"/></shaderType>
  <param name="g" type="float" default="1e400"/>
  <param name="n" type="float" default="-1e39"/>
  <param name="tiny" type="float" default="1e-60"/>
  <param name="c" type="color" default="1e39 -1e39 0.5"/>
  <param name="i" type="int" default="3"/>
  <output name="out"><tags><tag value="vstruct"/></tags></output>
  <output name="out_big" vstructmember="out.big" vstructConditionalExpr="set 1e39"><tags><tag value="float"/></tags></output>
  <output name="out_neg" vstructmember="out.neg" vstructConditionalExpr="set -1e39"><tags><tag value="float"/></tags></output>
  <output name="out_huge" vstructmember="out.huge" vstructConditionalExpr="set 1e400 if i == 3 else set 1"><tags><tag value="float"/></tags></output>
  <output name="out_copy" vstructmember="out.copy" vstructConditionalExpr="copy g"><tags><tag value="float"/></tags></output>
  <output name="out_copyn" vstructmember="out.copyn" vstructConditionalExpr="copy n"><tags><tag value="float"/></tags></output>
  <output name="out_copyc" vstructmember="out.copyc" vstructConditionalExpr="copy c"><tags><tag value="color"/></tags></output>
  <output name="out_tuple" vstructmember="out.tuple" vstructConditionalExpr="set -1e39"><tags><tag value="color"/></tags></output>
  <output name="out_conv" vstructmember="out.conv" vstructConditionalExpr="copy g"><tags><tag value="int"/></tags></output>
  <output name="out_plain" vstructmember="out.plain"><tags><tag value="float"/></tags></output>
</args>"#;

/// Downstream type: one member per upstream member.
const DOWN: &str = r#"<args format="1.0"><shaderType><tag value="bxdf"/></shaderType>
  <param name="inputMaterial" type="float" readOnly="true"><tags><tag value="vstruct"/></tags></param>
  <param name="p_big" type="float" vstructmember="inputMaterial.big"/>
  <param name="p_neg" type="float" vstructmember="inputMaterial.neg"/>
  <param name="p_huge" type="float" vstructmember="inputMaterial.huge"/>
  <param name="p_copy" type="float" vstructmember="inputMaterial.copy"/>
  <param name="p_copyn" type="float" vstructmember="inputMaterial.copyn"/>
  <param name="p_copyc" type="color" vstructmember="inputMaterial.copyc"/>
  <param name="p_tuple" type="color" vstructmember="inputMaterial.tuple"/>
  <param name="p_conv" type="int" vstructmember="inputMaterial.conv"/>
  <param name="p_plain" type="float" vstructmember="inputMaterial.plain"/>
  <param name="f" type="float" default="0"/>
  <param name="arr" type="float" arraySize="2" default="0 0"/>
  <param name="col" type="color" default="0 0 0"/>
</args>"#;

/// A folder holding `Up.args` and `Down.args`.
fn definitions() -> PathBuf {
    let dir = scratch("values_network.rib", NETWORK).with_file_name("values_defs");
    std::fs::create_dir_all(&dir).expect("definitions folder");
    std::fs::write(dir.join("Up.args"), UP).expect("Up.args");
    std::fs::write(dir.join("Down.args"), DOWN).expect("Down.args");
    dir
}

const NETWORK: &str = "Pattern \"Up\" \"u\"\n\
    Bxdf \"Down\" \"d\" \"reference struct inputMaterial\" [\"u:out\"]\n";

fn resolve_to(defs: &Path, input: &Path, output: &Path, format: &str) -> crate::Outcome {
    run(&[
        "--args".into(),
        defs.display().to_string(),
        "--ext".into(),
        "set-tuples".into(),
        "resolve".into(),
        input.display().to_string(),
        "--format".into(),
        format.into(),
        "-o".into(),
        output.display().to_string(),
    ])
}

/// `set 1e39` into a float member: VS023 and the largest finite float, in RIB and in JSON,
/// and vstructc reads its own output back.
#[test]
fn set_beyond_the_float_range_warns_and_the_output_reads_back() {
    let defs = definitions();
    let input = scratch("values_in.rib", NETWORK);
    for format in ["rib", "json"] {
        let output = input.with_extension(format!("out.{format}"));
        let o = resolve_to(&defs, &input, &output, format);
        crate::check(&format!("set 1e39 → {format}"), &o, 0, "warning[VS023]");
        assert!(
            o.stderr.contains(
                "`set 1e39` gives a float outside the finite f32 range (an infinity or NaN); \
                 d.p_big is saturated"
            ),
            "{}",
            o.stderr
        );
        assert!(o.stderr.contains("d.p_neg is saturated"), "{}", o.stderr);
        assert!(o.stderr.contains("d.p_tuple is saturated"), "{}", o.stderr);
        // The huge defaults were saturated where they were read.
        assert!(
            o.stderr
                .contains("warning[AR012]: `1e400` is outside the f32 range; 3.4028235e38 is used"),
            "{}",
            o.stderr
        );
        let text = std::fs::read_to_string(&output).expect("the output was written");
        assert!(!text.contains("inf") && !text.contains("null"), "{text}");
        assert!(!text.to_lowercase().contains("nan"), "{text}");
        let back = run(&[
            "--args".into(),
            defs.display().to_string(),
            "resolve".into(),
            output.display().to_string(),
        ]);
        assert_eq!(
            back.status,
            Some(0),
            "{format} does not read back:\n{}",
            back.stderr
        );
        assert!(!back.stderr.contains("error"), "{}", back.stderr);
    }
}

/// The same through the library: the written values are the largest finite floats.
#[test]
fn saturated_values_are_the_largest_finite_floats() {
    let reg = registry();
    let mut d = Diagnostics::new();
    let mut net = parse_rib(
        NETWORK.as_bytes(),
        "n.rib",
        &reg,
        &RibOptions::default(),
        &mut d,
    )
    .expect("reads");
    let options = ResolveOptions {
        extensions: Extensions::all(),
        ..ResolveOptions::default()
    };
    let res = resolve(&mut net, &reg, &options);
    let down = net.find("d").expect("d");
    assert_eq!(net.value(down, "p_big"), Some(&Value::Float(f32::MAX)));
    assert_eq!(net.value(down, "p_neg"), Some(&Value::Float(f32::MIN)));
    assert_eq!(net.value(down, "p_huge"), Some(&Value::Float(f32::MAX)));
    assert_eq!(net.value(down, "p_copy"), Some(&Value::Float(f32::MAX)));
    assert_eq!(
        net.value(down, "p_tuple"),
        Some(&Value::Triple(BaseType::Color, [f32::MIN; 3]))
    );
    assert_eq!(
        net.value(down, "p_copyc"),
        Some(&Value::Triple(BaseType::Color, [f32::MAX, f32::MIN, 0.5]))
    );
    assert_eq!(net.value(down, "p_conv"), Some(&Value::Int(i32::MAX)));
    assert_eq!(res.diagnostics.count("VS023"), 4, "{:#?}", res.diagnostics);
}

/// A network built in code may hold infinities and NaN; both writers saturate them (NaN
/// as 0) and both readers take the result.
#[test]
fn writers_saturate_non_finite_values_built_in_code() {
    let mut net = Network::new();
    let n = net.add_node("n", "PxrThing");
    net.set_param(n, "a", Value::Float(f32::INFINITY));
    net.set_param(n, "b", Value::Float(f32::NAN));
    net.set_param(
        n,
        "c",
        Value::Triple(BaseType::Color, [f32::NEG_INFINITY, 1.0, f32::NAN]),
    );
    net.set_param(
        n,
        "d",
        Value::Array(BaseType::Float, vec![Value::Float(f32::INFINITY); 2]),
    );
    let s = net.add_node("s", "PxrSurface");
    net.connect(s, "diffuseColor", n, "resultRGB");
    let rib = write_rib_to_vec(b"", &net, &NoDefinitions).expect("writes");
    let text = String::from_utf8_lossy(&rib);
    assert!(!text.contains("inf") && !text.contains("NaN"), "{text}");
    let mut d = Diagnostics::new();
    let back = parse_rib(
        &rib,
        "w.rib",
        &NoDefinitions,
        &RibOptions::default(),
        &mut d,
    )
    .unwrap_or_else(|e| panic!("{e}\n{text}"));
    let n2 = back.find("n").expect("n");
    assert_eq!(back.value(n2, "a"), Some(&Value::Float(f32::MAX)));
    assert_eq!(back.value(n2, "b"), Some(&Value::Float(0.0)));
    // The JSON form holds materials: without one it would hold no node.
    let m = net.add_material("m");
    net.set_terminal(m, "surface", s, None);
    let json = write_json(&net).unwrap();
    assert!(json.contains("\"n\"") && !json.contains("null"), "{json}");
    parse_json(json.as_bytes(), "w.json", &NoDefinitions, &mut d)
        .unwrap_or_else(|e| panic!("{e}\n{json}"));
    let mut usda = Vec::new();
    vstructc::back::usd::write_usd(
        &net,
        &NoDefinitions,
        vstructc::back::usd::UsdMode::Flatten,
        "usda",
        &mut usda,
    )
    .expect("writes");
    let usda = String::from_utf8_lossy(&usda);
    let values = usda.replace("info:id", "");
    assert!(!values.contains("inf") && !values.contains("NaN"), "{usda}");
}

fn registry() -> Registry {
    let mut reg = Registry::new(RegistryOptions {
        paths: vec![],
        use_env: false,
        ..RegistryOptions::default()
    });
    reg.add_args_text("Up", UP).expect("Up parses");
    reg.add_args_text("Down", DOWN).expect("Down parses");
    reg
}

/// Parameter values as RIB text: floats at and beyond the f32 range, subnormals, huge ints,
/// colours, arrays, strings, references (to members, heads and missing handles).
fn param() -> impl Strategy<Value = String> {
    let float = prop_oneof![
        Just("0".to_string()),
        Just("1e39".to_string()),
        Just("-1e39".to_string()),
        Just("1e400".to_string()),
        Just("-1e400".to_string()),
        Just("3.4028235e38".to_string()),
        Just("3.4028236e38".to_string()),
        Just("1e-45".to_string()),
        Just("1e-60".to_string()),
        Just("-0".to_string()),
        any::<f64>()
            .prop_filter("finite", |x| x.is_finite())
            .prop_map(|x| format!("{x:e}")),
        any::<f32>()
            .prop_filter("finite", |x| x.is_finite())
            .prop_map(|x| format!("{x}")),
    ];
    let floats = prop::collection::vec(float.clone(), 1..5).prop_map(|v| v.join(" "));
    let name = prop_oneof![
        Just("f"),
        Just("arr"),
        Just("col"),
        Just("g"),
        Just("i"),
        Just("c"),
        Just("p_big"),
        Just("p_plain"),
        Just("x"),
    ];
    let handle = prop_oneof![Just("u"), Just("v"), Just("d"), Just("nobody")];
    let output = prop_oneof![Just("out"), Just("out_big"), Just("out_plain"), Just("g")];
    prop_oneof![
        (name.clone(), float.clone()).prop_map(|(n, x)| format!("\"float {n}\" [{x}]")),
        (name.clone(), floats.clone()).prop_map(|(n, x)| format!("\"float[2] {n}\" [{x}]")),
        (name.clone(), floats.clone()).prop_map(|(n, x)| format!("\"color {n}\" [{x}]")),
        (name.clone(), floats).prop_map(|(n, x)| format!("\"float[] {n}\" [{x}]")),
        (name.clone(), any::<i64>()).prop_map(|(n, x)| format!("\"int {n}\" [{x}]")),
        (name.clone(), "[a-z ]{0,8}").prop_map(|(n, s)| format!("\"string {n}\" [\"{s}\"]")),
        (name.clone(), handle.clone(), output.clone())
            .prop_map(|(n, h, o)| format!("\"reference float {n}\" [\"{h}:{o}\"]")),
        (handle, output)
            .prop_map(|(h, o)| format!("\"reference struct inputMaterial\" [\"{h}:{o}\"]")),
        (name, float).prop_map(|(n, x)| format!("\"{n}\" [{x}]")),
    ]
}

/// A RIB network of up to six nodes of the test types and of real ones.
fn network() -> impl Strategy<Value = String> {
    let node = (
        prop_oneof![
            Just(("Pattern", "Up")),
            Just(("Bxdf", "Down")),
            Just(("Pattern", "PxrLayer")),
            Just(("Pattern", "PxrLayerMixer")),
            Just(("Bxdf", "PxrLayerSurface")),
            Just(("Pattern", "Unknown")),
        ],
        prop_oneof![Just("u"), Just("v"), Just("d")],
        prop::collection::vec(param(), 0..5),
    );
    prop::collection::vec(node, 1..6).prop_map(|nodes| {
        nodes
            .into_iter()
            .map(|((request, shader), handle, params)| {
                format!("{request} \"{shader}\" \"{handle}\" {}\n", params.join(" "))
            })
            .collect()
    })
}

/// `read(write(resolve(x)))` succeeds for RIB and JSON, and a second round trip through
/// JSON succeeds too.
fn round_trips(rib: &str, extensions: Extensions) -> Result<(), TestCaseError> {
    let reg = registry();
    let mut d = Diagnostics::new();
    let Ok(mut net) = parse_rib(
        rib.as_bytes(),
        "p.rib",
        &reg,
        &RibOptions::default(),
        &mut d,
    ) else {
        return Ok(()); // Only networks the reader accepts are in the property.
    };
    let options = ResolveOptions {
        extensions,
        ..ResolveOptions::default()
    };
    resolve(&mut net, &reg, &options);
    // Nothing non-finite reaches the writers (they would saturate it, but the source is
    // meant to be closed).
    for id in net.node_ids() {
        for p in net[id].params() {
            if let Some(v) = p.value() {
                prop_assert!(v.is_finite(), "{} = {v} in\n{rib}", p.name());
            }
        }
    }
    let written = write_rib_to_vec(rib.as_bytes(), &net, &reg).expect("the RIB writer writes");
    let text = String::from_utf8_lossy(&written).into_owned();
    if let Err(e) = parse_rib(&written, "w.rib", &reg, &RibOptions::default(), &mut d) {
        return Err(TestCaseError::fail(format!("RIB: {e}\n{text}")));
    }
    // A network without material has no JSON form (the writer says so).
    let Ok(json) = write_json(&net) else {
        return Ok(());
    };
    let mut back = parse_json(json.as_bytes(), "w.json", &reg, &mut d)
        .map_err(|e| TestCaseError::fail(format!("JSON: {e}\n{json}")))?;
    resolve(&mut back, &reg, &options);
    let again = write_json(&back).unwrap();
    parse_json(again.as_bytes(), "w2.json", &reg, &mut d)
        .map_err(|e| TestCaseError::fail(format!("JSON again: {e}\n{again}")))?;
    Ok(())
}

proptest! {
    #[test]
    fn every_output_reads_back(rib in network(), all in any::<bool>()) {
        let ext = if all { Extensions::all() } else { Extensions::none() };
        round_trips(&rib, ext)?;
    }
}

/// Float defaults beyond the f32 range where definitions are read: `.args` saturates them
/// (AR012), `.oso` drops them (OS010), so no `copy` can take an infinity from a default.
#[test]
fn huge_float_defaults_are_closed_at_the_reader() {
    let args = crate::run_file(
        "HugeDefault.args",
        "<args format=\"1.0\"><shaderType><tag value=\"pattern\"/></shaderType>\
         <param name=\"g\" type=\"float\" default=\"-1e39\"/>\
         <output name=\"out\" type=\"float\"/></args>\n",
    );
    crate::check("HugeDefault.args", &args, 0, "warning[AR012]");
    assert!(
        args.stderr
            .contains("`-1e39` is outside the f32 range; -3.4028235e38 is used"),
        "{}",
        args.stderr
    );
    let oso = crate::run_file(
        "HugeDefault.oso",
        "OpenShadingLanguage 1.00\nshader HugeDefault\n\
         param\tfloat\tg\t1e39\t\t%read{2147483647,-1} %write{2147483647,-1}\n\
         oparam\tfloat\tout\t0\t\t%read{2147483647,-1} %write{2147483647,-1}\n\
         code ___main___\n\tend\n",
    );
    crate::check("HugeDefault.oso", &oso, 0, "warning[OS010]");
    assert!(
        oso.stderr.contains("`1e39` is not a finite float"),
        "{}",
        oso.stderr
    );
}

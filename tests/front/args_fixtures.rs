//! Every public `.args` fixture loads; exact counts and encodings of the Pixar files.

use std::path::{Path, PathBuf};
use std::sync::Arc;
use vstructc::Diagnostics;
use vstructc::front::args::parse_args;
use vstructc::registry::{Definition, Registry, RegistryOptions, VstructTables};
use vstructc::types::{ArraySpec, BaseType, Value};

fn args_files(dir: &Path) -> Vec<PathBuf> {
    let mut out = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                stack.push(p);
            } else if p.extension().is_some_and(|x| x == "args") {
                out.push(p);
            }
        }
    }
    out.sort();
    out
}

fn load(path: &Path) -> (Definition, Diagnostics) {
    let bytes = std::fs::read(path).unwrap();
    let id = path.file_stem().unwrap().to_str().unwrap();
    let mut diags = Diagnostics::new();
    let def = parse_args(&bytes, &path.to_string_lossy(), id, &mut diags)
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    (def, diags)
}

#[test]
fn every_args_fixture_loads_without_warnings() {
    let dir = fixtures_or_skip!();
    let files = args_files(&dir.join("args"));
    assert!(
        files.len() >= 8,
        "expected the pixar and laika args, got {files:?}"
    );
    for f in files {
        let (def, diags) = load(&f);
        for d in &diags {
            eprintln!("{}", d.render_human());
        }
        assert!(
            !diags.has_warnings(),
            "{}: unexpected warnings",
            f.display()
        );
        assert!(
            !def.inputs.is_empty() || !def.outputs.is_empty(),
            "{}",
            f.display()
        );
        assert_ne!(def.kind, "unknown", "{}", f.display());
    }
}

fn pixar(dir: &Path, name: &str) -> Definition {
    load(&dir.join("args/pixar").join(format!("{name}.args"))).0
}

fn tables_of(dir: &Path, name: &str) -> (Arc<Definition>, Arc<VstructTables>) {
    let reg = Registry::new(RegistryOptions::only([dir.join("args/pixar")]));
    (reg.definition(name).unwrap(), reg.tables(name).unwrap())
}

#[test]
fn pxr_layer_has_83_inputs_and_79_conditional_output_members() {
    let dir = fixtures_or_skip!();
    let (def, t) = tables_of(&dir, "PxrLayer");
    assert_eq!(def.kind, "pattern");
    assert_eq!(def.inputs.len(), 83);
    assert_eq!(def.outputs.len(), 80);
    assert_eq!(t.input_heads().count(), 0);
    assert_eq!(t.output_heads().collect::<Vec<_>>(), ["pxrMaterialOut"]);
    let members = t.members_out("pxrMaterialOut");
    assert_eq!(members.len(), 79);
    assert!(
        members.iter().all(|m| m.cond.is_some()),
        "all 79 are conditional"
    );
    // Member names are the text after the head, found through the reverse table.
    for m in members {
        assert_eq!(m.names.len(), 1);
        assert_eq!(&*m.property, format!("pxrMaterialOut_{}", m.names[0]));
        let found = t.reverse_out("pxrMaterialOut", &m.names[0]).unwrap();
        assert_eq!(found.property, m.property);
    }
    // Encoding E3: the tag-only output head is normalised to vstruct.
    let head = def.output("pxrMaterialOut").unwrap();
    assert_eq!(head.ty.base, BaseType::Vstruct);
    assert_eq!(head.connection_types, ["vstruct"]);
}

#[test]
fn pxr_layer_conditional_text_and_position_are_exact() {
    let dir = fixtures_or_skip!();
    let (_, t) = tables_of(&dir, "PxrLayer");
    let m = t.reverse_out("pxrMaterialOut", "diffuseGain").unwrap();
    let c = &m.cond.as_ref().unwrap().source;
    // Raw value, trailing space included; the value starts after the quote on line 1121.
    assert_eq!(c.text, "connect if enableDiffuse == 1 ");
    assert_eq!((c.location.line, c.location.column), (1121, 29));
    let e = t.reverse_out("pxrMaterialOut", "enableSpecular").unwrap();
    assert_eq!(
        e.cond.as_ref().unwrap().source.text.trim(),
        "set 1 if enableSpecular == 1 else set 0"
    );
}

#[test]
fn pxr_layer_mixer_has_5_input_heads_of_79_and_one_output_head() {
    let dir = fixtures_or_skip!();
    let (def, t) = tables_of(&dir, "PxrLayerMixer");
    assert_eq!(def.inputs.len(), 409);
    let heads: Vec<_> = t.input_heads().collect();
    assert_eq!(heads, ["baselayer", "layer1", "layer2", "layer3", "layer4"]);
    for h in &heads {
        let members = t.members_in(h);
        assert_eq!(members.len(), 79, "{h}");
        for m in members {
            assert_eq!(&*m.property, format!("{h}_{}", m.names[0]));
        }
        // Encoding E2: `type="vstruct" default=""`; kind vstruct, no default.
        let p = def.input(h).unwrap();
        assert_eq!(p.ty.base, BaseType::Vstruct);
        assert_eq!(p.default, None);
    }
    assert_eq!(t.output_heads().collect::<Vec<_>>(), ["pxrMaterialOut"]);
    let out = t.members_out("pxrMaterialOut");
    assert_eq!(out.len(), 79);
    assert!(out.iter().all(|m| m.cond.is_some()));
    let dc = t.reverse_out("pxrMaterialOut", "diffuseColor").unwrap();
    assert_eq!(
        dc.cond.as_ref().unwrap().source.text.trim(),
        "connect if enableDiffuseAlways == 1"
    );
}

#[test]
fn mixer_input_members_match_layer_output_members() {
    let dir = fixtures_or_skip!();
    let (_, layer) = tables_of(&dir, "PxrLayer");
    let (_, mixer) = tables_of(&dir, "PxrLayerMixer");
    // Same member names (the files order the fuzz and iridescence blocks differently).
    let layer_names: Vec<&str> = sorted(
        layer
            .members_out("pxrMaterialOut")
            .iter()
            .map(|m| m.names[0].as_str())
            .collect(),
    );
    for h in ["baselayer", "layer1", "layer4"] {
        let names = sorted(
            mixer
                .members_in(h)
                .iter()
                .map(|m| m.names[0].as_str())
                .collect(),
        );
        assert_eq!(names, layer_names, "{h}");
    }
    let mixer_out = sorted(
        mixer
            .members_out("pxrMaterialOut")
            .iter()
            .map(|m| m.names[0].as_str())
            .collect(),
    );
    assert_eq!(mixer_out, layer_names);
}

#[test]
fn pages_nest_with_colons() {
    let dir = fixtures_or_skip!();
    let def = pixar(&dir, "PxrLayer");
    assert_eq!(def.input("enableDiffuseAlways").unwrap().page, None);
    assert_eq!(
        def.input("diffuseGain").unwrap().page.as_deref(),
        Some("Diffuse")
    );
    assert_eq!(
        def.input("diffuseBumpNormal").unwrap().page.as_deref(),
        Some("Diffuse:Diffuse Advanced")
    );
    assert_eq!(
        def.input("enableSpecular").unwrap().page.as_deref(),
        Some("Primary Specular")
    );
}

#[test]
fn typed_fields_and_verbatim_metadata() {
    let dir = fixtures_or_skip!();
    let def = pixar(&dir, "PxrLayer");
    let p = def.input("diffuseColor").unwrap();
    assert_eq!(p.ty.base, BaseType::Color);
    assert_eq!(p.default, Some(Value::Triple(BaseType::Color, [0.18; 3])));
    assert_eq!(p.label.as_deref(), Some("Color"));
    assert_eq!(p.widget.as_deref(), Some("color"));
    assert_eq!(p.help.as_deref(), Some("Diffuse color of this layer."));
    let keys: Vec<&str> = p.metadata.iter().map(|(k, _)| k).collect();
    assert_eq!(keys, ["name", "type", "label", "widget", "default"]);
    let o = def.output("pxrMaterialOut_diffuseGain").unwrap();
    let keys: Vec<&str> = o.metadata.iter().map(|(k, _)| k).collect();
    assert_eq!(keys, ["name", "vstructmember", "vstructConditionalExpr"]);
    assert_eq!(o.ty.base, BaseType::Float, "output type from its first tag");
    assert!(o.connectable);
    // Node-level raw elements.
    let (_, rfc) = def.metadata.iter().find(|(k, _)| *k == "rfcdata").unwrap();
    assert!(
        rfc.starts_with("<rfcdata") && rfc.contains("nodeid=\"1037674\""),
        "{rfc}"
    );
}

#[test]
fn pxr_osl_output_type_is_the_first_of_four_tags() {
    let dir = fixtures_or_skip!();
    let def = pixar(&dir, "PxrOSL");
    let r = def.output("result").unwrap();
    assert_eq!(r.ty.base, BaseType::Color);
    assert_eq!(r.connection_types, ["color", "vector", "normal", "point"]);
    let s = def.input("shader").unwrap();
    assert!(!s.connectable, "connectable=\"False\"");
    assert_eq!(s.default, Some(Value::Str(String::new())));
    assert_eq!(s.ty.array, ArraySpec::None);
}

#[test]
fn laika_spaced_equals_comments_and_html_help() {
    let dir = fixtures_or_skip!();
    let (def, _) = load(&dir.join("args/laika/KPVelvet.args"));
    assert_eq!(def.kind, "bxdf");
    let notes = def.input("Notes").unwrap();
    assert!(!notes.connectable);
    let help = notes.help.as_deref().unwrap();
    assert!(
        help.contains(
            "<a href='http://dx.doi.org/10.1007/s00138-002-0089-7'>Koenderink-Pont asperity</a>"
        ),
        "HTML inside <help> is kept as markup: {help}"
    );
    let gain = def.input("Gain").unwrap();
    assert_eq!(gain.default, Some(Value::Float(1.0)));
    assert_eq!(gain.meta("slidermax"), Some("4.0"));
    assert_eq!(
        gain.help.as_deref(),
        Some("Adjusts the <b>Gain</b> of the response.")
    );
}

#[test]
fn pxr_shaded_side_spaced_tag_kind() {
    let dir = fixtures_or_skip!();
    let def = pixar(&dir, "PxrShadedSide");
    assert_eq!(def.kind, "pattern");
    assert_eq!(def.input("invert").unwrap().default, Some(Value::Int(0)));
    assert_eq!(def.output("resultF").unwrap().ty.base, BaseType::Float);
}

#[test]
fn registry_over_all_fixture_args_has_no_errors() {
    let dir = fixtures_or_skip!();
    let reg = Registry::new(RegistryOptions::only([dir.join("args")]));
    let ids = reg.ids();
    for id in [
        "PxrLayer",
        "PxrLayerMixer",
        "PxrOSL",
        "PxrShadedSide",
        "KPVelvet",
        "HGScatter",
    ] {
        assert!(ids.contains(&id), "{id} in {ids:?}");
    }
    reg.load_all();
    for id in &ids {
        assert!(reg.definition(id).is_some(), "{id}");
    }
    let diags = reg.diagnostics();
    assert!(!diags.has_errors(), "{diags:?}");
    // Only diagnostics about conditionals (VS codes) may appear.
    for d in &diags {
        assert!(d.code.starts_with("VS"), "{}", d.render_human());
    }
}

#[test]
fn every_oso_fixture_loads() {
    let dir = fixtures_or_skip!();
    let reg = Registry::new(RegistryOptions::only([dir.join("oso")]));
    let ids = reg.ids();
    assert!(ids.contains(&"TestShaderPropertiesNodeOSL"), "{ids:?}");
    assert!(ids.contains(&"TestNodeOSL"), "{ids:?}");
    reg.load_all();
    let diags = reg.diagnostics();
    assert!(!diags.has_errors(), "{diags:?}");
    for id in &ids {
        assert!(reg.definition(id).is_some(), "{id}");
    }
    let t = reg.tables("TestShaderPropertiesNodeOSL").unwrap();
    let m = t.members_in("inputVstruct");
    assert_eq!(m.len(), 1);
    assert_eq!(&*m[0].property, "inputVstruct_parameter");
    assert_eq!(m[0].names, ["parameter"]);
}

fn sorted(mut v: Vec<&str>) -> Vec<&str> {
    v.sort_unstable();
    v
}

//! The check against definitions that resolution runs first: misspelt parameters, outputs
//! and node types are warnings naming the closest declared names (VS024, VS020), whatever
//! the network came from, and real networks raise none.

use vstructc::front::NetFormat;
use vstructc::network::{Network, RequestKind};
use vstructc::pipeline::{Lowering, PipelineOptions, run};
use vstructc::registry::{Registry, RegistryOptions};
use vstructc::resolve::{ResolveOptions, resolve};
use vstructc::{BaseType, Diagnostics, Severity, Value};

fn run_text(name: &str, text: &str, format: NetFormat, registry: &Registry) -> Diagnostics {
    let mut diags = Diagnostics::new();
    let options = PipelineOptions {
        lowering: Lowering::All,
        ..Default::default()
    };
    run(
        name,
        text.as_bytes(),
        format,
        registry,
        &options,
        &mut diags,
    )
    .unwrap();
    diags
}

fn rib(text: &str) -> Diagnostics {
    run_text("typo.rib", text, NetFormat::Rib, &Registry::embedded())
}

/// The messages of one code.
fn messages(d: &Diagnostics, code: &str) -> Vec<String> {
    d.with_code(code).map(|d| d.message.clone()).collect()
}

const TYPOS: &str = r#"Bxdf "PxrSurface" "ball" "color diffuseColour" [0.8 0.2 0.2]
Bxdf "PhysicalMaterial" "car" "float coat" [1] "string __materialid" ["car"]
"#;

#[test]
fn a_misspelt_rib_parameter_is_a_warning_with_the_declared_name() {
    let d = rib(TYPOS);
    let vs024: Vec<_> = d.with_code("VS024").collect();
    assert_eq!(vs024.len(), 2, "{d:#?}");
    assert!(vs024.iter().all(|d| d.severity == Severity::Warning));
    assert!(
        vs024[0].message.ends_with("did you mean `diffuseColor`?"),
        "{}",
        vs024[0].message
    );
    assert_eq!(vs024[0].node.as_deref(), Some("ball"));
    assert_eq!(vs024[0].param.as_deref(), Some("diffuseColour"));
    assert_eq!(vs024[0].location.as_ref().unwrap().column, 26);
    // `coat` begins `coating` (the parameter meant) and other coat parameters.
    assert!(
        vs024[1].message.contains("did you mean `coating`"),
        "{}",
        vs024[1].message
    );
}

#[test]
fn human_and_json_diagnostics_of_a_typo() {
    let d = rib(TYPOS);
    let shown: Vec<String> = d
        .with_code("VS024")
        .map(|d| format!("{}\n{}", d.render_human(), d.render_json()))
        .collect();
    insta::assert_snapshot!(shown.join("\n"));
}

#[test]
fn an_unknown_node_type_is_one_diagnostic_with_the_known_id() {
    let d = rib(r#"Pattern "PxrLayer" "paint" "int enableDiffuse" [1]
Bxdf "PxrSurfce" "ball" "color diffuseColor" [1 0 0]
Bxdf "PxrSurfce" "ball2"
Pattern "PxrTexture" "tex" "string filename" ["a.tex"]
"#);
    // RB019 (the reader's) is not repeated beside VS020.
    assert_eq!(d.count("RB019"), 0, "{d:#?}");
    let vs020: Vec<_> = d.with_code("VS020").collect();
    assert_eq!(vs020.len(), 2, "{d:#?}");
    assert_eq!(vs020[0].severity, Severity::Warning);
    assert!(
        vs020[0].message.contains("of 2 nodes (ball, ball2)")
            && vs020[0].message.ends_with("did you mean `PxrSurface`?"),
        "{}",
        vs020[0].message
    );
    // Nothing near `PxrTexture` is known: an info, no suggestion, no parameter warnings.
    assert_eq!(vs020[1].severity, Severity::Info);
    assert!(!vs020[1].message.contains("did you mean"));
    assert_eq!(d.count("VS024"), 0);
    let shown: Vec<String> = vs020
        .iter()
        .map(|d| format!("{}\n{}", d.render_human(), d.render_json()))
        .collect();
    insta::assert_snapshot!(shown.join("\n"));
}

/// A node of an unknown type is named once however many connections read it, and a head it
/// feeds is still named.
#[test]
fn an_unknown_node_read_by_connections_is_counted_once() {
    let d = rib(r#"Pattern "PxrTexture" "t" "string filename" ["a.tex"]
Bxdf "PxrSurface" "s" "reference color diffuseColor" ["t:resultRGB"]
    "reference color specularFaceColor" ["t:resultRGB"]
Pattern "MyLayer" "ml"
Pattern "PxrLayerMixer" "mix" "reference vstruct baselayer" ["ml:pxrMaterialOut"]
    "reference vstruct layer1" ["ml:pxrMaterialOut"]
"#);
    let vs020 = messages(&d, "VS020");
    assert_eq!(vs020.len(), 2, "{d:#?}");
    let texture = vs020.iter().find(|m| m.contains("PxrTexture")).unwrap();
    assert!(
        texture.starts_with("node type `PxrTexture` of t is not"),
        "{texture}"
    );
    let layer = vs020.iter().find(|m| m.contains("MyLayer")).unwrap();
    assert!(
        layer.starts_with("node type `MyLayer` of ml is not")
            && layer.contains("it feeds the head mix.baselayer"),
        "{layer}"
    );
}

#[test]
fn a_json_network_is_checked_the_same_way() {
    let json = r#"{"vstructcNetwork": 1, "materials": {"ball": {
        "nodes": {"ball": {"nodeTypeId": "PxrSurface",
            "parameters": {"diffuseColour": {"type": "color", "value": [1, 0, 0]}}}},
        "terminals": {"surface": {"upstreamNode": "ball", "upstreamOutputName": ""}}}}}"#;
    let d = run_text("typo.json", json, NetFormat::Json, &Registry::embedded());
    let vs024: Vec<_> = d.with_code("VS024").collect();
    assert_eq!(vs024.len(), 1, "{d:#?}");
    assert!(vs024[0].message.ends_with("did you mean `diffuseColor`?"));
    assert_eq!(
        vs024[0].location.as_ref().unwrap().pointer.as_deref(),
        Some("/materials/ball/nodes/ball/parameters/diffuseColour")
    );
}

#[test]
fn a_network_built_in_code_is_checked_by_resolve() {
    let registry = Registry::embedded();
    let mut net = Network::new();
    let layer = net.add_node("paint", "PxrLayer");
    net.set_param(layer, "enableDiffuse", Value::Int(1));
    let surface = net.add_node_of_kind("ball", "PxrLayerSurface", RequestKind::Bxdf);
    net.connect(surface, "inputMaterail", layer, "pxrMaterialOut");
    net.connect(surface, "bumpNormal", layer, "pxrMaterialOutt");
    let res = resolve(&mut net, &registry, &ResolveOptions::default());
    let got = messages(&res.diagnostics, "VS024");
    assert_eq!(got.len(), 2, "{:#?}", res.diagnostics);
    assert!(
        got.iter()
            .any(|m| m.starts_with("ball connects `inputMaterail`")
                && m.ends_with("did you mean `inputMaterial`?")),
        "{got:#?}"
    );
    assert!(
        got.iter()
            .any(|m| m.contains("declares no output `pxrMaterialOutt`")
                && m.ends_with("did you mean `pxrMaterialOut`?")),
        "{got:#?}"
    );
    let d = res.diagnostics.with_code("VS024").next().unwrap();
    assert_eq!(d.location, None);
    assert_eq!(d.node.as_deref(), Some("ball"));
}

#[test]
fn renderer_names_members_and_element_names_are_declared() {
    let registry = Registry::embedded();
    let mut net = Network::new();
    let layer = net.add_node("paint", "PxrLayer");
    net.set_param(layer, "__materialid", Value::Str("paint".into()));
    net.set_param(
        layer,
        "diffuseColor",
        Value::Triple(BaseType::Color, [1.0, 0.0, 0.0]),
    );
    let mixer = net.add_node("mix", "PxrLayerMixer");
    net.connect(mixer, "baselayer", layer, "pxrMaterialOut");
    // A member connected directly (to an output member) is declared on both ends.
    net.connect(
        mixer,
        "layer1_diffuseColor",
        layer,
        "pxrMaterialOut_diffuseColor",
    );
    let surface = net.add_node_of_kind("ball", "PxrLayerSurface", RequestKind::Bxdf);
    net.connect(surface, "inputMaterial", mixer, "pxrMaterialOut");
    let res = resolve(&mut net, &registry, &ResolveOptions::default());
    assert_eq!(res.diagnostics.count("VS024"), 0, "{:#?}", res.diagnostics);
    assert_eq!(res.diagnostics.count("VS020"), 0, "{:#?}", res.diagnostics);
}

/// The shipped examples, the generated bench scene and the real fixture resolved against
/// Pixar's definitions raise no VS024 (a false warning on real files would bury real ones).
#[test]
fn real_networks_raise_no_false_warnings() {
    let registry = Registry::embedded();
    let repo = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    for example in ["chain.rib", "layered.rib", "override.rib"] {
        let text = std::fs::read_to_string(repo.join("examples").join(example)).unwrap();
        let d = run_text(example, &text, NetFormat::Rib, &registry);
        assert_eq!(d.count("VS024") + d.count("VS020"), 0, "{example}: {d:#?}");
    }
    let scene = vstructc_testkit::testgen::layered_scene(20);
    let d = run_text("scene.rib", &scene, NetFormat::Rib, &registry);
    assert_eq!(d.count("VS024") + d.count("VS020"), 0, "{d:#?}");

    let dir = fixtures_or_skip!();
    // Pixar's definitions first, then the embedded ones (PxrLayerSurface).
    let pixar = Registry::new(RegistryOptions {
        paths: vec![dir.join("args/pixar")],
        ..RegistryOptions::default()
    });
    let path = dir.join("rib/ldd/pxrLayerSurface.0001.rib");
    let text = std::fs::read_to_string(&path).unwrap();
    let d = run_text("fixture.rib", &text, NetFormat::Rib, &pixar);
    assert_eq!(d.count("VS024"), 0, "{d:#?}");
}

/// `--no-conditions` is asked for: it is reported once, with the number of members it
/// connected unevaluated; `--verbose` lists each.
#[test]
fn no_conditions_is_reported_once_with_its_count() {
    let registry = Registry::embedded();
    let repo = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let text = std::fs::read(repo.join("examples/layered.rib")).unwrap();
    let resolve_with = |verbose: bool| {
        let mut diags = Diagnostics::new();
        let options = PipelineOptions {
            resolve: ResolveOptions {
                conditions: false,
                verbose,
                ..ResolveOptions::default()
            },
            ..Default::default()
        };
        run(
            "layered.rib",
            &text,
            NetFormat::Rib,
            &registry,
            &options,
            &mut diags,
        )
        .unwrap();
        diags
    };
    let d = resolve_with(false);
    let vs022: Vec<_> = d.with_code("VS022").collect();
    assert_eq!(vs022.len(), 1, "{d:#?}");
    assert_eq!(vs022[0].severity, Severity::Info);
    assert!(
        vs022[0]
            .message
            .starts_with("--no-conditions: 227 members were connected"),
        "{}",
        vs022[0].message
    );
    // About the whole run: no location (the first member is named in the message).
    assert!(vs022[0].location.is_none());
    let d = resolve_with(true);
    let notes = d
        .with_code("VS022")
        .filter(|d| d.severity == Severity::Note)
        .count();
    assert_eq!(notes, 227);
    assert_eq!(d.count("VS022"), 228);
}

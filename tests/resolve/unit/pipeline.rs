//! Unit tests of `pipeline` (`src/pipeline.rs`).

use vstructc::diag::{Diagnostics, Error};
use vstructc::front::NetFormat;
use vstructc::lower::network::report_placeholders;
use vstructc::network::Network;
use vstructc::network::RequestKind;
use vstructc::pipeline::*;
use vstructc::registry::Registry;
use vstructc::resolve::{ResolveOptions, resolve};

/// A mixer whose `layer1` is wired to a node without `pxrMaterialOut`: VS010 on resolve,
/// LW030 on lowering.
fn unresolvable() -> Network {
    let mut net = Network::new();
    let base = net.add_node("base", "PxrLayer");
    let other = net.add_node("other", "vsConstant");
    let mixer = net.add_node("mixer", "PxrLayerMixer");
    let surface = net.add_node_of_kind("surface", "PxrLayerSurface", RequestKind::Bxdf);
    net.connect(mixer, "baselayer", base, "pxrMaterialOut");
    net.connect(mixer, "layer1", other, "pxrMaterialOut");
    net.connect(surface, "inputMaterial", mixer, "pxrMaterialOut");
    net
}

/// Diagnostics of a network built in memory have no location but name their node and
/// parameter as fields.
#[test]
fn diagnostics_carry_node_and_parameter() {
    let registry = Registry::embedded();
    let mut net = unresolvable();
    let res = resolve(&mut net, &registry, &ResolveOptions::default());
    let vs010: Vec<_> = res
        .diagnostics
        .iter()
        .filter(|d| d.code == "VS010")
        .collect();
    assert_eq!(vs010.len(), 1, "{:#?}", res.diagnostics);
    assert_eq!(vs010[0].location, None);
    assert_eq!(vs010[0].node.as_deref(), Some("mixer"));
    assert_eq!(vs010[0].param.as_deref(), Some("layer1"));
    let mut diags = Diagnostics::new();
    report_placeholders(&net, &registry, &mut diags);
    let lw030 = diags.with_code("LW030").next().unwrap();
    assert_eq!(lw030.node.as_deref(), Some("mixer"));
    assert_eq!(lw030.param.as_deref(), Some("layer1"));
}

#[test]
fn run_resolves_lowers_and_drops_placeholders_when_asked() {
    let registry = Registry::embedded();
    let rib = br#"Pattern "PxrLayer" "base" "int enableDiffuse" [1]
Pattern "vsConstant" "other"
Pattern "PxrLayerMixer" "mixer" "reference vstruct baselayer" ["base:pxrMaterialOut"]
"reference vstruct layer1" ["other:pxrMaterialOut"]
Bxdf "PxrLayerSurface" "surface" "reference vstruct inputMaterial" ["mixer:pxrMaterialOut"]
"#;
    let run_with = |options: &PipelineOptions| {
        let mut diags = Diagnostics::new();
        let out = run("s.rib", rib, NetFormat::Rib, &registry, options, &mut diags);
        (out, diags)
    };
    let (out, diags) = run_with(&PipelineOptions::default());
    let out = out.unwrap();
    assert!(out.materials.is_empty());
    assert_eq!(diags.count("VS010"), 1, "{diags:#?}");
    assert_eq!(diags.count("LW030"), 0, "no lowering, no LW030");
    let mixer = out.network.find("mixer").unwrap();
    assert_eq!(out.network.connections(mixer, "layer1").len(), 1);

    let all = PipelineOptions {
        lowering: Lowering::All,
        ..Default::default()
    };
    let (out, diags) = run_with(&all);
    assert_eq!(out.unwrap().materials.len(), 1);
    assert_eq!(diags.count("LW030"), 1, "{diags:#?}");

    let dropped = PipelineOptions {
        resolve: ResolveOptions {
            drop_unresolved: true,
            ..ResolveOptions::default()
        },
        ..all.clone()
    };
    let (out, diags) = run_with(&dropped);
    let out = out.unwrap();
    let mixer = out.network.find("mixer").unwrap();
    assert!(out.network.connections(mixer, "layer1").is_empty());
    assert_eq!(diags.count("LW030"), 0);

    let only = PipelineOptions {
        lowering: Lowering::Only("nothing".into()),
        ..Default::default()
    };
    assert!(matches!(run_with(&only).0, Err(Error::Usage(_))));
}

#[test]
fn compile_gives_interpreter_materials() {
    let registry = Registry::embedded();
    let mut net = unresolvable();
    resolve(&mut net, &registry, &ResolveOptions::default());
    let mut diags = Diagnostics::new();
    let materials = compile(&net, &registry, &Lowering::All, &mut diags).unwrap();
    assert_eq!(materials.len(), 1);
    assert_eq!(materials[0].name(), "surface");
    assert!(
        compile(&net, &registry, &Lowering::None, &mut diags)
            .unwrap()
            .is_empty()
    );
}

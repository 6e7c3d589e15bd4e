//! USD: the corpus in `tests/data/usd/` resolves to exactly the member connections and
//! values of the equivalent RIB (node handles compared by their last path component), with
//! conditions on and off; RIB → usda → RIB and usda → resolve → usda → RIB keep every
//! connection and value; the reader's diagnostics.

use crate::common;

use std::collections::BTreeMap;
use vstructc::back::rib::write_rib_to_vec;
use vstructc::back::usd::{UsdMode, write_usd};
use vstructc::front::rib::{RibOptions, parse_rib};
use vstructc::front::usd::{crate_values_agree, parse_usd, parse_usd_composed, reads_layer_alone};
use vstructc::limits::Limits;
use vstructc::network::Network;
use vstructc::registry::Registry;
use vstructc::resolve::{ResolveOptions, resolve};
use vstructc::{Diagnostics, Severity};

fn usd_dir() -> std::path::PathBuf {
    common::repo_dir().join("tests/data/usd")
}

/// The last component of a prim path or a sanitised handle: the name both sides share.
fn short(handle: &str) -> String {
    handle.rsplit('/').next().unwrap_or(handle).to_string()
}

/// Every node's parameters (renderer `__` names left out): value and connections, with
/// handles shortened.
type Canon = BTreeMap<String, BTreeMap<String, (Option<String>, Vec<String>)>>;

fn canon(net: &Network) -> Canon {
    let mut out = Canon::new();
    for id in net.nodes_sorted() {
        let node = &net[id];
        let mut params = BTreeMap::new();
        for p in node.params_by_name() {
            if p.name().starts_with("__") {
                continue;
            }
            let links = p
                .connections()
                .iter()
                .map(|l| {
                    let up = match l.upstream_node() {
                        Some(u) => short(net[u].handle()),
                        None => format!("missing {}", l.missing_handle().unwrap_or("")),
                    };
                    format!("{up}:{}", l.output().unwrap_or(""))
                })
                .collect();
            params.insert(
                p.name().to_string(),
                (p.value().map(|v| format!("{v:?}")), links),
            );
        }
        let prev = out.insert(
            format!("{} {}", short(node.handle()), node.shader()),
            params,
        );
        assert!(prev.is_none(), "two nodes named {}", node.handle());
    }
    out
}

fn options(conditions: bool) -> ResolveOptions {
    ResolveOptions {
        conditions,
        ..ResolveOptions::default()
    }
}

fn read_rib(bytes: &[u8], name: &str, reg: &Registry) -> Network {
    let mut diags = Diagnostics::new();
    let net = parse_rib(bytes, name, reg, &RibOptions::default(), &mut diags).expect("RIB reads");
    assert!(!diags.has_errors(), "{name}: {diags:#?}");
    net
}

fn read_usd(bytes: &[u8], name: &str, reg: &Registry) -> (Network, Diagnostics) {
    let mut diags = Diagnostics::new();
    let net = parse_usd(bytes, name, reg, &Limits::default(), &mut diags)
        .unwrap_or_else(|e| panic!("{name}: {e}"));
    (net, diags)
}

fn resolved_rib(example: &str, reg: &Registry, conditions: bool) -> Network {
    let path = common::repo_dir().join("examples").join(example);
    let mut net = read_rib(&std::fs::read(&path).unwrap(), example, reg);
    resolve(&mut net, reg, &options(conditions));
    net
}

fn resolved_usd(file: &str, reg: &Registry, conditions: bool) -> Network {
    let path = usd_dir().join(file);
    let (mut net, diags) = read_usd(&std::fs::read(&path).unwrap(), path.to_str().unwrap(), reg);
    assert!(
        !diags.iter().any(|d| d.severity >= Severity::Warning),
        "{file}: {diags:#?}"
    );
    let res = resolve(&mut net, reg, &options(conditions));
    assert!(
        !res.diagnostics
            .iter()
            .any(|d| d.severity >= Severity::Warning),
        "{file}: {:#?}",
        res.diagnostics
    );
    net
}

/// Each stage of the corpus and the bundled RIB example it is equivalent to.
const PAIRS: &[(&str, &str)] = &[
    ("chain.usda", "chain.rib"),
    ("layered.usda", "layered.rib"),
    ("override.usda", "override.rib"),
    ("library_look.usda", "override.rib"),
    ("variants.usda", "override.rib"),
    ("nodegraph.usda", "layered.rib"),
    ("layered.usdc", "layered.rib"),
    ("layered.usdz", "layered.rib"),
];

#[test]
fn each_stage_resolves_as_its_rib_does() {
    let reg = Registry::embedded();
    for conditions in [true, false] {
        for &(usd, rib) in PAIRS {
            let want = canon(&resolved_rib(rib, &reg, conditions));
            let got = canon(&resolved_usd(usd, &reg, conditions));
            assert_eq!(got, want, "{usd} vs {rib}, conditions {conditions}");
        }
    }
}

#[test]
fn every_material_has_its_terminal_and_its_shaders() {
    let reg = Registry::embedded();
    let net = resolved_usd("nodegraph.usda", &reg, true);
    assert_eq!(net.materials().len(), 1);
    let m = &net.materials()[0];
    assert_eq!(m.name, "/Looks/layeredMaterial");
    assert_eq!(m.terminals.len(), 1);
    assert_eq!(m.terminals[0].name, "surface");
    let surface = m.terminals[0].link.upstream_node().unwrap();
    assert_eq!(net[surface].handle(), "/Looks/layeredMaterial/surface");
    assert_eq!(net[surface].kind(), vstructc::network::RequestKind::Bxdf);
    // The shader inside the node graph belongs to the material too.
    let mut members: Vec<String> = net
        .material_nodes(0)
        .into_iter()
        .map(|id| net[id].handle().to_string())
        .collect();
    members.sort();
    assert_eq!(
        members,
        [
            "/Looks/layeredMaterial/coat/redCoat",
            "/Looks/layeredMaterial/greenBase",
            "/Looks/layeredMaterial/mixer",
            "/Looks/layeredMaterial/surface",
        ]
    );
}

/// A shader under the material that no terminal reaches still belongs to it, and the
/// universal `outputs:surface` is the terminal when no `ri:` output exists.
#[test]
fn unreached_shaders_belong_and_universal_terminals_are_read() {
    let reg = Registry::embedded();
    let text = br#"#usda 1.0
def Material "M" {
    token outputs:surface.connect = </M/S.outputs:out>
    def Shader "Spare" {
        uniform token info:id = "PxrLayer"
        int inputs:enableDiffuse = 1
    }
    def Shader "S" {
        uniform token info:id = "PxrSurface"
        float inputs:diffuseGain = 0.5
    }
}
"#;
    let (net, diags) = read_usd(text, "m.usda", &reg);
    assert!(diags.is_empty(), "{diags:#?}");
    let m = &net.materials()[0];
    assert_eq!(m.terminals[0].name, "surface");
    assert_eq!(net.material_nodes(0).len(), 2);
}

#[test]
fn rib_to_usda_to_rib_keeps_every_connection_and_value() {
    let reg = Registry::embedded();
    for example in ["chain.rib", "layered.rib", "override.rib"] {
        for conditions in [true, false] {
            let net = resolved_rib(example, &reg, conditions);
            let want = canon(&net);
            let mut usda = Vec::new();
            write_usd(&net, &reg, UsdMode::Flatten, "usda", &mut usda).unwrap();
            let (back, diags) = read_usd(&usda, "out.usda", &reg);
            assert!(diags.is_empty(), "{example}: {diags:#?}");
            assert_eq!(canon(&back), want, "{example} → usda");
            assert_eq!(back.materials().len(), net.materials().len());
            let rib = write_rib_to_vec(&[], &back, &reg).unwrap();
            let again = read_rib(&rib, "back.rib", &reg);
            assert_eq!(canon(&again), want, "{example} → usda → RIB");
        }
    }
}

#[test]
fn usda_to_resolved_usda_to_rib_keeps_every_connection_and_value() {
    let reg = Registry::embedded();
    for &(usd, _) in PAIRS {
        let net = resolved_usd(usd, &reg, true);
        let want = canon(&net);
        let mut usda = Vec::new();
        write_usd(&net, &reg, UsdMode::Flatten, "usda", &mut usda).unwrap();
        let text = String::from_utf8(usda.clone()).unwrap();
        let (back, diags) = read_usd(&usda, "out.usda", &reg);
        assert!(diags.is_empty(), "{usd}: {diags:#?}");
        // Same prim paths.
        let handles = |n: &Network| -> Vec<String> {
            n.nodes_sorted()
                .into_iter()
                .map(|id| n[id].handle().to_string())
                .collect()
        };
        assert_eq!(handles(&back), handles(&net), "{usd}:\n{text}");
        assert_eq!(canon(&back), want, "{usd} → usda:\n{text}");
        let rib = write_rib_to_vec(&[], &back, &reg).unwrap();
        let again = read_rib(&rib, "back.rib", &reg);
        assert_eq!(canon(&again), want, "{usd} → usda → RIB");
    }
}

/// The writer types values as the definitions declare them (Sdr's mapping) and connects
/// the terminal to the Bxdf's `outputs:out`.
#[test]
fn the_writer_types_inputs_as_declared() {
    let reg = Registry::embedded();
    let net = resolved_rib("override.rib", &reg, true);
    let mut usda = Vec::new();
    write_usd(&net, &reg, UsdMode::Flatten, "usda", &mut usda).unwrap();
    let text = String::from_utf8(usda).unwrap();
    for line in [
        "def Material \"plasticSurface\"",
        "token outputs:ri:surface.connect = </Materials/plasticSurface/plasticSurface.outputs:out>",
        "int inputs:enableDiffuse = 1",
        "color3f inputs:diffuseColor = (0.8, 0.1, 0.1)",
        "color3f inputs:diffuseColor.connect = </Materials/plasticSurface/tint.outputs:pxrMaterialOut_diffuseColor>",
        "color3f outputs:pxrMaterialOut_diffuseColor",
        "uniform token info:id = \"PxrSurface\"",
    ] {
        assert!(text.contains(line), "{line}:\n{text}");
    }
    // Resolved: the vstruct head's placeholder is gone.
    assert!(!text.contains("inputs:inputMaterial"), "{text}");
    // An int given for a declared float is written as the float the definition declares;
    // a parameter the definition does not declare keeps its own type.
    let mut net = Network::new();
    let s = net.add_node_of_kind("s", "PxrSurface", vstructc::network::RequestKind::Bxdf);
    net.set_param(s, "diffuseGain", vstructc::Value::Int(1));
    net.set_param(s, "madeUp", vstructc::Value::Int(2));
    let m = net.add_material("m");
    net.set_terminal(m, "surface", s, None);
    let mut usda = Vec::new();
    write_usd(&net, &reg, UsdMode::Flatten, "usda", &mut usda).unwrap();
    let text = String::from_utf8(usda).unwrap();
    assert!(text.contains("float inputs:diffuseGain = 1\n"), "{text}");
    assert!(text.contains("int inputs:madeUp = 2\n"), "{text}");
}

/// Handles that are not USD identifiers are made into prim names, distinct ones kept
/// distinct.
#[test]
fn handles_become_prim_names() {
    let reg = Registry::embedded();
    let rib = br#"Pattern "PxrLayer" "3 coat:a" "int enableDiffuse" [1]
Pattern "PxrLayer" "3 coat-a" "int enableDiffuse" [0]
Pattern "PxrLayerMixer" "mix" "reference vstruct baselayer" ["3 coat:a:pxrMaterialOut"]
    "reference vstruct layer1" ["3 coat-a:pxrMaterialOut"]
Bxdf "PxrLayerSurface" "my surface" "reference float inputMaterial" ["mix:pxrMaterialOut"]
"#;
    let net = read_rib(rib, "h.rib", &reg);
    let mut usda = Vec::new();
    write_usd(&net, &reg, UsdMode::Flatten, "usda", &mut usda).unwrap();
    let text = String::from_utf8(usda).unwrap();
    assert!(text.contains("def Material \"my_surface\""), "{text}");
    assert!(text.contains("def Shader \"_3_coat_a\""), "{text}");
    assert!(text.contains("def Shader \"_3_coat_a_2\""), "{text}");
    let (back, diags) = read_usd(text.as_bytes(), "h.usda", &reg);
    assert!(diags.is_empty(), "{diags:#?}");
    assert_eq!(back.node_count(), 4);
    assert_eq!(canon(&back).len(), 4);
}

#[test]
fn time_samples_give_the_default_and_one_warning() {
    let reg = Registry::embedded();
    let text = br#"#usda 1.0
def Material "M" {
    def Shader "L" {
        uniform token info:id = "PxrLayer"
        float inputs:diffuseGain = 0.25
        float inputs:diffuseGain.timeSamples = { 1: 0.5, 2: 0.75 }
        float inputs:specularGain.timeSamples = { 1: 0.5 }
    }
}
"#;
    let (net, diags) = read_usd(text, "t.usda", &reg);
    let l = net.find("/M/L").unwrap();
    assert_eq!(
        net.value(l, "diffuseGain"),
        Some(&vstructc::Value::Float(0.25))
    );
    assert_eq!(net.value(l, "specularGain"), None);
    let w: Vec<_> = diags.iter().filter(|d| d.code == "US004").collect();
    assert_eq!(w.len(), 1, "{diags:#?}");
    assert!(w[0].message.contains("2 input(s)"), "{}", w[0].message);
}

#[test]
fn shaders_without_an_id_are_kept_as_unknown_nodes() {
    let reg = Registry::embedded();
    let text = br#"#usda 1.0
def Material "M" {
    def Shader "Osl" {
        uniform token info:implementationSource = "sourceAsset"
        uniform asset info:osl:sourceAsset = @noise.osl@
    }
    def Shader "Bare" {
    }
}
"#;
    let (net, diags) = read_usd(text, "u.usda", &reg);
    assert_eq!(net.node_count(), 2);
    assert_eq!(net[net.find("/M/Osl").unwrap()].shader(), "(sourceAsset)");
    let w: Vec<String> = diags
        .iter()
        .filter(|d| d.code == "US003")
        .map(|d| d.to_string())
        .collect();
    assert_eq!(w.len(), 2, "{diags:#?}");
    insta::assert_snapshot!(w.join("\n"));
}

#[test]
fn dangling_connections_unknown_types_and_bad_references_are_warnings() {
    let reg = Registry::embedded();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("bad.usda");
    let text = br#"#usda 1.0
def Material "M" {
    token outputs:ri:surface.connect = </M/S.outputs:out>
    def Shader "S" (
        references = @missing.usda@</Lib/S>
    ) {
        uniform token info:id = "PxrSurface"
        color3f inputs:diffuseColor.connect = </Nowhere/X.outputs:c>
        quatf inputs:diffuseGain = (1, 0, 0, 0)
    }
}
"#;
    std::fs::write(&path, text).unwrap();
    let (net, diags) = read_usd(text, path.to_str().unwrap(), &reg);
    let s = net.find("/M/S").unwrap();
    let links = net.connections(s, "diffuseColor");
    assert_eq!(links.len(), 1);
    assert_eq!(links[0].missing_handle(), Some("/Nowhere/X"));
    assert_eq!(net.value(s, "diffuseGain"), None);
    let codes: Vec<&str> = diags.iter().map(|d| d.code.as_str()).collect();
    assert!(codes.contains(&"US006"), "{diags:#?}");
    let us002 = diags.iter().filter(|d| d.code == "US002").count();
    assert!(
        us002 >= 2,
        "the dangling connection and the missing layer: {diags:#?}"
    );
    for d in diags.iter() {
        assert!(d.location.is_some(), "{d:?}");
    }
}

#[test]
fn unreadable_stages_are_errors_not_panics() {
    let reg = Registry::embedded();
    for (name, bytes) in [
        ("a.usda", &b"#usda 1.0\ndef Material \"M\" {"[..]),
        ("b.usdc", &b"PXR-USDC\0\0\0\0"[..]),
        ("c.usdz", &b"PK\x03\x04 not a zip"[..]),
        (
            "<stdin>",
            &b"#usda 1.0\ndef Shader \"S\" { float inputs:x = }"[..],
        ),
    ] {
        let mut diags = Diagnostics::new();
        let e = parse_usd(bytes, name, &reg, &Limits::default(), &mut diags).unwrap_err();
        assert_eq!(e.code(), Some("US001"), "{name}: {e}");
    }
}

/// Standard input (no extension) and a package held only in memory read as files do.
#[test]
fn stages_read_from_memory() {
    let reg = Registry::embedded();
    let layered = std::fs::read(usd_dir().join("layered.usdz")).unwrap();
    let (from_stdin, diags) = read_usd(&layered, "<stdin>", &reg);
    assert!(diags.is_empty(), "{diags:#?}");
    let (from_file, _) = read_usd(&layered, "somewhere/else.usdz", &reg);
    assert_eq!(canon(&from_stdin), canon(&from_file));
    assert_eq!(from_stdin.node_count(), 4);
}

/// `layered.usdc` and `layered.usdz` are `layered.usda` written by Pixar's USD
/// (`make_binaries.py`).
#[test]
fn binary_corpus_files_are_the_layered_look() {
    let dir = usd_dir();
    let reg = Registry::embedded();
    let want = canon(&resolved_usd("layered.usda", &reg, true));
    for f in ["layered.usdc", "layered.usdz"] {
        let bytes = std::fs::read(dir.join(f)).unwrap();
        assert!(bytes.starts_with(b"PXR-USDC") || bytes.starts_with(b"PK\x03\x04"));
        assert_eq!(canon(&resolved_usd(f, &reg, true)), want, "{f}");
    }
}

/// A layer that composes nothing is read directly, without composing a stage; that reading
/// gives exactly the network and diagnostics the composed stage gives. Layers with
/// sublayers, references, variants, overs or classes are composed.
#[test]
fn layers_read_alone_match_the_composed_stage() {
    let reg = Registry::embedded();
    let mut inputs: Vec<(String, Vec<u8>)> = Vec::new();
    for name in [
        "chain.usda",
        "layered.usda",
        "layered.usdc",
        "layered.usdz",
        "nodegraph.usda",
        "override.usda",
        "library_look.usda",
        "variants.usda",
    ] {
        let path = usd_dir().join(name);
        let bytes = std::fs::read(&path).unwrap();
        inputs.push((path.to_str().unwrap().to_string(), bytes));
    }
    for example in ["chain.rib", "layered.rib", "override.rib"] {
        let path = common::repo_dir().join("examples").join(example);
        let net = read_rib(&std::fs::read(&path).unwrap(), example, &reg);
        let mut usda = Vec::new();
        write_usd(&net, &reg, UsdMode::Flatten, "usda", &mut usda).unwrap();
        inputs.push((format!("{example}.usda"), usda));
        let mut usdc = Vec::new();
        write_usd(&net, &reg, UsdMode::Flatten, "usdc", &mut usdc).unwrap();
        inputs.push((format!("{example}.usdc"), usdc));
    }
    // Time samples, a value block, an asset, a dangling connection, a shader without an
    // id, a node-graph port with a value: read alone too.
    let odd = br#"#usda 1.0
def Material "M" {
    token outputs:ri:surface.connect = </M/G.outputs:out>
    def NodeGraph "G" {
        token outputs:out.connect = </M/S.outputs:out>
        float inputs:k = 2
    }
    def Shader "S" {
        uniform token info:id = "PxrSurface"
        float inputs:specularRoughness.timeSamples = { 1: 0.1, 2: 0.2 }
        float inputs:presence = None
        asset inputs:diffuseColorTexture = @tex.png@
        float inputs:diffuseGain.connect = </M/G.inputs:k>
        color3f inputs:diffuseColor.connect = </Nowhere.outputs:resultRGB>
        token outputs:out
    }
    def Shader "N" {
        token outputs:out
    }
}
"#;
    inputs.push(("odd.usda".to_string(), odd.to_vec()));
    // The same layer as a crate file: read alone by the crate reader.
    let odd_layer = openusd::usda::parse(std::str::from_utf8(odd).unwrap()).unwrap();
    let mut odd_usdc = std::io::Cursor::new(Vec::new());
    openusd::usdc::CrateWriter::write(&odd_layer, &mut odd_usdc).unwrap();
    inputs.push(("odd.usdc".to_string(), odd_usdc.into_inner()));
    // An inactive prim, a class inherited by a material, an over: composed.
    let arcs = br#"#usda 1.0
class Material "Base" {
    token outputs:ri:surface.connect = </Base/S.outputs:out>
    def Shader "S" {
        uniform token info:id = "PxrSurface"
        token outputs:out
    }
}
def Material "M" (inherits = </Base>) {
}
def Material "Off" (active = false) {
    def Shader "T" {
        uniform token info:id = "PxrSurface"
    }
}
over "Nothing" {
    def Shader "U" {
        uniform token info:id = "PxrSurface"
    }
}
"#;
    inputs.push(("arcs.usda".to_string(), arcs.to_vec()));
    // A class and an over, with nothing else that composes: composed.
    let overs = br#"#usda 1.0
def Material "M" {
    token outputs:ri:surface.connect = </M/S.outputs:out>
    def Shader "S" {
        uniform token info:id = "PxrSurface"
        token outputs:out
    }
}
class "C" {
    def Shader "T" {
        uniform token info:id = "PxrSurface"
    }
}
over "O" {
    def Shader "U" {
        uniform token info:id = "PxrSurface"
    }
}
"#;
    inputs.push(("overs.usda".to_string(), overs.to_vec()));
    // An inactive prim alone: composed.
    let inactive = br#"#usda 1.0
def Material "M" {
    token outputs:ri:surface.connect = </M/S.outputs:out>
    def Shader "S" {
        uniform token info:id = "PxrSurface"
        token outputs:out
    }
}
def Scope "Off" (active = false) {
    def Shader "V" {
        uniform token info:id = "PxrSurface"
    }
}
"#;
    inputs.push(("inactive.usda".to_string(), inactive.to_vec()));
    let mut alone = Vec::new();
    for (name, bytes) in &inputs {
        if reads_layer_alone(bytes, name) {
            alone.push(name.rsplit('/').next().unwrap().to_string());
        }
        assert_read_alone_as_composed(bytes, name, &reg);
    }
    assert_eq!(
        alone,
        [
            "chain.usda",
            "layered.usda",
            "layered.usdc",
            "nodegraph.usda",
            "override.usda",
            "chain.rib.usda",
            "chain.rib.usdc",
            "layered.rib.usda",
            "layered.rib.usdc",
            "override.rib.usda",
            "override.rib.usdc",
            "odd.usda",
            "odd.usdc",
        ]
    );
}

/// `parse_usd` (which reads a layer alone when nothing in it composes) gives the network
/// and diagnostics the composed stage gives.
fn assert_read_alone_as_composed(bytes: &[u8], name: &str, reg: &Registry) {
    let mut d1 = Diagnostics::new();
    let direct = parse_usd(bytes, name, reg, &Limits::default(), &mut d1).unwrap();
    let mut d2 = Diagnostics::new();
    let composed = parse_usd_composed(bytes, name, reg, &Limits::default(), &mut d2).unwrap();
    assert_eq!(format!("{direct:?}"), format!("{composed:?}"), "{name}");
    assert_eq!(d1, d2, "{name}");
}

/// The crate files the USD writer makes of `materials` generated layered materials, and of
/// the RIB examples.
fn generated_crate_files(reg: &Registry, materials: usize) -> Vec<(String, Vec<u8>)> {
    let mut out = Vec::new();
    let scene = vstructc_testkit::testgen::layered_scene(materials).into_bytes();
    let mut inputs = vec![("scene.rib".to_string(), scene)];
    for example in ["chain.rib", "layered.rib", "override.rib"] {
        let path = common::repo_dir().join("examples").join(example);
        inputs.push((example.to_string(), std::fs::read(&path).unwrap()));
    }
    for (name, rib) in inputs {
        let net = read_rib(&rib, &name, reg);
        let mut usdc = Vec::new();
        write_usd(&net, reg, UsdMode::Flatten, "usdc", &mut usdc).unwrap();
        out.push((format!("{name}.usdc"), usdc));
    }
    out
}

/// A large generated crate file is read alone, and that reading gives exactly the network
/// and diagnostics the composed stage gives.
#[test]
fn generated_crate_files_read_alone_match_the_composed_stage() {
    let reg = Registry::embedded();
    for (name, bytes) in generated_crate_files(&reg, 40) {
        assert!(reads_layer_alone(&bytes, &name), "{name}");
        assert_read_alone_as_composed(&bytes, &name, &reg);
    }
}

/// `bytes` (a crate file whose table of contents ends it) with a second table-of-contents
/// entry for its first section: `openusd` takes the first, the reader's own decoding of
/// the tables refuses the file, so that `openusd` reads its tables.
fn with_a_second_entry(bytes: &[u8]) -> Vec<u8> {
    let toc = u64::from_le_bytes(bytes[16..24].try_into().unwrap()) as usize;
    let count = u64::from_le_bytes(bytes[toc..toc + 8].try_into().unwrap()) as usize;
    assert_eq!(
        toc + 8 + count * 32,
        bytes.len(),
        "the table of contents ends the file"
    );
    let mut out = bytes.to_vec();
    out[toc..toc + 8].copy_from_slice(&(count as u64 + 1).to_le_bytes());
    out.extend_from_slice(&bytes[toc + 8..toc + 40]);
    out
}

/// Crate files whose tables the reader does not decode itself (`openusd` reads them) read
/// alone as the composed stage reads them.
#[test]
fn crate_files_read_through_openusd_match_the_composed_stage() {
    let reg = Registry::embedded();
    for (name, bytes) in generated_crate_files(&reg, 5) {
        let bytes = with_a_second_entry(&bytes);
        assert_eq!(
            crate_values_agree(&bytes),
            Err("the tables are not decoded here".to_string()),
            "{name}"
        );
        assert!(reads_layer_alone(&bytes, &name), "{name}");
        assert_read_alone_as_composed(&bytes, &name, &reg);
    }
}

/// A crate file with one byte changed, anywhere, or cut short: when the reader decodes its
/// tables itself, `openusd` reads the same tables and the same values from it (the reader
/// accepts no damage that `openusd` refuses); else `openusd` reads it, as before.
#[test]
fn damaged_crate_files_decode_as_openusd_reads_them() {
    let reg = Registry::embedded();
    let (name, bytes) = generated_crate_files(&reg, 2).remove(0);
    let mut decoded = 0;
    let mut refused = 0;
    for i in 0..bytes.len() {
        let mut damaged = vec![bytes[..i].to_vec()];
        for x in [0x01u8, 0x80, 0xff] {
            let mut b = bytes.clone();
            b[i] ^= x;
            damaged.push(b);
        }
        for b in damaged {
            match crate_values_agree(&b) {
                Ok(_) => decoded += 1,
                Err(e) if e == "the tables are not decoded here" => refused += 1,
                Err(e) => panic!("{name}, byte {i}: {e}"),
            }
        }
    }
    assert!(
        decoded > 0 && refused > 0,
        "{decoded} decoded, {refused} refused"
    );
}

/// The values the crate reader decodes itself (tokens, token arrays and vectors) equal
/// `openusd`'s decoding of the same fields, in the corpus's crate file and generated ones;
/// a corrupt or truncated file is refused, not a panic.
#[test]
fn crate_token_values_match_openusd() {
    let reg = Registry::embedded();
    let mut files = generated_crate_files(&reg, 10);
    files.push((
        "layered.usdc".to_string(),
        std::fs::read(usd_dir().join("layered.usdc")).unwrap(),
    ));
    for (name, bytes) in &files {
        let n = crate_values_agree(bytes).unwrap_or_else(|e| panic!("{name}: {e}"));
        assert!(n > 0, "{name}");
        // Cut short, or with a byte changed here and there: refused or read, never a
        // panic.
        for cut in [bytes.len() / 2, bytes.len() - 1] {
            let _ = crate_values_agree(&bytes[..cut]);
        }
        let mut bad = bytes.clone();
        for i in (0..bad.len()).step_by(97) {
            bad[i] ^= 0x5a;
        }
        let _ = crate_values_agree(&bad);
        let mut d = Diagnostics::new();
        let _ = parse_usd(&bad, name, &reg, &Limits::default(), &mut d);
    }
}

/// Materials as comparable text: name, terminals and the prim path each leads to.
fn terminals(net: &Network) -> Vec<String> {
    net.materials()
        .iter()
        .flat_map(|m| {
            m.terminals.iter().map(move |t| {
                let to = match t.link.upstream_node() {
                    Some(id) => net[id].handle().to_string(),
                    None => format!("missing {}", t.link.missing_handle().unwrap_or("")),
                };
                format!("{} {} {to}", m.name, t.name)
            })
        })
        .collect()
}

fn handles(net: &Network) -> Vec<String> {
    net.nodes_sorted()
        .into_iter()
        .map(|id| format!("{} {}", net[id].handle(), net[id].shader()))
        .collect()
}

/// Resolves the stage at `path` and writes it flattened and as an override layer over
/// `path` (sublayered by its absolute path, the layer written in `dir`); returns both read
/// back, and the override layer's text.
fn flat_and_over(
    path: &std::path::Path,
    reg: &Registry,
    conditions: bool,
    dir: &std::path::Path,
) -> (Network, Network, String) {
    let name = path.to_str().unwrap();
    let (mut net, _) = read_usd(&std::fs::read(path).unwrap(), name, reg);
    resolve(&mut net, reg, &options(conditions));
    let mut flat = Vec::new();
    write_usd(&net, reg, UsdMode::Flatten, "usda", &mut flat).unwrap();
    let over = over_layer(&net, reg, name, "usda");
    let over_path = dir.join("over.usda");
    std::fs::write(&over_path, &over).unwrap();
    let (flat_back, diags) = read_usd(&flat, "flat.usda", reg);
    assert!(diags.is_empty(), "{name}: {diags:#?}");
    let (over_back, diags) = read_usd(&over, over_path.to_str().unwrap(), reg);
    let text = String::from_utf8(over).unwrap();
    assert!(diags.is_empty(), "{name}: {diags:#?}\n{text}");
    (flat_back, over_back, text)
}

/// The override layer composed with its input (through its sublayer) reads as exactly the
/// network the flattened layer holds: same prims, values, connections and terminals, for
/// every look of the corpus, conditions on and off.
#[test]
fn override_layers_compose_to_the_flattened_output() {
    let reg = Registry::embedded();
    let dir = tempfile::tempdir().unwrap();
    for conditions in [true, false] {
        for &(usd, _) in PAIRS {
            let (flat, over, text) =
                flat_and_over(&usd_dir().join(usd), &reg, conditions, dir.path());
            let at = format!("{usd}, conditions {conditions}:\n{text}");
            assert_eq!(handles(&over), handles(&flat), "{at}");
            assert_eq!(canon(&over), canon(&flat), "{at}");
            assert_eq!(terminals(&over), terminals(&flat), "{at}");
            // Each look has vstruct heads to resolve: the layer overrides something.
            assert!(text.contains("over \""), "{at}");
            assert!(text.contains(".connect = None"), "{at}");
        }
    }
}

/// The binary encodings read back as the text layer does: every corpus look, resolved
/// (conditions on and off), written flattened as `usda`, `usdc` and `usdz`, and as an
/// override layer in `usdc` composed over its input, gives the same prims, values,
/// connections and terminals; so does every bundled RIB example written as `usdc`.
#[test]
fn binary_outputs_read_back_as_the_text_layer() {
    let reg = Registry::embedded();
    let dir = tempfile::tempdir().unwrap();
    let check = |net: &Network, back: &Network, at: &str| {
        assert_eq!(handles(back), handles(net), "{at}");
        assert_eq!(canon(back), canon(net), "{at}");
        assert_eq!(terminals(back), terminals(net), "{at}");
    };
    for conditions in [true, false] {
        for &(usd, _) in PAIRS {
            let path = usd_dir().join(usd);
            let name = path.to_str().unwrap();
            let (mut net, _) = read_usd(&std::fs::read(&path).unwrap(), name, &reg);
            resolve(&mut net, &reg, &options(conditions));
            for encoding in ["usda", "usdc", "usdz"] {
                let mut out = Vec::new();
                write_usd(&net, &reg, UsdMode::Flatten, encoding, &mut out).unwrap();
                let at = format!("{usd} as {encoding}, conditions {conditions}");
                let signature: &[u8] = match encoding {
                    "usda" => b"#usda 1.0",
                    "usdc" => b"PXR-USDC",
                    _ => b"PK\x03\x04",
                };
                assert!(out.starts_with(signature), "{at}");
                let (back, diags) = read_usd(&out, &format!("out.{encoding}"), &reg);
                assert!(diags.is_empty(), "{at}: {diags:#?}");
                check(&net, &back, &at);
            }
            let over = over_layer(&net, &reg, name, "usdc");
            let over_path = dir.path().join("over.usdc");
            std::fs::write(&over_path, &over).unwrap();
            let (back, diags) = read_usd(&over, over_path.to_str().unwrap(), &reg);
            let at = format!("{usd} as a usdc override layer, conditions {conditions}");
            assert!(diags.is_empty(), "{at}: {diags:#?}");
            check(&net, &back, &at);
        }
    }
    for example in ["chain.rib", "layered.rib", "override.rib"] {
        let net = resolved_rib(example, &reg, true);
        let mut usda = Vec::new();
        write_usd(&net, &reg, UsdMode::Flatten, "usda", &mut usda).unwrap();
        let (want, _) = read_usd(&usda, "out.usda", &reg);
        let mut usdc = Vec::new();
        write_usd(&net, &reg, UsdMode::Flatten, "usdc", &mut usdc).unwrap();
        let (back, diags) = read_usd(&usdc, "out.usdc", &reg);
        assert!(diags.is_empty(), "{example}: {diags:#?}");
        check(&want, &back, example);
    }
}

/// The override layer of `net` over the layer `name`, in `encoding`.
fn over_layer(net: &Network, reg: &Registry, name: &str, encoding: &str) -> Vec<u8> {
    let mut over = Vec::new();
    write_usd(
        net,
        reg,
        UsdMode::Over { sublayer: name },
        encoding,
        &mut over,
    )
    .unwrap();
    over
}

/// The crate files written store prim and property children as token vectors and sublayers
/// as a string vector, the types Pixar's USD requires (it rejects a `primChildren` value of
/// another type), never as token or string arrays; `usdz` packages hold such a file.
#[test]
fn crate_files_store_children_as_pixar_requires() {
    use openusd::usdc::CrateFile;
    const TOKEN_VECTOR: u64 = 41;
    const STRING_VECTOR: u64 = 50;
    let reg = Registry::embedded();
    let path = usd_dir().join("nodegraph.usda");
    let name = path.to_str().unwrap();
    let (mut net, _) = read_usd(&std::fs::read(&path).unwrap(), name, &reg);
    resolve(&mut net, &reg, &options(true));
    let mut flat = Vec::new();
    write_usd(&net, &reg, UsdMode::Flatten, "usdc", &mut flat).unwrap();
    let over = over_layer(&net, &reg, name, "usdc");
    let mut package = Vec::new();
    write_usd(&net, &reg, UsdMode::Flatten, "usdz", &mut package).unwrap();
    // The package's one file: stored uncompressed, its data 64-byte aligned (a zip local
    // header: method at 8, sizes at 18 and 22, name and extra lengths at 26 and 28).
    let packaged = {
        let u16_at = |at: usize| u16::from_le_bytes([package[at], package[at + 1]]) as usize;
        let u32_at = |at: usize| u32::from_le_bytes(package[at..at + 4].try_into().unwrap());
        assert!(package.starts_with(b"PK\x03\x04"));
        assert_eq!(u16_at(8), 0, "stored");
        let name_len = u16_at(26);
        assert_eq!(&package[30..30 + name_len], b"layer.usdc");
        let start = 30 + name_len + u16_at(28);
        assert_eq!(start % 64, 0, "aligned");
        let len = u32_at(18) as usize;
        assert_eq!(u32_at(22) as usize, len);
        package[start..start + len].to_vec()
    };
    for (what, bytes) in [("flat", &flat), ("over", &over), ("usdz", &packaged)] {
        let file = CrateFile::open(std::io::Cursor::new(bytes.as_slice())).unwrap();
        let mut seen = BTreeMap::new();
        for f in &file.fields {
            let name = file.tokens[f.token_index].as_str();
            let rep = f.value_rep.0;
            let (ty, array) = ((rep >> 48) & 0xff, rep >> 63 == 1);
            let want = match name {
                "primChildren" | "properties" => TOKEN_VECTOR,
                "subLayers" => STRING_VECTOR,
                _ => continue,
            };
            assert_eq!((ty, array), (want, false), "{what}: {name}");
            *seen.entry(name).or_insert(0) += 1;
        }
        assert!(
            seen.get("primChildren").is_some_and(|&n| n >= 3),
            "{what}: {seen:?}"
        );
        assert!(seen.contains_key("properties"), "{what}: {seen:?}");
        assert_eq!(
            seen.contains_key("subLayers"),
            what == "over",
            "{what}: {seen:?}"
        );
    }
}

/// An encoding other than `usda`, `usdc` and `usdz` is an invalid-input error.
#[test]
fn unknown_usd_encodings_are_refused() {
    let reg = Registry::embedded();
    let net = resolved_rib("chain.rib", &reg, true);
    let mut out = Vec::new();
    let e = write_usd(&net, &reg, UsdMode::Flatten, "usdx", &mut out).unwrap_err();
    assert_eq!(e.kind(), std::io::ErrorKind::InvalidInput);
    assert!(e.to_string().contains("usdx"), "{e}");
    assert!(out.is_empty());
}

/// A look resolution does not change gives an override layer without prims; a look with
/// untouched nodes and inputs gives a layer that does not mention them.
#[test]
fn override_layers_hold_only_what_resolution_changed() {
    let reg = Registry::embedded();
    let dir = tempfile::tempdir().unwrap();
    let plain = dir.path().join("plain.usda");
    std::fs::write(
        &plain,
        br#"#usda 1.0
def Material "M" {
    token outputs:ri:surface.connect = </M/S.outputs:out>
    def Shader "S" {
        uniform token info:id = "PxrSurface"
        float inputs:diffuseGain = 0.5
        color3f inputs:diffuseColor.connect = </M/T.outputs:resultRGB>
        token outputs:out
    }
    def Shader "T" {
        uniform token info:id = "PxrTexture"
        asset inputs:filename = @wood.tex@
        color3f outputs:resultRGB
    }
}
"#,
    )
    .unwrap();
    let (flat, over, text) = flat_and_over(&plain, &reg, true, dir.path());
    assert!(!text.contains("over") && !text.contains("def"), "{text}");
    assert!(text.contains("subLayers"), "{text}");
    assert_eq!(canon(&over), canon(&flat));
    // override.usda: the tint layer is untouched, and so are the surface's direct connection
    // (it wins over the expansion) and the plastic layer's values; the surface's head is
    // neutralised and its members connected.
    let (flat, over, text) =
        flat_and_over(&usd_dir().join("override.usda"), &reg, true, dir.path());
    assert_eq!(canon(&over), canon(&flat));
    for absent in [
        "tint",
        "inputs:diffuseColor",
        "inputs:enableDiffuse",
        "inputs:specularGain",
        "info:id",
        "outputs:ri:",
        "def ",
    ] {
        assert!(!text.contains(absent), "{absent}:\n{text}");
    }
    for present in [
        "over \"plasticSurface\"",
        "token inputs:inputMaterial = None",
        "token inputs:inputMaterial.connect = None",
        "float inputs:diffuseGain.connect = </plasticSurface/plastic.outputs:pxrMaterialOut_diffuseGain>",
        "float outputs:pxrMaterialOut_diffuseGain",
    ] {
        assert!(text.contains(present), "{present}:\n{text}");
    }
    // The layer sublayers the input by the path it was given.
    let name = usd_dir().join("override.usda");
    assert!(
        text.contains(&format!("@{}@", name.to_str().unwrap())),
        "{text}"
    );
}

/// A resolved head whose input also holds a value (hidden by its connection) composes to
/// nothing; a value that replaces an authored connection is written with an empty
/// connection list, a connection that replaces an authored value as the connection alone,
/// and a node the input does not hold in full; a network not read from USD has no override
/// layer.
#[test]
fn override_layers_replace_values_connections_and_add_nodes() {
    let reg = Registry::embedded();
    let dir = tempfile::tempdir().unwrap();
    let look = dir.path().join("look.usda");
    std::fs::write(
        &look,
        br#"#usda 1.0
def Material "M" {
    token outputs:ri:surface.connect = </M/S.outputs:out>
    def Shader "S" {
        uniform token info:id = "PxrSurface"
        float inputs:diffuseGain = 0.5
        float inputs:presence = 0.5
        color3f inputs:diffuseColor.connect = </M/T.outputs:resultRGB>
        token inputs:inputMaterial = "a value the connection hides"
        token inputs:inputMaterial.connect = </M/L.outputs:pxrMaterialOut>
        token outputs:out
    }
    def Shader "T" {
        uniform token info:id = "PxrTexture"
        color3f outputs:resultRGB
    }
    def Shader "L" {
        uniform token info:id = "PxrLayer"
        int inputs:enableDiffuse = 1
        token outputs:pxrMaterialOut
    }
}
"#,
    )
    .unwrap();
    let name = look.to_str().unwrap();
    let (mut net, _) = read_usd(&std::fs::read(&look).unwrap(), name, &reg);
    resolve(&mut net, &reg, &options(true));
    let s = net.find("/M/S").unwrap();
    let t = net.find("/M/T").unwrap();
    net.clear_connections(s, "diffuseColor");
    net.set_param(
        s,
        "diffuseColor",
        vstructc::Value::Triple(vstructc::BaseType::Color, [0.1, 0.2, 0.3]),
    );
    net.connect(s, "presence", t, "resultR");
    let n = net.add_node("/M/N", "PxrTexture");
    net.set_param(n, "filename", vstructc::Value::Asset("n.tex".into()));
    net.connect(s, "specularGain", n, "resultR");
    let over = over_layer(&net, &reg, name, "usda");
    let text = String::from_utf8(over.clone()).unwrap();
    for present in [
        "color3f inputs:diffuseColor = (0.1, 0.2, 0.3)",
        "color3f inputs:diffuseColor.connect = None",
        "float inputs:presence.connect = </M/T.outputs:resultR>",
        "float inputs:diffuseGain.connect = </M/L.outputs:pxrMaterialOut_diffuseGain>",
        "def Shader \"N\"",
        "asset inputs:filename = @n.tex@",
        "token inputs:inputMaterial = None",
        "token inputs:inputMaterial.connect = None",
    ] {
        assert!(text.contains(present), "{present}:\n{text}");
    }
    assert!(!text.contains("inputs:diffuseGain = "), "{text}");
    assert!(!text.contains("inputs:presence = "), "{text}");
    let over_path = dir.path().join("over.usda");
    std::fs::write(&over_path, &over).unwrap();
    let (back, diags) = read_usd(&over, over_path.to_str().unwrap(), &reg);
    assert!(diags.is_empty(), "{diags:#?}");
    let mut flat = Vec::new();
    write_usd(&net, &reg, UsdMode::Flatten, "usda", &mut flat).unwrap();
    let (flat, _) = read_usd(&flat, "flat.usda", &reg);
    assert_eq!(canon(&back), canon(&flat), "{text}");
    // Not read from USD: an error, nothing written.
    let rib = resolved_rib("override.rib", &reg, true);
    let mut out = Vec::new();
    let e = write_usd(
        &rib,
        &reg,
        UsdMode::Over { sublayer: "x.usda" },
        "usda",
        &mut out,
    )
    .unwrap_err();
    assert_eq!(e.kind(), std::io::ErrorKind::InvalidInput);
    assert!(out.is_empty());
}

/// The flattened layer of a network read from USD keeps the types the input gives the prims
/// that are neither materials nor shaders: the NodeGraph wrapper, scopes, transforms,
/// untyped prims.
#[test]
fn the_flattened_layer_keeps_the_input_prim_types() {
    let reg = Registry::embedded();
    let path = usd_dir().join("nodegraph.usda");
    let bytes = std::fs::read(&path).unwrap();
    let name = path.to_str().unwrap();
    let (mut net, _) = read_usd(&bytes, name, &reg);
    resolve(&mut net, &reg, &options(true));
    let mut out = Vec::new();
    write_usd(
        &net,
        &reg,
        UsdMode::FlattenFrom {
            name,
            bytes: &bytes,
        },
        "usda",
        &mut out,
    )
    .unwrap();
    let text = String::from_utf8(out).unwrap();
    assert!(text.contains("def Scope \"Looks\""), "{text}");
    assert!(text.contains("    def NodeGraph \"coat\""), "{text}");
    let text_of = |usda: &[u8]| -> String {
        let (mut net, _) = read_usd(usda, "t.usda", &reg);
        resolve(&mut net, &reg, &options(true));
        let mut out = Vec::new();
        write_usd(
            &net,
            &reg,
            UsdMode::FlattenFrom {
                name: "t.usda",
                bytes: usda,
            },
            "usda",
            &mut out,
        )
        .unwrap();
        String::from_utf8(out).unwrap()
    };
    // Other types and an untyped prim, outside and inside the material.
    let text = text_of(
        br#"#usda 1.0
def Xform "World" {
    def "Looks" {
        def Material "M" {
            token outputs:ri:surface.connect = </World/Looks/M/G/S.outputs:out>
            def Scope "G" {
                def Shader "S" {
                    uniform token info:id = "PxrSurface"
                    token outputs:out
                }
            }
        }
    }
}
"#,
    );
    for head in [
        "def Xform \"World\"",
        "\n    def \"Looks\"",
        "def Material \"M\"",
        "def Scope \"G\"",
        "def Shader \"S\"",
    ] {
        assert!(text.contains(head), "{head}:\n{text}");
    }
    // Without the input: the writer's own choice.
    let (net, _) = read_usd(text.as_bytes(), "t.usda", &reg);
    let mut out = Vec::new();
    write_usd(&net, &reg, UsdMode::Flatten, "usda", &mut out).unwrap();
    let plain = String::from_utf8(out).unwrap();
    assert!(plain.contains("def Scope \"World\""), "{plain}");
    assert!(plain.contains("def NodeGraph \"G\""), "{plain}");
}

proptest::proptest! {
    #![proptest_config(proptest::prelude::ProptestConfig::with_cases(2000))]

    /// The reader's own split of a connection target into prim and property is `openusd`'s,
    /// for any text made of path characters (variant selections, targets, dots, namespaces
    /// and non-ASCII letters included).
    #[test]
    fn property_paths_split_as_openusd_splits_them(
        text in "[/./A-Ba-c0-9_:{}=\\[\\]é-]{0,14}",
    ) {
        let path = openusd::sdf::Path::from(text.as_str());
        let ours = vstructc::front::usd::split_property(&path)
            .map(|(prim, name)| (prim.into_owned(), name.to_string()));
        let theirs = path
            .split_property()
            .map(|(prim, name)| (prim.as_str().to_string(), name.to_string()));
        proptest::prop_assert_eq!(ours, theirs, "{}", text);
    }
}

/// The usual connection targets take the reader's own split (and agree with `openusd`'s).
#[test]
fn usual_property_paths_split_at_their_last_element() {
    for (text, prim, name) in [
        (
            "/Mat/Layer.outputs:pxrMaterialOut",
            "/Mat/Layer",
            "outputs:pxrMaterialOut",
        ),
        ("/A.b", "/A", "b"),
        ("/Looks/é1.inputs:x_y", "/Looks/é1", "inputs:x_y"),
    ] {
        let path = openusd::sdf::Path::from(text);
        let (p, n) = vstructc::front::usd::split_property(&path).unwrap();
        assert!(matches!(p, std::borrow::Cow::Borrowed(_)), "{text}");
        assert_eq!((p.as_ref(), n), (prim, name), "{text}");
    }
    for text in [
        "/Mat/Layer",
        "/A.b.c",
        "/A{v=x}.b",
        "/A.rel[/B].c",
        "/A.",
        "/A.b-c",
    ] {
        let path = openusd::sdf::Path::from(text);
        let ours = vstructc::front::usd::split_property(&path)
            .map(|(p, n)| (p.into_owned(), n.to_string()));
        let theirs = path
            .split_property()
            .map(|(p, n)| (p.as_str().to_string(), n.to_string()));
        assert_eq!(ours, theirs, "{text}");
    }
}

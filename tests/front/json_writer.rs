//! JSON writer (formats.md §5.4): canonical form, round trips JSON → JSON, RIB → JSON grouping,
//! JSON → RIB → JSON.

use crate::common::network as network_common;

use network_common::summary;
use vstructc::back::json::write_json;
use vstructc::back::rib::write_rib_to_vec;
use vstructc::front::json::parse_json;
use vstructc::front::rib::{RibOptions, parse_rib};
use vstructc::network::{Network, NoDefinitions};
use vstructc::{Diagnostics, Value};

fn json(text: &str) -> Network {
    let mut d = Diagnostics::new();
    parse_json(text.as_bytes(), "n.json", &NoDefinitions, &mut d)
        .unwrap_or_else(|e| panic!("{e}\n{text}"))
}

fn rib(text: &[u8]) -> Network {
    let mut d = Diagnostics::new();
    parse_rib(
        text,
        "n.rib",
        &NoDefinitions,
        &RibOptions::default(),
        &mut d,
    )
    .unwrap_or_else(|e| panic!("{e}"))
}

const INPUT: &str = r#"{
  "materials": { "Layered SG": {
    "primvars": ["st", "displayColor"],
    "terminals": { "surface": { "upstreamNode": "surf", "upstreamOutputName": "" } },
    "nodes": {
      "surf": { "nodeTypeId": "PxrLayerSurface",
                "inputConnections": { "inputMaterial": [ { "upstreamNode": "mix", "upstreamOutputName": "pxrMaterialOut" } ] } },
      "mix": { "nodeTypeId": "PxrLayerMixer",
               "parameters": { "layer1Mask": { "type": "float", "value": 0.25 },
                               "enableDiffuseAlways": { "type": "int", "value": 1 } },
               "inputConnections": {
                 "layer1": [ { "upstreamNode": "top", "upstreamOutputName": "pxrMaterialOut" } ],
                 "baselayer": [ { "upstreamNode": "base", "upstreamOutputName": "pxrMaterialOut" } ] } },
      "base": { "nodeTypeId": "PxrLayer",
                "parameters": { "diffuseColor": { "type": "color", "value": [0.1, 0.2, 0.30000001] },
                                "label": { "type": "string", "value": "base \"layer\"\n" },
                                "ids": { "type": "int[3]", "value": [1, 2, 3] },
                                "offsets": { "type": "vector[]", "value": [[0, 0, 1], [1e-7, 3.4028235e38, -0.5]] } } },
      "top": { "nodeTypeId": "PxrLayer", "parameters": { "enableClearcoat": { "type": "int", "value": 0 } } }
    } } },
  "vstructcNetwork": 1
}"#;

#[test]
fn canonical_output() {
    let net = json(INPUT);
    let out = write_json(&net).unwrap();
    insta::assert_snapshot!("canonical", out);
    // Reading the output and writing it again gives the same text (a fixed point), and the
    // same network.
    let again = json(&out);
    assert_eq!(write_json(&again).unwrap(), out);
    assert_eq!(summary(&again), summary(&net));
    assert!(out.ends_with("}\n") && !out.ends_with("\n\n"));
    assert!(!out.contains('\t'));
}

#[test]
fn floats_read_back_exactly() {
    let mut net = Network::new();
    let n = net.add_node("n", "X");
    let values = [
        0.1f32,
        1.0 / 3.0,
        1e-7,
        3.402_823_5e38,
        -0.0,
        0.6,
        16_777_217.0,
        1.0,
    ];
    for (i, x) in values.iter().enumerate() {
        net.set_param(n, &format!("f{i}"), Value::Float(*x));
    }
    let m = net.add_material("M");
    net.set_terminal(m, "surface", n, None);
    let out = write_json(&net).unwrap();
    let again = json(&out);
    let n2 = again.find("n").unwrap();
    for (i, x) in values.iter().enumerate() {
        assert_eq!(
            again
                .value(n2, &format!("f{i}"))
                .map(|v| v.numbers()[0].to_bits()),
            Some(x.to_bits()),
            "{x}"
        );
    }
    for text in [
        "0.1",
        "0.33333334",
        "1e-7",
        "3.4028235e38",
        "-0.0",
        "0.6",
        "16777216",
        "1",
    ] {
        assert!(
            out.contains(&format!("\"value\": {text}\n")),
            "{text} not in {out}"
        );
    }
}

const SCENE: &[u8] = br#"Pattern "PxrFractal" "noise" "int layers" [2]
Pattern "PxrFractal" "unused"
Pattern "PxrRemap" "remap" "reference float inputF" ["noise:resultF"]
Pattern "PxrRemap" "remap" "reference float inputF" ["remap:resultF"]
Bxdf "PxrSurface" "red" "reference float diffuseGain" ["remap:resultF"] "string __materialid" ["RedSG"]
Bxdf "PxrDiffuse" "blue" "reference float diffuseGain" ["noise:resultF"] "reference float presence" ["ghost:resultF"]
Displace "PxrDisplace" "bump" "reference float dispScalar" ["noise:resultF"]
Light "PxrDomeLight" "dome" "float intensity" [1.5]
"#;

#[test]
fn rib_to_json_grouping() {
    let net = rib(SCENE);
    let out = write_json(&net).unwrap();
    insta::assert_snapshot!("rib_grouping", out);
    // Every material is readable again; the versions of `remap` in material RedSG are named
    // by key, and `unused` belongs to no material.
    let back = json(&out);
    let names: Vec<&str> = back.materials().iter().map(|m| m.name.as_str()).collect();
    assert_eq!(names, ["RedSG", "blue", "bump", "dome"]);
    assert!(back.find("remap#0").is_some() && back.find("remap#1").is_some());
    assert!(back.find("unused").is_none());
}

#[test]
fn json_to_rib_to_json() {
    let net = json(INPUT);
    let text = write_rib_to_vec(b"", &net, &NoDefinitions).unwrap();
    let mut back = rib(&text);
    // The RIB carries the material name as `__materialid` on the Bxdf.
    let surf = back.find("surf").unwrap();
    assert_eq!(back[surf].material_id(), Some("Layered SG"));
    back.remove_param(surf, "__materialid");
    // RIB has no primvars; put them back to compare the rest.
    back.materials_mut()[0].primvars = net.materials()[0].primvars.clone();
    assert_eq!(write_json(&back).unwrap(), write_json(&net).unwrap());
}

#[test]
fn golden_fixture_to_json() {
    let dir = fixtures_or_skip!();
    let bytes = std::fs::read(dir.join("rib/ldd/pxrLayerSurface.0001.rib")).unwrap();
    let net = rib(&bytes);
    let out = write_json(&net).unwrap();
    let back = json(&out);
    let names: Vec<&str> = back.materials().iter().map(|m| m.name.as_str()).collect();
    // Materials come back in key order.
    assert_eq!(names, ["PxrEnvDayLightShape", "PxrLayerSurface1SG"]);
    let m = &back.materials()[1];
    assert_eq!(
        m.terminals[0].link.upstream_node(),
        back.find("PxrLayerSurface1")
    );
    // Same nodes, values and connections as the RIB network (the light included).
    assert_eq!(summary(&back), summary(&net));
    let mixer = back.find("PxrLayerMixer1").unwrap();
    assert_eq!(back.connected_inputs(mixer).len(), 25);
}

/// A resolved scene's document written in pieces of every size, on one thread and on
/// rayon's pool, is the document of one pass (which `write_json` also gives); an empty
/// network's too.
#[test]
fn pieces_in_parallel_give_the_document_of_one_pass() {
    use vstructc::back::json::write_json_chunked;
    use vstructc::registry::Registry;
    use vstructc::resolve::{ResolveOptions, resolve};
    use vstructc_testkit::testgen::layered_scene;
    let reg = Registry::embedded();
    let mut d = Diagnostics::new();
    let text = layered_scene(50);
    let mut net = parse_rib(
        text.as_bytes(),
        "n.rib",
        &reg,
        &RibOptions::default(),
        &mut d,
    )
    .unwrap();
    resolve(&mut net, &reg, &ResolveOptions::default());
    for net in [net, Network::new()] {
        let mut whole = Vec::new();
        write_json_chunked(&net, &mut whole, usize::MAX, false).unwrap();
        assert!(write_json(&net).unwrap().into_bytes() == whole);
        for materials in [1, 2, 7, 64, 100_000] {
            for parallel in [false, true] {
                let mut out = Vec::new();
                write_json_chunked(&net, &mut out, materials, parallel).unwrap();
                assert!(
                    out == whole,
                    "pieces of {materials} materials, parallel {parallel}: {} bytes, not the \
                     {} of one pass",
                    out.len(),
                    whole.len()
                );
            }
        }
    }
}

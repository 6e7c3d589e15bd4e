//! The RIB reader and writer on the real public RIB files of `../shared/fixtures/rib`.
// Float literals are written exactly as they appear in the fixture files.
#![allow(clippy::excessive_precision)]

use crate::common::network as network_common;

use network_common::{codes, summary};
use std::path::{Path, PathBuf};
use vstructc::back::rib::write_rib_to_vec;
use vstructc::front::rib::{RibOptions, parse_rib};
use vstructc::network::{Link, Network, NoDefinitions, RequestKind, Upstream};
use vstructc::{BaseType, Diagnostics, Value};

fn ribs(dir: &Path) -> Vec<PathBuf> {
    let mut out = Vec::new();
    let mut stack = vec![dir.join("rib")];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                stack.push(p);
            } else if p.extension().is_some_and(|x| x == "rib") {
                out.push(p);
            }
        }
    }
    out.sort();
    assert!(!out.is_empty(), "no RIB fixtures found");
    out
}

fn read(path: &Path) -> (Vec<u8>, Network, Diagnostics) {
    let bytes = std::fs::read(path).unwrap();
    let mut d = Diagnostics::new();
    let net = parse_rib(
        &bytes,
        &path.display().to_string(),
        &NoDefinitions,
        &RibOptions::default(),
        &mut d,
    )
    .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    (bytes, net, d)
}

fn reparse(bytes: &[u8]) -> Network {
    let mut d = Diagnostics::new();
    parse_rib(
        bytes,
        "rewritten.rib",
        &NoDefinitions,
        &RibOptions::default(),
        &mut d,
    )
    .unwrap_or_else(|e| {
        panic!(
            "rewritten RIB does not parse: {e}\n{}",
            String::from_utf8_lossy(bytes)
        )
    })
}

#[test]
fn unmodified_write_is_byte_identical() {
    let dir = fixtures_or_skip!();
    for path in ribs(&dir) {
        let (bytes, net, _) = read(&path);
        let out = write_rib_to_vec(&bytes, &net, &NoDefinitions).unwrap();
        assert!(
            out == bytes,
            "{} changed on an unmodified write",
            path.display()
        );
    }
}

/// Touch every parameter of every node (value set away and back, connections cleared and
/// restored) so that every request is re-serialised, then check that the re-parsed network is
/// the same network.
#[test]
fn full_reserialisation_is_lossless() {
    let dir = fixtures_or_skip!();
    for path in ribs(&dir) {
        let (bytes, mut net, _) = read(&path);
        let before = summary(&net);
        let ids: Vec<_> = net.node_ids().collect();
        for id in &ids {
            let params: Vec<(String, Option<Value>, Vec<Link>)> = net[*id]
                .params()
                .map(|p| {
                    (
                        p.name().to_string(),
                        p.value().cloned(),
                        p.connections().to_vec(),
                    )
                })
                .collect();
            for (name, value, links) in params {
                if let Some(v) = value {
                    net.set_param(*id, &name, Value::Str("placeholder".into()));
                    net.set_param(*id, &name, v);
                }
                if !links.is_empty() {
                    net.clear_connections(*id, &name);
                    net.set_connections(*id, &name, links);
                }
            }
            assert!(
                net[*id].params().next().is_none() || net.is_modified(*id),
                "{} not marked modified",
                net[*id].key()
            );
        }
        let out = write_rib_to_vec(&bytes, &net, &NoDefinitions).unwrap();
        assert_ne!(out, bytes);
        let again = reparse(&out);
        assert_eq!(
            summary(&again),
            before,
            "{} lost information",
            path.display()
        );
        // Pass-through bytes are untouched: the rewritten file keeps every non-shading line.
        let text = String::from_utf8_lossy(&out);
        for line in String::from_utf8_lossy(&bytes).lines() {
            let t = line.trim();
            if t.starts_with("Option") || t.starts_with("Attribute ") || t.starts_with("Transform")
            {
                assert!(
                    text.contains(line),
                    "{}: lost line {line:?}",
                    path.display()
                );
            }
        }
    }
}

#[test]
fn golden_network_parse() {
    let dir = fixtures_or_skip!();
    let (_, net, diags) = read(&dir.join("rib/ldd/pxrLayerSurface.0001.rib"));
    let patterns: Vec<(&str, &str)> = net
        .node_ids()
        .filter(|&i| net[i].kind() != RequestKind::Light)
        .map(|i| (net[i].handle(), net[i].shader()))
        .collect();
    assert_eq!(
        patterns,
        [
            ("PxrFractal1", "PxrFractal"),
            ("PxrLayer2", "PxrLayer"),
            ("PxrThreshold1", "PxrThreshold"),
            ("PxrLayer1", "PxrLayer"),
            ("PxrLayerMixer1", "PxrLayerMixer"),
            ("PxrLayerSurface1", "PxrLayerSurface"),
        ]
    );
    // The trailing `Bxdf ... "string __materialid"` re-uses the node: no second version, no
    // RB017.
    assert_eq!(net.versions("PxrLayerSurface1").len(), 1);
    assert_eq!(diags.count("RB017"), 0, "{:?}", codes(&diags));
    let light = net.find("PxrEnvDayLightShape").unwrap();
    assert_eq!(net[light].kind(), RequestKind::Light);

    let mixer = net.find("PxrLayerMixer1").unwrap();
    let surface = net.find("PxrLayerSurface1").unwrap();
    assert_eq!(net.connected_inputs(mixer).len(), 25);
    assert_eq!(net.connected_inputs(surface).len(), 12);
    let threshold = net.find("PxrThreshold1").unwrap();
    let mask = net.connections(mixer, "layer1Mask");
    assert_eq!(mask, &[Link::node(threshold, Some("resultR"))]);
    let layer2 = net.find("PxrLayer2").unwrap();
    assert_eq!(
        net.connections(mixer, "layer1_diffuseColor"),
        &[Link::node(layer2, Some("pxrMaterialOut_diffuseColor"))]
    );
    // Values of every form.
    assert_eq!(
        net.value(mixer, "layer1_enableClearcoat"),
        Some(&Value::Int(0))
    );
    assert_eq!(
        net.value(surface, "roughSpecularRoughness"),
        Some(&Value::Float(0.600000024))
    );
    assert_eq!(
        net.value(surface, "utilityPattern"),
        Some(&Value::Array(BaseType::Int, vec![Value::Int(0)]))
    );
    assert_eq!(
        net.value(surface, "subsurfaceColor"),
        Some(&Value::Triple(
            BaseType::Color,
            [0.829999983, 0.791000009, 0.753000021]
        ))
    );
    // Material: the Bxdf, named by its __materialid, with the upstream closure as node set.
    let m = net
        .materials()
        .iter()
        .position(|m| m.name == "PxrLayerSurface1SG")
        .unwrap();
    let mut names: Vec<&str> = net
        .material_nodes(m)
        .iter()
        .map(|&i| net[i].handle())
        .collect();
    names.sort();
    assert_eq!(
        names,
        [
            "PxrFractal1",
            "PxrLayer1",
            "PxrLayer2",
            "PxrLayerMixer1",
            "PxrLayerSurface1",
            "PxrThreshold1"
        ]
    );
    // The light is its own material with a `light` terminal.
    assert!(
        net.materials()
            .iter()
            .any(|m| m.name == "PxrEnvDayLightShape" && m.terminals[0].name == "light")
    );
    assert!(!diags.has_warnings(), "{:?}", codes(&diags));
}

#[test]
fn hand_edited_network_versions_and_quotes() {
    let dir = fixtures_or_skip!();
    let (_, net, diags) = read(&dir.join("rib/ldd/PxrDirt_PxrFractal_Glass.rib"));
    assert_eq!(net.node_count(), 30);
    // Seven handles are redefined once each.
    assert_eq!(diags.count("RB017"), 7, "{:?}", codes(&diags));
    for h in [
        "Curvature",
        "ConstantCurvature",
        "Solid Material 21",
        "Unevenness",
        "PxrWireframe1",
        "PxrExposure1",
        "PxrColorCorrect1",
    ] {
        assert_eq!(net.versions(h).len(), 2, "{h}");
    }
    // References bind to the latest version defined before them.
    let c0 = net.by_key("Curvature#0").unwrap();
    let c1 = net.by_key("Curvature#1").unwrap();
    assert_eq!(net[c0].shader(), "PxrCurvature");
    assert_eq!(net[c1].shader(), "PxrDirt");
    let cc0 = net.by_key("ConstantCurvature#0").unwrap();
    let cc1 = net.by_key("ConstantCurvature#1").unwrap();
    assert_eq!(
        net.connections(cc0, "emitColor")[0].upstream(),
        Upstream::Node(c0)
    );
    let color_correct = net.by_key("PxrColorCorrect1#0").unwrap();
    assert_eq!(
        net.connections(cc1, "emitColor")[0].upstream(),
        Upstream::Node(color_correct)
    );
    assert_eq!(
        net.connections(color_correct, "inputRGB")[0].upstream(),
        Upstream::Node(c1)
    );
    // The commented-out parameter is not a parameter.
    assert_eq!(net[cc0].params().count(), 2);
    // Handles with spaces.
    let solid = net.by_key("Solid Material 21#1").unwrap();
    assert_eq!(
        net.connections(solid, "bumpNormal")[0].output(),
        Some("resultN")
    );
    // Single-quoted strings: accepted with an info each.
    assert_eq!(diags.count("RB011"), 4);
    let curv = net.by_key("PxrCurvature1#0").unwrap();
    assert_eq!(
        net.value(curv, "traceSet"),
        Some(&Value::Str(String::new()))
    );
    assert_eq!(
        net.value(c1, "biasDirectionCoordsys"),
        Some(&Value::Str("object".into()))
    );
    // Trailing comment after a value is attached to that parameter.
    let src = net[solid].source().unwrap();
    let ior = src
        .items
        .iter()
        .position(|it| {
            it.param()
                .is_some_and(|k| net[solid].all_params()[k as usize].name() == "specularIor")
        })
        .unwrap();
    assert!(src.trailing_comment(ior).is_some());
    // Materials: one per Bxdf version; the second version of a name gets a suffix.
    let names: Vec<&str> = net.materials().iter().map(|m| m.name.as_str()).collect();
    assert!(names.contains(&"ConstantCurvature") && names.contains(&"ConstantCurvature#1"));
    assert!(names.contains(&"PxrSurface1SG"));
}

#[test]
fn reference_struct_manifold_and_legacy_surface() {
    let dir = fixtures_or_skip!();
    let (_, net, diags) = read(&dir.join("rib/ldd/spoon_mat.rib"));
    let manifold = net.find("PxrManifold2D1").unwrap();
    for t in ["PxrTexture1", "PxrTexture2"] {
        let tex = net.find(t).unwrap();
        let p = net[tex].param("manifold").unwrap();
        assert_eq!(p.connections(), &[Link::node(manifold, Some("result"))]);
        assert_eq!(p.decl().unwrap().ty.base, BaseType::Struct(None));
    }
    // The legacy `Surface` request with a reference parameter is passed through (RB020).
    assert_eq!(diags.count("RB020"), 1);
    assert_eq!(net.node_count(), 4);
}

#[test]
fn commented_out_parameters_are_comments() {
    let dir = fixtures_or_skip!();
    let (_, net, diags) = read(&dir.join("rib/ldd/woodtex.rib"));
    let tex = net.find("PxrTexture1").unwrap();
    let names: Vec<&str> = net[tex].params().map(|p| p.name()).collect();
    assert_eq!(names, ["filename", "invertT", "linearize"]);
    assert!(diags.is_empty(), "{:?}", codes(&diags));
    let surface = net.find("PxrSurface1").unwrap();
    assert_eq!(
        net.connections(surface, "diffuseColor")[0].upstream_node(),
        Some(tex)
    );
}

/// formats.md §3.5 / vstruct.md §12.1: the golden network with its member connections replaced
/// by the three placeholders, written as RIB and read back.
#[test]
fn unresolved_golden_network_round_trip() {
    let dir = fixtures_or_skip!();
    let path = dir.join("rib/ldd/pxrLayerSurface.0001.rib");
    let (bytes, mut net, _) = read(&path);
    let types = network_common::Table::new()
        .shader("PxrLayerSurface", &[("inputMaterial", "float")], &[])
        .shader(
            "PxrLayerMixer",
            &[("baselayer", "vstruct"), ("layer1", "vstruct")],
            &[],
        )
        .shader("PxrLayer", &[], &[("pxrMaterialOut", "vstruct")]);
    let mixer = net.find("PxrLayerMixer1").unwrap();
    let surface = net.find("PxrLayerSurface1").unwrap();
    let layer1 = net.find("PxrLayer1").unwrap();
    let layer2 = net.find("PxrLayer2").unwrap();
    for node in [mixer, surface] {
        for input in net.connected_inputs(node) {
            let from_layers = net.connections(node, &input).iter().all(|l| {
                [layer1, layer2, mixer]
                    .map(Some)
                    .contains(&l.upstream_node())
            });
            if from_layers {
                net.remove_param(node, &input);
            }
        }
    }
    net.connect(surface, "inputMaterial", mixer, "pxrMaterialOut");
    net.connect(mixer, "baselayer", layer1, "pxrMaterialOut");
    net.connect(mixer, "layer1", layer2, "pxrMaterialOut");
    let out = write_rib_to_vec(&bytes, &net, &types).unwrap();
    let text = String::from_utf8(out.clone()).unwrap();
    for line in [
        "\t\t\t\"reference float inputMaterial\" [\"PxrLayerMixer1:pxrMaterialOut\"]\n",
        "\t\t\t\"reference vstruct baselayer\" [\"PxrLayer1:pxrMaterialOut\"]\n",
        "\t\t\t\"reference vstruct layer1\" [\"PxrLayer2:pxrMaterialOut\"]\n",
    ] {
        assert!(text.contains(line), "missing {line:?}");
    }
    let again = reparse(&out);
    assert_eq!(summary(&again), summary(&net));
    let m = again.find("PxrLayerMixer1").unwrap();
    assert_eq!(
        again.connected_inputs(m),
        ["baselayer", "layer1", "layer1Mask"]
    );
    let s = again.find("PxrLayerSurface1").unwrap();
    assert_eq!(again.connected_inputs(s), ["inputMaterial"]);
    // Everything outside the two edited requests is unchanged.
    let (start, end) = {
        let a = net[mixer].source().unwrap().span.start;
        let b = net[surface].source().unwrap().span.end;
        (a, b)
    };
    assert!(out.starts_with(&bytes[..start]));
    assert!(out.ends_with(&bytes[end..]));
}

//! The bridge API: build a network in code, edit it the way resolution does, write it as RIB
//! and JSON, and read both back (no file I/O).

use crate::common::network as network_common;

use network_common::summary;
use vstructc::back::json::write_json;
use vstructc::back::rib::write_rib_to_vec;
use vstructc::front::json::parse_json;
use vstructc::front::rib::{RibOptions, parse_rib};
use vstructc::network::{Link, Network, NoDefinitions, ParamChange, RequestKind};
use vstructc::{BaseType, Diagnostics, Value};

/// Two PxrLayers → PxrLayerMixer → PxrLayerSurface, with placeholder connections.
fn layered() -> Network {
    let mut net = Network::new();
    let base = net.add_node("PxrLayer1", "PxrLayer");
    let top = net.add_node("PxrLayer2", "PxrLayer");
    let mixer = net.add_node("PxrLayerMixer1", "PxrLayerMixer");
    let surface = net.add_node_of_kind("PxrLayerSurface1", "PxrLayerSurface", RequestKind::Bxdf);
    net.set_param(base, "enableDiffuse", Value::Int(1));
    net.set_param(
        base,
        "diffuseColor",
        Value::Triple(BaseType::Color, [0.00967447, 0.179702, 0.0572573]),
    );
    net.set_param(top, "enableSpecular", Value::Int(1));
    net.set_param(mixer, "layer1Mask", Value::Float(0.5));
    net.connect(mixer, "baselayer", base, "pxrMaterialOut");
    net.connect(mixer, "layer1", top, "pxrMaterialOut");
    net.connect(surface, "inputMaterial", mixer, "pxrMaterialOut");
    let m = net.add_material("PxrLayerSurface1SG");
    net.set_terminal(m, "surface", surface, None);
    net
}

#[test]
fn build_write_and_read_back() {
    let net = layered();
    let rib = write_rib_to_vec(b"", &net, &NoDefinitions).unwrap();
    let mut d = Diagnostics::new();
    let from_rib = parse_rib(
        &rib,
        "bridge.rib",
        &NoDefinitions,
        &RibOptions::default(),
        &mut d,
    )
    .unwrap();
    assert!(d.is_empty());
    let json = write_json(&net).unwrap();
    let from_json = parse_json(json.as_bytes(), "bridge.json", &NoDefinitions, &mut d).unwrap();
    assert!(d.is_empty());
    // RIB adds the material name as __materialid on the Bxdf; otherwise identical.
    let mut rib_summary = summary(&from_rib);
    rib_summary.retain(|l| !l.contains("__materialid"));
    assert_eq!(rib_summary, summary(&net));
    assert_eq!(summary(&from_json), summary(&net));
    assert_eq!(from_json.materials()[0].name, "PxrLayerSurface1SG");
    assert_eq!(from_rib.materials()[0].name, "PxrLayerSurface1SG");
}

/// The edits resolution makes (vstruct.md §4.3–§4.7): delete a placeholder, connect members,
/// write `set` values, remove values on heads; every edit is visible and tracked.
#[test]
fn resolution_style_edits() {
    let src = br#"Pattern "PxrLayer" "PxrLayer1" "int enableClearcoat" [0]
Pattern "PxrLayerMixer" "PxrLayerMixer1"
    "reference vstruct baselayer" ["PxrLayer1:pxrMaterialOut"]
    "float baselayer_diffuseGain" [0.25]
    "float baselayer" [0]
"#;
    let mut d = Diagnostics::new();
    let mut net = parse_rib(
        src,
        "in.rib",
        &NoDefinitions,
        &RibOptions::default(),
        &mut d,
    )
    .unwrap();
    let layer = net.find("PxrLayer1").unwrap();
    let mixer = net.find("PxrLayerMixer1").unwrap();
    // RB015: the reference and the value on `baselayer` are one parameter; the later wins.
    assert_eq!(d.count("RB015"), 1);
    assert_eq!(net.value(mixer, "baselayer"), Some(&Value::Float(0.0)));
    assert!(net.connections(mixer, "baselayer").is_empty());

    // Re-create the placeholder in code, then resolve it by hand.
    net.connect(mixer, "baselayer", layer, "pxrMaterialOut");
    let placeholder = net.connections(mixer, "baselayer").to_vec();
    assert_eq!(placeholder, [Link::node(layer, Some("pxrMaterialOut"))]);
    net.clear_connections(mixer, "baselayer");
    net.remove_value(mixer, "baselayer");
    net.set_connections(
        mixer,
        "baselayer_diffuseGain",
        vec![Link::node(layer, Some("pxrMaterialOut_diffuseGain"))],
    );
    net.set_param(mixer, "baselayer_enableClearcoat", Value::Int(0));

    assert_eq!(net.param_change(mixer, "baselayer"), ParamChange::Removed);
    assert_eq!(
        net.param_change(mixer, "baselayer_diffuseGain"),
        ParamChange::Connected
    );
    assert_eq!(
        net.param_change(mixer, "baselayer_enableClearcoat"),
        ParamChange::Added
    );
    assert_eq!(net.connected_inputs(mixer), ["baselayer_diffuseGain"]);
    // `connect` keeps the old value next to the connection; the writer emits the connection.
    assert_eq!(
        net.value(mixer, "baselayer_diffuseGain"),
        Some(&Value::Float(0.25))
    );
    assert!(!net.is_modified(layer));

    let out = String::from_utf8(write_rib_to_vec(src, &net, &NoDefinitions).unwrap()).unwrap();
    assert_eq!(
        out,
        "Pattern \"PxrLayer\" \"PxrLayer1\" \"int enableClearcoat\" [0]\n\
         Pattern \"PxrLayerMixer\" \"PxrLayerMixer1\"\n\
         \t\"reference float baselayer_diffuseGain\" [\"PxrLayer1:pxrMaterialOut_diffuseGain\"]\n\
         \t\"int baselayer_enableClearcoat\" [0]\n"
    );
}

#[test]
fn graph_view_matches_links() {
    let net = layered();
    let g = net.graph();
    assert_eq!(g.node_count(), 4);
    assert_eq!(g.edge_count(), 3);
    let mixer = net.find("PxrLayerMixer1").unwrap();
    let ups: Vec<&str> = net
        .upstream_nodes(mixer)
        .iter()
        .map(|&u| net[u].handle())
        .collect();
    assert_eq!(ups, ["PxrLayer1", "PxrLayer2"]);
    // petgraph algorithms work on the graph directly.
    assert!(!petgraph::algo::is_cyclic_directed(g));
    let sorted: Vec<&str> = net
        .nodes_sorted()
        .iter()
        .map(|&i| net[i].handle())
        .collect();
    assert_eq!(
        sorted,
        [
            "PxrLayer1",
            "PxrLayer2",
            "PxrLayerMixer1",
            "PxrLayerSurface1"
        ]
    );
    let closure = net.material_nodes(0);
    assert_eq!(closure.len(), 4);
}

/// The library tells the story of an input as `vstructc explain` does: a member the
/// lacquer layer's conditional wrote is `written`, its conditional read a value resolution
/// wrote earlier (told in turn), and that one's read ends at the authored value with its
/// line in the file.
#[test]
fn a_resolution_tells_the_story_of_a_written_member() {
    use vstructc::registry::Registry;
    use vstructc::resolve::{Outcome, ResolveOptions, resolve};
    let registry = Registry::embedded();
    let text = std::fs::read("examples/chain.rib").expect("the bundled example");
    let mut diags = Diagnostics::new();
    let mut net = parse_rib(
        &text,
        "chain.rib",
        &registry,
        &RibOptions::default(),
        &mut diags,
    )
    .expect("the example parses");
    let options = ResolveOptions {
        record_events: true,
        ..ResolveOptions::default()
    };
    let res = resolve(&mut net, &registry, &options);
    let finished = net.find("finished").expect("the example's last mixer");
    let story = res.story(&net, &registry, finished, "baselayer_enableDiffuse");
    assert_eq!(
        (story.origin, story.value.clone()),
        ("written", Some(Value::Int(1)))
    );
    assert_eq!(
        story.events[0].event.outcome,
        Outcome::Written(Value::Int(1))
    );
    let read = &story.events[0].reads[0];
    assert_eq!(
        (read.param.as_str(), read.origin),
        ("baselayer_enableDiffuse", "written")
    );
    let earlier = read.story.as_deref().expect("the story of the value read");
    let origin = &earlier.events[0].reads[0];
    assert_eq!(
        (earlier.events[0].upstream_node.as_str(), origin.origin),
        ("paint", "authored")
    );
    assert_eq!(origin.location.as_ref().map(|l| l.line), Some(14));

    // Without recorded events, only the final origin is told.
    let mut again = parse_rib(
        &text,
        "chain.rib",
        &registry,
        &RibOptions::default(),
        &mut diags,
    )
    .expect("the example parses");
    let res = resolve(&mut again, &registry, &ResolveOptions::default());
    let story = res.story(&again, &registry, finished, "baselayer_enableDiffuse");
    assert!(story.events.is_empty());
}

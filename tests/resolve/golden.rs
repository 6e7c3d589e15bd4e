//! The end-to-end golden test of spec vstruct.md §12: rebuild the unresolved network from the
//! RenderMan for Maya export, resolve it, and compare with what the exporter wrote.

use crate::common;

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};
use vstructc::back::rib::write_rib_to_vec;
use vstructc::front::rib::{RibOptions, parse_rib};
use vstructc::network::{Link, Network, NodeId};
use vstructc::registry::Registry;
use vstructc::resolve::{ResolveOptions, resolve};
use vstructc::{Diagnostics, Value};

use crate::common::{GOLDEN_RIB, golden_registry};

fn full_surface() -> PathBuf {
    common::repo_dir().join("args/PxrLayerSurface.args")
}

fn twelve_member_surface() -> PathBuf {
    common::repo_dir().join("tests/data/args/PxrLayerSurface12.args")
}

/// The connection set of a node as (input, upstream handle, output) triples.
fn connections(net: &Network, node: NodeId) -> BTreeSet<(String, String, String)> {
    let mut set = BTreeSet::new();
    for input in net.connected_inputs(node) {
        for link in net.connections(node, &input) {
            let up = link.upstream_node().map(|n| net[n].handle().to_string());
            set.insert((
                input.clone(),
                up.unwrap_or_default(),
                link.output().unwrap_or_default().to_string(),
            ));
        }
    }
    set
}

/// The int values written on the mixer's `*_enable*` members.
fn enable_values(net: &Network, node: NodeId) -> BTreeSet<(String, i32)> {
    let n = &net[node];
    n.params()
        .filter(|p| p.name().contains("_enable") && !p.is_connected())
        .filter_map(|p| match p.value() {
            Some(Value::Int(i)) => Some((p.name().to_string(), *i)),
            _ => None,
        })
        .collect()
}

/// §12.1: parse the export and turn it back into the unresolved network an artist wires.
fn unresolved(reg: &Registry, fixtures: &Path) -> (Network, Network) {
    let bytes = std::fs::read(fixtures.join(GOLDEN_RIB)).expect("read golden RIB");
    let mut diags = Diagnostics::new();
    let original = parse_rib(&bytes, GOLDEN_RIB, reg, &RibOptions::default(), &mut diags)
        .expect("golden RIB parses");
    let mut net = original.clone();
    let mixer = net.find("PxrLayerMixer1").expect("mixer");
    let surface = net.find("PxrLayerSurface1").expect("surface");
    for node in [mixer, surface] {
        let shader = net[node].shader().to_string();
        let def = reg.definition(&shader).expect("definition");
        for input in def.inputs.iter().filter(|p| p.vstruct.is_some()) {
            net.clear_connections(node, &input.name);
            net.remove_value(node, &input.name);
        }
    }
    let layer1 = net.find("PxrLayer1").expect("PxrLayer1");
    let layer2 = net.find("PxrLayer2").expect("PxrLayer2");
    net.connect(surface, "inputMaterial", mixer, "pxrMaterialOut");
    net.connect(mixer, "baselayer", layer1, "pxrMaterialOut");
    net.connect(mixer, "layer1", layer2, "pxrMaterialOut");
    (original, net)
}

fn no_errors_of_concern(diags: &Diagnostics) {
    for code in [
        "VS010", "VS011", "VS012", "VS013", "VS014", "VS001", "VS016",
    ] {
        assert_eq!(diags.count(code), 0, "unexpected {code}: {diags:#?}");
    }
}

#[test]
fn golden_network_resolves_like_the_exporter() {
    let fixtures = fixtures_or_skip!();
    for surface_args in [full_surface(), twelve_member_surface()] {
        let reg = golden_registry(&fixtures, &surface_args);
        let (original, mut net) = unresolved(&reg, &fixtures);
        let res = resolve(&mut net, &reg, &ResolveOptions::default());
        no_errors_of_concern(&res.diagnostics);

        let mixer = net.find("PxrLayerMixer1").unwrap();
        let surface = net.find("PxrLayerSurface1").unwrap();
        let got_mixer = connections(&net, mixer);
        let got_surface = connections(&net, surface);
        assert_eq!(got_mixer.len(), 25, "{got_mixer:#?}");
        assert_eq!(got_surface.len(), 12, "{got_surface:#?}");
        assert_eq!(
            got_mixer,
            connections(&original, original.find("PxrLayerMixer1").unwrap())
        );
        assert_eq!(
            got_surface,
            connections(&original, original.find("PxrLayerSurface1").unwrap())
        );

        let values = enable_values(&net, mixer);
        assert_eq!(values.len(), 20, "{values:#?}");
        for prefix in ["baselayer", "layer1"] {
            for lobe in [
                "Diffuse",
                "Specular",
                "RoughSpecular",
                "Clearcoat",
                "Iridescence",
                "Fuzz",
                "RR",
                "Subsurface",
                "Singlescatter",
                "Glow",
            ] {
                let want = i32::from(lobe == "Diffuse" || lobe == "Specular");
                assert!(
                    values.contains(&(format!("{prefix}_enable{lobe}"), want)),
                    "{prefix}_enable{lobe} should be {want}"
                );
            }
        }
        // The values equal the exporter's (which also wrote zeros for the unwired layer2–4).
        let exported: BTreeSet<(String, i32)> =
            enable_values(&original, original.find("PxrLayerMixer1").unwrap())
                .into_iter()
                .filter(|(name, _)| name.starts_with("baselayer_") || name.starts_with("layer1_"))
                .collect();
        assert_eq!(values, exported);

        // No placeholder survives and no head carries a value.
        for (node, head) in [
            (surface, "inputMaterial"),
            (mixer, "baselayer"),
            (mixer, "layer1"),
        ] {
            assert!(net.connections(node, head).is_empty());
            assert!(net.value(node, head).is_none());
        }
    }
}

#[test]
fn golden_network_without_conditions() {
    let fixtures = fixtures_or_skip!();
    for (surface_args, surface_count) in [(full_surface(), 69), (twelve_member_surface(), 12)] {
        let reg = golden_registry(&fixtures, &surface_args);
        let (_, mut net) = unresolved(&reg, &fixtures);
        let options = ResolveOptions {
            conditions: false,
            ..ResolveOptions::default()
        };
        let res = resolve(&mut net, &reg, &options);
        no_errors_of_concern(&res.diagnostics);
        let mixer = net.find("PxrLayerMixer1").unwrap();
        let surface = net.find("PxrLayerSurface1").unwrap();
        assert_eq!(connections(&net, mixer).len(), 159);
        assert_eq!(connections(&net, surface).len(), surface_count);
        // The enable members are connected, not set: no values are written.
        assert!(enable_values(&net, mixer).is_empty());
        assert!(res.diagnostics.count("VS022") > 0);
    }
}

#[test]
fn golden_network_expanded_without_upstream_first_gets_only_diffuse_color() {
    // R9-neg: if the surface were expanded before the mixer, the mixer's enable members would
    // still hold their defaults (0). Simulate that by not wiring the mixer's layers at all.
    let fixtures = fixtures_or_skip!();
    let reg = golden_registry(&fixtures, &full_surface());
    let (_, mut net) = unresolved(&reg, &fixtures);
    let mixer = net.find("PxrLayerMixer1").unwrap();
    net.clear_connections(mixer, "baselayer");
    net.clear_connections(mixer, "layer1");
    resolve(&mut net, &reg, &ResolveOptions::default());
    let surface = net.find("PxrLayerSurface1").unwrap();
    let got: Vec<String> = connections(&net, surface)
        .into_iter()
        .map(|c| c.0)
        .collect();
    assert_eq!(got, ["diffuseColor"]);
}

#[test]
fn golden_network_round_trips_through_the_writer() {
    let fixtures = fixtures_or_skip!();
    let reg = golden_registry(&fixtures, &full_surface());
    let (_, mut unresolved_net) = unresolved(&reg, &fixtures);
    let source = std::fs::read(fixtures.join(GOLDEN_RIB)).unwrap();

    // The unresolved network written as RIB reads back with its placeholders.
    let unresolved_rib = write_rib_to_vec(&source, &unresolved_net, &reg).unwrap();
    let mut diags = Diagnostics::new();
    let mut reread = parse_rib(
        &unresolved_rib,
        "unresolved.rib",
        &reg,
        &RibOptions::default(),
        &mut diags,
    )
    .expect("unresolved RIB parses");
    let mixer = reread.find("PxrLayerMixer1").unwrap();
    assert_eq!(
        reread.connections(mixer, "baselayer"),
        &[Link::node(
            reread.find("PxrLayer1").unwrap(),
            Some("pxrMaterialOut")
        )]
    );

    // Resolving the re-read network and writing it gives the §12.3 results after reading back.
    resolve(&mut unresolved_net, &reg, &ResolveOptions::default());
    resolve(&mut reread, &reg, &ResolveOptions::default());
    let resolved_rib = write_rib_to_vec(&unresolved_rib, &reread, &reg).unwrap();
    let back = parse_rib(
        &resolved_rib,
        "resolved.rib",
        &reg,
        &RibOptions::default(),
        &mut diags,
    )
    .expect("resolved RIB parses");
    for handle in ["PxrLayerMixer1", "PxrLayerSurface1"] {
        assert_eq!(
            connections(&back, back.find(handle).unwrap()),
            connections(&unresolved_net, unresolved_net.find(handle).unwrap()),
            "{handle}"
        );
    }
    let m = back.find("PxrLayerMixer1").unwrap();
    assert_eq!(
        enable_values(&back, m),
        enable_values(
            &unresolved_net,
            unresolved_net.find("PxrLayerMixer1").unwrap()
        )
    );
}

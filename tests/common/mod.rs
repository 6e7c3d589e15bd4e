//! Shared helpers for integration tests.
#![allow(dead_code)]

use std::path::PathBuf;

/// The repository root (where Cargo.toml is).
pub fn repo_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// `../shared/fixtures`, if present.
///
/// When it is missing: under `CI=true` this panics (CI must have the fixtures); otherwise it
/// prints a notice and returns `None`, and the caller skips the test.
pub fn fixtures() -> Option<PathBuf> {
    let dir = repo_dir().join("../shared/fixtures");
    if dir.is_dir() {
        return Some(dir);
    }
    if std::env::var("CI").map(|v| v == "true").unwrap_or(false) {
        panic!("../shared/fixtures is missing (CI=true): fixture tests cannot run");
    }
    eprintln!("notice: ../shared/fixtures not found; skipping fixture test");
    None
}

/// Skip the current test (return early) when the fixtures are missing.
#[macro_export]
macro_rules! fixtures_or_skip {
    () => {
        match common::fixtures() {
            Some(dir) => dir,
            None => return,
        }
    };
}

/// A stable text form of a network for snapshots: per node (sorted), each parameter's
/// connections or value.
pub fn dump_network(net: &vstructc::network::Network) -> String {
    let mut out = String::new();
    for id in net.nodes_sorted() {
        let node = &net[id];
        out.push_str(&format!("{} ({})\n", node.display_name(), node.shader()));
        for p in node.params_by_name() {
            if p.is_connected() {
                let links: Vec<String> = p
                    .connections()
                    .iter()
                    .map(|l| {
                        let up = match l.upstream_node() {
                            Some(n) => net[n].handle().to_string(),
                            None => format!("<missing {}>", l.missing_handle().unwrap_or_default()),
                        };
                        match l.output() {
                            Some(o) => format!("{up}.{o}"),
                            None => up,
                        }
                    })
                    .collect();
                out.push_str(&format!("  {} <- {}\n", p.name(), links.join(", ")));
            } else if let Some(v) = p.value() {
                out.push_str(&format!("  {} = {v}\n", p.name()));
            }
        }
    }
    out
}

/// Every terminal type with a lowering recipe (closures.md §4.1–§4.5).
pub const RECIPES: [&str; 5] = [
    "PxrSurface",
    "PxrLayerSurface",
    "VRayMtl",
    "PhysicalMaterial",
    "mia_material",
];

/// The recipe of `shader` lowered with every parameter at its embedded definition's default.
pub fn recipe_at_defaults(shader: &str) -> vstructc::ir::MaterialIr {
    let registry = vstructc::registry::Registry::embedded();
    let mut net = vstructc::network::Network::new();
    let node = net.add_node("m", shader);
    let mut diags = vstructc::Diagnostics::new();
    let ir = vstructc::lower::network::lower_terminal(&net, &registry, node, shader, &mut diags)
        .expect("lowers");
    assert_eq!(
        diags.count("LW003"),
        0,
        "{shader} has an embedded definition"
    );
    ir
}

/// The golden network of vstruct.md §12: the RenderMan for Maya export, relative to the
/// fixtures folder.
pub const GOLDEN_RIB: &str = "rib/ldd/pxrLayerSurface.0001.rib";

/// The golden network's registry: Pixar's PxrLayer and PxrLayerMixer from the fixtures, and
/// the PxrLayerSurface definition in `surface_args`.
pub fn golden_registry(
    fixtures: &std::path::Path,
    surface_args: &std::path::Path,
) -> vstructc::registry::Registry {
    use vstructc::registry::{Registry, RegistryOptions};
    let mut reg = Registry::new(RegistryOptions {
        paths: vec![fixtures.join("args/pixar")],
        use_env: false,
        use_embedded: false,
        ..RegistryOptions::default()
    });
    let text = std::fs::read_to_string(surface_args).expect("surface definition");
    reg.add_args_text("PxrLayerSurface", &text)
        .expect("surface definition parses");
    reg
}

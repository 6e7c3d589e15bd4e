//! Resolution on structure-aware fuzzed networks: `arbitrary` picks node types, handles,
//! values and connections (forward references, self-connections, cycles, fan-in, missing
//! handles); the network is written as RIB, read back with the embedded definitions,
//! resolved (with and without conditions), and written out. Resolving the same network twice
//! must give identical bytes (determinism).
#![no_main]

use arbitrary::Arbitrary;
use libfuzzer_sys::fuzz_target;
use std::fmt::Write as _;
use std::sync::LazyLock;
use vstructc::Diagnostics;
use vstructc::back::rib::write_rib_to_vec;
use vstructc::front::rib::{RibOptions, parse_rib};
use vstructc::registry::Registry;
use vstructc::resolve::{ResolveOptions, resolve};

static REGISTRY: LazyLock<Registry> = LazyLock::new(Registry::embedded);

const SHADERS: &[&str] = &[
    "PxrLayer",
    "PxrLayerMixer",
    "PxrLayerSurface",
    "PxrSurface",
    "PxrDiffuse",
    "Unknown",
];
const INPUTS: &[(&str, &str)] = &[
    ("struct", "baselayer"),
    ("struct", "layer1"),
    ("struct", "layer2"),
    ("struct", "inputMaterial"),
    ("float", "diffuseGain"),
    ("float", "layer1Mask"),
    ("int", "enableDiffuse"),
    ("int", "layer1Enabled"),
    ("color", "baselayer_diffuseColor"),
    ("vstruct", "baselayer"),
];
const OUTPUTS: &[&str] = &[
    "pxrMaterialOut",
    "pxrMaterialOut_diffuseColor",
    "resultF",
    "bxdf_out",
    "",
];

#[derive(Debug, Arbitrary)]
struct Net {
    nodes: Vec<Node>,
    no_conditions: bool,
}

#[derive(Debug, Arbitrary)]
struct Node {
    shader: u8,
    values: Vec<(u8, i8)>,
    links: Vec<Link>,
}

#[derive(Debug, Arbitrary)]
struct Link {
    input: u8,
    /// Index of the upstream node; may point forward, at itself, or past the end (missing).
    upstream: u8,
    output: u8,
    /// Extra connections on the same input (fan-in).
    fan: u8,
}

fn pick<T: Copy>(list: &[T], i: u8) -> T {
    list[i as usize % list.len()]
}

fn rib(net: &Net) -> String {
    let mut out = String::from("WorldBegin\n");
    let n = net.nodes.len().min(64);
    for (i, node) in net.nodes.iter().take(n).enumerate() {
        let shader = pick(SHADERS, node.shader);
        let request = if shader.contains("Surface") || shader == "PxrDiffuse" {
            "Bxdf"
        } else {
            "Pattern"
        };
        let _ = write!(out, "{request} \"{shader}\" \"n{i}\"");
        for (input, v) in node.values.iter().take(8) {
            let (ty, name) = pick(INPUTS, *input);
            match ty {
                "float" | "int" => {
                    let _ = write!(out, " \"{ty} {name}\" [{v}]");
                }
                "color" => {
                    let _ = write!(out, " \"color {name}\" [{v} 0 1]");
                }
                _ => {}
            }
        }
        for link in node.links.iter().take(8) {
            let (ty, name) = pick(INPUTS, link.input);
            let fan = 1 + link.fan as usize % 4;
            let targets: Vec<String> = (0..fan)
                .map(|k| {
                    let up = (link.upstream as usize + k) % (n + 2);
                    match pick(OUTPUTS, link.output) {
                        "" => format!("\"n{up}\""),
                        o => format!("\"n{up}:{o}\""),
                    }
                })
                .collect();
            let decl = if fan > 1 {
                format!("{ty}[{fan}]")
            } else {
                ty.to_string()
            };
            let _ = write!(out, " \"reference {decl} {name}\" [{}]", targets.join(" "));
        }
        out.push('\n');
    }
    out.push_str("WorldEnd\n");
    out
}

fn resolved(text: &[u8], options: &ResolveOptions) -> Option<Vec<u8>> {
    let registry: &Registry = &REGISTRY;
    let mut diags = Diagnostics::new();
    let mut net = parse_rib(
        text,
        "fuzz.rib",
        registry,
        &RibOptions::default(),
        &mut diags,
    )
    .ok()?;
    let _ = resolve(&mut net, registry, options);
    write_rib_to_vec(text, &net, registry).ok()
}

fuzz_target!(|net: Net| {
    let text = rib(&net);
    let options = ResolveOptions {
        conditions: !net.no_conditions,
        ..ResolveOptions::default()
    };
    let first = resolved(text.as_bytes(), &options);
    let second = resolved(text.as_bytes(), &options);
    assert_eq!(first, second, "resolution is not deterministic");
});

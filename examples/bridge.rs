//! How a bridge (a DCC plug-in, a Hydra delegate, a scene translator) uses vstructc as a
//! library: build a network in code, resolve its vstruct connections against a registry, and
//! read back connections, values and diagnostics. No files are read or written.
//!
//! Run with `cargo run --example bridge`.

use vstructc::network::Network;
use vstructc::registry::Registry;
use vstructc::resolve::{ResolveOptions, resolve};
use vstructc::{BaseType, Value};

fn main() {
    // The definitions compiled into vstructc (PxrLayer, PxrLayerMixer, PxrLayerSurface, …).
    // A bridge with a RenderMan install would use `Registry::new(RegistryOptions { paths:
    // vec![rman_args_dir], .. })`, or add in-memory definitions with `add_args_text`.
    let registry = Registry::embedded();

    // The artist's network: two layers, one mixer, one surface, each wired by ONE vstruct
    // connection.
    let mut net = Network::new();
    let base = net.add_node("base", "PxrLayer");
    net.set_param(base, "enableDiffuse", Value::Int(1));
    net.set_param(
        base,
        "diffuseColor",
        Value::Triple(BaseType::Color, [0.1, 0.4, 0.1]),
    );
    let coat = net.add_node("coat", "PxrLayer");
    net.set_param(coat, "enableClearcoat", Value::Int(1));
    let mixer = net.add_node("mixer", "PxrLayerMixer");
    net.set_param(mixer, "layer1Enabled", Value::Int(1));
    let surface = net.add_node("surface", "PxrLayerSurface");
    net.connect(mixer, "baselayer", base, "pxrMaterialOut");
    net.connect(mixer, "layer1", coat, "pxrMaterialOut");
    net.connect(surface, "inputMaterial", mixer, "pxrMaterialOut");

    // Expand every vstruct connection, upstream first, exactly as hdPrman does.
    let result = resolve(&mut net, &registry, &ResolveOptions::default());

    // Read back what the renderer needs.
    println!("connections of `surface`:");
    for input in net.connected_inputs(surface) {
        for link in net.connections(surface, &input) {
            let up = link.upstream_node().map(|n| net[n].handle()).unwrap_or("?");
            println!("  {input} <- {up}.{}", link.output().unwrap_or(""));
        }
    }
    println!(
        "mixer.layer1_enableClearcoat = {:?}",
        net.value(mixer, "layer1_enableClearcoat")
    );
    println!("{} diagnostics", result.diagnostics.len());
    for d in &result.diagnostics {
        println!("  {}", d.render_human());
    }
}

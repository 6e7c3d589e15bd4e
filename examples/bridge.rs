//! How a bridge (a DCC plug-in, a Hydra delegate, a scene translator) uses vstructc as a
//! library: build a network in code, resolve its vstruct connections against a registry,
//! read back connections, values and diagnostics, then compile the material and evaluate it
//! for one pair of directions. No files are read or written.
//!
//! Run with `cargo run --example bridge`. The library alone is enough:
//! `vstructc = { version = "0.1", default-features = false }`.

use vstructc::glam::Vec3;
use vstructc::interp::ShadingPoint;
use vstructc::network::{Network, RequestKind};
use vstructc::pipeline::{Lowering, compile};
use vstructc::registry::Registry;
use vstructc::resolve::{ResolveOptions, resolve};
use vstructc::{BaseType, Diagnostics, Value};

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
    let surface = net.add_node_of_kind("surface", "PxrLayerSurface", RequestKind::Bxdf);
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
        // The node and parameter are fields: a network built in memory has no file
        // position, and a plug-in should not parse the message to find the node.
        println!(
            "  {} on {}.{}: {}",
            d.code,
            d.node.as_deref().unwrap_or("?"),
            d.param.as_deref().unwrap_or(""),
            d.message
        );
    }

    // Compile the material for the interpreter and evaluate it: light from straight above,
    // viewed at 45 degrees, on a surface facing +Z.
    let mut diags = Diagnostics::new();
    let materials = match compile(&net, &registry, &Lowering::All, &mut diags) {
        Ok(m) => m,
        Err(e) => {
            eprintln!("error: {e}");
            std::process::exit(1);
        }
    };
    for d in &diags {
        println!("  {}", d.render_human());
    }
    let view = Vec3::new(1.0, 0.0, 1.0).normalize();
    let point = ShadingPoint::new(Vec3::Z, Vec3::X, view);
    for material in &materials {
        let prepared = material.prepare(&point);
        let eval = prepared.eval(Vec3::Z);
        let albedo = prepared.albedo();
        println!(
            "material `{}`: {} lobes, f·cos = {:.4}, pdf = {:.4}, albedo = {:.4}",
            material.name(),
            prepared.lobes().len(),
            eval.f_cos,
            eval.pdf,
            albedo.total()
        );
    }
}

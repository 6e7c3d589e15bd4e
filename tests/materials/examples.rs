//! The shipped examples show what they say: `examples/chain.rib` ("paint, dust, lacquer")
//! renders a coloured, coated ball, not the lacquer layer's grey diffuse.

use crate::common;
use vstructc::Diagnostics;
use vstructc::front::NetFormat;
use vstructc::interp::Material;
use vstructc::interp::preview::{PreviewOptions, render_ball};
use vstructc::ir::LeafKind;
use vstructc::pipeline::{Lowering, PipelineOptions, run};
use vstructc::registry::Registry;

/// The example's one material, lowered, and its ball rendered at `size`.
fn chain_ball(size: usize) -> (vstructc::ir::MaterialIr, Vec<[f32; 3]>, [f32; 3]) {
    let bytes = std::fs::read(common::repo_dir().join("examples/chain.rib")).unwrap();
    let options = PipelineOptions {
        lowering: Lowering::All,
        ..Default::default()
    };
    let mut diags = Diagnostics::new();
    let out = run(
        "chain.rib",
        &bytes,
        NetFormat::Rib,
        &Registry::embedded(),
        &options,
        &mut diags,
    )
    .unwrap();
    assert!(!diags.has_warnings(), "{diags:#?}");
    let ir = out.materials.into_iter().next().expect("one material");
    let material = Material::new(&ir).unwrap();
    let opts = PreviewOptions {
        size,
        ..PreviewOptions::default()
    };
    let image = render_ball(&material, &opts, &|_| {}).unwrap();
    let env = opts.env.to_array();
    let pixels = image.pixels.iter().map(|p| p.to_array()).collect();
    (ir, pixels, env)
}

#[test]
fn the_chain_example_shows_paint_dust_and_lacquer() {
    let (ir, pixels, env) = chain_ball(32);
    // The sphere's pixels (the background is the environment colour).
    let ball: Vec<[f32; 3]> = pixels.into_iter().filter(|p| *p != env).collect();
    assert!(ball.len() > 32 * 32 / 2, "{}", ball.len());
    let n = ball.len() as f32;
    let mean = |c: usize| ball.iter().map(|p| p[c]).sum::<f32>() / n;
    let (r, g, b) = (mean(0), mean(1), mean(2));
    // Chroma relative to brightness: the paint is blue (0.2 0.3 0.7) under 30 % of a
    // beige dust; a grey ball has a ratio near 0.
    let chroma = (r.max(g).max(b) - r.min(g).min(b)) / ((r + g + b) / 3.0);
    assert!(
        chroma > 0.25,
        "mean colour {r} {g} {b}: chroma ratio {chroma}"
    );
    assert!(b > g && g > r, "the paint's blue dominates: {r} {g} {b}");
    // The lacquer's coat is there, and the dust's roughness reaches the diffuse lobe.
    let labels: Vec<&str> = ir.leaves().map(|(_, l)| l.label.as_str()).collect();
    assert_eq!(labels, ["diffuse", "clearcoat"], "{labels:?}");
    assert!(
        ir.leaves()
            .any(|(_, l)| matches!(l.kind, LeafKind::OrenNayarE { .. })),
        "{labels:?}"
    );
}

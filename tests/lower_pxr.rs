//! PxrSurface / PxrLayerSurface lowering with PxrLayer and PxrLayerMixer interpreted
//! (closures.md §4.1, §4.2, §5.8).

use glam::Vec3;
use vstructc::diag::Diagnostics;
use vstructc::ir::{print, LeafKind, MaterialIr, Node, SimpleAlbedo};
use vstructc::lower::{lower_node, NoDefinitions, SimpleGraph};

/// The golden network of vstruct.md §12 in its resolved form, built by hand: two layers
/// (green base, red layer 1), a mixer whose layer-1 mask comes from PxrThreshold1, and the
/// 12 member connections on the surface.
fn golden() -> (SimpleGraph, usize) {
    let mut g = SimpleGraph::new();
    let thr = g.node("PxrThreshold1", "PxrThreshold");
    let l1 = g.node("PxrLayer1", "PxrLayer");
    let l2 = g.node("PxrLayer2", "PxrLayer");
    for (l, dc, fc) in [
        (l1, [0.00967446715, 0.179702222, 0.0572573431], [0.0, 0.0, 0.0]),
        (l2, [0.179702222, 0.0125546111, 0.0125546111], [0.179702222, 0.0125546111, 0.0125546111]),
    ] {
        g.seti(l, "enableDiffuse", 1).seti(l, "enableSpecular", 1);
        g.setf(l, "diffuseGain", 1.0).setc(l, "diffuseColor", dc);
        g.setf(l, "specularGain", 1.0).setc(l, "specularFaceColor", fc);
        g.setc(l, "specularEdgeColor", [1.0; 3]);
        g.setf(l, "specularRoughness", 0.2);
    }
    let mx = g.node("PxrLayerMixer1", "PxrLayerMixer");
    g.connect(mx, "layer1Mask", thr, "resultR");
    let members = [
        "diffuseGain", "diffuseColor", "diffuseRoughness", "diffuseBackColor",
        "diffuseTransmitGain", "diffuseTransmitColor", "specularFaceColor",
        "specularEdgeColor", "specularIor", "specularExtinctionCoeff", "specularRoughness",
        "specularAnisotropy",
    ];
    for (prefix, l) in [("baselayer", l1), ("layer1", l2)] {
        for m in members {
            g.connect(mx, &format!("{prefix}_{m}"), l, &format!("pxrMaterialOut_{m}"));
        }
        for x in ["Diffuse", "Specular"] {
            g.seti(mx, &format!("{prefix}_enable{x}"), 1);
        }
        for x in ["RoughSpecular", "Clearcoat", "Iridescence", "Fuzz", "RR", "Subsurface", "Singlescatter", "Glow"] {
            g.seti(mx, &format!("{prefix}_enable{x}"), 0);
        }
    }
    let s = g.node("PxrLayerSurface1", "PxrLayerSurface");
    for m in members {
        g.connect(s, m, mx, &format!("pxrMaterialOut_{m}"));
    }
    (g, s)
}

fn lower(g: &SimpleGraph, n: usize) -> (MaterialIr, Diagnostics) {
    let mut d = Diagnostics::new();
    let ir = lower_node(g, &NoDefinitions, n, "golden", &mut d).expect("lowers");
    (ir, d)
}

#[test]
fn golden_network_lowers_to_lambert_and_one_schlick_specular() {
    let (g, s) = golden();
    let (ir, d) = lower(&g, s);
    println!("{}", print::ir_text(&ir));
    println!("{}", print::lobes_text(&ir, &SimpleAlbedo));
    assert_eq!(ir.inputs.len(), 1, "one external slot");
    assert_eq!(ir.inputs[0].name, "PxrThreshold1.resultR");
    assert_eq!(ir.inputs[0].fallback_vec(), Vec3::ONE);
    assert_eq!(d.count("LW002"), 1);
    let leaves: Vec<_> = ir.leaves().map(|(_, l)| l.kind).collect();
    assert_eq!(leaves.len(), 2, "{leaves:?}");
    assert!(matches!(leaves[..], [LeafKind::MicrofacetR { .. }, LeafKind::Lambert { .. }] | [LeafKind::Lambert { .. }, LeafKind::MicrofacetR { .. }]));
    let _ = Node::Add { a: vstructc::ir::NodeId(0), b: vstructc::ir::NodeId(0) };
}

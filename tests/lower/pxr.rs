//! PxrSurface / PxrLayerSurface lowering with PxrLayer and PxrLayerMixer interpreted
//! (closures.md §4.1, §4.2, §5.8).

// Colours are written exactly as the fixture RIB writes them.
#![allow(clippy::excessive_precision)]
use glam::Vec3;
use vstructc::diag::Diagnostics;
use vstructc::ir::{LeafKind, MaterialIr, Node, SimpleAlbedo};
use vstructc::lower::{NoDefinitions, SimpleGraph, lower_node};

/// The golden network of vstruct.md §12 in its resolved form, built by hand: two layers
/// (green base, red layer 1), a mixer whose layer-1 mask comes from PxrThreshold1, and the
/// 12 member connections on the surface.
fn golden() -> (SimpleGraph, usize) {
    let mut g = SimpleGraph::new();
    let thr = g.node("PxrThreshold1", "PxrThreshold");
    let l1 = g.node("PxrLayer1", "PxrLayer");
    let l2 = g.node("PxrLayer2", "PxrLayer");
    for (l, dc, fc) in [
        (
            l1,
            [0.00967446715, 0.179702222, 0.0572573431],
            [0.0, 0.0, 0.0],
        ),
        (
            l2,
            [0.179702222, 0.0125546111, 0.0125546111],
            [0.179702222, 0.0125546111, 0.0125546111],
        ),
    ] {
        g.seti(l, "enableDiffuse", 1).seti(l, "enableSpecular", 1);
        g.setf(l, "diffuseGain", 1.0).setc(l, "diffuseColor", dc);
        g.setf(l, "specularGain", 1.0)
            .setc(l, "specularFaceColor", fc);
        g.setc(l, "specularEdgeColor", [1.0; 3]);
        g.setf(l, "specularRoughness", 0.2);
    }
    let mx = g.node("PxrLayerMixer1", "PxrLayerMixer");
    g.connect(mx, "layer1Mask", thr, "resultR");
    let members = [
        "diffuseGain",
        "diffuseColor",
        "diffuseRoughness",
        "diffuseBackColor",
        "diffuseTransmitGain",
        "diffuseTransmitColor",
        "specularFaceColor",
        "specularEdgeColor",
        "specularIor",
        "specularExtinctionCoeff",
        "specularRoughness",
        "specularAnisotropy",
    ];
    for (prefix, l) in [("baselayer", l1), ("layer1", l2)] {
        for m in members {
            g.connect(
                mx,
                &format!("{prefix}_{m}"),
                l,
                &format!("pxrMaterialOut_{m}"),
            );
        }
        for x in ["Diffuse", "Specular"] {
            g.seti(mx, &format!("{prefix}_enable{x}"), 1);
        }
        for x in [
            "RoughSpecular",
            "Clearcoat",
            "Iridescence",
            "Fuzz",
            "RR",
            "Subsurface",
            "Singlescatter",
            "Glow",
        ] {
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
    println!("{}", ir.text());
    println!("{}", ir.lobes_text(&SimpleAlbedo));
    assert_eq!(ir.inputs.len(), 1, "one external slot");
    assert_eq!(ir.inputs[0].name, "PxrThreshold1.resultR");
    assert_eq!(ir.inputs[0].fallback_vec(), Vec3::ONE);
    assert_eq!(d.count("LW002"), 1);
    let leaves: Vec<_> = ir.leaves().map(|(_, l)| l.kind).collect();
    assert_eq!(leaves.len(), 2, "{leaves:?}");
    assert!(matches!(
        leaves[..],
        [LeafKind::MicrofacetR { .. }, LeafKind::Lambert { .. }]
            | [LeafKind::Lambert { .. }, LeafKind::MicrofacetR { .. }]
    ));
    let _ = Node::Add {
        a: vstructc::ir::NodeId(0),
        b: vstructc::ir::NodeId(0),
    };
}

/// §5.8: with slot value 0 the surface shows PxrLayer1 (green diffuse, black-faced
/// specular with white edge, α = 0.04); with 1 it shows PxrLayer2.
#[test]
fn golden_network_slot_values_select_the_layers() {
    use vstructc::ir::Fresnel;
    use vstructc::ir::passes::specialize;
    let (g, s) = golden();
    let (ir, _) = lower(&g, s);
    let cases = [
        (
            0.0,
            Vec3::new(0.00967446715, 0.179702222, 0.0572573431),
            Vec3::ZERO,
        ),
        (
            1.0,
            Vec3::new(0.179702222, 0.0125546111, 0.0125546111),
            Vec3::new(0.179702222, 0.0125546111, 0.0125546111),
        ),
    ];
    for (slot, diffuse, f0) in cases {
        // Evaluating with the slot value and specialising must agree.
        let spec = specialize(&ir, 0, Vec3::splat(slot)).unwrap();
        assert!(spec.inputs.is_empty());
        assert_eq!(
            spec.program
                .ops
                .iter()
                .filter(|o| o.code != vstructc::ir::OpCode::Const)
                .count(),
            0,
            "all constant"
        );
        for m in [&ir, &spec] {
            let regs = m.run_program(Some(&[Vec3::splat(slot)][..m.inputs.len()]), 1.0);
            for (_, leaf) in m.leaves() {
                match leaf.kind {
                    LeafKind::Lambert { albedo } => assert_eq!(regs[albedo.index()], diffuse),
                    LeafKind::MicrofacetR {
                        alpha_x,
                        alpha_y,
                        fresnel: Fresnel::Schlick { f0: r0, f90, q },
                        ..
                    } => {
                        assert_eq!(regs[r0.index()], f0);
                        assert_eq!(regs[f90.index()], Vec3::ONE);
                        assert_eq!(regs[q.index()], Vec3::splat(5.0));
                        assert!((regs[alpha_x.index()].x - 0.04).abs() < 1e-6);
                        assert_eq!(regs[alpha_x.index()], regs[alpha_y.index()]);
                    }
                    k => panic!("unexpected lobe {k:?}"),
                }
            }
        }
    }
}

const LOBE_MEMBERS: [&str; 13] = [
    "diffuseGain",
    "diffuseColor",
    "diffuseRoughness",
    "specularFaceColor",
    "specularEdgeColor",
    "specularRoughness",
    "specularIor",
    "specularAnisotropy",
    "clearcoatFaceColor",
    "clearcoatEdgeColor",
    "clearcoatRoughness",
    "clearcoatThickness",
    "clearcoatAbsorptionTint",
];

fn add_layer(g: &mut SimpleGraph, name: &str, base: f32) -> usize {
    let l = g.node(name, "PxrLayer");
    g.seti(l, "enableDiffuse", 1)
        .seti(l, "enableSpecular", 1)
        .seti(l, "enableClearcoat", 1);
    g.setf(l, "diffuseGain", 0.9 - base)
        .setc(l, "diffuseColor", [base, 0.2, 0.3]);
    g.setf(l, "diffuseRoughness", base);
    g.setf(l, "specularGain", 1.0)
        .setc(l, "specularFaceColor", [0.04 + base, 0.04, 0.04]);
    g.setc(l, "specularEdgeColor", [1.0; 3])
        .setf(l, "specularRoughness", 0.1 + base);
    g.setf(l, "clearcoatGain", 1.0)
        .setc(l, "clearcoatFaceColor", [0.05; 3]);
    g.setc(l, "clearcoatEdgeColor", [0.5 + base; 3])
        .setf(l, "clearcoatRoughness", base);
    l
}

/// A surface fed by a mixer over two layers with the given mask, or by one layer directly.
fn mixer_graph(mask: Option<f32>, direct: Option<usize>, flags: [i32; 2]) -> (SimpleGraph, usize) {
    let mut g = SimpleGraph::new();
    let l1 = add_layer(&mut g, "base", 0.1);
    let l2 = add_layer(&mut g, "top", 0.4);
    let s = g.node("surface", "PxrLayerSurface");
    match direct {
        Some(k) => {
            let l = [l1, l2][k];
            for m in LOBE_MEMBERS {
                g.connect(s, m, l, &format!("pxrMaterialOut_{m}"));
            }
        }
        None => {
            let mx = g.node("mixer", "PxrLayerMixer");
            g.setf(mx, "layer1Mask", mask.unwrap_or(1.0))
                .seti(mx, "layer1Enabled", 1);
            for (prefix, l, flag) in [("baselayer", l1, flags[0]), ("layer1", l2, flags[1])] {
                for m in LOBE_MEMBERS {
                    // As resolution does: the base's coat members are connected only when
                    // its flag is on; layer 1's always (to show that the flag gates them).
                    if prefix == "baselayer" && flag == 0 && m.starts_with("clearcoat") {
                        continue;
                    }
                    g.connect(
                        mx,
                        &format!("{prefix}_{m}"),
                        l,
                        &format!("pxrMaterialOut_{m}"),
                    );
                }
                // Flags as resolution's `set` actions write them.
                g.seti(mx, &format!("{prefix}_enableDiffuse"), 1);
                g.seti(mx, &format!("{prefix}_enableSpecular"), 1);
                g.seti(mx, &format!("{prefix}_enableClearcoat"), flag);
            }
            for m in LOBE_MEMBERS {
                g.connect(s, m, mx, &format!("pxrMaterialOut_{m}"));
            }
        }
    }
    (g, s)
}

fn text(g: &SimpleGraph, s: usize) -> String {
    let (ir, _) = lower(g, s);
    ir.text()
}

/// §4.2 acceptance: mask 0 reproduces the base layer, mask 1 the top layer (the IRs are
/// identical, constant for constant).
#[test]
fn mixer_mask_zero_is_base_and_one_is_top() {
    let (g, s) = mixer_graph(Some(0.0), None, [1, 1]);
    let (gb, sb) = mixer_graph(None, Some(0), [1, 1]);
    assert_eq!(text(&g, s), text(&gb, sb));
    let (g, s) = mixer_graph(Some(1.0), None, [1, 1]);
    let (gt, st) = mixer_graph(None, Some(1), [1, 1]);
    assert_eq!(text(&g, s), text(&gt, st));
    // And a mask in between is neither.
    let (g, s) = mixer_graph(Some(0.5), None, [1, 1]);
    assert_ne!(text(&g, s), text(&gb, sb));
    assert_ne!(text(&g, s), text(&gt, st));
}

/// Enable flags written by `set` during resolution gate the mixer's compositing and so
/// prune the lobes they disable, even though the member connections exist.
#[test]
fn enable_flags_written_by_set_prune_lobes() {
    let count = |flags: [i32; 2]| {
        let (g, s) = mixer_graph(Some(1.0), None, flags);
        let (ir, _) = lower(&g, s);
        ir.leaves().filter(|(_, l)| l.label == "clearcoat").count()
    };
    assert_eq!(count([1, 1]), 1);
    assert_eq!(
        count([0, 1]),
        1,
        "the top layer's coat shows through mask 1"
    );
    // Both flags 0: the mixer's clearcoat colours stay at 0 and the lobe is removed.
    assert_eq!(count([0, 0]), 0);
    // Base on, top off with mask 1: the base's coat stays (the top does not participate).
    let (g, s) = mixer_graph(Some(1.0), None, [1, 0]);
    let (ir, _) = lower(&g, s);
    let (gb, sb) = mixer_graph(None, Some(0), [1, 1]);
    let (irb, _) = lower(&gb, sb);
    let cc = |ir: &MaterialIr| {
        let regs = ir.run_program(None, 1.0);
        ir.leaves()
            .filter(|(_, l)| l.label == "clearcoat")
            .map(|(_, l)| {
                l.kind
                    .params()
                    .iter()
                    .map(|(n, r)| (n.to_string(), regs[r.index()]))
                    .collect::<Vec<_>>()
            })
            .collect::<Vec<_>>()
    };
    assert_eq!(cc(&ir), cc(&irb));
}

/// PxrLayer folds its gains into the Fresnel colours and renames the RR members (§4.2).
#[test]
fn layer_outputs_fold_gains_and_rename_rr() {
    let mut g = SimpleGraph::new();
    let l = g.node("l", "PxrLayer");
    g.seti(l, "enableSpecular", 1)
        .setf(l, "specularGain", 0.5)
        .setc(l, "specularFaceColor", [0.2, 0.4, 0.6]);
    g.setc(l, "specularEdgeColor", [1.0; 3]);
    g.seti(l, "enableRR", 1)
        .setf(l, "rrRefractionGain", 1.0)
        .setf(l, "rrIor", 1.33);
    let s = g.node("s", "PxrSurface");
    for m in [
        "specularFaceColor",
        "specularEdgeColor",
        "refractionGain",
        "glassIor",
    ] {
        g.connect(s, m, l, &format!("pxrMaterialOut_{m}"));
    }
    let (ir, _) = lower(&g, s);
    let regs = ir.run_program(None, 1.0);
    let mut seen = 0;
    for (_, leaf) in ir.leaves() {
        match leaf.kind {
            LeafKind::MicrofacetR {
                fresnel: vstructc::ir::Fresnel::Schlick { f0, f90, .. },
                ..
            } if leaf.label == "specular" => {
                assert_eq!(regs[f0.index()], Vec3::new(0.1, 0.2, 0.3));
                assert_eq!(regs[f90.index()], Vec3::splat(0.5));
                seen += 1;
            }
            LeafKind::Dielectric { eta, .. } => {
                assert_eq!(regs[eta.index()], Vec3::splat(1.33));
                seen += 1;
            }
            _ => {}
        }
    }
    assert_eq!(seen, 2, "{}", ir.text());
    // refractionGain 1 replaces the opaque base entirely: no diffuse lobe.
    assert!(ir.leaves().all(|(_, l)| l.label != "diffuse"));
}

/// A cycle among interpreted patterns is LW011; a terminal without recipe is LW001.
#[test]
fn cycles_and_unknown_terminals_are_errors() {
    let mut g = SimpleGraph::new();
    let a = g.node("a", "vsMix");
    let b = g.node("b", "vsMix");
    g.connect(a, "color1", b, "resultRGB");
    g.connect(b, "color1", a, "resultRGB");
    let s = g.node("s", "PxrSurface");
    g.connect(s, "diffuseColor", a, "resultRGB");
    let mut d = Diagnostics::new();
    let err = lower_node(&g, &NoDefinitions, s, "c", &mut d).unwrap_err();
    assert_eq!(err.code(), Some("LW011"));
    let err = lower_node(&g, &NoDefinitions, a, "c", &mut d).unwrap_err();
    assert_eq!(err.code(), Some("LW001"));
}

/// Fused patterns: a checker on a uv manifold drives the diffuse colour as program ops, not
/// as an external slot.
#[test]
fn patterns_are_fused_into_the_program() {
    use vstructc::ir::{Globals, RunContext};
    let mut g = SimpleGraph::new();
    let uv = g.node("uv", "vsUvManifold");
    g.setf(uv, "scaleS", 2.0);
    let ch = g.node("ch", "vsChecker");
    g.connect(ch, "manifold", uv, "result");
    g.setf(ch, "frequency", 1.0)
        .setc(ch, "colorA", [1.0, 0.0, 0.0])
        .setc(ch, "colorB", [0.0, 0.0, 1.0]);
    let s = g.node("s", "PxrSurface");
    g.connect(s, "diffuseColor", ch, "resultRGB");
    let (ir, d) = lower(&g, s);
    assert!(ir.inputs.is_empty());
    assert_eq!(d.count("LW002"), 0);
    let albedo = ir
        .leaves()
        .find_map(|(_, l)| match l.kind {
            LeafKind::Lambert { albedo } => Some(albedo),
            _ => None,
        })
        .unwrap();
    let at = |u: f32, v: f32| {
        let regs = ir.program.run(&RunContext {
            inputs: &[],
            mu_o: &[1.0],
            globals: Globals {
                u,
                v,
                ..Globals::default()
            },
        });
        regs[albedo.index()]
    };
    assert_eq!(at(0.1, 0.1), Vec3::new(1.0, 0.0, 0.0));
    assert_eq!(
        at(0.6, 0.1),
        Vec3::new(0.0, 0.0, 1.0),
        "s = 2u crosses a cell"
    );
    assert_eq!(at(0.6, 1.1), Vec3::new(1.0, 0.0, 0.0));
}

/// The generated benchmark scene lowers completely, sequentially and in parallel alike.
#[test]
fn generated_scene_lowers_in_parallel_like_sequentially() {
    use vstructc::lower::lower_many;
    use vstructc_testkit::scene::layered_scene;
    let (g, t) = layered_scene(40);
    let a = lower_many(&g, &NoDefinitions, &t, false);
    let b = lower_many(&g, &NoDefinitions, &t, true);
    assert_eq!(a.len(), 40);
    for ((ra, _), (rb, _)) in a.iter().zip(&b) {
        let (ia, ib) = (ra.as_ref().unwrap(), rb.as_ref().unwrap());
        assert_eq!(ia.text(), ib.text());
        // Diffuse, specular and the top layer's clearcoat.
        assert_eq!(ia.lobe_count(), 3, "{}", ia.text());
    }
}

/// The diffuse albedo register of the (only) Lambert leaf, evaluated with `μ_o = mu`.
fn lambert_albedo_at(ir: &MaterialIr, mu: f32) -> Vec3 {
    let regs = ir.run_program(None, mu);
    let albedo = ir
        .leaves()
        .find_map(|(_, l)| match l.kind {
            LeafKind::Lambert { albedo } => Some(albedo),
            _ => None,
        })
        .expect("a Lambert leaf");
    regs[albedo.index()]
}

/// §4.1: a double-sided diffuse seen from below uses `diffuseBackColor` unless
/// `diffuseBackUseDiffuseColor` is set; one-sided, the back colour never applies.
#[test]
fn double_sided_diffuse_uses_the_back_colour_from_below() {
    let front = [0.8, 0.2, 0.1];
    let back = [0.1, 0.3, 0.9];
    let surface = |double: i32, use_front: i32| {
        let mut g = SimpleGraph::new();
        let s = g.node("S", "PxrSurface");
        g.seti(s, "diffuseDoubleSided", double)
            .seti(s, "diffuseBackUseDiffuseColor", use_front);
        g.setc(s, "diffuseColor", front)
            .setc(s, "diffuseBackColor", back);
        lower(&g, s).0
    };
    let ir = surface(1, 0);
    assert_eq!(lambert_albedo_at(&ir, 0.7), Vec3::from(front));
    assert_eq!(lambert_albedo_at(&ir, -0.7), Vec3::from(back));
    let ir = surface(1, 1);
    assert_eq!(lambert_albedo_at(&ir, -0.7), Vec3::from(front));
    let ir = surface(0, 0);
    assert_eq!(lambert_albedo_at(&ir, -0.7), Vec3::from(front));
}

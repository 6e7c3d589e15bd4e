//! Energy rules of each material model on its weights (closures.md §4.3–§4.5, §5.8).

use glam::Vec3;
use vstructc::diag::Diagnostics;
use vstructc::ir::{Leaf, MaterialIr, Node};
use vstructc::lower::{NoDefinitions, SimpleGraph, lower_node};

fn lower(g: &SimpleGraph, n: usize) -> MaterialIr {
    let mut d = Diagnostics::new();
    lower_node(g, &NoDefinitions, n, "m", &mut d).expect("lowers")
}

/// Weights by lobe label at `mu`, with `albedo(label)` as every leaf's E.
fn weights(ir: &MaterialIr, mu: f32, albedo: &dyn Fn(&str) -> Vec3) -> Vec<(String, Vec3)> {
    let src = |l: &Leaf, _: &[Vec3], _: f32| albedo(&l.label);
    let flat = ir.weights(None, mu, &src);
    flat.lobes
        .iter()
        .map(|l| match &ir.nodes[l.node.index()] {
            Node::Leaf(leaf) => (leaf.label.clone(), l.weight),
            _ => unreachable!(),
        })
        .collect()
}

fn w_of(ws: &[(String, Vec3)], label: &str) -> Vec3 {
    ws.iter().filter(|(l, _)| l == label).map(|(_, w)| *w).sum()
}

fn close(a: Vec3, b: Vec3, tol: f32) -> bool {
    (a - b).abs().max_element() <= tol
}

fn lum(c: [f64; 3]) -> f64 {
    0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2]
}

// ---------------------------------------------------------------- mia_material (§4.5)

fn mia(set: impl FnOnce(&mut SimpleGraph, usize)) -> MaterialIr {
    let mut g = SimpleGraph::new();
    let n = g.node("mia1", "mia_material");
    set(&mut g, n);
    lower(&g, n)
}

#[test]
fn mia_white_reflection_of_luminance_one_leaves_no_diffuse() {
    let ir = mia(|g, n| {
        g.setf(n, "reflectivity", 1.0)
            .setf(n, "brdf_0_degree_refl", 1.0)
            .setf(n, "brdf_90_degree_refl", 1.0);
    });
    for mu in [1.0, 0.5, 0.1] {
        let ws = weights(&ir, mu, &|_| Vec3::ONE);
        assert_eq!(w_of(&ws, "diffuse"), Vec3::ZERO, "at {mu}: {ws:?}");
        assert_eq!(w_of(&ws, "reflection"), Vec3::ONE);
    }
}

#[test]
fn mia_red_reflection_leaves_79_percent() {
    let ir = mia(|g, n| {
        g.setf(n, "reflectivity", 1.0)
            .setc(n, "refl_color", [1.0, 0.0, 0.0])
            .setf(n, "brdf_0_degree_refl", 1.0)
            .setf(n, "brdf_90_degree_refl", 1.0)
            .setc(n, "diffuse", [1.0, 1.0, 1.0]);
    });
    let ws = weights(&ir, 0.7, &|_| Vec3::ONE);
    let d = w_of(&ws, "diffuse");
    // Luminance-weighted: the same amount is removed from every channel.
    assert!(close(d, Vec3::splat(1.0 - 0.2126), 1e-6), "{d}");
    assert_eq!((d.x * 100.0).round(), 79.0);
}

/// §5.8: defaults except transparency 0.5 and translucency on, against a direct f64
/// implementation of §4.5's pseudocode.
#[test]
fn mia_four_weights_against_the_pseudocode() {
    for metal in [0, 1] {
        for fresnel in [0, 1] {
            let ir = mia(|g, n| {
                g.setf(n, "transparency", 0.5)
                    .seti(n, "refr_translucency", 1)
                    .seti(n, "refl_is_metal", metal)
                    .seti(n, "brdf_fresnel", fresnel)
                    .setc(n, "diffuse", [0.6, 0.3, 0.2]);
            });
            for mu in [1.0f64, 0.5, 0.2] {
                // Reference.
                let c = if fresnel == 1 {
                    fresnel_f64(mu, 1.4)
                } else {
                    let x = (1.0 - mu).powf(5.0);
                    0.2 * (1.0 - x) + 1.0 * x
                };
                let reflect = [0.6 * c; 3];
                let dcol = [0.6, 0.3, 0.2];
                let mut diffuse = dcol;
                let mut refract = [0.5; 3];
                let mut transl = [0.5 * 0.7, 0.5 * 0.6, 0.5 * 0.5];
                let t0 = lum(transl);
                let lr = lum(refract);
                diffuse = diffuse.map(|d| d * (1.0 - lr));
                refract = refract.map(|r| r * (1.0 - lum(reflect)));
                diffuse = diffuse.map(|d| d * (1.0 - lum(reflect)));
                for k in 0..3 {
                    transl[k] *= refract[k];
                }
                refract = refract.map(|r| r * (1.0 - t0));
                let r = if metal == 1 {
                    [
                        reflect[0] * dcol[0],
                        reflect[1] * dcol[1],
                        reflect[2] * dcol[2],
                    ]
                } else {
                    reflect
                };
                let v = |a: [f64; 3]| Vec3::new(a[0] as f32, a[1] as f32, a[2] as f32);
                let ws = weights(&ir, mu as f32, &|_| Vec3::ONE);
                for (label, want) in [
                    ("reflection", r),
                    ("diffuse", diffuse),
                    ("refraction", refract),
                    ("translucency", transl),
                ] {
                    let got = w_of(&ws, label);
                    assert!(
                        close(got, v(want), 2e-6),
                        "{label} metal={metal} fresnel={fresnel} mu={mu}: {got} vs {want:?}"
                    );
                }
            }
        }
    }
}

fn fresnel_f64(mu: f64, eta: f64) -> f64 {
    let g2 = eta * eta + mu * mu - 1.0;
    if g2 < 0.0 {
        return 1.0;
    }
    let g = g2.sqrt();
    let a = (g - mu) / (g + mu);
    let b = (mu * (g + mu) - 1.0) / (mu * (g - mu) + 1.0);
    0.5 * a * a * (1.0 + b * b)
}

// ---------------------------------------------------------- PhysicalMaterial (§4.4)

fn physical(set: impl FnOnce(&mut SimpleGraph, usize)) -> MaterialIr {
    let mut g = SimpleGraph::new();
    let n = g.node("phys1", "PhysicalMaterial");
    set(&mut g, n);
    lower(&g, n)
}

#[test]
fn physical_transparency_one_leaves_no_diffuse_or_sss() {
    let ir = physical(|g, n| {
        g.setf(n, "transparency", 1.0).setf(n, "scattering", 0.5);
    });
    let labels: Vec<_> = ir.leaves().map(|(_, l)| l.label.clone()).collect();
    assert!(!labels.contains(&"diffuse".to_string()), "{labels:?}");
    assert!(!labels.contains(&"sss".to_string()));
    assert!(labels.contains(&"transmission".to_string()));
}

#[test]
fn physical_metalness_one_leaves_only_reflection_and_coat() {
    let ir = physical(|g, n| {
        g.setf(n, "metalness", 1.0)
            .setf(n, "coating", 0.5)
            .setf(n, "transparency", 0.3)
            .setf(n, "scattering", 0.3);
    });
    let mut labels: Vec<_> = ir.leaves().map(|(_, l)| l.label.clone()).collect();
    labels.sort();
    assert_eq!(labels, ["coat", "metal"]);
}

/// The six scalar weights of §4.4 against a direct f64 implementation over a grid.
#[test]
fn physical_six_weights_against_direct_formula() {
    let grid = [0.0f32, 0.3, 1.0];
    let (e_r, e_c) = (0.35f32, 0.2f32);
    let coat_color = [0.9f32, 0.6, 0.3];
    let albedo = move |l: &str| match l {
        "reflection" => Vec3::splat(e_r),
        "coat" => Vec3::splat(e_c),
        _ => Vec3::ONE,
    };
    let mut checked = 0;
    for &w_r in &grid {
        for &w_t in &grid {
            for &w_s in &grid {
                for &m in &grid {
                    for &w_c in &grid {
                        let w_b = 0.8f32;
                        let ir = physical(|g, n| {
                            g.setf(n, "reflectivity", w_r)
                                .setf(n, "transparency", w_t)
                                .setf(n, "scattering", w_s)
                                .setf(n, "metalness", m)
                                .setf(n, "coating", w_c)
                                .setf(n, "base_weight", w_b)
                                .setc(n, "coat_color", coat_color);
                        });
                        let ws = weights(&ir, 0.6, &albedo);
                        let f = |x: f32| x as f64;
                        let k = 1.0 - f(w_r) * f(e_r);
                        let coat = |ch: usize| {
                            (1.0 - f(w_c)) + f(w_c) * f(coat_color[ch]) * (1.0 - f(e_c))
                        };
                        let expect = |s: f64| {
                            Vec3::new(
                                (s * coat(0)) as f32,
                                (s * coat(1)) as f32,
                                (s * coat(2)) as f32,
                            )
                        };
                        let diel = 1.0 - f(m);
                        let want = [
                            ("reflection", expect(f(w_r) * diel)),
                            ("transmission", expect(k * f(w_t) * diel)),
                            ("sss", expect(k * (1.0 - f(w_t)) * f(w_s) * diel)),
                            (
                                "diffuse",
                                expect(k * (1.0 - f(w_t)) * (1.0 - f(w_s)) * f(w_b) * diel),
                            ),
                            ("metal", expect(f(w_r) * f(m))),
                            ("coat", Vec3::splat(w_c)),
                        ];
                        for (label, v) in want {
                            let got = w_of(&ws, label);
                            assert!(
                                close(got, v, 2e-6),
                                "{label} at w_r={w_r} w_t={w_t} w_s={w_s} m={m} w_c={w_c}: {got} vs {v}"
                            );
                            checked += 1;
                        }
                    }
                }
            }
        }
    }
    assert_eq!(checked, 243 * 6);
}

// ---------------------------------------------------------------------- VRayMtl (§4.3)

/// Seed 000: `sheenBRDF·sheen_color + (1 − sheen_color·reflectance(sheenBRDF))·diffuse·diffuseBRDF`.
#[test]
fn vray_sheen_over_diffuse_formula() {
    let mut g = SimpleGraph::new();
    let n = g.node("v", "VRayMtl");
    let sheen = [0.8f32, 0.5, 0.2];
    g.setc(n, "sheen_color", sheen)
        .setc(n, "diffuse", [0.4, 0.5, 0.6]);
    let ir = lower(&g, n);
    for e in [0.1f32, 0.3, 0.7] {
        let ws = weights(&ir, 0.5, &|l| {
            if l == "sheen" {
                Vec3::splat(e)
            } else {
                Vec3::ONE
            }
        });
        let s = Vec3::from_array(sheen);
        assert!(close(w_of(&ws, "sheen"), s, 1e-7));
        assert!(
            close(w_of(&ws, "diffuse"), Vec3::ONE - s * e, 1e-6),
            "{ws:?}"
        );
    }
    // The diffuse colour is the lobe's albedo, not part of its weight.
    let d = ir.leaves().find(|(_, l)| l.label == "diffuse").unwrap().1;
    let regs = ir.run_program(None, 1.0);
    match d.kind {
        vstructc::ir::LeafKind::Lambert { albedo } => {
            assert_eq!(regs[albedo.index()], Vec3::new(0.4, 0.5, 0.6))
        }
        k => panic!("{k:?}"),
    }
}

#[test]
fn vray_metalness_one_removes_the_dielectric_stack() {
    let mut g = SimpleGraph::new();
    let n = g.node("v", "VRayMtl");
    g.setc(n, "reflect", [1.0; 3])
        .setf(n, "metalness", 1.0)
        .setc(n, "sheen_color", [0.5; 3]);
    let ir = lower(&g, n);
    let labels: Vec<_> = ir.leaves().map(|(_, l)| l.label.clone()).collect();
    assert_eq!(labels, ["metal"]);
}

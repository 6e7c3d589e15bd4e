//! The interpreter over whole materials (closures.md §1.4, §1.5, §5.3, §5.5): white furnace
//! of conserving configurations by deterministic quadrature, eval/pdf/sample consistency and
//! mean sample weight = albedo on several recipes, the prepare steps (weights against the
//! reference flattening, drop threshold, shared leaves, selection, absorbing materials,
//! transparency, emission, inputs, frames), the batched path against the scalar one, and
//! malformed IRs.

use glam::{Vec2, Vec3};
use vstructc::diag::{Diagnostics, Error};
use vstructc::interp::material::PrepareOptions;
use vstructc::interp::*;
use vstructc::ir::{
    Cl, DielectricMode, FrameSlot, Fresnel, IrBuilder, Leaf, LeafKind, Masking, MaterialIr, Node,
    NodeId, ProgramBuilder, RecipeId, Reg, TintMode,
};
use vstructc::lower::{NoDefinitions, SimpleGraph, lower_node};
use vstructc::types::{BaseType, Type, Value};
use vstructc_testkit::reference::{self, dielectric_r, lambert, mul, ref10_ir};
use vstructc_testkit::verify::Rng;

const MUS: [f32; 5] = [0.05, 0.2, 0.5, 0.8, 1.0];

fn view(mu: f32) -> Vec3 {
    Vec3::new((1.0 - mu * mu).max(0.0).sqrt(), 0.0, mu)
}

fn point(v: Vec3) -> ShadingPoint<'static> {
    ShadingPoint::new(Vec3::Z, Vec3::X, v)
}

fn finish(b: IrBuilder, root: Cl) -> MaterialIr {
    b.finish("test", RecipeId::Custom, root).expect("valid IR")
}

fn compile(ir: &MaterialIr) -> Material {
    Material::new(ir).expect("compiles")
}

// ---------------------------------------------------------------------------------------
// Building blocks.

fn sheen_ltc(b: &mut IrBuilder, r: f32) -> Cl {
    let r = b.prog.constf(r);
    b.simple_leaf(LeafKind::SheenLtc { roughness: r }, "fuzz")
}

fn sheen_ck(b: &mut IrBuilder, r: f32) -> Cl {
    reference::sheen_ck(b, r, "sheen")
}

fn schlick_metal(b: &mut IrBuilder, alpha: f32, f0: f32, comp: f32) -> Cl {
    let (a, f0, f90, q, k) = (
        b.prog.constf(alpha),
        b.prog.constf(f0),
        b.prog.constf(1.0),
        b.prog.constf(5.0),
        b.prog.constf(comp),
    );
    b.simple_leaf(
        LeafKind::MicrofacetR {
            alpha_x: a,
            alpha_y: a,
            fresnel: Fresnel::Schlick { f0, f90, q },
            masking: Masking::HeightCorrelated,
            comp: k,
        },
        "metal",
    )
}

fn dielectric_rt(b: &mut IrBuilder, alpha: f32, eta: f32) -> Cl {
    let (a, e, one) = (b.prog.constf(alpha), b.prog.constf(eta), b.prog.constf(1.0));
    b.simple_leaf(
        LeafKind::Dielectric {
            alpha_x: a,
            alpha_y: a,
            eta: e,
            mode: DielectricMode::Rt,
            refl_tint: one,
            trans_tint: one,
            t_fresnel: true,
            masking: Masking::HeightCorrelated,
        },
        "glass",
    )
}

/// `layer[mode](top, lambert ρ = 1)`.
fn over_white(mode: TintMode, top: impl Fn(&mut IrBuilder) -> Cl) -> MaterialIr {
    let mut b = IrBuilder::new();
    let t = top(&mut b);
    let base = lambert(&mut b, Vec3::ONE, "diffuse");
    let root = b.layer(t, base, mode);
    finish(b, root)
}

// ---------------------------------------------------------------------------------------
// Deterministic quadrature.

/// `∫ f |μ_i| dω` by the material's own one-sample MIS estimator on a stratified grid of
/// `n × n` values of `(u0, u1)` (with a fixed irrational sequence for `u2`): deterministic,
/// and exact in expectation whatever the lobes' shapes (delta lobes included).
fn quadrature(p: &Prepared, n: usize) -> [f64; 3] {
    let mut acc = [0.0f64; 3];
    for i in 0..n {
        for j in 0..n {
            let u = [
                (i as f32 + 0.5) / n as f32,
                (j as f32 + 0.5) / n as f32,
                ((i * n + j) as f32 * 0.618_034).fract(),
            ];
            if let Some(s) = p.sample(u) {
                for (a, w) in acc.iter_mut().zip(s.weight.to_array()) {
                    *a += f64::from(w);
                }
            }
        }
    }
    acc.map(|a| a / (n * n) as f64)
}

fn assert_furnace(name: &str, ir: &MaterialIr, mus: &[f32], tol: f64) {
    let m = compile(ir);
    for &mu in mus {
        let p = m.prepare(&point(view(mu)));
        let e = quadrature(&p, 320);
        for c in e {
            assert!((c - 1.0).abs() <= tol, "{name} μ {mu}: ∫f|μ_i| = {e:?}");
        }
        // The preview's furnace uses albedo(): 1 by the layering algebra.
        let a = p.albedo().total();
        assert!(
            (a - Vec3::ONE).abs().max_element() <= 1e-5,
            "{name} μ {mu}: {a}"
        );
    }
}

#[test]
fn furnace_white_lambert_is_one() {
    let mut b = IrBuilder::new();
    let root = lambert(&mut b, Vec3::ONE, "diffuse");
    let ir = finish(b, root);
    assert_furnace("lambert", &ir, &MUS, 1e-6);
}

#[test]
fn furnace_dielectric_over_white_lambert() {
    // §5.3: layer[Rgb](dielectric R, lambert ρ = 1) using tabulated E: 1 (table error, 3e-3).
    for alpha in [0.05f32, 0.3, 0.7] {
        let ir = over_white(TintMode::Rgb, |b| {
            dielectric_r(b, alpha, alpha, 1.5, "coat")
        });
        assert_furnace(&format!("dielectric α {alpha}"), &ir, &MUS, 3e-3);
    }
    // Anisotropic: the §5.3 row "any roughness, anisotropy", 2e-2.
    let ir = over_white(TintMode::Rgb, |b| dielectric_r(b, 0.1, 0.5, 1.5, "coat"));
    assert_furnace("dielectric anisotropic", &ir, &[0.5, 0.8, 1.0], 2e-2);
}

#[test]
fn anisotropic_table_lookup_error_at_grazing() {
    // At μ_o = 0.2 along the narrow axis the lookup at α = √(α_x α_y) was off by 7 %; the
    // anisotropic tables (`tables::aniso_albedo`) bring it within the §5.3 bound.
    let ir = over_white(TintMode::Rgb, |b| dielectric_r(b, 0.1, 0.5, 1.5, "coat"));
    let p = compile(&ir).prepare(&point(view(0.2)));
    let e = quadrature(&p, 320)[0];
    assert!((e - 1.0).abs() < 2e-2, "{e}");
}

#[test]
fn furnace_sheens_over_white_lambert() {
    // §5.3: layer[Gray](sheenLTC, lambert) 1 (1e-3; exact mass); layer[Rgb](sheenCK, lambert)
    // 1 (3e-3).
    for r in [0.3f32, 0.5, 1.0] {
        let ir = over_white(TintMode::Gray, |b| sheen_ltc(b, r));
        assert_furnace(&format!("sheenLTC r {r}"), &ir, &MUS, 1e-3);
        let ir = over_white(TintMode::Rgb, |b| sheen_ck(b, r));
        assert_furnace(&format!("sheenCK r {r}"), &ir, &MUS, 3e-3);
    }
}

#[test]
fn furnace_white_metal_with_turquin_compensation() {
    // §5.3: metal (generalized Schlick F0 = 1), Turquin k = 1: 1 (1e-2).
    for alpha in [0.1f32, 0.5, 1.0] {
        let mut b = IrBuilder::new();
        let root = schlick_metal(&mut b, alpha, 1.0, 1.0);
        let ir = finish(b, root);
        let m = compile(&ir);
        for mu in [0.2f32, 0.5, 0.8, 1.0] {
            let e = quadrature(&m.prepare(&point(view(mu))), 320);
            assert!((e[0] - 1.0).abs() <= 1e-2, "α {alpha} μ {mu}: {e:?}");
        }
    }
}

#[test]
fn furnace_mixes_and_coats_of_conserving_configurations() {
    // §5.3: any mix of the above, and any of the above under a white coat: 1 (2e-2).
    let mut b = IrBuilder::new();
    let d1 = dielectric_r(&mut b, 0.2, 0.2, 1.5, "spec");
    let base1 = lambert(&mut b, Vec3::ONE, "diffuse");
    let a = b.layer(d1, base1, TintMode::Rgb);
    let s = sheen_ltc(&mut b, 0.5);
    let base2 = lambert(&mut b, Vec3::ONE, "diffuse2");
    let c = b.layer(s, base2, TintMode::Gray);
    let m = b.prog.constf(0.3);
    let mixed = b.mix(a, c, m);
    let coat = dielectric_r(&mut b, 0.05, 0.05, 1.5, "coat");
    let coated = b.layer(coat, mixed, TintMode::Rgb);
    let fuzz = sheen_ck(&mut b, 0.4);
    let root = b.layer(fuzz, coated, TintMode::Rgb);
    let ir = finish(b, root);
    assert_furnace("coat and fuzz over a mix", &ir, &[0.2, 0.5, 0.8, 1.0], 2e-2);
}

#[test]
fn furnace_detects_an_absorbing_material() {
    // The furnace check above must be able to fail: ρ = 0.5 integrates to 0.5.
    let mut b = IrBuilder::new();
    let root = lambert(&mut b, Vec3::splat(0.5), "diffuse");
    let m = compile(&finish(b, root));
    let e = quadrature(&m.prepare(&point(view(0.7))), 64);
    assert!((e[0] - 0.5).abs() < 1e-5, "{e:?}");
}

#[test]
fn dielectric_rt_energy_matches_the_table_and_stays_below_one() {
    // §5.3: E_R + η'² E_T ≤ 1, equal to the tabulated single-scattering value within 2e-3.
    // The spec's examples (0.9664 at α = 0.5, μ_o = 0.8; 0.9481 at 0.5) are not reproduced
    // by two independent quadratures (tests/materials/leaves_furnace.rs pins 0.94576 and 0.89263);
    // the material must report the leaf's value.
    let mut b = IrBuilder::new();
    let root = dielectric_rt(&mut b, 0.5, 1.5);
    let m = compile(&finish(b, root));
    for (mu, expect) in [(0.8f32, 0.94576f32), (0.5, 0.89263)] {
        let a = m.prepare(&point(view(mu))).albedo();
        let e = a.reflect.x + a.transmit.x;
        assert!((e - expect).abs() < 2e-3, "μ {mu}: {e}");
        assert!(e <= 1.0);
        // Energy and radiance conventions differ by η'² = 2.25 for light entering glass.
        assert!((a.transmit.x - 2.25 * a.transmit_radiance.x).abs() < 1e-6);
    }
}

// ---------------------------------------------------------------------------------------
// Sampling consistency (§5.5) on whole materials.

fn recipe(shader: &str, set: impl FnOnce(&mut SimpleGraph, usize)) -> MaterialIr {
    let mut g = SimpleGraph::new();
    let n = g.node("m", shader);
    set(&mut g, n);
    let mut d = Diagnostics::new();
    lower_node(&g, &NoDefinitions, n, shader, &mut d).expect("lowers")
}

fn materials() -> Vec<(String, MaterialIr)> {
    let mut v = vec![("ref10".to_string(), ref10_ir())];
    v.push((
        "coat over lambert".into(),
        over_white(TintMode::Rgb, |b| dielectric_r(b, 0.3, 0.3, 1.5, "coat")),
    ));
    let mut b = IrBuilder::new();
    let glass = dielectric_rt(&mut b, 0.3, 1.5);
    v.push(("rough glass".into(), finish(b, glass)));
    let mut b = IrBuilder::new();
    let l = lambert(&mut b, Vec3::new(0.8, 0.5, 0.2), "diffuse");
    let tau = b.prog.constant3(Vec3::new(0.3, 0.6, 0.9));
    let t = b.transparent(tau);
    let m = b.prog.constf(0.4);
    let root = b.mix(l, t, m);
    v.push(("lambert + transparency".into(), finish(b, root)));
    for shader in ["PxrSurface", "VRayMtl", "PhysicalMaterial", "mia_material"] {
        v.push((format!("{shader} defaults"), recipe(shader, |_, _| {})));
    }
    v.push((
        "PxrSurface all lobes".into(),
        recipe("PxrLayerSurface", |g, n| {
            g.setf(n, "diffuseRoughness", 0.3);
            g.setc(n, "specularFaceColor", [0.04; 3])
                .setc(n, "specularEdgeColor", [1.0; 3]);
            g.setf(n, "specularRoughness", 0.3);
            g.setc(n, "clearcoatFaceColor", [0.04; 3])
                .setc(n, "clearcoatEdgeColor", [1.0; 3]);
            g.setf(n, "clearcoatRoughness", 0.1);
            g.setf(n, "fuzzGain", 0.5)
                .setc(n, "fuzzColor", [0.9, 0.8, 0.7]);
            g.setf(n, "refractionGain", 0.5)
                .setf(n, "reflectionGain", 1.0);
            g.setf(n, "glowGain", 0.1)
                .setc(n, "glowColor", [1.0, 0.5, 0.0]);
            g.setf(n, "presence", 0.9);
        }),
    ));
    v
}

#[test]
fn sample_pdf_weight_and_mean_agree_with_eval_and_albedo() {
    // The relative error of the albedo tables at view `v` (§3.17: 2e-3 for α ≥ 0.05, more
    // for the sheen fits), but 5e-2 for a view from inside the materials' glass (η = 1.5)
    // within one table node of its critical angle: there the albedo of a smooth interface
    // steps with total internal reflection, which the 32 linear μ nodes cannot follow (the
    // coat of ref10, α = 0.05, reads 2.9 % low at μ_o = 0.740 against μ_c = 0.745; the same
    // exception as tests/materials/leaves_chi2.rs).
    fn table_tolerance(v: Vec3) -> f64 {
        let critical = (1.0f32 - 1.0 / (1.5 * 1.5)).sqrt();
        if v.z < 0.0 && (v.z.abs() - critical).abs() < 1.0 / 31.0 {
            5e-2
        } else {
            5e-3
        }
    }
    for (name, ir) in materials() {
        let m = compile(&ir);
        let mut rng = Rng::new(0x5eed ^ name.len() as u64);
        for run in 0..4 {
            // A cosine-distributed view; from below on odd runs (two-sided lobes flip).
            let mut v = rng.cosine();
            if run % 2 == 1 {
                v.z = -v.z;
            }
            let p = m.prepare(&point(v));
            let n = 20_000;
            let (mut sum, mut sum2) = (glam::DVec3::ZERO, glam::DVec3::ZERO);
            for _ in 0..n {
                let Some(s) = p.sample(rng.u3()) else {
                    continue;
                };
                assert!(
                    s.weight.is_finite() && s.weight.min_element() >= 0.0,
                    "{name}"
                );
                if !s.delta {
                    let e = p.eval(s.l);
                    let tol = 1e-4 * e.pdf.max(1e-6);
                    assert!(
                        (s.pdf - e.pdf).abs() <= tol,
                        "{name}: pdf {} vs {}",
                        s.pdf,
                        e.pdf
                    );
                    let w = e.f_cos / e.pdf;
                    assert!(
                        (s.weight - w).abs().max_element() <= 1e-4 * w.max_element().max(1e-3),
                        "{name}: weight"
                    );
                } else if s.lobe == Sample::TRANSPARENCY_LOBE {
                    assert_eq!(s.l, -p.view());
                }
                let w = s.weight.as_dvec3();
                sum += w;
                sum2 += w * w;
            }
            let mean = sum / n as f64;
            let var = (sum2 / n as f64 - mean * mean).max(glam::DVec3::ZERO);
            let se = (var / n as f64).powf(0.5);
            let a = p.albedo();
            let expect = (a.reflect + a.transmit_radiance + p.transparency()).as_dvec3();
            let table = table_tolerance(v);
            for c in 0..3 {
                // 3 standard errors, plus the albedo tables' own error relative to the value.
                let tol = 3.0 * se[c] + table * expect[c].max(1e-3);
                assert!(
                    (mean[c] - expect[c]).abs() <= tol,
                    "{name} run {run} v {v}: mean {mean} vs albedo {expect} (se {se})"
                );
            }
        }
    }
}

#[test]
fn mixture_pdf_integrates_to_one_without_delta_lobes() {
    // Rough lobes only (no delta): ∫ pdf dω over the sphere = 1. Midpoint rule in (cos θ, φ).
    let mut b = IrBuilder::new();
    let d = dielectric_r(&mut b, 0.3, 0.5, 1.5, "spec");
    let l = lambert(&mut b, Vec3::splat(0.5), "diffuse");
    let top = b.layer(d, l, TintMode::Rgb);
    let s = sheen_ck(&mut b, 0.5);
    let root = b.layer(s, top, TintMode::Rgb);
    let m = compile(&finish(b, root));
    for mu in [0.3f32, 0.9] {
        let p = m.prepare(&point(view(mu)));
        let (nt, np) = (400, 800);
        let mut acc = 0.0f64;
        for i in 0..nt {
            let z = -1.0 + 2.0 * (i as f32 + 0.5) / nt as f32;
            let r = (1.0 - z * z).max(0.0).sqrt();
            for j in 0..np {
                let phi = std::f32::consts::TAU * (j as f32 + 0.5) / np as f32;
                let l = Vec3::new(r * phi.cos(), r * phi.sin(), z);
                acc += f64::from(p.eval(l).pdf);
            }
        }
        let total = acc * 4.0 * std::f64::consts::PI / (nt * np) as f64;
        assert!((total - 1.0).abs() < 1e-2, "μ {mu}: ∫pdf = {total}");
    }
}

// ---------------------------------------------------------------------------------------
// The prepare steps.

#[test]
fn weights_equal_the_reference_flattening_with_table_albedos() {
    // The interpreter's allocation-free throughput and weight passes against
    // `ir::algebra::flatten` with the same tables (`TableAlbedo`).
    for (name, ir) in materials() {
        let m = compile(&ir);
        for mu in [0.1f32, 0.5, 1.0] {
            let p = m.prepare(&point(view(mu)));
            let flat = ir.weights(None, mu, &TableAlbedo);
            for a in p.lobes() {
                let node = m.leaves()[a.leaf as usize].node;
                let w = flat.weight_of(node).max(Vec3::ZERO);
                assert!(
                    (a.weight - w).abs().max_element() <= 1e-5 * w.max_element().max(1e-3),
                    "{name} μ {mu} node {node:?}: {} vs {w}",
                    a.weight
                );
            }
            let e = flat.emission;
            assert!((p.emission() - e).abs().max_element() <= 1e-5, "{name}");
            let t = flat.transparency;
            assert!((p.transparency() - t).abs().max_element() <= 1e-5, "{name}");
        }
    }
}

/// A material whose specular lobe has Fresnel colours from an input (so it is not dropped
/// statically), over a Lambert.
fn spec_from_input() -> MaterialIr {
    let mut b = IrBuilder::new();
    let col = Type::scalar(BaseType::Color);
    let f0 = b.input_slot("tex.rgb", col, Value::Triple(BaseType::Color, [0.04; 3]));
    let (a, q, zero) = (b.prog.constf(0.3), b.prog.constf(5.0), b.prog.constf(0.0));
    let spec = b.simple_leaf(
        LeafKind::MicrofacetR {
            alpha_x: a,
            alpha_y: a,
            fresnel: Fresnel::Schlick { f0, f90: f0, q },
            masking: Masking::HeightCorrelated,
            comp: zero,
        },
        "specular",
    );
    let base = lambert(&mut b, Vec3::splat(0.5), "diffuse");
    let root = b.layer(spec, base, TintMode::Rgb);
    finish(b, root)
}

#[test]
fn zero_albedo_lobes_are_dropped_unless_disabled() {
    let ir = spec_from_input();
    let black = [0.0f32; 3];
    let v = view(0.6);
    let m = compile(&ir);
    let kept = m.prepare(&point(v).with_inputs(&black));
    assert_eq!(kept.lobes().len(), 1, "the black specular is dropped");
    assert_eq!(kept.lobes()[0].lobe.kind(), LobeKind::Lambert);
    let all = Material::with_options(
        &ir,
        PrepareOptions {
            drop_threshold: 0.0,
            ..PrepareOptions::default()
        },
    )
    .unwrap();
    let both = all.prepare(&point(v).with_inputs(&black));
    assert_eq!(both.lobes().len(), 2);
    // Dropping changes nothing but the lobe count.
    let mut rng = Rng::new(3);
    for _ in 0..100 {
        let l = rng.cosine();
        assert_eq!(kept.eval(l).f_cos, both.eval(l).f_cos);
    }
    // With the fallback (0.04) the specular lives.
    assert_eq!(m.prepare(&point(v)).lobes().len(), 2);
}

#[test]
fn inputs_take_fallbacks_when_missing_and_values_when_given() {
    let ir = spec_from_input();
    let m = compile(&ir);
    assert_eq!(m.input_layout(), &[(0, 3)]);
    assert_eq!(m.fallback_inputs(), vec![0.04; 3]);
    let v = view(1.0);
    let fallback = m.prepare(&point(v)).albedo().reflect;
    let short = m
        .prepare(&point(v).with_inputs(&[0.5, 0.5]))
        .albedo()
        .reflect;
    assert_eq!(fallback, short, "a partial slot takes its fallback");
    let given = m
        .prepare(&point(v).with_inputs(&[0.5, 0.5, 0.5]))
        .albedo()
        .reflect;
    assert!(given.x > fallback.x + 0.1, "{given} vs {fallback}");
}

#[test]
fn a_shared_leaf_is_one_lobe_with_the_summed_weight() {
    let mut b = IrBuilder::new();
    let l = lambert(&mut b, Vec3::ONE, "diffuse");
    let a = mul(&mut b, l, 0.3);
    let c = mul(&mut b, l, 0.2);
    let root = b.add(a, c);
    let m = compile(&finish(b, root));
    let p = m.prepare(&point(view(0.5)));
    assert_eq!(p.lobes().len(), 1);
    assert!((p.lobes()[0].weight - Vec3::splat(0.5)).abs().max_element() < 1e-6);
}

#[test]
fn selection_follows_albedo_luminance() {
    let ir = spec_from_input();
    let m = compile(&ir);
    let p = m.prepare(&point(view(0.8)));
    let lums: Vec<f32> = p
        .lobes()
        .iter()
        .map(|a| vstructc::interp::math::lum(a.albedo.reflect))
        .collect();
    let sum: f32 = lums.iter().sum();
    for (a, l) in p.lobes().iter().zip(&lums) {
        assert!((a.prob - l / sum).abs() < 1e-6);
    }
    let total: f32 = p.lobes().iter().map(|a| a.prob).sum();
    assert!((total - 1.0).abs() < 1e-6);
}

/// A colour input `tex.rgb` (fallback 0.5 grey), for albedos the tests set per point.
fn grey_input(b: &mut IrBuilder) -> Reg {
    let col = Type::scalar(BaseType::Color);
    b.input_slot("tex.rgb", col, Value::Triple(BaseType::Color, [0.5; 3]))
}

#[test]
fn lobes_that_reflect_nothing_are_selected_by_weight() {
    // Two black Lamberts kept (no drop): every albedo is 0, so step 7 falls back to
    // `lum(w_k)`, here the mix's 0.75 and 0.25.
    let mut b = IrBuilder::new();
    let rho = grey_input(&mut b);
    let first = b.simple_leaf(LeafKind::Lambert { albedo: rho }, "first");
    let second = b.simple_leaf(LeafKind::Lambert { albedo: rho }, "second");
    let m = b.prog.constf(0.25);
    let root = b.mix(first, second, m);
    let opts = PrepareOptions {
        drop_threshold: 0.0,
        ..PrepareOptions::default()
    };
    let m = Material::with_options(&finish(b, root), opts).unwrap();
    let p = m.prepare(&point(view(0.5)).with_inputs(&[0.0; 3]));
    assert_eq!(p.lobes().len(), 2);
    for a in p.lobes() {
        // The weight's own share: `lum(w) = w` for a grey weight.
        assert!(a.weight == Vec3::splat(0.25) || a.weight == Vec3::splat(0.75));
        assert!((a.prob - a.weight.x).abs() < 1e-6, "{a:?}");
    }
    assert!(!p.is_absorbing());
    // With albedo, the shares follow the weighted albedos (the same here: one ρ for both).
    let lit = m.prepare(&point(view(0.5)).with_inputs(&[0.5; 3]));
    for a in lit.lobes() {
        assert!((a.prob - a.weight.x).abs() < 1e-6, "{a:?}");
    }
}

#[test]
fn an_absorbing_material_samples_nothing() {
    let mut b = IrBuilder::new();
    let rho = grey_input(&mut b);
    let root = b.simple_leaf(LeafKind::Lambert { albedo: rho }, "diffuse");
    let m = compile(&finish(b, root));
    let p = m.prepare(&point(view(0.5)).with_inputs(&[0.0; 3]));
    assert!(p.is_absorbing());
    assert_eq!(p.sample([0.3, 0.3, 0.3]), None);
    assert_eq!(p.albedo().total(), Vec3::ZERO);
    assert_eq!(p.eval(Vec3::Z), Eval::default());
}

#[test]
fn transparency_and_emission_accumulate_and_sample() {
    let mut b = IrBuilder::new();
    let l = lambert(&mut b, Vec3::splat(0.5), "diffuse");
    let tau = b.prog.constant3(Vec3::new(1.0, 0.5, 0.25));
    let t = b.transparent(tau);
    let glow = b.prog.constant3(Vec3::new(2.0, 1.0, 0.0));
    let e = b.emission(glow);
    let m = b.prog.constf(0.25);
    let mixed = b.mix(l, t, m);
    let root = b.add(mixed, e);
    let m = compile(&finish(b, root));
    let v = view(0.6);
    let p = m.prepare(&point(v));
    assert_eq!(p.transparency(), Vec3::new(0.25, 0.125, 0.0625));
    assert_eq!(p.emission(), Vec3::new(2.0, 1.0, 0.0));
    assert_eq!(p.lobes().len(), 1, "transparency is not a lobe");
    // u[0] past every lobe interval chooses straight transmission.
    let s = p.sample([0.999, 0.5, 0.5]).expect("transmission");
    assert_eq!(s.lobe, Sample::TRANSPARENCY_LOBE);
    assert!(s.delta);
    assert_eq!(s.l, -v);
    assert!((s.weight * s.pdf - p.transparency()).abs().max_element() < 1e-6);
}

#[test]
fn a_lobe_uses_its_own_frame() {
    // A Lambert whose normal comes from an input: tilting it moves the response.
    let mut b = IrBuilder::new();
    let nty = Type::scalar(BaseType::Normal);
    let n = b.input_slot("bump.n", nty, Value::Triple(BaseType::Normal, [0.0; 3]));
    let frame = b.frame(FrameSlot {
        normal: Some(n),
        tangent: None,
        rotation: None,
    });
    let one = b.prog.constf(1.0);
    let root = b.leaf(Leaf {
        kind: LeafKind::Lambert { albedo: one },
        tint: one,
        ttint: one,
        frame,
        label: "diffuse".into(),
    });
    let m = compile(&finish(b, root));
    let v = view(1.0);
    let l = Vec3::new(0.6, 0.0, 0.8);
    // Zero normal input: the shading normal.
    let p = m.prepare(&point(v));
    assert!((p.eval(l).f_cos.x - 0.8 / std::f32::consts::PI).abs() < 1e-6);
    // Normal tilted toward L: μ_i = L·n.
    let tilted = Vec3::new(0.6, 0.0, 0.8);
    let p = m.prepare(&point(v).with_inputs(&tilted.to_array()));
    assert!((p.eval(l).f_cos.x - 1.0 / std::f32::consts::PI).abs() < 1e-5);
    assert!((p.frame(0).z - tilted).length() < 1e-6);
}

#[test]
fn globals_reach_the_program() {
    // albedo = u (through the program's `u` global).
    let mut b = IrBuilder::new();
    let u = b.prog.global(vstructc::ir::Global::U);
    let root = b.simple_leaf(LeafKind::Lambert { albedo: u }, "diffuse");
    let m = compile(&finish(b, root));
    let p = m.prepare(&point(view(1.0)).with_uv(Vec2::new(0.25, 0.0)));
    assert_eq!(p.albedo().reflect, Vec3::splat(0.25));
}

// ---------------------------------------------------------------------------------------
// Batched path.

fn batch_equals_scalar<const W: usize>(ir: &MaterialIr, seed: u64) {
    let m = compile(ir);
    let mut rng = Rng::new(seed);
    let frames: [Frame; W] = std::array::from_fn(|_| Frame::new(rng.sphere(), rng.sphere()));
    let vs: [Vec3; W] = std::array::from_fn(|k| {
        let v = rng.sphere();
        if v.dot(frames[k].z) < 0.0 && k % 3 != 0 {
            -v
        } else {
            v
        }
    });
    let batch = ShadingBatch::<W>::new(
        std::array::from_fn(|k| frames[k].z),
        std::array::from_fn(|k| frames[k].x),
        vs,
    );
    let pb = m.prepare_batch(&batch);
    for _ in 0..50 {
        let ls: [Vec3; W] = std::array::from_fn(|_| rng.sphere());
        let out = pb.eval(&ls);
        for k in 0..W {
            let s = m.prepare(&batch.lane(k)).eval(ls[k]);
            let tol = |x: f32| 1e-5 * x.abs().max(1e-6);
            assert!(
                (out[k].f_cos - s.f_cos).abs().max_element() <= tol(s.f_cos.max_element()),
                "lane {k}"
            );
            assert!((out[k].pdf - s.pdf).abs() <= tol(s.pdf), "lane {k}");
        }
    }
}

#[test]
fn batched_eval_equals_scalar_for_8_and_16_lanes() {
    for (name, ir) in materials() {
        let seed = name.len() as u64;
        batch_equals_scalar::<8>(&ir, seed);
        batch_equals_scalar::<16>(&ir, seed + 1);
    }
}

// ---------------------------------------------------------------------------------------
// Malformed IRs.

#[test]
fn malformed_and_oversized_irs_are_errors() {
    let mut ir = ref10_ir();
    // A child before its parent.
    if let vstructc::ir::Node::Layer { top, .. } = &mut ir.nodes[0] {
        *top = vstructc::ir::NodeId(0);
    }
    match Material::new(&ir) {
        Err(Error::Input(d)) => assert_eq!(d.code, "IR001"),
        other => panic!("expected IR001, got {:?}", other.map(|_| ())),
    }
    // Seventeen lobes (built by hand: the builder would refuse them itself).
    let mut pb = ProgramBuilder::new();
    let one = pb.constf(1.0);
    let leaf = Node::Leaf(Leaf {
        kind: LeafKind::Lambert { albedo: one },
        tint: one,
        ttint: one,
        frame: 0,
        label: "diffuse".into(),
    });
    let mut nodes = Vec::new();
    for k in 0..16u32 {
        nodes.push(Node::Add {
            a: NodeId(2 * k + 1),
            b: NodeId(2 * k + 2),
        });
        nodes.push(leaf.clone());
    }
    nodes.push(leaf);
    let ir = MaterialIr {
        name: "many".into(),
        recipe: RecipeId::Custom,
        inputs: Vec::new(),
        program: pb.program(),
        nodes,
        frames: vec![FrameSlot::default()],
        max_static_lobes: 17,
    };
    match Material::new(&ir) {
        Err(Error::Input(d)) => assert_eq!(d.code, "LW010"),
        other => panic!("expected LW010, got {:?}", other.map(|_| ())),
    }
    // Sixteen are fine: node 28 = add(29, 30) with two leaves ends the chain.
    let mut ok = ir.clone();
    ok.nodes.truncate(30);
    ok.nodes.push(ok.nodes[1].clone());
    let m = Material::new(&ok).expect("16 lobes compile");
    assert_eq!(m.leaves().len(), 16);
    assert_eq!(m.prepare(&point(view(0.5))).lobes().len(), 16);
}

/// Seen from below, the two-sided lobes are flipped (the one-sided ones are inactive): the
/// material's eval, which skips the per-lobe flip when no lobe is flipped, must then flip
/// each lobe itself and agree with the lobes evaluated one by one.
#[test]
fn eval_from_below_flips_the_two_sided_lobes() {
    tables::init_all();
    let m = compile(&ref10_ir());
    let mut rng = Rng::new(61);
    for _ in 0..50 {
        let v = -view(0.2 + 0.7 * rng.f32());
        let p = m.prepare(&point(v));
        assert!(
            p.lobes().iter().any(|a| a.lobe.is_flipped()),
            "a dielectric lobe is flipped"
        );
        for _ in 0..20 {
            let l = rng.sphere();
            let total = p.eval(l).f_cos;
            let sum: Vec3 = (0..p.lobes().len()).map(|k| p.eval_lobe(k, l).f_cos).sum();
            assert!(
                (total - sum).abs().max_element() <= 1e-5 * sum.abs().max_element().max(1e-6),
                "v {v} l {l}: eval {total} vs lobes {sum}"
            );
        }
    }
}

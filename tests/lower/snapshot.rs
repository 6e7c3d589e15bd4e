//! Snapshots of the IR and the lobe list for material configurations of every model, with
//! features switched on and off (closures.md §5.8). Weights are printed at μ_o = 1 and 0.5
//! with `SimpleAlbedo` (smooth-surface Fresnel estimates), so they can be checked by hand.

use vstructc::diag::Diagnostics;
use vstructc::ir::SimpleAlbedo;
use vstructc::lower::{NoDefinitions, SimpleGraph, lower_node};

fn snap(name: &str, g: &SimpleGraph, n: usize) {
    let mut d = Diagnostics::new();
    let ir = lower_node(g, &NoDefinitions, n, name, &mut d).expect("lowers");
    let mut text = ir.text();
    text.push('\n');
    text.push_str(&ir.lobes_text(&SimpleAlbedo));
    let codes: Vec<&str> = d
        .iter()
        .map(|d| d.code.as_str())
        .filter(|c| *c != "LW003")
        .collect();
    text.push_str(&format!("\ndiagnostics: {codes:?}\n"));
    insta::assert_snapshot!(name, text);
}

fn one(shader: &str, set: impl FnOnce(&mut SimpleGraph, usize)) -> (SimpleGraph, usize) {
    let mut g = SimpleGraph::new();
    let n = g.node("m", shader);
    set(&mut g, n);
    (g, n)
}

#[test]
fn pxr_surface_defaults() {
    let (g, n) = one("PxrSurface", |_, _| {});
    snap("pxr_surface_defaults", &g, n);
}

#[test]
fn pxr_surface_all_lobes() {
    let (g, n) = one("PxrLayerSurface", |g, n| {
        g.setf(n, "diffuseRoughness", 0.3);
        g.setc(n, "specularFaceColor", [0.04; 3])
            .setc(n, "specularEdgeColor", [1.0; 3]);
        g.setc(n, "roughSpecularFaceColor", [0.02; 3])
            .setc(n, "roughSpecularEdgeColor", [0.5; 3]);
        g.setc(n, "clearcoatFaceColor", [0.04; 3])
            .setc(n, "clearcoatEdgeColor", [1.0; 3]);
        g.setf(n, "clearcoatThickness", 0.5)
            .setc(n, "clearcoatAbsorptionTint", [0.8, 0.3, 0.1]);
        g.setf(n, "fuzzGain", 0.5)
            .setc(n, "fuzzColor", [0.9, 0.8, 0.7]);
        g.setf(n, "subsurfaceGain", 0.25);
        g.setf(n, "refractionGain", 0.5)
            .setf(n, "reflectionGain", 1.0);
        g.setf(n, "glowGain", 0.1)
            .setc(n, "glowColor", [1.0, 0.5, 0.0]);
        g.setf(n, "presence", 0.9);
    });
    snap("pxr_surface_all_lobes", &g, n);
}

#[test]
fn pxr_surface_physical_fresnel_anisotropy_bump() {
    let (mut g, n) = one("PxrSurface", |g, n| {
        g.seti(n, "specularFresnelMode", 1)
            .setc(n, "specularIor", [0.183, 0.421, 1.373]);
        g.setc(n, "specularExtinctionCoeff", [3.424, 2.346, 1.770]);
        g.setf(n, "specularAnisotropy", -0.5)
            .seti(n, "specularModelType", 1);
        g.setf(n, "diffuseGain", 0.0);
    });
    let bump = g.node("bump", "PxrNormalMap");
    g.connect(n, "specularBumpNormal", bump, "resultN");
    snap("pxr_surface_physical_fresnel_anisotropy_bump", &g, n);
}

#[test]
fn pxr_surface_thin_glass_and_diffuse_transmission() {
    let (g, n) = one("PxrSurface", |g, n| {
        g.seti(n, "diffuseDoubleSided", 1)
            .setf(n, "diffuseTransmitGain", 0.4);
        g.setf(n, "refractionGain", 0.3)
            .setf(n, "reflectionGain", 0.5)
            .seti(n, "thinGlass", 1);
        g.setc(n, "refractionColor", [0.9, 1.0, 0.9]);
    });
    snap("pxr_surface_thin_glass_and_diffuse_transmission", &g, n);
}

#[test]
fn pxr_surface_fused_patterns() {
    let mut g = SimpleGraph::new();
    let uv = g.node("uv", "vsUvManifold");
    g.setf(uv, "scaleS", 4.0).setf(uv, "scaleT", 4.0);
    let ch = g.node("checker", "vsChecker");
    g.connect(ch, "manifold", uv, "result");
    g.setc(ch, "colorA", [0.8, 0.1, 0.1])
        .setc(ch, "colorB", [0.1, 0.1, 0.8]);
    let noise = g.node("noise", "vsValueNoise");
    g.setf(noise, "frequency", 8.0);
    let remap = g.node("remap", "vsRemap");
    g.connect(remap, "input", noise, "resultRGB");
    g.setf(remap, "outputMin", 0.1)
        .setf(remap, "outputMax", 0.4);
    let clamp = g.node("clamp", "vsClamp");
    g.connect(clamp, "input", remap, "resultRGB");
    g.setc(clamp, "max", [0.3; 3]);
    let k = g.node("k", "vsConstant");
    g.setc(k, "color", [0.04; 3]);
    let mix = g.node("mix", "vsMix");
    g.connect(mix, "color1", k, "resultRGB");
    g.setc(mix, "color2", [1.0; 3]).setf(mix, "mix", 0.25);
    let s = g.node("surface", "PxrSurface");
    g.connect(s, "diffuseColor", ch, "resultRGB");
    g.connect(s, "specularRoughness", clamp, "resultF");
    g.connect(s, "specularFaceColor", k, "resultRGB");
    g.connect(s, "specularEdgeColor", mix, "resultRGB");
    snap("pxr_surface_fused_patterns", &g, s);
}

#[test]
fn vray_defaults() {
    let (g, n) = one("VRayMtl", |_, _| {});
    snap("vray_defaults", &g, n);
}

#[test]
fn vray_reflect_sheen_coat_refract() {
    let (g, n) = one("VRayMtl", |g, n| {
        g.setc(n, "reflect", [1.0; 3])
            .setf(n, "reflect_glossiness", 0.7);
        g.setc(n, "sheen_color", [0.3, 0.2, 0.1])
            .setf(n, "roughness", 0.5);
        g.setf(n, "coat_amount", 0.5)
            .setc(n, "coat_color", [0.9, 0.7, 0.5])
            .setf(n, "coat_glossiness", 0.9);
        g.setc(n, "refract", [0.5, 0.5, 0.25])
            .setf(n, "metalness", 0.25);
        g.setc(n, "self_illumination", [0.1, 0.0, 0.0]);
        g.setf(n, "anisotropy", 0.5)
            .setf(n, "anisotropy_rotation", 0.25);
    });
    snap("vray_reflect_sheen_coat_refract", &g, n);
}

#[test]
fn vray_translucency_thin_opacity_no_fresnel() {
    let (g, n) = one("VRayMtl", |g, n| {
        g.seti(n, "translucency", 1)
            .setc(n, "translucency_color", [0.9, 0.5, 0.4]);
        g.setc(n, "refract", [0.3; 3]).seti(n, "thin_walled", 1);
        g.setc(n, "opacity", [0.5; 3])
            .setc(n, "reflect", [0.5; 3])
            .seti(n, "fresnel", 0);
        g.seti(n, "brdf_type", 1);
    });
    snap("vray_translucency_thin_opacity_no_fresnel", &g, n);
}

#[test]
fn physical_defaults() {
    let (g, n) = one("PhysicalMaterial", |_, _| {});
    snap("physical_defaults", &g, n);
}

#[test]
fn physical_all_layers() {
    let (g, n) = one("PhysicalMaterial", |g, n| {
        g.setf(n, "coating", 0.5)
            .setc(n, "coat_color", [0.9, 0.8, 0.6])
            .setf(n, "coat_roughness", 0.2);
        g.setf(n, "scattering", 0.3)
            .setf(n, "transparency", 0.2)
            .setf(n, "metalness", 0.3);
        g.setf(n, "roughness", 0.8)
            .seti(n, "roughness_inv", 1)
            .seti(n, "brdf_mode", 0);
        g.setf(n, "diff_roughness", 0.5)
            .setf(n, "emission", 2.0)
            .setc(n, "emit_color", [1.0, 0.9, 0.8]);
    });
    snap("physical_all_layers", &g, n);
}

#[test]
fn physical_thin_walled_cutout_metal() {
    let (g, n) = one("PhysicalMaterial", |g, n| {
        g.setf(n, "transparency", 0.5)
            .seti(n, "thin_walled", 1)
            .setc(n, "trans_color", [0.2, 0.9, 0.2]);
        g.setf(n, "cutout", 0.75)
            .setf(n, "reflectivity", 0.5)
            .setf(n, "anisotropy", 0.5);
        g.setf(n, "trans_depth", 1.0);
    });
    snap("physical_thin_walled_cutout_metal", &g, n);
}

#[test]
fn mia_defaults() {
    let (g, n) = one("mia_material", |_, _| {});
    snap("mia_defaults", &g, n);
}

#[test]
fn mia_transparency_translucency() {
    let (g, n) = one("mia_material", |g, n| {
        g.setf(n, "transparency", 0.5)
            .seti(n, "refr_translucency", 1)
            .setf(n, "refr_gloss", 0.5);
        g.setf(n, "diffuse_roughness", 0.4);
    });
    snap("mia_transparency_translucency", &g, n);
}

#[test]
fn mia_metal_fresnel_thin_cutout() {
    let (g, n) = one("mia_material", |g, n| {
        g.seti(n, "refl_is_metal", 1)
            .seti(n, "brdf_fresnel", 1)
            .setc(n, "diffuse", [0.9, 0.6, 0.2]);
        g.setf(n, "reflectivity", 1.0)
            .setf(n, "refl_gloss", 0.5)
            .setf(n, "anisotropy", 2.0);
        g.setf(n, "transparency", 0.2)
            .seti(n, "thin_walled", 1)
            .setf(n, "cutout_opacity", 0.5);
        g.setc(n, "additional_color", [0.0, 0.05, 0.0])
            .seti(n, "brdf_conserve_energy", 0);
    });
    snap("mia_metal_fresnel_thin_cutout", &g, n);
}

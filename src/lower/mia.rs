//! mia_material (described for users in `docs/materials.md`).
//!
//! The energy rule is entirely in the weights, computed by the program per point and `μ_o`
//! (mia_material's luminance-weighted energy split); the tree has no `Layer` nodes:
//!
//! ```text
//! mia  = mix(transparent(1), body, cutout_opacity)
//! body = add(emission(additional_color), add(mul(highlight3, R), add(mul(miaDiffuse, diffuse),
//!        add(mul(REFR, refract), mul(translucent, transl)))))
//! ```
//!
//! Choices: `refl_hl_only` is recorded as LW020 (the `albedo()` exclusion it asks for is an
//! interpreter concern); the features without BSDF effect (listed in `docs/materials.md`)
//! report LW020 when they differ from their defaults.

use super::{Graph, Lower};
use crate::diag::Error;
use crate::ir::{Cl, DielectricMode, FrameSlot, Leaf, LeafKind, OpCode, Reg, WardVariant};
use crate::types::{BaseType, Value};

/// Built-in defaults, used only for a parameter whose definition gives no default (LW003).
pub fn builtin_default(param: &str) -> Value {
    let c = |v: f32| Value::Triple(BaseType::Color, [v, v, v]);
    let f = Value::Float;
    let i = Value::Int;
    match param {
        "diffuse_weight" => f(1.0),
        "diffuse" => c(0.5),
        "diffuse_roughness" => f(0.0),
        "reflectivity" => f(0.6),
        "refl_color" => c(1.0),
        "refl_gloss" => f(1.0),
        "refl_is_metal" | "refl_hl_only" | "thin_walled" | "refr_translucency" | "brdf_fresnel" => {
            i(0)
        }
        "transparency" => f(0.0),
        "refr_color" => c(1.0),
        "refr_gloss" => f(1.0),
        "refr_ior" => f(1.4),
        "refr_trans_color" => Value::Triple(BaseType::Color, [0.7, 0.6, 0.5]),
        "refr_trans_weight" => f(0.5),
        "anisotropy" => f(1.0),
        "anisotropy_rotation" => f(0.0),
        "brdf_0_degree_refl" => f(0.2),
        "brdf_90_degree_refl" => f(1.0),
        "brdf_curve" => f(5.0),
        "brdf_conserve_energy" => i(1),
        "cutout_opacity" => f(1.0),
        "additional_color" => c(0.0),
        _ => f(0.0),
    }
}

fn p<G: Graph>(cx: &mut Lower<'_, G>, n: G::Id, name: &str) -> Result<Reg, Error> {
    cx.param(n, name, builtin_default(name))
}

/// The four energy-split weights as registers: `(R, diffuse, refract, transl)`.
pub struct MiaWeights {
    /// Highlight/reflection weight (metal-tinted).
    pub reflect: Reg,
    /// Diffuse weight.
    pub diffuse: Reg,
    /// Refraction weight.
    pub refract: Reg,
    /// Translucency weight.
    pub transl: Reg,
}

/// The weights program: mia_material's luminance-weighted energy split, per point and `μ_o`.
pub fn weights<G: Graph>(cx: &mut Lower<'_, G>, n: G::Id) -> Result<MiaWeights, Error> {
    let mu = cx.b.prog.view_mu(0);
    let fresnel_mode = p(cx, n, "brdf_fresnel")?;
    let ior = p(cx, n, "refr_ior")?;
    let r0 = p(cx, n, "brdf_0_degree_refl")?;
    let r90 = p(cx, n, "brdf_90_degree_refl")?;
    let curve = p(cx, n, "brdf_curve")?;
    let reflectivity = p(cx, n, "reflectivity")?;
    let refl_color = p(cx, n, "refl_color")?;
    let dw = p(cx, n, "diffuse_weight")?;
    let dcol = p(cx, n, "diffuse")?;
    let transparency = p(cx, n, "transparency")?;
    let refr_color = p(cx, n, "refr_color")?;
    let tl_on = p(cx, n, "refr_translucency")?;
    let tl_w = p(cx, n, "refr_trans_weight")?;
    let tl_c = p(cx, n, "refr_trans_color")?;
    let conserve = p(cx, n, "brdf_conserve_energy")?;
    let metal = p(cx, n, "refl_is_metal")?;
    let thin = cx.static_scalar(n, "thin_walled", 0.0).unwrap_or(0.0) != 0.0;

    let pr = &mut cx.b.prog;
    let exact = pr.bin(OpCode::FresnelDielectric, mu, ior);
    let schlick = pr.schlick(mu, r0, r90, curve);
    let c = pr.select(fresnel_mode, exact, schlick);
    // Seen from inside a solid (μ_o < 0, not thin-walled) the one-sided highlight returns
    // nothing and the refraction lobe is the whole interface (Fresnel reflection with the
    // inverted index and transmission), so the reflection takes no energy there.
    let c = if thin {
        c
    } else {
        let zero = pr.constf(0.0);
        let front = pr.bin(OpCode::CmpGt, mu, zero);
        pr.select(front, c, zero)
    };
    let rc = pr.mul(reflectivity, refl_color);
    let reflect = pr.mul(rc, c);
    let diffuse = pr.mul(dw, dcol);
    let refract = pr.mul(transparency, refr_color);
    let zero = pr.constf(0.0);
    let tw = pr.mul(tl_w, tl_c);
    let transl = pr.select(tl_on, tw, zero);
    let t0 = pr.lum(transl);
    // Conservation (luminance-weighted, order as in the seed).
    let lum_refract = pr.lum(refract);
    let keep_t = pr.one_minus(lum_refract);
    let d1 = pr.mul(diffuse, keep_t);
    let lum_reflect = pr.lum(reflect);
    let keep_r = pr.one_minus(lum_reflect);
    let r1 = pr.mul(refract, keep_r);
    let d2 = pr.mul(d1, keep_r);
    let diffuse_c = pr.select(conserve, d2, diffuse);
    let refract_c = pr.select(conserve, r1, refract);
    // Translucency is a share of the (reduced) transparency, removed from refraction.
    let transl = pr.mul(transl, refract_c);
    let keep_tl = pr.one_minus(t0);
    let refract_f = pr.mul(refract_c, keep_tl);
    // Metal mode tints the reflection by the (unscaled) diffuse colour.
    let metal_r = pr.mul(reflect, dcol);
    let r = pr.select(metal, metal_r, reflect);
    // Negative weights (out-of-range inputs) are clamped so the tree stays valid.
    let clampw = |pr: &mut crate::ir::ProgramBuilder, x| pr.bin(OpCode::Max, x, zero);
    Ok(MiaWeights {
        reflect: clampw(pr, r),
        diffuse: clampw(pr, diffuse_c),
        refract: clampw(pr, refract_f),
        transl: clampw(pr, transl),
    })
}

/// The mia_material recipe.
pub fn lower<G: Graph>(cx: &mut Lower<'_, G>, n: G::Id) -> Result<Cl, Error> {
    let w = weights(cx, n)?;
    let one = cx.constf(1.0);

    let gloss = p(cx, n, "refl_gloss")?;
    let aniso = p(cx, n, "anisotropy")?;
    let rot = p(cx, n, "anisotropy_rotation")?;
    let frame = cx.b.frame(FrameSlot {
        normal: None,
        tangent: None,
        rotation: Some(rot),
    });
    let hl = cx.b.leaf(Leaf {
        kind: LeafKind::MiaHighlight3 {
            glossiness: gloss,
            anisotropy: aniso,
            variant: WardVariant::Classic,
        },
        tint: one,
        ttint: one,
        frame,
        label: "reflection".into(),
    });
    let hl = cx.b.mul(hl, w.reflect);

    let sigma = p(cx, n, "diffuse_roughness")?;
    let diff = cx.b.leaf(Leaf {
        kind: LeafKind::MiaDiffuse { albedo: one, sigma },
        tint: one,
        ttint: one,
        frame: 0,
        label: "diffuse".into(),
    });
    let diff = cx.b.mul(diff, w.diffuse);

    let thin = cx.static_scalar(n, "thin_walled", 0.0).unwrap_or(0.0) != 0.0;
    let refr = if thin {
        cx.b.transparent(one)
    } else {
        let ior = p(cx, n, "refr_ior")?;
        let g = p(cx, n, "refr_gloss")?;
        let alpha = gloss_to_alpha(cx, g);
        cx.dielectric(DielectricMode::T, alpha, ior, one, one, "refraction")
    };
    let refr = cx.b.mul(refr, w.refract);

    let tl = cx.b.leaf(Leaf {
        kind: LeafKind::Translucent { albedo: one },
        tint: one,
        ttint: one,
        frame: 0,
        label: "translucency".into(),
    });
    let tl = cx.b.mul(tl, w.transl);

    let add_col = p(cx, n, "additional_color")?;
    let em = cx.b.emission(add_col);
    let body = cx.b.add_all(&[em, hl, diff, refr, tl]);
    let cut = p(cx, n, "cutout_opacity")?;
    let clear = cx.b.transparent(one);
    let root = cx.b.mix(clear, body, cut);

    if cx.static_scalar(n, "refl_hl_only", 0.0) != Some(0.0) {
        let message = "`refl_hl_only`: the reflection lobe stays in the BSDF; excluding it from environment albedo is left to the renderer";
        cx.approximated(n, "refl_hl_only", message);
    }
    for (name, dflt) in [
        ("hl_vs_refl_balance", 1.0),
        ("refl_falloff_on", 0.0),
        ("refr_falloff_on", 0.0),
        ("ao_on", 0.0),
        ("no_visible_area_hl", 1.0),
        ("skip_inside_refl", 1.0),
        ("backface_cull", 0.0),
        ("propagate_alpha", 0.0),
    ] {
        if cx
            .graph
            .value(n, name)
            .is_some_and(|v| crate::ir::value_to_vec3(v).x != dflt)
        {
            let message = format!("`{name}` has no BSDF effect and is ignored");
            cx.approximated(n, name, message);
        }
    }
    Ok(root)
}

/// `α = √(2/(2^(8g) + 2))`; a delta (α ≈ 0) at g = 1 (refraction glossiness).
fn gloss_to_alpha<G: Graph>(cx: &mut Lower<'_, G>, g: Reg) -> Reg {
    let pr = &mut cx.b.prog;
    let eight = pr.constf(8.0);
    let two = pr.constf(2.0);
    let e = pr.mul(g, eight);
    let n = pr.pow(two, e);
    let den = pr.add(n, two);
    let q = pr.div(two, den);
    let a = pr.un(OpCode::Sqrt, q);
    // Glossiness 1 is a perfect refraction: map it below the GGX delta cut-off.
    let one = pr.constf(1.0);
    let full = pr.bin(OpCode::CmpGe, g, one);
    let zero = pr.constf(0.0);
    pr.select(full, zero, a)
}

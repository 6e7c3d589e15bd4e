//! VRayMtl (described for users in `docs/materials.md`).
//!
//! ```text
//! vray      = mix(transparent(1), body, opacity)
//! body      = add(emission(self_illumination), coated)
//! coated    = layer[Rgb](mul(CO, coat_amount), reflstack)
//! reflstack = mix(dielectric, metal, metalness)
//! dielectric= layer[Rgb](SPEC, under)
//! under     = mix(side, refraction, refract)
//! side      = translucency == 0 ? layer[Rgb](sheenCK(tint: sheen_color), DIFF) : subsurfaceProxy
//! metal     = microfacetR(generalized Schlick(F0: diffuse, F90: reflect, q: 5))
//! ```
//!
//! The sheen-over-diffuse layer in `Rgb` mode with the sheen colour as tint is exactly VRayMtl's
//! `sheenBRDF·sheen_color + (1 − sheen_color·reflectance(sheenBRDF))·diffuse·diffuseBRDF`.
//! Roughness from glossiness: `r = 1 − glossiness`, `α = r²`. A connected
//! `translucency` mode is lowered as `none` (LW020).

use super::{Graph, Lower, aniso_alpha};
use crate::diag::Error;
use crate::ir::{
    Cl, DielectricMode, FrameSlot, Fresnel, Leaf, LeafKind, Masking, Reg, SheenMasking, TintMode,
};
use crate::types::{BaseType, Value};

/// Built-in defaults, used only for a parameter whose definition gives no default (LW003).
pub fn builtin_default(param: &str) -> Value {
    let c = |v: f32| Value::Triple(BaseType::Color, [v, v, v]);
    let f = Value::Float;
    let i = Value::Int;
    match param {
        "diffuse" => c(0.5),
        "roughness" => f(0.0),
        "reflect" => c(0.0),
        "reflect_glossiness" => f(1.0),
        "fresnel" => i(1),
        "fresnel_ior" => f(1.6),
        "metalness" => f(0.0),
        "anisotropy" => f(0.0),
        "anisotropy_rotation" => f(0.0),
        "sheen_color" => c(0.0),
        "sheen_glossiness" => f(0.8),
        "brdf_type" => i(4),
        "refract" => c(0.0),
        "refract_glossiness" => f(1.0),
        "refract_ior" => f(1.6),
        "translucency" => i(0),
        "translucency_color" => c(1.0),
        "self_illumination" => c(0.0),
        "opacity" => c(1.0),
        "coat_amount" => f(0.0),
        "coat_color" => c(1.0),
        "coat_glossiness" => f(1.0),
        "coat_ior" => f(1.6),
        "thin_walled" => i(0),
        "hilight_glossiness" => f(1.0),
        "hilight_glossiness_lock" => i(1),
        _ => f(0.0),
    }
}

fn p<G: Graph>(cx: &mut Lower<'_, G>, n: G::Id, name: &str) -> Result<Reg, Error> {
    cx.param(n, name, builtin_default(name))
}

/// `α = (1 − glossiness)²`.
fn gloss_alpha<G: Graph>(cx: &mut Lower<'_, G>, g: Reg) -> Reg {
    let r = cx.b.prog.one_minus(g);
    let r = cx.b.prog.saturate(r);
    cx.b.prog.mul(r, r)
}

/// The VRayMtl recipe.
pub fn lower<G: Graph>(cx: &mut Lower<'_, G>, n: G::Id) -> Result<Cl, Error> {
    let one = cx.constf(1.0);
    let diffuse = p(cx, n, "diffuse")?;
    let reflect = p(cx, n, "reflect")?;

    // Diffuse with sheen on top (seed 000's formula).
    let rough = p(cx, n, "roughness")?;
    let dkind = if cx.b.prog.constant(rough) == Some(glam::Vec3::ZERO) {
        LeafKind::Lambert { albedo: diffuse }
    } else {
        LeafKind::OrenNayarE {
            albedo: diffuse,
            sigma: rough,
        }
    };
    let diff = cx.b.simple_leaf(dkind, "diffuse");
    let sheen_color = p(cx, n, "sheen_color")?;
    let sg = p(cx, n, "sheen_glossiness")?;
    let sr = cx.b.prog.one_minus(sg);
    let sheen = cx.b.leaf(Leaf {
        kind: LeafKind::SheenCk {
            roughness: sr,
            masking: SheenMasking::MaterialX,
        },
        tint: sheen_color,
        ttint: one,
        frame: 0,
        label: "sheen".into(),
    });
    let sheen_over_diffuse = cx.b.layer(sheen, diff, TintMode::Rgb);
    let side = match cx.static_scalar(n, "translucency", 0.0) {
        Some(t) if t != 0.0 => {
            let tc = p(cx, n, "translucency_color")?;
            cx.b.simple_leaf(LeafKind::SubsurfaceProxy { albedo: tc }, "translucency")
        }
        Some(_) => sheen_over_diffuse,
        None => {
            let message = "`translucency` is connected; lowered as none (0)";
            cx.approximated(n, "translucency", message);
            sheen_over_diffuse
        }
    };

    // Refraction.
    let thin = cx.static_scalar(n, "thin_walled", 0.0).unwrap_or(0.0) != 0.0;
    let refraction = if thin {
        cx.b.transparent(one)
    } else {
        let ior = p(cx, n, "refract_ior")?;
        let g = p(cx, n, "refract_glossiness")?;
        let a = gloss_alpha(cx, g);
        cx.dielectric(DielectricMode::T, a, ior, one, one, "refraction")
    };
    let refract = p(cx, n, "refract")?;
    let under = cx.b.mix(side, refraction, refract);

    // Reflection: SPEC over `under`, metal beside it.
    let rg = p(cx, n, "reflect_glossiness")?;
    let rr = cx.b.prog.one_minus(rg);
    let rr = cx.b.prog.saturate(rr);
    let aniso = p(cx, n, "anisotropy")?;
    let (ax, ay) = aniso_alpha(&mut cx.b, rr, aniso);
    let rot = p(cx, n, "anisotropy_rotation")?;
    let frame = cx.b.frame(FrameSlot {
        normal: None,
        tangent: None,
        rotation: Some(rot),
    });
    let fresnel = match cx.static_scalar(n, "fresnel", 1.0) {
        Some(0.0) => Fresnel::One,
        _ => Fresnel::Dielectric {
            eta: p(cx, n, "fresnel_ior")?,
        },
    };
    let zero = cx.constf(0.0);
    let spec = cx.b.leaf(Leaf {
        kind: LeafKind::MicrofacetR {
            alpha_x: ax,
            alpha_y: ay,
            fresnel,
            masking: Masking::HeightCorrelated,
            comp: zero,
        },
        tint: reflect,
        ttint: one,
        frame,
        label: "reflection".into(),
    });
    let dielectric = cx.b.layer(spec, under, TintMode::Rgb);
    let five = cx.constf(5.0);
    let metal = cx.b.leaf(Leaf {
        kind: LeafKind::MicrofacetR {
            alpha_x: ax,
            alpha_y: ay,
            fresnel: Fresnel::Schlick {
                f0: diffuse,
                f90: reflect,
                q: five,
            },
            masking: Masking::HeightCorrelated,
            comp: zero,
        },
        tint: one,
        ttint: one,
        frame,
        label: "metal".into(),
    });
    let metalness = p(cx, n, "metalness")?;
    let reflstack = cx.b.mix(dielectric, metal, metalness);

    // Coat.
    let cior = p(cx, n, "coat_ior")?;
    let cg = p(cx, n, "coat_glossiness")?;
    let ca = gloss_alpha(cx, cg);
    let ccolor = p(cx, n, "coat_color")?;
    let coat = cx.dielectric(DielectricMode::R, ca, cior, one, ccolor, "coat");
    let amount = p(cx, n, "coat_amount")?;
    let coat = cx.b.mul(coat, amount);
    let coated = cx.b.layer(coat, reflstack, TintMode::Rgb);

    let si = p(cx, n, "self_illumination")?;
    let em = cx.b.emission(si);
    let body = cx.b.add(em, coated);
    let opacity = p(cx, n, "opacity")?;
    let clear = cx.b.transparent(one);
    let root = cx.b.mix(clear, body, opacity);

    if cx.static_scalar(n, "brdf_type", 4.0) != Some(4.0) {
        let message = "`brdf_type` other than GGX (4) is approximated by GGX";
        cx.approximated(n, "brdf_type", message);
    }
    if cx.static_scalar(n, "hilight_glossiness_lock", 1.0) == Some(0.0) {
        let message = "unlocked `hilight_glossiness` is ignored; the reflection glossiness is used";
        cx.approximated(n, "hilight_glossiness_lock", message);
    }
    Ok(root)
}

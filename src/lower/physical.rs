//! 3ds Max Physical Material (described for users in `docs/materials.md`).
//!
//! ```text
//! physical  = mix(transparent(1), add(emission(emission · emit_color), coated), cutout)
//! coated    = layer[Gray](mul(COAT, w_c), body)
//! body      = mix(dielectric, mul(METAL, w_r), m)
//! dielectric= layer[Gray](mul(REFL, w_r), under)
//! under     = mix(mix(mul(DIFF, w_b), subsurfaceProxy(sss_color), w_s), TRANS, w_t)
//! ```
//!
//! Under the closure algebra this tree yields exactly the material's scalar weights (colours
//! ignored by `Gray`, except the coat colour as transmission tint). Roughness maps to `α = r²`;
//! `anisotropy` 1 is isotropic and maps to `a = 1 − anisotropy`.

use super::{Graph, Lower, aniso_alpha};
use crate::diag::Error;
use crate::ir::{
    Cl, DielectricMode, FrameSlot, Fresnel, Leaf, LeafKind, Masking, OpCode, Reg, TintMode,
};
use crate::types::{BaseType, Value};

/// Built-in defaults, used only for a parameter whose definition gives no default (LW003).
pub fn builtin_default(param: &str) -> Value {
    let c = |v: f32| Value::Triple(BaseType::Color, [v, v, v]);
    let f = Value::Float;
    let i = Value::Int;
    match param {
        "base_weight" => f(1.0),
        "base_color" => c(0.5),
        "diff_roughness" => f(0.0),
        "reflectivity" => f(1.0),
        "refl_color" => c(1.0),
        "roughness" => f(0.0),
        "roughness_inv" => i(0),
        "metalness" => f(0.0),
        "trans_ior" => f(1.52),
        "brdf_mode" => i(1),
        "brdf_low" => f(0.05),
        "brdf_high" => f(1.0),
        "brdf_curve" => f(5.0),
        "anisotropy" => f(1.0),
        "anisoangle" => f(0.0),
        "transparency" => f(0.0),
        "trans_color" => c(1.0),
        "trans_roughness" => f(0.0),
        "trans_depth" => f(0.0),
        "thin_walled" => i(0),
        "scattering" => f(0.0),
        "sss_color" => c(1.0),
        "emission" => f(0.0),
        "emit_color" => c(1.0),
        "coating" => f(0.0),
        "coat_color" => c(1.0),
        "coat_roughness" => f(0.0),
        "coat_ior" => f(1.52),
        "coat_affect_color" => f(0.0),
        "coat_affect_roughness" => f(0.0),
        "cutout" => f(1.0),
        _ => f(0.0),
    }
}

fn p<G: Graph>(cx: &mut Lower<'_, G>, n: G::Id, name: &str) -> Result<Reg, Error> {
    cx.param(n, name, builtin_default(name))
}

/// A weight parameter clamped to [0, 1].
fn w<G: Graph>(cx: &mut Lower<'_, G>, n: G::Id, name: &str) -> Result<Reg, Error> {
    let r = p(cx, n, name)?;
    Ok(cx.b.prog.saturate(r))
}

/// The PhysicalMaterial recipe.
pub fn lower<G: Graph>(cx: &mut Lower<'_, G>, n: G::Id) -> Result<Cl, Error> {
    let one = cx.constf(1.0);
    let zero = cx.constf(0.0);
    let w_b = w(cx, n, "base_weight")?;
    let w_s = w(cx, n, "scattering")?;
    let w_t = w(cx, n, "transparency")?;
    let w_r = w(cx, n, "reflectivity")?;
    let m = w(cx, n, "metalness")?;
    let w_c = w(cx, n, "coating")?;

    // Coat side effects (as Standard Surface).
    let coat_affect_color = p(cx, n, "coat_affect_color")?;
    let coat_affect_rough = p(cx, n, "coat_affect_roughness")?;
    let coat_rough = p(cx, n, "coat_roughness")?;
    let base_color = p(cx, n, "base_color")?;
    let pr = &mut cx.b.prog;
    let k = pr.mul(w_c, coat_affect_color);
    let expo = pr.add(one, k);
    let base_color = pr.pow(base_color, expo);

    // Reflection roughness (optionally inverted), darkened toward 1 under a rough coat.
    let rough = p(cx, n, "roughness")?;
    let inv = p(cx, n, "roughness_inv")?;
    let pr = &mut cx.b.prog;
    let flipped = pr.one_minus(rough);
    let rough = pr.select(inv, flipped, rough);
    let t = pr.mul(w_c, coat_affect_rough);
    let t = pr.mul(t, coat_rough);
    let rough = pr.lerp(rough, one, t);
    let aniso = p(cx, n, "anisotropy")?;
    let a = cx.b.prog.one_minus(aniso);
    let (ax, ay) = aniso_alpha(&mut cx.b, rough, a);
    let angle = p(cx, n, "anisoangle")?;
    let frame = cx.b.frame(FrameSlot {
        normal: None,
        tangent: None,
        rotation: Some(angle),
    });

    // REFL.
    let trans_ior = p(cx, n, "trans_ior")?;
    let fresnel = match cx.static_scalar(n, "brdf_mode", 1.0) {
        Some(0.0) => Fresnel::Schlick {
            f0: p(cx, n, "brdf_low")?,
            f90: p(cx, n, "brdf_high")?,
            q: p(cx, n, "brdf_curve")?,
        },
        _ => Fresnel::Dielectric { eta: trans_ior },
    };
    let refl_color = p(cx, n, "refl_color")?;
    let refl = cx.b.leaf(Leaf {
        kind: LeafKind::MicrofacetR {
            alpha_x: ax,
            alpha_y: ay,
            fresnel,
            masking: Masking::HeightCorrelated,
            comp: zero,
        },
        tint: refl_color,
        ttint: one,
        frame,
        label: "reflection".into(),
    });
    let refl = cx.b.mul(refl, w_r);

    // METAL (F82, opaque), with Turquin's multiple-scattering compensation at full strength:
    // a white metal (base and reflection colour 1) is then lossless at every roughness, where
    // single-scattering GGX alone returns 0.84–0.92 at roughness 0.5.
    let five = cx.constf(5.0);
    let metal = cx.b.leaf(Leaf {
        kind: LeafKind::MicrofacetR {
            alpha_x: ax,
            alpha_y: ay,
            fresnel: Fresnel::F82 {
                f0: base_color,
                f90: one,
                q: five,
                t: refl_color,
            },
            masking: Masking::HeightCorrelated,
            comp: one,
        },
        tint: one,
        ttint: one,
        frame,
        label: "metal".into(),
    });
    let metal = cx.b.mul(metal, w_r);

    // Diffuse, SSS, transmission.
    let dr = p(cx, n, "diff_roughness")?;
    let dkind = if cx.b.prog.constant(dr) == Some(glam::Vec3::ZERO) {
        LeafKind::Lambert { albedo: base_color }
    } else {
        LeafKind::OrenNayarE {
            albedo: base_color,
            sigma: dr,
        }
    };
    let diff = cx.b.simple_leaf(dkind, "diffuse");
    let diff = cx.b.mul(diff, w_b);
    let sss_color = p(cx, n, "sss_color")?;
    let sss =
        cx.b.simple_leaf(LeafKind::SubsurfaceProxy { albedo: sss_color }, "sss");
    let trans_color = p(cx, n, "trans_color")?;
    let thin = cx.static_scalar(n, "thin_walled", 0.0).unwrap_or(0.0) != 0.0;
    let trans = if thin {
        cx.b.transparent(trans_color)
    } else {
        let tr = p(cx, n, "trans_roughness")?;
        let ta = cx.b.prog.mul(tr, tr);
        cx.dielectric(
            DielectricMode::T,
            ta,
            trans_ior,
            trans_color,
            one,
            "transmission",
        )
    };
    if cx.static_scalar(n, "trans_depth", 0.0) != Some(0.0) {
        let message = "`trans_depth` (volume absorption) is ignored";
        cx.approximated(n, "trans_depth", message);
    }
    let ds = cx.b.mix(diff, sss, w_s);
    let under = cx.b.mix(ds, trans, w_t);
    let dielectric = cx.b.layer(refl, under, TintMode::Gray);
    let body = cx.b.mix(dielectric, metal, m);

    // COAT.
    let cior = p(cx, n, "coat_ior")?;
    let ca = cx.b.prog.mul(coat_rough, coat_rough);
    let ccolor = p(cx, n, "coat_color")?;
    let coat = cx.dielectric(DielectricMode::R, ca, cior, one, ccolor, "coat");
    let coat = cx.b.mul(coat, w_c);
    let coated = cx.b.layer(coat, body, TintMode::Gray);

    let e = p(cx, n, "emission")?;
    let ec = p(cx, n, "emit_color")?;
    let rad = cx.b.prog.mul(e, ec);
    let rad = cx.b.prog.bin(OpCode::Max, rad, zero);
    let em = cx.b.emission(rad);
    let inner = cx.b.add(em, coated);
    let cutout = p(cx, n, "cutout")?;
    let clear = cx.b.transparent(one);
    Ok(cx.b.mix(clear, inner, cutout))
}

//! PxrSurface / PxrLayerSurface and the interpretation of PxrLayer
//! and PxrLayerMixer as program expressions.
//!
//! Choices the spec leaves open, made here:
//! * a diffuse roughness that is connected (not a constant) selects EON, which evaluates as
//!   Lambert below σ = 1e-4, so the choice never changes a constant-0 result;
//! * a Fresnel mode that is connected is lowered as artistic (LW020);
//! * `*DoubleSided`: the lobes are two-sided when the interpreter is asked for both sides
//!   (`PrepareOptions::sides`); the diffuse back colour (`diffuseBackColor` /
//!   `diffuseBackUseDiffuseColor`) is chosen in the program by the sign of `μ_o` in the diffuse
//!   frame;
//! * LW020 for `<p>ModelType ≠ 1` and LW021 for iridescence and single scattering are
//!   reported only for lobes that survive constant folding.

use super::{Graph, Lower, NameBuf, aniso_alpha};
use crate::diag::{Diagnostic, Error};
use crate::ir::{
    Cl, DielectricMode, FrameSlot, Fresnel, Leaf, LeafKind, Masking, OpCode, Reg, SheenMasking,
    TintMode,
};
use crate::types::{BaseType, Value};

/// Built-in defaults of PxrSurface / PxrLayerSurface parameters, used only without a
/// definition. Values are `Value`s of the parameter's type.
pub fn builtin_default(param: &str) -> Value {
    let c = |v: f32| Value::Triple(BaseType::Color, [v, v, v]);
    let c3 = |a: f32, b: f32, d: f32| Value::Triple(BaseType::Color, [a, b, d]);
    let f = Value::Float;
    let i = Value::Int;
    if param.ends_with("BumpNormal") || param == "bumpNormal" || param.ends_with("Direction") {
        return Value::Triple(BaseType::Normal, [0.0; 3]);
    }
    if param.starts_with("enable") {
        return i(if param == "enableDiffuseAlways" { 1 } else { 0 });
    }
    // Strip the lobe prefix of the three microfacet lobes: they share defaults except the
    // roughness.
    for p in ["roughSpecular", "clearcoat", "specular"] {
        if let Some(rest) = param.strip_prefix(p) {
            return match rest {
                "FresnelMode" => i(0),
                "FaceColor" | "EdgeColor" => c(0.0),
                "FresnelShape" => f(5.0),
                "Ior" => c(1.5),
                "ExtinctionCoeff" => c(0.0),
                "Roughness" => f(match p {
                    "roughSpecular" => 0.6,
                    "clearcoat" => 0.0,
                    _ => 0.2,
                }),
                "ModelType" => i(0),
                "Anisotropy" => f(0.0),
                "DoubleSided" => i(0),
                "EnergyCompensation" => f(0.0),
                "Thickness" => f(0.0),
                "AbsorptionTint" => c(0.0),
                "Gain" => f(0.0),
                _ => f(0.0),
            };
        }
    }
    match param {
        "diffuseGain" => f(1.0),
        "diffuseColor" | "diffuseBackColor" | "diffuseTransmitColor" => c(0.18),
        "diffuseRoughness" => f(0.0),
        "diffuseExponent" => f(1.0),
        "diffuseDoubleSided" => i(0),
        "diffuseBackUseDiffuseColor" => i(1),
        "diffuseTransmitGain" => f(0.0),
        "fuzzGain" => f(0.0),
        "fuzzColor" => c(1.0),
        "fuzzConeAngle" => f(8.0),
        "fuzzDoubleSided" => i(0),
        "subsurfaceGain" => f(0.0),
        "subsurfaceColor" => c3(0.83, 0.791, 0.753),
        "subsurfacePostTint" => c(1.0),
        "subsurfaceType" => i(0),
        "refractionGain" | "reflectionGain" | "rrRefractionGain" | "rrReflectionGain" => f(0.0),
        "refractionColor" | "rrRefractionColor" => c(1.0),
        "glassRoughness" | "rrRoughness" => f(0.1),
        "glassIor" | "rrIor" => f(1.5),
        "thinGlass" => i(0),
        "ignoreFresnel" => i(0),
        "glowGain" => f(0.0),
        "glowColor" => c(1.0),
        "presence" => f(1.0),
        "layer1Mask" | "layer2Mask" | "layer3Mask" | "layer4Mask" => f(1.0),
        "layer1Enabled" | "layer2Enabled" | "layer3Enabled" | "layer4Enabled" => i(1),
        _ if param.ends_with("Color") || param.ends_with("Tint") => c(0.0),
        _ => f(0.0),
    }
}

/// The lobe group (`X` of `enableX`) a PxrLayer member belongs to; `None` for the
/// global `bumpNormal`.
pub(crate) fn member_lobe(member: &str) -> Option<&'static str> {
    const GROUPS: [(&str, &str); 14] = [
        ("roughSpecular", "RoughSpecular"),
        ("specular", "Specular"),
        ("clearcoat", "Clearcoat"),
        ("iridescence", "Iridescence"),
        ("fuzz", "Fuzz"),
        ("shortSubsurface", "Subsurface"),
        ("longSubsurface", "Subsurface"),
        ("subsurface", "Subsurface"),
        ("singlescatter", "Singlescatter"),
        ("glow", "Glow"),
        ("diffuse", "Diffuse"),
        ("refraction", "RR"),
        ("reflection", "RR"),
        ("glass", "RR"),
    ];
    if member == "bumpNormal" {
        return None;
    }
    GROUPS
        .iter()
        .find(|(p, _)| member.starts_with(p))
        .map(|(_, g)| *g)
        .or(Some("Diffuse"))
}

fn is_normal_member(member: &str) -> bool {
    member == "bumpNormal" || member.ends_with("BumpNormal")
}

/// PxrLayer output `pxrMaterialOut_<m>`: the layer's input of the same name, with
/// the five RR renames and the gains folded into the Fresnel colours.
pub(crate) fn layer_output<G: Graph>(
    cx: &mut Lower<'_, G>,
    n: G::Id,
    output: &str,
) -> Result<Option<Reg>, Error> {
    let Some(m) = output.strip_prefix("pxrMaterialOut_") else {
        return Ok(None);
    };
    let source = match m {
        "refractionGain" => "rrRefractionGain",
        "reflectionGain" => "rrReflectionGain",
        "refractionColor" => "rrRefractionColor",
        "glassRoughness" => "rrRoughness",
        "glassIor" => "rrIor",
        other => other,
    };
    let v = cx.param(n, source, builtin_default(source))?;
    for p in ["roughSpecular", "specular", "clearcoat"] {
        if matches!(m.strip_prefix(p), Some("FaceColor" | "EdgeColor")) {
            let gain_name = format!("{p}Gain");
            let gain = cx.param(n, &gain_name, Value::Float(0.0))?;
            return Ok(Some(cx.b.prog.mul(v, gain)));
        }
    }
    Ok(Some(v))
}

const MIXER_PREFIXES: [&str; 5] = ["baselayer", "layer1", "layer2", "layer3", "layer4"];

/// PxrLayerMixer output `pxrMaterialOut_<m>`: per member, each participating layer
/// composited over the accumulated value by its mask, in order; enable flags OR-ed.
pub(crate) fn mixer_output<G: Graph>(
    cx: &mut Lower<'_, G>,
    n: G::Id,
    output: &str,
) -> Result<Option<Reg>, Error> {
    let Some(m) = output.strip_prefix("pxrMaterialOut_") else {
        return Ok(None);
    };
    let zero = cx.constf(0.0);
    if let Some(x) = m.strip_prefix("enable") {
        let one = cx.constf(1.0);
        // OR of the five `<prefix>_enableX == 1`.
        let mut acc = zero;
        let mut name = NameBuf::default();
        for p in MIXER_PREFIXES {
            let e = cx.pi(n, name.join(&[p, "_enable", x]), 0)?;
            let on = cx.b.prog.bin(OpCode::CmpEq, e, one);
            acc = cx.b.prog.bin(OpCode::Or, acc, on);
        }
        return Ok(Some(acc));
    }
    let lobe = member_lobe(m);
    let normal = is_normal_member(m);
    let dflt = mixer_member_default(m);
    let mut name = NameBuf::default();
    let base = cx.param(n, name.join(&["baselayer_", m]), dflt.clone())?;
    let mut acc = if normal {
        cx.b.prog.un(OpCode::NormalOrDefault, base)
    } else {
        base
    };
    let mut any_normal = if normal { nonzero(cx, base) } else { zero };
    let gates = mixer_gates(cx, n, lobe)?;
    for (i, p) in MIXER_PREFIXES.iter().enumerate().skip(1) {
        let (gate, t) = gates[i - 1];
        let v = cx.param(n, name.join(&[p, "_", m]), dflt.clone())?;
        let v = if normal {
            let nz = nonzero(cx, v);
            let both = cx.b.prog.bin(OpCode::And, gate, nz);
            any_normal = cx.b.prog.bin(OpCode::Or, any_normal, both);
            cx.b.prog.un(OpCode::NormalOrDefault, v)
        } else {
            v
        };
        acc = cx.b.prog.lerp(acc, v, t);
    }
    if normal {
        let unit = cx.b.prog.un(OpCode::Normalize3, acc);
        acc = cx.b.prog.select(any_normal, unit, zero);
    }
    Ok(Some(acc))
}

/// For layers 1–4 of mixer `n` and lobe group `lobe` (`None`: the global bump normal): the
/// gate `g_i(X)` and the compositing factor `g_i ? clamp(mask_i) : 0` (memoised per node and
/// group: every member of a group shares them).
fn mixer_gates<G: Graph>(
    cx: &mut Lower<'_, G>,
    n: G::Id,
    lobe: Option<&'static str>,
) -> Result<[(Reg, Reg); 4], Error> {
    let key = lobe.unwrap_or("");
    if let Some(g) = cx.mixer_gates.get(&(n, key)) {
        return Ok(*g);
    }
    let zero = cx.constf(0.0);
    let one = cx.constf(1.0);
    let mut out = [(zero, zero); 4];
    let mut name = NameBuf::default();
    for (i, p) in MIXER_PREFIXES.iter().enumerate().skip(1) {
        let enabled = cx.pi(n, name.join(&[p, "Enabled"]), 1)?;
        let part = cx.b.prog.bin(OpCode::CmpEq, enabled, one);
        let gate_flag = match lobe {
            Some(x) => {
                let e = cx.pi(n, name.join(&[p, "_enable", x]), 0)?;
                cx.b.prog.bin(OpCode::CmpEq, e, one)
            }
            None => {
                let bump = cx.pv(n, name.join(&[p, "_bumpNormal"]), [0.0; 3])?;
                nonzero(cx, bump)
            }
        };
        let gate = cx.b.prog.bin(OpCode::And, part, gate_flag);
        let mask = cx.pf(n, name.join(&[p, "Mask"]), 1.0)?;
        let mask = cx.b.prog.saturate(mask);
        out[i - 1] = (gate, cx.b.prog.select(gate, mask, zero));
    }
    cx.mixer_gates.insert((n, key), out);
    Ok(out)
}

fn mixer_member_default(m: &str) -> Value {
    // The mixer's layer members default to 0, colours included (as in the reference).
    match builtin_default(m) {
        Value::Triple(b, _) => Value::Triple(b, [0.0; 3]),
        Value::Int(_) => Value::Int(0),
        _ => Value::Float(0.0),
    }
}

/// 1 when any lane of `v` is non-zero, else 0.
fn nonzero<G: Graph>(cx: &mut Lower<'_, G>, v: Reg) -> Reg {
    let zero = cx.constf(0.0);
    let ne = cx.b.prog.bin(OpCode::CmpNe, v, zero);
    cx.b.prog.un(OpCode::MaxComp, ne)
}

/// `p` if non-zero, else `q` (normals: the first non-zero wins).
fn first_nonzero<G: Graph>(cx: &mut Lower<'_, G>, p: Reg, q: Reg) -> Reg {
    let nz = nonzero(cx, p);
    cx.b.prog.select(nz, p, q)
}

fn frame_for<G: Graph>(cx: &mut Lower<'_, G>, n: G::Id, prefix: &str) -> Result<u32, Error> {
    let global = cx.pv(n, "bumpNormal", [0.0; 3])?;
    let own = cx.pv(n, &format!("{prefix}BumpNormal"), [0.0; 3])?;
    let normal = first_nonzero(cx, own, global);
    let tangent = if matches!(prefix, "specular" | "roughSpecular" | "clearcoat") {
        Some(cx.pv(n, &format!("{prefix}AnisotropyDirection"), [0.0; 3])?)
    } else {
        None
    };
    Ok(cx.b.frame(FrameSlot {
        normal: Some(normal),
        tangent,
        rotation: None,
    }))
}

fn p<G: Graph>(cx: &mut Lower<'_, G>, n: G::Id, name: &str) -> Result<Reg, Error> {
    cx.param(n, name, builtin_default(name))
}

/// One microfacet lobe of the surface (`specular`, `roughSpecular`, `clearcoat`).
fn specular_lobe<G: Graph>(
    cx: &mut Lower<'_, G>,
    n: G::Id,
    prefix: &str,
    comp_param: &str,
) -> Result<(Cl, u32, Fresnel), Error> {
    let rough = p(cx, n, &format!("{prefix}Roughness"))?;
    let aniso = p(cx, n, &format!("{prefix}Anisotropy"))?;
    let (ax, ay) = aniso_alpha(&mut cx.b, rough, aniso);
    let mode = cx.static_scalar(n, &format!("{prefix}FresnelMode"), 0.0);
    if mode.is_none() {
        let param = format!("{prefix}FresnelMode");
        let message = format!("`{param}` is connected; lowered as artistic (0)");
        cx.approximated(n, &param, message);
    }
    let fresnel = if mode == Some(1.0) {
        Fresnel::Conductor {
            eta: p(cx, n, &format!("{prefix}Ior"))?,
            kappa: p(cx, n, &format!("{prefix}ExtinctionCoeff"))?,
        }
    } else {
        Fresnel::Schlick {
            f0: p(cx, n, &format!("{prefix}FaceColor"))?,
            f90: p(cx, n, &format!("{prefix}EdgeColor"))?,
            q: p(cx, n, &format!("{prefix}FresnelShape"))?,
        }
    };
    let comp = p(cx, n, comp_param)?;
    let frame = frame_for(cx, n, prefix)?;
    let one = cx.constf(1.0);
    let leaf = cx.b.leaf(Leaf {
        kind: LeafKind::MicrofacetR {
            alpha_x: ax,
            alpha_y: ay,
            fresnel,
            masking: Masking::HeightCorrelated,
            comp,
        },
        tint: one,
        ttint: one,
        frame,
        label: prefix.to_string(),
    });
    if leaf.is_some() {
        let model = cx.static_scalar(n, &format!("{prefix}ModelType"), 0.0);
        if model != Some(1.0) {
            let param = format!("{prefix}ModelType");
            let message = format!("`{param}` is not 1 (GGX); approximated by GGX");
            cx.approximated(n, &param, message);
        }
    }
    Ok((leaf, frame, fresnel))
}

/// A double-sided diffuse seen from below (`μ_o < 0` in its frame) has the albedo
/// `diffuseColor` when `diffuseBackUseDiffuseColor` is set, else `diffuseBackColor`. Nothing
/// changes (and the program stays constant) when `diffuseDoubleSided` is a constant 0.
fn back_side_colour<G: Graph>(
    cx: &mut Lower<'_, G>,
    n: G::Id,
    front_colour: Reg,
    frame: u32,
) -> Result<Reg, Error> {
    let double = p(cx, n, "diffuseDoubleSided")?;
    if cx.b.prog.constant(double) == Some(glam::Vec3::ZERO) {
        return Ok(front_colour);
    }
    let use_front = p(cx, n, "diffuseBackUseDiffuseColor")?;
    let back_colour = p(cx, n, "diffuseBackColor")?;
    let back = cx.b.prog.select(use_front, front_colour, back_colour);
    let back = cx.b.prog.select(double, back, front_colour);
    let mu = cx.b.prog.view_mu(frame);
    let zero = cx.constf(0.0);
    let front = cx.b.prog.bin(OpCode::CmpGe, mu, zero);
    Ok(cx.b.prog.select(front, front_colour, back))
}

/// The PxrSurface / PxrLayerSurface recipe.
pub(crate) fn lower_surface<G: Graph>(cx: &mut Lower<'_, G>, n: G::Id) -> Result<Cl, Error> {
    let one = cx.constf(1.0);
    let zero = cx.constf(0.0);

    // Diffuse group.
    let dcolor = p(cx, n, "diffuseColor")?;
    let dgain = p(cx, n, "diffuseGain")?;
    let drough = p(cx, n, "diffuseRoughness")?;
    let dframe = frame_for(cx, n, "diffuse")?;
    let dcolor = back_side_colour(cx, n, dcolor, dframe)?;
    let dkind = if cx.b.prog.constant(drough) == Some(glam::Vec3::ZERO) {
        LeafKind::Lambert { albedo: dcolor }
    } else {
        LeafKind::OrenNayarE {
            albedo: dcolor,
            sigma: drough,
        }
    };
    let df = cx.b.leaf(Leaf {
        kind: dkind,
        tint: one,
        ttint: one,
        frame: dframe,
        label: "diffuse".into(),
    });
    if df.is_some() && cx.static_scalar(n, "diffuseExponent", 1.0) != Some(1.0) {
        let message = "`diffuseExponent` ≠ 1 is ignored (Lambert/EON)";
        cx.approximated(n, "diffuseExponent", message);
    }
    let double = p(cx, n, "diffuseDoubleSided")?;
    let tgain = p(cx, n, "diffuseTransmitGain")?;
    let tgain = cx.b.prog.saturate(tgain);
    let t_g = cx.b.prog.select(double, tgain, zero);
    let w_d = {
        let keep = cx.b.prog.one_minus(t_g);
        cx.b.prog.mul(dgain, keep)
    };
    let df = cx.b.mul(df, w_d);
    let tcolor = p(cx, n, "diffuseTransmitColor")?;
    let tl = cx.b.leaf(Leaf {
        kind: LeafKind::Translucent { albedo: tcolor },
        tint: one,
        ttint: one,
        frame: dframe,
        label: "diffuse_transmit".into(),
    });
    let tl = cx.b.mul(tl, t_g);
    let dgroup = cx.b.add(df, tl);

    // Subsurface proxy.
    let sscolor = p(cx, n, "subsurfaceColor")?;
    let sspost = p(cx, n, "subsurfacePostTint")?;
    let ssalb = cx.b.prog.mul(sscolor, sspost);
    let ss = cx.b.leaf(Leaf {
        kind: LeafKind::SubsurfaceProxy { albedo: ssalb },
        tint: one,
        ttint: one,
        frame: dframe,
        label: "subsurface".into(),
    });
    let ssgain = p(cx, n, "subsurfaceGain")?;
    let opaque = cx.b.mix(dgroup, ss, ssgain);
    if cx.b.prog.constant(ssgain) != Some(glam::Vec3::ZERO)
        && cx.static_scalar(n, "subsurfaceType", 0.0) != Some(0.0)
    {
        let message = "`subsurfaceType` ≠ 0 is approximated by the diffuse subsurface proxy";
        cx.approximated(n, "subsurfaceType", message);
    }

    // Glass.
    let glass = glass_lobe(cx, n)?;
    let rgain = p(cx, n, "refractionGain")?;
    let base = cx.b.mix(opaque, glass, rgain);

    // Fuzz.
    let cone = p(cx, n, "fuzzConeAngle")?;
    let twenty = cx.constf(20.0);
    let r_f = cx.b.prog.div(cone, twenty);
    let r_f = cx.b.prog.clamp(r_f, 0.01, 1.0);
    let fcolor = p(cx, n, "fuzzColor")?;
    let fframe = frame_for(cx, n, "fuzz")?;
    let fuzz = cx.b.leaf(Leaf {
        kind: LeafKind::SheenCk {
            roughness: r_f,
            masking: SheenMasking::MaterialX,
        },
        tint: fcolor,
        ttint: one,
        frame: fframe,
        label: "fuzz".into(),
    });
    let fgain = p(cx, n, "fuzzGain")?;
    let fuzz = cx.b.mul(fuzz, fgain);
    let fuzzed = cx.b.layer(fuzz, base, TintMode::Rgb);

    // Specular pair.
    let (sp, _, _) = specular_lobe(cx, n, "specular", "specularEnergyCompensation")?;
    let (rs, _, _) = specular_lobe(cx, n, "roughSpecular", "specularEnergyCompensation")?;
    let pair = cx.b.add(sp, rs);
    let specs = cx.b.layer(pair, fuzzed, TintMode::Rgb);

    // Clearcoat with its absorption tint as transmission tint.
    let (cc, ccframe, ccfresnel) =
        specular_lobe(cx, n, "clearcoat", "clearcoatEnergyCompensation")?;
    let cc = match cc {
        Some(id) => {
            let ttint = clearcoat_ttint(cx, n, ccframe, ccfresnel)?;
            retint(cx, id, ttint)
        }
        None => None,
    };
    let coated = cx.b.layer(cc, specs, TintMode::Rgb);

    // Glow and presence.
    let ggain = p(cx, n, "glowGain")?;
    let gcolor = p(cx, n, "glowColor")?;
    let rad = cx.b.prog.mul(ggain, gcolor);
    let glow = cx.b.emission(rad);
    let body = cx.b.add(glow, coated);
    let presence = p(cx, n, "presence")?;
    let clear = cx.b.transparent(one);
    let surface = cx.b.mix(clear, body, presence);

    dropped_features(cx, n)?;
    Ok(surface)
}

/// Re-emit leaf `id` with a new transmission tint.
fn retint<G: Graph>(cx: &mut Lower<'_, G>, id: crate::ir::NodeId, ttint: Reg) -> Cl {
    let mut leaf = match cx.b.node_at(id) {
        crate::ir::Node::Leaf(l) => l.clone(),
        _ => return Some(id),
    };
    leaf.ttint = ttint;
    cx.b.leaf(leaf)
}

/// `tint_a + (1 − tint_a) ⊙ exp(−thickness · (1/μ_t + 1))`, `μ_t = √(1 − (1 − μ_o²)/η_c²)`.
fn clearcoat_ttint<G: Graph>(
    cx: &mut Lower<'_, G>,
    n: G::Id,
    frame: u32,
    fresnel: Fresnel,
) -> Result<Reg, Error> {
    let tint_a = p(cx, n, "clearcoatAbsorptionTint")?;
    let thick = p(cx, n, "clearcoatThickness")?;
    let eta_c = match fresnel {
        Fresnel::Conductor { eta, .. } => cx.b.prog.un(OpCode::Mean, eta),
        _ => cx.constf(1.5),
    };
    let prog = &mut cx.b.prog;
    let mu = prog.view_mu(frame);
    let mu2 = prog.mul(mu, mu);
    let sin2 = prog.one_minus(mu2);
    let eta2 = prog.mul(eta_c, eta_c);
    let s = prog.div(sin2, eta2);
    let c2 = prog.one_minus(s);
    let mu_t = prog.un(OpCode::Sqrt, c2);
    let one = prog.constf(1.0);
    let inv = prog.div(one, mu_t);
    let path = prog.add(inv, one);
    let od = prog.mul(thick, path);
    let neg = prog.un(OpCode::Neg, od);
    let tr = prog.un(OpCode::Exp, neg);
    let rest = prog.one_minus(tint_a);
    let filtered = prog.mul(rest, tr);
    Ok(prog.add(tint_a, filtered))
}

/// `GL`: dielectric RT (or R + transparent for thin glass).
fn glass_lobe<G: Graph>(cx: &mut Lower<'_, G>, n: G::Id) -> Result<Cl, Error> {
    let ior = p(cx, n, "glassIor")?;
    let rough = p(cx, n, "glassRoughness")?;
    let alpha = cx.b.prog.mul(rough, rough);
    let rgain = p(cx, n, "reflectionGain")?;
    let rcolor = p(cx, n, "refractionColor")?;
    let one = cx.constf(1.0);
    let frame = 0;
    let thin = cx.static_scalar(n, "thinGlass", 0.0).unwrap_or(0.0) != 0.0;
    let mode = if thin {
        DielectricMode::R
    } else {
        DielectricMode::Rt
    };
    let leaf = cx.b.leaf(Leaf {
        kind: LeafKind::Dielectric {
            alpha_x: alpha,
            alpha_y: alpha,
            eta: ior,
            mode,
            refl_tint: rgain,
            trans_tint: rcolor,
            t_fresnel: true,
            masking: Masking::HeightCorrelated,
        },
        tint: one,
        ttint: one,
        frame,
        label: "glass".into(),
    });
    if leaf.is_some() && cx.static_scalar(n, "ignoreFresnel", 0.0).unwrap_or(0.0) != 0.0 {
        cx.approximated(n, "ignoreFresnel", "`ignoreFresnel` is ignored");
    }
    if !thin {
        return Ok(leaf);
    }
    let mu = cx.b.prog.view_mu(frame);
    let f = cx.b.prog.bin(OpCode::FresnelDielectric, mu, ior);
    let keep = cx.b.prog.one_minus(f);
    let tint = cx.b.prog.mul(rcolor, keep);
    let through = cx.b.transparent(tint);
    Ok(cx.b.add(leaf, through))
}

/// LW021 for iridescence and single scattering when their gains are non-zero or connected.
fn dropped_features<G: Graph>(cx: &mut Lower<'_, G>, n: G::Id) -> Result<(), Error> {
    for gain in [
        "iridescenceFaceGain",
        "iridescenceEdgeGain",
        "singlescatterGain",
        "singlescatterDirectGain",
    ] {
        let r = p(cx, n, gain)?;
        if cx.b.prog.constant(r) != Some(glam::Vec3::ZERO) {
            cx.diag(
                n,
                Diagnostic::warning(
                    "LW021",
                    format!(
                        "`{gain}` is non-zero or connected; the effect is not supported and dropped"
                    ),
                ),
            );
        }
    }
    Ok(())
}

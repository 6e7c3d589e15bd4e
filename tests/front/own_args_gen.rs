//! Generator of the project's own `.args` definitions, and checks of its tables.
//!
//! The files `args/PxrLayer.args`, `args/PxrLayerMixer.args`, `args/PxrLayerSurface.args`,
//! `args/PxrSurface.args`, `args/PxrDiffuse.args` and `tests/data/args/PxrLayerSurface12.args`
//! are built from the tables below, so that hundreds of parameters stay consistent. The test
//! `committed_files_match_the_generator` fails when a committed file differs from what the
//! tables give; regenerate with
//!
//! ```text
//! VSTRUCTC_REGEN=1 cargo test --test front own_args_gen
//! ```
//!
//! The other tests check the tables against the public interfaces they must match: the
//! PxrLayer/PxrLayerMixer `.args` fixtures (names, types, defaults, members, conditionals; read
//! here with quick-xml directly, independently of vstructc's reader), the `PxrLayerSurface1`
//! node of the RIB fixture, and the built-in defaults of closures.md §4.1.
//!
//! Parameter names, types, defaults and conditionals are interface facts; labels, pages and
//! help texts are our own.

use crate::common;

use std::collections::{BTreeMap, BTreeSet};

// ---------------------------------------------------------------------------------------
// Tables: PxrLayer lobes and members
// ---------------------------------------------------------------------------------------

/// One lobe input of PxrLayer.
#[derive(Clone, Copy)]
struct LayerParam {
    /// PxrLayer input name.
    input: &'static str,
    /// Member name on `pxrMaterialOut` (and on the mixer/surface heads); `None`: not a member.
    member: Option<&'static str>,
    ty: &'static str,
    /// Default on PxrLayer.
    layer_default: &'static str,
    /// Default of the corresponding PxrLayerMixer input members (`baselayer_<m>`, …).
    mixer_default: &'static str,
    /// `min`/`max` UI range.
    range: Option<(&'static str, &'static str)>,
}

/// A member whose name is the input's name.
const fn m(
    input: &'static str,
    ty: &'static str,
    layer: &'static str,
    mixer: &'static str,
) -> LayerParam {
    LayerParam {
        input,
        member: Some(input),
        ty,
        layer_default: layer,
        mixer_default: mixer,
        range: None,
    }
}

/// A member computed from an input of another name.
const fn renamed(
    input: &'static str,
    member: &'static str,
    ty: &'static str,
    layer: &'static str,
    mixer: &'static str,
) -> LayerParam {
    LayerParam {
        input,
        member: Some(member),
        ty,
        layer_default: layer,
        mixer_default: mixer,
        range: None,
    }
}

/// An input that is not a member (folded into other members by the layer).
const fn plain(input: &'static str, ty: &'static str, layer: &'static str) -> LayerParam {
    LayerParam {
        input,
        member: None,
        ty,
        layer_default: layer,
        mixer_default: "",
        range: None,
    }
}

impl LayerParam {
    const fn range(self, lo: &'static str, hi: &'static str) -> Self {
        LayerParam {
            range: Some((lo, hi)),
            ..self
        }
    }
}

/// One lobe of PxrLayer: its enable flag `enable<flag>` and its inputs.
struct Lobe {
    flag: &'static str,
    page: &'static str,
    /// Default of `enable<flag>` on PxrLayer (the mixer's members default to 0).
    enabled: &'static str,
    params: &'static [LayerParam],
}

const ZERO3: &str = "0 0 0";
const ONE3: &str = "1 1 1";
const GREY18: &str = "0.18 0.18 0.18";
const IOR15: &str = "1.5 1.5 1.5";
const SSS_COLOR: &str = "0.83 0.791 0.753";
const SSS_DMFP_COLOR: &str = "0.851 0.557 0.395";

const LOBES: &[Lobe] = &[
    Lobe {
        flag: "Diffuse",
        page: "Diffuse",
        enabled: "1",
        params: &[
            m("diffuseGain", "float", "1", "0").range("0", "1"),
            m("diffuseColor", "color", GREY18, ZERO3),
            m("diffuseRoughness", "float", "0", "0").range("0", "1"),
            m("diffuseBumpNormal", "normal", ZERO3, ZERO3),
            m("diffuseBackColor", "color", GREY18, ZERO3),
            m("diffuseTransmitGain", "float", "0", "0").range("0", "1"),
            m("diffuseTransmitColor", "color", GREY18, ZERO3),
        ],
    },
    Lobe {
        flag: "Specular",
        page: "Specular",
        enabled: "0",
        params: &[
            plain("specularGain", "float", "0").range("0", "1"),
            m("specularFaceColor", "color", ZERO3, ZERO3),
            m("specularEdgeColor", "color", ZERO3, ZERO3),
            m("specularRoughness", "float", "0.2", "0.2").range("0", "1"),
            m("specularIor", "color", IOR15, ZERO3),
            m("specularExtinctionCoeff", "color", ZERO3, ZERO3),
            m("specularAnisotropy", "float", "0", "0").range("-1", "1"),
            m("specularBumpNormal", "normal", ZERO3, ZERO3),
        ],
    },
    Lobe {
        flag: "RoughSpecular",
        page: "Rough Specular",
        enabled: "0",
        params: &[
            plain("roughSpecularGain", "float", "0").range("0", "1"),
            m("roughSpecularFaceColor", "color", ZERO3, ZERO3),
            m("roughSpecularEdgeColor", "color", ZERO3, ZERO3),
            m("roughSpecularRoughness", "float", "0.6", "0.6").range("0", "1"),
            m("roughSpecularIor", "color", IOR15, ZERO3),
            m("roughSpecularExtinctionCoeff", "color", ZERO3, ZERO3),
            m("roughSpecularAnisotropy", "float", "0", "0").range("-1", "1"),
            m("roughSpecularBumpNormal", "normal", ZERO3, ZERO3),
        ],
    },
    Lobe {
        flag: "Clearcoat",
        page: "Clearcoat",
        enabled: "0",
        params: &[
            plain("clearcoatGain", "float", "0").range("0", "1"),
            m("clearcoatFaceColor", "color", ZERO3, ZERO3),
            m("clearcoatEdgeColor", "color", ZERO3, ZERO3),
            m("clearcoatRoughness", "float", "0", "0").range("0", "1"),
            m("clearcoatIor", "color", IOR15, ZERO3),
            m("clearcoatExtinctionCoeff", "color", ZERO3, ZERO3),
            m("clearcoatThickness", "float", "0", "0").range("0", "1"),
            m("clearcoatAbsorptionTint", "color", ZERO3, ZERO3),
            m("clearcoatAnisotropy", "float", "0", "0").range("-1", "1"),
            m("clearcoatBumpNormal", "normal", ZERO3, ZERO3),
        ],
    },
    Lobe {
        flag: "Iridescence",
        page: "Iridescence",
        enabled: "0",
        params: &[
            m("iridescenceFaceGain", "float", "0", "0").range("0", "1"),
            m("iridescenceEdgeGain", "float", "0", "0").range("0", "1"),
            m("iridescencePrimaryColor", "color", "1 0 0", ZERO3),
            m("iridescenceSecondaryColor", "color", "0 0 1", ZERO3),
            m("iridescenceRoughness", "float", "0.2", "0.2").range("0", "1"),
            m("iridescenceThickness", "float", "800", "0"),
        ],
    },
    Lobe {
        flag: "Fuzz",
        page: "Fuzz",
        enabled: "0",
        params: &[
            m("fuzzGain", "float", "0", "0"),
            m("fuzzColor", "color", ONE3, ZERO3),
            m("fuzzConeAngle", "float", "8", "0").range("0", "20"),
            m("fuzzBumpNormal", "normal", ZERO3, ZERO3),
        ],
    },
    Lobe {
        flag: "Subsurface",
        page: "Subsurface",
        enabled: "0",
        params: &[
            m("subsurfaceGain", "float", "0", "0").range("0", "1"),
            m("subsurfaceColor", "color", SSS_COLOR, ZERO3),
            m("subsurfaceDmfp", "float", "10", "1"),
            m("subsurfaceDmfpColor", "color", SSS_DMFP_COLOR, ONE3),
            m("shortSubsurfaceGain", "float", "0", "0").range("0", "1"),
            m("shortSubsurfaceColor", "color", "0.9 0.9 0.9", ZERO3),
            m("shortSubsurfaceDmfp", "float", "5", "1"),
            m("longSubsurfaceGain", "float", "0", "0").range("0", "1"),
            m("longSubsurfaceColor", "color", "0.8 0 0", ZERO3),
            m("longSubsurfaceDmfp", "float", "20", "1"),
            m("subsurfacePostTint", "color", ONE3, ONE3),
            m("subsurfaceTransmitGain", "float", "0", "0").range("0", "1"),
        ],
    },
    Lobe {
        flag: "Singlescatter",
        page: "Single Scatter",
        enabled: "0",
        params: &[
            m("singlescatterGain", "float", "0", "0").range("0", "1"),
            m("singlescatterColor", "color", SSS_COLOR, ZERO3),
            m("singlescatterMfp", "float", "10", "1"),
            m("singlescatterMfpColor", "color", SSS_DMFP_COLOR, ONE3),
            m("singlescatterDirectionality", "float", "0", "0").range("-0.99", "0.99"),
            m("singlescatterIor", "float", "1.3", "0").range("1.001", "2"),
            m("singlescatterBlur", "float", "0", "0").range("0", "1"),
            m("singlescatterDirectGain", "float", "0", "0").range("0", "1"),
            m("singlescatterDirectGainTint", "color", ONE3, ONE3),
        ],
    },
    Lobe {
        flag: "RR",
        page: "Glass",
        enabled: "0",
        params: &[
            renamed("rrRefractionGain", "refractionGain", "float", "0", "0").range("0", "1"),
            renamed("rrReflectionGain", "reflectionGain", "float", "0", "0").range("0", "1"),
            renamed("rrRefractionColor", "refractionColor", "color", ONE3, ONE3),
            renamed("rrRoughness", "glassRoughness", "float", "0.1", "0.1").range("0", "1"),
            renamed("rrIor", "glassIor", "float", "1.5", "1.5"),
        ],
    },
    Lobe {
        flag: "Glow",
        page: "Glow",
        enabled: "0",
        params: &[
            m("glowGain", "float", "0", "0"),
            m("glowColor", "color", ONE3, ZERO3),
        ],
    },
];

/// What decides whether an output member connects (the shape of its conditional).
#[derive(Clone, Copy, PartialEq)]
enum CondKind {
    /// The global `bumpNormal`.
    GlobalBump,
    /// An `enable<flag>` member: `set 1 if … else set 0`.
    Flag,
    /// A per-lobe bump normal: connect if the lobe is on and the bump is connected.
    LobeBump,
    /// `diffuseColor`, driven by the hidden `enableDiffuseAlways`.
    DiffuseAlways,
    /// Any other lobe member.
    Lobe,
}

/// One member of the `pxrMaterialOut` vstruct.
struct Member {
    name: &'static str,
    ty: &'static str,
    /// The lobe flag (`Diffuse`, `RR`, …); empty for the global bump.
    flag: &'static str,
    kind: CondKind,
    mixer_default: &'static str,
}

/// The 79 members in our declaration order: global bump, then per lobe its flag and members.
fn members() -> Vec<Member> {
    let mut out = vec![Member {
        name: "bumpNormal",
        ty: "normal",
        flag: "",
        kind: CondKind::GlobalBump,
        mixer_default: ZERO3,
    }];
    for lobe in LOBES {
        out.push(Member {
            name: flag_name(lobe.flag),
            ty: "int",
            flag: lobe.flag,
            kind: CondKind::Flag,
            mixer_default: "0",
        });
        for p in lobe.params {
            let Some(name) = p.member else { continue };
            let kind = if name == "diffuseColor" {
                CondKind::DiffuseAlways
            } else if name.ends_with("BumpNormal") {
                CondKind::LobeBump
            } else {
                CondKind::Lobe
            };
            out.push(Member {
                name,
                ty: p.ty,
                flag: lobe.flag,
                kind,
                mixer_default: p.mixer_default,
            });
        }
    }
    out
}

/// `enable<flag>` as a static string.
fn flag_name(flag: &str) -> &'static str {
    Box::leak(format!("enable{flag}").into_boxed_str())
}

/// PxrLayer's conditional for member `m`.
fn layer_cond(m: &Member) -> String {
    let flag = format!("enable{}", m.flag);
    match m.kind {
        CondKind::GlobalBump => "connect if bumpNormal is connected".to_string(),
        CondKind::Flag => format!("set 1 if {flag} == 1 else set 0"),
        CondKind::LobeBump => format!("connect if {flag} == 1 and {} is connected", m.name),
        CondKind::DiffuseAlways => "connect if enableDiffuseAlways == 1".to_string(),
        CondKind::Lobe => format!("connect if {flag} == 1"),
    }
}

/// The mixer's input heads, in compositing order.
const MIXER_HEADS: [&str; 5] = ["baselayer", "layer1", "layer2", "layer3", "layer4"];

/// PxrLayerMixer's conditional for member `m`: the layer test OR-ed over the five heads.
fn mixer_cond(m: &Member) -> String {
    let flag = format!("enable{}", m.flag);
    let over_heads = |f: &dyn Fn(&str) -> String| {
        MIXER_HEADS
            .iter()
            .map(|h| f(h))
            .collect::<Vec<_>>()
            .join(" or ")
    };
    match m.kind {
        CondKind::GlobalBump => {
            format!(
                "connect if {}",
                over_heads(&|h| format!("({h}_bumpNormal is connected)"))
            )
        }
        CondKind::Flag => format!(
            "set 1 if ({}) else set 0",
            over_heads(&|h| format!("{h}_{flag} == 1"))
        ),
        CondKind::LobeBump => format!(
            "connect if {}",
            over_heads(&|h| format!("({h}_{flag} == 1 and {h}_{} is connected)", m.name))
        ),
        CondKind::DiffuseAlways => "connect if enableDiffuseAlways == 1".to_string(),
        CondKind::Lobe => format!(
            "connect if ({})",
            over_heads(&|h| format!("{h}_{flag} == 1"))
        ),
    }
}

// ---------------------------------------------------------------------------------------
// Tables: the bxdfs
// ---------------------------------------------------------------------------------------

/// PxrLayerSurface's parameters: every parameter of `PxrLayerSurface1` in
/// fixtures/rib/ldd/pxrLayerSurface.0001.rib with the RIB's type and value; parameters the RIB
/// connects take the built-in defaults of closures.md §4.1 (PxrLayer's defaults).
/// `int[]` is a dynamic int array (the RIB writes `int[1]` for its one element).
const SURFACE_PARAMS: &[(&str, &str, &str)] = &[
    ("diffuseGain", "float", "1"),
    ("diffuseColor", "color", GREY18),
    ("diffuseRoughness", "float", "0"),
    ("diffuseExponent", "float", "1"),
    ("diffuseBumpNormal", "normal", ZERO3),
    ("diffuseDoubleSided", "int", "0"),
    ("diffuseBackUseDiffuseColor", "int", "1"),
    ("diffuseBackColor", "color", GREY18),
    ("diffuseTransmitGain", "float", "0"),
    ("diffuseTransmitColor", "color", GREY18),
    ("specularFresnelMode", "int", "0"),
    ("specularFaceColor", "color", ZERO3),
    ("specularEdgeColor", "color", ZERO3),
    ("specularFresnelShape", "float", "5"),
    ("specularIor", "color", IOR15),
    ("specularExtinctionCoeff", "color", ZERO3),
    ("specularRoughness", "float", "0.2"),
    ("specularModelType", "int", "0"),
    ("specularAnisotropy", "float", "0"),
    ("specularAnisotropyDirection", "vector", ZERO3),
    ("specularBumpNormal", "normal", ZERO3),
    ("specularDoubleSided", "int", "0"),
    ("roughSpecularFresnelMode", "int", "0"),
    ("roughSpecularFaceColor", "color", ZERO3),
    ("roughSpecularEdgeColor", "color", ZERO3),
    ("roughSpecularFresnelShape", "float", "5"),
    ("roughSpecularIor", "color", IOR15),
    ("roughSpecularExtinctionCoeff", "color", ZERO3),
    ("roughSpecularRoughness", "float", "0.6"),
    ("roughSpecularModelType", "int", "0"),
    ("roughSpecularAnisotropy", "float", "0"),
    ("roughSpecularAnisotropyDirection", "vector", ZERO3),
    ("roughSpecularBumpNormal", "normal", ZERO3),
    ("roughSpecularDoubleSided", "int", "0"),
    ("clearcoatFresnelMode", "int", "0"),
    ("clearcoatFaceColor", "color", ZERO3),
    ("clearcoatEdgeColor", "color", ZERO3),
    ("clearcoatFresnelShape", "float", "5"),
    ("clearcoatIor", "color", IOR15),
    ("clearcoatExtinctionCoeff", "color", ZERO3),
    ("clearcoatRoughness", "float", "0"),
    ("clearcoatModelType", "int", "0"),
    ("clearcoatAnisotropy", "float", "0"),
    ("clearcoatAnisotropyDirection", "vector", ZERO3),
    ("clearcoatBumpNormal", "normal", ZERO3),
    ("clearcoatThickness", "float", "0"),
    ("clearcoatAbsorptionTint", "color", ZERO3),
    ("clearcoatDoubleSided", "int", "0"),
    ("specularEnergyCompensation", "float", "0"),
    ("clearcoatEnergyCompensation", "float", "0"),
    ("iridescenceFaceGain", "float", "0"),
    ("iridescenceEdgeGain", "float", "0"),
    ("iridescenceFresnelShape", "float", "5"),
    ("iridescenceMode", "int", "0"),
    ("iridescencePrimaryColor", "color", "1 0 0"),
    ("iridescenceSecondaryColor", "color", "0 0 1"),
    ("iridescenceRoughness", "float", "0.2"),
    ("iridescenceCurve", "float", "1"),
    ("iridescenceScale", "float", "1"),
    ("iridescenceFlip", "int", "0"),
    ("iridescenceThickness", "float", "800"),
    ("iridescenceDoubleSided", "int", "0"),
    ("fuzzGain", "float", "0"),
    ("fuzzColor", "color", ONE3),
    ("fuzzConeAngle", "float", "8"),
    ("fuzzBumpNormal", "normal", ZERO3),
    ("fuzzDoubleSided", "int", "0"),
    ("subsurfaceType", "int", "0"),
    ("subsurfaceGain", "float", "0"),
    ("subsurfaceColor", "color", SSS_COLOR),
    ("subsurfaceDmfp", "float", "10"),
    ("subsurfaceDmfpColor", "color", SSS_DMFP_COLOR),
    ("shortSubsurfaceGain", "float", "0"),
    ("shortSubsurfaceColor", "color", "0.9 0.9 0.9"),
    ("shortSubsurfaceDmfp", "float", "5"),
    ("longSubsurfaceGain", "float", "0"),
    ("longSubsurfaceColor", "color", "0.8 0 0"),
    ("longSubsurfaceDmfp", "float", "20"),
    ("subsurfaceDirectionality", "float", "0"),
    ("subsurfaceBleed", "float", "0"),
    ("subsurfaceDiffuseBlend", "float", "0"),
    ("subsurfaceResolveSelfIntersections", "int", "0"),
    ("subsurfaceIor", "float", "1.4"),
    ("subsurfacePostTint", "color", ONE3),
    ("subsurfaceDiffuseSwitch", "float", "1"),
    ("subsurfaceDoubleSided", "int", "0"),
    ("subsurfaceTransmitGain", "float", "0"),
    ("considerBackside", "int", "1"),
    ("continuationRayMode", "int", "0"),
    ("maxContinuationHits", "int", "2"),
    ("followTopology", "float", "0"),
    ("subsurfaceSubset", "string", ""),
    ("singlescatterGain", "float", "0"),
    ("singlescatterColor", "color", SSS_COLOR),
    ("singlescatterMfp", "float", "10"),
    ("singlescatterMfpColor", "color", SSS_DMFP_COLOR),
    ("singlescatterDirectionality", "float", "0"),
    ("singlescatterIor", "float", "1.3"),
    ("singlescatterBlur", "float", "0"),
    ("singlescatterDirectGain", "float", "0"),
    ("singlescatterDirectGainTint", "color", ONE3),
    ("singlescatterDoubleSided", "int", "0"),
    ("singlescatterConsiderBackside", "int", "1"),
    ("singlescatterContinuationRayMode", "int", "0"),
    ("singlescatterMaxContinuationHits", "int", "2"),
    ("singlescatterDirectGainMode", "int", "0"),
    ("singlescatterSubset", "string", ""),
    ("irradianceTint", "color", ONE3),
    ("irradianceRoughness", "float", "0"),
    ("unitLength", "float", "0.1"),
    ("refractionGain", "float", "0"),
    ("reflectionGain", "float", "0"),
    ("refractionColor", "color", ONE3),
    ("glassRoughness", "float", "0.1"),
    ("glassIor", "float", "1.5"),
    ("mwWalkable", "int", "0"),
    ("mwIor", "float", "-1"),
    ("thinGlass", "int", "0"),
    ("ignoreFresnel", "int", "0"),
    ("ignoreAccumOpacity", "int", "0"),
    ("ssAlbedo", "color", ZERO3),
    ("extinction", "color", ZERO3),
    ("g", "float", "0"),
    ("multiScatter", "int", "0"),
    ("enableOverlappingVolumes", "int", "0"),
    ("glowGain", "float", "0"),
    ("glowColor", "color", ONE3),
    ("bumpNormal", "normal", ZERO3),
    ("shadowColor", "color", ZERO3),
    ("shadowMode", "int", "0"),
    ("presence", "float", "1"),
    ("presenceCached", "int", "1"),
    ("mwStartable", "int", "0"),
    ("roughnessMollificationClamp", "float", "32"),
    ("utilityPattern", "int[]", "0"),
];

/// Parameters PxrSurface has in addition (seen on the PxrSurface node `IndustrialGlass2` of
/// fixtures/rib/ldd/PxrDirt_PxrFractal_Glass.rib, with its values).
const PXR_SURFACE_EXTRA: &[(&str, &str, &str)] = &[
    ("iridescenceAnisotropy", "float", "0"),
    ("iridescenceAnisotropyDirection", "vector", ZERO3),
    ("iridescenceBumpNormal", "normal", ZERO3),
    ("glassRefractionRoughness", "float", "-1"),
    ("glassAnisotropy", "float", "0"),
    ("glassAnisotropyDirection", "vector", ZERO3),
    ("glassBumpNormal", "normal", ZERO3),
    ("blocksVolumes", "int", "0"),
    ("shadowBumpTerminator", "int", "0"),
    ("userColor", "color", ZERO3),
];

/// PxrDiffuse: the parameters of the `PxrDiffuse1` node in
/// fixtures/rib/ldd/PxrDirt_PxrFractal_Glass.rib with its values; `diffuseColor` (connected
/// there) defaults to mid grey.
const PXR_DIFFUSE_PARAMS: &[(&str, &str, &str)] = &[
    ("diffuseColor", "color", "0.5 0.5 0.5"),
    ("transmissionBehavior", "int", "2"),
    ("transmissionColor", "color", ZERO3),
    ("presence", "float", "1"),
    ("bumpNormal", "normal", ZERO3),
];

/// The 12 members the golden network connects (vstruct.md §12.3).
const CONNECTED_12: [&str; 12] = [
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

/// Bxdf pages in display order, each with the name prefixes (or exact names) that go there.
const SURFACE_PAGES: &[(&str, &[&str])] = &[
    ("Diffuse", &["diffuse"]),
    ("Specular", &["specular"]),
    ("Rough Specular", &["roughSpecular"]),
    ("Clearcoat", &["clearcoat"]),
    ("Iridescence", &["iridescence"]),
    ("Fuzz", &["fuzz"]),
    (
        "Subsurface",
        &[
            "subsurface",
            "shortSubsurface",
            "longSubsurface",
            "considerBackside",
            "continuationRayMode",
            "maxContinuationHits",
            "followTopology",
            "irradiance",
            "unitLength",
        ],
    ),
    ("Single Scatter", &["singlescatter"]),
    (
        "Glass",
        &[
            "refraction",
            "reflection",
            "glass",
            "thinGlass",
            "ignoreFresnel",
            "ignoreAccumOpacity",
            "mw",
        ],
    ),
    (
        "Volume",
        &[
            "ssAlbedo",
            "extinction",
            "g",
            "multiScatter",
            "enableOverlappingVolumes",
            "blocksVolumes",
        ],
    ),
    ("Glow", &["glow"]),
    ("Globals", &[""]),
];

/// The page of a bxdf parameter: the first page with a prefix the name starts with (a prefix
/// must be followed by an upper-case letter or end the name; `""` catches everything).
fn surface_page(name: &str) -> &'static str {
    for (page, prefixes) in SURFACE_PAGES {
        for prefix in *prefixes {
            if prefix.is_empty() {
                return page;
            }
            if let Some(rest) = name.strip_prefix(prefix)
                && (rest.is_empty() || rest.starts_with(|c: char| c.is_ascii_uppercase()))
            {
                return page;
            }
        }
    }
    "Globals"
}

// ---------------------------------------------------------------------------------------
// Our prose: labels and help texts
// ---------------------------------------------------------------------------------------

/// Lobe prefixes stripped from names to make labels inside their page.
const LABEL_PREFIXES: &[&str] = &[
    "roughSpecular",
    "specular",
    "diffuse",
    "clearcoat",
    "iridescence",
    "fuzz",
    "singlescatter",
    "subsurface",
    "glass",
    "glow",
    "rr",
];

/// A label from a parameter name: lobe prefix dropped, camel case split into words.
fn label(name: &str) -> String {
    let mut base = name;
    for prefix in LABEL_PREFIXES {
        if let Some(rest) = name.strip_prefix(prefix)
            && rest.starts_with(|c: char| c.is_ascii_uppercase())
        {
            base = rest;
            break;
        }
    }
    let mut words = String::new();
    for (i, c) in base.chars().enumerate() {
        if i > 0 && c.is_ascii_uppercase() {
            words.push(' ');
        }
        words.push(if i == 0 { c.to_ascii_uppercase() } else { c });
    }
    words
        .replace("Ior", "IOR")
        .replace("Dmfp", "DMFP")
        .replace("Mfp", "MFP")
}

/// Short help texts, by exact name first, then by name pattern.
fn help(name: &str) -> Option<String> {
    let exact = match name {
        "enableDiffuseAlways" => {
            "Hidden switch: 1 makes the layer export its diffuse colour even when its diffuse lobe is off."
        }
        "bumpNormal" => {
            "Shading normal for the whole material; connect a bump or normal-map pattern. A lobe's own bump normal, where there is one, wins over it."
        }
        "diffuseRoughness" => "0 is Lambertian; larger values give Oren-Nayar reflection.",
        "diffuseExponent" => "Falloff exponent of the Lambertian lobe (1 is plain Lambert).",
        "diffuseDoubleSided" => "1 lights the back side too, and enables diffuse transmission.",
        "diffuseBackUseDiffuseColor" => {
            "1 uses the diffuse colour on the back side; 0 uses the back colour."
        }
        "diffuseTransmitGain" => {
            "Diffuse transmission strength; used only when the lobe is double-sided."
        }
        "clearcoatThickness" => {
            "Coat thickness: 0 filters nothing, thicker coats tend to the absorption tint."
        }
        "clearcoatAbsorptionTint" => "Colour seen through an infinitely thick coat.",
        "fuzzConeAngle" => "Width of the fuzz highlight, in degrees.",
        "subsurfacePostTint" => "Colour multiplied onto the subsurface result.",
        "presence" => "Coverage: 0 makes the surface invisible, 1 fully present.",
        "thinGlass" => "1 treats the glass as a thin sheet that does not bend rays.",
        "refractionGain" | "rrRefractionGain" => "Strength of the glass refraction.",
        "reflectionGain" | "rrReflectionGain" => "Strength of the glass reflection.",
        "refractionColor" | "rrRefractionColor" => "Tint of light refracted through the glass.",
        "glassRoughness" | "rrRoughness" => "Roughness of the glass interface.",
        "glassIor" | "rrIor" => "Index of refraction of the glass.",
        "inputMaterial" => {
            "Connect a PxrLayer or PxrLayerMixer output here; its members drive the layerable parameters."
        }
        "transmissionBehavior" => {
            "How transmission (shadow) rays treat the surface: 0, 1 or 2 (2 uses the transmission colour)."
        }
        "transmissionColor" => "Colour of light passing through for transmission rays.",
        "diffuseColor" => "Albedo of the diffuse lobe.",
        _ => "",
    };
    if !exact.is_empty() {
        return Some(exact.to_string());
    }
    let by_suffix = [
        (
            "FaceColor",
            "Reflectance at normal incidence (artistic Fresnel mode).",
        ),
        (
            "EdgeColor",
            "Reflectance at grazing angles (artistic Fresnel mode).",
        ),
        (
            "ExtinctionCoeff",
            "Per-channel extinction coefficient (physical Fresnel mode).",
        ),
        (
            "Anisotropy",
            "Stretches the highlight, from -1 to 1; 0 is isotropic.",
        ),
        (
            "BumpNormal",
            "Normal for this lobe only; overrides the global bump normal when connected.",
        ),
        (
            "FresnelMode",
            "0: artistic (face and edge colours); 1: physical (IOR and extinction).",
        ),
        ("ModelType", "Microfacet distribution; 1 is GGX."),
        ("DoubleSided", "1 shades the back side as well."),
        ("Roughness", "Microfacet roughness, 0 is a mirror."),
    ];
    for (suffix, text) in by_suffix {
        if name.ends_with(suffix) {
            return Some(text.to_string());
        }
    }
    if name.ends_with("Ior")
        && !name.starts_with("singlescatter")
        && !name.starts_with("subsurface")
    {
        return Some("Per-channel index of refraction (physical Fresnel mode).".to_string());
    }
    if let Some(flag) = name.strip_prefix("enable") {
        return Some(format!(
            "Turns the {} lobe of this layer on (1) or off (0).",
            lobe_words(flag)
        ));
    }
    if matches!(name, "specularGain" | "roughSpecularGain" | "clearcoatGain") {
        return Some("Scales the face and edge colours of the lobe.".to_string());
    }
    None
}

/// Human words for a lobe flag.
fn lobe_words(flag: &str) -> &'static str {
    match flag {
        "Diffuse" => "diffuse",
        "Specular" => "primary specular",
        "RoughSpecular" => "rough specular",
        "Clearcoat" => "clear-coat",
        "Iridescence" => "iridescence",
        "Fuzz" => "fuzz",
        "RR" => "glass (reflection and refraction)",
        "Subsurface" => "subsurface",
        "Singlescatter" => "single-scatter",
        "Glow" => "glow",
        _ => "unknown",
    }
}

// ---------------------------------------------------------------------------------------
// XML writer
// ---------------------------------------------------------------------------------------

/// Escape text for an attribute value or element content.
fn esc(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

/// One `<param>` or `<output>`.
struct El {
    tag: &'static str,
    attrs: Vec<(&'static str, String)>,
    help: Option<String>,
    tags: Vec<&'static str>,
}

impl El {
    fn param(name: &str, ty: &str, default: Option<&str>) -> El {
        let mut attrs = vec![("name", name.to_string())];
        if let Some(base) = ty.strip_suffix("[]") {
            attrs.push(("type", base.to_string()));
            attrs.push(("isDynamicArray", "1".to_string()));
        } else {
            attrs.push(("type", ty.to_string()));
        }
        if let Some(d) = default {
            attrs.push(("default", d.to_string()));
        }
        El {
            tag: "param",
            attrs,
            help: None,
            tags: Vec::new(),
        }
    }

    fn output(name: &str) -> El {
        El {
            tag: "output",
            attrs: vec![("name", name.to_string())],
            help: None,
            tags: Vec::new(),
        }
    }

    fn attr(mut self, key: &'static str, value: impl Into<String>) -> El {
        self.attrs.push((key, value.into()));
        self
    }

    fn range(self, range: Option<(&str, &str)>) -> El {
        match range {
            Some((lo, hi)) => self.attr("min", lo).attr("max", hi),
            None => self,
        }
    }

    fn help(mut self, text: Option<String>) -> El {
        self.help = text;
        self
    }

    fn tag(mut self, t: &'static str) -> El {
        self.tags.push(t);
        self
    }

    fn render(&self, out: &mut String, depth: usize) {
        let ind = "  ".repeat(depth);
        let attrs: String = self
            .attrs
            .iter()
            .map(|(k, v)| format!(" {k}=\"{}\"", esc(v)))
            .collect();
        if self.help.is_none() && self.tags.is_empty() {
            out.push_str(&format!("{ind}<{}{attrs}/>\n", self.tag));
            return;
        }
        out.push_str(&format!("{ind}<{}{attrs}>\n", self.tag));
        if let Some(h) = &self.help {
            out.push_str(&format!("{ind}  <help>{}</help>\n", esc(h)));
        }
        if !self.tags.is_empty() {
            let tags: String = self
                .tags
                .iter()
                .map(|t| format!("<tag value=\"{t}\"/>"))
                .collect();
            out.push_str(&format!("{ind}  <tags>{tags}</tags>\n"));
        }
        out.push_str(&format!("{ind}</{}>\n", self.tag));
    }
}

/// An `.args` document under construction.
struct Doc {
    out: String,
    depth: usize,
}

impl Doc {
    fn new(kind: &str, what: &str, help: &str) -> Doc {
        let mut out = String::from("<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n");
        // XML comments may not contain `--`, so the regeneration command is only referred to.
        out.push_str(&format!(
            "<!-- {what}\n     Written for vstructc and generated from the tables in tests/front/own_args_gen.rs;\n     do not edit by hand (that file says how to regenerate). -->\n"
        ));
        out.push_str("<args format=\"1.0\">\n");
        out.push_str(&format!(
            "  <shaderType><tag value=\"{kind}\"/></shaderType>\n"
        ));
        out.push_str(&format!("  <help>{}</help>\n", esc(help)));
        Doc { out, depth: 1 }
    }

    fn push(&mut self, el: El) {
        el.render(&mut self.out, self.depth);
    }

    fn page(&mut self, name: &str, fill: impl FnOnce(&mut Doc)) {
        self.out.push_str(&format!(
            "{}<page name=\"{}\">\n",
            "  ".repeat(self.depth),
            esc(name)
        ));
        self.depth += 1;
        fill(self);
        self.depth -= 1;
        self.out
            .push_str(&format!("{}</page>\n", "  ".repeat(self.depth)));
    }

    fn finish(mut self) -> String {
        self.out.push_str("</args>\n");
        self.out
    }
}

// ---------------------------------------------------------------------------------------
// The documents
// ---------------------------------------------------------------------------------------

fn lobe_param(p: &LayerParam) -> El {
    El::param(p.input, p.ty, Some(p.layer_default))
        .attr("label", label(p.input))
        .range(p.range)
        .help(help(p.input))
}

/// The `pxrMaterialOut` head and its member outputs, with conditionals from `cond`.
fn material_outputs(doc: &mut Doc, cond: fn(&Member) -> String) {
    doc.push(
        El::output("pxrMaterialOut")
            .help(Some("The whole material as one vstruct: connect it to a mixer layer or a surface's input material.".into()))
            .tag("vstruct"),
    );
    for m in members() {
        doc.push(
            El::output(&format!("pxrMaterialOut_{}", m.name))
                .attr("vstructmember", format!("pxrMaterialOut.{}", m.name))
                .attr("vstructConditionalExpr", cond(&m))
                .tag(m.ty),
        );
    }
}

fn pxr_layer() -> String {
    let mut doc = Doc::new(
        "pattern",
        "PxrLayer-compatible pattern: one material layer.",
        "One layer of a layered material. Each lobe can be switched on; its parameters leave through the pxrMaterialOut vstruct only when the lobe is on.",
    );
    doc.push(
        El::param("enableDiffuseAlways", "int", Some("1"))
            .attr("widget", "null")
            .help(help("enableDiffuseAlways")),
    );
    doc.push(
        El::param("bumpNormal", "normal", Some(ZERO3))
            .attr("label", "Bump Normal")
            .help(help("bumpNormal")),
    );
    for lobe in LOBES {
        doc.page(lobe.page, |doc| {
            let flag = flag_name(lobe.flag);
            doc.push(
                El::param(flag, "int", Some(lobe.enabled))
                    .attr("label", "Enable")
                    .attr("widget", "checkBox")
                    .help(help(flag)),
            );
            for p in lobe.params {
                doc.push(lobe_param(p));
            }
        });
    }
    material_outputs(&mut doc, layer_cond);
    doc.finish()
}

fn pxr_layer_mixer() -> String {
    let mut doc = Doc::new(
        "pattern",
        "PxrLayerMixer-compatible pattern: composites up to five layers.",
        "Composites a base layer and up to four masked layers, member by member, into one pxrMaterialOut vstruct.",
    );
    doc.push(
        El::param("enableDiffuseAlways", "int", Some("1"))
            .attr("widget", "null")
            .help(help("enableDiffuseAlways")),
    );
    let head = |name: &str, label: &str| {
        El::param(name, "vstruct", Some(""))
            .attr("label", label)
            .help(Some(format!(
                "Connect a layer's pxrMaterialOut here ({}).",
                label.to_lowercase()
            )))
            .tag("vstruct")
    };
    doc.page("Base Layer", |doc| {
        doc.push(head("baselayer", "Base Layer"))
    });
    for n in 1..=4 {
        doc.page(&format!("Layer {n}"), |doc| {
            doc.push(
                El::param(
                    &format!("layer{n}Enabled"),
                    "int",
                    Some(if n == 1 { "1" } else { "0" }),
                )
                .attr("label", "Enabled")
                .attr("widget", "checkBox")
                .help(Some(format!(
                    "1 composites layer {n} over the layers below it."
                ))),
            );
            doc.push(head(&format!("layer{n}"), &format!("Layer {n}")));
            doc.push(
                El::param(&format!("layer{n}Mask"), "float", Some("1"))
                    .attr("label", "Mask")
                    .range(Some(("0", "1")))
                    .help(Some(format!(
                        "Where layer {n} covers the layers below it: 0 not at all, 1 fully."
                    ))),
            );
        });
    }
    for h in MIXER_HEADS {
        for m in members() {
            doc.push(
                El::param(&format!("{h}_{}", m.name), m.ty, Some(m.mixer_default))
                    .attr("widget", "null")
                    .attr("vstructmember", format!("{h}.{}", m.name)),
            );
        }
    }
    material_outputs(&mut doc, mixer_cond);
    doc.finish()
}

/// Names of the bxdf members: PxrLayer's member names without the ten enable flags.
fn surface_member_names() -> BTreeSet<&'static str> {
    members()
        .iter()
        .filter(|m| m.kind != CondKind::Flag)
        .map(|m| m.name)
        .collect()
}

/// A PxrSurface-family bxdf: the `inputMaterial` head (encoding E1) and `params`, of which
/// those named in `members` are members of `inputMaterial`.
fn surface(
    what: &str,
    help_text: &str,
    params: &[(&str, &str, &str)],
    members: &BTreeSet<&str>,
) -> String {
    let mut doc = Doc::new("bxdf", what, help_text);
    doc.push(
        El::param("inputMaterial", "float", None)
            .attr("label", "Input Material")
            .attr("readOnly", "true")
            .help(help("inputMaterial"))
            .tag("vstruct"),
    );
    for (page, _) in SURFACE_PAGES {
        let on_page: Vec<_> = params
            .iter()
            .filter(|(n, _, _)| surface_page(n) == *page)
            .collect();
        if on_page.is_empty() {
            continue;
        }
        doc.page(page, |doc| {
            for (name, ty, default) in on_page {
                let mut el = El::param(name, ty, Some(default)).attr("label", label(name));
                if members.contains(name) {
                    el = el.attr("vstructmember", format!("inputMaterial.{name}"));
                }
                doc.push(el.help(help(name)));
            }
        });
    }
    doc.finish()
}

fn pxr_layer_surface() -> String {
    surface(
        "PxrLayerSurface-compatible bxdf: the surface at the end of a layer stack.",
        "Layered surface. Its inputMaterial head takes the pxrMaterialOut of a PxrLayer or PxrLayerMixer; the members it carries override the parameters of the same names.",
        SURFACE_PARAMS,
        &surface_member_names(),
    )
}

fn pxr_layer_surface_12() -> String {
    surface(
        "Test variant of PxrLayerSurface declaring only the 12 members of vstruct.md section 12.3.",
        "PxrLayerSurface with only the diffuse and primary-specular members the golden network connects.",
        SURFACE_PARAMS,
        &CONNECTED_12.into_iter().collect(),
    )
}

fn pxr_surface_params() -> Vec<(&'static str, &'static str, &'static str)> {
    SURFACE_PARAMS
        .iter()
        .chain(PXR_SURFACE_EXTRA)
        .copied()
        .collect()
}

fn pxr_surface() -> String {
    surface(
        "PxrSurface-compatible bxdf.",
        "General-purpose layerable surface: diffuse, two speculars, clear coat, iridescence, fuzz, subsurface, single scatter, glass and glow. The inputMaterial head accepts a PxrLayer or PxrLayerMixer.",
        &pxr_surface_params(),
        &surface_member_names(),
    )
}

fn pxr_diffuse() -> String {
    let mut doc = Doc::new(
        "bxdf",
        "PxrDiffuse-compatible bxdf.",
        "A plain diffuse surface.",
    );
    for (name, ty, default) in PXR_DIFFUSE_PARAMS {
        let mut el = El::param(name, ty, Some(default)).attr("label", label(name));
        if *name == "transmissionBehavior" {
            el = el.range(Some(("0", "2")));
        }
        doc.push(el.help(help(name)));
    }
    doc.finish()
}

/// Every generated file: path relative to the crate root, and its text.
fn generated() -> Vec<(&'static str, String)> {
    vec![
        ("args/PxrLayer.args", pxr_layer()),
        ("args/PxrLayerMixer.args", pxr_layer_mixer()),
        ("args/PxrLayerSurface.args", pxr_layer_surface()),
        ("args/PxrSurface.args", pxr_surface()),
        ("args/PxrDiffuse.args", pxr_diffuse()),
        (
            "tests/data/args/PxrLayerSurface12.args",
            pxr_layer_surface_12(),
        ),
    ]
}

#[test]
fn committed_files_match_the_generator() {
    let regen = std::env::var("VSTRUCTC_REGEN").is_ok_and(|v| v == "1");
    for (rel, text) in generated() {
        let path = common::repo_dir().join(rel);
        if regen {
            if let Some(dir) = path.parent() {
                std::fs::create_dir_all(dir).expect("create folder");
            }
            std::fs::write(&path, &text).expect("write generated file");
            continue;
        }
        let on_disk = std::fs::read_to_string(&path).unwrap_or_default();
        assert!(
            on_disk == text,
            "{rel} differs from the generator's output; run VSTRUCTC_REGEN=1 cargo test --test front own_args_gen"
        );
    }
}

// ---------------------------------------------------------------------------------------
// Checks of the tables against the public interfaces
// ---------------------------------------------------------------------------------------

/// The interface facts of one `<param>`/`<output>`, read with quick-xml.
#[derive(Debug, Clone, PartialEq)]
struct Iface {
    output: bool,
    ty: String,
    default: Vec<String>,
    member: Option<String>,
    cond: Option<String>,
    tags: Vec<String>,
}

/// Collapse runs of whitespace and trim.
fn norm(s: &str) -> String {
    s.split_whitespace().collect::<Vec<_>>().join(" ")
}

/// Numbers compare as f32 (so `0.600000024` equals `0.6`); other tokens verbatim.
fn default_tokens(s: &str) -> Vec<String> {
    s.split(|c: char| c.is_whitespace() || c == ',')
        .filter(|t| !t.is_empty())
        .map(|t| {
            t.parse::<f32>()
                .map_or_else(|_| t.to_string(), |x| format!("{x}"))
        })
        .collect()
}

/// Every property of an `.args` text by name (well-formedness checked by quick-xml).
fn read_iface(text: &str) -> BTreeMap<String, Iface> {
    use quick_xml::events::{BytesStart, Event};
    fn attrs(e: &BytesStart) -> BTreeMap<String, String> {
        e.attributes()
            .map(|a| {
                let a = a.expect("attribute");
                let key = a.key.as_ref().to_string();
                let value = a
                    .normalized_value(quick_xml::XmlVersion::Implicit1_0)
                    .expect("value")
                    .into_owned();
                (key, value)
            })
            .collect()
    }
    fn to_iface(output: bool, a: &BTreeMap<String, String>) -> (String, Iface) {
        let name = a.get("name").cloned().expect("name");
        let iface = Iface {
            output,
            ty: a.get("type").cloned().unwrap_or_default(),
            default: a
                .get("default")
                .map(|d| default_tokens(d))
                .unwrap_or_default(),
            member: a.get("vstructmember").cloned(),
            cond: a.get("vstructConditionalExpr").map(|c| norm(c)),
            tags: Vec::new(),
        };
        (name, iface)
    }
    let mut reader = quick_xml::Reader::from_str(text);
    reader.config_mut().check_comments = true;
    let mut out = BTreeMap::new();
    let mut current: Option<(String, Iface)> = None;
    loop {
        match reader.read_event().expect("well-formed XML") {
            Event::Empty(e) if matches!(e.name().as_ref(), "param" | "output") => {
                let (name, p) = to_iface(e.name().as_ref() == "output", &attrs(&e));
                assert!(out.insert(name.clone(), p).is_none(), "duplicate {name}");
            }
            Event::Start(e) if matches!(e.name().as_ref(), "param" | "output") => {
                assert!(current.is_none(), "nested property");
                current = Some(to_iface(e.name().as_ref() == "output", &attrs(&e)));
            }
            Event::Empty(e) if e.name().as_ref() == "tag" => {
                if let Some((_, p)) = current.as_mut() {
                    p.tags
                        .push(attrs(&e).get("value").cloned().unwrap_or_default());
                }
            }
            Event::End(e) if matches!(e.name().as_ref(), "param" | "output") => {
                let (name, p) = current.take().expect("open property");
                assert!(out.insert(name.clone(), p).is_none(), "duplicate {name}");
            }
            Event::Eof => break,
            _ => {}
        }
    }
    out
}

fn fixture_text(rel: &str) -> Option<String> {
    let dir = common::fixtures()?;
    Some(std::fs::read_to_string(dir.join(rel)).expect("fixture readable"))
}

/// Compare our interface with the fixture's: the same property names, and per property the
/// same direction, type, default, member declaration and (normalised) conditional; outputs
/// also the same first connection type, and params the same `vstruct` tag.
fn assert_same_interface(ours: &BTreeMap<String, Iface>, theirs: &BTreeMap<String, Iface>) {
    let a: BTreeSet<_> = ours.keys().collect();
    let b: BTreeSet<_> = theirs.keys().collect();
    assert_eq!(
        a.difference(&b).collect::<Vec<_>>(),
        Vec::<&&String>::new(),
        "only in ours"
    );
    assert_eq!(
        b.difference(&a).collect::<Vec<_>>(),
        Vec::<&&String>::new(),
        "only in the fixture"
    );
    for (name, o) in ours {
        let t = &theirs[name];
        assert_eq!(o.output, t.output, "{name}: direction");
        assert_eq!(o.ty, t.ty, "{name}: type");
        assert_eq!(o.default, t.default, "{name}: default");
        assert_eq!(o.member, t.member, "{name}: vstructmember");
        assert_eq!(o.cond, t.cond, "{name}: conditional");
        if o.output {
            assert_eq!(o.tags.first(), t.tags.first(), "{name}: output type tag");
        } else {
            let vs = |i: &Iface| i.tags.iter().any(|x| x == "vstruct");
            assert_eq!(vs(o), vs(t), "{name}: vstruct tag");
        }
    }
}

#[test]
fn pxr_layer_interface_matches_the_fixture() {
    let Some(fixture) = fixture_text("args/pixar/PxrLayer.args") else {
        return;
    };
    let ours = read_iface(&pxr_layer());
    assert_eq!(ours.values().filter(|p| !p.output).count(), 83);
    assert_eq!(
        ours.values()
            .filter(|p| p.output && p.cond.is_some())
            .count(),
        79
    );
    assert_same_interface(&ours, &read_iface(&fixture));
}

#[test]
fn pxr_layer_mixer_interface_matches_the_fixture() {
    let Some(fixture) = fixture_text("args/pixar/PxrLayerMixer.args") else {
        return;
    };
    let ours = read_iface(&pxr_layer_mixer());
    assert_eq!(ours.values().filter(|p| !p.output).count(), 409);
    assert_eq!(
        ours.values()
            .filter(|p| p.output && p.cond.is_some())
            .count(),
        79
    );
    assert_same_interface(&ours, &read_iface(&fixture));
}

/// One parameter of a RIB shading request: declared type, name, whether it is a
/// `reference` (a connection), and its values (strings unquoted).
#[derive(Debug)]
struct RibParam {
    ty: String,
    name: String,
    reference: bool,
    values: Vec<String>,
}

/// The parameters of every `REQUEST "TYPE" "HANDLE" …` in `rib`, by handle.
/// A small scanner for the shapes in the fixtures (strings, bracketed lists, comments).
fn rib_nodes(rib: &str, request: &str, ty: &str) -> Vec<(String, Vec<RibParam>)> {
    let opener = format!("{request} \"{ty}\" \"");
    let mut nodes = Vec::new();
    let mut rest = rib;
    while let Some(at) = rest.find(&opener) {
        let after = &rest[at + opener.len()..];
        let end = after.find('"').expect("handle ends");
        let handle = after[..end].to_string();
        let (params, tail) = rib_params(&after[end + 1..]);
        nodes.push((handle, params));
        rest = tail;
    }
    nodes
}

/// Read `"decl" [values]` pairs until the next request (an identifier at the start of a token).
fn rib_params(mut s: &str) -> (Vec<RibParam>, &str) {
    let mut params = Vec::new();
    loop {
        s = s.trim_start();
        if s.starts_with('#') {
            s = s.find('\n').map_or("", |i| &s[i..]);
            continue;
        }
        if !s.starts_with('"') {
            return (params, s);
        }
        let close = s[1..].find('"').expect("decl ends") + 1;
        let decl = &s[1..close];
        s = s[close + 1..].trim_start();
        let open = s.strip_prefix('[').expect("values follow a decl");
        let end = open.find(']').expect("values end");
        let values = rib_values(&open[..end]);
        s = &open[end + 1..];
        let words: Vec<&str> = decl.split_whitespace().collect();
        let reference = words.first() == Some(&"reference");
        let words = if reference { &words[1..] } else { &words[..] };
        params.push(RibParam {
            ty: words[0].to_string(),
            name: words[words.len() - 1].to_string(),
            reference,
            values,
        });
    }
}

fn rib_values(s: &str) -> Vec<String> {
    let mut out = Vec::new();
    let mut rest = s.trim();
    while !rest.is_empty() {
        if let Some(q) = rest.strip_prefix('"') {
            let end = q.find('"').expect("string ends");
            out.push(q[..end].to_string());
            rest = q[end + 1..].trim_start();
        } else {
            let end = rest.find(char::is_whitespace).unwrap_or(rest.len());
            out.push(rest[..end].to_string());
            rest = rest[end..].trim_start();
        }
    }
    out
}

/// RIB type `T[N]` matches our dynamic `T[]`; other types must be equal.
fn same_type(rib: &str, ours: &str) -> bool {
    match (rib.split_once('['), ours.strip_suffix("[]")) {
        (Some((base, _)), Some(our_base)) => base == our_base,
        _ => rib == ours,
    }
}

#[test]
fn pxr_layer_surface_matches_the_rib_node() {
    let Some(rib) = fixture_text("rib/ldd/pxrLayerSurface.0001.rib") else {
        return;
    };
    let nodes = rib_nodes(&rib, "Bxdf", "PxrLayerSurface");
    let (_, params) = nodes
        .iter()
        .find(|(h, p)| h == "PxrLayerSurface1" && p.len() > 1)
        .expect("node");
    let ours: BTreeMap<&str, (&str, &str)> = SURFACE_PARAMS
        .iter()
        .map(|(n, t, d)| (*n, (*t, *d)))
        .collect();
    let rib_names: BTreeSet<&str> = params
        .iter()
        .map(|p| p.name.as_str())
        .filter(|n| *n != "__materialid")
        .collect();
    assert_eq!(
        rib_names,
        ours.keys().copied().collect(),
        "same parameter set as the RIB node"
    );
    assert_eq!(
        ours.len(),
        SURFACE_PARAMS.len(),
        "no duplicates in the table"
    );
    let mut references = 0;
    for p in params.iter().filter(|p| p.name != "__materialid") {
        let (ty, default) = ours[p.name.as_str()];
        assert!(
            same_type(&p.ty, ty),
            "{}: RIB type {} vs {ty}",
            p.name,
            p.ty
        );
        if p.reference {
            references += 1;
        } else if ty == "string" {
            assert_eq!(p.values, vec![default.to_string()], "{}", p.name);
        } else {
            let rib_value = default_tokens(&p.values.join(" "));
            assert_eq!(
                default_tokens(default),
                rib_value,
                "{}: default is the RIB value",
                p.name
            );
        }
    }
    assert_eq!(
        references, 12,
        "the 12 connected members take the built-in defaults"
    );
}

/// closures.md §4.1 built-in defaults (one number stands for every channel).
fn builtin_defaults() -> Vec<(String, f32)> {
    let mut out: Vec<(String, f32)> = [
        ("diffuseGain", 1.0),
        ("diffuseColor", 0.18),
        ("diffuseRoughness", 0.0),
        ("diffuseExponent", 1.0),
        ("diffuseDoubleSided", 0.0),
        ("diffuseBackUseDiffuseColor", 1.0),
        ("diffuseBackColor", 0.18),
        ("diffuseTransmitGain", 0.0),
        ("diffuseTransmitColor", 0.18),
        ("specularEnergyCompensation", 0.0),
        ("clearcoatEnergyCompensation", 0.0),
        ("fuzzGain", 0.0),
        ("fuzzColor", 1.0),
        ("fuzzConeAngle", 8.0),
        ("subsurfaceGain", 0.0),
        ("subsurfacePostTint", 1.0),
        ("refractionGain", 0.0),
        ("reflectionGain", 0.0),
        ("refractionColor", 1.0),
        ("glassRoughness", 0.1),
        ("glassIor", 1.5),
        ("thinGlass", 0.0),
        ("glowGain", 0.0),
        ("glowColor", 1.0),
        ("presence", 1.0),
    ]
    .into_iter()
    .map(|(n, v)| (n.to_string(), v))
    .collect();
    for (prefix, roughness) in [
        ("specular", 0.2),
        ("roughSpecular", 0.6),
        ("clearcoat", 0.0),
    ] {
        for (suffix, v) in [
            ("FresnelMode", 0.0),
            ("FaceColor", 0.0),
            ("EdgeColor", 0.0),
            ("FresnelShape", 5.0),
            ("Ior", 1.5),
            ("ExtinctionCoeff", 0.0),
            ("Roughness", roughness),
            ("ModelType", 0.0),
            ("Anisotropy", 0.0),
        ] {
            out.push((format!("{prefix}{suffix}"), v));
        }
    }
    out.push(("clearcoatThickness".into(), 0.0));
    out.push(("clearcoatAbsorptionTint".into(), 0.0));
    out
}

#[test]
fn surface_defaults_are_the_builtin_defaults() {
    let ours: BTreeMap<&str, &str> = SURFACE_PARAMS.iter().map(|(n, _, d)| (*n, *d)).collect();
    for (name, value) in builtin_defaults() {
        let default = ours
            .get(name.as_str())
            .unwrap_or_else(|| panic!("{name} missing"));
        let numbers: Vec<f32> = default
            .split_whitespace()
            .map(|t| t.parse().expect("number"))
            .collect();
        assert!(
            !numbers.is_empty() && numbers.iter().all(|x| *x == value),
            "{name}: {default} vs {value}"
        );
    }
    let sss: Vec<f32> = ours["subsurfaceColor"]
        .split_whitespace()
        .map(|t| t.parse().unwrap())
        .collect();
    assert_eq!(sss, [0.83, 0.791, 0.753]);
}

#[test]
fn pxr_surface_and_pxr_diffuse_cover_every_fixture_node() {
    let Some(dir) = common::fixtures() else {
        return;
    };
    let surface: BTreeMap<&str, &str> = pxr_surface_params()
        .iter()
        .map(|(n, t, _)| (*n, *t))
        .collect();
    let diffuse: BTreeMap<&str, &str> = PXR_DIFFUSE_PARAMS
        .iter()
        .map(|(n, t, _)| (*n, *t))
        .collect();
    let mut seen = 0;
    for entry in std::fs::read_dir(dir.join("rib/ldd")).expect("rib folder") {
        let path = entry.expect("entry").path();
        if path.extension().is_none_or(|e| e != "rib") {
            continue;
        }
        let rib = std::fs::read_to_string(&path).expect("rib readable");
        for (ty, table) in [
            ("PxrSurface", &surface),
            ("PxrLayerSurface", &surface),
            ("PxrDiffuse", &diffuse),
        ] {
            for (handle, params) in rib_nodes(&rib, "Bxdf", ty) {
                for p in params.iter().filter(|p| p.name != "__materialid") {
                    let ours = table.get(p.name.as_str());
                    assert!(
                        ours.is_some(),
                        "{}: {ty} {handle}: {} not declared",
                        path.display(),
                        p.name
                    );
                    assert!(
                        same_type(&p.ty, ours.copied().unwrap_or("")),
                        "{handle}.{}: type",
                        p.name
                    );
                    seen += 1;
                }
            }
        }
    }
    assert!(
        seen > 400,
        "the fixtures' bxdf nodes were scanned ({seen} parameters)"
    );
}

#[test]
fn surface_documents_declare_the_expected_members() {
    for (text, expected) in [
        (pxr_layer_surface(), 69),
        (pxr_surface(), 69),
        (pxr_layer_surface_12(), 12),
    ] {
        let iface = read_iface(&text);
        let members: Vec<_> = iface.values().filter_map(|p| p.member.as_deref()).collect();
        assert_eq!(members.len(), expected);
        assert!(members.iter().all(|m| m.starts_with("inputMaterial.")));
        let head = &iface["inputMaterial"];
        assert_eq!(head.ty, "float");
        assert_eq!(head.tags, vec!["vstruct".to_string()]);
    }
    let diffuse = read_iface(&pxr_diffuse());
    assert_eq!(diffuse.len(), PXR_DIFFUSE_PARAMS.len());
}

#[test]
fn labels_and_pages_are_derived_as_intended() {
    assert_eq!(label("diffuseTransmitGain"), "Transmit Gain");
    assert_eq!(label("rrRefractionGain"), "Refraction Gain");
    assert_eq!(label("specularIor"), "IOR");
    assert_eq!(label("shortSubsurfaceDmfp"), "Short Subsurface DMFP");
    assert_eq!(label("g"), "G");
    assert_eq!(surface_page("g"), "Volume");
    assert_eq!(surface_page("glowGain"), "Glow");
    assert_eq!(surface_page("glassIor"), "Glass");
    assert_eq!(surface_page("specularEnergyCompensation"), "Specular");
    assert_eq!(surface_page("mwIor"), "Glass");
    assert_eq!(surface_page("presence"), "Globals");
    assert_eq!(surface_page("utilityPattern"), "Globals");
}

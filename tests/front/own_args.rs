//! The project's own `args/` definitions, read with vstructc's `.args` reader, agree with the
//! public interfaces: PxrLayer and PxrLayerMixer with the fixtures (every name, type, default,
//! member declaration and conditional), PxrLayerSurface/PxrSurface with vstruct.md §12.2.

use crate::common;

use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;
use vstructc::front::args::parse_args;
use vstructc::registry::{Definition, Property};
use vstructc::{BaseType, Diagnostics, Value};

/// The 69 member names of vstruct.md §12.2.
const MEMBERS_69: &str =
    "bumpNormal diffuseGain diffuseColor diffuseRoughness diffuseBumpNormal diffuseBackColor
diffuseTransmitGain diffuseTransmitColor specularFaceColor specularEdgeColor specularIor
specularExtinctionCoeff specularRoughness specularAnisotropy specularBumpNormal
roughSpecularFaceColor roughSpecularEdgeColor roughSpecularIor roughSpecularExtinctionCoeff
roughSpecularRoughness roughSpecularAnisotropy roughSpecularBumpNormal clearcoatFaceColor
clearcoatEdgeColor clearcoatIor clearcoatExtinctionCoeff clearcoatRoughness
clearcoatAnisotropy clearcoatBumpNormal clearcoatThickness clearcoatAbsorptionTint
iridescenceFaceGain iridescenceEdgeGain iridescencePrimaryColor iridescenceSecondaryColor
iridescenceThickness iridescenceRoughness fuzzGain fuzzColor fuzzConeAngle fuzzBumpNormal
refractionGain refractionColor reflectionGain glassRoughness glassIor subsurfaceGain
subsurfaceColor subsurfaceDmfp subsurfaceDmfpColor shortSubsurfaceGain shortSubsurfaceColor
shortSubsurfaceDmfp longSubsurfaceGain longSubsurfaceColor longSubsurfaceDmfp
subsurfacePostTint subsurfaceTransmitGain singlescatterGain singlescatterColor
singlescatterMfp singlescatterMfpColor singlescatterDirectionality singlescatterIor
singlescatterBlur singlescatterDirectGain singlescatterDirectGainTint glowGain glowColor";

/// The 12 members of vstruct.md §12.3.
const MEMBERS_12: &str =
    "diffuseGain diffuseColor diffuseRoughness diffuseBackColor diffuseTransmitGain
diffuseTransmitColor specularFaceColor specularEdgeColor specularIor specularExtinctionCoeff
specularRoughness specularAnisotropy";

fn names(list: &str) -> BTreeSet<String> {
    list.split_whitespace().map(str::to_string).collect()
}

/// Read one `.args` file with vstructc's reader.
fn load(path: &Path) -> (Definition, Diagnostics) {
    let bytes = std::fs::read(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let id = path
        .file_stem()
        .and_then(|s| s.to_str())
        .expect("file stem");
    let mut diags = Diagnostics::new();
    match parse_args(&bytes, &path.display().to_string(), id, &mut diags) {
        Ok(def) => (def, diags),
        Err(e) => panic!("{}: {e}", path.display()),
    }
}

fn own(name: &str) -> std::path::PathBuf {
    common::repo_dir().join("args").join(name)
}

fn norm(s: &str) -> String {
    s.split_whitespace().collect::<Vec<_>>().join(" ")
}

/// head → member names, over the properties of one direction.
fn members_by_head(props: &[Property]) -> BTreeMap<String, BTreeSet<String>> {
    let mut out: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
    for p in props {
        if let Some(m) = &p.vstruct {
            out.entry(m.head.clone())
                .or_default()
                .insert(m.member.clone());
        }
    }
    out
}

/// Everything of one property that belongs to the interface.
fn interface(p: &Property) -> String {
    let member = p.vstruct.as_ref().map(|m| {
        let cond = m.cond.as_ref().map(|c| norm(&c.text));
        format!("{}.{} alias={:?} cond={cond:?}", m.head, m.member, m.alias)
    });
    format!(
        "{:?} {} default={:?} member={member:?} connectable={} vstruct_tag={}",
        p.direction,
        p.ty,
        p.default,
        p.connectable,
        p.has_tag("vstruct")
    )
}

fn assert_same_interface(ours: &Definition, theirs: &Definition) {
    assert_eq!(ours.kind, theirs.kind);
    for (mine, fixture) in [
        (&ours.inputs, &theirs.inputs),
        (&ours.outputs, &theirs.outputs),
    ] {
        let a: BTreeMap<&str, String> = mine
            .iter()
            .map(|p| (p.name.as_str(), interface(p)))
            .collect();
        let b: BTreeMap<&str, String> = fixture
            .iter()
            .map(|p| (p.name.as_str(), interface(p)))
            .collect();
        assert_eq!(
            a.keys().collect::<Vec<_>>(),
            b.keys().collect::<Vec<_>>(),
            "property names"
        );
        for (name, i) in &a {
            assert_eq!(i, &b[name], "{name}");
        }
        assert_eq!(
            members_by_head(mine),
            members_by_head(fixture),
            "members per head"
        );
    }
}

#[test]
fn own_pxr_layer_agrees_with_the_fixture() {
    let dir = fixtures_or_skip!();
    let (ours, diags) = load(&own("PxrLayer.args"));
    assert!(!diags.has_warnings(), "{diags:?}");
    let (theirs, _) = load(&dir.join("args/pixar/PxrLayer.args"));
    assert_same_interface(&ours, &theirs);

    assert_eq!(ours.inputs.len(), 83);
    let heads = members_by_head(&ours.outputs);
    assert_eq!(heads.keys().collect::<Vec<_>>(), ["pxrMaterialOut"]);
    assert_eq!(heads["pxrMaterialOut"].len(), 79);
    assert!(
        ours.outputs
            .iter()
            .filter_map(|p| p.vstruct.as_ref())
            .all(|m| m.cond.is_some())
    );
    assert!(
        ours.output("pxrMaterialOut")
            .expect("head")
            .has_tag("vstruct")
    );
}

#[test]
fn own_pxr_layer_mixer_agrees_with_the_fixture() {
    let dir = fixtures_or_skip!();
    let (ours, diags) = load(&own("PxrLayerMixer.args"));
    assert!(!diags.has_warnings(), "{diags:?}");
    let (theirs, _) = load(&dir.join("args/pixar/PxrLayerMixer.args"));
    assert_same_interface(&ours, &theirs);

    assert_eq!(ours.inputs.len(), 409);
    let inputs = members_by_head(&ours.inputs);
    assert_eq!(
        inputs.keys().collect::<Vec<_>>(),
        ["baselayer", "layer1", "layer2", "layer3", "layer4"]
    );
    assert!(inputs.values().all(|m| m.len() == 79));
    let outputs = members_by_head(&ours.outputs);
    assert_eq!(outputs["pxrMaterialOut"].len(), 79);
    assert!(
        ours.outputs
            .iter()
            .filter_map(|p| p.vstruct.as_ref())
            .all(|m| m.cond.is_some())
    );
    let head = ours.input("baselayer").expect("head");
    assert_eq!(head.ty.base, BaseType::Vstruct);
    assert!(head.has_tag("vstruct"));
}

/// Checks a PxrSurface-family definition: E1 head, and exactly `expected` as members, each
/// on the input of the same name.
fn assert_surface(def: &Definition, expected: &BTreeSet<String>) {
    assert_eq!(def.kind, "bxdf");
    let head = def.input("inputMaterial").expect("inputMaterial");
    assert_eq!(
        head.ty.base,
        BaseType::Float,
        "encoding E1 declares the head as float"
    );
    assert!(head.has_tag("vstruct"));
    assert_eq!(head.meta("readOnly"), Some("true"));
    let heads = members_by_head(&def.inputs);
    assert_eq!(heads.keys().collect::<Vec<_>>(), ["inputMaterial"]);
    assert_eq!(&heads["inputMaterial"], expected);
    for p in def.inputs.iter().filter(|p| p.vstruct.is_some()) {
        assert_eq!(
            p.vstruct.as_ref().map(|m| m.member.as_str()),
            Some(p.name.as_str())
        );
        assert!(p.vstruct.as_ref().is_some_and(|m| m.cond.is_none()));
    }
}

#[test]
fn own_layer_surfaces_declare_exactly_the_69_members() {
    for file in ["PxrLayerSurface.args", "PxrSurface.args"] {
        let (def, diags) = load(&own(file));
        assert!(!diags.has_warnings(), "{file}: {diags:?}");
        assert_surface(&def, &names(MEMBERS_69));
        // Parameters the lowering reads, with closures.md §4.1 defaults (spot checks).
        let default = |n: &str| def.input(n).and_then(|p| p.default.clone());
        assert_eq!(default("presence"), Some(Value::Float(1.0)), "{file}");
        assert_eq!(
            default("specularFresnelShape"),
            Some(Value::Float(5.0)),
            "{file}"
        );
        assert_eq!(default("diffuseDoubleSided"), Some(Value::Int(0)), "{file}");
        assert_eq!(
            default("diffuseColor"),
            Some(Value::Triple(BaseType::Color, [0.18; 3])),
            "{file}"
        );
        assert_eq!(
            default("roughSpecularRoughness"),
            Some(Value::Float(0.6)),
            "{file}"
        );
    }
}

#[test]
fn the_69_members_are_pxr_layer_members_without_enable_flags() {
    let dir = fixtures_or_skip!();
    let (layer, _) = load(&dir.join("args/pixar/PxrLayer.args"));
    let shared: BTreeSet<String> = members_by_head(&layer.outputs)["pxrMaterialOut"]
        .iter()
        .filter(|m| !m.starts_with("enable"))
        .cloned()
        .collect();
    assert_eq!(shared, names(MEMBERS_69));
}

#[test]
fn test_variant_declares_only_the_12_connected_members() {
    let path = common::repo_dir().join("tests/data/args/PxrLayerSurface12.args");
    let (def, diags) = load(&path);
    assert!(!diags.has_warnings(), "{diags:?}");
    assert_surface(&def, &names(MEMBERS_12));
    assert!(def.input("glowGain").is_some_and(|p| p.vstruct.is_none()));
}

#[test]
fn own_pxr_diffuse_is_a_small_bxdf() {
    let (def, diags) = load(&own("PxrDiffuse.args"));
    assert!(!diags.has_warnings(), "{diags:?}");
    assert_eq!(def.kind, "bxdf");
    let inputs: Vec<&str> = def.inputs.iter().map(|p| p.name.as_str()).collect();
    assert_eq!(
        inputs,
        [
            "diffuseColor",
            "transmissionBehavior",
            "transmissionColor",
            "presence",
            "bumpNormal"
        ]
    );
    assert_eq!(
        def.input("transmissionBehavior")
            .and_then(|p| p.default.clone()),
        Some(Value::Int(2))
    );
}

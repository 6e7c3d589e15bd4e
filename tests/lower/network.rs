//! Lowering of real networks: the bundled examples (resolved first, embedded definitions;
//! IR and lobe-list snapshots), the golden network of vstruct.md §12 from the RenderMan for
//! Maya export (closures.md §5.8), set-written enable flags after real resolution, and the
//! `compile` command end to end.

// Colours are written exactly as the fixture RIB writes them.
#![allow(clippy::excessive_precision)]
use crate::common;

use glam::Vec3;
use std::process::Command;
use vstructc::front::rib::{RibOptions, parse_rib};
use vstructc::ir::{Fresnel, LeafKind, SimpleAlbedo};
use vstructc::lower::network::{lower_terminal, terminals};
use vstructc::network::Network;
use vstructc::registry::Registry;
use vstructc::resolve::{ResolveOptions, resolve};
use vstructc::{Diagnostics, Severity};

fn load(bytes: &[u8], name: &str, reg: &Registry) -> Network {
    let mut diags = Diagnostics::new();
    let mut net = parse_rib(bytes, name, reg, &RibOptions::default(), &mut diags).expect("parses");
    let res = resolve(&mut net, reg, &ResolveOptions::default());
    diags.extend(res.diagnostics);
    assert!(
        !diags.iter().any(|d| d.severity == Severity::Error),
        "{diags:#?}"
    );
    net
}

fn compile_all(net: &Network, reg: &Registry) -> (String, Diagnostics) {
    let mut diags = Diagnostics::new();
    let mut out = String::new();
    for (name, node) in terminals(net, None).unwrap() {
        let ir = lower_terminal(net, reg, node, &name, &mut diags).expect("lowers");
        out.push_str(&ir.text());
        out.push('\n');
        out.push_str(&ir.lobes_text(&SimpleAlbedo));
    }
    (out, diags)
}

fn example(name: &str) -> String {
    let path = common::repo_dir().join("examples").join(name);
    let bytes = std::fs::read(&path).expect("example exists");
    let reg = Registry::embedded();
    let net = load(&bytes, name, &reg);
    let (out, diags) = compile_all(&net, &reg);
    assert_eq!(diags.count("LW003"), 0, "embedded definitions are used");
    let codes: Vec<&str> = diags.iter().map(|d| d.code.as_str()).collect();
    format!("{out}\ndiagnostics: {codes:?}\n")
}

#[test]
fn example_layered() {
    insta::assert_snapshot!(example("layered.rib"));
}

#[test]
fn example_override() {
    insta::assert_snapshot!(example("override.rib"));
}

#[test]
fn example_chain() {
    insta::assert_snapshot!(example("chain.rib"));
}

/// closures.md §5.8 with the real export: one external slot `PxrThreshold1.resultR` with
/// fallback 1; Lambert + one generalized-Schlick specular; slot 0 shows PxrLayer1, slot 1
/// PxrLayer2.
#[test]
fn golden_fixture_lowers_to_two_lobes_and_one_slot() {
    let dir = fixtures_or_skip!();
    let surface = common::repo_dir().join("args/PxrLayerSurface.args");
    let reg = common::golden_registry(&dir, &surface);
    let bytes = std::fs::read(dir.join(common::GOLDEN_RIB)).unwrap();
    let net = load(&bytes, "pxrLayerSurface.0001.rib", &reg);
    let list = terminals(&net, None).unwrap();
    assert!(!list.is_empty());
    let mut diags = Diagnostics::new();
    let (name, node) = list[0].clone();
    let ir = lower_terminal(&net, &reg, node, &name, &mut diags).unwrap();
    assert_eq!(ir.inputs.len(), 1, "{}", ir.text());
    assert_eq!(ir.inputs[0].name, "PxrThreshold1.resultR");
    assert_eq!(ir.inputs[0].fallback_vec(), Vec3::ONE);
    assert_eq!(ir.lobe_count(), 2, "{}", ir.text());
    let layer1 = Vec3::new(0.00967446715, 0.179702222, 0.0572573431);
    let layer2 = Vec3::new(0.179702222, 0.0125546111, 0.0125546111);
    for (slot, diffuse, f0) in [(0.0, layer1, Vec3::ZERO), (1.0, layer2, layer2)] {
        let regs = ir.run_program(Some(&[Vec3::splat(slot)]), 1.0);
        let mut seen = 0;
        for (_, leaf) in ir.leaves() {
            match leaf.kind {
                LeafKind::Lambert { albedo } => {
                    assert!((regs[albedo.index()] - diffuse).abs().max_element() < 1e-7);
                    seen += 1;
                }
                LeafKind::MicrofacetR {
                    alpha_x,
                    alpha_y,
                    fresnel: Fresnel::Schlick { f0: r0, f90, .. },
                    ..
                } => {
                    assert!((regs[r0.index()] - f0).abs().max_element() < 1e-7);
                    assert_eq!(regs[f90.index()], Vec3::ONE);
                    assert!((regs[alpha_x.index()].x - 0.04).abs() < 1e-6);
                    assert_eq!(alpha_x, alpha_y);
                    seen += 1;
                }
                k => panic!("unexpected lobe {k:?}"),
            }
        }
        assert_eq!(seen, 2);
    }
}

/// After real resolution the `set`-written flags of the chain example gate the mixers: the
/// lacquer layer's clearcoat reaches the surface only because `finished.layer1_enableClearcoat`
/// was set to 1; setting `enableClearcoat 0` on the lacquer prunes the coat lobe.
#[test]
fn set_written_enable_flags_prune_lobes_after_resolution() {
    let path = common::repo_dir().join("examples/chain.rib");
    let text = std::fs::read_to_string(path).unwrap();
    // Give the lacquer a gain so that its coat is visible (PxrLayer's gains default to 0).
    let on = text.replace(
        "\"int enableClearcoat\" [1]",
        "\"int enableClearcoat\" [1]\n\t\t\t\"float clearcoatGain\" [1]",
    );
    let off = text.replace(
        "\"int enableClearcoat\" [1]",
        "\"int enableClearcoat\" [0]\n\t\t\t\"float clearcoatGain\" [1]",
    );
    let reg = Registry::embedded();
    let count = |src: &str| {
        let net = load(src.as_bytes(), "chain.rib", &reg);
        let (name, node) = terminals(&net, None).unwrap()[0].clone();
        let mut d = Diagnostics::new();
        let ir = lower_terminal(&net, &reg, node, &name, &mut d).unwrap();
        ir.leaves().filter(|(_, l)| l.label == "clearcoat").count()
    };
    assert_eq!(count(&on), 1);
    assert_eq!(count(&off), 0);
}

fn vstructc(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_vstructc"))
        .args(args)
        .current_dir(common::repo_dir())
        .output()
        .expect("runs")
}

#[test]
fn compile_command_emits_ir_lobes_and_dot() {
    let ir = vstructc(&["compile", "examples/layered.rib"]);
    assert!(
        ir.status.success(),
        "{}",
        String::from_utf8_lossy(&ir.stderr)
    );
    let out = String::from_utf8(ir.stdout).unwrap();
    assert!(
        out.starts_with("material layeredMaterial (recipe pxr_surface)"),
        "{out}"
    );
    let lobes = vstructc(&["compile", "--emit", "lobes", "examples/layered.rib"]);
    assert!(String::from_utf8(lobes.stdout).unwrap().contains("lobe #"));
    let dot = vstructc(&["compile", "--emit", "dot", "examples/layered.rib"]);
    let dot = String::from_utf8(dot.stdout).unwrap();
    assert!(
        dot.starts_with("digraph \"layeredMaterial\" {") && dot.trim_end().ends_with('}'),
        "{dot}"
    );
    let missing = vstructc(&["compile", "--material", "nope", "examples/layered.rib"]);
    assert_eq!(missing.status.code(), Some(2));
    let absent = vstructc(&["compile", "examples/does-not-exist.rib"]);
    assert_eq!(absent.status.code(), Some(1));
}

/// §4.0: constants outside the documented range (`min` / `max` of the definition) are clamped
/// with LW022; the clamped value is what the lobes use.
#[test]
fn out_of_range_constants_are_clamped_with_lw022() {
    let out = vstructc(&[
        "compile",
        "--emit",
        "lobes",
        "tests/data/lower/out_of_range.rib",
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let stderr = String::from_utf8(out.stderr).unwrap();
    assert!(
        stderr.contains("info[LW022]: `layer.diffuseGain` = 2 is outside its documented range [0, 1]; clamped to 1"),
        "{stderr}"
    );
    assert!(
        stderr.contains("`layer.specularRoughness` = -0.5"),
        "{stderr}"
    );
    let stdout = String::from_utf8(out.stdout).unwrap();
    // The diffuse lobe's weight is the clamped gain 1, not 2.
    assert!(
        stdout.contains("lobe #0 lambert \"diffuse\"\n  weight = 1\n"),
        "{stdout}"
    );
    // In-range values give no LW022.
    let plain = vstructc(&["compile", "examples/override.rib"]);
    assert!(!String::from_utf8_lossy(&plain.stderr).contains("LW022"));
}

/// LW020 is about what the network says: a parameter left at its default is the recipe's
/// documented choice (docs/materials.md), not a finding; a value the network sets is
/// reported once per material, node and parameter.
#[test]
fn lw020_only_for_values_the_network_sets() {
    use vstructc::front::NetFormat;
    use vstructc::pipeline::{Lowering, PipelineOptions, run};
    let reg = Registry::embedded();
    let lw020 = |rib: &str| {
        let mut diags = Diagnostics::new();
        let options = PipelineOptions {
            lowering: Lowering::All,
            ..Default::default()
        };
        let out = run(
            "m.rib",
            rib.as_bytes(),
            NetFormat::Rib,
            &reg,
            &options,
            &mut diags,
        );
        assert_eq!(out.unwrap().materials.len(), 2);
        diags
            .with_code("LW020")
            .map(|d| {
                let node = d.node.clone().unwrap_or_default();
                (node, d.param.clone().unwrap_or_default())
            })
            .collect::<Vec<_>>()
    };
    let unset = r#"Bxdf "PxrSurface" "a" "color specularFaceColor" [0.5 0.5 0.5]
Bxdf "PxrSurface" "b" "color specularFaceColor" [0.5 0.5 0.5]
"#;
    assert_eq!(lw020(unset), []);
    let set = unset.replace("0.5]", "0.5] \"int specularModelType\" [0]");
    let pairs = |n: &str| (n.to_string(), "specularModelType".to_string());
    assert_eq!(lw020(&set), [pairs("a"), pairs("b")]);
}

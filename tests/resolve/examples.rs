//! The bundled examples resolve with the embedded definitions and no flags; their resolved
//! connections are snapshots. Also the `resolve` and `explain` commands end to end.

use crate::common;

use std::process::Command;
use vstructc::front::rib::{RibOptions, parse_rib};
use vstructc::registry::Registry;
use vstructc::resolve::{ResolveOptions, resolve};
use vstructc::{Diagnostics, Severity};

fn resolve_example(name: &str) -> String {
    let path = common::repo_dir().join("examples").join(name);
    let bytes = std::fs::read(&path).expect("example exists");
    let reg = Registry::embedded();
    let mut diags = Diagnostics::new();
    let mut net =
        parse_rib(&bytes, name, &reg, &RibOptions::default(), &mut diags).expect("example parses");
    let res = resolve(&mut net, &reg, &ResolveOptions::default());
    diags.extend(res.diagnostics);
    assert!(
        !diags.iter().any(|d| d.severity >= Severity::Warning),
        "{name}: {diags:#?}"
    );
    let notes: Vec<String> = diags
        .iter()
        .map(|d| format!("{}[{}]: {}", d.severity, d.code, d.message))
        .collect();
    format!("{}--\n{}\n", common::dump_network(&net), notes.join("\n"))
}

#[test]
fn example_layered() {
    insta::assert_snapshot!(resolve_example("layered.rib"));
}

#[test]
fn example_override() {
    insta::assert_snapshot!(resolve_example("override.rib"));
}

#[test]
fn example_chain() {
    insta::assert_snapshot!(resolve_example("chain.rib"));
}

fn vstructc() -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_vstructc"));
    c.current_dir(common::repo_dir())
        .env_remove("VSTRUCTC_ARGS_PATH");
    c
}

#[test]
fn cli_resolve_example_succeeds_and_rereads() {
    let out = vstructc()
        .args(["resolve", "examples/layered.rib"])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(0));
    let text = String::from_utf8(out.stdout).unwrap();
    assert!(
        text.contains(r#""reference color diffuseColor" ["mixer:pxrMaterialOut_diffuseColor"]"#)
    );
    assert!(!text.contains("inputMaterial"));
    // Resolving the output again changes nothing.
    let dir = std::env::temp_dir().join(format!("vstructc-resolve-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let once = dir.join("once.rib");
    std::fs::write(&once, &text).unwrap();
    let twice = vstructc()
        .args(["resolve", once.to_str().unwrap()])
        .output()
        .unwrap();
    assert_eq!(String::from_utf8(twice.stdout).unwrap(), text);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn cli_resolve_json_output_and_stdin() {
    let rib = std::fs::read(common::repo_dir().join("examples/override.rib")).unwrap();
    let mut child = vstructc()
        .args(["resolve", "--format", "json", "-"])
        .stdin(std::process::Stdio::piped())
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    use std::io::Write;
    child.stdin.take().unwrap().write_all(&rib).unwrap();
    let out = child.wait_with_output().unwrap();
    assert_eq!(out.status.code(), Some(0));
    let json: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(json["vstructcNetwork"], 1);
    // The VS019 info names the location in <stdin>.
    let err = String::from_utf8(out.stderr).unwrap();
    assert!(
        err.contains("info[VS019]") && err.contains("<stdin>:"),
        "{err}"
    );
}

#[test]
fn cli_output_file_is_written_atomically_and_not_on_failure() {
    let dir = std::env::temp_dir().join(format!("vstructc-out-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let out_path = dir.join("out.rib");
    let ok = vstructc()
        .args([
            "resolve",
            "examples/chain.rib",
            "-o",
            out_path.to_str().unwrap(),
        ])
        .output()
        .unwrap();
    assert_eq!(ok.status.code(), Some(0));
    assert!(std::fs::read_to_string(&out_path).unwrap().contains("Bxdf"));

    // A broken input: exit 1, the previous output untouched, no temporary left behind.
    let bad = dir.join("bad.rib");
    std::fs::write(
        &bad,
        "Pattern \"PxrLayer\" \"x\" \"float diffuseGain\" [1\n\"unterminated",
    )
    .unwrap();
    let before = std::fs::read(&out_path).unwrap();
    let fail = vstructc()
        .args([
            "resolve",
            bad.to_str().unwrap(),
            "-o",
            out_path.to_str().unwrap(),
        ])
        .output()
        .unwrap();
    assert_eq!(fail.status.code(), Some(1));
    assert_eq!(std::fs::read(&out_path).unwrap(), before);
    let leftovers: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .filter_map(|e| e.ok())
        .filter(|e| e.file_name().to_string_lossy().ends_with(".tmp"))
        .collect();
    assert!(leftovers.is_empty());

    // Reading from and writing to the same path is safe.
    let same = dir.join("same.rib");
    std::fs::copy(common::repo_dir().join("examples/layered.rib"), &same).unwrap();
    let st = vstructc()
        .args([
            "resolve",
            same.to_str().unwrap(),
            "-o",
            same.to_str().unwrap(),
        ])
        .output()
        .unwrap();
    assert_eq!(st.status.code(), Some(0));
    assert!(
        std::fs::read_to_string(&same)
            .unwrap()
            .contains("pxrMaterialOut_diffuseColor")
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn cli_exit_codes() {
    let usage = vstructc().args(["resolve"]).output().unwrap();
    assert_eq!(usage.status.code(), Some(2));
    let bad_ext = vstructc()
        .args(["resolve", "--ext", "no-such-thing", "examples/layered.rib"])
        .output()
        .unwrap();
    assert_eq!(bad_ext.status.code(), Some(2));
    let missing = vstructc()
        .args(["resolve", "examples/does-not-exist.rib"])
        .output()
        .unwrap();
    assert_eq!(missing.status.code(), Some(1));
    // A warning fails only under --deny-warnings.
    let dir = std::env::temp_dir().join(format!("vstructc-deny-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let warn = dir.join("warn.rib");
    std::fs::write(
        &warn,
        "Bxdf \"PxrSurface\" \"s\" \"reference float inputMaterial\" [\"ghost:pxrMaterialOut\"]\n",
    )
    .unwrap();
    let lenient = vstructc()
        .args(["resolve", warn.to_str().unwrap()])
        .output()
        .unwrap();
    assert_eq!(lenient.status.code(), Some(0));
    assert!(String::from_utf8_lossy(&lenient.stderr).contains("warning[VS010]"));
    let strict = vstructc()
        .args(["resolve", "--deny-warnings", warn.to_str().unwrap()])
        .output()
        .unwrap();
    assert_eq!(strict.status.code(), Some(1));
    assert!(strict.stdout.is_empty());
    // The unresolved placeholder is written unchanged, unless --drop-unresolved.
    assert!(String::from_utf8_lossy(&lenient.stdout).contains("ghost:pxrMaterialOut"));
    let dropped = vstructc()
        .args(["resolve", "--drop-unresolved", warn.to_str().unwrap()])
        .output()
        .unwrap();
    assert_eq!(dropped.status.code(), Some(0));
    assert!(!String::from_utf8_lossy(&dropped.stdout).contains("inputMaterial"));
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn cli_explain_tells_the_story() {
    let out = vstructc()
        .args([
            "explain",
            "surface.clearcoatFaceColor",
            "examples/layered.rib",
        ])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(0));
    insta::assert_snapshot!(String::from_utf8(out.stdout).unwrap());
    let set = vstructc()
        .args([
            "explain",
            "mixer.layer1_enableClearcoat",
            "examples/layered.rib",
        ])
        .output()
        .unwrap();
    insta::assert_snapshot!(String::from_utf8(set.stdout).unwrap());
}

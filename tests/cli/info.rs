//! `vstructc info`: human summary (insta snapshot over the Pixar fixture), `--json`, exit codes.

use std::process::{Command, Output};

fn vstructc(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_vstructc"))
        .args(args)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .env_remove("VSTRUCTC_ARGS_PATH")
        .output()
        .unwrap()
}

/// The Pixar definitions of the fixtures folder, as an argument.
fn pixar(fixtures: &std::path::Path) -> String {
    fixtures.join("args/pixar").display().to_string()
}

#[test]
fn info_pxr_layer_mixer_human() {
    let dir = fixtures_or_skip!();
    let out = vstructc(&["info", "PxrLayerMixer", "--args", &pixar(&dir)]);
    assert_eq!(
        out.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    // The snapshot names the fixtures folder as it sits beside the repository.
    let stdout = String::from_utf8(out.stdout)
        .unwrap()
        .replace(&dir.display().to_string(), "../shared/fixtures");
    insta::assert_snapshot!(stdout);
}

#[test]
fn info_pxr_layer_mixer_json() {
    let dir = fixtures_or_skip!();
    let out = vstructc(&["info", "PxrLayerMixer", "--args", &pixar(&dir), "--json"]);
    assert_eq!(out.status.code(), Some(0));
    let doc: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let def = &doc["definition"];
    assert_eq!(def["id"], "PxrLayerMixer");
    assert_eq!(def["kind"], "pattern");
    assert_eq!(def["inputs"].as_array().unwrap().len(), 409);
    let heads = doc["vstruct"]["inputHeads"].as_array().unwrap();
    let names: Vec<&str> = heads.iter().map(|h| h["name"].as_str().unwrap()).collect();
    assert_eq!(names, ["baselayer", "layer1", "layer2", "layer3", "layer4"]);
    assert!(
        heads
            .iter()
            .all(|h| h["members"].as_array().unwrap().len() == 79)
    );
    let outs = doc["vstruct"]["outputHeads"].as_array().unwrap();
    assert_eq!(outs.len(), 1);
    let members = outs[0]["members"].as_array().unwrap();
    assert_eq!(members.len(), 79);
    assert!(members.iter().all(|m| m["cond"]["text"].is_string()));
    let dc = members
        .iter()
        .find(|m| m["property"] == "pxrMaterialOut_diffuseColor")
        .unwrap();
    assert_eq!(dc["names"][0], "diffuseColor");
    assert!(dc["cond"]["location"]["line"].as_u64().unwrap() > 0);
}

#[test]
fn info_unknown_shader_is_a_usage_error() {
    let dir = fixtures_or_skip!();
    let out = vstructc(&["info", "NoSuchShader", "--args", &pixar(&dir)]);
    assert_eq!(out.status.code(), Some(2));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.contains("unknown shader `NoSuchShader`"), "{stderr}");
    assert!(
        stderr.contains("PxrLayerMixer"),
        "lists the known ids: {stderr}"
    );
}

#[test]
fn info_missing_args_path_is_an_input_error() {
    let out = vstructc(&["info", "X", "--args", "tests/data/args/no-such-folder"]);
    assert_eq!(out.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&out.stderr).contains("error[AR005]"));
}

#[test]
fn info_shows_pages_heads_and_normalised_types() {
    let out = vstructc(&[
        "info",
        "aliases",
        "--args",
        "tests/data/args/tables/aliases.args",
    ]);
    assert_eq!(out.status.code(), Some(0));
    let s = String::from_utf8(out.stdout).unwrap();
    assert!(s.starts_with("aliases: bxdf\n"), "{s}");
    assert!(s.contains("in      vstruct"), "{s}");
    assert!(s.contains("head (3 members), declared float"), "{s}");
    assert!(s.contains("member in.a alias \"alpha\""), "{s}");
    assert!(s.contains("input   in   3 members"), "{s}");
    assert!(s.contains("output  out  2 members, 0 conditional"), "{s}");
}

/// A reader that stops early (`vstructc info PxrLayerMixer | head -1`) ends the program as it
/// ends `cat`, by SIGPIPE, never with a panic (exit 101 and "failed printing to stdout").
#[cfg(unix)]
#[test]
fn a_closed_output_pipe_ends_the_program_quietly() {
    use std::os::unix::process::ExitStatusExt;
    use std::process::Stdio;
    let child = Command::new(env!("CARGO_BIN_EXE_vstructc"))
        .args(["info", "PxrLayerMixer"])
        .env_remove("VSTRUCTC_ARGS_PATH")
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    // Close the read end before the program writes: its first write meets a closed pipe.
    let mut child = child;
    drop(child.stdout.take());
    let out = child.wait_with_output().unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!stderr.contains("panicked"), "{stderr}");
    assert_eq!(out.status.signal(), Some(libc::SIGPIPE), "{:?}", out.status);
}

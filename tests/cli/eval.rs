//! `vstructc eval`: per-lobe weights and values and the total, as a text
//! table (snapshot, reviewed by hand) and as JSON (checked against the library).

use std::path::PathBuf;
use std::process::Command;

const BIN: &str = env!("CARGO_BIN_EXE_vstructc");

fn repo() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn eval(args: &[&str]) -> (Option<i32>, String, String) {
    let o = Command::new(BIN).arg("eval").args(args).output().unwrap();
    (
        o.status.code(),
        String::from_utf8_lossy(&o.stdout).into_owned(),
        String::from_utf8_lossy(&o.stderr).into_owned(),
    )
}

#[test]
fn eval_text_table_of_the_white_material() {
    let input = repo().join("tests/data/render/two.rib");
    let (code, out, err) = eval(&[
        input.to_str().unwrap(),
        "--wo",
        "0,0,1",
        "--wi",
        "0,0.6,0.8",
    ]);
    assert_eq!(code, Some(0), "{err}");
    insta::assert_snapshot!("eval_two_materials", out);
}

#[test]
fn eval_json_matches_the_formulas() {
    let input = repo().join("tests/data/render/two.rib");
    let (code, out, err) = eval(&[
        input.to_str().unwrap(),
        "--wo",
        "0,0,2",
        "--wi",
        "0,0.6,0.8",
        "--json",
        "--material",
        "white",
    ]);
    assert_eq!(code, Some(0), "{err}");
    let doc: serde_json::Value = serde_json::from_str(&out).unwrap();
    let mats = doc["materials"].as_array().unwrap();
    assert_eq!(mats.len(), 1);
    let m = &mats[0];
    assert_eq!(m["name"], "white");
    // wo is normalised.
    assert_eq!(m["wo"], serde_json::json!([0.0, 0.0, 1.0]));
    let lobes = m["lobes"].as_array().unwrap();
    assert_eq!(lobes.len(), 1);
    assert_eq!(lobes[0]["kind"], "lambert");
    // White Lambert: f·μ_i = μ_i/π = 0.8/π, pdf = μ_i/π, probability 1.
    let expect = 0.8 / std::f64::consts::PI;
    let f = lobes[0]["f_cos"][1].as_f64().unwrap();
    assert!((f - expect).abs() < 1e-6, "{f}");
    assert!((m["total"]["pdf"].as_f64().unwrap() - expect).abs() < 1e-6);
    assert_eq!(lobes[0]["prob"].as_f64(), Some(1.0));
    assert_eq!(m["albedo"]["reflect"], serde_json::json!([1.0, 1.0, 1.0]));
}

#[test]
fn eval_usage_errors() {
    let input = repo().join("tests/data/render/white.rib");
    let i = input.to_str().unwrap();
    for bad in [
        vec![i, "--wo", "0,0", "--wi", "0,0,1"],
        vec![i, "--wo", "0,0,0", "--wi", "0,0,1"],
        vec![i, "--wo", "0,0,1", "--wi", "a,b,c"],
        vec![i, "--wo", "0,0,1", "--wi", "0,0,1", "--uv", "1"],
        vec![i, "--wo", "0,0,1"],
    ] {
        let (code, _, err) = eval(&bad);
        assert_eq!(code, Some(2), "{bad:?}: {err}");
    }
    // Negative components are accepted.
    let (code, out, err) = eval(&[
        i,
        "--wo",
        "-0.5,0,0.8660254",
        "--wi",
        "-0.6644630,0.2418448,0.7071068",
    ]);
    assert_eq!(code, Some(0), "{err}");
    // Lambert config A of closures.md §5.1: f·μ_i = 0.225079.
    assert!(out.contains("0.225079"), "{out}");
}

/// `--uv` reaches the pattern program and `--input` the external slots: in
/// tests/data/render/textured.rib a vsChecker over uv (frequency 2) gives the specular a
/// black or a white F0, and the diffuse colour is an external slot (fallback 0.18).
#[test]
fn uv_and_external_inputs_reach_the_program() {
    let input = repo().join("tests/data/render/textured.rib");
    let i = input.to_str().unwrap();
    let material = |extra: &[&str]| {
        let mut args = vec![i, "--wo", "0,0,1", "--wi", "0,0.6,0.8", "--json"];
        args.extend_from_slice(extra);
        let (code, out, err) = eval(&args);
        assert_eq!(code, Some(0), "{err}");
        let doc: serde_json::Value = serde_json::from_str(&out).unwrap();
        doc["materials"][0].clone()
    };
    let reflect = |m: &serde_json::Value| m["albedo"]["reflect"][0].as_f64().unwrap();
    // Checker cell (0, 0): colorA, so only the diffuse fallback reflects.
    let black = material(&["--uv", "0.25,0.25"]);
    assert!((reflect(&black) - 0.18).abs() < 1e-3, "{black}");
    // Cell (1, 0): colorB, a white F0 over the diffuse.
    let white = material(&["--uv", "0.75,0.25"]);
    assert!(reflect(&white) > 0.9, "{white}");
    // A red diffuse from the slot: the Lambert's f·cosθ is (cosθ/π, 0, 0).
    let red = material(&["--uv", "0.25,0.25", "--input", "tex.resultRGB=1,0,0"]);
    let lambert = red["lobes"]
        .as_array()
        .unwrap()
        .iter()
        .find(|l| l["kind"] == "lambert")
        .expect("a Lambert lobe")
        .clone();
    let f: Vec<f64> = lambert["f_cos"]
        .as_array()
        .unwrap()
        .iter()
        .map(|c| c.as_f64().unwrap())
        .collect();
    let want = 0.8 / std::f64::consts::PI;
    assert!(
        (f[0] - want).abs() < 1e-6 && f[1] == 0.0 && f[2] == 0.0,
        "{f:?}"
    );
}

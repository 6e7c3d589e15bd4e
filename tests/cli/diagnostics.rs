//! Diagnostics a user reads: typos named with the declared name, unknown shaders with the
//! known one, and no flood for what the user asked for or did not set.

use std::process::{Command, Output};

fn vstructc(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_vstructc"))
        .args(args)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .env_remove("VSTRUCTC_ARGS_PATH")
        .output()
        .unwrap()
}

fn stderr(out: &Output) -> String {
    String::from_utf8_lossy(&out.stderr).into_owned()
}

#[test]
fn no_conditions_on_the_layered_example_is_reported_in_one_diagnostic() {
    let out = vstructc(&[
        "resolve",
        "--no-conditions",
        "examples/layered.rib",
        "-o",
        "/dev/null",
    ]);
    assert_eq!(out.status.code(), Some(0));
    let err = stderr(&out);
    // One diagnostic about the whole run: no location, so no snippet.
    assert!(err.lines().count() <= 3, "{err}");
    assert_eq!(err.matches("info[").count(), 1, "{err}");
    assert!(
        err.contains("info[VS022]: --no-conditions: 227 members"),
        "{err}"
    );
}

#[test]
fn compiling_the_bench_scene_prints_at_most_20_lines() {
    let dir = tempfile::tempdir().unwrap();
    let scene = dir.path().join("scene.rib");
    std::fs::write(&scene, vstructc_testkit::testgen::layered_scene(10_000)).unwrap();
    let out = vstructc(&["compile", "--emit", "lobes", scene.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    let err = stderr(&out);
    assert!(err.lines().count() <= 20, "{err}");
}

#[test]
fn a_typo_is_a_warning_that_names_the_parameter_meant() {
    let dir = tempfile::tempdir().unwrap();
    let rib = dir.path().join("typo.rib");
    std::fs::write(
        &rib,
        "Bxdf \"PxrSurface\" \"ball\" \"color diffuseColour\" [0.8 0.2 0.2]\n",
    )
    .unwrap();
    let out = vstructc(&["compile", rib.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(0));
    let err = stderr(&out);
    assert!(
        err.starts_with(
            "warning[VS024]: ball sets `diffuseColour`, which `PxrSurface` does not declare \
             as an input; did you mean `diffuseColor`?"
        ),
        "{err}"
    );
    let denied = vstructc(&["--deny-warnings", "compile", rib.to_str().unwrap()]);
    assert_eq!(denied.status.code(), Some(1));
}

#[test]
fn unknown_shader_and_material_names_get_suggestions() {
    let out = vstructc(&["info", "pxrlayer"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(
        stderr(&out).starts_with("error: unknown shader `pxrlayer`; did you mean `PxrLayer`?"),
        "{}",
        stderr(&out)
    );
    let out = vstructc(&[
        "compile",
        "--material",
        "layeredMaterail",
        "examples/layered.rib",
    ]);
    assert_eq!(out.status.code(), Some(2));
    assert!(
        stderr(&out).contains(
            "error: no material or terminal named `layeredMaterail`; did you mean \
             `layeredMaterial`?"
        ),
        "{}",
        stderr(&out)
    );
}

/// A scratch folder holding `files`.
fn files(files: &[(&str, &[u8])]) -> tempfile::TempDir {
    let dir = tempfile::tempdir().unwrap();
    for (name, bytes) in files {
        std::fs::write(dir.path().join(name), bytes).unwrap();
    }
    dir
}

#[test]
fn usd_inputs_are_read_and_materialx_is_named_not_misread() {
    let dir = files(&[
        ("look.usda", b"#usda 1.0\n(\n)\ndef Material \"red\" {}\n"),
        ("look.usdc", b"PXR-USDC\0\0\0\0"),
        (
            "red.mtlx",
            b"<?xml version=\"1.0\"?>\n<materialx version=\"1.38\"/>\n",
        ),
        (
            "red.xml",
            b"<?xml version=\"1.0\"?>\n<materialx version=\"1.38\"/>\n",
        ),
    ]);
    // A USD text layer is read (by extension and, from standard input, by its signature).
    let out = Command::new(env!("CARGO_BIN_EXE_vstructc"))
        .args(["resolve", "look.usda"])
        .current_dir(dir.path())
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    let text = String::from_utf8(out.stdout).unwrap();
    assert!(text.starts_with("#usda 1.0"), "{text}");
    assert!(text.contains("def Material \"red\""), "{text}");
    let mut shown = Vec::new();
    for name in ["look.usdc", "red.mtlx", "red.xml"] {
        let path = dir.path().join(name);
        for format in ["human", "json"] {
            let out = Command::new(env!("CARGO_BIN_EXE_vstructc"))
                .args(["--diag-format", format, "resolve", name])
                .current_dir(dir.path())
                .output()
                .unwrap();
            assert_eq!(out.status.code(), Some(1), "{name}: {}", stderr(&out));
            let err = stderr(&out);
            assert!(!err.contains("RB004"), "{err}");
            shown.push(err);
        }
        assert!(path.exists());
    }
    let text = shown.concat();
    assert_eq!(text.matches("US001").count(), 2, "{text}");
    assert_eq!(
        text.matches("MaterialX input is not supported").count(),
        4,
        "{text}"
    );
    insta::assert_snapshot!(text);
}

#[test]
fn the_output_extension_picks_the_output_format() {
    let dir = tempfile::tempdir().unwrap();
    // `vstructc resolve INPUT -o OUTPUT`, which must succeed.
    let resolve_to = |input: &str, output: &std::path::Path| {
        let out = vstructc(&["resolve", input, "-o", output.to_str().unwrap()]);
        assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    };
    let json = dir.path().join("out.json");
    resolve_to("examples/chain.rib", &json);
    let text = std::fs::read_to_string(&json).unwrap();
    serde_json::from_str::<serde_json::Value>(&text).expect("JSON was written");
    let rib = dir.path().join("back.rib");
    resolve_to(json.to_str().unwrap(), &rib);
    assert!(
        std::fs::read_to_string(&rib)
            .unwrap()
            .contains("Bxdf \"PxrLayerSurface\"")
    );
    // A contradiction, or a format that cannot be written, is a usage error before any work.
    let conflict = dir.path().join("conflict.json");
    let out = vstructc(&[
        "resolve",
        "--format",
        "rib",
        "examples/chain.rib",
        "-o",
        conflict.to_str().unwrap(),
    ]);
    assert_eq!(out.status.code(), Some(2));
    assert!(
        stderr(&out).contains("--format rib conflicts"),
        "{}",
        stderr(&out)
    );
    assert!(!conflict.exists());
    // Binary USD output when the extension asks for it: a crate file, a package holding
    // one; both read back as the text output does.
    let text = dir.path().join("out.usda");
    resolve_to("examples/chain.rib", &text);
    let json = |path: &std::path::Path| {
        let out = vstructc(&["resolve", path.to_str().unwrap(), "--format", "json"]);
        assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
        out.stdout
    };
    for (ext, signature) in [("usdc", &b"PXR-USDC"[..]), ("usdz", &b"PK\x03\x04"[..])] {
        let bin = dir.path().join(format!("out.{ext}"));
        resolve_to("examples/chain.rib", &bin);
        assert!(std::fs::read(&bin).unwrap().starts_with(signature), "{ext}");
        assert_eq!(json(&bin), json(&text), "{ext}");
    }
    let conflict = dir.path().join("out2.usda");
    let out = vstructc(&[
        "resolve",
        "examples/chain.rib",
        "--format",
        "json",
        "-o",
        conflict.to_str().unwrap(),
    ]);
    assert_eq!(out.status.code(), Some(2));
    assert!(
        stderr(&out).contains("conflicts with the output file's extension `.usda`"),
        "{}",
        stderr(&out)
    );
    assert!(!conflict.exists());
    let usda = dir.path().join("out.usda");
    resolve_to("examples/chain.rib", &usda);
    assert!(
        std::fs::read_to_string(&usda)
            .unwrap()
            .contains("def Material \"car\""),
        "a USD layer was written"
    );
    let jpg = dir.path().join("ball.jpg");
    let out = vstructc(&["render", "examples/chain.rib", "-o", jpg.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(2));
    assert!(
        stderr(&out).contains("`.jpg` output is not supported"),
        "{}",
        stderr(&out)
    );
    assert!(!jpg.exists());
}

/// `--usd-mode over` writes an override layer that sublayers the input by a path relative to
/// the output's folder and reads as the flattened output does, as `.usda` or `.usdc`; with
/// a non-USD input, a non-USD or `.usdz` output or standard input it is a usage error that
/// writes nothing.
#[test]
fn usd_mode_over_sublayers_the_input_and_refuses_what_it_cannot_write() {
    let dir = tempfile::tempdir().unwrap();
    let (input, output) = (dir.path().join("in"), dir.path().join("out"));
    std::fs::create_dir_all(&input).unwrap();
    std::fs::create_dir_all(&output).unwrap();
    let look = input.join("look.usda");
    std::fs::copy("tests/data/usd/nodegraph.usda", &look).unwrap();
    let (look, over, flat) = (
        look.to_str().unwrap(),
        output.join("over.usda"),
        output.join("flat.usda"),
    );
    let write_over = |path: &std::path::Path| {
        let out = vstructc(&[
            "resolve",
            look,
            "--usd-mode",
            "over",
            "-o",
            path.to_str().unwrap(),
        ]);
        assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    };
    write_over(&over);
    let text = std::fs::read_to_string(&over).unwrap();
    assert!(
        text.contains("subLayers = [\n        @../in/look.usda@\n    ]"),
        "{text}"
    );
    let out = vstructc(&["resolve", look, "-o", flat.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    let json = |path: &std::path::Path| {
        let out = vstructc(&["resolve", path.to_str().unwrap(), "--format", "json"]);
        assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
        out.stdout
    };
    assert_eq!(json(&over), json(&flat));
    // The override layer in the binary form too.
    let over_c = output.join("over.usdc");
    write_over(&over_c);
    assert!(std::fs::read(&over_c).unwrap().starts_with(b"PXR-USDC"));
    assert_eq!(json(&over_c), json(&flat));
    // On standard output the path is relative to the current folder.
    let out = vstructc(&[
        "resolve",
        "tests/data/usd/override.usda",
        "--usd-mode",
        "over",
    ]);
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    let text = String::from_utf8(out.stdout).unwrap();
    assert!(text.contains("@tests/data/usd/override.usda@"), "{text}");
    // Errors: exit 2, a message naming the problem, no output file.
    let target = output.join("refused");
    for (args, message) in [
        (
            vec!["examples/layered.rib", "-o", "refused.usda"],
            "--usd-mode over needs a USD input",
        ),
        (
            vec![look, "--format", "json", "-o", "refused.json"],
            "the json output asked for is not usda",
        ),
        (
            vec![look, "-o", "refused.rib"],
            "the rib output asked for is not usda",
        ),
        (
            vec![look, "--json", "-o", "refused.json"],
            "--json is not usda",
        ),
        (
            vec!["-", "-o", "refused.usda"],
            "standard input cannot be sublayered",
        ),
        (
            vec![look, "-o", "refused.usdz"],
            "a `.usdz` package would look for the input inside itself",
        ),
    ] {
        let file = args.last().unwrap().to_string();
        let path = target.with_file_name(&file);
        let path = path.to_str().unwrap();
        let mut full = vec!["resolve", "--usd-mode", "over"];
        full.extend(args[..args.len() - 1].iter().copied());
        full.push(path);
        let out = vstructc(&full);
        assert_eq!(out.status.code(), Some(2), "{full:?}: {}", stderr(&out));
        assert!(stderr(&out).contains(message), "{full:?}: {}", stderr(&out));
        assert!(!std::path::Path::new(path).exists(), "{full:?}");
    }
}

/// A pattern whose vstruct output `set`s a number into the colour member `fuzzColor`: every
/// `PxrLayerSurface` reading it gets VS013 (a NUMBER is not written to a color input).
const FUZZ_LAYER: &str = r#"<args format="1.0">
  <shaderType><tag value="pattern"/></shaderType>
  <output name="pxrMaterialOut"><tags><tag value="vstruct"/></tags></output>
  <output name="pxrMaterialOut_fuzzColor" vstructmember="pxrMaterialOut.fuzzColor"
          vstructConditionalExpr="set 0.5"><tags><tag value="color"/></tags></output>
</args>
"#;

/// `materials` materials, each a `FuzzLayer` read by a `PxrLayerSurface`.
fn fuzz_scene(materials: usize) -> String {
    use std::fmt::Write as _;
    let mut rib = String::from("##RenderMan RIB\nversion 3.04\nWorldBegin\n");
    for m in 0..materials {
        let _ = write!(
            rib,
            "AttributeBegin\n\tPattern \"FuzzLayer\" \"m{m}_fuzz\"\n\
             \tBxdf \"PxrLayerSurface\" \"m{m}_surface\"\n\
             \t\t\"reference float inputMaterial\" [\"m{m}_fuzz:pxrMaterialOut\"]\n\
             \t\t\"string __materialid\" [\"m{m}_SG\"]\nAttributeEnd\n"
        );
    }
    rib.push_str("WorldEnd\n");
    rib
}

#[test]
fn the_same_warning_on_2000_materials_is_one_diagnostic_naming_the_count() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("FuzzLayer.args"), FUZZ_LAYER).unwrap();
    let scene = dir.path().join("scene.rib");
    std::fs::write(&scene, fuzz_scene(2000)).unwrap();
    let (args, scene) = (dir.path().to_str().unwrap(), scene.to_str().unwrap());
    let out = vstructc(&["--args", args, "compile", scene]);
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    let err = stderr(&out);
    assert!(err.lines().count() <= 20, "{err}");
    assert_eq!(err.matches("warning[VS013]").count(), 1, "{err}");
    assert!(
        err.contains(
            "warning[VS013]: <node>.fuzzColor: `set 0.5`: `set` not applied: a NUMBER cannot \
             be written to a color input (see --ext set-tuples) on 2,000 nodes (m0_surface, \
             m1_surface, m2_surface, …)\n"
        ),
        "{err}"
    );
    // One snippet: the first node's.
    assert_eq!(err.matches(" --> ").count(), 1, "{err}");
    assert!(
        err.contains("Bxdf \"PxrLayerSurface\" \"m0_surface\""),
        "{err}"
    );
    assert!(!err.contains("more VS013"), "{err}");

    // JSON keeps one entry per node.
    let json = vstructc(&["--args", args, "--diag-format", "json", "compile", scene]);
    let mut nodes: Vec<String> = stderr(&json)
        .lines()
        .filter(|l| l.contains("\"VS013\""))
        .map(|l| {
            let v: serde_json::Value = serde_json::from_str(l).unwrap();
            v["node"].as_str().unwrap().to_string()
        })
        .collect();
    assert_eq!(nodes.len(), 2000);
    nodes.sort();
    nodes.dedup();
    assert_eq!(nodes.len(), 2000);
}

#[test]
fn the_same_warning_on_two_materials_names_both() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("FuzzLayer.args"), FUZZ_LAYER).unwrap();
    let scene = dir.path().join("scene.rib");
    std::fs::write(&scene, fuzz_scene(2)).unwrap();
    let (args, scene) = (dir.path().to_str().unwrap(), scene.to_str().unwrap());
    let err = stderr(&vstructc(&["--args", args, "compile", scene]));
    assert!(
        err.contains("on 2 nodes (m0_surface, m1_surface)\n"),
        "{err}"
    );
    // One material: its own message, unchanged.
    std::fs::write(dir.path().join("one.rib"), fuzz_scene(1)).unwrap();
    let one = dir.path().join("one.rib");
    let err = stderr(&vstructc(&[
        "--args",
        args,
        "compile",
        one.to_str().unwrap(),
    ]));
    assert!(
        err.starts_with("warning[VS013]: m0_surface.fuzzColor: `set 0.5`"),
        "{err}"
    );
    assert!(!err.contains("<node>"), "{err}");
}

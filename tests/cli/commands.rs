//! The commands agree with each other: `--json` on every command that prints data (plain
//! documented fields, no serde enum shapes), `list`, every flag checked before the input is
//! read, the same exit status rules (0 success, 1 input errors or nothing to act on, 2 usage
//! errors), `explain` telling where a value comes from, `--ext` values in `--help`.

use serde_json::Value as Json;
use std::process::{Command, Output};

fn vstructc(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_vstructc"))
        .args(args)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .env_remove("VSTRUCTC_ARGS_PATH")
        .output()
        .unwrap()
}

fn stdout(out: &Output) -> String {
    String::from_utf8_lossy(&out.stdout).into_owned()
}

fn stderr(out: &Output) -> String {
    String::from_utf8_lossy(&out.stderr).into_owned()
}

/// Run, expect exit 0, parse standard output as JSON.
fn json_of(args: &[&str]) -> Json {
    let out = vstructc(args);
    assert_eq!(out.status.code(), Some(0), "{args:?}: {}", stderr(&out));
    serde_json::from_slice(&out.stdout).unwrap_or_else(|e| panic!("{args:?}: {e}"))
}

/// Every object key in `v`, recursively.
fn keys(v: &Json, out: &mut Vec<String>) {
    match v {
        Json::Object(m) => {
            for (k, v) in m {
                out.push(k.clone());
                keys(v, out);
            }
        }
        Json::Array(items) => items.iter().for_each(|i| keys(i, out)),
        _ => {}
    }
}

/// No serde enum shapes: every key is a documented lower-case field name (`{"Int": 1}`,
/// `{"array": "None"}`, `{"Triple": [...]}` are the library's internal shapes).
fn assert_plain(what: &str, doc: &Json) {
    let mut all = Vec::new();
    keys(doc, &mut all);
    for k in &all {
        assert!(
            k.chars().next().is_some_and(|c| c.is_ascii_lowercase()),
            "{what}: key `{k}` is not a documented field"
        );
    }
    let text = doc.to_string();
    for internal in ["\"array\":\"None\"", "\"Int\"", "\"Float\"", "\"Triple\""] {
        assert!(
            !text.contains(internal),
            "{what}: {internal} in {text:.300}"
        );
    }
}

fn field_names(v: &Json) -> Vec<&str> {
    let mut names: Vec<&str> = v
        .as_object()
        .expect("an object")
        .keys()
        .map(String::as_str)
        .collect();
    names.sort();
    names
}

#[test]
fn info_json_has_plain_values_and_types() {
    let doc = json_of(&["info", "--json", "PxrLayer"]);
    assert_plain("info", &doc);
    assert_eq!(field_names(&doc), ["definition", "sources", "vstruct"]);
    let def = &doc["definition"];
    assert_eq!(
        field_names(def),
        [
            "format", "id", "inputs", "kind", "metadata", "origin", "outputs", "path"
        ]
    );
    assert_eq!(def["origin"], "embedded");
    let enable = def["inputs"]
        .as_array()
        .unwrap()
        .iter()
        .find(|p| p["name"] == "enableDiffuse")
        .unwrap();
    assert_eq!(
        field_names(enable),
        [
            "connectable",
            "connectionTypes",
            "declaredType",
            "default",
            "help",
            "label",
            "location",
            "metadata",
            "name",
            "options",
            "page",
            "type",
            "vstruct",
            "widget"
        ]
    );
    assert_eq!(enable["type"], "int");
    assert_eq!(
        enable["default"],
        serde_json::json!({"type": "int", "value": 1})
    );
    let colour = def["inputs"]
        .as_array()
        .unwrap()
        .iter()
        .find(|p| p["name"] == "diffuseColor")
        .unwrap();
    assert_eq!(colour["default"]["type"], "color");
    assert_eq!(
        colour["default"]["value"],
        serde_json::json!([0.18, 0.18, 0.18]),
        "f32 numbers print as their shortest decimal"
    );
    let out = &def["outputs"][0];
    assert_eq!(out["type"], "vstruct");
}

#[test]
fn list_names_every_embedded_shader_with_kind_and_origin() {
    let out = vstructc(&["list"]);
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    let text = stdout(&out);
    let row = text
        .lines()
        .find(|l| l.starts_with("PxrLayer "))
        .expect("PxrLayer listed");
    let words: Vec<&str> = row.split_whitespace().collect();
    assert_eq!(
        words,
        [
            "PxrLayer",
            "pattern",
            "args",
            "embedded",
            "<embedded>/PxrLayer.args"
        ]
    );
    assert!(text.starts_with("SHADER"), "{text}");

    let doc = json_of(&["list", "--json"]);
    assert_plain("list", &doc);
    let shaders = doc["shaders"].as_array().unwrap();
    let ids: Vec<&str> = shaders.iter().map(|s| s["id"].as_str().unwrap()).collect();
    let mut sorted = ids.clone();
    sorted.sort();
    assert_eq!(ids, sorted);
    for want in ["PxrSurface", "PxrLayerMixer", "VRayMtl", "vsMix"] {
        assert!(ids.contains(&want), "{want}: {ids:?}");
    }
    let surface = shaders.iter().find(|s| s["id"] == "PxrSurface").unwrap();
    assert_eq!(
        field_names(surface),
        ["format", "id", "kind", "origin", "path", "shadowed"]
    );
    assert_eq!(surface["kind"], "bxdf");
    assert_eq!(surface["origin"], "embedded");
}

#[test]
fn list_says_which_file_wins_and_which_is_shadowed() {
    let dir = tempfile::tempdir().unwrap();
    let mine = dir.path().join("vsConstant.args");
    std::fs::copy("args/vsConstant.args", &mine).unwrap();
    let folder = dir.path().display().to_string();
    let doc = json_of(&["list", "--json", "--args", &folder]);
    let row = doc["shaders"]
        .as_array()
        .unwrap()
        .iter()
        .find(|s| s["id"] == "vsConstant")
        .unwrap()
        .clone();
    assert_eq!(row["origin"], "args-option");
    assert_eq!(row["path"], mine.display().to_string());
    assert_eq!(
        row["shadowed"],
        serde_json::json!(["<embedded>/vsConstant.args"])
    );
    let text = stdout(&vstructc(&["list", "--args", &folder]));
    assert!(
        text.contains("also <embedded>/vsConstant.args (not used)"),
        "{text}"
    );
}

#[test]
fn compile_json_lists_materials_nodes_and_lobes() {
    let doc = json_of(&["compile", "--json", "--emit", "lobes", "examples/chain.rib"]);
    assert_plain("compile", &doc);
    assert_eq!(doc["emit"], "lobes");
    let m = &doc["materials"][0];
    assert_eq!(
        field_names(m),
        ["inputs", "lobes", "name", "nodes", "recipe", "text"]
    );
    assert_eq!(m["name"], "car");
    assert_eq!(m["recipe"], "pxr_surface");
    let nodes = m["nodes"].as_array().unwrap();
    let leaves = nodes.iter().filter(|n| n["type"] == "leaf").count();
    assert_eq!(m["lobes"].as_u64().unwrap() as usize, leaves);
    assert_eq!(
        field_names(&nodes[0]),
        ["children", "id", "kind", "label", "type"]
    );
    // The text is what `--emit lobes` prints.
    let text = stdout(&vstructc(&[
        "compile",
        "--emit",
        "lobes",
        "examples/chain.rib",
    ]));
    assert_eq!(m["text"].as_str().unwrap().to_string() + "\n", text);
}

#[test]
fn compile_json_snapshot() {
    let doc = json_of(&["compile", "--json", "examples/override.rib"]);
    insta::assert_snapshot!(serde_json::to_string_pretty(&doc).unwrap());
}

#[test]
fn resolve_json_is_the_json_network_form() {
    let doc = json_of(&["resolve", "--json", "examples/chain.rib"]);
    assert_eq!(doc["vstructcNetwork"], 1);
    let by_format = json_of(&["resolve", "--format", "json", "examples/chain.rib"]);
    assert_eq!(doc, by_format);
    let conflict = vstructc(&["resolve", "--json", "--format", "rib", "examples/chain.rib"]);
    assert_eq!(conflict.status.code(), Some(2));
}

#[test]
fn every_data_command_has_json() {
    let docs = [
        json_of(&["list", "--json"]),
        json_of(&["info", "--json", "PxrSurface"]),
        json_of(&["expr", "--json", "set 1 if a == 1 else set 0"]),
        json_of(&["resolve", "--json", "examples/layered.rib"]),
        json_of(&[
            "explain",
            "--json",
            "mixer.layer1_enableClearcoat",
            "examples/layered.rib",
        ]),
        json_of(&["compile", "--json", "examples/layered.rib"]),
        json_of(&[
            "eval",
            "--json",
            "examples/layered.rib",
            "--wo",
            "0,0,1",
            "--wi",
            "0,0.6,0.8",
        ]),
    ];
    assert!(docs.iter().all(Json::is_object));
    // The network form's keys include node and material names; the others are all fields.
    for (i, doc) in docs.iter().enumerate().filter(|(i, _)| *i != 3) {
        assert_plain(&format!("document {i}"), doc);
    }
}

/// `explain` on the chain example: the value the lacquer layer's conditional wrote into the
/// second mixer is `written`, not authored, and a value read from the first mixer is followed
/// to the paint layer where it was authored.
#[test]
fn explain_tells_written_values_from_authored_ones() {
    let out = vstructc(&[
        "explain",
        "finished.baselayer_enableDiffuse",
        "examples/chain.rib",
    ]);
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    let text = stdout(&out);
    assert!(
        text.starts_with("finished.baselayer_enableDiffuse = 1 (written by resolution)\n"),
        "{text}"
    );
    assert!(
        text.contains("reads dusty.baselayer_enableDiffuse = 1, written by resolution\n"),
        "{text}"
    );
    assert!(
        !text.contains("dusty.baselayer_enableDiffuse = authored"),
        "a value resolution wrote is not authored: {text}"
    );
    assert!(
        text.contains("reads paint.enableDiffuse = authored 1 at examples/chain.rib:14:"),
        "{text}"
    );

    let doc = json_of(&[
        "explain",
        "--json",
        "finished.baselayer_enableDiffuse",
        "examples/chain.rib",
    ]);
    assert_plain("explain", &doc);
    assert_eq!(
        field_names(&doc),
        [
            "connections",
            "events",
            "input",
            "location",
            "node",
            "origin",
            "shader",
            "toldAbove",
            "truncated",
            "upstream",
            "value"
        ]
    );
    assert_eq!(doc["origin"], "written");
    assert_eq!(doc["value"], serde_json::json!({"type": "int", "value": 1}));
    let read = &doc["events"][0]["reads"][0];
    assert_eq!(read["param"], "baselayer_enableDiffuse");
    assert_eq!(read["origin"], "written");
    let origin = &read["story"]["events"][0]["reads"][0];
    assert_eq!(
        (&origin["node"], &origin["origin"]),
        (&"paint".into(), &"authored".into())
    );
    assert_eq!(origin["location"]["line"], 14);
}

#[test]
fn explain_follows_a_connection_to_the_authored_colour() {
    let text = stdout(&vstructc(&[
        "explain",
        "car.diffuseColor",
        "examples/chain.rib",
    ]));
    assert!(
        text.starts_with(
            "car.diffuseColor <- finished.pxrMaterialOut_diffuseColor (connected by resolution)\n"
        ),
        "{text}"
    );
    assert!(
        text.contains("paint.diffuseColor = 0.2 0.3 0.7 (authored at examples/chain.rib:15:"),
        "{text}"
    );
    assert!(
        text.contains("dust.diffuseColor = 0.45 0.4 0.35 (authored"),
        "{text}"
    );
}

#[test]
fn explain_an_authored_value_and_a_default() {
    let text = stdout(&vstructc(&[
        "explain",
        "paint.diffuseColor",
        "examples/chain.rib",
    ]));
    assert!(
        text.starts_with(
            "paint.diffuseColor = 0.2 0.3 0.7 (authored at examples/chain.rib:15:4)\n"
        ),
        "{text}"
    );
    let doc = json_of(&[
        "explain",
        "--json",
        "paint.diffuseColor",
        "examples/chain.rib",
    ]);
    assert_eq!(doc["origin"], "authored");
    assert_eq!(doc["location"]["line"], 15);
    assert!(doc["events"].as_array().unwrap().is_empty());
    let doc = json_of(&[
        "explain",
        "--json",
        "paint.specularIor",
        "examples/chain.rib",
    ]);
    assert_eq!(doc["origin"], "default");
}

#[test]
fn explain_json_snapshot() {
    let doc = json_of(&[
        "explain",
        "--json",
        "finished.layer1_enableDiffuse",
        "examples/chain.rib",
    ]);
    insta::assert_snapshot!(serde_json::to_string_pretty(&doc).unwrap());
}

#[test]
fn explain_names_an_unknown_node_or_input_with_a_suggestion() {
    let out = vstructc(&["explain", "paint.diffuseColour", "examples/chain.rib"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(
        stderr(&out).contains("did you mean `diffuseColor`?"),
        "{}",
        stderr(&out)
    );
    assert!(out.stdout.is_empty());
    let out = vstructc(&["explain", "pant.diffuseColor", "examples/chain.rib"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(
        stderr(&out).contains("did you mean `paint`?"),
        "{}",
        stderr(&out)
    );
}

/// A usage error is found before the input is read: with an input that does not exist, the
/// only message is the usage error (no IO001), and the exit status is 2.
#[test]
fn every_flag_is_checked_before_the_input_is_read() {
    let missing = "examples/does-not-exist.rib";
    let cases: &[&[&str]] = &[
        &["render", "--aov", "diffuse", missing],
        &["render", "--aov", "lobe:", missing],
        &["render", "--input", "noequals", missing],
        &["render", "--input", "x=abc", missing],
        &["render", "--input", "x=1,2", missing],
        &["render", "--size", "0", missing],
        &["render", "-o", "ball.tiff", missing],
        &[
            "eval", "--wo", "0,0,1", "--wi", "0,0,1", "--input", "x=", missing,
        ],
        &["eval", "--wo", "0,0", "--wi", "0,0,1", missing],
        &["resolve", "--format", "rib", "-o", "out.usdc", missing],
        &["resolve", "--json", "-o", "out.rib", missing],
        &["resolve", "--ext", "nested", missing],
        &["compile", "--ext", "bogus", missing],
        &["compile", "--emit", "text", missing],
        &["explain", "nodot", missing],
        &["info", "--ext", "bogus", "PxrLayer"],
        &["list", "--ext", "bogus"],
    ];
    for args in cases {
        let out = vstructc(args);
        let err = stderr(&out);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {err}");
        assert!(
            !err.contains("IO001") && !err.contains("warning"),
            "{args:?}: {err}"
        );
        assert!(out.stdout.is_empty(), "{args:?}");
    }
}

/// `render --aov diffuse` on a real input: the usage error alone, no diagnostics first.
#[test]
fn render_aov_without_lobe_prefix_prints_only_the_usage_error() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("typo.rib");
    // A typo (a warning) that would be printed if the input were read first.
    std::fs::write(
        &input,
        "Bxdf \"PxrSurface\" \"s\" \"color diffuseColour\" [1 0 0]\n",
    )
    .unwrap();
    let input = input.display().to_string();
    let read = vstructc(&["compile", &input]);
    assert!(stderr(&read).contains("diffuseColour"), "{}", stderr(&read));
    let out = vstructc(&["render", "--aov", "diffuse", &input]);
    assert_eq!(out.status.code(), Some(2));
    let err = stderr(&out);
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(
        err.starts_with("error: --aov `diffuse`: expected `lobe:NAME`"),
        "{err}"
    );
}

/// Exit 1 when the input has no material with a lowering recipe, in every command that acts
/// on materials.
#[test]
fn no_material_is_exit_1_in_every_material_command() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("pattern-only.rib");
    std::fs::write(&input, "Pattern \"PxrLayer\" \"p\"\n").unwrap();
    let input = input.display().to_string();
    let out_png = dir.path().join("x.png").display().to_string();
    let cases: &[&[&str]] = &[
        &["compile", &input],
        &["compile", "--json", &input],
        &["render", &input, "-o", &out_png],
        &["eval", &input, "--wo", "0,0,1", "--wi", "0,0,1"],
    ];
    for args in cases {
        let out = vstructc(args);
        assert_eq!(out.status.code(), Some(1), "{args:?}: {}", stderr(&out));
        assert!(
            stderr(&out).contains("error: the input has no material with a lowering recipe"),
            "{args:?}: {}",
            stderr(&out)
        );
        assert!(out.stdout.is_empty(), "{args:?}");
    }
    assert!(!dir.path().join("x.png").exists());
    // `resolve` acts on the network, not on materials: it is written back (exit 0).
    let out = vstructc(&["resolve", &input]);
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
}

/// A usage error is exit 2 in every command.
#[test]
fn a_usage_error_is_exit_2_in_every_command() {
    let cases: &[&[&str]] = &[
        &["list", "extra"],
        &["info"],
        &["info", "NoSuchShader"],
        &["expr"],
        &["resolve", "--format", "usd", "examples/chain.rib"],
        &["explain", "ghost.input", "examples/chain.rib"],
        &["compile", "--material", "nothing", "examples/chain.rib"],
        &[
            "render",
            "--material",
            "nothing",
            "examples/chain.rib",
            "-o",
            "-",
        ],
        &["eval", "examples/chain.rib", "--wo", "0,0,1"],
    ];
    for args in cases {
        let out = vstructc(args);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {}", stderr(&out));
        assert!(out.stdout.is_empty(), "{args:?}");
    }
}

#[test]
fn help_lists_the_extension_names() {
    let out = vstructc(&["resolve", "--help"]);
    let help = stdout(&out);
    for name in [
        "else-if",
        "strict-ne",
        "token-strings",
        "set-tuples",
        "copy-convert",
        "multi-alias",
        "array-heads",
        "nested",
        "array-index",
        "args-child-meta",
        "all",
    ] {
        assert!(help.contains(&format!("- {name}:")), "{name}: {help}");
    }
    let short = stdout(&vstructc(&["-h"]));
    assert!(short.contains("[possible values: else-if,"), "{short}");
}

#[test]
fn help_states_the_exit_status_rules() {
    for command in [
        "", "list", "info", "expr", "resolve", "explain", "compile", "render", "eval",
    ] {
        let args: Vec<&str> = [command, "--help"]
            .into_iter()
            .filter(|a| !a.is_empty())
            .collect();
        let help = stdout(&vstructc(&args));
        assert!(
            help.contains("Exit status (every command): 0 success"),
            "{command}: {help}"
        );
        assert!(
            help.contains("holds no material to act on"),
            "{command}: {help}"
        );
        assert!(help.contains("2 usage errors"), "{command}: {help}");
    }
}

/// A value written through a long chain of mixers: the story follows it 16 steps upstream
/// and says where it stops.
#[test]
fn explain_stops_a_long_story_and_says_so() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("mixers.rib");
    let mut rib = String::from(
        "Pattern \"PxrLayer\" \"layer\" \"int enableDiffuse\" [1]\n\
         Pattern \"PxrLayerMixer\" \"m0\" \"reference vstruct baselayer\" [\"layer:pxrMaterialOut\"]\n",
    );
    for i in 1..24 {
        rib.push_str(&format!(
            "Pattern \"PxrLayerMixer\" \"m{i}\" \"reference vstruct baselayer\" [\"m{}:pxrMaterialOut\"]\n",
            i - 1
        ));
    }
    std::fs::write(&input, rib).unwrap();
    let input = input.display().to_string();
    let out = vstructc(&["explain", "m23.baselayer_enableDiffuse", &input]);
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    let text = stdout(&out);
    assert!(text.starts_with("m23.baselayer_enableDiffuse = 1 (written by resolution)\n"));
    assert!(
        text.contains("the story goes on upstream (more than 16 steps)"),
        "{text}"
    );
    assert!(!text.contains("reads layer.enableDiffuse"), "{text}");
    let near = vstructc(&["explain", "m3.baselayer_enableDiffuse", &input]);
    assert!(
        stdout(&near).contains("reads layer.enableDiffuse = authored 1 at "),
        "{}",
        stdout(&near)
    );
}

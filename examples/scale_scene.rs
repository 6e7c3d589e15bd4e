//! Writes a generated scene for whole-process measurements (BENCHMARKS.md):
//!
//! ```text
//! cargo run --release --example scale_scene -- SHAPE N DIR
//! ```
//!
//! SHAPE is `layered` (the bench scene of N materials), `chain` (a pattern chain of N nodes)
//! or one of the scaling shapes (`shared_layer`, `shared_mixer`, `fan_in`, `redefined_bxdf`,
//! `args_params`, `args_heads`, `args_params_one_line`,
//! `args_heads_one_line`). Writes `DIR/scene.rib`, and for the `.args` shapes the
//! definition next to it (pass `--args DIR` to `vstructc`). For `layered` it also
//! writes `DIR/scene.json`, the same network in the JSON form (for the JSON reader's figures).

use std::path::PathBuf;
use std::process::ExitCode;
use vstructc::Diagnostics;
use vstructc::back::json::write_json;
use vstructc::front::rib::{RibOptions, parse_rib};
use vstructc::registry::Registry;
use vstructc_testkit::testgen::{self, Shape};

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let [shape, n, dir] = args.as_slice() else {
        eprintln!("usage: scale_scene SHAPE N DIR");
        return ExitCode::FAILURE;
    };
    let Ok(n) = n.parse::<usize>() else {
        eprintln!("N must be a number");
        return ExitCode::FAILURE;
    };
    let dir = PathBuf::from(dir);
    let json = shape == "layered";
    let (rib, args) = match shape.as_str() {
        "layered" => (testgen::layered_scene(n), None),
        "chain" => (testgen::pattern_chain(n), None),
        name => match Shape::ALL.into_iter().find(|s| s.name() == name) {
            Some(s) => {
                let scene = s.scene(n);
                (scene.rib, scene.args)
            }
            None => {
                eprintln!("unknown shape `{name}`");
                return ExitCode::FAILURE;
            }
        },
    };
    let json = json.then(|| json_of(&rib));
    let written = std::fs::create_dir_all(&dir)
        .and_then(|()| std::fs::write(dir.join("scene.rib"), &rib))
        .and_then(|()| match &json {
            Some(text) => std::fs::write(dir.join("scene.json"), text),
            None => Ok(()),
        })
        .and_then(|()| match args {
            Some((id, text)) => std::fs::write(dir.join(format!("{id}.args")), text),
            None => Ok(()),
        });
    match written {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("{}: {e}", dir.display());
            ExitCode::FAILURE
        }
    }
}

/// The network of `rib` (read with the embedded definitions) in the JSON form.
fn json_of(rib: &str) -> String {
    let registry = Registry::embedded();
    let mut diags = Diagnostics::new();
    let net = parse_rib(
        rib.as_bytes(),
        "scene.rib",
        &registry,
        &RibOptions::default(),
        &mut diags,
    )
    .expect("generated scene parses");
    write_json(&net).unwrap()
}

//! Every public `.args` fixture loads; exact counts and encodings of the Pixar files.

mod common;

use std::path::{Path, PathBuf};
use vstructc::Diagnostics;
use vstructc::front::args::parse_args;
use vstructc::registry::{Definition, Direction};
use vstructc::types::{ArraySpec, BaseType, Value};

fn args_files(dir: &Path) -> Vec<PathBuf> {
    let mut out = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                stack.push(p);
            } else if p.extension().is_some_and(|x| x == "args") {
                out.push(p);
            }
        }
    }
    out.sort();
    out
}

fn load(path: &Path) -> (Definition, Diagnostics) {
    let bytes = std::fs::read(path).unwrap();
    let id = path.file_stem().unwrap().to_str().unwrap();
    let mut diags = Diagnostics::new();
    let def = parse_args(&bytes, &path.to_string_lossy(), id, &mut diags)
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    (def, diags)
}

#[test]
fn every_args_fixture_loads_without_warnings() {
    let dir = fixtures_or_skip!();
    let files = args_files(&dir.join("args"));
    assert!(
        files.len() >= 8,
        "expected the pixar and laika args, got {files:?}"
    );
    for f in files {
        let (def, diags) = load(&f);
        for d in &diags {
            eprintln!("{}", d.render_human());
        }
        assert!(
            !diags.has_warnings(),
            "{}: unexpected warnings",
            f.display()
        );
        assert!(
            !def.inputs.is_empty() || !def.outputs.is_empty(),
            "{}",
            f.display()
        );
        assert_ne!(def.kind, "unknown", "{}", f.display());
    }
}

#[test]
fn dump_tmp() {
    let dir = fixtures_or_skip!();
    for f in args_files(&dir.join("args")) {
        let (def, diags) = load(&f);
        println!(
            "== {} kind={} in={} out={} meta={:?}",
            def.id,
            def.kind,
            def.inputs.len(),
            def.outputs.len(),
            def.metadata
                .iter()
                .map(|(k, v)| (k.clone(), v.chars().take(60).collect::<String>()))
                .collect::<Vec<_>>()
        );
        for d in &diags {
            println!("  {}", d.render_human());
        }
        for p in def.inputs.iter().chain(def.outputs.iter()).take(6) {
            println!(
                "  {:?} {} ty={} decl={:?} def={:?} page={:?} conn={} tags={:?} help={:?} opts={:?} vs={:?} loc={}",
                p.direction,
                p.name,
                p.ty,
                p.declared_type,
                p.default.as_ref().map(|v| v.to_string()),
                p.page,
                p.connectable,
                p.connection_types,
                p.help
                    .as_ref()
                    .map(|h| h.chars().take(50).collect::<String>()),
                p.options,
                p.vstruct,
                p.location
            );
        }
        if def.id == "PxrLayer" {
            let p = def.output("pxrMaterialOut_diffuseGain").unwrap();
            println!("{:?}", p);
        }
    }
}

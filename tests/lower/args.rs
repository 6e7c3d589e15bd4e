//! The project's own definitions for the lowered models (`args/VRayMtl.args`,
//! `args/PhysicalMaterial.args`, `args/mia_material.args`) declare exactly the defaults the
//! recipes use as built-ins (closures.md §4.3–§4.5 tables), so lowering with and without a
//! registry gives the same result.

use std::path::Path;
use vstructc::Value;
use vstructc::ir::value_to_vec3;
use vstructc::lower::{mia, physical, vray};

/// `(name, type, default)` of every `<param>` (a small scan; the files are generated with one
/// `<param ...>` per line).
fn params(file: &str) -> Vec<(String, String, Vec<f32>)> {
    let text = std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("args")
            .join(file),
    )
    .unwrap();
    let attr = |line: &str, key: &str| {
        let start = line.find(&format!("{key}=\""))? + key.len() + 2;
        let end = line[start..].find('"')? + start;
        Some(line[start..end].to_string())
    };
    text.lines()
        .filter(|l| l.trim_start().starts_with("<param "))
        .map(|l| {
            let d = attr(l, "default").unwrap();
            let nums = d
                .split_whitespace()
                .map(|x| x.parse::<f32>().unwrap())
                .collect();
            (attr(l, "name").unwrap(), attr(l, "type").unwrap(), nums)
        })
        .collect()
}

fn check(file: &str, builtin: fn(&str) -> Value, expected_count: usize) {
    let ps = params(file);
    assert_eq!(ps.len(), expected_count, "{file}");
    for (name, ty, d) in ps {
        let b = builtin(&name);
        let want = value_to_vec3(&b);
        let got = if d.len() == 3 {
            glam::Vec3::new(d[0], d[1], d[2])
        } else {
            glam::Vec3::splat(d[0])
        };
        assert_eq!(got, want, "{file}: {name}");
        let is_triple = matches!(b, Value::Triple(..));
        assert_eq!(is_triple, ty == "color", "{file}: {name} type {ty}");
        if ty == "int" {
            assert!(matches!(b, Value::Int(_)), "{file}: {name} int");
        }
    }
}

#[test]
fn vray_args_match_builtins() {
    check("VRayMtl.args", vray::builtin_default, 24);
}

#[test]
fn physical_args_match_builtins() {
    check("PhysicalMaterial.args", physical::builtin_default, 31);
}

#[test]
fn mia_args_match_builtins() {
    check("mia_material.args", mia::builtin_default, 25);
}

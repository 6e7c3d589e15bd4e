//! Build script: embeds every `*.args` file under `args/` into the binary.
//!
//! It writes `$OUT_DIR/embedded_args.rs`, a slice of `(relative path, bytes)` pairs in byte-wise
//! sorted path order, each bytes value an `include_bytes!` of the file. Adding a file to `args/`
//! needs no code change: Cargo reruns this script when anything under `args/` changes.

use std::fs;
use std::path::{Path, PathBuf};

fn collect(dir: &Path, out: &mut Vec<PathBuf>) {
    let Ok(entries) = fs::read_dir(dir) else {
        return;
    };
    for entry in entries.flatten() {
        let path = entry.path();
        if path.is_dir() {
            collect(&path, out);
        } else if path.extension().is_some_and(|e| e == "args") {
            out.push(path);
        }
    }
}

fn main() {
    let root = PathBuf::from(std::env::var("CARGO_MANIFEST_DIR").expect("CARGO_MANIFEST_DIR"));
    let args_dir = root.join("args");
    println!("cargo:rerun-if-changed=args");
    println!("cargo:rerun-if-changed=build.rs");
    let mut files = Vec::new();
    collect(&args_dir, &mut files);
    files.sort_by(|a, b| {
        a.as_os_str()
            .as_encoded_bytes()
            .cmp(b.as_os_str().as_encoded_bytes())
    });
    let mut code = String::from("&[\n");
    for f in &files {
        let rel = f.strip_prefix(&args_dir).unwrap_or(f);
        let rel = rel.to_string_lossy().replace('\\', "/");
        // The path is joined when the crate compiles, not here: a build script's output is
        // reused when the same target directory serves another checkout of the project.
        code.push_str(&format!(
            "    ({rel:?}, include_bytes!(concat!(env!(\"CARGO_MANIFEST_DIR\"), \"/args/{}\")) as &[u8]),\n",
            rel.escape_default()
        ));
    }
    code.push_str("]\n");
    let out = PathBuf::from(std::env::var("OUT_DIR").expect("OUT_DIR")).join("embedded_args.rs");
    fs::write(out, code).expect("write embedded_args.rs");
}

//! Determinism: `resolve` gives byte-identical output (stdout and stderr) across
//! runs and across rayon thread counts, in RIB and JSON; so do the stages after it, `compile`
//! (IR and lobe listings) and `render` (the preview image, rendered in parallel by rows).

use std::path::{Path, PathBuf};
use std::process::Command;

/// stdout and stderr of `vstructc resolve FILE --format FORMAT` with `threads` rayon threads.
fn resolve(file: &Path, format: &str, threads: &str) -> (Vec<u8>, Vec<u8>) {
    let path = file.display().to_string();
    run(&["resolve", "--format", format, path.as_str()], threads)
}

fn inputs() -> Vec<PathBuf> {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let mut files: Vec<PathBuf> = std::fs::read_dir(root.join("examples"))
        .expect("examples/")
        .map(|e| e.expect("dir entry").path())
        .filter(|p| p.extension().is_some_and(|e| e == "rib" || e == "json"))
        .collect();
    files.sort();
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("determinism");
    std::fs::create_dir_all(&dir).expect("scratch dir");
    let scene = dir.join("layered50.rib");
    std::fs::write(&scene, vstructc_testkit::testgen::layered_scene(50)).expect("scene");
    files.push(scene);
    files
}

#[test]
fn same_input_same_bytes_across_runs_and_thread_counts() {
    for file in inputs() {
        for format in ["rib", "json"] {
            let first = resolve(&file, format, "1");
            assert!(!first.0.is_empty(), "{}: empty output", file.display());
            for threads in ["1", "2", "2"] {
                let again = resolve(&file, format, threads);
                assert!(
                    again == first,
                    "{} ({format}, RAYON_NUM_THREADS={threads}): output differs between runs",
                    file.display()
                );
            }
        }
    }
}

/// stdout and stderr of `vstructc ARGS...` with `threads` rayon threads (exit status 0).
fn run(args: &[&str], threads: &str) -> (Vec<u8>, Vec<u8>) {
    let out = Command::new(env!("CARGO_BIN_EXE_vstructc"))
        .args(args)
        .env("RAYON_NUM_THREADS", threads)
        .output()
        .expect("the vstructc binary runs");
    assert_eq!(
        out.status.code(),
        Some(0),
        "{args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    (out.stdout, out.stderr)
}

#[test]
fn compile_and_render_are_deterministic_across_thread_counts() {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("determinism-render");
    std::fs::create_dir_all(&dir).expect("scratch dir");
    for file in inputs() {
        let path = file.display().to_string();
        for emit in ["ir", "lobes"] {
            let args = ["compile", "--emit", emit, path.as_str()];
            let first = run(&args, "1");
            assert_eq!(run(&args, "2"), first, "compile --emit {emit} {path}");
        }
        let mut images = Vec::new();
        for threads in ["1", "2"] {
            let png = dir
                .join(format!("ball-{threads}.pfm"))
                .display()
                .to_string();
            run(
                &[
                    "render",
                    "--size",
                    "32",
                    "--pfm",
                    path.as_str(),
                    "-o",
                    png.as_str(),
                ],
                threads,
            );
            images.push(std::fs::read(&png).expect("rendered image"));
        }
        assert_eq!(
            images[0], images[1],
            "render {path}: image depends on the thread count"
        );
    }
}

/// Reading from standard input gives the same bytes every time (each process seeds its hash
/// maps differently, so any dependence on hash-map iteration order shows up here).
#[test]
fn stdin_input_is_repeatable() {
    let text = vstructc_testkit::testgen::layered_scene(20);
    let once = || {
        let out = Command::new(env!("CARGO_BIN_EXE_vstructc"))
            .args(["resolve", "-"])
            .stdin_file(&text)
            .output()
            .expect("runs");
        out.stdout
    };
    assert_eq!(once(), once());
}

/// Feed a string to a command's standard input through a temporary file.
trait StdinFile {
    fn stdin_file(&mut self, text: &str) -> &mut Self;
}

impl StdinFile for Command {
    fn stdin_file(&mut self, text: &str) -> &mut Self {
        let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("determinism");
        std::fs::create_dir_all(&dir).expect("scratch dir");
        let path = dir.join(format!("stdin-{}.rib", std::process::id()));
        std::fs::write(&path, text).expect("stdin file");
        self.stdin(std::fs::File::open(&path).expect("open stdin file"))
    }
}

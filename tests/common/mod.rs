//! Helpers shared by the test binaries (each `tests/<stage>/main.rs` includes this module).
#![allow(dead_code)]

pub mod leaves_ref;
pub mod network;
pub mod pfm;
pub mod png_decode;

use std::path::PathBuf;

/// The repository root (where Cargo.toml is).
pub fn repo_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// The environment variable that names the fixtures folder instead of `../shared/fixtures`.
pub const FIXTURES_VAR: &str = "VSTRUCTC_FIXTURES";

/// Whether `CI=true`: there, every test must be able to run.
pub fn under_ci() -> bool {
    std::env::var("CI").is_ok_and(|v| v == "true")
}

/// The fixtures folder: `$VSTRUCTC_FIXTURES` when set, else `../shared/fixtures` beside the
/// repository; `None` when it is missing.
///
/// When it is missing: under `CI=true` this panics (CI must have the fixtures); otherwise the
/// calling test is recorded as not run (see [`not_run`]) and the caller returns early.
pub fn fixtures() -> Option<PathBuf> {
    let dir = match std::env::var_os(FIXTURES_VAR) {
        Some(dir) => PathBuf::from(dir),
        None => repo_dir().join("../shared/fixtures"),
    };
    if dir.is_dir() {
        return Some(dir);
    }
    if under_ci() {
        panic!(
            "{} is missing (CI=true): fixture tests cannot run",
            dir.display()
        );
    }
    not_run(&format!(
        "fixtures not found at {} (set {FIXTURES_VAR} to the fixtures folder; \
         under CI=true this is a failure)",
        dir.display()
    ));
    None
}

/// Return the fixtures folder, or return early from the calling test, recorded as not run,
/// when it is missing.
#[macro_export]
macro_rules! fixtures_or_skip {
    () => {
        match $crate::common::fixtures() {
            Some(dir) => dir,
            None => return,
        }
    };
}

/// Tests of this binary that could not check what they are for, with the reason.
static NOT_RUN: std::sync::Mutex<Vec<(String, String)>> = std::sync::Mutex::new(Vec::new());

/// Record that the calling test checks nothing here (or only part of what it is for), and
/// why. The test harness swallows what a passing test prints, so the list is written to
/// standard output when the test binary exits, after the harness's own summary: a run that
/// passes with tests that did not run says so, with their number.
pub fn not_run(why: &str) {
    let test = std::thread::current()
        .name()
        .filter(|name| *name != "main")
        .unwrap_or("(a test run on the main thread)")
        .to_string();
    NOT_RUN
        .lock()
        .unwrap_or_else(|e| e.into_inner())
        .push((test, why.to_string()));
    report_at_exit();
}

/// Folders of scratch files to remove when the test binary exits.
static SCRATCH: std::sync::Mutex<Vec<PathBuf>> = std::sync::Mutex::new(Vec::new());

/// Whether a test of this run panicked (failed).
static FAILED: std::sync::atomic::AtomicBool = std::sync::atomic::AtomicBool::new(false);

/// Remove `dir`, a folder of scratch files under the target folder, when the test binary exits,
/// unless a test of this run failed: then the files stay to be looked at. (Some tests write
/// hundreds of megabytes of monster inputs and outputs.)
pub fn remove_at_exit(dir: &std::path::Path) {
    SCRATCH
        .lock()
        .unwrap_or_else(|e| e.into_inner())
        .push(dir.to_path_buf());
    static HOOK: std::sync::Once = std::sync::Once::new();
    HOOK.call_once(|| {
        let previous = std::panic::take_hook();
        std::panic::set_hook(Box::new(move |info| {
            FAILED.store(true, std::sync::atomic::Ordering::SeqCst);
            previous(info)
        }));
    });
    report_at_exit();
}

/// What the binary does at exit: report the tests that did not run, remove the scratch
/// folders of a run without failures.
fn at_exit() -> String {
    if !FAILED.load(std::sync::atomic::Ordering::SeqCst)
        && let Ok(dirs) = SCRATCH.try_lock()
    {
        for dir in dirs.iter() {
            let _ = std::fs::remove_dir_all(dir);
        }
    }
    not_run_report()
}

#[cfg(unix)]
fn report_at_exit() {
    static ONCE: std::sync::Once = std::sync::Once::new();
    ONCE.call_once(|| {
        extern "C" fn report() {
            let text = at_exit();
            // The harness captures `print!`; at exit, write to the standard output itself.
            // SAFETY: writes `text`'s bytes, which outlive the call, to descriptor 1.
            unsafe { libc::write(1, text.as_ptr().cast(), text.len()) };
        }
        // SAFETY: registers a plain function without captured state.
        unsafe { libc::atexit(report) };
    });
}

/// Without `atexit`, each test that did not run is written out at once (and scratch files
/// stay).
#[cfg(not(unix))]
fn report_at_exit() {
    use std::io::Write as _;
    let _ = std::io::stdout().write_all(not_run_report().as_bytes());
    NOT_RUN.lock().unwrap_or_else(|e| e.into_inner()).clear();
}

/// "N tests did not run: why" per reason, each followed by the tests' names.
fn not_run_report() -> String {
    let list = match NOT_RUN.try_lock() {
        Ok(list) => list.clone(),
        Err(std::sync::TryLockError::Poisoned(e)) => e.into_inner().clone(),
        Err(std::sync::TryLockError::WouldBlock) => return String::new(),
    };
    let mut reasons: Vec<&str> = list.iter().map(|(_, why)| why.as_str()).collect();
    reasons.sort_unstable();
    reasons.dedup();
    let mut out = String::new();
    for why in reasons {
        let mut tests: Vec<&str> = list
            .iter()
            .filter(|(_, w)| w == why)
            .map(|(t, _)| t.as_str())
            .collect();
        tests.sort_unstable();
        let s = if tests.len() == 1 { "" } else { "s" };
        out.push_str(&format!("NOT RUN: {} test{s}: {why}\n", tests.len()));
        for t in tests {
            out.push_str(&format!("    {t}\n"));
        }
    }
    out
}

/// A stable text form of a network for snapshots: per node (sorted), each parameter's
/// connections or value.
pub fn dump_network(net: &vstructc::network::Network) -> String {
    let mut out = String::new();
    for id in net.nodes_sorted() {
        let node = &net[id];
        out.push_str(&format!("{} ({})\n", node.display_name(), node.shader()));
        for p in node.params_by_name() {
            if p.is_connected() {
                let links: Vec<String> = p
                    .connections()
                    .iter()
                    .map(|l| {
                        let up = match l.upstream_node() {
                            Some(n) => net[n].handle().to_string(),
                            None => format!("<missing {}>", l.missing_handle().unwrap_or_default()),
                        };
                        match l.output() {
                            Some(o) => format!("{up}.{o}"),
                            None => up,
                        }
                    })
                    .collect();
                out.push_str(&format!("  {} <- {}\n", p.name(), links.join(", ")));
            } else if let Some(v) = p.value() {
                out.push_str(&format!("  {} = {v}\n", p.name()));
            }
        }
    }
    out
}

/// Every terminal type with a lowering recipe (closures.md §4.1–§4.5).
pub const RECIPES: [&str; 5] = [
    "PxrSurface",
    "PxrLayerSurface",
    "VRayMtl",
    "PhysicalMaterial",
    "mia_material",
];

/// The recipe of `shader` lowered with every parameter at its embedded definition's default.
pub fn recipe_at_defaults(shader: &str) -> vstructc::ir::MaterialIr {
    let registry = vstructc::registry::Registry::embedded();
    let mut net = vstructc::network::Network::new();
    let node = net.add_node("m", shader);
    let mut diags = vstructc::Diagnostics::new();
    let ir = vstructc::lower::network::lower_terminal(&net, &registry, node, shader, &mut diags)
        .expect("lowers");
    assert_eq!(
        diags.count("LW003"),
        0,
        "{shader} has an embedded definition"
    );
    ir
}

/// The golden network of vstruct.md §12: the RenderMan for Maya export, relative to the
/// fixtures folder.
pub const GOLDEN_RIB: &str = "rib/ldd/pxrLayerSurface.0001.rib";

/// The golden network's registry: Pixar's PxrLayer and PxrLayerMixer from the fixtures, and
/// the PxrLayerSurface definition in `surface_args`.
pub fn golden_registry(
    fixtures: &std::path::Path,
    surface_args: &std::path::Path,
) -> vstructc::registry::Registry {
    use vstructc::registry::{Registry, RegistryOptions};
    let mut reg = Registry::new(RegistryOptions {
        paths: vec![fixtures.join("args/pixar")],
        use_env: false,
        use_embedded: false,
        ..RegistryOptions::default()
    });
    let text = std::fs::read_to_string(surface_args).expect("surface definition");
    reg.add_args_text("PxrLayerSurface", &text)
        .expect("surface definition parses");
    reg
}

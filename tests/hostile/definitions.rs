//! Definition folders and files that would hang or exhaust vstructc: symlink loops, FIFOs
//! and devices named `*.args`/`*.oso`, oversized files; and networks from FIFOs, which are
//! legitimate. Every child runs under the watchdog of [`crate::output::wait`].

use crate::check;
use crate::output::{folder, run_cmd, vstructc, wait};
use std::io::Write;
use std::os::unix::fs::symlink;
use std::path::Path;
use std::process::Stdio;
use std::time::Instant;
use vstructc::diag::Severity;
use vstructc::limits::Limits;
use vstructc::registry::{Registry, RegistryOptions};

const GOOD_ARGS: &str = "<args format=\"1.0\"><shaderType><tag value=\"pattern\"/></shaderType>\
    <param name=\"x\" type=\"float\" default=\"1\"/><output name=\"out\" type=\"float\"/></args>\n";

fn s(p: &Path) -> &str {
    p.to_str().expect("UTF-8 temporary path")
}

fn mkfifo(path: &Path) {
    let c = std::ffi::CString::new(s(path)).expect("path");
    // SAFETY: a valid NUL-terminated path.
    assert_eq!(unsafe { libc::mkfifo(c.as_ptr(), 0o600) }, 0, "mkfifo");
}

/// A symlink back to an enclosing folder is one warning (RG003) naming the link and the
/// folder, and the walk goes on to find the definition; a second way into an already listed
/// folder lists it once (no duplicate definitions, RG001). The warning is also in the
/// registry's returned diagnostics, with the link's path.
#[test]
fn a_symlink_loop_is_reported_once_and_the_walk_goes_on() {
    let dir = folder("loop");
    let defs = dir.path().join("defs");
    std::fs::create_dir_all(defs.join("a/deeper")).unwrap();
    std::fs::write(defs.join("a/deeper/Good.args"), GOOD_ARGS).unwrap();
    symlink("../..", defs.join("a/deeper/back")).unwrap();
    symlink("a", defs.join("again")).unwrap();
    let ran = run_cmd(&mut vstructc(&["info", "Good", "--args", s(&defs)]));
    check("symlink loop", &ran.out, 0, "warning[RG003]");
    assert_eq!(
        ran.out.stderr.matches("RG003").count(),
        1,
        "{}",
        ran.out.stderr
    );
    assert!(
        ran.out.stderr.contains("a/deeper/back"),
        "{}",
        ran.out.stderr
    );
    assert!(!ran.out.stderr.contains("RG001"), "{}", ran.out.stderr);
    assert!(String::from_utf8_lossy(&ran.stdout).contains("Good: pattern"));

    let reg = Registry::new(RegistryOptions::only([&defs]));
    let diags = reg.diagnostics();
    let loops: Vec<_> = diags
        .with_code("RG003")
        .filter(|d| d.severity == Severity::Warning)
        .collect();
    assert_eq!(loops.len(), 1, "{diags:?}");
    let at = loops[0].location.as_ref().expect("located");
    assert!(at.file.ends_with("a/deeper/back"), "{at}");
    assert!(reg.definition("Good").is_some());
    assert_eq!(reg.sources("Good").len(), 1);
}

/// FIFOs named `x.args` and `y.oso` in a folder are warnings (RG004) and skipped: nothing
/// waits for a writer. Given explicitly with `--args`, one is an error; as a
/// `VSTRUCTC_ARGS_PATH` entry, a warning.
#[test]
fn a_fifo_named_like_a_definition_is_skipped() {
    let dir = folder("fifo");
    let defs = dir.path().join("defs");
    std::fs::create_dir(&defs).unwrap();
    std::fs::write(defs.join("Good.args"), GOOD_ARGS).unwrap();
    mkfifo(&defs.join("x.args"));
    mkfifo(&defs.join("y.oso"));
    let ran = run_cmd(&mut vstructc(&["info", "Good", "--args", s(&defs)]));
    check("FIFO in folder", &ran.out, 0, "warning[RG004]");
    assert_eq!(ran.out.stderr.matches("warning[RG004]").count(), 2);
    for name in ["x.args", "y.oso"] {
        assert!(ran.out.stderr.contains(name), "{}", ran.out.stderr);
    }
    assert!(ran.out.stderr.contains("a FIFO"), "{}", ran.out.stderr);

    let fifo = defs.join("x.args");
    let ran = run_cmd(&mut vstructc(&["info", "x", "--args", s(&fifo)]));
    check("FIFO as --args", &ran.out, 1, "error[RG004]");
    assert!(ran.out.stderr.contains(s(&fifo)), "{}", ran.out.stderr);

    let ran = run_cmd(vstructc(&["info", "PxrLayerMixer"]).env("VSTRUCTC_ARGS_PATH", s(&fifo)));
    check("FIFO in VSTRUCTC_ARGS_PATH", &ran.out, 0, "warning[RG004]");
}

/// A definition that is `/dev/zero` through a symlink is never read: given with `--args` it
/// is an error naming the file (RG004); in a folder it is a warning and skipped.
#[test]
fn a_definition_linked_to_dev_zero_is_not_read() {
    let dir = folder("zero");
    let defs = dir.path().join("defs");
    std::fs::create_dir(&defs).unwrap();
    std::fs::write(defs.join("Good.args"), GOOD_ARGS).unwrap();
    let zero = defs.join("Zero.args");
    symlink("/dev/zero", &zero).unwrap();
    symlink("/dev/zero", defs.join("Zero.oso")).unwrap();
    let ran = run_cmd(&mut vstructc(&["info", "Zero", "--args", s(&zero)]));
    check("--args /dev/zero link", &ran.out, 1, "error[RG004]");
    assert!(
        ran.out.stderr.contains(s(&zero)) && ran.out.stderr.contains("a character device"),
        "{}",
        ran.out.stderr
    );
    let ran = run_cmd(&mut vstructc(&["info", "Good", "--args", s(&defs)]));
    check("/dev/zero links in folder", &ran.out, 0, "warning[RG004]");
    assert_eq!(ran.out.stderr.matches("warning[RG004]").count(), 2);
}

/// A definition file above [`Limits::definition_file_bytes`] is an error (LM001) naming the
/// file, the limit and its size, and is not read; one of exactly the limit is read (and rejected for what it
/// holds, here zeros, not for its size). The files are sparse: no disk is used.
#[test]
fn an_oversized_definition_is_an_error_with_its_size() {
    let max = Limits::default().definition_file_bytes;
    let dir = folder("big");
    let big = dir.path().join("Big.args");
    let file = std::fs::File::create(&big).unwrap();
    file.set_len(max + 1).unwrap();
    let ran = run_cmd(&mut vstructc(&["info", "Big", "--args", s(dir.path())]));
    check("oversized .args", &ran.out, 1, "error[LM001]");
    assert!(
        ran.out.stderr.contains("definition_file_bytes"),
        "{}",
        ran.out.stderr
    );
    let size = (max + 1).to_string();
    assert!(
        ran.out.stderr.contains(s(&big)) && ran.out.stderr.contains(&size),
        "{}",
        ran.out.stderr
    );
    file.set_len(max).unwrap();
    let ran = run_cmd(&mut vstructc(&["info", "Big", "--args", s(dir.path())]));
    assert_eq!(ran.out.status, Some(1), "{}", ran.out.stderr);
    assert!(!ran.out.stderr.contains("LM001"), "{}", ran.out.stderr);
}

/// A network from a FIFO is legitimate and read to its end (streams are capped at
/// `Limits::network_file_bytes`, tested in the library: 4 GiB is too much for a test).
#[test]
fn a_network_from_a_fifo_is_read() {
    let dir = folder("netfifo");
    let fifo = dir.path().join("scene.rib");
    mkfifo(&fifo);
    let input =
        std::fs::read(Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/chain.rib")).unwrap();
    let writer_path = fifo.clone();
    let expected = run_cmd(&mut vstructc(&["resolve", "examples/chain.rib"])).stdout;
    // Detached: if vstructc never opened the FIFO, this thread would wait forever; the
    // watchdog on vstructc fails the test first.
    std::thread::spawn(move || {
        if let Ok(mut f) = std::fs::OpenOptions::new().write(true).open(&writer_path) {
            let _ = f.write_all(&input);
        }
    });
    let child = vstructc(&["resolve", s(&fifo)])
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let ran = wait(child, Instant::now());
    check("resolve FIFO", &ran.out, 0, "");
    assert_eq!(ran.stdout, expected);
}

/// A network file above `Limits::network_file_bytes` is refused by its size before a byte is
/// read (LM001 naming the limit and the size); the file is sparse, so no disk is used.
#[test]
fn an_oversized_network_file_is_refused_unread() {
    let max = Limits::default().network_file_bytes;
    let dir = folder("bignet");
    let big = dir.path().join("scene.rib");
    std::fs::File::create(&big)
        .unwrap()
        .set_len(max + 1)
        .unwrap();
    let ran = run_cmd(&mut vstructc(&["resolve", s(&big)]));
    check("oversized network", &ran.out, 1, "error[LM001]");
    let size = (max + 1).to_string();
    assert!(
        ran.out.stderr.contains("network_file_bytes") && ran.out.stderr.contains(&size),
        "{}",
        ran.out.stderr
    );
}

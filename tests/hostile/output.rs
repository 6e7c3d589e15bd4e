//! Output targets: what `-o` names (a FIFO, a symlink, a read-only or private file, a
//! character device, a descriptor link) and standard output on a full disk. Each case checks
//! the exit status, the message, and the target's state afterwards; every child process runs
//! under a watchdog, so a regression that blocks fails instead of hanging the suite.

use crate::{Outcome, check};
use std::fs::File;
use std::io::{Read, Write};
use std::os::unix::fs::{FileTypeExt, MetadataExt, PermissionsExt, symlink};
use std::os::unix::process::CommandExt;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::sync::mpsc;
use std::time::{Duration, Instant};

/// A child still running after this long is killed and the test fails.
const WATCHDOG: Duration = Duration::from_secs(20);

/// The user that runs the unprivileged cases when the tests run as root.
const NOBODY: u32 = 65534;

/// What a finished child produced.
pub(crate) struct Ran {
    /// Status, stderr and time, as the shared [`check`] reads them.
    pub(crate) out: Outcome,
    /// Standard output, when it was piped.
    pub(crate) stdout: Vec<u8>,
}

/// `vstructc` with no `VSTRUCTC_ARGS_PATH`, in the repository (for `examples/`).
pub(crate) fn vstructc(args: &[&str]) -> Command {
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_vstructc"));
    cmd.args(args)
        .env("VSTRUCTC_ARGS_PATH", "")
        .current_dir(env!("CARGO_MANIFEST_DIR"));
    cmd
}

/// Runs `vstructc args` in `examples/`'s parent as a user who may not write what root may:
/// the calling user, or `nobody` when the tests run as root. `None`, with the calling test
/// recorded as not run and the reason printed, when `nobody` cannot run the binary here.
///
/// `nobody` runs copies of the binary and of `examples/chain.rib` in a fresh folder every user
/// may enter, read and execute (0755), that folder its working directory: the build's own
/// binary and the repository may sit where only their owner can reach them (a clone in a
/// 0700 home folder), and `nobody` could then neither start the binary nor read the example.
fn run_unprivileged(args: &[&str]) -> Option<Ran> {
    if !is_root() {
        return Some(run_cmd(&mut vstructc(args)));
    }
    let open = |p: &Path, mode: u32| {
        std::fs::set_permissions(p, std::fs::Permissions::from_mode(mode))
            .expect("permissions of the copy for nobody")
    };
    let copy = folder("nobody");
    open(copy.path(), 0o755);
    let exe = copy.path().join("vstructc");
    std::fs::copy(env!("CARGO_BIN_EXE_vstructc"), &exe).expect("copy of the binary");
    open(&exe, 0o755);
    let examples = copy.path().join("examples");
    std::fs::create_dir(&examples).expect("examples folder of the copy");
    open(&examples, 0o755);
    let chain = examples.join("chain.rib");
    std::fs::copy(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/chain.rib"),
        &chain,
    )
    .expect("copy of examples/chain.rib");
    open(&chain, 0o644);
    let as_nobody = |cmd: &mut Command| {
        cmd.env("VSTRUCTC_ARGS_PATH", "")
            .current_dir(copy.path())
            .uid(NOBODY)
            .gid(NOBODY);
    };
    // Whether `nobody` can start the copy at all (a temporary folder inside a private one,
    // or a system that refuses the change of user, would stop it).
    let mut probe = Command::new(&exe);
    probe.arg("--version");
    as_nobody(&mut probe);
    let refused = match probe.stdout(Stdio::null()).stderr(Stdio::null()).status() {
        Ok(status) if status.success() => None,
        Ok(status) => Some(format!(
            "`vstructc --version` as nobody exited with {status}"
        )),
        Err(e) => Some(format!("nobody cannot start vstructc: {e}")),
    };
    if let Some(why) = refused {
        let why = format!("{why} (a copy in {})", copy.path().display());
        eprintln!("NOT RUN: the unprivileged case: {why}");
        crate::common::not_run(&why);
        return None;
    }
    let mut cmd = Command::new(&exe);
    cmd.args(args);
    as_nobody(&mut cmd);
    Some(run_cmd(&mut cmd))
}

/// Run `cmd` with no input and piped output, under the watchdog.
pub(crate) fn run_cmd(cmd: &mut Command) -> Ran {
    let child = cmd
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("the vstructc binary runs");
    wait(child, Instant::now())
}

/// Wait for `child` (stderr piped; stdout piped or not), killing it after [`WATCHDOG`].
pub(crate) fn wait(child: Child, start: Instant) -> Ran {
    let pid = child.id() as libc::pid_t;
    let (done, finished) = mpsc::channel::<()>();
    let watchdog = std::thread::spawn(move || {
        let expired = finished.recv_timeout(WATCHDOG).is_err();
        if expired {
            // SAFETY: plain kill(2) of our own child, which has not been waited for yet.
            unsafe { libc::kill(pid, libc::SIGKILL) };
        }
        expired
    });
    let output = child.wait_with_output().expect("wait for vstructc");
    let _ = done.send(());
    let expired = watchdog.join().expect("watchdog");
    let out = Outcome {
        status: output.status.code(),
        stderr: String::from_utf8_lossy(&output.stderr).into_owned(),
        elapsed: start.elapsed(),
    };
    assert!(
        !expired,
        "killed after {WATCHDOG:?}: stderr:\n{}",
        out.stderr
    );
    Ran {
        out,
        stdout: output.stdout,
    }
}

/// A fresh temporary folder (removed when dropped).
pub(crate) fn folder(name: &str) -> tempfile::TempDir {
    tempfile::Builder::new()
        .prefix(&format!("vstructc-hostile-{name}-"))
        .tempdir()
        .expect("temporary folder")
}

fn is_root() -> bool {
    // SAFETY: geteuid has no preconditions.
    unsafe { libc::geteuid() == 0 }
}

fn mode(p: &Path) -> u32 {
    std::fs::metadata(p).expect("target exists").mode() & 0o7777
}

fn s(p: &Path) -> &str {
    p.to_str().expect("UTF-8 temporary path")
}

/// Names in `dir` that look like temporary output files.
fn temporaries(dir: &Path) -> Vec<String> {
    std::fs::read_dir(dir)
        .expect("folder")
        .map(|e| e.expect("entry").file_name().to_string_lossy().into_owned())
        .filter(|n| n.starts_with('.') && n.ends_with(".tmp"))
        .collect()
}

/// `resolve examples/chain.rib -o target`.
fn resolve_to(target: &Path) -> Ran {
    run_cmd(&mut vstructc(&[
        "resolve",
        "examples/chain.rib",
        "-o",
        s(target),
    ]))
}

fn resolved_chain() -> Vec<u8> {
    let ran = run_cmd(&mut vstructc(&["resolve", "examples/chain.rib"]));
    check("resolve to stdout", &ran.out, 0, "");
    assert!(!ran.stdout.is_empty());
    ran.stdout
}

fn mkfifo(path: &Path) {
    let c = std::ffi::CString::new(s(path)).expect("path");
    // SAFETY: a valid NUL-terminated path.
    assert_eq!(unsafe { libc::mkfifo(c.as_ptr(), 0o600) }, 0, "mkfifo");
}

/// A FIFO is written in place: a reader on the other end receives the whole output and the
/// FIFO is still a FIFO. (Before, it was replaced by a regular file.)
#[test]
fn a_fifo_target_is_written_in_place() {
    let dir = folder("fifo");
    let fifo = dir.path().join("out.rib");
    mkfifo(&fifo);
    let (sent, received) = mpsc::channel();
    let reader_path = fifo.clone();
    // Detached: if the FIFO were replaced, this thread would wait forever in `open`, and the
    // `recv_timeout` below fails the test instead.
    std::thread::spawn(move || {
        let mut bytes = Vec::new();
        let read = File::open(&reader_path).and_then(|mut f| f.read_to_end(&mut bytes));
        let _ = sent.send(read.map(|_| bytes));
    });
    let ran = resolve_to(&fifo);
    check("-o FIFO", &ran.out, 0, "");
    let bytes = received
        .recv_timeout(WATCHDOG)
        .expect("the reader got end of file")
        .expect("the reader read");
    assert_eq!(bytes, resolved_chain());
    let t = std::fs::symlink_metadata(&fifo).unwrap().file_type();
    assert!(t.is_fifo(), "{t:?}");
    assert!(temporaries(dir.path()).is_empty());
}

/// A symlink is written through: the file at the end of the chain gets the output, replaced
/// in its own folder, and the links stay links.
#[test]
fn a_symlink_target_stays_a_link_and_its_file_is_replaced() {
    let dir = folder("symlink");
    let real = dir.path().join("real");
    std::fs::create_dir(&real).unwrap();
    let pointee = real.join("scene.rib");
    std::fs::write(&pointee, "old").unwrap();
    std::fs::set_permissions(&pointee, std::fs::Permissions::from_mode(0o640)).unwrap();
    let link = dir.path().join("out.rib");
    symlink("real/scene.rib", &link).unwrap();
    let link2 = dir.path().join("out2.rib");
    symlink(&link, &link2).unwrap();
    let ran = resolve_to(&link2);
    check("-o symlink", &ran.out, 0, "");
    for l in [&link, &link2] {
        assert!(std::fs::symlink_metadata(l).unwrap().is_symlink(), "{l:?}");
    }
    assert_eq!(std::fs::read(&pointee).unwrap(), resolved_chain());
    assert_eq!(mode(&pointee), 0o640);
    assert!(temporaries(dir.path()).is_empty());
    assert!(temporaries(&real).is_empty());
}

/// As root: in a sticky world-writable folder (like `/tmp`), a symlink owned by another
/// user is not followed, as Linux's `protected_symlinks` keeps `>` from following it: the
/// write is refused and the file it points to is untouched. The user's own link there is
/// followed.
#[test]
fn a_foreign_symlink_in_a_shared_folder_is_not_followed() {
    if !is_root() {
        crate::common::not_run("needs root");
        return;
    }
    let dir = folder("sticky");
    let victim = dir.path().join("victim");
    std::fs::write(&victim, "precious").unwrap();
    let shared = dir.path().join("shared");
    std::fs::create_dir(&shared).unwrap();
    std::fs::set_permissions(&shared, std::fs::Permissions::from_mode(0o1777)).unwrap();
    let link = shared.join("out.rib");
    symlink(&victim, &link).unwrap();
    std::os::unix::fs::lchown(&link, Some(NOBODY), Some(NOBODY)).unwrap();
    let ran = resolve_to(&link);
    check(
        "-o foreign link in /tmp-like folder",
        &ran.out,
        1,
        "error[IO001]",
    );
    assert!(
        ran.out.stderr.contains("another user"),
        "{}",
        ran.out.stderr
    );
    assert_eq!(std::fs::read(&victim).unwrap(), b"precious");
    assert!(std::fs::symlink_metadata(&link).unwrap().is_symlink());
    assert!(temporaries(&shared).is_empty() && temporaries(dir.path()).is_empty());

    std::fs::remove_file(&link).unwrap();
    symlink(&victim, &link).unwrap();
    let ran = resolve_to(&link);
    check("-o own link in /tmp-like folder", &ran.out, 0, "");
    assert_eq!(std::fs::read(&victim).unwrap(), resolved_chain());
}

/// A 0600 file stays 0600 (before, it became 0644) and keeps its owner: as root the
/// replacement is given back to the file's owner.
#[test]
fn a_private_file_keeps_its_mode_and_owner() {
    let dir = folder("private");
    let target = dir.path().join("out.rib");
    std::fs::write(&target, "old").unwrap();
    std::fs::set_permissions(&target, std::fs::Permissions::from_mode(0o600)).unwrap();
    if is_root() {
        std::os::unix::fs::chown(&target, Some(NOBODY), Some(NOBODY)).unwrap();
    }
    let owner = std::fs::metadata(&target).unwrap();
    let ran = resolve_to(&target);
    check("-o 0600 file", &ran.out, 0, "");
    assert_eq!(std::fs::read(&target).unwrap(), resolved_chain());
    assert_eq!(mode(&target), 0o600);
    let after = std::fs::metadata(&target).unwrap();
    assert_eq!((after.uid(), after.gid()), (owner.uid(), owner.gid()));
}

/// A read-only file is refused like `>` refuses it: for a user who may not write it, exit 1
/// with the system's "Permission denied", the file byte-identical and no temporary file.
/// Root may write it, as with `>`, and its mode stays 0444. (As root, the unprivileged case
/// runs as `nobody`: [`run_unprivileged`].)
#[test]
fn a_read_only_file_is_refused_unless_root() {
    let dir = folder("readonly");
    std::fs::set_permissions(dir.path(), std::fs::Permissions::from_mode(0o777)).unwrap();
    let target = dir.path().join("out.rib");
    std::fs::write(&target, "read only").unwrap();
    std::fs::set_permissions(&target, std::fs::Permissions::from_mode(0o444)).unwrap();

    if let Some(ran) = run_unprivileged(&["resolve", "examples/chain.rib", "-o", s(&target)]) {
        check("-o read-only file", &ran.out, 1, "error[IO001]");
        assert!(
            ran.out.stderr.contains("Permission denied") && ran.out.stderr.contains(s(&target)),
            "{}",
            ran.out.stderr
        );
        assert_eq!(std::fs::read(&target).unwrap(), b"read only");
        assert_eq!(mode(&target), 0o444);
        assert!(temporaries(dir.path()).is_empty());
    }

    if is_root() {
        let ran = resolve_to(&target);
        check("-o read-only file as root", &ran.out, 0, "");
        assert_eq!(std::fs::read(&target).unwrap(), resolved_chain());
        assert_eq!(mode(&target), 0o444);
    }
}

/// A writable file in a folder the user may not write cannot be replaced atomically: it is
/// refused (exit 1, the folder named), not written in place. (As root, the case runs as
/// `nobody`: [`run_unprivileged`].)
#[test]
fn a_file_in_an_unwritable_folder_is_refused() {
    let dir = folder("lockedfolder");
    std::fs::set_permissions(dir.path(), std::fs::Permissions::from_mode(0o777)).unwrap();
    let locked = dir.path().join("locked");
    std::fs::create_dir(&locked).unwrap();
    let target = locked.join("out.rib");
    std::fs::write(&target, "old").unwrap();
    std::fs::set_permissions(&target, std::fs::Permissions::from_mode(0o666)).unwrap();
    std::fs::set_permissions(&locked, std::fs::Permissions::from_mode(0o555)).unwrap();
    if let Some(ran) = run_unprivileged(&["resolve", "examples/chain.rib", "-o", s(&target)]) {
        check("-o file in read-only folder", &ran.out, 1, "error[IO001]");
        assert!(
            ran.out.stderr.contains("cannot create a temporary file in"),
            "{}",
            ran.out.stderr
        );
        assert_eq!(std::fs::read(&target).unwrap(), b"old");
    }
    std::fs::set_permissions(&locked, std::fs::Permissions::from_mode(0o755)).unwrap();
}

/// A run that fails leaves an existing target byte-identical and no temporary file: bad
/// input (resolve and render), and a resolution that reports an error (`--deny-warnings`).
#[test]
fn a_failing_run_leaves_the_target_byte_identical() {
    let dir = folder("failing");
    let bad = dir.path().join("bad.rib");
    std::fs::write(
        &bad,
        "Pattern \"PxrLayer\" \"x\" \"float diffuseGain\" [1\n\"open",
    )
    .unwrap();
    let warns = dir.path().join("warns.rib");
    std::fs::write(
        &warns,
        "Bxdf \"PxrLayerSurface\" \"s\" \"reference struct inputMaterial\" [\"nobody:pxrMaterialOut\"]\n",
    )
    .unwrap();
    let target = dir.path().join("out.rib");
    let before: Vec<u8> = (0..=255u8).cycle().take(5000).collect();
    std::fs::write(&target, &before).unwrap();
    let image = dir.path().join("ball.png");
    std::fs::write(&image, &before).unwrap();
    let cases: [(&str, Vec<&str>, &Path, &str); 3] = [
        (
            "resolve bad input",
            vec!["resolve", s(&bad), "-o"],
            &target,
            "error[RB",
        ),
        (
            "resolve --deny-warnings",
            vec!["--deny-warnings", "resolve", s(&warns), "-o"],
            &target,
            "warning[",
        ),
        (
            "render bad input",
            vec!["render", "--size", "8", s(&bad), "-o"],
            &image,
            "error[RB",
        ),
    ];
    for (name, mut args, out, code) in cases {
        args.push(s(out));
        let ran = run_cmd(&mut vstructc(&args));
        check(name, &ran.out, 1, code);
        assert_eq!(std::fs::read(out).unwrap(), before, "{name}");
        assert!(temporaries(dir.path()).is_empty(), "{name}");
    }
}

/// As root, a character device made with `mknod` (the null device's numbers) is written in
/// place and is still the same device afterwards. (Before, `-o /dev/null` as root replaced
/// the device with a regular file.) Not run when not root or when the container forbids
/// `mknod`, and says so.
#[test]
fn a_character_device_is_written_in_place() {
    if !is_root() {
        crate::common::not_run("needs root");
        return;
    }
    let dir = folder("chardev");
    let dev = dir.path().join("null");
    let c = std::ffi::CString::new(s(&dev)).unwrap();
    let rdev = libc::makedev(1, 3);
    // SAFETY: a valid NUL-terminated path; mknod has no other preconditions.
    if unsafe { libc::mknod(c.as_ptr(), libc::S_IFCHR | 0o666, rdev) } != 0 {
        let e = std::io::Error::last_os_error();
        assert_eq!(e.raw_os_error(), Some(libc::EPERM), "mknod: {e}");
        crate::common::not_run(&format!("mknod refused here ({e})"));
        return;
    }
    for args in [
        vec!["resolve", "examples/chain.rib", "-o", s(&dev)],
        vec![
            "render",
            "--size",
            "8",
            "examples/layered.rib",
            "-o",
            s(&dev),
        ],
    ] {
        let ran = run_cmd(&mut vstructc(&args));
        check(args[0], &ran.out, 0, "");
        let m = std::fs::symlink_metadata(&dev).unwrap();
        assert!(m.file_type().is_char_device(), "{:?}", m.file_type());
        assert_eq!(m.rdev(), rdev);
        assert!(temporaries(dir.path()).is_empty());
    }
}

/// `/dev/fd/1` is a descriptor link (`/proc/self/fd/1`) to the child's stdout, a pipe:
/// written in place, the whole output arrives on the pipe. (Before, a temporary file was
/// attempted in `/dev/fd/`, and the run failed.)
#[test]
fn a_descriptor_link_is_written_in_place() {
    let ran = run_cmd(&mut vstructc(&[
        "resolve",
        "examples/chain.rib",
        "-o",
        "/dev/fd/1",
    ]));
    check("-o /dev/fd/1", &ran.out, 0, "");
    assert_eq!(ran.stdout, resolved_chain());
}

/// Symlinks planted at the temporary file's names do not change the file they point to.
///
/// The old temporary name, `.NAME.vstructc-PID.tmp`, was predictable and opened without
/// `O_EXCL`: a link planted there redirected the output into any file. The name is now
/// `.NAME.` + 12 random letters + `.tmp` (62^12 names), so a link cannot be planted at
/// every name the file could take; this test plants at the old predictable name (the
/// child's PID is known before it writes: it reads its input from a pipe first) and at a
/// sample of 200 names of the new form. What makes any hit harmless is that the file is
/// created with `O_CREAT | O_EXCL`, which refuses every existing entry, symlinks included
/// (`O_NOFOLLOW` semantics); the library's unit test
/// `back::output::tests::a_planted_symlink_at_the_temporary_name_is_never_followed` makes
/// the name fully predictable and shows that creation then fails rather than follow the link.
#[test]
fn planted_symlinks_at_temporary_names_are_not_followed() {
    let dir = folder("planted");
    let victim = dir.path().join("victim");
    std::fs::write(&victim, "precious").unwrap();
    let target = dir.path().join("out.rib");
    let input = std::fs::read(PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("examples/chain.rib"))
        .unwrap();
    let start = Instant::now();
    let mut child = vstructc(&["resolve", "-", "-o", s(&target)])
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut planted = vec![
        dir.path()
            .join(format!(".out.rib.vstructc-{}.tmp", child.id())),
    ];
    let mut rng = 0x9e37_79b9_7f4a_7c15_u64;
    let letters = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789";
    for _ in 0..200 {
        let name: String = (0..12)
            .map(|_| {
                rng ^= rng << 13;
                rng ^= rng >> 7;
                rng ^= rng << 17;
                letters[(rng % letters.len() as u64) as usize] as char
            })
            .collect();
        planted.push(dir.path().join(format!(".out.rib.{name}.tmp")));
    }
    for p in &planted {
        symlink(&victim, p).unwrap();
    }
    let mut stdin = child.stdin.take().unwrap();
    stdin.write_all(&input).unwrap();
    drop(stdin);
    let ran = wait(child, start);
    check("-o with planted links", &ran.out, 0, "");
    assert_eq!(std::fs::read(&victim).unwrap(), b"precious");
    assert_eq!(std::fs::read(&target).unwrap(), resolved_chain());
    for p in &planted {
        assert!(std::fs::symlink_metadata(p).unwrap().is_symlink());
    }
    assert_eq!(temporaries(dir.path()).len(), planted.len());
}

/// Standard output on a full disk (`> /dev/full`): every command that prints reports IO001
/// naming `<stdout>` with exit 1, never a panic (101). (Before, `info`, `compile`, `eval`
/// and `expr` panicked.)
#[test]
fn a_full_disk_on_stdout_is_io001_in_every_command() {
    let commands: &[&[&str]] = &[
        &["info", "PxrLayerMixer"],
        &["info", "--json", "PxrLayerMixer"],
        &["compile", "examples/layered.rib"],
        &["compile", "--emit", "lobes", "examples/layered.rib"],
        &[
            "eval",
            "examples/layered.rib",
            "--wo",
            "0,0,1",
            "--wi",
            "0.5,0.5,0.7",
        ],
        &[
            "eval",
            "--json",
            "examples/layered.rib",
            "--wo",
            "0,0,1",
            "--wi",
            "0.5,0.5,0.7",
        ],
        &["expr", "connect if a == 1 else ignore"],
        &["expr", "--json", "connect if a == 1 else ignore"],
        &["expr", "--json", "connect if a == else ignore"],
        &[
            "explain",
            "mixer.layer1_diffuseColor",
            "examples/layered.rib",
        ],
        &[
            "explain",
            "--json",
            "mixer.layer1_enableClearcoat",
            "examples/layered.rib",
        ],
        &["compile", "--json", "examples/layered.rib"],
        &["list"],
        &["list", "--json"],
        &["resolve", "--json", "examples/chain.rib"],
        &[
            "explain",
            "mixer.enableDiffuseAlways",
            "examples/layered.rib",
        ],
        &["resolve", "examples/chain.rib"],
        &["resolve", "--format", "json", "examples/chain.rib"],
        &["render", "--size", "8", "examples/layered.rib", "-o", "-"],
    ];
    for args in commands {
        let full = File::options().write(true).open("/dev/full").unwrap();
        let child = vstructc(args)
            .stdin(Stdio::null())
            .stdout(Stdio::from(full))
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        let ran = wait(child, Instant::now());
        let name = args.join(" ");
        check(&name, &ran.out, 1, "error[IO001]");
        assert!(
            ran.out.stderr.contains("No space left on device")
                && ran.out.stderr.contains("<stdout>"),
            "{name}: {}",
            ran.out.stderr
        );
        assert!(!ran.out.stderr.contains("panicked"), "{name}");
    }
}

/// A full disk on standard error (`2>/dev/full`) loses the messages but never panics: each
/// command ends with the exit status it would have had (1 for input errors, 2 for usage
/// errors), whether the message came from a diagnostic report or a plain `error:` line.
#[test]
fn a_full_disk_on_stderr_keeps_the_exit_status() {
    let commands: &[(&[&str], i32)] = &[
        (&["info", "NoSuchShader"], 2),
        (&["explain", "nodot", "examples/layered.rib"], 2),
        (&["explain", "ghost.input", "examples/layered.rib"], 2),
        (&["expr", "connect if a = 1"], 1),
        (&["resolve", "tests/hostile/corpus/truncated.rib"], 1),
        (
            &["resolve", "tests/hostile/corpus/cycle2.rib", "-o", "-"],
            0,
        ),
        (
            &["render", "--size", "0", "examples/layered.rib", "-o", "-"],
            2,
        ),
    ];
    for (args, status) in commands {
        let full = File::options().write(true).open("/dev/full").unwrap();
        let out = vstructc(args)
            .stdin(Stdio::null())
            .stdout(Stdio::null())
            .stderr(Stdio::from(full))
            .status()
            .unwrap();
        assert_eq!(out.code(), Some(*status), "{}", args.join(" "));
    }
}

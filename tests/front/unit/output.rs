//! Unit tests of `back::output` (`src/back/output.rs`).

use std::fs::{File, OpenOptions};
use std::io::{self, Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};
use vstructc::back::output::*;
use vstructc::diag::Error;

/// [`write_file`] for bytes already in memory.
fn write_bytes(path: &Path, data: &[u8]) -> Result<(), Error> {
    write_file(path, |out| out.write_all(data))
}
use std::os::unix::fs::{PermissionsExt, symlink};

fn folder(name: &str) -> tempfile::TempDir {
    tempfile::Builder::new()
        .prefix(&format!("vstructc-output-{name}-"))
        .tempdir()
        .expect("temporary folder")
}

fn mode(p: &Path) -> u32 {
    std::fs::metadata(p).unwrap().permissions().mode() & 0o7777
}

fn leftovers(dir: &Path) -> Vec<String> {
    std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.ends_with(".tmp"))
        .collect()
}

/// The temporary file is opened with `O_CREAT | O_EXCL`: with its name made predictable
/// (no random letters) and a symlink planted at that name, creation fails instead of
/// following the link, and the link's target is untouched. The random letters only make
/// planting unlikely to hit; this is what makes a hit harmless.
#[test]
fn a_planted_symlink_at_the_temporary_name_is_never_followed() {
    let dir = folder("plant");
    let victim = dir.path().join("victim");
    std::fs::write(&victim, "precious").unwrap();
    let target = dir.path().join("out.rib");
    let prefix = temp_prefix(&target);
    let planted = dir.path().join(format!("{}.tmp", prefix.to_string_lossy()));
    symlink(&victim, &planted).unwrap();
    let err = create_temp(dir.path(), &prefix, 0, false).unwrap_err();
    assert_eq!(err.kind(), io::ErrorKind::AlreadyExists, "{err}");
    // A dangling planted link is refused the same way (it would create the pointee).
    let absent = dir.path().join("absent");
    std::fs::remove_file(&planted).unwrap();
    symlink(&absent, &planted).unwrap();
    let err = create_temp(dir.path(), &prefix, 0, true).unwrap_err();
    assert_eq!(err.kind(), io::ErrorKind::AlreadyExists, "{err}");
    assert!(!absent.exists());
    assert_eq!(std::fs::read(&victim).unwrap(), b"precious");
}

#[test]
fn a_failing_producer_leaves_the_target_and_no_temporary_file() {
    let dir = folder("fail");
    let target = dir.path().join("out.rib");
    std::fs::write(&target, "old").unwrap();
    let err = write_file(&target, |out| {
        out.write_all(&[b'x'; 200_000])?;
        Err(io::Error::other("the producer failed"))
    })
    .unwrap_err();
    assert!(err.to_string().contains("the producer failed"), "{err}");
    assert_eq!(std::fs::read(&target).unwrap(), b"old");
    assert!(leftovers(dir.path()).is_empty());
    // Same for a target that did not exist: nothing is created.
    let fresh = dir.path().join("fresh.rib");
    assert!(write_file(&fresh, |_| Err(io::Error::other("no"))).is_err());
    assert!(!fresh.exists());
    assert!(leftovers(dir.path()).is_empty());
}

#[test]
fn a_regular_file_is_replaced_with_its_mode() {
    let dir = folder("mode");
    let target = dir.path().join("out.rib");
    std::fs::write(&target, "old").unwrap();
    std::fs::set_permissions(&target, std::fs::Permissions::from_mode(0o640)).unwrap();
    write_bytes(&target, b"new").unwrap();
    assert_eq!(std::fs::read(&target).unwrap(), b"new");
    assert_eq!(mode(&target), 0o640);
    assert!(leftovers(dir.path()).is_empty());
}

#[test]
fn a_new_file_gets_the_umask_mode_of_a_redirection() {
    let dir = folder("new");
    let made = dir.path().join("made");
    File::create(&made).unwrap();
    let target = dir.path().join("out.rib");
    write_bytes(&target, b"new").unwrap();
    assert_eq!(mode(&target), mode(&made));
}

#[test]
fn a_symlink_chain_is_written_through() {
    let dir = folder("chain");
    std::fs::create_dir(dir.path().join("real")).unwrap();
    let end = dir.path().join("real/end.rib");
    std::fs::write(&end, "old").unwrap();
    // link1 -> real/end.rib (relative), link2 -> link1 (absolute).
    let link1 = dir.path().join("link1");
    symlink("real/end.rib", &link1).unwrap();
    let link2 = dir.path().join("link2");
    symlink(&link1, &link2).unwrap();
    write_bytes(&link2, b"new").unwrap();
    assert_eq!(std::fs::read(&end).unwrap(), b"new");
    for l in [&link1, &link2] {
        assert!(std::fs::symlink_metadata(l).unwrap().is_symlink());
    }
    assert!(leftovers(&dir.path().join("real")).is_empty());
}

#[test]
fn a_dangling_symlink_creates_its_target() {
    let dir = folder("dangling");
    let link = dir.path().join("link");
    symlink("made.rib", &link).unwrap();
    write_bytes(&link, b"new").unwrap();
    assert_eq!(std::fs::read(dir.path().join("made.rib")).unwrap(), b"new");
    assert!(std::fs::symlink_metadata(&link).unwrap().is_symlink());
}

#[test]
fn a_symlink_loop_is_an_error() {
    let dir = folder("loop");
    let a = dir.path().join("a");
    let b = dir.path().join("b");
    symlink(&b, &a).unwrap();
    symlink(&a, &b).unwrap();
    let err = write_bytes(&a, b"x").unwrap_err();
    assert!(matches!(err, Error::Io { .. }), "{err}");
    assert!(std::fs::symlink_metadata(&a).unwrap().is_symlink());
}

#[test]
fn a_folder_is_refused() {
    let dir = folder("dir");
    let err = write_bytes(dir.path(), b"x").unwrap_err();
    assert!(err.to_string().contains("is a folder"), "{err}");
}

/// `/proc/self/fd/N` of a deleted file has no folder to rename in: the output is staged
/// and copied in, and a failed run leaves the file as it was.
#[cfg(target_os = "linux")]
#[test]
fn a_descriptor_link_to_a_deleted_file_is_written_in_place() {
    use std::io::Read;
    use std::os::fd::AsRawFd;
    let dir = folder("fd");
    let path = dir.path().join("deleted");
    let mut file = OpenOptions::new()
        .read(true)
        .write(true)
        .create_new(true)
        .open(&path)
        .unwrap();
    file.write_all(b"old content").unwrap();
    std::fs::remove_file(&path).unwrap();
    let link = PathBuf::from(format!("/proc/self/fd/{}", file.as_raw_fd()));
    assert!(matches!(plan(&link).unwrap(), Plan::Staged));
    assert!(write_file(&link, |_| Err(io::Error::other("no"))).is_err());
    let mut text = String::new();
    file.seek(SeekFrom::Start(0)).unwrap();
    file.read_to_string(&mut text).unwrap();
    assert_eq!(text, "old content");
    write_bytes(&link, b"new").unwrap();
    text.clear();
    file.seek(SeekFrom::Start(0)).unwrap();
    file.read_to_string(&mut text).unwrap();
    assert_eq!(text, "new");
}

/// Outputs of tens of megabytes are written to disk in steps while they are produced: the
/// file gets every byte in order, a new one or a replaced one, and a producer failing after
/// several steps leaves the old file as it was.
#[test]
fn a_large_output_written_out_in_steps_is_whole() {
    let dir = folder("large");
    let target = dir.path().join("out.rib");
    // 20 MB in writes of an odd size, each byte telling its place.
    let data: Vec<u8> = (0..20_000_017u32).map(|i| (i % 251) as u8).collect();
    let produce = |out: &mut dyn Write| data.chunks(100_003).try_for_each(|c| out.write_all(c));
    write_file(&target, produce).unwrap();
    assert!(std::fs::read(&target).unwrap() == data);
    std::fs::write(&target, "old").unwrap();
    write_file(&target, produce).unwrap();
    assert!(std::fs::read(&target).unwrap() == data);
    std::fs::write(&target, "old").unwrap();
    let failing = write_file(&target, |out| {
        produce(out)?;
        Err(io::Error::other("late failure"))
    });
    assert!(failing.is_err());
    assert_eq!(std::fs::read(&target).unwrap(), b"old");
    assert!(leftovers(dir.path()).is_empty());
}

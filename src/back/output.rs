//! Writing an output file safely: the one way every command writes a file, for bridges too.
//!
//! [`write_file`] hands the producer a buffered writer and decides, from what the target path
//! names, how the bytes reach it:
//!
//! * **A regular file, or nothing yet**: the output goes into a temporary file created in the
//!   target's folder, which is renamed over the target only when everything succeeded. A run
//!   that fails for any reason (the producer's error, a full disk, a failed rename) removes
//!   the temporary file and leaves an existing target byte-identical.
//! * **The temporary file** is created exclusively (`O_CREAT | O_EXCL`, mode 0600) under an
//!   unpredictable name, `.NAME.` + random letters + `.tmp`, by the `tempfile` crate. With
//!   `O_EXCL` the kernel refuses any existing entry at that name, a symlink included, so a link
//!   planted there is never followed (the crate tries another name).
//! * **A symlink** is written through: the link chain is followed to its end and the file at
//!   the end is replaced atomically in its own folder; the links stay links. A dangling link
//!   creates the file it points to, as a shell redirection (`>`) does; a chain longer than 40
//!   links is an error. As Linux's `protected_symlinks` does for `>`, a link in a sticky
//!   world-writable folder (`/tmp`) owned by neither the user nor the folder's owner is not
//!   followed: the write is refused.
//! * **A character or block device, a FIFO or a socket** (`/dev/null`, `/dev/stdout`,
//!   `-o >(gzip)`, which is `/dev/fd/N`) is opened for writing without truncation and written
//!   in place: no temporary file, the node itself is never replaced. Output already written
//!   to such a target when a run fails cannot be taken back.
//! * **A regular file reachable only through a descriptor link** (`/dev/fd/N` or
//!   `/proc/PID/fd/N` naming a deleted or anonymous file, which has no folder to rename in):
//!   the output is first produced into an unnamed temporary file, then copied into the target,
//!   truncated, only when everything succeeded.
//! * **Permissions**: a replaced file keeps its permission bits (set-user-ID, set-group-ID and
//!   sticky bits included) and, where the process may set it (`fchown`: root, or a group the
//!   user belongs to), its owner and group. When the owner or group cannot be kept, the
//!   set-user-ID or set-group-ID bit is dropped rather than granted to the new owner. A new
//!   file gets `0666` minus the umask, as `>` gives. Access control lists and extended
//!   attributes are not copied.
//! * **A target the process may not write** (a read-only file for a non-root user, a file in
//!   a folder it may not write) is refused before anything is produced, with the operating
//!   system's message, as a shell redirection refuses it: the target is opened for writing
//!   without truncation as a probe. Root may write a read-only file, as with `>`; its mode
//!   stays as it was.
//! * A replaced file is a new inode: other hard links to the old file keep the old content.
//!   A process killed by a signal mid-write may leave its temporary file behind.
//!
//! [`write_stdout`] is the same producer interface for standard output: a write error (a full
//! disk, an I/O error) is returned as [`Error::Io`] naming `<stdout>`. A closed pipe is not
//! seen here when the process keeps SIGPIPE's default disposition (the `vstructc` binary
//! does): the write ends the process, as it ends `cat`.

use crate::diag::Error;
use std::ffi::OsString;
use std::fs::{File, Metadata, OpenOptions};
use std::io::{self, BufWriter, Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};

/// The name used for standard output in errors.
pub(crate) const STDOUT_NAME: &str = "<stdout>";

/// The longest symlink chain followed to find the file to replace (Linux's own limit).
pub(crate) const MAX_SYMLINK_CHAIN: usize = 40;

/// Capacity of the buffer between the producer and the file.
const BUFFER: usize = 1 << 16;

/// Random letters in a temporary file's name (62^12 ≈ 3·10^21 names).
const RANDOM_LETTERS: usize = 12;

/// Write the output of `produce` to `path` by the rules of the [module](self): a regular
/// file is replaced atomically, a device, FIFO or socket is written in place, a symlink is
/// written through. Errors name `path` (as given) and say what failed.
pub fn write_file(
    path: &Path,
    produce: impl FnOnce(&mut dyn Write) -> io::Result<()>,
) -> Result<(), Error> {
    write_to(path, produce).map_err(|source| Error::Io {
        path: path.to_path_buf(),
        source,
    })
}

/// [`write_file`] for bytes already in memory (the unit tests' shorthand).
#[cfg(test)]
fn write_bytes(path: &Path, data: &[u8]) -> Result<(), Error> {
    write_file(path, |out| out.write_all(data))
}

/// Write the output of `produce` to standard output (buffered, flushed at the end). Write
/// errors are [`Error::Io`] naming `<stdout>`.
pub fn write_stdout(produce: impl FnOnce(&mut dyn Write) -> io::Result<()>) -> Result<(), Error> {
    let mut out = BufWriter::with_capacity(BUFFER, io::stdout().lock());
    produce(&mut out)
        .and_then(|()| out.flush())
        .map_err(|source| Error::Io {
            path: PathBuf::from(STDOUT_NAME),
            source,
        })
}

/// How the bytes reach a target.
#[derive(Debug)]
enum Plan {
    /// Rename a temporary file over `real` (the end of the link chain); `existing` is the
    /// metadata of the regular file there, if any.
    Replace {
        real: PathBuf,
        existing: Option<Metadata>,
    },
    /// Open the path itself for writing and write in place (devices, FIFOs, sockets).
    InPlace,
    /// A regular file without a folder to rename in (a descriptor link to a deleted or
    /// anonymous file): stage the output, then copy it in.
    Staged,
}

fn write_to(path: &Path, produce: impl FnOnce(&mut dyn Write) -> io::Result<()>) -> io::Result<()> {
    match plan(path)? {
        Plan::Replace { real, existing } => replace(&real, existing.as_ref(), produce),
        Plan::InPlace => in_place(path, produce),
        Plan::Staged => staged(path, produce),
    }
}

/// Decide how to write `path` from what it names now.
fn plan(path: &Path) -> io::Result<Plan> {
    match std::fs::metadata(path) {
        Ok(m) if m.is_dir() => Err(io::Error::new(
            io::ErrorKind::IsADirectory,
            "is a folder, not a file",
        )),
        Ok(m) if m.is_file() => {
            let real = follow_links(path)?;
            match std::fs::symlink_metadata(&real) {
                Ok(r) if r.is_file() && same_file(&m, &r) => Ok(Plan::Replace {
                    real,
                    existing: Some(r),
                }),
                _ => Ok(Plan::Staged),
            }
        }
        Ok(_) => Ok(Plan::InPlace),
        Err(e) if e.kind() == io::ErrorKind::NotFound => Ok(Plan::Replace {
            real: follow_links(path)?,
            existing: None,
        }),
        Err(e) => Err(e),
    }
}

/// The path at the end of `path`'s symlink chain (or `path` itself). A link's relative
/// target is taken relative to the link's folder; a missing entry ends the chain (a
/// dangling link names the file to create).
fn follow_links(path: &Path) -> io::Result<PathBuf> {
    let mut p = path.to_path_buf();
    for _ in 0..=MAX_SYMLINK_CHAIN {
        match std::fs::symlink_metadata(&p) {
            Ok(m) if m.file_type().is_symlink() => {
                refuse_foreign_link_in_shared_folder(&p, &m)?;
                let to = std::fs::read_link(&p)?;
                p = match p.parent() {
                    Some(dir) => dir.join(to),
                    None => to,
                };
            }
            Ok(_) => return Ok(p),
            Err(e) if e.kind() == io::ErrorKind::NotFound => return Ok(p),
            Err(e) => return Err(e),
        }
    }
    Err(io::Error::other(format!(
        "more than {MAX_SYMLINK_CHAIN} symbolic links to follow"
    )))
}

/// Linux's `protected_symlinks` rule, which following links by hand would bypass: in a
/// sticky world-writable folder (`/tmp`), a symlink is followed only when it belongs to the
/// process's user or to the folder's owner. Otherwise anyone could plant `/tmp/out.rib`
/// pointing at a file of the user running vstructc, and `-o /tmp/out.rib` would replace it.
#[cfg(unix)]
fn refuse_foreign_link_in_shared_folder(link: &Path, meta: &Metadata) -> io::Result<()> {
    use std::os::unix::fs::MetadataExt;
    let Ok(folder) = std::fs::metadata(folder_of(link)) else {
        return Ok(());
    };
    let shared = folder.mode() & 0o1002 == 0o1002;
    // SAFETY: geteuid has no preconditions.
    let me = unsafe { libc::geteuid() };
    if shared && meta.uid() != me && meta.uid() != folder.uid() {
        return Err(io::Error::new(
            io::ErrorKind::PermissionDenied,
            format!(
                "{} is a symlink of another user in a shared folder: not followed",
                link.display()
            ),
        ));
    }
    Ok(())
}

#[cfg(not(unix))]
fn refuse_foreign_link_in_shared_folder(_: &Path, _: &Metadata) -> io::Result<()> {
    Ok(())
}

#[cfg(unix)]
fn same_file(a: &Metadata, b: &Metadata) -> bool {
    use std::os::unix::fs::MetadataExt;
    (a.dev(), a.ino()) == (b.dev(), b.ino())
}

#[cfg(not(unix))]
fn same_file(_: &Metadata, _: &Metadata) -> bool {
    true
}

/// `io::Error` with `what` in front of its message, keeping its kind.
fn context(e: io::Error, what: impl std::fmt::Display) -> io::Error {
    io::Error::new(e.kind(), format!("{what}: {e}"))
}

/// The folder a temporary file for `real` is created in (`.` for a bare name).
fn folder_of(real: &Path) -> &Path {
    real.parent()
        .filter(|d| !d.as_os_str().is_empty())
        .unwrap_or(Path::new("."))
}

/// The temporary file's name pattern: `prefix` (`.NAME.`, see [`temp_prefix`]) + `random`
/// random letters + `.tmp`.
fn temp_builder(prefix: &OsString, random: usize) -> tempfile::Builder<'_, 'static> {
    let mut b = tempfile::Builder::new();
    b.prefix(prefix).suffix(".tmp").rand_bytes(random);
    b
}

/// `.NAME.` for a target named `NAME`: hidden, and recognisably the target's.
fn temp_prefix(real: &Path) -> OsString {
    let mut prefix = OsString::from(".");
    prefix.push(real.file_name().unwrap_or("output".as_ref()));
    prefix.push(".");
    prefix
}

/// Create the temporary file in `folder` (exclusively; see the module docs). A `new_file`
/// gets the mode a new file would get; a replacement starts private (0600) and gets the old
/// file's mode once written.
fn create_temp(
    folder: &Path,
    prefix: &OsString,
    random: usize,
    new_file: bool,
) -> io::Result<tempfile::NamedTempFile> {
    let mut builder = temp_builder(prefix, random);
    #[cfg(unix)]
    if new_file {
        // `0666` minus the umask, as `open(O_CREAT)` gives a shell redirection.
        use std::os::unix::fs::PermissionsExt;
        builder.permissions(std::fs::Permissions::from_mode(0o666));
    }
    #[cfg(not(unix))]
    let _ = new_file;
    builder.tempfile_in(folder)
}

/// Produce into a temporary file beside `real`, give it the old file's owner and mode, and
/// rename it over `real`. The temporary file is removed on every failure (dropping a
/// `NamedTempFile` deletes it).
fn replace(
    real: &Path,
    existing: Option<&Metadata>,
    produce: impl FnOnce(&mut dyn Write) -> io::Result<()>,
) -> io::Result<()> {
    if existing.is_some() {
        // The probe a shell redirection amounts to: may this process write the file?
        OpenOptions::new().write(true).open(real)?;
    }
    let folder = folder_of(real);
    let mut tmp = create_temp(
        folder,
        &temp_prefix(real),
        RANDOM_LETTERS,
        existing.is_none(),
    )
    .map_err(|e| {
        context(
            e,
            format_args!("cannot create a temporary file in {}", folder.display()),
        )
    })?;
    produce_into(tmp.as_file_mut(), produce)?;
    if let Some(m) = existing {
        keep_owner_and_mode(tmp.as_file(), m)?;
    }
    tmp.as_file().sync_all()?;
    tmp.persist(real).map_err(|e| {
        context(
            e.error,
            format_args!("cannot rename the temporary file to {}", real.display()),
        )
    })?;
    Ok(())
}

/// Run `produce` into `file` through a buffer and flush it.
fn produce_into(
    file: &mut File,
    produce: impl FnOnce(&mut dyn Write) -> io::Result<()>,
) -> io::Result<()> {
    let mut out = BufWriter::with_capacity(BUFFER, file);
    produce(&mut out)?;
    out.flush()
}

/// Give `file` the owner, group and permission bits of `old` (as far as allowed).
#[cfg(unix)]
fn keep_owner_and_mode(file: &File, old: &Metadata) -> io::Result<()> {
    use std::os::unix::fs::{MetadataExt, PermissionsExt, fchown};
    let mut mode = old.mode() & 0o7777;
    let now = file.metadata()?;
    if (now.uid(), now.gid()) != (old.uid(), old.gid()) {
        // Root may give the file back to its owner; a user may at least keep the group
        // when it is one of theirs. Failing both is not an error: the file is theirs.
        if fchown(file, Some(old.uid()), Some(old.gid())).is_err() {
            let _ = fchown(file, None, Some(old.gid()));
        }
        let now = file.metadata()?;
        if now.uid() != old.uid() {
            mode &= !0o4000;
        }
        if now.gid() != old.gid() {
            mode &= !0o2000;
        }
    }
    // After `fchown`, which clears the set-ID bits.
    file.set_permissions(std::fs::Permissions::from_mode(mode))
}

#[cfg(not(unix))]
fn keep_owner_and_mode(file: &File, old: &Metadata) -> io::Result<()> {
    file.set_permissions(old.permissions())
}

/// Write into a device, FIFO or socket: open it (no creation, no truncation) and write.
fn in_place(path: &Path, produce: impl FnOnce(&mut dyn Write) -> io::Result<()>) -> io::Result<()> {
    let mut file = OpenOptions::new().write(true).open(path)?;
    produce_into(&mut file, produce)
}

/// Produce into an unnamed temporary file, then copy into `path` (opened before producing,
/// truncated only after success).
fn staged(path: &Path, produce: impl FnOnce(&mut dyn Write) -> io::Result<()>) -> io::Result<()> {
    let mut target = OpenOptions::new().write(true).open(path)?;
    let mut stage = tempfile::tempfile()
        .map_err(|e| context(e, "cannot create a temporary file to stage the output"))?;
    produce_into(&mut stage, produce)?;
    stage.seek(SeekFrom::Start(0))?;
    target.set_len(0)?;
    target.seek(SeekFrom::Start(0))?;
    io::copy(&mut stage, &mut target)?;
    target.flush()
}

#[cfg(all(test, unix))]
mod tests {
    use super::*;
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
}

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
//! * **Durability**: the temporary file is flushed to disk (`fsync`) before the rename. On
//!   Linux the kernel is asked to start writing it out every few megabytes while it is
//!   produced, so that flush waits for the last part only.
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
#[cfg_attr(feature = "testkit", visibility::make(pub))]
enum Plan {
    /// Rename a temporary file over `real` (the end of the link chain); `existing` is the
    /// metadata of the regular file there, if any.
    Replace {
        /// The file to replace.
        real: PathBuf,
        /// The regular file there now, if any.
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
#[cfg_attr(feature = "testkit", visibility::make(pub))]
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
#[cfg_attr(feature = "testkit", visibility::make(pub))]
fn temp_prefix(real: &Path) -> OsString {
    let mut prefix = OsString::from(".");
    prefix.push(real.file_name().unwrap_or("output".as_ref()));
    prefix.push(".");
    prefix
}

/// Create the temporary file in `folder` (exclusively; see the module docs). A `new_file`
/// gets the mode a new file would get; a replacement starts private (0600) and gets the old
/// file's mode once written.
#[cfg_attr(feature = "testkit", visibility::make(pub))]
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
    produce_into_new(tmp.as_file_mut(), produce)?;
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
    produce_into_writer(file, produce)
}

/// [`produce_into`] a new temporary `file` (written from its start), asking the kernel to
/// start writing the output to disk every [`WRITEBACK_STEP`] bytes: the `fsync` before the
/// rename then waits for the last few megabytes, not for the whole output, which the disk
/// took while the rest was produced.
fn produce_into_new(
    file: &mut File,
    produce: impl FnOnce(&mut dyn Write) -> io::Result<()>,
) -> io::Result<()> {
    let mut early = EarlyWriteback {
        file,
        written: 0,
        started: 0,
    };
    produce_into_writer(&mut early, produce)
}

/// [`produce_into`] for any writer.
fn produce_into_writer(
    w: &mut dyn Write,
    produce: impl FnOnce(&mut dyn Write) -> io::Result<()>,
) -> io::Result<()> {
    let mut out = BufWriter::with_capacity(BUFFER, w);
    produce(&mut out)?;
    out.flush()
}

/// Bytes written to a temporary file between two requests to start writing it to disk.
const WRITEBACK_STEP: u64 = 8 << 20;

/// A file written from its start that has the kernel start writing out every
/// [`WRITEBACK_STEP`] bytes it receives (Linux's `sync_file_range`; elsewhere a plain file).
struct EarlyWriteback<'f> {
    file: &'f mut File,
    /// Bytes written so far: the file's length.
    written: u64,
    /// Where the bytes not yet handed to the disk start.
    started: u64,
}

impl EarlyWriteback<'_> {
    /// Starts writing out the bytes from `started` to `written`. Only a hint: a failure
    /// leaves the work to the `fsync` that follows.
    #[cfg(target_os = "linux")]
    fn start_writeback(&mut self) {
        use std::os::fd::AsRawFd;
        let (Ok(from), Ok(len)) = (
            i64::try_from(self.started),
            i64::try_from(self.written - self.started),
        ) else {
            return;
        };
        // SAFETY: the descriptor is open for the borrow of `file`; the call reads no memory
        // of this process and only starts the write-out of dirty pages in the range.
        let _ = unsafe {
            libc::sync_file_range(
                self.file.as_raw_fd(),
                from,
                len,
                libc::SYNC_FILE_RANGE_WRITE,
            )
        };
        self.started = self.written;
    }

    #[cfg(not(target_os = "linux"))]
    fn start_writeback(&mut self) {
        self.started = self.written;
    }
}

impl Write for EarlyWriteback<'_> {
    fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
        let n = self.file.write(buf)?;
        self.written += n as u64;
        if self.written - self.started >= WRITEBACK_STEP {
            self.start_writeback();
        }
        Ok(n)
    }

    fn flush(&mut self) -> io::Result<()> {
        self.file.flush()
    }
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
    produce_into_new(&mut stage, produce)?;
    stage.seek(SeekFrom::Start(0))?;
    target.set_len(0)?;
    target.seek(SeekFrom::Start(0))?;
    io::copy(&mut stage, &mut target)?;
    target.flush()
}

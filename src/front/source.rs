//! Reading input bytes with bounds: definition files and networks come from paths the user
//! (or a folder someone else controls) names, so what a path names decides how it is read.
//!
//! * `read_regular_file` reads only a regular file (after following symlinks) of at most a
//!   given size. It opens without blocking, so a FIFO with that name is refused instead of
//!   waiting forever for a writer, and it checks the opened file, not the name, so a file
//!   swapped after a folder walk is judged as what is actually read. Definitions are read
//!   this way (at most [`crate::limits::Limits::definition_file_bytes`]).
//! * [`read_stream`] reads a stream (standard input, a FIFO, a device) up to a cap: such an
//!   input is legitimate for a network (`gen | vstructc resolve -`), but `/dev/zero` must not
//!   fill the memory. The command line caps every network input at
//!   [`crate::limits::Limits::network_file_bytes`]: a regular file by its size before it is
//!   read, a stream when the limit is passed.

use std::fs::{File, FileType};
use std::io::{self, Read};
use std::path::Path;

/// Why bytes could not be read.
#[derive(Debug, thiserror::Error)]
pub enum ReadError {
    /// The path names something other than a regular file (a FIFO, a device, a socket, a
    /// folder).
    #[error("not a regular file but {kind}: not read")]
    NotRegular {
        /// What it is, with an article (`a FIFO`, `a character device`, ...).
        kind: &'static str,
    },
    /// The input is larger than the limit.
    #[error("{}", too_large_message(*.size, *.limit, *.at_least))]
    TooLarge {
        /// The input's size in bytes (for a stream: the bytes read before stopping).
        size: u64,
        /// The limit in bytes.
        limit: u64,
        /// True for a stream, whose full size is unknown: `size` is a lower bound.
        at_least: bool,
    },
    /// The operating system refused.
    #[error("{0}")]
    Io(#[from] io::Error),
}

fn too_large_message(size: u64, limit: u64, at_least: bool) -> String {
    let limit = format!("the limit of {} ({limit} bytes)", human_size(limit));
    if at_least {
        format!("more than {limit}")
    } else {
        format!("{size} bytes, more than {limit}")
    }
}

/// `bytes` in the largest binary unit that keeps it at least 1 (`64 MiB`, `1.5 GiB`).
#[cfg_attr(feature = "testkit", visibility::make(pub))]
pub(crate) fn human_size(bytes: u64) -> String {
    const UNITS: [&str; 4] = ["KiB", "MiB", "GiB", "TiB"];
    if bytes < 1024 {
        return format!("{bytes} B");
    }
    let mut value = bytes as f64 / 1024.0;
    let mut unit = 0;
    while value >= 1024.0 && unit + 1 < UNITS.len() {
        value /= 1024.0;
        unit += 1;
    }
    if value.fract() == 0.0 {
        format!("{value:.0} {}", UNITS[unit])
    } else {
        format!("{value:.1} {}", UNITS[unit])
    }
}

/// What a file type is, with an article, for messages.
pub(crate) fn kind_name(t: FileType) -> &'static str {
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt;
        if t.is_fifo() {
            return "a FIFO";
        }
        if t.is_char_device() {
            return "a character device";
        }
        if t.is_block_device() {
            return "a block device";
        }
        if t.is_socket() {
            return "a socket";
        }
    }
    if t.is_dir() {
        "a folder"
    } else if t.is_symlink() {
        "a symbolic link"
    } else if t.is_file() {
        "a regular file"
    } else {
        "a special file"
    }
}

/// Open `path` for reading without waiting for a FIFO's writer.
fn open_nonblocking(path: &Path) -> io::Result<File> {
    let mut options = std::fs::OpenOptions::new();
    options.read(true);
    #[cfg(unix)]
    {
        use std::os::unix::fs::OpenOptionsExt;
        // Reads of a regular file never block, so the flag changes nothing for them; it only
        // keeps `open` of a FIFO from waiting for a writer.
        options.custom_flags(libc::O_NONBLOCK);
    }
    options.open(path)
}

/// Open `path` (symlinks followed) for reading if it is a regular file; returns the file and
/// its size. Never waits: a FIFO is refused, not opened for a writer to come.
pub(crate) fn open_regular(path: &Path) -> Result<(File, u64), ReadError> {
    let file = open_nonblocking(path)?;
    let meta = file.metadata()?;
    if !meta.is_file() {
        return Err(ReadError::NotRegular {
            kind: kind_name(meta.file_type()),
        });
    }
    Ok((file, meta.len()))
}

/// Read the regular file `path` (symlinks followed) if it holds at most `limit` bytes.
#[cfg_attr(feature = "testkit", visibility::make(pub))]
pub(crate) fn read_regular_file(path: &Path, limit: u64) -> Result<Vec<u8>, ReadError> {
    let (file, len) = open_regular(path)?;
    if len > limit {
        return Err(ReadError::TooLarge {
            size: len,
            limit,
            at_least: false,
        });
    }
    // The file may grow after the check: never read more than the limit.
    read_stream(file, limit)
}

/// Read `reader` to its end, failing once more than `limit` bytes arrive (what was read is
/// dropped; at most `limit + 1` bytes are held).
pub fn read_stream(reader: impl Read, limit: u64) -> Result<Vec<u8>, ReadError> {
    let mut bytes = Vec::new();
    reader
        .take(limit.saturating_add(1))
        .read_to_end(&mut bytes)?;
    let read = bytes.len() as u64;
    if read > limit {
        return Err(ReadError::TooLarge {
            size: limit,
            limit,
            at_least: true,
        });
    }
    Ok(bytes)
}

//! The `vstructc` command-line program. The command line ([`cli`]) belongs to this binary,
//! not to the library: a crate embedding vstructc builds none of it (feature `cli`).

mod cli;

// Reading definitions and networks allocates many small strings; mimalloc makes that about
// 15 % faster end to end than the system allocator. The library itself
// does not choose an allocator: bridges embedding it keep their own.
#[global_allocator]
static ALLOCATOR: mimalloc::MiMalloc = mimalloc::MiMalloc;

fn main() -> std::process::ExitCode {
    restore_default_sigpipe();
    purge_freed_memory_at_once();
    cli::main()
}

// mimalloc's own API (linked in through the `mimalloc` crate).
unsafe extern "C" {
    fn mi_option_set(option: std::ffi::c_int, value: std::ffi::c_long);
}

/// `mi_option_purge_delay` in mimalloc's `mi_option_t` (the same in its v2 and v3).
const MI_OPTION_PURGE_DELAY: std::ffi::c_int = 15;

/// Returns memory freed while reading and resolving to the system at once instead of after
/// mimalloc's default delay (a second): a run lasts about that long, and the temporaries of
/// one step would otherwise stay resident under the peak of the next (about 6 MB of the
/// 150 MB peak of a 10,000-material scene). A `MIMALLOC_PURGE_DELAY` set in the environment
/// still wins.
fn purge_freed_memory_at_once() {
    if std::env::var_os("MIMALLOC_PURGE_DELAY").is_none() {
        // SAFETY: a plain setter of a global option, valid at any time; the option index
        // is the one of the mimalloc version linked.
        unsafe { mi_option_set(MI_OPTION_PURGE_DELAY, 0) }
    }
}

/// Lets a closed output pipe end the program quietly, as it ends `cat` or `grep`
/// (`vstructc info PxrLayer | head`). Rust ignores SIGPIPE, so a write to a closed pipe
/// fails instead, and `println!` turns that failure into a panic.
fn restore_default_sigpipe() {
    #[cfg(unix)]
    // SAFETY: called first in `main`, before any other thread exists; SIG_DFL is a valid
    // disposition for SIGPIPE.
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
}

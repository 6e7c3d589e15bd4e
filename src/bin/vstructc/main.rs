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
    cli::main()
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

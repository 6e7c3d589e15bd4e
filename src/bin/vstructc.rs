//! The `vstructc` command-line program: a thin wrapper over [`vstructc::cli`].

// Reading definitions and networks allocates many small strings; mimalloc makes that about
// 15 % faster end to end than the system allocator (see BENCHMARKS.md). The library itself
// does not choose an allocator: bridges embedding it keep their own.
#[global_allocator]
static ALLOCATOR: mimalloc::MiMalloc = mimalloc::MiMalloc;

fn main() -> std::process::ExitCode {
    vstructc::cli::main()
}

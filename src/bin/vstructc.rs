//! The `vstructc` command-line program: a thin wrapper over [`vstructc::cli`].

fn main() -> std::process::ExitCode {
    vstructc::cli::main()
}

//! The `vibrofem` command-line program: everything is in [`vibrofem::app::cli`] (exit codes
//! there).

fn main() -> std::process::ExitCode {
    vibrofem::app::cli::main()
}

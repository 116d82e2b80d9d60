//! The `ternary` command line: parses arguments and calls the library.

mod bench;
mod cli;

fn main() -> std::process::ExitCode {
    cli::main()
}

//! The `aabench` command line; its arguments and commands are [`aabench::cli`].

fn main() -> std::process::ExitCode {
    aabench::cli::main()
}

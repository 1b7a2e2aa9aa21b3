//! The `gcr` program: parses the arguments, runs one subcommand, maps errors to exit codes
//! (0 success, 1 an error, 2 a usage error; `--help` and `--version` exit 0).

fn main() {
    if let Err(e) = gcr_cli::run(std::env::args_os()) {
        std::process::exit(gcr_cli::report(&e));
    }
}

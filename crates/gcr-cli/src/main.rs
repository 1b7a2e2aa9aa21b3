//! The `gcr` program: parses the arguments, runs one subcommand, maps errors to exit codes
//! (0 success, 1 an error, 2 a usage error, 130 interrupted; `--help` and `--version` exit 0).

fn main() {
    gcr_cli::stop_cleanly_on_signals();
    if let Err(e) = gcr_cli::run(std::env::args_os()) {
        std::process::exit(gcr_cli::report(&e));
    }
}

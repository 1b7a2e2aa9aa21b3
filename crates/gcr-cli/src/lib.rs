//! The `gcr` command-line program as a library: [`run`] parses the arguments and dispatches to one
//! function per subcommand ([`scenes`], [`solve`], [`reference`](mod@reference), [`merge`]). `main.rs` only calls it, and
//! tests can run the program in-process.

pub mod args;
pub mod merge;
pub mod progress;
pub mod reference;
pub mod scenes;
pub mod solve;

use args::{Cli, Command};
use clap::Parser;
use std::ffi::OsString;

/// Exit code of a run that failed on its input or output.
pub const EXIT_ERROR: i32 = 1;
/// Exit code of a command line that does not parse (clap's).
pub const EXIT_USAGE: i32 = 2;

/// Exit code of a run stopped by SIGINT, SIGTERM or SIGHUP (128 + SIGINT, as shells report
/// Ctrl-C).
pub const EXIT_INTERRUPTED: i32 = 130;

/// Makes SIGINT (Ctrl-C), SIGTERM and SIGHUP stop the program cleanly: the temporary files of
/// outputs not yet committed are removed (a commit in progress finishes first), a line says so,
/// and the exit code is [`EXIT_INTERRUPTED`]. Without it they stayed behind as hidden
/// `.NAME.gcr-PID-N.tmp` files. Called by `main` (not by [`run`], which tests call in-process).
pub fn stop_cleanly_on_signals() {
    let installed = ctrlc::set_handler(|| {
        gcr::output::remove_temporary_files();
        eprintln!("\ninterrupted: temporary files removed, no target half written");
        std::process::exit(EXIT_INTERRUPTED);
    });
    if let Err(e) = installed {
        eprintln!("warning: signals will not clean up temporary files: {e}");
    }
}

/// Runs `gcr` with `args` (the first is the program name, as in `std::env::args_os`).
/// A command line that does not parse (and `--help`, `--version`) is returned as a
/// [`clap::Error`] inside the error; [`report`] prints it.
pub fn run(args: impl IntoIterator<Item = impl Into<OsString> + Clone>) -> anyhow::Result<()> {
    let cli = Cli::try_parse_from(args)?;
    match cli.command {
        Command::Scenes => scenes::run(),
        Command::Solve(a) => solve::run(&a),
        Command::Reference(a) => reference::run(&a),
        Command::Merge(a) => merge::run(&a),
    }
}

/// Prints an error of [`run`] to stderr and returns the exit code: clap's usage errors, help and
/// version as clap prints them (2, or 0 for help/version), every other error as
/// `error: <message>: <cause>…` (1).
pub fn report(e: &anyhow::Error) -> i32 {
    if let Some(clap) = e.downcast_ref::<clap::Error>() {
        let _ = clap.print();
        return if clap.use_stderr() { EXIT_USAGE } else { 0 };
    }
    eprintln!("error: {}", gcr::error_message(e.as_ref()));
    EXIT_ERROR
}

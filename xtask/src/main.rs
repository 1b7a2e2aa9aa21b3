//! `cargo xtask figures` regenerates the dissertation's figures into `docs/results/figures/`;
//! `cargo xtask bench` runs the time-against-error benchmarks and writes `docs/results/benchmarks*.md`.

mod bench;
mod ctx;
mod figures;
#[allow(dead_code)] // used by the figure and benchmark groups as they land
mod plot;

use anyhow::Result;
use clap::{Parser, Subcommand};
use ctx::Ctx;
use std::path::PathBuf;

#[derive(Parser)]
#[command(name = "xtask", about = "GCR project automation")]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Regenerate the dissertation's figures (PNG) into docs/results/figures/.
    Figures {
        /// Small sizes: a smoke run that finishes in seconds (CI runs this).
        #[arg(long)]
        quick: bool,
        /// Only the figure groups whose name contains this text (e.g. `isgcs`, `gauss`).
        #[arg(long)]
        only: Option<String>,
        /// Output folder (default docs/results/figures; with --quick target/figures-quick, so that a smoke
        /// run never overwrites the committed figures).
        #[arg(long)]
        out: Option<PathBuf>,
    },
    /// Benchmarks: time against error, scaling curves; writes docs/results/benchmarks*.md.
    Bench {
        /// Small sizes: a smoke run.
        #[arg(long)]
        quick: bool,
        /// Only the benchmark groups whose name contains this text.
        #[arg(long)]
        only: Option<String>,
        /// Output folder (default docs/results; with --quick target/bench-quick, so that a smoke run never
        /// overwrites the committed reports).
        #[arg(long)]
        out: Option<PathBuf>,
    },
    /// Internal (run by `bench --only scenes`): peak memory of building `random_boxes(N, 1)` and its BVH,
    /// printed as one JSON line. A separate process per size, so that each peak is that size's own.
    #[command(hide = true)]
    MemProbe {
        /// Number of random boxes' triangles to ask `random_boxes` for.
        triangles: usize,
    },
}

/// Where a run writes without `--out`: the committed folder, or a scratch one for a smoke run.
fn default_out(quick: bool, full: &str, smoke: &str) -> PathBuf {
    PathBuf::from(if quick { smoke } else { full })
}

fn main() -> Result<()> {
    let cli = Cli::parse();
    match cli.command {
        Command::Figures { quick, only, out } => {
            let out = out.unwrap_or_else(|| {
                default_out(quick, "docs/results/figures", "target/figures-quick")
            });
            std::fs::create_dir_all(&out)?;
            figures::run(&Ctx { quick, out }, only.as_deref())
        }
        Command::Bench { quick, only, out } => {
            let out =
                out.unwrap_or_else(|| default_out(quick, "docs/results", "target/bench-quick"));
            std::fs::create_dir_all(&out)?;
            bench::run(&Ctx { quick, out }, only.as_deref())
        }
        Command::MemProbe { triangles } => bench::mem_probe(triangles),
    }
}

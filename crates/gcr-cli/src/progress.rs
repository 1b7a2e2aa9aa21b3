//! Progress on stderr: one line, rewritten in place, with the solver's phase, the network sizes
//! and the elapsed time. No remaining-time estimate: the last FEM step and the output gather are
//! not predictable from the training progress.

use gcr::{Metrics, Progress};
use std::io::Write;

/// Prints solver progress to stderr unless quiet.
pub struct ProgressLine {
    quiet: bool,
    shown: bool,
}

impl ProgressLine {
    /// A progress line; `quiet` prints nothing at all.
    pub fn new(quiet: bool) -> Self {
        Self {
            quiet,
            shown: false,
        }
    }

    /// Shows the solver's state (the observer of `gcr::solve`).
    pub fn update(&mut self, p: &Progress) {
        if self.quiet {
            return;
        }
        self.shown = true;
        let mut err = std::io::stderr().lock();
        let _ = write!(
            err,
            "\r{:>8} kernel {:>5}/{} cells  shading {:>4}  samples {:>6}  FEM {:>3}  {:>6.1} s   ",
            p.phase,
            p.kernel_cells,
            p.kernel_budget,
            p.shading_cells,
            p.samples,
            p.fem_steps,
            p.elapsed
        );
        let _ = err.flush();
    }

    /// Ends the progress line before the outputs are written.
    pub fn solved(&mut self) {
        if !self.quiet && self.shown {
            eprintln!();
            self.shown = false;
        }
    }

    /// The summary after the outputs are written.
    pub fn done(&mut self, m: &Metrics) {
        self.solved();
        if !self.quiet {
            let error = m.relative_std_error.map_or(String::new(), |e| {
                format!(", estimated error {:.2} % (standard error)", 100.0 * e)
            });
            let rays = if m.gather_rays > 0 {
                format!(", {} rays per point", m.gather_rays)
            } else {
                String::new()
            };
            if m.stopped_by == "unused" {
                eprintln!(
                    "done: {} gather{rays} (no networks: nothing reads them), {:.1} s{error}",
                    m.gather, m.seconds.total
                );
            } else {
                eprintln!(
                    "done: {} kernel cells, {} shading cells, {} FEM steps, {} gather{rays}, \
                     {:.1} s{error}",
                    m.kernel_cells, m.shading_cells, m.fem_steps, m.gather, m.seconds.total
                );
            }
        }
    }
}

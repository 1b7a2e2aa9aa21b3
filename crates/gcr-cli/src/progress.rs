//! Progress on stderr: one line, rewritten in place. While the networks train: the phase, the
//! network sizes and the elapsed time (no time left: the last FEM step is not predictable from
//! the training). While the outputs are gathered: the phase (mesh, refinement, probes, pixels),
//! the points, the rays per point, the error against the target, the share done and the time
//! left of that gather ([`gcr::GatherProgress`]).

use gcr::{GatherProgress, Metrics, Progress};
use std::io::Write;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

/// Prints solver progress to stderr unless quiet.
pub struct ProgressLine {
    quiet: bool,
    shown: bool,
    /// A gather's line is on screen (set from the gather's threads).
    gather_shown: Arc<AtomicBool>,
}

impl ProgressLine {
    /// A progress line; `quiet` prints nothing at all.
    pub fn new(quiet: bool) -> Self {
        Self {
            quiet,
            shown: false,
            gather_shown: Arc::new(AtomicBool::new(false)),
        }
    }

    /// The observer of the output gathers ([`gcr::observe_gathers`]).
    pub fn gathers(&self) -> impl Fn(&GatherProgress) + Send + Sync + 'static {
        let (quiet, shown) = (self.quiet, Arc::clone(&self.gather_shown));
        move |p: &GatherProgress| {
            if quiet {
                return;
            }
            shown.store(true, Ordering::Relaxed);
            let error = p.error.map_or(String::from("error …"), |e| {
                format!("error {:.2} %", 100.0 * e)
            });
            let left = p.remaining.map_or(String::new(), |r| {
                let digits = usize::from(r < 10.0);
                format!(", about {r:.digits$} s left")
            });
            let mut err = std::io::stderr().lock();
            let _ = write!(
                err,
                "\r{:>10} {:>8} points  {:>6} rays  {error} (target {:.1} %)  {:>3.0} %  {:.1} s{left}     ",
                p.phase,
                p.points,
                p.rays,
                100.0 * p.target,
                100.0 * p.done,
                p.elapsed,
            );
            let _ = err.flush();
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

    /// A step before the solve (loading the scene, building its BVH): its name and what it
    /// works on, until [`ProgressLine::step_done`] clears it.
    pub fn step(&mut self, step: &str, what: &str) {
        if self.quiet {
            return;
        }
        let mut err = std::io::stderr().lock();
        let _ = write!(err, "\r{step:>8}  {what}   ");
        let _ = err.flush();
    }

    /// Clears a [`ProgressLine::step`]'s line (a warning or the next line takes its place).
    pub fn step_done(&mut self) {
        if self.quiet {
            return;
        }
        let mut err = std::io::stderr().lock();
        let _ = write!(err, "\r{:80}\r", "");
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
        if !self.quiet && self.gather_shown.swap(false, Ordering::Relaxed) {
            eprintln!();
        }
        if !self.quiet {
            let error = m.relative_std_error.map_or(String::new(), |e| {
                format!(", estimated error {:.2} % (standard error)", 100.0 * e)
            });
            let rays = if m.gather_rays > 0 {
                let guided = if m.guided { " guided" } else { "" };
                format!(",{guided} {} rays per point", m.gather_rays)
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

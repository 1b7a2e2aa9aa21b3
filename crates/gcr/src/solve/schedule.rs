//! When the main loop stops and when it runs a FEM step (sec. 4.4.1, fig. B.1).

use crate::config::SolveConfig;

/// The final FEM step's cost relative to the last training step's, scaled to the same cells
/// ([`Schedule::final_reserve`]).
const FINAL_STEP_FACTOR: f64 = 2.0;

/// The loop's clock: the budgets and the FEM steps' spacing.
pub(super) struct Schedule {
    kernel_cells: usize,
    time_budget: Option<f64>,
    fem_every: u64,
    projection: bool,
    base_used: bool,
    last_fem_insertions: u64,
    last_projected_cells: usize,
    /// Seconds and kernel cells of the last FEM step, to reserve time for the final one.
    last_fem: Option<(f64, usize)>,
}

impl Schedule {
    pub(super) fn new(config: &SolveConfig) -> Self {
        Self {
            kernel_cells: config.kernel_cells,
            time_budget: config.time_budget,
            fem_every: config.fem_every as u64,
            projection: config.output_fit == crate::config::OutputFit::Projection,
            base_used: config.needs_base(),
            last_fem_insertions: 0,
            last_projected_cells: 0,
            last_fem: None,
        }
    }

    /// Why training stops now, if it does: the kernel cell budget (`"cells"`) or the time budget
    /// (`"time"`). The time budget covers the final FEM step too: training stops when the time
    /// left is what that step is expected to take ([`Schedule::final_reserve`]).
    pub(super) fn stop(&self, kernel_cells: usize, elapsed: f64) -> Option<&'static str> {
        if kernel_cells >= self.kernel_cells {
            Some("cells")
        } else if self
            .time_budget
            .is_some_and(|t| elapsed + self.final_reserve(kernel_cells) >= t)
        {
            Some("time")
        } else {
            None
        }
    }

    /// The expected cost of the final FEM step with `kernel_cells` cells: the last step's time
    /// scaled by the Gram matrix's growth (cells²), doubled for the final step's longer bounce
    /// iteration (measured on cornell-box at 400–800 cells: the final step took 1.3–2× the last
    /// training step scaled this way).
    fn final_reserve(&self, kernel_cells: usize) -> f64 {
        self.last_fem.map_or(0.0, |(seconds, cells)| {
            let growth = kernel_cells as f64 / cells.max(1) as f64;
            FINAL_STEP_FACTOR * seconds * growth * growth
        })
    }

    /// Records how long the FEM step just run took.
    pub(super) fn fem_took(&mut self, seconds: f64, kernel_cells: usize) {
        self.last_fem = Some((seconds, kernel_cells));
    }

    /// Whether a FEM step is due, recording it when it is: every `fem_every` kernel insertions
    /// (sec. 4.4.1), once the shading network has a simplex (when the base is read), and with the
    /// projected output layer only after the kernel doubled since the last step and not in the
    /// last half of the cell budget: its Gram matrix costs O(cells²), so the training steps
    /// together cost at most a third of the final one (Σ 4⁻ᵏ from a quarter on). They only keep
    /// the kernel's target K·s current while it places its cells (the final step projects and
    /// bounces to convergence on its own): a step at every growth by a quarter (2.8× the final
    /// step) gave the same outputs at 1400 cells (`docs/results/benchmarks-fem.md`).
    pub(super) fn fem_due(
        &mut self,
        insertions: u64,
        kernel_cells: usize,
        shading_cells: usize,
    ) -> bool {
        let due = insertions - self.last_fem_insertions >= self.fem_every
            && (shading_cells >= 3 || !self.base_used)
            && (!self.projection
                || kernel_cells >= self.last_projected_cells * 2
                    && kernel_cells * 2 <= self.kernel_cells);
        if due {
            self.last_fem_insertions = insertions;
            self.last_projected_cells = kernel_cells;
        }
        due
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::config::OutputFit;

    #[test]
    fn budgets_stop_training_cells_first() {
        let config = SolveConfig {
            kernel_cells: 100,
            time_budget: Some(2.0),
            ..SolveConfig::default()
        };
        let s = Schedule::new(&config);
        assert_eq!(s.stop(99, 1.0), None);
        assert_eq!(s.stop(100, 1.0), Some("cells"));
        assert_eq!(s.stop(100, 3.0), Some("cells"));
        assert_eq!(s.stop(50, 2.0), Some("time"));
    }

    /// The time budget keeps room for the final FEM step: the last step's time scaled by the
    /// cells' growth squared, twice.
    #[test]
    fn the_time_budget_reserves_the_final_fem_step() {
        let config = SolveConfig {
            kernel_cells: 1000,
            time_budget: Some(10.0),
            ..SolveConfig::default()
        };
        let mut s = Schedule::new(&config);
        assert_eq!(s.stop(100, 9.0), None, "no step measured yet");
        s.fem_took(0.5, 100);
        assert_eq!(s.stop(100, 8.9), None, "reserve 1 s");
        assert_eq!(s.stop(100, 9.0), Some("time"));
        assert_eq!(
            s.stop(200, 6.0),
            Some("time"),
            "reserve 4 s at twice the cells"
        );
        assert_eq!(s.stop(200, 5.9), None);
    }

    /// The projection's steps need the kernel twice as large as at the last step; the delta rule
    /// steps every `fem_every` insertions, once the shading network has a simplex.
    #[test]
    fn projected_steps_thin_out_geometrically() {
        let config = SolveConfig {
            fem_every: 30,
            kernel_cells: 300,
            ..SolveConfig::default()
        };
        let mut s = Schedule::new(&config);
        assert!(!s.fem_due(29, 34, 0));
        assert!(s.fem_due(30, 35, 0));
        assert!(!s.fem_due(60, 69, 0), "69 < 2 · 35");
        assert!(s.fem_due(60, 70, 0));
        assert!(!s.fem_due(70, 200, 0), "only 10 insertions since");
        assert!(!s.fem_due(90, 139, 0), "139 < 2 · 70");
        assert!(s.fem_due(90, 140, 0));
        assert!(
            !s.fem_due(200, 290, 0),
            "past half the budget: the final step comes"
        );

        let delta = SolveConfig {
            fem_every: 30,
            output_fit: OutputFit::DeltaRule,
            skip_unused_base: false,
            ..SolveConfig::default()
        };
        let mut s = Schedule::new(&delta);
        assert!(!s.fem_due(30, 35, 2), "the base needs a shading simplex");
        assert!(s.fem_due(30, 35, 3));
        assert!(
            s.fem_due(60, 36, 3),
            "no growth condition without the projection"
        );
    }
}

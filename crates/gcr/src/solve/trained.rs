//! The state after training: what the gathers read.

use crate::cell_lanes::Collection;
use crate::config::SolveConfig;
use crate::domain::Domain;
use crate::element::Bands;
use crate::fem::{Base, FemSettings, FemSolution, SceneSurface};
use crate::kernel_cells::KernelCells;
use crate::metrics::Metrics;
use crate::sample::Sample;
use glam::DVec3;
use std::sync::Arc;

/// The state after training: everything the gathers need.
pub struct Trained {
    /// The kernel network frozen.
    pub kernel: KernelCells,
    /// Sender integrals c_o of the frozen kernel.
    pub sender: Vec<f64>,
    /// The last FEM step.
    pub fem: FemSolution,
    /// The samples at the end.
    pub samples: Vec<Sample>,
    /// Metrics of the solve (`gcr::output::write_outputs` completes them with the gather and
    /// output phases).
    pub metrics: Metrics,
    /// The kernel collection through `kernel` and `sender`, prepared for many points.
    pub(super) collection: Collection,
}

impl Trained {
    /// A solution without networks, for a gather that reads none
    /// ([`SolveConfig::reads_networks`]: the paths gather with every ray corrected) and outputs
    /// that need no output mesh (probes): the kernel and the base are empty (B_refl from them is
    /// 0), no sample was shot, and the metrics say `stopped_by: "unused"`.
    pub fn without_networks(domain: &Domain, config: &SolveConfig) -> Self {
        let fem_settings = FemSettings {
            surface_dim: domain.surface_dim(),
            ..FemSettings::default()
        };
        let empty = SceneSurface::new(Vec::new(), Vec::new(), 1.0);
        let base = Base::new(Default::default(), fem_settings, Arc::new(empty));
        Self {
            kernel: KernelCells::default(),
            sender: Vec::new(),
            fem: FemSolution {
                base,
                gamma: Vec::new(),
                rejected: 0,
            },
            samples: Vec::new(),
            collection: Collection::default(),
            metrics: Metrics {
                bands: domain.bands(),
                seed: config.seed,
                threads: rayon::current_num_threads(),
                stopped_by: "unused".into(),
                ..Default::default()
            },
        }
    }

    /// B_refl at a point by the kernel collection (fig. 4.13c).
    pub fn reflected_kernel(&self, y: DVec3, n: DVec3) -> Bands {
        self.collection.at(y, n)
    }
}

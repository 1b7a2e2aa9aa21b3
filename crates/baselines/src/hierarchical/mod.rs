//! Hierarchical radiosity (HR; Hanrahan, Salzman and Aupperle 1991) with a constant base — the method chapter 4
//! of the dissertation compares the growing-cells kernel with, at equal numbers of links (sec. 4.1, fig. 4.5).
//!
//! * [`strings`] — Flatland form factors by crossed strings (docs/design/math.md §7) and the ray estimate of the visible
//!   fraction.
//! * [`flatland`] — [`FlatHr`]: binary patch subdivision, links, the BF refinement oracle with partial
//!   visibility as a reason to refine, gathering with push-pull, refinement/solution passes to convergence.
//! * [`budget`] — [`solve_for_links`]: bisects `log ε` until the solution has a requested number of links.
//! * [`kernel`] — HR's kernel as a piecewise constant over `(s, t) ∈ [0,1]²` (fig. 4.2b), the exact Flatland
//!   kernel on the same parameterization, and the kernel error measure of issue #6.
//! * [`polygon`] — 3-D point-to-polygon form factors (with clipping) and triangle sampling.
//! * [`triangles`] — [`TriHr`]: 3-D HR on triangles with a constant base (four-way subdivision, averaged
//!   point-to-polygon form factors, visibility by rays through [`scene_sampler::SceneBvh`]).
//!
//! Shares no code with the growing-cells crates; geometry, visibility and scenes come from [`scene_sampler`].
//! See `docs/design/hierarchical.md` for the measured behaviour.

pub mod budget;
pub mod error;
pub mod flatland;
pub mod kernel;
pub mod polygon;
pub mod strings;
pub mod triangles;

pub use budget::{BudgetResult, TriBudgetResult, solve_for_links, solve_tri_for_links};
pub use error::{HrError, Result};
pub use flatland::{FlatHr, FlatHrConfig, FlatHrStats, Link, PartialVisibility, Patch};
pub use kernel::{
    HrKernel, KernelError, Weight, exact_kernel_at, kernel_error, kernel_error_clamped,
};
pub use triangles::{TriHr, TriHrConfig, TriHrStats, TriLink, TriPatch};

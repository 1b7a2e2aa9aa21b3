//! Reference radiosity solvers that share no code with the growing-cells networks.
//!
//! * [`pointwise`] — the path-traced pointwise reference of docs/design/math.md §8 for 3-D scenes, fixed-count or adaptive
//!   (to a relative standard error).
//! * [`flatland`] — the same path tracer in Flatland, and the converged fine-mesh solver with crossed-strings
//!   form factors and exact visibility ([`flatland::ExactSolver`]).
//! * [`classical`] — classical 3-D radiosity on a uniform mesh (Gauss–Seidel).
//! * [`hierarchical`] — hierarchical radiosity (Hanrahan, Salzman, Aupperle 1991) in Flatland and
//!   3-D with a link budget, and its kernel as a piecewise constant for comparisons with the
//!   kernel network.
//!
//! Every solver reports radiosity B (exitance) per colour band as `[f64; 3]`; grey scenes carry the same value
//! in all three bands. Bad parameters give a [`BaselineError`].

pub mod classical;
pub mod error;
pub mod flatland;
pub mod hierarchical;
pub mod pointwise;
pub mod progressive;
mod stats;

pub use error::BaselineError;
pub use stats::{Adaptive, AdaptiveEstimate, Estimate, relative_error_bound};

/// The README's code, compiled and run as a doctest.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
pub struct ReadmeDoctests;

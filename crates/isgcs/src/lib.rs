//! Incremental supervised growing cell structures (ISGCS): a generic function approximator
//! (Bohn 2000, ch. 2; Fritzke's growing cell structures with an RBF output layer).
//!
//! A network of z cells with centres w_i ∈ Rⁿ, widths d_i (mean incident edge length, eq. 2.10)
//! and outputs v_i ∈ Rᵐ computes Ψ(ξ) = Σ v_i exp(−|ξ − w_i|²/d_i²) (eq. 2.1–2.5). The cells form a
//! pure k-dimensional simplicial complex (sec. 2.3) that grows by splitting the longest edge of the
//! cell with the highest resource every λ steps (sec. 2.3.2, 2.4.1), and optionally shrinks by
//! deleting low-resource cells every κ steps (sec. 2.3.3), falling apart into components.
//!
//! * [`Params::thesis`] (= `Params::default()`) holds the dissertation's defaults;
//!   [`Params::accurate`] with [`Isgcs::fit_outputs`] (least-squares output layer) is far more
//!   accurate on smooth functions (docs/design/isgcs.md: Franke's function at 500 cells, rms 0.2214 vs
//!   0.0007 relative to the function's standard deviation).
//! * [`Isgcs::fit`] runs the training loop on a [`GoalFunction`] with a [`Termination`] and an
//!   observer; [`Isgcs::train`] is one step for callers with their own loop.
//! * Resampling (sec. 2.5): [`Isgcs::critical_cells`], [`Isgcs::in_critical_region`],
//!   [`Isgcs::resample_positions`].
//! * With the cargo feature `linfa`, `isgcs::linfa` wraps the network as a regressor
//!   behind linfa's `Fit` / `Predict` traits (ndarray records, `Array1` or `Array2` targets).
//! * [`rbf::GaussianRbf`] is the reference fit the network is measured against.
//! * [`gaussian`] is the cells' factor e^(−e) the network evaluates (within an ulp or two of
//!   `f64::exp`, vectorizable), for callers that sum the same Gaussians themselves.
//!
//! ```
//! use isgcs::{Isgcs, Params};
//! let mut net = Isgcs::new(Params::default(), 1, 1, 1, vec![vec![0.0], vec![1.0]]).unwrap();
//! for step in 0..20_000 {
//!     let x = (step as f64 * 0.618_033_988_7).fract();
//!     net.train(&[x], &[2.0 * x], None);
//! }
//! assert!(net.len() > 2);
//! let mut y = [0.0];
//! net.predict(&[0.5], &mut y);
//! assert!((y[0] - 1.0).abs() < 0.1);
//! ```

mod data;
mod driver;
mod gaussian;
mod kmeans;
mod linalg;
#[cfg(feature = "linfa")]
pub mod linfa;
mod network;
mod params;
pub mod rbf;
mod readout;
pub mod regressor;
mod resample;
pub mod test_functions;

pub use driver::{Event, GoalFunction, Stopped, Termination};
pub use gaussian::gaussian;
pub use network::{Isgcs, IsgcsError};
pub use params::Params;

//! Why a solve could not run.

use thiserror::Error;

/// Why a solve could not run.
#[derive(Debug, Error)]
pub enum SolveError {
    /// A setting is out of range.
    #[error(transparent)]
    Config(#[from] crate::config::ConfigError),
    /// The networks could not be created.
    #[error("network: {0}")]
    Network(#[from] isgcs::IsgcsError),
    /// The kernel projection kept breaking the maximum-principle bound on B.
    #[error("numerically unstable solve: {0}")]
    Unstable(String),
    /// No ray of the scene connects two surfaces: there is nothing to carry light.
    #[error(
        "no ray of the scene connects two surfaces ({shots} shot, all left the scene or hit \
         nothing): nothing to solve (is the scene a single surface, or open everywhere?)"
    )]
    NoRays {
        /// Rays shot.
        shots: u64,
    },
}

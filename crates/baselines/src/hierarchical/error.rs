//! Errors of the hierarchical radiosity solvers.

/// Everything that can go wrong in a hierarchical radiosity run. Bad input never panics.
#[derive(Debug, thiserror::Error)]
pub enum HrError {
    /// A parameter is outside its valid range (NaN, negative, zero where a positive value is needed, …).
    #[error("invalid HR parameter `{name}` = {value}: {reason}")]
    InvalidParameter {
        /// The parameter's name.
        name: &'static str,
        /// The value given.
        value: f64,
        /// What is required of it.
        reason: &'static str,
    },
    /// Refinement produced more links than the configured safety limit.
    #[error(
        "refinement exceeded the link limit of {limit} (ε = {epsilon:e}); raise ε or the limit"
    )]
    LinkLimit {
        /// The limit.
        limit: usize,
        /// The refinement threshold in use.
        epsilon: f64,
    },
    /// The link-budget driver could not get within tolerance of the requested link count.
    #[error(
        "no ε gives {target} links within {tolerance_percent}% (closest: {closest} links at ε = {epsilon:e})"
    )]
    BudgetNotReached {
        /// Requested number of links.
        target: usize,
        /// Allowed relative deviation, in percent.
        tolerance_percent: f64,
        /// The closest link count found.
        closest: usize,
        /// The ε that gave it.
        epsilon: f64,
    },
    /// A point handed to a query does not lie on the patch it names.
    #[error("point is not on segment {segment}: {reason}")]
    NotOnSurface {
        /// The segment (or triangle) index.
        segment: u32,
        /// Why.
        reason: String,
    },
    /// A scene-level error (loading, probe snapping).
    #[error(transparent)]
    Scene(#[from] scene_sampler::SceneError),
}

/// `Result` with [`HrError`].
pub type Result<T> = std::result::Result<T, HrError>;

//! What every figure or benchmark group receives.

use std::path::PathBuf;

/// A group's run: its sizes and where it writes.
pub struct Ctx {
    /// Smoke-run sizes.
    pub quick: bool,
    /// Output folder.
    pub out: PathBuf,
}

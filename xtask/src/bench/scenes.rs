//! Benchmarks of the `scenes` group (filled in as the crates land).

use crate::Ctx;
use anyhow::Result;

/// Runs this group's benchmarks and writes its report into `ctx.out`.
pub fn run(_ctx: &Ctx) -> Result<()> {
    Ok(())
}

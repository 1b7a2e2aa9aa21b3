//! Figures of the `gauss` group (filled in as the crates land).

use crate::Ctx;
use anyhow::Result;

/// Writes this group's figures into `ctx.out`.
pub fn run(_ctx: &Ctx) -> Result<()> {
    Ok(())
}

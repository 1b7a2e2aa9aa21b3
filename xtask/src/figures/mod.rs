//! Figure groups, one file per crate or chapter. Each group writes PNGs into `ctx.out`.

mod comparisons;
mod floor;
mod gauss;
mod gcr;
mod isgcs;
mod kernel3d;
mod scenes;
mod topology;

use crate::ctx::Ctx;
use anyhow::Result;

/// A named figure group.
type Group = (&'static str, fn(&Ctx) -> Result<()>);

const GROUPS: &[Group] = &[
    ("isgcs", isgcs::run),
    ("gauss", gauss::run),
    ("scenes", scenes::run),
    ("gcr", gcr::run),
    ("comparisons", comparisons::run),
    ("kernel3d", kernel3d::run),
    ("floor", floor::run),
];

/// Runs every group whose name contains `only` (all when `None`).
pub fn run(ctx: &Ctx, only: Option<&str>) -> Result<()> {
    for (name, f) in GROUPS {
        if only.is_none_or(|o| name.contains(o)) {
            let t = std::time::Instant::now();
            f(ctx)?;
            println!("figures {name}: {:.1} s", t.elapsed().as_secs_f64());
        }
    }
    Ok(())
}

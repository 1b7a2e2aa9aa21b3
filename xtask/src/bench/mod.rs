//! Benchmark groups, one file per crate or comparison. Each writes its report into `ctx.out`.

mod breaking;
mod compare;
mod daylit;
mod fem;
mod field;
mod gauss;
mod gcr;
mod guiding;
mod images;
mod irradiance;
mod isgcs;
mod isgcs_peers;
mod lights;
mod public_models;
mod radiance;
mod rays;
mod scenes;

use crate::ctx::Ctx;
use anyhow::Result;

pub use scenes::mem_probe;

/// A named benchmark group.
type Group = (&'static str, fn(&Ctx) -> Result<()>);

const GROUPS: &[Group] = &[
    ("isgcs", isgcs::run),
    ("isgcs-peers", isgcs_peers::run),
    ("gauss", gauss::run),
    ("scenes", scenes::run),
    ("gcr", gcr::run),
    ("breaking", breaking::run),
    ("fem", fem::run),
    ("compare", compare::run),
    ("field", field::run),
    ("images", images::run),
    ("irradiance", irradiance::run),
    ("lights", lights::run),
    ("rtrace", radiance::run),
    ("rays", rays::run),
    ("guiding", guiding::run_group),
    ("daylit", daylit::run),
];

/// Runs every group whose name contains `only` (all when `None`).
pub fn run(ctx: &Ctx, only: Option<&str>) -> Result<()> {
    for (name, f) in GROUPS {
        if only.is_none_or(|o| name.contains(o)) {
            let t = std::time::Instant::now();
            f(ctx)?;
            println!("bench {name}: {:.1} s", t.elapsed().as_secs_f64());
        }
    }
    Ok(())
}

//! The default estimator: B and irradiance at points by the **paths gather**, an unbiased path
//! tracer run in rounds to a target error, with the rays of neighbouring points shared.
//!
//! What `gcr solve` runs by default ([`crate::SolveConfig::preset`]), step by step:
//!
//! | step | file | what |
//! |---|---|---|
//! | the front door | `points.rs` ([`radiosity_at_points`], [`irradiance_at_points`]) | one seed per point from its position ([`point_seed`]); rounds to the target, or each point on its own (`pointwise.rs`: no target, or the dissertation's gathers) |
//! | one point's estimate | `paths.rs` (`PathGather`) | next-event estimation through the lights ([`scene_sampler::lights`]) and cosine rays by MIS, paths continued with Russian roulette, Owen-scrambled Sobol points in two replicates (the standard error) |
//! | neighbours share paths | `neighbours.rs` | groups of nearby, alike-facing points; every member weighs every member's rays by the multi-sample balance heuristic (unbiased) |
//! | guided first bounces | `guide.rs` (`--guiding`) | each group's cosine rays warped by a density learned from its earlier rounds, mixed with the cosine density (defensive); `auto` (the default) when the pilot round finds hard light |
//! | secondary sources | `secondary.rs` (the table), `relay.rs` (`--guiding`) | the surfaces the lights reach directly, tabulated by direct radiosity over equal-area cells; at every path vertex a point drawn from the table is joined by a shadow ray, weighed against the bounce by the balance heuristic; `auto` keeps the table where a trial round says it halves the variance per ray |
//! | blocks | `blocks.rs` (`Blocks`, [`shard_points`]) | the groups formed once per point set and cut into blocks of at least `--block-points` points, each running its rounds on its own: a point's value depends only on its block, so shards (`--shard`) match a single run |
//! | rounds to the target | `rounds.rs` (`rounds_to_target`) | a pilot round, then rounds up to the next power of two of Sobol points that covers the missing rays, until the 90 % bound of the estimated relative error ([`relative_std_error`]) meets the target or the ray cap |
//! | pixels | `pixel_rounds.rs` | a pixel image's rays allocated by each pixel's relative σ (Neyman), stopping on the per-pixel relative error |
//!
//! The design and its measurements: `docs/design/estimator.md`. The dissertation's gathers (base,
//! kernel, rays: they read the networks and are not corrected) are in [`crate::gather`] and are
//! reached through the same front door.

pub(crate) mod blocks;
pub(crate) mod guide;
pub(crate) mod neighbours;
pub(crate) mod paths;
pub(crate) mod pixel_rounds;
mod points;
mod pointwise;
pub(crate) mod relay;
pub(crate) mod rounds;
mod secondary;

pub use blocks::{ShardError, shard_points};
pub use points::{
    GatherError, irradiance_at_points, irradiance_at_shard, point_seed, radiosity_at_points,
    radiosity_at_shard,
};
pub(crate) use rounds::StopOn;
pub use rounds::{GatherStats, relative_std_error};

//! The front door of every gather: B at surface points and irradiance at any points, one seeding
//! convention ([`point_seed`]), dispatching to the paths gather in rounds to a target
//! ([`super::rounds`], over the blocks of [`super::blocks`]) or to each point on its own
//! ([`super::pointwise`]: the paths gather without a target, or the dissertation's gathers).

use super::blocks::Blocks;
use super::paths::PathGather;
use super::relay::{group_variance, table_if_it_pays};
use super::rounds::{StopOn, grouped_rounds, paths_to_target};
use crate::config::{GatherMode, Guiding, SolveConfig};
use crate::domain::Domain;
use crate::element::{BANDS, Bands};
use crate::emitters::Emitters;
use crate::gather::{Gathered, GuidingTrial};
use crate::solve::Trained;
use glam::DVec3;

/// Why radiosity could not be gathered from a solution.
#[derive(Debug, thiserror::Error)]
pub enum GatherError {
    /// [`GatherMode::Base`] on a solution solved without a base.
    #[error(
        "the base gather needs a solution with a base: solve with a config whose needs_base() is \
         true (gather = base, or skip_unused_base = false)"
    )]
    NoBase,
    /// Irradiance asked of a gather other than [`GatherMode::Paths`].
    #[error(
        "irradiance needs the paths gather (the default); the {0} gather estimates radiosity at \
         surface points only"
    )]
    IrradianceNeedsPaths(&'static str),
    /// The configured shard has no block ([`super::shard_points`]).
    #[error(transparent)]
    Shard(#[from] super::ShardError),
    /// The output mesh has more vertices to gather than the memory available holds (checked
    /// before they are gathered; `crate::output::mesh`).
    #[error(
        "the output mesh has {points} vertices to gather: about {} at the gather's peak, more \
         than the {} available; an image alone gathers only what its camera sees (leave out \
         --mesh and --ply)",
        crate::metrics::gib(*needed),
        crate::metrics::gib(*available)
    )]
    MeshMemory {
        /// Vertices to gather.
        points: usize,
        /// Bytes they would take.
        needed: u64,
        /// Bytes available.
        available: u64,
    },
}

/// Radiosity at many surface points `(point, normal, face)` in parallel by the configured gather.
/// Every entry point gathers through here, with one seeding convention: a point's ray gather is
/// seeded from the solve's seed and the point's coordinates ([`point_seed`]), so its value does
/// not depend on its index, its neighbours or the thread count.
pub fn radiosity_at_points(
    domain: &Domain,
    trained: &Trained,
    emitters: &Emitters,
    config: &SolveConfig,
    points: &[(DVec3, DVec3, u32)],
) -> Result<Vec<Gathered>, GatherError> {
    radiosity_at_shard(domain, trained, emitters, config, (points, None))
        .map(|(gathered, _)| gathered)
}

/// [`radiosity_at_points`] and the indices (ascending) of the points estimated: those of the
/// shard `config` asks for ([`super::shard_points`], the others left at `Gathered::default()`;
/// an error when it has no block), else every one. The groups and blocks are formed once for
/// both.
pub fn radiosity_at_shard(
    domain: &Domain,
    trained: &Trained,
    emitters: &Emitters,
    config: &SolveConfig,
    (points, stop): (&[(DVec3, DVec3, u32)], Option<&StopOn<'_>>),
) -> Result<(Vec<Gathered>, Vec<usize>), GatherError> {
    check_base(trained, config)?;
    let frame = domain.frame();
    let mut paths = path_gather(domain, trained, emitters, config);
    let seeds: Vec<u64> = (points.iter())
        .map(|&(y, _, _)| point_seed(config.seed, y, frame))
        .collect();
    // ⟨The blocks of neighbour groups: for the rounds, or to know a shard's points⟩
    let target = config
        .paths
        .target_error
        .filter(|_| config.gather == GatherMode::Paths);
    let blocks = (target.is_some() || config.paths.shard.is_some())
        .then(|| Blocks::new(domain, points, &config.paths));
    let estimated = estimated(blocks.as_ref(), points.len(), config)?;
    let (mut gathered, trial) = match (target, blocks) {
        // ⟨The paths gather to a target: in rounds, block by block⟩
        (Some(target), Some(blocks)) => {
            let material = |(y, _, face): (DVec3, DVec3, u32)| {
                (domain.reflectance_at(face, y), domain.emission(face))
            };
            let trial = decide_table(&mut paths, &blocks, (points, &seeds), material, config);
            let target = (target, stop);
            (
                paths_to_target(domain, &paths, (points, &seeds), &blocks, target, config),
                trial,
            )
        }
        // ⟨Otherwise each point on its own by the configured gather (a shard's points only)⟩
        (_, blocks) => {
            let mine = blocks.map(|b| b.mask(points.len()));
            let solution = (domain, trained, emitters, &paths);
            let each = (points, &seeds[..]);
            let g = super::pointwise::radiosity_each(solution, config, each, mine.as_deref());
            (g, None)
        }
    };
    mark_table(&paths, &mut gathered, (&estimated, trial));
    Ok((gathered, estimated))
}

/// The points (indices, ascending) a gather of `count` points estimates: the configured shard's
/// ([`Blocks::estimated`]; an error when it has no block), else every one.
fn estimated(
    blocks: Option<&Blocks>,
    count: usize,
    config: &SolveConfig,
) -> Result<Vec<usize>, GatherError> {
    match (config.paths.shard, blocks) {
        (Some(_), Some(blocks)) => Ok(blocks.estimated(count, &config.paths)?),
        _ => Ok((0..count).collect()),
    }
}

/// Irradiance E(y, n) = ∫ L cos θ dω at any points `(point, unit normal)` — on a surface or in the
/// air, as Radiance's `rtrace -I` — by the paths gather (`PathGather::estimate_irradiance`),
/// to the configured target error when there is one. The values are in
/// [`Gathered::radiosity`]: the radiosity a white (ρ = 1), non-emitting receiver there would have.
/// Seeded like [`radiosity_at_points`] (from the point's coordinates, salted: an irradiance probe
/// on a surface does not share its radiosity probe's rays).
pub fn irradiance_at_points(
    domain: &Domain,
    trained: &Trained,
    emitters: &Emitters,
    config: &SolveConfig,
    points: &[(DVec3, DVec3)],
) -> Result<Vec<Gathered>, GatherError> {
    irradiance_at_shard(domain, trained, emitters, config, (points, None))
        .map(|(gathered, _)| gathered)
}

/// [`irradiance_at_points`] and the indices (ascending) of the points estimated, as
/// [`radiosity_at_shard`].
pub fn irradiance_at_shard(
    domain: &Domain,
    trained: &Trained,
    emitters: &Emitters,
    config: &SolveConfig,
    (points, stop): (&[(DVec3, DVec3)], Option<&StopOn<'_>>),
) -> Result<(Vec<Gathered>, Vec<usize>), GatherError> {
    if config.gather != GatherMode::Paths {
        return Err(GatherError::IrradianceNeedsPaths(config.gather.name()));
    }
    let frame = domain.frame();
    let mut paths = path_gather(domain, trained, emitters, config);
    let seeds: Vec<u64> = (points.iter())
        .map(|&(y, _)| point_seed(config.seed ^ IRRADIANCE_SALT, y, frame))
        .collect();
    // receivers in the air (on no face), white, not emitting: they share paths as surface
    // points do
    let receivers: Vec<_> = (points.iter())
        .map(|&(y, n)| (y, n, scene_sampler::NO_FACE))
        .collect();
    let target = config.paths.target_error;
    let blocks = (target.is_some() || config.paths.shard.is_some())
        .then(|| Blocks::new(domain, &receivers, &config.paths));
    let estimated = estimated(blocks.as_ref(), points.len(), config)?;
    let (mut gathered, trial) = match (target, blocks) {
        (Some(target), Some(blocks)) => {
            let white = |_| ([1.0; BANDS], [0.0; BANDS]);
            let at = (&receivers[..], &seeds[..]);
            let trial = decide_table(&mut paths, &blocks, at, white, config);
            let g = grouped_rounds(domain, &paths, at, &blocks, white, (target, stop), config);
            (g, trial)
        }
        (_, blocks) => {
            let mine = blocks.map(|b| b.mask(points.len()));
            let each = (points, &seeds[..]);
            let g = super::pointwise::irradiance_each(&paths, config, each, mine.as_deref());
            (g, None)
        }
    };
    mark_table(&paths, &mut gathered, (&estimated, trial));
    Ok((gathered, estimated))
}

/// The paths gather of a solution, its networks' reflected radiosity as C.
fn path_gather<'a>(
    domain: &'a Domain<'a>,
    trained: &'a Trained,
    emitters: &'a Emitters,
    config: &SolveConfig,
) -> PathGather<'a, impl Fn(DVec3, DVec3) -> Bands + Sync + 'a> {
    let g = PathGather::new(
        domain,
        emitters,
        |x, n| trained.reflected_kernel(x, n),
        config.gather_samples,
        config.paths,
    );
    match config.paths.guiding {
        Guiding::On => g.with_secondary_sources(config.seed),
        _ => g,
    }
}

/// `Guiding::Auto` before the rounds to a target: the table of secondary sources for `paths`
/// where a trial on the points says it pays (`secondary.rs`, [`table_if_it_pays`]); what the
/// trial measured (None: no trial).
fn decide_table(
    paths: &mut PathGather<'_, impl Fn(DVec3, DVec3) -> Bands + Sync>,
    blocks: &Blocks,
    at: (&[(DVec3, DVec3, u32)], &[u64]),
    material: impl Fn((DVec3, DVec3, u32)) -> (Bands, Bands) + Sync,
    config: &SolveConfig,
) -> Option<GuidingTrial> {
    if config.paths.guiding != Guiding::Auto {
        return None;
    }
    let samples = config.gather_samples;
    let variance =
        |p: &PathGather<'_, _>| group_variance(p, &blocks.groups, at, &material, samples);
    let rays = samples.direct.max(samples.indirect);
    let target = config.paths.target_error.unwrap_or(1.0);
    let work = at.0.len() as f64 / (target * target);
    table_if_it_pays(paths, variance, (rays, config.seed, work))
}

/// Marks the `estimated` values of a gather as guided where it drew from a table of secondary
/// sources (the metrics' `guided`; `secondary.rs`), and records the `trial` that decided about
/// it for the output stage (the metrics' `guiding_trial`, [`super::relay::record_trial`]).
fn mark_table<C>(
    paths: &PathGather<'_, C>,
    gathered: &mut [Gathered],
    (estimated, trial): (&[usize], Option<GuidingTrial>),
) {
    for &i in estimated {
        gathered[i].guided |= paths.secondary.is_some();
    }
    super::relay::record_trial(trial);
}

/// Mixed into the solve's seed for irradiance probes ([`irradiance_at_points`]).
const IRRADIANCE_SALT: u64 = 0x6972_7261_6469_616E;

/// A skipped base (`skip_unused_base` with a non-base gather) has no cells; reading it would
/// silently report B = E.
fn check_base(trained: &Trained, config: &SolveConfig) -> Result<(), GatherError> {
    if config.gather == GatherMode::Base && trained.fem.base.geo.is_empty() {
        return Err(GatherError::NoBase);
    }
    Ok(())
}

/// The ray gather's seed at point `y`: the solve's seed mixed with y's coordinates in the
/// scene's frame ([`Domain::frame`]) quantized to 2⁻²⁴ of the diagonal (SplitMix64 finalizer
/// per coordinate). A point's seed depends neither on its index among the points asked for nor
/// on the scene's position or scale.
pub fn point_seed(seed: u64, y: DVec3, (origin, diagonal): (DVec3, f64)) -> u64 {
    let mix = |mut z: u64| {
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    };
    let q = (y - origin) / diagonal.max(f64::MIN_POSITIVE) * (1u64 << 24) as f64;
    [q.x, q.y, q.z]
        .iter()
        .fold(mix(seed ^ 0x9E37_79B9_7F4A_7C15), |h, c| {
            mix(h ^ (c.round() as i64) as u64)
        })
}

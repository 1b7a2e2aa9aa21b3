//! The gathers without rounds: each output point estimated on its own, in parallel, by the
//! configured gather — the paths gather at a fixed number of rays ([`super::paths`]), or the
//! dissertation's gathers from the networks ([`crate::gather`]: base, kernel, rays).

use super::paths::PathGather;
use crate::config::{GatherMode, SolveConfig};
use crate::domain::Domain;
use crate::element::{BANDS, Bands};
use crate::emitters::Emitters;
use crate::gather::{Gathered, gather};
use crate::solve::Trained;
use glam::DVec3;
use rayon::prelude::*;

/// A solution as the gathers read it: the domain, the networks, the lights and the paths gather.
type Solution<'a, C> = (
    &'a Domain<'a>,
    &'a Trained,
    &'a Emitters,
    &'a PathGather<'a, C>,
);

/// Radiosity at each surface point `(point, normal, face)` with its seed, by the configured
/// gather; only the points `mine` marks (a shard's), the others left at `Gathered::default()`.
pub(super) fn radiosity_each<C: Fn(DVec3, DVec3) -> Bands + Sync>(
    solution: Solution<'_, C>,
    config: &SolveConfig,
    (points, seeds): (&[(DVec3, DVec3, u32)], &[u64]),
    mine: Option<&[bool]>,
) -> Vec<Gathered> {
    (points.par_iter().zip(seeds).enumerate())
        .map_init(Vec::new, |scratch, (i, (&point, &seed))| {
            if mine.is_some_and(|m| !m[i]) {
                return Gathered::default();
            }
            radiosity_at(solution, config, point, seed, scratch)
        })
        .collect()
}

/// Irradiance at each point `(point, unit normal)` with its seed by the paths gather at the
/// configured rays ([`PathGather::estimate_irradiance`]); only the points `mine` marks.
pub(super) fn irradiance_each(
    paths: &PathGather<impl Fn(DVec3, DVec3) -> Bands + Sync>,
    config: &SolveConfig,
    (points, seeds): (&[(DVec3, DVec3)], &[u64]),
    mine: Option<&[bool]>,
) -> Vec<Gathered> {
    (0..points.len())
        .into_par_iter()
        .map(|i| match mine.is_some_and(|m| !m[i]) {
            true => Gathered::default(),
            false => (paths.estimate_irradiance(points[i], seeds[i], 0, config.gather_samples))
                .gathered(),
        })
        .collect()
}

/// Radiosity at surface point (y, n, face) by the configured gather (a base checked by
/// `points::check_base`).
fn radiosity_at<C: Fn(DVec3, DVec3) -> Bands>(
    (domain, trained, emitters, paths): Solution<'_, C>,
    config: &SolveConfig,
    (y, n, face): (DVec3, DVec3, u32),
    seed: u64,
    scratch: &mut Vec<u32>,
) -> Gathered {
    let e = domain.emission(face);
    let reflected = |b: Bands| {
        let mut out = Gathered::default();
        for k in 0..BANDS {
            out.from_networks[k] = b[k].max(0.0);
            out.radiosity[k] = e[k] + out.from_networks[k];
        }
        out
    };
    match config.gather {
        GatherMode::Base => reflected(trained.fem.reflected_from_base(y, n, scratch)),
        GatherMode::Kernel => reflected(trained.reflected_kernel(y, n)),
        GatherMode::Rays => gather(
            domain,
            emitters,
            y,
            n,
            face,
            config.gather_samples,
            seed,
            &|x, nx, _| trained.reflected_kernel(x, nx),
        ),
        GatherMode::Paths => paths.gather((y, n, face), seed),
    }
}

//! Rounds to a target error: the paths gather run in rounds of Sobol points until the upper
//! confidence bound of the estimated relative error meets the target (or the ray cap), over
//! groups of neighbouring points that share paths; the error estimate and its χ² bound.

use super::blocks::Blocks;
use super::guide::{GroupGuide, SpatialGuides, SpatialLearner, guiding_bytes};
use super::paths::{PathGather, PointEstimate, REPLICATES};
use crate::config::{GatherSamples, Guiding, SolveConfig};
use crate::domain::Domain;
use crate::element::{BANDS, Bands};
use crate::gather::Gathered;
use glam::DVec3;
use rayon::prelude::*;
use std::sync::{Arc, Mutex};

/// The paths gather in rounds until the points' estimated relative error ([`relative_std_error`])
/// is at most `target`: a pilot round with the configured rays, then each round continues every
/// replicate's Sobol sequence up to the next power of two that covers the rays its standard errors
/// say are missing (the variance falls as 1/rays; 2–4× the rays so far), until the target or
/// `max_rays` per point is reached.
///
/// The stopping test is conservative where the estimate is rough: with `k` degrees of freedom
/// (one per group of points that share paths and reflect: a lone point is its own group; members
/// of a group share their replicates) the estimated variance is scaled by
/// `k/χ²_{0.1}(k)`, its one-sided 90 % upper bound (Wilson–Hilferty), so that a handful of probes
/// do not stop on a lucky small spread (1.06 in variance at 1000 points, ×190 at one point, whose
/// rays are cheap).
pub(super) fn paths_to_target(
    domain: &Domain,
    paths: &PathGather<impl Fn(DVec3, DVec3) -> Bands + Sync>,
    (points, seeds): (&[(DVec3, DVec3, u32)], &[u64]),
    blocks: &Blocks,
    target: (f64, Option<&StopOn<'_>>),
    config: &SolveConfig,
) -> Vec<Gathered> {
    let material =
        |(y, _, face): (DVec3, DVec3, u32)| (domain.reflectance_at(face, y), domain.emission(face));
    grouped_rounds(
        domain,
        paths,
        (points, seeds),
        blocks,
        material,
        target,
        config,
    )
}

/// The error bound the rounds of a block stop on instead of the relative standard error's
/// ([`error_bound`]): an upper confidence bound of an error of the block's points (their indices
/// among all the points gathered, in ascending order) from their values so far; None when
/// nothing was measured. The lightmap denoiser's (`lightmap/denoise.rs`, `denoised_error`): a
/// denoised bake stops when its denoised texels meet the target.
pub(crate) type StopOn<'a> = dyn Fn(&[usize], &[Gathered]) -> Option<f64> + Sync + 'a;

/// [`rounds_to_target`] over the groups of neighbouring `points` with their `seeds`, block by
/// block ([`Blocks`] of these points: each block's rounds on their own; only the blocks of the
/// configured shard, the other points left at `Gathered::default()`), each round of a group by
/// [`PathGather::estimate_group`] with the members' (ρ, E) from `material`; `target` the error
/// to reach and what it is of ([`StopOn`]; default the relative standard error).
pub(super) fn grouped_rounds(
    domain: &Domain,
    paths: &PathGather<impl Fn(DVec3, DVec3) -> Bands + Sync>,
    (points, seeds): (&[(DVec3, DVec3, u32)], &[u64]),
    blocks: &Blocks,
    material: impl Fn((DVec3, DVec3, u32)) -> (Bands, Bands) + Sync,
    target: (f64, Option<&StopOn<'_>>),
    config: &SolveConfig,
) -> Vec<Gathered> {
    let groups = &blocks.groups;
    let mut out = vec![Gathered::default(); points.len()];
    for block in blocks.mine.iter().map(|&b| &blocks.blocks[b]) {
        // the block's points in their original order (one block: exactly the points given)
        let mut members: Vec<usize> = groups[block.clone()].iter().flatten().copied().collect();
        members.sort_unstable();
        let mut local = vec![usize::MAX; points.len()];
        members.iter().enumerate().for_each(|(k, &i)| local[i] = k);
        let block_groups: Vec<Vec<usize>> = (groups[block.clone()].iter())
            .map(|g| g.iter().map(|&i| local[i]).collect())
            .collect();
        let block_points: Vec<_> = members.iter().map(|&i| points[i]).collect();
        let block_seeds: Vec<u64> = members.iter().map(|&i| seeds[i]).collect();
        let at = (&block_points[..], &block_groups[..], &block_seeds[..]);
        let (target, stop) = target;
        let bound = |g: &[Gathered], dof: usize| match stop {
            Some(stop) => stop(&members, g),
            None => error_bound(g, dof),
        };
        let gathered = block_rounds(domain, paths, at, &material, (target, &bound), config);
        for (&i, g) in members.iter().zip(gathered) {
            out[i] = g;
        }
    }
    out
}

/// Whether the guides of `groups` groups ([`guiding_bytes`]) fit in `available` bytes (none: not
/// known, they do).
fn guides_fit(groups: usize, available: Option<u64>) -> bool {
    available.is_none_or(|a| guiding_bytes(groups) <= a)
}

/// A block's points, its groups (indices into the points) and the points' seeds.
type Block<'a> = (&'a [(DVec3, DVec3, u32)], &'a [Vec<usize>], &'a [u64]);

/// The rounds of one block of [`grouped_rounds`]: `points` in `groups` (indices into `points`)
/// with their `seeds`; the block's own guides.
fn block_rounds(
    domain: &Domain,
    paths: &PathGather<impl Fn(DVec3, DVec3) -> Bands + Sync>,
    (points, groups, seeds): Block<'_>,
    material: &(impl Fn((DVec3, DVec3, u32)) -> (Bands, Bands) + Sync),
    target: (f64, &ErrorBound<'_>),
    config: &SolveConfig,
) -> Vec<Gathered> {
    // ⟨Guiding: each group's guide, learned from its earlier rounds (estimator/guide.rs);
    // `auto` only where the guides fit in the memory left (`--guiding on` was checked before the
    // solve, `OutputPlan::check_config`)⟩
    let guiding = match config.paths.guiding {
        Guiding::Auto if !guides_fit(groups.len(), crate::metrics::available_memory()) => {
            Guiding::Off
        }
        g => g,
    };
    let guides: Vec<Mutex<GroupGuide>> = if guiding != Guiding::Off {
        groups.iter().map(|_| Mutex::default()).collect()
    } else {
        Vec::new()
    };
    // the spatial guides of the paths' bounces: learned from every group's records of the
    // earlier rounds, merged in the groups' order when a round's first group starts
    let spatial = Mutex::new((
        usize::MAX,
        SpatialLearner::new(domain.frame(), groups.len()),
        Arc::default(),
    ));
    let frozen = |first: usize| -> Arc<SpatialGuides> {
        let mut s = spatial.lock().expect("the spatial guides");
        if s.0 != first {
            for g in &guides {
                let mut g = g.lock().expect("a group's guide");
                s.1.learn(&g.records);
                g.records.clear();
            }
            s.2 = Arc::new(s.1.guides());
            s.0 = first;
        }
        Arc::clone(&s.2)
    };
    let mut owner = vec![0; points.len()];
    for (gi, g) in groups.iter().enumerate() {
        g.iter().for_each(|&i| owner[i] = gi);
    }
    rounds_to_target(
        points.len(),
        groups,
        |group: &[usize], first, samples, guided| {
            let members: Vec<_> = group.iter().map(|&i| points[i]).collect();
            let materials: Vec<_> = members.iter().map(|&p| material(p)).collect();
            let member_seeds: Vec<u64> = group.iter().map(|&i| seeds[i]).collect();
            let spatial = guided.then(|| frozen(first));
            let mut guide = (guides.get(owner[group[0]]))
                .filter(|_| guided)
                .map(|m| m.lock().expect("a group's guide"));
            let guiding = guide.as_deref_mut().zip(spatial.as_deref());
            let round = (first, samples);
            let e = paths.estimate_group(&members, &materials, &member_seeds, round, guiding);
            if let Some(g) = guide.as_mut() {
                g.next_round();
            }
            e
        },
        (config.gather_samples, None),
        target,
        (config.paths.max_rays, guiding),
    )
}

/// The rounds of [`paths_to_target`] for `count` estimates gathered in `groups` (each index in
/// exactly one), `estimate(group, first, samples)` being the group's round with `samples` rays per
/// member from Sobol index `first` on, one estimate per member (a point's gather, a group of
/// neighbours sharing paths, [`PathGather::estimate_group`], a pixel's footprint). `piloted`:
/// the pilot round's estimates when the caller has run it (`estimator::pixel_rounds`).
///
/// `guiding` ([`Guiding`]): whether a round is guided — `estimate`'s last argument; a guided
/// round takes its own scrambling from index 0 (`estimator::guide`) and a power of two of points
/// per replicate instead of continuing one sequence, and runs whole; unguided rounds run in
/// [`parts`]. `Auto` decides after the pilot round, which
/// is unguided, by the rays per point it predicts to the target and their variance
/// ([`Guiding::pays`]).
pub(crate) fn rounds_to_target(
    count: usize,
    groups: &[Vec<usize>],
    estimate: impl Fn(&[usize], usize, GatherSamples, bool) -> Vec<PointEstimate> + Sync,
    (pilot, piloted): (GatherSamples, Option<Vec<PointEstimate>>),
    (target, bound_of): (f64, &ErrorBound<'_>),
    (max_rays, guiding): (usize, Guiding),
) -> Vec<Gathered> {
    let mut fresh = guiding == Guiding::On;
    let pilot_rays = pilot.direct.max(pilot.indirect).min(max_rays);
    let reporter = crate::progress::Reporter::new(count, pilot_rays, target);
    let round = |first: usize, samples: GatherSamples, guided: bool| {
        let per_group: Vec<Vec<PointEstimate>> = groups
            .par_iter()
            .map(|g| {
                let e = estimate(g, first, samples, guided);
                reporter.finished(g.len(), samples.direct.max(samples.indirect));
                e
            })
            .collect();
        let mut out = vec![PointEstimate::default(); count];
        for (g, e) in groups.iter().zip(per_group) {
            for (&i, e) in g.iter().zip(e) {
                out[i] = e;
            }
        }
        out
    };
    let bound_at = |estimates: &[PointEstimate], guided: bool| {
        bound_of_estimates(estimates, groups, guided, bound_of)
    };
    // ⟨Pilot round: the configured rays⟩
    let mut estimates = piloted.unwrap_or_else(|| round(0, pilot, fresh));
    let mut rays = pilot_rays;
    // the last guided round's relative variance and rays (when combined by variances)
    let mut last: Option<(f64, usize)> = None;
    loop {
        // ⟨Stop at the target (its upper confidence bound) or the ray cap⟩
        let (gathered, dof, bound) = bound_at(&estimates, fresh);
        let Some(bound) = bound else {
            return gathered;
        };
        if bound <= target || rays >= max_rays {
            reporter.round(bound, rays, rays);
            return gathered;
        }
        // ⟨Next round: each replicate's Sobol points up to the next power of two that covers the
        // missing rays (variance ∝ 1/rays), at least twice and at most four times as many as so
        // far. Owen-scrambled Sobol points are a balanced net only at powers of two (and in
        // aligned blocks of them, the parts below): two-blockers' pixels at 296 rays (148 per
        // replicate, not a union of aligned blocks) had 13× the relative MSE of 512, cornell-box's
        // and wall-floor's the same or 1.5× per ray (docs/guide/images.md). The cap keeps a long
        // extrapolation from overshooting (the points converge faster than 1/√rays at first)⟩
        let needed = rays_to_target(rays, bound, target);
        // ⟨Guiding::Auto: guide from here on when the pilot predicts hard light⟩
        if guiding == Guiding::Auto && rays == pilot_rays && Guiding::pays(rays, bound, needed) {
            fresh = true;
        }
        // the relative error so far (guided rounds: their sizes and weights)
        let error = fresh.then(|| relative_std_error(&gathered)).flatten();
        let guided = fresh.then_some((last, error, chi2_scale(dof)));
        let more = round_rays((rays, needed, max_rays), (target, guided));
        // ⟨The round: guided whole (each its own scrambling from index 0), combined with the
        // earlier ones by their variances; unguided in parts ([`parts`]), each merged by counts,
        // stopping at the part that meets the target (the progress expects the part that covers
        // the rays predicted). Each replicate has used ⌈rays / REPLICATES⌉ Sobol points of its
        // sequence so far⟩
        let start = rays.div_ceil(REPLICATES);
        let mut done = 0;
        let parted = (!fresh && dof >= PARTS_FROM).then_some(start);
        let plan = parts(parted, more);
        let expect = |needed: usize| part_end(&plan, rays, needed);
        reporter.round(bound, expect(needed), needed.min(max_rays));
        for &(offset, part) in &plan {
            let samples = GatherSamples {
                direct: part,
                indirect: part,
            };
            done += part;
            let next = round(start + offset, samples, fresh);
            let weight = (fresh && dof >= WEIGHTED_FROM)
                .then(|| next_weight(error, &next))
                .flatten();
            last = weight.map(|(_, v)| (v, more));
            combine(&mut estimates, &next, weight.map(|(v, _)| v));
            if done < more {
                match bound_at(&estimates, fresh).2 {
                    Some(b) if b <= target => break,
                    Some(b) => {
                        let needed = rays_to_target(rays + done, b, target);
                        reporter.round(b, expect(needed), needed.min(max_rays));
                    }
                    None => {}
                }
            }
        }
        rays += done;
    }
}

/// What sizes a guided round ([`round_rays`]): the last guided round's relative variance and
/// rays, the relative error so far and the confidence factor of the bound.
type Guided = (Option<(f64, usize)>, Option<f64>, f64);

/// The rays of the next round after `rays` rays so far, `needed` predicted to the target, at most
/// `max_rays` in all ([`rounds_to_target`]). Unguided: each replicate's Sobol points up to the
/// next power of two that covers the missing ones, at least twice and at most four times as many
/// as so far. Guided ([`Guided`]): [`guided_round`] of what rays as good as
/// the last round's need ([`guided_rays_needed`]), else of the missing ones.
fn round_rays(
    (rays, needed, max_rays): (usize, usize, usize),
    (target, guided): (f64, Option<Guided>),
) -> usize {
    if let Some((last, error, scale)) = guided {
        // each round its own scrambling from index 0 (guided rounds)
        let missing = match (last, error) {
            (Some(last), Some(error)) => guided_rays_needed(error, last, target, scale),
            _ => needed.saturating_sub(rays),
        };
        return guided_round(missing, rays, max_rays);
    }
    let per = rays.div_ceil(REPLICATES);
    let want = (needed.div_ceil(REPLICATES))
        .clamp(per + 1, 4 * per)
        .next_power_of_two();
    (want * REPLICATES)
        .min(max_rays)
        .saturating_sub(rays)
        .max(REPLICATES)
}

/// The values of `estimates` (`guided` marks them), their degrees of freedom and the error bound
/// `bound_of` of them ([`rounds_to_target`]): one degree of freedom per group with a reflecting
/// point (a group's members share their paths, so their standard errors come from the same two
/// replicates).
fn bound_of_estimates(
    estimates: &[PointEstimate],
    groups: &[Vec<usize>],
    guided: bool,
    bound_of: &ErrorBound<'_>,
) -> (Vec<Gathered>, usize, Option<f64>) {
    let gathered: Vec<Gathered> = (estimates.iter())
        .map(|e| Gathered {
            guided,
            ..e.gathered()
        })
        .collect();
    let dof = (groups.iter())
        .filter(|g| (g.iter()).any(|&i| gathered[i].std_error.iter().any(|s| *s != 0.0)))
        .count();
    let bound = bound_of(&gathered, dof);
    (gathered, dof, bound)
}

/// The most rays per replicate of a part of a round ([`parts`]).
const PART: usize = 1024;

/// The fewest rays per replicate of a part of a round ([`parts`]).
const MIN_PART: usize = 16;

/// Groups with a standard error from which an unguided round stops part-way ([`parts`]): the
/// bound is then checked after every part, and with few groups its estimate is noisy enough that
/// stopping at the first low one leaves the standard errors too small — the side-lit room's 21
/// work-plane points (in small blocks, each its own rounds) against a path-traced reference:
/// Σd²/Σσ² 3.9, 1.7 with whole rounds (`tests/tests/lights.rs`). With 125 groups (2 000 points
/// under the sun patch room's ceiling, four seeds) the actual error over the estimate was 1.05
/// in parts and 1.02 without. Guided rounds run whole: their paths are heavy-tailed, and in parts
/// the door gap's work plane (2 000 points, seed 1) stopped at 11 600 rays per point on an
/// estimated 1.83 % that measured 2.64 % against a 0.74 % reference (whole: 1.57 % measured for
/// 1.67 % estimated, and the three seeds' 1.3–1.8 % within 10 % of their estimates).
const PARTS_FROM: usize = 64;

/// An unguided round of `rays` rays from Sobol index `start` (per replicate; `None`: run whole)
/// in parts, each an offset from `start` (per replicate) and its rays. A part is a quarter of the
/// points so far per replicate (at least [`MIN_PART`], at most [`PART`], a power of two that
/// divides `start`), so that every part is an aligned block of the sequence — a balanced net —
/// and the rounds stop at the first part that meets the target. Whole, the last of the rounds,
/// which double, overshot: under the sun patch room's ceiling it reached 1.25 % where 2 % was
/// asked (16 384 rays per point, 8.5 s; in parts of 1 024, 10 240, 5.5 s); the temple compound's
/// 340 671 output-mesh vertices stood at 2.06 % after 256 rays and took a round to 512 (a quarter
/// more rays meet 2 %).
fn parts(start: Option<usize>, rays: usize) -> Vec<(usize, usize)> {
    let per = rays / REPLICATES;
    let Some(start) = start.filter(|s| *s > 0) else {
        return vec![(0, rays)];
    };
    // the largest power of two at most a quarter of `start` that divides it, at most PART
    let quarter = (start / 4).max(1);
    let part = (1 << quarter.ilog2())
        .min(start & start.wrapping_neg())
        .min(PART);
    if part < MIN_PART || rays % REPLICATES != 0 || per % part != 0 || per < 2 * part {
        return vec![(0, rays)];
    }
    (0..per / part)
        .map(|k| (k * part, part * REPLICATES))
        .collect()
}

/// The rays per point that bring an error bound `bound` after `rays` rays to `target`
/// (variance ∝ 1/rays).
fn rays_to_target(rays: usize, bound: f64, target: f64) -> usize {
    (rays as f64 * (bound / target).powi(2)).ceil() as usize
}

/// Where a round in parts `plan` ([`parts`]) after `rays` rays is expected to stop: the end of
/// its first part that reaches `needed` rays, else its end.
fn part_end(plan: &[(usize, usize)], rays: usize, needed: usize) -> usize {
    let mut end = rays;
    for &(_, part) in plan {
        end += part;
        if end >= needed {
            break;
        }
    }
    end
}

/// Merges a round's estimates `next` into `estimates`: with weight `weight` on the round, or by
/// their ray counts.
fn combine(estimates: &mut [PointEstimate], next: &[PointEstimate], weight: Option<f64>) {
    for (e, n) in estimates.iter_mut().zip(next) {
        match weight {
            Some(v) => e.merge_weighted(n, v),
            None => e.merge(n),
        }
    }
}

/// Groups with a standard error from which guided rounds are combined by their variances
/// ([`next_weight`]).
const WEIGHTED_FROM: usize = 64;

/// The weight of a guided round's estimates `next` against those of the rounds so far (their
/// relative error `so_far`):
/// the inverse-variance weight V/(V + V') of their relative variances over all the points (V so
/// far, V' the round's; None when either was not measured). Guided rounds differ in kind — the
/// unguided pilot, guides that learned from a few rays, guides that learned from many — so their
/// variances per ray do too: combined by ray counts, the pilot's 5 000 rays per point at 15 %
/// kept the door gap's work plane above 2 % after 40 000 guided ones. One weight for all the
/// points, from at least [`WEIGHTED_FROM`] groups' spreads: it hardly depends on any one point's
/// values (a weight that followed a point's own spread would bias it toward its lucky rounds).
/// Also returns V'.
fn next_weight(so_far: Option<f64>, next: &[PointEstimate]) -> Option<(f64, f64)> {
    let next: Vec<Gathered> = next.iter().map(PointEstimate::gathered).collect();
    let (v, v_next) = (so_far?, relative_std_error(&next)?);
    let (v, v_next) = (v * v, v_next * v_next);
    Some((v / (v + v_next), v_next))
}

/// The rays of a guided round (each its own scrambling from index 0) after `rays` rays so far:
/// the `missing` ones — after a guided round, as many as rays as good as its own need
/// ([`guided_rays_needed`]: the rounds are combined by their variances, [`next_weight`], so the
/// pilot's and the first guides' worse rays count less than their number), else by the error so
/// far — a quarter to twice those so far, a power of two per replicate below 1 024 and a
/// multiple of [`GUIDED_STEP`] above (unions of balanced nets), at most the ray cap. Twice, not
/// three times: a guided round runs whole and its guides improved since the round it is sized
/// by, so a long step overshoots — the door gap's work plane to 2 % (2 000 points, seeds 1/2/3)
/// took 16.6 / 18.4 / 20.2 s with three times (17 744 / 19 792 / 21 840 rays per point) and 16.8 /
/// 17.1 / 16.7 s with twice (17 744 each; 0.92× on the mean, each within 20 % of its estimated
/// error against a 0.74 % reference); to 1 % the bench's work plane 41.7 s against 55.7 s
/// (`cargo xtask bench --only guiding`); under the sun patch room's ceiling the same bits.
fn guided_round(missing: usize, rays: usize, max_rays: usize) -> usize {
    let per = rays.div_ceil(REPLICATES);
    let missing = (missing.div_ceil(REPLICATES)).clamp(per / 4 + 1, 2 * per + 1);
    let per_round = if missing < 1024 {
        missing.next_power_of_two()
    } else {
        missing.next_multiple_of(GUIDED_STEP)
    };
    (per_round * REPLICATES).min(max_rays.saturating_sub(rays).max(REPLICATES))
}

/// The step of a guided round's points per replicate above 1 024 ([`guided_round`]): any multiple
/// of 256 Sobol points from index 0 is a union of balanced nets of at least 256 points. It was
/// 1 024, and the last round, rounded up to it, overshot: under the sun patch room's ceiling to
/// 2 % (2 000 points, seeds 1/2/3, against a 0.37 % reference) 5 456 rays per point and 3.9 s for
/// errors of 1.43 / 1.45 / 1.52 % (estimated 1.44 / 1.25 / 1.50 %); with 256 4 432 rays, 3.2 s,
/// 1.66 / 1.71 / 1.53 % (estimated 1.68 / 1.64 / 1.67 %). The door gap to 2 %: 15.0 s against
/// 14.8 s (17 744 against 17 232 rays); to 1 % under the ceiling (four seeds) 8.7 s against
/// 8.5 s on the mean.
const GUIDED_STEP: usize = 256;

/// The rays a guided round needs so that the rounds combined by their variances meet `target`
/// (an error's upper bound: the error itself at most target/`scale`): the rounds so far have
/// relative error `error`, the last one had relative variance `v` over `rays` rays, and a round of
/// k rays as good adds k/(v·rays) to the inverse variance: k = v·rays·(1/t² − 1/error²).
fn guided_rays_needed(error: f64, (v, rays): (f64, usize), target: f64, scale: f64) -> usize {
    let t = target / scale;
    let k = v * rays as f64 * (1.0 / (t * t) - 1.0 / (error * error));
    k.max(0.0).ceil().min(usize::MAX as f64 / 2.0) as usize
}

/// The error a round to a target compares with the target: of the values gathered so far and
/// their degrees of freedom (one per group with a standard error), None when nothing was measured
/// ([`error_bound`], or the per-pixel relative error of `estimator::pixel_rounds`).
pub(crate) type ErrorBound<'a> = dyn Fn(&[Gathered], usize) -> Option<f64> + 'a;

/// Every estimate its own group ([`rounds_to_target`]).
pub(crate) fn singletons(count: usize) -> Vec<Vec<usize>> {
    (0..count).map(|i| vec![i]).collect()
}

/// The upper confidence bound (90 %) of the relative error of `gathered` ([`relative_std_error`],
/// None when nothing was measured), its standard errors estimated with `dof` degrees of freedom
/// in all: `error·√(dof/χ²₀.₁(dof))`. What rounds to a target compare with the target.
pub(crate) fn error_bound(gathered: &[Gathered], dof: usize) -> Option<f64> {
    relative_std_error(gathered).map(|error| error * chi2_scale(dof))
}

/// `√(dof/χ²₀.₁(dof))`: an estimated standard error with `dof` degrees of freedom to its 90 %
/// upper bound.
pub(crate) fn chi2_scale(dof: usize) -> f64 {
    (dof as f64 / chi2_lower(dof)).sqrt()
}

/// The lower 10 % quantile of χ² with `k` degrees of freedom (Wilson–Hilferty:
/// `k·(1 − 2/(9k) − 1.2816·√(2/(9k)))³`, floored at `k/1000`).
fn chi2_lower(k: usize) -> f64 {
    let k = k.max(1) as f64;
    let c = 2.0 / (9.0 * k);
    (k * (1.0 - c - 1.281_551_6 * c.sqrt()).max(0.0).powi(3)).max(k / 1000.0)
}

/// What a gather at a set of output points (a mesh's vertices, the probes) measured beside B.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct GatherStats {
    /// Share of B (all bands) that came from the networks: area-weighted over a mesh's
    /// triangles, a plain mean over probes.
    pub network_share: f64,
    /// [`relative_std_error`] of the values (None unless the gather measures it).
    pub relative_std_error: Option<f64>,
    /// The most shadow and cosine rays (each) any point got ([`Gathered::rays`]).
    pub rays: usize,
    /// Every value is 0 in every band (and there is at least one): no light reached the points.
    pub dark: bool,
    /// Whether the rounds were guided ([`Gathered::guided`]; `--guiding auto` decides).
    pub guided: bool,
    /// What `--guiding auto`'s trial measured before the gather's rounds (None from
    /// [`GatherStats::of`]: the output stage adds it, `estimator::relay::take_trial`).
    pub trial: Option<crate::gather::GuidingTrial>,
}

impl GatherStats {
    /// The statistics of gathered values, the network share a plain mean over the points.
    pub fn of(gathered: &[Gathered]) -> Self {
        let (mut total, mut net) = (0.0, 0.0);
        for g in gathered {
            total += g.radiosity.iter().sum::<f64>();
            net += g.from_networks.iter().sum::<f64>();
        }
        Self {
            network_share: if total > 0.0 { net / total } else { 0.0 },
            relative_std_error: relative_std_error(gathered),
            guided: gathered.iter().any(|g| g.guided),
            trial: None,
            rays: gathered.iter().map(|g| g.rays).max().unwrap_or(0),
            dark: !gathered.is_empty()
                && gathered
                    .iter()
                    .all(|g| g.radiosity.iter().all(|v| *v == 0.0)),
        }
    }
}

/// The estimated relative error of gathered values, ‖σ‖₂/‖B‖₂ over points and bands from their
/// standard errors σ, over the points the gather estimated (σ ≠ 0: points that do not reflect have
/// B = E exactly, and a bright emitter among them would make the ratio look small); None when the
/// gather measured none (every σ is 0).
pub fn relative_std_error(gathered: &[Gathered]) -> Option<f64> {
    let (mut v, mut b) = (0.0, 0.0);
    for g in gathered
        .iter()
        .filter(|g| g.std_error.iter().any(|s| *s != 0.0))
    {
        for k in 0..BANDS {
            v += g.std_error[k] * g.std_error[k];
            b += g.radiosity[k] * g.radiosity[k];
        }
    }
    (v > 0.0 && b > 0.0).then(|| (v / b).sqrt())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::config::GatherMode;
    use crate::config::PathSettings;
    use crate::emitters::Emitters;
    use crate::estimator::radiosity_at_points;
    use crate::solve::Trained;
    use scene_sampler::{AnyScene, KernelSampler, SceneBvh, builtin};

    /// The paths gather run to a target error in the furnace (B = E/(1 − ρ) everywhere): it stops
    /// with its estimate at most the target, in more than one round, the rounds' merged values are
    /// unbiased (mean of 300 points within 4 standard errors of the exact B) and their standard
    /// errors still predict the spread (Σ error² / Σ σ² in [0.5, 2]); a tighter target takes
    /// more rays.
    #[test]
    fn the_paths_gather_reaches_its_target_error_in_rounds() {
        let AnyScene::ThreeD(scene) = builtin("furnace").unwrap() else {
            panic!()
        };
        let (e, rho) = (scene.faces[0].emission.0[0], scene.faces[0].rho.0[0]);
        let exact = e / (1.0 - rho);
        let bvh = SceneBvh::new(&scene);
        let domain = Domain::ThreeD(KernelSampler::new(&scene, &bvh));
        let points: Vec<(DVec3, DVec3, u32)> = scene_sampler::SurfaceSampler::new(&scene)
            .spread(300, |_| true)
            .into_iter()
            .map(|q| (q.point, q.normal, q.face))
            .collect();
        let run = |target: f64| {
            let config = SolveConfig {
                gather: GatherMode::Paths,
                gather_samples: GatherSamples {
                    direct: 4,
                    indirect: 4,
                },
                paths: PathSettings {
                    target_error: Some(target),
                    ..PathSettings::default()
                },
                ..SolveConfig::default()
            };
            let trained = Trained::without_networks(&domain, &config);
            radiosity_at_points(&domain, &trained, &Emitters::new(&domain), &config, &points)
                .unwrap()
        };
        let mut rays = Vec::new();
        for target in [0.02, 0.005] {
            let g = run(target);
            let estimate = relative_std_error(&g).unwrap();
            assert!(
                estimate <= target,
                "estimate {estimate} above target {target}"
            );
            assert!(g[0].rays > 4, "one round only ({} rays)", g[0].rays);
            let (mut sum, mut var, mut sq) = (0.0, 0.0, 0.0);
            for x in &g {
                sum += x.radiosity[0];
                var += x.std_error[0].powi(2);
                sq += (x.radiosity[0] - exact).powi(2);
            }
            let n = g.len() as f64;
            let (mean, se) = (sum / n, var.sqrt() / n);
            assert!(
                (mean - exact).abs() < 4.0 * se,
                "target {target}: mean {mean} vs {exact} (±{se})"
            );
            let ratio = sq / var;
            assert!(
                (0.5..2.0).contains(&ratio),
                "target {target}: Σ error² / Σ σ² = {ratio}"
            );
            rays.push(g[0].rays);
        }
        assert!(rays[1] > rays[0], "rays {rays:?}");
    }

    /// The stopping bound's χ² quantile: close to k for many degrees of freedom, far below it
    /// for one (the 10 % quantile of χ²₁ is 0.0158; the approximation is lower, so safer).
    #[test]
    fn the_chi_square_quantile_is_conservative_for_few_points() {
        assert!((chi2_lower(20_000) / 20_000.0 - 0.987).abs() < 0.002);
        assert!((chi2_lower(100) - 82.36).abs() < 0.5, "{}", chi2_lower(100));
        assert!(chi2_lower(1) < 0.0158);
    }

    /// A synthetic estimate of B = 1 at point `i` over `rays` rays of relative variance 1 per
    /// ray: each replicate's value 1 ± √(2/rays), the sign a hash of `i`, `key` and the replicate.
    fn synthetic(i: usize, key: usize, rays: usize) -> PointEstimate {
        let mut share = [[0.0; BANDS]; REPLICATES];
        for (r, s) in share.iter_mut().enumerate() {
            // SplitMix64's finalizer
            let mut z = ((i as u64) << 32) ^ ((key as u64) << 4) ^ r as u64;
            z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
            z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
            let sign = if (z ^ (z >> 31)) % 2 == 0 { 1.0 } else { -1.0 };
            *s = [(1.0 + sign * (2.0 / rays as f64).sqrt()) / REPLICATES as f64; BANDS];
        }
        PointEstimate {
            share,
            replicates: REPLICATES,
            rays,
            reflects: true,
            ..PointEstimate::default()
        }
    }

    const PILOT: GatherSamples = GatherSamples {
        direct: 64,
        indirect: 64,
    };

    /// The rounds of 1 000 [`synthetic`] points (64-ray pilot) to `target` with `guiding` (every
    /// round guided for `On`, none for `Off`): their values and each call's (first Sobol index,
    /// rays), in order, repeats of a round's groups removed.
    fn synthetic_rounds(target: f64, guiding: Guiding) -> (Vec<Gathered>, Vec<(usize, usize)>) {
        let n = 1000;
        let calls = std::sync::Mutex::new(Vec::new());
        let estimate = |g: &[usize], first: usize, samples: GatherSamples, guided: bool| {
            assert_eq!(guided, guiding == Guiding::On);
            calls.lock().unwrap().push((first, samples.indirect));
            let rays = samples.indirect;
            g.iter().map(|&i| synthetic(i, first, rays)).collect()
        };
        let bound = |g: &[Gathered], dof: usize| error_bound(g, dof);
        let g = rounds_to_target(
            n,
            &singletons(n),
            estimate,
            (PILOT, None),
            (target, &bound),
            (1 << 20, guiding),
        );
        let mut calls: Vec<(usize, usize)> = calls.into_inner().unwrap();
        calls.dedup();
        (g, calls)
    }

    /// A round that meets the target part-way stops there: 1 000 [`synthetic`] points to
    /// 1.45 %. The rounds go 64, 256, 1 024, 4 096 rays per point (bound ≈ 1.64 % there), the
    /// rounds from 256 on in parts of a quarter of the points so far per replicate (32, then 128,
    /// then 512), and the round to 8 192 stops after its first part, at 5 120 rays (bound ≈
    /// 1.44 %; whole, 8 192; in parts of [`PART`], 6 144). Every part is an aligned block of the
    /// sequence (its first Sobol index a multiple of its points) and every round continues the
    /// sequence where the rays so far end.
    #[test]
    fn a_round_stops_at_the_part_that_meets_the_target() {
        let (g, starts) = synthetic_rounds(0.0145, Guiding::Off);
        assert_eq!(g[0].rays, 5120);
        assert!(error_bound(&g, g.len()).unwrap() <= 0.0145);
        assert_eq!(starts[..3], [(0, 64), (32, 192), (128, 64)]);
        assert_eq!(starts.last(), Some(&(2048, 1024)));
        for w in starts.windows(2) {
            assert_eq!(w[1].0, w[0].0 + w[0].1 / REPLICATES, "{starts:?}");
        }
        for &(first, rays) in &starts[2..] {
            assert_eq!(first % (rays / REPLICATES), 0, "{starts:?}");
        }
        // the parts' sizes: a quarter of the points so far per replicate
        assert_eq!(starts[2..].iter().filter(|c| c.1 == 64).count(), 12);
        assert_eq!(starts.iter().filter(|c| c.1 == 256).count(), 12);
    }

    /// Parts ([`parts`]): a quarter of the points so far per replicate, a power of two dividing
    /// them, from [`MIN_PART`] to [`PART`]; whole below, or when not asked for.
    #[test]
    fn parts_are_aligned_blocks_of_a_quarter_of_the_points_so_far() {
        assert_eq!(parts(None, 512), [(0, 512)]);
        assert_eq!(parts(Some(32), 192), [(0, 192)], "a part of 8 is too small");
        assert_eq!(
            parts(Some(128), 256),
            [(0, 64), (32, 64), (64, 64), (96, 64)]
        );
        // 160 so far per replicate (a part-way stop): parts of 32
        assert_eq!(parts(Some(160), 192).len(), 3);
        assert!(
            parts(Some(1 << 14), 1 << 15)
                .iter()
                .all(|p| p.1 == PART * REPLICATES)
        );
    }

    /// `--guiding auto` guides only where its guides fit: 50 000 groups need about 280 MB.
    #[test]
    fn automatic_guiding_needs_the_memory_of_its_guides() {
        assert!(guides_fit(50_000, None));
        assert!(guides_fit(50_000, Some(300 << 20)));
        assert!(!guides_fit(50_000, Some(200 << 20)));
        assert!(
            !guides_fit(10, Some(100 << 20)),
            "the records' and cells' 185 MB"
        );
    }

    /// A guided round: a quarter to twice the rays so far per replicate, a power of two below
    /// 1 024 and a multiple of [`GUIDED_STEP`] above, at most the cap.
    #[test]
    fn guided_rounds_take_unions_of_balanced_nets() {
        // 336 rays so far (168 per replicate): 100 missing, 50 per replicate → 64
        assert_eq!(guided_round(100, 336, 1 << 20), 128);
        // 1 360 so far (680): 3 115 missing → 1 558, at most 1 361 → 1 536 per replicate
        assert_eq!(guided_round(3115, 1360, 1 << 20), 3072);
        // 5 456 so far (2 728): 4 100 missing → 2 050 → 2 304 per replicate
        assert_eq!(guided_round(4100, 5456, 1 << 20), 4608);
        // the cap
        assert_eq!(guided_round(1 << 20, 5456, 8192), 8192 - 5456);
    }

    /// Guided rounds run whole: each round of [`synthetic`] points to 0.4 % is one call (its own
    /// `first`), a round of at least 2·[`PART`] rays per replicate among them, and a point's rays
    /// are the sum of the rounds'. (In parts, the door gap's heavy-tailed guided rounds stopped on
    /// a low estimate: 2.64 % measured against 1.83 % estimated; [`PARTS_FROM`].)
    #[test]
    fn guided_rounds_run_whole() {
        let (g, calls) = synthetic_rounds(0.004, Guiding::On);
        assert!(error_bound(&g, g.len()).unwrap() <= 0.004);
        let firsts: std::collections::BTreeSet<usize> = calls.iter().map(|c| c.0).collect();
        assert_eq!(firsts.len(), calls.len(), "{calls:?}");
        assert!(
            calls.iter().any(|c| c.1 >= 2 * PART * REPLICATES),
            "{calls:?}"
        );
        assert_eq!(g[0].rays, calls.iter().map(|c| c.1).sum::<usize>());
    }
}

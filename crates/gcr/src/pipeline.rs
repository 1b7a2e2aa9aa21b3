//! From a trained solution to outputs: radiosity at arbitrary surface points by the three gathers,
//! the re-triangulated output mesh, and probe values.

use crate::config::GatherSamples;
use crate::config::{GatherMode, SolveConfig};
use crate::domain::Domain;
use crate::element::{BANDS, Bands};
use crate::emitters::Emitters;
use crate::gather::{Gathered, gather};
use crate::mesh::ShadedMesh;
use crate::paths::{PathGather, PointEstimate, REPLICATES};
use crate::refine::{RefineLimits, refine};
use crate::retriangulate::{RetriangulateLimits, retriangulate};
use crate::solve::Trained;
use crate::spatial::BoxGrid;
use glam::DVec3;
use rayon::prelude::*;

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
    check_base(trained, config)?;
    let frame = domain.frame();
    let paths = path_gather(domain, trained, emitters, config);
    if let (GatherMode::Paths, Some(target)) = (config.gather, config.paths.target_error) {
        let seeds: Vec<u64> = points
            .iter()
            .map(|&(y, _, _)| point_seed(config.seed, y, frame))
            .collect();
        return Ok(paths_to_target(
            domain, &paths, points, &seeds, target, config,
        ));
    }
    Ok(points
        .par_iter()
        .map_init(Vec::new, |scratch, &(y, n, face)| {
            let seed = point_seed(config.seed, y, frame);
            radiosity_at(
                (domain, trained, emitters, &paths),
                config,
                (y, n, face),
                seed,
                scratch,
            )
        })
        .collect())
}

/// Irradiance E(y, n) = ∫ L cos θ dω at any points `(point, unit normal)` — on a surface or in the
/// air, as Radiance's `rtrace -I` — by the paths gather ([`PathGather::estimate_irradiance`]),
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
    if config.gather != GatherMode::Paths {
        return Err(GatherError::IrradianceNeedsPaths(config.gather.name()));
    }
    let frame = domain.frame();
    let paths = path_gather(domain, trained, emitters, config);
    let seeds: Vec<u64> = points
        .iter()
        .map(|&(y, _)| point_seed(config.seed ^ IRRADIANCE_SALT, y, frame))
        .collect();
    Ok(match config.paths.target_error {
        Some(target) => {
            // receivers in the air (on no face), white, not emitting: they share paths as
            // surface points do
            let receivers: Vec<_> = points
                .iter()
                .map(|&(y, n)| (y, n, scene_sampler::NO_FACE))
                .collect();
            let white = |_| ([1.0; BANDS], [0.0; BANDS]);
            grouped_rounds(domain, &paths, &receivers, white, &seeds, target, config)
        }
        None => (0..points.len())
            .into_par_iter()
            .map(|i| {
                (paths.estimate_irradiance(points[i], seeds[i], 0, config.gather_samples))
                    .gathered()
            })
            .collect(),
    })
}

/// The paths gather of a solution, its networks' reflected radiosity as C.
fn path_gather<'a>(
    domain: &'a Domain<'a>,
    trained: &'a Trained,
    emitters: &'a Emitters,
    config: &SolveConfig,
) -> PathGather<'a, impl Fn(DVec3, DVec3) -> Bands + Sync + 'a> {
    PathGather::new(
        domain,
        emitters,
        |x, n| trained.reflected_kernel(x, n),
        config.gather_samples,
        config.paths,
    )
}

/// Mixed into the solve's seed for irradiance probes ([`irradiance_at_points`]).
const IRRADIANCE_SALT: u64 = 0x6972_7261_6469_616E;

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
fn paths_to_target(
    domain: &Domain,
    paths: &PathGather<impl Fn(DVec3, DVec3) -> Bands + Sync>,
    points: &[(DVec3, DVec3, u32)],
    seeds: &[u64],
    target: f64,
    config: &SolveConfig,
) -> Vec<Gathered> {
    let material =
        |(y, _, face): (DVec3, DVec3, u32)| (domain.reflectance_at(face, y), domain.emission(face));
    grouped_rounds(domain, paths, points, material, seeds, target, config)
}

/// [`rounds_to_target`] over the groups of neighbouring `points` ([`crate::neighbours::groups`],
/// at most `PathSettings::neighbours` a group), each round of a group by
/// [`PathGather::estimate_group`] with the members' (ρ, E) from `material`.
fn grouped_rounds(
    domain: &Domain,
    paths: &PathGather<impl Fn(DVec3, DVec3) -> Bands + Sync>,
    points: &[(DVec3, DVec3, u32)],
    material: impl Fn((DVec3, DVec3, u32)) -> (Bands, Bands) + Sync,
    seeds: &[u64],
    target: f64,
    config: &SolveConfig,
) -> Vec<Gathered> {
    let groups = crate::neighbours::groups(domain, points, config.paths.neighbours);
    rounds_to_target(
        points.len(),
        &groups,
        |group: &[usize], first, samples| {
            let members: Vec<_> = group.iter().map(|&i| points[i]).collect();
            let materials: Vec<_> = members.iter().map(|&p| material(p)).collect();
            let member_seeds: Vec<u64> = group.iter().map(|&i| seeds[i]).collect();
            paths.estimate_group(&members, &materials, &member_seeds, first, samples)
        },
        (config.gather_samples, None),
        (target, &error_bound),
        config.paths.max_rays,
    )
}

/// The rounds of [`paths_to_target`] for `count` estimates gathered in `groups` (each index in
/// exactly one), `estimate(group, first, samples)` being the group's round with `samples` rays per
/// member from Sobol index `first` on, one estimate per member (a point's gather, a group of
/// neighbours sharing paths, [`PathGather::estimate_group`], a pixel's footprint). `piloted`:
/// the pilot round's estimates when the caller has run it (`output::adaptive`).
pub(crate) fn rounds_to_target(
    count: usize,
    groups: &[Vec<usize>],
    estimate: impl Fn(&[usize], usize, GatherSamples) -> Vec<PointEstimate> + Sync,
    (pilot, piloted): (GatherSamples, Option<Vec<PointEstimate>>),
    (target, bound_of): (f64, &ErrorBound<'_>),
    max_rays: usize,
) -> Vec<Gathered> {
    let pilot_rays = pilot.direct.max(pilot.indirect).min(max_rays);
    let reporter = crate::progress::Reporter::new(count, pilot_rays, target);
    let round = |first: usize, samples: GatherSamples| -> Vec<PointEstimate> {
        let per_group: Vec<Vec<PointEstimate>> = groups
            .par_iter()
            .map(|g| {
                let e = estimate(g, first, samples);
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
    // ⟨Pilot round: the configured rays⟩
    let mut estimates = piloted.unwrap_or_else(|| round(0, pilot));
    let mut rays = pilot_rays;
    loop {
        let gathered: Vec<Gathered> = estimates.iter().map(PointEstimate::gathered).collect();
        // ⟨Stop at the target (its upper confidence bound) or the ray cap⟩
        // one degree of freedom per group with a reflecting point: a group's members share
        // their paths, so their standard errors come from the same two replicates
        let dof = (groups.iter())
            .filter(|g| (g.iter()).any(|&i| gathered[i].std_error.iter().any(|s| *s != 0.0)))
            .count();
        let Some(bound) = bound_of(&gathered, dof) else {
            return gathered;
        };
        if bound <= target || rays >= max_rays {
            reporter.round(bound, rays, rays);
            return gathered;
        }
        // ⟨Next round: each replicate's Sobol points up to the next power of two that covers the
        // missing rays (variance ∝ 1/rays), at least twice and at most four times as many as so
        // far. Owen-scrambled Sobol points are a balanced net only at powers of two: two-blockers'
        // pixels at 296 rays (148 per replicate) had 13× the relative MSE of 512, cornell-box's
        // and wall-floor's the same or 1.5× per ray (docs/images.md). The cap keeps a long
        // extrapolation from overshooting (the points converge faster than 1/√rays at first)⟩
        let needed = (rays as f64 * (bound / target).powi(2)).ceil() as usize;
        let per = rays.div_ceil(REPLICATES);
        let want = (needed.div_ceil(REPLICATES))
            .clamp(per + 1, 4 * per)
            .next_power_of_two();
        let more = (want * REPLICATES)
            .min(max_rays)
            .saturating_sub(rays)
            .max(REPLICATES);
        reporter.round(bound, rays + more, needed.min(max_rays));
        // Each replicate has used ⌈rays / REPLICATES⌉ Sobol points of its sequence so far.
        let samples = GatherSamples {
            direct: more,
            indirect: more,
        };
        let next = round(rays.div_ceil(REPLICATES), samples);
        for (e, n) in estimates.iter_mut().zip(&next) {
            e.merge(n);
        }
        rays += more;
    }
}

/// The error a round to a target compares with the target: of the values gathered so far and
/// their degrees of freedom (one per group with a standard error), None when nothing was measured
/// ([`error_bound`], or the per-pixel relative error of `output::adaptive`).
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

/// Radiosity at surface point (y, n, face) by the configured gather ([`check_base`] first).
fn radiosity_at(
    (domain, trained, emitters, paths): (
        &Domain,
        &Trained,
        &Emitters,
        &PathGather<impl Fn(DVec3, DVec3) -> Bands>,
    ),
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

/// The output mesh's starting resolution when no network was trained (the paths gather reads
/// none): the edge of this many equilateral triangles covering the scene. Coarse on purpose:
/// [`crate::refine`] then splits where B varies (shadows), which on cornell-box's floor resolves
/// the short block's shadow better, and sooner, than starting from the networks' resolution
/// (docs/bakes.md). Faces already smaller than the edge are kept as they are.
pub const UNIFORM_MESH_TRIANGLES: f64 = 150.0;

/// The local edge length the shading network asks for near `p`: the width (mean edge length,
/// eq. 2.10) of the nearest shading cell. Without networks ([`Trained::without_networks`]) one
/// edge everywhere: that of [`UNIFORM_MESH_TRIANGLES`] equilateral triangles covering the scene.
pub struct LocalEdge {
    centres: Vec<DVec3>,
    widths: Vec<f64>,
    grid: BoxGrid,
    reach: f64,
    /// The edge where there are no cells.
    uniform: f64,
}

impl LocalEdge {
    /// Indexes the shading cells of the last FEM step; when the shading network was skipped
    /// (`SolveConfig::skip_unused_base`), the kernel cells' receiver halves and widths, which set
    /// the detail of B_refl.
    pub fn new(trained: &Trained, total_area: f64) -> Self {
        let geo = &trained.fem.base.geo;
        let (centres, widths) = if geo.is_empty() {
            (trained.kernel.wy.clone(), trained.kernel.width.clone())
        } else {
            (geo.centres.clone(), geo.widths.clone())
        };
        let mean = widths.iter().sum::<f64>() / widths.len().max(1) as f64;
        let reach = 2.0 * mean.max(1e-300);
        Self {
            grid: BoxGrid::new(centres.iter().map(|c| (*c, *c)).collect(), reach),
            centres,
            widths,
            reach,
            // an equilateral triangle of edge e has area √3/4 · e²
            uniform: (4.0 * total_area / (3f64.sqrt() * UNIFORM_MESH_TRIANGLES)).sqrt(),
        }
    }

    /// Width of the nearest cell to `p` (the uniform edge when there are no cells).
    pub fn at(&self, p: DVec3) -> f64 {
        if self.centres.is_empty() {
            return self.uniform;
        }
        let mut near = Vec::new();
        let mut r = self.reach;
        for _ in 0..6 {
            self.grid.query_ball(p, r, &mut near);
            if !near.is_empty() {
                break;
            }
            r *= 4.0;
        }
        let pick = |it: &mut dyn Iterator<Item = usize>| {
            it.min_by(|&a, &b| {
                self.centres[a]
                    .distance_squared(p)
                    .total_cmp(&self.centres[b].distance_squared(p))
            })
        };
        let best = if near.is_empty() {
            pick(&mut (0..self.centres.len()))
        } else {
            pick(&mut near.iter().map(|&i| i as usize))
        };
        best.map_or(self.uniform, |i| self.widths[i])
    }
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

/// Where [`output_mesh`] gathers B for a vertex at `p` of `face`: 10⁻⁴ of the way from `p` to the
/// face's centroid. A vertex on an edge of its face where another face meets it (a block standing
/// on the floor, the floor at a wall) gathers, exactly there, about half its B: the adjoining
/// face, within the ray offsets of the point, blocks the rays that leave toward it (measured on
/// cornell-box, docs/bakes.md). The move is far below the mesh's resolution.
pub fn vertex_gather_point(face: &scene_sampler::Face, p: DVec3) -> DVec3 {
    p + 1e-4 * (face.centroid() - p)
}

/// Re-triangulates the scene to the shading network's resolution (sec. 4.3.1) and gathers B at
/// every vertex ([`radiosity_at_points`], at [`vertex_gather_point`]); with the paths gather the
/// mesh is then refined where B varies faster than linear interpolation follows
/// ([`crate::refine`]: shadow edges). Returns the mesh and what the gather measured.
pub fn output_mesh(
    domain: &Domain,
    trained: &Trained,
    config: &SolveConfig,
    limits: RetriangulateLimits,
) -> Result<(ShadedMesh, GatherStats), GatherError> {
    let Domain::ThreeD(k) = domain else {
        return Ok((ShadedMesh::default(), GatherStats::default()));
    };
    let scene = k.scene;
    let faces: Vec<[DVec3; 3]> = scene.faces.iter().map(|f| f.v).collect();
    let local = LocalEdge::new(trained, scene.total_area());
    let tri = retriangulate(&faces, |p| local.at(p), limits);
    let mut vertex_face = vec![0u32; tri.positions.len()];
    for (t, f) in tri.triangles.iter().zip(&tri.face_of_triangle) {
        for &v in t {
            vertex_face[v as usize] = *f;
        }
    }
    let emitters = Emitters::new(domain);
    let gather_at = |at: &[(DVec3, u32)]| {
        let points: Vec<(DVec3, DVec3, u32)> = (at.iter())
            .map(|&(p, f)| {
                let face = &scene.faces[f as usize];
                (vertex_gather_point(face, p), face.normal, f)
            })
            .collect();
        radiosity_at_points(domain, trained, &emitters, config, &points)
    };
    let vertices: Vec<(DVec3, u32)> = tri.positions.iter().copied().zip(vertex_face).collect();
    // ⟨Gather once where coplanar faces of one material share a vertex (crate::weld)⟩
    let welded = crate::weld::weld(&scene.faces, k.bvh, scene.diagonal(), &vertices);
    let at: Vec<(DVec3, u32)> = welded.gathered.iter().map(|&v| vertices[v]).collect();
    let phase = crate::progress::phase("mesh");
    let once = gather_at(&at)?;
    drop(phase);
    let gathered = welded.representative.iter().map(|&r| once[r]).collect();
    // ⟨Refine where B varies faster than linear interpolation follows (shadow edges)⟩
    let (tri, gathered) = if config.gather == GatherMode::Paths {
        let refine_limits = RefineLimits::for_diagonal(scene.diagonal());
        let _phase = crate::progress::phase("refinement");
        refine(tri, gathered, refine_limits, gather_at)?
    } else {
        (tri, gathered)
    };
    // Network share: area-weighted over triangles, all bands.
    let (mut total, mut net) = (0.0, 0.0);
    for t in &tri.triangles {
        let [a, b, c] = t.map(|i| tri.positions[i as usize]);
        let area = 0.5 * (b - a).cross(c - a).length();
        for &v in t {
            let g = &gathered[v as usize];
            total += area * g.radiosity.iter().sum::<f64>();
            net += area * g.from_networks.iter().sum::<f64>();
        }
    }
    let grey = domain.bands() == 1;
    let mesh = ShadedMesh {
        positions: tri.positions,
        triangles: tri.triangles,
        face_of_triangle: tri.face_of_triangle,
        radiosity: gathered
            .iter()
            .map(|g| {
                if grey {
                    [g.radiosity[0]; 3]
                } else {
                    g.radiosity
                }
            })
            .collect(),
    };
    let stats = GatherStats {
        network_share: if total > 0.0 { net / total } else { 0.0 },
        ..GatherStats::of(&gathered)
    };
    Ok((mesh, stats))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::config::PathSettings;
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
}

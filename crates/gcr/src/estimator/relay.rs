//! Drawing from the table of secondary sources (`secondary.rs`) at the vertices of the paths
//! gather, its weights against the bounces, and `Guiding::Auto`'s trial of whether it pays
//! (docs/design/estimator.md, "Secondary sources").

use super::guide::Guide;
use super::paths::{PathGather, SobolRay, Vertex};
use super::secondary::SecondarySources;
use crate::domain::Domain;
use crate::element::{BANDS, Bands};
use crate::gather::{GuidingTrial, Mis, geometry_3d};
use glam::DVec3;
use rand::Rng;
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;

/// Groups of neighbours in the trial that decides whether the table pays, at most
/// ([`table_if_it_pays`]).
const TRIAL_GROUPS: usize = 64;
/// The table is tried only where one ray's relative variance without it (the trial's squared
/// relative error × its rays) is at least this: below, plain paths find the light easily (the
/// Cornell box's points above the blocks 0.014, the closed room's 0.046, the sun patch room's
/// work plane 0.034, lightmaps of two-blockers, wall-floor and the furnace 0.03–0.04).
pub(crate) const TRIAL_VARIANCE: f64 = 0.1;
/// Under this relative variance per ray the table must pay [`EASY_PAYS`], above it
/// [`TABLE_PAYS`]: light that plain paths find fairly well converges faster than 1/rays on their
/// Sobol points, which a trial of a few rays does not show (the Cornell box's 2 000 spread
/// points, 0.22 per ray, tried a ratio of 0.34 but took as long to 0.3 % with the table as
/// without; the closed room's lightmap, 0.23, tried 0.245 and took 81.9 s to 2 % against 61.6 s;
/// the uplight room's lightmap, 0.24, tried 0.07 and took 21.6 s against 53.6 s).
pub(crate) const EASY_VARIANCE: f64 = 0.5;
/// The table is kept where it divides the variance per ray by more than this (hard light: one
/// ray's relative variance at least [`EASY_VARIANCE`]; the uplight room 1.5, the sun patch room's
/// ceiling 6, the door gap 26): its draws cost about as much as the rest of a path (1.75–1.95×
/// the time per ray, measured on the door gap, the sun patch room, the uplight room and the many
/// rooms; docs/design/estimator.md).
pub(crate) const TABLE_PAYS: f64 = 0.5;
/// The ratio the table must reach where one ray's relative variance is between
/// [`TRIAL_VARIANCE`] and [`EASY_VARIANCE`] ([`EASY_VARIANCE`]'s measurements).
pub(crate) const EASY_PAYS: f64 = 0.1;
/// Where one ray's relative variance is under [`EASY_VARIANCE`], the table is tried only when the
/// rays the trial predicts to the target over all the points (variance per ray × points/target²)
/// are at least this many times the table's own next-event rays: a small job pays for the
/// table's build and the trial's second half out of its own time (a 96 × 96 per-pixel image of
/// two-blockers to 5 %, 0.136 per ray, ran 1.16× slower trying it: 0.5 million rays predicted
/// against the table's 131 000).
const EASY_WORK: f64 = 20.0;

/// `Guiding::Auto`'s choice for `paths` (module docs): `variance(paths)`, a trial round's
/// estimated relative variance with `rays` rays per point, first without a table; where one
/// ray's is at least [`TRIAL_VARIANCE`], the table is built (seeded by `seed`) and the trial run
/// again with it, and kept if the ratio of the two variances is under [`TABLE_PAYS`]
/// ([`EASY_PAYS`] where one ray's is under [`EASY_VARIANCE`], and tried there only where the job
/// is large enough, `work` = points/target² the rays per unit variance to the target:
/// [`EASY_WORK`]). What the trial measured, None where nothing could be tried (no light reflected
/// at the trial's points, or no table to draw). Deterministic (a ratio of variances, not of
/// times).
pub(crate) fn table_if_it_pays<'a, C: Fn(DVec3, DVec3) -> Bands + Sync>(
    paths: &mut PathGather<'a, C>,
    variance: impl Fn(&PathGather<'a, C>) -> Option<f64>,
    (rays, seed, work): (usize, u64, f64),
) -> Option<GuidingTrial> {
    paths.secondary = None;
    let plain = variance(paths)?;
    let per_ray = rays as f64 * plain;
    let table_rays = (super::secondary::CELLS * super::secondary::SAMPLES) as f64;
    let small = per_ray < EASY_VARIANCE && per_ray * work < EASY_WORK * table_rays;
    if per_ray < TRIAL_VARIANCE || small {
        return Some(GuidingTrial {
            variance_per_ray: per_ray,
            table_ratio: None,
            table_kept: false,
        });
    }
    paths.build_table(seed);
    paths.secondary.as_ref()?;
    let ratio = variance(paths).map_or(0.0, |with| with / plain);
    let keep = ratio
        < if per_ray < EASY_VARIANCE {
            EASY_PAYS
        } else {
            TABLE_PAYS
        };
    if !keep {
        paths.secondary = None;
    }
    Some(GuidingTrial {
        variance_per_ray: per_ray,
        table_ratio: Some(ratio),
        table_kept: keep,
    })
}

thread_local! {
    /// The trial of the last gather on this thread ([`record_trial`]).
    static LAST_TRIAL: std::cell::Cell<Option<GuidingTrial>> = const { std::cell::Cell::new(None) };
}

/// Records what the trial before a gather measured (None: none ran), on the gather's calling
/// thread, for the output stage that reports it ([`take_trial`]): one value a gather, kept out
/// of its points' values.
pub(crate) fn record_trial(trial: Option<GuidingTrial>) {
    LAST_TRIAL.with(|t| t.set(trial));
}

/// What [`record_trial`] recorded last on this thread, cleared.
pub(crate) fn take_trial() -> Option<GuidingTrial> {
    LAST_TRIAL.with(std::cell::Cell::take)
}

/// The trial of [`table_if_it_pays`] for points in groups of neighbours: one round of `samples`
/// rays at every k-th of the `groups` of `points` (at most [`TRIAL_GROUPS`], the same in every
/// shard: the groups are the whole point set's) with `seeds` and (ρ, E) from `material`; the
/// squared relative error ([`super::relative_std_error`]).
pub(crate) fn group_variance<C: Fn(DVec3, DVec3) -> Bands + Sync>(
    paths: &PathGather<'_, C>,
    groups: &[Vec<usize>],
    (points, seeds): (&[(DVec3, DVec3, u32)], &[u64]),
    material: &(impl Fn((DVec3, DVec3, u32)) -> (Bands, Bands) + Sync),
    samples: crate::config::GatherSamples,
) -> Option<f64> {
    let step = groups.len().div_ceil(TRIAL_GROUPS).max(1);
    let gathered: Vec<crate::gather::Gathered> = (groups.par_iter().step_by(step))
        .flat_map_iter(|g| {
            let members: Vec<_> = g.iter().map(|&i| points[i]).collect();
            let material: Vec<_> = members.iter().map(|&m| material(m)).collect();
            let seeds: Vec<u64> = g.iter().map(|&i| seeds[i]).collect();
            let e = paths.estimate_group(&members, &material, &seeds, (0, samples), None);
            e.into_iter().map(|e| e.gathered())
        })
        .collect();
    super::rounds::relative_std_error(&gathered).map(|e| e * e)
}

impl<C: Fn(DVec3, DVec3) -> Bands> PathGather<'_, C> {
    /// This gather with the table of its scene's secondary sources (seeded by `seed`), drawn at
    /// every vertex ([`PathGather::build_table`]).
    pub(crate) fn with_secondary_sources(mut self, seed: u64) -> Self
    where
        C: Sync,
    {
        self.build_table(seed);
        self
    }

    /// Builds the table of the scene's secondary sources (seeded by `seed`), drawn at every
    /// vertex from then on; none in Flatland or where no light reaches a reflecting face.
    pub(crate) fn build_table(&mut self, seed: u64)
    where
        C: Sync,
    {
        let Domain::ThreeD(kernel) = self.domain else {
            self.secondary = None;
            return;
        };
        let alone = self.lights_alone();
        let scene = kernel.scene;
        let direct = |face: u32, p: DVec3, u: [f64; 3]| {
            let z = Vertex {
                p,
                n: scene.faces[face as usize].normal,
                face,
            };
            self.direct_radiosity(&z, &alone, u).iter().sum::<f64>() / BANDS as f64
        };
        let table = SecondarySources::new(scene, seed, direct).map(std::sync::Arc::new);
        self.secondary = table;
    }

    /// The weights of a next-event estimate that stands alone (one light sample, no cosine ray
    /// to weigh it against: weight 1), as a point drawn from the table gets it.
    pub(crate) fn lights_alone(&self) -> Mis<'_> {
        Mis {
            emitters: self.emitters,
            n_e: 1.0,
            n_c: 0.0,
        }
    }

    /// F̂(z) = ρ(z)·Ĥ_d(z): z's direct radiosity by one shadow ray to a light drawn with `u[0]`
    /// and sampled with `u[1..3]`, MIS-weighted by `mis` (weight 1 with no cosine rays).
    pub(crate) fn direct_radiosity(&self, z: &Vertex, mis: &Mis, u: [f64; 3]) -> Bands {
        let rho = self.domain.reflectance_at(z.face, z.p);
        if rho.iter().all(|r| *r == 0.0) {
            return [0.0; BANDS];
        }
        let h = self.next_event(z, mis, (u[0], [u[1], u[2]]));
        std::array::from_fn(|b| rho[b] * h[b])
    }

    /// A point drawn from the table: its vertex and the table's area density there.
    pub(crate) fn table_draw(&self, u: [f64; 3]) -> Option<(Vertex, f64)> {
        let (Some(table), Domain::ThreeD(k)) = (&self.secondary, self.domain) else {
            return None;
        };
        let ((p, n, face), q) = table.sample(k.scene, u)?;
        Some((Vertex { p, n, face }, q))
    }

    /// The arrival at `x` of a bounce from `from` cast with count density `count` (roulette
    /// probability × branches × a guide's density): its area density p_a = count·G(from, x), per
    /// draw from the table at `from` ([`PathGather::bounce_weight`]); None without a table.
    pub(crate) fn arrival(&self, from: &Vertex, x: &Vertex, count: f64) -> Option<f64> {
        (self.secondary.as_ref()).map(|_| count * geometry_3d(from.p, from.n, x.p, x.n))
    }

    /// The weight of the direct light at x brought to x's predecessor by its bounce: p_a/(p_a + Q(x))
    /// with `arrival` the bounce's area density at x per point drawn from the table there (module
    /// docs of `secondary.rs`); 1 without a table or an arrival.
    pub(crate) fn bounce_weight(&self, x: &Vertex, arrival: Option<f64>) -> f64 {
        match (&self.secondary, self.domain, arrival) {
            (Some(table), Domain::ThreeD(k), Some(pa)) => {
                let q = table.density(k.scene, x.face, x.p);
                if q > 0.0 { pa / (pa + q) } else { 1.0 }
            }
            _ => 1.0,
        }
    }

    /// The table at a path vertex x whose bounce has count `count` and may be guided by `guide`:
    /// (the weight of x's direct light, [`PathGather::bounce_weight`] of `arrival`; x's own draw,
    /// [`PathGather::relay`], with random numbers from `rng`). (1, 0) without a table.
    pub(crate) fn vertex_relay(
        &self,
        x: &Vertex,
        arrival: Option<f64>,
        (guide, count): (Option<&Guide>, f64),
        rng: &mut ChaCha8Rng,
    ) -> (f64, Bands) {
        if self.secondary.is_none() {
            return (1.0, [0.0; BANDS]);
        }
        let u: [f64; 6] = std::array::from_fn(|_| rng.random());
        let q_g = |d: DVec3| guide.map_or(1.0, |g| g.density_toward(x.n, d));
        (self.bounce_weight(x, arrival), self.relay(x, count, q_g, u))
    }

    /// One point z drawn from the table and joined to x: F̂′(z)·G(x, z)·V/(p_a + Q(z)) per unit
    /// ρ_x, with p_a = `count`·q_g(z − x)·G the density of x's bounce at z (module docs of
    /// `secondary.rs`); `u` the random numbers (the table's three, the light's three). 0 without
    /// a table.
    pub(crate) fn relay(
        &self,
        x: &Vertex,
        count: f64,
        q_g: impl Fn(DVec3) -> f64,
        u: [f64; 6],
    ) -> Bands {
        let zero = [0.0; BANDS];
        let (Some((z, q)), Domain::ThreeD(k)) = (self.table_draw([u[0], u[1], u[2]]), self.domain)
        else {
            return zero;
        };
        let g = geometry_3d(x.p, x.n, z.p, z.n);
        if z.face == x.face || g <= 0.0 {
            return zero;
        }
        let from = Domain::surface_point_3d(x.p, x.n, x.face);
        if !k
            .bvh
            .visible(&from, &Domain::surface_point_3d(z.p, z.n, z.face))
        {
            return zero;
        }
        let f = self.direct_radiosity(&z, &self.lights_alone(), [u[3], u[4], u[5]]);
        let w = g / (count * q_g(z.p - x.p) * g + q);
        f.map(|v| v * w)
    }

    /// [`PathGather::relay`] from an output point y that draws one point from the table per
    /// cosine ray (count 1 per draw, unguided), with the Sobol point `u`'s dimensions 12–17.
    pub(crate) fn relay_from_point(&self, y: &Vertex, u: SobolRay) -> Bands {
        if self.secondary.is_none() {
            return [0.0; BANDS];
        }
        let (a, b) = (u.set(3), u.set(4));
        self.relay(y, 1.0, |_| 1.0, [a[0], a[1], a[2], a[3], b[0], b[1]])
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::config::{GatherSamples, PathSettings};
    use crate::emitters::Emitters;
    use crate::estimator::paths::PointEstimate;
    use scene_sampler::{KernelSampler, Scene, SceneBvh};

    /// The shipped scene `stem` with its lighting file.
    fn shipped(stem: &str) -> Scene {
        let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes");
        let mut scene = scene_sampler::load(root.join(format!("{stem}.obj")))
            .unwrap()
            .into_3d()
            .unwrap();
        let lighting = scene_sampler::Lighting::read(&root.join(format!("{stem}.lights.json")));
        scene.add_lights(lighting.unwrap().lights().unwrap());
        scene
    }

    /// Mean and variance of the mean of the values.
    fn stats(v: &[f64]) -> (f64, f64) {
        let n = v.len() as f64;
        let m = v.iter().sum::<f64>() / n;
        (
            m,
            v.iter().map(|a| (a - m).powi(2)).sum::<f64>() / (n - 1.0) / n,
        )
    }

    /// `runs` independent rounds of `rays` rays at each of `points` (irradiance probes), lone
    /// and as one shared group, with and without the table: per point, the four means with the
    /// variances of their means.
    fn rounds(
        scene: &Scene,
        points: &[(DVec3, DVec3)],
        rays: usize,
        runs: u64,
    ) -> Vec<[(f64, f64); 4]> {
        let bvh = SceneBvh::new(scene);
        let d = Domain::ThreeD(KernelSampler::new(scene, &bvh));
        let em = Emitters::new(&d);
        let samples = GatherSamples {
            direct: rays,
            indirect: rays,
        };
        let net = |_: DVec3, _: DVec3| [0.0; BANDS];
        let plain = PathGather::new(&d, &em, net, samples, PathSettings::default());
        let table = PathGather::new(&d, &em, net, samples, PathSettings::default())
            .with_secondary_sources(5);
        assert!(table.secondary.is_some());
        let members: Vec<_> = points
            .iter()
            .map(|&(p, n)| (p, n, scene_sampler::NO_FACE))
            .collect();
        let white = vec![([1.0; BANDS], [0.0; BANDS]); points.len()];
        let value = |e: &PointEstimate| e.gathered().radiosity[0];
        let mut per: Vec<[Vec<f64>; 4]> = vec![Default::default(); points.len()];
        for run in 0..runs {
            let seeds: Vec<u64> = (0..points.len() as u64).map(|i| run * 1000 + i).collect();
            for (k, g) in [&plain, &table].into_iter().enumerate() {
                let group = g.estimate_group(&members, &white, &seeds, (0, samples), None);
                for (i, &(p, n)) in points.iter().enumerate() {
                    let lone = g.estimate_irradiance((p, n), seeds[i], 0, samples);
                    per[i][k].push(value(&lone));
                    per[i][2 + k].push(value(&group[i]));
                }
            }
        }
        per.iter()
            .map(|v| std::array::from_fn(|k| stats(&v[k])))
            .collect()
    }

    /// The table keeps the gather unbiased and finds the sun patch: at eight points under the
    /// sun patch room's ceiling, facing down (lit only by the patch the sun makes on the floor
    /// and what it lights), 48 rounds of 64 rays, lone and shared, with the table agree with
    /// those without it within 4 standard errors at every point (and their squared z-scores
    /// average under 2.5), and vary less: the table's variance is under a quarter of the
    /// plain one's, alone and shared.
    #[test]
    fn the_table_agrees_with_plain_paths_and_finds_the_sun_patch() {
        let scene = shipped("sun-patch-room");
        let points: Vec<(DVec3, DVec3)> = (0..8)
            .map(|i| {
                (
                    DVec3::new(1.0 + 0.02 * i as f64, 2.95, 3.0 + 0.03 * i as f64),
                    -DVec3::Y,
                )
            })
            .collect();
        let r = rounds(&scene, &points, 64, 48);
        let (mut z2, mut n) = (0.0, 0.0);
        for (i, s) in r.iter().enumerate() {
            for (a, b) in [(0, 1), (2, 3), (0, 3)] {
                let z = (s[a].0 - s[b].0) / (s[a].1 + s[b].1).sqrt();
                assert!(z.abs() < 4.0, "point {i}: {:?} vs {:?}", s[a], s[b]);
                z2 += z * z;
                n += 1.0;
            }
            assert!(
                s[1].1 < 0.25 * s[0].1,
                "point {i} alone: {:?} vs {:?}",
                s[1],
                s[0]
            );
            assert!(
                s[3].1 < 0.25 * s[2].1,
                "point {i} shared: {:?} vs {:?}",
                s[3],
                s[2]
            );
        }
        assert!(z2 / n < 2.5, "mean z² {}", z2 / n);
    }

    /// `Guiding::Auto`'s trial: under the sun patch room's ceiling the table divides the variance
    /// per ray many times over and is kept; in the Cornell box plain paths find the light fairly
    /// easily (variance per ray under `EASY_VARIANCE`) and the table is not kept.
    #[test]
    fn the_trial_keeps_the_table_where_light_is_hard_to_find() {
        let trial = |scene: &Scene, points: Vec<(DVec3, DVec3, u32)>| {
            let bvh = SceneBvh::new(scene);
            let d = Domain::ThreeD(KernelSampler::new(scene, &bvh));
            let em = Emitters::new(&d);
            let samples = GatherSamples {
                direct: 16,
                indirect: 16,
            };
            let net = |_: DVec3, _: DVec3| [0.0; BANDS];
            let mut g = PathGather::new(&d, &em, net, samples, PathSettings::default());
            let groups: Vec<Vec<usize>> = (0..points.len()).map(|i| vec![i]).collect();
            let seeds: Vec<u64> = (0..points.len() as u64).collect();
            let material = |(y, _, face): (DVec3, DVec3, u32)| match face {
                scene_sampler::NO_FACE => ([1.0; BANDS], [0.0; BANDS]),
                _ => (d.reflectance_at(face, y), d.emission(face)),
            };
            let at = (&points[..], &seeds[..]);
            let variance =
                |p: &PathGather<'_, _>| group_variance(p, &groups, at, &material, samples);
            let choice = table_if_it_pays(&mut g, variance, (16, 1, 1e12));
            (choice, g.secondary.is_some())
        };
        let ceiling = (0..64)
            .map(|i| {
                let (x, z) = (0.5 + 0.7 * (i % 8) as f64, 0.5 + 0.9 * (i / 8) as f64);
                (DVec3::new(x, 2.95, z), -DVec3::Y, scene_sampler::NO_FACE)
            })
            .collect();
        match trial(&shipped("sun-patch-room"), ceiling) {
            (Some(t), true) if t.table_kept => {
                let (v, ratio) = (t.variance_per_ray, t.table_ratio.unwrap());
                assert!(ratio < 0.2 && v >= TRIAL_VARIANCE, "ratio {ratio}, {v}")
            }
            other => panic!("sun patch room: {other:?}"),
        }
        let cornell = scene_sampler::builtin("cornell-box")
            .unwrap()
            .into_3d()
            .unwrap();
        let points = scene_sampler::SurfaceSampler::new(&cornell)
            .spread(64, |_| true)
            .into_iter()
            .map(|q| (q.point, q.normal, q.face))
            .collect();
        match trial(&cornell, points) {
            (Some(t), false) if !t.table_kept => match t.table_ratio {
                None => assert!(t.variance_per_ray < TRIAL_VARIANCE, "variance {t:?}"),
                Some(ratio) => {
                    let v = t.variance_per_ray;
                    assert!(v < EASY_VARIANCE && ratio >= EASY_PAYS, "{v}, {ratio}")
                }
            },
            other => panic!("cornell box: {other:?}"),
        }
    }
}

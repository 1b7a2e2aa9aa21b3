//! Per-pixel images (`--image-mode pixel`, beyond the dissertation): B by the output gather at
//! the surfaces the pixels see, instead of rasterizing the output mesh. Pixel (i, j) of W × H
//! covers [i, i + 1) × [j, j + 1) of the camera of [`super::raster`] (centre ((i + ½)/W,
//! (j + ½)/H): Mitsuba's `perspective` framing); a pixel is the mean of L = B/π over it (a box
//! filter; back faces are black, the background shows the scene's sky or environment map, if any).
//!
//! * **The paths gather with every ray corrected (the default)**: each pixel's footprint is
//!   estimated as a whole ([`render_footprints`]): every ray has its own point in the pixel, where
//!   it gets E, one shadow ray and one cosine ray continued as a path — a path tracer with Owen-
//!   scrambled Sobol points over the pixel and the first bounce, in rounds to the target error of
//!   the pixels (`--quality`, `--target-error`), with their standard errors. Each pixel's rays
//!   follow its standard deviation ([`super::adaptive`]): edges (an emitter's outline dominates a
//!   Cornell box's squared error) get many, flat walls few.
//! * **The other gathers** read the networks at fixed points: `--pixel-samples N` sub-samples per
//!   pixel (1: the centre; N: the first N points of the R2 sequence `frac(½ + k·(α₁, α₂))`), B
//!   gathered at each visible point ([`radiosity_at_points`]), their mean. A pixel's error is its
//!   sub-samples' over √N, so a target applies to each sub-sample ×√N.
//!
//! No mesh is needed: the image has the gather's accuracy at every pixel, not the bake's at its
//! vertices.

use super::raster::{Coverage, PinholeCamera, RadianceImage};
use super::tonemap::{Exposure, srgb_encode};
use crate::Trained;
use crate::config::SolveConfig;
use crate::config::{GatherMode, Guiding};
use crate::domain::Domain;
use crate::emitters::Emitters;
use crate::estimator::paths::{FirstHit, PathGather, PointEstimate};
use crate::estimator::pixel_rounds::{pixel_error, relative_floor};
use crate::estimator::relay::table_if_it_pays;
use crate::estimator::{GatherError, GatherStats, radiosity_at_points};
use crate::gather::Gathered;
use crate::gather::GuidingTrial;
use glam::DVec3;
use rayon::prelude::*;

/// R2 sequence steps (1/φ₂ and 1/φ₂², φ₂ the plastic number): the sub-sample offsets.
const R2: [f64; 2] = [0.754_877_666_246_692_7, 0.569_840_290_998_053_3];

/// What one sub-sample's ray saw.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Seen {
    /// Nothing (background, black).
    Nothing,
    /// The back of a face (black).
    Back,
    /// The front of a face: B there (its index among the gathered points).
    Front(usize),
}

/// A per-pixel image before it is encoded: B at each sub-sample's visible point.
#[derive(Clone, Debug)]
pub struct PixelImage {
    width: u32,
    height: u32,
    spp: u32,
    seen: Vec<Seen>,
    /// B at the front hits (footprints: per pixel), in the order of [`Seen::Front`].
    radiosity: Vec<[f64; 3]>,
    /// Whether each entry of `radiosity` enters the automatic exposure: a front hit that does not
    /// emit (left out, like the emitters of a mesh).
    lit: Vec<bool>,
    /// What the sub-samples (footprints: the pixel centres) saw.
    coverage: Coverage,
    /// What the gather measured at the hits (with a shard: at its pixels).
    pub stats: GatherStats,
    /// With a shard (footprints only): every pixel's estimate (the others' left at
    /// `Gathered::default()`) and the shard's pixels (ascending), for its partial output.
    pub(super) shard: Option<(Vec<Gathered>, Vec<usize>)>,
}

/// Seen fractions of a list of sub-samples; `lit(k, i)`: whether sub-sample `k`, which sees the
/// front hit `i`, has B > 0.
fn coverage_of(seen: &[Seen], lit: impl Fn(usize, usize) -> bool) -> Coverage {
    let n = seen.len().max(1) as f64;
    let count = |f: fn(&Seen) -> bool| seen.iter().filter(|s| f(s)).count() as f64 / n;
    let lit = (seen.iter().enumerate())
        .filter(|&(k, s)| matches!(s, Seen::Front(i) if lit(k, *i)))
        .count() as f64
        / n;
    Coverage {
        lit,
        front: count(|s| matches!(s, Seen::Front(_))),
        back: count(|s| matches!(s, Seen::Back)),
        nothing: count(|s| matches!(s, Seen::Nothing)),
    }
}

/// Whether a gathered B is above 0 in some band.
fn positive(g: &Gathered) -> bool {
    g.radiosity.iter().any(|&b| b > 0.0)
}

/// Renders `camera`'s view of `domain` (3-D) at `width × height` with `spp` sub-samples per
/// pixel, B gathered by `config`'s gather (module docs).
pub fn render_pixels(
    domain: &Domain,
    trained: &Trained,
    config: &SolveConfig,
    camera: &PinholeCamera,
    size: (u32, u32, u32),
) -> Result<PixelImage, GatherError> {
    render_pixel_shard(domain, trained, config, camera, size, None)
}

/// [`render_pixels`], with the pixels' estimates taken from `merged` (one per pixel, merged from
/// shards: `super::shards`) instead of gathered when given; with a shard in `config`, only its
/// pixels estimated ([`PixelImage::shard`]).
pub(super) fn render_pixel_shard(
    domain: &Domain,
    trained: &Trained,
    config: &SolveConfig,
    camera: &PinholeCamera,
    (width, height, spp): (u32, u32, u32),
    merged: Option<Vec<Gathered>>,
) -> Result<PixelImage, GatherError> {
    let Domain::ThreeD(k) = domain else {
        return Ok(PixelImage::empty(width, height, spp));
    };
    let _phase = crate::progress::phase("pixels");
    if config.gather == GatherMode::Paths && !config.reads_networks() {
        return render_footprints(domain, config, camera, (width, height), merged);
    }
    let (scene, bvh) = (k.scene, k.bvh);
    let spp = spp.max(1);
    let aspect = f64::from(width) / f64::from(height);
    // ⟨Primary rays: the first surface behind each sub-sample⟩
    let n = (width * height * spp) as usize;
    let hits: Vec<Option<(DVec3, DVec3, u32, bool)>> = (0..n)
        .into_par_iter()
        .map(|i| {
            let s = (i % spp as usize) as f64;
            let p = i / spp as usize;
            let (px, py) = ((p % width as usize) as f64, (p / width as usize) as f64);
            let (ox, oy) = if spp == 1 {
                (0.5, 0.5)
            } else {
                ((0.5 + s * R2[0]).fract(), (0.5 + s * R2[1]).fract())
            };
            let dir = camera.ray_direction(
                (px + ox) / f64::from(width),
                (py + oy) / f64::from(height),
                aspect,
            );
            let hit = bvh.closest_hit(camera.eye, dir, f64::INFINITY, u32::MAX)?;
            let normal = scene.faces[hit.face as usize].normal;
            Some((hit.point, normal, hit.face, normal.dot(dir) < 0.0))
        })
        .collect();
    // ⟨B at every front hit, by the output gather (to its target over all of them)⟩
    let mut seen = Vec::with_capacity(n);
    let mut points = Vec::new();
    let mut lit = Vec::new();
    for h in &hits {
        seen.push(match *h {
            None => Seen::Nothing,
            Some((_, _, _, false)) => Seen::Back,
            Some((x, nx, face, true)) => {
                points.push((x, nx, face));
                lit.push(scene.faces[face as usize].emission.is_zero());
                Seen::Front(points.len() - 1)
            }
        });
    }
    // A pixel is the mean of its spp independent sub-samples: its error is theirs over √spp, so
    // the gather's target applies to the pixels (its target for one sub-sample is √spp times
    // larger, at most 50 %).
    let spread = f64::from(spp).sqrt();
    let config = SolveConfig {
        paths: crate::config::PathSettings {
            target_error: config.paths.target_error.map(|t| (t * spread).min(0.5)),
            ..config.paths
        },
        ..*config
    };
    let gathered = radiosity_at_points(domain, trained, &Emitters::new(domain), &config, &points)?;
    let pixels = pixel_means(&seen, &gathered, spp as usize);
    Ok(PixelImage {
        width,
        height,
        spp,
        coverage: coverage_of(&seen, |_, i| positive(&gathered[i])),
        seen,
        radiosity: gathered.iter().map(|g| g.radiosity).collect(),
        lit,
        stats: GatherStats {
            relative_std_error: crate::relative_std_error(&pixels),
            ..GatherStats::of(&gathered)
        },
        shard: None,
    })
}

/// The paths gather over each pixel's footprint ([`PathGather::estimate_footprint`]): every ray
/// has its own point in the pixel (a path tracer's antialiasing, Sobol dimensions for the pixel
/// and the first bounce), to the target error over the pixels with each pixel's rays in
/// proportion to its standard deviation ([`super::adaptive`]). `--pixel-samples` plays no part:
/// the rays are the sub-samples.
fn render_footprints(
    domain: &Domain,
    config: &SolveConfig,
    camera: &PinholeCamera,
    (width, height): (u32, u32),
    merged: Option<Vec<Gathered>>,
) -> Result<PixelImage, GatherError> {
    let Domain::ThreeD(k) = domain else {
        return Ok(PixelImage::empty(width, height, 1));
    };
    let (scene, bvh) = (k.scene, k.bvh);
    let aspect = f64::from(width) / f64::from(height);
    let first_hit = |sx: f64, sy: f64| {
        let dir = camera.ray_direction(sx, sy, aspect);
        let hit = bvh.closest_hit(camera.eye, dir, f64::INFINITY, u32::MAX)?;
        let normal = scene.faces[hit.face as usize].normal;
        Some((hit.point, normal, hit.face, normal.dot(dir) < 0.0))
    };
    let n = (width * height) as usize;
    let pixel = |p: usize| ((p % width as usize) as f64, (p / width as usize) as f64);
    // ⟨The pixel centres: what the image shows, for the coverage and the exposure⟩
    let centres: Vec<Seen> = (0..n)
        .into_par_iter()
        .map(|p| {
            let (px, py) = pixel(p);
            match first_hit(
                (px + 0.5) / f64::from(width),
                (py + 0.5) / f64::from(height),
            ) {
                None => Seen::Nothing,
                Some((_, _, _, false)) => Seen::Back,
                Some((_, _, face, true)) => Seen::Front(face as usize),
            }
        })
        .collect();
    let lit = centres
        .iter()
        .map(|s| matches!(s, Seen::Front(f) if scene.faces[*f].emission.is_zero()))
        .collect();
    // ⟨Each pixel's mean B over its footprint, in rounds to the target⟩
    let emitters = Emitters::new(domain);
    let mut gather = PathGather::new(
        domain,
        &emitters,
        |_, _| [0.0; 3],
        config.gather_samples,
        config.paths,
    );
    let footprint = |gather: &PathGather<'_, _>, p: usize, first: usize, rays: usize| {
        let (px, py) = pixel(p);
        let receiver = |u: [f64; 2]| {
            let sx = (px + u[0]) / f64::from(width);
            let sy = (py + u[1]) / f64::from(height);
            match first_hit(sx, sy) {
                Some((x, nx, face, true)) => FirstHit::Front(x, nx, face),
                Some(_) => FirstHit::Back,
                None => FirstHit::Escaped(camera.ray_direction(sx, sy, aspect).normalize()),
            }
        };
        gather.estimate_footprint(&receiver, pixel_seed(config.seed, px, py), first, rays)
    };
    let trial = match merged {
        None => decide_table(&mut gather, &footprint, n, config),
        Some(_) => None,
    };
    crate::estimator::relay::record_trial(trial);
    let estimate = |p: usize, first: usize, rays: usize| footprint(&gather, p, first, rays);
    // ⟨In strips of rows, each to the target on its own (a shard's only), or from the shards⟩
    let strips = PixelStrips::new(width, height, config);
    let mine = strips.mine(config)?;
    let gathered = match merged {
        // the caller checked its length (`super::views`)
        Some(merged) => merged,
        None => strips.gather(&mine, &estimate, config),
    };
    let shard = config.paths.shard.map(|_| {
        let mine: Vec<usize> = (mine.iter()).flat_map(|&s| strips.pixels(s)).collect();
        let stats = GatherStats::of(&mine.iter().map(|&p| gathered[p]).collect::<Vec<_>>());
        (mine, stats)
    });
    Ok(PixelImage {
        width,
        height,
        spp: 1,
        seen: (0..n).map(Seen::Front).collect(),
        radiosity: gathered.iter().map(|g| g.radiosity).collect(),
        lit,
        coverage: coverage_of(&centres, |p, _| positive(&gathered[p])),
        stats: match &shard {
            Some((_, stats)) => *stats,
            None => GatherStats {
                // what the rounds ran to: the per-pixel relative error (estimator::pixel_rounds)
                relative_std_error: pixel_error(&gathered, relative_floor(&gathered)),
                ..GatherStats::of(&gathered)
            },
        },
        shard: shard.map(|(mine, _)| (gathered, mine)),
    })
}

/// The blocks of a footprint image: strips of whole rows, each of at least
/// [`crate::PathSettings::block_points`] pixels, each run to the target on its own (its own
/// pilot, allocation and stopping test: `pixel_rounds`), so that a pixel's value depends only on
/// its strip and a shard (every N-th strip, as the probes' blocks) computes the single run's
/// values. By default one strip, the whole image, as before strips existed.
struct PixelStrips {
    width: usize,
    pixels: usize,
    /// Rows per strip (the last may have fewer).
    rows: usize,
}

impl PixelStrips {
    fn new(width: u32, height: u32, config: &SolveConfig) -> Self {
        let (width, height) = (width as usize, height as usize);
        Self {
            width,
            pixels: width * height,
            rows: config
                .paths
                .block_points
                .div_ceil(width.max(1))
                .clamp(1, height.max(1)),
        }
    }

    /// How many strips there are.
    fn count(&self) -> usize {
        self.pixels.div_ceil(self.width * self.rows).max(1)
    }

    /// The pixels of strip `s`.
    fn pixels(&self, s: usize) -> std::ops::Range<usize> {
        let size = self.width * self.rows;
        s * size..((s + 1) * size).min(self.pixels)
    }

    /// The strips (ascending) `config`'s shard computes; every strip without a shard; an error
    /// when the shard has none.
    fn mine(&self, config: &SolveConfig) -> Result<Vec<usize>, GatherError> {
        use crate::estimator::blocks::{check_shard, of_shard};
        let mine = of_shard(self.count(), config.paths.shard);
        check_shard(mine.is_empty(), (self.count(), self.pixels), &config.paths)?;
        Ok(mine)
    }

    /// Every pixel's estimate (those of strips not in `mine` left at `Gathered::default()`):
    /// each strip of `mine` in rounds to the target on its own, else every pixel with the first
    /// round's rays.
    fn gather(
        &self,
        mine: &[usize],
        estimate: &(dyn Fn(usize, usize, usize) -> PointEstimate + Sync),
        config: &SolveConfig,
    ) -> Vec<Gathered> {
        let rays = (config.gather_samples.direct).max(config.gather_samples.indirect);
        // strip by strip in order, each strip's values moved in: one image of estimates at the
        // peak and a strip's (the whole image's when it is one strip: moved, not copied)
        let mut gathered = Vec::with_capacity(if self.count() > 1 { self.pixels } else { 0 });
        for s in 0..self.count() {
            let strip = self.pixels(s);
            if mine.binary_search(&s).is_err() {
                gathered.resize(strip.end, Gathered::default());
                continue;
            }
            let at = |i: usize, first: usize, rays: usize| estimate(strip.start + i, first, rays);
            let values: Vec<Gathered> = match config.paths.target_error {
                Some(target) => crate::estimator::pixel_rounds::allocated_rounds(
                    strip.len(),
                    &at,
                    rays,
                    target,
                    config.paths.max_rays,
                ),
                None => (strip.clone())
                    .into_par_iter()
                    .map(|p| estimate(p, 0, rays).gathered())
                    .collect(),
            };
            match self.count() {
                1 => gathered = values,
                _ => gathered.extend(values),
            }
        }
        gathered
    }
}

/// Pixels in the trial that decides whether a table of secondary sources pays, at most.
const TRIAL_PIXELS: usize = 512;

/// The table of secondary sources for a per-pixel image's `gather` (`estimator/relay.rs`):
/// with `--guiding on`; with `auto`, before rounds to a target, where a trial round at every k-th
/// of the `n` pixels (at most [`TRIAL_PIXELS`]; `footprint(gather, pixel, first, rays)` a
/// pixel's estimate) says it halves the per-pixel relative variance ([`table_if_it_pays`]); what
/// the trial measured (None: no trial).
fn decide_table<'a, C: Fn(DVec3, DVec3) -> crate::element::Bands + Sync>(
    gather: &mut PathGather<'a, C>,
    footprint: &(impl Fn(&PathGather<'a, C>, usize, usize, usize) -> PointEstimate + Sync),
    n: usize,
    config: &SolveConfig,
) -> Option<GuidingTrial> {
    match (config.paths.guiding, config.paths.target_error) {
        (Guiding::On, _) => {
            gather.build_table(config.seed);
            return None;
        }
        (Guiding::Auto, Some(_)) => {}
        _ => return None,
    }
    let rays = (config.gather_samples.direct).max(config.gather_samples.indirect);
    let trial: Vec<usize> = (0..n).step_by(n.div_ceil(TRIAL_PIXELS).max(1)).collect();
    let variance = |g: &PathGather<'a, C>| {
        let gathered: Vec<Gathered> = (trial.par_iter())
            .map(|&p| footprint(g, p, 0, rays).gathered())
            .collect();
        pixel_error(&gathered, relative_floor(&gathered)).map(|e| e * e)
    };
    let target = config.paths.target_error.unwrap_or(1.0);
    let work = n as f64 / (target * target);
    table_if_it_pays(gather, variance, (rays, config.seed, work))
}

/// A pixel's seed from the solve's seed and its integer coordinates (`point_seed` quantizes to 2⁻²⁴
/// of the "diagonal": with 2²⁴ it keeps the coordinates), so no two pixels share a scrambling.
fn pixel_seed(seed: u64, px: f64, py: f64) -> u64 {
    crate::estimator::point_seed(
        seed,
        DVec3::new(px, py, 0.0),
        (DVec3::ZERO, (1u64 << 24) as f64),
    )
}

/// Per pixel, the mean B of its sub-samples and the standard error of that mean
/// (√(Σ σ²)/spp: independent sub-samples; back faces and background count as exact zeros).
fn pixel_means(seen: &[Seen], gathered: &[Gathered], spp: usize) -> Vec<Gathered> {
    seen.chunks(spp)
        .map(|subs| {
            let mut px = Gathered::default();
            for s in subs {
                if let Seen::Front(i) = s {
                    for k in 0..3 {
                        px.radiosity[k] += gathered[*i].radiosity[k] / spp as f64;
                        px.std_error[k] += gathered[*i].std_error[k].powi(2);
                    }
                    px.rays = px.rays.max(gathered[*i].rays);
                }
            }
            px.std_error = px.std_error.map(|v| v.sqrt() / spp as f64);
            px
        })
        .collect()
}

impl PixelImage {
    fn empty(width: u32, height: u32, spp: u32) -> Self {
        let seen = vec![Seen::Nothing; (width * height * spp.max(1)) as usize];
        Self {
            width,
            height,
            spp: spp.max(1),
            coverage: coverage_of(&seen, |_, _| false),
            seen,
            radiosity: Vec::new(),
            lit: Vec::new(),
            stats: GatherStats::default(),
            shard: None,
        }
    }

    /// B at the front hits that do not emit: the input of an automatic exposure.
    pub fn lit(&self) -> impl Iterator<Item = [f64; 3]> + '_ {
        self.radiosity
            .iter()
            .zip(&self.lit)
            .filter(|(_, l)| **l)
            .map(|(b, _)| *b)
    }

    /// What the sub-samples (with the paths gather: the pixel centres) saw, as fractions.
    pub fn coverage(&self) -> Coverage {
        self.coverage
    }

    /// Per pixel, the mean of `map(B)` over its sub-samples (0 where they see no front face).
    fn reduce(&self, map: impl Fn([f64; 3]) -> [f64; 3]) -> Vec<[f64; 3]> {
        self.seen
            .chunks(self.spp as usize)
            .map(|subs| {
                let mut acc = [0.0; 3];
                for s in subs {
                    if let Seen::Front(i) = s {
                        let v = map(self.radiosity[*i]);
                        for c in 0..3 {
                            acc[c] += v[c];
                        }
                    }
                }
                acc.map(|a| a / subs.len() as f64)
            })
            .collect()
    }

    /// Linear radiance L = B/π per pixel.
    pub fn radiance(&self) -> RadianceImage {
        let inv_pi = 1.0 / std::f64::consts::PI;
        RadianceImage {
            width: self.width,
            height: self.height,
            radiance: self
                .reduce(|b| b.map(|c| if c.is_finite() { c * inv_pi } else { 0.0 }))
                .into_iter()
                .map(|l| l.map(|c| c as f32))
                .collect(),
            coverage: self.coverage(),
        }
    }

    /// 8-bit sRGB RGB pixels, row-major, top row first: each sub-sample exposed and clipped
    /// ([`Exposure::linear`]), averaged, encoded (the raster's order).
    pub fn tone_mapped(&self, exposure: &Exposure) -> Vec<u8> {
        self.reduce(|b| exposure.linear(b))
            .into_iter()
            .flat_map(|v| v.map(|c| (srgb_encode(c) * 255.0).round() as u8))
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::config::GatherSamples;

    /// Every pixel of a 256 × 256 image has its own seed (a first version keyed them by the pixel
    /// index at a coarse quantization: about 60 neighbours in a row shared one Sobol scrambling).
    #[test]
    fn no_two_pixels_share_a_seed() {
        let mut seeds: Vec<u64> = (0..256)
            .flat_map(|y| (0..256).map(move |x| pixel_seed(1, f64::from(x), f64::from(y))))
            .collect();
        seeds.sort_unstable();
        seeds.dedup();
        assert_eq!(seeds.len(), 256 * 256);
    }
    use crate::output::raster::project;
    use scene_sampler::{AnyScene, KernelSampler, SceneBvh, builtin};

    /// In the furnace (B = 2 everywhere, every face emits 1 and reflects 0.5) seen from inside,
    /// every pixel sees a front face and its radiance is B/π up to the gather's noise; a 3-D point
    /// on the far wall lands on the pixel the camera's projection puts it on (no mirroring: the
    /// image's left is the camera's left).
    #[test]
    fn the_furnace_from_inside_is_uniform_and_pixels_are_where_the_camera_puts_them() {
        let AnyScene::ThreeD(scene) = builtin("furnace").unwrap() else {
            panic!()
        };
        let bvh = SceneBvh::new(&scene);
        let domain = Domain::ThreeD(KernelSampler::new(&scene, &bvh));
        let config = SolveConfig {
            gather: GatherMode::Paths,
            gather_samples: GatherSamples {
                direct: 16,
                indirect: 16,
            },
            ..SolveConfig::default()
        };
        let trained = Trained::without_networks(&domain, &config);
        let camera = PinholeCamera {
            eye: DVec3::new(0.5, 0.5, 0.1),
            target: DVec3::new(0.5, 0.5, 1.0),
            up: DVec3::Y,
            fov_y_degrees: 60.0,
        };
        let img = render_pixels(&domain, &trained, &config, &camera, (32, 24, 2)).unwrap();
        assert_eq!(img.coverage().front, 1.0);
        let l = img.radiance();
        assert_eq!(l.radiance.len(), 32 * 24);
        let mean: f64 =
            l.radiance.iter().map(|p| f64::from(p[0])).sum::<f64>() / l.radiance.len() as f64;
        let exact = 2.0 / std::f64::consts::PI;
        assert!(
            (mean / exact - 1.0).abs() < 0.02,
            "mean L {mean} vs {exact}"
        );
        // A point on the far wall (z = 1) to the camera's left and up: its pixel and the ray
        // through that pixel's centre hit the same place.
        let p = DVec3::new(0.7, 0.6, 1.0);
        let s = project(&camera, 32, 24, p).expect("in view");
        let (i, j) = (s.x.floor(), s.y.floor());
        let dir = camera.ray_direction((i + 0.5) / 32.0, (j + 0.5) / 24.0, 32.0 / 24.0);
        let hit = bvh
            .closest_hit(camera.eye, dir, f64::INFINITY, u32::MAX)
            .unwrap();
        assert!((hit.point - p).length() < 0.05, "{:?} vs {p:?}", hit.point);
        // +x is the camera's left when it looks along +z with y up (Mitsuba's look_at).
        assert!(i < 16.0, "x = 0.7 drawn in column {i} of 32");
    }
}

//! The radiosity kernel as a goal function (sec. 3.1, docs/design/math.md §4, §6, §7).
//!
//! The kernel of the radiosity equation (eq. 1.2) is `K(x, y) = ρ(y)·G(x, y)·V(x, y)`, with
//! * 3-D: `G = cos θx cos θy / (π r²)`,
//! * Flatland: `G = cos θx cos θy / (2 r)` (integrates to 1 over a half-plane),
//!
//! and the kernel network's training target is `K(x, y)·s(x)` per band, `s(x) = E(x) + B_refl(x)` (docs/design/math.md §4).
//! A [`KernelSample`] stores everything but `s`, so a caller can re-evaluate `K·s` for a new `s` without
//! tracing again.
//!
//! # The `r → 0` singularity (docs/design/math.md §6)
//! Where two surfaces meet (a corner), `G` grows like `1/r²` (Flatland `1/r`): the integral stays finite but
//! single samples become arbitrarily large. We clamp the distance: `G_c = cos θx cos θy / (π max(r, r_min)²)`
//! (Flatland `/(2 max(r, r_min))`) with `r_min = 10⁻³ · diagonal` by default ([`KernelSampler::r_min`]).
//! The clamp only lowers `G`, so the bias is negative and confined to pairs closer than `r_min`; for a receiver
//! at distance `h` from a right-angle corner the lost fraction of the form factor is O(r_min/h)·small — the
//! test `clamp_bias_at_corner` measures it against the analytic perpendicular-rectangle factor (docs/design/math.md §8).
//! `g_unclamped` is kept for callers who want the raw value.

use crate::{
    FlatPoint, FlatSampler, FlatVisibility, FlatlandScene, Scene, SceneBvh, Spectrum, SurfacePoint,
    SurfaceSampler,
};
use std::f64::consts::PI;

/// One evaluated kernel sample `(x, y)` in 3-D: x is the sender, y the receiver.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct KernelSample {
    /// Sender point x.
    pub x: SurfacePoint,
    /// Receiver point y.
    pub y: SurfacePoint,
    /// `cos θx = n_x · (y − x)/r` (may be ≤ 0).
    pub cos_x: f64,
    /// `cos θy = n_y · (x − y)/r` (may be ≤ 0).
    pub cos_y: f64,
    /// Distance `r = |x − y|`.
    pub r: f64,
    /// Geometry term with the distance clamp (0 if either cosine ≤ 0).
    pub g: f64,
    /// Geometry term without the clamp (0 if either cosine ≤ 0).
    pub g_unclamped: f64,
    /// Mutual visibility (false without tracing when either cosine ≤ 0).
    pub visible: bool,
    /// ρ(y) per band.
    pub rho_y: Spectrum,
}

impl KernelSample {
    /// The kernel `K(x,y) = ρ(y)·G·V` per band (clamped G).
    pub fn kernel(&self) -> Spectrum {
        if self.visible {
            self.rho_y * self.g
        } else {
            Spectrum::ZERO
        }
    }
    /// The goal function `K(x,y)·s(x)` per band for the sender strength `s` at x (docs/design/math.md §4).
    pub fn k_times_s(&self, s: Spectrum) -> Spectrum {
        self.kernel() * s
    }
}

/// One evaluated Flatland kernel sample.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FlatKernelSample {
    /// Sender x.
    pub x: FlatPoint,
    /// Receiver y.
    pub y: FlatPoint,
    /// `cos θx`.
    pub cos_x: f64,
    /// `cos θy`.
    pub cos_y: f64,
    /// Distance.
    pub r: f64,
    /// `cos θx cos θy / (2 max(r, r_min))`, 0 if a cosine ≤ 0.
    pub g: f64,
    /// `cos θx cos θy / (2 r)`, 0 if a cosine ≤ 0.
    pub g_unclamped: f64,
    /// Mutual visibility.
    pub visible: bool,
    /// ρ(y).
    pub rho_y: Spectrum,
}

impl FlatKernelSample {
    /// `K(x,y) = ρ(y)·G·V` per band.
    pub fn kernel(&self) -> Spectrum {
        if self.visible {
            self.rho_y * self.g
        } else {
            Spectrum::ZERO
        }
    }
    /// `K(x,y)·s(x)` per band.
    pub fn k_times_s(&self, s: Spectrum) -> Spectrum {
        self.kernel() * s
    }
}

/// Evaluates the 3-D kernel at surface pairs, sampled area-uniformly from `(s,t,u,v) ∈ [0,1]⁴` (docs/design/math.md §6, B.2).
pub struct KernelSampler<'a> {
    /// The scene.
    pub scene: &'a Scene,
    /// Its BVH.
    pub bvh: &'a SceneBvh,
    /// Its area-uniform parameterization.
    pub sampler: SurfaceSampler,
    /// Distance clamp of the `r → 0` singularity (module docs).
    pub r_min: f64,
}

impl<'a> KernelSampler<'a> {
    /// A sampler with the default clamp `r_min = 1e-3 · diagonal`.
    pub fn new(scene: &'a Scene, bvh: &'a SceneBvh) -> Self {
        KernelSampler {
            scene,
            bvh,
            sampler: SurfaceSampler::new(scene),
            r_min: 1e-3 * scene.diagonal(),
        }
    }
    /// Evaluates `K` at a given pair (x sender, y receiver). No ray is traced when either cosine is ≤ 0.
    pub fn eval(&self, x: SurfacePoint, y: SurfacePoint) -> KernelSample {
        let d = y.point - x.point;
        let r = d.length();
        let rho_y = if self.scene.textures.is_empty() {
            self.sampler.rho(y.face)
        } else {
            self.scene.rho_at(y.face, y.point)
        };
        let (cos_x, cos_y) = if r > 0.0 {
            (x.normal.dot(d) / r, -y.normal.dot(d) / r)
        } else {
            (0.0, 0.0)
        };
        if cos_x <= 0.0 || cos_y <= 0.0 || x.face == y.face {
            return KernelSample {
                x,
                y,
                cos_x,
                cos_y,
                r,
                g: 0.0,
                g_unclamped: 0.0,
                visible: false,
                rho_y,
            };
        }
        let cc = cos_x * cos_y / PI;
        let g_unclamped = cc / (r * r);
        let rc = r.max(self.r_min);
        let g = cc / (rc * rc);
        let visible = self.bvh.visible(&x, &y);
        KernelSample {
            x,
            y,
            cos_x,
            cos_y,
            r,
            g,
            g_unclamped,
            visible,
            rho_y,
        }
    }
    /// Samples `x` from `(u[0], u[1])` and `y` from `(u[2], u[3])` area-uniformly and evaluates the kernel.
    /// The pair density is `1 / A²` (A = total area), so `A²·K·s` is an unbiased estimate of `∫∫ K s`.
    pub fn sample(&self, u: [f64; 4]) -> KernelSample {
        let (x, y) = self.sampler.sample_pair(u);
        self.eval(x, y)
    }

    /// [`KernelSampler::sample`] for each parameter vector of `us`, in order, bit for bit — but faster on large
    /// scenes: while sample `i` traces its ray, the look-ups of samples `i + 1 … i + 3` are under way
    /// (software prefetch in three stages: guide entries, then bucket records and `cdf`, then the face
    /// records), so the sampler's cache misses leave the critical path. Use it wherever the parameter vectors
    /// are known a few samples ahead; on one `u` at a time [`KernelSampler::sample`] is the same.
    pub fn samples<I: IntoIterator<Item = [f64; 4]>>(&self, us: I) -> Samples<'_, 'a, I::IntoIter> {
        Samples {
            k: self,
            prefetch: self.sampler.recs_bytes() >= PREFETCH_MIN_BYTES,
            inner: us.into_iter(),
            buf: [[0.0; 4]; 4],
            head: 0,
            len: 0,
        }
    }

    /// [`KernelSampler::sample`] for many parameter vectors, in parallel (rayon), in input order.
    ///
    /// Works in chunks of 256, each through [`KernelSampler::samples`]. A convenience for generating a
    /// training batch; it allocates the whole result (~200 bytes per sample), so for pure throughput
    /// `par_chunks(…).map(|c| k.samples(c.iter().copied())…)` consuming samples on the fly is faster.
    pub fn sample_batch(&self, us: &[[f64; 4]]) -> Vec<KernelSample> {
        use rayon::prelude::*;
        us.par_chunks(256)
            .flat_map_iter(|chunk| self.samples(chunk.iter().copied()))
            .collect()
    }
}

/// [`KernelSampler::samples`] prefetches when the sampler's face records take at least this many bytes (the
/// L2 cache of the machine it was tuned on is 1 MiB; below that the look-ups hit the cache anyway).
const PREFETCH_MIN_BYTES: usize = 1 << 20;

/// The iterator of [`KernelSampler::samples`]: kernel samples in input order, with a look-ahead of three
/// parameter vectors whose memory reads are prefetched.
pub struct Samples<'k, 'a, I> {
    k: &'k KernelSampler<'a>,
    /// False on small scenes, whose tables stay cached: there the prefetch stages would only add work.
    prefetch: bool,
    inner: I,
    /// Ring of the next `len` parameter vectors from `head`: position 0 is sampled next, position `d` has had
    /// prefetch stages `1..=4-d`.
    buf: [[f64; 4]; 4],
    head: usize,
    len: usize,
}

impl<I: Iterator<Item = [f64; 4]>> Iterator for Samples<'_, '_, I> {
    type Item = KernelSample;

    #[inline]
    fn next(&mut self) -> Option<KernelSample> {
        if !self.prefetch {
            return self.inner.next().map(|u| self.k.sample(u));
        }
        let s = &self.k.sampler;
        while self.len < 4 {
            let Some(u) = self.inner.next() else { break };
            self.buf[(self.head + self.len) & 3] = u;
            self.len += 1;
            s.prefetch_guide(u);
        }
        if self.len == 0 {
            return None;
        }
        if self.len > 2 {
            s.prefetch_bucket(self.buf[(self.head + 2) & 3]);
        }
        if self.len > 1 {
            s.prefetch_faces(self.buf[(self.head + 1) & 3]);
        }
        let u = self.buf[self.head];
        self.head = (self.head + 1) & 3;
        self.len -= 1;
        Some(self.k.sample(u))
    }

    fn size_hint(&self) -> (usize, Option<usize>) {
        let (lo, hi) = self.inner.size_hint();
        (
            lo.saturating_add(self.len),
            hi.and_then(|h| h.checked_add(self.len)),
        )
    }
}

/// Evaluates the Flatland kernel, sampled arc-length-uniformly from `(s, t) ∈ [0,1]²` (x from s, y from t).
pub struct FlatKernelSampler<'a> {
    /// The scene.
    pub scene: &'a FlatlandScene,
    /// Its visibility structure.
    pub vis: FlatVisibility,
    /// Its arc-length parameterization.
    pub sampler: FlatSampler,
    /// Distance clamp (default `1e-3 · diagonal`).
    pub r_min: f64,
}

impl<'a> FlatKernelSampler<'a> {
    /// A sampler with the default clamp.
    pub fn new(scene: &'a FlatlandScene) -> Self {
        FlatKernelSampler {
            scene,
            vis: FlatVisibility::new(scene),
            sampler: FlatSampler::new(scene),
            r_min: 1e-3 * scene.diagonal(),
        }
    }
    /// Evaluates `K` at a pair (x sender, y receiver).
    pub fn eval(&self, x: FlatPoint, y: FlatPoint) -> FlatKernelSample {
        let d = y.point - x.point;
        let r = d.length();
        let rho_y = self.scene.segments[y.segment as usize].rho;
        let (cos_x, cos_y) = if r > 0.0 {
            (x.normal.dot(d) / r, -y.normal.dot(d) / r)
        } else {
            (0.0, 0.0)
        };
        if cos_x <= 0.0 || cos_y <= 0.0 || x.segment == y.segment {
            return FlatKernelSample {
                x,
                y,
                cos_x,
                cos_y,
                r,
                g: 0.0,
                g_unclamped: 0.0,
                visible: false,
                rho_y,
            };
        }
        let cc = 0.5 * cos_x * cos_y;
        let visible = self.vis.visible(&x, &y);
        FlatKernelSample {
            x,
            y,
            cos_x,
            cos_y,
            r,
            g: cc / r.max(self.r_min),
            g_unclamped: cc / r,
            visible,
            rho_y,
        }
    }
    /// Samples x at parameter `s` and y at `t` and evaluates (the kernel plots of figs. 4.1b and 4.6b).
    pub fn sample(&self, s: f64, t: f64) -> FlatKernelSample {
        self.eval(self.sampler.sample(s), self.sampler.sample(t))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DVec3;
    use rand::{Rng, SeedableRng};

    /// The kernel sample exactly as the code computed it before the sampler was restructured (plain cdf
    /// binary search over all faces, geometry and ρ read from `Scene::faces`).
    struct Reference<'a> {
        scene: &'a Scene,
        bvh: &'a SceneBvh,
        cdf: Vec<f64>,
        r_min: f64,
    }

    impl<'a> Reference<'a> {
        fn new(scene: &'a Scene, bvh: &'a SceneBvh) -> Self {
            let total: f64 = scene.faces.iter().map(|f| f.area).sum();
            let mut cdf = vec![0.0];
            let mut acc = 0.0;
            for f in &scene.faces {
                acc += f.area;
                cdf.push(acc / total);
            }
            *cdf.last_mut().unwrap() = 1.0;
            Reference {
                scene,
                bvh,
                cdf,
                r_min: 1e-3 * scene.diagonal(),
            }
        }
        fn point(&self, u: [f64; 2]) -> SurfacePoint {
            let n = self.scene.faces.len();
            let ux = u[0].clamp(0.0, 1.0);
            let uy = u[1].clamp(0.0, 1.0);
            let i = (self.cdf.partition_point(|&c| c <= ux).saturating_sub(1)).min(n - 1);
            let v = self.scene.faces[i].v;
            let (e1, e2): (DVec3, DVec3) = (v[1] - v[0], v[2] - v[0]);
            let up = ((ux - self.cdf[i]) / (self.cdf[i + 1] - self.cdf[i])).clamp(0.0, 1.0);
            let c = e1.cross(e2);
            let su = up.sqrt();
            SurfacePoint {
                point: v[0] + e1 * (uy * su) + e2 * (1.0 - su),
                normal: c / c.length(),
                face: i as u32,
            }
        }
        fn sample(&self, u: [f64; 4]) -> KernelSample {
            let (x, y) = (self.point([u[0], u[1]]), self.point([u[2], u[3]]));
            let d = y.point - x.point;
            let r = d.length();
            let rho_y = self.scene.faces[y.face as usize].rho;
            let (cos_x, cos_y) = if r > 0.0 {
                (x.normal.dot(d) / r, -y.normal.dot(d) / r)
            } else {
                (0.0, 0.0)
            };
            let (mut g, mut g_unclamped, mut visible) = (0.0, 0.0, false);
            if !(cos_x <= 0.0 || cos_y <= 0.0 || x.face == y.face) {
                let cc = cos_x * cos_y / PI;
                g_unclamped = cc / (r * r);
                let rc = r.max(self.r_min);
                g = cc / (rc * rc);
                visible = self.bvh.visible(&x, &y);
            }
            KernelSample {
                x,
                y,
                cos_x,
                cos_y,
                r,
                g,
                g_unclamped,
                visible,
                rho_y,
            }
        }
    }

    fn bits(k: &KernelSample) -> Vec<u64> {
        let p = |p: &SurfacePoint| {
            let mut v: Vec<u64> = p.point.to_array().iter().map(|c| c.to_bits()).collect();
            v.extend(p.normal.to_array().iter().map(|c| c.to_bits()));
            v.push(p.face as u64);
            v
        };
        let mut v = p(&k.x);
        v.extend(p(&k.y));
        v.extend([k.cos_x, k.cos_y, k.r, k.g, k.g_unclamped].map(f64::to_bits));
        v.push(k.visible as u64);
        v.extend(k.rho_y.0.map(f64::to_bits));
        v
    }

    /// The restructured sampler (guide table + interleaved look-ups, stored normals, the prefetching
    /// iterator) returns bit-identical kernel samples: random u, plus u exactly on face boundaries and on
    /// guide-bucket starts (the search's edge cases), on the Cornell box and 100k random boxes.
    #[test]
    fn sampler_is_bit_identical_to_reference() {
        for scene in [
            crate::builtin::cornell_box(),
            crate::random_boxes(100_000, 1),
        ] {
            let bvh = SceneBvh::with_quality(&scene, crate::BuildQuality::Medium);
            let k = KernelSampler::new(&scene, &bvh);
            let reference = Reference::new(&scene, &bvh);
            let n = scene.faces.len();
            let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(11);
            let mut us: Vec<[f64; 4]> = (0..4000).map(|_| rng.random()).collect();
            for j in 0..200 {
                let i = rng.random_range(0..=n);
                let b = rng.random_range(0..n);
                let edge = [reference.cdf[i], b as f64 / n as f64, 0.0, 1.0][j % 4];
                let other = [reference.cdf[b], rng.random(), 1.0, 0.0][(j / 4) % 4];
                us.push([edge, rng.random(), other, rng.random()]);
                us.push([other, rng.random(), edge, rng.random()]);
            }
            let mut traced = 0;
            for u in &us {
                let (a, b) = (k.sample(*u), reference.sample(*u));
                assert_eq!(bits(&a), bits(&b), "u = {u:?}");
                assert_eq!(k.sampler.sample([u[0], u[1]]), a.x);
                assert_eq!(k.sampler.face_of(u[0].clamp(0.0, 1.0)), a.x.face as usize);
                traced += (a.g > 0.0) as usize;
            }
            assert!(traced > 100, "{traced} traced pairs");
            // the prefetching iterator (active on the 100k scene, pass-through on the Cornell box)
            assert!(
                k.samples(us.iter().copied())
                    .zip(&us)
                    .all(|(a, u)| bits(&a) == bits(&k.sample(*u)))
            );
            assert_eq!(k.samples(us.iter().copied()).count(), us.len());
            let batch = k.sample_batch(&us);
            assert!(
                batch
                    .iter()
                    .zip(&us)
                    .all(|(a, u)| bits(a) == bits(&k.sample(*u)))
            );
        }
    }
}

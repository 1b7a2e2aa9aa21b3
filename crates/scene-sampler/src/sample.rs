//! Area-uniform surface parameterizations (fig. B.2) and direction sampling helpers.
//!
//! [`SurfaceSampler`] maps `u ∈ [0,1]²` to a point distributed uniformly by area over all faces (density
//! `1 / total_area`), [`FlatSampler`] maps `s ∈ [0,1]` to a point uniform by arc length over all segments. Both
//! are invertible, which the Flatland kernel plots over `(s, t)` (figs. 4.1b, 4.6b) need.

use crate::{Discrete, FlatlandScene, Scene, Spectrum};
use glam::{DVec2, DVec3};

/// A point on a 3-D scene's surface.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SurfacePoint {
    /// Position.
    pub point: DVec3,
    /// Unit normal of the front side of `face`.
    pub normal: DVec3,
    /// Face index into [`Scene::faces`], or [`NO_FACE`] for a point on no face (a receiver in
    /// the air: an irradiance probe).
    pub face: u32,
}

/// The face of a [`SurfacePoint`] that lies on no face of the scene: rays from it skip no face, and
/// [`crate::SceneBvh::trace_from`] lifts them off along the point's normal.
pub const NO_FACE: u32 = u32::MAX;

/// A point on a Flatland scene's segments.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FlatPoint {
    /// Position.
    pub point: DVec2,
    /// Unit normal of the front side of `segment`.
    pub normal: DVec2,
    /// Segment index into [`FlatlandScene::segments`].
    pub segment: u32,
}

/// Area-uniform parameterization of a 3-D scene: `[0,1]² → (point, normal, face)`.
///
/// `u.x` selects a face in the cumulative area table and is then rescaled to
/// `[0,1)` within that face; together with `u.y` it is warped to the triangle by the standard square-root map
/// `b0 = 1 − √u', b1 = u.y·√u'` (pbrt 4, `SampleUniformTriangle`'s classic form), which is area-uniform.
/// Neighbouring `u` map to neighbouring points within a face, and the map is a bijection up to face
/// boundaries, so [`SurfaceSampler::inverse`] exists.
///
/// The face search uses a guide table (Devroye's indexed search, *Non-Uniform Random Variate Generation*
/// III.2.4): `guide[k]` is the face containing `u = k/n`, so the search for `u` only scans the faces between
/// `guide[⌊u·n⌋]` and `guide[⌊u·n⌋ + 1]` — O(1) expected, O(log faces) worst case — and returns exactly the
/// face a binary search over the whole table would.
#[derive(Clone, Debug)]
pub struct SurfaceSampler {
    /// The faces by area: `cdf[i]` = (area of faces `0..i`) / total, `cdf[n] = 1`.
    table: Discrete,
    /// `guide[k]` = face containing `k / guide.len()` (plus a sentinel `n - 1`).
    guide: Vec<u32>,
    /// Per face: its parameter interval and geometry in one record, so a look-up touches one place.
    recs: Vec<FaceRec>,
    /// ρ per face (the kernel sampler reads it for the receiver only).
    rho: Vec<Spectrum>,
    total_area: f64,
}

impl SurfaceSampler {
    /// Builds the cumulative area table (O(faces)).
    pub fn new(scene: &Scene) -> Self {
        let areas: Vec<f64> = scene.faces.iter().map(|f| f.area).collect();
        let table = Discrete::new(&areas).expect("a validated scene has faces of positive area");
        let (cdf, total) = (table.cdf(), table.total());
        let n = scene.faces.len();
        let mut guide: Vec<u32> = (0..n)
            .map(|k| table.sample(k as f64 / n as f64) as u32)
            .collect();
        guide.push((n - 1) as u32);
        let recs = scene
            .faces
            .iter()
            .enumerate()
            .map(|(i, f)| {
                let (e1, e2) = (f.v[1] - f.v[0], f.v[2] - f.v[0]);
                // the normal exactly as `Face::new` computes it (same operations, same bits)
                let c = e1.cross(e2);
                FaceRec {
                    lo: cdf[i],
                    hi: cdf[i + 1],
                    v0: f.v[0],
                    e1,
                    e2,
                    normal: c / c.length(),
                }
            })
            .collect();
        SurfaceSampler {
            guide,
            recs,
            rho: scene.faces.iter().map(|f| f.rho).collect(),
            total_area: total,
            table,
        }
    }

    /// The face whose parameter interval `[cdf[i], cdf[i+1])` contains `u` (the last face for `u = 1`).
    #[inline]
    pub fn face_of(&self, u: f64) -> usize {
        let (lo, hi) = self.bucket(u);
        let first = &self.recs[lo];
        self.face_in(u, lo, hi, first.lo, first.hi)
    }

    /// The guide-table bucket of `u`: the first and last face it can lie in.
    #[inline]
    fn bucket(&self, u: f64) -> (usize, usize) {
        let n = self.recs.len();
        let k = ((u * n as f64) as usize).min(n - 1);
        (self.guide[k] as usize, self.guide[k + 1] as usize)
    }

    /// The search of [`SurfaceSampler::face_of`] within bucket faces `lo..=hi`, given face `lo`'s parameter
    /// interval `[first_lo, first_hi)` (read by the caller, so that two look-ups can overlap their loads).
    #[inline]
    fn face_in(&self, u: f64, lo: usize, hi: usize, first_lo: f64, first_hi: f64) -> usize {
        let n = self.recs.len();
        if first_lo > u {
            // u·n rounded up across a bucket boundary: fall back to the full search
            return self.table.sample(u);
        }
        // faces lo..=hi; the first i in there with cdf[i+1] > u. Face `lo` is the common answer: test it
        // alone first, so the usual look-up touches one record (the `hi`s are non-decreasing, so this is
        // what the search over the whole range returns); the rest is searched in the compact `cdf`
        // (`cdf[i + 1]` is `recs[i].hi`, bit for bit), not in the 128-byte records
        if first_hi > u {
            return lo;
        }
        let i = lo + 1 + self.table.cdf()[lo + 2..=hi + 1].partition_point(|&c| c <= u);
        i.min(n - 1)
    }

    /// Total area; the sampling density is `1 / total_area` per unit area.
    pub fn total_area(&self) -> f64 {
        self.total_area
    }

    /// Probability density per unit area of every sample (`1 / total_area`).
    pub fn pdf(&self) -> f64 {
        1.0 / self.total_area
    }

    /// Up to `count` points spread evenly over the surface: the images of the low-discrepancy R2
    /// sequence `u_i = ({i·α₁}, {i·α₂})`, i = 1, 2, … (Roberts' plastic-number constants), that
    /// `keep` accepts, in order, trying at most `100·count` of them. Deterministic, and denser
    /// than random points for the same count: the probe sets of benchmarks and examples.
    pub fn spread(&self, count: usize, keep: impl Fn(&SurfacePoint) -> bool) -> Vec<SurfacePoint> {
        (1..=100 * count as u64)
            .map(|i| {
                self.sample([
                    (i as f64 * 0.754_877_666_246_692_7).fract(),
                    (i as f64 * 0.569_840_290_998_053_3).fract(),
                ])
            })
            .filter(|p| keep(p))
            .take(count)
            .collect()
    }

    /// Maps `u ∈ [0,1]²` to a point. Inputs are clamped to `[0,1]`.
    pub fn sample(&self, u: [f64; 2]) -> SurfacePoint {
        let ux = u[0].clamp(0.0, 1.0);
        let uy = u[1].clamp(0.0, 1.0);
        self.point_on(self.face_of(ux), ux, uy)
    }

    /// `[sample(u[0..2]), sample(u[2..4])]`, bit for bit, with the two look-ups interleaved: both guide
    /// entries and both first records are requested before either search branches on one of them, so their
    /// cache misses overlap instead of queueing (the kernel sampler's hot path).
    #[inline]
    pub(crate) fn sample_pair(&self, u: [f64; 4]) -> (SurfacePoint, SurfacePoint) {
        let (ax, ay) = (u[0].clamp(0.0, 1.0), u[1].clamp(0.0, 1.0));
        let (bx, by) = (u[2].clamp(0.0, 1.0), u[3].clamp(0.0, 1.0));
        let (alo, ahi) = self.bucket(ax);
        let (blo, bhi) = self.bucket(bx);
        let (ra, rb) = (&self.recs[alo], &self.recs[blo]);
        let (a_lo, a_hi, b_lo, b_hi) = (ra.lo, ra.hi, rb.lo, rb.hi);
        let ia = self.face_in(ax, alo, ahi, a_lo, a_hi);
        let ib = self.face_in(bx, blo, bhi, b_lo, b_hi);
        (self.point_on(ia, ax, ay), self.point_on(ib, bx, by))
    }

    /// The point of face `i` at clamped parameters `(ux, uy)` (`ux` in the face's interval).
    #[inline]
    fn point_on(&self, i: usize, ux: f64, uy: f64) -> SurfacePoint {
        let r = &self.recs[i];
        let up = ((ux - r.lo) / (r.hi - r.lo)).clamp(0.0, 1.0);
        let normal = r.normal;
        let su = up.sqrt();
        let b1 = uy * su; // weight of v1
        let b2 = 1.0 - su; // weight of v2; v0 gets su·(1 − uy)
        let point = r.v0 + r.e1 * b1 + r.e2 * b2;
        SurfacePoint {
            point,
            normal,
            face: i as u32,
        }
    }

    /// Bytes of the face records (what a look-up reads at random).
    pub(crate) fn recs_bytes(&self) -> usize {
        std::mem::size_of_val(&self.recs[..])
    }

    /// Prefetch stage 1 of [`crate::Samples`] for the two points of `u`: requests their guide entries.
    #[inline]
    pub(crate) fn prefetch_guide(&self, u: [f64; 4]) {
        for ux in [u[0], u[2]] {
            let n = self.recs.len();
            let k = ((ux.clamp(0.0, 1.0) * n as f64) as usize).min(n - 1);
            prefetch(&self.guide[k]);
        }
    }

    /// Prefetch stage 2: the guide entries are cached now; requests the first face record of each bucket and
    /// the bucket's stretch of `cdf` (what [`SurfaceSampler::face_of`] reads).
    #[inline]
    pub(crate) fn prefetch_bucket(&self, u: [f64; 4]) {
        for ux in [u[0], u[2]] {
            let (lo, _) = self.bucket(ux.clamp(0.0, 1.0));
            self.recs[lo].prefetch();
            prefetch(&self.table.cdf()[lo + 1]);
        }
    }

    /// Prefetch stage 3: the bucket data is cached now; finds each point's face and requests its record, and
    /// ρ of the second point's face.
    #[inline]
    pub(crate) fn prefetch_faces(&self, u: [f64; 4]) {
        self.recs[self.face_of(u[0].clamp(0.0, 1.0))].prefetch();
        let y = self.face_of(u[2].clamp(0.0, 1.0));
        self.recs[y].prefetch();
        prefetch(&self.rho[y]);
    }

    /// ρ of face `face`.
    #[inline]
    pub(crate) fn rho(&self, face: u32) -> Spectrum {
        self.rho[face as usize]
    }

    /// Inverse of [`SurfaceSampler::sample`]: the parameters of a point lying on face `face`
    /// (the point is projected onto the face's plane first).
    pub fn inverse(&self, face: u32, point: DVec3) -> [f64; 2] {
        let i = face as usize;
        let r = &self.recs[i];
        let (b1, b2) = barycentric([r.v0, r.v0 + r.e1, r.v0 + r.e2], point);
        let su = (1.0 - b2).clamp(0.0, 1.0);
        let uy = if su > 0.0 {
            (b1 / su).clamp(0.0, 1.0)
        } else {
            0.0
        };
        let up = su * su;
        [
            self.table.cdf()[i] + up * (self.table.cdf()[i + 1] - self.table.cdf()[i]),
            uy,
        ]
    }
}

/// What [`SurfaceSampler`] and the kernel sampler need of one face, stored together so that a look-up touches
/// one place: 112 bytes padded to two whole cache lines (128 bytes, aligned; a packed 88-byte record would
/// straddle 2–3 lines). The normal is stored, not recomputed from the edges (that cost two square roots and six
/// divisions per sample pair); ρ, which only the receiver needs, lives in a separate array.
#[derive(Clone, Copy, Debug)]
#[repr(C, align(64))]
struct FaceRec {
    lo: f64,
    hi: f64,
    v0: DVec3,
    e1: DVec3,
    e2: DVec3,
    /// Unit normal, computed once as `Face::new` computes it (bit-identical).
    normal: DVec3,
}

impl FaceRec {
    /// Requests both cache lines of the record.
    #[inline]
    fn prefetch(&self) {
        prefetch(&self.lo);
        prefetch(&self.e2);
    }
}

/// A hint to load the cache line holding `r` into all cache levels: the x86 `prefetcht0` instruction (through
/// `safe_arch`, no `unsafe` here), nothing on other targets. It never faults and never changes a result.
#[inline(always)]
pub(crate) fn prefetch<T>(r: &T) {
    #[cfg(all(
        any(target_arch = "x86", target_arch = "x86_64"),
        target_feature = "sse"
    ))]
    safe_arch::prefetch_t0(r);
    #[cfg(not(all(
        any(target_arch = "x86", target_arch = "x86_64"),
        target_feature = "sse"
    )))]
    let _ = r;
}

/// Barycentric weights `(b1, b2)` of `p` projected onto the plane of triangle `v` (weights of v1 and v2).
pub fn barycentric(v: [DVec3; 3], p: DVec3) -> (f64, f64) {
    let e1 = v[1] - v[0];
    let e2 = v[2] - v[0];
    let d = p - v[0];
    let (d11, d12, d22) = (e1.dot(e1), e1.dot(e2), e2.dot(e2));
    let (dp1, dp2) = (d.dot(e1), d.dot(e2));
    let den = d11 * d22 - d12 * d12;
    let b1 = (d22 * dp1 - d12 * dp2) / den;
    let b2 = (d11 * dp2 - d12 * dp1) / den;
    (b1, b2)
}

/// Arc-length-uniform parameterization of a Flatland scene: `s ∈ [0,1] → (point, normal, segment)` (fig. B.2).
///
/// Segments are laid end to end in scene order, each from `a` to `b`; `s` is the arc length so far divided by
/// the total length.
#[derive(Clone, Debug)]
pub struct FlatSampler {
    /// The segments by length (cumulative, from 0 to 1).
    table: Discrete,
    segs: Vec<(DVec2, DVec2, DVec2)>,
    total_length: f64,
}

impl FlatSampler {
    /// Builds the cumulative length table.
    pub fn new(scene: &FlatlandScene) -> Self {
        let lengths: Vec<f64> = scene.segments.iter().map(|s| s.length).collect();
        let table =
            Discrete::new(&lengths).expect("a validated scene has segments of positive length");
        let total = table.total();
        FlatSampler {
            table,
            segs: scene
                .segments
                .iter()
                .map(|s| (s.a, s.b, s.normal))
                .collect(),
            total_length: total,
        }
    }
    /// Total length; the sampling density is `1 / total_length` per unit length.
    pub fn total_length(&self) -> f64 {
        self.total_length
    }
    /// Density per unit length (`1 / total_length`).
    pub fn pdf(&self) -> f64 {
        1.0 / self.total_length
    }
    /// Maps `s ∈ [0,1]` (clamped) to a point.
    pub fn sample(&self, s: f64) -> FlatPoint {
        let (i, t) = self.table.sample_remapped(s.clamp(0.0, 1.0));
        let (a, b, normal) = self.segs[i];
        FlatPoint {
            point: a + t * (b - a),
            normal,
            segment: i as u32,
        }
    }
    /// Inverse of [`FlatSampler::sample`] for a point on segment `segment` (projected onto it).
    pub fn inverse(&self, segment: u32, point: DVec2) -> f64 {
        let i = segment as usize;
        let (a, b, _) = self.segs[i];
        let d = b - a;
        let t = ((point - a).dot(d) / d.length_squared()).clamp(0.0, 1.0);
        self.table.cdf()[i] + t * (self.table.cdf()[i + 1] - self.table.cdf()[i])
    }
    /// The parameter interval `[s0, s1]` that segment `segment` occupies.
    pub fn segment_range(&self, segment: u32) -> (f64, f64) {
        (
            self.table.cdf()[segment as usize],
            self.table.cdf()[segment as usize + 1],
        )
    }
}

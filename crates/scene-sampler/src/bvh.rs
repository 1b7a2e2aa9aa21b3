//! Ray queries: an eight-wide BVH over the scene's triangles (built by obvhs, f32; `wide.rs`) and brute-force Flatland segment casting.
//!
//! # Self-intersection policy
//! The scene is f64, the BVH f32. A triangle stored in f32 is off by up to ~6·10⁻⁸·|coordinate|, so a ray that
//! starts exactly on a face can re-hit it or its coplanar neighbour. [`SceneBvh`] therefore
//! 1. skips the faces the ray starts and ends on (by id), and
//! 2. moves both ends off their surfaces by `eps` along the normal, toward the side the ray leaves / arrives on,
//!    and trims `eps` from both ends of the parameter range (and [`SceneBvh::trace_from`] also moves the
//!    origin `eps` toward the face's centroid, away from edges where another wall may meet it),
//!
//! 3. starts every BVH ray [`SceneBvh::backoff`] behind its origin (obvhs culls node hits closer than an
//!    absolute 10⁻⁴ to the ray origin; see there),
//!
//! with `eps = 1e-5 · max(diagonal, largest |coordinate|)` ([`SceneBvh::epsilon`]) — about 170 f32 ulps of the
//! largest coordinate, and 10⁻⁵ of the scene size, far below any feature a radiosity solver resolves. The price
//! is that occluders thinner than `eps`, or closer than `eps` to an end point, are missed.
//!
//! # Coordinates relative to the BVH's centre
//! The f32 triangles and rays are stored relative to the centre `c` of the scene's bounding box: the
//! subtraction `p − c` is made in f64 before rounding to f32. So "largest |coordinate|" above is measured
//! from `c` (at most half the diagonal) and the f32 error scales with the scene's size, not with its distance
//! from the origin: the Cornell box moved by 10⁶ along x has the same visibility as at the origin (in f32 at
//! 10⁶ the spacing of representable numbers is 0.06, a tenth of the box). Inputs and outputs ([`Hit::point`])
//! stay in the scene's own coordinates.

mod wide;

use crate::{AlphaMask, Face, FlatPoint, FlatlandScene, NO_FACE, Scene, SurfacePoint};
use glam::{DVec2, DVec3, Vec3A};
use obvhs::{BvhBuildParams, bvh2::builder::build_bvh2_from_tris, triangle::Triangle};
use rayon::prelude::*;
pub(crate) use wide::Ray;
use wide::WideBvh;

/// How much effort the BVH build spends (a trade between build time and trace speed).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum BuildQuality {
    /// obvhs `medium_build`: builds 4–6× faster than `High`; for occlusion rays between surface points it
    /// traced as fast as `High` in our benchmark (docs/design/scene-sampler.md).
    Medium,
    /// obvhs `very_slow_build` (spatial splits, full reinsertion): the default; ≈0.45 s per 100k triangles,
    /// ≈6 s per million.
    #[default]
    High,
}

/// The closest intersection of a ray with the scene.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    /// Face index into [`Scene::faces`].
    pub face: u32,
    /// Ray parameter (distance, for a unit direction).
    pub t: f64,
    /// Hit position (`origin + t·dir`, in f64).
    pub point: DVec3,
}

/// A compressed-wide BVH over a scene's triangles, built once, queried from many threads.
pub struct SceneBvh {
    /// obvhs's binary BVH collapsed to eight-wide nodes ([`wide`]).
    bvh: WideBvh,
    /// Face normals (f64), by face index.
    normals: Vec<DVec3>,
    /// Face centroids (f64), by face index: `trace_from` nudges origins toward them, away from edges.
    centroids: Vec<DVec3>,
    /// The centre of the scene's bounds: the origin of the f32 frame (module docs).
    centre: DVec3,
    eps: f64,
    /// Cut-outs (module docs): by face index, the index into `cut_faces` or `u32::MAX`; empty
    /// when the scene has none, so that other scenes pay one length test per candidate hit.
    cut_index: Vec<u32>,
    /// The faces with a cut-out.
    cut_faces: Vec<Face>,
    /// The scene's alpha masks.
    masks: Vec<AlphaMask>,
}

impl std::fmt::Debug for SceneBvh {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("SceneBvh")
            .field("nodes", &self.bvh.node_count())
            .field("packs", &self.bvh.pack_count())
            .field("depth", &self.bvh.depth())
            .field("eps", &self.eps)
            .finish()
    }
}

fn v3a(p: DVec3) -> Vec3A {
    Vec3A::new(p.x as f32, p.y as f32, p.z as f32)
}

/// The BVH ray from `origin` along `dir` over `[tmin, tmax]`, with each direction component that
/// is ±0 replaced by +10⁻³⁰: with obvhs's slab test a direction with components of −0 (−Y is
/// (−0, −1, −0)) had infinite inverse components of the wrong sign and missed every triangle
/// (found by the cut-out tests with a ray straight down). Our slab test needs no nudge
/// (`wide.rs`); it stays so that every ray, hence every hit distance, is the one it was. The
/// change of direction is far below f32's resolution of any hit.
fn ray(origin: Vec3A, dir: Vec3A, tmin: f32, tmax: f32) -> Ray {
    let nudge = |c: f32| if c == 0.0 { 1e-30 } else { c };
    Ray {
        origin,
        direction: Vec3A::new(nudge(dir.x), nudge(dir.y), nudge(dir.z)),
        tmin,
        tmax,
    }
}

impl SceneBvh {
    /// Builds the BVH with [`BuildQuality::High`].
    pub fn new(scene: &Scene) -> Self {
        Self::with_quality(scene, BuildQuality::High)
    }

    /// Builds the BVH with the given build quality.
    pub fn with_quality(scene: &Scene, quality: BuildQuality) -> Self {
        let (lo, hi) = scene.bounds;
        let centre = 0.5 * (lo + hi);
        let tris: Vec<Triangle> = scene
            .faces
            .iter()
            .map(|f| Triangle {
                v0: v3a(f.v[0] - centre),
                v1: v3a(f.v[1] - centre),
                v2: v3a(f.v[2] - centre),
            })
            .collect();
        let params = BvhBuildParams {
            // a leaf is one four-lane pack (wide.rs)
            max_prims_per_leaf: 4,
            ..match quality {
                BuildQuality::Medium => BvhBuildParams::medium_build(),
                BuildQuality::High => BvhBuildParams::very_slow_build(),
            }
        };
        let bvh2 = build_bvh2_from_tris(&tris, params, &mut std::time::Duration::default());
        let bvh = WideBvh::from_bvh2(&bvh2, &tris);
        // the largest |coordinate| in the f32 frame: (hi − lo)/2 per axis
        let max_abs = (0.5 * (hi - lo)).max_element();
        let eps = 1e-5 * scene.diagonal().max(max_abs);
        let (mut cut_index, mut cut_faces) = (Vec::new(), Vec::new());
        if scene.faces.iter().any(|f| f.cutout.is_some()) {
            cut_index = (scene.faces.iter())
                .map(|f| match f.cutout {
                    Some(_) => {
                        cut_faces.push(*f);
                        cut_faces.len() as u32 - 1
                    }
                    None => u32::MAX,
                })
                .collect();
        }
        SceneBvh {
            bvh,
            normals: scene.faces.iter().map(|f| f.normal).collect(),
            centroids: scene.faces.iter().map(|f| f.centroid()).collect(),
            centre,
            eps,
            cut_index,
            cut_faces,
            masks: scene.masks.clone(),
        }
    }

    /// Whether the ray `r` (the BVH's frame) meeting face `face` at `t` is a hit: not one in a
    /// cut-out's hole. Every query's test of a geometric hit.
    #[inline]
    fn solid(&self, r: &Ray, face: u32, t: f32) -> bool {
        self.cut_index.is_empty() || !self.in_hole(face, r, t)
    }

    /// Whether the point at `t` along `r` on face `face` is in a hole of its cut-out.
    fn in_hole(&self, face: u32, r: &Ray, t: f32) -> bool {
        let Some(f) =
            (self.cut_index.get(face as usize)).and_then(|&k| self.cut_faces.get(k as usize))
        else {
            return false;
        };
        let d = |v: Vec3A| DVec3::new(f64::from(v.x), f64::from(v.y), f64::from(v.z));
        let p = self.centre + d(r.origin) + d(r.direction) * f64::from(t);
        let (b1, b2) = f.barycentric(p);
        f.cutout.is_some_and(|c| c.is_hole(&self.masks, b1, b2))
    }

    /// How far rays start *behind* their true origin (`2·10⁻⁴ + eps`, world units), with `tmin` raised by the
    /// same amount. obvhs's own CWBVH node test clamped the entry distance to an absolute `1e-4`
    /// (`cwbvh::node::EPSILON`), which silently dropped every hit closer than 10⁻⁴ world units to the ray
    /// origin — a ray leaving a concave corner escaped through the adjoining wall. Our traversal
    /// (`bvh/wide.rs`) has no such clamp; the backoff stays so that every f32 ray, hence every hit
    /// distance, is the one it was (the primitive test's `tmin` still excludes hits behind the
    /// true origin).
    pub fn backoff(&self) -> f64 {
        2e-4 + self.eps
    }

    /// Whether a point `p` on face `face` (unit normal `normal`) lies inside or under a solid
    /// along the unit direction `dir` (along the face): the distance to the first face that a ray
    /// lifted off the face by [`SceneBvh::backoff`] meets within `reach`, when it meets the back
    /// of that face (the point is on the solid's inner side); `None` when it meets a front or
    /// nothing. Points of a face under a wall standing on it are moved out this way (lightmap
    /// texels, output-mesh vertices), to just past the face met.
    pub fn solid_exit(
        &self,
        scene: &Scene,
        (p, normal, face): (DVec3, DVec3, u32),
        dir: DVec3,
        reach: f64,
    ) -> Option<f64> {
        let hit = self.closest_hit(p + normal * self.backoff(), dir, reach, face)?;
        (scene.faces[hit.face as usize].normal.dot(dir) > 0.0).then_some(hit.t)
    }

    /// The self-intersection offset (see the module docs).
    pub fn epsilon(&self) -> f64 {
        self.eps
    }

    /// True if the open segment between `x` and `y` is unobstructed (mutual visibility `V(x, y)` of eq. 1.2).
    ///
    /// Faces `x.face` and `y.face` never block. Sidedness is not checked here: the kernel checks the cosines
    /// before calling this (no ray is traced when either is ≤ 0).
    pub fn visible(&self, x: &SurfacePoint, y: &SurfacePoint) -> bool {
        let d = y.point - x.point;
        let ox = x.point + x.normal * (self.eps * d.dot(x.normal).signum());
        let oy = y.point + y.normal * (self.eps * (-d).dot(y.normal).signum());
        self.segment_clear(ox, oy, x.face, y.face)
    }

    /// True if nothing (other than faces `skip_a`, `skip_b`) intersects the segment `a → b`, trimmed by
    /// `eps` at both ends. Pass `u32::MAX` to skip nothing.
    pub fn segment_clear(&self, a: DVec3, b: DVec3, skip_a: u32, skip_b: u32) -> bool {
        let d = b - a;
        let len = d.length();
        if len <= 2.0 * self.eps {
            return true;
        }
        let dir = d / len;
        let back = self.backoff();
        let ray = ray(
            v3a(a - dir * back - self.centre),
            v3a(dir),
            (back + self.eps) as f32,
            (back + len - self.eps) as f32,
        );
        !self.bvh.any(&ray, |f, t| {
            f != skip_a && f != skip_b && self.solid(&ray, f, t)
        })
    }

    /// Visibility for many pairs at once, in parallel (rayon). `out[i] = visible(&pairs[i].0, &pairs[i].1)`.
    pub fn visible_batch(&self, pairs: &[(SurfacePoint, SurfacePoint)]) -> Vec<bool> {
        pairs
            .par_iter()
            .with_min_len(256)
            .map(|(x, y)| self.visible(x, y))
            .collect()
    }

    /// The closest hit of the ray `origin + t·dir`, `t ∈ (0, tmax]`, ignoring face `skip` (the face the ray
    /// leaves from, or `u32::MAX`). `dir` need not be normalized; `t` is in units of `|dir|`.
    pub fn closest_hit(&self, origin: DVec3, dir: DVec3, tmax: f64, skip: u32) -> Option<Hit> {
        let len = dir.length();
        if len == 0.0 || !len.is_finite() {
            return None;
        }
        let u = dir / len;
        let back = self.backoff();
        let tmax_world = if tmax.is_finite() {
            (back + tmax * len) as f32
        } else {
            f32::INFINITY
        };
        let ray = ray(
            v3a(origin - u * back - self.centre),
            v3a(u),
            back as f32,
            tmax_world,
        );
        // Two-sided thin geometry is two coincident faces with opposite normals, and a ray meets
        // both at the same t. The one facing the ray must win (the other one's back is not a
        // surface the ray can reach), so back faces are pushed back by a tie margin.
        let tie = self.eps as f32;
        let (face, key) = self.bvh.closest(&ray, |face, t| {
            if face == skip || !self.solid(&ray, face, t) {
                f32::INFINITY
            } else if self.normals[face as usize].dot(u) > 0.0 {
                t + tie
            } else {
                t
            }
        })?;
        let t_hit = if self.normals[face as usize].dot(u) > 0.0 {
            key - tie
        } else {
            key
        };
        let t_world = (t_hit as f64 - back).max(0.0);
        Some(Hit {
            face,
            t: t_world / len,
            point: origin + u * t_world,
        })
    }

    /// Closest hit of a ray leaving surface point `from` in direction `dir` (which should be on its front
    /// side); `from.face` is skipped. This is the query a path tracer makes at every bounce.
    ///
    /// The origin is offset by `eps` along the normal toward `dir` *and* by `eps` toward the face's centroid.
    /// The second offset matters at concave corners: a point within f32 precision of an adjoining wall would
    /// otherwise start its ray at t ≈ 0 from that wall, where the f32 test can miss it and the ray escapes
    /// (test `furnace_is_watertight`).
    pub fn trace_from(&self, from: &SurfacePoint, dir: DVec3) -> Option<Hit> {
        self.closest_hit(self.origin(from, dir), dir, f64::INFINITY, from.face)
    }

    /// True when a ray leaving surface point `from` in direction `dir` hits nothing (offsets as
    /// [`SceneBvh::trace_from`]): the shadow ray toward a light at infinity (the sun, the sky).
    pub fn escapes(&self, from: &SurfacePoint, dir: DVec3) -> bool {
        let len = dir.length();
        if len == 0.0 || !len.is_finite() {
            return false;
        }
        let u = dir / len;
        let back = self.backoff();
        let ray = ray(
            v3a(self.origin(from, dir) - u * back - self.centre),
            v3a(u),
            back as f32,
            f32::INFINITY,
        );
        !self
            .bvh
            .any(&ray, |f, t| f != from.face && self.solid(&ray, f, t))
    }

    /// Whether a light sample's shadow ray from the receiver `from` is clear: to a point, the
    /// segment ([`SceneBvh::visible`], the point's face not an occluder); toward a direction, the
    /// ray escapes the scene ([`SceneBvh::escapes`]).
    pub fn reaches(&self, from: &SurfacePoint, target: &crate::ShadowTarget) -> bool {
        match *target {
            crate::ShadowTarget::Point {
                point,
                normal,
                face,
            } => {
                let x = SurfacePoint {
                    point,
                    normal,
                    face: face.unwrap_or(NO_FACE),
                };
                self.visible(&x, from)
            }
            crate::ShadowTarget::Direction(w) => self.escapes(from, w),
        }
    }

    /// The origin of a ray leaving `from` toward `dir` ([`SceneBvh::trace_from`]'s offsets).
    fn origin(&self, from: &SurfacePoint, dir: DVec3) -> DVec3 {
        if from.face == NO_FACE {
            // a point on no face: lifted off whatever surface it lies on, towards its normal's side
            return from.point + from.normal * self.eps;
        }
        let to_c = self.centroids[from.face as usize] - from.point;
        let inward = to_c.normalize_or_zero() * self.eps.min(to_c.length());
        from.point + inward + from.normal * (self.eps * dir.dot(from.normal).signum())
    }

    /// The normal of face `face` (convenience for path tracers: a [`Hit`] plus this is a [`SurfacePoint`]).
    pub fn surface_point(&self, hit: &Hit) -> SurfacePoint {
        SurfacePoint {
            point: hit.point,
            normal: self.normals[hit.face as usize],
            face: hit.face,
        }
    }

    /// A bare occlusion query: no face skipping, no offsets, no cut-outs (for [`crate::bench`]).
    /// The ray is in the BVH's frame: see [`SceneBvh::centre`].
    pub(crate) fn bare_miss(&self, ray: &Ray) -> bool {
        !self.bvh.any(ray, |_, _| true)
    }

    /// The origin of the BVH's f32 frame (the centre of the scene's bounds): a bare `Ray` for the BVH
    /// has its origin at `p − centre` for a scene point `p`.
    pub fn centre(&self) -> DVec3 {
        self.centre
    }

    /// Number of BVH primitives (more than the face count when spatial splits duplicated references).
    pub fn primitive_count(&self) -> usize {
        self.bvh.primitive_count()
    }

    /// The instructions the traversal tests eight child boxes with on this CPU: `"AVX"` (one
    /// 256-bit register per bound) or `"SSE"` (two halves); the same hits either way.
    pub fn node_test(&self) -> &'static str {
        self.bvh.node_test()
    }
}

/// The closest hit of a Flatland ray.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FlatHit {
    /// Segment index.
    pub segment: u32,
    /// Ray parameter in units of `|dir|`.
    pub t: f64,
    /// Hit position.
    pub point: DVec2,
}

/// Ray casting and visibility in a Flatland scene: brute force over the segments (Flatland scenes have tens
/// of segments; a loop beats any tree there). f64 throughout; same id-skipping and offset policy as
/// [`SceneBvh`] with `eps = 1e-9 · diagonal`.
#[derive(Clone, Debug)]
pub struct FlatVisibility {
    segs: Vec<(DVec2, DVec2, DVec2)>,
    eps: f64,
}

/// Parameter `(t, s)` of the intersection of `o + t·d` with segment `a + s·(b − a)`, if `s ∈ [0,1]`.
fn seg_intersect(o: DVec2, d: DVec2, a: DVec2, b: DVec2) -> Option<f64> {
    let e = b - a;
    let den = d.perp_dot(e);
    if den == 0.0 {
        return None;
    }
    let w = a - o;
    let t = w.perp_dot(e) / den;
    let s = w.perp_dot(d) / den;
    if (0.0..=1.0).contains(&s) {
        Some(t)
    } else {
        None
    }
}

impl FlatVisibility {
    /// Prepares the segment list.
    pub fn new(scene: &FlatlandScene) -> Self {
        FlatVisibility {
            segs: scene
                .segments
                .iter()
                .map(|s| (s.a, s.b, s.normal))
                .collect(),
            eps: 1e-9 * scene.diagonal(),
        }
    }
    /// The offset used at ray ends.
    pub fn epsilon(&self) -> f64 {
        self.eps
    }
    /// True if the open segment between `x` and `y` crosses no other segment.
    pub fn visible(&self, x: &FlatPoint, y: &FlatPoint) -> bool {
        let d = y.point - x.point;
        let len = d.length();
        if len <= 2.0 * self.eps {
            return true;
        }
        for (i, &(a, b, _)) in self.segs.iter().enumerate() {
            let i = i as u32;
            if i == x.segment || i == y.segment {
                continue;
            }
            if let Some(t) = seg_intersect(x.point, d / len, a, b) {
                if t > self.eps && t < len - self.eps {
                    return false;
                }
            }
        }
        true
    }
    /// Closest hit of `origin + t·dir`, `t ∈ (eps, ∞)`, skipping segment `skip` (or `u32::MAX`).
    pub fn closest_hit(&self, origin: DVec2, dir: DVec2, skip: u32) -> Option<FlatHit> {
        let len = dir.length();
        if len == 0.0 || !len.is_finite() {
            return None;
        }
        let u = dir / len;
        let mut best: Option<(u32, f64, f64)> = None;
        for (i, &(a, b, _)) in self.segs.iter().enumerate() {
            if i as u32 == skip {
                continue;
            }
            if let Some(t) = seg_intersect(origin, u, a, b) {
                // Coincident segments with opposite normals (a two-sided edge): the one facing
                // the ray wins the tie.
                let key = if self.segs[i].2.dot(u) > 0.0 {
                    t + self.eps
                } else {
                    t
                };
                if t > self.eps && best.is_none_or(|(_, bk, _)| key < bk) {
                    best = Some((i as u32, key, t));
                }
            }
        }
        best.map(|(segment, _, t)| FlatHit {
            segment,
            t: t / len,
            point: origin + u * t,
        })
    }
    /// Closest hit of a ray leaving `from` in direction `dir` (its own segment skipped).
    pub fn trace_from(&self, from: &FlatPoint, dir: DVec2) -> Option<FlatHit> {
        self.closest_hit(from.point, dir, from.segment)
    }
    /// The [`FlatPoint`] of a hit.
    pub fn surface_point(&self, hit: &FlatHit) -> FlatPoint {
        FlatPoint {
            point: hit.point,
            normal: self.segs[hit.segment as usize].2,
            segment: hit.segment,
        }
    }
}

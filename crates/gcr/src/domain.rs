//! The scene as the solver sees it, in either dimension.
//!
//! Flatland points are embedded in the z = 0 plane of 3-D space so that one code path serves both
//! dimensions (the Gaussian closed forms do not care about an extra zero coordinate); only the
//! network input dimensions differ: the kernel network sees (x, y) ∈ R^6 in 3-D and R^4 in
//! Flatland, the shading network R^3 or R^2.

use crate::element::{BANDS, Bands, Element};
use glam::{DVec2, DVec3};
use scene_sampler::{
    FlatKernelSampler, FlatPoint, FlatlandScene, KernelSampler, Scene, SurfacePoint,
};

/// One training sample of the kernel network: a ray from sender x to receiver y (sec. 3.4).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ray {
    /// Sender x (Flatland: z = 0).
    pub x: DVec3,
    /// Unit normal at x.
    pub nx: DVec3,
    /// Receiver y.
    pub y: DVec3,
    /// Unit normal at y.
    pub ny: DVec3,
    /// Face (segment) of x.
    pub face_x: u32,
    /// Face (segment) of y.
    pub face_y: u32,
    /// The kernel K(x,y) = ρ(y)·G(x,y)·V(x,y) per band (distance-clamped G, see scene-sampler).
    pub kernel: Bands,
    /// Emission E(x) per band, read exactly from the scene (docs/design/math.md §4).
    pub emission_x: Bands,
}

/// The two end points of a ray, before the kernel is evaluated.
#[derive(Clone, Copy, Debug)]
pub enum Endpoints {
    /// Sender and receiver on a 3-D scene.
    ThreeD(SurfacePoint, SurfacePoint),
    /// Sender and receiver on a Flatland scene.
    Flat(FlatPoint, FlatPoint),
}

impl Endpoints {
    /// The kernel network's input (x, y) for these end points: 6 or 4 numbers.
    pub fn input(&self, out: &mut Vec<f64>) {
        out.clear();
        match self {
            Endpoints::ThreeD(x, y) => {
                out.extend_from_slice(&x.point.to_array());
                out.extend_from_slice(&y.point.to_array());
            }
            Endpoints::Flat(x, y) => {
                out.extend_from_slice(&x.point.to_array());
                out.extend_from_slice(&y.point.to_array());
            }
        }
    }
}

/// A scene of either dimension with its kernel evaluator.
pub enum Domain<'a> {
    /// A 3-D triangle scene.
    ThreeD(KernelSampler<'a>),
    /// A Flatland scene.
    Flat(FlatKernelSampler<'a>),
}

fn d3(p: DVec2) -> DVec3 {
    DVec3::new(p.x, p.y, 0.0)
}

impl Domain<'_> {
    /// Ambient dimension: 3 or 2.
    pub fn dim(&self) -> usize {
        match self {
            Domain::ThreeD(_) => 3,
            Domain::Flat(_) => 2,
        }
    }

    /// Parameters per ray: 4 (s,t,u,v) in 3-D, 2 (s,t) in Flatland (fig. B.2).
    pub fn param_dim(&self) -> usize {
        2 * (self.dim() - 1)
    }

    /// Surface dimension: 2 in 3-D, 1 in Flatland.
    pub fn surface_dim(&self) -> u32 {
        self.dim() as u32 - 1
    }

    /// Colour bands of the scene (1 or 3).
    pub fn bands(&self) -> usize {
        match self {
            Domain::ThreeD(k) => k.scene.bands,
            Domain::Flat(k) => k.scene.bands,
        }
    }

    /// Length of the scene's bounding-box diagonal.
    pub fn diagonal(&self) -> f64 {
        match self {
            Domain::ThreeD(k) => k.scene.diagonal(),
            Domain::Flat(k) => k.scene.diagonal(),
        }
    }

    /// The scene's frame: the low corner of its bounding box and the box's diagonal. Seeds and
    /// other per-point choices read coordinates in this frame, so that they do not depend on
    /// where the scene sits or on its scale.
    pub fn frame(&self) -> (DVec3, f64) {
        match self {
            Domain::ThreeD(k) => (k.scene.bounds.0, k.scene.diagonal()),
            Domain::Flat(k) => {
                let lo = k
                    .scene
                    .segments
                    .iter()
                    .fold(DVec2::splat(f64::INFINITY), |lo, s| lo.min(s.a).min(s.b));
                (d3(lo), k.scene.diagonal())
            }
        }
    }

    /// Total surface area (Flatland: total length).
    pub fn total_measure(&self) -> f64 {
        match self {
            Domain::ThreeD(k) => k.sampler.total_area(),
            Domain::Flat(k) => k.sampler.total_length(),
        }
    }

    /// Draws the ray with parameters `u ∈ [0,1]^param_dim` and evaluates the kernel on it.
    pub fn ray(&self, u: &[f64]) -> Ray {
        self.evaluate(&self.endpoints(u))
    }

    /// [`Domain::ray`] for each parameter vector of `us`, in order, with identical results. In 3-D the
    /// samples go through [`KernelSampler::samples`], which prefetches the surface look-ups of the next
    /// samples while one traces its ray (faster on large scenes).
    pub fn rays(&self, us: &[Vec<f64>]) -> Vec<Ray> {
        match self {
            Domain::ThreeD(k) => k
                .samples(us.iter().map(|u| [u[0], u[1], u[2], u[3]]))
                .map(|s| ray_3d(k, &s))
                .collect(),
            Domain::Flat(_) => us.iter().map(|u| self.ray(u)).collect(),
        }
    }

    /// The end points of the ray with parameters `u`, without evaluating the kernel (no ray is
    /// traced): cheap enough to test candidates for resampling (sec. 2.5).
    pub fn endpoints(&self, u: &[f64]) -> Endpoints {
        match self {
            Domain::ThreeD(k) => Endpoints::ThreeD(
                k.sampler.sample([u[0], u[1]]),
                k.sampler.sample([u[2], u[3]]),
            ),
            Domain::Flat(k) => Endpoints::Flat(k.sampler.sample(u[0]), k.sampler.sample(u[1])),
        }
    }

    /// Evaluates the kernel (tracing visibility) between the end points.
    pub fn evaluate(&self, e: &Endpoints) -> Ray {
        match (self, e) {
            (Domain::ThreeD(k), Endpoints::ThreeD(x, y)) => ray_3d(k, &k.eval(*x, *y)),
            (Domain::Flat(k), Endpoints::Flat(x, y)) => {
                let s = k.eval(*x, *y);
                Ray {
                    x: d3(s.x.point),
                    nx: d3(s.x.normal),
                    y: d3(s.y.point),
                    ny: d3(s.y.normal),
                    face_x: s.x.segment,
                    face_y: s.y.segment,
                    kernel: s.kernel().0,
                    emission_x: k.scene.segments[s.x.segment as usize].emission.0,
                }
            }
            _ => unreachable!("end points come from the same domain"),
        }
    }

    /// The kernel network's input vector (x, y) for a ray: 6 or 4 numbers.
    pub fn kernel_input(&self, ray: &Ray, out: &mut Vec<f64>) {
        out.clear();
        let d = self.dim();
        out.extend_from_slice(&ray.x.to_array()[..d]);
        out.extend_from_slice(&ray.y.to_array()[..d]);
    }

    /// The scene's surface elements for exact integration: segments, or triangles with coplanar
    /// pairs merged into quadrilaterals.
    pub fn elements(&self) -> Vec<Element> {
        self.surface_elements().into_iter().map(|e| e.0).collect()
    }

    /// Unit normals of [`Domain::elements`], in the same order (Flatland normals in z = 0).
    pub fn element_normals(&self) -> Vec<DVec3> {
        self.surface_elements().into_iter().map(|e| e.1).collect()
    }

    /// The integration elements with their normals: Flatland segments; in 3-D the scene's
    /// triangles of positive area, where two consecutive ones share an edge, lie in one plane
    /// and form a convex quadrilateral (a rectangle split on load) merged into one
    /// [`Element::Quad`], whose exact Gaussian integral costs two thirds of the two triangles'.
    pub(crate) fn surface_elements(&self) -> Vec<(Element, DVec3)> {
        match self {
            Domain::ThreeD(k) => {
                let faces: Vec<_> = k.scene.faces.iter().filter(|f| f.area > 0.0).collect();
                let tol = 1e-12 * self.diagonal();
                let mut out = Vec::with_capacity(faces.len());
                let mut i = 0;
                while i < faces.len() {
                    let merged = faces
                        .get(i + 1)
                        .and_then(|next| Element::merge_triangles(faces[i].v, next.v, tol));
                    match merged {
                        Some(q) => {
                            out.push((Element::Quad(q), faces[i].normal));
                            i += 2;
                        }
                        None => {
                            out.push((Element::Triangle(faces[i].v), faces[i].normal));
                            i += 1;
                        }
                    }
                }
                out
            }
            Domain::Flat(k) => k
                .scene
                .segments
                .iter()
                .map(|s| (Element::Segment([d3(s.a), d3(s.b)]), d3(s.normal)))
                .collect(),
        }
    }

    /// Emission of face (segment) `face`.
    pub fn emission(&self, face: u32) -> Bands {
        match self {
            Domain::ThreeD(k) => k.scene.faces[face as usize].emission.0,
            Domain::Flat(k) => k.scene.segments[face as usize].emission.0,
        }
    }

    /// Reflectance at `point` on face (segment) `face`: a textured face's texture there
    /// ([`scene_sampler::Scene::rho_at`]), else the face's ρ.
    pub fn reflectance_at(&self, face: u32, point: DVec3) -> Bands {
        match self {
            Domain::ThreeD(k) => k.scene.rho_at(face, point).0,
            Domain::Flat(k) => k.scene.segments[face as usize].rho.0,
        }
    }

    /// Per band, the maximum principle's bound `E_max / (1 − ρ_max)` on any radiosity (and any
    /// sample strength): `B = E + ρ ∫ G B` with `∫_S G(x, y) dy ≤ 1` gives
    /// `B_max ≤ E_max + ρ_max B_max`. Infinite when ρ_max ≥ 1 (the loaders reject that).
    pub fn radiosity_bound(&self) -> Bands {
        let faces: Vec<(Bands, Bands)> = match self {
            Domain::ThreeD(k) => k
                .scene
                .faces
                .iter()
                .map(|f| (f.emission.0, f.rho.0))
                .collect(),
            Domain::Flat(k) => k
                .scene
                .segments
                .iter()
                .map(|s| (s.emission.0, s.rho.0))
                .collect(),
        };
        let mut bound = [0.0; BANDS];
        for (k, b) in bound.iter_mut().enumerate() {
            let e = faces.iter().map(|f| f.0[k]).fold(0.0, f64::max);
            let rho = faces.iter().map(|f| f.1[k]).fold(0.0, f64::max);
            *b = if rho < 1.0 {
                e / (1.0 - rho)
            } else {
                f64::INFINITY
            };
        }
        bound
    }

    /// The 3-D scene, if this is one.
    pub fn scene_3d(&self) -> Option<&Scene> {
        match self {
            Domain::ThreeD(k) => Some(k.scene),
            Domain::Flat(_) => None,
        }
    }

    /// The Flatland scene, if this is one.
    pub fn scene_flat(&self) -> Option<&FlatlandScene> {
        match self {
            Domain::ThreeD(_) => None,
            Domain::Flat(k) => Some(k.scene),
        }
    }

    /// True when the midpoint of the straight line a–b lies farther than `tol` from the surfaces
    /// along the normal `n` (both ways): the line spans empty space (the breaking operator's gap
    /// test). O(log faces) in 3-D through the BVH.
    pub fn spans_gap(&self, a: DVec3, b: DVec3, n: DVec3, tol: f64) -> bool {
        let m = 0.5 * (a + b);
        if n == DVec3::ZERO {
            return false;
        }
        match self {
            Domain::ThreeD(k) => k
                .bvh
                .closest_hit(m - n * tol, n, 2.0 * tol, u32::MAX)
                .is_none(),
            Domain::Flat(k) => {
                let (m2, n2) = (DVec2::new(m.x, m.y), DVec2::new(n.x, n.y));
                k.vis
                    .closest_hit(m2 - n2 * tol, n2 * (2.0 * tol), u32::MAX)
                    .is_none_or(|h| h.t > 1.0)
            }
        }
    }

    /// A surface point as the 3-D kernel sees it (for gathers at arbitrary points).
    pub fn surface_point_3d(point: DVec3, normal: DVec3, face: u32) -> SurfacePoint {
        SurfacePoint {
            point,
            normal,
            face,
        }
    }

    /// A Flatland surface point from its embedding.
    pub fn flat_point(point: DVec3, normal: DVec3, segment: u32) -> FlatPoint {
        FlatPoint {
            point: DVec2::new(point.x, point.y),
            normal: DVec2::new(normal.x, normal.y),
            segment,
        }
    }
}

/// The [`Ray`] of a 3-D kernel sample.
fn ray_3d(k: &KernelSampler, s: &scene_sampler::KernelSample) -> Ray {
    Ray {
        x: s.x.point,
        nx: s.x.normal,
        y: s.y.point,
        ny: s.y.normal,
        face_x: s.x.face,
        face_y: s.y.face,
        kernel: s.kernel().0,
        emission_x: k.scene.faces[s.x.face as usize].emission.0,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use scene_sampler::{AnyScene, SceneBvh, builtin};

    /// The bound is E_max/(1 − ρ_max) per band: tight in the furnace (B = E/(1 − ρ) exactly),
    /// above every face's own E in the Cornell box.
    #[test]
    fn radiosity_bound_is_the_maximum_principle() {
        let AnyScene::ThreeD(furnace) = builtin("furnace").unwrap() else {
            panic!()
        };
        let bvh = SceneBvh::new(&furnace);
        let d = Domain::ThreeD(KernelSampler::new(&furnace, &bvh));
        let f = &furnace.faces[0];
        let b = d.radiosity_bound();
        for k in 0..d.bands() {
            let exact = f.emission.0[k] / (1.0 - f.rho.0[k]);
            assert!((b[k] - exact).abs() <= 1e-12 * exact, "{b:?} vs {exact}");
        }
        let AnyScene::ThreeD(cornell) = builtin("cornell-box").unwrap() else {
            panic!()
        };
        let bvh = SceneBvh::new(&cornell);
        let d = Domain::ThreeD(KernelSampler::new(&cornell, &bvh));
        let b = d.radiosity_bound();
        let light = cornell
            .faces
            .iter()
            .find(|f| !f.emission.is_zero())
            .unwrap();
        for k in 0..3 {
            assert!(b[k] > light.emission.0[k] && b[k].is_finite(), "{b:?}");
        }
    }

    /// `Domain::rays` (batched, prefetching on large scenes) returns exactly `Domain::ray` per vector, in
    /// order: on the Cornell box, on 20k random boxes (large enough for the prefetching path), in Flatland.
    #[test]
    fn batched_rays_equal_single_rays() {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
        let AnyScene::ThreeD(cornell) = builtin("cornell-box").unwrap() else {
            panic!()
        };
        let boxes = scene_sampler::random_boxes(20_000, 2);
        for scene in [&cornell, &boxes] {
            let bvh = SceneBvh::with_quality(scene, scene_sampler::BuildQuality::Medium);
            let d = Domain::ThreeD(KernelSampler::new(scene, &bvh));
            let us: Vec<Vec<f64>> = (0..500)
                .map(|_| (0..4).map(|_| rng.random()).collect())
                .collect();
            let single: Vec<Ray> = us.iter().map(|u| d.ray(u)).collect();
            assert_eq!(d.rays(&us), single);
            assert_eq!(d.rays(&us[..3]), single[..3]);
        }
        let AnyScene::Flatland(flat) = builtin("flatland-corner").unwrap() else {
            panic!()
        };
        let d = Domain::Flat(FlatKernelSampler::new(&flat));
        let us: Vec<Vec<f64>> = (0..100).map(|_| vec![rng.random(), rng.random()]).collect();
        let single: Vec<Ray> = us.iter().map(|u| d.ray(u)).collect();
        assert_eq!(d.rays(&us), single);
    }

    #[test]
    fn cornell_rays_have_finite_nonnegative_kernels_and_6d_inputs() {
        let AnyScene::ThreeD(scene) = builtin("cornell-box").unwrap() else {
            panic!()
        };
        let bvh = SceneBvh::new(&scene);
        let d = Domain::ThreeD(KernelSampler::new(&scene, &bvh));
        assert_eq!((d.dim(), d.param_dim(), d.surface_dim()), (3, 4, 2));
        let mut input = Vec::new();
        let mut nonzero = 0;
        for i in 0..200 {
            let u = [0.13, 0.71, 0.37, 0.93].map(|v: f64| (v * (i + 1) as f64).fract());
            let r = d.ray(&u);
            assert!(r.kernel.iter().all(|k| k.is_finite() && *k >= 0.0));
            nonzero += (r.kernel[0] > 0.0) as usize;
            d.kernel_input(&r, &mut input);
            assert_eq!(input.len(), 6);
            assert_eq!(input[3..], r.y.to_array());
        }
        assert!(
            nonzero > 50,
            "most pairs in a closed box see each other: {nonzero}"
        );
        // The gap test: a chord across the box interior spans empty space, one on the floor does not.
        let floor = scene
            .faces
            .iter()
            .find(|f| f.normal.y > 0.99 && f.emission.is_zero())
            .unwrap();
        let (a, b) = (floor.v[0], floor.point(0.5, 0.4));
        assert!(!d.spans_gap(a, b, floor.normal, 1e-3 * d.diagonal()));
        let up = a + floor.normal * 0.3 * d.diagonal();
        assert!(d.spans_gap(a, up + (b - a), floor.normal, 1e-3 * d.diagonal()));
    }

    #[test]
    fn flatland_rays_live_in_the_z0_plane_with_4d_inputs() {
        let AnyScene::Flatland(scene) = builtin("flatland-corner").unwrap() else {
            panic!()
        };
        let d = Domain::Flat(FlatKernelSampler::new(&scene));
        assert_eq!((d.dim(), d.param_dim(), d.surface_dim()), (2, 2, 1));
        let r = d.ray(&[0.2, 0.8]);
        assert_eq!((r.x.z, r.y.z, r.nx.z), (0.0, 0.0, 0.0));
        let mut input = Vec::new();
        d.kernel_input(&r, &mut input);
        assert_eq!(input.len(), 4);
        assert_eq!(d.elements().len(), scene.segments.len());
    }
}

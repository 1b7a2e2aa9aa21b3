//! Classical radiosity in 3-D (sec. 1.3, eqs. 1.13–1.17 with constant elements): the faces are subdivided
//! uniformly to a target element size, the form factors `F_ij` are computed point-to-area (the exact
//! unoccluded point-to-polygon form factor, averaged over sample points of the receiver) times a ray-traced
//! visibility fraction, and `b = e + diag(ρ) F b` is solved by Gauss–Seidel ([`solve`]). Progressive refinement
//! on the same mesh and form factors is in [`crate::progressive`].

use crate::error::{BaselineError, check_range};
use glam::DVec3;
use rayon::prelude::*;
use scene_sampler::{Scene, SceneBvh, SurfacePoint};

/// The exact form factor from a differential area at `x` with unit normal `n` to a convex polygon `poly`
/// (Lambert's contour integral: `F = (1/2π) |Σ_k γ_k · n|`, `γ_k` the angle subtended by edge k times the
/// unit normal of the plane through `x` and that edge). The polygon is first clipped to the front half-space
/// of `x`; visibility is not considered. Zero if `x` is behind the polygon's plane.
///
/// This is the quantity of the analytic configuration factors of docs/design/math.md §8.
pub fn point_to_polygon(x: DVec3, n: DVec3, poly: &[DVec3]) -> f64 {
    if poly.len() < 3 {
        return 0.0;
    }
    // x must see the polygon's front: polygon normal from its winding (Newell)
    let mut pn = DVec3::ZERO;
    for k in 0..poly.len() {
        let (a, b) = (poly[k], poly[(k + 1) % poly.len()]);
        pn += (a - x).cross(b - x);
    }
    if pn.dot(x - poly[0]) <= 0.0 {
        // x on the back side (the winding seen from x is clockwise)
        return 0.0;
    }
    // Sutherland–Hodgman against n·(p − x) ≥ 0
    let mut clipped: Vec<DVec3> = Vec::with_capacity(poly.len() + 1);
    for k in 0..poly.len() {
        let (a, b) = (poly[k], poly[(k + 1) % poly.len()]);
        let (fa, fb) = (n.dot(a - x), n.dot(b - x));
        if fa >= 0.0 {
            clipped.push(a);
        }
        if (fa >= 0.0) != (fb >= 0.0) {
            clipped.push(a + (b - a) * (fa / (fa - fb)));
        }
    }
    if clipped.len() < 3 {
        return 0.0;
    }
    let mut sum = 0.0;
    for k in 0..clipped.len() {
        let (a, b) = (clipped[k] - x, clipped[(k + 1) % clipped.len()] - x);
        let c = a.cross(b);
        let cl = c.length();
        if cl == 0.0 {
            continue;
        }
        let angle = cl.atan2(a.dot(b));
        sum += angle * c.dot(n) / cl;
    }
    (sum / (2.0 * std::f64::consts::PI)).abs()
}

/// One constant element: a sub-triangle of a scene face, same winding (normal) as its face.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Element {
    /// Scene face index.
    pub face: u32,
    /// Vertices.
    pub v: [DVec3; 3],
    /// Unit normal (the face's).
    pub normal: DVec3,
    /// Area.
    pub area: f64,
    /// Reflectance per band (the face's).
    pub rho: [f64; 3],
    /// Emitted radiosity per band (the face's).
    pub emission: [f64; 3],
}

impl Element {
    /// Centroid.
    pub fn centroid(&self) -> DVec3 {
        (self.v[0] + self.v[1] + self.v[2]) / 3.0
    }
    /// Longest edge.
    pub fn diameter(&self) -> f64 {
        let [a, b, c] = self.v;
        a.distance(b).max(b.distance(c)).max(c.distance(a))
    }
}

/// The `k²` equal-area sub-triangles of a `k × k` barycentric subdivision of `v` (same orientation as `v`).
pub fn subdivide(v: [DVec3; 3], k: usize) -> Vec<[DVec3; 3]> {
    let k = k.max(1);
    let p = |i: usize, j: usize| {
        v[0] + (v[1] - v[0]) * (i as f64 / k as f64) + (v[2] - v[0]) * (j as f64 / k as f64)
    };
    let mut out = Vec::with_capacity(k * k);
    for j in 0..k {
        for i in 0..k - j {
            out.push([p(i, j), p(i + 1, j), p(i, j + 1)]);
            if i + j + 1 < k {
                out.push([p(i + 1, j), p(i + 1, j + 1), p(i, j + 1)]);
            }
        }
    }
    out
}

/// Largest mesh the dense-pair solvers accept.
pub const MAX_ELEMENTS: usize = 40_000;

/// A uniform mesh of a scene: face `f` is split into `k_f²` sub-triangles with `k_f = ⌈longest edge / size⌉`.
#[derive(Clone, Debug)]
pub struct Mesh {
    /// The elements, face by face.
    pub elements: Vec<Element>,
    /// Elements of face `f` are `first[f]..first[f + 1]`.
    pub first: Vec<usize>,
    /// Subdivision level per face.
    pub level: Vec<usize>,
}

impl Mesh {
    /// Meshes `scene` to the target element size (longest element edge ≤ `size`).
    ///
    /// # Errors
    /// `size` not positive and finite, or more than [`MAX_ELEMENTS`] elements.
    pub fn new(scene: &Scene, size: f64) -> Result<Mesh, BaselineError> {
        check_range(
            "element_size",
            size,
            0.0,
            f64::INFINITY,
            "a positive length",
        )?;
        let level: Vec<usize> = scene
            .faces
            .iter()
            .map(|f| {
                let [a, b, c] = f.v;
                let l = a.distance(b).max(b.distance(c)).max(c.distance(a));
                (l / size).ceil().clamp(1.0, 1e6) as usize
            })
            .collect();
        let total: usize = level.iter().map(|k| k * k).sum();
        if total > MAX_ELEMENTS {
            return Err(BaselineError::TooManyElements {
                elements: total,
                limit: MAX_ELEMENTS,
            });
        }
        let mut elements = Vec::with_capacity(total);
        let mut first = vec![0];
        for (fi, f) in scene.faces.iter().enumerate() {
            for v in subdivide(f.v, level[fi]) {
                elements.push(Element {
                    face: fi as u32,
                    v,
                    normal: f.normal,
                    area: f.area / (level[fi] * level[fi]) as f64,
                    rho: f.rho.0,
                    emission: f.emission.0,
                });
            }
            first.push(elements.len());
        }
        Ok(Mesh {
            elements,
            first,
            level,
        })
    }

    /// The element of face `p.face` that contains `p.point` (the nearest one if the point is off the face).
    ///
    /// # Errors
    /// The face is not in the mesh.
    pub fn locate(&self, p: &SurfacePoint) -> Result<usize, BaselineError> {
        let f = p.face as usize;
        if f + 1 >= self.first.len() {
            return Err(BaselineError::NoSuchElement {
                index: 0,
                what: "face",
                id: p.face,
                count: self.first.len() - 1,
            });
        }
        let mut best = (f64::INFINITY, self.first[f]);
        for i in self.first[f]..self.first[f + 1] {
            let d = scene_sampler::Face::new(
                self.elements[i].v,
                Default::default(),
                Default::default(),
                0,
                0,
            )
            .closest_point(p.point)
            .distance_squared(p.point);
            if d < best.0 {
                best = (d, i);
            }
        }
        Ok(best.1)
    }
}

/// How form factors are computed.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FormFactorOptions {
    /// Visibility rays per element pair (spread over the receiver's sample points, at least one each).
    pub visibility_rays: usize,
    /// Seed of the jittered ray end points on the source element (each pair has its own stream).
    pub seed: u64,
}

impl Default for FormFactorOptions {
    /// 16 rays per pair, seed 1.
    fn default() -> Self {
        FormFactorOptions {
            visibility_rays: 16,
            seed: 1,
        }
    }
}

/// SplitMix64: a tiny per-pair random stream (deterministic whatever the thread count).
struct SplitMix(u64);
impl SplitMix {
    fn next_f64(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^= z >> 31;
        (z >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// Receiver sample points: centroids of the `k²` sub-triangles, `k` from the distance of the pair relative
/// to the larger element (2 when far, 4 when closer than 4 diameters, 8 when closer than 1.5).
fn receiver_level(ei: &Element, ej: &Element) -> usize {
    let d = ei.centroid().distance(ej.centroid());
    let r = ei.diameter().max(ej.diameter());
    if d < 1.5 * r {
        8
    } else if d < 4.0 * r {
        4
    } else {
        2
    }
}

/// A uniformly distributed point of triangle `v` from `u ∈ [0,1)²` (square-root map).
fn triangle_point(v: &[DVec3; 3], u0: f64, u1: f64) -> DVec3 {
    let su = u0.sqrt();
    v[0] * (1.0 - su) + v[1] * (su * (1.0 - u1)) + v[2] * (su * u1)
}

/// Form factor `F_ij` (the fraction of the power leaving element `i` that arrives at element `j`):
/// `F_ij ≈ (1/S) Σ_s F(x_s → j) · v_s` over `S` equal-area sample points `x_s` of `i`, with
/// [`point_to_polygon`] exact for the unoccluded part and `v_s` the fraction of rays from `x_s` to jittered
/// points of `j` that [`SceneBvh::visible`] lets through.
pub fn form_factor(
    bvh: &SceneBvh,
    elements: &[Element],
    i: usize,
    j: usize,
    opts: &FormFactorOptions,
) -> f64 {
    let (ei, ej) = (&elements[i], &elements[j]);
    if i == j || ei.face == ej.face {
        return 0.0;
    }
    // quick rejects: j entirely behind i, or i entirely behind j
    if ej.v.iter().all(|p| ei.normal.dot(*p - ei.v[0]) <= 0.0)
        || ei.v.iter().all(|p| ej.normal.dot(*p - ej.v[0]) <= 0.0)
    {
        return 0.0;
    }
    let xs: Vec<DVec3> = subdivide(ei.v, receiver_level(ei, ej))
        .iter()
        .map(|t| (t[0] + t[1] + t[2]) / 3.0)
        .collect();
    let per = opts.visibility_rays.div_ceil(xs.len()).max(1);
    let mut rng = SplitMix(
        opts.seed
            ^ (i as u64).wrapping_mul(0xD1B5_4A32_D192_ED03)
            ^ (j as u64).wrapping_mul(0x8CB9_2BA7_2F3D_8DD7),
    );
    let mut total = 0.0;
    for &x in &xs {
        let f = point_to_polygon(x, ei.normal, &ej.v);
        if f <= 0.0 {
            continue;
        }
        let px = SurfacePoint {
            point: x,
            normal: ei.normal,
            face: ei.face,
        };
        let mut seen = 0;
        for _ in 0..per {
            let y = triangle_point(&ej.v, rng.next_f64(), rng.next_f64());
            let py = SurfacePoint {
                point: y,
                normal: ej.normal,
                face: ej.face,
            };
            if bvh.visible(&px, &py) {
                seen += 1;
            }
        }
        total += f * seen as f64 / per as f64;
    }
    total / xs.len() as f64
}

/// Row `i` of the form factor matrix as sparse `(j, F_ij)` pairs (zeros left out), `j` in parallel.
pub fn form_factor_row(
    bvh: &SceneBvh,
    elements: &[Element],
    i: usize,
    opts: &FormFactorOptions,
) -> Vec<(u32, f64)> {
    (0..elements.len())
        .into_par_iter()
        .with_min_len(64)
        .filter_map(|j| {
            let f = form_factor(bvh, elements, i, j, opts);
            (f > 0.0).then_some((j as u32, f))
        })
        .collect()
}

/// Options of the classical (Gauss–Seidel) solver.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ClassicalOptions {
    /// Target element size (longest element edge), world units.
    pub element_size: f64,
    /// Form factor options.
    pub form_factors: FormFactorOptions,
    /// Stop when a sweep changes no B by more than `tolerance ·` the largest B.
    pub tolerance: f64,
    /// Sweep cap.
    pub max_iterations: usize,
}

impl Default for ClassicalOptions {
    /// Element size 0.05, 16 visibility rays per pair, tolerance 10⁻⁹, at most 1000 sweeps.
    fn default() -> Self {
        ClassicalOptions {
            element_size: 0.05,
            form_factors: FormFactorOptions::default(),
            tolerance: 1e-9,
            max_iterations: 1000,
        }
    }
}

/// A solved classical radiosity system.
#[derive(Clone, Debug)]
pub struct ClassicalRadiosity {
    /// The mesh.
    pub mesh: Mesh,
    /// Sparse form factor rows `(j, F_ij)`.
    pub rows: Vec<Vec<(u32, f64)>>,
    /// Radiosity per element, per band.
    pub b: Vec<[f64; 3]>,
    /// Gauss–Seidel sweeps used.
    pub iterations: usize,
}

/// Gauss–Seidel on `b_i = e_i + ρ_i Σ_j F_ij b_j` (eq. 1.17 with the newest values), all bands at once.
/// Returns `(b, sweeps)`.
pub(crate) fn gauss_seidel(
    elements: &[Element],
    rows: &[Vec<(u32, f64)>],
    tolerance: f64,
    max_iterations: usize,
) -> Result<(Vec<[f64; 3]>, usize), BaselineError> {
    let mut b: Vec<[f64; 3]> = elements.iter().map(|e| e.emission).collect();
    let mut change = f64::INFINITY;
    for it in 1..=max_iterations {
        change = 0.0;
        let mut largest: f64 = 0.0;
        for i in 0..b.len() {
            let mut g = [0.0; 3];
            for &(j, f) in &rows[i] {
                for k in 0..3 {
                    g[k] += f * b[j as usize][k];
                }
            }
            for k in 0..3 {
                let v = elements[i].emission[k] + elements[i].rho[k] * g[k];
                change = change.max((v - b[i][k]).abs());
                largest = largest.max(v);
                b[i][k] = v;
            }
        }
        if change <= tolerance * largest {
            return Ok((b, it));
        }
    }
    Err(BaselineError::NotConverged {
        iterations: max_iterations,
        change,
    })
}

/// Meshes the scene, computes all form factors (rows in parallel) and solves by Gauss–Seidel.
///
/// # Errors
/// Bad options (non-positive size or tolerance, zero rays), too many elements, or no convergence.
pub fn solve(
    scene: &Scene,
    bvh: &SceneBvh,
    opts: &ClassicalOptions,
) -> Result<ClassicalRadiosity, BaselineError> {
    check_range("tolerance", opts.tolerance, 0.0, 1.0, "0 < tolerance < 1")?;
    if opts.form_factors.visibility_rays == 0 {
        return Err(BaselineError::InvalidParameter {
            name: "visibility_rays",
            value: 0.0,
            expected: "at least one ray per pair",
        });
    }
    let mesh = Mesh::new(scene, opts.element_size)?;
    let rows: Vec<Vec<(u32, f64)>> = (0..mesh.elements.len())
        .into_par_iter()
        .map(|i| {
            (0..mesh.elements.len())
                .filter_map(|j| {
                    let f = form_factor(bvh, &mesh.elements, i, j, &opts.form_factors);
                    (f > 0.0).then_some((j as u32, f))
                })
                .collect()
        })
        .collect();
    let (b, iterations) = gauss_seidel(&mesh.elements, &rows, opts.tolerance, opts.max_iterations)?;
    Ok(ClassicalRadiosity {
        mesh,
        rows,
        b,
        iterations,
    })
}

/// B at surface points from a per-element solution: the value of the element containing each point.
pub(crate) fn element_values(
    mesh: &Mesh,
    b: &[[f64; 3]],
    points: &[SurfacePoint],
) -> Result<Vec<[f64; 3]>, BaselineError> {
    points
        .iter()
        .enumerate()
        .map(|(index, p)| {
            mesh.locate(p).map(|i| b[i]).map_err(|e| match e {
                BaselineError::NoSuchElement {
                    what, id, count, ..
                } => BaselineError::NoSuchElement {
                    index,
                    what,
                    id,
                    count,
                },
                other => other,
            })
        })
        .collect()
}

/// Final gather at surface points: `B(p) = E(p) + ρ(p) Σ_j F(p → j) v_j b_j` with the exact unoccluded
/// point-to-element form factor and a visibility fraction from `rays` jittered rays per element (eq. 1.4 with
/// the piecewise-constant solution under the integral). In parallel over points.
pub(crate) fn gather(
    scene: &Scene,
    bvh: &SceneBvh,
    mesh: &Mesh,
    b: &[[f64; 3]],
    points: &[SurfacePoint],
    rays: usize,
    seed: u64,
) -> Result<Vec<[f64; 3]>, BaselineError> {
    for (index, p) in points.iter().enumerate() {
        if p.face as usize >= scene.faces.len() {
            return Err(BaselineError::NoSuchElement {
                index,
                what: "face",
                id: p.face,
                count: scene.faces.len(),
            });
        }
    }
    let rays = rays.max(1);
    Ok(points
        .par_iter()
        .enumerate()
        .map(|(pi, p)| {
            let face = &scene.faces[p.face as usize];
            let mut g = [0.0; 3];
            for (j, ej) in mesh.elements.iter().enumerate() {
                if ej.face == p.face {
                    continue;
                }
                let f = point_to_polygon(p.point, p.normal, &ej.v);
                if f <= 0.0 {
                    continue;
                }
                let mut rng = SplitMix(
                    seed ^ (pi as u64).wrapping_mul(0xD1B5_4A32_D192_ED03)
                        ^ (j as u64).wrapping_mul(0x8CB9_2BA7_2F3D_8DD7),
                );
                let seen = (0..rays)
                    .filter(|_| {
                        let y = triangle_point(&ej.v, rng.next_f64(), rng.next_f64());
                        bvh.visible(
                            p,
                            &SurfacePoint {
                                point: y,
                                normal: ej.normal,
                                face: ej.face,
                            },
                        )
                    })
                    .count();
                let w = f * seen as f64 / rays as f64;
                for k in 0..3 {
                    g[k] += w * b[j][k];
                }
            }
            [0, 1, 2].map(|k| face.emission.0[k] + face.rho.0[k] * g[k])
        })
        .collect())
}

impl ClassicalRadiosity {
    /// `Σ_j F_ij` for element `i` (≤ 1 up to sampling error; ≈ 1 in a closed scene).
    pub fn row_sum(&self, i: usize) -> f64 {
        self.rows[i].iter().map(|r| r.1).sum()
    }
    /// B at surface points: the value of the containing element (piecewise constant).
    ///
    /// # Errors
    /// A point whose face is not in the scene.
    pub fn at_points(&self, points: &[SurfacePoint]) -> Result<Vec<[f64; 3]>, BaselineError> {
        element_values(&self.mesh, &self.b, points)
    }
    /// B at surface points by a final gather over all elements (see the crate docs); `rays` visibility rays
    /// per element and point. Much closer to the pointwise truth than [`ClassicalRadiosity::at_points`].
    ///
    /// # Errors
    /// A point whose face is not in the scene.
    pub fn gather(
        &self,
        scene: &Scene,
        bvh: &SceneBvh,
        points: &[SurfacePoint],
        rays: usize,
        seed: u64,
    ) -> Result<Vec<[f64; 3]>, BaselineError> {
        gather(scene, bvh, &self.mesh, &self.b, points, rays, seed)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::pointwise;
    use scene_sampler::{AnyScene, Face, Spectrum, builtin};
    use std::f64::consts::PI;

    /// docs/design/math.md §8, parallel rectangle a×b at height c above one corner.
    fn parallel(a: f64, b: f64, c: f64) -> f64 {
        let (x, y) = (a / c, b / c);
        let (sx, sy) = ((1.0 + x * x).sqrt(), (1.0 + y * y).sqrt());
        (x / sx * (y / sx).atan() + y / sy * (x / sy).atan()) / (2.0 * PI)
    }
    /// docs/design/math.md §8, perpendicular rectangle: edge a on the element's plane at distance b, height c.
    fn perpendicular(a: f64, b: f64, c: f64) -> f64 {
        let (x, y) = (c / a, b / a);
        let s = (x * x + y * y).sqrt();
        ((1.0 / y).atan() - y / s * (1.0 / s).atan()) / (2.0 * PI)
    }

    #[test]
    fn point_to_polygon_matches_the_analytic_configuration_factors() {
        let o = DVec3::ZERO;
        for (a, b, c) in [(1.0, 1.0, 1.0), (2.0, 0.5, 0.7), (0.3, 3.0, 2.0)] {
            // rectangle [0,a]×[0,b] at z = c, facing down (clockwise seen from above)
            let rect = [
                DVec3::new(0.0, 0.0, c),
                DVec3::new(0.0, b, c),
                DVec3::new(a, b, c),
                DVec3::new(a, 0.0, c),
            ];
            let f = point_to_polygon(o, DVec3::Z, &rect);
            assert!(
                (f - parallel(a, b, c)).abs() < 1e-12,
                "{f} vs {}",
                parallel(a, b, c)
            );
            // as two triangles
            let t = point_to_polygon(o, DVec3::Z, &rect[..3])
                + point_to_polygon(o, DVec3::Z, &[rect[0], rect[2], rect[3]]);
            assert!((t - f).abs() < 1e-12);
            // wrong side: zero
            assert_eq!(
                point_to_polygon(o, DVec3::Z, &[rect[3], rect[2], rect[1], rect[0]]),
                0.0
            );
        }
        for (a, b, c) in [(1.0, 1.0, 1.0), (2.0, 0.5, 0.7), (0.4, 1.5, 2.0)] {
            // element at the origin facing +x... the rectangle stands on the element's plane (z = 0) at x = b,
            // edge of length a along y from the origin's foot, height c; faces −x
            let rect = [
                DVec3::new(b, 0.0, 0.0),
                DVec3::new(b, 0.0, c),
                DVec3::new(b, a, c),
                DVec3::new(b, a, 0.0),
            ];
            let f = point_to_polygon(o, DVec3::Z, &rect);
            assert!(
                (f - perpendicular(a, b, c)).abs() < 1e-12,
                "{f} vs {}",
                perpendicular(a, b, c)
            );
        }
        // a polygon straddling the tangent plane is clipped: the full hemisphere cap of a huge box wall
        let big = [
            DVec3::new(-1e3, -1e3, 1.0),
            DVec3::new(-1e3, 1e3, 1.0),
            DVec3::new(1e3, 1e3, 1.0),
            DVec3::new(1e3, -1e3, 1.0),
        ];
        assert!((point_to_polygon(o, DVec3::Z, &big) - 1.0).abs() < 2e-3);
    }

    fn rect_faces(p: [DVec3; 4], rho: f64, e: f64, obj: u32) -> Vec<Face> {
        vec![
            Face::new(
                [p[0], p[1], p[2]],
                Spectrum::grey(rho),
                Spectrum::grey(e),
                obj,
                obj,
            ),
            Face::new(
                [p[0], p[2], p[3]],
                Spectrum::grey(rho),
                Spectrum::grey(e),
                obj,
                obj,
            ),
        ]
    }

    #[test]
    fn element_form_factors_reproduce_the_configuration_factors_within_one_percent() {
        // a 2 mm receiver at the origin, a 1 × 0.6 rectangle 0.8 above its corner, and a perpendicular one
        let s = 0.002;
        let mut faces = rect_faces(
            [
                DVec3::new(-s, -s, 0.0),
                DVec3::new(0.0, -s, 0.0),
                DVec3::new(0.0, 0.0, 0.0),
                DVec3::new(-s, 0.0, 0.0),
            ],
            0.5,
            0.0,
            0,
        );
        let (a, b, c) = (1.0, 0.6, 0.8);
        faces.extend(rect_faces(
            [
                DVec3::new(0.0, 0.0, c),
                DVec3::new(0.0, b, c),
                DVec3::new(a, b, c),
                DVec3::new(a, 0.0, c),
            ],
            0.5,
            1.0,
            1,
        ));
        let (pa, pb, pc) = (0.7, 0.5, 0.9);
        faces.extend(rect_faces(
            [
                DVec3::new(-s - pb, 0.0, 0.0),
                DVec3::new(-s - pb, pa, 0.0),
                DVec3::new(-s - pb, pa, pc),
                DVec3::new(-s - pb, 0.0, pc),
            ],
            0.5,
            0.0,
            2,
        ));
        let scene = Scene::new("cf", "test", faces, vec![], None).unwrap();
        let bvh = SceneBvh::new(&scene);
        let mesh = Mesh::new(&scene, 10.0).unwrap();
        assert_eq!(mesh.elements.len(), 6);
        let o = FormFactorOptions::default();
        let to = |j0: usize| {
            (0..2)
                .map(|r| {
                    form_factor(&bvh, &mesh.elements, r, j0, &o)
                        + form_factor(&bvh, &mesh.elements, r, j0 + 1, &o)
                })
                .sum::<f64>()
                / 2.0
        };
        let fp = to(2);
        let want = parallel(a, b, c);
        assert!((fp / want - 1.0).abs() < 0.01, "parallel: {fp} vs {want}");
        // the perpendicular rectangle is at distance pb + s from the receiver's centre... within 1 %
        let fq = to(4);
        let want = perpendicular(pa, pb, pc);
        assert!(
            (fq / want - 1.0).abs() < 0.01,
            "perpendicular: {fq} vs {want}"
        );
    }

    #[test]
    fn furnace_rows_sum_to_one_and_b_is_e_over_one_minus_rho() {
        let AnyScene::ThreeD(scene) = builtin("furnace").unwrap() else {
            panic!()
        };
        let bvh = SceneBvh::new(&scene);
        let opts = ClassicalOptions {
            element_size: 0.4,
            ..Default::default()
        };
        let sol = solve(&scene, &bvh, &opts).unwrap();
        let n = sol.mesh.elements.len();
        let worst_row = (0..n)
            .map(|i| (sol.row_sum(i) - 1.0).abs())
            .fold(0.0, f64::max);
        assert!(worst_row < 5e-3, "worst row sum error {worst_row}");
        for bi in &sol.b {
            assert!((bi[0] - 2.0).abs() < 0.02, "{bi:?}");
        }
    }

    #[test]
    fn bad_options_are_errors() {
        let AnyScene::ThreeD(scene) = builtin("furnace").unwrap() else {
            panic!()
        };
        let bvh = SceneBvh::new(&scene);
        let d = ClassicalOptions::default();
        for o in [
            ClassicalOptions {
                element_size: 0.0,
                ..d
            },
            ClassicalOptions {
                element_size: 1e-4,
                ..d
            },
            ClassicalOptions {
                tolerance: 0.0,
                ..d
            },
            ClassicalOptions {
                form_factors: FormFactorOptions {
                    visibility_rays: 0,
                    seed: 0,
                },
                ..d
            },
        ] {
            assert!(solve(&scene, &bvh, &o).is_err(), "{o:?}");
        }
    }

    #[test]
    fn cornell_box_agrees_with_the_path_tracer() {
        let AnyScene::ThreeD(scene) = builtin("cornell-box").unwrap() else {
            panic!()
        };
        let bvh = SceneBvh::new(&scene);
        let opts = ClassicalOptions {
            element_size: 0.12,
            ..Default::default()
        };
        let sol = solve(&scene, &bvh, &opts).unwrap();
        let probes = cornell_probes(&scene);
        let g = sol.gather(&scene, &bvh, &probes, 8, 3).unwrap();
        let ad = crate::Adaptive {
            rel_error: 0.015,
            batch: 2048,
            min_paths: 2048,
            max_paths: 400_000,
            seed: 5,
        };
        let pt = pointwise::radiosity_adaptive(&scene, &bvh, &probes, &ad).unwrap();
        for ((p, g), e) in probes.iter().zip(&g).zip(&pt) {
            for k in 0..3 {
                // 3 standard errors of the path tracer plus 3 % discretization: at this element size the
                // gather is within 2.4 % of a 0.5 %-error path tracer (example `cornell_classical`)
                let tol = 3.0 * e.std_error[k] + 0.03 * e.mean[k];
                assert!(
                    (g[k] - e.mean[k]).abs() < tol,
                    "{:?}: {g:?} vs {e:?}",
                    p.point
                );
            }
        }
    }

    /// Probes on the floor, back wall, left and right walls and ceiling of the Cornell box.
    pub(crate) fn cornell_probes(scene: &Scene) -> Vec<SurfacePoint> {
        let want = [
            (DVec3::new(0.45, 0.0, 0.1), DVec3::Y),
            (DVec3::new(0.28, 0.3, 0.559), -DVec3::Z),
            (DVec3::new(0.55, 0.3, 0.3), -DVec3::X),
            (DVec3::new(0.0, 0.2, 0.2), DVec3::X),
            (DVec3::new(0.1, 0.5488, 0.1), -DVec3::Y),
        ];
        want.iter()
            .map(|&(p, n)| {
                let probe = scene_sampler::Probe {
                    point: p,
                    normal: n,
                    line: 0,
                };
                scene.snap_probe(&probe, 0.01, "test").unwrap()
            })
            .collect()
    }
}

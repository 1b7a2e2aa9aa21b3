//! One FEM step (sec. 3.3–3.9 with docs/design/math.md §3–§5): from the kernel network and the shading
//! network to the reflected radiosity, in O(kernel cells × neighbours).
//!
//! With Λ_q the shading network's Gaussians (eq. 3.20), G their Gram matrix (eq. 3.31),
//! G = L Lᵀ and A = L⁻¹ (the orthonormalization, eq. 3.38–3.40, done stably), and the
//! kernel network Ψ(x,y) = Σ_o v_o exp(−|x − w_o^x|²/d_o²)·exp(−|y − w_o^y|²/d_o²):
//!
//! ```text
//! c_o   = ∫_S exp(−|x − w_o^x|²/d_o²) dx                 (sender side; docs/design/math.md §3)
//! β_qo  = ∫_Ŝ Λ_q(y) exp(−|y − w_o^y|²/d_o²) dy          (receiver side, product rule)
//! u_q   = Σ_o v_o c_o β_qo = ⟨Λ_q | B_refl⟩
//! r     = A u                                              (eq. 3.11 without forming H)
//! γ     = Aᵀ r = G⁻¹ u,    B_refl(x) ≈ Σ_q γ_q Λ_q(x)
//! ```
//!
//! The dissertation's variant ("projected", eq. 3.9–3.12) replaces c_o by
//! c̄_o = ∫ B̄(x) exp(−|x − w_o^x|²/d_o²) dx with B̄ the base's projection of the constant 1.
//!
//! Integration per Gaussian follows fig. 3.6: a base Gaussian whose fuzzy roughness is below the
//! threshold (0.4) and whose depth flag is at least 1 is integrated in closed form over its
//! tangent plane (line in Flatland); otherwise exactly, as the sum over the shading network's
//! triangles (segments) under its support. Inner products are zero across sub-networks and
//! between opposed normals; a transfer is zero when the sender lies behind the receiver.

use crate::cluster::{ClusterTree, Mask};
use crate::config::{BaseDomain, SurfaceClusters, Transfer};
use crate::domain::Domain;
use crate::element::{BANDS, Bands, Element};
use crate::kernel_cells::KernelCells;
use crate::shading::ShadingGeometry;
use crate::spatial::{BoxGrid, width_a};
use gauss_integrals::support_radius;
use glam::DVec3;
use rayon::prelude::*;
use std::sync::Arc;

impl Element {
    /// ∫_element exp(−a|x − c|²) dx, exactly (erf for segments, Owen's T for triangles).
    /// Many Gaussians on one element: [`SceneSurface`] prepares it once.
    pub fn gaussian_integral(&self, c: DVec3, a: f64) -> f64 {
        Prepared::of(self).gaussian_integral(c, a)
    }
}

/// The true scene surface S, indexed for support queries (the sender integral c_o, and the
/// base's integrals when it lives on S, [`BaseDomain::Scene`]).
///
/// Small surfaces are integrated exactly, element by element. Surfaces with many elements
/// (≥ [`SurfaceClusters::min_elements`]) get a [`ClusterTree`] whose nodes stand in for their
/// elements where a Gaussian is too wide to tell them apart, so that the cost of an integral no
/// longer grows with the polygon count (`cluster.rs`).
#[derive(Clone, Debug)]
pub struct SceneSurface {
    /// Elements of S.
    pub elements: Vec<Element>,
    /// Unit normal of each element.
    pub normals: Vec<DVec3>,
    index: SurfaceIndex,
    /// Per element, its polygon's Gaussian-independent geometry ([`Prepared`]); empty on a
    /// clustered surface (its many elements would cost ~400 bytes each).
    prepared: Vec<Prepared>,
}

/// An element ready for many Gaussian integrals: a Gram matrix integrates each of a small
/// surface's elements against ~10⁶ Gaussian products, and a polygon's edge frames
/// ([`gauss_integrals::ConvexPolygon`]) are the same for all of them.
// A surface holds one kind (Flatland: segments; 3-D: polygons), so the small variant wastes
// nothing that boxing the large one (one indirection per integral) would save.
#[allow(clippy::large_enum_variant)]
#[derive(Clone, Copy, Debug)]
enum Prepared {
    Segment([DVec3; 2]),
    Polygon(gauss_integrals::ConvexPolygon),
    /// A degenerate polygon: its integral is 0.
    Empty,
}

impl Prepared {
    fn of(element: &Element) -> Self {
        let polygon = match *element {
            Element::Segment(s) => return Self::Segment(s),
            Element::Triangle([p, q, r]) => {
                gauss_integrals::ConvexPolygon::triangle(p.to_array(), q.to_array(), r.to_array())
            }
            Element::Quad(q) => gauss_integrals::ConvexPolygon::quad(q.map(|v| v.to_array())),
        };
        polygon.map_or(Self::Empty, Self::Polygon)
    }

    /// `∫ exp(−a|x − c|²) dx` over the element (erf for segments, the signed edge sum for polygons).
    #[inline]
    fn gaussian_integral(&self, c: DVec3, a: f64) -> f64 {
        match self {
            Self::Segment([p, q]) => integrals::segment(c, a, *p, *q),
            Self::Polygon(polygon) => polygon.gaussian_integral(c.to_array(), a),
            Self::Empty => 0.0,
        }
    }
}

/// How a [`SceneSurface`] finds the elements under a Gaussian: a hash grid for exact sums, or the
/// cluster tree of a large surface (which needs no grid).
#[derive(Clone, Debug)]
enum SurfaceIndex {
    Grid(BoxGrid),
    Tree(Box<ClusterTree>),
}

impl SceneSurface {
    /// The scene surface S of `domain` indexed for Gaussian integrals (cells of 5 % of the
    /// diagonal), exact.
    pub fn of(domain: &Domain) -> Self {
        Self::of_clustered(
            domain,
            SurfaceClusters {
                min_elements: usize::MAX,
                ..Default::default()
            },
        )
    }

    /// [`SceneSurface::of`], clustered when it has at least `clusters.min_elements` elements
    /// (`cluster.rs`).
    pub fn of_clustered(domain: &Domain, clusters: SurfaceClusters) -> Self {
        let (elements, normals) = domain.surface_elements().into_iter().unzip();
        Self::with_clusters(elements, normals, 0.05 * domain.diagonal(), clusters)
    }

    /// Indexes `elements` (with their unit `normals`) with buckets of about `cell` (typically
    /// a kernel width); every integral is exact.
    pub fn new(elements: Vec<Element>, normals: Vec<DVec3>, cell: f64) -> Self {
        Self::with_clusters(
            elements,
            normals,
            cell,
            SurfaceClusters {
                min_elements: usize::MAX,
                ..SurfaceClusters::default()
            },
        )
    }

    /// [`SceneSurface::new`], clustered when `clusters` says so.
    pub fn with_clusters(
        elements: Vec<Element>,
        normals: Vec<DVec3>,
        cell: f64,
        clusters: SurfaceClusters,
    ) -> Self {
        assert_eq!(elements.len(), normals.len(), "one normal per element");
        let clustered = elements.len() >= clusters.min_elements;
        let prepared = if clustered {
            Vec::new()
        } else {
            elements.iter().map(Prepared::of).collect()
        };
        let index = if clustered {
            SurfaceIndex::Tree(Box::new(ClusterTree::new(
                &elements,
                &normals,
                clusters.theta,
            )))
        } else {
            SurfaceIndex::Grid(BoxGrid::new(
                elements.iter().map(Element::bounds).collect(),
                cell,
            ))
        };
        Self {
            elements,
            normals,
            index,
            prepared,
        }
    }

    /// `∫ exp(−a|x − c|²) dx` over element `e`, from its prepared geometry when it has one.
    #[inline]
    fn element_integral(&self, e: u32, c: DVec3, a: f64) -> f64 {
        match self.prepared.get(e as usize) {
            Some(p) => p.gaussian_integral(c, a),
            None => self.elements[e as usize].gaussian_integral(c, a),
        }
    }

    /// The cluster tree, when the surface is large enough to have one.
    pub fn clusters(&self) -> Option<&ClusterTree> {
        match &self.index {
            SurfaceIndex::Tree(tree) => Some(tree),
            SurfaceIndex::Grid(_) => None,
        }
    }

    /// ∫_S exp(−a|x − c|²) dx over the elements within the support (relative cut-off `tol`).
    pub fn gaussian_integral(&self, c: DVec3, a: f64, tol: f64, scratch: &mut Vec<u32>) -> f64 {
        self.masked_gaussian_integral(c, a, tol, &[], 0.0, scratch)
    }

    /// Elements whose bounding boxes meet the ball (centre, radius), ascending. Empty on a
    /// clustered surface, whose integrals do not take candidate lists.
    pub fn elements_near(&self, centre: DVec3, radius: f64, out: &mut Vec<u32>) {
        match &self.index {
            SurfaceIndex::Grid(grid) => grid.query_ball(centre, radius, out),
            SurfaceIndex::Tree(_) => out.clear(),
        }
    }

    /// [`SceneSurface::gaussian_integral`] with the support query answered from `candidates`
    /// (ascending element ids, a superset of the elements within the support, e.g. from
    /// [`SceneSurface::elements_near`] with a larger ball): the same elements in the same
    /// order, hence the same sum, without a grid query. A clustered surface ignores the list.
    pub fn gaussian_integral_among(&self, c: DVec3, a: f64, tol: f64, candidates: &[u32]) -> f64 {
        self.masked_gaussian_integral_among(c, a, tol, &Mask::ALL, candidates)
    }

    /// [`SceneSurface::gaussian_integral_among`] over the elements that `mask` accepts.
    pub fn masked_gaussian_integral_among(
        &self,
        c: DVec3,
        a: f64,
        tol: f64,
        mask: &Mask,
        candidates: &[u32],
    ) -> f64 {
        let r = support_radius(a, tol);
        let grid = match &self.index {
            SurfaceIndex::Tree(tree) => {
                return tree.integral(c, a, r, mask, &mut |e| {
                    if mask.accepts(self.normals[e as usize]) {
                        self.element_integral(e, c, a)
                    } else {
                        0.0
                    }
                });
            }
            SurfaceIndex::Grid(grid) => grid,
        };
        candidates
            .iter()
            .filter(|&&e| grid.box_hits(e, c, r) && mask.accepts(self.normals[e as usize]))
            .map(|&e| self.element_integral(e, c, a))
            .sum()
    }

    /// ∫ exp(−a|x − c|²) dx over the elements of S that face like every normal in `facing`
    /// (element normal · n > `cos_min`; a zero n accepts every element).
    pub fn masked_gaussian_integral(
        &self,
        c: DVec3,
        a: f64,
        tol: f64,
        facing: &[DVec3],
        cos_min: f64,
        scratch: &mut Vec<u32>,
    ) -> f64 {
        let r = support_radius(a, tol);
        let mask = Mask { facing, cos_min };
        let grid = match &self.index {
            SurfaceIndex::Tree(tree) => {
                return tree.integral(c, a, r, &mask, &mut |e| {
                    if mask.accepts(self.normals[e as usize]) {
                        self.element_integral(e, c, a)
                    } else {
                        0.0
                    }
                });
            }
            SurfaceIndex::Grid(grid) => grid,
        };
        grid.query_ball(c, r, scratch);
        scratch
            .iter()
            .filter(|&&e| mask.accepts(self.normals[e as usize]))
            .map(|&e| self.element_integral(e, c, a))
            .sum()
    }
}

/// Settings of one FEM step.
#[derive(Clone, Copy, Debug)]
pub struct FemSettings {
    /// 2 for surfaces in 3-D, 1 for Flatland segments.
    pub surface_dim: u32,
    /// Closed form only where FSR < this (radians; sec. 4.4.1: 0.4).
    pub roughness_threshold: f64,
    /// Closed form only where DF ≥ this (sec. 4.4.1: 1).
    pub depth_threshold: u32,
    /// Relative cut-off of Gaussian supports.
    pub support_tolerance: f64,
    /// Components whose Cholesky pivot falls below this fraction of the diagonal are rejected
    /// as nearly dependent (sec. 3.8.1).
    pub rejection: f64,
    /// Sender integral variant.
    pub transfer: Transfer,
    /// Use the flat closed forms at all (off: always the exact element sums).
    pub closed_forms: bool,
    /// Where the base is integrated.
    pub base_domain: BaseDomain,
    /// With [`BaseDomain::Scene`]: Λ_k lives on the elements whose normal · n_k exceeds this.
    pub facing_cos: f64,
}

impl Default for FemSettings {
    fn default() -> Self {
        Self {
            surface_dim: 2,
            roughness_threshold: 0.4,
            depth_threshold: 1,
            support_tolerance: 1e-9,
            rejection: 1e-6,
            transfer: Transfer::Direct,
            closed_forms: true,
            base_domain: BaseDomain::Scene,
            facing_cos: 50f64.to_radians().cos(),
        }
    }
}

/// The Gaussian base on the shading network (eq. 3.20) with everything a FEM step needs to
/// integrate it: inverse squared widths, the closed-form decision per cell, and spatial indices
/// over its centres and its simplices.
#[derive(Clone, Debug)]
pub struct Base {
    /// The frozen shading network.
    pub geo: ShadingGeometry,
    /// a_k = 1/d̂_k².
    pub a: Vec<f64>,
    /// Whether cell k may be integrated in closed form over its tangent plane (fig. 3.6).
    pub flat: Vec<bool>,
    /// The shading simplices as integration elements (Ŝ).
    pub elements: Vec<Element>,
    element_grid: BoxGrid,
    centre_grid: BoxGrid,
    max_reach: f64,
    settings: FemSettings,
    surface: Arc<SceneSurface>,
}

impl Base {
    /// Prepares the base of `geo` under `settings`; `surface` is the scene S (used with
    /// [`BaseDomain::Scene`]).
    pub fn new(geo: ShadingGeometry, settings: FemSettings, surface: Arc<SceneSurface>) -> Self {
        let a: Vec<f64> = geo.widths.iter().map(|d| 1.0 / (d * d)).collect();
        let flat = (0..geo.len())
            .into_par_iter()
            .map_init(Vec::new, |scratch, k| {
                if !settings.closed_forms || geo.normals[k] == DVec3::ZERO {
                    return false;
                }
                match settings.base_domain {
                    // The criterion of sec. 3.9.4 on the shading network's own geometry.
                    BaseDomain::Shading => {
                        geo.fuzzy_roughness[k] < settings.roughness_threshold
                            && geo.depth[k] >= settings.depth_threshold
                    }
                    // On S the question "does Λ_k see a whole plane?" has an exact answer: its
                    // norm over its faces equals the plane value. Only then is the closed form
                    // consistent with the exact integrals of its neighbours.
                    BaseDomain::Scene => {
                        let a2 = 2.0 * a[k];
                        let exact = surface.masked_gaussian_integral(
                            geo.centres[k],
                            a2,
                            settings.support_tolerance,
                            &[geo.normals[k]],
                            settings.facing_cos,
                            scratch,
                        );
                        let plane = integrals::flat(a2, 0.0, settings.surface_dim);
                        (exact - plane).abs() <= FLAT_AGREEMENT * plane
                    }
                }
            })
            .collect();
        let elements: Vec<Element> = (0..geo.simplices.len())
            .map(|t| {
                let s = geo.simplex(t);
                if geo.k == 1 {
                    Element::Segment([geo.centres[s[0]], geo.centres[s[1]]])
                } else {
                    Element::Triangle([geo.centres[s[0]], geo.centres[s[1]], geo.centres[s[2]]])
                }
            })
            .collect();
        let mean_width = geo.widths.iter().sum::<f64>() / geo.len().max(1) as f64;
        let cell = support_radius(width_a(mean_width.max(1e-300)), settings.support_tolerance);
        let element_grid = BoxGrid::new(elements.iter().map(Element::bounds).collect(), cell);
        let centre_grid = BoxGrid::new(geo.centres.iter().map(|c| (*c, *c)).collect(), cell);
        let max_reach = geo
            .widths
            .iter()
            .map(|d| support_radius(width_a(*d), settings.support_tolerance))
            .fold(0.0, f64::max);
        Self {
            geo,
            a,
            flat,
            elements,
            element_grid,
            centre_grid,
            max_reach,
            settings,
            surface,
        }
    }

    /// Number of base Gaussians.
    pub fn len(&self) -> usize {
        self.geo.len()
    }

    /// True when the base is empty.
    pub fn is_empty(&self) -> bool {
        self.geo.is_empty()
    }

    /// ∫ Λ_k(x) · exp(−b|x − w|²) dx over k's domain: the product rule (docs/design/math.md §2) turns the
    /// integrand into one Gaussian, integrated over k's tangent plane when k is flat, else
    /// exactly over Ŝ or over the part of S that faces like k ([`BaseDomain`]).
    pub fn product_integral(&self, k: usize, w: DVec3, b: f64, scratch: &mut Vec<u32>) -> f64 {
        self.product_integral_on(k, None, DVec3::ZERO, w, b, scratch)
    }

    /// [`Base::product_integral`] restricted further to the surfaces facing like `facing` (the
    /// facing mask of a kernel half, [`KernelCells::facing_x`]; zero: no restriction). Where k is
    /// integrated over one orientation only (its tangent plane, or Ŝ), k is taken or not as a
    /// whole.
    pub fn product_integral_facing(
        &self,
        k: usize,
        w: DVec3,
        b: f64,
        facing: DVec3,
        scratch: &mut Vec<u32>,
    ) -> f64 {
        self.product_integral_on(k, None, facing, w, b, scratch)
    }

    /// [`Base::product_integral`] on the common domain of cells k and `other` (the Gram entry
    /// ⟨Λ_k|Λ_other⟩ when w, b are other's centre and inverse squared width).
    fn product_integral_on(
        &self,
        k: usize,
        other: Option<usize>,
        facing: DVec3,
        w: DVec3,
        b: f64,
        scratch: &mut Vec<u32>,
    ) -> f64 {
        let nk = self.geo.normals[k];
        let cos = self.settings.facing_cos;
        let whole = self.settings.base_domain == BaseDomain::Shading || self.flat[k];
        if whole && !(facing == DVec3::ZERO || nk == DVec3::ZERO || nk.dot(facing) > cos) {
            return 0.0;
        }
        let (a, p) = (self.a[k], self.geo.centres[k]);
        let ab = a + b;
        let scale = (-(a * b / ab) * p.distance_squared(w)).exp();
        if scale == 0.0 {
            return 0.0;
        }
        let c = (a * p + b * w) / ab;
        if self.flat[k] && other.is_none_or(|q| self.flat[q]) {
            let h = (c - p).dot(self.geo.normals[k]);
            return scale * integrals::flat(ab, h, self.settings.surface_dim);
        }
        let tol = self.settings.support_tolerance;
        match self.settings.base_domain {
            BaseDomain::Scene => {
                let nq = other.map_or(DVec3::ZERO, |q| self.geo.normals[q]);
                scale
                    * self.surface.masked_gaussian_integral(
                        c,
                        ab,
                        tol,
                        &[nk, nq, facing],
                        cos,
                        scratch,
                    )
            }
            BaseDomain::Shading => {
                let r = support_radius(ab, tol);
                self.element_grid.query_ball(c, r, scratch);
                scale
                    * scratch
                        .iter()
                        .map(|&e| self.elements[e as usize].gaussian_integral(c, ab))
                        .sum::<f64>()
            }
        }
    }

    /// Base cells whose Gaussian can reach the ball (centre, radius).
    pub fn cells_near(&self, centre: DVec3, radius: f64, out: &mut Vec<u32>) {
        self.centre_grid
            .query_ball(centre, radius + self.max_reach, out);
    }

    /// The Gram matrix G_pq = ⟨Λ_p|Λ_q⟩ over Ŝ (eq. 3.31) as a dense symmetric matrix, with the
    /// zero rules of fig. 3.6 (separate sub-networks, opposed normals).
    pub fn gram(&self) -> nalgebra::DMatrix<f64> {
        let n = self.len();
        let rows: Vec<Vec<(usize, f64)>> = (0..n)
            .into_par_iter()
            .map_init(
                || (Vec::new(), Vec::new()),
                |(near, scratch), p| {
                    let reach = support_radius(
                        width_a(self.geo.widths[p]),
                        self.settings.support_tolerance,
                    );
                    self.cells_near(self.geo.centres[p], reach, near);
                    near.iter()
                        .map(|&q| q as usize)
                        .filter(|&q| q >= p && self.may_overlap(p, q))
                        .map(|q| {
                            (
                                q,
                                self.product_integral_on(
                                    p,
                                    Some(q),
                                    DVec3::ZERO,
                                    self.geo.centres[q],
                                    self.a[q],
                                    scratch,
                                ),
                            )
                        })
                        .filter(|(_, g)| *g != 0.0)
                        .collect()
                },
            )
            .collect();
        let mut g = nalgebra::DMatrix::zeros(n, n);
        for (p, row) in rows.into_iter().enumerate() {
            for (q, v) in row {
                g[(p, q)] = v;
                g[(q, p)] = v;
            }
        }
        g
    }

    fn may_overlap(&self, p: usize, q: usize) -> bool {
        let facing = self.geo.normals[p].dot(self.geo.normals[q]) > 0.0;
        p == q
            || match self.settings.base_domain {
                // Two cells whose normals differ by up to twice the facing angle (100° by
                // default, so even opposed-ish blends at corners) can share a face: only the
                // masked integral knows. Zeroing such entries made G inconsistent with u.
                BaseDomain::Scene => true,
                BaseDomain::Shading => self.geo.component[p] == self.geo.component[q] && facing,
            }
    }

    /// Whether Λ_k is defined at a surface point with unit normal `normal`.
    fn lives_on(&self, k: usize, normal: DVec3) -> bool {
        let nk = self.geo.normals[k];
        self.settings.base_domain == BaseDomain::Shading
            || nk == DVec3::ZERO
            || normal == DVec3::ZERO
            || nk.dot(normal) > self.settings.facing_cos
    }

    /// Evaluates Σ_k coeff_k Λ_k(x) with the support cut-off at a surface point x with unit
    /// normal `normal` (with [`BaseDomain::Scene`] only the Gaussians that live on surfaces
    /// facing like `normal` contribute).
    pub fn evaluate(
        &self,
        coeff: &[Bands],
        x: DVec3,
        normal: DVec3,
        scratch: &mut Vec<u32>,
    ) -> Bands {
        self.cells_near(x, 0.0, scratch);
        let mut out = [0.0; BANDS];
        for &k in scratch.iter() {
            let k = k as usize;
            if !self.lives_on(k, normal) {
                continue;
            }
            let g = (-self.a[k] * self.geo.centres[k].distance_squared(x)).exp();
            for band in 0..BANDS {
                out[band] += coeff[k][band] * g;
            }
        }
        out
    }
}

/// The result of one FEM step.
#[derive(Clone, Debug)]
pub struct FemSolution {
    /// The base the step ran on.
    pub base: Base,
    /// Coefficients γ of the reflected radiosity in the (non-orthogonal) Gaussians:
    /// B_refl(x) ≈ Σ_k γ_k Λ_k(x).
    pub gamma: Vec<Bands>,
    /// Base components rejected as nearly dependent.
    pub rejected: usize,
}

impl FemSolution {
    /// B_refl(x) from the base (fig. 4.13a/b) at a surface point with unit normal `normal`.
    pub fn reflected_from_base(&self, x: DVec3, normal: DVec3, scratch: &mut Vec<u32>) -> Bands {
        self.base.evaluate(&self.gamma, x, normal, scratch)
    }
}

/// Sender integrals c_o = ∫_S exp(−|x − w_o^x|²/d_o²) dx for every kernel cell, exact on the
/// scene's elements (docs/design/math.md §3).
pub fn sender_integrals(kernel: &KernelCells, scene: &SceneSurface, tol: f64) -> Vec<f64> {
    half_integrals(kernel, scene, tol, |o| (kernel.wx[o], kernel.facing_x(o)))
}

/// Receiver integrals ∫_S exp(−|y − w_o^y|²/d_o²) dy for every kernel cell: with the sender
/// integrals they give the reflected power of the kernel collection,
/// ∫_S B_refl = Σ_o v_o c_o ∫_S g_o^y.
pub fn receiver_integrals(kernel: &KernelCells, scene: &SceneSurface, tol: f64) -> Vec<f64> {
    half_integrals(kernel, scene, tol, |o| (kernel.wy[o], kernel.facing_y(o)))
}

/// ∫_S exp(−|x − w|²/d_o²) dx over the surfaces facing like the half, for the half
/// `half(o)` = (centre w, facing direction) of every kernel cell o.
fn half_integrals(
    kernel: &KernelCells,
    scene: &SceneSurface,
    tol: f64,
    half: impl Fn(usize) -> (DVec3, DVec3) + Sync,
) -> Vec<f64> {
    (0..kernel.len())
        .into_par_iter()
        .map_init(Vec::new, |scratch, o| {
            let (centre, facing) = half(o);
            let a = 1.0 / (kernel.width[o] * kernel.width[o]);
            scene.masked_gaussian_integral(centre, a, tol, &[facing], kernel.facing_cos, scratch)
        })
        .collect()
}

/// B_refl(y) = Σ_o v_o c_o exp(−|y − w_o^y|²/d_o²): the final collection through the kernel
/// network (fig. 4.13c), with `sender` from [`sender_integrals`], at a surface point y with unit
/// normal `n` (only cells whose receiver half faces like `n` contribute; a zero `n` takes all).
/// For many points, prepare the cells once: `cell_lanes::Collection` (which this calls).
#[cfg_attr(not(feature = "stages"), allow(dead_code))] // read through `gcr::stages`
pub fn reflected_from_kernel(kernel: &KernelCells, sender: &[f64], y: DVec3, n: DVec3) -> Bands {
    crate::cell_lanes::Collection::new(kernel, sender).at(y, n)
}

/// With [`BaseDomain::Scene`], a cell is integrated in closed form when its exact norm over its
/// faces agrees with the whole-plane value to this relative tolerance.
const FLAT_AGREEMENT: f64 = 1e-9;

/// Smallest ‖Λ_k‖² on its domain, as a fraction of its whole-plane value, for a base Gaussian
/// to be kept.
const MIN_MASS_FRACTION: f64 = 0.01;

/// One FEM step (sec. 3.3–3.9) of `base` against the frozen `kernel` with its sender integrals
/// c_o in `sender` ([`sender_integrals`], computed once by the caller): the Gram matrix and its
/// orthonormalization, the receiver projections u, and the coefficients γ of the reflected
/// radiosity in the base. Under [`Transfer::Projected`] `sender` is first replaced by the
/// dissertation's c̄_o (eq. 3.9–3.12), so that it holds the integrals the step used.
pub fn fem_step(base: Base, kernel: &KernelCells, sender: &mut Vec<f64>) -> FemSolution {
    // ⟨Gram matrix and orthonormalization (eq. 3.31, 3.38; docs/design/math.md §5)⟩
    let ortho = orthonormalize(&base);
    // ⟨The dissertation's sender integrals c̄_o, when selected⟩
    if base.settings.transfer == Transfer::Projected {
        *sender = projected_sender(&base, &ortho, kernel);
    }
    // ⟨Receiver projections u_q = ⟨Λ_q|B_refl⟩ and the coefficients γ = G⁻¹u⟩
    let u = receiver_projections(&base, kernel, sender);
    let mut gamma = vec![[0.0; BANDS]; base.len()];
    for band in 0..BANDS {
        let ub: Vec<f64> = u.iter().map(|x| x[band]).collect();
        for (g, v) in gamma.iter_mut().zip(ortho.solve(&ub)) {
            g[band] = v;
        }
    }
    FemSolution {
        rejected: ortho.rejected(),
        base,
        gamma,
    }
}

/// The base's Gram matrix, orthonormalized with the rejection of nearly dependent components.
/// A Gaussian with almost none of its mass on its domain (a shading cell far from Ŝ, say) has a
/// tiny diagonal that the relative pivot test cannot see; its coefficient would be huge and it
/// is evaluated where it has no support. It is dropped first: ‖Λ_k‖² below
/// [`MIN_MASS_FRACTION`] of the plane value.
fn orthonormalize(base: &Base) -> integrals::Orthonormal {
    let settings = base.settings;
    let mut gram = base.gram();
    for k in 0..base.len() {
        let plane = integrals::flat(2.0 * base.a[k], 0.0, settings.surface_dim);
        if gram[(k, k)] < MIN_MASS_FRACTION * plane {
            gram.row_mut(k).fill(0.0);
            gram.column_mut(k).fill(0.0);
        }
    }
    integrals::Orthonormal::new(&gram, settings.rejection)
}

/// c̄_o = ∫ B̄ exp(−|x − w_o^x|²/d_o²): B̄ is the constant 1 projected onto the base,
/// γ̄ = G⁻¹ ū with ū_k = ∫_Ŝ Λ_k (eq. 3.9–3.12; it adds the "surface base error" of fig. 3.4).
fn projected_sender(base: &Base, ortho: &integrals::Orthonormal, kernel: &KernelCells) -> Vec<f64> {
    let tol = base.settings.support_tolerance;
    let ones: Vec<f64> = (0..base.len())
        .into_par_iter()
        .map_init(Vec::new, |scratch, k| {
            base.product_integral(k, base.geo.centres[k], 0.0, scratch)
        })
        .collect();
    let gamma_bar = ortho.solve(&ones);
    (0..kernel.len())
        .into_par_iter()
        .map_init(
            || (Vec::new(), Vec::new()),
            |(near, scratch), o| {
                let b = 1.0 / (kernel.width[o] * kernel.width[o]);
                base.cells_near(
                    kernel.wx[o],
                    support_radius(width_a(kernel.width[o]), tol),
                    near,
                );
                near.iter()
                    .map(|&k| {
                        gamma_bar[k as usize]
                            * base.product_integral_facing(
                                k as usize,
                                kernel.wx[o],
                                b,
                                kernel.facing_x(o),
                                scratch,
                            )
                    })
                    .sum()
            },
        )
        .collect()
}

/// u_q = Σ_o v_o · sender_o · β_qo, accumulated over fixed chunks of kernel cells and summed in
/// chunk order, so that the result does not depend on the number of threads.
///
/// No zero rule of fig. 3.6 (sender behind the receiver) here: the kernel collection
/// B_refl(y) = Σ_o v_o c_o g_o(y) sums every cell, and projected weights cancel each other, so
/// dropping cells made u inconsistent with G (on wall-floor the base then missed B_refl by 135 %,
/// and by 7 % without it).
fn receiver_projections(base: &Base, kernel: &KernelCells, sender: &[f64]) -> Vec<Bands> {
    const CHUNK: usize = 128;
    let (n, tol) = (base.len(), base.settings.support_tolerance);
    let partial: Vec<Vec<Bands>> = (0..kernel.len().div_ceil(CHUNK))
        .into_par_iter()
        .map(|chunk| {
            let mut acc = vec![[0.0; BANDS]; n];
            let (mut near, mut scratch) = (Vec::new(), Vec::new());
            for o in chunk * CHUNK..((chunk + 1) * CHUNK).min(kernel.len()) {
                if sender[o] == 0.0 {
                    continue;
                }
                let b = 1.0 / (kernel.width[o] * kernel.width[o]);
                base.cells_near(
                    kernel.wy[o],
                    support_radius(width_a(kernel.width[o]), tol),
                    &mut near,
                );
                for &q in &near {
                    let q = q as usize;
                    let beta = base.product_integral_facing(
                        q,
                        kernel.wy[o],
                        b,
                        kernel.facing_y(o),
                        &mut scratch,
                    );
                    for band in 0..BANDS {
                        acc[q][band] += kernel.v[o][band] * sender[o] * beta;
                    }
                }
            }
            acc
        })
        .collect();
    let mut u = vec![[0.0; BANDS]; n];
    for acc in partial {
        for (x, y) in u.iter_mut().zip(acc) {
            for band in 0..BANDS {
                x[band] += y[band];
            }
        }
    }
    u
}

/// Thin adapter from glam vectors to [`gauss_integrals`].
mod integrals {
    use glam::DVec3;

    pub use gauss_integrals::Orthonormal;

    /// ∫ over segment p–q of exp(−a|x − c|²).
    pub fn segment(c: DVec3, a: f64, p: DVec3, q: DVec3) -> f64 {
        gauss_integrals::segment(c.to_array(), a, p.to_array(), q.to_array())
    }

    /// ∫ over a whole flat domain (plane if `surface_dim` = 2, line if 1) at distance `h`.
    pub fn flat(a: f64, h: f64, surface_dim: u32) -> f64 {
        if surface_dim == 1 {
            gauss_integrals::line(a, h)
        } else {
            gauss_integrals::plane(a, h)
        }
    }
}

#[cfg(test)]
#[cfg(test)]
mod tests {
    use super::*;
    use crate::config::Breaking;

    /// A flat n×n shading grid with spacing h on z = 0, normals +z.
    fn grid_base(n: usize, h: f64, settings: FemSettings) -> Base {
        let mut centres = Vec::new();
        for j in 0..n {
            for i in 0..n {
                centres.push(DVec3::new(i as f64 * h, j as f64 * h, 0.0));
            }
        }
        let mut tris = Vec::new();
        for j in 0..n - 1 {
            for i in 0..n - 1 {
                let a = j * n + i;
                tris.push([a, a + 1, a + n + 1]);
                tris.push([a, a + n + 1, a + n]);
            }
        }
        let geo = ShadingGeometry::new(
            centres,
            vec![h; n * n],
            vec![DVec3::Z; n * n],
            2,
            &tris,
            Breaking::default(),
            |_, _, _| false,
        );
        // The scene: the grid's plane (a big triangle under it).
        let floor = Element::Triangle([
            DVec3::new(-100.0, -100.0, 0.0),
            DVec3::new(100.0, -100.0, 0.0),
            DVec3::new(0.0, 150.0, 0.0),
        ]);
        Base::new(
            geo,
            settings,
            Arc::new(SceneSurface::new(vec![floor], vec![DVec3::Z], 2.0)),
        )
    }

    #[test]
    fn gram_is_symmetric_and_flat_entries_match_exact_element_sums_in_the_interior() {
        let flat = grid_base(12, 1.0, FemSettings::default());
        let exact = grid_base(
            12,
            1.0,
            FemSettings {
                closed_forms: false,
                ..Default::default()
            },
        );
        let (gf, ge) = (flat.gram(), exact.gram());
        assert!((&gf - gf.transpose()).amax() == 0.0);
        // Deep interior cells: the plane closed form (eq. 3.52, corrected norm π d²/2) equals the
        // exact triangle sum up to the Gaussian tail beyond the grid.
        let i = 6 * 12 + 6;
        assert!((gf[(i, i)] - std::f64::consts::PI / 2.0).abs() < 1e-9);
        assert!(
            (ge[(i, i)] - gf[(i, i)]).abs() < 1e-6,
            "{} vs {}",
            ge[(i, i)],
            gf[(i, i)]
        );
        assert!((ge[(i, i + 1)] - gf[(i, i + 1)]).abs() < 1e-6);
    }

    #[test]
    fn base_projection_reproduces_the_kernel_collection_on_a_flat_receiver() {
        // A light-like sender patch above a 16×16 receiver grid, one broad kernel cell.
        let base = grid_base(16, 0.5, FemSettings::default());
        let kernel = KernelCells {
            wx: vec![DVec3::new(3.75, 3.75, 4.0)],
            wy: vec![DVec3::new(3.75, 3.75, 0.0)],
            width: vec![1.5],
            v: vec![[1.0, 0.5, 0.25]],
            ..KernelCells::default()
        };
        let sender_plane = Element::Triangle([
            DVec3::new(-50.0, -50.0, 4.0),
            DVec3::new(50.0, -50.0, 4.0),
            DVec3::new(0.0, 80.0, 4.0),
        ]);
        let scene = SceneSurface::new(vec![sender_plane], vec![DVec3::NEG_Z], 2.0);
        let mut sender =
            sender_integrals(&kernel, &scene, FemSettings::default().support_tolerance);
        let sol = fem_step(base, &kernel, &mut sender);
        assert!(
            sol.rejected < 256 / 8,
            "wide Gaussians are nearly dependent; few are dropped: {}",
            sol.rejected
        );
        // c_o for a centre on the sender plane is the whole-plane value π d².
        assert!((sender[0] - std::f64::consts::PI * 2.25).abs() < 1e-9);
        let mut scratch = Vec::new();
        for p in [
            DVec3::new(3.75, 3.75, 0.0),
            DVec3::new(3.0, 4.5, 0.0),
            DVec3::new(5.0, 3.0, 0.0),
        ] {
            let from_base = sol.reflected_from_base(p, DVec3::Z, &mut scratch);
            let direct = reflected_from_kernel(&kernel, &sender, p, DVec3::Z);
            for b in 0..3 {
                assert!(
                    (from_base[b] - direct[b]).abs() < 0.02 * direct[0],
                    "{p}: {from_base:?} vs {direct:?}"
                );
            }
        }
    }
}

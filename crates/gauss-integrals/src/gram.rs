//! Gram matrices of Gaussian bases on a triangulated (3-D) or segmented (2-D) domain
//! (sec. 3.6.1, 3.9.2 and fig. 3.6; docs/design/math.md §2 and §5).
//!
//! An entry `G_ij = ⟨A_i|A_j⟩ = ∫_S A_i A_j dx` is, per pair,
//! - **0** by the zero rules of fig. 3.6: the two Gaussians lie on different sub-networks, or
//!   their normals are opposed (`n_i·n_j < 0`);
//! - the **flat closed form** of eq. 3.52 with docs/design/math.md's corrected norm,
//!   `π d_i²d_j²/(d_i²+d_j²)·exp(−|w_i−w_j|²/(d_i²+d_j²))` in 3-D (its square root form
//!   `√(π d_i²d_j²/(d_i²+d_j²))·exp(…)` in 2-D), when the caller's criterion accepts both
//!   Gaussians as lying on a unique flat domain ([`Gaussian::flat`], e.g. from
//!   [`crate::criteria::decide`]);
//! - otherwise the **exact element sum**: the product of the two Gaussians is one Gaussian
//!   (product rule, docs/design/math.md §2) integrated in closed form over every element under its support.
//!
//! The matrix is sparse: a pair whose product is below `tol` everywhere
//! (`a_i a_j/(a_i+a_j)·|w_i−w_j|² > ln(1/tol)`) is 0, and an element farther than the product's
//! support radius `√(ln(1/tol)/(a_i+a_j))` from its centre is skipped. Pairs are found by a sweep
//! over the centres sorted along their longest axis, elements by a uniform grid; rows are computed
//! in parallel with rayon.
//!
//! ```
//! use gauss_integrals::gram::{Domain, Gaussian, GramConfig, gram};
//! use gauss_integrals::Orthonormal;
//! // A flat 20×20 square of two triangles; two Gaussians of width 0.5 near its middle.
//! let v = vec![[0.0, 0.0, 0.0], [20.0, 0.0, 0.0], [20.0, 20.0, 0.0], [0.0, 20.0, 0.0]];
//! let dom = Domain::triangles(v, &[[0, 1, 2], [0, 2, 3]]).unwrap();
//! let g = [Gaussian::new([10.0, 10.0, 0.0], 0.5), Gaussian::new([10.4, 10.0, 0.0], 0.5)];
//! let m = gram(&dom, &g, &GramConfig::default()).unwrap().matrix;
//! // ⟨A|A⟩ = π d²/2 (docs/design/math.md §2's correction of eq. 3.53).
//! assert!((m.get(0, 0) - std::f64::consts::PI * 0.25 / 2.0).abs() < 1e-13);
//! let o = Orthonormal::new(&m.to_dense(), 1e-12);
//! assert_eq!(o.rejected(), 0);
//! ```

use crate::closed_form::{ConvexPolygon, product, segment, triangle};
use crate::criteria::Integration;
use nalgebra::DMatrix;
use rayon::prelude::*;
use std::collections::HashMap;
use std::f64::consts::PI;

type V = [f64; 3];

fn sub(a: V, b: V) -> V {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
fn dot(a: V, b: V) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
fn dist2(a: V, b: V) -> f64 {
    let d = sub(a, b);
    dot(d, d)
}
fn finite(v: V) -> bool {
    v.iter().all(|x| x.is_finite())
}

/// Bad input to the Gram-matrix builders.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum GramError {
    /// An element refers to a vertex that does not exist.
    #[error("element {element} refers to vertex {vertex}, but there are only {count} vertices")]
    BadIndex {
        /// The element.
        element: usize,
        /// The offending vertex index.
        vertex: u32,
        /// Number of vertices.
        count: usize,
    },
    /// A vertex coordinate is NaN or infinite.
    #[error("vertex {0} is not finite")]
    NonFiniteVertex(usize),
    /// A Gaussian's centre or normal is not finite, or its width not finite and positive.
    #[error(
        "Gaussian {0} has a non-finite centre or normal, or a width that is not finite and > 0"
    )]
    BadGaussian(usize),
    /// The support cut-off is not in (0, 1).
    #[error("support cut-off {0} is not in (0, 1)")]
    BadTolerance(f64),
    /// A vector's length does not match the matrix.
    #[error("length {got} does not match the expected {expected}")]
    Length {
        /// Expected length.
        expected: usize,
        /// Given length.
        got: usize,
    },
}

/// Space dimension of a [`Domain`]; selects the flat closed form (plane in 3-D, line in 2-D).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Dim {
    /// Flatland: segments in the plane (z = 0).
    Two,
    /// Triangles in space.
    Three,
}

/// A triangulated (3-D) or segmented (2-D) integration domain with a uniform grid over its
/// elements for neighbour queries.
#[derive(Clone, Debug)]
pub struct Domain {
    dim: Dim,
    vertices: Vec<V>,
    /// Vertex ids; segments repeat their second vertex.
    elements: Vec<[u32; 3]>,
    /// Bounding-sphere centre and radius per element.
    spheres: Vec<(V, f64)>,
    /// Per triangle (3-D), its Gaussian-independent geometry (`None`: degenerate, integral 0).
    tris: Vec<Option<ConvexPolygon>>,
    cell: f64,
    buckets: HashMap<[i64; 3], Vec<u32>>,
}

impl Domain {
    /// A triangulated surface in space.
    pub fn triangles(vertices: Vec<V>, triangles: &[[u32; 3]]) -> Result<Self, GramError> {
        Self::build(Dim::Three, vertices, triangles.to_vec())
    }

    /// A height field: the grid of `nx × ny` squares of edge `h` over `[0, nx·h] × [0, ny·h]`, two
    /// triangles each, lifted to `z = height(x, y)` at the vertices (a test and benchmark surface).
    pub fn height_field(
        nx: usize,
        ny: usize,
        h: f64,
        height: impl Fn(f64, f64) -> f64,
    ) -> Result<Self, GramError> {
        let mut v = Vec::with_capacity((nx + 1) * (ny + 1));
        for y in 0..=ny {
            for x in 0..=nx {
                let (px, py) = (x as f64 * h, y as f64 * h);
                v.push([px, py, height(px, py)]);
            }
        }
        let id = |x: usize, y: usize| (y * (nx + 1) + x) as u32;
        let mut t = Vec::with_capacity(2 * nx * ny);
        for y in 0..ny {
            for x in 0..nx {
                t.push([id(x, y), id(x + 1, y), id(x + 1, y + 1)]);
                t.push([id(x, y), id(x + 1, y + 1), id(x, y + 1)]);
            }
        }
        Self::triangles(v, &t)
    }

    /// A segmented curve in the plane (Flatland).
    pub fn segments(vertices: &[[f64; 2]], segments: &[[u32; 2]]) -> Result<Self, GramError> {
        let v = vertices.iter().map(|p| [p[0], p[1], 0.0]).collect();
        let e = segments.iter().map(|s| [s[0], s[1], s[1]]).collect();
        Self::build(Dim::Two, v, e)
    }

    fn build(dim: Dim, vertices: Vec<V>, elements: Vec<[u32; 3]>) -> Result<Self, GramError> {
        if let Some(i) = vertices.iter().position(|v| !finite(*v)) {
            return Err(GramError::NonFiniteVertex(i));
        }
        for (k, e) in elements.iter().enumerate() {
            if let Some(&v) = e.iter().find(|&&v| v as usize >= vertices.len()) {
                return Err(GramError::BadIndex {
                    element: k,
                    vertex: v,
                    count: vertices.len(),
                });
            }
        }
        let spheres: Vec<(V, f64)> = elements
            .iter()
            .map(|e| {
                let p = e.map(|v| vertices[v as usize]);
                let c = [0, 1, 2].map(|k| (p[0][k] + p[1][k] + p[2][k]) / 3.0);
                let r = p.iter().map(|q| dist2(*q, c)).fold(0.0, f64::max).sqrt();
                (c, r)
            })
            .collect();
        // Bucket edge: the mean element diameter (at least a tiny positive length).
        let mean_d = spheres.iter().map(|s| 2.0 * s.1).sum::<f64>() / spheres.len().max(1) as f64;
        let cell = if mean_d > 0.0 && mean_d.is_finite() {
            mean_d
        } else {
            1.0
        };
        let mut buckets: HashMap<[i64; 3], Vec<u32>> = HashMap::new();
        for (k, (c, r)) in spheres.iter().enumerate() {
            let lo = key(sub(*c, [*r; 3]), cell);
            let hi = key([c[0] + r, c[1] + r, c[2] + r], cell);
            let count = (0..3)
                .map(|i| hi[i] as f64 - lo[i] as f64 + 1.0)
                .product::<f64>();
            if count > 64.0 {
                // A huge element against the mean: keep it in a catch-all bucket.
                buckets.entry([i64::MIN; 3]).or_default().push(k as u32);
                continue;
            }
            for x in lo[0]..=hi[0] {
                for y in lo[1]..=hi[1] {
                    for z in lo[2]..=hi[2] {
                        buckets.entry([x, y, z]).or_default().push(k as u32);
                    }
                }
            }
        }
        let tris = match dim {
            Dim::Three => elements
                .iter()
                .map(|e| {
                    let [p, q, r] = e.map(|v| vertices[v as usize]);
                    ConvexPolygon::triangle(p, q, r)
                })
                .collect(),
            Dim::Two => Vec::new(),
        };
        Ok(Self {
            dim,
            vertices,
            elements,
            spheres,
            tris,
            cell,
            buckets,
        })
    }

    /// The space dimension.
    pub fn dim(&self) -> Dim {
        self.dim
    }

    /// Number of elements.
    pub fn len(&self) -> usize {
        self.elements.len()
    }

    /// Whether there are no elements.
    pub fn is_empty(&self) -> bool {
        self.elements.is_empty()
    }

    /// The vertices of element `k` (segments: the second vertex repeated).
    pub fn element(&self, k: usize) -> [V; 3] {
        self.elements[k].map(|v| self.vertices[v as usize])
    }

    /// Ids (ascending) of the elements whose bounding sphere meets the ball (c, r).
    pub fn elements_near(&self, c: V, r: f64, out: &mut Vec<u32>) {
        out.clear();
        if r.is_nan() || r < 0.0 || !finite(c) {
            return;
        }
        let near = |k: u32| {
            let (ec, er) = self.spheres[k as usize];
            dist2(c, ec).sqrt() <= r + er
        };
        let lo = key(sub(c, [r; 3]), self.cell);
        let hi = key([c[0] + r, c[1] + r, c[2] + r], self.cell);
        let count = (0..3)
            .map(|i| hi[i] as f64 - lo[i] as f64 + 1.0)
            .product::<f64>();
        if count > self.buckets.len() as f64 || count > 4.0 * self.elements.len() as f64 {
            out.extend((0..self.elements.len() as u32).filter(|k| near(*k)));
            return;
        }
        for x in lo[0]..=hi[0] {
            for y in lo[1]..=hi[1] {
                for z in lo[2]..=hi[2] {
                    if let Some(b) = self.buckets.get(&[x, y, z]) {
                        out.extend(b.iter().copied().filter(|k| near(*k)));
                    }
                }
            }
        }
        if let Some(b) = self.buckets.get(&[i64::MIN; 3]) {
            out.extend(b.iter().copied().filter(|k| near(*k)));
        }
        out.sort_unstable();
        out.dedup();
    }

    /// `∫_S exp(−a|x − c|²) dx` over the elements among `candidates` (all when `None`) that come
    /// within `√(ln(1/tol)/a)` of `c`; each element in closed form (docs/design/math.md §2): [`segment`] in
    /// 2-D, [`triangle_fast`](crate::triangle_fast) (or the relative-accuracy [`triangle`] when `accurate`) in 3-D.
    pub fn integrate(
        &self,
        c: V,
        a: f64,
        tol: f64,
        accurate: bool,
        candidates: Option<&[u32]>,
    ) -> f64 {
        let r = support_radius(a, tol);
        match candidates {
            Some(ids) => self.sum_within(c, a, r, accurate, ids.iter().copied()).0,
            None => {
                self.sum_within(c, a, r, accurate, 0..self.elements.len() as u32)
                    .0
            }
        }
    }

    /// Σ over the elements among `ids` whose bounding sphere comes within `r` of `c`, and the
    /// number of element integrals evaluated.
    fn sum_within(
        &self,
        c: V,
        a: f64,
        r: f64,
        accurate: bool,
        ids: impl Iterator<Item = u32>,
    ) -> (f64, usize) {
        if a.is_nan() || a <= 0.0 || !a.is_finite() || !finite(c) {
            return (0.0, 0);
        }
        let mut sum = 0.0;
        let mut n = 0;
        let sa = a.sqrt();
        for k in ids {
            let k = k as usize;
            let (ec, er) = self.spheres[k];
            let d = dist2(c, ec).sqrt() - er;
            if d > r {
                continue;
            }
            n += 1;
            sum += match (self.dim, accurate) {
                (Dim::Two, _) => {
                    let [p, q, _] = self.element(k);
                    segment(c, a, p, q)
                }
                // The precomputed geometry: the same signed edge sum as `triangle_fast`.
                (Dim::Three, false) => self.tris[k].as_ref().map_or(0.0, |t| t.integral(c, a, sa)),
                (Dim::Three, true) => {
                    let [p, q, s] = self.element(k);
                    triangle(c, a, p, q, s)
                }
            };
        }
        (sum, n)
    }
}

fn key(p: V, cell: f64) -> [i64; 3] {
    // Saturating float-to-int casts: far-away points land in the extreme buckets.
    p.map(|x| (x / cell).floor() as i64)
}

/// Radius beyond which `exp(−a r²) < tol`.
pub fn support_radius(a: f64, tol: f64) -> f64 {
    ((1.0 / tol).ln().max(0.0) / a).sqrt()
}

/// One Gaussian `A(x) = exp(−|x − w|²/d²)` of a base, with what the zero rules and the caller's
/// flatness criterion need.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Gaussian {
    /// Centre `w` (Flatland: z = 0).
    pub centre: V,
    /// Width `d` (eq. 2.1; `a = 1/d²`).
    pub width: f64,
    /// Unit surface normal at the centre; the zero vector disables the opposed-normal rule.
    pub normal: V,
    /// Sub-network id: entries across sub-networks are 0 (fig. 3.6 c).
    pub subnet: u32,
    /// The caller's criterion accepted this Gaussian for the flat closed form (sec. 3.9.4:
    /// fuzzy roughness and depth, [`crate::criteria::decide`]).
    pub flat: bool,
}

impl Gaussian {
    /// A Gaussian without normal, on sub-network 0, integrated by the exact element sum.
    pub fn new(centre: V, width: f64) -> Self {
        Self {
            centre,
            width,
            normal: [0.0; 3],
            subnet: 0,
            flat: false,
        }
    }

    fn a(&self) -> f64 {
        1.0 / (self.width * self.width)
    }

    fn valid(&self) -> bool {
        finite(self.centre)
            && finite(self.normal)
            && self.width.is_finite()
            && self.width > 0.0
            && self.a().is_finite()
    }
}

/// The decision of fig. 3.6 for the inner product of a pair: 0 across sub-networks or for
/// opposed normals, the flat closed form when the criterion accepted both, else the element sum.
pub fn inner_product_rule(i: &Gaussian, j: &Gaussian) -> Integration {
    if i.subnet != j.subnet || dot(i.normal, j.normal) < 0.0 {
        Integration::Zero
    } else if i.flat && j.flat {
        Integration::ClosedForm
    } else {
        Integration::ElementSum
    }
}

/// The flat closed form of the inner product (eq. 3.52, norm corrected by docs/design/math.md §2):
/// 3-D `π d_i²d_j²/(d_i²+d_j²)·exp(−|w_i−w_j|²/(d_i²+d_j²))`, 2-D with `√(π d_i²d_j²/(d_i²+d_j²))`.
/// Hence `⟨A_i|A_i⟩ = π d_i²/2` (not eq. 3.53's value).
pub fn flat_inner_product(dim: Dim, wi: V, di: f64, wj: V, dj: f64) -> f64 {
    let (ai, aj) = (di * di, dj * dj);
    let s = ai + aj;
    let k = (-dist2(wi, wj) / s).exp();
    match dim {
        Dim::Three => PI * ai * aj / s * k,
        Dim::Two => (PI * ai * aj / s).sqrt() * k,
    }
}

/// Settings of the Gram builders.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GramConfig {
    /// Support cut-off: Gaussian (products) below `tol` times their maximum count as 0.
    pub tol: f64,
    /// Use the relative-accuracy [`triangle`] per element instead of [`triangle_fast`](crate::triangle_fast)
    /// (absolute error ≲ 2e−15/a per element, what a Gram matrix needs; the accurate one is
    /// much slower for elements in the Gaussian's tail).
    pub accurate: bool,
}

impl Default for GramConfig {
    fn default() -> Self {
        Self {
            tol: 1e-14,
            accurate: false,
        }
    }
}

/// A sparse matrix in compressed rows (columns ascending within a row).
#[derive(Clone, Debug, PartialEq)]
pub struct Sparse {
    ncols: usize,
    row_ptr: Vec<usize>,
    cols: Vec<u32>,
    vals: Vec<f64>,
}

impl Sparse {
    fn from_rows(ncols: usize, rows: Vec<Vec<(u32, f64)>>) -> Self {
        let mut row_ptr = Vec::with_capacity(rows.len() + 1);
        row_ptr.push(0);
        let nnz = rows.iter().map(Vec::len).sum();
        let (mut cols, mut vals) = (Vec::with_capacity(nnz), Vec::with_capacity(nnz));
        for mut r in rows {
            r.sort_unstable_by_key(|e| e.0);
            for (c, v) in r {
                cols.push(c);
                vals.push(v);
            }
            row_ptr.push(cols.len());
        }
        Self {
            ncols,
            row_ptr,
            cols,
            vals,
        }
    }

    /// Number of rows.
    pub fn nrows(&self) -> usize {
        self.row_ptr.len() - 1
    }

    /// Number of columns.
    pub fn ncols(&self) -> usize {
        self.ncols
    }

    /// Stored (non-zero) entries.
    pub fn nnz(&self) -> usize {
        self.vals.len()
    }

    /// The stored entries `(column, value)` of row `i`.
    pub fn row(&self, i: usize) -> impl Iterator<Item = (usize, f64)> + '_ {
        let r = self.row_ptr[i]..self.row_ptr[i + 1];
        self.cols[r.clone()]
            .iter()
            .zip(&self.vals[r])
            .map(|(c, v)| (*c as usize, *v))
    }

    /// Entry (i, j) (0 when not stored).
    pub fn get(&self, i: usize, j: usize) -> f64 {
        let r = self.row_ptr[i]..self.row_ptr[i + 1];
        match self.cols[r.clone()].binary_search(&(j as u32)) {
            Ok(k) => self.vals[r.start + k],
            Err(_) => 0.0,
        }
    }

    /// The dense matrix.
    pub fn to_dense(&self) -> DMatrix<f64> {
        let mut m = DMatrix::zeros(self.nrows(), self.ncols);
        for i in 0..self.nrows() {
            for (j, v) in self.row(i) {
                m[(i, j)] = v;
            }
        }
        m
    }

    /// `y = M x`.
    pub fn mul_vec(&self, x: &[f64]) -> Result<Vec<f64>, GramError> {
        if x.len() != self.ncols {
            return Err(GramError::Length {
                expected: self.ncols,
                got: x.len(),
            });
        }
        Ok((0..self.nrows())
            .map(|i| self.row(i).map(|(j, v)| v * x[j]).sum())
            .collect())
    }

    /// `y = Mᵀ x`.
    pub fn tr_mul_vec(&self, x: &[f64]) -> Result<Vec<f64>, GramError> {
        if x.len() != self.nrows() {
            return Err(GramError::Length {
                expected: self.nrows(),
                got: x.len(),
            });
        }
        let mut y = vec![0.0; self.ncols];
        for i in 0..self.nrows() {
            for (j, v) in self.row(i) {
                y[j] += v * x[i];
            }
        }
        Ok(y)
    }
}

/// A Gram matrix and how its pairs were integrated.
#[derive(Clone, Debug, PartialEq)]
pub struct Gram {
    /// The symmetric matrix (both triangles stored).
    pub matrix: Sparse,
    /// Pairs (i ≤ j, within the support cut-off) set to 0 by the zero rules.
    pub zero_rule: usize,
    /// Pairs by the flat closed form.
    pub closed_form: usize,
    /// Pairs by the exact element sum.
    pub element_sum: usize,
    /// Element integrals evaluated for the element sums.
    pub element_integrals: usize,
}

/// Counts of how [`cross_with`] / [`gram_with`] integrated their pairs.
#[derive(Clone, Copy, Debug, Default)]
struct Counts {
    zero: usize,
    flat: usize,
    sum: usize,
    evals: usize,
}

/// Per Gaussian, the elements within twice its support radius, sorted by the lower bound
/// `|e − w| − r_e` of their distance from the centre: a superset of the support of its product
/// with any Gaussian the pair cut keeps (with `L = ln(1/tol)` a kept pair has
/// `a_i a_j/(a_i+a_j)|Δ|² ≤ L`, so the product's centre lies within `√(L/a_i)` of `w_i` and its
/// support radius `√(L/(a_i+a_j))` is smaller still). A pair reads only the prefix that can reach
/// its product's support.
struct Near {
    lower: Vec<f64>,
    ids: Vec<u32>,
}

impl Near {
    /// The candidates within `reach` of the centre.
    fn within(&self, reach: f64) -> &[u32] {
        &self.ids[..self.lower.partition_point(|l| *l <= reach)]
    }
}

fn candidates(domain: &Domain, g: &[Gaussian], tol: f64) -> Vec<Near> {
    g.par_iter()
        .map(|gi| {
            let mut out = Vec::new();
            domain.elements_near(gi.centre, 2.0 * support_radius(gi.a(), tol), &mut out);
            let mut v: Vec<(f64, u32)> = out
                .iter()
                .map(|k| {
                    let (ec, er) = domain.spheres[*k as usize];
                    (dist2(ec, gi.centre).sqrt() - er, *k)
                })
                .collect();
            v.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
            Near {
                lower: v.iter().map(|e| e.0).collect(),
                ids: v.iter().map(|e| e.1).collect(),
            }
        })
        .collect()
}

fn check(g: &[Gaussian], cfg: &GramConfig) -> Result<(), GramError> {
    if !(cfg.tol > 0.0 && cfg.tol < 1.0) {
        return Err(GramError::BadTolerance(cfg.tol));
    }
    match g.iter().position(|x| !x.valid()) {
        Some(i) => Err(GramError::BadGaussian(i)),
        None => Ok(()),
    }
}

/// Centres sorted along their longest axis, for the pair sweep.
struct Sweep {
    axis: usize,
    order: Vec<u32>,
    keys: Vec<f64>,
    max_d2: f64,
}

impl Sweep {
    fn new(g: &[Gaussian]) -> Self {
        let ext = |k: usize| {
            let (lo, hi) = g
                .iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), x| {
                    (l.min(x.centre[k]), h.max(x.centre[k]))
                });
            hi - lo
        };
        let axis = (0..3)
            .max_by(|a, b| ext(*a).total_cmp(&ext(*b)))
            .unwrap_or(0);
        let mut order: Vec<u32> = (0..g.len() as u32).collect();
        order.sort_by(|a, b| g[*a as usize].centre[axis].total_cmp(&g[*b as usize].centre[axis]));
        let keys = order.iter().map(|i| g[*i as usize].centre[axis]).collect();
        let max_d2 = g.iter().map(|x| x.width * x.width).fold(0.0, f64::max);
        Self {
            axis,
            order,
            keys,
            max_d2,
        }
    }

    /// Ids whose centre is within `r` of `x` along the axis.
    fn range(&self, x: f64, r: f64) -> &[u32] {
        let lo = self.keys.partition_point(|k| *k < x - r);
        let hi = self.keys.partition_point(|k| *k <= x + r);
        &self.order[lo..hi]
    }
}

/// One entry by the chosen method, and the number of element integrals it took. The element
/// sum skips elements on which the product `s·exp(−a|x − c|²)` stays below `tol` (radius
/// `√((ln(1/tol) + ln s)/a)` around `c`): on a plane the skipped mass is below `tol·π/a`.
fn entry(
    domain: &Domain,
    (gi, ni): (&Gaussian, &Near),
    (gj, nj): (&Gaussian, &Near),
    how: Integration,
    cfg: &GramConfig,
) -> (f64, usize) {
    match how {
        Integration::Zero => (0.0, 0),
        Integration::ClosedForm => (
            flat_inner_product(domain.dim, gi.centre, gi.width, gj.centre, gj.width),
            0,
        ),
        Integration::ElementSum => {
            let (a, c, s) = product(gi.a(), gi.centre, gj.a(), gj.centre);
            let budget = (1.0 / cfg.tol).ln() + s.ln();
            if s == 0.0 || budget <= 0.0 {
                return (0.0, 0);
            }
            let r = (budget / a).sqrt();
            let ci = ni.within(dist2(c, gi.centre).sqrt() + r);
            let cj = nj.within(dist2(c, gj.centre).sqrt() + r);
            let ids = if ci.len() <= cj.len() { ci } else { cj };
            let (v, n) = domain.sum_within(c, a, r, cfg.accurate, ids.iter().copied());
            (s * v, n)
        }
    }
}

/// The Gram matrix `G_ij = ⟨A_i|A_j⟩` of `gaussians` on `domain` with the zero rules and
/// decision of fig. 3.6 ([`inner_product_rule`]).
pub fn gram(domain: &Domain, gaussians: &[Gaussian], cfg: &GramConfig) -> Result<Gram, GramError> {
    gram_with(domain, gaussians, cfg, inner_product_rule)
}

/// The Gram matrix with the caller's per-pair decision `rule` (called with `i ≤ j`).
pub fn gram_with<R>(
    domain: &Domain,
    gaussians: &[Gaussian],
    cfg: &GramConfig,
    rule: R,
) -> Result<Gram, GramError>
where
    R: Fn(&Gaussian, &Gaussian) -> Integration + Sync,
{
    check(gaussians, cfg)?;
    let g = gaussians;
    let cand = candidates(domain, g, cfg.tol);
    let sweep = Sweep::new(g);
    let cut = (1.0 / cfg.tol).ln();
    let upper: Vec<(Vec<(u32, f64)>, Counts)> = (0..g.len())
        .into_par_iter()
        .map(|i| {
            let gi = &g[i];
            let mut row = Vec::new();
            let mut n = Counts::default();
            let reach = (cut * (gi.width * gi.width + sweep.max_d2)).sqrt();
            for &j in sweep.range(gi.centre[sweep.axis], reach) {
                let j = j as usize;
                if j < i {
                    continue;
                }
                let gj = &g[j];
                let (ai, aj) = (gi.a(), gj.a());
                if ai * aj / (ai + aj) * dist2(gi.centre, gj.centre) > cut {
                    continue;
                }
                let how = rule(gi, gj);
                match how {
                    Integration::Zero => n.zero += 1,
                    Integration::ClosedForm => n.flat += 1,
                    Integration::ElementSum => n.sum += 1,
                }
                let (v, evals) = entry(domain, (gi, &cand[i]), (gj, &cand[j]), how, cfg);
                n.evals += evals;
                if v != 0.0 {
                    row.push((j as u32, v));
                }
            }
            (row, n)
        })
        .collect();
    let mut rows: Vec<Vec<(u32, f64)>> = vec![Vec::new(); g.len()];
    let mut total = Counts::default();
    for (i, (row, n)) in upper.into_iter().enumerate() {
        total.zero += n.zero;
        total.flat += n.flat;
        total.sum += n.sum;
        total.evals += n.evals;
        for (j, v) in row {
            rows[i].push((j, v));
            if j as usize != i {
                rows[j as usize].push((i as u32, v));
            }
        }
    }
    Ok(Gram {
        matrix: Sparse::from_rows(g.len(), rows),
        zero_rule: total.zero,
        closed_form: total.flat,
        element_sum: total.sum,
        element_integrals: total.evals,
    })
}

/// The rectangular matrix `M_ij = ∫_S R_i C_j dx` between two sets of Gaussians (e.g. kernel
/// halves against a base, docs/design/math.md §3), each pair by the caller's `rule`.
pub fn cross_with<R>(
    domain: &Domain,
    rows: &[Gaussian],
    cols: &[Gaussian],
    cfg: &GramConfig,
    rule: R,
) -> Result<Sparse, GramError>
where
    R: Fn(&Gaussian, &Gaussian) -> Integration + Sync,
{
    check(rows, cfg)?;
    check(cols, cfg)?;
    let cand_r = candidates(domain, rows, cfg.tol);
    let cand_c = candidates(domain, cols, cfg.tol);
    let sweep = Sweep::new(cols);
    let cut = (1.0 / cfg.tol).ln();
    let out: Vec<Vec<(u32, f64)>> = rows
        .par_iter()
        .enumerate()
        .map(|(i, gi)| {
            let mut row = Vec::new();
            let reach = (cut * (gi.width * gi.width + sweep.max_d2)).sqrt();
            for &j in sweep.range(gi.centre[sweep.axis], reach) {
                let gj = &cols[j as usize];
                let (ai, aj) = (gi.a(), gj.a());
                if ai * aj / (ai + aj) * dist2(gi.centre, gj.centre) > cut {
                    continue;
                }
                let how = rule(gi, gj);
                let (v, _) = entry(
                    domain,
                    (gi, &cand_r[i]),
                    (gj, &cand_c[j as usize]),
                    how,
                    cfg,
                );
                if v != 0.0 {
                    row.push((j, v));
                }
            }
            row
        })
        .collect();
    Ok(Sparse::from_rows(cols.len(), out))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::closed_form::triangle_fast;
    use crate::cubature::triangle_cubature;
    use crate::orthonormal::Orthonormal;
    use proptest::prelude::*;

    /// A bumpy n×n grid of squares (two triangles each) of edge h over [0, n h]², height
    /// `bump·sin·sin`.
    pub(crate) fn bumpy_grid(n: usize, h: f64, bump: f64) -> Domain {
        Domain::height_field(n, n, h, |x, y| bump * (1.3 * x).sin() * (0.9 * y).cos()).unwrap()
    }

    fn cubature_entry(domain: &Domain, gi: &Gaussian, gj: &Gaussian) -> f64 {
        let f = |x: V| (-gi.a() * dist2(x, gi.centre) - gj.a() * dist2(x, gj.centre)).exp();
        (0..domain.len())
            .map(|k| triangle_cubature(f, domain.element(k), 1e-15).value)
            .sum()
    }

    #[test]
    fn element_sum_matches_cubature_over_every_element() {
        let dom = bumpy_grid(6, 0.5, 0.3);
        let g = [
            Gaussian::new([1.2, 1.4, 0.1], 0.6),
            Gaussian::new([1.6, 1.1, -0.2], 0.4),
            Gaussian::new([0.1, 2.9, 0.3], 0.9),
        ];
        let cfg = GramConfig {
            tol: 1e-16,
            accurate: true,
        };
        let m = gram(&dom, &g, &cfg).unwrap().matrix;
        for i in 0..3 {
            for j in 0..3 {
                let want = cubature_entry(&dom, &g[i], &g[j]);
                let got = m.get(i, j);
                assert!(
                    (got - want).abs() <= 1e-12 * want.max(1e-3),
                    "{i},{j}: {got} vs {want}"
                );
            }
        }
    }

    #[test]
    fn flat_closed_form_is_the_element_sum_far_from_the_border_and_has_the_corrected_norm() {
        // A flat 40×40 square of edge 0.5 (z = 0); Gaussians near its middle.
        let dom = bumpy_grid(40, 0.5, 0.0);
        let g = [
            Gaussian::new([10.0, 10.2, 0.0], 0.7),
            Gaussian::new([10.9, 9.6, 0.0], 1.1),
        ];
        let m = gram(&dom, &g, &GramConfig::default()).unwrap().matrix;
        for i in 0..2 {
            for j in 0..2 {
                let flat = flat_inner_product(
                    Dim::Three,
                    g[i].centre,
                    g[i].width,
                    g[j].centre,
                    g[j].width,
                );
                assert!(
                    (m.get(i, j) - flat).abs() <= 1e-13 * flat,
                    "{} vs {flat}",
                    m.get(i, j)
                );
            }
            let d = g[i].width;
            assert!((m.get(i, i) - PI * d * d / 2.0).abs() < 1e-13);
        }
        // 2-D: a long straight line.
        let v: Vec<[f64; 2]> = (0..=200).map(|k| [k as f64 * 0.1, 0.0]).collect();
        let s: Vec<[u32; 2]> = (0..200).map(|k| [k, k + 1]).collect();
        let dom = Domain::segments(&v, &s).unwrap();
        let g = [
            Gaussian::new([10.0, 0.0, 0.0], 0.3),
            Gaussian::new([10.5, 0.0, 0.0], 0.5),
        ];
        let m = gram(&dom, &g, &GramConfig::default()).unwrap().matrix;
        let flat = flat_inner_product(Dim::Two, g[0].centre, 0.3, g[1].centre, 0.5);
        assert!((m.get(0, 1) - flat).abs() <= 1e-13 * flat);
        assert!((m.get(0, 0) - (PI / 2.0).sqrt() * 0.3).abs() < 1e-14);
    }

    #[test]
    fn flatland_element_sum_matches_a_fine_midpoint_rule_and_orthonormalizes() {
        // A curved polyline (quarter circle of radius 3, 60 segments) with 12 Gaussians on it.
        let v: Vec<[f64; 2]> = (0..=60)
            .map(|k| {
                let t = k as f64 / 60.0 * std::f64::consts::FRAC_PI_2;
                [3.0 * t.cos(), 3.0 * t.sin()]
            })
            .collect();
        let s: Vec<[u32; 2]> = (0..60).map(|k| [k, k + 1]).collect();
        let dom = Domain::segments(&v, &s).unwrap();
        let g: Vec<Gaussian> = (0..12)
            .map(|k| {
                let t = (k as f64 + 0.5) / 12.0 * std::f64::consts::FRAC_PI_2;
                Gaussian::new([3.0 * t.cos(), 3.0 * t.sin(), 0.0], 0.5 + 0.02 * k as f64)
            })
            .collect();
        let m = gram(&dom, &g, &GramConfig::default())
            .unwrap()
            .matrix
            .to_dense();
        let f = |x: V, i: usize, j: usize| {
            (-dist2(x, g[i].centre) / g[i].width.powi(2)
                - dist2(x, g[j].centre) / g[j].width.powi(2))
            .exp()
        };
        for (i, j) in [(0, 0), (0, 1), (3, 5), (11, 11), (2, 9)] {
            // Composite midpoint rule, 4000 points per segment: error ~1e-9 relative.
            let mut want = 0.0;
            for k in 0..dom.len() {
                let [p, q, _] = dom.element(k);
                let len = dist2(p, q).sqrt();
                let nmid = 4000;
                for t in 0..nmid {
                    let u = (t as f64 + 0.5) / nmid as f64;
                    let x = [0, 1, 2].map(|c| p[c] + u * (q[c] - p[c]));
                    want += f(x, i, j) * len / nmid as f64;
                }
            }
            assert!(
                (m[(i, j)] - want).abs() <= 1e-8 * m[(i, i)],
                "{i},{j}: {} vs {want}",
                m[(i, j)]
            );
        }
        let a = Orthonormal::new(&m, 1e-12).matrix_a();
        let err = (&a * &m * a.transpose() - DMatrix::identity(12, 12)).amax();
        assert!(err < 1e-10, "{err:e}");
    }

    #[test]
    fn zero_rules_and_flat_decision_of_fig_3_6() {
        let dom = bumpy_grid(10, 0.5, 0.0);
        let up = [0.0, 0.0, 1.0];
        let mut g = [Gaussian::new([2.0, 2.0, 0.0], 0.5); 4];
        g[1].centre = [2.3, 2.0, 0.0];
        g[1].subnet = 1;
        g[2].centre = [2.0, 2.3, 0.0];
        g[2].normal = [0.0, 0.0, -1.0];
        g[0].normal = up;
        g[3].centre = [2.2, 2.2, 0.0];
        g[3].normal = up;
        let r = gram(&dom, &g, &GramConfig::default()).unwrap();
        assert_eq!(r.matrix.get(0, 1), 0.0); // separate sub-networks
        assert_eq!(r.matrix.get(0, 2), 0.0); // opposed normals
        assert!(r.matrix.get(0, 3) > 0.0 && r.matrix.get(1, 1) > 0.0);
        assert_eq!((r.zero_rule, r.closed_form), (5, 0)); // 1 with 0, 2, 3; 2 with 0, 3
        g[0].flat = true;
        g[3].flat = true;
        let r = gram(&dom, &g, &GramConfig::default()).unwrap();
        assert_eq!(r.closed_form, 3); // (0,0), (0,3), (3,3)
        let flat = flat_inner_product(Dim::Three, g[0].centre, 0.5, g[3].centre, 0.5);
        assert_eq!(r.matrix.get(0, 3), flat);
    }

    #[test]
    fn bad_input_is_an_error() {
        assert!(matches!(
            Domain::triangles(vec![[0.0; 3]], &[[0, 1, 2]]),
            Err(GramError::BadIndex { .. })
        ));
        assert_eq!(
            Domain::triangles(vec![[f64::NAN, 0.0, 0.0]], &[]).unwrap_err(),
            GramError::NonFiniteVertex(0)
        );
        let dom = bumpy_grid(2, 1.0, 0.0);
        let g = [Gaussian::new([0.0; 3], 0.0)];
        assert_eq!(
            gram(&dom, &g, &GramConfig::default()).unwrap_err(),
            GramError::BadGaussian(0)
        );
        let g = [Gaussian::new([0.0; 3], 1.0)];
        let cfg = GramConfig {
            tol: 0.0,
            accurate: false,
        };
        assert!(matches!(
            gram(&dom, &g, &cfg),
            Err(GramError::BadTolerance(_))
        ));
    }

    #[test]
    fn degenerate_elements_and_far_or_stacked_gaussians_stay_finite() {
        // Zero-area triangle, zero-length segment.
        let dom = Domain::triangles(
            vec![[0.0; 3], [1.0, 0.0, 0.0], [2.0, 0.0, 0.0]],
            &[[0, 1, 2]],
        )
        .unwrap();
        let g = [Gaussian::new([0.5, 0.0, 0.0], 1.0)];
        assert_eq!(
            gram(&dom, &g, &GramConfig::default()).unwrap().matrix.nnz(),
            0
        );
        let dom = Domain::segments(&[[0.0, 0.0], [0.0, 0.0]], &[[0, 1]]).unwrap();
        assert_eq!(
            gram(&dom, &g, &GramConfig::default()).unwrap().matrix.nnz(),
            0
        );
        // Underflow far away; widths from 1e-6 to 1e6 of the element size; 300 on one point.
        let dom = bumpy_grid(4, 1.0, 0.0);
        let mut g = vec![
            Gaussian::new([1e200, 0.0, 0.0], 1.0),
            Gaussian::new([2.0, 2.0, 0.0], 1e-6),
            Gaussian::new([2.0, 2.0, 0.0], 1e6),
        ];
        g.extend(std::iter::repeat_n(
            Gaussian::new([1.5, 1.5, 0.1], 0.8),
            300,
        ));
        let m = gram(&dom, &g, &GramConfig::default()).unwrap().matrix;
        assert!((0..m.nrows()).all(|i| m.row(i).all(|(_, v)| v.is_finite() && v >= 0.0)));
        assert_eq!(m.get(0, 0), 0.0);
        assert!(m.get(1, 1) > 0.0 && m.get(2, 2) > 0.0);
        let o = Orthonormal::new(&m.to_dense(), 1e-10);
        // The far one (empty), and all but one of the 300 stacked copies are rejected.
        assert_eq!(o.rejected(), 1 + 299);
    }

    fn jittered_base(n: usize, h: f64, jitter: f64, seed: u64) -> Vec<Gaussian> {
        let mut s = seed;
        let mut rnd = || {
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (s >> 11) as f64 / (1u64 << 53) as f64 - 0.5
        };
        let mut g = Vec::new();
        for y in 0..n {
            for x in 0..n {
                let c = [
                    (x as f64 + 0.5 + jitter * rnd()) * h,
                    (y as f64 + 0.5 + jitter * rnd()) * h,
                    0.0,
                ];
                g.push(Gaussian::new(c, h * (1.0 + 0.2 * rnd())));
            }
        }
        g
    }

    #[test]
    fn gram_is_symmetric_psd_cauchy_schwarz_and_orthonormalizes() {
        let dom = bumpy_grid(16, 0.5, 0.4);
        let mut g = jittered_base(8, 1.0, 0.3, 7);
        for x in &mut g {
            x.centre[2] = 0.4 * (1.3 * x.centre[0]).sin() * (0.9 * x.centre[1]).cos();
        }
        let m = gram(&dom, &g, &GramConfig::default())
            .unwrap()
            .matrix
            .to_dense();
        let n = g.len();
        assert!((&m - m.transpose()).amax() == 0.0);
        for i in 0..n {
            for j in 0..n {
                assert!(m[(i, j)] * m[(i, j)] <= m[(i, i)] * m[(j, j)] * (1.0 + 1e-12));
            }
        }
        let eig = m.clone().symmetric_eigen();
        assert!(eig.eigenvalues.min() > -1e-12 * eig.eigenvalues.max());
        let o = Orthonormal::new(&m, 1e-12);
        assert_eq!(o.rejected(), 0);
        let a = o.matrix_a();
        let err = (&a * &m * a.transpose() - DMatrix::identity(n, n)).amax();
        assert!(err < 1e-10, "{err:e}");
    }

    #[test]
    fn spanned_space_does_not_depend_on_order() {
        // Projection of a function onto the span: the same coefficients per Gaussian.
        let dom = bumpy_grid(12, 0.5, 0.2);
        let g = jittered_base(5, 1.0, 0.2, 3);
        let u: Vec<f64> = g
            .iter()
            .map(|x| (x.centre[0] - 0.3 * x.centre[1]).cos())
            .collect();
        let m = gram(&dom, &g, &GramConfig::default())
            .unwrap()
            .matrix
            .to_dense();
        let gamma = Orthonormal::new(&m, 1e-12).solve(&u);
        let perm: Vec<usize> = (0..g.len()).rev().collect();
        let gp: Vec<Gaussian> = perm.iter().map(|i| g[*i]).collect();
        let up: Vec<f64> = perm.iter().map(|i| u[*i]).collect();
        let mp = gram(&dom, &gp, &GramConfig::default())
            .unwrap()
            .matrix
            .to_dense();
        let gammap = Orthonormal::new(&mp, 1e-12).solve(&up);
        for (k, i) in perm.iter().enumerate() {
            assert!(
                (gammap[k] - gamma[*i]).abs()
                    < 1e-8 * gamma.iter().fold(1.0f64, |a, b| a.max(b.abs()))
            );
        }
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(16))]
        #[test]
        fn sparse_entries_match_a_dense_uncut_sum(
            c in prop::array::uniform6(0.5f64..3.5),
            d in prop::array::uniform2(0.2f64..1.0),
        ) {
            let dom = bumpy_grid(8, 0.5, 0.3);
            let g = [Gaussian::new([c[0], c[1], c[2] - 2.0], d[0]), Gaussian::new([c[3], c[4], c[5] - 2.0], d[1])];
            let m = gram(&dom, &g, &GramConfig::default()).unwrap().matrix;
            let (a, cc, s) = product(g[0].a(), g[0].centre, g[1].a(), g[1].centre);
            let full: f64 = (0..dom.len()).map(|k| {
                let [p, q, r] = dom.element(k);
                s * triangle_fast(cc, a, p, q, r)
            }).sum();
            prop_assert!((m.get(0, 1) - full).abs() <= 1e-13 * PI / a + 1e-12 * full);
            prop_assert_eq!(m.get(0, 1), m.get(1, 0));
        }
    }
}

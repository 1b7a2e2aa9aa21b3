//! Gaussian integrals over huge surfaces in time independent of the polygon count: a cluster
//! tree whose nodes stand in for their elements where a Gaussian cannot tell them apart.
//!
//! Every FEM integral is `∫_S exp(−a|x − c|²) dx` over the scene's elements, possibly masked by
//! normal (the base Gaussians live on the faces that face like their cell, [`crate::config::BaseDomain::Scene`]).
//! Summed exactly, one integral touches every element within the support radius
//! `r = √(ln(1/tol)/a)`; on a scene of a million small triangles that is a large fraction of the
//! scene, and the FEM step costs minutes per step.
//!
//! A Gaussian of width `d = 1/√a` cannot resolve detail much below `d`. The tree groups elements
//! spatially (median splits, at most [`LEAF`] per leaf). Each node stores its area `A`, its area
//! centroid `m` and covariance `Σ = ∫ (x − m)(x − m)ᵀ dx / A`, and replaces the integral over its
//! elements by the six-point rule with the same area, centroid and covariance,
//!
//! ```text
//! ∫_node f(x) dx ≈ (A/6) Σ_{i=1..3} [ f(m + √(3λ_i) e_i) + f(m − √(3λ_i) e_i) ]
//! ```
//!
//! (λ_i, e_i the eigenpairs of Σ), which is exact for every quadratic f, hence for the Gaussian to
//! second order in the node's size: the relative error is `O((a R²)²)` with `R` the node's radius
//! about `m`. A node is used in place of its elements when `a·R² ≤ θ` ([`ClusterTree::theta`]);
//! otherwise the query descends, and at the leaves the elements are summed exactly. The rule is a
//! positive measure, so Gram matrices built with it stay positive semi-definite.
//!
//! Masked integrals: each node keeps its area per direction bin ([`BINS`] bins over the sphere);
//! a node used in place of its elements contributes the share of its area whose bin direction
//! passes the mask. That is the only approximation in the mask, and only on nodes that are
//! approximated anyway.

use crate::element::Element;
use glam::{DMat3, DVec3};

/// Elements per leaf at most.
pub const LEAF: usize = 8;

/// Direction bins of the node normal histograms: the 26 directions from the centre of a cube
/// to its face centres, edge midpoints and corners.
pub const BINS: usize = 26;

/// A node of the tree: what a traversal reads at every visit.
#[derive(Clone, Debug)]
struct Node {
    lo: DVec3,
    hi: DVec3,
    /// Squared radius about the centroid: max |v − m|² over the elements' corners.
    radius2: f64,
    /// Element range in `order` (all of the subtree's elements).
    first: u32,
    count: u32,
    /// Children, or `u32::MAX` for a leaf.
    left: u32,
    right: u32,
}

/// What a traversal reads only where a node replaces its elements.
#[derive(Clone, Debug)]
struct NodeRule {
    /// The six-point rule: points and the common weight A/6.
    points: [DVec3; 6],
    weight: f64,
    /// Area per direction bin.
    bins: [f32; BINS],
}

/// Area, first and second moments of a set of elements (about the origin).
#[derive(Clone, Copy, Debug)]
struct Moments {
    area: f64,
    first: DVec3,
    second: DMat3,
}

impl Default for Moments {
    /// Zero moments (glam's `DMat3::default()` is the identity, not zero).
    fn default() -> Self {
        Moments {
            area: 0.0,
            first: DVec3::ZERO,
            second: DMat3::ZERO,
        }
    }
}

impl Moments {
    fn add(&mut self, o: &Moments) {
        self.area += o.area;
        self.first += o.first;
        self.second += o.second;
    }

    /// Exact moments of a triangle: ∫ x dA = A·g, ∫ x xᵀ dA = (A/12)(Σ p_i p_iᵀ + s sᵀ), s = Σ p_i.
    fn triangle(p: [DVec3; 3]) -> Moments {
        let area = 0.5 * (p[1] - p[0]).cross(p[2] - p[0]).length();
        let s = p[0] + p[1] + p[2];
        let outer = |u: DVec3, v: DVec3| DMat3::from_cols(u * v.x, u * v.y, u * v.z);
        let second = (outer(p[0], p[0]) + outer(p[1], p[1]) + outer(p[2], p[2]) + outer(s, s))
            * (area / 12.0);
        Moments {
            area,
            first: s * (area / 3.0),
            second,
        }
    }

    /// Exact moments of a segment: ∫ x x ᵀ ds = L·((ppᵀ + qqᵀ)/3 + (pqᵀ + qpᵀ)/6).
    fn segment(p: DVec3, q: DVec3) -> Moments {
        let len = p.distance(q);
        let outer = |u: DVec3, v: DVec3| DMat3::from_cols(u * v.x, u * v.y, u * v.z);
        let second = ((outer(p, p) + outer(q, q)) * (1.0 / 3.0)
            + (outer(p, q) + outer(q, p)) * (1.0 / 6.0))
            * len;
        Moments {
            area: len,
            first: (p + q) * (0.5 * len),
            second,
        }
    }

    fn of(e: &Element) -> Moments {
        match *e {
            Element::Segment([p, q]) => Moments::segment(p, q),
            Element::Triangle(t) => Moments::triangle(t),
            Element::Quad(q) => {
                let mut m = Moments::triangle([q[0], q[1], q[2]]);
                m.add(&Moments::triangle([q[0], q[2], q[3]]));
                m
            }
        }
    }
}

/// The bin directions (unit vectors).
fn bin_directions() -> [DVec3; BINS] {
    let mut out = [DVec3::ZERO; BINS];
    let mut i = 0;
    for x in -1..=1 {
        for y in -1..=1 {
            for z in -1..=1 {
                if (x, y, z) != (0, 0, 0) {
                    out[i] = DVec3::new(x as f64, y as f64, z as f64).normalize();
                    i += 1;
                }
            }
        }
    }
    out
}

/// The bin of a unit normal: the nearest bin direction.
fn bin_of(n: DVec3, dirs: &[DVec3; BINS]) -> usize {
    let mut best = (f64::NEG_INFINITY, 0);
    for (i, d) in dirs.iter().enumerate() {
        let c = d.dot(n);
        if c > best.0 {
            best = (c, i);
        }
    }
    best.1
}

/// A cluster tree over a surface's elements (module docs).
#[derive(Clone, Debug)]
pub struct ClusterTree {
    nodes: Vec<Node>,
    rules: Vec<NodeRule>,
    /// Per element: its own three-point rule, for elements small enough on their own.
    small: Vec<SmallRule>,
    /// Element ids, grouped by leaf.
    order: Vec<u32>,
    dirs: [DVec3; BINS],
    theta: f64,
}

impl ClusterTree {
    /// Builds the tree over `elements` (unit `normals`, one per element); nodes replace their
    /// elements in integrals of Gaussians with `a·R² ≤ theta`.
    pub fn new(elements: &[Element], normals: &[DVec3], theta: f64) -> Self {
        let dirs = bin_directions();
        let moments: Vec<Moments> = elements.iter().map(Moments::of).collect();
        let bounds: Vec<(DVec3, DVec3)> = elements.iter().map(Element::bounds).collect();
        let centroid: Vec<DVec3> = bounds.iter().map(|(lo, hi)| 0.5 * (*lo + *hi)).collect();
        let bins: Vec<usize> = normals.iter().map(|n| bin_of(*n, &dirs)).collect();
        let mut order: Vec<u32> = (0..elements.len() as u32).collect();
        let small = elements
            .iter()
            .zip(normals)
            .zip(&moments)
            .map(|((e, n), m)| SmallRule::new(e, *n, m))
            .collect();
        let mut tree = ClusterTree {
            nodes: Vec::with_capacity(2 * elements.len() / LEAF + 1),
            rules: Vec::with_capacity(2 * elements.len() / LEAF + 1),
            small,
            order: Vec::new(),
            dirs,
            theta,
        };
        if !elements.is_empty() {
            let data = BuildData {
                elements,
                moments: &moments,
                bounds: &bounds,
                centroid: &centroid,
                bins: &bins,
            };
            tree.build(&data, &mut order, 0);
        }
        tree.order = order;
        tree
    }

    /// The node criterion θ: a node stands in for its elements when `a·R² ≤ θ`.
    pub fn theta(&self) -> f64 {
        self.theta
    }

    /// Number of nodes.
    pub fn nodes(&self) -> usize {
        self.nodes.len()
    }

    /// Builds the subtree over `ids` (a slice of the final order starting at `first`); returns
    /// its node index.
    fn build(&mut self, d: &BuildData, ids: &mut [u32], first: usize) -> u32 {
        let index = self.nodes.len();
        let mut m = Moments::default();
        let (mut lo, mut hi) = (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY));
        let (mut clo, mut chi) = (lo, hi);
        let mut bins = [0f32; BINS];
        for &e in ids.iter() {
            let e = e as usize;
            m.add(&d.moments[e]);
            lo = lo.min(d.bounds[e].0);
            hi = hi.max(d.bounds[e].1);
            clo = clo.min(d.centroid[e]);
            chi = chi.max(d.centroid[e]);
            bins[d.bins[e]] += d.moments[e].area as f32;
        }
        let (centre, points, weight) = six_point_rule(&m, lo, hi);
        let radius2 = ids
            .iter()
            .flat_map(|&e| corners(&d.elements[e as usize]))
            .map(|v| v.distance_squared(centre))
            .fold(0.0, f64::max);
        self.rules.push(NodeRule {
            points,
            weight,
            bins,
        });
        self.nodes.push(Node {
            lo,
            hi,
            radius2,
            first: first as u32,
            count: ids.len() as u32,
            left: u32::MAX,
            right: u32::MAX,
        });
        if ids.len() > LEAF {
            let extent = chi - clo;
            let axis = if extent.x >= extent.y && extent.x >= extent.z {
                0
            } else if extent.y >= extent.z {
                1
            } else {
                2
            };
            let mid = ids.len() / 2;
            ids.select_nth_unstable_by(mid, |&p, &q| {
                d.centroid[p as usize][axis].total_cmp(&d.centroid[q as usize][axis])
            });
            let (l, r) = ids.split_at_mut(mid);
            let left = self.build(d, l, first);
            let right = self.build(d, r, first + mid);
            self.nodes[index].left = left;
            self.nodes[index].right = right;
        }
        index as u32
    }

    /// `∫ exp(−a|x − c|²) dx` over the elements whose normal passes `mask` (see
    /// `Mask`), with the support cut at radius `r`; `exact(e)` integrates element `e`.
    pub fn integral(
        &self,
        c: DVec3,
        a: f64,
        r: f64,
        mask: &Mask,
        exact: &mut dyn FnMut(u32) -> f64,
    ) -> f64 {
        if self.nodes.is_empty() {
            return 0.0;
        }
        let mut sum = 0.0;
        // Median splits keep the depth near log2(elements / LEAF); 128 levels is far beyond any
        // surface that fits in memory.
        let mut stack = [0u32; 128];
        let mut top = 1;
        while top > 0 {
            top -= 1;
            let i = stack[top];
            let node = &self.nodes[i as usize];
            if c.clamp(node.lo, node.hi).distance_squared(c) > r * r {
                continue;
            }
            if a * node.radius2 <= self.theta {
                let rule = &self.rules[i as usize];
                let share = mask.share(&rule.bins, &self.dirs);
                if share > 0.0 {
                    let f: f64 = rule
                        .points
                        .iter()
                        .map(|p| (-a * p.distance_squared(c)).exp())
                        .sum();
                    sum += share * rule.weight * f;
                }
            } else if node.left == u32::MAX {
                let range = node.first as usize..(node.first + node.count) as usize;
                for &e in &self.order[range] {
                    let small = &self.small[e as usize];
                    if a * small.radius2 <= self.theta {
                        if mask.accepts(small.normal) {
                            let f: f64 = small
                                .points
                                .iter()
                                .map(|p| (-a * p.distance_squared(c)).exp())
                                .sum();
                            sum += small.weight * f;
                        }
                    } else {
                        sum += exact(e);
                    }
                }
            } else {
                stack[top] = node.right;
                stack[top + 1] = node.left;
                top += 2;
            }
        }
        sum
    }
}

/// The edge-midpoint rule of one element, `∫_T f ≈ (A/3) Σ f(edge midpoints)`, exact for
/// quadratics (a quadrilateral: the rule on each of its two triangles, weights by area). Used for
/// an element of a leaf whose own radius passes the criterion although the leaf's does not (a
/// small element next to a large one).
#[derive(Clone, Copy, Debug)]
struct SmallRule {
    points: [DVec3; 6],
    /// Common weight of the points (A/6: quads use six points, triangles three points twice).
    weight: f64,
    /// Squared radius about the centroid.
    radius2: f64,
    normal: DVec3,
}

impl SmallRule {
    /// The rule of element `e` with unit `normal` and moments `m` (`Moments::of(e)`).
    fn new(e: &Element, normal: DVec3, m: &Moments) -> Self {
        let mid = |p: DVec3, q: DVec3| 0.5 * (p + q);
        let centre = if m.area > 0.0 {
            m.first / m.area
        } else {
            DVec3::ZERO
        };
        let radius2 = corners(e)
            .map(|v| v.distance_squared(centre))
            .fold(0.0, f64::max);
        let (points, weight) = match *e {
            Element::Segment([p, q]) => {
                // Two-point Gauss–Legendre (midpoint ± (q − p)/(2√3), weight L/2 each; exact for
                // cubics), written as six points of weight L/6.
                let h = (q - p) * (0.5 / 3f64.sqrt());
                let c = mid(p, q);
                ([c + h, c - h, c + h, c - h, c + h, c - h], m.area / 6.0)
            }
            Element::Triangle([p, q, r]) => {
                let (a, b, c) = (mid(p, q), mid(q, r), mid(r, p));
                ([a, b, c, a, b, c], m.area / 6.0)
            }
            Element::Quad(q) => {
                // Two triangles of possibly different areas: equal weights need equal areas, so
                // fall back to the quad's own six-point moment rule.
                let (_, pts, w) = six_point_rule(m, q[0].min(q[2]), q[0].max(q[2]));
                (pts, w)
            }
        };
        SmallRule {
            points,
            weight,
            radius2,
            normal,
        }
    }
}

/// Which normals an integral accepts: every one (`facing` empty or zero), or those with
/// `n · f > cos_min` for every non-zero `f` in `facing`.
#[derive(Clone, Copy, Debug)]
pub struct Mask<'a> {
    /// Required facing directions (zero vectors are ignored).
    pub facing: &'a [DVec3],
    /// Cosine threshold.
    pub cos_min: f64,
}

impl Mask<'_> {
    /// Accepts every element.
    pub const ALL: Mask<'static> = Mask {
        facing: &[],
        cos_min: 0.0,
    };

    /// Whether a unit normal passes.
    pub fn accepts(&self, n: DVec3) -> bool {
        self.facing
            .iter()
            .all(|f| *f == DVec3::ZERO || n.dot(*f) > self.cos_min)
    }

    /// Share of a node's area whose bin direction passes.
    fn share(&self, bins: &[f32; BINS], dirs: &[DVec3; BINS]) -> f64 {
        if self.facing.iter().all(|f| *f == DVec3::ZERO) {
            return 1.0;
        }
        let (mut pass, mut all) = (0.0f64, 0.0f64);
        for (b, d) in bins.iter().zip(dirs) {
            all += *b as f64;
            if *b > 0.0 && self.accepts(*d) {
                pass += *b as f64;
            }
        }
        if all > 0.0 { pass / all } else { 0.0 }
    }
}

struct BuildData<'a> {
    elements: &'a [Element],
    moments: &'a [Moments],
    bounds: &'a [(DVec3, DVec3)],
    centroid: &'a [DVec3],
    bins: &'a [usize],
}

fn corners(e: &Element) -> impl Iterator<Item = DVec3> {
    let (arr, n) = match *e {
        Element::Segment([p, q]) => ([p, q, q, q], 2),
        Element::Triangle([p, q, r]) => ([p, q, r, r], 3),
        Element::Quad(q) => (q, 4),
    };
    arr.into_iter().take(n)
}

/// The six-point rule of a node (module docs): its centroid, the points, and the weight A/6.
fn six_point_rule(m: &Moments, lo: DVec3, hi: DVec3) -> (DVec3, [DVec3; 6], f64) {
    if m.area <= 0.0 || !m.area.is_finite() {
        return (0.5 * (lo + hi), [0.5 * (lo + hi); 6], 0.0);
    }
    let centre = m.first / m.area;
    let outer = DMat3::from_cols(centre * centre.x, centre * centre.y, centre * centre.z);
    let cov = m.second * (1.0 / m.area) - outer;
    let sym = nalgebra::Matrix3::from_fn(|i, j| 0.5 * (cov.col(j)[i] + cov.col(i)[j]));
    let eig = nalgebra::SymmetricEigen::new(sym);
    let mut points = [centre; 6];
    for i in 0..3 {
        let lambda = eig.eigenvalues[i].max(0.0);
        let e = eig.eigenvectors.column(i);
        let step = DVec3::new(e[0], e[1], e[2]) * (3.0 * lambda).sqrt();
        points[2 * i] = centre + step;
        points[2 * i + 1] = centre - step;
    }
    (centre, points, m.area / 6.0)
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};

    fn exact_sum(elements: &[Element], c: DVec3, a: f64) -> f64 {
        elements
            .iter()
            .map(|e| match *e {
                Element::Triangle([p, q, r]) => gauss_integrals::triangle(
                    c.to_array(),
                    a,
                    p.to_array(),
                    q.to_array(),
                    r.to_array(),
                ),
                _ => unreachable!(),
            })
            .sum()
    }

    /// Random small triangles in a box: the clutter of the large-scene benchmark.
    fn clutter(n: usize, size: f64) -> (Vec<Element>, Vec<DVec3>) {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
        let mut els = Vec::new();
        let mut normals = Vec::new();
        for _ in 0..n {
            let c = DVec3::new(rng.random(), rng.random(), 0.5 * rng.random::<f64>());
            let mut p = || {
                c + size
                    * DVec3::new(
                        rng.random_range(-1.0..1.0),
                        rng.random_range(-1.0..1.0),
                        rng.random_range(-1.0..1.0),
                    )
            };
            let t = [p(), p(), p()];
            let n = (t[1] - t[0]).cross(t[2] - t[0]);
            if n.length() > 1e-12 {
                normals.push(n.normalize());
                els.push(Element::Triangle(t));
            }
        }
        (els, normals)
    }

    #[test]
    fn moments_match_the_six_point_rule_on_quadratics() {
        // The rule is exact for quadratics: check ∫ |x − c|² over one triangle.
        let t = [
            DVec3::new(0.1, 0.2, 0.3),
            DVec3::new(1.3, -0.2, 0.5),
            DVec3::new(0.4, 0.9, -0.6),
        ];
        let m = Moments::triangle(t);
        let (centre, pts, w) = six_point_rule(&m, DVec3::ZERO, DVec3::ONE);
        let c = DVec3::new(0.3, -0.4, 0.8);
        let rule: f64 = pts.iter().map(|p| w * p.distance_squared(c)).sum();
        // Reference: a fine midpoint subdivision of the triangle.
        let n = 400;
        let mut reference = 0.0;
        let area = m.area;
        for i in 0..n {
            for j in 0..n - i {
                // Two sub-triangles per (i, j) except the last row; use centroid rule on the
                // upward ones and the downward ones.
                let u = |a: f64, b: f64| {
                    t[0] + (t[1] - t[0]) * (a / n as f64) + (t[2] - t[0]) * (b / n as f64)
                };
                let up = (u(i as f64, j as f64)
                    + u(i as f64 + 1.0, j as f64)
                    + u(i as f64, j as f64 + 1.0))
                    / 3.0;
                reference += up.distance_squared(c);
                if i + j + 1 < n {
                    let down = (u(i as f64 + 1.0, j as f64)
                        + u(i as f64, j as f64 + 1.0)
                        + u(i as f64 + 1.0, j as f64 + 1.0))
                        / 3.0;
                    reference += down.distance_squared(c);
                }
            }
        }
        reference *= area / (n * n) as f64;
        assert!((centre - (t[0] + t[1] + t[2]) / 3.0).length() < 1e-14);
        assert!(
            (rule - reference).abs() < 1e-5 * reference,
            "{rule} vs {reference}"
        );
    }

    #[test]
    fn tree_integrals_converge_to_the_exact_sums_as_theta_falls() {
        let (els, normals) = clutter(1500, 0.02);
        let c = DVec3::new(0.5, 0.5, 0.25);
        for a in [20.0, 100.0, 400.0] {
            let reference = exact_sum(&els, c, a);
            let mut last = f64::INFINITY;
            for theta in [1.0, 0.25, 0.05, 0.0] {
                let tree = ClusterTree::new(&els, &normals, theta);
                let mut exact = |e: u32| exact_sum(&els[e as usize..e as usize + 1], c, a);
                let got = tree.integral(c, a, f64::INFINITY, &Mask::ALL, &mut exact);
                let err = (got - reference).abs() / reference;
                eprintln!("a {a} theta {theta}: relative error {err:.2e}");
                if theta == 0.0 {
                    assert!(err < 1e-12, "theta 0 must be the exact sum: {err}");
                } else {
                    assert!(
                        err < 0.02 * theta,
                        "a {a} theta {theta}: relative error {err}"
                    );
                }
                assert!(err <= last + 1e-12);
                last = err;
            }
        }
    }

    #[test]
    fn masked_integrals_follow_the_bins_on_axis_aligned_faces() {
        // Axis-aligned faces fall exactly into face bins: the masked approximation then only
        // selects whole faces, like the exact mask.
        let mut els = Vec::new();
        let mut normals = Vec::new();
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
        for _ in 0..1500 {
            let o = DVec3::new(rng.random(), rng.random(), rng.random());
            let (n, t) = if rng.random::<bool>() {
                (DVec3::Z, [o, o + 0.01 * DVec3::X, o + 0.01 * DVec3::Y])
            } else {
                (DVec3::X, [o, o + 0.01 * DVec3::Y, o + 0.01 * DVec3::Z])
            };
            els.push(Element::Triangle(t));
            normals.push(n);
        }
        let c = DVec3::splat(0.5);
        let a = 30.0;
        let facing = [DVec3::Z];
        let mask = Mask {
            facing: &facing,
            cos_min: 0.5,
        };
        let kept: Vec<Element> = els
            .iter()
            .zip(&normals)
            .filter(|(_, n)| mask.accepts(**n))
            .map(|(e, _)| *e)
            .collect();
        let reference = exact_sum(&kept, c, a);
        for (theta, bound) in [(0.25, 0.03), (0.05, 0.01), (0.0, 1e-12)] {
            let tree = ClusterTree::new(&els, &normals, theta);
            let mut exact = |e: u32| {
                if mask.accepts(normals[e as usize]) {
                    exact_sum(&els[e as usize..e as usize + 1], c, a)
                } else {
                    0.0
                }
            };
            let got = tree.integral(c, a, f64::INFINITY, &mask, &mut exact);
            let err = (got - reference).abs() / reference;
            eprintln!("masked, theta {theta}: relative error {err:.2e}");
            assert!(err < bound, "theta {theta}: {got} vs {reference}");
        }
    }
}

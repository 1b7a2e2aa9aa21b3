//! The surface elements integrals run over (and the band array, [`Bands`], from the scenes).

use glam::DVec3;

pub use scene_sampler::{BANDS, Bands};

/// A surface element of an integration domain: a segment (Flatland, z = 0), a triangle, or a
/// planar convex quadrilateral (two coplanar scene triangles sharing an edge, merged: its exact
/// Gaussian integral needs four edges instead of six).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Element {
    /// A Flatland segment in the z = 0 plane.
    Segment([DVec3; 2]),
    /// A 3-D triangle.
    Triangle([DVec3; 3]),
    /// A planar convex quadrilateral, corners in order.
    Quad([DVec3; 4]),
}

impl Element {
    /// Axis-aligned bounds.
    pub fn bounds(&self) -> (DVec3, DVec3) {
        match self {
            Element::Segment(p) => (p[0].min(p[1]), p[0].max(p[1])),
            Element::Triangle(p) => (p[0].min(p[1]).min(p[2]), p[0].max(p[1]).max(p[2])),
            Element::Quad(p) => (
                p[0].min(p[1]).min(p[2]).min(p[3]),
                p[0].max(p[1]).max(p[2]).max(p[3]),
            ),
        }
    }

    /// The quadrilateral formed by triangles `t1` and `t2` (same winding) when they share an
    /// edge, lie in one plane (within `tol` of each other) and their union is convex; corners in
    /// `t1`'s winding. `None` otherwise.
    pub fn merge_triangles(t1: [DVec3; 3], t2: [DVec3; 3], tol: f64) -> Option<[DVec3; 4]> {
        let shared: Vec<usize> = (0..3).filter(|&i| t2.contains(&t1[i])).collect();
        if shared.len() != 2 {
            return None;
        }
        let k = (0..3).find(|i| !shared.contains(i))?;
        let (y, u, v) = (t1[k], t1[(k + 1) % 3], t1[(k + 2) % 3]);
        let x = *t2.iter().find(|p| **p != u && **p != v)?;
        let n = (u - y).cross(v - y);
        let len = n.length();
        if len.is_nan() || len <= 0.0 {
            return None;
        }
        let n = n / len;
        // t2 must wind like t1 (it traverses the shared edge v → u) and lie in its plane.
        let n2 = (t2[1] - t2[0]).cross(t2[2] - t2[0]);
        if n2.dot(n) <= 0.0 || n.dot(x - u).abs() > tol {
            return None;
        }
        let quad = [y, u, x, v];
        let convex = (0..4).all(|i| {
            let (a, b, c) = (quad[i], quad[(i + 1) % 4], quad[(i + 2) % 4]);
            (b - a).cross(c - b).dot(n) > 0.0
        });
        convex.then_some(quad)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_split_rectangle_merges_and_other_pairs_do_not() {
        let (a, b, c, d) = (
            DVec3::new(0.0, 0.0, 0.0),
            DVec3::new(2.0, 0.0, 0.0),
            DVec3::new(2.0, 1.0, 0.0),
            DVec3::new(0.0, 1.0, 0.0),
        );
        let q = Element::merge_triangles([a, b, c], [a, c, d], 1e-12).unwrap();
        // The same region in the same winding: corners a, b, c, d up to rotation.
        let start = q.iter().position(|p| *p == a).unwrap();
        let rotated: Vec<DVec3> = (0..4).map(|i| q[(start + i) % 4]).collect();
        assert_eq!(rotated, vec![a, b, c, d]);
        // Opposite winding, a fold out of the plane, a non-convex union, no shared edge.
        assert!(Element::merge_triangles([a, b, c], [a, d, c], 1e-12).is_none());
        let up = DVec3::new(0.0, 1.0, 0.5);
        assert!(Element::merge_triangles([a, b, c], [a, c, up], 1e-12).is_none());
        let dent = DVec3::new(2.5, 1.8, 0.0);
        assert!(Element::merge_triangles([a, b, c], [a, c, dent], 1e-12).is_none());
        assert!(Element::merge_triangles([a, b, c], [d, up, dent], 1e-12).is_none());
    }
}

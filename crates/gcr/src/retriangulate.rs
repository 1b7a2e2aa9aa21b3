//! Re-triangulation of the scene's faces down to a local edge length (sec. 4.3.1, fig. B.5).
//!
//! The dissertation splits quads at their centre until a sub-patch is no larger than the shading
//! network's simplex "under" it. Our scenes are triangulated on load, so we split triangles 1 → 4
//! at edge midpoints (which keeps the sub-triangles' shape, unlike centre splits that produce
//! slivers) until the longest edge is no longer than the smallest target length at its corners and centroid.
//! Midpoints are shared between neighbouring sub-triangles of one face, so a face whose
//! sub-triangles all reach the same depth is a conforming mesh; where depths differ, T-junctions
//! remain (as in the dissertation's quad scheme). They only affect colour interpolation.

use glam::DVec3;
use std::collections::HashMap;

/// Limits for `retriangulate`.
#[derive(Clone, Copy, Debug)]
pub struct RetriangulateLimits {
    /// Maximum number of 1 → 4 splits of one scene face (depth 8 ⇒ up to 65 536 pieces).
    pub max_depth: u32,
    /// Stop splitting once the whole output has this many triangles (a memory guard).
    pub max_triangles: usize,
}

impl Default for RetriangulateLimits {
    fn default() -> Self {
        Self {
            max_depth: 7,
            max_triangles: 2_000_000,
        }
    }
}

/// Output of [`retriangulate`]: positions, triangles, and the source face of each triangle.
#[derive(Clone, Debug, Default)]
pub struct Triangulation {
    /// Vertex positions.
    pub positions: Vec<DVec3>,
    /// Vertex indices per triangle, in the winding of the source face.
    pub triangles: Vec<[u32; 3]>,
    /// Source face of each triangle.
    pub face_of_triangle: Vec<u32>,
}

/// Splits every face `faces[f] = [a, b, c]` until its longest edge is at most
/// `target_edge(centroid)`. `target_edge` should return the shading network's local edge length
/// (the mean edge length `d_i` of the best-matching cell, eq. 2.10); values ≤ 0 or non-finite
/// stop the splitting of that triangle.
pub fn retriangulate(
    faces: &[[DVec3; 3]],
    target_edge: impl Fn(DVec3) -> f64,
    limits: RetriangulateLimits,
) -> Triangulation {
    let mut out = Triangulation::default();
    // Number of triangles the output will have once every pending split is finished.
    let mut leaves = 0usize;
    for (f, tri) in faces.iter().enumerate() {
        // Vertex dedup is per face: faces are separate surfaces with their own normals.
        leaves += 1;
        let mut face_builder = FaceBuilder {
            out: &mut out,
            midpoints: HashMap::new(),
            leaves: &mut leaves,
        };
        let ids = tri.map(|p| face_builder.push(p));
        split(&mut face_builder, ids, 0, f as u32, &target_edge, &limits);
    }
    out
}

struct FaceBuilder<'a> {
    out: &'a mut Triangulation,
    midpoints: HashMap<(u32, u32), u32>,
    leaves: &'a mut usize,
}

impl FaceBuilder<'_> {
    fn push(&mut self, p: DVec3) -> u32 {
        self.out.positions.push(p);
        (self.out.positions.len() - 1) as u32
    }

    fn midpoint(&mut self, a: u32, b: u32) -> u32 {
        let key = (a.min(b), a.max(b));
        if let Some(&m) = self.midpoints.get(&key) {
            return m;
        }
        let p = 0.5 * (self.out.positions[a as usize] + self.out.positions[b as usize]);
        let m = self.push(p);
        self.midpoints.insert(key, m);
        m
    }
}

fn split(
    b: &mut FaceBuilder<'_>,
    [i0, i1, i2]: [u32; 3],
    depth: u32,
    face: u32,
    target_edge: &impl Fn(DVec3) -> f64,
    limits: &RetriangulateLimits,
) {
    let [p0, p1, p2] = [i0, i1, i2].map(|i| b.out.positions[i as usize]);
    let longest = p0.distance(p1).max(p1.distance(p2)).max(p2.distance(p0));
    // The finest length asked for anywhere on the triangle (corners and centroid), so that a
    // small feature near a corner of a large triangle is not missed by a centroid-only test.
    let target = [p0, p1, p2, (p0 + p1 + p2) / 3.0]
        .map(&target_edge)
        .into_iter()
        .fold(f64::INFINITY, f64::min);
    let wants_split = target.is_finite() && target > 0.0 && longest > target;
    // Each split adds three triangles net; stop before the global budget would be exceeded.
    let room = *b.leaves + 3 <= limits.max_triangles;
    if wants_split && depth < limits.max_depth && room {
        *b.leaves += 3;
        let m01 = b.midpoint(i0, i1);
        let m12 = b.midpoint(i1, i2);
        let m20 = b.midpoint(i2, i0);
        split(b, [i0, m01, m20], depth + 1, face, target_edge, limits);
        split(b, [m01, i1, m12], depth + 1, face, target_edge, limits);
        split(b, [m20, m12, i2], depth + 1, face, target_edge, limits);
        split(b, [m01, m12, m20], depth + 1, face, target_edge, limits);
    } else {
        b.out.triangles.push([i0, i1, i2]);
        b.out.face_of_triangle.push(face);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn area(t: &Triangulation) -> f64 {
        t.triangles
            .iter()
            .map(|&[a, b, c]| {
                let [a, b, c] = [a, b, c].map(|i| t.positions[i as usize]);
                0.5 * (b - a).cross(c - a).length()
            })
            .sum()
    }

    #[test]
    fn uniform_target_splits_to_the_requested_edge_length_and_keeps_area() {
        let tri = [DVec3::ZERO, DVec3::X, DVec3::Y];
        let t = retriangulate(&[tri], |_| 0.2, RetriangulateLimits::default());
        // Longest edge sqrt(2) → needs 3 halvings (0.177 ≤ 0.2): 4^3 triangles.
        assert_eq!(t.triangles.len(), 64);
        assert!((area(&t) - 0.5).abs() < 1e-12);
        for &[a, b, c] in &t.triangles {
            let [a, b, c] = [a, b, c].map(|i| t.positions[i as usize]);
            let longest = a.distance(b).max(b.distance(c)).max(c.distance(a));
            assert!(longest <= 0.2 + 1e-12);
            // Winding kept: normal still +z.
            assert!((b - a).cross(c - a).z > 0.0);
        }
        // Uniform depth → conforming grid: V = (n+1)(n+2)/2 with n = 8 segments per edge.
        assert_eq!(t.positions.len(), 45);
    }

    #[test]
    fn adaptive_target_refines_only_where_asked() {
        let tri = [
            DVec3::ZERO,
            DVec3::new(4.0, 0.0, 0.0),
            DVec3::new(0.0, 4.0, 0.0),
        ];
        let fine_near_origin = |p: DVec3| if p.length() < 1.0 { 0.1 } else { 10.0 };
        let t = retriangulate(&[tri], fine_near_origin, RetriangulateLimits::default());
        assert!((area(&t) - 8.0).abs() < 1e-9);
        assert!(t.triangles.len() > 16, "refined near the origin");
        assert!(t.triangles.len() < 4usize.pow(7), "not refined everywhere");
    }

    #[test]
    fn limits_and_bad_targets_stop_splitting() {
        let tri = [DVec3::ZERO, DVec3::X, DVec3::Y];
        let t = retriangulate(&[tri], |_| f64::NAN, RetriangulateLimits::default());
        assert_eq!(t.triangles.len(), 1);
        let t = retriangulate(
            &[tri],
            |_| 1e-9,
            RetriangulateLimits {
                max_depth: 20,
                max_triangles: 100,
            },
        );
        assert!(t.triangles.len() <= 100);
        assert!((area(&t) - 0.5).abs() < 1e-12);
    }
}

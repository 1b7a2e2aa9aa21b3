//! The shading network's geometry as the FEM sees it (sec. 3.2, 3.9.4): cells with centres,
//! widths and learned normals, the simplices of its topology (triangles, k = 2, in 3-D; segments,
//! k = 1, in Flatland, whose points lie in the z = 0 plane), and the per-cell properties
//! the integration criterion needs — surface roughness SR, its diffusion FSR, depth flags DF and
//! sub-network ids — plus the "breaking operator" the dissertation asks for (sec. 4.4.2).
//!
//! The dissertation updates SR at the best-matching unit during training and DF on insertion and
//! deletion. We recompute all of them from the current topology at every FEM step instead: it is
//! O(cells + triangles), exact (no stale values after cells moved), and the FEM step is the only
//! consumer.

use crate::config::Breaking;
use glam::DVec3;
use std::collections::{HashMap, VecDeque};

/// The shading network frozen for one FEM step.
#[derive(Clone, Debug, Default)]
pub struct ShadingGeometry {
    /// Cell centres ŵ_k (eq. 3.20).
    pub centres: Vec<DVec3>,
    /// Gaussian widths d̂_k: the mean incident edge length (eq. 2.10).
    pub widths: Vec<f64>,
    /// Unit normals learned by the output layer (sec. 3.2); zero where unknown.
    pub normals: Vec<DVec3>,
    /// Topology dimension: 2 (triangles) or 1 (Flatland segments).
    pub k: usize,
    /// The simplices that survive the breaking operator, oriented so that their geometric normal
    /// agrees with the mean learned normal of their corners. Only the first `k + 1` entries of
    /// each are used.
    pub simplices: Vec<[usize; 3]>,
    /// Sub-network id per cell (connected components over `simplices`; isolated cells get their
    /// own id).
    pub component: Vec<u32>,
    /// Surface roughness SR_i: the root-mean-square angle (radians) between the normals of the
    /// simplices around cell i and their mean (sec. 3.9.4).
    pub roughness: Vec<f64>,
    /// Fuzzy surface roughness FSR_i: SR diffused over the edges (sec. 3.9.4).
    pub fuzzy_roughness: Vec<f64>,
    /// Depth flag DF_i: edges to the nearest boundary cell (0 on the boundary).
    pub depth: Vec<u32>,
}

impl ShadingGeometry {
    /// Builds the geometry from the network's cells and its `k`-simplices (`k` = 1 or 2; for
    /// `k` = 1 the third index of each simplex is ignored).
    ///
    /// `spans_gap(a, b, n)` answers whether the straight edge between two cell centres a and b
    /// (mean learned normal n) leaves the scene's surfaces; it is only consulted when
    /// `breaking.enabled`.
    pub fn new(
        centres: Vec<DVec3>,
        widths: Vec<f64>,
        normals: Vec<DVec3>,
        k: usize,
        simplices: &[[usize; 3]],
        breaking: Breaking,
        spans_gap: impl Fn(DVec3, DVec3, DVec3) -> bool,
    ) -> Self {
        assert!(k == 1 || k == 2, "shading networks have k = 1 or k = 2");
        let n = centres.len();
        let normals: Vec<DVec3> = normals.into_iter().map(|v| v.normalize_or_zero()).collect();
        let mut gap_cache: HashMap<(usize, usize), bool> = HashMap::new();
        let mut kept = Vec::with_capacity(simplices.len());
        for simplex in simplices {
            let s = &simplex[..=k];
            if s.iter().any(|&i| i >= n) || (1..s.len()).any(|i| s[..i].contains(&s[i])) {
                continue;
            }
            let pairs = simplex_edges(s);
            if breaking.enabled {
                let cos_max = breaking.max_normal_angle.cos();
                if pairs
                    .iter()
                    .any(|&(i, j)| normals[i].dot(normals[j]) < cos_max)
                {
                    continue;
                }
                let gap = pairs.iter().any(|&(i, j)| {
                    *gap_cache.entry((i.min(j), i.max(j))).or_insert_with(|| {
                        spans_gap(
                            centres[i],
                            centres[j],
                            (normals[i] + normals[j]).normalize_or_zero(),
                        )
                    })
                });
                if gap {
                    continue;
                }
            }
            // Orient by the learned normals (the network's simplices carry no orientation).
            let learned: DVec3 = s.iter().map(|&i| normals[i]).sum();
            let mut oriented = *simplex;
            if geometric_normal(&centres, &oriented, k).dot(learned) < 0.0 {
                oriented.swap(0, 1);
            }
            kept.push(oriented);
        }
        let mut geo = Self {
            centres,
            widths,
            normals,
            k,
            simplices: kept,
            component: Vec::new(),
            roughness: Vec::new(),
            fuzzy_roughness: Vec::new(),
            depth: Vec::new(),
        };
        geo.component = geo.components();
        geo.roughness = geo.surface_roughness();
        geo.fuzzy_roughness = geo.diffuse_roughness(0.25, 1e-4, 200);
        geo.depth = geo.depth_flags();
        geo
    }

    /// Number of cells.
    pub fn len(&self) -> usize {
        self.centres.len()
    }

    /// True when there are no cells.
    pub fn is_empty(&self) -> bool {
        self.centres.is_empty()
    }

    /// The cells of simplex `t` (k + 1 of them).
    pub fn simplex(&self, t: usize) -> &[usize] {
        &self.simplices[t][..=self.k]
    }

    /// Unit normal of simplex `t` (zero when degenerate). Flatland segments lie in z = 0 and
    /// their normal is the edge direction turned by +90°.
    pub fn simplex_normal(&self, t: usize) -> DVec3 {
        geometric_normal(&self.centres, &self.simplices[t], self.k).normalize_or_zero()
    }

    /// Simplices incident to each cell.
    pub fn incident_simplices(&self) -> Vec<Vec<usize>> {
        let mut inc = vec![Vec::new(); self.len()];
        for t in 0..self.simplices.len() {
            for &i in self.simplex(t) {
                inc[i].push(t);
            }
        }
        inc
    }

    /// Edge adjacency over the surviving simplices (sorted, deduplicated).
    pub fn neighbours(&self) -> Vec<Vec<usize>> {
        let mut nb = vec![Vec::new(); self.len()];
        for t in 0..self.simplices.len() {
            for (i, j) in simplex_edges(self.simplex(t)) {
                nb[i].push(j);
                nb[j].push(i);
            }
        }
        for v in &mut nb {
            v.sort_unstable();
            v.dedup();
        }
        nb
    }

    fn components(&self) -> Vec<u32> {
        let nb = self.neighbours();
        let mut comp = vec![u32::MAX; self.len()];
        let mut next = 0u32;
        for start in 0..self.len() {
            if comp[start] != u32::MAX {
                continue;
            }
            comp[start] = next;
            let mut queue = VecDeque::from([start]);
            while let Some(i) = queue.pop_front() {
                for &j in &nb[i] {
                    if comp[j] == u32::MAX {
                        comp[j] = next;
                        queue.push_back(j);
                    }
                }
            }
            next += 1;
        }
        comp
    }

    fn surface_roughness(&self) -> Vec<f64> {
        let inc = self.incident_simplices();
        inc.iter()
            .map(|ts| {
                let ns: Vec<DVec3> = ts
                    .iter()
                    .map(|&t| self.simplex_normal(t))
                    .filter(|n| *n != DVec3::ZERO)
                    .collect();
                if ns.len() < 2 {
                    return 0.0;
                }
                let mean = ns.iter().copied().sum::<DVec3>().normalize_or_zero();
                let ms = ns
                    .iter()
                    .map(|n| n.dot(mean).clamp(-1.0, 1.0).acos().powi(2))
                    .sum::<f64>()
                    / ns.len() as f64;
                ms.sqrt()
            })
            .collect()
    }

    /// FSR: starts from SR as a potential and lets it flow along edges with `strength` until the
    /// mean absolute flow of a sweep falls below `tolerance` (sec. 3.9.4). The result never falls
    /// below the local SR: blurring must not hide a rough spot from the cell that has it.
    fn diffuse_roughness(&self, strength: f64, tolerance: f64, max_sweeps: usize) -> Vec<f64> {
        let nb = self.neighbours();
        let mut p = self.roughness.clone();
        for _ in 0..max_sweeps {
            let mut next = p.clone();
            let mut flow = 0.0;
            for i in 0..p.len() {
                if nb[i].is_empty() {
                    continue;
                }
                let mean = nb[i].iter().map(|&j| p[j]).sum::<f64>() / nb[i].len() as f64;
                let d = strength * (mean - p[i]);
                next[i] += d;
                flow += d.abs();
            }
            p = next;
            if flow / (p.len().max(1) as f64) < tolerance {
                break;
            }
        }
        p.iter()
            .zip(&self.roughness)
            .map(|(f, s)| f.max(*s))
            .collect()
    }

    /// DF: breadth-first distance (in edges) from the boundary. A boundary cell lies on a facet
    /// (an edge of a triangle, an end point of a segment) used by exactly one simplex, or belongs
    /// to no simplex at all. On a closed surface every cell keeps `u32::MAX` ("infinitely deep").
    fn depth_flags(&self) -> Vec<u32> {
        let mut facet_use: HashMap<(usize, usize), u32> = HashMap::new();
        for t in 0..self.simplices.len() {
            let s = self.simplex(t);
            if self.k == 2 {
                for (i, j) in simplex_edges(s) {
                    *facet_use.entry((i.min(j), i.max(j))).or_default() += 1;
                }
            } else {
                for &i in s {
                    *facet_use.entry((i, i)).or_default() += 1;
                }
            }
        }
        let mut depth = vec![u32::MAX; self.len()];
        let mut queue = VecDeque::new();
        let inc = self.incident_simplices();
        for i in 0..self.len() {
            if inc[i].is_empty() {
                depth[i] = 0;
                queue.push_back(i);
            }
        }
        let mut boundary: Vec<usize> = facet_use
            .iter()
            .filter(|(_, uses)| **uses == 1)
            .flat_map(|(&(i, j), _)| [i, j])
            .collect();
        boundary.sort_unstable();
        boundary.dedup();
        for k in boundary {
            if depth[k] != 0 {
                depth[k] = 0;
                queue.push_back(k);
            }
        }
        let nb = self.neighbours();
        while let Some(i) = queue.pop_front() {
            for &j in &nb[i] {
                if depth[j] == u32::MAX {
                    depth[j] = depth[i] + 1;
                    queue.push_back(j);
                }
            }
        }
        depth
    }
}

/// The vertex pairs (edges) of a simplex given by its cells.
fn simplex_edges(s: &[usize]) -> Vec<(usize, usize)> {
    let mut out = Vec::with_capacity(3);
    for i in 0..s.len() {
        for j in i + 1..s.len() {
            out.push((s[i], s[j]));
        }
    }
    out
}

/// Unnormalised normal of a simplex: the triangle's cross product, or a Flatland segment's
/// direction turned by +90° in the z = 0 plane (left of a→b, as in FORMATS.md).
fn geometric_normal(centres: &[DVec3], s: &[usize; 3], k: usize) -> DVec3 {
    let (a, b) = (centres[s[0]], centres[s[1]]);
    if k == 1 {
        let e = b - a;
        DVec3::new(-e.y, e.x, 0.0)
    } else {
        (b - a).cross(centres[s[2]] - a)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An n×n grid of cells on the z = 0 plane (or folded along x = fold_at by 90°).
    fn grid(n: usize, fold_at: Option<usize>) -> (Vec<DVec3>, Vec<DVec3>, Vec<[usize; 3]>) {
        let mut centres = Vec::new();
        let mut normals = Vec::new();
        for j in 0..n {
            for i in 0..n {
                match fold_at {
                    Some(f) if i > f => {
                        centres.push(DVec3::new(f as f64, j as f64, (i - f) as f64));
                        normals.push(DVec3::NEG_X);
                    }
                    _ => {
                        centres.push(DVec3::new(i as f64, j as f64, 0.0));
                        normals.push(DVec3::Z);
                    }
                }
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
        (centres, normals, tris)
    }

    #[test]
    fn flat_grid_has_zero_roughness_depth_rings_and_one_component() {
        let (c, nrm, t) = grid(7, None);
        let g = ShadingGeometry::new(
            c,
            vec![1.0; 49],
            nrm,
            2,
            &t,
            Breaking::default(),
            |_, _, _| false,
        );
        assert_eq!(g.simplices.len(), 72);
        assert!(g.roughness.iter().all(|&r| r < 1e-12));
        assert!(g.fuzzy_roughness.iter().all(|&r| r < 1e-12));
        assert!(g.component.iter().all(|&c| c == 0));
        // Centre of a 7×7 grid is 3 edges from the border.
        assert_eq!(g.depth[3 * 7 + 3], 3);
        assert_eq!(g.depth[0], 0);
        for t in 0..g.simplices.len() {
            assert!(
                g.simplex_normal(t).z > 0.99,
                "oriented along the learned normals"
            );
        }
    }

    #[test]
    fn breaking_splits_a_folded_network_into_two_flat_pieces() {
        let (c, nrm, t) = grid(8, Some(3));
        let unbroken = ShadingGeometry::new(
            c.clone(),
            vec![1.0; 64],
            nrm.clone(),
            2,
            &t,
            Breaking {
                enabled: false,
                ..Default::default()
            },
            |_, _, _| false,
        );
        assert!(unbroken.component.iter().all(|&k| k == 0));
        assert!(
            unbroken.roughness.iter().any(|&r| r > 0.3),
            "the fold is rough"
        );
        let broken = ShadingGeometry::new(
            c,
            vec![1.0; 64],
            nrm,
            2,
            &t,
            Breaking::default(),
            |_, _, _| false,
        );
        let floor = broken.component[0];
        let wall = broken.component[7];
        assert_ne!(floor, wall);
        assert!(
            broken.roughness.iter().all(|&r| r < 1e-9),
            "each piece is flat"
        );
        // The fold line became a boundary.
        assert_eq!(broken.depth[2 * 8 + 3], 0);
    }

    #[test]
    fn fuzzy_roughness_spreads_but_never_hides_local_roughness() {
        let (c, nrm, t) = grid(8, Some(3));
        let g = ShadingGeometry::new(
            c,
            vec![1.0; 64],
            nrm,
            2,
            &t,
            Breaking {
                enabled: false,
                ..Default::default()
            },
            |_, _, _| false,
        );
        for i in 0..g.len() {
            assert!(g.fuzzy_roughness[i] >= g.roughness[i]);
        }
        // A cell two columns from the fold is smooth locally but rough in the fuzzy sense.
        let i = 4 * 8 + 1;
        assert!(g.roughness[i] < 1e-9 && g.fuzzy_roughness[i] > 1e-3);
    }

    #[test]
    fn gap_test_removes_spanning_triangles() {
        let (c, nrm, t) = grid(6, None);
        // Pretend there is a slit along x = 2.5.
        let g = ShadingGeometry::new(
            c,
            vec![1.0; 36],
            nrm,
            2,
            &t,
            Breaking::default(),
            |a, b, _| (a.x - 2.5) * (b.x - 2.5) < 0.0,
        );
        assert_ne!(g.component[0], g.component[5]);
    }

    #[test]
    fn flatland_chain_folded_at_a_corner() {
        // A floor along +x (normal +y) meeting a wall along +y at x = 0 (normal +x), with the
        // chain's segments given in arbitrary orientation.
        let mut centres = Vec::new();
        let mut normals = Vec::new();
        for i in (1..=4).rev() {
            centres.push(DVec3::new(0.0, i as f64, 0.0));
            normals.push(DVec3::X);
        }
        for i in 0..=4 {
            centres.push(DVec3::new(i as f64, 0.0, 0.0));
            normals.push(DVec3::Y);
        }
        let segs: Vec<[usize; 3]> = (0..8)
            .map(|i| {
                if i % 2 == 0 {
                    [i, i + 1, 0]
                } else {
                    [i + 1, i, 0]
                }
            })
            .collect();
        let g = ShadingGeometry::new(
            centres.clone(),
            vec![1.0; 9],
            normals.clone(),
            1,
            &segs,
            Breaking {
                enabled: false,
                ..Default::default()
            },
            |_, _, _| false,
        );
        assert_eq!(g.simplices.len(), 8);
        for t in 0..8 {
            let n = g.simplex_normal(t);
            let learned: DVec3 = g.simplex(t).iter().map(|&i| g.normals[i]).sum();
            assert!(n.dot(learned) > 0.0, "oriented by the learned normals");
        }
        assert_eq!(g.depth[0], 0);
        assert_eq!(g.depth[8], 0);
        assert_eq!(g.depth[4], 4);
        assert!(g.roughness[4] > 0.5, "the corner cell is rough");
        let broken = ShadingGeometry::new(
            centres,
            vec![1.0; 9],
            normals,
            1,
            &segs,
            Breaking::default(),
            |_, _, _| false,
        );
        assert_ne!(broken.component[0], broken.component[8]);
        assert_eq!(broken.simplices.len(), 7);
    }
}

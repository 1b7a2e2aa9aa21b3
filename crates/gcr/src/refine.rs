//! Refinement of the output mesh where the gathered radiosity varies (beyond the dissertation).
//!
//! The output mesh is cut to the shading network's resolution ([`crate::retriangulate`]), and a
//! viewer interpolates B linearly between its vertices. Where B changes faster than that — a shadow
//! edge, a penumbra — the interpolation is wrong even when every vertex value is right: on
//! cornell-box the bake was 42.6 % off across the short block's shadow where probes at the same
//! points were 4.4 % off (docs/guide/bakes.md). So after B is gathered at the vertices, triangles whose
//! vertex values differ by more than [`RefineLimits::spread`] of their mean are split 1 → 4 at their
//! edge midpoints, B is gathered at the new vertices, and this repeats for
//! [`RefineLimits::levels`] levels. Neighbours keep the mesh conforming: a triangle with two or
//! three split edges is split 1 → 4 too, one with a single split edge is halved towards it
//! (red-green refinement), so no vertex sits on another triangle's edge.

use crate::gather::Gathered;
use crate::retriangulate::Triangulation;
use glam::DVec3;
use std::collections::HashMap;

/// How far [`refine`] goes.
#[derive(Clone, Copy, Debug)]
pub struct RefineLimits {
    /// Splitting rounds (each at most halves an edge).
    pub levels: u32,
    /// A triangle is split when its vertices' B (summed over bands) spread by more than this
    /// fraction of their mean. 0.2: well above the 2 % noise of the default gather's vertices.
    pub spread: f64,
    /// The output may grow to this many times the vertices it started with.
    pub max_growth: f64,
    /// No edge shorter than this (scene units) is split.
    pub min_edge: f64,
    /// The most new vertices one level may gather (what the memory holds; `usize::MAX`: no limit).
    pub max_level_points: usize,
}

impl RefineLimits {
    /// The defaults for a scene of diagonal `diagonal` whose uniform output mesh has edges of
    /// `uniform` (`output::mesh`): 4 levels, 20 % spread, 6× the vertices, edges down to the
    /// uniform edge's 1/16 (what 4 levels reach from the uniform start) and 1/1000 of the
    /// diagonal. From a coarse uniform start (no networks) these resolve cornell-box's shadows
    /// better than 3 levels and 4× from the networks' finer start, in less time
    /// (docs/guide/bakes.md). A model whose own faces are finer than that keeps them as they
    /// are: refining a public 125 000-triangle model's 340 000 vertices down to 1/1000 of its
    /// diagonal gathered 1.3 million more (620 of its 777 s).
    pub fn for_scene(diagonal: f64, uniform: f64) -> Self {
        let levels = 4;
        Self {
            levels,
            spread: 0.2,
            max_growth: 6.0,
            min_edge: (1e-3 * diagonal).max(uniform / f64::from(1u32 << levels)),
            max_level_points: usize::MAX,
        }
    }
}

/// Refines `tri` (module docs), `values[v]` being B at vertex `v`; `gather(points)` returns B at
/// new vertices `(position, source face)`. `finest(p)`: no edge of a triangle whose centroid is
/// `p` is split when its longest edge is at most this (nor below [`RefineLimits::min_edge`]); an
/// image alone needs no edge shorter than a pixel or two where it is seen
/// (`output::mesh::MeshExtent`). Returns the refined triangulation and values.
pub fn refine<E>(
    mut tri: Triangulation,
    mut values: Vec<Gathered>,
    limits: RefineLimits,
    finest: impl Fn(DVec3) -> f64,
    mut gather: impl FnMut(&[(DVec3, u32)]) -> Result<Vec<Gathered>, E>,
) -> Result<(Triangulation, Vec<Gathered>), E> {
    let budget = (tri.positions.len() as f64 * limits.max_growth) as usize;
    let level_of = |v: &Gathered| v.radiosity.iter().sum::<f64>();
    for _ in 0..limits.levels {
        // ⟨Mark the triangles whose vertex values spread, widest first, within the budget⟩
        let floor = 1e-3 * values.iter().map(level_of).sum::<f64>() / values.len().max(1) as f64;
        let mut marked: Vec<(f64, usize)> = tri
            .triangles
            .iter()
            .enumerate()
            .filter_map(|(t, &[a, b, c])| {
                let y = [a, b, c].map(|v| level_of(&values[v as usize]));
                let (lo, hi) = (
                    y.iter().cloned().fold(f64::INFINITY, f64::min),
                    y.iter().cloned().fold(0.0, f64::max),
                );
                let mean = (y[0] + y[1] + y[2]) / 3.0;
                let p = [a, b, c].map(|v| tri.positions[v as usize]);
                let longest = (p[0].distance(p[1]))
                    .max(p[1].distance(p[2]))
                    .max(p[2].distance(p[0]));
                let spread = (hi - lo) / mean.max(floor);
                let finest = limits.min_edge.max(finest((p[0] + p[1] + p[2]) / 3.0));
                (spread > limits.spread && longest > finest).then_some((spread, t))
            })
            .collect();
        if marked.is_empty() {
            break;
        }
        marked.sort_by(|a, b| b.0.total_cmp(&a.0));
        // each red split adds at most 3 vertices (its neighbours' closure a few more)
        let room = (budget.saturating_sub(tri.positions.len())).min(limits.max_level_points) / 3;
        marked.truncate(room);
        if marked.is_empty() {
            break;
        }
        // ⟨Closure: split edges, and every triangle with two or three of them red⟩
        let mut red = vec![false; tri.triangles.len()];
        let mut split: HashMap<(u32, u32), u32> = HashMap::new();
        let key = |a: u32, b: u32| (a.min(b), a.max(b));
        let mut edges: HashMap<(u32, u32), Vec<usize>> = HashMap::new();
        for (s, &[x, y, z]) in tri.triangles.iter().enumerate() {
            for (p, q) in [(x, y), (y, z), (z, x)] {
                edges.entry(key(p, q)).or_default().push(s);
            }
        }
        let mut pending: Vec<usize> = marked.iter().map(|m| m.1).collect();
        let mut new_points: Vec<(DVec3, u32)> = Vec::new();
        while let Some(t) = pending.pop() {
            if red[t] {
                continue;
            }
            red[t] = true;
            let [a, b, c] = tri.triangles[t];
            for (u, v) in [(a, b), (b, c), (c, a)] {
                split.entry(key(u, v)).or_insert_with(|| {
                    let id = (tri.positions.len() + new_points.len()) as u32;
                    let mid = 0.5 * (tri.positions[u as usize] + tri.positions[v as usize]);
                    new_points.push((mid, tri.face_of_triangle[t]));
                    id
                });
            }
            // neighbours now with two split edges become red
            for (u, v) in [(a, b), (b, c), (c, a)] {
                for &s in &edges[&key(u, v)] {
                    let [x, y, z] = tri.triangles[s];
                    let n = [(x, y), (y, z), (z, x)]
                        .iter()
                        .filter(|(p, q)| split.contains_key(&key(*p, *q)))
                        .count();
                    if !red[s] && n >= 2 {
                        pending.push(s);
                    }
                }
            }
        }
        // ⟨B at the new vertices⟩
        let gathered = gather(&new_points)?;
        tri.positions.extend(new_points.iter().map(|p| p.0));
        values.extend(gathered);
        // ⟨Red triangles 1 → 4, green ones (one split edge) 1 → 2, windings kept⟩
        split_triangles(&mut tri, &split);
    }
    Ok((tri, values))
}

/// Replaces every triangle with split edges (`split`: edge → its midpoint) by its pieces: 1 → 4
/// with three, 1 → 2 towards the midpoint with one (the closure leaves none with two).
fn split_triangles(tri: &mut Triangulation, split: &HashMap<(u32, u32), u32>) {
    let key = |a: u32, b: u32| (a.min(b), a.max(b));
    let mut triangles = Vec::with_capacity(tri.triangles.len() * 2);
    let mut faces = Vec::with_capacity(tri.triangles.len() * 2);
    for (t, &[a, b, c]) in tri.triangles.iter().enumerate() {
        let f = tri.face_of_triangle[t];
        let mid = |u: u32, v: u32| split.get(&key(u, v)).copied();
        let pieces: Vec<[u32; 3]> = match (mid(a, b), mid(b, c), mid(c, a)) {
            (Some(ab), Some(bc), Some(ca)) => {
                vec![[a, ab, ca], [ab, b, bc], [ca, bc, c], [ab, bc, ca]]
            }
            (Some(ab), None, None) => vec![[a, ab, c], [ab, b, c]],
            (None, Some(bc), None) => vec![[a, b, bc], [a, bc, c]],
            (None, None, Some(ca)) => vec![[a, b, ca], [ca, b, c]],
            _ => vec![[a, b, c]],
        };
        faces.extend(std::iter::repeat_n(f, pieces.len()));
        triangles.extend(pieces);
    }
    tri.triangles = triangles;
    tri.face_of_triangle = faces;
}

#[cfg(test)]
mod tests {
    use super::*;

    fn g(b: f64) -> Gathered {
        Gathered {
            radiosity: [b; 3],
            ..Gathered::default()
        }
    }

    /// A level gathers at most [`RefineLimits::max_level_points`] new vertices (what the memory
    /// holds): the unit square's two triangles across a shadow edge split into 5 new vertices
    /// in one level, into 3 (one triangle, the widest spread) when 3 fit.
    #[test]
    fn a_level_gathers_no_more_vertices_than_fit() {
        let b = |p: DVec3| if p.x + 0.3 * p.y < 0.5 { 1.0 } else { 0.0 };
        let square = Triangulation {
            positions: vec![DVec3::ZERO, DVec3::X, DVec3::new(1.0, 1.0, 0.0), DVec3::Y],
            triangles: vec![[0, 1, 2], [0, 2, 3]],
            face_of_triangle: vec![0, 0],
        };
        let values: Vec<Gathered> = square.positions.iter().map(|p| g(b(*p))).collect();
        let new_vertices = |max_level_points: usize| {
            let limits = RefineLimits {
                levels: 1,
                spread: 0.2,
                max_growth: 100.0,
                min_edge: 0.0,
                max_level_points,
            };
            let gather =
                |pts: &[(DVec3, u32)]| Ok::<_, ()>(pts.iter().map(|(p, _)| g(b(*p))).collect());
            let (tri, _) = refine(square.clone(), values.clone(), limits, |_| 0.0, gather).unwrap();
            tri.positions.len() - 4
        };
        assert_eq!(new_vertices(usize::MAX), 5);
        assert_eq!(new_vertices(3), 3);
    }

    /// A unit square (two triangles of one face) lit on the left half only (B = 1 for x < 0.5):
    /// refinement concentrates vertices along the edge x = 0.5, keeps the mesh conforming (every
    /// edge is shared by at most two triangles with no vertex inside another's edge), keeps the
    /// area and the windings, and leaves a uniform square alone.
    #[test]
    fn refinement_follows_a_shadow_edge_and_stays_conforming() {
        let b = |p: DVec3| if p.x < 0.5 { 1.0 } else { 0.0 };
        let square = Triangulation {
            positions: vec![DVec3::ZERO, DVec3::X, DVec3::new(1.0, 1.0, 0.0), DVec3::Y],
            triangles: vec![[0, 1, 2], [0, 2, 3]],
            face_of_triangle: vec![0, 0],
        };
        let values: Vec<Gathered> = square.positions.iter().map(|p| g(b(*p))).collect();
        let limits = RefineLimits {
            levels: 4,
            spread: 0.2,
            max_growth: 100.0,
            min_edge: 0.0,
            max_level_points: usize::MAX,
        };
        let (tri, values) = refine(
            square.clone(),
            values,
            limits,
            |_| 0.0,
            |pts| Ok::<_, ()>(pts.iter().map(|(p, _)| g(b(*p))).collect()),
        )
        .unwrap();
        assert_eq!(tri.positions.len(), values.len());
        assert!(tri.triangles.len() > 20, "{}", tri.triangles.len());
        let area: f64 = tri
            .triangles
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|i| tri.positions[i as usize]);
                let n = (b - a).cross(c - a);
                assert!(n.z > 0.0, "winding kept");
                0.5 * n.length()
            })
            .sum();
        assert!((area - 1.0).abs() < 1e-12);
        // conforming: no vertex lies strictly inside an edge of a triangle it does not belong to
        for t in &tri.triangles {
            for (u, v) in [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])] {
                let (p, q) = (tri.positions[u as usize], tri.positions[v as usize]);
                for (w, &r) in tri.positions.iter().enumerate() {
                    if w as u32 == u || w as u32 == v {
                        continue;
                    }
                    let s = (r - p).dot(q - p) / (q - p).length_squared();
                    let off = (p + s * (q - p)).distance(r);
                    assert!(
                        !(s > 1e-9 && s < 1.0 - 1e-9 && off < 1e-12),
                        "T-junction at {r}"
                    );
                }
            }
        }
        // vertices concentrate near x = 0.5
        let near = tri
            .positions
            .iter()
            .filter(|p| (p.x - 0.5).abs() < 0.2)
            .count();
        assert!(
            near * 2 > tri.positions.len(),
            "{near} of {}",
            tri.positions.len()
        );
        // a uniform square is left alone
        let uniform: Vec<Gathered> = square.positions.iter().map(|_| g(1.0)).collect();
        let (same, _) = refine(
            square.clone(),
            uniform,
            limits,
            |_| 0.0,
            |_| Ok::<_, ()>(Vec::new()),
        )
        .unwrap();
        assert_eq!(same.triangles, square.triangles);
    }
}

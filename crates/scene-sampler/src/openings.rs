//! Openings found in a scene's geometry, for sky portals (`gcr solve --portal auto`): the holes a
//! window or a skylight leaves in a wall or a roof. A hole is a loop of boundary edges (edges of
//! one face only) that is planar and whose inside no face covers; its portal is the rectangle in
//! its plane that bounds it, oriented along its longest edge (a portal larger than the opening
//! only costs a few wasted shadow rays: the sky's sampling stays unbiased).
//!
//! Meant for interiors: a hole seen from outside the building would draw the outdoor points'
//! shadow rays into the building. Branching boundaries, non-planar loops and loops on the outline
//! of a surface (the rim of an open floor, the top of an open box) are not openings.

use crate::Scene;
use crate::sample::barycentric;
use glam::DVec3;
use std::collections::HashMap;

/// At most this many openings, the largest first.
const MAX_OPENINGS: usize = 64;

/// The openings of `scene` as portal corners (four, in order around each rectangle), largest
/// first.
pub fn openings(scene: &Scene) -> Vec<[[f64; 3]; 4]> {
    let diag = scene.diagonal();
    let loops = boundary_loops(scene, 1e-9 * diag);
    let mut found: Vec<(f64, [[f64; 3]; 4])> = loops
        .iter()
        .filter_map(|l| rectangle(l, diag))
        .filter(|(_, corners, n)| !covered(scene, centre(corners), *n, 1e-5 * diag))
        .map(|(area, corners, _)| (area, corners.map(|c| c.to_array())))
        .collect();
    found.sort_by(|a, b| b.0.total_cmp(&a.0));
    found.truncate(MAX_OPENINGS);
    found.into_iter().map(|(_, c)| c).collect()
}

/// The closed loops of boundary edges, as vertex positions; vertices within `tol` are one.
fn boundary_loops(scene: &Scene, tol: f64) -> Vec<Vec<DVec3>> {
    let key = |p: DVec3| (p / tol).round().as_i64vec3().to_array();
    let mut ids: HashMap<[i64; 3], u32> = HashMap::new();
    let mut positions = Vec::new();
    let mut id = |p: DVec3| {
        *ids.entry(key(p)).or_insert_with(|| {
            positions.push(p);
            (positions.len() - 1) as u32
        })
    };
    let mut edges: HashMap<(u32, u32), usize> = HashMap::new();
    for f in &scene.faces {
        let v = f.v.map(&mut id);
        for k in 0..3 {
            let (a, b) = (v[k], v[(k + 1) % 3]);
            *edges.entry((a.min(b), a.max(b))).or_insert(0) += 1;
        }
    }
    let mut next: HashMap<u32, Vec<u32>> = HashMap::new();
    for (&(a, b), _) in edges.iter().filter(|(_, n)| **n == 1) {
        next.entry(a).or_default().push(b);
        next.entry(b).or_default().push(a);
    }
    let mut loops = Vec::new();
    let mut seen = std::collections::HashSet::new();
    let mut starts: Vec<u32> = next.keys().copied().collect();
    starts.sort_unstable();
    for start in starts {
        if seen.contains(&start) {
            continue;
        }
        // walk the loop; a vertex of degree ≠ 2 (a branching boundary) ends it unclosed
        let (mut path, mut prev, mut at) = (vec![start], u32::MAX, start);
        let closed = loop {
            seen.insert(at);
            let Some(n) = next.get(&at).filter(|n| n.len() == 2) else {
                break false;
            };
            let to = if n[0] != prev { n[0] } else { n[1] };
            if to == start {
                break true;
            }
            if seen.contains(&to) || path.len() > 10_000 {
                break false;
            }
            path.push(to);
            (prev, at) = (at, to);
        };
        if closed && path.len() >= 3 {
            loops.push(path.iter().map(|&i| positions[i as usize]).collect());
        }
    }
    loops
}

/// The bounding rectangle of a planar loop in its plane, along its longest edge: (area, corners,
/// unit normal); `None` for a loop that is not planar (10⁻³ of its size) or has no area.
fn rectangle(l: &[DVec3], diag: f64) -> Option<(f64, [DVec3; 4], DVec3)> {
    // Newell's normal
    let mut n = DVec3::ZERO;
    for (i, a) in l.iter().enumerate() {
        n += a.cross(l[(i + 1) % l.len()]);
    }
    let area = 0.5 * n.length();
    let n = n.try_normalize()?;
    let c = l.iter().sum::<DVec3>() / l.len() as f64;
    let size = l.iter().map(|p| p.distance(c)).fold(0.0, f64::max);
    if area <= 1e-6 * diag * diag || l.iter().any(|p| n.dot(*p - c).abs() > 1e-3 * size) {
        return None;
    }
    let longest = (0..l.len())
        .map(|i| l[(i + 1) % l.len()] - l[i])
        .max_by(|a, b| a.length_squared().total_cmp(&b.length_squared()))?;
    let u = (longest - n * n.dot(longest)).try_normalize()?;
    let v = n.cross(u);
    let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
    for p in l {
        let q = [u.dot(*p - c), v.dot(*p - c)];
        for k in 0..2 {
            lo[k] = lo[k].min(q[k]);
            hi[k] = hi[k].max(q[k]);
        }
    }
    let at = |a: f64, b: f64| c + u * a + v * b;
    let corners = [
        at(lo[0], lo[1]),
        at(hi[0], lo[1]),
        at(hi[0], hi[1]),
        at(lo[0], hi[1]),
    ];
    Some(((hi[0] - lo[0]) * (hi[1] - lo[1]), corners, n))
}

fn centre(c: &[DVec3; 4]) -> DVec3 {
    0.25 * (c[0] + c[1] + c[2] + c[3])
}

/// Whether a face lies in the plane (n, through p, within `tol`) over the point p.
fn covered(scene: &Scene, p: DVec3, n: DVec3, tol: f64) -> bool {
    scene.faces.iter().any(|f| {
        if f.normal.cross(n).length() > 1e-6 || f.normal.dot(p - f.v[0]).abs() > tol {
            return false;
        }
        let (b1, b2) = barycentric(f.v, p);
        b1 >= -1e-9 && b2 >= -1e-9 && b1 + b2 <= 1.0 + 1e-9
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The shipped side-lit room has one opening, its window (1.2–2.8 × 0.9–2.1 in the z = 5
    /// wall); an open floor (its rim is a loop around faces) has none.
    #[test]
    fn the_window_of_the_side_lit_room_is_found_and_a_floor_rim_is_not() {
        let path = concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../../scenes/side-lit-room.obj"
        );
        let room = crate::load_obj(path).unwrap();
        let found = openings(&room);
        assert_eq!(found.len(), 1, "{found:?}");
        let c = found[0].map(DVec3::from_array);
        assert!(c.iter().all(|p| (p.z - 5.0).abs() < 1e-9), "{c:?}");
        let (lo, hi) = c.iter().fold(
            (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)),
            |(lo, hi), p| (lo.min(*p), hi.max(*p)),
        );
        assert!((lo - DVec3::new(1.2, 0.9, 5.0)).length() < 1e-9, "{lo}");
        assert!((hi - DVec3::new(2.8, 2.1, 5.0)).length() < 1e-9, "{hi}");
        let floor = crate::builtin("wall-floor").unwrap().into_3d().unwrap();
        assert!(openings(&floor).is_empty());
    }
}

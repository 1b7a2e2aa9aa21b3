//! The surface points of a lightmap's texels: each texel a chart covers gets a point on its face,
//! and texels whose point lies under other geometry are left out (filled later by dilation).
//!
//! * **Coverage**: a texel whose centre falls in a face's triangle (in page coordinates) samples
//!   the face there; a texel within a texel's half-diagonal of a triangle but outside every one (a
//!   chart's rim) samples the nearest point of the nearest triangle, so that bilinear filtering at
//!   a chart's edge reads the surface's value, not the empty padding.
//! * **Leaks**: where a wall stands on a floor, the floor's texels under the wall would gather the
//!   dark inside of the wall and smear it out beside the wall ("darkness leaking"), and a room's
//!   floor running under a wall into a lit room would bring its light in. A texel's point casts
//!   four short rays along its face (±t, ±b, one texel long, lifted off the face); when one meets
//!   the back of a face, the point is inside or under a solid: it is moved out along the ray
//!   that left the solid soonest, to just past that face (the visible surface nearest to it), and
//!   the texel is left out only when the moved point is under a solid still (deep under a thick
//!   wall: a texel nobody sees, filled by dilation).

use super::atlas::Atlas;
use glam::{DVec2, DVec3};
use rayon::prelude::*;
use scene_sampler::{Scene, SceneBvh};

/// A texel's sample.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Texel {
    /// Atlas page.
    pub page: u32,
    /// Column and row on the page.
    pub x: u32,
    /// Row (0 at the top of the image).
    pub y: u32,
    /// The surface point.
    pub point: DVec3,
    /// Its face's unit normal.
    pub normal: DVec3,
    /// Its face.
    pub face: u32,
}

/// What the rasterization found per texel: the face and barycentrics (b1, b2) of the point, and
/// the distance in texels from the texel's centre to the face's triangle (0 inside).
#[derive(Clone, Copy)]
struct Candidate {
    face: u32,
    bary: [f64; 2],
    distance: f64,
}

/// Texels farther than this (in texels) from every triangle are not covered: a texel's
/// half-diagonal, so every texel a triangle touches is.
const REACH: f64 = std::f64::consts::FRAC_1_SQRT_2;

/// Every covered texel of every page with its point, those inside geometry left out; with the
/// number left out.
pub fn texels(scene: &Scene, bvh: &SceneBvh, atlas: &Atlas) -> (Vec<Texel>, usize) {
    let (w, h) = (atlas.width as usize, atlas.height as usize);
    let mut covered = Vec::new();
    for page in 0..atlas.pages {
        let mut best: Vec<Option<Candidate>> = vec![None; w * h];
        for (face, uv) in atlas.faces.iter().enumerate() {
            let Some(uv) = uv.filter(|uv| uv.page == page) else {
                continue;
            };
            let t = uv
                .uv
                .map(|c| DVec2::new(f64::from(c[0]) * w as f64, f64::from(c[1]) * h as f64));
            rasterize(t, w, h, |i, bary, distance| {
                let better = best[i].is_none_or(|b| distance < b.distance);
                if better {
                    best[i] = Some(Candidate {
                        face: face as u32,
                        bary,
                        distance,
                    });
                }
            });
        }
        for (i, c) in best.iter().enumerate() {
            if let Some(c) = c {
                let f = &scene.faces[c.face as usize];
                let [b1, b2] = c.bary;
                covered.push(Texel {
                    page,
                    x: (i % w) as u32,
                    y: (i / w) as u32,
                    point: f.v[0] * (1.0 - b1 - b2) + f.v[1] * b1 + f.v[2] * b2,
                    normal: f.normal,
                    face: c.face,
                });
            }
        }
    }
    // ⟨Move the texels under geometry out to the nearest visible surface, or leave them out⟩
    let reach = 1.0 / atlas.texels_per_unit;
    let kept: Vec<Texel> = covered
        .par_iter()
        .filter_map(|t| match exit(scene, bvh, t, reach) {
            None => Some(*t),
            Some(moved) => {
                let out = Texel { point: moved, ..*t };
                exit(scene, bvh, &out, reach).is_none().then_some(out)
            }
        })
        .collect();
    let left_out = covered.len() - kept.len();
    (kept, left_out)
}

/// When a short ray along the face from the texel's point (lifted off the face) meets the back
/// of a face within `reach` (the point is inside or under a solid), the point moved along the
/// ray that meets one soonest to just past that face; `None` when no ray does.
fn exit(scene: &Scene, bvh: &SceneBvh, t: &Texel, reach: f64) -> Option<DVec3> {
    let (tu, tv) = scene_sampler::orthonormal_basis(t.normal);
    let at = (t.point, t.normal, t.face);
    [tu, -tu, tv, -tv]
        .iter()
        .filter_map(|&dir| Some((bvh.solid_exit(scene, at, dir, reach)?, dir)))
        .min_by(|a, b| a.0.total_cmp(&b.0))
        .map(|(d, dir)| t.point + dir * (d + 2.0 * bvh.backoff()))
}

/// Calls `visit(texel index, (b1, b2), distance in texels)` for every texel of a `w × h` page
/// within [`REACH`] of triangle `t` (texel coordinates: texel (x, y) spans [x, x+1) × [y, y+1)),
/// with the barycentrics of its centre clamped to the triangle.
fn rasterize(t: [DVec2; 3], w: usize, h: usize, mut visit: impl FnMut(usize, [f64; 2], f64)) {
    let lo = t[0].min(t[1]).min(t[2]) - DVec2::splat(REACH);
    let hi = t[0].max(t[1]).max(t[2]) + DVec2::splat(REACH);
    let (x0, y0) = (
        (lo.x - 0.5).ceil().max(0.0) as usize,
        (lo.y - 0.5).ceil().max(0.0) as usize,
    );
    let (x1, y1) = (
        ((hi.x - 0.5).floor() as i64).min(w as i64 - 1),
        ((hi.y - 0.5).floor() as i64).min(h as i64 - 1),
    );
    for y in y0 as i64..=y1 {
        for x in x0 as i64..=x1 {
            let c = DVec2::new(x as f64 + 0.5, y as f64 + 0.5);
            let (bary, distance) = closest_on_triangle(c, t);
            if distance <= REACH {
                visit(y as usize * w + x as usize, bary, distance);
            }
        }
    }
}

/// The point of triangle `t` closest to `p`, as barycentrics (b1, b2) of `t[1]`, `t[2]`, and its
/// distance (0 inside). Degenerate triangles give their nearest vertex.
fn closest_on_triangle(p: DVec2, t: [DVec2; 3]) -> ([f64; 2], f64) {
    let (e1, e2) = (t[1] - t[0], t[2] - t[0]);
    let det = e1.perp_dot(e2);
    if det.abs() > 1e-12 {
        let d = p - t[0];
        let b1 = d.perp_dot(e2) / det;
        let b2 = e1.perp_dot(d) / det;
        if b1 >= 0.0 && b2 >= 0.0 && b1 + b2 <= 1.0 {
            return ([b1, b2], 0.0);
        }
    }
    // outside: the nearest point of the three edges
    let edge = |a: DVec2, b: DVec2| {
        let ab = b - a;
        let s = if ab.length_squared() > 0.0 {
            ((p - a).dot(ab) / ab.length_squared()).clamp(0.0, 1.0)
        } else {
            0.0
        };
        (s, (a + ab * s).distance(p))
    };
    let (s01, d01) = edge(t[0], t[1]);
    let (s12, d12) = edge(t[1], t[2]);
    let (s20, d20) = edge(t[2], t[0]);
    if d01 <= d12 && d01 <= d20 {
        ([s01, 0.0], d01)
    } else if d12 <= d20 {
        ([1.0 - s12, s12], d12)
    } else {
        ([0.0, 1.0 - s20], d20)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_closest_point_is_inside_or_on_the_nearest_edge() {
        let t = [DVec2::ZERO, DVec2::new(4.0, 0.0), DVec2::new(0.0, 4.0)];
        let (b, d) = closest_on_triangle(DVec2::new(1.0, 1.0), t);
        assert_eq!(d, 0.0);
        assert!((b[0] - 0.25).abs() < 1e-12 && (b[1] - 0.25).abs() < 1e-12);
        let (b, d) = closest_on_triangle(DVec2::new(2.0, -0.5), t);
        assert!((d - 0.5).abs() < 1e-12 && (b[0] - 0.5).abs() < 1e-12 && b[1] == 0.0);
        let (b, d) = closest_on_triangle(DVec2::new(3.0, 3.0), t);
        assert!((d - 2f64.sqrt()).abs() < 1e-12 && (b[0] - 0.5).abs() < 1e-12);
    }

    #[test]
    fn a_triangle_covers_the_texels_it_touches_and_no_others() {
        // the lower-left half of a 4 × 4 block: 10 centres inside, the diagonal's neighbours
        // within half a diagonal
        let t = [DVec2::ZERO, DVec2::new(4.0, 0.0), DVec2::new(0.0, 4.0)];
        let mut inside = 0;
        let mut all = Vec::new();
        rasterize(t, 8, 8, |i, _, d| {
            inside += usize::from(d == 0.0);
            all.push(i);
        });
        assert_eq!(inside, 10);
        assert!(all.iter().all(|&i| i % 8 < 5 && i / 8 < 5), "{all:?}");
        assert!(all.contains(&(8 + 3)), "the texel the diagonal crosses");
        assert!(
            !all.contains(&(4 * 8 + 4)),
            "a texel only touching a corner's reach"
        );
    }
}

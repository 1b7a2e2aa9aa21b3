//! The automatic camera: a view that sees the lit side of the scene, from inside closed scenes
//! and framing open ones tightly.
//!
//! Candidates are scored by a small ray-traced probe image (24 × 24 rays through the BVH): with
//! `lit` the share of rays that hit the front of a surface some light reaches (display brightness
//! above 0: the outside walls of a closed building under no sky are front faces, but black), and
//! three qualities each divided by its best value over the candidates — the mean display
//! brightness of what the rays hit (B from a quick gather at the faces the candidates see,
//! `output/camera_choice.rs`, and an exposure), the mean hit
//! distance (a view across the room rather than at a wall), and the number of distinct surfaces
//! seen — score = lit² · (½ + ⅙ · (brightness + distance + surfaces)). Candidates:
//!
//! * **outside**: 8 azimuths × 2 elevations (15°, 35°) looking down at the bounding box, each
//!   framing its eight corners tightly (the smallest distance at which they all fit, centred);
//! * **inside**: the 6 points of a 6³ grid in the bounding box that are enclosed (128 rays spread
//!   over the sphere all hit front faces) and farthest from every surface (the largest open
//!   spaces; none closer than 8 % of the diagonal); from
//!   each, 8 azimuths × 2 tilts (0°, −20°), the eye backed off toward the wall behind (70 % of the
//!   free distance) so that the view spans the room.
//!
//! A closed room seen from outside shows only back faces or unlit outer walls (score 0), so an
//! inside view wins there; an open scene has no enclosed point, or its inside views see the
//! background.

use super::raster::PinholeCamera;
use glam::DVec3;
use rayon::prelude::*;
use scene_sampler::{Scene, SceneBvh};

/// Probe image side (rays) for scoring a candidate.
const PROBE: usize = 24;
/// The least distance from an inside camera's open point to every surface, as a share of the
/// scene's diagonal.
const MIN_CLEARANCE: f64 = 0.08;
/// Field of view of an inside camera when none is given (degrees).
const INSIDE_FOV: f64 = 60.0;

/// The chosen camera and how it was found.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AutoCamera {
    /// The camera.
    pub camera: PinholeCamera,
    /// Whether it is inside the scene (a closed scene, or an open one best seen from inside).
    pub inside: bool,
    /// Its probe score in [0, 1] (see the module documentation).
    pub score: f64,
}

/// The automatic camera's candidate views (module docs), each with whether it is inside:
/// [`Candidates::faces_seen`] names the faces whose brightness [`Candidates::best`] reads.
pub struct Candidates {
    views: Vec<(PinholeCamera, bool)>,
    aspect: f64,
}

impl Candidates {
    /// The candidates for `scene` at `aspect` = width / height and `fov` (vertical, degrees;
    /// default 40° outside, 60° inside).
    pub fn new(scene: &Scene, bvh: &SceneBvh, aspect: f64, fov: Option<f64>) -> Self {
        let (lo, hi) = scene.bounds;
        let outside_fov = fov.unwrap_or(super::camera::DEFAULT_FOV);
        let mut views: Vec<(PinholeCamera, bool)> = Vec::new();
        for el in [15.0f64, 35.0] {
            for k in 0..8 {
                let d = direction(45.0 * k as f64, -el);
                views.push((framing(lo, hi, d, DVec3::Y, outside_fov, aspect), false));
            }
        }
        let inside_fov = fov.unwrap_or(INSIDE_FOV);
        for p in open_spaces(scene, bvh) {
            for tilt in [0.0, -20.0] {
                for k in 0..8 {
                    let d = direction(45.0 * k as f64, tilt);
                    if let Some(cam) = backed_off(scene, bvh, p, d, inside_fov) {
                        views.push((cam, true));
                    }
                }
            }
        }
        Self { views, aspect }
    }

    /// The faces whose front some candidate's probe image hits, ascending: the only faces whose
    /// brightness [`Candidates::best`] reads.
    pub fn faces_seen(&self, scene: &Scene, bvh: &SceneBvh) -> Vec<u32> {
        let mut faces: Vec<u32> = (self.views.par_iter())
            .flat_map_iter(|(c, _)| {
                let mut seen = Vec::new();
                probe_hits(scene, bvh, c, self.aspect, |face, _| seen.push(face));
                seen
            })
            .collect();
        faces.sort_unstable();
        faces.dedup();
        faces
    }

    /// The best-scoring candidate for the faces' `brightness` (module docs).
    pub fn best(&self, scene: &Scene, bvh: &SceneBvh, brightness: &[f64]) -> AutoCamera {
        let stats: Vec<Probe> = (self.views.par_iter())
            .map(|(c, _)| probe(scene, bvh, brightness, c, self.aspect))
            .collect();
        let best_of = |f: fn(&Probe) -> f64| stats.iter().map(f).fold(1e-300, f64::max);
        let (b, d, n) = (
            best_of(|p| p.brightness),
            best_of(|p| p.distance),
            best_of(|p| p.surfaces),
        );
        let scores: Vec<f64> = stats
            .iter()
            .map(|p| {
                let quality = (p.brightness / b + p.distance / d + p.surfaces / n) / 6.0;
                p.lit * p.lit * (0.5 + quality)
            })
            .collect();
        let mut best = 0;
        for (i, s) in scores.iter().enumerate() {
            if *s > scores[best] {
                best = i;
            }
        }
        AutoCamera {
            camera: self.views[best].0,
            inside: self.views[best].1,
            score: scores[best],
        }
    }
}

/// The unit direction at azimuth `az` (degrees, about +y from +z) and elevation `el` (degrees,
/// positive upwards).
fn direction(az: f64, el: f64) -> DVec3 {
    let (az, el) = (az.to_radians(), el.to_radians());
    DVec3::new(el.cos() * az.sin(), el.sin(), el.cos() * az.cos())
}

/// A camera looking along `d` that frames the box `[lo, hi]` tightly: the smallest distance at
/// which all eight corners are inside the field of view, the box's projection centred.
pub fn framing(lo: DVec3, hi: DVec3, d: DVec3, up: DVec3, fov: f64, aspect: f64) -> PinholeCamera {
    let d = d.normalize();
    let left = up.cross(d).normalize();
    let u = d.cross(left);
    let ty = (0.5 * fov.to_radians()).tan();
    let tx = aspect * ty;
    let c = 0.5 * (lo + hi);
    let corners: Vec<(f64, f64, f64)> = (0..8)
        .map(|i| {
            let q = DVec3::new(
                if i & 1 == 0 { lo.x } else { hi.x },
                if i & 2 == 0 { lo.y } else { hi.y },
                if i & 4 == 0 { lo.z } else { hi.z },
            ) - c;
            (q.dot(left), q.dot(u), q.dot(d))
        })
        .collect();
    // Along one image axis with half-angle tangent t, the eye offset a and distance s must
    // satisfy |x − a| ≤ (z + s)·t for every corner: s ≥ max(x/t − z) − a/t and
    // s ≥ max(−x/t − z) + a/t, tightest at s = (max(x/t − z) + max(−x/t − z)) / 2.
    let need = |t: f64, coord: &dyn Fn(&(f64, f64, f64)) -> f64| {
        let p = corners
            .iter()
            .map(|q| coord(q) / t - q.2)
            .fold(f64::MIN, f64::max);
        let m = corners
            .iter()
            .map(|q| -coord(q) / t - q.2)
            .fold(f64::MIN, f64::max);
        0.5 * (p + m)
    };
    let extent = (hi - lo).length().max(1e-12);
    let dist = need(tx, &|q| q.0).max(need(ty, &|q| q.1)) * 1.02 + 1e-6 * extent;
    let a = centre_offset(corners.iter().map(|q| (q.0, q.2 + dist)));
    let b = centre_offset(corners.iter().map(|q| (q.1, q.2 + dist)));
    let eye = c + left * a + u * b - d * dist;
    PinholeCamera {
        eye,
        target: eye + d * dist,
        up,
        fov_y_degrees: fov,
    }
}

/// The offset a along one image axis that centres the projections (x − a)/z of `points`
/// `(x, z)`, z > 0 (bisection: the right margin grows with a, the left one shrinks).
fn centre_offset(points: impl Iterator<Item = (f64, f64)> + Clone) -> f64 {
    let (mut lo, mut hi) = points
        .clone()
        .fold((f64::MAX, f64::MIN), |(l, h), (x, _)| (l.min(x), h.max(x)));
    for _ in 0..100 {
        let a = 0.5 * (lo + hi);
        let right = points
            .clone()
            .map(|(x, z)| (x - a) / z)
            .fold(f64::MIN, f64::max);
        let left = points
            .clone()
            .map(|(x, z)| (a - x) / z)
            .fold(f64::MIN, f64::max);
        if right > left {
            lo = a;
        } else {
            hi = a;
        }
    }
    0.5 * (lo + hi)
}

/// `n` directions spread evenly over the sphere (a Fibonacci lattice).
fn sphere_directions(n: usize) -> Vec<DVec3> {
    let golden = std::f64::consts::PI * (3.0 - 5f64.sqrt());
    (0..n)
        .map(|i| {
            let z = 1.0 - (2.0 * i as f64 + 1.0) / n as f64;
            let r = (1.0 - z * z).sqrt();
            let phi = golden * i as f64;
            DVec3::new(r * phi.cos(), z, r * phi.sin())
        })
        .collect()
}

/// Up to 6 points of a 6³ grid over the bounding box that are enclosed (every one of 128 rays
/// spread over the sphere hits the front of a surface), at least [`MIN_CLEARANCE`] of the
/// diagonal from the nearest hit, farthest first.
fn open_spaces(scene: &Scene, bvh: &SceneBvh) -> Vec<DVec3> {
    let (lo, hi) = scene.bounds;
    let dirs = sphere_directions(128);
    let n = 6;
    let grid: Vec<DVec3> = (0..n * n * n)
        .map(|i| {
            let f = |k: usize| (k as f64 + 0.5) / n as f64;
            lo + (hi - lo) * DVec3::new(f(i % n), f(i / n % n), f(i / (n * n)))
        })
        .collect();
    let mut enclosed: Vec<(f64, DVec3)> = grid
        .par_iter()
        .filter_map(|&p| {
            let mut clearance = f64::INFINITY;
            for &d in &dirs {
                let hit = bvh.closest_hit(p, d, f64::INFINITY, u32::MAX)?;
                if scene.faces[hit.face as usize].normal.dot(d) >= 0.0 {
                    return None;
                }
                clearance = clearance.min(hit.t);
            }
            // a nook (behind a block in an open room) is no place for a camera
            (clearance >= MIN_CLEARANCE * scene.diagonal()).then_some((clearance, p))
        })
        .collect();
    enclosed.sort_by(|a, b| b.0.total_cmp(&a.0));
    enclosed.into_iter().take(6).map(|(_, p)| p).collect()
}

/// An inside camera looking along `d` from the open point `p`, backed off toward the wall behind
/// by 70 % of the free distance; `None` when the ray behind does not meet a front face.
fn backed_off(
    scene: &Scene,
    bvh: &SceneBvh,
    p: DVec3,
    d: DVec3,
    fov: f64,
) -> Option<PinholeCamera> {
    let hit = bvh.closest_hit(p, -d, f64::INFINITY, u32::MAX)?;
    if scene.faces[hit.face as usize].normal.dot(-d) >= 0.0 {
        return None;
    }
    let eye = p - d * (0.7 * hit.t);
    Some(PinholeCamera {
        eye,
        target: eye + d,
        up: DVec3::Y,
        fov_y_degrees: fov,
    })
}

/// What a camera's probe image sees.
struct Probe {
    /// Share of rays hitting the front of a surface with a display brightness above 0.
    lit: f64,
    /// Mean display brightness over all rays (0 for misses and back faces).
    brightness: f64,
    /// Mean hit distance of the front hits.
    distance: f64,
    /// Distinct surfaces hit on their front.
    surfaces: f64,
}

/// Traces the probe image of a camera: `front(face, distance)` for every ray that hits the front
/// of a face.
fn probe_hits(
    scene: &Scene,
    bvh: &SceneBvh,
    cam: &PinholeCamera,
    aspect: f64,
    mut front: impl FnMut(u32, f64),
) {
    for j in 0..PROBE {
        for i in 0..PROBE {
            let (sx, sy) = (
                (i as f64 + 0.5) / PROBE as f64,
                (j as f64 + 0.5) / PROBE as f64,
            );
            let d = cam.ray_direction(sx, sy, aspect);
            let Some(hit) = bvh.closest_hit(cam.eye, d, f64::INFINITY, u32::MAX) else {
                continue;
            };
            if scene.faces[hit.face as usize].normal.dot(d) < 0.0 {
                front(hit.face, hit.t);
            }
        }
    }
}

/// Scores the probe image of a camera.
fn probe(
    scene: &Scene,
    bvh: &SceneBvh,
    brightness: &[f64],
    cam: &PinholeCamera,
    aspect: f64,
) -> Probe {
    let (mut front, mut lit, mut light, mut dist) = (0usize, 0usize, 0.0, 0.0);
    let mut surfaces = std::collections::HashSet::new();
    probe_hits(scene, bvh, cam, aspect, |face, t| {
        front += 1;
        let b = brightness.get(face as usize).copied().unwrap_or(0.0);
        lit += usize::from(b > 0.0);
        light += b;
        dist += t;
        surfaces.insert(scene.faces[face as usize].surface);
    });
    let n = (PROBE * PROBE) as f64;
    Probe {
        lit: lit as f64 / n,
        brightness: light / n,
        distance: dist / front.max(1) as f64,
        surfaces: surfaces.len() as f64,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::output::raster::project;

    #[test]
    fn framing_puts_the_box_corners_inside_the_image_and_touches_its_border() {
        let (lo, hi) = (DVec3::new(-1.0, 0.0, 2.0), DVec3::new(3.0, 1.0, 2.5));
        for (d, aspect) in [
            (direction(30.0, -20.0), 1.0),
            (direction(200.0, -35.0), 1.5),
        ] {
            let cam = framing(lo, hi, d, DVec3::Y, 40.0, aspect);
            let (w, h) = ((400.0 * aspect) as u32, 400);
            let (mut xmin, mut xmax, mut ymin, mut ymax) = (f64::MAX, f64::MIN, f64::MAX, f64::MIN);
            for i in 0..8 {
                let q = DVec3::new(
                    if i & 1 == 0 { lo.x } else { hi.x },
                    if i & 2 == 0 { lo.y } else { hi.y },
                    if i & 4 == 0 { lo.z } else { hi.z },
                );
                let s = project(&cam, w, h, q).expect("in front");
                (xmin, xmax) = (xmin.min(s.x), xmax.max(s.x));
                (ymin, ymax) = (ymin.min(s.y), ymax.max(s.y));
            }
            assert!(xmin >= 0.0 && ymin >= 0.0 && xmax <= w as f64 && ymax <= h as f64);
            // Tight: one axis spans at least 95 % of the image, centred.
            let span = ((xmax - xmin) / w as f64).max((ymax - ymin) / h as f64);
            assert!(span > 0.95, "span {span}");
            assert!(((xmin + xmax) / 2.0 - w as f64 / 2.0).abs() < 1.0);
            assert!(((ymin + ymax) / 2.0 - h as f64 / 2.0).abs() < 1.0);
        }
    }
}

//! A small z-buffered software rasterizer: draws a [`ShadedMesh`] from a pinhole camera with
//! perspective-correct interpolation of the vertex radiosity. No GPU, no window, deterministic.
//!
//! Back faces are drawn black: in radiosity only the front side of a face reflects or emits,
//! so a visible back face means the camera looks at the unlit side of a surface.

use crate::mesh::ShadedMesh;
use crate::output::tonemap::Exposure;
use glam::{DVec3, DVec4};

/// A pinhole camera.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PinholeCamera {
    /// Eye position.
    pub eye: DVec3,
    /// Point looked at.
    pub target: DVec3,
    /// Up direction (need not be orthogonal to the view direction).
    pub up: DVec3,
    /// Vertical field of view in degrees.
    pub fov_y_degrees: f64,
}

/// Renders `mesh` to an 8-bit sRGB RGB image of `width × height`, row-major, top row first.
/// Each pixel averages `ss × ss` sub-samples (anti-aliasing). The background is black.
pub fn render(
    mesh: &ShadedMesh,
    camera: &PinholeCamera,
    exposure: &Exposure,
    width: u32,
    height: u32,
    ss: u32,
) -> Vec<u8> {
    let ss = ss.max(1);
    let (w, h) = ((width * ss) as usize, (height * ss) as usize);
    let mut depth = vec![f64::INFINITY; w * h];
    let mut colour = vec![[0.0f64; 3]; w * h];

    let forward = (camera.target - camera.eye).normalize_or(DVec3::NEG_Z);
    let right = forward.cross(camera.up).normalize_or(DVec3::X);
    let up = right.cross(forward);
    let f = 1.0 / (camera.fov_y_degrees.to_radians() * 0.5).tan();
    let aspect = w as f64 / h as f64;
    let near = 1e-4
        * mesh
            .bounds()
            .map_or(1.0, |(lo, hi)| (hi - lo).length().max(1e-12));

    // Radiosity is interpolated first and tone-mapped per sub-sample: the physically meaningful
    // order (tone mapping per vertex would clip highlights before interpolation).
    for &[a, b, c] in &mesh.triangles {
        let idx = [a as usize, b as usize, c as usize];
        let world = idx.map(|i| mesh.positions[i]);
        let normal = (world[1] - world[0]).cross(world[2] - world[0]);
        let front = normal.dot(camera.eye - world[0]) > 0.0;
        let rad = idx.map(|i| if front { mesh.radiosity[i] } else { [0.0; 3] });
        // Camera space: x right, y up, z forward (distance along the view direction).
        let cam: Vec<(DVec3, [f64; 3])> = (0..3)
            .map(|k| {
                let d = world[k] - camera.eye;
                (DVec3::new(d.dot(right), d.dot(up), d.dot(forward)), rad[k])
            })
            .collect();
        if let Some(poly) = clip_near(&cam, near) {
            // Fan-triangulate the clipped polygon (3 or 4 vertices).
            for k in 1..poly.len() - 1 {
                raster_triangle(
                    [poly[0], poly[k], poly[k + 1]],
                    f,
                    aspect,
                    w,
                    h,
                    &mut depth,
                    &mut colour,
                );
            }
        }
    }

    let mut out = vec![0u8; (width * height * 3) as usize];
    let n = (ss * ss) as f64;
    for py in 0..height as usize {
        for px in 0..width as usize {
            let mut acc = [0.0; 3];
            for sy in 0..ss as usize {
                for sx in 0..ss as usize {
                    let i = (py * ss as usize + sy) * w + px * ss as usize + sx;
                    let lin = exposure.linear(colour[i]);
                    for ch in 0..3 {
                        acc[ch] += lin[ch];
                    }
                }
            }
            for ch in 0..3 {
                let v = crate::output::tonemap::srgb_encode(acc[ch] / n);
                out[(py * width as usize + px) * 3 + ch] = (v * 255.0).round() as u8;
            }
        }
    }
    out
}

/// Sutherland–Hodgman clip of a camera-space polygon against the plane z = near.
fn clip_near(poly: &[(DVec3, [f64; 3])], near: f64) -> Option<Vec<(DVec3, [f64; 3])>> {
    let mut out = Vec::with_capacity(4);
    for i in 0..poly.len() {
        let (p, cp) = poly[i];
        let (q, cq) = poly[(i + 1) % poly.len()];
        let (pin, qin) = (p.z >= near, q.z >= near);
        if pin {
            out.push((p, cp));
        }
        if pin != qin {
            let t = (near - p.z) / (q.z - p.z);
            let c = [0, 1, 2].map(|k| cp[k] + t * (cq[k] - cp[k]));
            out.push((p + t * (q - p), c));
        }
    }
    (out.len() >= 3).then_some(out)
}

fn raster_triangle(
    v: [(DVec3, [f64; 3]); 3],
    f: f64,
    aspect: f64,
    w: usize,
    h: usize,
    depth: &mut [f64],
    colour: &mut [[f64; 3]],
) {
    // Screen coordinates (pixels) and 1/z for perspective-correct interpolation.
    let s: [DVec4; 3] = v.map(|(p, _)| {
        let x = (p.x * f / aspect / p.z * 0.5 + 0.5) * w as f64;
        let y = (0.5 - p.y * f / p.z * 0.5) * h as f64;
        DVec4::new(x, y, p.z, 1.0 / p.z)
    });
    let area = edge(s[0], s[1], s[2].x, s[2].y);
    if area.abs() < 1e-18 || !area.is_finite() {
        return;
    }
    let xmin = s
        .iter()
        .map(|p| p.x)
        .fold(f64::INFINITY, f64::min)
        .floor()
        .max(0.0) as usize;
    let xmax = s
        .iter()
        .map(|p| p.x)
        .fold(f64::NEG_INFINITY, f64::max)
        .ceil()
        .min(w as f64) as usize;
    let ymin = s
        .iter()
        .map(|p| p.y)
        .fold(f64::INFINITY, f64::min)
        .floor()
        .max(0.0) as usize;
    let ymax = s
        .iter()
        .map(|p| p.y)
        .fold(f64::NEG_INFINITY, f64::max)
        .ceil()
        .min(h as f64) as usize;
    for y in ymin..ymax {
        for x in xmin..xmax {
            let (cx, cy) = (x as f64 + 0.5, y as f64 + 0.5);
            let b = [
                edge(s[1], s[2], cx, cy) / area,
                edge(s[2], s[0], cx, cy) / area,
                edge(s[0], s[1], cx, cy) / area,
            ];
            if b.iter().any(|&t| t < 0.0) {
                continue;
            }
            let inv_z = b[0] * s[0].w + b[1] * s[1].w + b[2] * s[2].w;
            let z = 1.0 / inv_z;
            let i = y * w + x;
            if z < depth[i] {
                depth[i] = z;
                let mut c = [0.0; 3];
                for k in 0..3 {
                    let wk = b[k] * s[k].w * z;
                    for ch in 0..3 {
                        c[ch] += wk * v[k].1[ch];
                    }
                }
                colour[i] = c;
            }
        }
    }
}

fn edge(a: DVec4, b: DVec4, x: f64, y: f64) -> f64 {
    (b.x - a.x) * (y - a.y) - (b.y - a.y) * (x - a.x)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn quad(colour: [f64; 3]) -> ShadedMesh {
        // A unit square in the z = 0 plane facing +z.
        ShadedMesh {
            positions: vec![
                DVec3::new(-1.0, -1.0, 0.0),
                DVec3::new(1.0, -1.0, 0.0),
                DVec3::new(1.0, 1.0, 0.0),
                DVec3::new(-1.0, 1.0, 0.0),
            ],
            triangles: vec![[0, 1, 2], [0, 2, 3]],
            face_of_triangle: vec![0, 0],
            radiosity: vec![colour; 4],
        }
    }

    #[test]
    fn a_facing_quad_fills_the_centre_and_leaves_the_corners_black() {
        let mesh = quad([std::f64::consts::PI; 3]); // radiance 1
        let cam = PinholeCamera {
            eye: DVec3::new(0.0, 0.0, 4.0),
            target: DVec3::ZERO,
            up: DVec3::Y,
            fov_y_degrees: 30.0,
        };
        let img = render(&mesh, &cam, &Exposure { scale: 1.0 }, 32, 32, 2);
        let px = |x: usize, y: usize| &img[(y * 32 + x) * 3..(y * 32 + x) * 3 + 3];
        assert_eq!(px(16, 16), &[255, 255, 255]);
        // tan(15°)·4 ≈ 1.07 > 1: the square covers almost the whole view but not the corners.
        assert_eq!(px(0, 0), &[0, 0, 0]);
    }

    #[test]
    fn back_faces_are_black_and_geometry_behind_the_eye_is_clipped() {
        let mesh = quad([std::f64::consts::PI; 3]);
        let cam = PinholeCamera {
            eye: DVec3::new(0.0, 0.0, -4.0),
            target: DVec3::ZERO,
            up: DVec3::Y,
            fov_y_degrees: 30.0,
        };
        let img = render(&mesh, &cam, &Exposure { scale: 1.0 }, 16, 16, 1);
        assert!(img.iter().all(|&v| v == 0));
        // Eye inside the square's plane extent, looking along it: nothing crashes, nothing NaN.
        let cam = PinholeCamera {
            eye: DVec3::new(0.0, 0.0, 0.5),
            target: DVec3::new(0.0, 0.0, -1.0),
            up: DVec3::Y,
            fov_y_degrees: 90.0,
        };
        let _ = render(&mesh, &cam, &Exposure { scale: 1.0 }, 16, 16, 1);
    }
}

//! A small z-buffered software rasterizer: draws a [`ShadedMesh`] from a pinhole camera with
//! perspective-correct interpolation of the vertex radiosity. No GPU, no window, deterministic.
//!
//! Back faces are drawn black: in radiosity only the front side of a face reflects or emits,
//! so a visible back face means the camera looks at the unlit side of a surface.
//!
//! Cut-outs: given the scene, a sub-sample on a triangle of a face with an alpha cut-out tests
//! its point (interpolated, perspective-correct, like the radiosity) against the face's mask
//! ([`scene_sampler::Scene::is_hole`]) and lets what lies behind show through a hole, as the
//! per-pixel images and every ray do.
//!
//! [`render_image`] also keeps the depth buffer, so that points and line segments in world space
//! can be drawn over the shaded image with hidden-point removal ([`Image::draw_points`],
//! [`Image::draw_lines`]): the figures of the sample distribution, the shading network and the
//! re-triangulation (figs. 4.12, 4.15) are drawn that way.

use crate::mesh::ShadedMesh;
use crate::output::tonemap::Exposure;
use glam::{DVec3, DVec4};
use scene_sampler::Scene;

/// Anti-aliasing of the 3-D camera image: sub-samples per pixel side.
pub(super) const IMAGE_SUPERSAMPLING: u32 = 2;

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

/// The camera's orthonormal frame and focal factor, shared by the rasterizer and the projection of points.
struct Frame {
    eye: DVec3,
    right: DVec3,
    up: DVec3,
    forward: DVec3,
    /// 1 / tan(fov_y / 2).
    f: f64,
}

impl Frame {
    fn new(camera: &PinholeCamera) -> Self {
        let forward = (camera.target - camera.eye).normalize_or(DVec3::NEG_Z);
        let right = forward.cross(camera.up).normalize_or(DVec3::X);
        let up = right.cross(forward);
        let f = 1.0 / (camera.fov_y_degrees.to_radians() * 0.5).tan();
        Self {
            eye: camera.eye,
            right,
            up,
            forward,
            f,
        }
    }

    /// Camera space: x right, y up, z forward (distance along the view direction).
    fn to_camera(&self, p: DVec3) -> DVec3 {
        let d = p - self.eye;
        DVec3::new(d.dot(self.right), d.dot(self.up), d.dot(self.forward))
    }

    /// Camera space to pixel coordinates (x right, y down, in pixels) and depth z.
    fn to_screen(&self, c: DVec3, w: f64, h: f64) -> DVec3 {
        let aspect = w / h;
        DVec3::new(
            (c.x * self.f / aspect / c.z * 0.5 + 0.5) * w,
            (0.5 - c.y * self.f / c.z * 0.5) * h,
            c.z,
        )
    }
}

/// Projects the world point `p` into a `width × height` image of `camera`: pixel coordinates
/// (x to the right, y downwards, the pixel (i, j) covering [i, i+1) × [j, j+1)) and the depth
/// along the view direction. `None` when `p` is not in front of the camera.
#[cfg(test)]
pub(crate) fn project(camera: &PinholeCamera, width: u32, height: u32, p: DVec3) -> Option<DVec3> {
    let frame = Frame::new(camera);
    let c = frame.to_camera(p);
    (c.z > 0.0).then(|| frame.to_screen(c, f64::from(width), f64::from(height)))
}

/// A rendered image with its depth buffer, to draw overlays on (see [`render_image`]).
#[derive(Clone, Debug)]
pub struct Image {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// 8-bit sRGB RGB, row-major, top row first.
    pub pixels: Vec<u8>,
    /// Per pixel, the nearest depth (distance along the view direction) of the mesh among the
    /// pixel's sub-samples; infinite where only background was hit.
    pub depth: Vec<f64>,
    /// The camera the image was rendered from.
    pub camera: PinholeCamera,
    /// What the image's sub-samples saw.
    pub coverage: Coverage,
}

impl Image {
    /// Whether a point at pixel (x, y) and depth z is in front of the rendered surfaces, up to
    /// a relative depth tolerance `tol` (points lying on a surface need a small positive one).
    fn visible(&self, x: usize, y: usize, z: f64, tol: Option<f64>) -> bool {
        tol.is_none_or(|t| z <= self.depth[y * self.width as usize + x] * (1.0 + t))
    }

    fn blend(&mut self, x: usize, y: usize, colour: [u8; 3], alpha: f64) {
        let i = (y * self.width as usize + x) * 3;
        for ch in 0..3 {
            let old = f64::from(self.pixels[i + ch]);
            let new = old + alpha * (f64::from(colour[ch]) - old);
            self.pixels[i + ch] = new.round().clamp(0.0, 255.0) as u8;
        }
    }

    /// Draws every world point of `points` as a disc of `radius` pixels in `colour`, blended
    /// with opacity `alpha` ∈ [0, 1]. With `depth_tol = Some(t)` a point is drawn only where its
    /// depth is at most (1 + t) times the rendered depth at its pixel (hidden points are left
    /// out); `None` draws all points in front of the camera.
    pub fn draw_points(
        &mut self,
        points: &[DVec3],
        radius: f64,
        colour: [u8; 3],
        alpha: f64,
        depth_tol: Option<f64>,
    ) {
        let frame = Frame::new(&self.camera);
        let (w, h) = (f64::from(self.width), f64::from(self.height));
        let r = radius.max(0.5);
        for &p in points {
            let c = frame.to_camera(p);
            if c.z <= 0.0 {
                continue;
            }
            let s = frame.to_screen(c, w, h);
            let inside = s.x >= 0.0 && s.x < w && s.y >= 0.0 && s.y < h;
            if !inside || !self.visible(s.x as usize, s.y as usize, s.z, depth_tol) {
                continue;
            }
            let (x0, x1) = ((s.x - r).floor().max(0.0), (s.x + r).ceil().min(w));
            let (y0, y1) = ((s.y - r).floor().max(0.0), (s.y + r).ceil().min(h));
            for y in y0 as usize..y1 as usize {
                for x in x0 as usize..x1 as usize {
                    let (dx, dy) = (x as f64 + 0.5 - s.x, y as f64 + 0.5 - s.y);
                    if dx * dx + dy * dy <= r * r {
                        self.blend(x, y, colour, alpha);
                    }
                }
            }
        }
    }

    /// Draws the world-space segments `(a, b)` as one-pixel lines in `colour`, blended with
    /// opacity `alpha`. Each segment is clipped to the front of the camera and sampled every
    /// half pixel; `depth_tol` hides the hidden parts as in [`Image::draw_points`] (per sample,
    /// so a segment running behind an occluder is interrupted there).
    pub fn draw_lines(
        &mut self,
        segments: &[(DVec3, DVec3)],
        colour: [u8; 3],
        alpha: f64,
        depth_tol: Option<f64>,
    ) {
        let frame = Frame::new(&self.camera);
        let (w, h) = (f64::from(self.width), f64::from(self.height));
        let near = 1e-9;
        for &(a, b) in segments {
            let (mut ca, mut cb) = (frame.to_camera(a), frame.to_camera(b));
            if ca.z < near && cb.z < near {
                continue;
            }
            if ca.z < near {
                ca = ca + (near - ca.z) / (cb.z - ca.z) * (cb - ca);
            } else if cb.z < near {
                cb = cb + (near - cb.z) / (ca.z - cb.z) * (ca - cb);
            }
            let (sa, sb) = (frame.to_screen(ca, w, h), frame.to_screen(cb, w, h));
            let len = (sb.truncate() - sa.truncate()).length();
            // Guard against segments that project to absurd lengths near the eye.
            let n = (2.0 * len.min(8.0 * (w + h))).ceil() as usize + 1;
            let mut last = usize::MAX;
            for k in 0..=n {
                // Interpolate in camera space: perspective-correct positions and depths.
                let c = ca.lerp(cb, k as f64 / n as f64);
                let s = frame.to_screen(c, w, h);
                if !(s.x >= 0.0 && s.x < w && s.y >= 0.0 && s.y < h) {
                    continue;
                }
                let (x, y) = (s.x as usize, s.y as usize);
                let idx = y * self.width as usize + x;
                if idx == last || !self.visible(x, y, s.z, depth_tol) {
                    continue;
                }
                last = idx;
                self.blend(x, y, colour, alpha);
            }
        }
    }
}

/// What the sub-samples of an image saw, as fractions of all sub-samples (they sum to 1).
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct Coverage {
    /// The front (lit) side of a surface.
    pub front: f64,
    /// Of those, the ones with B > 0 in some band: what the picture shows lit. The front of a
    /// surface that no light reaches (the outside of a closed building under no sky) is black.
    pub lit: f64,
    /// The back side of a surface (drawn black: the camera is inside a solid or behind a wall).
    pub back: f64,
    /// No surface (the background: the scene's sky or environment map, else black).
    pub nothing: f64,
}

impl Coverage {
    /// A warning when most of the image is black for want of a lit surface (the camera outside a
    /// closed scene, inside a solid, or looking away from everything); `None` otherwise. With
    /// `sky` (the scene has a background light, [`scene_sampler::Light::is_background`]) the
    /// pixels that show no surface show the sky: the warning asks that half of the others be
    /// lit, and that they be at least a tenth of the image.
    pub fn warning(&self, what: &str, sky: bool) -> Option<String> {
        // under a sky, the pixels that show no surface show the sky: only the scene's share counts
        let (shown, nothing) = match sky {
            true => (1.0 - self.nothing, "the sky"),
            false => (1.0, "nothing"),
        };
        (self.lit < 0.5 * shown || shown < 0.1).then(|| {
            format!(
                "{what}: only {:.0} % of the pixels show a lit surface ({:.0} % the front of a \
                 surface no light reaches, {:.0} % {nothing}, {:.0} % back faces, drawn black): \
                 the camera looks away from the scene or from outside its walls; set \
                 --camera-eye and --camera-target (or --auto-camera)",
                100.0 * self.lit,
                100.0 * (self.front - self.lit),
                100.0 * self.nothing,
                100.0 * self.back
            )
        })
    }
}

/// A linear HDR image: radiance L = B/π per pixel (the box-filtered mean of its sub-samples).
#[derive(Clone, Debug)]
pub struct RadianceImage {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Linear RGB radiance, row-major, top row first; 0 where no front face is seen.
    pub radiance: Vec<[f32; 3]>,
    /// What the sub-samples saw.
    pub coverage: Coverage,
}

/// Renders `mesh` to an 8-bit sRGB RGB image of `width × height`, row-major, top row first.
/// Each pixel averages `ss × ss` sub-samples (anti-aliasing). The background is black.
#[cfg(test)]
pub(crate) fn render(
    mesh: &ShadedMesh,
    camera: &PinholeCamera,
    exposure: &Exposure,
    width: u32,
    height: u32,
    ss: u32,
) -> Vec<u8> {
    render_image(mesh, None, camera, exposure, width, height, ss).pixels
}

/// Renders `mesh` to an 8-bit sRGB image of `width × height` (row-major, top row first; each pixel
/// averages `ss × ss` sub-samples), keeping the depth buffer (at the output resolution) for
/// overlays. `cutouts`: the scene `mesh` was made from, whose faces' alpha cut-outs are holes and
/// whose sky or environment map fills the background (`None`: every face solid, the background
/// black).
pub fn render_image(
    mesh: &ShadedMesh,
    cutouts: Option<&Scene>,
    camera: &PinholeCamera,
    exposure: &Exposure,
    width: u32,
    height: u32,
    ss: u32,
) -> Image {
    let samples = Samples::rasterize(mesh, cutouts, camera, width, height, ss);
    let mut out = vec![0u8; (width * height * 3) as usize];
    let mut out_depth = vec![f64::INFINITY; (width * height) as usize];
    for (p, (acc, near)) in samples
        .reduce(|b| exposure.linear(b))
        .into_iter()
        .enumerate()
    {
        for ch in 0..3 {
            let v = crate::output::tonemap::srgb_encode(acc[ch]);
            out[p * 3 + ch] = (v * 255.0).round() as u8;
        }
        out_depth[p] = near;
    }
    Image {
        width,
        height,
        pixels: out,
        depth: out_depth,
        camera: *camera,
        coverage: samples.coverage(),
    }
}

/// Renders `mesh` as linear radiance L = B/π per pixel (no exposure, no clipping; the mean of
/// `ss × ss` sub-samples), for HDR output; `cutouts` as [`render_image`].
pub fn render_radiance(
    mesh: &ShadedMesh,
    cutouts: Option<&Scene>,
    camera: &PinholeCamera,
    width: u32,
    height: u32,
    ss: u32,
) -> RadianceImage {
    let samples = Samples::rasterize(mesh, cutouts, camera, width, height, ss);
    let inv_pi = 1.0 / std::f64::consts::PI;
    let radiance = samples
        .reduce(|b| b.map(|c| if c.is_finite() { c * inv_pi } else { 0.0 }))
        .into_iter()
        .map(|(l, _)| l.map(|c| c as f32))
        .collect();
    RadianceImage {
        width,
        height,
        radiance,
        coverage: samples.coverage(),
    }
}

/// Which of `faces` scene faces show their front at some sub-sample of `mesh`'s image from
/// `camera` (rasterized as [`render_radiance`] rasterizes it, cut-outs and all): the faces whose
/// radiosity that image can show. A refinement of the mesh within its faces leaves this set as it
/// is (up to ties along the faces' shared edges).
pub(crate) fn faces_seen(
    mesh: &ShadedMesh,
    cutouts: Option<&Scene>,
    camera: &PinholeCamera,
    (width, height, ss): (u32, u32, u32),
    faces: usize,
) -> Vec<bool> {
    let mut samples = Samples::rasterize(mesh, cutouts, camera, width, height, ss);
    // ⟨Again, marking every front face within a hair of the nearest depth: coplanar faces that
    // overlap win a sub-sample by rounding, which another triangulation of them changes⟩
    samples.ties = Some(vec![false; faces]);
    samples.draw(mesh, cutouts, camera);
    samples.ties.unwrap_or_default()
}

/// What a sub-sample saw.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Seen {
    Nothing,
    Front,
    Back,
}

/// The sub-sample buffers of one rasterization: radiosity B (0 on back faces), depth and what
/// was seen, at `ss × ss` sub-samples per pixel.
struct Samples {
    width: usize,
    height: usize,
    ss: usize,
    colour: Vec<[f64; 3]>,
    depth: Vec<f64>,
    seen: Vec<Seen>,
    /// Set: drawing marks the front faces whose depth at a sub-sample is within [`TIE`] of the
    /// nearest drawn there, and changes nothing else ([`faces_seen`]).
    ties: Option<Vec<bool>>,
}

/// Relative depth within which [`faces_seen`] counts a face as seen at a sub-sample.
const TIE: f64 = 1e-4;

impl Samples {
    fn rasterize(
        mesh: &ShadedMesh,
        cutouts: Option<&Scene>,
        camera: &PinholeCamera,
        width: u32,
        height: u32,
        ss: u32,
    ) -> Self {
        let ss = ss.max(1);
        let (w, h) = ((width * ss) as usize, (height * ss) as usize);
        let mut buf = Self {
            width: width as usize,
            height: height as usize,
            ss: ss as usize,
            colour: vec![[0.0f64; 3]; w * h],
            depth: vec![f64::INFINITY; w * h],
            seen: vec![Seen::Nothing; w * h],
            ties: None,
        };
        buf.draw(mesh, cutouts, camera);
        if let Some(scene) = cutouts {
            buf.show_background(scene, camera);
        }
        buf
    }

    /// Gives the sub-samples that see no surface the light of the scene's background lights (a
    /// sky, an environment map: [`scene_sampler::Light::is_background`]) in their direction, as
    /// B = π·L, which is what a per-pixel image's escaping rays bring.
    fn show_background(&mut self, scene: &Scene, camera: &PinholeCamera) {
        let lights: Vec<_> = (scene.lights.iter())
            .filter(|l| l.is_background())
            .collect();
        if lights.is_empty() {
            return;
        }
        let (w, h) = (self.width * self.ss, self.height * self.ss);
        let aspect = w as f64 / h as f64;
        for (i, (seen, colour)) in self.seen.iter().zip(&mut self.colour).enumerate() {
            if *seen == Seen::Nothing {
                let (x, y) = ((i % w) as f64 + 0.5, (i / w) as f64 + 0.5);
                let d = camera.ray_direction(x / w as f64, y / h as f64, aspect);
                let d = d.normalize();
                for l in &lights {
                    let e = l.escaped(d);
                    for (c, v) in colour.iter_mut().zip(e) {
                        *c += v;
                    }
                }
            }
        }
    }

    /// Draws `mesh`'s triangles into the buffers (depth-tested).
    fn draw(&mut self, mesh: &ShadedMesh, cutouts: Option<&Scene>, camera: &PinholeCamera) {
        let (w, h) = (self.width * self.ss, self.height * self.ss);
        let frame = Frame::new(camera);
        let aspect = w as f64 / h as f64;
        let near = 1e-4
            * mesh
                .bounds()
                .map_or(1.0, |(lo, hi)| (hi - lo).length().max(1e-12));
        // Radiosity is interpolated first and tone-mapped per sub-sample: the physically
        // meaningful order (tone mapping per vertex would clip highlights before interpolation).
        for (t, &[a, b, c]) in mesh.triangles.iter().enumerate() {
            let idx = [a as usize, b as usize, c as usize];
            let world = idx.map(|i| mesh.positions[i]);
            let normal = (world[1] - world[0]).cross(world[2] - world[0]);
            let front = normal.dot(camera.eye - world[0]) > 0.0;
            let rad = idx.map(|i| if front { mesh.radiosity[i] } else { [0.0; 3] });
            let seen = if front { Seen::Front } else { Seen::Back };
            // the face's holes, when it has a cut-out: tested at each sub-sample's point
            let face = mesh.face_of_triangle.get(t).copied();
            let hole = match (cutouts, face) {
                (Some(scene), Some(f)) if scene.faces[f as usize].cutout.is_some() => {
                    Some(move |p: DVec3| scene.is_hole(f, p))
                }
                _ => None,
            };
            let hole = hole.as_ref().map(|h| h as &dyn Fn(DVec3) -> bool);
            let face = face.unwrap_or(u32::MAX);
            // per vertex: its radiosity, then its world position (affine in camera space, so
            // clipped and interpolated as the radiosity is)
            let cam: Vec<(DVec3, [f64; 6])> = (0..3)
                .map(|k| {
                    let (r, p) = (rad[k], world[k]);
                    (frame.to_camera(p), [r[0], r[1], r[2], p.x, p.y, p.z])
                })
                .collect();
            if let Some(poly) = clip_near(&cam, near) {
                // Fan-triangulate the clipped polygon (3 or 4 vertices).
                for k in 1..poly.len() - 1 {
                    let tri = [poly[0], poly[k], poly[k + 1]];
                    let what = (seen, face, hole);
                    raster_triangle(tri, frame.f, aspect, (w, h), self, what);
                }
            }
        }
    }

    /// Per output pixel: the mean of `map(B)` over its sub-samples, and the nearest depth.
    fn reduce(&self, map: impl Fn([f64; 3]) -> [f64; 3]) -> Vec<([f64; 3], f64)> {
        let (ss, w) = (self.ss, self.width * self.ss);
        let n = (ss * ss) as f64;
        let mut out = Vec::with_capacity(self.width * self.height);
        for py in 0..self.height {
            for px in 0..self.width {
                let mut acc = [0.0; 3];
                let mut near = f64::INFINITY;
                for sy in 0..ss {
                    for sx in 0..ss {
                        let i = (py * ss + sy) * w + px * ss + sx;
                        let v = map(self.colour[i]);
                        for ch in 0..3 {
                            acc[ch] += v[ch];
                        }
                        near = near.min(self.depth[i]);
                    }
                }
                out.push((acc.map(|a| a / n), near));
            }
        }
        out
    }

    fn coverage(&self) -> Coverage {
        let n = self.seen.len().max(1) as f64;
        let count = |s: Seen| self.seen.iter().filter(|&&x| x == s).count() as f64 / n;
        let lit = (self.seen.iter().zip(&self.colour))
            .filter(|(s, c)| **s == Seen::Front && c.iter().any(|&v| v > 0.0))
            .count() as f64
            / n;
        Coverage {
            front: count(Seen::Front),
            lit,
            back: count(Seen::Back),
            nothing: count(Seen::Nothing),
        }
    }
}

/// Sutherland–Hodgman clip of a camera-space polygon against the plane z = near (vertex
/// attributes interpolated linearly).
fn clip_near(poly: &[(DVec3, [f64; 6])], near: f64) -> Option<Vec<(DVec3, [f64; 6])>> {
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
            let c = [0, 1, 2, 3, 4, 5].map(|k| cp[k] + t * (cq[k] - cp[k]));
            out.push((p + t * (q - p), c));
        }
    }
    (out.len() >= 3).then_some(out)
}

/// Draws one camera-space triangle (per vertex: radiosity, then world position) into `buf`;
/// `hole`: whether a world point is in the face's cut-out (its sub-samples then draw nothing).
fn raster_triangle(
    v: [(DVec3, [f64; 6]); 3],
    f: f64,
    aspect: f64,
    (w, h): (usize, usize),
    buf: &mut Samples,
    (seen, face, hole): (Seen, u32, Option<&dyn Fn(DVec3) -> bool>),
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
            if let Some(ties) = buf.ties.as_mut() {
                let near = z <= buf.depth[i] * (1.0 + TIE);
                if near && seen == Seen::Front && !hole.is_some_and(|in_hole| in_hole(at(&v, b, z)))
                {
                    if let Some(t) = ties.get_mut(face as usize) {
                        *t = true;
                    }
                }
                continue;
            }
            if z < buf.depth[i] {
                let mut c = [0.0; 6];
                for k in 0..3 {
                    let wk = b[k] * s[k].w * z;
                    for ch in 0..6 {
                        c[ch] += wk * v[k].1[ch];
                    }
                }
                if hole.is_some_and(|in_hole| in_hole(DVec3::new(c[3], c[4], c[5]))) {
                    continue;
                }
                buf.depth[i] = z;
                buf.seen[i] = seen;
                buf.colour[i] = [c[0], c[1], c[2]];
            }
        }
    }
}

/// The world position (attributes 3..6) at screen barycentrics `b` and depth `z` of a triangle
/// whose vertices are `v` ([`raster_triangle`]'s perspective-correct weights).
fn at(v: &[(DVec3, [f64; 6]); 3], b: [f64; 3], z: f64) -> DVec3 {
    let mut p = DVec3::ZERO;
    for k in 0..3 {
        let wk = b[k] / v[k].0.z * z;
        p += wk * DVec3::new(v[k].1[3], v[k].1[4], v[k].1[5]);
    }
    p
}

fn edge(a: DVec4, b: DVec4, x: f64, y: f64) -> f64 {
    (b.x - a.x) * (y - a.y) - (b.y - a.y) * (x - a.x)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Looking down −z at the origin from z = 4, 30° vertical field of view.
    fn front_camera() -> PinholeCamera {
        PinholeCamera {
            eye: DVec3::new(0.0, 0.0, 4.0),
            target: DVec3::ZERO,
            up: DVec3::Y,
            fov_y_degrees: 30.0,
        }
    }

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
    fn faces_seen_are_the_fronts_that_win_a_sub_sample_or_tie_with_it() {
        // face 0 in front, face 1 a smaller square right behind it (hidden), face 2 coplanar
        // with face 0 and overlapping it (a tie), face 3 facing away behind them all
        let mut mesh = quad([0.0; 3]);
        let square = |z: f64, s: f64, shift: f64| {
            [(-s, -s), (s, -s), (s, s), (-s, s)].map(|(x, y)| DVec3::new(x + shift, y, z))
        };
        for (f, corners) in [
            (1, square(-0.5, 0.5, 0.0)),
            (2, square(0.0, 0.5, 0.3)),
            (3, square(-1.0, 0.3, 0.0)),
        ] {
            let n = mesh.positions.len() as u32;
            mesh.positions.extend(corners);
            let winding = if f == 3 {
                [[0, 2, 1], [0, 3, 2]]
            } else {
                [[0, 1, 2], [0, 2, 3]]
            };
            for t in winding {
                mesh.triangles.push(t.map(|i| n + i));
                mesh.face_of_triangle.push(f);
                mesh.radiosity.resize(mesh.positions.len(), [0.0; 3]);
            }
        }
        let cam = front_camera();
        let seen = faces_seen(&mesh, None, &cam, (32, 32, 2), 4);
        assert_eq!(seen, [true, false, true, false]);
        // from behind, only the back-facing square shows its front
        let behind = PinholeCamera {
            eye: DVec3::new(0.0, 0.0, -4.0),
            ..cam
        };
        let seen = faces_seen(&mesh, None, &behind, (32, 32, 2), 4);
        assert_eq!(seen, [false, false, false, true]);
    }

    /// Under a uniform sky of horizontal illuminance E (radiance E/π, B = E), the image's empty
    /// pixels show B = E, the quad its own B, and the coverage's warning counts the sky as sky.
    #[test]
    fn empty_pixels_show_the_sky() {
        use scene_sampler::lights::{Sky, SkyModel};
        let mut scene = scene_sampler::builtin("wall-floor")
            .unwrap()
            .into_3d()
            .unwrap();
        let sky = Sky::new(SkyModel::Uniform, DVec3::Y, [3.0; 3], [0.0; 3]).unwrap();
        scene.add_lights([std::sync::Arc::new(sky) as std::sync::Arc<dyn scene_sampler::Light>]);
        let mesh = quad([std::f64::consts::PI; 3]); // radiance 1
        let cam = front_camera();
        let img = render_radiance(&mesh, Some(&scene), &cam, 32, 32, 2);
        let at = |x: usize, y: usize| img.radiance[y * 32 + x];
        assert!((at(16, 16)[0] - 1.0).abs() < 1e-6);
        let sky_l = 3.0 / std::f64::consts::PI;
        assert!(
            (f64::from(at(0, 0)[0]) - sky_l).abs() < 1e-5,
            "{:?}",
            at(0, 0)
        );
        assert!(img.coverage.nothing > 0.0 && img.coverage.nothing < 0.2);
        assert!(img.coverage.warning("image", true).is_none());
        // without a sky the same corners are black
        let bare = render_radiance(&mesh, None, &cam, 32, 32, 2);
        assert_eq!(bare.radiance[0], [0.0; 3]);
    }

    #[test]
    fn a_facing_quad_fills_the_centre_and_leaves_the_corners_black() {
        let mesh = quad([std::f64::consts::PI; 3]); // radiance 1
        let cam = front_camera();
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

    #[test]
    fn overlays_are_hidden_behind_surfaces_and_drawn_in_front_of_them() {
        let mesh = quad([0.0; 3]); // black square
        let cam = front_camera();
        let mut img = render_image(&mesh, None, &cam, &Exposure { scale: 1.0 }, 32, 32, 2);
        let centre = project(&cam, 32, 32, DVec3::ZERO).unwrap();
        assert!((centre.x - 16.0).abs() < 1e-9 && (centre.y - 16.0).abs() < 1e-9);
        assert!((img.depth[16 * 32 + 16] - 4.0).abs() < 1e-6);
        // A point behind the square is hidden; one on it (within the tolerance) is drawn.
        img.draw_points(
            &[DVec3::new(0.0, 0.0, -1.0)],
            1.0,
            [255, 0, 0],
            1.0,
            Some(1e-3),
        );
        assert_eq!(&img.pixels[(16 * 32 + 16) * 3..][..3], &[0, 0, 0]);
        img.draw_points(&[DVec3::ZERO], 1.0, [255, 0, 0], 1.0, Some(1e-3));
        assert_eq!(&img.pixels[(16 * 32 + 16) * 3..][..3], &[255, 0, 0]);
        // A horizontal line through the middle, on the square: drawn across it.
        img.draw_lines(
            &[(DVec3::new(-0.5, 0.5, 0.0), DVec3::new(0.5, 0.5, 0.0))],
            [0, 255, 0],
            1.0,
            Some(1e-3),
        );
        let row = project(&cam, 32, 32, DVec3::new(0.0, 0.5, 0.0)).unwrap().y as usize;
        let green = (0..32)
            .filter(|&x| img.pixels[(row * 32 + x) * 3 + 1] == 255)
            .count();
        // 1 unit at distance 4 spans 32 / (2·4·tan 15°) ≈ 14.9 pixels.
        assert!((14..=17).contains(&green), "{green} green pixels");
    }
}

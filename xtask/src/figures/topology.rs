//! What the solver built, drawn from the scene's camera (figs. 4.12a–c, 4.15d–e): the receiver
//! points of the kernel training samples, the shading network, and the re-triangulated output
//! mesh. Each is an overlay ([`gcr::output::Image::draw_points`] / `draw_lines`, with
//! hidden-point removal against the depth buffer) on a flat-shaded view of the scene's faces.
//!
//! * `gcr-<scene>-samples.png` (fig. 4.12a): the end points y_i of every sample ray the kernel
//!   network was trained on (the solver keeps all of them, [`gcr::Trained::samples`]);
//! * `gcr-<scene>-network.png` (figs. 4.12b, 4.15d): the shading network of the last FEM step
//!   ([`gcr::stages::ShadingGeometry`]): cell centres as dots, the edges of its triangles as lines.
//!   Only the triangles that survive our breaking operator (sec. 4.4.2, on by default) exist there;
//!   the dissertation's network has no such operator (`gcr-wall-floor-network-unbroken.png` is a
//!   solve with the operator off);
//! * `gcr-<scene>-triangulation.png` (figs. 4.12c, 4.15e): the edges of the output mesh, the scene's
//!   faces split to the shading network's local edge length (sec. 4.3.1).

use anyhow::{Context, Result};
use gcr::output::Exposure;
use gcr::output::{Image, PinholeCamera, render_image};
use gcr::{ShadedMesh, Trained};
use glam::DVec3;
use scene_sampler::Scene;
use std::collections::BTreeSet;
use std::path::Path;

/// Relative depth tolerance for overlays that lie on the scene's surfaces (sample points, mesh
/// edges): rasterized and projected depths of one surface point agree to far better than this.
const ON_SURFACE: f64 = 2e-3;
/// Relative depth tolerance for the shading network, whose cells only approximate the surfaces.
const NEAR_SURFACE: f64 = 2e-2;

/// Counts of what the three overlays show.
pub struct Counts {
    /// Sample rays (receiver points drawn).
    pub samples: usize,
    /// Shading network cells.
    pub cells: usize,
    /// Shading network triangles (after the breaking operator).
    pub simplices: usize,
    /// Output mesh triangles.
    pub triangles: usize,
    /// Output mesh vertices.
    pub vertices: usize,
}

/// The scene's faces flat-shaded in light greys (a head light: brighter where the face looks at
/// the camera), emitters pale yellow, so that dark overlays stand out.
pub fn geometry_background(scene: &Scene, cam: &PinholeCamera, size: u32, ss: u32) -> Image {
    let mut mesh = ShadedMesh::default();
    for f in &scene.faces {
        let base = mesh.positions.len() as u32;
        let centroid = (f.v[0] + f.v[1] + f.v[2]) / 3.0;
        let c = f.normal.dot((cam.eye - centroid).normalize()).abs();
        // Linear display value; Exposure { scale: 1 } shows B/π.
        let grey = 0.30 + 0.45 * c;
        let rgb = if f.emission.is_zero() {
            [grey; 3]
        } else {
            [1.0, 0.95, 0.6]
        };
        mesh.positions.extend_from_slice(&f.v);
        mesh.triangles.push([base, base + 1, base + 2]);
        mesh.face_of_triangle
            .push(mesh.face_of_triangle.len() as u32);
        mesh.radiosity
            .extend([rgb.map(|v| v * std::f64::consts::PI); 3]);
    }
    render_image(&mesh, None, cam, &Exposure { scale: 1.0 }, size, size, ss)
}

/// Unique undirected edges of triangles, as segments.
fn edges(positions: &[DVec3], triangles: impl Iterator<Item = [usize; 3]>) -> Vec<(DVec3, DVec3)> {
    let mut set = BTreeSet::new();
    for t in triangles {
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            set.insert((a.min(b), a.max(b)));
        }
    }
    set.into_iter()
        .map(|(a, b)| (positions[a], positions[b]))
        .collect()
}

/// Saves an [`Image`] as PNG.
pub fn save(img: &Image, path: &Path) -> Result<()> {
    image::RgbImage::from_raw(img.width, img.height, img.pixels.clone())
        .context("image buffer")?
        .save(path)
        .with_context(|| format!("writing {}", path.display()))
}

/// The shading network of the last FEM step drawn over `background`: its triangles' edges as
/// lines, its cell centres as dots.
pub fn network_image(background: &Image, trained: &Trained) -> Image {
    let geo = &trained.fem.base.geo;
    let dot = (background.width as f64 / 400.0).max(0.6);
    let mut network = background.clone();
    let net_edges = edges(&geo.centres, geo.simplices.iter().copied());
    network.draw_lines(&net_edges, [20, 50, 170], 0.9, Some(NEAR_SURFACE));
    network.draw_points(&geo.centres, 1.6 * dot, [0, 0, 0], 1.0, Some(NEAR_SURFACE));
    network
}

/// Draws the three overlays of one solve and writes `gcr-<name>-{samples,network,triangulation}.png`
/// into `out`. Returns the images (for the figure panels) and what they show.
pub fn write(
    out: &Path,
    name: &str,
    scene: &Scene,
    trained: &Trained,
    mesh: &ShadedMesh,
    cam: &PinholeCamera,
    size: u32,
) -> Result<([Image; 3], Counts)> {
    let background = geometry_background(scene, cam, size, 2);
    // Dot size and line opacity scale with the image so that the quick run stays readable.
    let dot = (size as f64 / 400.0).max(0.6);

    let mut samples = background.clone();
    let ends: Vec<DVec3> = trained.samples.iter().map(|s| s.ray.y).collect();
    samples.draw_points(&ends, dot, [170, 20, 20], 0.85, Some(ON_SURFACE));
    save(&samples, &out.join(format!("gcr-{name}-samples.png")))?;

    let geo = &trained.fem.base.geo;
    let network = network_image(&background, trained);
    save(&network, &out.join(format!("gcr-{name}-network.png")))?;

    let mut tri = background;
    let mesh_edges = edges(
        &mesh.positions,
        mesh.triangles.iter().map(|t| t.map(|i| i as usize)),
    );
    tri.draw_lines(&mesh_edges, [25, 25, 25], 0.8, Some(ON_SURFACE));
    save(&tri, &out.join(format!("gcr-{name}-triangulation.png")))?;

    let counts = Counts {
        samples: ends.len(),
        cells: geo.centres.len(),
        simplices: geo.simplices.len(),
        triangles: mesh.triangles.len(),
        vertices: mesh.positions.len(),
    };
    Ok(([samples, network, tri], counts))
}

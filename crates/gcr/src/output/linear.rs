//! A 3-D image as numbers: the linear radiance L = B/π per pixel that an `.exr` image output
//! holds, in memory (the Python package's `Solution.image`), made as [`super::write_outputs`]
//! makes that file when no mesh output is asked for: the same camera choice, the same output mesh
//! of what the camera sees (mesh mode) or the same per-pixel gather (pixel mode). (With a glTF or
//! PLY output the file's image is drawn from the whole mesh instead: the same within the gathers'
//! noise.)

use super::OutputError;
use super::camera::{ImageMode, ImageSettings};
use super::camera_choice::camera_of;
use super::mesh::{MeshExtent, output_mesh_of};
use super::pixel::render_pixels;
use super::raster::{IMAGE_SUPERSAMPLING, PinholeCamera, RadianceImage, render_radiance};
use crate::config::SolveConfig;
use crate::domain::Domain;
use crate::estimator::GatherStats;
use crate::retriangulate::RetriangulateLimits;
use crate::solve::Trained;

/// A linear radiance image and how it was made.
#[derive(Clone, Debug)]
pub struct LinearImage {
    /// L = B/π per pixel (RGB, f32, rows from the top), as an `.exr` output holds it.
    pub radiance: RadianceImage,
    /// The camera used.
    pub camera: PinholeCamera,
    /// Where the camera came from: `given`, `scene`, `automatic-inside` or `automatic-outside`.
    pub camera_source: &'static str,
    /// What the gather measured: the output mesh's (mesh mode) or the pixels' (pixel mode).
    pub stats: GatherStats,
}

/// The main image of `settings` (its camera, resolution and mode; not its views or exposure,
/// which tone-mapped outputs alone use, but for placing the automatic camera) as linear radiance.
/// Errs for a Flatland domain (its images are tone-mapped PNGs only) and for settings that
/// [`ImageSettings::validate`] refuses.
pub fn render_linear(
    domain: &Domain,
    trained: &Trained,
    config: &SolveConfig,
    settings: &ImageSettings,
) -> Result<LinearImage, OutputError> {
    settings.validate()?;
    let Some(scene) = domain.scene_3d() else {
        return Err(OutputError::ImageNeeds3d("an image as numbers"));
    };
    // ⟨The camera, then the output mesh of what it sees (mesh mode)⟩
    let choice = (settings.camera, "given");
    let (camera, camera_source) = camera_of(domain, trained, config, choice, settings)?;
    let seen_by = [(camera, settings.width, settings.height)];
    let mesh = match settings.mode {
        ImageMode::Mesh => Some(output_mesh_of(
            domain,
            trained,
            config,
            RetriangulateLimits::default(),
            MeshExtent::SeenBy(&seen_by),
        )?),
        ImageMode::Pixel => None,
    };
    let (w, h) = (settings.width, settings.height);
    // ⟨Per pixel, or the mesh rasterized⟩
    let (radiance, stats) = match (settings.mode, mesh) {
        (ImageMode::Pixel, _) => {
            let img = render_pixels(
                domain,
                trained,
                config,
                &camera,
                (w, h, settings.pixel_samples),
            )?;
            (img.radiance(), img.stats)
        }
        (ImageMode::Mesh, Some((mesh, stats))) => (
            render_radiance(&mesh, Some(scene), &camera, w, h, IMAGE_SUPERSAMPLING),
            stats,
        ),
        (ImageMode::Mesh, None) => unreachable!("mesh-mode images build the mesh"),
    };
    Ok(LinearImage {
        radiance,
        camera,
        camera_source,
        stats,
    })
}

//! Each image's camera: the given one, the scene's, or the automatic one ([`super::autocam`]),
//! whose choice reads how bright the faces its candidate views see are — from a quick gather at
//! those faces, so that no output mesh is needed to aim a camera.

use super::OutputError;
use super::autocam::Candidates;
use super::camera::{CameraChoice, ImageSettings};
use super::raster::PinholeCamera;
use super::tonemap::{Exposure, luminance};
use crate::config::{GatherSamples, SolveConfig};
use crate::domain::Domain;
use crate::emitters::Emitters;
use crate::estimator::{GatherError, radiosity_at_points};
use crate::solve::Trained;
use glam::DVec3;
use std::path::Path;

/// Shadow and cosine rays (each) per face of the automatic camera's quick gather: the choice
/// reads whether a face is lit and how bright it is next to the other candidates' faces, not B
/// to the target.
const QUICK_RAYS: usize = 16;

/// A camera with where it came from (`given`, `view`, `scene`, `automatic-inside`,
/// `automatic-outside`).
pub(super) type Sourced = (PinholeCamera, &'static str);

/// Each image's camera with its source name: the given one, the scene's, or the automatic one.
pub(super) fn image_cameras<'a>(
    domain: &Domain,
    trained: &Trained,
    config: &SolveConfig,
    images: &[(&'a Path, CameraChoice, &'static str)],
    settings: &ImageSettings,
) -> Result<Vec<(&'a Path, Sourced)>, OutputError> {
    (images.iter())
        .map(|&(path, choice, source)| {
            let camera = camera_of(domain, trained, config, (choice, source), settings)?;
            Ok((path, camera))
        })
        .collect()
}

/// One image's camera with its source name (`source` for a given camera): the given one, the
/// scene's, or the automatic one.
pub(super) fn camera_of(
    domain: &Domain,
    trained: &Trained,
    config: &SolveConfig,
    (choice, source): (CameraChoice, &'static str),
    settings: &ImageSettings,
) -> Result<Sourced, OutputError> {
    let Domain::ThreeD(k) = domain else {
        unreachable!("3-D images only for 3-D domains")
    };
    match choice {
        CameraChoice::Given(c) => Ok((c, source)),
        CameraChoice::Scene { fov } if k.scene.camera_given => {
            let mut c = PinholeCamera::of_scene(k.scene);
            c.fov_y_degrees = fov.unwrap_or(c.fov_y_degrees);
            Ok((c, "scene"))
        }
        CameraChoice::Scene { fov } | CameraChoice::Automatic { fov } => {
            automatic(domain, trained, config, settings, fov)
        }
    }
}

/// The automatic camera ([`super::autocam`]) with its source name: the faces its candidates'
/// probe images see get B from [`QUICK_RAYS`] rays at their centroids, shown at the given
/// exposure or at their own automatic one.
fn automatic(
    domain: &Domain,
    trained: &Trained,
    config: &SolveConfig,
    settings: &ImageSettings,
    fov: Option<f64>,
) -> Result<Sourced, OutputError> {
    let Domain::ThreeD(k) = domain else {
        unreachable!("3-D images only for 3-D domains")
    };
    let aspect = f64::from(settings.width) / f64::from(settings.height);
    let candidates = Candidates::new(k.scene, k.bvh, aspect, fov);
    let faces = candidates.faces_seen(k.scene, k.bvh);
    let brightness = quick_brightness(domain, trained, config, &faces, settings.exposure)?;
    let auto = candidates.best(k.scene, k.bvh, &brightness);
    let source = if auto.inside {
        "automatic-inside"
    } else {
        "automatic-outside"
    };
    Ok((auto.camera, source))
}

/// Per scene face, the display luminance in [0, 1] of B at the centroids of `faces` (0
/// elsewhere), from one round of [`QUICK_RAYS`] rays; at `exposure` when given, else at the
/// automatic exposure of the faces that do not emit.
fn quick_brightness(
    domain: &Domain,
    trained: &Trained,
    config: &SolveConfig,
    faces: &[u32],
    exposure: Option<f64>,
) -> Result<Vec<f64>, GatherError> {
    let Domain::ThreeD(k) = domain else {
        unreachable!("3-D images only for 3-D domains")
    };
    let scene = k.scene;
    let points: Vec<(DVec3, DVec3, u32)> = (faces.iter())
        .map(|&f| {
            let face = &scene.faces[f as usize];
            (face.centroid(), face.normal, f)
        })
        .collect();
    let mut quick = config.clone();
    quick.paths.target_error = None;
    quick.gather_samples = GatherSamples {
        direct: QUICK_RAYS,
        indirect: QUICK_RAYS,
    };
    let phase = crate::progress::phase("camera");
    let b = radiosity_at_points(domain, trained, &Emitters::new(domain), &quick, &points)?;
    drop(phase);
    let rgb = |g: &crate::gather::Gathered| g.rgb(domain.bands());
    let exposure = match exposure {
        Some(scale) => Exposure { scale },
        None => Exposure::auto(
            (faces.iter().zip(&b))
                .filter(|(f, _)| scene.faces[**f as usize].emission.is_zero())
                .map(|(_, g)| rgb(g)),
        ),
    };
    let mut brightness = vec![0.0; scene.faces.len()];
    for (&f, g) in faces.iter().zip(&b) {
        brightness[f as usize] = luminance(exposure.linear(rgb(g)));
    }
    Ok(brightness)
}

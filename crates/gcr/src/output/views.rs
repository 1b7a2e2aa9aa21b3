//! The 3-D outputs of a solve: the re-triangulated output mesh, images (mesh-mode from the mesh,
//! per-pixel from [`super::pixel`]) from given, scene or automatic cameras, one exposure for
//! every tone-mapped output, the lightmap ([`super::lightmap`]), and their files.

use super::OutputError;
use super::camera::{CameraChoice, ImageMode, ImageSettings};
use super::camera_choice::image_cameras;
use super::encode::{Format, format_of, write_jpeg, write_png};
use super::mesh::{MeshExtent, output_mesh_of};
use super::pixel::render_pixel_shard;
use super::plan::{OutputPaths, OutputPlan};
use super::raster::{Coverage, IMAGE_SUPERSAMPLING, PinholeCamera, render_image, render_radiance};
use super::stage::Stage;
use super::staged::StagedFiles;
use super::tonemap::Exposure;
use crate::config::SolveConfig;
use crate::domain::Domain;
use crate::mesh::ShadedMesh;
use crate::metrics::{ImageRecord, Metrics};
use crate::retriangulate::RetriangulateLimits;
use crate::solve::Trained;
use scene_sampler::Scene;
use std::path::Path;
use std::time::Instant;

/// The 3-D outputs: the re-triangulated output mesh (when glTF, PLY, a mesh-mode image or the
/// automatic camera asks for it), per-pixel images ([`super::pixel`]), one exposure for all of
/// them (given, else from the mesh's non-emitting triangles, else from the first pixel image's
/// lit hits), and the files.
pub(super) fn write_3d(
    domain: &Domain,
    trained: &Trained,
    config: &SolveConfig,
    plan: &OutputPlan,
    stage: &mut Stage,
) -> Result<(), OutputError> {
    let Some(scene) = domain.scene_3d() else {
        return Ok(());
    };
    let (paths, settings) = (plan.paths(), plan.images());
    let images = image_jobs(paths, settings);
    let pixel = settings.mode == ImageMode::Pixel;
    // ⟨Each image's camera (the automatic one from a quick gather where its candidates look)⟩
    let tg = Instant::now();
    let jobs = image_cameras(domain, trained, config, &images, settings)?;
    // the cameras' quick gathers are not outputs: their trial is not reported
    let _ = crate::estimator::relay::take_trial();
    stage.metrics.seconds.gather += tg.elapsed().as_secs_f64();
    // ⟨The output mesh, when an output needs it: whole for a file of its own, else what the
    // mesh-mode images see⟩
    let seen_by: Vec<(PinholeCamera, u32, u32)> = (jobs.iter())
        .map(|(_, (c, _))| (*c, settings.width, settings.height))
        .collect();
    let extent = match paths.mesh.is_some() || paths.ply.is_some() {
        true => MeshExtent::Whole,
        false => MeshExtent::SeenBy(&seen_by),
    };
    let mesh = match plan.needs_mesh() {
        true => Some(staged_mesh(domain, trained, config, extent, stage)?),
        false => None,
    };
    let mesh_exposure = mesh.as_ref().map(|m| match settings.exposure {
        Some(scale) => Exposure { scale },
        None => exposure_of_mesh(m, scene),
    });
    // ⟨Per-pixel images: B gathered at every sub-sample's visible point (or merged)⟩
    let tg = Instant::now();
    let mut rendered = Vec::new();
    for (_, (camera, _)) in jobs.iter().filter(|_| pixel) {
        let size = (settings.width, settings.height, settings.pixel_samples);
        let merged = merged_pixels(domain, config, plan, camera)?;
        let img = render_pixel_shard(domain, trained, config, camera, size, merged)?;
        stage.push_gather(img.stats);
        rendered.push(img);
    }
    stage.metrics.seconds.gather += tg.elapsed().as_secs_f64();
    // ⟨The lightmap: its own gather at the texels, its files (a shard: its part)⟩
    if let Some(path) = &paths.lightmap {
        super::lightmap::write_lightmap(domain, trained, config, plan, path, stage)?;
    }
    if let Some(shard) = config.paths.shard {
        // ⟨A shard writes its pixels' estimates, no image⟩
        let images = jobs.iter().map(|(path, (camera, _))| (*path, camera));
        return write_pixel_parts(
            domain,
            config,
            settings,
            images.zip(&rendered),
            shard,
            stage,
        );
    }
    let (metrics, staged) = (&mut stage.metrics, &mut stage.files);
    let to = Instant::now();
    // ⟨One exposure for every tone-mapped output⟩
    let exposure = one_exposure(settings, mesh_exposure, rendered.first());
    let tone_mapped = paths.mesh.is_some()
        || paths.ply.is_some()
        || jobs.iter().any(|(p, _)| format_of(p) != Format::Exr);
    if tone_mapped {
        record_exposure(metrics, &exposure, settings);
    }
    // ⟨The images, then the meshes⟩
    for (i, (path, (camera, source))) in jobs.iter().enumerate() {
        let coverage = match rendered.get(i) {
            Some(img) => write_pixel_image(img, &exposure, path, staged)?,
            None => {
                let mesh = mesh.as_ref().expect("mesh-mode images build the mesh");
                write_image((mesh, scene), camera, settings, &exposure, path, staged)?
            }
        };
        let what = format!("image `{}`", path.display());
        let sky = scene.lights.iter().any(|l| l.is_background());
        metrics.warnings.extend(coverage.warning(&what, sky));
        metrics
            .images
            .push(image_record(path, settings, camera, source, coverage));
    }
    if let Some(mesh) = &mesh {
        if let Some(path) = &paths.mesh {
            staged.write(path, |w| super::glb::write_glb(mesh, scene, &exposure, w))?;
        }
        if let Some(path) = &paths.ply {
            staged.write(path, |w| super::ply::write_ply(mesh, &exposure, w))?;
        }
    }
    metrics.seconds.output += to.elapsed().as_secs_f64();
    Ok(())
}

/// The output mesh, its gather's statistics, size and time recorded in `stage`.
fn staged_mesh(
    domain: &Domain,
    trained: &Trained,
    config: &SolveConfig,
    extent: MeshExtent,
    stage: &mut Stage,
) -> Result<ShadedMesh, OutputError> {
    let tg = Instant::now();
    let limits = RetriangulateLimits::default();
    let (mesh, stats) = output_mesh_of(domain, trained, config, limits, extent)?;
    stage.push_gather(stats);
    stage.metrics.output_vertices = mesh.vertex_count();
    stage.metrics.output_triangles = mesh.triangle_count();
    stage.metrics.seconds.gather += tg.elapsed().as_secs_f64();
    Ok(mesh)
}

/// The exposure of every tone-mapped output: given, else the mesh's, else from the first pixel
/// image's lit hits, else 1.
fn one_exposure(
    settings: &ImageSettings,
    mesh: Option<Exposure>,
    first_image: Option<&super::pixel::PixelImage>,
) -> Exposure {
    match (settings.exposure, mesh, first_image) {
        (Some(scale), _, _) => Exposure { scale },
        (None, Some(e), _) => e,
        (None, None, Some(img)) => Exposure::auto(img.lit()),
        (None, None, None) => Exposure { scale: 1.0 },
    }
}

/// The fingerprint of a sharded per-pixel image ([`super::shards::fingerprint`]): the scene, the
/// settings, the camera and the resolution.
fn pixel_fingerprint(
    domain: &Domain,
    config: &SolveConfig,
    settings: &ImageSettings,
    camera: &PinholeCamera,
) -> u64 {
    let view = format!("{camera:?} {}x{}", settings.width, settings.height);
    super::shards::fingerprint(domain, &[], config, &view)
}

/// The pixels' estimates merged from shards (`--from-shards`), checked to be of this image;
/// `None` when the image is gathered.
fn merged_pixels(
    domain: &Domain,
    config: &SolveConfig,
    plan: &OutputPlan,
    camera: &PinholeCamera,
) -> Result<Option<Vec<crate::gather::Gathered>>, OutputError> {
    let kind = super::shards::Kind::Image;
    if !plan.merges(kind) {
        return Ok(None);
    }
    let settings = plan.images();
    let print = pixel_fingerprint(domain, config, settings, camera);
    let merged = plan.merged_shards(kind, print)?;
    let pixels = settings.width as usize * settings.height as usize;
    if merged.len() != pixels {
        return Err(OutputError::MergeShards(format!(
            "the shards hold {} pixels, the image {pixels}",
            merged.len()
        )));
    }
    Ok(Some(merged))
}

/// Writes a shard's partial images (`<stem>.shard-I-of-N.txt` beside each image: its pixels'
/// whole estimates with their indices, `super::shards`) instead of the images.
fn write_pixel_parts<'a>(
    domain: &Domain,
    config: &SolveConfig,
    settings: &ImageSettings,
    images: impl Iterator<Item = ((&'a Path, &'a PinholeCamera), &'a super::pixel::PixelImage)>,
    shard: crate::config::Shard,
    stage: &mut Stage,
) -> Result<(), OutputError> {
    use super::shards::{Kind, gathered_line, part_path, partial_text};
    for ((path, camera), img) in images {
        let Some((estimates, mine)) = &img.shard else {
            continue;
        };
        let lines: Vec<String> = estimates.iter().map(gathered_line).collect();
        let print = pixel_fingerprint(domain, config, settings, camera);
        let text = partial_text(Kind::Image, shard, print, &lines, mine);
        let part = part_path(path, shard);
        super::staged::check_target(&part, "image shard", None)?;
        stage.files.write_bytes(&part, text.as_bytes())?;
    }
    Ok(())
}

/// The automatic exposure of a mesh's outputs: from the radiosity of its faces that do not emit.
pub(super) fn exposure_of_mesh(mesh: &ShadedMesh, scene: &scene_sampler::Scene) -> Exposure {
    let lit = (mesh.triangles.iter())
        .zip(&mesh.face_of_triangle)
        .filter(|(_, f)| scene.faces[**f as usize].emission.is_zero())
        .map(|(t, _)| mesh.radiosity[t[0] as usize]);
    Exposure::auto(lit)
}

/// Records the exposure of the tone-mapped outputs and where it came from.
fn record_exposure(metrics: &mut Metrics, exposure: &Exposure, settings: &ImageSettings) {
    metrics.exposure = Some(exposure.scale);
    metrics.exposure_source = if settings.exposure.is_some() {
        "given"
    } else {
        "auto"
    }
    .into();
}

/// Writes a per-pixel image: linear radiance for .exr, tone-mapped for PNG and JPEG.
fn write_pixel_image(
    img: &super::pixel::PixelImage,
    exposure: &Exposure,
    path: &Path,
    staged: &mut StagedFiles,
) -> Result<Coverage, OutputError> {
    let radiance = img.radiance();
    if format_of(path) == Format::Exr {
        stage_exr(&radiance, path, staged)?;
        return Ok(radiance.coverage);
    }
    let rgb = image::RgbImage::from_raw(radiance.width, radiance.height, img.tone_mapped(exposure))
        .expect("a pixel image has w·h RGB pixels");
    stage_tone_mapped(&rgb, path, staged)?;
    Ok(radiance.coverage)
}

/// Stages linear radiance as OpenEXR for `path`.
fn stage_exr(
    img: &super::raster::RadianceImage,
    path: &Path,
    staged: &mut StagedFiles,
) -> Result<(), OutputError> {
    let bytes = super::encode::encode_exr(img).map_err(|source| OutputError::Write {
        path: path.to_path_buf(),
        source,
    })?;
    staged.write_bytes(path, &bytes)
}

/// Stages a tone-mapped image for `path`: JPEG for .jpg and .jpeg, PNG otherwise.
fn stage_tone_mapped(
    rgb: &image::RgbImage,
    path: &Path,
    staged: &mut StagedFiles,
) -> Result<(), OutputError> {
    if format_of(path) == Format::Jpeg {
        staged.write(path, |out| write_jpeg(rgb, out))
    } else {
        staged.write(path, |out| write_png(rgb, out))
    }
}

/// The 3-D images to write: the main image with its camera choice, then the views.
fn image_jobs<'a>(
    paths: &'a OutputPaths,
    settings: &'a ImageSettings,
) -> Vec<(&'a Path, CameraChoice, &'static str)> {
    let main = paths
        .image
        .as_deref()
        .map(|p| (p, settings.camera, "given"));
    let views = settings
        .views
        .iter()
        .map(|v| (v.path.as_path(), CameraChoice::Given(v.camera), "view"));
    main.into_iter().chain(views).collect()
}

/// Renders and stages one image; returns what its sub-samples saw.
fn write_image(
    (mesh, scene): (&ShadedMesh, &Scene),
    camera: &PinholeCamera,
    settings: &ImageSettings,
    exposure: &Exposure,
    path: &Path,
    staged: &mut StagedFiles,
) -> Result<Coverage, OutputError> {
    let (w, h) = (settings.width, settings.height);
    if format_of(path) == Format::Exr {
        let img = render_radiance(mesh, Some(scene), camera, w, h, IMAGE_SUPERSAMPLING);
        stage_exr(&img, path, staged)?;
        return Ok(img.coverage);
    }
    let img = render_image(
        mesh,
        Some(scene),
        camera,
        exposure,
        w,
        h,
        IMAGE_SUPERSAMPLING,
    );
    let coverage = img.coverage;
    let rgb = image::RgbImage::from_raw(w, h, img.pixels).expect("render fills w·h RGB pixels");
    stage_tone_mapped(&rgb, path, staged)?;
    Ok(coverage)
}

fn image_record(
    path: &Path,
    settings: &ImageSettings,
    camera: &PinholeCamera,
    source: &str,
    coverage: Coverage,
) -> ImageRecord {
    ImageRecord {
        path: path.display().to_string(),
        format: match format_of(path) {
            Format::Png => "png",
            Format::Jpeg => "jpeg",
            Format::Exr => "exr",
        }
        .into(),
        width: settings.width,
        height: settings.height,
        eye: camera.eye.to_array(),
        target: camera.target.to_array(),
        up: camera.up.to_array(),
        fov_y_deg: camera.fov_y_degrees,
        camera_source: source.into(),
        front_share: coverage.front,
        lit_share: coverage.lit,
        back_share: coverage.back,
        nothing_share: coverage.nothing,
    }
}

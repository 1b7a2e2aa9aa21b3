//! The output stage of a solve: every file `gcr solve` writes, and the metrics of the run.
//!
//! [`OutputPlan::new`] checks every path and reads the probes *before* the solve (a bad probe
//! line or an unwritable path is reported in milliseconds, not after the solve);
//! [`write_outputs`] gathers, renders and writes all files at once through [`StagedFiles`]:
//! either every output reaches its target, or none does.

use super::OutputError;
use super::camera::{CameraChoice, ImageMode, ImageSettings};
use super::flatland::{light_flow_image, scene_image};
use super::mesh::output_mesh;
use super::probes::{ProbeSettings, probe_values, read_probes};
use super::raster::{Coverage, PinholeCamera, render_image, render_radiance};
use super::staged::{StagedFiles, check_target};
use super::tonemap::{Exposure, luminance};
use crate::config::{GatherMode, SolveConfig};
use crate::domain::Domain;
use crate::emitters::Emitters;
use crate::estimator::{GatherError, GatherStats};
use crate::gather::Gathered;
use crate::lightmap::LightmapSettings;
use crate::mesh::ShadedMesh;
use crate::metrics::{ImageRecord, Metrics, peak_memory_bytes};
use crate::retriangulate::RetriangulateLimits;
use crate::solve::Trained;
use glam::DVec3;
use scene_sampler::Scene;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// The extensions an image output accepts (the format follows the extension): tone-mapped PNG
/// and JPEG, linear OpenEXR (3-D only).
pub const IMAGE_EXTENSIONS: &str = "png|jpg|jpeg|exr";
/// Anti-aliasing of the 3-D camera image: sub-samples per pixel side.
pub(super) const IMAGE_SUPERSAMPLING: u32 = 2;

/// Where the outputs of a solve go; `None` skips an output.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct OutputPaths {
    /// Image (.png, .jpg, .jpeg; .exr for 3-D scenes): from the camera of
    /// `ImageSettings::camera` (3-D) or of the whole scene (Flatland, PNG).
    pub image: Option<PathBuf>,
    /// Flatland only: PNG of the light flow over the kernel domain
    /// ([`super::flatland::light_flow_image`]).
    pub kernel_image: Option<PathBuf>,
    /// 3-D only: binary glTF (.glb) of the output mesh with vertex colours.
    pub mesh: Option<PathBuf>,
    /// 3-D only: PLY of the output mesh with radiosity per vertex.
    pub ply: Option<PathBuf>,
    /// 3-D only: binary glTF (.glb) of the scene with a baked lightmap on `TEXCOORD_1`, its pages
    /// beside it as `<stem>-lightmap-<k>.exr` (`output/lightmap.rs`).
    pub lightmap: Option<PathBuf>,
    /// Probe points to read (`x y z nx ny nz` per line; Flatland `x y nx ny`).
    pub probes_in: Option<PathBuf>,
    /// Where to write radiosity at the probes (`r g b` per line; grey Flatland `b`).
    pub probe_out: Option<PathBuf>,
    /// JSON metrics of the run.
    pub metrics: Option<PathBuf>,
}

impl OutputPaths {
    /// Every output target with its name (for messages) and required extension.
    fn targets(&self) -> Vec<(&Path, &'static str, Option<&'static str>)> {
        [
            (&self.image, "image", Some(IMAGE_EXTENSIONS)),
            (&self.kernel_image, "kernel image", Some("png")),
            (&self.mesh, "mesh", Some("glb")),
            (&self.ply, "PLY mesh", Some("ply")),
            (&self.lightmap, "lightmap", Some("glb")),
            (&self.probe_out, "probe", None),
            (&self.metrics, "metrics", None),
        ]
        .into_iter()
        .filter_map(|(p, what, ext)| p.as_deref().map(|p| (p, what, ext)))
        .collect()
    }
}

/// Outputs checked against a domain, with the probes read and snapped onto its surfaces: what
/// [`write_outputs`] needs, built before the solve.
#[derive(Clone, Debug)]
pub struct OutputPlan {
    paths: OutputPaths,
    images: ImageSettings,
    probes: Vec<(DVec3, DVec3, u32)>,
    probe_settings: ProbeSettings,
    lightmap: LightmapSettings,
    /// The partial lightmap outputs (name, text) whose texels the lightmap takes instead of
    /// gathering them (`--from-shards`; `super::shards`).
    lightmap_parts: Vec<(String, String)>,
    /// The scene brings its own camera (a built-in's or a glTF camera node).
    scene_camera: bool,
    /// The scene is a Flatland scene.
    flatland: bool,
}

impl OutputPlan {
    /// Whether an output reads the networks whatever the gather: only the kernel image, which
    /// draws the kernel network. The output mesh (images, views, glTF, PLY) is re-triangulated to
    /// the shading network's resolution when there is one and to a uniform one otherwise
    /// (`output::mesh::LocalEdge`), then refined by B; probes and metrics read none.
    pub fn needs_networks(&self) -> bool {
        self.paths.kernel_image.is_some()
    }

    /// Whether the outputs need the output mesh: glTF, PLY, images in mesh mode, and pixel
    /// images from the automatic camera (placed from the mesh's brightness); a Flatland image.
    fn needs_mesh(&self) -> bool {
        let p = &self.paths;
        let images = p.image.is_some() || !self.images.views.is_empty();
        let automatic = p.image.is_some() && is_automatic(self.images.camera, self.scene_camera);
        p.mesh.is_some()
            || p.ply.is_some()
            || (images && (self.images.mode == ImageMode::Mesh || automatic || self.flatland))
    }

    /// Checks every output of `paths` for `domain` before anything is solved: the outputs fit
    /// the domain (mesh and PLY need 3-D, the kernel image Flatland), probes come with a probe
    /// output, each target has its extension (.png, .glb, .ply) and an existing, writable
    /// directory, no two outputs share a target, and the probe file parses and every probe
    /// snaps onto the scene. Images with the default [`ImageSettings`].
    pub fn new(domain: &Domain, paths: OutputPaths) -> Result<Self, OutputError> {
        Self::with_images(domain, paths, ImageSettings::default())
    }

    /// [`OutputPlan::new`] with image settings, checked too: cameras, resolution and exposure
    /// valid ([`ImageSettings::validate`]), the views' targets as the image's, and for a
    /// Flatland scene none of them (nor an EXR image).
    pub fn with_images(
        domain: &Domain,
        paths: OutputPaths,
        images: ImageSettings,
    ) -> Result<Self, OutputError> {
        Self::with_options(domain, paths, images, ProbeSettings::default())
    }

    /// The whole plan of a run, checked before its solve as `gcr solve` and Python's
    /// `Solution.write` check it: [`OutputPlan::with_options`], the lightmap settings and the
    /// parts of a sharded lightmap to merge ([`OutputPlan::with_lightmap`],
    /// [`OutputPlan::with_lightmap_parts`]), then what `config` can compute and the machine hold
    /// ([`OutputPlan::check_config`]) and its shard ([`OutputPlan::check_shard`]).
    pub fn checked(
        domain: &Domain,
        (paths, images, probe_settings): (OutputPaths, ImageSettings, ProbeSettings),
        (lightmap, parts): (LightmapSettings, Vec<(String, String)>),
        config: &SolveConfig,
    ) -> Result<Self, OutputError> {
        let plan = Self::with_options(domain, paths, images, probe_settings)?
            .with_lightmap(lightmap)?
            .with_lightmap_parts(parts, config)?;
        plan.check_config(config)?;
        plan.check_shard(domain, config)?;
        Ok(plan)
    }

    /// [`OutputPlan::with_images`] with probe settings, checked too
    /// ([`ProbeSettings::validate`]; radiosity probes snap within its tolerance).
    pub fn with_options(
        domain: &Domain,
        paths: OutputPaths,
        images: ImageSettings,
        probe_settings: ProbeSettings,
    ) -> Result<Self, OutputError> {
        images.validate()?;
        probe_settings.validate()?;
        if domain.scene_flat().is_some() {
            let default = ImageSettings::default();
            if images.views.len() + usize::from(images.camera != default.camera) > 0 {
                return Err(OutputError::ImageNeeds3d("a camera or a --view"));
            }
            if (images.width, images.height) != (default.width, default.height) {
                return Err(OutputError::ImageNeeds3d("an image resolution"));
            }
            if images.exposure.is_some() {
                return Err(OutputError::ImageNeeds3d("an exposure"));
            }
            if images.mode != default.mode || images.pixel_samples != default.pixel_samples {
                return Err(OutputError::ImageNeeds3d("a per-pixel image"));
            }
            if paths
                .image
                .as_deref()
                .is_some_and(|p| format_of(p) == Format::Exr)
            {
                return Err(OutputError::ImageNeeds3d("an EXR image"));
            }
        }
        if domain.scene_3d().is_none()
            && (paths.mesh.is_some() || paths.ply.is_some() || paths.lightmap.is_some())
        {
            return Err(OutputError::MeshNeeds3d);
        }
        if domain.scene_flat().is_none() && paths.kernel_image.is_some() {
            return Err(OutputError::KernelImageNeedsFlatland);
        }
        if paths.probes_in.is_some() != paths.probe_out.is_some() {
            return Err(OutputError::ProbesWithoutOutput);
        }
        if let (Some(input), Some(output)) = (&paths.probes_in, &paths.probe_out) {
            if same_file(input, output) {
                return Err(OutputError::SameTarget {
                    first: "probe input",
                    second: "probe",
                    path: output.to_path_buf(),
                });
            }
        }
        let mut targets = paths.targets();
        targets.extend(
            images
                .views
                .iter()
                .map(|v| (v.path.as_path(), "view image", Some(IMAGE_EXTENSIONS))),
        );
        for (i, (path, what, ext)) in targets.iter().enumerate() {
            check_target(path, what, *ext)?;
            if let Some((_, first, _)) = targets[..i].iter().find(|t| same_file(t.0, path)) {
                return Err(OutputError::SameTarget {
                    first,
                    second: what,
                    path: path.to_path_buf(),
                });
            }
        }
        let probes = match &paths.probes_in {
            Some(path) => read_probes(domain, path, &probe_settings)?,
            None => Vec::new(),
        };
        Ok(Self {
            paths,
            images,
            probes,
            probe_settings,
            lightmap: LightmapSettings::default(),
            lightmap_parts: Vec::new(),
            scene_camera: domain.scene_3d().is_some_and(|s| s.camera_given),
            flatland: domain.scene_flat().is_some(),
        })
    }

    /// Checks that `config` can compute the planned outputs (irradiance probes need the paths
    /// gather) and that the machine can hold the images ([`super::memory`]): call it before the
    /// solve.
    pub fn check_config(&self, config: &SolveConfig) -> Result<(), OutputError> {
        let irradiance = self.probe_settings.quantity.is_irradiance();
        if irradiance && !self.probes.is_empty() && config.gather != GatherMode::Paths {
            return Err(GatherError::IrradianceNeedsPaths(config.gather.name()).into());
        }
        // ⟨A shard writes its probes' and its lightmap texels' values and nothing else
        // (`super::shards`)⟩
        if config.paths.shard.is_some() {
            let p = &self.paths;
            let other = [
                (
                    p.image.is_some() || !self.images.views.is_empty(),
                    "an image",
                ),
                (p.mesh.is_some() || p.ply.is_some(), "a mesh"),
                (p.kernel_image.is_some(), "a kernel image"),
                (
                    p.probe_out.is_none() && p.lightmap.is_none(),
                    "a run without probes or a lightmap",
                ),
            ];
            if let Some((_, what)) = other.iter().find(|(asked, _)| *asked) {
                return Err(OutputError::ShardOutput(what));
            }
        }
        // ⟨An image or probes the machine cannot hold are refused now, not after the solve⟩
        let available = super::memory::available_memory();
        let images = self.paths.image.is_some() || !self.images.views.is_empty();
        if images && !self.flatland {
            let footprints = config.gather == GatherMode::Paths && !config.reads_networks();
            super::memory::check_image_memory(&self.images, footprints, available)?;
        }
        super::memory::check_probe_memory(self.probes.len(), available)?;
        Ok(())
    }

    /// Checks that the shard `config` asks for, if any, has probes: the probe set makes at least
    /// as many blocks as there are shards ([`crate::shard_points`]). Call it before the solve.
    pub fn check_shard(&self, domain: &Domain, config: &SolveConfig) -> Result<(), OutputError> {
        if config.paths.shard.is_some() && !self.probes.is_empty() {
            let irradiance = self.probe_settings.quantity != super::ProbeQuantity::Radiosity;
            crate::shard_points(domain, &self.probes, irradiance, config)?;
        }
        Ok(())
    }

    /// The plan with these lightmap settings, checked ([`LightmapSettings::validate`]).
    pub fn with_lightmap(mut self, settings: LightmapSettings) -> Result<Self, OutputError> {
        settings.validate()?;
        self.lightmap = settings;
        Ok(self)
    }

    /// The plan with the lightmap's texels taken from the partial outputs `parts` (file name,
    /// text) of a sharded bake instead of gathered (`--from-shards`; `super::shards`). The run
    /// must ask for the lightmap with the shards' settings and no shard of its own.
    pub fn with_lightmap_parts(
        mut self,
        parts: Vec<(String, String)>,
        config: &SolveConfig,
    ) -> Result<Self, OutputError> {
        if !parts.is_empty() {
            if self.paths.lightmap.is_none() {
                return Err(OutputError::MergeShards(
                    "--from-shards fills a lightmap's texels: ask for it with --lightmap".into(),
                ));
            }
            if config.paths.shard.is_some() {
                return Err(OutputError::MergeShards(
                    "--from-shards merges every shard: run it without --shard".into(),
                ));
            }
        }
        self.lightmap_parts = parts;
        Ok(self)
    }

    /// The checked image settings.
    pub fn images(&self) -> &ImageSettings {
        &self.images
    }

    /// The checked paths.
    pub fn paths(&self) -> &OutputPaths {
        &self.paths
    }

    /// The probes snapped onto the scene: `(point, normal, face)`, Flatland with z = 0.
    pub fn probes(&self) -> &[(DVec3, DVec3, u32)] {
        &self.probes
    }
}

/// Whether `choice` is placed automatically (from the output mesh's brightness) for a scene
/// with or without a camera of its own.
pub(super) fn is_automatic(choice: CameraChoice, scene_camera: bool) -> bool {
    match choice {
        CameraChoice::Given(_) => false,
        CameraChoice::Automatic { .. } => true,
        CameraChoice::Scene { .. } => !scene_camera,
    }
}

/// Whether two targets name the same file (same directory after resolving links, same name).
fn same_file(a: &Path, b: &Path) -> bool {
    let key = |p: &Path| {
        let dir = p.parent().filter(|d| !d.as_os_str().is_empty());
        let dir = std::fs::canonicalize(dir.unwrap_or(Path::new("."))).ok();
        (dir, p.file_name().map(|n| n.to_owned()))
    };
    a == b || key(a) == key(b)
}

/// Gathers, renders and writes every output of `plan` for a solution, and returns the run's
/// metrics: `trained.metrics` completed with the scene name, the gather, the output mesh, the
/// gather and output times, the total time since `started` and the peak memory (these are what
/// the metrics file holds). All files are written through [`StagedFiles`]: on an error no target
/// is created or changed.
pub fn write_outputs(
    domain: &Domain,
    trained: &Trained,
    config: &SolveConfig,
    plan: &OutputPlan,
    scene_name: &str,
    started: Instant,
) -> Result<Metrics, OutputError> {
    let paths = plan.paths();
    let mut metrics = trained.metrics.clone();
    metrics.scene = scene_name.to_string();
    metrics.gather = config.gather.name().to_string();
    metrics.scene_elements = domain.elements().len();
    let mut staged = StagedFiles::new();
    let emitters = Emitters::new(domain);
    if let Some(path) = &paths.probe_out {
        let tg = Instant::now();
        let probes = (plan.probes(), &plan.probe_settings);
        let _phase = crate::progress::phase("probes");
        let (text, stats) = probe_values(domain, trained, &emitters, config, probes)?;
        metrics.probe_quantity = plan.probe_settings.quantity.name().into();
        record_gather(&mut metrics, &stats, config);
        metrics.seconds.gather += tg.elapsed().as_secs_f64();
        staged.write_bytes(path, text.as_bytes())?;
    }
    if domain.scene_3d().is_some() {
        write_3d(domain, trained, config, plan, &mut metrics, &mut staged)?;
    } else if let Some(flat) = domain.scene_flat() {
        let to = Instant::now();
        if let Some(path) = &paths.image {
            let img = scene_image(domain, trained, &emitters, config, flat)?;
            staged.write(path, |w| write_png(&img, w))?;
        }
        if let Some(path) = &paths.kernel_image {
            if let Some(img) = light_flow_image(domain, trained) {
                staged.write(path, |w| write_png(&img, w))?;
            }
        }
        metrics.seconds.output += to.elapsed().as_secs_f64();
    }
    metrics.seconds.total = started.elapsed().as_secs_f64();
    metrics.peak_memory_bytes = peak_memory_bytes();
    if let Some(path) = &paths.metrics {
        let json = serde_json::to_string_pretty(&metrics).map_err(OutputError::Metrics)?;
        staged.write_bytes(path, json.as_bytes())?;
    }
    staged.commit()?;
    Ok(metrics)
}

/// The 3-D outputs: the re-triangulated output mesh (when glTF, PLY, a mesh-mode image or the
/// automatic camera asks for it), per-pixel images ([`super::pixel`]), one exposure for all of
/// them (given, else from the mesh's non-emitting triangles, else from the first pixel image's
/// lit hits), and the files.
fn write_3d(
    domain: &Domain,
    trained: &Trained,
    config: &SolveConfig,
    plan: &OutputPlan,
    metrics: &mut Metrics,
    staged: &mut StagedFiles,
) -> Result<(), OutputError> {
    let Some(scene) = domain.scene_3d() else {
        return Ok(());
    };
    let (paths, settings) = (plan.paths(), plan.images());
    let images = image_jobs(paths, settings);
    let pixel = settings.mode == ImageMode::Pixel;
    // ⟨The output mesh, when an output needs it⟩
    let tg = Instant::now();
    let mesh = if plan.needs_mesh() {
        let (mesh, stats) = output_mesh(domain, trained, config, RetriangulateLimits::default())?;
        record_gather(metrics, &stats, config);
        metrics.output_vertices = mesh.vertex_count();
        metrics.output_triangles = mesh.triangle_count();
        Some(mesh)
    } else {
        None
    };
    metrics.seconds.gather += tg.elapsed().as_secs_f64();
    // ⟨Each image's camera (the automatic one from the mesh's brightness, before any exposure
    // is known: its own)⟩
    let mesh_exposure = mesh.as_ref().map(|m| match settings.exposure {
        Some(scale) => Exposure { scale },
        None => exposure_of_mesh(m, scene),
    });
    let jobs = image_cameras(
        domain,
        scene,
        &images,
        mesh.as_ref().zip(mesh_exposure.as_ref()),
        settings,
    );
    // ⟨Per-pixel images: B gathered at every sub-sample's visible point⟩
    let tg = Instant::now();
    let mut rendered = Vec::new();
    if pixel {
        for (_, (camera, _)) in &jobs {
            let size = (settings.width, settings.height, settings.pixel_samples);
            let img = super::pixel::render_pixels(domain, trained, config, camera, size)?;
            record_gather(metrics, &img.stats, config);
            rendered.push(img);
        }
    }
    metrics.seconds.gather += tg.elapsed().as_secs_f64();
    // ⟨The lightmap: its own gather at the texels, its files⟩
    if let Some(path) = &paths.lightmap {
        write_lightmap(domain, trained, config, plan, path, metrics, staged)?;
    }
    let to = Instant::now();
    // ⟨One exposure for every tone-mapped output⟩
    let exposure = match (settings.exposure, &mesh_exposure, rendered.first()) {
        (Some(scale), _, _) => Exposure { scale },
        (None, Some(e), _) => *e,
        (None, None, Some(img)) => Exposure::auto(img.lit()),
        (None, None, None) => Exposure { scale: 1.0 },
    };
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
        metrics.warnings.extend(coverage.warning(&what));
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

/// Bakes the lightmap ([`crate::lightmap::bake_lightmap`]) and stages its .glb and EXR pages.
fn write_lightmap(
    domain: &Domain,
    trained: &Trained,
    config: &SolveConfig,
    plan: &OutputPlan,
    path: &Path,
    metrics: &mut Metrics,
    staged: &mut StagedFiles,
) -> Result<(), OutputError> {
    let Some(scene) = domain.scene_3d() else {
        return Err(OutputError::MeshNeeds3d);
    };
    let tg = Instant::now();
    let settings = &plan.lightmap;
    let texels = crate::lightmap::lay_out_texels(domain, settings)?;
    let points = texels.points();
    let print = || super::shards::fingerprint(domain, &points, config, &format!("{settings:?}"));
    // ⟨The texels' values: gathered (all of them, or a shard's), or the shards' merged⟩
    let gathered = if plan.lightmap_parts.is_empty() {
        let _phase = crate::progress::phase("lightmap");
        crate::lightmap::gather_texels(domain, trained, config, settings, &texels)?
    } else {
        merged_texels(&plan.lightmap_parts, &format!("{:016x}", print()))?
    };
    if let Some(shard) = config.paths.shard {
        // ⟨A shard writes its texels' estimates with their indices, nothing else⟩
        let irradiance = settings.quantity == crate::LightmapQuantity::Irradiance;
        let mine = crate::shard_points(domain, &points, irradiance, config)?;
        let theirs: Vec<Gathered> = mine.iter().map(|&i| gathered[i]).collect();
        record_gather(metrics, &GatherStats::of(&theirs), config);
        metrics.seconds.gather += tg.elapsed().as_secs_f64();
        let lines: Vec<String> = gathered.iter().map(super::shards::gathered_line).collect();
        let kind = super::shards::Kind::Lightmap;
        let text = super::shards::partial_text(kind, shard, print(), &lines, &mine);
        let part = super::shards::lightmap_part_path(path, shard);
        check_target(&part, "lightmap shard", None)?;
        staged.write_bytes(&part, text.as_bytes())?;
        return Ok(());
    }
    metrics.warnings.extend(texels.atlas.note.clone());
    let lightmap = crate::lightmap::assemble_lightmap(texels, &gathered, settings);
    record_gather(metrics, &lightmap.stats, config);
    metrics.seconds.gather += tg.elapsed().as_secs_f64();
    let to = Instant::now();
    let scale = super::lightmap::png_scale(&lightmap);
    let io = |source| OutputError::Write {
        path: path.to_path_buf(),
        source,
    };
    let glb = super::lightmap::to_lightmap_glb(&lightmap, scene, scale).map_err(io)?;
    staged.write_bytes(path, &glb)?;
    let pages = super::lightmap::page_paths(path, lightmap.atlas.pages);
    for (k, page) in pages.iter().enumerate() {
        check_target(page, "lightmap page", Some("exr"))?;
        let exr = super::lightmap::encode_page_exr(&lightmap, k).map_err(io)?;
        staged.write_bytes(page, &exr)?;
    }
    metrics.lightmap = Some(crate::metrics::LightmapRecord {
        path: path.display().to_string(),
        pages: lightmap.atlas.pages,
        width: lightmap.atlas.width,
        height: lightmap.atlas.height,
        texels_per_unit: lightmap.atlas.texels_per_unit,
        charts: lightmap.atlas.charts,
        uv_source: if lightmap.atlas.from_input {
            "input"
        } else {
            "unwrapped"
        },
        utilization: lightmap.atlas.utilization,
        texels: lightmap.texels.len(),
        left_out: lightmap.left_out,
        png_scale: scale,
    });
    metrics.seconds.output += to.elapsed().as_secs_f64();
    Ok(())
}

/// The texels' estimates from the partial lightmap outputs `parts` of a sharded bake, merged
/// ([`super::shards::merge`]) and checked to be of this run (its `fingerprint`).
fn merged_texels(
    parts: &[(String, String)],
    fingerprint: &str,
) -> Result<Vec<Gathered>, OutputError> {
    let merged =
        super::shards::merge(parts).map_err(|e| OutputError::MergeShards(e.to_string()))?;
    if merged.kind != super::shards::Kind::Lightmap {
        return Err(OutputError::MergeShards(
            "these are shards of probes: `gcr merge` joins them".into(),
        ));
    }
    if merged.fingerprint != fingerprint {
        return Err(OutputError::MergeShards(format!(
            "the shards have fingerprint {}, this run {fingerprint}: they are of another scene, \
             lightmap or solve settings (give the options of the shard runs, --shard excepted, \
             --block-points included)",
            merged.fingerprint
        )));
    }
    (merged.text.lines().enumerate())
        .map(|(i, line)| {
            super::shards::parse_gathered(line).ok_or_else(|| {
                OutputError::MergeShards(format!("texel {i}: not an estimate: `{line}`"))
            })
        })
        .collect()
}

/// The automatic exposure of a mesh's outputs: from the radiosity of its faces that do not emit.
pub(super) fn exposure_of_mesh(mesh: &ShadedMesh, scene: &scene_sampler::Scene) -> Exposure {
    let lit = (mesh.triangles.iter())
        .zip(&mesh.face_of_triangle)
        .filter(|(_, f)| scene.faces[**f as usize].emission.is_zero())
        .map(|(t, _)| mesh.radiosity[t[0] as usize]);
    Exposure::auto(lit)
}

/// Records what the output gather measured (the last output set wins: the mesh after the
/// probes) and the target it ran to, with its warnings ([`gather_warnings`]).
fn record_gather(metrics: &mut Metrics, stats: &GatherStats, config: &SolveConfig) {
    metrics.network_share = stats.network_share;
    metrics.relative_std_error = stats.relative_std_error;
    metrics.gather_rays = stats.rays;
    metrics.guided = stats.guided;
    metrics.target_error = config.paths.target_error;
    metrics.warnings.extend(gather_warnings(stats, config));
}

/// What the numbers of a gather cannot say: no light at all, a target the ray cap kept out of
/// reach (the warnings of the metrics and of `gcr solve`).
pub fn gather_warnings(stats: &GatherStats, config: &SolveConfig) -> Vec<String> {
    let mut warnings = Vec::new();
    if stats.dark {
        warnings.push(
            "every output point got 0: no light reaches them (a light inside closed geometry or \
             behind the surfaces, a sun below the horizon, or reflectance 0 everywhere?)"
                .into(),
        );
    }
    if let (Some(target), Some(error)) = (config.paths.target_error, stats.relative_std_error) {
        if error > target && stats.rays >= config.paths.max_rays {
            warnings.push(format!(
                "the target error {:.3} % was not met: {:.3} % at the cap of {} rays per point",
                100.0 * target,
                100.0 * error,
                config.paths.max_rays
            ));
        }
    }
    warnings
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

/// Each image's camera with its source name: the given one, the scene's, or the automatic one
/// (from the mesh's brightness at its own exposure, before the outputs' exposure is known).
fn image_cameras<'a>(
    domain: &Domain,
    scene: &Scene,
    images: &[(&'a Path, CameraChoice, &'static str)],
    mesh: Option<(&ShadedMesh, &Exposure)>,
    settings: &ImageSettings,
) -> Vec<(&'a Path, (PinholeCamera, &'static str))> {
    (images.iter())
        .map(|&(path, choice, source)| {
            let camera = camera_of(domain, scene, (choice, source), mesh, settings);
            (path, camera)
        })
        .collect()
}

/// One image's camera with its source name (`source` for a given camera): the given one, the
/// scene's, or the automatic one (from `mesh` at its exposure: present whenever
/// [`is_automatic`]).
pub(super) fn camera_of(
    domain: &Domain,
    scene: &Scene,
    (choice, source): (CameraChoice, &'static str),
    mesh: Option<(&ShadedMesh, &Exposure)>,
    settings: &ImageSettings,
) -> (PinholeCamera, &'static str) {
    match choice {
        CameraChoice::Given(c) => (c, source),
        CameraChoice::Scene { fov } if scene.camera_given => {
            let mut c = PinholeCamera::of_scene(scene);
            c.fov_y_degrees = fov.unwrap_or(c.fov_y_degrees);
            (c, "scene")
        }
        CameraChoice::Scene { fov } | CameraChoice::Automatic { fov } => {
            let (mesh, exposure) =
                mesh.expect("the automatic camera's outputs build the mesh (needs_mesh)");
            automatic(domain, mesh, exposure, settings, fov)
        }
    }
}

/// Writes a per-pixel image: linear radiance for .exr, tone-mapped for PNG and JPEG.
fn write_pixel_image(
    img: &super::pixel::PixelImage,
    exposure: &Exposure,
    path: &Path,
    staged: &mut StagedFiles,
) -> Result<Coverage, OutputError> {
    let format = format_of(path);
    let radiance = img.radiance();
    if format == Format::Exr {
        let bytes = super::hdr::encode_exr(&radiance).map_err(|source| OutputError::Write {
            path: path.to_path_buf(),
            source,
        })?;
        staged.write_bytes(path, &bytes)?;
        return Ok(radiance.coverage);
    }
    let rgb = image::RgbImage::from_raw(radiance.width, radiance.height, img.tone_mapped(exposure))
        .expect("a pixel image has w·h RGB pixels");
    if format == Format::Jpeg {
        staged.write(path, |out| write_jpeg(&rgb, out))?;
    } else {
        staged.write(path, |out| write_png(&rgb, out))?;
    }
    Ok(radiance.coverage)
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

/// The automatic camera ([`super::autocam`]) for the solved mesh, with its source name.
fn automatic(
    domain: &Domain,
    mesh: &ShadedMesh,
    exposure: &Exposure,
    settings: &ImageSettings,
    fov: Option<f64>,
) -> (PinholeCamera, &'static str) {
    let Domain::ThreeD(k) = domain else {
        unreachable!("3-D outputs only for 3-D domains")
    };
    let brightness = face_brightness(mesh, exposure, k.scene.faces.len());
    let aspect = f64::from(settings.width) / f64::from(settings.height);
    let auto = super::autocam::automatic_camera(k.scene, k.bvh, &brightness, aspect, fov);
    let source = if auto.inside {
        "automatic-inside"
    } else {
        "automatic-outside"
    };
    (auto.camera, source)
}

/// Per scene face, the mean display luminance (in [0, 1]) of its output triangles.
fn face_brightness(mesh: &ShadedMesh, exposure: &Exposure, faces: usize) -> Vec<f64> {
    let mut sum = vec![(0.0, 0usize); faces];
    for (t, &f) in mesh.triangles.iter().zip(&mesh.face_of_triangle) {
        let mut b = [0.0; 3];
        for &v in t {
            for ch in 0..3 {
                b[ch] += mesh.radiosity[v as usize][ch] / 3.0;
            }
        }
        if let Some(s) = sum.get_mut(f as usize) {
            s.0 += luminance(exposure.linear(b));
            s.1 += 1;
        }
    }
    sum.into_iter()
        .map(|(s, n)| if n > 0 { s / n as f64 } else { 0.0 })
        .collect()
}

/// An image's file format, from its extension (checked by [`OutputPlan::with_images`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Format {
    Png,
    Jpeg,
    Exr,
}

fn format_of(path: &Path) -> Format {
    match path.extension().map(|e| e.to_string_lossy().to_lowercase()) {
        Some(e) if e == "exr" => Format::Exr,
        Some(e) if e == "jpg" || e == "jpeg" => Format::Jpeg,
        _ => Format::Png,
    }
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
    let format = format_of(path);
    if format == Format::Exr {
        let img = render_radiance(mesh, Some(scene), camera, w, h, IMAGE_SUPERSAMPLING);
        let bytes = super::hdr::encode_exr(&img).map_err(|source| OutputError::Write {
            path: path.to_path_buf(),
            source,
        })?;
        staged.write_bytes(path, &bytes)?;
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
    if format == Format::Jpeg {
        staged.write(path, |out| write_jpeg(&rgb, out))?;
    } else {
        staged.write(path, |out| write_png(&rgb, out))?;
    }
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

/// Encodes `img` as JPEG (quality 92) into `w`.
pub fn write_jpeg(img: &image::RgbImage, w: &mut dyn Write) -> std::io::Result<()> {
    encode(
        image::codecs::jpeg::JpegEncoder::new_with_quality(w, 92),
        img,
    )
}

/// Encodes `img` as PNG into `w` (the encoder `image::save` uses for .png, same bytes).
pub fn write_png(img: &image::RgbImage, w: &mut dyn Write) -> std::io::Result<()> {
    encode(image::codecs::png::PngEncoder::new(w), img)
}

/// `img` through `encoder`, its errors as I/O errors.
fn encode(encoder: impl image::ImageEncoder, img: &image::RgbImage) -> std::io::Result<()> {
    encoder
        .write_image(
            img.as_raw(),
            img.width(),
            img.height(),
            image::ExtendedColorType::Rgb8,
        )
        .map_err(|e| match e {
            image::ImageError::IoError(e) => e,
            other => std::io::Error::other(other),
        })
}

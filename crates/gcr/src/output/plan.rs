//! The outputs of a solve, checked before it: [`OutputPlan::new`] checks every path and reads
//! the probes *before* the solve (a bad probe line or an unwritable path is reported in
//! milliseconds, not after the solve); [`super::write_outputs`] then writes them all at once.

use super::OutputError;
use super::camera::{CameraChoice, ImageMode, ImageSettings};
use super::encode::{Format, format_of};
use super::probes::{ProbeSettings, read_probes};
use super::shards::{Kind, Merged, merge, merged_estimates};
use super::staged::check_target;
use crate::config::{GatherMode, Guiding, SolveConfig};
use crate::domain::Domain;
use crate::estimator::GatherError;
use crate::gather::Gathered;
use crate::lightmap::LightmapSettings;
use glam::DVec3;
use std::path::{Path, PathBuf};

/// The extensions an image output accepts (the format follows the extension): tone-mapped PNG
/// and JPEG, linear OpenEXR (3-D only).
pub const IMAGE_EXTENSIONS: &str = "png|jpg|jpeg|exr";

/// Where the outputs of a solve go; `None` skips an output.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct OutputPaths {
    /// Image (.png, .jpg, .jpeg; .exr for 3-D scenes): from the camera of
    /// `ImageSettings::camera` (3-D) or of the whole scene (Flatland, PNG).
    pub image: Option<PathBuf>,
    /// Flatland only: PNG of the light flow over the kernel domain
    /// (`output/flatland.rs`, `light_flow_image`).
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
/// [`super::write_outputs`] needs, built before the solve.
#[derive(Clone, Debug)]
pub struct OutputPlan {
    paths: OutputPaths,
    images: ImageSettings,
    probes: Vec<(DVec3, DVec3, u32)>,
    pub(super) probe_settings: ProbeSettings,
    pub(super) lightmap: LightmapSettings,
    /// The merged shards (`--from-shards`; `super::shards`) whose estimates the lightmap's texels
    /// or the image's pixels take instead of gathering them.
    from_shards: Option<Merged>,
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

    /// Whether the outputs need the output mesh: glTF, PLY, images in mesh mode; a Flatland
    /// image. (The automatic camera reads a quick gather of its own: `camera_choice.rs`.)
    pub(super) fn needs_mesh(&self) -> bool {
        let p = &self.paths;
        let images = p.image.is_some() || !self.images.views.is_empty();
        p.mesh.is_some()
            || p.ply.is_some()
            || (images && (self.images.mode == ImageMode::Mesh || self.flatland))
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
    /// parts of a sharded lightmap or image to merge ([`OutputPlan::with_lightmap`],
    /// [`OutputPlan::with_shards`]), then what `config` can compute and the machine hold
    /// ([`OutputPlan::check_config`]) and its shard ([`OutputPlan::check_shard`]).
    pub fn checked(
        domain: &Domain,
        (paths, images, probe_settings): (OutputPaths, ImageSettings, ProbeSettings),
        (lightmap, parts): (LightmapSettings, Vec<(String, String)>),
        config: &SolveConfig,
    ) -> Result<Self, OutputError> {
        let plan = Self::with_options(domain, paths, images, probe_settings)?
            .with_lightmap(lightmap)?
            .with_shards(parts, config)?;
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
            from_shards: None,
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
        if self.paths.lightmap.is_some()
            && self.lightmap.denoise
            && config.gather != GatherMode::Paths
        {
            return Err(crate::lightmap::LightmapError::Settings(format!(
                "--lightmap-denoise needs the paths gather (the default), whose replicates measure \
                 the noise it weighs; not --gather {}",
                config.gather.name()
            ))
            .into());
        }
        // ⟨A shard writes its probes', its lightmap texels' and its pixels' values and nothing
        // else (`super::shards`); an image merged from shards is a shard's image⟩
        if config.paths.shard.is_some() || self.merges(Kind::Image) {
            let p = &self.paths;
            let footprints = config.gather == GatherMode::Paths && !config.reads_networks();
            let other = [
                (!self.images.views.is_empty(), "a --view image"),
                (
                    p.image.is_some() && self.images.mode != ImageMode::Pixel,
                    "an image in mesh mode",
                ),
                (
                    p.image.is_some() && is_automatic(self.images.camera, self.scene_camera),
                    "an image from the automatic camera",
                ),
                (
                    p.image.is_some() && !footprints,
                    "an image by a gather other than the default",
                ),
                (p.mesh.is_some() || p.ply.is_some(), "a mesh"),
                (p.kernel_image.is_some(), "a kernel image"),
                (
                    p.probe_out.is_none() && p.lightmap.is_none() && p.image.is_none(),
                    "a run without probes, a lightmap or an image",
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
        let guided = config.gather == GatherMode::Paths && config.paths.guiding == Guiding::On;
        super::memory::check_probe_memory(self.probes.len(), guided, available)?;
        Ok(())
    }

    /// Checks that the shard `config` asks for, if any, has probes: the probe set makes at least
    /// as many blocks as there are shards ([`crate::shard_points`]). Call it before the solve.
    /// Only where the solve costs time (it trains networks: their gather, or an output, reads
    /// them): the gather makes the same check as it forms the blocks (2.5 ms for 20 000 probes,
    /// measured).
    pub fn check_shard(&self, domain: &Domain, config: &SolveConfig) -> Result<(), OutputError> {
        let costly_solve = config.reads_networks() || self.needs_networks();
        if config.paths.shard.is_some() && !self.probes.is_empty() && costly_solve {
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

    /// The plan with the lightmap's texels or the image's pixels taken from the partial outputs
    /// `parts` (file name, text) of a sharded run instead of gathered (`--from-shards`;
    /// `super::shards`), merged now. The run must ask for that output with the shards' settings
    /// and no shard of its own.
    pub fn with_shards(
        mut self,
        parts: Vec<(String, String)>,
        config: &SolveConfig,
    ) -> Result<Self, OutputError> {
        if parts.is_empty() {
            return Ok(self);
        }
        let refuse = |what: &str| Err(OutputError::MergeShards(what.into()));
        if config.paths.shard.is_some() {
            return refuse("--from-shards merges every shard: run it without --shard");
        }
        let merged = merge(&parts).map_err(|e| OutputError::MergeShards(e.to_string()))?;
        match merged.kind {
            Kind::Probes => return refuse("these are shards of probes: `gcr merge` joins them"),
            Kind::Lightmap if self.paths.lightmap.is_none() => {
                return refuse("these are a lightmap's shards: ask for it with --lightmap");
            }
            Kind::Image if self.paths.image.is_none() => {
                return refuse("these are an image's shards: ask for it with --image");
            }
            _ => {}
        }
        self.from_shards = Some(merged);
        Ok(self)
    }

    /// Whether the run takes `kind`'s estimates from merged shards ([`OutputPlan::with_shards`]).
    pub(super) fn merges(&self, kind: Kind) -> bool {
        self.from_shards.as_ref().is_some_and(|m| m.kind == kind)
    }

    /// The estimates of the merged shards of `kind` (one per point, in order), checked to be of
    /// this run: its `fingerprint` ([`super::shards::fingerprint`]).
    pub(super) fn merged_shards(
        &self,
        kind: Kind,
        fingerprint: u64,
    ) -> Result<Vec<Gathered>, OutputError> {
        let merged = (self.from_shards.as_ref()).ok_or_else(|| {
            OutputError::MergeShards(format!("no {} shards to merge", kind.words().0))
        })?;
        merged_estimates(merged, kind, &format!("{fingerprint:016x}"))
            .map_err(OutputError::MergeShards)
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

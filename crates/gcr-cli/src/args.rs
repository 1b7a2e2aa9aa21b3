//! The command line (clap derive): `gcr scenes`, `gcr solve`, `gcr reference`.

use clap::{Args, Parser, Subcommand};
use gcr::output::PinholeCamera;
use gcr::output::{
    CameraChoice, ImageMode, ImageSettings, OutputPaths, ProbeQuantity, ProbeSettings, View,
};
use gcr::{
    GatherMode, NetworkTarget, OutputFit, Quality, SolveConfig, SolveOptions, SurfaceClusters,
};
use scene_sampler::AnyScene;
use scene_sampler::LoadOptions;
use scene_sampler::confine::{DEFAULT_MAX_FILE_BYTES, DEFAULT_MAX_TEXTURE_BYTES};
use std::path::PathBuf;

/// The heading of the options for research on the method (the networks, the dissertation's
/// gathers, the estimator's knobs): shown by `--help`, not by `-h`.
const RESEARCH: &str =
    "Research options (the networks, the dissertation's gathers; --help shows them)";

/// `gcr`'s arguments.
#[derive(Parser)]
#[command(
    name = "gcr",
    version,
    about = "Growing Cells Radiosity: radiosity on evolving networks (Bohn 2000)"
)]
pub struct Cli {
    /// The subcommand.
    #[command(subcommand)]
    pub command: Command,
}

/// The subcommands.
#[derive(Subcommand)]
pub enum Command {
    /// List the built-in scenes.
    Scenes,
    /// Solve a scene (a file: .obj, .gltf, .glb, Flatland .json; or a built-in name).
    Solve(Box<SolveArgs>),
    /// The pointwise path-traced reference (`baselines`) at probe points: B per probe with its
    /// standard error on stderr.
    Reference(Box<ReferenceArgs>),
    /// Join the partial probe outputs of `gcr solve --shard I/N` into the single run's probe
    /// output (byte for byte): every shard once, all of one run.
    Merge(MergeArgs),
}

/// `gcr merge`.
#[derive(Args)]
pub struct MergeArgs {
    /// The partial probe outputs, one per shard, in any order.
    #[arg(required = true)]
    pub parts: Vec<PathBuf>,
    /// Where to write the merged probe output.
    #[arg(long)]
    pub probe_out: PathBuf,
}

/// `gcr solve`.
#[derive(Args)]
#[command(group = clap::ArgGroup::new("shardable").args(["probes", "lightmap", "image"]).multiple(true))]
#[command(group = clap::ArgGroup::new("mergeable").args(["lightmap", "image"]).multiple(true))]
pub struct SolveArgs {
    /// Scene file or built-in name.
    pub scene: String,
    /// Kernel network cell budget ("links").
    #[arg(help_heading = RESEARCH, hide_short_help = true, long, default_value_t = SolveOptions::default().cells)]
    pub cells: usize,
    /// Shading network cell budget.
    #[arg(help_heading = RESEARCH, hide_short_help = true, long)]
    pub shading_cells: Option<usize>,
    /// Time budget of the solve in seconds: training stops early enough for the final FEM step to
    /// finish within it; the gather at the outputs (probes, mesh, image) comes after, its time
    /// reported in the metrics (`seconds.gather`).
    #[arg(help_heading = RESEARCH, hide_short_help = true, long)]
    pub time_budget: Option<f64>,
    /// Seed.
    #[arg(long, default_value_t = SolveOptions::default().seed)]
    pub seed: u64,
    /// Output gather: paths (the default: the ray gather plus a path-traced correction of the
    /// networks' error at the first `--corrections` rays, unbiased, run until `--quality` or
    /// `--target-error` is met, with the estimated error in the metrics and the closing line),
    /// or the dissertation's base, kernel and rays (approximate, no error estimate).
    #[arg(help_heading = RESEARCH, hide_short_help = true, long, default_value = "paths")]
    pub gather: GatherMode,
    /// The estimated relative error (standard error, relative L2 over the output points) to stop
    /// at: draft 5 %, good 2 %, final 1 % [default: good, unless --gather-rays fixes the rays].
    #[arg(long, conflicts_with = "target_error",
          value_parser = parse_quality)]
    pub quality: Option<Quality>,
    /// `--gather paths`: stop when the estimated relative error of the output is at most this
    /// (a fraction, e.g. 0.02 for 2 %); rounds of rays are added until it is, up to 65536 per
    /// point.
    #[arg(long, value_name = "E")]
    pub target_error: Option<f64>,
    /// Kernel output layer: `projection` (Galerkin projection of K·s on shot rays) or
    /// `delta-rule` (the dissertation's eq. 2.8).
    #[arg(help_heading = RESEARCH, hide_short_help = true, long, default_value = "projection")]
    pub output_fit: OutputFit,
    /// What the kernel network learns (with the projection it only places the cells):
    /// `clamped-kernel` (K·s with G's 1/r² clamped at 5 % of the scene's diagonal),
    /// `kernel-value` (the dissertation's K·s, which crowds cells into the edges where K is
    /// singular) or `sample-weight` (each shot ray's importance weight ρ·s/p_x).
    #[arg(help_heading = RESEARCH, hide_short_help = true, long, default_value = "clamped-kernel")]
    pub network_target: NetworkTarget,
    /// Shadow rays and cosine rays per point (each). The ray gather: 64 by default (more lower
    /// its own noise: two-blockers, 200 points: 6.2 % at 64, 4.4 % at 256, 3.9 % at 4096). The
    /// paths gather: alone, a fixed count (no target); with --quality or --target-error, the
    /// first round's (default 16).
    #[arg(help_heading = RESEARCH, hide_short_help = true, long)]
    pub gather_rays: Option<usize>,
    /// `--gather paths`: cosine rays per point whose hit gets a path-traced correction of the
    /// networks' value (default: all of them, so that the networks' value cancels and the gather is
    /// a path tracer with Sobol points at its first vertex; fewer read the networks, which measured
    /// less accurate per second on cornell-box).
    #[arg(help_heading = RESEARCH, hide_short_help = true, long)]
    pub corrections: Option<usize>,
    /// `--gather paths` to a target error: at most this many neighbouring output points (close for
    /// the points' density, facing alike) share each other's cosine rays and paths, each weighted
    /// for every member by the multi-sample balance heuristic (unbiased; docs/design/estimator.md).
    /// 1: every point alone.
    #[arg(help_heading = RESEARCH, hide_short_help = true, long, default_value_t = SolveOptions::default().share_paths as u32, value_parser = clap::value_parser!(u32).range(1..=64))]
    pub share_paths: u32,
    /// `--gather paths` to a target error: guide the rays where light is hard to find. At every
    /// path vertex, join a point drawn from a table of the surfaces the lights reach directly
    /// (the sun patch on a floor, a lit ceiling), and draw the cosine rays from guides learned
    /// from earlier rounds (both weighed against plain sampling: unbiased). auto: the table where
    /// a trial round finds light hard to find (one ray's relative variance at least 0.5) and the
    /// table halving it, or fairly hard (0.1–0.5, in a job of many rays) and the table dividing it
    /// by 10; the learned guides when the pilot round finds hard light (at least 8 192 rays
    /// per point to the target, each varying by more than 1.7 times the mean); off: plain paths;
    /// docs/design/estimator.md, "Guiding" and "Secondary sources".
    #[arg(help_heading = RESEARCH, hide_short_help = true, long, default_value = "auto", value_parser = ["auto", "on", "off"])]
    pub guiding: String,
    /// Train the shading network and build its base even when the gather does not read it
    /// (by default they are skipped: same result, less time).
    #[arg(help_heading = RESEARCH, hide_short_help = true, long)]
    pub keep_base: bool,
    /// Train the networks even when nothing reads them (the default paths gather skips them and
    /// the metrics say `stopped_by: "unused"`: the same values at probes and pixels, less time;
    /// an output mesh then starts from a uniform resolution instead of the shading network's).
    #[arg(help_heading = RESEARCH, hide_short_help = true, long)]
    pub keep_networks: bool,
    /// Facing masks on the projected kernel's Gaussians: each lives only on surfaces facing
    /// like the samples it was fitted to, so light does not blur across edges (sharper kernel
    /// gather on cluttered scenes, mass lost along edges of smooth fields).
    #[arg(help_heading = RESEARCH, hide_short_help = true, long)]
    pub kernel_facing: bool,
    /// Surfaces with at least this many elements get a cluster tree for the FEM integrals
    /// (nodes stand in for their elements where a Gaussian cannot resolve them).
    #[arg(help_heading = RESEARCH, hide_short_help = true, long, default_value_t = SolveOptions::default().surface_clusters.min_elements)]
    pub cluster_min_elements: usize,
    /// Cluster criterion θ: a node replaces its elements when a·R² ≤ θ (0: exact).
    #[arg(help_heading = RESEARCH, hide_short_help = true, long, default_value_t = SolveOptions::default().surface_clusters.theta)]
    pub cluster_theta: f64,
    /// Image: tone-mapped .png, .jpg/.jpeg, or linear radiance L = B/π as .exr (RGB float; 3-D
    /// scenes). From the --camera-* camera, else the scene's (a built-in's, a glTF camera
    /// node), else the automatic one (docs/guide/images.md).
    #[arg(help_heading = "Images", long)]
    pub image: Option<PathBuf>,
    /// Camera position X,Y,Z (with --camera-target). The convention is Mitsuba 3's
    /// `perspective` sensor with `to_world = look_at(eye, target, up)`, `fov_axis = y`.
    #[arg(help_heading = "Images", long, value_name = "X,Y,Z", value_parser = parse_vec3, requires = "camera_target",
          allow_hyphen_values = true)]
    pub camera_eye: Option<[f64; 3]>,
    /// The point the camera looks at, X,Y,Z (with --camera-eye).
    #[arg(help_heading = "Images", long, value_name = "X,Y,Z", value_parser = parse_vec3, requires = "camera_eye",
          allow_hyphen_values = true)]
    pub camera_target: Option<[f64; 3]>,
    /// The camera's up direction X,Y,Z (need not be orthogonal to the view direction).
    #[arg(help_heading = "Images", long, value_name = "X,Y,Z", value_parser = parse_vec3, requires = "camera_eye",
          allow_hyphen_values = true, default_value = "0,1,0")]
    pub camera_up: [f64; 3],
    /// Vertical field of view in degrees, in (0, 180) [default: 40 with --camera-eye; else the
    /// scene camera's, or the automatic camera's: 40 outside, 60 inside a closed scene].
    #[arg(
        help_heading = "Images",
        long,
        value_name = "DEG",
        allow_hyphen_values = true
    )]
    pub fov: Option<f64>,
    /// Place the camera automatically even when the scene has one (from inside closed scenes,
    /// framing open ones tightly).
    #[arg(help_heading = "Images", long, conflicts_with = "camera_eye")]
    pub auto_camera: bool,
    /// Image size in pixels, WIDTHxHEIGHT (each 1 to 16384).
    #[arg(help_heading = "Images", long, value_name = "WxH", value_parser = parse_resolution, default_value = "512x512")]
    pub resolution: (u32, u32),
    /// How 3-D images get B: `mesh` rasterizes the output mesh (B at its vertices,
    /// interpolated: fast, the bake's accuracy), `pixel` estimates each pixel with the output
    /// gather (the default paths gather: a path tracer over the pixel's footprint, to the target
    /// error of the pixels; no mesh needed).
    #[arg(help_heading = "Images", long, default_value = "mesh")]
    pub image_mode: ImageMode,
    /// `--image-mode pixel` with a gather that reads the networks: sub-samples per pixel (box
    /// filter; 1 is the pixel centre), 1 to 4096. The default paths gather gives every ray its
    /// own point in the pixel instead.
    #[arg(help_heading = RESEARCH, hide_short_help = true, long, default_value_t = 1)]
    pub pixel_samples: u32,
    /// Exposure of the tone-mapped outputs (PNG/JPEG, glTF and PLY colours): display value =
    /// clamp(L · exposure), L = B/π [default: automatic, the 95th percentile of the lit
    /// surfaces' luminance maps to 0.8]. The value used is printed and in the metrics.
    #[arg(help_heading = "Images", long, allow_hyphen_values = true)]
    pub exposure: Option<f64>,
    /// One more image of the same solve: `EYE;TARGET[;UP[;FOV]]=PATH`, vectors as X,Y,Z (up
    /// default 0,1,0, FOV default 40), PATH .png, .jpg or .exr; repeatable.
    #[arg(long, value_name = "EYE;TARGET[;UP[;FOV]]=PATH", value_parser = parse_view,
          allow_hyphen_values = true)]
    #[arg(help_heading = "Images")]
    pub view: Vec<View>,
    /// Flatland only: PNG of the light flow over the kernel domain (s of the sender to the
    /// right, t of the receiver upwards; fig. 4.1b): the sampled K·s on the left, the kernel
    /// network's Ψ on the right, dark = large; the training rays marked red on the right.
    #[arg(help_heading = RESEARCH, hide_short_help = true, long)]
    pub kernel_image: Option<PathBuf>,
    /// Binary glTF mesh with vertex colours (.glb).
    #[arg(help_heading = "Outputs", long)]
    pub mesh: Option<PathBuf>,
    /// A lightmap bake (.glb): the scene with a second UV set (TEXCOORD_1) and the light baked
    /// into texture pages there (MOZ_lightmap, 8-bit PNG with its scale), the linear pages beside
    /// it as `<NAME>-lightmap-<K>.exr` (docs/guide/lightmaps.md).
    #[arg(long, help_heading = "Lightmaps", value_name = "OUT.glb")]
    pub lightmap: Option<PathBuf>,
    /// Lightmap texels per scene unit [default: the highest density that fits one page].
    #[arg(
        long,
        help_heading = "Lightmaps",
        value_name = "TEXELS",
        requires = "lightmap",
        allow_hyphen_values = true
    )]
    pub lightmap_density: Option<f64>,
    /// Lightmap page width and height in texels (more pages when the atlas does not fit one).
    #[arg(long, help_heading = "Lightmaps", value_name = "N", default_value_t = gcr::LightmapSettings::default().page_size, requires = "lightmap")]
    pub lightmap_size: u32,
    /// Empty texels around each lightmap chart (filled from the chart's edge: no seams when
    /// filtered).
    #[arg(long, help_heading = "Lightmaps", value_name = "TEXELS", default_value_t = gcr::LightmapSettings::default().padding, requires = "lightmap")]
    pub lightmap_padding: u32,
    /// What the lightmap holds: `irradiance` E (what engines multiply by the albedo) or
    /// `radiosity` B (the surface's own brightness).
    #[arg(
        long,
        help_heading = "Lightmaps",
        default_value = "irradiance",
        requires = "lightmap"
    )]
    pub lightmap_quantity: gcr::LightmapQuantity,
    /// Denoise the lightmap: each texel averaged with its neighbours on the same surface over
    /// the scale Stein's unbiased risk estimate says is best there; the reported error includes
    /// the blur (docs/guide/lightmaps.md, "Denoising").
    #[arg(long, help_heading = "Lightmaps", requires = "lightmap")]
    pub lightmap_denoise: bool,
    /// Take the lightmap's texels, or the per-pixel image's pixels, from the partial outputs of
    /// `--shard` runs (`<NAME>.shard-I-of-N.txt`, every shard once) instead of gathering them, and
    /// write the files a single run writes, byte for byte; give the shard runs' options, --shard
    /// excepted.
    #[arg(
        long,
        help_heading = "Lightmaps",
        value_name = "PARTS",
        num_args = 1..,
        requires = "mergeable",
        conflicts_with = "shard"
    )]
    pub from_shards: Vec<PathBuf>,
    /// PLY mesh with radiosity per vertex (.ply).
    #[arg(help_heading = "Outputs", long)]
    pub ply: Option<PathBuf>,
    /// Probe points (`x y z nx ny nz` per line; Flatland `x y nx ny`).
    #[arg(help_heading = "Probes and work planes", long, requires = "probe_out")]
    pub probes: Option<PathBuf>,
    /// Where to write the probes' values (`r g b` per line, in the probe file's order).
    #[arg(help_heading = "Probes and work planes", long, requires = "probes")]
    pub probe_out: Option<PathBuf>,
    /// Estimate only shard INDEX of COUNT of the probes, of the lightmap's texels and of a
    /// per-pixel image's pixels (0 <= INDEX < COUNT; e.g. a Slurm array or Kubernetes indexed
    /// job's index): the probes with their indices to --probe-out, joined by `gcr merge`
    /// (docs/guide/probes.md, "Sharded runs"); the texels to `<NAME>.shard-INDEX-of-COUNT.txt`
    /// beside --lightmap's NAME.glb, the pixels beside --image's NAME.exr (--image-mode pixel,
    /// a fixed camera), joined by --from-shards (docs/guide/lightmaps.md, "Sharded bakes";
    /// docs/guide/images.md, "Sharded images"). Byte for byte the single run's.
    #[arg(
        help_heading = "Probes and work planes",
        long,
        value_name = "INDEX/COUNT",
        requires = "shardable"
    )]
    pub shard: Option<gcr::Shard>,
    /// The paths gather runs its rounds in blocks of at least this many points, each to the
    /// target on its own (a point's value then depends only on its block; a per-pixel image's
    /// blocks are strips of whole rows of at least N pixels); blocks are what --shard splits, so
    /// a sharded run needs them, the same in every shard and in any single run compared with it
    /// [default: one block, every point to the target together].
    #[arg(help_heading = "Probes and work planes", long, value_name = "N", value_parser = clap::builder::RangedU64ValueParser::<usize>::new().range(1..))]
    pub block_points: Option<usize>,
    /// What the probes get: `radiosity` (B at surface points: each probe snaps onto the nearest
    /// face its normal faces, within --probe-tolerance) or `irradiance` (E = ∫ L cos dω for the
    /// hemisphere about the probe's normal, at the point as given: on a surface or in the air,
    /// like Radiance's `rtrace -I`; needs the paths gather) or `daylight-factor` (that irradiance in
    /// percent of the outdoor illuminance of `--sky cie-overcast:LUX`, with no sun).
    #[arg(
        help_heading = "Probes and work planes",
        long,
        default_value = "radiosity",
        requires = "probes"
    )]
    pub probe_quantity: ProbeQuantity,
    /// Radiosity probes: the largest distance (scene units) from a probe to the surface it snaps
    /// onto (default 1e-4 of the scene's diagonal).
    #[arg(help_heading = "Probes and work planes", long, requires = "probes")]
    pub probe_tolerance: Option<f64>,
    /// JSON metrics.
    #[arg(help_heading = "Outputs", long)]
    pub metrics: Option<PathBuf>,
    /// No progress output.
    #[arg(long)]
    pub quiet: bool,
    /// What the scene file may make gcr read.
    #[command(flatten)]
    pub input: InputLimits,
    /// Lights beside the scene's own.
    #[command(flatten)]
    pub lights: LightArgs,
}

/// Lights given on the command line or in a lighting file, beside the scene's own emitting faces
/// (3-D scenes; `scene_sampler::lights::lighting` has the conventions, docs/guide/lights.md the
/// workflow).
#[derive(Args, Clone, Debug, Default)]
#[command(next_help_heading = "Lights (3-D scenes)")]
pub struct LightArgs {
    /// A sun at compass bearing AZ (0 north, 90 east) and elevation EL (degrees), with normal
    /// illuminance LUX, and angular diameter DIAM degrees (default 0.53; 0: sharp shadows).
    #[arg(long, value_name = "AZ,EL,LUX[,DIAM]", value_parser = scene_sampler::lights::lighting::parse_sun, allow_hyphen_values = true)]
    pub sun: Option<scene_sampler::lights::lighting::SunSpec>,
    /// A sky: uniform, cie-overcast, cie-clear (needs --sun) or perez (the Perez all-weather sky:
    /// needs --sun, whose normal illuminance and LUX set its clearness and brightness; lux), with
    /// its horizontal (diffuse) illuminance LUX.
    #[arg(long, value_name = "MODEL:LUX", value_parser = scene_sampler::lights::lighting::parse_sky)]
    pub sky: Option<scene_sampler::lights::lighting::SkySpec>,
    /// An environment map: an equirectangular .hdr or .exr of radiance (top row the zenith, the
    /// left edge north, east a quarter across: Mitsuba's envmap), turned ROT degrees about the
    /// zenith (its north then looks toward bearing ROT) and scaled by SCALE.
    #[arg(long, value_name = "FILE[,ROT[,SCALE]]", value_parser = scene_sampler::lights::lighting::parse_env)]
    pub env: Option<scene_sampler::lights::lighting::EnvSpec>,
    /// The ground's reflectance below the horizon (Radiance's ground glow: ρ·(sky + sun
    /// horizontal illuminance)/π); 0 for a black ground.
    #[arg(long, value_name = "RHO", default_value_t = scene_sampler::DEFAULT_GROUND_REFLECTANCE, requires = "sky")]
    pub ground_reflectance: f64,
    /// The zenith axis of --sun and --sky: y (glTF: north −Z, east +X) or z (Radiance: north +Y,
    /// east +X).
    #[arg(long, value_name = "AXIS", default_value = "y", value_parser = ["y", "z"])]
    pub up: String,
    /// A sky portal: an opening (window, skylight) through which the interior sees the sky, as
    /// its four corners in order around a parallelogram; the sky's shadow rays then go mostly
    /// through the portals (much less noise deep in daylit rooms). Repeatable.
    #[arg(long, value_name = "X,Y,Z,X,Y,Z,X,Y,Z,X,Y,Z", value_parser = scene_sampler::lights::lighting::parse_portal, allow_hyphen_values = true)]
    pub portal: Vec<[[f64; 3]; 4]>,
    /// Find the scene's openings (holes in walls and roofs: planar loops of boundary edges that no
    /// face covers) and use them as sky portals; each is printed. For interiors.
    #[arg(long)]
    pub auto_portals: bool,
    /// A point light at X,Y,Z with intensity CD (candela); repeatable.
    #[arg(long, value_name = "X,Y,Z,CD", value_parser = scene_sampler::lights::lighting::parse_point, allow_hyphen_values = true)]
    pub point_light: Vec<scene_sampler::lights::lighting::PointSpec>,
    /// A spot light at X,Y,Z shining along DX,DY,DZ with intensity CD, full within INNER and none
    /// beyond OUTER degrees of its axis; repeatable.
    #[arg(long, value_name = "X,Y,Z,DX,DY,DZ,CD,INNER,OUTER", value_parser = scene_sampler::lights::lighting::parse_spot, allow_hyphen_values = true)]
    pub spot_light: Vec<scene_sampler::lights::lighting::SpotSpec>,
    /// A JSON lighting file (its format in docs/guide/lights.md); options above add to it.
    #[arg(long, value_name = "FILE")]
    pub lights: Option<PathBuf>,
}

impl LightArgs {
    /// The library's light options ([`scene_sampler::LightOptions`]) these arguments give.
    pub fn options(&self) -> scene_sampler::LightOptions {
        use scene_sampler::lights::lighting::Up;
        scene_sampler::LightOptions {
            sun: self.sun.clone(),
            sky: self.sky.clone(),
            env: self.env.clone(),
            ground_reflectance: self.ground_reflectance,
            // `--up y` is the default: it leaves a lighting file's axis alone
            up: (self.up == "z").then_some(Up::Z),
            portals: self.portal.clone(),
            auto_portals: self.auto_portals,
            point_lights: self.point_light.clone(),
            spot_lights: self.spot_light.clone(),
            file: self.lights.clone(),
        }
    }

    /// Lights `loaded` (a 3-D scene) with these options ([`scene_sampler::LightOptions::light`]),
    /// naming the openings `--auto-portals` found on stderr unless `quiet`.
    pub fn light(&self, loaded: AnyScene, quiet: bool) -> anyhow::Result<AnyScene> {
        let lit = self.options().light(loaded)?;
        if self.auto_portals && !quiet {
            eprintln!("portals: {} opening(s) found", lit.found_portals.len());
            for c in &lit.found_portals {
                let v: Vec<String> = c.iter().flatten().map(|x| format!("{x:.6}")).collect();
                eprintln!("  --portal {}", v.join(","));
            }
        }
        Ok(lit.scene)
    }

    /// The outdoor horizontal illuminance of daylight factors
    /// ([`scene_sampler::LightOptions::outdoor_illuminance`]).
    pub fn outdoor_illuminance(&self) -> Option<f64> {
        self.options().outdoor_illuminance()
    }
}

impl SolveArgs {
    /// The settings given, as the library takes them ([`gcr::SolveOptions`]).
    pub fn options(&self) -> SolveOptions {
        SolveOptions {
            quality: self.quality,
            target_error: self.target_error,
            seed: self.seed,
            cells: self.cells,
            shading_cells: self.shading_cells,
            time_budget: self.time_budget,
            gather: self.gather,
            output_fit: self.output_fit,
            network_target: self.network_target,
            gather_rays: self.gather_rays,
            corrections: self.corrections,
            share_paths: self.share_paths as usize,
            block_points: self.block_points.unwrap_or(usize::MAX),
            shard: self.shard,
            guiding: self.guiding.parse().expect("clap checked the value"),
            keep_base: self.keep_base,
            keep_networks: self.keep_networks,
            kernel_facing: self.kernel_facing,
            surface_clusters: SurfaceClusters {
                min_elements: self.cluster_min_elements,
                theta: self.cluster_theta,
            },
        }
    }

    /// The solver settings (not yet validated: `SolveConfig::validate`):
    /// [`SolveOptions::config`], the library's [`SolveConfig::preset`] at `--quality` with the
    /// options given.
    pub fn config(&self) -> SolveConfig {
        self.options().config()
    }

    /// The image settings (not yet validated: `ImageSettings::validate`, through
    /// `OutputPlan::with_images`).
    pub fn images(&self) -> ImageSettings {
        let eye_target = (self.camera_eye.zip(self.camera_target))
            .map(|(eye, target)| (eye.into(), target.into()));
        let camera = CameraChoice::from_options(
            eye_target,
            self.camera_up.into(),
            self.fov,
            self.auto_camera,
        );
        ImageSettings {
            camera,
            width: self.resolution.0,
            height: self.resolution.1,
            exposure: self.exposure,
            views: self.view.clone(),
            mode: self.image_mode,
            pixel_samples: self.pixel_samples,
        }
    }

    /// The probe settings (not yet validated: `ProbeSettings::validate`, through
    /// `OutputPlan::with_options`).
    pub fn probe_settings(&self) -> ProbeSettings {
        ProbeSettings {
            quantity: self.probe_quantity,
            tolerance: self.probe_tolerance,
            outdoor_illuminance: self.lights.outdoor_illuminance(),
        }
    }

    /// The lightmap settings (not yet validated: `LightmapSettings::validate`, through
    /// `OutputPlan::with_lightmap`).
    pub fn lightmap_settings(&self) -> gcr::LightmapSettings {
        gcr::LightmapSettings {
            texels_per_unit: self.lightmap_density,
            page_size: self.lightmap_size,
            padding: self.lightmap_padding,
            quantity: self.lightmap_quantity,
            denoise: self.lightmap_denoise,
        }
    }

    /// The output files.
    pub fn outputs(&self) -> OutputPaths {
        OutputPaths {
            image: self.image.clone(),
            kernel_image: self.kernel_image.clone(),
            mesh: self.mesh.clone(),
            ply: self.ply.clone(),
            lightmap: self.lightmap.clone(),
            probes_in: self.probes.clone(),
            probe_out: self.probe_out.clone(),
            metrics: self.metrics.clone(),
        }
    }
}

/// `gcr reference`.
#[derive(Args)]
pub struct ReferenceArgs {
    /// Scene file or built-in name.
    pub scene: String,
    /// Probe points (`x y z nx ny nz` per line; Flatland `x y nx ny`).
    #[arg(long)]
    pub probes: PathBuf,
    /// Where to write B at the probes (`r g b` per line; Flatland grey: `b`).
    #[arg(long)]
    pub probe_out: PathBuf,
    /// `radiosity` (B at surface points, the probes snapped) or `irradiance` (E = ∫ L cos dω at
    /// each point as given, for the hemisphere about its normal: `rtrace -I`; 3-D scenes) or
    /// `daylight-factor` (that irradiance in percent of `--sky cie-overcast:LUX`'s LUX).
    #[arg(long, default_value = "radiosity")]
    pub probe_quantity: ProbeQuantity,
    /// Radiosity probes: the largest distance (scene units) from a probe to the surface it snaps
    /// onto (default 1e-4 of the scene's diagonal).
    #[arg(long)]
    pub probe_tolerance: Option<f64>,
    /// Where to write each probe's standard error of B (same layout as `--probe-out`) and its
    /// path count and relative error bound (`inf` where no path found light).
    #[arg(long)]
    pub std_out: Option<PathBuf>,
    /// Target relative standard error per probe and band.
    #[arg(long, default_value_t = 0.01)]
    pub rel_error: f64,
    /// Path cap per probe.
    #[arg(long, default_value_t = 1_000_000)]
    pub max_paths: usize,
    /// Seed.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// What the scene file may make gcr read.
    #[command(flatten)]
    pub input: InputLimits,
    /// Lights beside the scene's own.
    #[command(flatten)]
    pub lights: LightArgs,
}

/// What a scene file may make `gcr` read (docs/guide/bad-input.md, "Running on untrusted scenes"): by
/// default the files it names inside its own folder only, regular files of at most 2 GiB each, and
/// at most 1 GiB of decoded textures.
#[derive(Args, Clone, Copy, Debug)]
#[command(next_help_heading = "Untrusted scenes")]
pub struct InputLimits {
    /// Let the scene read files it names outside its own folder (`../`, absolute paths, `file://`
    /// URIs, symbolic links leading out): only for scenes you trust.
    #[arg(long)]
    pub allow_outside_files: bool,
    /// The largest file read for the scene (the scene file, its buffers, images, material
    /// libraries, textures), in MiB.
    #[arg(long, value_name = "MIB", default_value_t = DEFAULT_MAX_FILE_BYTES >> 20)]
    pub max_file_mib: u64,
    /// The largest memory the scene's textures may take decoded (12 bytes per texel), in MiB.
    #[arg(long, value_name = "MIB", default_value_t = DEFAULT_MAX_TEXTURE_BYTES >> 20)]
    pub max_texture_mib: u64,
    /// Read glTF doubleSided materials as one-sided: their faces get no back face (half the work
    /// for models whose surfaces are closed solids; the backs then absorb light).
    #[arg(long)]
    pub single_sided: bool,
}

impl InputLimits {
    /// The loader's options.
    pub fn load_options(&self) -> LoadOptions {
        LoadOptions {
            allow_outside: self.allow_outside_files,
            max_file_bytes: self.max_file_mib.saturating_mul(1 << 20),
            max_texture_bytes: self.max_texture_mib.saturating_mul(1 << 20),
            single_sided: self.single_sided,
        }
    }
}

/// `--quality`: draft, good or final.
fn parse_quality(s: &str) -> Result<Quality, String> {
    s.parse().map_err(|e: gcr::ConfigError| e.to_string())
}

/// `X,Y,Z` as three numbers (NaN and infinities parse; the camera check rejects them).
fn parse_vec3(s: &str) -> Result<[f64; 3], String> {
    let parts: Vec<&str> = s.split(',').map(str::trim).collect();
    let [x, y, z] = parts[..] else {
        return Err(format!("`{s}`: expected three numbers X,Y,Z"));
    };
    let num = |t: &str| {
        t.parse::<f64>()
            .map_err(|_| format!("`{s}`: `{t}` is not a number"))
    };
    Ok([num(x)?, num(y)?, num(z)?])
}

/// `WxH` as two integers.
fn parse_resolution(s: &str) -> Result<(u32, u32), String> {
    let (w, h) = s
        .split_once(['x', 'X'])
        .ok_or_else(|| format!("`{s}`: expected WIDTHxHEIGHT, e.g. 512x512"))?;
    let num = |t: &str| {
        t.trim()
            .parse::<u32>()
            .map_err(|_| format!("`{s}`: `{t}` is not a pixel count"))
    };
    Ok((num(w)?, num(h)?))
}

/// `EYE;TARGET[;UP[;FOV]]=PATH`.
fn parse_view(s: &str) -> Result<View, String> {
    let (spec, path) = s
        .split_once('=')
        .ok_or_else(|| format!("`{s}`: expected EYE;TARGET[;UP[;FOV]]=PATH"))?;
    if path.is_empty() {
        return Err(format!("`{s}`: no image path after `=`"));
    }
    let parts: Vec<&str> = spec.split(';').collect();
    if !(2..=4).contains(&parts.len()) {
        return Err(format!(
            "`{s}`: expected 2 to 4 `;`-separated parts before `=` (EYE;TARGET[;UP[;FOV]])"
        ));
    }
    let up = parts
        .get(2)
        .map_or(Ok([0.0, 1.0, 0.0]), |u| parse_vec3(u))?;
    let fov = match parts.get(3) {
        Some(f) => f
            .trim()
            .parse::<f64>()
            .map_err(|_| format!("`{s}`: field of view `{f}` is not a number"))?,
        None => gcr::output::DEFAULT_FOV,
    };
    Ok(View {
        camera: PinholeCamera {
            eye: parse_vec3(parts[0])?.into(),
            target: parse_vec3(parts[1])?.into(),
            up: up.into(),
            fov_y_degrees: fov,
        },
        path: PathBuf::from(path),
    })
}

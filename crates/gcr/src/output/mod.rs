//! Writers for a solved scene: PNG, JPEG and OpenEXR images, binary glTF, PLY, and the tone
//! mapping they share; [`write`] is the output stage of a solve (all files at once, checked
//! before the solve); `camera.rs` the image settings and `autocam.rs` the automatic camera;
//! [`render_linear`] an image as numbers and [`place_probes`] / [`gather_probes`] the probes at a
//! caller's points, as the files get them.

use std::path::PathBuf;

mod autocam;
mod camera;
mod camera_choice;
mod encode;
mod flatland;
mod glb;
mod gltf_bin;
mod lightmap;
mod linear;
pub mod memory;
mod mesh;
mod pixel;
mod plan;
mod ply;
mod probes;
mod raster;
pub mod shards;
mod stage;
mod staged;
mod tonemap;
mod views;
mod write;

pub use camera::DEFAULT_FOV;
pub use camera::{CameraChoice, CameraError, ImageMode, ImageSettings, View};
pub use encode::{write_jpeg, write_png};
pub use glb::{to_glb, write_glb};
pub use lightmap::{encode_page_exr, page_paths, png_scale, to_lightmap_glb};
pub use linear::{LinearImage, render_linear};
pub use mesh::{UNIFORM_MESH_TRIANGLES, output_mesh, vertex_gather_point};
pub use pixel::{PixelImage, render_pixels};
pub use plan::{IMAGE_EXTENSIONS, OutputPaths, OutputPlan};
pub use probes::{
    ProbePoints, ProbeQuantity, ProbeSettings, gather_probe_shard, gather_probes, place_probes,
};
pub use raster::{Image, PinholeCamera, RadianceImage, render_image};
pub use stage::gather_warnings;
pub use staged::{StagedFiles, check_target, remove_temporary_files};
pub use tonemap::Exposure;
pub use write::write_outputs;

/// Why outputs cannot be written (checked before the solve by [`OutputPlan::new`], or met
/// while writing by [`write_outputs`]).
#[derive(Debug, thiserror::Error)]
pub enum OutputError {
    /// A mesh or PLY output for a Flatland scene.
    #[error("a mesh, PLY or lightmap output needs a 3-D scene; this is a Flatland scene")]
    MeshNeeds3d,
    /// A kernel image for a 3-D scene.
    #[error(
        "a kernel image needs a Flatland scene (the 3-D kernel has four parameters); this is a \
         3-D scene"
    )]
    KernelImageNeedsFlatland,
    /// A probe tolerance out of range, or given for irradiance probes.
    #[error("probe tolerance {0}")]
    ProbeTolerance(String),
    /// Daylight factors without a CIE overcast sky alone to divide by.
    #[error(
        "daylight factors are defined under a CIE overcast sky and no sun: light the scene with \
         --sky cie-overcast:LUX (its LUX is the outdoor illuminance) and no --sun or --env"
    )]
    DaylightWithoutOvercast,
    /// An image that would take more memory than the machine has ([`memory`]).
    #[error(transparent)]
    ImageMemory(#[from] memory::ImageTooLarge),
    /// Probes that would take more memory than the machine has ([`memory`]).
    #[error(transparent)]
    ProbeMemory(#[from] memory::TooManyProbes),
    /// A shard that cannot be formed ([`crate::shard_points`]).
    #[error(transparent)]
    Shard(#[from] crate::ShardError),
    /// A shard (or an image merged from shards) asked for outputs other than probes, a lightmap
    /// and a per-pixel image from a fixed camera, or for none.
    #[error(
        "--shard splits the probes (--probes, --probe-out), a lightmap's texels (--lightmap) and \
         the pixels of one per-pixel image from a fixed camera (--image with --image-mode pixel \
         and --camera-eye/--camera-target or the scene's camera) and nothing else: {0} needs the \
         whole solution; run it without --shard"
    )]
    ShardOutput(&'static str),
    /// Lightmap or image shards that cannot be merged, or merged into another run.
    #[error("merging the shards: {0}")]
    MergeShards(String),
    /// Probes without a probe output, or the other way round.
    #[error("probes and a probe output go together: give both or neither")]
    ProbesWithoutOutput,
    /// A target that is a directory or has no file name.
    #[error("{what} output `{}`: not a file name (is it a directory?)", path.display())]
    NotAFile {
        /// Which output.
        what: &'static str,
        /// The target.
        path: PathBuf,
    },
    /// A target with the wrong extension (the format follows the option, not the name).
    #[error("{what} output `{}`: expected a {} file", path.display(), dotted(expected))]
    Extension {
        /// Which output.
        what: &'static str,
        /// The target.
        path: PathBuf,
        /// The extensions the format accepts, separated by `|` (`png|jpg|jpeg|exr`).
        expected: &'static str,
    },
    /// A target whose directory does not exist.
    #[error("{what} output `{}`: directory `{}` does not exist", path.display(), dir.display())]
    MissingDirectory {
        /// Which output.
        what: &'static str,
        /// The target.
        path: PathBuf,
        /// Its directory.
        dir: PathBuf,
    },
    /// A target whose directory does not accept new files.
    #[error("{what} output `{}`: cannot create a file there", path.display())]
    NotWritable {
        /// Which output.
        what: &'static str,
        /// The target.
        path: PathBuf,
        /// The error creating a test file beside it.
        source: std::io::Error,
    },
    /// Two outputs with one target.
    #[error("the {first} and {second} outputs both go to `{}`", path.display())]
    SameTarget {
        /// The first output.
        first: &'static str,
        /// The second output.
        second: &'static str,
        /// Their target.
        path: PathBuf,
    },
    /// A camera, resolution or exposure that cannot make an image.
    #[error(transparent)]
    Camera(#[from] CameraError),
    /// Camera, resolution, exposure, view or EXR options for a Flatland scene.
    #[error(
        "{0} needs a 3-D scene (Flatland images show the whole scene, tone-mapped); this is a \
         Flatland scene"
    )]
    ImageNeeds3d(&'static str),
    /// The probe file cannot be read or parsed, or a probe is off the scene's surfaces.
    #[error(transparent)]
    Probes(#[from] scene_sampler::SceneError),
    /// Writing a target failed (before any target was changed; only a failed rename, after the
    /// writes all succeeded, can leave the targets renamed before it in place).
    #[error("writing `{}`", path.display())]
    Write {
        /// The target.
        path: PathBuf,
        /// The I/O error.
        source: std::io::Error,
    },
    /// The metrics could not be serialized.
    #[error("serializing the metrics: {0}")]
    Metrics(serde_json::Error),
    /// The radiosity could not be gathered from the solution.
    #[error(transparent)]
    Gather(#[from] crate::estimator::GatherError),
    /// The lightmap could not be laid out or baked.
    #[error(transparent)]
    Lightmap(#[from] crate::lightmap::LightmapError),
}

/// `png|jpg|exr` as `.png, .jpg or .exr`.
fn dotted(extensions: &str) -> String {
    let dots: Vec<String> = extensions.split('|').map(|e| format!(".{e}")).collect();
    match dots.split_last() {
        Some((last, rest)) if !rest.is_empty() => format!("{} or {last}", rest.join(", ")),
        _ => dots.concat(),
    }
}

//! Metrics of one solve, assembled by [`crate::output::write_outputs`] and written as JSON by
//! `gcr solve --metrics`.

use serde::Serialize;

/// Wall time spent per phase of a solve, in seconds.
#[derive(Clone, Debug, Default, Serialize)]
pub struct PhaseTimes {
    /// Reading the scene and checking it (its files, textures, faces), by the program.
    pub load: f64,
    /// Building the scene's BVH, by the program.
    pub bvh: f64,
    /// Drawing rays and evaluating the kernel goal function (tracing visibility).
    pub sampling: f64,
    /// Training steps of the kernel network (USL, SL, insertions, deletions).
    pub kernel_training: f64,
    /// Training steps of the shading network.
    pub shading_training: f64,
    /// FEM steps: base, Gram matrix, orthonormalization, transfer, sample updates.
    pub fem: f64,
    /// Resampling of critical regions.
    pub resampling: f64,
    /// Re-triangulation and the final gather at the output vertices.
    pub gather: f64,
    /// Writing images and meshes.
    pub output: f64,
    /// Everything, end to end.
    pub total: f64,
}

/// A baked lightmap, as the metrics record it.
#[derive(Clone, Debug, Default, Serialize)]
pub struct LightmapRecord {
    /// The .glb written (its pages beside it).
    pub path: String,
    /// Atlas pages.
    pub pages: u32,
    /// Page width in texels.
    pub width: u32,
    /// Page height in texels.
    pub height: u32,
    /// Texels per scene unit.
    pub texels_per_unit: f64,
    /// Charts (0 when the input's own `TEXCOORD_1` is the layout).
    pub charts: u32,
    /// Where the layout came from: `"input"` (the scene's `TEXCOORD_1`) or `"unwrapped"`.
    pub uv_source: &'static str,
    /// Share of the pages' texels covered by charts.
    pub utilization: f64,
    /// Texels estimated.
    pub texels: usize,
    /// Texels left out under geometry (filled by dilation).
    pub left_out: usize,
    /// The 8-bit pages' scale (PNG value = linear value × scale, sRGB-encoded).
    pub png_scale: f64,
    /// What the denoiser did (`--lightmap-denoise`), when it ran.
    pub denoised: Option<DenoiseRecord>,
}

/// What the lightmap denoiser did (`lightmap/denoise.rs`).
#[derive(Clone, Debug, Serialize)]
pub struct DenoiseRecord {
    /// The texels' estimated relative error before denoising (the solve's `relative_std_error`
    /// is the denoised one's).
    pub raw_error: Option<f64>,
    /// The share of the texels left as they were (their region chose no averaging).
    pub unfiltered: f64,
    /// The texels' mean spatial σ of the chosen filters, in texels.
    pub mean_sigma: f64,
    /// Seconds spent on the guide bake and on the filters.
    pub guide_seconds: f64,
    /// Seconds spent on the filters.
    pub filter_seconds: f64,
}

/// Everything a user may want to know about a solve.
#[derive(Clone, Debug, Default, Serialize)]
pub struct Metrics {
    /// Scene name or file.
    pub scene: String,
    /// Number of integration elements: Flatland segments, or 3-D triangles with coplanar pairs
    /// merged into quadrilaterals (cornell-box: 38 triangles → 20 elements).
    pub scene_elements: usize,
    /// Colour bands solved (1 for grey scenes, 3 for RGB).
    pub bands: usize,
    /// Seed of the run.
    pub seed: u64,
    /// Worker threads used.
    pub threads: usize,
    /// Kernel network cells ("links") at the end.
    pub kernel_cells: usize,
    /// Shading network cells at the end.
    pub shading_cells: usize,
    /// Shading network simplices used as the integration domain in the last FEM step.
    pub shading_triangles: usize,
    /// Training samples (rays) held at the end.
    pub samples: usize,
    /// Rays traced for visibility in total (sampling, resampling, gather).
    pub rays_traced: u64,
    /// FEM steps executed.
    pub fem_steps: usize,
    /// Light bounces propagated through projected kernels (`--output-fit projection`).
    pub bounces: usize,
    /// Bounce iterations stopped because their changes grew (a projected kernel with a mode of
    /// gain above 1; the strengths went back to the bounce with the smallest change).
    pub diverging_bounces_stopped: usize,
    /// Projections redone with a higher rejection threshold (0.5, then 0.9) because their
    /// bounces diverged: fewer, nearly orthogonal kernel cells, a stable but coarser fit.
    pub stabilized_projections: usize,
    /// Kernel cells left out of the last projection for want of samples in their support
    /// (`SolveConfig::projection_min_support`).
    pub unsupported_cells: usize,
    /// Kernel output layer: `delta-rule` or `projection`.
    pub output_fit: String,
    /// Kernel network training target with the projection: `kernel-value` or `sample-weight`.
    pub network_target: String,
    /// Kernel training steps executed.
    pub training_steps: u64,
    /// Base components rejected as nearly dependent in the last FEM step.
    pub rejected_base_components: usize,
    /// Output mesh vertices and triangles.
    pub output_vertices: usize,
    /// Output mesh triangles.
    pub output_triangles: usize,
    /// Gather mode used for the output (`base`, `kernel`, `rays` or `paths`).
    pub gather: String,
    /// Share of the output radiosity (area-weighted, all bands) that came from the networks
    /// (indirect light), as opposed to exact emission and, with `rays`, exact direct light.
    pub network_share: f64,
    /// Estimated relative error of the output, ‖σ‖₂/‖B‖₂ over its estimated points (not the
    /// emitters, whose B = E is exact) and bands from each point's standard error: measured by the `paths` gather (unbiased, so this is its whole
    /// error), None for the others (their error is mostly the networks' bias, which they cannot
    /// see). From the mesh when one is written, else from the probes. Each point's σ has one degree
    /// of freedom (two Sobol replicates): over thousands of points it predicts the error to a few
    /// per cent (docs/design/estimator.md), over a handful it is rough (cornell-box's 18 reflecting
    /// probes: 2.3 % estimated, 3.6 % measured).
    pub relative_std_error: Option<f64>,
    /// The error the paths gather was asked to stop at (`--target-error`, `--quality`), None
    /// without one.
    pub target_error: Option<f64>,
    /// Shadow and cosine rays (each) per point of the output gather: the most any point got
    /// (with a target error, the rounds' sum); 0 for the base and kernel gathers.
    pub gather_rays: usize,
    /// Whether the paths gather guided its rays (`--guiding`: `auto`, the default, guides when
    /// the pilot round finds hard light, `Guiding::pays`).
    pub guided: bool,
    /// What `--guiding auto`'s trial measured before the rounds to a target (one ray's relative
    /// variance; the table of secondary sources' variance ratio and whether it was kept) of the
    /// output the error is reported for (its last gather: a mesh's last refinement level), None
    /// where no trial ran (`--guiding on|off`, no target, a merge of shards).
    pub guiding_trial: Option<crate::gather::GuidingTrial>,
    /// Energy balance of the final projection: the reflected power of the projected kernel,
    /// ∫_S B_refl, over the power the shot samples carry (their Monte-Carlo estimate of the same
    /// integral), before the energy correction rescales it to 1. `None` when not measured
    /// (delta-rule output layer, or `energy_correction` off).
    pub energy_balance: Option<f64>,
    /// Time per phase.
    pub seconds: PhaseTimes,
    /// Peak resident memory of the process in bytes (Linux: VmHWM), if known.
    pub peak_memory_bytes: Option<u64>,
    /// The reason the training stopped (`cells`, `time`, `error`, `steps`), or `unused` when the
    /// networks were not trained because nothing read them (`Trained::without_networks`).
    pub stopped_by: String,
    /// Direct solves of the linearized bounce (the final propagation's fixed point, found by LU
    /// instead of ~1/(1 − ρ) bounces; `SolveConfig::direct_solve_cells`).
    pub direct_solves: usize,
    /// Bounces of the final propagation alone (after a direct solve: the polishing bounces).
    pub final_bounces: usize,
    /// What the solve noticed and the user should know (the result is still what was asked).
    pub warnings: Vec<String>,
    /// Exposure of the tone-mapped outputs (PNG and JPEG images, glTF and PLY vertex colours):
    /// display value = clamp(L · exposure) with L = B/π, then the sRGB curve for images. `None`
    /// when the run wrote none of them (EXR images are linear radiance, not exposed).
    pub exposure: Option<f64>,
    /// How [`Metrics::exposure`] was set: `given` (`--exposure`) or `auto` (the 95th percentile
    /// of the lit surfaces' luminance maps to 0.8); empty without an exposure.
    pub exposure_source: String,
    /// What the probe output holds: `radiosity` or `irradiance`; empty without probes.
    pub probe_quantity: String,
    /// The 3-D images written, with the cameras they were rendered from.
    pub images: Vec<ImageRecord>,
    /// The lightmap written, if any.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub lightmap: Option<LightmapRecord>,
}

/// One 3-D image written by a solve.
#[derive(Clone, Debug, Default, Serialize)]
pub struct ImageRecord {
    /// Its file.
    pub path: String,
    /// `png`, `jpeg` or `exr`.
    pub format: String,
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Camera eye (Mitsuba `look_at` origin).
    pub eye: [f64; 3],
    /// Camera target.
    pub target: [f64; 3],
    /// Camera up.
    pub up: [f64; 3],
    /// Vertical field of view in degrees.
    pub fov_y_deg: f64,
    /// Where the camera came from: `given` (command line), `view` (`--view`), `scene` (a
    /// built-in's or a glTF camera node), `automatic-inside` or `automatic-outside`.
    pub camera_source: String,
    /// Share of the sub-samples that see the front (lit side) of a surface.
    pub front_share: f64,
    /// Share that see the front of a surface with B > 0 (what the picture shows lit; the front of
    /// a surface no light reaches is black).
    pub lit_share: f64,
    /// Share that see a back face (drawn black).
    pub back_share: f64,
    /// Share that see no surface (black background).
    pub nothing_share: f64,
}

/// Peak resident set size of this process (`VmHWM` from `/proc/self/status`), when available.
pub fn peak_memory_bytes() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kb: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb * 1024)
}

/// `bytes` in GiB, for the messages of the memory checks.
pub(crate) fn gib(bytes: u64) -> String {
    format!("{:.1} GiB", bytes as f64 / f64::from(1u32 << 30))
}

/// The memory this process may still take: `MemAvailable`, at most what a cgroup v2 limit
/// leaves; `None` where neither can be read.
pub fn available_memory() -> Option<u64> {
    let meminfo = std::fs::read_to_string("/proc/meminfo").ok()?;
    let kib = |key: &str| -> Option<u64> {
        let line = meminfo.lines().find(|l| l.starts_with(key))?;
        line.split_whitespace().nth(1)?.parse::<u64>().ok()
    };
    let available = kib("MemAvailable:")?.saturating_mul(1024);
    let read = |p: &str| -> Option<u64> { std::fs::read_to_string(p).ok()?.trim().parse().ok() };
    let cgroup = match (
        read("/sys/fs/cgroup/memory.max"),
        read("/sys/fs/cgroup/memory.current"),
    ) {
        (Some(max), Some(current)) => Some(max.saturating_sub(current)),
        _ => None,
    };
    Some(cgroup.map_or(available, |c| c.min(available)))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn metrics_serialize_and_memory_is_reported_on_linux() {
        let m = Metrics {
            scene: "x".into(),
            ..Default::default()
        };
        let json = serde_json::to_string(&m).unwrap();
        assert!(json.contains("\"kernel_cells\":0"));
        if cfg!(target_os = "linux") {
            assert!(peak_memory_bytes().unwrap() > 1 << 20);
        }
    }
}

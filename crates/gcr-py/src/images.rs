//! Images and files of a solution: [`image`] as numbers ([`gcr::output::render_linear`], what an
//! `.exr` output holds) and [`write`], the program's output stage
//! ([`gcr::output::OutputPlan`] checked first, then [`gcr::output::write_outputs`]: every file
//! reaches its target, or none does).

use crate::errors::{gcr_error, value_error, warn_all};
use crate::runner;
use crate::solve::Solved;
use anyhow::Context;
use gcr::output::{
    CameraChoice, ImageMode, ImageSettings, OutputPaths, OutputPlan, ProbeQuantity, ProbeSettings,
    View, render_linear, write_outputs,
};
use glam::DVec3;
use numpy::{PyArray1, PyArrayDyn, PyArrayMethods};
use pyo3::prelude::*;
use std::path::PathBuf;
use std::sync::Arc;

/// The camera and image arguments shared by `Solution.image` and `Solution.write`.
pub(crate) struct ImageArgs {
    pub camera_eye: Option<[f64; 3]>,
    pub camera_target: Option<[f64; 3]>,
    pub camera_up: [f64; 3],
    pub fov: Option<f64>,
    pub auto_camera: bool,
    pub resolution: Option<(u32, u32)>,
    pub image_mode: Option<String>,
    pub pixel_samples: u32,
    pub exposure: Option<f64>,
}

/// One more view of `Solution.write`: `(path, eye, target[, up[, fov]])`.
#[derive(FromPyObject)]
pub(crate) enum ViewArg {
    /// With up and field of view.
    Full(PathBuf, [f64; 3], [f64; 3], [f64; 3], f64),
    /// With up.
    Up(PathBuf, [f64; 3], [f64; 3], [f64; 3]),
    /// Up (0, 1, 0), the default field of view.
    Short(PathBuf, [f64; 3], [f64; 3]),
}

impl ViewArg {
    fn view(self) -> View {
        let (path, eye, target, up, fov) = match self {
            ViewArg::Full(p, e, t, u, f) => (p, e, t, u, f),
            ViewArg::Up(p, e, t, u) => (p, e, t, u, gcr::output::DEFAULT_FOV),
            ViewArg::Short(p, e, t) => (p, e, t, [0.0, 1.0, 0.0], gcr::output::DEFAULT_FOV),
        };
        View {
            camera: gcr::output::PinholeCamera {
                eye: eye.into(),
                target: target.into(),
                up: up.into(),
                fov_y_degrees: fov,
            },
            path,
        }
    }
}

impl ImageArgs {
    /// The library's image settings (validated by the library: its messages), or a
    /// `ValueError` for arguments that do not go together or parse.
    pub(crate) fn settings(&self, views: Vec<ViewArg>) -> PyResult<ImageSettings> {
        let eye_target: Option<(DVec3, DVec3)> = match (self.camera_eye, self.camera_target) {
            (Some(e), Some(t)) => Some((e.into(), t.into())),
            (None, None) => None,
            _ => {
                return Err(value_error(
                    "camera_eye and camera_target go together: give both",
                ));
            }
        };
        let default = ImageSettings::default();
        let (width, height) = self.resolution.unwrap_or((default.width, default.height));
        let mode = match self.image_mode.as_deref() {
            None => default.mode,
            Some(m) => m.parse::<ImageMode>().map_err(value_error)?,
        };
        Ok(ImageSettings {
            camera: CameraChoice::from_options(
                eye_target,
                self.camera_up.into(),
                self.fov,
                self.auto_camera,
            ),
            width,
            height,
            exposure: self.exposure,
            views: views.into_iter().map(ViewArg::view).collect(),
            mode,
            pixel_samples: self.pixel_samples,
        })
    }
}

/// The image of `settings` as linear radiance L = B/π, H × W × 3 float32, rows from the top.
pub(crate) fn image<'py>(
    py: Python<'py>,
    solved: &Arc<Solved>,
    settings: ImageSettings,
    progress: Option<&Bound<'py, PyAny>>,
) -> PyResult<Bound<'py, PyArrayDyn<f32>>> {
    let linear = runner::run(py, progress, |monitor| {
        monitor.observing(|| {
            solved.scene.with_domain(|domain| {
                render_linear(domain, &solved.trained, &solved.config, &settings)
            })
        })
    })?
    .map_err(gcr_error)?;
    let r = linear.radiance;
    let flat: Vec<f32> = r.radiance.iter().flatten().copied().collect();
    let shape = vec![r.height as usize, r.width as usize, 3];
    PyArray1::from_vec(py, flat).reshape(shape)
}

/// The files of `Solution.write` and how to make them.
pub(crate) struct WriteArgs {
    pub paths: OutputPaths,
    pub images: ImageSettings,
    pub probe_quantity: Option<String>,
    pub probe_tolerance: Option<f64>,
    pub lightmap: gcr::LightmapSettings,
    /// The shard to bake (`--shard`), if any.
    pub shard: Option<gcr::Shard>,
    /// The lightmap's parts to merge (`--from-shards`).
    pub from_shards: Vec<std::path::PathBuf>,
}

/// Writes the outputs as `gcr solve` does after its solve (checked first, all at once) and
/// returns the run's metrics as a dict; the warnings the writing adds are issued.
pub(crate) fn write<'py>(
    py: Python<'py>,
    solved: &Arc<Solved>,
    args: WriteArgs,
    progress: Option<&Bound<'py, PyAny>>,
) -> PyResult<Bound<'py, PyAny>> {
    let quantity = match args.probe_quantity.as_deref() {
        None => ProbeQuantity::default(),
        Some(q) => q.parse().map_err(value_error)?,
    };
    let probe_settings = ProbeSettings {
        quantity,
        tolerance: args.probe_tolerance,
        outdoor_illuminance: solved.scene.outdoor_illuminance,
    };
    let metrics = runner::run(py, progress, |monitor| {
        monitor.observing(|| {
            let settings = (args.images, probe_settings, args.lightmap);
            let shards = (args.shard, &args.from_shards[..]);
            write_files(solved, args.paths, settings, shards, monitor)
        })
    })?
    .map_err(gcr_error)?;
    let known = solved
        .trained
        .metrics
        .warnings
        .len()
        .min(metrics.warnings.len());
    warn_all(py, &metrics.warnings[known..])?;
    let json = serde_json::to_string(&metrics).map_err(gcr_error)?;
    py.import("json")?.call_method1("loads", (json,))
}

/// `gcr solve`'s output stage: the plan checked (with the program's context), the networks
/// trained for this write when an output reads them and the solve skipped them (a Flatland
/// kernel image; the solve is deterministic, so they are the program's), then every file.
fn write_files(
    solved: &Solved,
    paths: OutputPaths,
    (images, probes, lightmap): (ImageSettings, ProbeSettings, gcr::LightmapSettings),
    (shard, from_shards): (Option<gcr::Shard>, &[std::path::PathBuf]),
    monitor: &Arc<runner::Monitor>,
) -> anyhow::Result<gcr::Metrics> {
    let name = &solved.scene.name;
    let mut config = solved.config.clone();
    config.paths.shard = shard;
    let parts = gcr::output::shards::read_parts(from_shards)?;
    solved.scene.with_domain(|domain| {
        let plan = OutputPlan::checked(domain, (paths, images, probes), (lightmap, parts), &config)
            .with_context(|| format!("checking the outputs for `{name}`"))?;
        let (options, config) = (&solved.options, &config);
        let retrained = match plan.needs_networks() && !options.trains_networks(config, false) {
            true => {
                let mut observer = monitor.solve_observer();
                Some(gcr::solve_for_outputs(
                    domain,
                    options,
                    config,
                    true,
                    &mut observer,
                )?)
            }
            false => None,
        };
        let trained = retrained.as_ref().unwrap_or(&solved.trained);
        Ok(write_outputs(
            domain,
            trained,
            config,
            &plan,
            name,
            solved.started,
        )?)
    })
}

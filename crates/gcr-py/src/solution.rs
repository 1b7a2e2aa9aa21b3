//! The methods of `gcr.Solution` (the class itself: `solve.rs`): values at points
//! (`points.rs`), images and files (`images.rs`), the metrics.

use crate::errors::gcr_error;
use crate::images::{self, ImageArgs, ViewArg, WriteArgs};
use crate::points::{self, Values};
use crate::scene::Scene;
use crate::solve::Solution;
use gcr::output::{OutputPaths, ProbeQuantity};
use numpy::{AllowTypeChange, PyArrayDyn, PyArrayLikeDyn};
use pyo3::prelude::*;
use std::path::PathBuf;
use std::sync::Arc;

/// The lightmap settings of [`Solution::write`]'s arguments (the program's defaults for those not
/// given; checked by the output plan).
fn lightmap_settings(
    density: Option<f64>,
    size: Option<u32>,
    padding: Option<u32>,
    (quantity, denoise): (Option<String>, bool),
) -> PyResult<gcr::LightmapSettings> {
    let defaults = gcr::LightmapSettings::default();
    Ok(gcr::LightmapSettings {
        texels_per_unit: density,
        page_size: size.unwrap_or(defaults.page_size),
        padding: padding.unwrap_or(defaults.padding),
        quantity: match quantity {
            Some(q) => q.parse().map_err(crate::errors::value_error)?,
            None => defaults.quantity,
        },
        denoise,
    })
}

/// A shard's row indices, values and standard errors.
type ShardValues<'py> = (
    Bound<'py, numpy::PyArray1<usize>>,
    Bound<'py, PyArrayDyn<f64>>,
    Bound<'py, PyArrayDyn<f64>>,
);

/// N × dim points and normals, as the methods take them.
type Points<'py> = PyArrayLikeDyn<'py, f64, AllowTypeChange>;

#[pymethods]
impl Solution {
    /// Radiosity B (exitance) at surface points: ``(values, std_errors)``, N × 3 float64 each
    /// (N × 1 for a grey Flatland scene), in the points' order.
    ///
    /// ``points`` and ``normals`` are N × 3 (Flatland N × 2) array-likes, as the lines of a
    /// probe file (``gcr solve --probes``): each point snaps onto the nearest face its normal
    /// faces, within ``tolerance`` (default 1e-4 of the scene's diagonal), and the points are
    /// gathered together (neighbours share paths; the rounds run until their estimated error
    /// meets the solve's target), so the same points give the program's numbers exactly. The
    /// standard errors are the gather's estimates (0 for the gathers that measure none). Raises
    /// :class:`gcr.GcrError` for a point off the surfaces (``points:ROW: …``, rows from 1).
    #[pyo3(signature = (points, normals, *, tolerance=None, progress=None))]
    fn radiosity<'py>(
        &self,
        py: Python<'py>,
        points: Points<'py>,
        normals: Points<'py>,
        tolerance: Option<f64>,
        progress: Option<Bound<'py, PyAny>>,
    ) -> PyResult<Values<'py>> {
        let settings = points::settings(&self.inner, ProbeQuantity::Radiosity, tolerance);
        points::at_points(
            py,
            &self.inner,
            (points, normals),
            settings,
            progress.as_ref(),
        )
    }

    /// Irradiance E = ∫ L cos θ dω at any points (on a surface or in the air), for the
    /// hemisphere about each normal, like Radiance's ``rtrace -I`` and ``gcr solve
    /// --probe-quantity irradiance``: ``(values, std_errors)`` as :meth:`radiosity`. Needs the
    /// paths gather (the default).
    #[pyo3(signature = (points, normals, *, progress=None))]
    fn irradiance<'py>(
        &self,
        py: Python<'py>,
        points: Points<'py>,
        normals: Points<'py>,
        progress: Option<Bound<'py, PyAny>>,
    ) -> PyResult<Values<'py>> {
        let settings = points::settings(&self.inner, ProbeQuantity::Irradiance, None);
        points::at_points(
            py,
            &self.inner,
            (points, normals),
            settings,
            progress.as_ref(),
        )
    }

    /// Daylight factors in percent: the irradiance as :meth:`irradiance` over the outdoor
    /// horizontal illuminance of the scene's CIE overcast sky (``sky="cie-overcast:LUX"``, no
    /// sun or environment map), as ``--probe-quantity daylight-factor``.
    #[pyo3(signature = (points, normals, *, progress=None))]
    fn daylight_factor<'py>(
        &self,
        py: Python<'py>,
        points: Points<'py>,
        normals: Points<'py>,
        progress: Option<Bound<'py, PyAny>>,
    ) -> PyResult<Values<'py>> {
        let settings = points::settings(&self.inner, ProbeQuantity::DaylightFactor, None);
        points::at_points(
            py,
            &self.inner,
            (points, normals),
            settings,
            progress.as_ref(),
        )
    }

    /// The values of one shard of ``points``: ``(indices, values, std_errors)``, the rows (from
    /// 0, ascending) that shard ``shard = (index, count)`` holds and their values as
    /// :meth:`radiosity` (``quantity="radiosity"``), :meth:`irradiance` or
    /// :meth:`daylight_factor` give them, bit for bit, for the same points and a solve with the
    /// same ``block_points`` (``gcr solve --shard``). Shards split the points' blocks
    /// (``gcr.solve(..., block_points=N)``; without it all points are one block, one shard);
    /// fewer blocks than shards raise :class:`gcr.GcrError`. ``gcr.distributed`` runs the shards
    /// on a Dask cluster.
    #[pyo3(signature = (points, normals, *, shard, quantity="radiosity", tolerance=None, progress=None))]
    #[allow(clippy::too_many_arguments)]
    fn shard_values<'py>(
        &self,
        py: Python<'py>,
        points: Points<'py>,
        normals: Points<'py>,
        shard: (usize, usize),
        quantity: &str,
        tolerance: Option<f64>,
        progress: Option<Bound<'py, PyAny>>,
    ) -> PyResult<ShardValues<'py>> {
        let quantity: ProbeQuantity = quantity.parse().map_err(crate::errors::value_error)?;
        if shard.0 >= shard.1 {
            return Err(crate::errors::value_error(format!(
                "shard {shard:?}: expected (index, count) with 0 <= index < count"
            )));
        }
        let shard = gcr::Shard {
            index: shard.0,
            count: shard.1,
        };
        let settings = points::settings(&self.inner, quantity, tolerance);
        let (indices, (values, errors)) = points::shard_at_points(
            py,
            &self.inner,
            (points, normals),
            settings,
            shard,
            progress.as_ref(),
        )?;
        Ok((indices, values, errors))
    }

    /// An image as numbers: linear radiance L = B/π per pixel, an H × W × 3 float32 array
    /// (rows from the top), what ``gcr solve --image x.exr`` writes with the same options.
    ///
    /// The camera: ``camera_eye`` and ``camera_target`` (with ``camera_up``, ``fov``: Mitsuba's
    /// ``look_at`` convention), else the automatic one with ``auto_camera``, else the scene's
    /// (else the automatic one). ``resolution`` is ``(width, height)`` (default 512 × 512);
    /// ``image_mode`` ``"mesh"`` (rasterize the bake) or ``"pixel"`` (gather B at every pixel;
    /// ``pixel_samples`` for the dissertation's gathers); ``exposure`` only steers the automatic
    /// camera, as in the program.
    #[pyo3(signature = (
        *, camera_eye=None, camera_target=None, camera_up=[0.0, 1.0, 0.0], fov=None,
        auto_camera=false, resolution=None, image_mode=None, pixel_samples=1, exposure=None,
        progress=None
    ))]
    #[allow(clippy::too_many_arguments)]
    fn image<'py>(
        &self,
        py: Python<'py>,
        camera_eye: Option<[f64; 3]>,
        camera_target: Option<[f64; 3]>,
        camera_up: [f64; 3],
        fov: Option<f64>,
        auto_camera: bool,
        resolution: Option<(u32, u32)>,
        image_mode: Option<String>,
        pixel_samples: u32,
        exposure: Option<f64>,
        progress: Option<Bound<'py, PyAny>>,
    ) -> PyResult<Bound<'py, PyArrayDyn<f32>>> {
        let args = ImageArgs {
            camera_eye,
            camera_target,
            camera_up,
            fov,
            auto_camera,
            resolution,
            image_mode,
            pixel_samples,
            exposure,
        };
        images::image(
            py,
            &self.inner,
            args.settings(Vec::new())?,
            progress.as_ref(),
        )
    }

    /// Writes the program's outputs of this solution, as ``gcr solve`` does after its solve:
    /// ``image`` (.png, .jpg, .exr), ``mesh`` (glTF .glb with vertex colours: the bake),
    /// ``lightmap`` (.glb with a lightmap atlas on TEXCOORD_1 and the EXR pages beside it, with
    /// ``lightmap_density``, ``lightmap_size``, ``lightmap_padding``, ``lightmap_quantity`` and
    /// ``lightmap_denoise`` as ``--lightmap-*``), ``ply``,
    /// ``metrics`` (JSON), ``probes`` (a probe file) with ``probe_out`` (and
    /// ``probe_quantity``, ``probe_tolerance``), ``kernel_image`` (Flatland), ``views``
    /// (``(path, eye, target[, up[, fov]])`` each), and the camera and image options of
    /// :meth:`image`. ``shard=(index, count)`` bakes one shard of the lightmap's texels, of the
    /// probes and of a per-pixel image's pixels (``image_mode="pixel"``, a fixed camera), as
    /// ``gcr solve --shard`` (the lightmap's part goes to ``NAME.shard-I-of-N.txt`` beside
    /// ``lightmap``'s ``NAME.glb``, the image's beside ``image``, the probes' to ``probe_out``);
    /// ``from_shards`` (paths of a lightmap's or an image's parts) takes the texels or pixels
    /// from them, as ``--from-shards``: with the solve's ``block_points``, the files are the
    /// single run's, byte for byte.
    /// Every output is checked before anything is computed, and the files are
    /// written all at once: either every one reaches its target or none is created or changed.
    /// Returns the run's metrics (the metrics file's contents) as a dict. Raises
    /// :class:`gcr.GcrError` with the program's message.
    #[pyo3(signature = (
        *, image=None, mesh=None, ply=None, metrics=None, probes=None, probe_out=None,
        probe_quantity=None, probe_tolerance=None, kernel_image=None, views=Vec::new(),
        lightmap=None, lightmap_density=None, lightmap_size=None, lightmap_padding=None,
        lightmap_quantity=None, lightmap_denoise=false, shard=None, from_shards=Vec::new(),
        camera_eye=None, camera_target=None, camera_up=[0.0, 1.0, 0.0], fov=None,
        auto_camera=false, resolution=None, image_mode=None, pixel_samples=1, exposure=None,
        progress=None
    ))]
    #[allow(clippy::too_many_arguments)]
    fn write<'py>(
        &self,
        py: Python<'py>,
        image: Option<PathBuf>,
        mesh: Option<PathBuf>,
        ply: Option<PathBuf>,
        metrics: Option<PathBuf>,
        probes: Option<PathBuf>,
        probe_out: Option<PathBuf>,
        probe_quantity: Option<String>,
        probe_tolerance: Option<f64>,
        kernel_image: Option<PathBuf>,
        views: Vec<ViewArg>,
        lightmap: Option<PathBuf>,
        lightmap_density: Option<f64>,
        lightmap_size: Option<u32>,
        lightmap_padding: Option<u32>,
        lightmap_quantity: Option<String>,
        lightmap_denoise: bool,
        shard: Option<(usize, usize)>,
        from_shards: Vec<PathBuf>,
        camera_eye: Option<[f64; 3]>,
        camera_target: Option<[f64; 3]>,
        camera_up: [f64; 3],
        fov: Option<f64>,
        auto_camera: bool,
        resolution: Option<(u32, u32)>,
        image_mode: Option<String>,
        pixel_samples: u32,
        exposure: Option<f64>,
        progress: Option<Bound<'py, PyAny>>,
    ) -> PyResult<Bound<'py, PyAny>> {
        let image_args = ImageArgs {
            camera_eye,
            camera_target,
            camera_up,
            fov,
            auto_camera,
            resolution,
            image_mode,
            pixel_samples,
            exposure,
        };
        let args = WriteArgs {
            paths: OutputPaths {
                image,
                kernel_image,
                mesh,
                ply,
                lightmap,
                probes_in: probes,
                probe_out,
                metrics,
            },
            images: image_args.settings(views)?,
            probe_quantity,
            probe_tolerance,
            lightmap: lightmap_settings(
                lightmap_density,
                lightmap_size,
                lightmap_padding,
                (lightmap_quantity, lightmap_denoise),
            )?,
            shard: match shard {
                None => None,
                Some((index, count)) if index < count => Some(gcr::Shard { index, count }),
                Some(s) => {
                    return Err(crate::errors::value_error(format!(
                        "shard {s:?}: expected (index, count) with 0 <= index < count"
                    )));
                }
            },
            from_shards,
        };
        images::write(py, &self.inner, args, progress.as_ref())
    }

    /// The solve's metrics as a dict (the metrics file's fields before any output was
    /// gathered: :meth:`write` returns the complete ones).
    #[getter]
    fn metrics<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let json = serde_json::to_string(&self.inner.trained.metrics).map_err(gcr_error)?;
        py.import("json")?.call_method1("loads", (json,))
    }

    /// The scene solved.
    #[getter]
    fn scene(&self) -> Scene {
        Scene {
            inner: Arc::clone(&self.inner.scene),
        }
    }

    /// Whether the solve trained the networks (only when something reads them: a gather other
    /// than the default, or ``keep_networks=True``).
    #[getter]
    fn networks_trained(&self) -> bool {
        let s = &self.inner;
        s.options.trains_networks(&s.config, false)
    }

    fn __repr__(&self) -> String {
        let s = &self.inner;
        let target = s.config.paths.target_error;
        format!(
            "gcr.Solution(scene={:?}, gather={:?}, target_error={target:?}, seed={})",
            s.scene.name,
            s.config.gather.name(),
            s.config.seed
        )
    }
}

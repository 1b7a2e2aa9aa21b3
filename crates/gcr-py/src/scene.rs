//! `gcr.Scene`: a scene loaded (a file or a built-in, with the program's loader and its limits on
//! untrusted files) and lit (its own emitters and the light arguments), with its BVH built once.

use crate::errors::{gcr_error, warn_all};
use crate::lights::LightArgs;
use crate::runner;
use anyhow::Context;
use gcr::Domain;
use pyo3::prelude::*;
use scene_sampler::confine::{DEFAULT_MAX_FILE_BYTES, DEFAULT_MAX_TEXTURE_BYTES};
use scene_sampler::{AnyScene, FlatKernelSampler, KernelSampler, LoadOptions, SceneBvh};
use std::path::PathBuf;
use std::sync::Arc;

/// A loaded, lit scene and what solves read from it.
pub(crate) struct Loaded {
    /// The name or path it was loaded by (the metrics' `scene`).
    pub name: String,
    pub geometry: Geometry,
    /// The outdoor illuminance of daylight factors (a CIE overcast sky alone), if any.
    pub outdoor_illuminance: Option<f64>,
    /// The openings `auto_portals` found.
    pub found_portals: Vec<[[f64; 3]; 4]>,
}

/// The scene proper: 3-D with its BVH, or Flatland.
pub(crate) enum Geometry {
    ThreeD(Box<(scene_sampler::Scene, SceneBvh)>),
    Flat(scene_sampler::FlatlandScene),
}

impl Loaded {
    /// Runs `f` on the scene's kernel domain (built per call: the BVH is kept, the samplers are
    /// cheap).
    pub(crate) fn with_domain<R>(&self, f: impl FnOnce(&Domain) -> R) -> R {
        match &self.geometry {
            Geometry::ThreeD(s) => f(&Domain::ThreeD(KernelSampler::new(&s.0, &s.1))),
            Geometry::Flat(s) => f(&Domain::Flat(FlatKernelSampler::new(s))),
        }
    }

    /// 3 for a 3-D scene, 2 for Flatland.
    pub(crate) fn dim(&self) -> usize {
        match self.geometry {
            Geometry::ThreeD(_) => 3,
            Geometry::Flat(_) => 2,
        }
    }
}

/// A scene to solve: a file (.obj, .gltf, .glb, Flatland .json) or a built-in by name, lit by its
/// own emitting faces and the lights given to :meth:`Scene.load`. Immutable; a scene can be
/// solved many times and from several threads.
#[pyclass(module = "gcr", frozen)]
pub struct Scene {
    pub(crate) inner: Arc<Loaded>,
}

#[pymethods]
impl Scene {
    /// Loads and lights a scene, as ``gcr solve SCENE`` does with the same options.
    ///
    /// ``scene``: a file (.obj, .gltf, .glb, Flatland .json) or a built-in name
    /// (:func:`gcr.builtin_scenes`). The loader's limits (``allow_outside_files``,
    /// ``max_file_mib``, ``max_texture_mib``, ``single_sided``) and the lights (``sun``, ``sky``,
    /// ``env``, ``ground_reflectance``, ``up``, ``portals``, ``auto_portals``, ``point_lights``,
    /// ``spot_lights``, ``lights``) are the program's options of the same names; a light is given
    /// as the option's text (``sun="135,40,80000"``) or as numbers (``sun=(135, 40, 80000)``).
    /// Loader warnings are issued as :class:`gcr.GcrWarning`. Raises :class:`gcr.GcrError`
    /// with the program's message when the scene cannot be read or nothing lights it, and
    /// ``ValueError`` for a light argument that does not parse.
    #[staticmethod]
    #[pyo3(signature = (
        scene, *, allow_outside_files=false, max_file_mib=None, max_texture_mib=None,
        single_sided=false, sun=None, sky=None, env=None, ground_reflectance=None, up=None,
        portals=Vec::new(), auto_portals=false, point_lights=Vec::new(), spot_lights=Vec::new(),
        lights=None
    ))]
    #[allow(clippy::too_many_arguments)]
    fn load<'py>(
        py: Python<'py>,
        scene: PathBuf,
        allow_outside_files: bool,
        max_file_mib: Option<u64>,
        max_texture_mib: Option<u64>,
        single_sided: bool,
        sun: Option<Bound<'py, PyAny>>,
        sky: Option<String>,
        env: Option<Bound<'py, PyAny>>,
        ground_reflectance: Option<f64>,
        up: Option<String>,
        portals: Vec<Bound<'py, PyAny>>,
        auto_portals: bool,
        point_lights: Vec<Bound<'py, PyAny>>,
        spot_lights: Vec<Bound<'py, PyAny>>,
        lights: Option<PathBuf>,
    ) -> PyResult<Self> {
        let load = LoadOptions {
            allow_outside: allow_outside_files,
            max_file_bytes: max_file_mib
                .map_or(DEFAULT_MAX_FILE_BYTES, |m| m.saturating_mul(1 << 20)),
            max_texture_bytes: (max_texture_mib)
                .map_or(DEFAULT_MAX_TEXTURE_BYTES, |m| m.saturating_mul(1 << 20)),
            single_sided,
        };
        let light = LightArgs {
            sun,
            sky,
            env,
            ground_reflectance,
            up,
            portals,
            auto_portals,
            point_lights,
            spot_lights,
            lights,
        }
        .options()?;
        let name = scene.to_string_lossy().into_owned();
        let (loaded, warnings) =
            runner::run(py, None, |_| load_and_light(&name, &load, &light))?.map_err(gcr_error)?;
        warn_all(py, &warnings)?;
        Ok(Self {
            inner: Arc::new(loaded),
        })
    }

    /// The name or path the scene was loaded by.
    #[getter]
    fn name(&self) -> &str {
        &self.inner.name
    }

    /// 3 for a 3-D scene, 2 for a Flatland scene.
    #[getter]
    fn dim(&self) -> usize {
        self.inner.dim()
    }

    /// Colour bands: 3, or 1 for a grey Flatland scene.
    #[getter]
    fn bands(&self) -> usize {
        self.inner.with_domain(|d| d.bands())
    }

    /// Faces (3-D triangles) or segments (Flatland).
    #[getter]
    fn faces(&self) -> usize {
        match &self.inner.geometry {
            Geometry::ThreeD(s) => s.0.faces.len(),
            Geometry::Flat(s) => s.segments.len(),
        }
    }

    /// The openings ``auto_portals=True`` found, each four corners (``[[x, y, z]] * 4``).
    #[getter]
    fn found_portals(&self) -> Vec<[[f64; 3]; 4]> {
        self.inner.found_portals.clone()
    }

    fn __repr__(&self) -> String {
        format!(
            "gcr.Scene({:?}, dim={}, faces={})",
            self.inner.name,
            self.inner.dim(),
            self.faces()
        )
    }
}

/// The program's load and light steps (`gcr solve`'s first two), with its error contexts.
fn load_and_light(
    name: &str,
    load: &LoadOptions,
    light: &scene_sampler::LightOptions,
) -> anyhow::Result<(Loaded, Vec<String>)> {
    let loaded = scene_sampler::load_or_builtin_with(name, load)
        .with_context(|| format!("loading scene `{name}`"))?;
    let warnings = loaded.warnings().to_vec();
    let lit = light
        .light(loaded)
        .with_context(|| format!("lighting `{name}`"))?;
    let geometry = match lit.scene {
        AnyScene::ThreeD(s) => {
            let bvh = SceneBvh::new(&s);
            Geometry::ThreeD(Box::new((s, bvh)))
        }
        AnyScene::Flatland(s) => Geometry::Flat(s),
    };
    let loaded = Loaded {
        name: name.to_string(),
        geometry,
        outdoor_illuminance: light.outdoor_illuminance(),
        found_portals: lit.found_portals,
    };
    Ok((loaded, warnings))
}

/// The built-in scene names (``gcr scenes``): each loads with :meth:`Scene.load`. Generated
/// families load too: ``random-boxes-<N>`` and ``tessellated-cornell-<N>``.
#[pyfunction]
pub(crate) fn builtin_scenes() -> Vec<&'static str> {
    scene_sampler::BUILTIN_NAMES.to_vec()
}

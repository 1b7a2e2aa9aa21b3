//! Radiosity scenes (OBJ, glTF, Flatland, built-ins), area-uniform sampling, BVH visibility and the radiosity
//! kernel.
//!
//! This crate is the geometric ground every GCR solver stands on:
//!
//! * **Scenes** — [`Scene`] (3-D triangles) and [`FlatlandScene`] (2-D segments), each face with reflectance ρ
//!   and emitted radiosity E per colour band ([`Spectrum`]), validated on load ([`SceneError`]). Loaders:
//!   [`load`](fn@load) (OBJ + MTL, glTF/GLB, Flatland JSON), built-ins by name: [`builtin`](fn@builtin), [`BUILTIN_NAMES`].
//!   A scene file reads nothing outside its own folder, regular files only, within bounds on file size
//!   and decoded texture memory ([`LoadOptions`], [`load_with`], [`confine`]).
//! * **Sampling** — area-uniform parameterizations [`SurfaceSampler`] (`[0,1]² →` surface) and [`FlatSampler`]
//!   (`[0,1] →` segments), with inverses (fig. B.2); cosine-weighted direction helpers.
//! * **Visibility** — [`SceneBvh`] (obvhs's BVH collapsed to eight-wide nodes, f32, with a documented self-intersection policy):
//!   occlusion between surface points, batched in parallel, and closest-hit queries; [`FlatVisibility`].
//! * **The kernel** — [`KernelSampler`] / [`FlatKernelSampler`] evaluate `K(x,y) = ρ(y)·G(x,y)·V(x,y)` (sec. 3.1,
//!   docs/design/math.md §4), with the `r → 0` singularity clamped as documented in [`kernel`].
//! * **Provenance** — [`Face::part`], [`Scene::parts`] and [`Scene::gltf`] ([`provenance`]): which input
//!   primitive of which node each face came from, and the glTF node tree, so that outputs can keep the
//!   input's structure.
//! * **Lights** — [`lights`]: one interface ([`Light`]) for the sun, skies, point and spot lights beside
//!   the emitting faces ([`EmitterTable`]), and light selection ([`LightSet`]); [`LightOptions`] lights a
//!   loaded scene with the front ends' light options (the program's `--sun`, `--sky`, …; Python's).
//! * **Probes** — [`read_probes`] / [`Scene::snap_probe`]: the points where all solvers report radiosity.
//!
//! # Units
//! Files give emitted **radiance** (OBJ `Ke`, glTF emissive); scenes store emitted radiosity `E = π·Ke`, and
//! solvers report radiosity B (exitance). Flatland JSON gives E directly.
//!
//! ```
//! use scene_sampler::{builtin, AnyScene, SceneBvh, KernelSampler};
//! let AnyScene::ThreeD(scene) = builtin("cornell-box").unwrap() else { unreachable!() };
//! let bvh = SceneBvh::new(&scene);
//! let k = KernelSampler::new(&scene, &bvh);
//! let s = k.sample([0.1, 0.2, 0.7, 0.4]);
//! assert!(s.g >= 0.0);
//! ```

pub mod bench;
pub mod builtin;
pub mod bvh;
pub mod confine;
pub mod cutout;
pub mod distribution;
pub mod error;
pub mod flatland;
mod gltf;
mod gltf_accessors;
mod gltf_cutouts;
mod gltf_emission;
mod gltf_lights;
mod gltf_resources;
pub mod kernel;
pub mod light_options;
pub mod lights;
pub mod load;
pub mod mis;
pub mod nearest;
mod obj;
pub mod openings;
pub mod probe;
pub mod provenance;
mod read;
pub mod sample;
pub mod scene;
pub mod spectrum;
pub mod texture;
pub mod warp;
mod write;

pub use builtin::{BUILTIN_NAMES, builtin, is_builtin, nearest_builtin, random_boxes};
pub use bvh::{BuildQuality, FlatHit, FlatVisibility, Hit, SceneBvh};
pub use confine::LoadOptions;
pub use cutout::{AlphaMask, FaceCutout};
pub use distribution::{Discrete, uniform_triangle};
pub use error::{Result, SceneError};
pub use flatland::{FlatView, FlatlandScene, Segment};
pub use kernel::{FlatKernelSample, FlatKernelSampler, KernelSample, KernelSampler, Samples};
pub use light_options::{DEFAULT_GROUND_REFLECTANCE, LightOptions, Lit, PortalCorners};
pub use lights::{
    EmitterTable, EnvMap, Light, LightBounds, LightSample, LightSet, LightTree, Lighting, Pick,
    PointLight, Portal, Portals, Receiver, ShadowTarget, Sky, SkyModel, Sun,
};
pub use load::{
    load, load_flatland, load_gltf, load_obj, load_or_builtin, load_or_builtin_with, load_with,
    to_gltf, to_obj, write_flatland, write_gltf, write_obj,
};
pub use mis::PowerHeuristic;
pub use nearest::{Nearest, NearestFaces};
pub use probe::{
    FlatProbe, Probe, ProbeSnapper, flat_probes_from_rows, parse_flat_probes, parse_probes,
    probes_from_rows, read_flat_probes, read_probes,
};
pub use provenance::{GltfMaterial, GltfMesh, GltfNode, GltfSource, NodeTransform, Part};
pub use sample::{FlatPoint, FlatSampler, NO_FACE, SurfacePoint, SurfaceSampler};
pub use scene::{Camera, Face, RHO_MAX, Scene};
pub use spectrum::{BANDS, Bands, Spectrum};
pub use texture::{FaceTexture, Mipmaps, Texture, Wrap, srgb_to_linear};
pub use warp::{
    cosine_halfplane, cosine_hemisphere, hemisphere_quadrature, orthonormal_basis, uniform_cone,
    uniform_cone_about, uniform_cone_pdf,
};

/// A scene of either dimension, as returned by [`load`](fn@load) and [`builtin`](fn@builtin).
// one value per loaded scene, moved a few times: boxing the larger variant would buy nothing
#[allow(clippy::large_enum_variant)]
#[derive(Clone, Debug)]
pub enum AnyScene {
    /// A 3-D triangle scene.
    ThreeD(Scene),
    /// A Flatland segment scene.
    Flatland(FlatlandScene),
}

impl AnyScene {
    /// The scene's name.
    pub fn name(&self) -> &str {
        match self {
            AnyScene::ThreeD(s) => &s.name,
            AnyScene::Flatland(s) => &s.name,
        }
    }
    /// Number of colour bands (1 or 3).
    pub fn bands(&self) -> usize {
        match self {
            AnyScene::ThreeD(s) => s.bands,
            AnyScene::Flatland(s) => s.bands,
        }
    }
    /// Non-fatal load warnings.
    pub fn warnings(&self) -> &[String] {
        match self {
            AnyScene::ThreeD(s) => &s.warnings,
            AnyScene::Flatland(s) => &s.warnings,
        }
    }
    /// The 3-D scene, or an error naming the scene if it is Flatland.
    pub fn into_3d(self) -> Result<Scene> {
        match self {
            AnyScene::ThreeD(s) => Ok(s),
            AnyScene::Flatland(s) => Err(SceneError::WrongDimension(format!(
                "`{}` is a Flatland scene, a 3-D scene is needed",
                s.name
            ))),
        }
    }
    /// The Flatland scene, or an error if it is 3-D.
    pub fn into_flatland(self) -> Result<FlatlandScene> {
        match self {
            AnyScene::Flatland(s) => Ok(s),
            AnyScene::ThreeD(s) => Err(SceneError::WrongDimension(format!(
                "`{}` is a 3-D scene, a Flatland scene is needed",
                s.name
            ))),
        }
    }
}

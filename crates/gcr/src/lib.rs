//! Growing Cells Radiosity: radiosity on evolving networks (Bohn 2000).
//!
//! The solver learns the light flow K(x,y)·B(x) with a growing-cell-structures network (the
//! *kernel network*, [`isgcs`]), meshes the surfaces with a second one (the *shading network*),
//! and integrates between them in closed form ([`gauss_integrals`]).
//!
//! A solve in three calls: a [`Domain`] over a scene (from `scene_sampler`), [`solve`] with a
//! [`SolveConfig`], then [`radiosity_at_points`] (B at any surface points), [`output_mesh`] (the
//! re-triangulated scene with B at its vertices) or the writers of [`output`]. The front ends (the
//! `gcr` program, the Python package) take a user's settings as [`SolveOptions`] (the program's
//! defaults) and solve with [`solve_for_outputs`], which trains the networks only when something
//! reads them.
//!
//! ```
//! use gcr::{Domain, Emitters, SolveConfig, radiosity_at_points};
//! use scene_sampler::{KernelSampler, SceneBvh};
//!
//! let scene = scene_sampler::builtin("cornell-box")?.into_3d()?;
//! let bvh = SceneBvh::new(&scene);
//! let domain = Domain::ThreeD(KernelSampler::new(&scene, &bvh));
//! let config = SolveConfig { kernel_cells: 60, ..SolveConfig::default() };
//! let trained = gcr::solve(&domain, &config, &mut |_| {})?;
//! let f = &scene.faces[0];
//! let centre = (f.v[0] + f.v[1] + f.v[2]) / 3.0;
//! let b = radiosity_at_points(&domain, &trained, &Emitters::new(&domain), &config,
//!                             &[(centre, f.normal, 0)])?;
//! assert!(b[0].radiosity.iter().all(|v| v.is_finite() && *v >= 0.0));
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
//!
//! Where things are: `docs/architecture.md`.

mod cell_lanes;
mod cluster;
mod config;
mod domain;
mod element;
mod emitters;
mod estimator;
mod fem;
mod gather;
mod kernel_cells;
mod lightmap;
mod mesh;
mod message;
mod metrics;
mod network;
mod options;
pub mod output;
mod progress;
mod projection;
mod refine;
mod retriangulate;
mod sample;
mod shading;
mod shooting;
mod solve;
mod spatial;
mod weld;

pub use config::{
    BaseDomain, Breaking, ConfigError, GUIDING_FROM, GUIDING_VARIANCE, GatherMode, GatherSamples,
    Guiding, NetworkTarget, OutputFit, PILOT_RAYS, PathSettings, Quality, Shard, SolveConfig,
    StrengthFrom, SurfaceClusters, Transfer,
};
pub use domain::{Domain, Ray};
pub use element::{BANDS, Bands};
pub use emitters::Emitters;
pub use estimator::{
    GatherError, GatherStats, ShardError, irradiance_at_points, point_seed, radiosity_at_points,
    relative_std_error, shard_points,
};
pub use gather::Gathered;
pub use lightmap::{
    Atlas as LightmapAtlas, DenoiseReport, FaceUv, GUIDE_DARK_RAYS, GUIDE_RAYS, Lightmap,
    LightmapError, LightmapGuide, LightmapQuantity, LightmapSettings, LightmapTexels, Texel,
    assemble_lightmap, bake_lightmap, gather_guide, gather_texels, lay_out_texels,
};
pub use mesh::ShadedMesh;
pub use message::error_message;
pub use metrics::{
    DenoiseRecord, ImageRecord, LightmapRecord, Metrics, PhaseTimes, peak_memory_bytes,
};
pub use network::GrowingNetwork;
pub use options::{SolveOptions, solve_for_outputs};
pub use output::{output_mesh, vertex_gather_point};
pub use progress::{GatherProgress, observe_gathers};
pub use retriangulate::RetriangulateLimits;
pub use sample::Sample;
pub use solve::{Progress, SolveError, Trained, make_networks, solve, train};

/// The solver's stages one at a time, for benchmarks and experiments (`cargo xtask bench`, the
/// examples): the FEM step and its integrals, the frozen networks, the shading geometry and the
/// ray gather. A solve does not need them: behind the `stages` feature.
#[cfg(feature = "stages")]
pub mod stages {
    pub use crate::cluster::ClusterTree;
    pub use crate::element::Element;
    pub use crate::fem::{
        Base, FemSettings, FemSolution, SceneSurface, fem_step, receiver_integrals,
        reflected_from_kernel, sender_integrals,
    };
    pub use crate::gather::gather;
    pub use crate::kernel_cells::KernelCells;
    pub use crate::projection::{KernelProjection, kernel_gram};
    pub use crate::retriangulate::{Triangulation, retriangulate};
    pub use crate::shading::ShadingGeometry;
    pub use crate::solve::{freeze_kernel, freeze_shading};
}

/// The README's code, compiled and run as a doctest.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
pub struct ReadmeDoctests;

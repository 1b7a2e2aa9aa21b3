//! From a trained solution to outputs: radiosity at arbitrary surface points by the three gathers,
//! the re-triangulated output mesh, and probe values.

use crate::config::{GatherMode, SolveConfig};
use crate::domain::Domain;
use crate::element::{Bands, MAX_BANDS};
use crate::emitters::Emitters;
use crate::gather::{Gathered, gather};
use crate::mesh::ShadedMesh;
use crate::paths::PathGather;
use crate::retriangulate::{RetriangulateLimits, retriangulate};
use crate::solve::Trained;
use crate::spatial::BoxGrid;
use glam::DVec3;
use rayon::prelude::*;

/// Why radiosity could not be gathered from a solution.
#[derive(Debug, thiserror::Error)]
pub enum GatherError {
    /// [`GatherMode::Base`] on a solution solved without a base.
    #[error(
        "the base gather needs a solution with a base: solve with a config whose needs_base() is \
         true (gather = base, or skip_unused_base = false)"
    )]
    NoBase,
}

/// Radiosity at many surface points `(point, normal, face)` in parallel by the configured gather.
/// Every entry point gathers through here, with one seeding convention: a point's ray gather is
/// seeded from the solve's seed and the point's coordinates ([`point_seed`]), so its value does
/// not depend on its index, its neighbours or the thread count.
pub fn radiosity_at_points(
    domain: &Domain,
    trained: &Trained,
    emitters: &Emitters,
    config: &SolveConfig,
    points: &[(DVec3, DVec3, u32)],
) -> Result<Vec<Gathered>, GatherError> {
    check_base(trained, config)?;
    let frame = domain.frame();
    let paths = PathGather::new(
        domain,
        emitters,
        |x, n| trained.reflected_kernel(x, n),
        config.gather_samples,
        config.paths,
    );
    Ok(points
        .par_iter()
        .map_init(Vec::new, |scratch, &(y, n, face)| {
            let seed = point_seed(config.seed, y, frame);
            radiosity_at(
                (domain, trained, emitters, &paths),
                config,
                (y, n, face),
                seed,
                scratch,
            )
        })
        .collect())
}

/// A skipped base (`skip_unused_base` with a non-base gather) has no cells; reading it would
/// silently report B = E.
fn check_base(trained: &Trained, config: &SolveConfig) -> Result<(), GatherError> {
    if config.gather == GatherMode::Base && trained.fem.base.geo.is_empty() {
        return Err(GatherError::NoBase);
    }
    Ok(())
}

/// The ray gather's seed at point `y`: the solve's seed mixed with y's coordinates in the
/// scene's frame ([`Domain::frame`]) quantized to 2⁻²⁴ of the diagonal (SplitMix64 finalizer
/// per coordinate). A point's seed depends neither on its index among the points asked for nor
/// on the scene's position or scale.
pub fn point_seed(seed: u64, y: DVec3, (origin, diagonal): (DVec3, f64)) -> u64 {
    let mix = |mut z: u64| {
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    };
    let q = (y - origin) / diagonal.max(f64::MIN_POSITIVE) * (1u64 << 24) as f64;
    [q.x, q.y, q.z]
        .iter()
        .fold(mix(seed ^ 0x9E37_79B9_7F4A_7C15), |h, c| {
            mix(h ^ (c.round() as i64) as u64)
        })
}

/// Radiosity at surface point (y, n, face) by the configured gather ([`check_base`] first).
fn radiosity_at(
    (domain, trained, emitters, paths): (
        &Domain,
        &Trained,
        &Emitters,
        &PathGather<impl Fn(DVec3, DVec3) -> Bands>,
    ),
    config: &SolveConfig,
    (y, n, face): (DVec3, DVec3, u32),
    seed: u64,
    scratch: &mut Vec<u32>,
) -> Gathered {
    let e = domain.emission(face);
    let reflected = |b: Bands| {
        let mut out = Gathered::default();
        for k in 0..MAX_BANDS {
            out.from_networks[k] = b[k].max(0.0);
            out.radiosity[k] = e[k] + out.from_networks[k];
        }
        out
    };
    match config.gather {
        GatherMode::Base => reflected(trained.fem.reflected_from_base(y, n, scratch)),
        GatherMode::Kernel => reflected(trained.reflected_kernel(y, n)),
        GatherMode::Rays => gather(
            domain,
            emitters,
            y,
            n,
            face,
            config.gather_samples,
            seed,
            &|x, nx, _| trained.reflected_kernel(x, nx),
        ),
        GatherMode::Paths => paths.gather((y, n, face), seed),
    }
}

/// The local edge length the shading network asks for near `p`: the width (mean edge length,
/// eq. 2.10) of the nearest shading cell.
pub struct LocalEdge {
    centres: Vec<DVec3>,
    widths: Vec<f64>,
    grid: BoxGrid,
    reach: f64,
}

impl LocalEdge {
    /// Indexes the shading cells of the last FEM step; when the shading network was skipped
    /// (`SolveConfig::skip_unused_base`), the kernel cells' receiver halves and widths, which set
    /// the detail of B_refl.
    pub fn new(trained: &Trained) -> Self {
        let geo = &trained.fem.base.geo;
        let (centres, widths) = if geo.is_empty() {
            (trained.kernel.wy.clone(), trained.kernel.width.clone())
        } else {
            (geo.centres.clone(), geo.widths.clone())
        };
        let mean = widths.iter().sum::<f64>() / widths.len().max(1) as f64;
        let reach = 2.0 * mean.max(1e-300);
        Self {
            grid: BoxGrid::new(centres.iter().map(|c| (*c, *c)).collect(), reach),
            centres,
            widths,
            reach,
        }
    }

    /// Width of the nearest cell to `p` (infinite when there are no cells).
    pub fn at(&self, p: DVec3) -> f64 {
        let mut near = Vec::new();
        let mut r = self.reach;
        for _ in 0..6 {
            self.grid.query_ball(p, r, &mut near);
            if !near.is_empty() {
                break;
            }
            r *= 4.0;
        }
        let pick = |it: &mut dyn Iterator<Item = usize>| {
            it.min_by(|&a, &b| {
                self.centres[a]
                    .distance_squared(p)
                    .total_cmp(&self.centres[b].distance_squared(p))
            })
        };
        let best = if near.is_empty() {
            pick(&mut (0..self.centres.len()))
        } else {
            pick(&mut near.iter().map(|&i| i as usize))
        };
        best.map_or(f64::INFINITY, |i| self.widths[i])
    }
}

/// What the gather at an output mesh's vertices measured beside B.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct MeshGather {
    /// Area-weighted share of B (all bands) that came from the networks.
    pub network_share: f64,
    /// [`relative_std_error`] of the vertices' values (None unless the gather measures it).
    pub relative_std_error: Option<f64>,
}

/// The estimated relative error of gathered values, ‖σ‖₂/‖B‖₂ over points and bands from their
/// standard errors σ, over the points the gather estimated (σ ≠ 0: points that do not reflect have
/// B = E exactly, and a bright emitter among them would make the ratio look small); None when the
/// gather measured none (every σ is 0).
pub fn relative_std_error(gathered: &[Gathered]) -> Option<f64> {
    let (mut v, mut b) = (0.0, 0.0);
    for g in gathered
        .iter()
        .filter(|g| g.std_error.iter().any(|s| *s != 0.0))
    {
        for k in 0..MAX_BANDS {
            v += g.std_error[k] * g.std_error[k];
            b += g.radiosity[k] * g.radiosity[k];
        }
    }
    (v > 0.0 && b > 0.0).then(|| (v / b).sqrt())
}

/// Re-triangulates the scene to the shading network's resolution (sec. 4.3.1) and gathers B at
/// every vertex ([`radiosity_at_points`]). Returns the mesh and what the gather measured.
pub fn output_mesh(
    domain: &Domain,
    trained: &Trained,
    config: &SolveConfig,
    limits: RetriangulateLimits,
) -> Result<(ShadedMesh, MeshGather), GatherError> {
    let Some(scene) = domain.scene_3d() else {
        return Ok((ShadedMesh::default(), MeshGather::default()));
    };
    let faces: Vec<[DVec3; 3]> = scene.faces.iter().map(|f| f.v).collect();
    let local = LocalEdge::new(trained);
    let tri = retriangulate(&faces, |p| local.at(p), limits);
    let mut vertex_face = vec![0u32; tri.positions.len()];
    for (t, f) in tri.triangles.iter().zip(&tri.face_of_triangle) {
        for &v in t {
            vertex_face[v as usize] = *f;
        }
    }
    let points: Vec<(DVec3, DVec3, u32)> = (0..tri.positions.len())
        .map(|v| {
            let face = vertex_face[v];
            (tri.positions[v], scene.faces[face as usize].normal, face)
        })
        .collect();
    let gathered = radiosity_at_points(domain, trained, &Emitters::new(domain), config, &points)?;
    // Network share: area-weighted over triangles, all bands.
    let (mut total, mut net) = (0.0, 0.0);
    for t in &tri.triangles {
        let [a, b, c] = t.map(|i| tri.positions[i as usize]);
        let area = 0.5 * (b - a).cross(c - a).length();
        for &v in t {
            let g = &gathered[v as usize];
            total += area * g.radiosity.iter().sum::<f64>();
            net += area * g.from_networks.iter().sum::<f64>();
        }
    }
    let grey = domain.bands() == 1;
    let mesh = ShadedMesh {
        positions: tri.positions,
        triangles: tri.triangles,
        face_of_triangle: tri.face_of_triangle,
        radiosity: gathered
            .iter()
            .map(|g| {
                if grey {
                    [g.radiosity[0]; 3]
                } else {
                    g.radiosity
                }
            })
            .collect(),
    };
    let stats = MeshGather {
        network_share: if total > 0.0 { net / total } else { 0.0 },
        relative_std_error: relative_std_error(&gathered),
    };
    Ok((mesh, stats))
}

//! The output mesh: the scene re-triangulated at the shading network's resolution (or a uniform
//! one), B gathered at every vertex, refined where B varies (sec. 4.3.1–4.3.2).

use crate::config::GatherMode;
use crate::config::SolveConfig;
use crate::domain::Domain;
use crate::emitters::Emitters;
use crate::estimator::{GatherError, GatherStats, radiosity_at_points};
use crate::mesh::ShadedMesh;
use crate::refine::{RefineLimits, refine};
use crate::retriangulate::{RetriangulateLimits, retriangulate};
use crate::solve::Trained;
use crate::spatial::BoxGrid;
use glam::DVec3;

/// The output mesh's starting resolution when no network was trained (the paths gather reads
/// none): the edge of this many equilateral triangles covering the scene. Coarse on purpose:
/// The refinement (`refine.rs`) then splits where B varies (shadows), which on cornell-box's floor resolves
/// the short block's shadow better, and sooner, than starting from the networks' resolution
/// (docs/guide/bakes.md). Faces already smaller than the edge are kept as they are.
pub const UNIFORM_MESH_TRIANGLES: f64 = 150.0;

/// The local edge length the shading network asks for near `p`: the width (mean edge length,
/// eq. 2.10) of the nearest shading cell. Without networks ([`Trained::without_networks`]) one
/// edge everywhere: that of [`UNIFORM_MESH_TRIANGLES`] equilateral triangles covering the scene.
pub struct LocalEdge {
    centres: Vec<DVec3>,
    widths: Vec<f64>,
    grid: BoxGrid,
    reach: f64,
    /// The edge where there are no cells.
    uniform: f64,
}

impl LocalEdge {
    /// Indexes the shading cells of the last FEM step; when the shading network was skipped
    /// (`SolveConfig::skip_unused_base`), the kernel cells' receiver halves and widths, which set
    /// the detail of B_refl.
    pub fn new(trained: &Trained, total_area: f64) -> Self {
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
            // an equilateral triangle of edge e has area √3/4 · e²
            uniform: (4.0 * total_area / (3f64.sqrt() * UNIFORM_MESH_TRIANGLES)).sqrt(),
        }
    }

    /// Width of the nearest cell to `p` (the uniform edge when there are no cells).
    pub fn at(&self, p: DVec3) -> f64 {
        if self.centres.is_empty() {
            return self.uniform;
        }
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
        best.map_or(self.uniform, |i| self.widths[i])
    }
}

/// Where [`output_mesh`] gathers B for a vertex at `p` of `face`: 10⁻⁴ of the way from `p` to the
/// face's centroid. A vertex on an edge of its face where another face meets it (a block standing
/// on the floor, the floor at a wall) gathers, exactly there, about half its B: the adjoining
/// face, within the ray offsets of the point, blocks the rays that leave toward it (measured on
/// cornell-box, docs/guide/bakes.md). The move is far below the mesh's resolution.
pub fn vertex_gather_point(face: &scene_sampler::Face, p: DVec3) -> DVec3 {
    p + 1e-4 * (face.centroid() - p)
}

/// Re-triangulates the scene to the shading network's resolution (sec. 4.3.1) and gathers B at
/// every vertex ([`radiosity_at_points`], at [`vertex_gather_point`]); with the paths gather the
/// mesh is then refined where B varies faster than linear interpolation follows
/// (`refine.rs`: shadow edges). Returns the mesh and what the gather measured.
pub fn output_mesh(
    domain: &Domain,
    trained: &Trained,
    config: &SolveConfig,
    limits: RetriangulateLimits,
) -> Result<(ShadedMesh, GatherStats), GatherError> {
    let Domain::ThreeD(k) = domain else {
        return Ok((ShadedMesh::default(), GatherStats::default()));
    };
    let scene = k.scene;
    let faces: Vec<[DVec3; 3]> = scene.faces.iter().map(|f| f.v).collect();
    let local = LocalEdge::new(trained, scene.total_area());
    let tri = retriangulate(&faces, |p| local.at(p), limits);
    let mut vertex_face = vec![0u32; tri.positions.len()];
    for (t, f) in tri.triangles.iter().zip(&tri.face_of_triangle) {
        for &v in t {
            vertex_face[v as usize] = *f;
        }
    }
    let emitters = Emitters::new(domain);
    let gather_at = |at: &[(DVec3, u32)]| {
        let points: Vec<(DVec3, DVec3, u32)> = (at.iter())
            .map(|&(p, f)| {
                let face = &scene.faces[f as usize];
                (vertex_gather_point(face, p), face.normal, f)
            })
            .collect();
        radiosity_at_points(domain, trained, &emitters, config, &points)
    };
    let vertices: Vec<(DVec3, u32)> = tri.positions.iter().copied().zip(vertex_face).collect();
    // ⟨Gather once where coplanar faces of one material share a vertex (crate::weld)⟩
    let welded = crate::weld::weld(&scene.faces, k.bvh, scene.diagonal(), &vertices);
    let at: Vec<(DVec3, u32)> = welded.gathered.iter().map(|&v| vertices[v]).collect();
    let phase = crate::progress::phase("mesh");
    let once = gather_at(&at)?;
    drop(phase);
    let gathered = welded.representative.iter().map(|&r| once[r]).collect();
    // ⟨Refine where B varies faster than linear interpolation follows (shadow edges)⟩
    let (tri, gathered) = if config.gather == GatherMode::Paths {
        let refine_limits = RefineLimits::for_diagonal(scene.diagonal());
        let _phase = crate::progress::phase("refinement");
        refine(tri, gathered, refine_limits, gather_at)?
    } else {
        (tri, gathered)
    };
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
    let stats = GatherStats {
        network_share: if total > 0.0 { net / total } else { 0.0 },
        ..GatherStats::of(&gathered)
    };
    Ok((mesh, stats))
}

//! The output mesh: the scene's faces re-triangulated, with a radiosity value per vertex.

use glam::DVec3;

/// A triangle mesh with per-vertex radiosity, the result of a solve (sec. 4.3.1–4.3.2).
///
/// `radiosity[v]` is the radiosity B (exitance, emission included) at vertex `v`, one value per
/// colour band (grey scenes repeat the band three times so that every writer sees RGB).
#[derive(Clone, Debug, Default)]
pub struct ShadedMesh {
    /// Vertex positions in scene units.
    pub positions: Vec<DVec3>,
    /// Counter-clockwise vertex indices; the front side follows the scene face's winding.
    pub triangles: Vec<[u32; 3]>,
    /// Index of the scene face each triangle was cut from.
    pub face_of_triangle: Vec<u32>,
    /// Radiosity B per vertex, RGB.
    pub radiosity: Vec<[f64; 3]>,
}

impl ShadedMesh {
    /// Number of vertices.
    pub fn vertex_count(&self) -> usize {
        self.positions.len()
    }

    /// Number of triangles.
    pub fn triangle_count(&self) -> usize {
        self.triangles.len()
    }

    /// Axis-aligned bounds `(min, max)` of the vertices; `None` for an empty mesh.
    pub fn bounds(&self) -> Option<(DVec3, DVec3)> {
        let first = *self.positions.first()?;
        Some(
            self.positions
                .iter()
                .fold((first, first), |(lo, hi), p| (lo.min(*p), hi.max(*p))),
        )
    }
}

//! One gather for a mesh vertex that several faces share (beyond the dissertation).
//!
//! The output mesh keeps each input face's own vertices ([`crate::retriangulate`] cuts face by
//! face), so a vertex of a tessellated wall is gathered once for every triangle around it: about six
//! times in a regular mesh, and on models of 10⁵ triangles, that is most of the output's time. B is
//! continuous across an edge between coplanar faces of one material unless something stands on the
//! edge (a wall on a floor's edge: one side lit, the other under it). So vertices at the same
//! position on coplanar, untextured faces of equal ρ and E are gathered once, unless a short segment
//! between the two faces' sides of the vertex, lifted off the plane, is blocked.

use glam::DVec3;
use scene_sampler::{Face, SceneBvh};
use std::collections::HashMap;

/// Which vertices share one gather: `representative[k]` is the index, among the representatives,
/// of vertex `k`'s gather.
pub(crate) struct Welded {
    /// Vertices gathered: indices into the caller's vertex list.
    pub(crate) gathered: Vec<usize>,
    /// For every vertex, its gather's index in `gathered`.
    pub(crate) representative: Vec<usize>,
}

/// Groups `vertices` (position, face) of `faces` that can share a gather (module docs). `bvh`
/// tests the segment between two faces' sides of a vertex: from the vertex toward each face's
/// centroid (a tenth of the way, at least 20 ray offsets, at most half), lifted along the normal by
/// 10 ray offsets ([`SceneBvh::epsilon`]), so that it passes over the coplanar faces around the
/// vertex and through anything standing on the edge. Positions match on a grid of 10⁻⁹ of the
/// scene's diagonal.
pub(crate) fn weld(
    faces: &[Face],
    bvh: &SceneBvh,
    diagonal: f64,
    vertices: &[(DVec3, u32)],
) -> Welded {
    let grid = 1e-9 * diagonal;
    let key = |p: DVec3| (p / grid).round().as_i64vec3().to_array();
    let eps = bvh.epsilon();
    let mut at: HashMap<[i64; 3], Vec<usize>> = HashMap::new();
    let mut welded = Welded {
        gathered: Vec::new(),
        representative: Vec::with_capacity(vertices.len()),
    };
    for (k, &(p, f)) in vertices.iter().enumerate() {
        let face = &faces[f as usize];
        let candidates = at.entry(key(p)).or_default();
        let shares = |r: usize| {
            let (q, g) = vertices[welded.gathered[r]];
            if g == f {
                return true;
            }
            let other = &faces[g as usize];
            let side = |c: DVec3| {
                let t = (20.0 * eps / c.distance(q).max(1e-300)).clamp(0.1, 0.5);
                q + t * (c - q) + 10.0 * eps * face.normal
            };
            face.texture.is_none()
                && other.texture.is_none()
                && face.rho == other.rho
                && face.emission == other.emission
                && face.normal.dot(other.normal) > 1.0 - 1e-9
                && bvh.segment_clear(side(face.centroid()), side(other.centroid()), f, g)
        };
        match candidates.iter().copied().find(|&r| shares(r)) {
            Some(r) => welded.representative.push(r),
            None => {
                candidates.push(welded.gathered.len());
                welded.representative.push(welded.gathered.len());
                welded.gathered.push(k);
            }
        }
    }
    welded
}

#[cfg(test)]
mod tests {
    use super::*;
    use scene_sampler::{Scene, Spectrum};

    /// The unit square at y = 0 (normal +y) as two triangles sharing the diagonal (0,0,0)–(1,0,1),
    /// the second of albedo `rho2`; with `wall`, a vertical triangle standing on that diagonal.
    fn floor(rho2: f64, wall: bool) -> (Scene, Vec<(DVec3, u32)>) {
        let p = |x: f64, y: f64, z: f64| DVec3::new(x, y, z);
        let mut faces = vec![
            Face::new(
                [p(0., 0., 0.), p(0., 0., 1.), p(1., 0., 1.)],
                Spectrum::grey(0.5),
                Spectrum::ZERO,
                0,
                0,
            ),
            Face::new(
                [p(0., 0., 0.), p(1., 0., 1.), p(1., 0., 0.)],
                Spectrum::grey(rho2),
                Spectrum::ZERO,
                0,
                0,
            ),
        ];
        if wall {
            faces.push(Face::new(
                [p(0., 0., 0.), p(1., 0., 1.), p(0.5, 1., 0.5)],
                Spectrum::grey(0.5),
                Spectrum::ZERO,
                1,
                1,
            ));
        }
        let scene = Scene::new(
            "weld",
            "test",
            faces,
            vec!["floor".into(), "wall".into()],
            None,
        )
        .unwrap();
        let vertices = (scene.faces.iter().enumerate())
            .flat_map(|(f, face)| face.v.map(|v| (v, f as u32)))
            .collect();
        (scene, vertices)
    }

    fn gathers(rho2: f64, wall: bool) -> Vec<usize> {
        let (scene, vertices) = floor(rho2, wall);
        let bvh = SceneBvh::new(&scene);
        let w = weld(&scene.faces, &bvh, scene.diagonal(), &vertices);
        assert_eq!(w.representative.len(), vertices.len());
        for (k, &r) in w.representative.iter().enumerate() {
            assert_eq!(
                vertices[w.gathered[r]].0, vertices[k].0,
                "a vertex shares only its own position"
            );
        }
        w.representative
    }

    #[test]
    fn coplanar_faces_of_one_material_share_their_common_vertices() {
        // the diagonal's two ends are gathered once: 4 gathers for 6 vertices
        assert_eq!(gathers(0.5, false), [0, 1, 2, 0, 2, 3]);
    }

    #[test]
    fn a_wall_on_the_edge_or_another_material_keeps_them_apart() {
        // one side of the diagonal is under the wall's lit side, the other under its dark side
        assert_eq!(gathers(0.5, true), [0, 1, 2, 3, 4, 5, 6, 7, 8]);
        assert_eq!(gathers(0.7, false), [0, 1, 2, 3, 4, 5]);
    }
}

//! The output mesh: the scene re-triangulated at the shading network's resolution (or a uniform
//! one), B gathered at every vertex, refined where B varies (sec. 4.3.1–4.3.2).

use super::raster::{IMAGE_SUPERSAMPLING, PinholeCamera, faces_seen};
use crate::config::GatherMode;
use crate::config::SolveConfig;
use crate::domain::Domain;
use crate::emitters::Emitters;
use crate::estimator::{GatherError, GatherStats, radiosity_at_points};
use crate::gather::Gathered;
use crate::mesh::ShadedMesh;
use crate::refine::{RefineLimits, refine};
use crate::retriangulate::{RetriangulateLimits, retriangulate};
use crate::solve::Trained;
use crate::spatial::BoxGrid;
use glam::DVec3;
use scene_sampler::{Scene, SceneBvh};

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

/// The faces whose front some image of `images` shows, the starting triangulation rasterized
/// as the images will be ([`faces_seen`]).
fn faces_seen_by(
    tri: &crate::retriangulate::Triangulation,
    scene: &Scene,
    images: &[(PinholeCamera, u32, u32)],
) -> Vec<bool> {
    let flat = ShadedMesh {
        positions: tri.positions.clone(),
        triangles: tri.triangles.clone(),
        face_of_triangle: tri.face_of_triangle.clone(),
        radiosity: vec![[0.0; 3]; tri.positions.len()],
    };
    let mut seen = vec![false; scene.faces.len()];
    for (camera, w, h) in images {
        let size = (*w, *h, IMAGE_SUPERSAMPLING);
        let one = faces_seen(&flat, Some(scene), camera, size, scene.faces.len());
        for (s, o) in seen.iter_mut().zip(one) {
            *s |= o;
        }
    }
    seen
}

/// The side of the finest pixel any of `images` has at `p`: 2·d·tan(fov/2)/height at the
/// distance d from its eye (the centre of the image's footprint; off-axis pixels are a little
/// larger).
fn finest_pixel(images: &[(PinholeCamera, u32, u32)], p: DVec3) -> f64 {
    (images.iter())
        .map(|(c, _, h)| {
            let t = (0.5 * c.fov_y_degrees).to_radians().tan();
            2.0 * c.eye.distance(p) * t / f64::from((*h).max(1))
        })
        .fold(f64::INFINITY, f64::min)
}

/// Where [`output_mesh`] gathers B for a vertex at `p` of face `f`: 10⁻⁴ of the way from `p` to
/// the face's centroid. A vertex on an edge of its face where another face meets it (a block
/// standing on the floor, the floor at a wall) gathers, exactly there, about half its B: the
/// adjoining face, within the ray offsets of the point, blocks the rays that leave toward it
/// (measured on cornell-box, docs/guide/bakes.md). The move is far below the mesh's resolution.
///
/// A vertex under a solid (a floor's corner under a wall standing on it, common in real models)
/// would gather the solid's dark inside, and its triangles would show a dark wedge reaching into
/// the open floor: a short ray along the face toward its centroid, lifted off the face, that
/// meets the back of a face first (the point is inside a solid) moves the point to just past that
/// face, where the visible part of the face begins — as lightmap texels are moved
/// (`lightmap/texels.rs`). When the way to the centroid does not come out (the centroid is under
/// a solid too: a large ground triangle whose corners and middle lie under a platform while a
/// strip of it shows), a point under a solid (along its normal the back of a face comes first)
/// gathers at the nearest of 136 points spread over its face that is not: a triangle of three
/// buried corners showed a dark wedge in a public temple's image.
pub fn vertex_gather_point(scene: &Scene, bvh: &SceneBvh, f: u32, p: DVec3) -> DVec3 {
    let face = &scene.faces[f as usize];
    let q = p + 1e-4 * (face.centroid() - p);
    let to_centre = face.centroid() - q;
    let (reach, dir) = (to_centre.length(), to_centre.normalize_or_zero());
    if let Some(d) = bvh.solid_exit(scene, (q, face.normal, f), dir, reach) {
        return q + dir * (d + 2.0 * bvh.backoff()).min(reach);
    }
    let under = |x: DVec3| {
        (bvh.solid_exit(scene, (x, face.normal, f), face.normal, f64::INFINITY)).is_some()
    };
    if !under(q) {
        return q;
    }
    nearest_open_point(face, q, under).unwrap_or(q)
}

/// Parts per side of the grid [`vertex_gather_point`] searches a buried vertex's face with.
const OPEN_POINT_GRID: u32 = 16;

/// The point nearest `p` for which `under` is false among the centres of the upright
/// sub-triangles of `face` with each side cut in [`OPEN_POINT_GRID`] parts (136 points).
fn nearest_open_point(
    face: &scene_sampler::Face,
    p: DVec3,
    under: impl Fn(DVec3) -> bool,
) -> Option<DVec3> {
    let n = f64::from(OPEN_POINT_GRID);
    let [a, b, c] = face.v;
    let mut points: Vec<DVec3> = (0..OPEN_POINT_GRID)
        .flat_map(|i| (0..OPEN_POINT_GRID - i).map(move |j| (f64::from(i), f64::from(j))))
        .map(|(i, j)| {
            let (u, v) = ((i + 1.0 / 3.0) / n, (j + 1.0 / 3.0) / n);
            a + (b - a) * u + (c - a) * v
        })
        .collect();
    points.sort_by(|x, y| x.distance_squared(p).total_cmp(&y.distance_squared(p)));
    points.into_iter().find(|&x| !under(x))
}

/// Which faces the output mesh gathers B for.
#[derive(Clone, Copy, Debug)]
pub enum MeshExtent<'a> {
    /// Every face: the mesh is an output of its own (glTF, PLY).
    Whole,
    /// Only what these images show, `(camera, width, height)` each: faces whose front no image
    /// sees keep B = 0 and are not refined, and no edge is split below two pixels of the image
    /// that sees it finest. For images alone: from a public 125 000-triangle model an automatic
    /// view showed a fifth of it, and the whole mesh was 340 000 vertices refined to 1.6 million.
    SeenBy(&'a [(PinholeCamera, u32, u32)]),
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
    output_mesh_of(domain, trained, config, limits, MeshExtent::Whole)
}

/// [`output_mesh`] for the faces of `extent` only.
pub(crate) fn output_mesh_of(
    domain: &Domain,
    trained: &Trained,
    config: &SolveConfig,
    limits: RetriangulateLimits,
    extent: MeshExtent,
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
                let at = vertex_gather_point(scene, k.bvh, f, p);
                (at, scene.faces[f as usize].normal, f)
            })
            .collect();
        radiosity_at_points(domain, trained, &emitters, config, &points)
    };
    // ⟨The vertices to gather: all, or those of the faces an image sees⟩
    let seen = match extent {
        MeshExtent::Whole => None,
        MeshExtent::SeenBy(images) => Some(faces_seen_by(&tri, scene, images)),
    };
    let keep: Vec<bool> = (vertex_face.iter())
        .map(|&f| seen.as_ref().is_none_or(|s| s[f as usize]))
        .collect();
    let vertices: Vec<(DVec3, u32)> = (tri.positions.iter().copied().zip(vertex_face))
        .zip(&keep)
        .filter_map(|(v, &k)| k.then_some(v))
        .collect();
    // ⟨Gather once where coplanar faces of one material share a vertex (crate::weld)⟩
    let welded = crate::weld::weld(&scene.faces, k.bvh, scene.diagonal(), &vertices);
    let at: Vec<(DVec3, u32)> = welded.gathered.iter().map(|&v| vertices[v]).collect();
    // ⟨What the memory holds, checked before the gather; each refinement level at most that⟩
    let fits = super::memory::check_mesh_memory(at.len(), crate::metrics::available_memory())?;
    let phase = crate::progress::phase("mesh");
    let once = gather_at(&at)?;
    drop(phase);
    let mut kept = welded.representative.iter().map(|&r| once[r]);
    let gathered = (keep.iter())
        .map(|keep| match keep {
            true => kept.next().expect("one value per kept vertex"),
            false => Gathered::default(),
        })
        .collect();
    // ⟨Refine where B varies faster than linear interpolation follows (shadow edges)⟩
    let (tri, gathered) = if config.gather == GatherMode::Paths {
        let refine_limits = RefineLimits {
            max_level_points: fits,
            ..RefineLimits::for_scene(scene.diagonal(), local.uniform)
        };
        let finest = |p: DVec3| match extent {
            MeshExtent::Whole => 0.0,
            MeshExtent::SeenBy(images) => 2.0 * finest_pixel(images, p),
        };
        let _phase = crate::progress::phase("refinement");
        refine(tri, gathered, refine_limits, finest, gather_at)?
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
    let mesh = ShadedMesh {
        positions: tri.positions,
        triangles: tri.triangles,
        face_of_triangle: tri.face_of_triangle,
        radiosity: gathered.iter().map(|g| g.rgb(domain.bands())).collect(),
    };
    let stats = GatherStats {
        network_share: if total > 0.0 { net / total } else { 0.0 },
        ..GatherStats::of(&gathered)
    };
    Ok((mesh, stats))
}

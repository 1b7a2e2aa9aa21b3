//! Secondary sources (beyond the dissertation; issue 32): the surfaces the lights reach directly,
//! sampled as lights of their own at every vertex of the paths gather.
//!
//! Where indirect light is hard to find (a sun patch on the floor lighting a room, a wall that
//! a lamp lights through a door gap), most of it comes from a small part of the scene that the
//! lights reach directly. A cosine-distributed bounce finds that part rarely; a guide learns it
//! only from the bounces that found it. Here it is tabulated before the gather, once for every
//! point: the direct radiosity F(z) = ρ(z)·H_d(z) (H_d the irradiance straight from the lights,
//! by next-event estimation) over cells of equal area on every face, and at each vertex x a point
//! z is drawn in proportion to F·area (a cell by its weight, a point uniform in it) and joined to
//! x by a shadow ray: the strategy of a bidirectional path tracer that joins a light path's first
//! surface vertex to the eye path, with the light path replaced by the table (its density is
//! known everywhere, so the weights are exact).
//!
//! The direct radiosity's share of x's reflected light, `∫ F(z)·G(x, z)·V dA(z)` (G = cos θ_x
//! cos θ_z/(π r²)), is then estimated twice, and the two are combined by the balance heuristic
//! (Veach 1997, eq. 9.4): the bounce from x that hits z brings z's direct light F̂(z) with weight
//! p_a/(p_a + Q), and the drawn z brings F̂′(z)·G·V/(p_a + Q), where
//!
//! ```text
//! p_a(z) = c·q_g·G(x, z)     the bounce's density at z in area measure (c its count: the
//!                            roulette's probability × branches; q_g a guide's density)
//! Q(z)   = w_cell/(W·A_cell) the table's
//! ```
//!
//! Both weights sum to one at every z (unbiased whatever the table says: a cell the table missed
//! is left to the bounce, as without it). F̂′(z) is the lights' next-event estimate at z alone
//! (no MIS against z's own bounce, which the drawn z does not cast). Groups of neighbours draw
//! z as they share hits (`neighbours.rs`): each z is seen by every member, the bounce's density
//! being the members' mixture.
//!
//! This file is the table; `relay.rs` draws from it at the paths' vertices and decides where it
//! pays.
//!
//! The cells: the face's square parameter domain of the uniform warp
//! ([`scene_sampler::uniform_triangle`], area-preserving) cut into k × k squares, k set so that a
//! cell's area is about the scene's area over [`CELLS`] (one cell at least per face). Each cell's
//! weight is the mean of F̂ over [`SAMPLES`] uniform points in it times its area.

use glam::DVec3;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use scene_sampler::{Discrete, Scene, uniform_triangle};

/// Cells of the table over the whole scene, about (every face has one at least).
pub(crate) const CELLS: usize = 1 << 16;
/// Next-event samples per cell.
pub(crate) const SAMPLES: usize = 2;

/// The table of direct radiosity over the scene's faces (module docs).
pub(crate) struct SecondarySources {
    /// Per face: its first cell and its cells per side (k; k² cells).
    faces: Vec<(u32, u32)>,
    /// Cell → face.
    cell_face: Vec<u32>,
    /// The cells, drawn by weight.
    cells: Discrete,
}

impl SecondarySources {
    /// The table of `scene` with `direct(face, point, u)` the luminance of F̂ at a point of a face
    /// (one next-event estimate with the random numbers `u`), its samples seeded by `seed`; None
    /// where no light reaches a reflecting face.
    pub(crate) fn new(
        scene: &Scene,
        seed: u64,
        direct: impl Fn(u32, DVec3, [f64; 3]) -> f64 + Sync,
    ) -> Option<Self> {
        let cell_area = scene.total_area() / CELLS as f64;
        let mut faces = Vec::with_capacity(scene.faces.len());
        let mut count = 0u32;
        for f in &scene.faces {
            let k = ((f.area / cell_area).sqrt().ceil() as u32).clamp(1, 256);
            faces.push((count, k));
            count = count.checked_add(k * k)?;
        }
        // ⟨Each face's cells: the mean direct radiosity at SAMPLES points times the area⟩
        let weights: Vec<Vec<f64>> = (0..scene.faces.len())
            .into_par_iter()
            .map(|i| {
                let f = &scene.faces[i];
                let k = faces[i].1;
                let mut rng = ChaCha8Rng::seed_from_u64(seed ^ ((i as u64 + 1) * 0x9E37_79B9));
                (0..k * k)
                    .map(|c| {
                        let sum: f64 = (0..SAMPLES)
                            .map(|_| {
                                let u: [f64; 5] = std::array::from_fn(|_| rng.random());
                                let p = cell_point(f, k, c, [u[0], u[1]]);
                                direct(i as u32, p, [u[2], u[3], u[4]])
                            })
                            .sum();
                        sum / SAMPLES as f64 * f.area / (k * k) as f64
                    })
                    .collect()
            })
            .collect();
        let weights: Vec<f64> = weights.into_iter().flatten().collect();
        let cells = Discrete::new(&weights)?;
        let cell_face = (faces.iter().enumerate())
            .flat_map(|(i, &(_, k))| std::iter::repeat_n(i as u32, (k * k) as usize))
            .collect();
        Some(Self {
            faces,
            cell_face,
            cells,
        })
    }

    /// A point drawn from the table with `u`: (point, normal, face) and the table's area density
    /// there; None where it falls in a cut-out hole (no surface there: it brings nothing).
    pub(crate) fn sample(&self, scene: &Scene, u: [f64; 3]) -> Option<((DVec3, DVec3, u32), f64)> {
        let cell = self.cells.sample(u[0]);
        let face = self.cell_face[cell];
        let (first, k) = self.faces[face as usize];
        let f = &scene.faces[face as usize];
        let p = cell_point(f, k, cell as u32 - first, [u[1], u[2]]);
        if scene.is_hole(face, p) {
            return None;
        }
        let density = self.cells.probability(cell) * (k * k) as f64 / f.area;
        Some(((p, f.normal, face), density))
    }

    /// The table's area density at `p` on `face` (0 on no face).
    pub(crate) fn density(&self, scene: &Scene, face: u32, p: DVec3) -> f64 {
        let Some(&(first, k)) = self.faces.get(face as usize) else {
            return 0.0;
        };
        let f = &scene.faces[face as usize];
        let (b1, b2) = f.barycentric(p);
        // the inverse of the warp: s = b1 + b2 = √u0, u1 = b2/s
        let s = (b1 + b2).clamp(0.0, 1.0);
        let u1 = if s > 0.0 {
            (b2 / s).clamp(0.0, 1.0)
        } else {
            0.0
        };
        let cell_of = |u: f64| ((u * k as f64) as u32).min(k - 1);
        let cell = first + cell_of(s * s) * k + cell_of(u1);
        self.cells.probability(cell as usize) * (k * k) as f64 / f.area
    }
}

/// The point of cell `c` (row-major in the k × k square) of face `f` at `u` within the cell.
fn cell_point(f: &scene_sampler::Face, k: u32, c: u32, u: [f64; 2]) -> DVec3 {
    let (row, col) = (c / k, c % k);
    let square = [
        (row as f64 + u[0]) / k as f64,
        (col as f64 + u[1]) / k as f64,
    ];
    let [b1, b2] = uniform_triangle(square);
    f.point(b1, b2)
}

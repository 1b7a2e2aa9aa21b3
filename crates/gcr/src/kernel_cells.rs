//! The kernel network frozen for the FEM steps and the projection (docs/design/math.md §3): per cell the
//! sender and receiver halves of its centre, its width, its outputs and the facing masks of its
//! halves.

use crate::element::{BANDS, Bands};
use glam::DVec3;
use rayon::prelude::*;

/// The kernel network frozen for one FEM step: per cell o the sender half w_o^x, the receiver
/// half w_o^y of its centre, its width d_o and output v_o.
#[derive(Clone, Debug, Default)]
pub struct KernelCells {
    /// Sender halves w_o^x.
    pub wx: Vec<DVec3>,
    /// Receiver halves w_o^y.
    pub wy: Vec<DVec3>,
    /// Widths d_o (eq. 2.10, in the 6-D / 4-D input space).
    pub width: Vec<f64>,
    /// Outputs v_o per band.
    pub v: Vec<Bands>,
    /// Facing direction of each sender half: with facing masks
    /// ([`crate::config::SolveConfig::kernel_facing`]) the Gaussian lives only on surfaces whose
    /// normal n has n · nx_o > [`KernelCells::facing_cos`]. Empty, or a zero vector: everywhere.
    pub nx: Vec<DVec3>,
    /// Facing direction of each receiver half (as [`KernelCells::nx`]).
    pub ny: Vec<DVec3>,
    /// Cosine threshold of the facing masks.
    pub facing_cos: f64,
}

impl KernelCells {
    /// Number of cells.
    pub fn len(&self) -> usize {
        self.wx.len()
    }

    /// True when empty.
    pub fn is_empty(&self) -> bool {
        self.wx.is_empty()
    }

    /// The facing direction of cell o's sender half (zero: no mask).
    pub fn facing_x(&self, o: usize) -> DVec3 {
        self.nx.get(o).copied().unwrap_or(DVec3::ZERO)
    }

    /// The facing direction of cell o's receiver half (zero: no mask).
    pub fn facing_y(&self, o: usize) -> DVec3 {
        self.ny.get(o).copied().unwrap_or(DVec3::ZERO)
    }

    /// Whether a half with facing direction `f` lives at a surface point with unit normal `n`.
    pub fn lives_on(&self, f: DVec3, n: DVec3) -> bool {
        f == DVec3::ZERO || n == DVec3::ZERO || f.dot(n) > self.facing_cos
    }

    /// Whether cell o's Gaussian lives at a sender with unit normal `nx` and a receiver with unit
    /// normal `ny`; one test of an empty vector when there are no masks (the inner loops of the
    /// moments and the collection run it per cell and point).
    #[inline]
    pub fn accepts(&self, o: usize, nx: DVec3, ny: DVec3) -> bool {
        self.nx.is_empty() || (self.lives_on(self.nx[o], nx) && self.lives_on(self.ny[o], ny))
    }

    /// [`KernelCells::accepts`] for the receiver half alone.
    #[inline]
    pub fn accepts_receiver(&self, o: usize, ny: DVec3) -> bool {
        self.ny.is_empty() || self.lives_on(self.ny[o], ny)
    }

    /// Gives every cell facing masks: each half faces like the surface at the sample nearest to
    /// the cell's centre in the kernel's input space (x, y). Cells then stop blurring light
    /// across the edges where surfaces meet (a Gaussian centred on a lit floor no longer puts
    /// light on the shaded side of a block standing on it) — the kernel's counterpart of the
    /// breaking operator (sec. 4.4.2) and the sub-network zero rules of fig. 3.6.
    pub fn assign_facing(&mut self, samples: &[(DVec3, DVec3, DVec3, DVec3)], facing_cos: f64) {
        self.facing_cos = facing_cos;
        let (nx, ny): (Vec<DVec3>, Vec<DVec3>) = (0..self.len())
            .into_par_iter()
            .map(|o| {
                let mut best = (f64::INFINITY, DVec3::ZERO, DVec3::ZERO);
                for (x, nx, y, ny) in samples {
                    let d = self.wx[o].distance_squared(*x) + self.wy[o].distance_squared(*y);
                    if d < best.0 {
                        best = (d, *nx, *ny);
                    }
                }
                (best.1, best.2)
            })
            .unzip();
        self.nx = nx;
        self.ny = ny;
    }

    /// The network's light flow Ψ(x, y) = Σ_o v_o exp(−(|x − w_o^x|² + |y − w_o^y|²)/d_o²)
    /// per band (eq. 2.1–2.3 with the kernel's 6-D / 4-D input), summed over every cell whose
    /// facing masks accept the normals `nx` at x and `ny` at y.
    pub fn evaluate(&self, x: DVec3, nx: DVec3, y: DVec3, ny: DVec3) -> Bands {
        let mut out = [0.0; BANDS];
        for o in 0..self.len() {
            if !self.accepts(o, nx, ny) {
                continue;
            }
            let e = (self.wx[o].distance_squared(x) + self.wy[o].distance_squared(y))
                / (self.width[o] * self.width[o]);
            let g = (-e).exp();
            for (acc, v) in out.iter_mut().zip(&self.v[o]) {
                *acc += g * v;
            }
        }
        out
    }
}

//! The kernel cells laid out for the loops that visit every cell at every point: the moments and
//! supports of the projection (one per shot sample and fit), the kernel collection (one per sample
//! and bounce, and per gather ray).
//!
//! At 1400 cells a bounce evaluates about 2·10⁷ Gaussians. A loop over [`KernelCells`] tests each
//! cell's cut-off with a branch that goes either way (a third to a half of the cells are beyond
//! e^(−cut) at a point) and calls `f64::exp` for the rest. Here the centres are stored by
//! coordinate, and every cell's factor is computed branch-free, four lanes wide on AVX2 (`pulp`'s
//! runtime dispatch): g_o = [`isgcs::gaussian`](e_o) where e_o ≤ cut and the facing masks accept
//! the point, else 0. Cells beyond the cut-off thus contribute exactly 0, as the branch did.

use crate::element::{BANDS, Bands};
use crate::kernel_cells::KernelCells;
use glam::DVec3;
use isgcs::gaussian;
use std::ops::Range;

/// Cells per block of [`Collection::at`]: the factors of one block live in a stack array.
const BLOCK: usize = 64;

/// One half (sender x or receiver y) of every cell: centre coordinates by axis and the facing
/// directions of the masks (empty without masks: [`KernelCells::nx`] empty).
#[derive(Clone, Debug, Default)]
struct Halves {
    c: [Vec<f64>; 3],
    f: [Vec<f64>; 3],
    /// The facing direction is zero (the half lives everywhere).
    f_zero: Vec<bool>,
}

impl Halves {
    fn new(centres: &[DVec3], facing: &[DVec3]) -> Self {
        let axis = |v: &[DVec3], k: usize| v.iter().map(|p| p[k]).collect::<Vec<f64>>();
        Self {
            c: [axis(centres, 0), axis(centres, 1), axis(centres, 2)],
            f: [axis(facing, 0), axis(facing, 1), axis(facing, 2)],
            f_zero: facing.iter().map(|f| *f == DVec3::ZERO).collect(),
        }
    }

    /// The centres' coordinates of the cells in `r`.
    #[inline(always)]
    fn slices(&self, r: Range<usize>) -> Axes<'_> {
        [&self.c[0][r.clone()], &self.c[1][r.clone()], &self.c[2][r]]
    }

    /// The facing directions of the cells in `r` (with masks), and which are zero.
    #[inline(always)]
    fn facing(&self, r: Range<usize>) -> (Axes<'_>, &[bool]) {
        let f = [
            &self.f[0][r.clone()],
            &self.f[1][r.clone()],
            &self.f[2][r.clone()],
        ];
        (f, &self.f_zero[r])
    }
}

/// Three coordinate slices of equal length.
type Axes<'a> = [&'a [f64]; 3];

/// |p − w_i|² with w_i from the coordinate slices (summed x, y, z, as
/// `DVec3::distance_squared`).
#[inline(always)]
fn distance_squared(c: Axes<'_>, i: usize, p: DVec3) -> f64 {
    let d = [c[0][i] - p.x, c[1][i] - p.y, c[2][i] - p.z];
    d[0] * d[0] + d[1] * d[1] + d[2] * d[2]
}

/// [`KernelCells::lives_on`] of half i (facing directions `f`, zero flags) at a point with unit
/// normal `n` ≠ 0.
#[inline(always)]
fn lives_on((f, zero): (Axes<'_>, &[bool]), i: usize, n: DVec3, cos_min: f64) -> bool {
    zero[i] | (f[0][i] * n.x + f[1][i] * n.y + f[2][i] * n.z > cos_min)
}

/// The kernel cells by coordinate, with a = 1/d_o² and the cells left out of the projection.
#[derive(Clone, Debug, Default)]
pub struct CellLanes {
    x: Halves,
    y: Halves,
    a: Vec<f64>,
    /// Cells whose pair Gaussians are 0 (left out of the projection for want of samples).
    skip: Vec<bool>,
    masks: bool,
    cos_min: f64,
}

impl CellLanes {
    /// The cells of `kernel`; `excluded` (empty, or one flag per cell) marks cells whose pair
    /// factor ([`CellLanes::pair_gaussians`]) is always 0.
    pub fn new(kernel: &KernelCells, excluded: &[bool]) -> Self {
        let n = kernel.len();
        let masks = !kernel.nx.is_empty();
        Self {
            x: Halves::new(&kernel.wx, &kernel.nx),
            y: Halves::new(&kernel.wy, &kernel.ny),
            a: kernel.width.iter().map(|d| 1.0 / (d * d)).collect(),
            skip: (0..n)
                .map(|o| excluded.get(o).copied().unwrap_or(false))
                .collect(),
            masks,
            cos_min: kernel.facing_cos,
        }
    }

    /// Number of cells.
    pub fn len(&self) -> usize {
        self.a.len()
    }

    /// `out[o] = exp(−(|x − w_o^x|² + |y − w_o^y|²)/d_o²)`, the cell's Gaussian at ξ = (x, y)
    /// (eq. 2.1 in the kernel's input space), for every cell whose exponent is at most `cut`, that
    /// is not skipped and whose facing masks accept the normals `nx` at x and `ny` at y; 0 for the
    /// others. `out` has one entry per cell.
    pub fn pair_gaussians(
        &self,
        (x, nx): (DVec3, DVec3),
        (y, ny): (DVec3, DVec3),
        cut: f64,
        out: &mut [f64],
    ) {
        assert_eq!(out.len(), self.len(), "one factor per cell");
        pulp::Arch::new().dispatch(Pair {
            lanes: self,
            x: (x, nx),
            y: (y, ny),
            cut,
            out,
        });
    }

    /// `out[o] = exp(−|y − w_o^y|²/d_o²)` for every cell, as [`CellLanes::pair_gaussians`] for
    /// the receiver halves alone (at a point y with unit normal `n`), skipped cells included:
    /// the collection weighs a cell by its output, which is 0 for a cell left out of the
    /// projection.
    pub fn receiver_gaussians(&self, (y, n): (DVec3, DVec3), cut: f64, out: &mut [f64]) {
        assert_eq!(out.len(), self.len(), "one factor per cell");
        pulp::Arch::new().dispatch(Receiver {
            lanes: self,
            y: (y, n),
            cut,
            out,
        });
    }

    /// `out[i] = exp(−|y − w_o^y|²/d_o²)` for the cells `o = first + i` of one block, as
    /// [`CellLanes::receiver_gaussians`].
    #[inline(always)]
    fn receiver_block(&self, first: usize, (y, n): (DVec3, DVec3), cut: f64, out: &mut [f64]) {
        let r = first..first + out.len();
        let a = &self.a[r.clone()];
        let c = self.y.slices(r.clone());
        if self.masks && n != DVec3::ZERO {
            let f = self.y.facing(r);
            for (i, g) in out.iter_mut().enumerate() {
                let e = a[i] * distance_squared(c, i, y);
                let keep = (e <= cut) & lives_on(f, i, n, self.cos_min);
                *g = if keep { gaussian(e) } else { 0.0 };
            }
        } else {
            for (i, g) in out.iter_mut().enumerate() {
                let e = a[i] * distance_squared(c, i, y);
                *g = if e <= cut { gaussian(e) } else { 0.0 };
            }
        }
    }
}

/// [`CellLanes::pair_gaussians`] as an operation `pulp` compiles for the processor.
struct Pair<'a> {
    lanes: &'a CellLanes,
    x: (DVec3, DVec3),
    y: (DVec3, DVec3),
    cut: f64,
    out: &'a mut [f64],
}

impl pulp::WithSimd for Pair<'_> {
    type Output = ();

    #[inline(always)]
    fn with_simd<S: pulp::Simd>(self, _: S) {
        let Pair {
            lanes: l,
            x: (x, nx),
            y: (y, ny),
            cut,
            out,
        } = self;
        let r = 0..out.len();
        let (a, skip) = (&l.a[r.clone()], &l.skip[r.clone()]);
        let (cx, cy) = (l.x.slices(r.clone()), l.y.slices(r.clone()));
        if l.masks && (nx != DVec3::ZERO || ny != DVec3::ZERO) {
            let (fx, fy) = (l.x.facing(r.clone()), l.y.facing(r));
            for (i, g) in out.iter_mut().enumerate() {
                let e = a[i] * (distance_squared(cx, i, x) + distance_squared(cy, i, y));
                let faces = (nx == DVec3::ZERO || lives_on(fx, i, nx, l.cos_min))
                    & (ny == DVec3::ZERO || lives_on(fy, i, ny, l.cos_min));
                let keep = (e <= cut) & !skip[i] & faces;
                *g = if keep { gaussian(e) } else { 0.0 };
            }
        } else {
            for (i, g) in out.iter_mut().enumerate() {
                let e = a[i] * (distance_squared(cx, i, x) + distance_squared(cy, i, y));
                let keep = (e <= cut) & !skip[i];
                *g = if keep { gaussian(e) } else { 0.0 };
            }
        }
    }
}

/// [`CellLanes::receiver_gaussians`] as an operation `pulp` compiles for the processor.
struct Receiver<'a> {
    lanes: &'a CellLanes,
    y: (DVec3, DVec3),
    cut: f64,
    out: &'a mut [f64],
}

impl pulp::WithSimd for Receiver<'_> {
    type Output = ();

    #[inline(always)]
    fn with_simd<S: pulp::Simd>(self, _: S) {
        self.lanes.receiver_block(0, self.y, self.cut, self.out);
    }
}

/// The kernel collection B_refl(y) = Σ_o v_o c_o exp(−|y − w_o^y|²/d_o²) (fig. 4.13c) prepared
/// for many points: the cells by coordinate and the products v_o c_o by band.
#[derive(Clone, Debug, Default)]
pub struct Collection {
    lanes: CellLanes,
    w: [Vec<f64>; BANDS],
}

/// Gaussian factors below e^(−COLLECTION_CUT) = 10⁻⁹ are left out of the collection: a thousandth
/// of the largest projection tolerance ([`crate::config::SolveConfig::projection_tolerance`]
/// ≤ 10⁻⁶), so the collection is never cruder than the projection whose weights it sums.
const COLLECTION_CUT: f64 = 20.723_265_836_946_41;

impl Collection {
    /// The collection through the frozen `kernel` with its sender integrals c_o in `sender`
    /// ([`crate::fem::sender_integrals`]).
    pub fn new(kernel: &KernelCells, sender: &[f64]) -> Self {
        assert_eq!(sender.len(), kernel.len(), "one sender integral per cell");
        Self {
            lanes: CellLanes::new(kernel, &[]),
            w: std::array::from_fn(|k| {
                kernel.v.iter().zip(sender).map(|(v, c)| v[k] * c).collect()
            }),
        }
    }

    /// B_refl at the surface point y with unit normal `n` (only cells whose receiver half faces
    /// like `n` contribute; a zero `n` takes all). Cells whose Gaussian is below 10⁻⁹ at y are
    /// left out; the sum runs in four interleaved partial sums (a fixed order: the same on every
    /// processor and thread count).
    pub fn at(&self, y: DVec3, n: DVec3) -> Bands {
        pulp::Arch::new().dispatch(At { c: self, y, n })
    }
}

/// [`Collection::at`] as an operation `pulp` compiles for the processor.
struct At<'a> {
    c: &'a Collection,
    y: DVec3,
    n: DVec3,
}

impl pulp::WithSimd for At<'_> {
    type Output = Bands;

    #[inline(always)]
    fn with_simd<S: pulp::Simd>(self, _: S) -> Bands {
        let At { c, y, n } = self;
        let mut acc = [[0.0f64; 4]; BANDS];
        let mut g = [0.0f64; BLOCK];
        let total = c.lanes.len();
        let mut first = 0;
        while first < total {
            let len = BLOCK.min(total - first);
            let g = &mut g[..len];
            c.lanes.receiver_block(first, (y, n), COLLECTION_CUT, g);
            for (k, acc) in acc.iter_mut().enumerate() {
                let w = &c.w[k][first..first + len];
                let mut i = 0;
                while i + 4 <= len {
                    for lane in 0..4 {
                        acc[lane] += w[i + lane] * g[i + lane];
                    }
                    i += 4;
                }
                for (lane, (wi, gi)) in w[i..].iter().zip(&g[i..]).enumerate() {
                    acc[lane] += wi * gi;
                }
            }
            first += len;
        }
        std::array::from_fn(|k| (acc[k][0] + acc[k][1]) + (acc[k][2] + acc[k][3]))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    /// Random cells in the unit cube, widths 0.05–0.5, facing masks when `masks`.
    fn cells(n: usize, masks: bool, rng: &mut ChaCha8Rng) -> KernelCells {
        let mut p = || DVec3::new(rng.random(), rng.random(), rng.random());
        let wx: Vec<DVec3> = (0..n).map(|_| p()).collect();
        let wy: Vec<DVec3> = (0..n).map(|_| p()).collect();
        let axes = [DVec3::X, DVec3::Y, DVec3::Z, -DVec3::X, DVec3::ZERO];
        let mut facing = |i: usize| axes[(i * 7 + n) % axes.len()];
        KernelCells {
            wx,
            wy,
            width: (0..n)
                .map(|i| 0.05 + 0.45 * (i as f64 / n as f64))
                .collect(),
            v: (0..n).map(|i| [1.0, 0.5 + i as f64 * 0.01, -0.2]).collect(),
            nx: if masks {
                (0..n).map(&mut facing).collect()
            } else {
                Vec::new()
            },
            ny: if masks {
                (0..n).map(|i| facing(i + 3)).collect()
            } else {
                Vec::new()
            },
            facing_cos: 0.5,
        }
    }

    /// The cells' Gaussians at (x, y) by the definitions: `KernelCells::accepts`, the exponent,
    /// the cut-off, `f64::exp`.
    fn reference(
        k: &KernelCells,
        skip: &[bool],
        x: (DVec3, DVec3),
        y: (DVec3, DVec3),
        cut: f64,
    ) -> Vec<f64> {
        (0..k.len())
            .map(|o| {
                let e = (k.wx[o].distance_squared(x.0) + k.wy[o].distance_squared(y.0))
                    / (k.width[o] * k.width[o]);
                let ok = !skip[o] && k.accepts(o, x.1, y.1) && e <= cut;
                if ok { (-e).exp() } else { 0.0 }
            })
            .collect()
    }

    #[test]
    fn pair_gaussians_equal_the_definition_with_and_without_masks() {
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        for masks in [false, true] {
            let k = cells(203, masks, &mut rng);
            let skip: Vec<bool> = (0..k.len()).map(|o| o % 11 == 4).collect();
            let lanes = CellLanes::new(&k, &skip);
            let mut out = vec![0.0; k.len()];
            let (mut kept, mut cut_off) = (0, 0);
            for i in 0..50 {
                let x = DVec3::new(rng.random(), rng.random(), rng.random());
                let y = DVec3::new(rng.random(), rng.random(), rng.random());
                let nx = [DVec3::X, DVec3::ZERO, -DVec3::Z][i % 3];
                let ny = [DVec3::Y, -DVec3::X, DVec3::ZERO, DVec3::Z][i % 4];
                lanes.pair_gaussians((x, nx), (y, ny), 13.8, &mut out);
                let want = reference(&k, &skip, (x, nx), (y, ny), 13.8);
                for (g, w) in out.iter().zip(&want) {
                    // a = 1/d² against a division: the exponent e ≤ 13.8 differs by an ulp or
                    // two, which e^(−e) turns into ~e ulps.
                    assert!((g - w).abs() <= 64.0 * f64::EPSILON * w, "{g} vs {w}");
                    kept += usize::from(*w > 0.0);
                    cut_off += usize::from(*w == 0.0);
                }
            }
            // Both sides of the cut-off and of the masks were exercised.
            assert!(kept > 1000 && cut_off > 1000, "{kept} kept, {cut_off} cut");
        }
    }

    #[test]
    fn collection_equals_the_sum_over_cells() {
        let mut rng = ChaCha8Rng::seed_from_u64(5);
        for masks in [false, true] {
            let k = cells(131, masks, &mut rng);
            let sender: Vec<f64> = (0..k.len()).map(|o| 0.1 + (o % 5) as f64).collect();
            let collection = Collection::new(&k, &sender);
            for i in 0..40 {
                let y = DVec3::new(rng.random(), rng.random(), rng.random());
                let n = [DVec3::X, DVec3::ZERO, DVec3::Y][i % 3];
                let got = collection.at(y, n);
                let mut want = [0.0; BANDS];
                let mut scale = [0.0f64; BANDS];
                for o in 0..k.len() {
                    if !k.accepts_receiver(o, n) {
                        continue;
                    }
                    let g = sender[o]
                        * (-k.wy[o].distance_squared(y) / (k.width[o] * k.width[o])).exp();
                    for b in 0..BANDS {
                        want[b] += k.v[o][b] * g;
                        scale[b] += (k.v[o][b] * g).abs();
                    }
                }
                for b in 0..BANDS {
                    // The cut-off drops terms below 10⁻⁹ of each cell's weight; the rest is
                    // rounding of the interleaved sums.
                    assert!(
                        (got[b] - want[b]).abs() <= 1e-9 * scale[b] + 1e-300,
                        "{got:?} vs {want:?}"
                    );
                }
            }
        }
    }
}

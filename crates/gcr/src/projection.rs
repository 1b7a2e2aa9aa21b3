//! The projected output layer (beyond the dissertation): the kernel network's output weights as
//! the L2(S × S) projection of `K·s` onto its Gaussians.
//!
//! The dissertation learns the output weights v_o with the delta rule (eq. 2.8) on single samples of
//! `K(x,y)·s(x)`. That is stochastic gradient descent on `Σ_i (Ψ(ξ_i) − K s(ξ_i))²`, whose samples are
//! heavy-tailed near the edges where surfaces meet (docs/design/math.md §6): a few samples decide the fit, and on
//! `cornell-box` with 200 cells the learned Ψ misses the samples by 93 % (relative RMS) and the kernel
//! collection misses B_refl by 82 %. For fixed centres and widths, the best weights solve the normal
//! equations of the Galerkin projection
//!
//! ```text
//! Σ_o' G_oo' v_o' = b_o,   G_oo' = ∫∫ g_o g_o' dx dy,   b_o = ∫∫ g_o(x,y) K(x,y) s(x) dx dy.
//! ```
//!
//! Both are computable well:
//! - the 2n-dimensional isotropic Gaussians factor into sender and receiver halves, so
//!   `G_oo' = I_oo'(x)·I_oo'(y)`, each a product of two Gaussians on the scene surface — one
//!   Gaussian (the product rule of docs/design/math.md §2) integrated exactly over the scene's triangles
//!   (segments);
//! - `b_o` is a Monte-Carlo sum over *shot* rays ([`crate::shooting`]) whose importance weights
//!   `ρ(y)·s(x)/p_x(x)` are bounded: `b_o ≈ (1/N) Σ_i g_o(ξ_i)·ρ(y_i)·s_i/p_x(x_i)`, N counting
//!   every shot, also those that left the scene.
//!
//! The Gram matrix of overlapping Gaussians is ill-conditioned; it is solved with the rejecting
//! Cholesky factorization of docs/design/math.md §5 ([`gauss_integrals::Orthonormal`]), which drops nearly
//! dependent cells instead of amplifying the Monte-Carlo noise in b.

use crate::cell_lanes::CellLanes;
use crate::cluster::Mask;
use crate::element::{BANDS, Bands};
use crate::fem::SceneSurface;
use crate::kernel_cells::KernelCells;
use crate::sample::Sample;
use crate::spatial::width_a;
use gauss_integrals as integrals;
use gauss_integrals::support_radius;
use glam::DVec3;
use nalgebra::DMatrix;
use rayon::prelude::*;

/// What a projection did.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ProjectionReport {
    /// Cells whose Gaussian was rejected as nearly dependent (their weight is 0).
    pub rejected: usize,
    /// Non-zero Gram entries (both triangles).
    pub gram_entries: usize,
}

/// `∫_S g(x; w1, d1)·g(x; w2, d2) dx` (3-D: the 3 first coordinates; Flatland embeds z = 0):
/// the product is one Gaussian (docs/design/math.md §2) integrated exactly over the scene's elements among
/// `candidates` (ascending ids covering the product's support).
fn half_overlap(
    scene: &SceneSurface,
    (w1, a1): (DVec3, f64),
    (w2, a2): (DVec3, f64),
    tol: f64,
    mask: &Mask,
    candidates: &[u32],
) -> f64 {
    let a = a1 + a2;
    let c = (a1 * w1 + a2 * w2) / a;
    let k = (-(a1 * a2 / a) * w1.distance_squared(w2)).exp();
    if k == 0.0 {
        return 0.0;
    }
    k * scene.masked_gaussian_integral_among(c, a, tol, mask, candidates)
}

/// Per cell, the elements within twice its support radius of each half: a superset of the
/// support of its product with any cell the pair cut keeps. With `ln(1/tol) = L`, a kept pair
/// has `a_o a_p/(a_o + a_p)·|Δ|² ≤ L`, so the product's centre lies within `√(L/a_o)` of `w_o`
/// and its support radius `√(L/(a_o + a_p))` is smaller still. Replaces one grid query per
/// pair and half by one per cell and half.
fn candidates(centres: &[DVec3], widths: &[f64], scene: &SceneSurface, tol: f64) -> Vec<Vec<u32>> {
    centres
        .par_iter()
        .zip(widths)
        .map(|(c, d)| {
            let mut out = Vec::new();
            scene.elements_near(*c, 2.0 * support_radius(width_a(*d), tol), &mut out);
            out
        })
        .collect()
}

/// The Gram matrix `G_oo' = ∫∫_{S×S} g_o g_o'` of the kernel cells (module docs). Entries whose
/// Gaussian product is below `tol` everywhere are exactly 0.
#[cfg_attr(not(feature = "stages"), allow(dead_code))] // read through `gcr::stages`
pub fn kernel_gram(kernel: &KernelCells, scene: &SceneSurface, tol: f64) -> DMatrix<f64> {
    kernel_gram_excluding(kernel, scene, tol, &[])
}

/// [`kernel_gram`] with the rows and columns of the cells flagged in `excluded` left 0 (not
/// computed).
pub fn kernel_gram_excluding(
    kernel: &KernelCells,
    scene: &SceneSurface,
    tol: f64,
    excluded: &[bool],
) -> DMatrix<f64> {
    let skip = |o: usize| excluded.get(o).copied().unwrap_or(false);
    let n = kernel.len();
    let a: Vec<f64> = kernel.width.iter().map(|d| 1.0 / (d * d)).collect();
    let cut = (1.0 / tol).ln();
    let near_x = candidates(&kernel.wx, &kernel.width, scene, tol);
    let near_y = candidates(&kernel.wy, &kernel.width, scene, tol);
    let shorter = |lists: &[Vec<u32>], o: usize, p: usize| -> usize {
        if lists[o].len() <= lists[p].len() {
            o
        } else {
            p
        }
    };
    let rows: Vec<Vec<(usize, f64)>> = (0..n)
        .into_par_iter()
        .map(|o| {
            let mut row = Vec::new();
            if skip(o) {
                return row;
            }
            for p in (o..n).filter(|&p| !skip(p)) {
                let ab = a[o] * a[p] / (a[o] + a[p]);
                let d2 = kernel.wx[o].distance_squared(kernel.wx[p])
                    + kernel.wy[o].distance_squared(kernel.wy[p]);
                if ab * d2 > cut {
                    continue;
                }
                let (ho, hp) = ((kernel.wx[o], a[o]), (kernel.wx[p], a[p]));
                let facing = [kernel.facing_x(o), kernel.facing_x(p)];
                let mask = Mask {
                    facing: &facing,
                    cos_min: kernel.facing_cos,
                };
                let ix = half_overlap(scene, ho, hp, tol, &mask, &near_x[shorter(&near_x, o, p)]);
                if ix == 0.0 {
                    continue;
                }
                let (ho, hp) = ((kernel.wy[o], a[o]), (kernel.wy[p], a[p]));
                let facing = [kernel.facing_y(o), kernel.facing_y(p)];
                let mask = Mask {
                    facing: &facing,
                    cos_min: kernel.facing_cos,
                };
                let iy = half_overlap(scene, ho, hp, tol, &mask, &near_y[shorter(&near_y, o, p)]);
                if iy != 0.0 {
                    row.push((p, ix * iy));
                }
            }
            row
        })
        .collect();
    let mut g = DMatrix::zeros(n, n);
    for (o, row) in rows.into_iter().enumerate() {
        for (p, v) in row {
            g[(o, p)] = v;
            g[(p, o)] = v;
        }
    }
    g
}

/// The right-hand sides `b_o` per band (module docs) from the shot samples; samples without an
/// importance weight (`inv_px == 0`, drawn some other way) are skipped, and so are the cells
/// flagged in `excluded` (their `b_o` stays 0). `shots` is the number of rays shot, including
/// those that left the scene.
pub fn kernel_moments(
    kernel: &KernelCells,
    samples: &[Sample],
    shots: u64,
    reflectance: &(impl Fn(u32, DVec3) -> Bands + Sync),
    (tol, excluded): (f64, &[bool]),
) -> Vec<Bands> {
    let n = kernel.len();
    let cut = (1.0 / tol).ln();
    let lanes = CellLanes::new(kernel, excluded);
    let chunk = 1024;
    let partial: Vec<Vec<Bands>> = samples
        .par_chunks(chunk)
        .map(|part| {
            let mut b = vec![[0.0; BANDS]; n];
            let mut g = vec![0.0; n];
            for smp in part {
                if smp.inv_px == 0.0 {
                    continue;
                }
                let rho = reflectance(smp.ray.face_y, smp.ray.y);
                let mut w = [0.0; BANDS];
                let mut any = false;
                for k in 0..BANDS {
                    if smp.ray.kernel[k] > 0.0 {
                        w[k] = rho[k] * smp.s[k] * smp.inv_px;
                        any |= w[k] != 0.0;
                    }
                }
                if !any {
                    continue;
                }
                gaussians_at(&lanes, smp, cut, &mut g);
                for (acc, &g) in b.iter_mut().zip(&g) {
                    for k in 0..BANDS {
                        acc[k] += g * w[k];
                    }
                }
            }
            b
        })
        .collect();
    let mut b = vec![[0.0; BANDS]; n];
    for part in partial {
        for (acc, v) in b.iter_mut().zip(part) {
            for k in 0..BANDS {
                acc[k] += v[k];
            }
        }
    }
    let inv = 1.0 / shots.max(1) as f64;
    for v in &mut b {
        for x in v.iter_mut() {
            *x *= inv;
        }
    }
    b
}

/// Every cell's Gaussian g_o(ξ) at the sample's ray ξ = (x, y), 0 beyond `exp(−cut)`, for cells
/// left out and where the facing masks refuse the ray's normals ([`CellLanes::pair_gaussians`]).
fn gaussians_at(lanes: &CellLanes, smp: &Sample, cut: f64, out: &mut [f64]) {
    let r = &smp.ray;
    lanes.pair_gaussians((r.x, r.nx), (r.y, r.ny), cut, out);
}

/// The sample support of every kernel cell, `n_o = Σ_i g_o(ξ_i)` over the shot samples: how many
/// samples' worth of data its moment `b_o` averages. A cell with `n_o` well below 1 has a moment
/// made of at most one or two samples, and its projected weight is that noise divided by its tiny
/// Gram diagonal ([`KernelProjection::new`]).
pub fn kernel_support(kernel: &KernelCells, samples: &[Sample], tol: f64) -> Vec<f64> {
    let n = kernel.len();
    let cut = (1.0 / tol).ln();
    let lanes = CellLanes::new(kernel, &[]);
    let partial: Vec<Vec<f64>> = samples
        .par_chunks(1024)
        .map(|part| {
            let mut c = vec![0.0; n];
            let mut g = vec![0.0; n];
            for smp in part.iter().filter(|smp| smp.inv_px != 0.0) {
                gaussians_at(&lanes, smp, cut, &mut g);
                for (c, g) in c.iter_mut().zip(&g) {
                    *c += g;
                }
            }
            c
        })
        .collect();
    let mut c = vec![0.0; n];
    for part in partial {
        for (acc, v) in c.iter_mut().zip(part) {
            *acc += v;
        }
    }
    c
}

/// Reflected power per band that the samples carry: the Monte-Carlo estimate of
/// `∫∫ K(x,y)·s(x) dx dy = ∫_S B_refl`, the moments' estimator with g_o replaced by 1.
pub fn sampled_reflected_power(
    samples: &[Sample],
    shots: u64,
    reflectance: &(impl Fn(u32, DVec3) -> Bands + Sync),
) -> Bands {
    // Fixed chunks summed in order: the result does not depend on the threads (a rayon
    // `reduce` would, in the last bits).
    let partial: Vec<Bands> = samples
        .par_chunks(1024)
        .map(|part| {
            let mut w = [0.0; BANDS];
            for smp in part.iter().filter(|smp| smp.inv_px != 0.0) {
                let rho = reflectance(smp.ray.face_y, smp.ray.y);
                for k in 0..BANDS {
                    if smp.ray.kernel[k] > 0.0 {
                        w[k] += rho[k] * smp.s[k] * smp.inv_px;
                    }
                }
            }
            w
        })
        .collect();
    let mut p = [0.0; BANDS];
    for w in partial {
        for k in 0..BANDS {
            p[k] += w[k];
        }
    }
    let inv = 1.0 / shots.max(1) as f64;
    for x in &mut p {
        *x *= inv;
    }
    p
}

/// Reflected power per band that the samples carry, for a closed scene (every shot landed) whose
/// strengths are `s = E + B_refl` with a known `∫_S B_refl = generated` (the reflected power of
/// the kernel collection that bounced them): the ratio estimator
///
/// ```text
/// P̃_k = ρ̂_k·(u·E_k + generated_k),   ρ̂_k = Σ_i ρ_k(y_i) s_ik u_i / Σ_i s_ik u_i,   u_i = inv_px_i/N.
/// ```
///
/// [`sampled_reflected_power`] estimates `∫ B_refl` of the strengths by Monte Carlo, with a
/// relative error ε that the bounces amplify by 1/(1 − ρ) (a grey ρ = 0.99 furnace settled at
/// B = 44 instead of 100 with ε ≈ −1.3 %); here only the mean albedo ρ̂ is sampled (exact in a
/// furnace) and the reflected part of ∫s is the exact integral of the collection.
pub fn closed_reflected_power(
    samples: &[Sample],
    shots: u64,
    reflectance: &(impl Fn(u32, DVec3) -> Bands + Sync),
    generated: Bands,
) -> Bands {
    let partial: Vec<[Bands; 3]> = samples
        .par_chunks(1024)
        .map(|part| {
            let mut acc = [[0.0; BANDS]; 3];
            for smp in part.iter().filter(|smp| smp.inv_px != 0.0) {
                let rho = reflectance(smp.ray.face_y, smp.ray.y);
                for k in 0..BANDS {
                    if smp.ray.kernel[k] > 0.0 {
                        acc[0][k] += rho[k] * smp.s[k] * smp.inv_px;
                    }
                    acc[1][k] += smp.s[k] * smp.inv_px;
                    acc[2][k] += smp.ray.emission_x[k] * smp.inv_px;
                }
            }
            acc
        })
        .collect();
    let mut sum = [[0.0; BANDS]; 3];
    for acc in partial {
        for (t, a) in sum.iter_mut().zip(acc) {
            for k in 0..BANDS {
                t[k] += a[k];
            }
        }
    }
    let inv = 1.0 / shots.max(1) as f64;
    let mut p = [0.0; BANDS];
    for k in 0..BANDS {
        if sum[1][k] > 0.0 {
            p[k] = sum[0][k] / sum[1][k] * (sum[2][k] * inv + generated[k]);
        }
    }
    p
}

/// Reflected power per band of the kernel collection: `∫_S B_refl = Σ_o v_o·c_o·r_o` with the
/// sender integrals c_o and receiver integrals r_o ([`crate::fem::receiver_integrals`]).
pub fn kernel_reflected_power(kernel: &KernelCells, sender: &[f64], receiver: &[f64]) -> Bands {
    let mut p = [0.0; BANDS];
    for o in 0..kernel.len() {
        for k in 0..BANDS {
            p[k] += kernel.v[o][k] * sender[o] * receiver[o];
        }
    }
    p
}

/// One bounce of the projected kernel, linearized in weight space (the clamp `max(0, ·)` of
/// [`crate::solve`]'s strengths left out), per band k:
///
/// ```text
/// s = E + A v,          A_ip = c_p·g_p^y(x_i)            (N × m: the kernel collection at x_i)
/// b(s) = M_k s,         M_k,oi = g_o(ξ_i)·w_k,i          (m × N: the moments, eq. above)
/// w_k,i = ρ_k(y_i)·inv_px_i / N                         (the sampled-power weights)
/// ```
///
/// so that a fit of the bounced strengths is `G⁻¹ (M_k E + (M_k A) v)`. Holds the parts that do
/// not depend on v: `M_k A` (m × m), `M_k E`, `A^T w_k` and `w_k·E`.
pub struct BounceOperator {
    /// `(M_k A)` per band, m × m (rows: moments o, columns: weights p).
    pub ma: Vec<DMatrix<f64>>,
    /// `M_k E`: the moments of the emission alone.
    pub me: Vec<Bands>,
    /// `(A^T w_k)_p`: the sampled power of cell p's unit contribution to s.
    pub atw: Vec<Bands>,
    /// `w_k·E`: the sampled power of the emission alone.
    pub we: Bands,
    /// `(A^T u)_p` with the area weights `u_i = inv_px_i / N` ([`closed_reflected_power`]).
    pub atu: Vec<Bands>,
    /// `u·E`: the sampled emitted power.
    pub ue: Bands,
}

/// The cells `p` with a non-zero factor `g[p]`, with `f(p, g[p])`: per sample, the moments' cells
/// at ξ_i, and the collection's `A_ip = c_p·g_p^y(x_i)` (fig. 4.13c, cut where `g_p^y < tol`;
/// facing masks apply).
fn nonzero(g: &[f64], f: impl Fn(usize, f64) -> f64) -> Vec<(u32, f64)> {
    g.iter()
        .enumerate()
        .filter(|&(_, &g)| g != 0.0)
        .map(|(p, &g)| (p as u32, f(p, g)))
        .filter(|&(_, v)| v != 0.0)
        .collect()
}

/// The sampled-power weights `w_k,i·N = ρ_k(y_i)·inv_px_i` of a sample (0 in bands without
/// kernel, as in [`kernel_moments`]).
fn power_weights(smp: &Sample, rho: Bands) -> Bands {
    let mut w = [0.0; BANDS];
    for k in 0..BANDS {
        if smp.ray.kernel[k] > 0.0 {
            w[k] = rho[k] * smp.inv_px;
        }
    }
    w
}

/// Assembles the [`BounceOperator`] of the frozen `kernel` with sender integrals `sender` on the
/// shot samples. Cost O(N·m) to find the cells at each sample, then O(N·k_o·k_p) for `M A`
/// (k_o cells at ξ_i, k_p at x_i). Rows are summed over the samples in index order: the result
/// does not depend on the threads.
pub fn bounce_operator(
    kernel: &KernelCells,
    sender: &[f64],
    samples: &[Sample],
    shots: u64,
    reflectance: &(impl Fn(u32, DVec3) -> Bands + Sync),
    (tol, excluded): (f64, &[bool]),
) -> BounceOperator {
    let m = kernel.len();
    let cut = (1.0 / tol).ln();
    let lanes = CellLanes::new(kernel, excluded);
    let inv = 1.0 / shots.max(1) as f64;
    // ⟨Per sample: its power weights, the cells at ξ_i (moments), the cells at x_i (collection)⟩
    let shot: Vec<usize> = (0..samples.len())
        .filter(|&i| samples[i].inv_px != 0.0)
        .collect();
    type AtSample = (Bands, Vec<(u32, f64)>, Vec<(u32, f64)>);
    let per: Vec<AtSample> = shot
        .par_iter()
        .map(|&i| {
            let smp = &samples[i];
            let w = power_weights(smp, reflectance(smp.ray.face_y, smp.ray.y));
            let mut g = vec![0.0; m];
            gaussians_at(&lanes, smp, cut, &mut g);
            let at = nonzero(&g, |_, g| g);
            lanes.receiver_gaussians((smp.ray.x, smp.ray.nx), cut, &mut g);
            (w, at, nonzero(&g, |p, g| sender[p] * g))
        })
        .collect();
    // ⟨Invert the moments' lists: per cell o, the samples in its support⟩
    let mut by_cell: Vec<Vec<(u32, f64)>> = vec![Vec::new(); m];
    for (j, (_, at, _)) in per.iter().enumerate() {
        for &(o, g) in at {
            by_cell[o as usize].push((j as u32, g));
        }
    }
    // ⟨Rows of M A, M E; A^T w; w·E⟩
    let rows: Vec<(Vec<Bands>, Bands)> = by_cell
        .par_iter()
        .map(|list| {
            let mut row = vec![[0.0; BANDS]; m];
            let mut me = [0.0; BANDS];
            for &(j, g) in list {
                let (w, _, coll) = &per[j as usize];
                let e = &samples[shot[j as usize]].ray.emission_x;
                for k in 0..BANDS {
                    me[k] += g * w[k] * e[k] * inv;
                }
                for &(p, ap) in coll {
                    for k in 0..BANDS {
                        row[p as usize][k] += g * w[k] * ap * inv;
                    }
                }
            }
            (row, me)
        })
        .collect();
    let (mut atw, mut atu) = (vec![[0.0; BANDS]; m], vec![[0.0; BANDS]; m]);
    let (mut we, mut ue) = ([0.0; BANDS], [0.0; BANDS]);
    for (j, (w, _, coll)) in per.iter().enumerate() {
        let smp = &samples[shot[j]];
        let (e, u) = (&smp.ray.emission_x, smp.inv_px * inv);
        for k in 0..BANDS {
            we[k] += w[k] * e[k] * inv;
            ue[k] += u * e[k];
        }
        for &(p, ap) in coll {
            for k in 0..BANDS {
                atw[p as usize][k] += w[k] * ap * inv;
                atu[p as usize][k] += u * ap;
            }
        }
    }
    let ma = (0..BANDS)
        .map(|k| DMatrix::from_fn(m, m, |o, p| rows[o].0[p][k]))
        .collect();
    let me = rows.iter().map(|r| r.1).collect();
    BounceOperator {
        ma,
        me,
        atw,
        we,
        atu,
        ue,
    }
}

/// The factored Gram matrix of a frozen kernel network: the expensive half of a projection,
/// computed once per network state and reused for every bounce (the moments change with s, the
/// Gram matrix does not).
pub struct KernelProjection {
    ortho: integrals::Orthonormal,
    excluded: Vec<bool>,
    tol: f64,
    #[cfg_attr(not(feature = "stages"), allow(dead_code))] // read through `gcr::stages`
    report: ProjectionReport,
}

impl KernelProjection {
    /// Builds and factors the Gram matrix of `kernel` on `scene` (support cut-off `tol`, relative
    /// pivot `rejection`).
    #[cfg_attr(not(feature = "stages"), allow(dead_code))] // read through `gcr::stages`
    pub fn new(kernel: &KernelCells, scene: &SceneSurface, tol: f64, rejection: f64) -> Self {
        Self::excluding(kernel, scene, tol, rejection, &[])
    }

    /// [`KernelProjection::new`] with the cells flagged in `excluded` (indexed like the cells;
    /// missing entries count as `false`) left out of the projection: their weights are 0 and
    /// they count as rejected.
    #[cfg_attr(not(feature = "stages"), allow(dead_code))] // read through `gcr::stages`
    pub fn excluding(
        kernel: &KernelCells,
        scene: &SceneSurface,
        tol: f64,
        rejection: f64,
        excluded: &[bool],
    ) -> Self {
        let gram = kernel_gram_excluding(kernel, scene, tol, excluded);
        Self::from_gram(&gram, tol, rejection, excluded)
    }

    /// Factors a Gram matrix computed by `kernel_gram_excluding` with the same `tol` and
    /// `excluded`: a projection redone at another `rejection` need not recompute it.
    pub fn from_gram(gram: &DMatrix<f64>, tol: f64, rejection: f64, excluded: &[bool]) -> Self {
        let ortho = integrals::Orthonormal::new(gram, rejection);
        let report = ProjectionReport {
            rejected: ortho.rejected(),
            gram_entries: gram.iter().filter(|v| **v != 0.0).count(),
        };
        Self {
            ortho,
            excluded: excluded.to_vec(),
            tol,
            report,
        }
    }

    /// `G⁻¹ u` over the kept cells (the weights of moments `u`; rejected cells get 0).
    pub fn solve(&self, u: &[f64]) -> Vec<f64> {
        self.ortho.solve(u)
    }

    /// Rejections and Gram size.
    #[cfg_attr(not(feature = "stages"), allow(dead_code))] // read through `gcr::stages`
    pub fn report(&self) -> ProjectionReport {
        self.report
    }

    /// Replaces the output weights of `kernel` (the network the projection was built for) by the
    /// projection of `K·s` with the samples' current strengths s.
    pub fn fit(
        &self,
        kernel: &mut KernelCells,
        samples: &[Sample],
        shots: u64,
        reflectance: &(impl Fn(u32, DVec3) -> Bands + Sync),
    ) {
        let b = kernel_moments(
            kernel,
            samples,
            shots,
            reflectance,
            (self.tol, &self.excluded),
        );
        for k in 0..BANDS {
            let rhs: Vec<f64> = b.iter().map(|v| v[k]).collect();
            let v = self.ortho.solve(&rhs);
            for (o, x) in v.into_iter().enumerate() {
                kernel.v[o][k] = x;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::domain::Domain;
    use crate::element::Element;
    use glam::DVec3;
    use scene_sampler::{KernelSampler, SceneBvh, builtin};

    /// Shot samples on cornell-box with s = E, as the solver draws them.
    fn shot_samples(domain: &Domain, count: usize) -> Vec<Sample> {
        use rand::SeedableRng;
        let density = crate::shooting::SenderDensity::new(domain);
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
        (0..count)
            .filter_map(|_| density.shoot(domain, &mut rng))
            .map(|shot| Sample {
                s: shot.ray.emission_x,
                ray: shot.ray,
                inv_px: shot.inv_px,
            })
            .collect()
    }

    /// The built-in Cornell box.
    fn cornell() -> scene_sampler::Scene {
        builtin("cornell-box").unwrap().into_3d().unwrap()
    }

    /// Kernel cells with the given halves `(w_x, w_y, width)` and zero weights.
    fn cells(halves: impl IntoIterator<Item = (DVec3, DVec3, f64)>) -> KernelCells {
        let mut kernel = KernelCells::default();
        for (wx, wy, d) in halves {
            kernel.wx.push(wx);
            kernel.wy.push(wy);
            kernel.width.push(d);
            kernel.v.push([0.0; BANDS]);
        }
        kernel
    }

    /// A wide cell, a tiny one on one sample and one away from every sample: their supports
    /// against the plain sum of the Gaussian over every sample (no cut-off).
    #[test]
    fn kernel_support_counts_the_samples_in_each_cell() {
        let scene = cornell();
        let bvh = SceneBvh::new(&scene);
        let domain = Domain::ThreeD(KernelSampler::new(&scene, &bvh));
        let samples = shot_samples(&domain, 4000);
        let on = samples[17].ray;
        let kernel = cells([
            (samples[3].ray.x, samples[3].ray.y, 0.2),
            (on.x, on.y, 0.003),
            (DVec3::splat(5.0), DVec3::splat(-5.0), 0.1),
        ]);
        let tol = 1e-6;
        let support = kernel_support(&kernel, &samples, tol);
        for o in 0..kernel.len() {
            let plain: f64 = samples
                .iter()
                .map(|s| {
                    let e = (kernel.wx[o].distance_squared(s.ray.x)
                        + kernel.wy[o].distance_squared(s.ray.y))
                        / (kernel.width[o] * kernel.width[o]);
                    (-e).exp()
                })
                .sum();
            assert!(
                (support[o] - plain).abs() <= tol * samples.len() as f64,
                "cell {o}: {} vs {plain}",
                support[o]
            );
        }
        assert!(
            support[0] > 20.0,
            "the wide cell holds many samples: {}",
            support[0]
        );
        assert!(
            (1.0..2.0).contains(&support[1]),
            "the tiny cell holds its own sample and little else: {}",
            support[1]
        );
        assert_eq!(support[2], 0.0);
    }

    /// Excluded cells get weight 0 and count as rejected; the others are fitted.
    #[test]
    fn excluded_cells_get_no_weight() {
        let scene = cornell();
        let bvh = SceneBvh::new(&scene);
        let domain = Domain::ThreeD(KernelSampler::new(&scene, &bvh));
        let surface = SceneSurface::of(&domain);
        let samples = shot_samples(&domain, 4000);
        let mut kernel = cells([3, 40, 90].map(|i| (samples[i].ray.x, samples[i].ray.y, 0.2)));
        let reflectance = |f, y| domain.reflectance_at(f, y);
        let shots = samples.len() as u64;
        let all = KernelProjection::new(&kernel, &surface, 1e-6, 1e-6);
        all.fit(&mut kernel, &samples, shots, &reflectance);
        assert_eq!(all.report().rejected, 0);
        assert!(kernel.v.iter().all(|v| v[0] != 0.0), "{:?}", kernel.v);
        let some = KernelProjection::excluding(&kernel, &surface, 1e-6, 1e-6, &[false, true]);
        some.fit(&mut kernel, &samples, shots, &reflectance);
        assert_eq!(some.report().rejected, 1);
        assert_eq!(kernel.v[1], [0.0; BANDS]);
        assert!(kernel.v[0][0] != 0.0 && kernel.v[2][0] != 0.0);
    }

    /// Every Gram entry against an independent evaluation: both 3-D halves by adaptive cubature
    /// over every triangle of the scene as loaded (no support cut-off, no product rule, no merged
    /// quadrilaterals).
    #[test]
    fn gram_entries_match_cubature_of_both_halves() {
        let scene = cornell();
        let bvh = SceneBvh::new(&scene);
        let domain = Domain::ThreeD(KernelSampler::new(&scene, &bvh));
        let surface = SceneSurface::of(&domain);
        assert!(
            domain
                .elements()
                .iter()
                .any(|e| matches!(e, Element::Quad(_))),
            "the scene's rectangles are integrated as quadrilaterals"
        );
        let diag = domain.diagonal();
        let triangles: Vec<[DVec3; 3]> = scene.faces.iter().map(|f| f.v).collect();
        // Cells near the surfaces: centres on face centroids, widths from narrow to wide.
        let centroid = |i: usize| triangles[i].iter().sum::<DVec3>() / 3.0;
        let mut kernel = cells(
            [(0, 5), (1, 5), (3, 8), (12, 20), (30, 2)]
                .into_iter()
                .enumerate()
                .map(|(k, (i, j))| {
                    let d = diag * [0.05, 0.1, 0.2, 0.3, 0.15][k];
                    (centroid(i) + DVec3::splat(0.01 * k as f64), centroid(j), d)
                }),
        );
        // Unmasked, then with facing masks from the faces the halves sit on (a Gaussian
        // restricted to the faces that face like it: the cubature skips the others).
        for masked in [false, true] {
            if masked {
                kernel.facing_cos = 50f64.to_radians().cos();
                for (i, j) in [(0, 5), (1, 5), (3, 8), (12, 20), (30, 2)] {
                    kernel.nx.push(scene.faces[i].normal);
                    kernel.ny.push(scene.faces[j].normal);
                }
            }
            let g = kernel_gram(&kernel, &surface, 1e-14);
            let half = |w1: DVec3, f1: DVec3, d1: f64, w2: DVec3, f2: DVec3, d2: f64| -> f64 {
                triangles
                    .iter()
                    .zip(&scene.faces)
                    .filter(|(_, face)| {
                        kernel.lives_on(f1, face.normal) && kernel.lives_on(f2, face.normal)
                    })
                    .map(|(&[p, q, r], _)| {
                        let f = |x: [f64; 3]| {
                            let x = DVec3::from_array(x);
                            (-(x.distance_squared(w1) / (d1 * d1)
                                + x.distance_squared(w2) / (d2 * d2)))
                                .exp()
                        };
                        integrals::cubature::triangle_cubature(
                            f,
                            [p.to_array(), q.to_array(), r.to_array()],
                            1e-13,
                        )
                        .value
                    })
                    .sum()
            };
            let mut zeros = 0;
            for o in 0..kernel.len() {
                for p in 0..kernel.len() {
                    let (d1, d2) = (kernel.width[o], kernel.width[p]);
                    let (fx, gx) = (kernel.facing_x(o), kernel.facing_x(p));
                    let (fy, gy) = (kernel.facing_y(o), kernel.facing_y(p));
                    let reference = half(kernel.wx[o], fx, d1, kernel.wx[p], gx, d2)
                        * half(kernel.wy[o], fy, d1, kernel.wy[p], gy, d2);
                    zeros += usize::from(reference == 0.0);
                    let scale = (g[(o, o)] * g[(p, p)]).sqrt();
                    assert!(
                        (g[(o, p)] - reference).abs() <= 1e-9 * scale,
                        "masked {masked}: G[{o},{p}] = {} vs cubature {reference}",
                        g[(o, p)]
                    );
                }
            }
            if masked {
                assert!(
                    zeros > 0,
                    "some pairs face apart: their masks share no face"
                );
            }
            // Symmetric positive definite for these well-separated cells.
            let ortho = integrals::Orthonormal::new(&g, 1e-10);
            assert_eq!(ortho.rejected(), 0);
        }
    }
}

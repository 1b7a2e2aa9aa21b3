//! The lightmap denoiser (beyond the dissertation): each texel a local polynomial fit of its
//! neighbours on the same surface, edges kept by an independent guide bake, the fit chosen region
//! by region by Stein's unbiased risk estimate (SURE), and the denoised lightmap's error
//! estimated the same way — its blur included.
//!
//! Lightmaps are smooth almost everywhere: indirect light varies over metres, a texel is a few
//! centimetres. Averaging `m` neighbours divides the noise's variance by up to `m` and adds a
//! bias where the light is not smooth (a shadow's edge, a curve). What pays is a question of the
//! data, answered by SURE (Stein 1981; for rendering, Li, Wu and Chuang 2012, "SURE-based
//! optimization for adaptive sampling and reconstruction").
//!
//! **The filters.** Candidate `k` is a weighted least-squares fit (linear, or quadratic at the
//! widest scales: [`FITS`]) in the texel's surface coordinates, evaluated at the texel, with
//! texel j's weight
//!
//! ```text
//! w_ij = exp(−|p_i − p_j|² / 2(σ_k h)²) · exp(−(g_i − g_j)² / 2τ_k²(v_i + v_j))
//! ```
//!
//! over the texels of the same page on the same surface (normals within [`SAME_NORMAL`], off the
//! texel's plane by less than a texel h, as near in the scene as on the page, so charts that
//! touch on the page but not in the scene do not mix), g the **guide**: a second, cheap bake with
//! rays of its own (independent of the values) at one texel in four ([`guides`]), each texel's g
//! the mean of those around it and v that mean's variance. A shadow's edge is an edge of the
//! guide, so the values are not averaged across it, and the weights do not depend on the values:
//! each candidate is a linear filter of them, F = W y (W the fit's hat matrix).
//!
//! **SURE with shared paths.** A texel's value y_i is the mean of two independent replicates
//! A_i, B_i; their signed half-difference s_i = (A_i − B_i)/2 ([`Gathered::spread`]) has
//! E[s_i s_j] = Cov(y_i, y_j) for every pair, even where neighbours share paths and so their
//! noise. For a linear filter with normalized weights w_ij,
//!
//! ```text
//! E[(F_i − μ_i)²] = E[(F_i − y_i)²] − Var(y_i) + 2 Σ_j w_ij Cov(y_i, y_j)
//! SURE_i = (F_i − y_i)² − s_i² + 2 s_i (W s)_i
//! ```
//!
//! without bias and without assuming Gaussian noise (expand F_i − μ_i = (F_i − y_i) + (y_i − μ_i);
//! F is linear in y; W need not be positive, so a fit's hat matrix serves as well as a mean's).
//! The texel alone (the identity) has SURE s_i², the raw value's variance.
//!
//! **The choice.** Per region of [`REGION`]² texels of a page, the candidate whose SURE summed
//! over the region and the regions around it is least, over one texel in eight ([`chooses`]). A
//! single texel's SURE is far too noisy to choose on (choosing per texel, even on SURE
//! averaged over a neighbourhood, made the estimate 3–8× optimistic in the tests: the choice
//! follows the noise); a sum over thousands is not. The estimated error of the result is
//! `√(Σ_i SURE_i / Σ_i y_i²)` over the reflecting texels the choice did not look at (seven in
//! eight; their noise is not what chose) — the relative L2 error the raw gather reports
//! ([`crate::estimator::relative_std_error`]), now with the blur in it. A denoised bake's rounds
//! stop on it ([`denoised_error`], from another texel in eight).
//!
//! **Radiosity.** B = E + ρ·L: the noise is in L alone, and a textured ρ is sharp where L is
//! smooth, so B's texels are filtered as L = (B − E)/ρ (demodulated, as image denoisers divide
//! by the albedo) and their SURE weighed by ρ² back in B's units; a band with ρ = 0 is left as
//! it is.

use super::atlas::Atlas;
use super::texels::Texel;
use crate::element::{BANDS, Bands};
use crate::gather::Gathered;
use glam::DVec3;
use rayon::prelude::*;

/// The candidates' spatial σ, in texels.
const SIGMAS: [f64; 4] = [2.0, 4.0, 8.0, 16.0];

/// The candidates' range τ, in standard deviations of the guide's difference (∞: geometry alone;
/// `Grid::candidates` computes the weights of these three).
const TAUS: [f64; 3] = [1.0, 3.0, f64::INFINITY];

/// The fits after the texel alone, as (σ, τ, terms) indices into [`SIGMAS`], [`TAUS`] and the
/// terms of the fit (3: linear; [`TERMS`]: quadratic, for the wide σ only, over which light
/// curves: a wide linear fit of concave light — bright in a wall's middle — comes out low).
const FITS: [(usize, usize, usize); 18] = [
    (0, 0, 3),
    (0, 1, 3),
    (0, 2, 3),
    (1, 0, 3),
    (1, 1, 3),
    (1, 2, 3),
    (2, 0, 3),
    (2, 1, 3),
    (2, 2, 3),
    (3, 0, 3),
    (3, 1, 3),
    (3, 2, 3),
    (2, 0, TERMS),
    (2, 1, TERMS),
    (2, 2, TERMS),
    (3, 0, TERMS),
    (3, 1, TERMS),
    (3, 2, TERMS),
];

/// Candidates: the texel alone (0), then [`FITS`].
const CANDIDATES: usize = 1 + FITS.len();

/// The side of a region that chooses one candidate, in texels.
const REGION: usize = 32;

/// Neighbours are on the same surface when their normals' cosine is at least this (18°).
const SAME_NORMAL: f64 = 0.95;

/// A fit needs every Cholesky pivot of its moments above this share of its diagonal element
/// (else its neighbours do not determine it: a strip of texels, a chart's corner).
const PIVOT: f64 = 1e-3;

/// What denoising did.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct DenoiseReport {
    /// The estimated relative error of the denoised values (module docs; None when the gather
    /// measured no standard error).
    pub error: Option<f64>,
    /// The raw values' estimated relative error (their standard errors, as the gather reports).
    pub raw_error: Option<f64>,
    /// The share of the reflecting texels whose region chose the texel alone (no averaging).
    pub unfiltered: f64,
    /// The texels' mean spatial σ of the chosen filters, in texels (0 for the texel alone).
    pub mean_sigma: f64,
    /// Seconds the filters took.
    pub seconds: f64,
}

/// The spatial σ (texels) of candidate `k` (`k` ≥ 1).
fn candidate_sigma(k: usize) -> f64 {
    SIGMAS[FITS[k - 1].0]
}

/// A texel's data for filtering: its point and normal, its demodulated value L and spread, the
/// weight ρ² of its bands back in the output's units (0: a band that does not reflect, left as it
/// is), and the guide's demodulated luminance and that one's variance.
#[derive(Clone, Copy)]
struct Sample {
    point: DVec3,
    normal: DVec3,
    value: Bands,
    spread: Bands,
    weight: Bands,
    guide: f64,
    guide_var: f64,
    has_guide: bool,
}

impl Sample {
    fn measured(&self) -> bool {
        self.weight.iter().any(|w| *w > 0.0)
    }

    /// Whether the guide found no light at all around the texel (a closed room's texels).
    fn dark(&self) -> bool {
        self.guide == 0.0 && self.guide_var.is_finite()
    }

    /// Whether `other` has the same bands filtered (a neighbour must: its L is unknown where ρ = 0).
    fn same_bands(&self, other: &Sample) -> bool {
        (0..BANDS).all(|k| (self.weight[k] > 0.0) == (other.weight[k] > 0.0))
    }
}

/// Denoises the `gathered` values of `texels` (in order) on `atlas` with the independent bake
/// `guide` of the same texels; `material` gives each texel's (ρ, E) for radiosity (B = E + ρ·L),
/// or `None` for irradiance (filtered as it is). Texels that do not reflect keep their values
/// and are no one's neighbours; texels around which the guide found no light at all (a closed
/// room) mix only with each other.
pub fn denoise(
    atlas: &Atlas,
    texels: &[Texel],
    (gathered, guide): (&[Gathered], &[Gathered]),
    material: Option<&[(Bands, Bands)]>,
) -> (Vec<Gathered>, DenoiseReport) {
    let started = std::time::Instant::now();
    let (grid, samples) = prepare(atlas, texels, (gathered, guide), material);
    // ⟨Per region the candidate of least summed SURE, over every second texel of every
    // second row (a region's sum over 256 of them is as good to choose by)⟩
    let (choice, _) = grid.choose(texels, &samples);
    // ⟨The chosen candidate at every texel: its value and SURE; the error over the measured⟩
    let chosen: Vec<(Bands, f64)> = (0..texels.len())
        .into_par_iter()
        .map(|i| grid.candidates(&samples, texels, i, Some(choice[i]))[choice[i]])
        .collect();
    let mut report = DenoiseReport {
        raw_error: crate::estimator::relative_std_error(gathered),
        ..DenoiseReport::default()
    };
    let (mut sure_sum, mut square, mut count) = (0.0, 0.0, 0.0);
    let mut out = gathered.to_vec();
    for (i, o) in out.iter_mut().enumerate() {
        if !samples[i].measured() {
            continue;
        }
        let (f, s) = chosen[i];
        if !chooses(&texels[i]) {
            sure_sum += s;
            square += gathered[i].radiosity.iter().map(|b| b * b).sum::<f64>();
        }
        count += 1.0;
        match choice[i] {
            0 => report.unfiltered += 1.0,
            k => report.mean_sigma += candidate_sigma(k),
        }
        let (rho, e) = material.map_or(([1.0; BANDS], [0.0; BANDS]), |m| m[i]);
        // (light is never negative: a fit's value below 0 is raised to 0, which only brings it
        // nearer the truth, so SURE still bounds the error)
        for b in 0..BANDS {
            if samples[i].weight[b] > 0.0 {
                o.radiosity[b] = e[b] + rho[b] * f[b].max(0.0);
            }
        }
    }
    if count > 0.0 {
        report.unfiltered /= count;
        report.mean_sigma /= count;
    }
    report.error = (square > 0.0).then(|| (sure_sum.max(0.0) / square).sqrt());
    report.seconds = started.elapsed().as_secs_f64();
    (out, report)
}

/// The estimated relative error that [`denoise`] would report, from one texel in eight ([`checks`]:
/// not those the choice looks at, so the estimate is not the optimistic one of choosing and
/// judging on the same texels): what rounds to a target error stop on when the bake is
/// denoised.
pub(crate) fn denoised_error(
    atlas: &Atlas,
    texels: &[Texel],
    (gathered, guide): (&[Gathered], &[Gathered]),
    material: Option<&[(Bands, Bands)]>,
) -> Option<f64> {
    let (grid, samples) = prepare(atlas, texels, (gathered, guide), material);
    let (choice, _) = grid.choose(texels, &samples);
    let others: Vec<usize> = (0..texels.len())
        .filter(|&i| checks(&texels[i]) && samples[i].measured())
        .collect();
    let sure_sum: f64 = (others.par_iter())
        .map(|&i| grid.candidates(&samples, texels, i, Some(choice[i]))[choice[i]].1)
        .sum();
    let square: f64 = (others.iter())
        .map(|&i| gathered[i].radiosity.iter().map(|b| b * b).sum::<f64>())
        .sum();
    (square > 0.0).then(|| (sure_sum.max(0.0) / square).sqrt())
}

/// The texels' grid and their samples, the guide smoothed over each texel's neighbourhood.
fn prepare(
    atlas: &Atlas,
    texels: &[Texel],
    (gathered, guide): (&[Gathered], &[Gathered]),
    material: Option<&[(Bands, Bands)]>,
) -> (Grid, Vec<Sample>) {
    let grid = Grid::new(atlas, texels, 1.0 / atlas.texels_per_unit);
    let raw: Vec<Sample> = (0..texels.len())
        .map(|i| {
            sample(
                &texels[i],
                (&gathered[i], &guide[i]),
                material.map(|m| m[i]),
            )
        })
        .collect();
    let samples = (0..texels.len())
        .into_par_iter()
        .map(|i| grid.smooth_guide(&raw, texels, i))
        .collect();
    (grid, samples)
}

/// Whether texel `t` carries the guide: the guide bake (`super::gather_guide`) estimates every
/// second texel of every second row alone, a quarter of the texels (each texel's guide is a
/// mean over the guide's texels around it anyway, [`Grid::smooth_guide`]).
pub(super) fn guides(t: &Texel) -> bool {
    t.x % 2 == 0 && t.y % 2 == 0
}

/// Whether the choice of candidates looks at texel `t`: every second texel of every fourth row,
/// one in eight (the error is estimated over the others, whose noise the choice does not
/// follow; one in four chose no better, one in 16 worse: Cornell box 1.72 / 1.67 / 1.88 %).
fn chooses(t: &Texel) -> bool {
    t.x % 2 == 0 && t.y % 4 == 0
}

/// Whether the rounds' stopping test looks at texel `t` ([`denoised_error`]): as many texels as
/// [`chooses`], between them.
fn checks(t: &Texel) -> bool {
    t.x % 2 == 1 && t.y % 4 == 2
}

/// A texel's [`Sample`]: L = (y − E)/ρ and s/ρ per band with ρ > 0, weight ρ² (ρ = 1 for
/// irradiance); the guide's L and its spread² as the mean over those bands. A texel that does
/// not reflect has weight 0 in every band.
fn sample(
    t: &Texel,
    (g, guide): (&Gathered, &Gathered),
    material: Option<(Bands, Bands)>,
) -> Sample {
    let (rho, e) = material.unwrap_or(([1.0; BANDS], [0.0; BANDS]));
    let mut s = Sample {
        point: t.point,
        normal: t.normal,
        value: [0.0; BANDS],
        spread: [0.0; BANDS],
        weight: [0.0; BANDS],
        guide: 0.0,
        guide_var: 0.0,
        has_guide: guides(t),
    };
    let (mut bands, mut guide_spread) = (0.0, 0.0);
    for k in 0..BANDS {
        // every reflecting texel, also one whose replicates agree (both 0 where light is rare):
        // leaving those out made the neighbours a choice by the values, and SURE 2.6× low
        if rho[k] > 0.0 {
            s.value[k] = (g.radiosity[k] - e[k]) / rho[k];
            s.spread[k] = g.spread[k] / rho[k];
            s.weight[k] = rho[k] * rho[k];
            s.guide += (guide.radiosity[k] - e[k]) / rho[k];
            guide_spread += guide.spread[k] / rho[k];
            bands += 1.0;
        }
    }
    if bands > 0.0 {
        s.guide /= bands;
        s.guide_var = (guide_spread / bands).powi(2);
    }
    s
}

/// SURE of one candidate at texel `t` (module docs), summed over the bands in the output's
/// units: its value `f` and the filtered spreads `ws`.
fn sure(t: &Sample, f: &Bands, ws: &Bands) -> f64 {
    (0..BANDS)
        .map(|k| {
            let s = t.spread[k];
            t.weight[k] * ((f[k] - t.value[k]).powi(2) - s * s + 2.0 * s * ws[k])
        })
        .sum()
}

/// Terms of a fit of degree 2 around a texel: 1, u, v, u², uv, v² (u, v a neighbour's offset
/// along the texel's surface, in units of the candidate's σ); a fit of degree 1 takes the first
/// three.
const TERMS: usize = 6;

/// The weighted sums of a local polynomial fit around a texel: Σ w φ_a φ_b over the neighbours
/// (upper triangle, row by row) and per band of the values and spreads times φ_a.
#[derive(Clone, Copy)]
struct Moments {
    m: [f64; TERMS * (TERMS + 1) / 2],
    y: [[f64; TERMS]; BANDS],
    s: [[f64; TERMS]; BANDS],
}

impl Default for Moments {
    fn default() -> Self {
        Self {
            m: [0.0; TERMS * (TERMS + 1) / 2],
            y: [[0.0; TERMS]; BANDS],
            s: [[0.0; TERMS]; BANDS],
        }
    }
}

/// Where Σ w φ_a φ_b (a ≤ b) is kept in [`Moments::m`].
fn pair(a: usize, b: usize) -> usize {
    a * TERMS - a * (a + 1) / 2 + b
}

impl Moments {
    /// Adds neighbour `n` with weight `w` at offset (u, v) (in σ) to a fit of `terms` terms.
    fn add(&mut self, w: f64, (u, v): (f64, f64), n: &Sample, terms: usize) {
        let phi = [1.0, u, v, u * u, u * v, v * v];
        for a in 0..terms {
            let wa = w * phi[a];
            for b in a..terms {
                self.m[pair(a, b)] += wa * phi[b];
            }
            for k in 0..BANDS {
                self.y[k][a] += wa * n.value[k];
                self.s[k][a] += wa * n.spread[k];
            }
        }
    }

    /// The fit's value at the texel (a local polynomial regression of `terms` terms; fewer —
    /// linear, then the weighted mean — where the neighbours cannot hold it: a strip of texels,
    /// a chart's corner) and the same weights applied to the spreads. The hat matrix's row is
    /// w_j·Σ_a g_a φ_a(j), g the first column of the moments' inverse.
    fn solve(&self, terms: usize) -> (Bands, Bands) {
        let g = [terms, 3, 1]
            .into_iter()
            .filter(|&t| t <= terms)
            .find_map(|t| self.first_column(t))
            .unwrap_or([0.0; TERMS]);
        let apply = |m: &[[f64; TERMS]; BANDS]| -> Bands {
            std::array::from_fn(|k| (0..TERMS).map(|a| g[a] * m[k][a]).sum())
        };
        (apply(&self.y), apply(&self.s))
    }

    /// The first column of the inverse of the `t × t` moments (Cholesky), None when a pivot
    /// falls below [`PIVOT`] of its diagonal (the neighbours do not determine the fit).
    fn first_column(&self, t: usize) -> Option<[f64; TERMS]> {
        let mut l = [[0.0; TERMS]; TERMS];
        for i in 0..t {
            for j in 0..=i {
                let mut sum = self.m[pair(j, i)];
                for k in 0..j {
                    sum -= l[i][k] * l[j][k];
                }
                if i == j {
                    if sum.is_nan() || sum <= PIVOT * self.m[pair(i, i)] {
                        return None;
                    }
                    l[i][i] = sum.sqrt();
                } else {
                    l[i][j] = sum / l[j][j];
                }
            }
        }
        // L Lᵀ g = e₁: forward, then back
        let mut z = [0.0; TERMS];
        for i in 0..t {
            let mut sum = if i == 0 { 1.0 } else { 0.0 };
            for k in 0..i {
                sum -= l[i][k] * z[k];
            }
            z[i] = sum / l[i][i];
        }
        let mut g = [0.0; TERMS];
        for i in (0..t).rev() {
            let mut sum = z[i];
            for k in i + 1..t {
                sum -= l[k][i] * g[k];
            }
            g[i] = sum / l[i][i];
        }
        Some(g)
    }
}

/// The texels a choice looked at, with their candidates' SURE.
type Picked = Vec<(usize, [f64; CANDIDATES])>;

/// The texels' places on the pages (texel index per page, row and column), and the texel's size
/// in the scene.
struct Grid {
    width: usize,
    height: usize,
    index: Vec<u32>,
    h: f64,
}

impl Grid {
    fn new(atlas: &Atlas, texels: &[Texel], h: f64) -> Self {
        let (width, height) = (atlas.width as usize, atlas.height as usize);
        let mut index = vec![u32::MAX; width * height * atlas.pages as usize];
        for (i, t) in texels.iter().enumerate() {
            index[(t.page as usize * height + t.y as usize) * width + t.x as usize] = i as u32;
        }
        Self {
            width,
            height,
            index,
            h,
        }
    }

    /// Calls `visit(j, w_ij, (u, v))` for the measured neighbours j of texel `i` on its surface
    /// with the same bands (itself included, weight 1, offset 0): their spatial weight under the
    /// Gaussian of `sigma` texels and their offset along the surface in texels. Wide Gaussians
    /// visit every `σ/2`-th texel of every `σ/2`-th row: the same filter, a fraction of the cost,
    /// and about as many independent values (neighbours that share paths share noise).
    fn neighbours(
        &self,
        samples: &[Sample],
        texels: &[Texel],
        i: usize,
        sigma: f64,
        mut visit: impl FnMut(usize, f64, (f64, f64)),
    ) {
        let (t, c) = (&texels[i], &samples[i]);
        visit(i, 1.0, (0.0, 0.0));
        let (tu, tv) = scene_sampler::orthonormal_basis(c.normal);
        let reach = (2.0 * sigma).ceil() as i64;
        let step = ((sigma / 2.0).floor() as usize).max(1);
        // the weight by the offset on the page (a chart keeps the density: the same distance in
        // the scene), one exponential per row and column
        let weight = |d: i64| (-0.5 * (d as f64 / sigma).powi(2)).exp();
        let across: Vec<f64> = (-reach..=reach).step_by(step).map(weight).collect();
        let page = t.page as usize * self.height;
        for (wy, dy) in (-reach..=reach).step_by(step).enumerate() {
            let y = t.y as i64 + dy;
            if y < 0 || y >= self.height as i64 {
                continue;
            }
            for (wx, dx) in (-reach..=reach).step_by(step).enumerate() {
                let x = t.x as i64 + dx;
                if x < 0 || x >= self.width as i64 || (dx == 0 && dy == 0) {
                    continue;
                }
                let j = self.index[(page + y as usize) * self.width + x as usize];
                if j == u32::MAX {
                    continue;
                }
                let s = &samples[j as usize];
                if !s.measured() || !c.same_bands(s) || s.normal.dot(c.normal) < SAME_NORMAL {
                    continue;
                }
                // off the texel's plane, or farther in the scene than on the page (another chart)
                let d = s.point - c.point;
                let page_distance = ((dx * dx + dy * dy) as f64).sqrt() + 1.0;
                if c.normal.dot(d).abs() > self.h
                    || d.length_squared() > (page_distance * self.h).powi(2)
                {
                    continue;
                }
                let offset = (d.dot(tu) / self.h, d.dot(tv) / self.h);
                visit(j as usize, across[wy] * across[wx], offset);
            }
        }
    }

    /// Texel `i`'s sample with its guide the mean over the guide's texels around it ([`guides`];
    /// a Gaussian of σ = 1.5 texels) and that mean's variance (the guide's texels independent:
    /// Σw²v/(Σw)²); with none around it (a chart of a few texels), no guide: an infinite variance
    /// (the range weights do not distinguish).
    fn smooth_guide(&self, raw: &[Sample], texels: &[Texel], i: usize) -> Sample {
        let (mut sum, mut var, mut total) = (0.0, 0.0, 0.0);
        self.neighbours(raw, texels, i, 1.5, |j, w, _| {
            if raw[j].has_guide {
                sum += w * raw[j].guide;
                var += w * w * raw[j].guide_var;
                total += w;
            }
        });
        let (guide, guide_var) = if total > 0.0 {
            (sum / total, var / (total * total))
        } else {
            (0.0, f64::INFINITY)
        };
        Sample {
            guide,
            guide_var,
            ..raw[i]
        }
    }

    /// The candidates at texel `i` (only `only` when given; the others are left at the texel
    /// alone): each one's value (demodulated) and its SURE in the output's units
    /// (module docs).
    fn candidates(
        &self,
        samples: &[Sample],
        texels: &[Texel],
        i: usize,
        only: Option<usize>,
    ) -> [(Bands, f64); CANDIDATES] {
        let c = &samples[i];
        let mut out = [(c.value, sure(c, &c.value, &c.spread)); CANDIDATES];
        let wanted = |k: usize| only.is_none_or(|o| o == k);
        for (si, &sigma) in SIGMAS.iter().enumerate() {
            // the fits of this σ wanted: their range τs and the most terms they take
            let (mut want, mut terms) = ([false; TAUS.len()], 0);
            for (f, &(fs, ft, fterms)) in FITS.iter().enumerate() {
                if fs == si && wanted(f + 1) {
                    want[ft] = true;
                    terms = terms.max(fterms);
                }
            }
            if terms == 0 {
                continue;
            }
            let mut acc = [Moments::default(); TAUS.len()];
            self.neighbours(samples, texels, i, sigma, |j, w, offset| {
                let s = &samples[j];
                // light found around one and none around the other: a wall between them (a
                // floor running under it into a closed room), or light's edge; never mixed
                if c.dark() != s.dark() {
                    return;
                }
                let scale = c.guide_var + s.guide_var;
                let diff = (c.guide - s.guide).powi(2);
                let range = if scale > 0.0 {
                    diff / (2.0 * scale)
                } else if diff == 0.0 {
                    0.0
                } else {
                    f64::INFINITY
                };
                // exp(−r/τ²) for τ = 1, 3, ∞: the first the second to the 9th power
                let wide = (-range / 9.0).exp();
                let narrow = wide.powi(9);
                let at = (offset.0 / sigma, offset.1 / sigma);
                for ((a, r), on) in acc.iter_mut().zip([narrow, wide, 1.0]).zip(want) {
                    if on {
                        a.add(w * r, at, s, terms);
                    }
                }
            });
            // (a quadratic fit's sums hold the linear one's: both from one pass)
            for (f, &(fs, ft, fterms)) in FITS.iter().enumerate() {
                if fs == si && wanted(f + 1) {
                    let (value, ws) = acc[ft].solve(fterms);
                    out[f + 1] = (value, sure(c, &value, &ws));
                }
            }
        }
        out
    }

    /// Each texel's candidate: the one of least SURE summed over its region ([`REGION`]² texels
    /// of a page) and the regions around it, over the reflecting texels it [`chooses`] by;
    /// with those texels and their candidates' SURE.
    fn choose(&self, texels: &[Texel], samples: &[Sample]) -> (Vec<usize>, Picked) {
        let (across, down) = (self.width.div_ceil(REGION), self.height.div_ceil(REGION));
        let region = |t: &Texel| {
            (t.page as usize * down + t.y as usize / REGION) * across + t.x as usize / REGION
        };
        let regions = self.index.len() / (self.width * self.height) * across * down;
        let picked: Vec<usize> = (0..texels.len())
            .filter(|&i| chooses(&texels[i]) && samples[i].measured())
            .collect();
        let sure: Vec<[f64; CANDIDATES]> = (picked.par_iter())
            .map(|&i| self.candidates(samples, texels, i, None).map(|c| c.1))
            .collect();
        let mut sums = vec![[0.0; CANDIDATES]; regions];
        for (&i, s) in picked.iter().zip(&sure) {
            let r = &mut sums[region(&texels[i])];
            r.iter_mut().zip(s).for_each(|(a, b)| *a += b);
        }
        let best: Vec<usize> = (0..regions)
            .map(|r| {
                let (page, y, x) = (r / (across * down), r / across % down, r % across);
                let mut s = [0.0; CANDIDATES];
                for ny in y.saturating_sub(1)..(y + 2).min(down) {
                    for nx in x.saturating_sub(1)..(x + 2).min(across) {
                        let n = (page * down + ny) * across + nx;
                        s.iter_mut().zip(&sums[n]).for_each(|(a, b)| *a += b);
                    }
                }
                (0..CANDIDATES)
                    .min_by(|&a, &b| s[a].total_cmp(&s[b]))
                    .unwrap_or(0)
            })
            .collect();
        let choice = texels.iter().map(|t| best[region(t)]).collect();
        (choice, picked.into_iter().zip(sure).collect())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DVec3;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    /// A flat 64 × 64-texel chart (one texel per unit) lit by a smooth gradient with a shadow's
    /// sharp edge across it, and a chart beside it on the page that stands elsewhere in the scene
    /// (its texels at x + 1000) and is twice as bright.
    fn chart() -> (Atlas, Vec<Texel>, Vec<f64>) {
        let n = 64;
        let atlas = Atlas {
            width: 2 * n,
            height: n,
            pages: 1,
            texels_per_unit: 1.0,
            charts: 2,
            utilization: 1.0,
            faces: Vec::new(),
            from_input: false,
            note: None,
        };
        let (mut texels, mut mean) = (Vec::new(), Vec::new());
        for y in 0..n {
            for x in 0..2 * n {
                let far = if x >= n { 1000.0 } else { 0.0 };
                let point = DVec3::new(f64::from(x) + 0.5 + far, f64::from(y) + 0.5, 0.0);
                texels.push(Texel {
                    page: 0,
                    x,
                    y,
                    point,
                    normal: DVec3::Z,
                    face: 0,
                });
                let lit = if x < n && x > 40 { 0.2 } else { 1.0 };
                let side = if x >= n { 2.0 } else { 1.0 };
                mean.push(side * lit * (1.0 + 0.3 * (f64::from(y) / 20.0).sin()));
            }
        }
        (atlas, texels, mean)
    }

    /// The gathered values of one bake: two replicates per texel, each the mean plus noise of
    /// relative size `noise`, half of it independent per texel and half shared by 2 × 2 blocks of
    /// texels (as neighbours share paths).
    fn bake(mean: &[f64], width: u32, noise: f64, seed: u64) -> Vec<Gathered> {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let mut normal = || {
            let (u, v): (f64, f64) = (rng.random(), rng.random());
            (-2.0 * (1.0 - u).ln()).sqrt() * (std::f64::consts::TAU * v).cos()
        };
        let blocks: Vec<[f64; 2]> = (0..mean.len()).map(|_| [normal(), normal()]).collect();
        let w = width as usize;
        (0..mean.len())
            .map(|i| {
                let block = blocks[(i / w / 2) * w + (i % w) / 2];
                let [a, b] = [0, 1].map(|r| {
                    let e = (0.5f64.sqrt()) * (normal() + block[r]);
                    mean[i] * (1.0 + noise * e)
                });
                let y = 0.5 * (a + b);
                let s = 0.5 * (a - b);
                Gathered {
                    radiosity: [y; BANDS],
                    std_error: [s.abs(); BANDS],
                    spread: [s; BANDS],
                    ..Gathered::default()
                }
            })
            .collect()
    }

    fn measured_error(values: &[Gathered], mean: &[f64]) -> f64 {
        let (mut d, mut m) = (0.0, 0.0);
        for (g, &mu) in values.iter().zip(mean) {
            d += g.radiosity.iter().map(|v| (v - mu).powi(2)).sum::<f64>();
            m += BANDS as f64 * mu * mu;
        }
        (d / m).sqrt()
    }

    /// Denoising a noisy bake (3–30 % per texel) lowers its error three times or more; the
    /// estimate, blur included, stays within 15 % of the error measured against the exact values
    /// (mean over seeds, half the noise shared by 2 × 2 texels as the paths gather shares paths);
    /// the raw error estimate agrees with the raw error; the shadow's edge and the other chart
    /// are not blurred into each other (the texels on both sides of the edge closer to the
    /// exact values than the raw ones wherever the guide sees the edge).
    #[test]
    fn denoising_lowers_the_error_and_estimates_it_with_its_blur() {
        let (atlas, texels, mean) = chart();
        let mut checks = Vec::new();
        for noise in [0.3, 0.1, 0.03] {
            let (mut raw, mut den, mut est, mut raw_est) = (0.0, 0.0, 0.0, 0.0);
            let seeds = 8;
            // squared relative errors of the texels on both sides of the edge, raw and denoised
            let (mut edge_raw, mut edge) = (0.0, 0.0);
            for seed in 0..seeds {
                let g = bake(&mean, atlas.width, noise, seed);
                // the guide: an independent bake of a quarter of the rays
                let guide = bake(&mean, atlas.width, 2.0 * noise, seed + 1000);
                let (out, report) = denoise(&atlas, &texels, (&g, &guide), None);
                raw += measured_error(&g, &mean) / seeds as f64;
                den += measured_error(&out, &mean) / seeds as f64;
                est += report.error.unwrap() / seeds as f64;
                raw_est += report.raw_error.unwrap() / seeds as f64;
                // the texels just inside the shadow, and just outside it
                for y in 10..54 {
                    for x in [40usize, 41] {
                        let i = y * atlas.width as usize + x;
                        edge += (out[i].radiosity[0] / mean[i] - 1.0).powi(2);
                        edge_raw += (g[i].radiosity[0] / mean[i] - 1.0).powi(2);
                    }
                }
            }
            eprintln!(
                "noise {noise}: raw {raw:.4} (estimated {raw_est:.4}), denoised {den:.4} \
                 (estimated {est:.4}); beside the edge {:.4} raw, {:.4} denoised",
                edge_raw.sqrt(),
                edge.sqrt()
            );
            let (edge_raw, edge) = (edge_raw.sqrt(), edge.sqrt());

            checks.push((noise, raw, raw_est, den, est, (edge_raw, edge)));
        }
        for (noise, raw, raw_est, den, est, (edge_raw, edge)) in checks {
            assert!((raw_est / raw - 1.0).abs() < 0.1, "{raw_est} vs {raw}");
            assert!(den < raw / 3.0, "denoised {den} vs raw {raw}");
            assert!(
                (est / den - 1.0).abs() < 0.15,
                "noise {noise}: estimated {est} vs {den}"
            );
            // (at 30 % noise the guide, at 60 %, cannot see the edge: the blur is SURE's best)
            assert!(
                noise > 0.1 || edge < edge_raw,
                "noise {noise}: beside the edge {edge} denoised, {edge_raw} raw"
            );
        }
    }
}

//! Rays where an image needs them (beyond the dissertation): the paths gather's rays over the
//! pixels of `--image-mode pixel` in proportion to each pixel's relative standard deviation.
//!
//! Image users judge an image by its per-pixel relative MSE, mean((x − r)²/(r² + ε)): a dim pixel
//! weighs as much as a bright one. Its expectation is `Σ_p σ_p²/n_p / P` over the pixels, with
//! σ_p² = Σ_k var_pk/(B_pk² + ε) the relative variance of one ray's estimate of pixel p (ε:
//! [`relative_floor`]) and n_p its rays. For a given total of rays it is smallest at `n_p ∝ σ_p`
//! (Neyman's allocation), and it is then `(Σ σ_p)²/N` instead of `Σ σ_p²·P/N` with every pixel
//! alike: the gain is the ratio of the mean of σ² to the square of the mean of σ. The rounds stop
//! on the same measure ([`pixel_error`], its χ² bound), so `--target-error` is per pixel.
//! Images are far from uniform: an emitter's outline, a shadow's edge or a bright patch seen
//! through a pixel's footprint have a σ many times that of a wall's interior.
//!
//! The steps ([`allocated_rounds`]):
//!
//! 1. a pilot round gives every pixel the same rays (the configured first round); if it meets
//!    the target, it is the image; if the allocation would not halve the rays (Neyman's gain
//!    over the pixels that vary above ½: an image without edges), the rounds go on uniformly
//!    from the pilot ([`super::rounds::rounds_to_target`]). Half, not less: the gain is
//!    Neyman's for independent rays, but the Sobol points of a smooth pixel converge faster than
//!    1/rays, so a mild gain does not survive (wall-floor: expected 0.64, measured none — the
//!    allocated image took 1.2× the uniform rounds' time for the same error), while a strong one
//!    does (cornell-box 0.05, two-blockers 0.04), even where the target is nearly met and the
//!    allocation leaves out the pilot: the uniform rounds overshoot to the next power of two
//!    (two-blockers at 10 %: 0.17 s allocated against 0.21–0.24 s uniform). Pixels that do not
//!    vary (the background, an emitter that does not reflect) cost a primary ray per ray and
//!    need none in either scheme, so they are left out of the gain;
//! 2. each pixel's share of the rays is set once, from the pilot: the variance of one ray's
//!    estimate over the pilot's rays (pilot − 1 degrees of freedom), a quarter of the rays spread
//!    evenly over all pixels (a defensive floor: a pixel whose variance the pilot missed gets at
//!    least a quarter of the uniform rays);
//! 3. rounds raise a level R (mean rays per pixel) until the χ² bound of the estimated error
//!    meets the target or every pixel reaches the cap; pixel p's Sobol points run to the power of
//!    two that covers `share_p·R` (each round an aligned block: a balanced net).
//!
//! The pilot decides the shares, so its rays are not in the image: each pixel's value is the
//! mean of its later rounds, whose ray counts depend on the pilot and the level only, not on
//! their own values (the pixel's value stays unbiased; the level depends on the whole image's
//! estimated error, as every round to a target does).

use super::paths::{PointEstimate, REPLICATES};
use super::rounds::{rounds_to_target, singletons};
use crate::config::GatherSamples;
use crate::gather::Gathered;
use rayon::prelude::*;

/// Share of the rays spread evenly over the pixels (step 2).
const EVEN_SHARE: f64 = 0.25;

/// The floor of the per-pixel relative error's denominator, as a share of the image's mean B
/// ([`relative_floor`]).
const FLOOR: f64 = 0.1;

/// Pixel `p`'s estimate over a footprint: `estimate(p, first, rays)` with `rays` rays from Sobol
/// index `first` (per replicate) on.
pub(super) type Estimate<'a> = dyn Fn(usize, usize, usize) -> PointEstimate + Sync + 'a;

/// `n` pixels gathered to the relative error `target` with the rays allocated by each pixel's
/// standard deviation (module docs); `pilot` rays per pixel in the first round, at most
/// `max_rays` per pixel.
pub(crate) fn allocated_rounds(
    n: usize,
    estimate: &Estimate,
    pilot: usize,
    target: f64,
    max_rays: usize,
) -> Vec<Gathered> {
    // ⟨Pilot: the same rays at every pixel; it is the image when it meets the target⟩
    let pilot = pilot.min(max_rays).max(REPLICATES);
    let reporter = crate::progress::Reporter::new(n, pilot, target);
    let needed = |rays: f64, bound: f64| (rays * (bound / target).powi(2)).min(max_rays as f64);
    let (pilot_estimates, pilot_gathered) = pilot_round(n, estimate, pilot, &reporter);
    let floor = relative_floor(&pilot_gathered);
    let bound = match pixel_error_bound(&pilot_gathered, floor) {
        Some(bound) if bound > target && pilot < max_rays => bound,
        bound => return reporter.last_round(bound, pilot, pilot_gathered),
    };
    reporter.round(bound, pilot, needed(pilot as f64, bound) as usize);
    // ⟨Shares: each ray's relative standard deviation in the pilot, a quarter spread evenly;
    // even shares unless the allocation halves the rays (step 1)⟩
    let sigma: Vec<f64> = (pilot_estimates.iter())
        .zip(&pilot_gathered)
        .map(|(e, g)| ray_sigma(e, g, pilot, floor))
        .collect();
    let (mean_sigma, share) = shares(&sigma);
    if neyman_gain(&sigma) > 0.5 {
        let samples = GatherSamples {
            direct: pilot,
            indirect: pilot,
        };
        return rounds_to_target(
            n,
            &singletons(n),
            |g: &[usize], first, samples: GatherSamples, _guided| {
                vec![estimate(g[0], first, samples.direct)]
            },
            (samples, Some(pilot_estimates)),
            (target, &move |g: &[Gathered], _| {
                pixel_error_bound(g, floor)
            }),
            (max_rays, crate::config::Guiding::Off),
        );
    }
    // Neyman's level over all pixels (shares of mean 1 over all of them): the uniform rays
    // times the mean of σ, squared, over the mean of σ²
    let gain = mean_sigma.powi(2) / (sigma.iter().map(|s| s * s).sum::<f64>() / n as f64);
    // ⟨Rounds: raise the level until the bound meets the target or every pixel is capped⟩
    let uniform = pilot as f64 * (bound / target).powi(2);
    let start = pilot.div_ceil(REPLICATES);
    let cap = (max_rays / REPLICATES).max(2 * start);
    // per pixel: its Sobol index so far (per replicate) and its estimate after the pilot
    let mut done = vec![start; n];
    let mut estimates: Vec<Option<PointEstimate>> = vec![None; n];
    let mut level = (uniform * gain).max(pilot as f64);
    loop {
        let wanted: Vec<usize> = (share.iter())
            .map(|s| end_index(start, s * level / REPLICATES as f64, cap))
            .collect();
        let rounds: Vec<Option<PointEstimate>> = (0..n)
            .into_par_iter()
            .map(|p| {
                (wanted[p] > done[p]).then(|| {
                    let rays = (wanted[p] - done[p]) * REPLICATES;
                    let e = estimate(p, done[p], rays);
                    reporter.finished(1, rays);
                    e
                })
            })
            .collect();
        for (p, round) in rounds.into_iter().enumerate() {
            if let Some(r) = round {
                match &mut estimates[p] {
                    Some(e) => e.merge(&r),
                    none => *none = Some(r),
                }
                done[p] = wanted[p];
            }
        }
        let gathered: Vec<Gathered> = (estimates.iter())
            .map(|e| {
                let mut g = e.as_ref().map(PointEstimate::gathered).unwrap_or_default();
                g.rays += pilot;
                g
            })
            .collect();
        let capped = done.iter().all(|&d| d >= cap);
        let rays = pilot + level as usize;
        match pixel_error_bound(&gathered, floor) {
            Some(bound) if bound > target && !capped => {
                reporter.round(bound, rays, needed(rays as f64, bound) as usize);
                // variance ∝ 1/level: the next level covers the missing part, 2× to 4×
                level *= (bound / target).powi(2).clamp(2.0, 4.0);
            }
            bound => return reporter.last_round(bound, rays, gathered),
        }
    }
}

/// Each pixel's share of the rays (mean 1): a quarter spread evenly, the rest ∝ its σ; and the
/// mean σ.
fn shares(sigma: &[f64]) -> (f64, Vec<f64>) {
    let mean_sigma = sigma.iter().sum::<f64>() / sigma.len().max(1) as f64;
    let share = if mean_sigma > 0.0 {
        (sigma.iter())
            .map(|s| EVEN_SHARE + (1.0 - EVEN_SHARE) * s / mean_sigma)
            .collect()
    } else {
        vec![1.0; sigma.len()]
    };
    (mean_sigma, share)
}

/// The pilot: `pilot` rays at every pixel; its estimates and their values.
fn pilot_round(
    n: usize,
    estimate: &Estimate,
    pilot: usize,
    reporter: &crate::progress::Reporter,
) -> (Vec<PointEstimate>, Vec<Gathered>) {
    let estimates: Vec<PointEstimate> = (0..n)
        .into_par_iter()
        .map(|p| {
            let e = estimate(p, 0, pilot);
            reporter.finished(1, pilot);
            e
        })
        .collect();
    let gathered: Vec<Gathered> = estimates.iter().map(|e| e.gathered()).collect();
    (estimates, gathered)
}

/// The floor ε of the per-pixel relative error: (10 % of the mean B over the pixels and bands
/// that vary)², so that a black pixel does not ask for endless rays. Scale-free: the relative MSE
/// image users compute, mean((x − r)²/(r² + 0.01)), floors at 0.1 of an image of mean about 1.
pub(crate) fn relative_floor(gathered: &[Gathered]) -> f64 {
    let varying = gathered
        .iter()
        .filter(|g| g.std_error.iter().any(|s| *s != 0.0));
    let (sum, count) = varying.fold((0.0, 0.0), |(s, c), g| {
        (
            s + g.radiosity.iter().map(|b| b.abs()).sum::<f64>(),
            c + g.radiosity.len() as f64,
        )
    });
    let mean = if count > 0.0 { sum / count } else { 0.0 };
    (FLOOR * mean).powi(2).max(1e-300)
}

/// The per-pixel relative error of an image: the root mean over pixels and bands of
/// σ²/(B² + ε) (`floor` = ε, [`relative_floor`]); None when no pixel has a standard error.
pub(crate) fn pixel_error(gathered: &[Gathered], floor: f64) -> Option<f64> {
    if measured(gathered) == 0 {
        return None;
    }
    let sum: f64 = (gathered.iter())
        .flat_map(|g| {
            (0..g.radiosity.len())
                .map(|k| g.std_error[k].powi(2) / (g.radiosity[k].powi(2) + floor))
        })
        .sum();
    Some((sum / (gathered.len() * gathered[0].radiosity.len()) as f64).sqrt())
}

/// [`pixel_error`]'s 90 % upper bound: × √(dof/χ²₀.₁(dof)), dof the pixels with a standard error.
fn pixel_error_bound(gathered: &[Gathered], floor: f64) -> Option<f64> {
    pixel_error(gathered, floor).map(|e| e * super::rounds::chi2_scale(measured(gathered)))
}

/// Neyman's gain over the pixels that vary (σ > 0): the mean of σ, squared, over the mean of
/// σ² (1: nothing to gain).
fn neyman_gain(sigma: &[f64]) -> f64 {
    let (mut count, mut sum, mut square) = (0.0, 0.0, 0.0);
    for &s in sigma.iter().filter(|s| **s > 0.0) {
        (count, sum, square) = (count + 1.0, sum + s, square + s * s);
    }
    if square > 0.0 {
        (sum * sum / (count * square)).min(1.0)
    } else {
        1.0
    }
}

/// Degrees of freedom of the pixels' standard errors: one per pixel that has one (two replicates).
fn measured(gathered: &[Gathered]) -> usize {
    (gathered.iter())
        .filter(|g| g.std_error.iter().any(|s| *s != 0.0))
        .count()
}

/// The Sobol index (per replicate) a pixel's rays run to for `wanted` rays per replicate after
/// the pilot's `start`: the power of two that covers them, at least `2·start` (one aligned block
/// after the pilot), at most `cap`.
fn end_index(start: usize, wanted: f64, cap: usize) -> usize {
    let need = start + wanted.ceil().max(0.0) as usize;
    need.next_power_of_two().max(2 * start).min(cap)
}

/// The relative standard deviation of one ray's estimate, `√Σ_k var_k/(B_k² + ε)`, from a round
/// of `rays` rays: each band's variance the rays' mean square less the square of their mean,
/// unbiased (× rays/(rays − 1)), over the pixel's B² floored by `floor` ([`relative_floor`]).
fn ray_sigma(e: &PointEstimate, g: &Gathered, rays: usize, floor: f64) -> f64 {
    let n = rays as f64;
    let var: f64 = (0..e.ray_square.len())
        .map(|k| {
            let v = (e.ray_square[k] - (g.radiosity[k] - e.emission[k]).powi(2)).max(0.0);
            v / (g.radiosity[k].powi(2) + floor)
        })
        .sum::<f64>()
        * n
        / (n - 1.0).max(1.0);
    var.sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::element::Bands;

    /// The gain counts the pixels that vary only: a background of σ = 0 costs a primary ray per
    /// ray and needs no rays in either scheme, so it must not make the allocation look better
    /// (with it counted, half the pixels black made a flat image's gain 0.5).
    #[test]
    fn neyman_gain_leaves_out_pixels_that_do_not_vary() {
        assert_eq!(neyman_gain(&[1.0, 1.0, 1.0, 1.0]), 1.0);
        assert_eq!(neyman_gain(&[1.0, 1.0, 0.0, 0.0]), 1.0);
        assert!((neyman_gain(&[3.0, 1.0, 0.0]) - 0.8).abs() < 1e-15);
        assert_eq!(neyman_gain(&[0.0, 0.0]), 1.0);
    }

    /// A synthetic image: pixel p's rays are independent draws with mean m_p and standard
    /// deviation s_p (s large on a vertical "edge" column, small elsewhere), each replicate the
    /// mean of its rays. Allocated rounds give the edge more rays than the interior, every pixel
    /// stays unbiased (the mean over 100 runs within 4 standard errors of m_p), and at the same
    /// total of rays the image's squared error is below the uniform allocation's.
    #[test]
    fn rays_follow_the_standard_deviation_and_pixels_stay_unbiased() {
        use rand::{Rng, SeedableRng};
        use rand_chacha::ChaCha8Rng;
        let (w, h) = (12, 8);
        let mean = |p: usize| 1.0 + (p % w) as f64 * 0.1;
        let sd = |p: usize| if p % w == 5 { 20.0 } else { 0.5 };
        // one estimate: replicate means of rays/REPLICATES normal draws each (Box–Muller)
        let run = |seed: u64| {
            move |p: usize, first: usize, rays: usize| {
                let mut rng = ChaCha8Rng::seed_from_u64(
                    seed ^ (p as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15) ^ (first as u64) << 40,
                );
                let per = rays / REPLICATES;
                let mut share = [Bands::default(); REPLICATES];
                let mut square = 0.0;
                for s in share.iter_mut() {
                    let mut acc = 0.0;
                    for _ in 0..per {
                        let (u, v): (f64, f64) = (rng.random(), rng.random());
                        let z = (-2.0 * (1.0 - u).ln()).sqrt() * (std::f64::consts::TAU * v).cos();
                        let b = mean(p) + sd(p) * z;
                        acc += b;
                        square += b * b / rays as f64;
                    }
                    *s = [acc / per as f64 / REPLICATES as f64; 3];
                }
                PointEstimate {
                    share,
                    replicates: REPLICATES,
                    rays,
                    reflects: true,
                    ray_square: [square; 3],
                    ..PointEstimate::default()
                }
            }
        };
        let runs = 100;
        let (mut sum, mut sq_err, mut rays) = (vec![0.0; w * h], 0.0, 0usize);
        let (mut edge_rays, mut inner_rays) = (0, 0);
        for seed in 0..runs {
            let est = run(seed);
            let g = allocated_rounds(w * h, &est, 16, 0.05, 1 << 16);
            for (p, g) in g.iter().enumerate() {
                sum[p] += g.radiosity[0];
                sq_err += (g.radiosity[0] - mean(p)).powi(2);
                rays += g.rays;
            }
            edge_rays += g[5].rays;
            inner_rays += g[1].rays;
        }
        assert!(
            edge_rays > 4 * inner_rays,
            "edge {edge_rays} vs interior {inner_rays} rays"
        );
        for p in 0..w * h {
            let m = sum[p] / runs as f64;
            // each run's pixel has at least 2·8 rays after the pilot
            let se = sd(p) / (16.0 * runs as f64).sqrt();
            assert!(
                (m - mean(p)).abs() < 4.0 * se,
                "pixel {p}: {m} vs {}",
                mean(p)
            );
        }
        // the uniform allocation at the same mean rays per pixel
        let per_pixel = rays as f64 / (runs as usize * w * h) as f64;
        let uniform: f64 = (0..w * h).map(|p| sd(p).powi(2) / per_pixel).sum::<f64>();
        let allocated = sq_err / runs as f64;
        eprintln!(
            "squared error {allocated:.4} allocated, {uniform:.4} uniform; rays edge/interior {:.1}",
            edge_rays as f64 / inner_rays as f64
        );
        assert!(
            allocated < 0.5 * uniform,
            "squared error {allocated} allocated vs {uniform} uniform"
        );
    }
}

//! The factorized transfer step (docs/design/math.md §3; sec. 3.8.2, eq. 3.41–3.43).
//!
//! A kernel Gaussian `Ω_o(x, y) = exp(−(|x−w_o^x|² + |y−w_o^y|²)/d_o²)` is isotropic in the joint
//! space, so it is the product `g(x; w_o^x, d_o)·g(y; w_o^y, d_o)` and the coefficient of eq. 3.43
//! factorizes exactly:
//! `ĥ_pqo = ∫∫ Λ_p(x) Ω_o(x, y) Λ_q(y) dx dy = α_{p,o} β_{q,o}` with
//! `α_{p,o} = ∫ Λ_p g(·; w_o^x, d_o)`, `β_{q,o} = ∫ Λ_q g(·; w_o^y, d_o)`.
//! With the orthonormal base `N = A Λ` (eq. 3.38) the transfer matrix of eq. 3.42 is
//! `H = Σ_o v_o (A α_o)(A β_o)ᵀ` (row: sender, column: receiver) and is never formed:
//! - [`reflect`] (docs/design/math.md §3): the sender is the exact constant 1, so
//!   `r = A Σ_o v_o c_o β_o` with `c_o = ∫_S g(·; w_o^x, d_o)`;
//! - [`reflect_projected`] (the dissertation's variant, eq. 3.10–3.12): the constant is first
//!   projected onto the base (coefficients `b̄`), `r = Hᵀ b̄ = A Σ_o v_o β_o (α_o · Aᵀ b̄)`;
//! - [`reflect_naive`]: the same quantity through the dense triple sum
//!   `Ĥ_pq = Σ_o v_o α_{p,o} β_{q,o}` (O(z ẑ²), the cost of eq. 3.42 as written), kept for the
//!   comparing test and the benchmark.
//!
//! Each α, β entry and each `c_o` is the flat closed form or the exact element sum, as for the
//! Gram matrix ([`crate::gram`](mod@crate::gram)). The zero rule "normals not facing" of fig. 3.6 is not applied:
//! it only saves work, the kernel network gives 0 there anyway (footnote 12 of sec. 3.9.1).

use crate::criteria::Integration;
use crate::gram::{
    Dim, Domain, Gaussian, GramConfig, GramError, Sparse, cross_with, support_radius,
};
use crate::orthonormal::Orthonormal;
use rayon::prelude::*;
use std::f64::consts::PI;

type V = [f64; 3];

/// One kernel Gaussian: centre halves `w_o^x` (sender) and `w_o^y` (receiver), width `d_o` and
/// output weight `v_o`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct KernelGaussian {
    /// Sender half of the centre.
    pub wx: V,
    /// Receiver half of the centre.
    pub wy: V,
    /// Width `d_o` (the same in both halves: the Gaussian is isotropic).
    pub width: f64,
    /// Output-layer weight `v_o`.
    pub weight: f64,
    /// The caller's criterion accepts the flat closed form for both halves.
    pub flat: bool,
}

/// The factors of the transfer coefficients.
#[derive(Clone, Debug, PartialEq)]
pub struct Factors {
    /// `α_{p,o}`: row o (kernel), column p (base).
    pub alpha: Sparse,
    /// `β_{q,o}`: row o (kernel), column q (base).
    pub beta: Sparse,
    /// `c_o = ∫_S g(·; w_o^x, d_o)`.
    pub c: Vec<f64>,
}

fn halves(kernel: &[KernelGaussian], y: bool) -> Vec<Gaussian> {
    kernel
        .iter()
        .map(|k| Gaussian {
            flat: k.flat,
            ..Gaussian::new(if y { k.wy } else { k.wx }, k.width)
        })
        .collect()
}

/// α, β and c of `kernel` against `base` on `domain`: the flat closed forms where both the kernel
/// Gaussian and the base Gaussian are flat (`c_o`: the whole plane `π d_o²`, in 2-D the whole line
/// `√π d_o`), else the exact element sums.
pub fn factors(
    domain: &Domain,
    base: &[Gaussian],
    kernel: &[KernelGaussian],
    cfg: &GramConfig,
) -> Result<Factors, GramError> {
    let rule = |k: &Gaussian, b: &Gaussian| {
        if k.flat && b.flat {
            Integration::ClosedForm
        } else {
            Integration::ElementSum
        }
    };
    let xs = halves(kernel, false);
    let alpha = cross_with(domain, &xs, base, cfg, rule)?;
    let beta = cross_with(domain, &halves(kernel, true), base, cfg, rule)?;
    let c = xs
        .par_iter()
        .map(|k| {
            if k.flat {
                match domain.dim() {
                    Dim::Three => PI * k.width * k.width,
                    Dim::Two => PI.sqrt() * k.width,
                }
            } else {
                let a = 1.0 / (k.width * k.width);
                let mut near = Vec::new();
                domain.elements_near(k.centre, support_radius(a, cfg.tol), &mut near);
                domain.integrate(k.centre, a, cfg.tol, cfg.accurate, Some(&near))
            }
        })
        .collect();
    Ok(Factors { alpha, beta, c })
}

fn check(f: &Factors, kernel: &[KernelGaussian], ortho: &Orthonormal) -> Result<usize, GramError> {
    let n = ortho.kept().len();
    for (expected, got) in [
        (kernel.len(), f.alpha.nrows()),
        (kernel.len(), f.beta.nrows()),
        (kernel.len(), f.c.len()),
        (n, f.alpha.ncols()),
        (n, f.beta.ncols()),
    ] {
        if expected != got {
            return Err(GramError::Length { expected, got });
        }
    }
    Ok(n)
}

/// Reflected coefficients of the exact constant sender radiosity 1 (docs/design/math.md §3):
/// `r = A Σ_o v_o c_o β_o`, O(z · neighbours) plus one triangular solve.
pub fn reflect(
    f: &Factors,
    kernel: &[KernelGaussian],
    ortho: &Orthonormal,
) -> Result<Vec<f64>, GramError> {
    let n = check(f, kernel, ortho)?;
    Ok(receive(f, kernel, ortho, &f.c, n))
}

/// `A Σ_o v_o·sender_o·β_o`: the receiver side both variants share, with `sender_o` the kernel
/// cell's sender integral (c_o, or α_o · Aᵀ b̄).
fn receive(
    f: &Factors,
    kernel: &[KernelGaussian],
    ortho: &Orthonormal,
    sender: &[f64],
    n: usize,
) -> Vec<f64> {
    let mut s = vec![0.0; n];
    for (o, k) in kernel.iter().enumerate() {
        let w = k.weight * sender[o];
        for (q, b) in f.beta.row(o) {
            s[q] += w * b;
        }
    }
    ortho.apply_a(&s)
}

/// The dissertation's variant (eq. 3.10–3.12, 3.42): the sender radiosity is `Σ b̄_i N_i`
/// (e.g. the projection of 1 onto the base, fig. 3.4); `r = Hᵀ b̄ = A Σ_o v_o β_o (α_o · Aᵀ b̄)`.
pub fn reflect_projected(
    f: &Factors,
    kernel: &[KernelGaussian],
    ortho: &Orthonormal,
    bbar: &[f64],
) -> Result<Vec<f64>, GramError> {
    let n = check(f, kernel, ortho)?;
    if bbar.len() != n {
        return Err(GramError::Length {
            expected: n,
            got: bbar.len(),
        });
    }
    let gamma = ortho.apply_at(bbar);
    let t = f.alpha.mul_vec(&gamma)?;
    Ok(receive(f, kernel, ortho, &t, n))
}

/// The same as [`reflect_projected`] through the dense triple sum of eq. 3.42:
/// `Ĥ_pq = Σ_o v_o α_{p,o} β_{q,o}` over all o, p, q (O(z ẑ²) time, O(ẑ²) memory), then
/// `r = A Ĥᵀ Aᵀ b̄`. For comparison and benchmarks only.
pub fn reflect_naive(
    f: &Factors,
    kernel: &[KernelGaussian],
    ortho: &Orthonormal,
    bbar: &[f64],
) -> Result<Vec<f64>, GramError> {
    let n = check(f, kernel, ortho)?;
    if bbar.len() != n {
        return Err(GramError::Length {
            expected: n,
            got: bbar.len(),
        });
    }
    let (alpha, beta) = (f.alpha.to_dense(), f.beta.to_dense());
    // Row-major Ĥ, rows p in parallel once the work pays for the threads.
    let row = |p: usize| {
        let mut row = vec![0.0; n];
        for (o, k) in kernel.iter().enumerate() {
            let w = k.weight * alpha[(o, p)];
            for q in 0..n {
                row[q] += w * beta[(o, q)];
            }
        }
        row
    };
    let h: Vec<Vec<f64>> = if n * n * kernel.len() < 1 << 20 {
        (0..n).map(row).collect()
    } else {
        (0..n).into_par_iter().map(row).collect()
    };
    let gamma = ortho.apply_at(bbar);
    let mut s = vec![0.0; n];
    for p in 0..n {
        for q in 0..n {
            s[q] += h[p][q] * gamma[p];
        }
    }
    Ok(ortho.apply_a(&s))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cubature::triangle_cubature;
    use crate::gram::gram;

    fn grid(n: usize, h: f64, bump: f64) -> Domain {
        let mut v = Vec::new();
        for y in 0..=n {
            for x in 0..=n {
                let (px, py) = (x as f64 * h, y as f64 * h);
                v.push([px, py, bump * (1.1 * px).sin() * (0.7 * py).sin()]);
            }
        }
        let id = |x: usize, y: usize| (y * (n + 1) + x) as u32;
        let mut t = Vec::new();
        for y in 0..n {
            for x in 0..n {
                t.push([id(x, y), id(x + 1, y), id(x + 1, y + 1)]);
                t.push([id(x, y), id(x + 1, y + 1), id(x, y + 1)]);
            }
        }
        Domain::triangles(v, &t).unwrap()
    }

    fn setup(bump: f64) -> (Domain, Vec<Gaussian>, Vec<KernelGaussian>) {
        let dom = grid(12, 0.5, bump);
        let z = |x: f64, y: f64| bump * (1.1 * x).sin() * (0.7 * y).sin();
        let mut base = Vec::new();
        for y in 0..6 {
            for x in 0..6 {
                let (px, py) = (0.5 + x as f64, 0.5 + y as f64 + 0.1 * x as f64);
                base.push(Gaussian::new([px, py, z(px, py)], 0.9));
            }
        }
        let kernel = (0..7)
            .map(|o| {
                let (x, y) = (0.8 * o as f64, 5.5 - 0.7 * o as f64);
                KernelGaussian {
                    wx: [x, 1.0 + 0.3 * x, z(x, 1.0 + 0.3 * x)],
                    wy: [y, 4.0 - 0.2 * y, z(y, 4.0 - 0.2 * y)],
                    width: 0.8 + 0.1 * o as f64,
                    weight: 1.0 - 0.2 * o as f64,
                    flat: false,
                }
            })
            .collect();
        (dom, base, kernel)
    }

    #[test]
    fn naive_triple_sum_equals_factorized_form() {
        let (dom, base, kernel) = setup(0.3);
        let cfg = GramConfig::default();
        let g = gram(&dom, &base, &cfg).unwrap().matrix.to_dense();
        let ortho = Orthonormal::new(&g, 1e-12);
        let f = factors(&dom, &base, &kernel, &cfg).unwrap();
        let bbar: Vec<f64> = (0..base.len())
            .map(|i| 1.0 + 0.1 * (i as f64).sin())
            .collect();
        let fast = reflect_projected(&f, &kernel, &ortho, &bbar).unwrap();
        let naive = reflect_naive(&f, &kernel, &ortho, &bbar).unwrap();
        let scale = naive.iter().fold(0.0f64, |m, x| m.max(x.abs()));
        assert!(scale > 0.0);
        for (a, b) in fast.iter().zip(&naive) {
            assert!((a - b).abs() <= 1e-12 * scale, "{a} vs {b}");
        }
        assert!(reflect_projected(&f, &kernel, &ortho, &bbar[1..]).is_err());
    }

    #[test]
    fn factors_match_cubature_and_reflect_is_the_integral_of_the_constant() {
        let (dom, base, kernel) = setup(0.3);
        let cfg = GramConfig::default();
        let f = factors(&dom, &base, &kernel, &cfg).unwrap();
        let cub = |c: V, a: f64, other: Option<&Gaussian>| -> f64 {
            let func = |x: V| {
                let d = |p: V| (0..3).map(|k| (x[k] - p[k]).powi(2)).sum::<f64>();
                let e = other.map_or(0.0, |g| d(g.centre) / (g.width * g.width));
                (-a * d(c) - e).exp()
            };
            (0..dom.len())
                .map(|k| triangle_cubature(func, dom.element(k), 1e-14).value)
                .sum()
        };
        for (o, k) in kernel.iter().enumerate() {
            let a = 1.0 / (k.width * k.width);
            let want = cub(k.wx, a, None);
            assert!((f.c[o] - want).abs() < 1e-11 * want, "{} vs {want}", f.c[o]);
            for p in [0, 7, 20, 35] {
                let want = cub(k.wx, a, Some(&base[p]));
                assert!(
                    (f.alpha.get(o, p) - want).abs() < 1e-12,
                    "{} vs {want}",
                    f.alpha.get(o, p)
                );
                let want = cub(k.wy, a, Some(&base[p]));
                assert!((f.beta.get(o, p) - want).abs() < 1e-12);
            }
        }
    }

    #[test]
    fn flat_shortcuts_equal_element_sums_on_a_large_flat_domain() {
        // 2-D and 3-D: far from the border of a flat domain the closed forms are exact.
        let v: Vec<[f64; 2]> = (0..=400).map(|k| [k as f64 * 0.05, 0.0]).collect();
        let s: Vec<[u32; 2]> = (0..400).map(|k| [k, k + 1]).collect();
        let line = Domain::segments(&v, &s).unwrap();
        let plane = grid(40, 0.5, 0.0);
        for dom in [&line, &plane] {
            let base: Vec<Gaussian> = (0..5)
                .map(|i| {
                    Gaussian::new(
                        [
                            9.0 + 0.4 * i as f64,
                            if dom.dim() == Dim::Two { 0.0 } else { 10.0 },
                            0.0,
                        ],
                        0.5,
                    )
                })
                .collect();
            let y = if dom.dim() == Dim::Two { 0.0 } else { 10.2 };
            let mut kernel = vec![KernelGaussian {
                wx: [9.5, y, 0.0],
                wy: [10.1, y, 0.0],
                width: 0.7,
                weight: 0.8,
                flat: false,
            }];
            let mut flat_base = base.clone();
            flat_base.iter_mut().for_each(|g| g.flat = true);
            let cfg = GramConfig::default();
            let exact = factors(dom, &base, &kernel, &cfg).unwrap();
            kernel[0].flat = true;
            let flat = factors(dom, &flat_base, &kernel, &cfg).unwrap();
            assert!((exact.c[0] - flat.c[0]).abs() < 1e-13 * flat.c[0]);
            for p in 0..5 {
                let (e, s) = (exact.alpha.get(0, p), flat.alpha.get(0, p));
                assert!((e - s).abs() < 1e-13 * s, "{e} vs {s}");
                let (e, s) = (exact.beta.get(0, p), flat.beta.get(0, p));
                assert!((e - s).abs() < 1e-13 * s, "{e} vs {s}");
            }
        }
    }

    #[test]
    fn direct_constant_and_projected_constant_agree_up_to_the_base_error() {
        // On a flat patch the projection of 1 onto the base (fig. 3.4) is close to 1 inside, so
        // the dissertation's variant and the direct c_o agree to a few per cent.
        let (dom, base, kernel) = setup(0.0);
        let cfg = GramConfig::default();
        let g = gram(&dom, &base, &cfg).unwrap().matrix.to_dense();
        let ortho = Orthonormal::new(&g, 1e-12);
        let u: Vec<f64> = base
            .iter()
            .map(|b| dom.integrate(b.centre, 1.0 / (b.width * b.width), cfg.tol, false, None))
            .collect();
        let bbar = ortho.apply_a(&u);
        let f = factors(&dom, &base, &kernel, &cfg).unwrap();
        let direct = reflect(&f, &kernel, &ortho).unwrap();
        let projected = reflect_projected(&f, &kernel, &ortho, &bbar).unwrap();
        let norm = |v: &[f64]| v.iter().map(|x| x * x).sum::<f64>().sqrt();
        let diff: Vec<f64> = direct.iter().zip(&projected).map(|(a, b)| a - b).collect();
        let rel = norm(&diff) / norm(&direct);
        assert!(rel > 0.0 && rel < 0.1, "relative difference {rel}");
    }
}

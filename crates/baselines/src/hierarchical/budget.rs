//! The link budget: find the refinement threshold ε that makes HR produce a requested number of links
//! (sec. 4.1 compares methods "for the equivalent number of links": about 16, 100 and 500 in fig. 4.5).
//!
//! The link count is a non-increasing step function of ε (smaller ε refines more). [`solve_for_links`]
//! brackets the target by decades from an ε that refines nothing, then bisects `log ε`, keeping the solution
//! whose count is closest to the target; it succeeds when `|links − target| ≤ max(rel_tol · target, 1)`.
//! A single ε step can refine a whole cascade of links at once (a link whose halves also exceed ε), so some
//! counts are unreachable for a given minimum patch length; the error then names the closest count found.

use super::error::{HrError, Result};
use super::flatland::{FlatHr, FlatHrConfig};
use super::triangles::{TriHr, TriHrConfig};
use scene_sampler::{FlatlandScene, Scene};

/// A solution at a link budget.
#[derive(Clone, Debug)]
pub struct BudgetResult {
    /// The solution.
    pub hr: FlatHr,
    /// The ε that produced it.
    pub epsilon: f64,
    /// Number of complete HR solutions the search made.
    pub solves: usize,
}

/// The default minimum patch length for a budget of `target` links: the total scene length over the target
/// (no patch finer than a uniform mesh with as many elements as there are links). At a corner the BF
/// oracle's `ρ·F·B` does not shrink with the patches (`F` between the two halves at a right angle stays
/// `1 − 1/√2`), so without a budget-dependent floor a small budget is unreachable: the corner alone would be
/// refined to the floor.
pub fn min_length_for(scene: &FlatlandScene, target: usize) -> f64 {
    scene.total_length() / target.max(1) as f64
}

/// Runs HR with `base` (its `epsilon` is ignored) at the ε that gives `target` links within
/// `max(rel_tol · target, 1)`; see the module docs.
pub fn solve_for_links(
    scene: &FlatlandScene,
    target: usize,
    base: FlatHrConfig,
    rel_tol: f64,
) -> Result<BudgetResult> {
    base.validate()?;
    let (mut e_max, mut rho_max) = (0.0f64, 0.0f64);
    for s in &scene.segments {
        e_max = e_max.max(s.emission.max());
        rho_max = rho_max.max(s.rho.max());
    }
    let (hr, epsilon, solves) = search(
        target,
        rel_tol,
        e_max,
        rho_max,
        base.max_links,
        |eps| {
            FlatHr::solve(
                scene,
                FlatHrConfig {
                    epsilon: eps,
                    ..base
                },
            )
        },
        FlatHr::link_count,
    )?;
    Ok(BudgetResult {
        hr,
        epsilon,
        solves,
    })
}

/// A 3-D solution at a link budget.
#[derive(Debug)]
pub struct TriBudgetResult {
    /// The solution.
    pub hr: TriHr,
    /// The ε that produced it.
    pub epsilon: f64,
    /// Number of complete HR solutions the search made.
    pub solves: usize,
}

/// The default minimum patch area for a budget of `target` links in 3-D: the total scene area over the
/// target (no patch finer than a uniform mesh with as many elements as there are links).
pub fn min_area_for(scene: &Scene, target: usize) -> f64 {
    scene.total_area() / target.max(1) as f64
}

/// [`solve_for_links`] for 3-D HR on triangles. The initial linking of all facing triangle pairs sets a
/// lower bound on the count: smaller budgets are errors ([`HrError::BudgetNotReached`]).
pub fn solve_tri_for_links(
    scene: &Scene,
    target: usize,
    base: TriHrConfig,
    rel_tol: f64,
) -> Result<TriBudgetResult> {
    base.validate()?;
    let (mut e_max, mut rho_max) = (0.0f64, 0.0f64);
    for f in &scene.faces {
        e_max = e_max.max(f.emission.max());
        rho_max = rho_max.max(f.rho.max());
    }
    let (hr, epsilon, solves) = search(
        target,
        rel_tol,
        e_max,
        rho_max,
        base.max_links,
        |eps| {
            TriHr::solve(
                scene,
                TriHrConfig {
                    epsilon: eps,
                    ..base
                },
            )
        },
        TriHr::link_count,
    )?;
    Ok(TriBudgetResult {
        hr,
        epsilon,
        solves,
    })
}

/// The search of the module docs, for any solver: `solve(ε)` runs HR, `count` reads its link count. Returns
/// the solution, its ε and the number of solves.
fn search<T>(
    target: usize,
    rel_tol: f64,
    e_max: f64,
    rho_max: f64,
    max_links: usize,
    mut solve: impl FnMut(f64) -> Result<T>,
    count: impl Fn(&T) -> usize,
) -> Result<(T, f64, usize)> {
    if target == 0 {
        return Err(HrError::InvalidParameter {
            name: "target",
            value: 0.0,
            reason: "must be ≥ 1",
        });
    }
    if !(rel_tol.is_finite() && rel_tol >= 0.0) {
        return Err(HrError::InvalidParameter {
            name: "rel_tol",
            value: rel_tol,
            reason: "must be finite and ≥ 0",
        });
    }
    let tol = (rel_tol * target as f64).max(1.0);
    let mut solves = 0usize;
    let mut best: Option<(usize, f64, T)> = None;
    let mut eval = |eps: f64, best: &mut Option<(usize, f64, T)>| -> Result<usize> {
        solves += 1;
        match solve(eps) {
            Ok(hr) => {
                let n = count(&hr);
                let d = n.abs_diff(target);
                if best
                    .as_ref()
                    .is_none_or(|(bn, _, _)| d < bn.abs_diff(target))
                {
                    *best = Some((n, eps, hr));
                }
                Ok(n)
            }
            Err(HrError::LinkLimit { .. }) => Ok(usize::MAX),
            Err(e) => Err(e),
        }
    };
    let done = |n: usize| n != usize::MAX && (n.abs_diff(target) as f64) <= tol;
    // an ε above every possible ρ·F·B: F ≤ 1 and B ≤ max E / (1 − max ρ)
    let mut hi = 2.0 * e_max / (1.0 - rho_max);
    let n_hi = eval(hi, &mut best)?;
    if !done(n_hi) && n_hi < target {
        let mut lo = hi;
        let mut n_lo = n_hi;
        for _ in 0..30 {
            lo *= 0.1;
            n_lo = eval(lo, &mut best)?;
            if n_lo >= target || done(n_lo) {
                break;
            }
            hi = lo;
        }
        if !done(n_lo) && n_lo > target {
            for _ in 0..60 {
                let mid = (lo * hi).sqrt();
                let n = eval(mid, &mut best)?;
                if done(n) {
                    break;
                }
                if n > target {
                    lo = mid;
                } else {
                    hi = mid;
                }
                if hi / lo < 1.0 + 1e-9 {
                    break;
                }
            }
        }
    }
    let Some((n, eps, hr)) = best else {
        return Err(HrError::LinkLimit {
            limit: max_links,
            epsilon: hi,
        });
    };
    if !done(n) {
        return Err(HrError::BudgetNotReached {
            target,
            tolerance_percent: 100.0 * rel_tol,
            closest: n,
            epsilon: eps,
        });
    }
    Ok((hr, eps, solves))
}

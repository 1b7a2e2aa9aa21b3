//! Flatland hierarchical radiosity: form factors against quadrature, the furnace, the link budget, convergence
//! against a fine uniform mesh, and errors on bad input.

use baselines::hierarchical::strings::{Piece, form_factor, geometry_term};
use baselines::hierarchical::*;
use glam::DVec2;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use scene_sampler::{FlatlandScene, Segment, Spectrum, builtin};

/// `(1/L_i) ∫_i ∫_j G` by the composite midpoint rule with `n × n` points (independent of crossed strings).
fn quadrature(i: &Piece, j: &Piece, n: usize) -> f64 {
    let (li, lj) = (i.length(), j.length());
    let mut sum = 0.0;
    for a in 0..n {
        let x = i.a + (i.b - i.a) * ((a as f64 + 0.5) / n as f64);
        for b in 0..n {
            let y = j.a + (j.b - j.a) * ((b as f64 + 0.5) / n as f64);
            sum += geometry_term(x, i.normal, y, j.normal);
        }
    }
    sum * (li / n as f64) * (lj / n as f64) / li
}

/// Distance between two segments (0 if they cross).
fn seg_distance(i: &Piece, j: &Piece) -> f64 {
    let pt = |p: DVec2, s: &Piece| {
        let d = s.b - s.a;
        let t = ((p - s.a).dot(d) / d.length_squared()).clamp(0.0, 1.0);
        (s.a + d * t - p).length()
    };
    let side = |p: DVec2, s: &Piece| (s.b - s.a).perp_dot(p - s.a);
    if side(i.a, j) * side(i.b, j) < 0.0 && side(j.a, i) * side(j.b, i) < 0.0 {
        return 0.0;
    }
    pt(i.a, j).min(pt(i.b, j)).min(pt(j.a, i)).min(pt(j.b, i))
}

#[test]
fn crossed_strings_match_quadrature_and_reciprocity() {
    let mut rng = ChaCha8Rng::seed_from_u64(7);
    let mut partial = 0;
    let mut checked = 0;
    while checked < 12 {
        let p = |rng: &mut ChaCha8Rng| {
            DVec2::new(rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0))
        };
        let i = Piece::new(p(&mut rng), p(&mut rng), 0);
        let j = Piece::new(p(&mut rng), p(&mut rng), 1);
        // keep the pairs well separated (the midpoint rule needs a bounded integrand)
        if seg_distance(&i, &j) < 0.3 || i.length() < 0.2 || j.length() < 0.2 {
            continue;
        }
        let f = form_factor(&i, &j);
        let fq = quadrature(&i, &j, 1200);
        assert!(
            (f - fq).abs() <= 2e-4 * fq.max(1e-2),
            "crossed strings {f} vs quadrature {fq} for {i:?} {j:?}"
        );
        let g = form_factor(&j, &i);
        assert!((i.length() * f - j.length() * g).abs() <= 1e-12 * (1.0 + i.length() * f));
        // one end of j behind i's line (or vice versa): the clipped case
        let behind = |a: &Piece, b: &Piece| {
            let s0 = a.normal.dot(b.a - a.a);
            let s1 = a.normal.dot(b.b - a.a);
            s0 * s1 < 0.0
        };
        if f > 0.0 && (behind(&i, &j) || behind(&j, &i)) {
            partial += 1;
        }
        checked += 1;
    }
    assert!(
        partial >= 2,
        "only {partial} clipped configurations were tested"
    );
}

fn seg(a: (f64, f64), b: (f64, f64), rho: f64, e: f64, i: u32) -> Segment {
    Segment::new(
        DVec2::new(a.0, a.1),
        DVec2::new(b.0, b.1),
        Spectrum::grey(rho),
        Spectrum::grey(e),
        i,
        i,
    )
}

/// A closed convex polygon (counter-clockwise corners, so the left = front side faces inward).
fn closed_room(corners: &[(f64, f64)], rho: f64, e: f64) -> FlatlandScene {
    let n = corners.len();
    let segs = (0..n)
        .map(|k| seg(corners[k], corners[(k + 1) % n], rho, e, k as u32))
        .collect();
    FlatlandScene::new("furnace", "test", segs, vec![], None, false).unwrap()
}

/// Largest `|B − E/(1−ρ)| / (E/(1−ρ))` over the leaves.
fn furnace_error(hr: &FlatHr, want: f64) -> f64 {
    hr.leaves()
        .map(|l| (l.radiosity.0[0] - want).abs() / want)
        .fold(0.0, f64::max)
}

#[test]
fn furnace_gives_e_over_one_minus_rho() {
    for corners in [
        vec![(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)],
        vec![(0.0, 0.0), (2.0, 0.2), (1.5, 1.3), (0.4, 1.0), (-0.3, 0.5)],
    ] {
        let (rho, e) = (0.6, 0.7);
        let want = e / (1.0 - rho);
        let scene = closed_room(&corners, rho, e);
        // no refinement: root links only, each root's form factors sum to 1, so B is exact
        let coarse = FlatHrConfig {
            epsilon: 10.0,
            ..FlatHrConfig::default()
        };
        let hr = FlatHr::solve(&scene, coarse).unwrap();
        assert_eq!(hr.link_count(), corners.len() * (corners.len() - 1));
        assert!(furnace_error(&hr, want) < 1e-9);
        // ε = 0: every link refined down to the finest level, a uniform mesh: exact again
        let full = FlatHrConfig {
            epsilon: 0.0,
            min_length: 0.1,
            ..FlatHrConfig::default()
        };
        let hr = FlatHr::solve(&scene, full).unwrap();
        assert!(hr.leaves().all(|l| l.length < 0.2));
        assert!(furnace_error(&hr, want) < 1e-9);
        // in between, push-pull hands each leaf its ancestors' average transfer, which is not exactly its
        // own: the furnace holds to the discretization error only
        let mid = FlatHrConfig {
            epsilon: 1e-3,
            min_length: 1.0 / 64.0,
            ..FlatHrConfig::default()
        };
        let hr = FlatHr::solve(&scene, mid).unwrap();
        assert!(hr.link_count() > 10 * corners.len());
        let err = furnace_error(&hr, want);
        assert!(err < 1e-2, "furnace error {err}");
    }
}

#[test]
fn link_budget_is_hit_on_both_scenes() {
    for name in ["flatland-corner", "flatland-blocker"] {
        let scene = builtin(name).unwrap().into_flatland().unwrap();
        for target in [16usize, 100, 500] {
            let base = FlatHrConfig {
                min_length: budget::min_length_for(&scene, target),
                ..FlatHrConfig::default()
            };
            let r = solve_for_links(&scene, target, base, 0.05).unwrap();
            let n = r.hr.link_count();
            assert!(
                n.abs_diff(target) as f64 <= (0.05 * target as f64).max(1.0),
                "{name}: {n} links for a budget of {target}"
            );
            assert!(r.hr.stats().converged);
        }
    }
}

/// Classical radiosity on a uniform mesh of `n` elements per segment, form factors by crossed strings, no
/// occlusion (for scenes without blockers); B per element, solved by Jacobi iteration to 1e-13.
fn uniform_mesh(scene: &FlatlandScene, n: usize) -> Vec<(u32, f64, f64, f64)> {
    let mut el = Vec::new();
    for (k, s) in scene.segments.iter().enumerate() {
        for m in 0..n {
            let (t0, t1) = (m as f64 / n as f64, (m + 1) as f64 / n as f64);
            el.push((
                k as u32,
                t0,
                t1,
                Piece::new(s.point(t0), s.point(t1), k as u32),
            ));
        }
    }
    let m = el.len();
    let mut f = vec![0.0; m * m];
    for a in 0..m {
        for b in 0..m {
            if el[a].0 != el[b].0 {
                f[a * m + b] = form_factor(&el[a].3, &el[b].3);
            }
        }
    }
    let rho: Vec<f64> = el
        .iter()
        .map(|e| scene.segments[e.0 as usize].rho.0[0])
        .collect();
    let em: Vec<f64> = el
        .iter()
        .map(|e| scene.segments[e.0 as usize].emission.0[0])
        .collect();
    let mut b = em.clone();
    for _ in 0..1000 {
        let nb: Vec<f64> = (0..m)
            .map(|a| em[a] + rho[a] * (0..m).map(|c| f[a * m + c] * b[c]).sum::<f64>())
            .collect();
        let d = nb
            .iter()
            .zip(&b)
            .map(|(x, y)| (x - y).abs())
            .fold(0.0, f64::max);
        b = nb;
        if d < 1e-13 {
            break;
        }
    }
    el.iter().zip(b).map(|(e, b)| (e.0, e.1, e.2, b)).collect()
}

#[test]
fn converges_to_a_fine_uniform_mesh_as_the_budget_grows() {
    let scene = builtin("flatland-corner").unwrap().into_flatland().unwrap();
    let fine = uniform_mesh(&scene, 256);
    // compare the length-weighted L2 norm of B over the fine elements
    let err = |hr: &FlatHr| {
        let (mut d2, mut r2) = (0.0, 0.0);
        for &(seg, t0, t1, b) in &fine {
            let bh = hr.leaf_at(seg, 0.5 * (t0 + t1)).unwrap().radiosity.0[0];
            d2 += (bh - b) * (bh - b);
            r2 += b * b;
        }
        (d2 / r2).sqrt()
    };
    let mut errs = Vec::new();
    for target in [16usize, 100, 500] {
        let base = FlatHrConfig {
            min_length: budget::min_length_for(&scene, target),
            ..FlatHrConfig::default()
        };
        let r = solve_for_links(&scene, target, base, 0.05).unwrap();
        errs.push(err(&r.hr));
    }
    assert!(errs[0] > errs[1] && errs[1] > errs[2], "errors {errs:?}");
    assert!(errs[2] < 0.02, "errors {errs:?}");
}

#[test]
fn bad_input_is_an_error() {
    let scene = builtin("flatland-corner").unwrap().into_flatland().unwrap();
    for cfg in [
        FlatHrConfig {
            epsilon: f64::NAN,
            ..FlatHrConfig::default()
        },
        FlatHrConfig {
            min_length: 0.0,
            ..FlatHrConfig::default()
        },
        FlatHrConfig {
            visibility_rays: 0,
            ..FlatHrConfig::default()
        },
        FlatHrConfig {
            tolerance: -1.0,
            ..FlatHrConfig::default()
        },
    ] {
        assert!(matches!(
            FlatHr::solve(&scene, cfg),
            Err(HrError::InvalidParameter { .. })
        ));
    }
    let tiny = FlatHrConfig {
        epsilon: 0.0,
        min_length: 1e-6,
        max_links: 50,
        ..FlatHrConfig::default()
    };
    assert!(matches!(
        FlatHr::solve(&scene, tiny),
        Err(HrError::LinkLimit { .. })
    ));
    assert!(solve_for_links(&scene, 0, FlatHrConfig::default(), 0.05).is_err());
    let hr = FlatHr::solve(&scene, FlatHrConfig::default()).unwrap();
    assert!(hr.leaf_at(7, 0.5).is_err());
    assert!(hr.leaf_at(0, 1.5).is_err());
    let off = scene_sampler::FlatPoint {
        point: DVec2::new(0.5, 0.5),
        normal: DVec2::Y,
        segment: 1,
    };
    assert!(hr.radiosity_at(&off).is_err());
}

#[test]
fn refine_rule_splits_every_partially_visible_link_to_the_floor() {
    // flatland-blocker: with ε above every transfer only the partial-visibility rule refines
    let scene = builtin("flatland-blocker")
        .unwrap()
        .into_flatland()
        .unwrap();
    let min_length = budget::min_length_for(&scene, 100);
    let run = |partial| {
        FlatHr::solve(
            &scene,
            FlatHrConfig {
                epsilon: 1e3,
                min_length,
                partial,
                ..FlatHrConfig::default()
            },
        )
        .unwrap()
    };
    let splittable = |hr: &FlatHr, p: u32| 0.5 * hr.patches()[p as usize].length >= min_length;
    let refine = run(PartialVisibility::Refine);
    let bound = run(PartialVisibility::UnoccludedBound);
    assert!(refine.links().iter().any(|l| l.partial));
    for l in refine.links().iter().filter(|l| l.partial) {
        assert!(!splittable(&refine, l.receiver) && !splittable(&refine, l.sender));
    }
    // the default rule judges by ρ·F_u·B, which ε = 1e3 exceeds nowhere: the initial links stay
    assert!(refine.link_count() > bound.link_count());
    assert!(
        bound
            .links()
            .iter()
            .any(|l| l.partial && splittable(&bound, l.receiver))
    );
}

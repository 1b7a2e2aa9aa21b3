//! 3-D hierarchical radiosity on triangles: point-to-polygon form factors against closed forms and quadrature,
//! the furnace, the link budget, agreement with the path tracer, and errors on bad input.

use baselines::hierarchical::polygon::{point_to_polygon, triangle_point, triangle_to_polygon};
use baselines::hierarchical::*;
use baselines::pointwise;
use glam::DVec3;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use scene_sampler::builtin::furnace;
use scene_sampler::{Scene, SceneBvh, Spectrum, SurfacePoint, builtin};

/// Differential area at the origin (normal +z) to the rectangle `[0,a]×[0,b]` at height `c`, facing down
/// (the classical closed form, e.g. Howell's catalogue of configuration factors, B-3).
fn parallel_rectangle(a: f64, b: f64, c: f64) -> f64 {
    let (x, y) = (a / c, b / c);
    let (sx, sy) = ((1.0 + x * x).sqrt(), (1.0 + y * y).sqrt());
    (x / sx * (y / sx).atan() + y / sy * (x / sy).atan()) / (2.0 * std::f64::consts::PI)
}

#[test]
fn point_to_polygon_matches_the_closed_form() {
    for (a, b, c) in [(1.0, 1.0, 1.0), (0.3, 2.0, 0.7), (5.0, 0.1, 0.2)] {
        // the rectangle wound so that its normal is −z (toward the point)
        let quad = [
            DVec3::new(0.0, 0.0, c),
            DVec3::new(0.0, b, c),
            DVec3::new(a, b, c),
            DVec3::new(a, 0.0, c),
        ];
        let want = parallel_rectangle(a, b, c);
        let f = point_to_polygon(DVec3::ZERO, DVec3::Z, &quad, -DVec3::Z);
        assert!((f - want).abs() < 1e-13, "{f} vs {want}");
        // as two triangles
        let t0 = [quad[0], quad[1], quad[2]];
        let t1 = [quad[0], quad[2], quad[3]];
        let f2 = point_to_polygon(DVec3::ZERO, DVec3::Z, &t0, -DVec3::Z)
            + point_to_polygon(DVec3::ZERO, DVec3::Z, &t1, -DVec3::Z);
        assert!((f2 - want).abs() < 1e-13);
        // seen from behind: nothing
        assert_eq!(
            point_to_polygon(DVec3::ZERO, DVec3::Z, &quad, DVec3::Z),
            0.0
        );
    }
}

/// `(1/A_r) ∫_r ∫_s cos⁺ cos⁺ / (π r²)` by the midpoint rule on `4^k` sub-triangles of each.
fn brute_force(r: &[DVec3; 3], nr: DVec3, s: &[DVec3; 3], ns: DVec3, k: u32) -> f64 {
    fn split(t: [DVec3; 3], k: u32, out: &mut Vec<(DVec3, f64)>) {
        if k == 0 {
            let a = 0.5 * (t[1] - t[0]).cross(t[2] - t[0]).length();
            out.push(((t[0] + t[1] + t[2]) / 3.0, a));
            return;
        }
        let (ab, bc, ca) = (
            (t[0] + t[1]) * 0.5,
            (t[1] + t[2]) * 0.5,
            (t[2] + t[0]) * 0.5,
        );
        for c in [[t[0], ab, ca], [ab, t[1], bc], [ca, bc, t[2]], [ab, bc, ca]] {
            split(c, k - 1, out);
        }
    }
    let (mut pr, mut ps) = (Vec::new(), Vec::new());
    split(*r, k, &mut pr);
    split(*s, k, &mut ps);
    let ar: f64 = pr.iter().map(|p| p.1).sum();
    let mut sum = 0.0;
    for &(x, ax) in &pr {
        for &(y, ay) in &ps {
            let d = y - x;
            let r2 = d.length_squared();
            let (cx, cy) = (nr.dot(d).max(0.0), (-ns.dot(d)).max(0.0));
            sum += cx * cy / (r2 * r2) * ax * ay;
        }
    }
    sum / (std::f64::consts::PI * ar)
}

#[test]
fn triangle_to_polygon_matches_quadrature_with_both_clippings() {
    // receiver on the floor (normal +y), crossing the sender's plane x = 0.5; sender in that plane (normal −x),
    // reaching below the floor; the two never touch (z ranges apart)
    let r = [
        DVec3::new(0.0, 0.0, 0.0),
        DVec3::new(0.0, 0.0, 1.0),
        DVec3::new(1.0, 0.0, 0.0),
    ];
    let s = [
        DVec3::new(0.5, -0.3, 1.3),
        DVec3::new(0.5, 0.2, 2.3),
        DVec3::new(0.5, 1.0, 1.5),
    ];
    let (nr, ns) = (DVec3::Y, -DVec3::X);
    let f = triangle_to_polygon(&r, nr, &s, ns);
    let q = brute_force(&r, nr, &s, ns, 5);
    assert!(f > 0.0 && (f - q).abs() < 2e-3 * q, "{f} vs quadrature {q}");
    // a well separated, unclipped pair: the degree-2 rule is much closer still
    let s2 = s.map(|p| p + DVec3::new(0.0, 0.4, 0.0));
    let f2 = triangle_to_polygon(&r, nr, &s2, ns);
    let q2 = brute_force(&r, nr, &s2, ns, 5);
    assert!((f2 - q2).abs() < 2e-3 * q2, "{f2} vs quadrature {q2}");
}

#[test]
fn form_factors_of_an_enclosure_sum_to_one() {
    let scene = furnace(Spectrum::grey(1.0), Spectrum::grey(0.5));
    for (i, r) in scene.faces.iter().enumerate() {
        let sum: f64 = scene
            .faces
            .iter()
            .enumerate()
            .filter(|(j, _)| *j != i)
            .map(|(_, s)| triangle_to_polygon(&r.v, r.normal, &s.v, s.normal))
            .sum();
        assert!((sum - 1.0).abs() < 1e-12, "face {i}: {sum}");
    }
}

fn furnace_error(hr: &TriHr, want: f64) -> f64 {
    hr.leaves()
        .map(|l| (l.radiosity.0[0] - want).abs() / want)
        .fold(0.0, f64::max)
}

#[test]
fn furnace_gives_e_over_one_minus_rho() {
    let (e, rho) = (0.7, 0.6);
    let want = e / (1.0 - rho);
    let scene = furnace(Spectrum::grey(e), Spectrum::grey(rho));
    let tight = TriHrConfig {
        tolerance: 1e-13,
        ..TriHrConfig::default()
    };
    // root links only: every receiver's factors sum to one and nothing is occluded
    let coarse = TriHr::solve(
        &scene,
        TriHrConfig {
            epsilon: 100.0,
            ..tight
        },
    )
    .unwrap();
    assert!(coarse.link_count() >= 10 * 12);
    assert!(coarse.links().iter().all(|l| l.visibility == 1.0));
    let err = furnace_error(&coarse, want);
    assert!(err < 1e-9, "{err}");
    // the final gather at any point: exact point-to-polygon factors summing to one
    let mut rng = ChaCha8Rng::seed_from_u64(5);
    for k in 0..10 {
        let i = rng.random_range(0..scene.faces.len());
        let f = &scene.faces[i];
        let p = SurfacePoint {
            point: triangle_point(&f.v, [rng.random(), rng.random()]),
            normal: f.normal,
            face: i as u32,
        };
        let b = coarse.gather_at(&p, 4, k).unwrap().0[0];
        assert!((b - want).abs() < 1e-9 * want, "gather {b} vs {want}");
    }
    // ε = 0: uniform refinement to the floor, exact again
    let full = TriHr::solve(
        &scene,
        TriHrConfig {
            epsilon: 0.0,
            min_area: 0.5 / 16.0,
            ..tight
        },
    )
    .unwrap();
    assert!(full.leaves().all(|l| l.area <= 0.5 / 4.0 + 1e-12));
    let err = furnace_error(&full, want);
    assert!(err < 1e-9, "{err}");
    // adaptive: push-pull hands each leaf its ancestors' transfer, computed for the ancestor's area, so the
    // furnace holds only to the discretization error, which falls with ε (near the cube's edges and corners,
    // where the BF oracle refines, a leaf sees less of the far walls than its ancestors do)
    let leaf_errors = |eps: f64| {
        let hr = TriHr::solve(
            &scene,
            TriHrConfig {
                epsilon: eps,
                min_area: 0.5 / 256.0,
                ..tight
            },
        )
        .unwrap();
        let (mut area, mut l1) = (0.0, 0.0);
        for l in hr.leaves() {
            area += l.area;
            l1 += l.area * (l.radiosity.0[0] / want - 1.0).abs();
        }
        (furnace_error(&hr, want), l1 / area, hr.link_count())
    };
    let (max_a, l1_a, n_a) = leaf_errors(0.05);
    let (max_b, l1_b, n_b) = leaf_errors(0.01);
    assert!(n_a > 2 * coarse.link_count() && n_b > n_a);
    assert!(
        max_b < max_a && l1_b < l1_a,
        "{max_a} {l1_a} → {max_b} {l1_b}"
    );
    assert!(l1_a < 0.1 && l1_b < 0.05, "{l1_a} {l1_b}");
}

fn cornell() -> Scene {
    builtin("cornell-box").unwrap().into_3d().unwrap()
}

#[test]
fn link_budget_is_hit_on_the_cornell_box() {
    let scene = cornell();
    for target in [3000usize, 10_000] {
        let base = TriHrConfig {
            min_area: budget::min_area_for(&scene, target),
            ..TriHrConfig::default()
        };
        let r = solve_tri_for_links(&scene, target, base, 0.05).unwrap();
        let n = r.hr.link_count();
        assert!(
            n.abs_diff(target) as f64 <= 0.05 * target as f64,
            "{n} links for a budget of {target}"
        );
        assert!(r.hr.stats().converged);
    }
    // below the initial linking: unreachable, and said so
    let base = TriHrConfig {
        min_area: budget::min_area_for(&scene, 100),
        ..TriHrConfig::default()
    };
    assert!(matches!(
        solve_tri_for_links(&scene, 100, base, 0.05),
        Err(HrError::BudgetNotReached { .. })
    ));
}

#[test]
fn cornell_box_agrees_with_the_path_tracer_on_average() {
    // random non-emitting points; HR's constant leaves are not exact pointwise, but their bias is small
    let scene = cornell();
    let bvh = SceneBvh::new(&scene);
    let mut rng = ChaCha8Rng::seed_from_u64(11);
    let mut points = Vec::new();
    while points.len() < 24 {
        let i = rng.random_range(0..scene.faces.len());
        let f = &scene.faces[i];
        if f.emission.is_zero() {
            points.push(SurfacePoint {
                point: triangle_point(&f.v, [rng.random(), rng.random()]),
                normal: f.normal,
                face: i as u32,
            });
        }
    }
    let reference = pointwise::radiosity_at(&scene, &bvh, &points, 20_000, 3);
    let hr = TriHr::solve(
        &scene,
        TriHrConfig {
            epsilon: 0.03,
            min_area: scene.total_area() / 20_000.0,
            visibility_rays: 32,
            ..TriHrConfig::default()
        },
    )
    .unwrap();
    let (mut sum_hr, mut sum_ref, mut d2, mut n2) = (0.0, 0.0, 0.0, 0.0);
    for (p, e) in points.iter().zip(&reference) {
        let b = hr.radiosity_at(p).unwrap();
        for k in 0..3 {
            sum_hr += b.0[k];
            sum_ref += e.mean[k];
            d2 += (b.0[k] - e.mean[k]).powi(2);
            n2 += e.mean[k].powi(2);
        }
    }
    let bias = sum_hr / sum_ref - 1.0;
    let l2 = (d2 / n2).sqrt();
    assert!(bias.abs() < 0.05, "mean bias {bias}");
    assert!(l2 < 0.2, "relative L2 {l2}");
}

#[test]
fn bad_input_is_an_error() {
    let scene = furnace(Spectrum::grey(1.0), Spectrum::grey(0.5));
    for cfg in [
        TriHrConfig {
            epsilon: -1.0,
            ..TriHrConfig::default()
        },
        TriHrConfig {
            min_area: f64::NAN,
            ..TriHrConfig::default()
        },
        TriHrConfig {
            visibility_rays: 0,
            ..TriHrConfig::default()
        },
        TriHrConfig {
            max_iterations: 0,
            ..TriHrConfig::default()
        },
    ] {
        assert!(matches!(
            TriHr::solve(&scene, cfg),
            Err(HrError::InvalidParameter { .. })
        ));
    }
    let tiny = TriHrConfig {
        epsilon: 0.0,
        min_area: 1e-6,
        max_links: 500,
        ..TriHrConfig::default()
    };
    assert!(matches!(
        TriHr::solve(&scene, tiny),
        Err(HrError::LinkLimit { .. })
    ));
    assert!(solve_tri_for_links(&scene, 0, TriHrConfig::default(), 0.05).is_err());
    let hr = TriHr::solve(&scene, TriHrConfig::default()).unwrap();
    assert!(hr.leaf_at(99, DVec3::ZERO).is_err());
    assert!(hr.leaf_at(0, DVec3::NAN).is_err());
    let off = SurfacePoint {
        point: DVec3::splat(0.5),
        normal: DVec3::Y,
        face: 0,
    };
    assert!(hr.radiosity_at(&off).is_err());
    assert!(hr.gather_at(&off, 4, 0).is_err());
    let on = SurfacePoint {
        point: scene.faces[0].centroid(),
        normal: scene.faces[0].normal,
        face: 0,
    };
    assert!(hr.gather_at(&on, 0, 0).is_err());
    assert!(hr.gather_at(&on, 4, 0).is_ok());
}

//! Area-uniformity of the parameterizations (fig. B.2), their inverses, and the direction samplers.

use glam::{DVec2, DVec3};
use proptest::prelude::*;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use scene_sampler::*;

fn cornell() -> Scene {
    builtin("cornell-box").unwrap().into_3d().unwrap()
}

/// Pearson χ² statistic of `counts` against expected probabilities `p`.
fn chi2(counts: &[f64], p: &[f64], n: f64) -> f64 {
    counts
        .iter()
        .zip(p)
        .map(|(&c, &p)| (c - n * p).powi(2) / (n * p))
        .sum()
}

/// Face frequencies match area fractions, and within each face the four midpoint sub-triangles get a quarter
/// each (χ² tests at fixed seed; the bound is dof + 6·sqrt(2·dof), far in the tail of χ²).
#[test]
fn area_uniform_over_faces_and_within() {
    let scene = cornell();
    let s = SurfaceSampler::new(&scene);
    let nf = scene.faces.len();
    let mut counts = vec![0.0; nf];
    let mut sub = vec![[0.0; 4]; nf];
    let mut rng = ChaCha8Rng::seed_from_u64(11);
    let n = 400_000;
    for _ in 0..n {
        let p = s.sample([rng.random(), rng.random()]);
        let f = &scene.faces[p.face as usize];
        assert!((p.point - f.closest_point(p.point)).length() < 1e-12);
        assert_eq!(p.normal, f.normal);
        counts[p.face as usize] += 1.0;
        let (b1, b2) = scene_sampler::sample::barycentric(f.v, p.point);
        let b0 = 1.0 - b1 - b2;
        let k = if b0 > 0.5 {
            0
        } else if b1 > 0.5 {
            1
        } else if b2 > 0.5 {
            2
        } else {
            3
        };
        sub[p.face as usize][k] += 1.0;
    }
    let total = scene.total_area();
    let p: Vec<f64> = scene.faces.iter().map(|f| f.area / total).collect();
    let c = chi2(&counts, &p, n as f64);
    let dof = (nf - 1) as f64;
    assert!(
        c < dof + 6.0 * (2.0 * dof).sqrt(),
        "faces χ² = {c}, dof {dof}"
    );
    let mut c_sub = 0.0;
    for (i, q) in sub.iter().enumerate() {
        c_sub += chi2(q, &[0.25; 4], counts[i]);
    }
    let dof = (3 * nf) as f64;
    assert!(
        c_sub < dof + 6.0 * (2.0 * dof).sqrt(),
        "sub-triangle χ² = {c_sub}, dof {dof}"
    );
}

#[test]
fn flatland_arc_length_uniform() {
    let scene = builtin("flatland-blocker")
        .unwrap()
        .into_flatland()
        .unwrap();
    let s = FlatSampler::new(&scene);
    let mut counts = vec![0.0; scene.segments.len()];
    let mut halves = vec![[0.0; 2]; scene.segments.len()];
    let mut rng = ChaCha8Rng::seed_from_u64(3);
    let n = 100_000;
    for _ in 0..n {
        let p = s.sample(rng.random());
        let seg = &scene.segments[p.segment as usize];
        counts[p.segment as usize] += 1.0;
        halves[p.segment as usize][usize::from(seg.closest_t(p.point) > 0.5)] += 1.0;
    }
    let p: Vec<f64> = scene
        .segments
        .iter()
        .map(|g| g.length / scene.total_length())
        .collect();
    let c = chi2(&counts, &p, n as f64);
    assert!(c < 3.0 + 6.0 * 6f64.sqrt(), "χ² {c}");
    for (i, h) in halves.iter().enumerate() {
        let c = chi2(h, &[0.5, 0.5], counts[i]);
        assert!(c < 1.0 + 6.0 * 2f64.sqrt());
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]
    /// The guide-table search returns the face a full binary search returns, for wildly uneven areas.
    #[test]
    fn guide_table_matches_binary_search(areas in prop::collection::vec(-6.0f64..1.0, 1..60), us in prop::collection::vec(0.0f64..=1.0, 50)) {
        let faces: Vec<Face> = areas.iter().enumerate().map(|(i, &a)| {
            let s = 10f64.powf(a);
            let o = DVec3::new(i as f64, 0.0, 0.0);
            Face::new([o, o + DVec3::X * s, o + DVec3::Y], Spectrum::grey(0.5), Spectrum::ONE, 0, i as u32)
        }).collect();
        let scene = Scene::new("t", "t", faces, vec![], None).unwrap();
        let s = SurfaceSampler::new(&scene);
        let total = scene.total_area();
        let mut cdf = vec![0.0];
        let mut acc = 0.0;
        for f in &scene.faces { acc += f.area; cdf.push(acc / total); }
        let n = scene.faces.len();
        *cdf.last_mut().unwrap() = 1.0;
        let mut edge: Vec<f64> = cdf.clone();
        edge.extend(cdf.iter().map(|c| c - 1e-17));
        for &u in us.iter().chain(edge.iter().filter(|u| (0.0..=1.0).contains(*u))) {
            let want = (cdf.partition_point(|&c| c <= u).saturating_sub(1)).min(n - 1);
            prop_assert_eq!(s.face_of(u), want, "u = {}", u);
        }
    }

    #[test]
    fn surface_inverse_roundtrip(u in 0.0f64..1.0, v in 0.001f64..0.999) {
        let scene = cornell();
        let s = SurfaceSampler::new(&scene);
        let p = s.sample([u, v]);
        let w = s.inverse(p.face, p.point);
        // interior of a face: exact up to rounding
        prop_assert!((w[0] - u).abs() < 1e-9, "{u} -> {}", w[0]);
        prop_assert!((w[1] - v).abs() < 1e-6, "{v} -> {}", w[1]);
    }

    #[test]
    fn flat_inverse_roundtrip(u in 0.0f64..1.0) {
        let scene = builtin("flatland-corner").unwrap().into_flatland().unwrap();
        let s = FlatSampler::new(&scene);
        let p = s.sample(u);
        prop_assert!((s.inverse(p.segment, p.point) - u).abs() < 1e-12);
    }

    #[test]
    fn hemisphere_directions(n in prop::array::uniform3(-1.0f64..1.0), u in prop::array::uniform2(0.0f64..1.0)) {
        let n = DVec3::from(n);
        prop_assume!(n.length() > 0.1);
        let n = n.normalize();
        let d = cosine_hemisphere(n, u);
        prop_assert!((d.length() - 1.0).abs() < 1e-12);
        prop_assert!(d.dot(n) >= -1e-12);
        let (t, b) = orthonormal_basis(n);
        prop_assert!(t.dot(n).abs() < 1e-12 && b.dot(n).abs() < 1e-12 && t.dot(b).abs() < 1e-12);
    }

    /// A cone's directions are unit without renormalising (`uniform_cone_about`) and within its
    /// half-angle, for a sun's 0.27° as for wide cones.
    #[test]
    fn cone_directions(a in prop::array::uniform3(-1.0f64..1.0), u in prop::array::uniform2(0.0f64..1.0), half_deg in prop::sample::select(vec![0.265, 5.0, 60.0, 179.0])) {
        let a = DVec3::from(a);
        prop_assume!(a.length() > 0.1);
        let a = a.normalize();
        let omc = 2.0 * (f64::to_radians(half_deg) / 2.0).sin().powi(2);
        let d = uniform_cone(a, omc, u);
        prop_assert!((d.length() - 1.0).abs() < 1e-12, "{}", d.length());
        prop_assert!(1.0 - d.dot(a) <= omc * (1.0 + 1e-9) + 1e-15);
        prop_assert_eq!(d, uniform_cone_about((a, orthonormal_basis(a)), omc, u));
    }
}

/// Cosine-weighted density: E[cos θ] = 2/3 (3-D, density cos θ/π), E[cos θ] = π/4 (Flatland, density cos θ/2).
#[test]
fn cosine_sampling_moments() {
    let mut rng = ChaCha8Rng::seed_from_u64(9);
    let n = DVec3::new(0.3, -0.5, 0.8).normalize();
    let m = 200_000;
    let mean: f64 = (0..m)
        .map(|_| cosine_hemisphere(n, [rng.random(), rng.random()]).dot(n))
        .sum::<f64>()
        / m as f64;
    assert!((mean - 2.0 / 3.0).abs() < 3e-3, "{mean}");
    let n2 = DVec2::new(-0.6, 0.8);
    let mean2: f64 = (0..m)
        .map(|_| cosine_halfplane(n2, rng.random()).dot(n2))
        .sum::<f64>()
        / m as f64;
    assert!((mean2 - std::f64::consts::PI / 4.0).abs() < 3e-3, "{mean2}");
}

/// `spread` keeps the R2 points `keep` accepts, in sequence order, and stops at `count`.
#[test]
fn spread_points_are_the_kept_r2_points_in_order() {
    let scene = cornell();
    let sampler = SurfaceSampler::new(&scene);
    let dark = |p: &SurfacePoint| scene.faces[p.face as usize].emission.is_zero();
    let points = sampler.spread(50, dark);
    assert_eq!(points.len(), 50);
    let by_hand: Vec<_> = (1..)
        .map(|i: u64| {
            sampler.sample([
                (i as f64 * 0.754_877_666_246_692_7).fract(),
                (i as f64 * 0.569_840_290_998_053_3).fract(),
            ])
        })
        .filter(dark)
        .take(50)
        .collect();
    assert_eq!(points, by_hand);
    // Nothing accepted: the search stops after 100·count tries.
    assert!(sampler.spread(5, |_| false).is_empty());
}

//! BVH visibility and closest hit against brute force on random triangle soups; Flatland ray casting.

use glam::{DVec2, DVec3};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use scene_sampler::*;

fn soup(n: usize, seed: u64) -> Scene {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut r = || DVec3::new(rng.random(), rng.random(), rng.random());
    let faces = (0..n)
        .map(|i| {
            let c = r();
            let v = [
                c + (r() - 0.5) * 0.3,
                c + (r() - 0.5) * 0.3,
                c + (r() - 0.5) * 0.3,
            ];
            Face::new(
                v,
                Spectrum::grey(0.5),
                Spectrum::grey(if i == 0 { 1.0 } else { 0.0 }),
                0,
                i as u32,
            )
        })
        .collect();
    Scene::new("soup", "soup", faces, vec![], None).unwrap()
}

/// f64 Möller–Trumbore: parameter t of the hit and the smallest barycentric margin (how far inside the edges).
fn hit64(f: &Face, o: DVec3, d: DVec3) -> Option<(f64, f64)> {
    let e1 = f.v[1] - f.v[0];
    let e2 = f.v[2] - f.v[0];
    let p = d.cross(e2);
    let det = e1.dot(p);
    if det.abs() < 1e-300 {
        return None;
    }
    let s = o - f.v[0];
    let u = s.dot(p) / det;
    let q = s.cross(e1);
    let v = d.dot(q) / det;
    let t = e2.dot(q) / det;
    let margin = u.min(v).min(1.0 - u - v);
    Some((t, margin))
}

#[test]
fn occlusion_matches_brute_force() {
    let scene = soup(300, 1);
    let bvh = SceneBvh::new(&scene);
    let mut rng = ChaCha8Rng::seed_from_u64(2);
    let (mut checked, mut blocked) = (0, 0);
    for _ in 0..20_000 {
        let a = DVec3::new(rng.random(), rng.random(), rng.random()) * 1.4 - 0.2;
        let b = DVec3::new(rng.random(), rng.random(), rng.random()) * 1.4 - 0.2;
        let d = b - a;
        let len = d.length();
        let mut ambiguous = false;
        let mut occluded = false;
        for f in &scene.faces {
            if let Some((t, margin)) = hit64(f, a, d) {
                let near_edge = margin.abs() < 1e-4;
                let near_end = (t * len).abs() < 1e-3 || ((1.0 - t) * len).abs() < 1e-3;
                if margin >= 0.0 && t > 0.0 && t < 1.0 {
                    occluded = true;
                    ambiguous |= near_edge || near_end;
                } else if (near_edge && t > -1e-3 && t < 1.0 + 1e-3) || (margin >= 0.0 && near_end)
                {
                    ambiguous = true;
                }
            }
        }
        if ambiguous {
            continue;
        }
        checked += 1;
        blocked += usize::from(occluded);
        assert_eq!(
            bvh.segment_clear(a, b, u32::MAX, u32::MAX),
            !occluded,
            "segment {a} -> {b}"
        );
    }
    assert!(
        checked > 18_000 && blocked > 1000 && blocked < checked - 1000,
        "{checked} {blocked}"
    );
}

#[test]
fn closest_hit_matches_brute_force() {
    let scene = soup(300, 4);
    for quality in [BuildQuality::High, BuildQuality::Medium] {
        let bvh = SceneBvh::with_quality(&scene, quality);
        let mut rng = ChaCha8Rng::seed_from_u64(5);
        let mut hits = 0;
        for _ in 0..20_000 {
            let o = DVec3::new(rng.random(), rng.random(), rng.random()) * 1.4 - 0.2;
            let d = DVec3::new(
                rng.random::<f64>() - 0.5,
                rng.random::<f64>() - 0.5,
                rng.random::<f64>() - 0.5,
            );
            if d.length() < 1e-3 {
                continue;
            }
            let mut cands: Vec<(f64, usize, f64)> = scene
                .faces
                .iter()
                .enumerate()
                .filter_map(|(i, f)| hit64(f, o, d).map(|(t, m)| (t, i, m)))
                .filter(|&(t, _, m)| t > -1e-4 && m > -1e-4)
                .collect();
            cands.sort_by(|a, b| a.0.total_cmp(&b.0));
            let got = bvh.closest_hit(o, d, f64::INFINITY, u32::MAX);
            let ambiguous = cands
                .iter()
                .any(|&(t, _, m)| m.abs() < 1e-4 || t.abs() < 1e-3)
                || (cands.len() >= 2 && (cands[1].0 - cands[0].0) * d.length() < 1e-4);
            if ambiguous {
                continue;
            }
            let want = cands.first().filter(|c| c.2 >= 0.0 && c.0 > 0.0);
            match (got, want) {
                (None, None) => {}
                (Some(h), Some(&(t, i, _))) => {
                    hits += 1;
                    assert_eq!(h.face as usize, i);
                    assert!((h.t - t).abs() < 1e-4 * (1.0 + t), "t {} vs {t}", h.t);
                    assert!((h.point - (o + d * t)).length() < 1e-4);
                }
                (g, w) => panic!("bvh {g:?} vs brute force {w:?}"),
            }
        }
        assert!(hits > 5000, "{hits}");
    }
}

/// Points on surfaces: a point sees another on the same plane region (adjacent triangles of one quad do not
/// self-occlude), and the Cornell blocks occlude as expected.
#[test]
fn self_intersection_policy() {
    let scene = builtin("cornell-box").unwrap().into_3d().unwrap();
    let bvh = SceneBvh::new(&scene);
    let s = SurfaceSampler::new(&scene);
    let mut rng = ChaCha8Rng::seed_from_u64(8);
    // the light (faces 2, 3) sees the floor point straight below the centre of the room's front part
    let floor_pt = SurfacePoint {
        point: DVec3::new(0.278, 0.0, 0.02),
        normal: DVec3::Y,
        face: 0,
    };
    let light_pt = SurfacePoint {
        point: DVec3::new(0.278, 0.5488, 0.28),
        normal: -DVec3::Y,
        face: 2,
    };
    assert!(bvh.visible(&floor_pt, &light_pt));
    // under the short block: not visible
    let under = SurfacePoint {
        point: DVec3::new(0.185, 0.0, 0.17),
        normal: DVec3::Y,
        face: 0,
    };
    assert!(!bvh.visible(&under, &light_pt));
    // near the floor/back-wall corner (z > 0.5 m, y < 0.05 m is empty space): every pair must see each other,
    // down to millimetre distances from the corner line, in single and batched queries
    let mut pairs = Vec::new();
    for _ in 0..2000 {
        let x = DVec3::new(
            rng.random_range(0.01..0.54),
            0.0,
            0.5592 - rng.random::<f64>().powi(4) * 0.05,
        );
        let y = DVec3::new(
            rng.random_range(0.01..0.54),
            rng.random::<f64>().powi(4) * 0.05,
            0.5592,
        );
        let px = scene
            .snap_probe(
                &Probe {
                    point: x,
                    normal: DVec3::Y,
                    line: 0,
                },
                1e-9,
                "t",
            )
            .unwrap();
        let py = scene
            .snap_probe(
                &Probe {
                    point: y,
                    normal: -DVec3::Z,
                    line: 0,
                },
                1e-9,
                "t",
            )
            .unwrap();
        assert!(bvh.visible(&px, &py), "{x} {y}");
        pairs.push((px, py));
        pairs.push((
            s.sample([rng.random(), rng.random()]),
            s.sample([rng.random(), rng.random()]),
        ));
    }
    let batch = bvh.visible_batch(&pairs);
    for (i, (x, y)) in pairs.iter().enumerate() {
        assert_eq!(batch[i], bvh.visible(x, y));
    }
    // trace_from a floor point straight up hits the light or the ceiling
    let h = bvh.trace_from(&floor_pt, DVec3::Y).unwrap();
    assert!((h.point.y - 0.5488).abs() < 1e-6, "{h:?}");
    assert_eq!(bvh.surface_point(&h).normal, -DVec3::Y);
}

#[test]
fn flatland_rays() {
    let scene = builtin("flatland-blocker")
        .unwrap()
        .into_flatland()
        .unwrap();
    let vis = FlatVisibility::new(&scene);
    let light = FlatPoint {
        point: DVec2::new(0.5, 1.0),
        normal: DVec2::new(0.0, -1.0),
        segment: 0,
    };
    let floor_mid = FlatPoint {
        point: DVec2::new(0.5, 0.0),
        normal: DVec2::Y,
        segment: 3,
    };
    let floor_side = FlatPoint {
        point: DVec2::new(0.05, 0.0),
        normal: DVec2::Y,
        segment: 3,
    };
    assert!(!vis.visible(&light, &floor_mid));
    assert!(vis.visible(&light, &floor_side));
    let h = vis.trace_from(&floor_mid, DVec2::Y).unwrap();
    assert_eq!(h.segment, 1); // blocker underside
    assert!((h.t - 0.5).abs() < 1e-12 && (h.point - DVec2::new(0.5, 0.5)).length() < 1e-12);
    assert_eq!(vis.surface_point(&h).normal, DVec2::new(0.0, -1.0));
    assert!(
        vis.closest_hit(DVec2::new(2.0, 2.0), DVec2::X, u32::MAX)
            .is_none()
    );
}

/// A closed box does not leak: cosine-distributed rays from random surface points of the furnace always hit
/// a front face, including rays leaving near edges and corners (the path tracer's bounce query).
#[test]
fn furnace_is_watertight() {
    let scene = builtin("furnace").unwrap().into_3d().unwrap();
    let bvh = SceneBvh::new(&scene);
    let s = SurfaceSampler::new(&scene);
    let mut rng = ChaCha8Rng::seed_from_u64(12);
    for i in 0..100_000 {
        // every 4th point hugs an edge: push u towards the face boundaries
        let mut u: [f64; 2] = [rng.random(), rng.random()];
        if i % 4 == 0 {
            u[1] = 1.0 - 1e-9 * rng.random::<f64>();
        }
        let x = s.sample(u);
        let d = cosine_hemisphere(x.normal, [rng.random(), rng.random()]);
        let h = bvh
            .trace_from(&x, d)
            .unwrap_or_else(|| panic!("ray from {x:?} along {d} escaped"));
        let n = scene.faces[h.face as usize].normal;
        assert!(n.dot(d) < 0.0, "hit a back face from inside the box");
        assert!(
            h.point.cmpge(DVec3::splat(-1e-6)).all()
                && h.point.cmple(DVec3::splat(1.0 + 1e-6)).all()
        );
    }
}

/// Hits and occluders closer than obvhs's absolute node epsilon (1e-4) to the ray origin are still found.
#[test]
fn near_hits_below_obvhs_epsilon() {
    let scene = builtin("furnace").unwrap().into_3d().unwrap();
    let bvh = SceneBvh::new(&scene);
    for dist in [5e-5, 2e-5] {
        let o = DVec3::new(0.5, 0.5, 1.0 - dist);
        let h = bvh
            .closest_hit(o, DVec3::Z, f64::INFINITY, u32::MAX)
            .expect("wall just ahead");
        assert!((h.t - dist).abs() < 1e-6, "t {} vs {dist}", h.t);
        assert!(!bvh.segment_clear(o, o + DVec3::Z * 1e-3, u32::MAX, u32::MAX));
    }
}

/// A two-sided thin wall is two coincident faces with opposite normals; a ray must land on the
/// one that faces it, from either side (else light onto thin geometry is lost: the back face
/// has a zero kernel).
#[test]
fn coincident_two_sided_faces_report_the_front_face() {
    let (a, b, c) = (
        DVec3::new(0.0, 0.0, 0.0),
        DVec3::new(1.0, 0.0, 0.0),
        DVec3::new(0.0, 1.0, 0.0),
    );
    let grey = Spectrum::grey(0.5);
    let lamp = Face::new(
        [
            DVec3::new(0.0, 0.0, 5.0),
            DVec3::new(0.1, 0.0, 5.0),
            DVec3::new(0.0, 0.1, 5.0),
        ],
        grey,
        Spectrum::grey(1.0),
        1,
        2,
    );
    for order in [false, true] {
        let up = Face::new([a, b, c], grey, Spectrum::grey(0.0), 0, 0);
        let down = Face::new([a, c, b], grey, Spectrum::grey(0.0), 0, 1);
        let faces = if order {
            vec![down, up, lamp]
        } else {
            vec![up, down, lamp]
        };
        let (up_index, down_index) = if order { (1, 0) } else { (0, 1) };
        let scene = Scene::new("thin", "thin", faces, vec![], None).unwrap();
        let bvh = SceneBvh::new(&scene);
        let from_above = bvh
            .closest_hit(
                DVec3::new(0.2, 0.2, 1.0),
                DVec3::NEG_Z,
                f64::INFINITY,
                u32::MAX,
            )
            .unwrap();
        assert_eq!(from_above.face, up_index);
        assert!((from_above.t - 1.0).abs() < 1e-6);
        let from_below = bvh
            .closest_hit(
                DVec3::new(0.2, 0.2, -1.0),
                DVec3::Z,
                f64::INFINITY,
                u32::MAX,
            )
            .unwrap();
        assert_eq!(from_below.face, down_index);
        assert!((from_below.t - 1.0).abs() < 1e-6);
    }
    // Flatland: the built-in blocker is such a pair (segments 1 facing down, 2 facing up).
    let flat = builtin("flatland-blocker")
        .unwrap()
        .into_flatland()
        .unwrap();
    let vis = FlatVisibility::new(&flat);
    let down = vis
        .closest_hit(DVec2::new(0.5, 0.9), DVec2::new(0.0, -1.0), u32::MAX)
        .unwrap();
    assert_eq!(down.segment, 2, "from above: the up-facing top");
    let up = vis
        .closest_hit(DVec2::new(0.5, 0.1), DVec2::new(0.0, 1.0), u32::MAX)
        .unwrap();
    assert_eq!(up.segment, 1, "from below: the down-facing underside");
}

/// Rays along a negative coordinate axis (−Y = (−0, −1, −0)) hit a flat floor: obvhs's traversal
/// missed them before `SceneBvh` nudged ±0 direction components (found by the cut-out tests).
#[test]
fn axis_aligned_rays_hit_a_flat_floor() {
    let v = |x: f64, y: f64, z: f64| DVec3::new(x, y, z);
    let grey = Spectrum::grey(0.5);
    let faces = vec![
        Face::new(
            [v(0., 0., 0.), v(0., 0., 4.), v(4., 0., 4.)],
            grey,
            Spectrum::ZERO,
            0,
            0,
        ),
        Face::new(
            [v(0., 0., 0.), v(4., 0., 4.), v(4., 0., 0.)],
            grey,
            Spectrum::ZERO,
            0,
            0,
        ),
        Face::new(
            [v(1., 1., 1.), v(1., 1., 3.), v(3., 1., 3.)],
            grey,
            Spectrum::ZERO,
            1,
            1,
        ),
        Face::new(
            [v(1., 1., 1.), v(3., 1., 3.), v(3., 1., 1.)],
            grey,
            Spectrum::ZERO,
            1,
            1,
        ),
    ];
    let scene = Scene::new("floor", "test", faces, vec![], None).unwrap();
    let bvh = SceneBvh::new(&scene);
    for (x, z) in [(0.5, 2.0), (0.5, 2.01), (3.5, 0.5), (2.0, 3.9)] {
        let h = bvh.closest_hit(v(x, 1.5, z), -DVec3::Y, f64::INFINITY, u32::MAX);
        assert!(h.is_some_and(|h| h.face < 2), "({x}, {z}): {h:?}");
        let up = SurfacePoint {
            point: v(x, 0.0, z),
            normal: DVec3::Y,
            face: 0,
        };
        assert!(bvh.escapes(&up, DVec3::Y), "({x}, {z}) up");
    }
}

//! Lightmaps on a scene of modular pieces: a floor of two tiles that meet, walls that meet, a box
//! standing on the floor, and a closed room beside a lit one whose floor runs under the wall
//! between them. The lightmap must keep the closed room black (no light leaks under the wall),
//! leave no dark rim at the box's base (no darkness leaks out from under it), show no seam where
//! the tiles' charts meet, and hold at its texels what the estimator gives at the same points.

use gcr::{
    Domain, Emitters, GatherMode, LightmapQuantity, LightmapSettings, PathSettings, SolveConfig,
    Trained, bake_lightmap,
};
use glam::DVec3;
use scene_sampler::{Face, KernelSampler, Scene, SceneBvh, Spectrum};

/// A quad (two faces) from its corners, counter-clockwise seen from its front.
fn quad(c: [DVec3; 4], rho: f64, emission: f64, object: u32) -> [Face; 2] {
    let (r, e) = (Spectrum::grey(rho), Spectrum::grey(emission));
    [
        Face::new([c[0], c[1], c[2]], r, e, object, object),
        Face::new([c[0], c[2], c[3]], r, e, object, object),
    ]
}

/// The room at x ∈ [0, 1] is lit by a ceiling panel; the room at x ∈ [1.1, 2.1] is closed off
/// by a 0.1 thick wall standing on the floor, which runs on under it (tile 2). Height 1, depth 1.
fn two_rooms() -> Scene {
    let v = DVec3::new;
    let mut faces = Vec::new();
    let (x1, x2) = (2.1, 1.0);
    // floor tiles facing up: tile 1 x ∈ [0, 0.5], tile 2 x ∈ [0.5, 2.1] (under the wall)
    faces.extend(quad(
        [v(0., 0., 0.), v(0., 0., 1.), v(0.5, 0., 1.), v(0.5, 0., 0.)],
        0.6,
        0.0,
        0,
    ));
    faces.extend(quad(
        [v(0.5, 0., 0.), v(0.5, 0., 1.), v(x1, 0., 1.), v(x1, 0., 0.)],
        0.6,
        0.0,
        1,
    ));
    // ceiling facing down, walls facing in
    faces.extend(quad(
        [v(0., 1., 0.), v(x1, 1., 0.), v(x1, 1., 1.), v(0., 1., 1.)],
        0.6,
        0.0,
        2,
    ));
    faces.extend(quad(
        [v(0., 0., 0.), v(0., 1., 0.), v(0., 1., 1.), v(0., 0., 1.)],
        0.6,
        0.0,
        3,
    ));
    faces.extend(quad(
        [v(x1, 0., 0.), v(x1, 0., 1.), v(x1, 1., 1.), v(x1, 1., 0.)],
        0.6,
        0.0,
        3,
    ));
    faces.extend(quad(
        [v(0., 0., 0.), v(x1, 0., 0.), v(x1, 1., 0.), v(0., 1., 0.)],
        0.6,
        0.0,
        3,
    ));
    faces.extend(quad(
        [v(0., 0., 1.), v(0., 1., 1.), v(x1, 1., 1.), v(x1, 0., 1.)],
        0.6,
        0.0,
        3,
    ));
    // the thick wall between the rooms: its two sides
    faces.extend(quad(
        [v(x2, 0., 0.), v(x2, 0., 1.), v(x2, 1., 1.), v(x2, 1., 0.)],
        0.6,
        0.0,
        4,
    ));
    let x3 = 1.1;
    faces.extend(quad(
        [v(x3, 0., 0.), v(x3, 1., 0.), v(x3, 1., 1.), v(x3, 0., 1.)],
        0.6,
        0.0,
        4,
    ));
    // the ceiling panel of the lit room, facing down
    let y = 0.999;
    faces.extend(quad(
        [
            v(0.4, y, 0.4),
            v(0.6, y, 0.4),
            v(0.6, y, 0.6),
            v(0.4, y, 0.6),
        ],
        0.0,
        10.0,
        5,
    ));
    // a box on the lit room's floor, x ∈ [0.2, 0.4], z ∈ [0.6, 0.8], 0.2 high
    let (a, b, c, d, h) = (0.2, 0.4, 0.6, 0.8, 0.2);
    faces.extend(quad(
        [v(a, h, c), v(a, h, d), v(b, h, d), v(b, h, c)],
        0.6,
        0.0,
        6,
    ));
    faces.extend(quad(
        [v(a, 0., c), v(a, 0., d), v(a, h, d), v(a, h, c)],
        0.6,
        0.0,
        6,
    ));
    faces.extend(quad(
        [v(b, 0., c), v(b, h, c), v(b, h, d), v(b, 0., d)],
        0.6,
        0.0,
        6,
    ));
    faces.extend(quad(
        [v(a, 0., c), v(a, h, c), v(b, h, c), v(b, 0., c)],
        0.6,
        0.0,
        6,
    ));
    faces.extend(quad(
        [v(a, 0., d), v(b, 0., d), v(b, h, d), v(a, h, d)],
        0.6,
        0.0,
        6,
    ));
    let objects = [
        "tile 1",
        "tile 2",
        "ceiling",
        "walls",
        "wall between",
        "panel",
        "box",
    ];
    Scene::new(
        "two rooms",
        "test",
        faces,
        objects.map(String::from).to_vec(),
        None,
    )
    .unwrap()
}

fn config(target: f64) -> SolveConfig {
    SolveConfig {
        gather: GatherMode::Paths,
        paths: PathSettings {
            target_error: Some(target),
            ..PathSettings::default()
        },
        ..SolveConfig::default()
    }
}

/// The face of `scene` under a floor point (facing up, containing it).
fn floor_face(scene: &Scene, p: DVec3) -> u32 {
    (scene.faces.iter().enumerate())
        .find(|(_, f)| {
            f.normal.y > 0.99
                && f.v[0].y.abs() < 1e-9
                && (0..3).all(|k| {
                    let (a, b) = (f.v[k], f.v[(k + 1) % 3]);
                    (b - a).cross(p - a).y >= -1e-12
                })
        })
        .map(|(i, _)| i as u32)
        .expect("a floor face under the point")
}

#[test]
fn no_leaks_no_seams_and_the_estimators_values() {
    let scene = two_rooms();
    let bvh = SceneBvh::new(&scene);
    let domain = Domain::ThreeD(KernelSampler::new(&scene, &bvh));
    let target = 0.02;
    let config = config(target);
    let trained = Trained::without_networks(&domain, &config);
    let texels_per_unit = 40.0;
    let settings = LightmapSettings {
        texels_per_unit: Some(texels_per_unit),
        page_size: 256,
        quantity: LightmapQuantity::Irradiance,
        ..LightmapSettings::default()
    };
    let lm = bake_lightmap(&domain, &trained, &config, &settings).unwrap();
    assert!(
        lm.left_out < lm.texels.len() / 10,
        "left out {}",
        lm.left_out
    );
    let texel = 1.0 / texels_per_unit;

    // ⟨The closed room: every texel there, and the floor read right up to the wall, black⟩
    let dark: Vec<_> = lm
        .texels
        .iter()
        .filter(|t| t.point.x > 1.1 + 1e-9)
        .collect();
    assert!(dark.len() > 1000);
    let page = &lm.pages[0];
    let w = lm.atlas.width as usize;
    for t in &dark {
        assert_eq!(
            page[t.y as usize * w + t.x as usize],
            [0.0; 3],
            "texel at {}",
            t.point
        );
    }
    for k in 0..40 {
        let p = DVec3::new(
            1.1 + 0.1 * texel + 0.025 * k as f64,
            0.0,
            0.1 + 0.02 * k as f64,
        );
        let got = lm.sample(&scene, floor_face(&scene, p), p).unwrap();
        assert_eq!(got, [0.0; 3], "light under the wall at {p}");
    }
    // denoised too: the floor runs on under the wall, but the guide finds no light in the closed
    // room, so its texels mix with the lit room's at most through a texel moved out from under
    // the wall (far below anything a map can show: 10⁻⁹ of the lit room's mean)
    let denoised = LightmapSettings {
        denoise: true,
        ..settings
    };
    let dn = bake_lightmap(&domain, &trained, &config, &denoised).unwrap();
    let value = |t: &gcr::Texel| f64::from(dn.pages[0][t.y as usize * w + t.x as usize][0]);
    let lit: Vec<f64> = (dn.texels.iter())
        .filter(|t| t.point.x < 1.0 - 1e-9)
        .map(value)
        .collect();
    let lit_mean = lit.iter().sum::<f64>() / lit.len() as f64;
    let leak = dark.iter().map(|t| value(t)).fold(0.0, f64::max);
    eprintln!("denoised: closed room at most {leak:e}, the lit room's mean {lit_mean}");
    assert!(leak <= 1e-9 * lit_mean, "light {leak} in the closed room");

    // ⟨The box's base and the lit room's wall base read like the estimator there (no dark rim)⟩
    let emitters = Emitters::new(&domain);
    let rim: Vec<DVec3> = (0..20)
        .flat_map(|k| {
            let z = 0.61 + 0.009 * k as f64;
            [
                DVec3::new(0.2 - 0.3 * texel, 0.0, z),
                DVec3::new(0.4 + 0.3 * texel, 0.0, z),
                DVec3::new(1.0 - 0.3 * texel, 0.0, 0.1 + 0.04 * k as f64),
            ]
        })
        .collect();
    let at: Vec<_> = rim.iter().map(|&p| (p, DVec3::Y)).collect();
    let want = gcr::irradiance_at_points(&domain, &trained, &emitters, &config, &at).unwrap();
    // (a texel cannot follow the steep fall of the light into the box's vertical edges: there the
    // map reads brighter, up to 1.4× at 0.3 texel from the edge; it must never read darker)
    let mut ratios = Vec::new();
    for (p, w) in rim.iter().zip(&want) {
        let got = lm.sample(&scene, floor_face(&scene, *p), *p).unwrap()[0] as f64;
        let ratio = got / w.radiosity[0];
        assert!(
            ratio > 0.8,
            "a dark rim at {p}: lightmap {got}, estimator {}",
            w.radiosity[0]
        );
        ratios.push(ratio);
    }
    ratios.sort_by(f64::total_cmp);
    let median = ratios[ratios.len() / 2];
    assert!(
        (0.95..1.05).contains(&median),
        "median lightmap / estimator at the bases {median}"
    );

    // ⟨Where the tiles' charts meet (x = 0.5) each reads what the estimator gives there, within
    // the noise: no seam (a chart edge read against its padding would be dark)⟩
    let edge: Vec<_> = (0..40)
        .map(|k| (DVec3::new(0.5, 0.0, 0.02 + 0.024 * k as f64), DVec3::Y))
        .collect();
    let want = gcr::irradiance_at_points(&domain, &trained, &emitters, &config, &edge).unwrap();
    let (mut d2, mut b2) = (0.0, 0.0);
    for ((p, _), w) in edge.iter().zip(&want) {
        for side in [-1e-6, 1e-6] {
            let q = *p + DVec3::X * side;
            let v = lm.sample(&scene, floor_face(&scene, q), q).unwrap()[0] as f64;
            d2 += (v - w.radiosity[0]).powi(2);
            b2 += w.radiosity[0].powi(2);
        }
    }
    let seam = (d2 / b2).sqrt();
    assert!(
        seam < 2.5 * target,
        "the tiles' edge against the estimator: {seam}"
    );

    // ⟨Texels hold the estimator's values at their points, within the target error⟩
    let some: Vec<_> = lm
        .texels
        .iter()
        .step_by(13)
        .filter(|t| t.point.x < 1.0)
        .collect();
    let at: Vec<_> = some.iter().map(|t| (t.point, t.normal)).collect();
    let again = gcr::irradiance_at_points(&domain, &trained, &emitters, &config, &at).unwrap();
    let (mut d2, mut b2) = (0.0, 0.0);
    for (t, g) in some.iter().zip(&again) {
        let v = f64::from(page[t.y as usize * w + t.x as usize][0]);
        d2 += (v - g.radiosity[0]).powi(2);
        b2 += g.radiosity[0].powi(2);
    }
    let rel = (d2 / b2).sqrt();
    assert!(rel < 2.5 * target, "texels against the estimator: {rel}");
}

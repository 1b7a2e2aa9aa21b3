//! Lights other than emitting faces (`scene_sampler::lights`) through gcr's estimators, against
//! exact values: a point light's inverse-square cosine law, a spot's cone, the sun on an open
//! plane and the penumbra of a sun-lit edge, a uniform and a CIE overcast sky over an open plane,
//! the sky seen through an opening (a converged quadrature of the opening), many lamps drawn by
//! the light tree (Lambert's formula and the inverse-square law), and a constant
//! environment — a light written in this test file, through the public interface only — through
//! every estimator: radiosity and irradiance probes by the paths gather, the dissertation's ray
//! gather, per-pixel images, and the path-traced reference of `gcr reference` (`baselines`).

use gcr::output::PinholeCamera;
use gcr::output::render_pixels;
use gcr::{Domain, Emitters, GatherMode, Gathered, PathSettings, SolveConfig, Trained};
use glam::DVec3;
use scene_sampler::{
    BANDS, Bands, Face, KernelSampler, Light, LightSample, PointLight, Portal, Portals, Receiver,
    Scene, SceneBvh, ShadowTarget, Sky, SkyModel, Spectrum, Sun, cosine_hemisphere,
    hemisphere_quadrature,
};
use std::f64::consts::PI;
use std::sync::Arc;

/// The paths gather to `target`, without networks (it reads none).
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

/// A quad (two faces) from its corners, counter-clockwise seen from its front.
fn quad(c: [DVec3; 4], rho: f64, object: u32, surface: u32) -> [Face; 2] {
    let r = Spectrum::grey(rho);
    [
        Face::new([c[0], c[1], c[2]], r, Spectrum::ZERO, object, surface),
        Face::new([c[0], c[2], c[3]], r, Spectrum::ZERO, object, surface),
    ]
}

/// A floor 20 × 20 at y = 0 facing up, reflectance ρ, and `lights`.
fn floor(rho: f64, lights: Vec<Arc<dyn Light>>) -> Scene {
    let c = |x: f64, z: f64| DVec3::new(x, 0.0, z);
    let faces = quad(
        [
            c(-10.0, -10.0),
            c(-10.0, 10.0),
            c(10.0, 10.0),
            c(10.0, -10.0),
        ],
        rho,
        0,
        0,
    );
    let mut s = Scene::new("floor", "test", faces.to_vec(), vec!["floor".into()], None).unwrap();
    assert!(s.faces[0].normal.y > 0.99);
    s.lights = lights;
    s
}

fn irradiance(scene: &Scene, target: f64, at: &[(DVec3, DVec3)]) -> Vec<Gathered> {
    let bvh = SceneBvh::new(scene);
    let domain = Domain::ThreeD(KernelSampler::new(scene, &bvh));
    let config = config(target);
    let trained = Trained::without_networks(&domain, &config);
    gcr::irradiance_at_points(&domain, &trained, &Emitters::new(&domain), &config, at).unwrap()
}

fn radiosity(scene: &Scene, target: f64, at: &[(DVec3, DVec3, u32)]) -> Vec<Gathered> {
    let bvh = SceneBvh::new(scene);
    let domain = Domain::ThreeD(KernelSampler::new(scene, &bvh));
    let config = config(target);
    let trained = Trained::without_networks(&domain, &config);
    gcr::radiosity_at_points(&domain, &trained, &Emitters::new(&domain), &config, at).unwrap()
}

fn close(got: f64, want: f64, rel: f64, what: &str) {
    assert!(
        (got - want).abs() <= rel * want.abs(),
        "{what}: {got} vs {want} (±{:.2} %)",
        100.0 * rel
    );
}

/// E = I cos θ/d² at points in the air and B = ρ·I cos θ/d² on the floor (nothing above them
/// reflects: exact but for rounding); a spot light's cone: full inside, glTF's falloff between
/// the angles, nothing outside.
#[test]
fn point_and_spot_lights_follow_the_inverse_square_cosine_law() {
    let i = 100.0;
    let light: Arc<dyn Light> =
        Arc::new(PointLight::new(DVec3::new(0.0, 2.0, 0.0), [i; BANDS]).unwrap());
    let scene = floor(0.5, vec![light]);
    let xs = [0.0, 1.0, 2.5];
    let at: Vec<_> = xs
        .iter()
        .map(|&x| (DVec3::new(x, 0.5, x), DVec3::Y))
        .collect();
    for (g, &x) in irradiance(&scene, 0.01, &at).iter().zip(&xs) {
        let d2 = 2.25 + 2.0 * x * x;
        close(
            g.radiosity[0],
            i * (1.5 / d2.sqrt()) / d2,
            1e-9,
            "E in the air",
        );
    }
    let on: Vec<_> = xs
        .iter()
        .map(|&x| (DVec3::new(x, 0.0, 0.0), DVec3::Y, 0))
        .collect();
    for (g, &x) in radiosity(&scene, 0.01, &on).iter().zip(&xs) {
        let d2 = 4.0 + x * x;
        close(
            g.radiosity[0],
            0.5 * i * (2.0 / d2.sqrt()) / d2,
            1e-9,
            "B on the floor",
        );
    }
    let (inner, outer) = (20f64.to_radians(), 30f64.to_radians());
    let spot: Arc<dyn Light> = Arc::new(
        PointLight::spot(
            DVec3::new(0.0, 2.0, 0.0),
            [i; BANDS],
            -DVec3::Y,
            inner,
            outer,
        )
        .unwrap(),
    );
    let scene = floor(0.5, vec![spot]);
    let angles = [10.0f64, 25.0, 31.0];
    let at: Vec<_> = (angles.iter())
        .map(|a| (DVec3::new(2.0 * a.to_radians().tan(), 0.0, 0.0), DVec3::Y))
        .collect();
    let got = irradiance(&scene, 0.01, &at);
    let plain = |a: f64| i * a.to_radians().cos().powi(3) / 4.0;
    close(got[0].radiosity[0], plain(10.0), 1e-9, "inside the cone");
    let t = (25f64.to_radians().cos() - outer.cos()) / (inner.cos() - outer.cos());
    close(
        got[1].radiosity[0],
        plain(25.0) * t * t,
        1e-9,
        "in the falloff",
    );
    assert_eq!(got[2].radiosity[0], 0.0, "outside the cone");
}

/// The sun on an open plane gives E = E_n cos θ (within the 0.2 % target), and an edge casts a
/// penumbra of the disc's width: under a plate at height h with the sun at the zenith, a floor
/// point x past the edge sees the part of the disc beyond the chord at distance x/h from its
/// centre (angles), f(d) = 1/2 + (d √(1 − d²) + asin d)/π with d = x/(h·α).
#[test]
fn the_sun_on_an_open_plane_and_its_penumbra() {
    let sun: Arc<dyn Light> =
        Arc::new(Sun::new(DVec3::new(0.0, 1.0, 1.0), [1000.0; BANDS], 0.53).unwrap());
    let scene = floor(0.3, vec![sun]);
    let at = [(DVec3::new(1.0, 0.2, -2.0), DVec3::Y)];
    let g = irradiance(&scene, 0.002, &at);
    close(
        g[0].radiosity[0],
        1000.0 * 45f64.to_radians().cos(),
        0.006,
        "E_n cos θ",
    );
    // a plate over x < 0 at height 1, black underneath, sun at the zenith
    let h = 1.0;
    let c = |x: f64, z: f64| DVec3::new(x, h, z);
    let mut faces = quad(
        [c(-10.0, -10.0), c(-10.0, 10.0), c(0.0, 10.0), c(0.0, -10.0)],
        0.0,
        1,
        1,
    )
    .to_vec();
    faces.extend(quad(
        [c(-10.0, -10.0), c(0.0, -10.0), c(0.0, 10.0), c(-10.0, 10.0)],
        0.0,
        1,
        2,
    ));
    let base = floor(0.0, Vec::new());
    let mut all = base.faces.clone();
    all.extend(faces);
    let mut scene = Scene::new(
        "edge",
        "test",
        all,
        vec!["floor".into(), "plate".into()],
        None,
    )
    .unwrap();
    let sun = Sun::new(DVec3::Y, [1.0; BANDS], 0.53).unwrap();
    scene.lights = vec![Arc::new(sun)];
    let alpha = (0.53f64 / 2.0).to_radians();
    let ds = [-1.5, -0.5, 0.0, 0.5, 1.5];
    let at: Vec<_> = ds
        .iter()
        .map(|&d| (DVec3::new(d * h * alpha.tan(), 1e-6, 0.0), DVec3::Y))
        .collect();
    for (g, &d) in irradiance(&scene, 0.003, &at).iter().zip(&ds) {
        let dc = d.clamp(-1.0, 1.0);
        let f = 0.5 + (dc * (1.0 - dc * dc).sqrt() + dc.asin()) / PI;
        assert!(
            (g.radiosity[0] - f).abs() < 0.02,
            "d = {d}: {} vs visible fraction {f}",
            g.radiosity[0]
        );
    }
}

/// A uniform sky over an open plane: E = π L (the sky's horizontal irradiance) on the plane and
/// B = ρ·π L; the CIE overcast sky's horizontal irradiance is 7π L_z/9 (the model is given by
/// it: the probe measures it back), and a vertical plane under it sees
/// L_z/3 ∫ (1 + 2 cos θ) cos γ dω over the sky half = L_z π (1/2 + 4/(3π))/3·… (by quadrature).
#[test]
fn skies_over_an_open_plane() {
    let e_h = 1000.0;
    let uniform: Arc<dyn Light> =
        Arc::new(Sky::new(SkyModel::Uniform, DVec3::Y, [e_h; BANDS], [0.0; BANDS]).unwrap());
    let scene = floor(0.5, vec![uniform]);
    let g = irradiance(&scene, 0.005, &[(DVec3::new(0.0, 0.5, 0.0), DVec3::Y)]);
    close(g[0].radiosity[0], e_h, 1e-9, "E = πL facing up");
    let b = radiosity(&scene, 0.005, &[(DVec3::ZERO, DVec3::Y, 0)]);
    close(b[0].radiosity[0], 0.5 * e_h, 1e-9, "B = ρπL");
    let overcast = Sky::new(SkyModel::CieOvercast, DVec3::Y, [e_h; BANDS], [0.0; BANDS]).unwrap();
    let scene = floor(0.0, vec![Arc::new(overcast.clone())]);
    let up = irradiance(&scene, 0.003, &[(DVec3::new(0.0, 0.5, 0.0), DVec3::Y)]);
    close(up[0].radiosity[0], e_h, 0.01, "overcast E_h");
    // a vertical receiver (black floor): ∫ L(θ) cos γ dω over its hemisphere above the horizon
    let side = irradiance(&scene, 0.003, &[(DVec3::new(0.0, 0.5, 0.0), DVec3::X)]);
    let want = quadrature(|w| overcast.escaped(w)[0] / PI * w.x.max(0.0));
    close(side[0].radiosity[0], want, 0.01, "overcast, vertical");
    let l_z = 9.0 * e_h / (7.0 * PI);
    close(
        overcast.escaped(DVec3::Y)[0] / PI,
        l_z,
        1e-12,
        "L_z = 9 E_h/(7π)",
    );
}

/// ∫ f(ω) dω over the upper (+Y) hemisphere ([`hemisphere_quadrature`]).
fn quadrature(f: impl Fn(DVec3) -> f64) -> f64 {
    hemisphere_quadrature(DVec3::Y, 600, f)
}

/// The sky component through an unglazed opening: a closed black room 4 × 3 × 4 with a window
/// 2 × 1 in its +Z wall, under a CIE overcast sky (black ground): the irradiance at a point of
/// the floor is ∫ over the opening of L(ω) cos θ_y cos θ_w/r² dA, here by a converged midpoint
/// rule over the opening (Tregenza & Sharples' sky component, by quadrature); the same with the
/// window marked as a sky portal.
#[test]
fn the_sky_through_a_window() {
    let (w, h, d) = (4.0, 3.0, 4.0);
    let v = |x: f64, y: f64, z: f64| DVec3::new(x, y, z);
    let mut faces = Vec::new();
    let mut s = 0;
    let mut wall = |c: [DVec3; 4]| {
        faces.extend(quad(c, 0.0, 0, s));
        s += 1;
    };
    // inward-facing walls: floor, ceiling, x = 0, x = w, z = 0
    wall([v(0., 0., 0.), v(w, 0., 0.), v(w, 0., d), v(0., 0., d)]);
    wall([v(0., h, 0.), v(0., h, d), v(w, h, d), v(w, h, 0.)]);
    wall([v(0., 0., 0.), v(0., 0., d), v(0., h, d), v(0., h, 0.)]);
    wall([v(w, 0., 0.), v(w, h, 0.), v(w, h, d), v(w, 0., d)]);
    wall([v(0., 0., 0.), v(0., h, 0.), v(w, h, 0.), v(w, 0., 0.)]);
    // the z = d wall facing −z, with the opening x ∈ [1, 3], y ∈ [1, 2]
    let (x0, x1, y0, y1) = (1.0, 3.0, 1.0, 2.0);
    let zw = |a: f64, b: f64, c: f64, e: f64| [v(a, c, d), v(a, e, d), v(b, e, d), v(b, c, d)];
    wall(zw(0.0, w, 0.0, y0));
    wall(zw(0.0, w, y1, h));
    wall(zw(0.0, x0, y0, y1));
    wall(zw(x1, w, y0, y1));
    let bare = Scene::new("window", "test", faces, vec!["room".into()], None).unwrap();
    let sky = Sky::new(
        SkyModel::CieOvercast,
        DVec3::Y,
        [10_000.0; BANDS],
        [0.0; BANDS],
    )
    .unwrap();
    // the same sky, its shadow rays mostly through the window marked as a portal: same values
    let portal = Portal::new([v(x0, y0, d), v(x1, y0, d), v(x1, y1, d), v(x0, y1, d)]).unwrap();
    let through = sky.clone().with_portals(Portals::new(vec![portal]));
    let skies: [Arc<dyn Light>; 2] = [Arc::new(sky.clone()), Arc::new(through)];
    for light in skies {
        let mut scene = bare.clone();
        scene.lights = vec![light];
        window_matches_quadrature(&scene, &sky, (x0, x1, y0, y1, d));
    }
}

/// The irradiance at three floor points of the window room against the quadrature over the
/// opening `(x0, x1, y0, y1)` at z = d.
fn window_matches_quadrature(
    scene: &Scene,
    sky: &Sky,
    (x0, x1, y0, y1, d): (f64, f64, f64, f64, f64),
) {
    let v = |x: f64, y: f64, z: f64| DVec3::new(x, y, z);
    let points = [v(2.0, 0.0, 2.0), v(1.0, 0.0, 3.0), v(3.5, 0.0, 1.0)];
    let got = radiosity(
        scene,
        0.003,
        &points.iter().map(|&p| (p, DVec3::Y, 0)).collect::<Vec<_>>(),
    );
    for (g, &y) in got.iter().zip(&points) {
        // the floor's ρ is 0: B = 0; its irradiance through an irradiance probe instead
        assert_eq!(g.radiosity[0], 0.0);
        let e = irradiance(scene, 0.003, &[(y + DVec3::Y * 1e-4, DVec3::Y)])[0].radiosity[0];
        let n = 400;
        let mut want = 0.0;
        for i in 0..n {
            for j in 0..n {
                let x = v(
                    x0 + (x1 - x0) * (i as f64 + 0.5) / n as f64,
                    y0 + (y1 - y0) * (j as f64 + 0.5) / n as f64,
                    d,
                );
                let r = x - y;
                let r2 = r.length_squared();
                let dir = r / r2.sqrt();
                want += sky.escaped(dir)[0] / PI * dir.y * dir.z / r2;
            }
        }
        want *= (x1 - x0) * (y1 - y0) / (n * n) as f64;
        close(e, want, 0.015, &format!("sky component at {y}"));
    }
}

/// A constant environment: radiance L from every direction, written here against the public
/// [`Light`] interface alone (sampled by the receiver's cosine hemisphere). With it a convex
/// object sees nothing but the environment: every point of a cube of reflectance ρ has
/// B = ρ·π L, every point in the open E = π L whatever its orientation, and a camera sees π L/π
/// = L in the background and ρ L on the cube, through each estimator.
#[derive(Debug)]
struct Constant(f64);

impl Light for Constant {
    fn sample(&self, at: &Receiver, u: [f64; 2]) -> Option<LightSample> {
        let w = cosine_hemisphere(at.n, u);
        let g = at.n.dot(w) / PI;
        (g > 0.0).then_some(LightSample {
            target: ShadowTarget::Direction(w),
            emission: [PI * self.0; BANDS],
            g,
            pdf: g,
        })
    }
    fn escaped(&self, _dir: DVec3) -> Bands {
        [PI * self.0; BANDS]
    }
    fn escaped_pdf(&self, at: &Receiver, dir: DVec3) -> f64 {
        at.n.dot(dir).max(0.0) / PI
    }
    fn is_delta(&self) -> bool {
        false
    }
    fn power(&self, radius: f64) -> f64 {
        PI * radius * radius * PI * self.0
    }
    fn is_grey(&self) -> bool {
        true
    }
    fn describe(&self) -> String {
        format!("constant environment {}", self.0)
    }
}

#[test]
fn a_constant_environment_through_every_estimator() {
    let l = 2.0;
    let rho = 0.6;
    let v = |x: f64, y: f64, z: f64| DVec3::new(x, y, z);
    let (a, b) = (0.0, 1.0);
    let mut faces = Vec::new();
    // outward-facing unit cube
    for (i, c) in [
        [v(a, a, a), v(a, b, a), v(b, b, a), v(b, a, a)],
        [v(a, a, b), v(b, a, b), v(b, b, b), v(a, b, b)],
        [v(a, a, a), v(b, a, a), v(b, a, b), v(a, a, b)],
        [v(a, b, a), v(a, b, b), v(b, b, b), v(b, b, a)],
        [v(a, a, a), v(a, a, b), v(a, b, b), v(a, b, a)],
        [v(b, a, a), v(b, b, a), v(b, b, b), v(b, a, b)],
    ]
    .into_iter()
    .enumerate()
    {
        faces.extend(quad(c, rho, 0, i as u32));
    }
    let mut scene = Scene::new("cube", "test", faces, vec!["cube".into()], None).unwrap();
    scene.lights = vec![Arc::new(Constant(l))];
    // radiosity on every side of the cube (the shared-path groups included)
    let on: Vec<_> = (scene.faces.iter().enumerate())
        .map(|(f, face)| {
            (
                face.v[0] * 0.4 + face.v[1] * 0.3 + face.v[2] * 0.3,
                face.normal,
                f as u32,
            )
        })
        .collect();
    for g in radiosity(&scene, 0.005, &on) {
        close(g.radiosity[0], rho * PI * l, 0.02, "B on the cube");
    }
    // the dissertation's ray gather (its networks empty: on a convex object all light is direct)
    {
        let bvh = SceneBvh::new(&scene);
        let domain = Domain::ThreeD(KernelSampler::new(&scene, &bvh));
        let rays = SolveConfig {
            gather: GatherMode::Rays,
            ..SolveConfig::default()
        };
        let trained = Trained::without_networks(&domain, &rays);
        let got = gcr::radiosity_at_points(&domain, &trained, &Emitters::new(&domain), &rays, &on)
            .unwrap();
        for g in got {
            close(g.radiosity[0], rho * PI * l, 0.03, "B by the ray gather");
        }
        // the reference path tracer (`gcr reference`)
        let points: Vec<_> = (on.iter())
            .map(|&(point, normal, face)| scene_sampler::SurfacePoint {
                point,
                normal,
                face,
            })
            .collect();
        let adaptive = baselines::Adaptive {
            rel_error: 0.005,
            ..baselines::Adaptive::default()
        };
        for r in baselines::pointwise::reference_at(&scene, &bvh, &points, &adaptive).unwrap() {
            close(r.estimate.mean[0], rho * PI * l, 0.02, "B by the reference");
        }
    }
    // irradiance in the open, facing anywhere away from the cube
    let at = [
        (v(0.5, 3.0, 0.5), DVec3::Y),
        (v(3.0, 0.5, 0.5), DVec3::X),
        (v(0.5, 0.5, -2.0), v(0.3, -0.5, -1.0).normalize()),
    ];
    for g in irradiance(&scene, 0.005, &at) {
        close(g.radiosity[0], PI * l, 0.02, "E in the open");
    }
    // a camera: the sky around the cube is L, the cube ρ L
    let bvh = SceneBvh::new(&scene);
    let domain = Domain::ThreeD(KernelSampler::new(&scene, &bvh));
    let config = config(0.02);
    let trained = Trained::without_networks(&domain, &config);
    let camera = PinholeCamera {
        eye: v(0.5, 0.5, 4.0),
        target: v(0.5, 0.5, 0.5),
        up: DVec3::Y,
        fov_y_degrees: 40.0,
    };
    let image = render_pixels(&domain, &trained, &config, &camera, (16, 16, 1)).unwrap();
    let radiance = image.radiance();
    let corner = f64::from(radiance.radiance[0][0]);
    let centre = f64::from(radiance.radiance[8 * 16 + 8][0]);
    close(corner, l, 1e-6, "the background pixel");
    close(centre, rho * l, 0.05, "the cube's pixel");
}

/// The projected solid angle of the convex polygon `v` seen from (y, n) (Lambert's formula:
/// ½ |Σ_edges θ_i n·ĝ_i|, θ_i the angle the edge subtends and ĝ_i the unit normal of the plane
/// through y and the edge), for a polygon wholly above the receiver's horizon.
fn projected_solid_angle(y: DVec3, n: DVec3, v: &[DVec3]) -> f64 {
    let mut sum = 0.0;
    for i in 0..v.len() {
        let (a, b) = (
            (v[i] - y).normalize(),
            (v[(i + 1) % v.len()] - y).normalize(),
        );
        sum += a.dot(b).clamp(-1.0, 1.0).acos() * n.dot(a.cross(b).normalize());
    }
    0.5 * sum.abs()
}

/// Many lamps far apart over a black floor (no reflected light): ceiling panels at different
/// heights and places (emitting faces, facing down), point lights and a spot. Each probe's
/// irradiance is exact (Lambert's formula for the panels, I cos θ/d² for the points); the light
/// tree draws each shadow ray toward the lamps near the probe, and the estimate stays unbiased
/// within 5 of its own standard errors — including at a probe above a panel (which it cannot
/// see) and under the spot's cone's edge.
#[test]
fn many_lamps_through_the_light_tree() {
    let m = 40.0; // the panels' exitance π·L
    let panels = [
        (DVec3::new(-6.0, 2.5, -6.0), 0.6),
        (DVec3::new(6.0, 2.5, -6.0), 1.0),
        (DVec3::new(-6.0, 3.5, 6.0), 0.4),
        (DVec3::new(0.0, 1.2, 0.0), 0.5),
    ];
    let mut faces = floor(0.0, Vec::new()).faces;
    let mut corners = Vec::new();
    for (k, &(c, h)) in panels.iter().enumerate() {
        // counter-clockwise seen from below: facing down
        let q = [
            c + DVec3::new(-h, 0.0, -h),
            c + DVec3::new(h, 0.0, -h),
            c + DVec3::new(h, 0.0, h),
            c + DVec3::new(-h, 0.0, h),
        ];
        let e = Spectrum::grey(m);
        let r = Spectrum::grey(0.0);
        let o = 1 + k as u32;
        faces.push(Face::new([q[0], q[1], q[2]], r, e, o, o));
        faces.push(Face::new([q[0], q[2], q[3]], r, e, o, o));
        assert!(faces.last().unwrap().normal.y < -0.99);
        corners.push(q);
    }
    let objects = (0..=panels.len()).map(|k| format!("o{k}")).collect();
    let mut scene = Scene::new("lamps", "test", faces, objects, None).unwrap();
    let points = [
        (DVec3::new(6.0, 3.0, 6.0), 30.0),
        (DVec3::new(-7.0, 1.0, 1.0), 10.0),
        (DVec3::new(3.0, 0.4, -2.0), 5.0),
    ];
    let (spot_at, inner, outer) = (DVec3::new(2.0, 3.0, 7.0), 0.3f64, 0.5f64);
    let mut lights: Vec<Arc<dyn Light>> = (points.iter())
        .map(|&(p, i)| Arc::new(PointLight::new(p, [i; BANDS]).unwrap()) as Arc<dyn Light>)
        .collect();
    lights.push(Arc::new(
        PointLight::spot(spot_at, [50.0; BANDS], -DVec3::Y, inner, outer).unwrap(),
    ));
    scene.lights = lights;
    let exact = |y: DVec3| {
        let n = DVec3::Y;
        let mut e = 0.0;
        for q in &corners {
            if q[0].y > y.y {
                e += m / PI * projected_solid_angle(y, n, q);
            }
        }
        for &(p, i) in &points {
            let d = p - y;
            e += i * n.dot(d).max(0.0) / d.length().powi(3);
        }
        let d = spot_at - y;
        let cd = (-d.normalize()).dot(-DVec3::Y);
        let t = ((cd - outer.cos()) / (inner.cos() - outer.cos())).clamp(0.0, 1.0);
        e + 50.0 * t * t * n.dot(d).max(0.0) / d.length().powi(3)
    };
    let spot_edge = spot_at.x + 3.0 * 0.4f64.tan();
    let at: Vec<(DVec3, DVec3)> = [
        DVec3::new(-6.0, 0.5, -6.0),
        DVec3::new(5.0, 0.5, -5.5),
        DVec3::new(-5.5, 0.3, 5.0),
        DVec3::new(0.0, 1.5, 0.0), // above the low panel: it cannot light this probe
        DVec3::new(0.3, 0.2, 0.4),
        DVec3::new(6.0, 0.5, 6.0),
        DVec3::new(spot_edge, 0.0, 7.0),
        DVec3::new(9.0, 0.1, -9.0),
    ]
    .iter()
    .map(|&y| (y, DVec3::Y))
    .collect();
    let got = irradiance(&scene, 0.01, &at);
    for (g, &(y, _)) in got.iter().zip(&at) {
        let want = exact(y);
        let (v, s) = (g.radiosity[0], g.std_error[0]);
        assert!(s <= 0.05 * want, "σ {s} for {want} at {y}");
        assert!(
            (v - want).abs() <= 5.0 * s + 1e-9 * want,
            "at {y}: {v} ± {s} vs exact {want}"
        );
    }
}

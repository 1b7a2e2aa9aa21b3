//! Built-in scenes by name, and a generator of large test scenes.

use crate::{
    AnyScene, Camera, Face, FlatView, FlatlandScene, Result, Scene, SceneError, Segment, Spectrum,
};
use glam::{DVec2, DVec3};
use rand::{Rng, SeedableRng};

/// Names accepted by [`builtin`].
pub const BUILTIN_NAMES: &[&str] = &[
    "cornell-box",
    "wall-floor",
    "two-blockers",
    "furnace",
    "closed-room",
    "flatland-corner",
    "flatland-blocker",
];

/// Name prefix of the generated clutter scene: `random-boxes-<N>` is [`random_boxes`]`(N, 1)`.
pub const RANDOM_BOXES_PREFIX: &str = "random-boxes-";

/// Name prefix of the generated tessellated scene: `tessellated-cornell-<N>` is
/// [`tessellated_cornell`]`(N)`.
pub const TESSELLATED_CORNELL_PREFIX: &str = "tessellated-cornell-";

/// Largest `N` accepted in the generated scenes' names (about 1.5 GB of scene and BVH at 20 M
/// triangles).
pub const GENERATED_MAX: usize = 20_000_000;

/// Builds a generated scene of about `n` triangles.
type Generator = fn(usize) -> Scene;

/// A generated scene's generator and its size, when `name` is `<prefix><digits>` for one of the generated
/// scenes' prefixes (`_` allowed between digits); `None` otherwise (so that a file such as
/// `random-boxes-7.obj` still loads as a file). The size is `None` when the digits overflow.
fn generated_name(name: &str) -> Option<(&'static str, Generator, Option<usize>)> {
    const GENERATORS: [(&str, Generator); 2] = [
        (RANDOM_BOXES_PREFIX, |n| random_boxes(n, 1)),
        (TESSELLATED_CORNELL_PREFIX, tessellated_cornell),
    ];
    GENERATORS.iter().find_map(|&(prefix, generate)| {
        let digits = name.strip_prefix(prefix)?.replace('_', "");
        (!digits.is_empty() && digits.bytes().all(|b| b.is_ascii_digit()))
            .then(|| (prefix, generate, digits.parse().ok()))
    })
}

/// The generated scene `name` names ([`generated_name`]), or an error when its size is out of range.
fn parse_generated(name: &str) -> Option<Result<Scene>> {
    let (prefix, generate, n) = generated_name(name)?;
    Some(match n {
        Some(n) if (40..=GENERATED_MAX).contains(&n) => Ok(generate(n)),
        _ => Err(SceneError::UnknownBuiltin {
            name: name.into(),
            hint: String::new(),
            known: format!(
                "{} (and {prefix}<N> for N from 40 to {GENERATED_MAX} triangles)",
                BUILTIN_NAMES.join(", ")
            ),
        }),
    })
}

/// Levenshtein distance (insertions, deletions, substitutions; by chars).
fn edit_distance(a: &str, b: &str) -> usize {
    let b: Vec<char> = b.chars().collect();
    let mut row: Vec<usize> = (0..=b.len()).collect();
    for (i, ca) in a.chars().enumerate() {
        let mut diag = row[0];
        row[0] = i + 1;
        for (j, &cb) in b.iter().enumerate() {
            let next = (diag + usize::from(ca != cb))
                .min(row[j] + 1)
                .min(row[j + 1] + 1);
            diag = row[j + 1];
            row[j + 1] = next;
        }
    }
    row[b.len()]
}

/// The known scene name closest to `name` (a typo such as `cornel-box`), if it is within a third of the
/// name's length (at least 2 edits). Generated names are compared without their size.
pub fn nearest_builtin(name: &str) -> Option<String> {
    let bare = name.trim_end_matches(|c: char| c.is_ascii_digit() || c == '_');
    let generated = ["random-boxes-", "tessellated-cornell-"];
    let (d, best) = BUILTIN_NAMES
        .iter()
        .map(|&k| (edit_distance(name, k), k.to_string()))
        .chain(
            generated
                .iter()
                .map(|&k| (edit_distance(bare, k), format!("{k}<N>"))),
        )
        .min_by_key(|(d, _)| *d)?;
    (d <= (name.chars().count() / 3).max(2)).then_some(best)
}

/// The ` — did you mean …?` part of an unknown-name message.
pub(crate) fn hint(name: &str) -> String {
    nearest_builtin(name).map_or_else(String::new, |n| format!(" — did you mean `{n}`?"))
}

/// Whether [`builtin`] accepts `name`: one of [`BUILTIN_NAMES`], `random-boxes-<N>` or
/// `tessellated-cornell-<N>`.
pub fn is_builtin(name: &str) -> bool {
    BUILTIN_NAMES.contains(&name) || generated_name(name).is_some()
}

/// Builds a built-in scene by name (see [`BUILTIN_NAMES`] and `docs/design/scene-sampler.md` for their geometry).
///
/// Besides the fixed names, two generated scenes of about `N` triangles: `random-boxes-<N>` (e.g.
/// `random-boxes-1000000`), the Cornell box filled with small random boxes ([`random_boxes`] with
/// seed 1; a dense clutter), and `tessellated-cornell-<N>`, the Cornell box with every face cut into
/// small triangles ([`tessellated_cornell`]; the same light transport as `cornell-box`).
pub fn builtin(name: &str) -> Result<AnyScene> {
    if let Some(scene) = parse_generated(name) {
        return Ok(AnyScene::ThreeD(scene?));
    }
    Ok(match name {
        "cornell-box" => AnyScene::ThreeD(cornell_box()),
        "wall-floor" => AnyScene::ThreeD(wall_floor()),
        "two-blockers" => AnyScene::ThreeD(two_blockers()),
        "furnace" => AnyScene::ThreeD(furnace(Spectrum::grey(1.0), Spectrum::grey(0.5))),
        "closed-room" => AnyScene::ThreeD(closed_room()),
        "flatland-corner" => AnyScene::Flatland(flatland_corner()),
        "flatland-blocker" => AnyScene::Flatland(flatland_blocker()),
        _ => {
            return Err(SceneError::UnknownBuiltin {
                name: name.into(),
                hint: hint(name),
                known: format!(
                    "{}, random-boxes-<N>, tessellated-cornell-<N>",
                    BUILTIN_NAMES.join(", ")
                ),
            });
        }
    })
}

/// Collects triangulated quads with consistent orientation.
struct Builder {
    faces: Vec<Face>,
    objects: Vec<String>,
    surface: u32,
}

impl Builder {
    fn new() -> Self {
        Builder {
            faces: Vec::new(),
            objects: Vec::new(),
            surface: 0,
        }
    }
    fn object(&mut self, name: &str) -> u32 {
        self.objects.push(name.into());
        (self.objects.len() - 1) as u32
    }
    /// Adds the planar polygon `p` (convex, in order) as a fan, wound so that its normal points along `toward`.
    fn poly(&mut self, obj: u32, p: &[DVec3], toward: DVec3, rho: Spectrum, e: Spectrum) {
        let n = (p[1] - p[0]).cross(p[2] - p[0]);
        let flip = n.dot(toward) < 0.0;
        for k in 1..p.len() - 1 {
            let v = if flip {
                [p[0], p[k + 1], p[k]]
            } else {
                [p[0], p[k], p[k + 1]]
            };
            self.faces.push(Face::new(v, rho, e, obj, self.surface));
        }
        self.surface += 1;
    }
    /// Adds a convex block given its bottom and top rectangles (4 points each, same order), outward normals.
    /// `with_bottom = false` omits the bottom face (blocks standing on the floor, as in the Cornell data).
    fn block(
        &mut self,
        obj: u32,
        bottom: [DVec3; 4],
        top: [DVec3; 4],
        rho: Spectrum,
        with_bottom: bool,
    ) {
        let c = bottom
            .iter()
            .chain(top.iter())
            .fold(DVec3::ZERO, |a, &b| a + b)
            / 8.0;
        let out = |p: &[DVec3]| p.iter().fold(DVec3::ZERO, |a, &b| a + b) / p.len() as f64 - c;
        self.poly(obj, &top, out(&top), rho, Spectrum::ZERO);
        if with_bottom {
            self.poly(obj, &bottom, out(&bottom), rho, Spectrum::ZERO);
        }
        for k in 0..4 {
            let q = [bottom[k], bottom[(k + 1) % 4], top[(k + 1) % 4], top[k]];
            self.poly(obj, &q, out(&q), rho, Spectrum::ZERO);
        }
    }
    fn finish(self, name: &str, camera: Camera) -> Scene {
        Scene::new(
            name,
            &format!("builtin:{name}"),
            self.faces,
            self.objects,
            Some(camera),
        )
        .expect("built-in scenes are valid")
    }
}

fn mm(x: f64, y: f64, z: f64) -> DVec3 {
    DVec3::new(x, y, z) * 1e-3
}

/// Reflectances of the Cornell box in RGB (white, red, green), as used by the widely shared
/// physically-based conversions of the Cornell data set (e.g. the Mitsuba/Tungsten `cornell-box` scenes by
/// B. Bitterli): the measured spectral reflectances integrated against sRGB primaries.
pub const CORNELL_WHITE: Spectrum = Spectrum::rgb(0.725, 0.71, 0.68);
/// Red (left) wall reflectance.
pub const CORNELL_RED: Spectrum = Spectrum::rgb(0.63, 0.065, 0.05);
/// Green (right) wall reflectance.
pub const CORNELL_GREEN: Spectrum = Spectrum::rgb(0.14, 0.45, 0.091);
/// Emitted radiance Ke of the Cornell light (same source); the scene stores `E = π·Ke`.
pub const CORNELL_LIGHT_RADIANCE: Spectrum = Spectrum::rgb(17.0, 12.0, 4.0);

/// The Cornell box with its two blocks: the published geometry of the Cornell Program of Computer Graphics
/// ("Cornell Box Data", graphics.cornell.edu/online/box/data.html) converted from millimetres to metres,
/// with the light cut out of the ceiling (the data places both at y = 548.8 mm; we split the ceiling into four
/// quads around the light instead of overlapping coplanar faces). Camera: the published one (eye
/// (278, 273, −800) mm looking toward +z, 35 mm focal length, 25 mm film → 39.3° field of view).
pub fn cornell_box() -> Scene {
    let mut b = Builder::new();
    let inside = mm(278.0, 274.4, 279.6);
    let (w, r, g) = (CORNELL_WHITE, CORNELL_RED, CORNELL_GREEN);
    let z = Spectrum::ZERO;
    let floor = b.object("floor");
    let p = [
        mm(552.8, 0.0, 0.0),
        mm(0.0, 0.0, 0.0),
        mm(0.0, 0.0, 559.2),
        mm(549.6, 0.0, 559.2),
    ];
    b.poly(floor, &p, DVec3::Y, w, z);
    let light = b.object("light");
    let lp = [
        mm(343.0, 548.8, 227.0),
        mm(343.0, 548.8, 332.0),
        mm(213.0, 548.8, 332.0),
        mm(213.0, 548.8, 227.0),
    ];
    b.poly(
        light,
        &lp,
        -DVec3::Y,
        Spectrum::ZERO,
        CORNELL_LIGHT_RADIANCE * std::f64::consts::PI,
    );
    let ceiling = b.object("ceiling");
    let y = 548.8;
    for q in [
        [
            mm(556.0, y, 0.0),
            mm(556.0, y, 227.0),
            mm(0.0, y, 227.0),
            mm(0.0, y, 0.0),
        ],
        [
            mm(556.0, y, 332.0),
            mm(556.0, y, 559.2),
            mm(0.0, y, 559.2),
            mm(0.0, y, 332.0),
        ],
        [
            mm(556.0, y, 227.0),
            mm(556.0, y, 332.0),
            mm(343.0, y, 332.0),
            mm(343.0, y, 227.0),
        ],
        [
            mm(213.0, y, 227.0),
            mm(213.0, y, 332.0),
            mm(0.0, y, 332.0),
            mm(0.0, y, 227.0),
        ],
    ] {
        b.poly(ceiling, &q, -DVec3::Y, w, z);
    }
    let back = b.object("back wall");
    let p = [
        mm(549.6, 0.0, 559.2),
        mm(0.0, 0.0, 559.2),
        mm(0.0, 548.8, 559.2),
        mm(556.0, 548.8, 559.2),
    ];
    b.poly(back, &p, inside - p[0], w, z);
    let right = b.object("right wall (green)");
    let p = [
        mm(0.0, 0.0, 559.2),
        mm(0.0, 0.0, 0.0),
        mm(0.0, 548.8, 0.0),
        mm(0.0, 548.8, 559.2),
    ];
    b.poly(right, &p, inside - p[0], g, z);
    let left = b.object("left wall (red)");
    let p = [
        mm(552.8, 0.0, 0.0),
        mm(549.6, 0.0, 559.2),
        mm(556.0, 548.8, 559.2),
        mm(556.0, 548.8, 0.0),
    ];
    b.poly(left, &p, inside - p[0], r, z);
    let short = b.object("short block");
    let top = [
        mm(130.0, 165.0, 65.0),
        mm(82.0, 165.0, 225.0),
        mm(240.0, 165.0, 272.0),
        mm(290.0, 165.0, 114.0),
    ];
    b.block(short, top.map(|p| DVec3::new(p.x, 0.0, p.z)), top, w, false);
    let tall = b.object("tall block");
    let top = [
        mm(423.0, 330.0, 247.0),
        mm(265.0, 330.0, 296.0),
        mm(314.0, 330.0, 456.0),
        mm(472.0, 330.0, 406.0),
    ];
    b.block(tall, top.map(|p| DVec3::new(p.x, 0.0, p.z)), top, w, false);
    let fov = 2.0 * (12.5f64 / 35.0).atan().to_degrees();
    b.finish(
        "cornell-box",
        Camera {
            eye: mm(278.0, 273.0, -800.0),
            target: mm(278.0, 273.0, 0.0),
            up: DVec3::Y,
            fov_y_deg: fov,
        },
    )
}

/// A closed room with high albedo (issue 16): many bounces carry a large part of B, unlike the open
/// scenes. The box `[0,4]×[0,2.5]×[0,3]` (x, y up, z), closed on all six sides, normals inward: white
/// ceiling ρ = 0.85, light-grey floor ρ = (0.75, 0.72, 0.68), back (z = 3) and front (z = 0) walls
/// ρ = 0.8 grey, red left wall (x = 0) ρ = (0.85, 0.3, 0.25), green right wall (x = 4) ρ = (0.3, 0.8, 0.35);
/// a 0.8 × 1.4 × 0.8 grey box (ρ = 0.7) standing on the floor at `[1.4,2.2]×[0,1.4]×[1.2,2.0]` (no bottom
/// face), and a 0.6 × 0.6 ceiling light centred over `(2, 1.5)`, cut out of the ceiling (the ceiling is four
/// quads around it), facing down, ρ = 0, E = 30 (grey). Every ray from inside hits a face from its front.
pub fn closed_room() -> Scene {
    let mut b = Builder::new();
    let (sx, sy, sz) = (4.0, 2.5, 3.0);
    let inside = DVec3::new(sx / 2.0, sy / 2.0, sz / 2.0);
    let z = Spectrum::ZERO;
    let floor = b.object("floor");
    b.poly(
        floor,
        &rect_xz(0.0, sx, 0.0, sz, 0.0),
        DVec3::Y,
        Spectrum::rgb(0.75, 0.72, 0.68),
        z,
    );
    let (lx0, lx1, lz0, lz1) = (1.7, 2.3, 1.2, 1.8);
    let light = b.object("light");
    b.poly(
        light,
        &rect_xz(lx0, lx1, lz0, lz1, sy),
        -DVec3::Y,
        Spectrum::ZERO,
        Spectrum::grey(30.0),
    );
    let ceiling = b.object("ceiling");
    let white = Spectrum::grey(0.85);
    for q in [
        rect_xz(0.0, sx, 0.0, lz0, sy),
        rect_xz(0.0, sx, lz1, sz, sy),
        rect_xz(0.0, lx0, lz0, lz1, sy),
        rect_xz(lx1, sx, lz0, lz1, sy),
    ] {
        b.poly(ceiling, &q, -DVec3::Y, white, z);
    }
    let wall = |x0: f64, z0: f64, x1: f64, z1: f64| {
        [
            DVec3::new(x0, 0.0, z0),
            DVec3::new(x1, 0.0, z1),
            DVec3::new(x1, sy, z1),
            DVec3::new(x0, sy, z0),
        ]
    };
    let grey = Spectrum::grey(0.8);
    for (name, p, rho) in [
        ("back wall", wall(0.0, sz, sx, sz), grey),
        ("front wall", wall(0.0, 0.0, sx, 0.0), grey),
        (
            "left wall (red)",
            wall(0.0, 0.0, 0.0, sz),
            Spectrum::rgb(0.85, 0.3, 0.25),
        ),
        (
            "right wall (green)",
            wall(sx, 0.0, sx, sz),
            Spectrum::rgb(0.3, 0.8, 0.35),
        ),
    ] {
        let o = b.object(name);
        let toward = inside - (p[0] + p[2]) / 2.0;
        b.poly(o, &p, toward, rho, z);
    }
    let blocker = b.object("blocker");
    let top = rect_xz(1.4, 2.2, 1.2, 2.0, 1.4);
    b.block(
        blocker,
        top.map(|p| DVec3::new(p.x, 0.0, p.z)),
        top,
        Spectrum::grey(0.7),
        false,
    );
    b.finish(
        "closed-room",
        Camera {
            eye: DVec3::new(3.7, 1.9, 0.2),
            target: DVec3::new(1.6, 0.7, 2.2),
            up: DVec3::Y,
            fov_y_deg: 70.0,
        },
    )
}

fn rect_xz(x0: f64, x1: f64, z0: f64, z1: f64, y: f64) -> [DVec3; 4] {
    [
        DVec3::new(x0, y, z0),
        DVec3::new(x1, y, z0),
        DVec3::new(x1, y, z1),
        DVec3::new(x0, y, z1),
    ]
}

/// Fig. 4.11: a wall and a floor at right angles, lit from above. Floor `[0,1]×{0}×[0,1]` (normal +y), wall
/// `[0,1]×[0,1]×{0}` (normal +z), both ρ = 0.7; a downward-facing 0.3 × 0.3 light at height 1, centred over
/// `(0.5, 0.35)` (closer to the wall, so that the wall is lit at grazing angles), E = 10. Grey.
pub fn wall_floor() -> Scene {
    let mut b = Builder::new();
    let rho = Spectrum::grey(0.7);
    let z = Spectrum::ZERO;
    let floor = b.object("floor");
    b.poly(floor, &rect_xz(0.0, 1.0, 0.0, 1.0, 0.0), DVec3::Y, rho, z);
    let wall = b.object("wall");
    let p = [
        DVec3::new(0.0, 0.0, 0.0),
        DVec3::new(1.0, 0.0, 0.0),
        DVec3::new(1.0, 1.0, 0.0),
        DVec3::new(0.0, 1.0, 0.0),
    ];
    b.poly(wall, &p, DVec3::Z, rho, z);
    let light = b.object("light");
    b.poly(
        light,
        &rect_xz(0.35, 0.65, 0.2, 0.5, 1.0),
        -DVec3::Y,
        Spectrum::ZERO,
        Spectrum::grey(10.0),
    );
    b.finish(
        "wall-floor",
        Camera {
            eye: DVec3::new(1.9, 1.1, 2.2),
            target: DVec3::new(0.45, 0.3, 0.4),
            up: DVec3::Y,
            fov_y_deg: 40.0,
        },
    )
}

/// Fig. 4.15: a floor and a back wall lit by a ceiling light, with two box-shaped blockers between light and
/// floor casting overlapping shadows. Floor `[0,2]×{0}×[0,2]`, wall at z = 0, light 0.5 × 0.5 at height 1.5,
/// blockers: a 0.4 × 0.3 × 0.4 box on the floor and a thin 0.5 × 0.05 × 0.3 plate floating at height 0.8.
/// ρ = 0.6 everywhere, E = 20 (grey).
pub fn two_blockers() -> Scene {
    two_blockers_with(TwoBlockers {
        name: "two-blockers",
        light: (0.75, 1.25, 20.0),
        block: (rect_xz(0.5, 0.9, 0.6, 1.0, 0.0), 0.3),
        plate: (rect_xz(1.0, 1.5, 1.0, 1.3, 0.8), 0.85),
    })
}

/// Fig. 4.19a/b: the second two-blocker geometry, built for sharp shadows. The floor, wall and camera of
/// [`two_blockers`], but a small 0.2 × 0.2 light at height 1.5 centred over `(1, 1)` with the same power
/// (E = 125), a 0.3 × 0.6 × 0.3 box standing on the floor and a 0.5 × 0.05 × 0.4 plate floating low, at
/// height 0.45–0.5, so that both shadows have narrow penumbrae (about 0.1 for the plate). ρ = 0.6, grey.
///
/// Not in [`BUILTIN_NAMES`] (it has no files in `scenes/`): call it directly.
pub fn two_blockers_sharp() -> Scene {
    two_blockers_with(TwoBlockers {
        name: "two-blockers-sharp",
        light: (0.9, 1.1, 125.0),
        block: (rect_xz(0.55, 0.85, 0.9, 1.2, 0.0), 0.6),
        plate: (rect_xz(1.1, 1.6, 1.1, 1.5, 0.45), 0.5),
    })
}

/// What differs between the two-blocker scenes of figs. 4.15 and 4.19.
struct TwoBlockers {
    name: &'static str,
    /// The square light's extent `[lo, hi]` in x and z at height 1.5, and its emission (grey).
    light: (f64, f64, f64),
    /// The box standing on the floor: its bottom rectangle and the height of its top.
    block: ([DVec3; 4], f64),
    /// The floating plate: its bottom rectangle and the height of its top.
    plate: ([DVec3; 4], f64),
}

/// The floor `[0,2]×{0}×[0,2]`, the wall at z = 0 (1.5 high), a ceiling light, a box on the floor and a
/// floating plate; ρ = 0.6 everywhere, the camera of fig. 4.15.
fn two_blockers_with(t: TwoBlockers) -> Scene {
    let mut b = Builder::new();
    let rho = Spectrum::grey(0.6);
    let z = Spectrum::ZERO;
    let floor = b.object("floor");
    b.poly(floor, &rect_xz(0.0, 2.0, 0.0, 2.0, 0.0), DVec3::Y, rho, z);
    let wall = b.object("wall");
    let p = [
        DVec3::new(0.0, 0.0, 0.0),
        DVec3::new(2.0, 0.0, 0.0),
        DVec3::new(2.0, 1.5, 0.0),
        DVec3::new(0.0, 1.5, 0.0),
    ];
    b.poly(wall, &p, DVec3::Z, rho, z);
    let light = b.object("light");
    let (lo, hi, e) = t.light;
    b.poly(
        light,
        &rect_xz(lo, hi, lo, hi, 1.5),
        -DVec3::Y,
        Spectrum::ZERO,
        Spectrum::grey(e),
    );
    let lift = |(r, top): ([DVec3; 4], f64)| (r, r.map(|v| DVec3::new(v.x, top, v.z)));
    let box1 = b.object("blocker 1 (box)");
    let (bottom, top) = lift(t.block);
    b.block(box1, bottom, top, rho, false);
    let plate = b.object("blocker 2 (plate)");
    let (bottom, top) = lift(t.plate);
    b.block(plate, bottom, top, rho, true);
    b.finish(
        t.name,
        Camera {
            eye: DVec3::new(1.0, 1.2, 4.2),
            target: DVec3::new(1.0, 0.5, 0.8),
            up: DVec3::Y,
            fov_y_deg: 45.0,
        },
    )
}

/// A furnace: the closed unit cube seen from inside (normals inward), every face with emission `e` and
/// reflectance `rho`. Exact solution `B = E/(1 − ρ)` everywhere (docs/design/math.md §8). The built-in uses E = 1, ρ = 0.5.
///
/// # Panics
/// If `rho` is outside `[0,1)` or `e` is negative/not finite (this is a programming error, not input).
pub fn furnace(e: Spectrum, rho: Spectrum) -> Scene {
    let mut b = Builder::new();
    let c = DVec3::splat(0.5);
    let o = b.object("box");
    let corners = |x: f64, y: f64, z: f64| DVec3::new(x, y, z);
    let faces: [[DVec3; 4]; 6] = [
        rect_xz(0.0, 1.0, 0.0, 1.0, 0.0),
        rect_xz(0.0, 1.0, 0.0, 1.0, 1.0),
        [
            corners(0., 0., 0.),
            corners(1., 0., 0.),
            corners(1., 1., 0.),
            corners(0., 1., 0.),
        ],
        [
            corners(0., 0., 1.),
            corners(1., 0., 1.),
            corners(1., 1., 1.),
            corners(0., 1., 1.),
        ],
        [
            corners(0., 0., 0.),
            corners(0., 1., 0.),
            corners(0., 1., 1.),
            corners(0., 0., 1.),
        ],
        [
            corners(1., 0., 0.),
            corners(1., 1., 0.),
            corners(1., 1., 1.),
            corners(1., 0., 1.),
        ],
    ];
    for q in faces {
        let m = (q[0] + q[2]) * 0.5;
        b.poly(o, &q, c - m, rho, e);
    }
    Scene::new(
        "furnace",
        "builtin:furnace",
        b.faces,
        b.objects,
        Some(Camera {
            eye: DVec3::new(0.5, 0.5, 0.05),
            target: DVec3::new(0.5, 0.5, 1.0),
            up: DVec3::Y,
            fov_y_deg: 90.0,
        }),
    )
    .expect("furnace parameters must be valid")
}

fn seg(a: (f64, f64), b: (f64, f64), rho: f64, e: f64, obj: u32, surf: u32) -> Segment {
    Segment::new(
        DVec2::new(a.0, a.1),
        DVec2::new(b.0, b.1),
        Spectrum::grey(rho),
        Spectrum::grey(e),
        obj,
        surf,
    )
}

/// Fig. 4.1a: a vertical wall that emits (x = 0, y ∈ \[0,1\], facing +x, E = 1, ρ = 0.5) and a floor with moderate
/// emission (y = 0, x ∈ \[0,1\], facing +y, E = 0.2, ρ = 0.5), meeting in a corner. Segment order: wall from the
/// top down, then floor from the corner outward, so `s = 0` is the top of the wall and `s = 1` the far end of the
/// floor (the dissertation runs the other way: its parameter is `1 − s`).
pub fn flatland_corner() -> FlatlandScene {
    let segs = vec![
        seg((0.0, 1.0), (0.0, 0.0), 0.5, 1.0, 0, 0),
        seg((0.0, 0.0), (1.0, 0.0), 0.5, 0.2, 1, 1),
    ];
    FlatlandScene::new(
        "flatland-corner",
        "builtin:flatland-corner",
        segs,
        vec!["wall (light)".into(), "floor".into()],
        Some(FlatView {
            min: DVec2::new(-0.1, -0.1),
            max: DVec2::new(1.1, 1.1),
        }),
        false,
    )
    .expect("valid")
}

/// Fig. 4.6a: a ceiling light (y = 1, x ∈ [0.3, 0.7], facing down, E = 1, ρ = 0), a two-sided blocking edge
/// (y = 0.5, x ∈ [0.35, 0.65], ρ = 0.5, two back-to-back segments) and a floor (y = 0, x ∈ \[0,1\], facing up,
/// ρ = 0.5). Segment order: light (right to left), blocker underside, blocker top, floor (left to right).
pub fn flatland_blocker() -> FlatlandScene {
    let segs = vec![
        seg((0.7, 1.0), (0.3, 1.0), 0.0, 1.0, 0, 0),
        seg((0.65, 0.5), (0.35, 0.5), 0.5, 0.0, 1, 1),
        seg((0.35, 0.5), (0.65, 0.5), 0.5, 0.0, 1, 2),
        seg((0.0, 0.0), (1.0, 0.0), 0.5, 0.0, 2, 3),
    ];
    FlatlandScene::new(
        "flatland-blocker",
        "builtin:flatland-blocker",
        segs,
        vec!["ceiling light".into(), "blocker".into(), "floor".into()],
        Some(FlatView {
            min: DVec2::new(-0.1, -0.1),
            max: DVec2::new(1.1, 1.1),
        }),
        false,
    )
    .expect("valid")
}

/// The Cornell box ([`cornell_box`]) with every triangle cut into a uniform grid of k² smaller
/// ones (k per face, so that they all have about the same area), about `n` triangles in all.
/// Same geometry, materials and light as `cornell-box`, so the same radiosity: a solver whose cost
/// or error depends on the polygon count shows it here.
pub fn tessellated_cornell(n: usize) -> Scene {
    let base = cornell_box();
    let total: f64 = base.faces.iter().map(|f| f.area).sum();
    let target = total / n.max(1) as f64;
    let mut faces = Vec::with_capacity(n + n / 4);
    for f in &base.faces {
        let k = ((f.area / target).sqrt().round() as usize).max(1);
        let [p0, p1, p2] = f.v;
        let (e1, e2) = ((p1 - p0) / k as f64, (p2 - p0) / k as f64);
        let v = |i: usize, j: usize| p0 + e1 * i as f64 + e2 * j as f64;
        for i in 0..k {
            for j in 0..k - i {
                // The upward and downward triangles of the grid keep p0, p1, p2's winding.
                let up = [v(i, j), v(i + 1, j), v(i, j + 1)];
                faces.push(Face::new(up, f.rho, f.emission, f.object, f.surface));
                if i + j + 1 < k {
                    let down = [v(i + 1, j), v(i + 1, j + 1), v(i, j + 1)];
                    faces.push(Face::new(down, f.rho, f.emission, f.object, f.surface));
                }
            }
        }
    }
    Scene::new(
        &format!("tessellated-cornell-{n}"),
        "generated:tessellated-cornell",
        faces,
        base.objects.clone(),
        Some(base.camera),
    )
    .expect("generated scene is valid")
}

/// A large test scene of about `n` triangles: the Cornell box (walls, light, blocks) plus a field of randomly
/// placed, randomly rotated small boxes (12 triangles each) filling the lower half of the room, deterministic
/// per `seed`. For BVH and sampler benchmarks at 100k and 1M triangles.
pub fn random_boxes(n: usize, seed: u64) -> Scene {
    let base = cornell_box();
    let mut faces = base.faces.clone();
    let mut objects = base.objects.clone();
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    let boxes = n.saturating_sub(faces.len()) / 12;
    let obj = objects.len() as u32;
    objects.push("random boxes".into());
    let mut surf = faces.iter().map(|f| f.surface).max().unwrap_or(0) + 1;
    let size = 0.5 / (boxes.max(1) as f64).cbrt();
    for _ in 0..boxes {
        let c = DVec3::new(
            rng.random_range(0.03..0.52),
            rng.random_range(0.03..0.5),
            rng.random_range(0.03..0.53),
        );
        let ax = DVec3::new(
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
        )
        .normalize_or(DVec3::X);
        let q = glam::DQuat::from_axis_angle(ax, rng.random_range(0.0..std::f64::consts::TAU));
        let h = DVec3::new(
            rng.random_range(0.3..1.0),
            rng.random_range(0.3..1.0),
            rng.random_range(0.3..1.0),
        ) * size
            * 0.5;
        let corner = |i: usize| {
            let s = DVec3::new(
                if i & 1 == 0 { -1.0 } else { 1.0 },
                if i & 2 == 0 { -1.0 } else { 1.0 },
                if i & 4 == 0 { -1.0 } else { 1.0 },
            );
            c + q * (s * h)
        };
        // six faces as corner-index quads, each wound outward
        for quad in [
            [0, 2, 3, 1],
            [4, 5, 7, 6],
            [0, 1, 5, 4],
            [2, 6, 7, 3],
            [0, 4, 6, 2],
            [1, 3, 7, 5],
        ] {
            let p = quad.map(corner);
            let mid = (p[0] + p[2]) * 0.5;
            let mut t1 = [p[0], p[1], p[2]];
            let mut t2 = [p[0], p[2], p[3]];
            if (p[1] - p[0]).cross(p[2] - p[0]).dot(mid - c) < 0.0 {
                t1.swap(1, 2);
                t2.swap(1, 2);
            }
            faces.push(Face::new(t1, CORNELL_WHITE, Spectrum::ZERO, obj, surf));
            faces.push(Face::new(t2, CORNELL_WHITE, Spectrum::ZERO, obj, surf));
            surf += 1;
        }
    }
    Scene::new(
        &format!("random-boxes-{n}"),
        "generated:random-boxes",
        faces,
        objects,
        Some(base.camera),
    )
    .expect("generated scene is valid")
}

#[cfg(test)]
mod random_boxes_name_tests {
    use super::*;

    /// The closed room loads by name and is closed: rays from points spread through the free interior, in
    /// directions spread over the sphere, all hit a face, and from its front side.
    #[test]
    fn closed_room_is_closed() {
        let s = builtin("closed-room").unwrap().into_3d().unwrap();
        assert!(s.faces.iter().all(|f| f.rho.max() <= 0.85));
        assert!(
            s.faces.iter().any(|f| f.rho.0[0] != f.rho.0[1]),
            "coloured walls"
        );
        assert_eq!(s.emitters().len(), 2);
        let bvh = crate::SceneBvh::new(&s);
        let mut k = 0u32;
        for i in 0..64 {
            let f = |a: f64| (0.5 + a * i as f64).fract();
            let o = DVec3::new(
                0.05 + 3.9 * f(0.618_034),
                0.05 + 2.4 * f(0.754_878),
                0.05 + 2.9 * f(0.569_840),
            );
            // outside the blocker
            if (1.4..=2.2).contains(&o.x) && o.y <= 1.4 && (1.2..=2.0).contains(&o.z) {
                continue;
            }
            for j in 0..200 {
                let u = (j as f64 + 0.5) / 200.0;
                let phi = j as f64 * 2.399_963;
                let (ct, st) = (1.0 - 2.0 * u, (1.0 - (1.0 - 2.0 * u).powi(2)).sqrt());
                let d = DVec3::new(st * phi.cos(), ct, st * phi.sin());
                let h = bvh.closest_hit(o, d, f64::INFINITY, u32::MAX);
                let h = h.unwrap_or_else(|| panic!("ray {o} {d} escapes"));
                assert!(
                    s.faces[h.face as usize].normal.dot(d) < 0.0,
                    "ray {o} {d} hits a back face"
                );
                k += 1;
            }
        }
        assert!(k > 10_000);
    }

    #[test]
    fn random_boxes_by_name() {
        let AnyScene::ThreeD(s) = builtin("random-boxes-1000").unwrap() else {
            panic!("3-D scene expected")
        };
        assert!((990..=1000).contains(&s.faces.len()), "{}", s.faces.len());
        assert!(is_builtin("random-boxes-1_000"));
        let AnyScene::ThreeD(t) = builtin("tessellated-cornell-10000").unwrap() else {
            panic!("3-D scene expected")
        };
        let cornell = cornell_box();
        let area = |s: &Scene| s.faces.iter().map(|f| f.area).sum::<f64>();
        assert!(
            (8000..=12_000).contains(&t.faces.len()),
            "{}",
            t.faces.len()
        );
        assert!((area(&t) - area(&cornell)).abs() < 1e-9 * area(&cornell));
        let emitting = |s: &Scene| {
            s.faces
                .iter()
                .filter(|f| !f.emission.is_zero())
                .map(|f| f.area)
                .sum::<f64>()
        };
        assert!((emitting(&t) - emitting(&cornell)).abs() < 1e-9 * emitting(&cornell));
        assert!(!is_builtin("random-boxes-7.obj"));
        assert!(!is_builtin("random-boxes-"));
        assert!(builtin("random-boxes-5").is_err());
        assert!(builtin("tessellated-cornell-7").is_err());
        assert!(builtin("random-boxes-999999999999").is_err());
    }
}

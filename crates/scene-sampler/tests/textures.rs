//! Albedo textures (issue 18 item 4): `map_Kd` with `vt` in OBJ, sRGB decoded, ρ(x) = Kd × texel.

use glam::DVec3;
use scene_sampler::{Scene, srgb_to_linear};

fn checker_room() -> Scene {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../../scenes/checker-room.obj");
    scene_sampler::load_obj(path).unwrap()
}

/// The floor's checks: 8×8 texels repeated 4 times over the 1 m floor (a texel is 1/32 m), light
/// sRGB 230 and dark 40, times Kd 0.9; at texel centres the lookup is the texel itself.
#[test]
fn the_floor_reads_its_checkerboard() {
    let scene = checker_room();
    assert_eq!(scene.textures.len(), 2);
    let floor = scene
        .faces
        .iter()
        .position(|f| scene.objects[f.object as usize] == "floor")
        .unwrap() as u32;
    let (light, dark) = (
        0.9 * srgb_to_linear(230.0 / 255.0),
        0.9 * srgb_to_linear(40.0 / 255.0),
    );
    // Texel (0, 0) of the image (top-left, light) is at OBJ v near 1 of the first tile: world z
    // near 1/4 (vt v = 4 at z = 1; the image's top row is v = 1, 2, 3, 4 from the bottom).
    let centre = |i: f64, j: f64| DVec3::new((i + 0.5) / 32.0, 0.0, (j + 0.5) / 32.0);
    let mut seen = [0usize; 2];
    for i in 0..8 {
        for j in 0..8 {
            let p = centre(f64::from(i), f64::from(j));
            let face = (0..scene.faces.len() as u32)
                .filter(|&f| scene.objects[scene.faces[f as usize].object as usize] == "floor")
                .find(|&f| scene.faces[f as usize].closest_point(p).distance(p) < 1e-12)
                .unwrap_or(floor);
            let rho = scene.rho_at(face, p).0[0];
            let is_light = (rho - light).abs() < 1e-6;
            assert!(is_light || (rho - dark).abs() < 1e-6, "{p}: {rho}");
            seen[usize::from(is_light)] += 1;
        }
    }
    assert_eq!(seen, [32, 32], "half the checks light");
    // Neighbouring texels alternate.
    let a = scene.rho_at(floor, centre(0.0, 0.0)).0[0];
    let b = scene.rho_at(floor, centre(1.0, 0.0)).0[0];
    assert!((a - b).abs() > 0.5 * (light - dark));
    // The face's ρ is the mean of its texture (half light, half dark, bilinear in between).
    let mean = scene.faces[floor as usize].rho.0[0];
    assert!((mean - 0.5 * (light + dark)).abs() < 0.02, "{mean}");
}

/// The back wall's colour checks reach the three bands apart.
#[test]
fn the_back_wall_is_coloured() {
    let scene = checker_room();
    assert_eq!(scene.bands, 3);
    let back = scene
        .faces
        .iter()
        .position(|f| scene.objects[f.object as usize] == "back")
        .unwrap() as u32;
    let rho = scene
        .rho_at(back, DVec3::new(0.5 / 16.0, 0.5 / 16.0, 1.0))
        .0;
    assert!(rho[0] != rho[2], "{rho:?}");
}

/// A missing texture file is an error naming the material; options on `map_Kd` too.
#[test]
fn bad_texture_statements_are_errors() {
    let dir = std::env::temp_dir().join(format!("gcr-tex-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let obj = "mtllib t.mtl\nv 0 0 0\nv 1 0 0\nv 0 0 1\nvt 0 0\nvt 1 0\nvt 0 1\nusemtl m\nf 1/1 3/3 2/2\n\
               v 0 1 0\nv 0 1 1\nv 1 1 0\nusemtl l\nf 4 5 6\n";
    std::fs::write(dir.join("t.obj"), obj).unwrap();
    for (mtl, want) in [
        (
            "newmtl m\nKd 0.5 0.5 0.5\nmap_Kd nothere.png\nnewmtl l\nKe 1 1 1\n",
            "nothere.png",
        ),
        (
            "newmtl m\nKd 0.5 0.5 0.5\nmap_Kd -s 2 2 1 t.png\nnewmtl l\nKe 1 1 1\n",
            "options",
        ),
    ] {
        std::fs::write(dir.join("t.mtl"), mtl).unwrap();
        let err = scene_sampler::load_obj(dir.join("t.obj"))
            .unwrap_err()
            .to_string();
        assert!(err.contains(want), "{err}");
    }
}

/// The same room as .glb with the PNGs embedded (`xtask/py/make_checker_room_glb.py`): the same
/// reflectance at the same points as the OBJ.
#[test]
fn the_glb_reads_the_same_textures_as_the_obj() {
    let obj = checker_room();
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../../scenes/checker-room.glb");
    let glb = scene_sampler::load_gltf(path).unwrap();
    assert_eq!(glb.textures.len(), 2);
    assert_eq!(glb.faces.len(), obj.faces.len());
    for (fa, a) in obj.faces.iter().enumerate() {
        // the same triangle in the .glb (f32 positions, node order may differ)
        let fb = (glb.faces.iter())
            .position(|b| (0..3).all(|k| a.v[k].distance(b.v[k]) < 1e-6))
            .unwrap_or_else(|| panic!("face {fa} not in the .glb")) as u32;
        assert_eq!(
            a.texture.is_some(),
            glb.faces[fb as usize].texture.is_some()
        );
        for (u, v) in [(0.2, 0.3), (0.6, 0.1), (0.05, 0.9)] {
            let p = a.point(u, v * (1.0 - u));
            let (ra, rb) = (obj.rho_at(fa as u32, p).0, glb.rho_at(fb, p).0);
            for k in 0..3 {
                assert!((ra[k] - rb[k]).abs() < 1e-5, "{p}: {ra:?} vs {rb:?}");
            }
        }
    }
}

/// A textured face written twice with other texture coordinates (a model's UV seam, 152 pairs in a
/// public cathedral) is merged with a warning naming both faces, not refused; a coincident face
/// with another texture still is.
#[test]
fn coincident_faces_differing_only_in_uvs_are_merged() {
    let dir = std::env::temp_dir().join(format!("gcr-tex-dup-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let mut png = std::io::Cursor::new(Vec::new());
    image::RgbImage::from_fn(4, 4, |x, y| image::Rgb([(40 * (x + y)) as u8; 3]))
        .write_to(&mut png, image::ImageFormat::Png)
        .unwrap();
    std::fs::write(dir.join("t.png"), png.into_inner()).unwrap();
    std::fs::write(dir.join("u.png"), std::fs::read(dir.join("t.png")).unwrap()).unwrap();
    std::fs::write(
        dir.join("t.mtl"),
        "newmtl m\nKd 0.8 0.8 0.8\nmap_Kd t.png\nnewmtl n\nKd 0.8 0.8 0.8\nmap_Kd u.png\n\
         newmtl l\nKe 1 1 1\n",
    )
    .unwrap();
    let obj = |second: &str| {
        format!(
            "mtllib t.mtl\nv 0 0 0\nv 1 0 0\nv 0 0 1\nvt 0 0\nvt 1 0\nvt 0 1\nvt 0.5 0.5\n\
             o a\nusemtl m\nf 1/1 3/3 2/2\no b\nusemtl {second}\nf 1/4 3/3 2/2\n\
             v 0 1 0\nv 0 1 1\nv 1 1 0\no lamp\nusemtl l\nf 4 5 6\n"
        )
    };
    std::fs::write(dir.join("same.obj"), obj("m")).unwrap();
    let s = scene_sampler::load_obj(dir.join("same.obj")).unwrap();
    assert_eq!(s.faces.len(), 2, "{:?}", s.warnings);
    let w: Vec<_> = s
        .warnings
        .iter()
        .filter(|w| w.contains("duplicate"))
        .collect();
    assert_eq!(w.len(), 1, "{:?}", s.warnings);
    assert!(
        w[0].contains("face 1 (object `b`) = face 0 (object `a`) (other texture coordinates)"),
        "{w:?}"
    );
    // the first face's mapping is kept
    assert_eq!(
        s.faces[0].texture.unwrap().uv[0],
        glam::DVec2::new(0.0, 1.0)
    );
    std::fs::write(dir.join("other.obj"), obj("n")).unwrap();
    let e = scene_sampler::load_obj(dir.join("other.obj")).unwrap_err();
    assert!(e.to_string().contains("different material"), "{e}");
}

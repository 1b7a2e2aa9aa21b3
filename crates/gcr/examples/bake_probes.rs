//! Reads a bake (`gcr solve --mesh out.glb`) back as probes, for measuring its accuracy against
//! `gcr reference` (docs/guide/bakes.md):
//!
//! ```sh
//! # every vertex of the bake, in world coordinates (moved 10⁻⁴ of the way into a triangle of its
//! # own, so that the probe snaps onto the vertex's face): `x y z nx ny nz`, its _RADIOSITY `r g b`
//! cargo run --release -p gcr --example bake_probes -- vertices out.glb verts.txt verts.b.txt
//! # the bake interpolated (barycentric, as a viewer shows it) at probe points: `r g b` per probe
//! cargo run --release -p gcr --example bake_probes -- interpolate out.glb line.txt line.bake.txt
//! # relative L2 error ‖a − b‖₂ / ‖b‖₂ over all values of two `r g b` files (b the reference)
//! cargo run --release -p gcr --example bake_probes -- compare a.txt b.txt
//! ```

use glam::{DMat4, DVec3};
use std::fmt::Write as _;

type Error = Box<dyn std::error::Error>;

/// A bake vertex: world position, world normal, B.
type Vertex = (DVec3, DVec3, [f64; 3]);

/// A bake triangle in world coordinates with `_RADIOSITY` at its corners.
struct Triangle {
    v: [DVec3; 3],
    b: [[f64; 3]; 3],
    normal: DVec3,
}

/// Every vertex (world position moved just inside a triangle of its own, world normal, B) and
/// every triangle of the bake.
fn read_bake(path: &str) -> Result<(Vec<Vertex>, Vec<Triangle>), Error> {
    let (doc, buffers, _) = gltf::import(path)?;
    let mut world = vec![None; doc.nodes().count()];
    let mut stack: Vec<(gltf::Node, DMat4)> = doc
        .default_scene()
        .ok_or("no scene")?
        .nodes()
        .map(|n| (n, DMat4::IDENTITY))
        .collect();
    while let Some((n, parent)) = stack.pop() {
        let m = n.transform().matrix().map(|c| c.map(f64::from));
        let w = parent * DMat4::from_cols_array_2d(&m);
        world[n.index()] = Some(w);
        stack.extend(n.children().map(|c| (c, w)));
    }
    let (mut verts, mut tris) = (Vec::new(), Vec::new());
    for node in doc.nodes() {
        let (Some(mesh), Some(w)) = (node.mesh(), world[node.index()]) else {
            continue;
        };
        let normal_to_world = w.inverse().transpose();
        for prim in mesh.primitives() {
            let r = prim.reader(|b| Some(&buffers[b.index()]));
            let d = |p: [f32; 3]| DVec3::new(p[0].into(), p[1].into(), p[2].into());
            let pos: Vec<DVec3> = (r.read_positions().ok_or("no POSITION")?)
                .map(|p| w.transform_point3(d(p)))
                .collect();
            let nrm: Vec<DVec3> = (r.read_normals().ok_or("no NORMAL")?)
                .map(|n| normal_to_world.transform_vector3(d(n)).normalize())
                .collect();
            let acc = prim
                .attributes()
                .find(|(s, _)| matches!(s, gltf::Semantic::Extras(n) if n == "RADIOSITY"))
                .ok_or("no _RADIOSITY")?
                .1;
            let view = acc.view().ok_or("sparse _RADIOSITY")?;
            let data = &buffers[view.buffer().index()][view.offset() + acc.offset()..];
            let b: Vec<[f64; 3]> = (0..acc.count())
                .map(|i| {
                    std::array::from_fn(|c| {
                        let at = 12 * i + 4 * c;
                        f64::from(f32::from_le_bytes(
                            data[at..at + 4].try_into().expect("4 bytes"),
                        ))
                    })
                })
                .collect();
            let base = verts.len();
            verts.extend((0..pos.len()).map(|i| (pos[i], nrm[i], b[i])));
            let idx: Vec<u32> = r.read_indices().ok_or("no indices")?.into_u32().collect();
            // a vertex on an edge between two faces (the light and the ceiling, a wall and the
            // floor) is as near to the other face as to its own: as a probe it is moved 10⁻⁴ of
            // the way to the centre of a triangle of its own, so that it snaps onto its face
            let mut moved = vec![false; pos.len()];
            for t in idx.chunks_exact(3) {
                let c = (pos[t[0] as usize] + pos[t[1] as usize] + pos[t[2] as usize]) / 3.0;
                for &v in t {
                    if !std::mem::replace(&mut moved[v as usize], true) {
                        let p = &mut verts[base + v as usize].0;
                        *p += 1e-4 * (c - *p);
                    }
                }
            }
            for t in idx.chunks_exact(3) {
                let i = [0, 1, 2].map(|k| t[k] as usize);
                tris.push(Triangle {
                    v: i.map(|k| pos[k]),
                    b: i.map(|k| b[k]),
                    normal: verts[base + i[0]].1,
                });
            }
        }
    }
    Ok((verts, tris))
}

/// `x y z nx ny nz` per line (`#` comments and blank lines skipped).
fn read_points(path: &str) -> Result<Vec<(DVec3, DVec3)>, Error> {
    let mut out = Vec::new();
    for line in std::fs::read_to_string(path)?.lines() {
        let l = line.trim();
        if l.is_empty() || l.starts_with('#') {
            continue;
        }
        let v: Vec<f64> = l
            .split_whitespace()
            .map(str::parse)
            .collect::<Result<_, _>>()?;
        let [x, y, z, a, b, c] = v[..] else {
            return Err(format!("`{l}`: not x y z nx ny nz").into());
        };
        out.push((DVec3::new(x, y, z), DVec3::new(a, b, c).normalize()));
    }
    Ok(out)
}

/// `r g b` per line.
fn read_values(path: &str) -> Result<Vec<f64>, Error> {
    Ok(std::fs::read_to_string(path)?
        .split_whitespace()
        .map(str::parse)
        .collect::<Result<_, _>>()?)
}

/// The bake's B at `p`: barycentric in the nearest triangle facing along `n`.
fn interpolate(tris: &[Triangle], p: DVec3, n: DVec3) -> Option<[f64; 3]> {
    let mut best: Option<(f64, [f64; 3])> = None;
    for t in tris.iter().filter(|t| t.normal.dot(n) > 0.9) {
        let [a, b, c] = t.v;
        let face = scene_sampler::Face::new(t.v, Default::default(), Default::default(), 0, 0);
        let q = face.closest_point(p);
        let d = q.distance(p);
        if best.is_some_and(|(e, _)| e <= d) {
            continue;
        }
        // barycentric weights of q
        let (v0, v1, v2) = (b - a, c - a, q - a);
        let (d00, d01, d11) = (v0.dot(v0), v0.dot(v1), v1.dot(v1));
        let (d20, d21) = (v2.dot(v0), v2.dot(v1));
        let den = d00 * d11 - d01 * d01;
        let w1 = (d11 * d20 - d01 * d21) / den;
        let w2 = (d00 * d21 - d01 * d20) / den;
        let w0 = 1.0 - w1 - w2;
        let v = std::array::from_fn(|k| w0 * t.b[0][k] + w1 * t.b[1][k] + w2 * t.b[2][k]);
        best = Some((d, v));
    }
    best.map(|(_, v)| v)
}

fn main() -> Result<(), Error> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let arg = |i: usize| -> Result<&str, Error> {
        args.get(i)
            .map(String::as_str)
            .ok_or_else(|| "usage: see the example's docs".into())
    };
    match arg(0)? {
        "vertices" => {
            let (verts, _) = read_bake(arg(1)?)?;
            let (mut probes, mut values) = (String::new(), String::new());
            for (p, n, b) in &verts {
                writeln!(probes, "{} {} {} {} {} {}", p.x, p.y, p.z, n.x, n.y, n.z)?;
                writeln!(values, "{} {} {}", b[0], b[1], b[2])?;
            }
            std::fs::write(arg(2)?, probes)?;
            std::fs::write(arg(3)?, values)?;
            println!("{} vertices", verts.len());
        }
        "interpolate" => {
            let (_, tris) = read_bake(arg(1)?)?;
            let mut out = String::new();
            for (p, n) in read_points(arg(2)?)? {
                let b = interpolate(&tris, p, n).ok_or("no bake triangle faces a probe")?;
                writeln!(out, "{} {} {}", b[0], b[1], b[2])?;
            }
            std::fs::write(arg(3)?, out)?;
        }
        "compare" => {
            let (a, b) = (read_values(arg(1)?)?, read_values(arg(2)?)?);
            if a.len() != b.len() {
                return Err(format!("{} values against {}", a.len(), b.len()).into());
            }
            let (mut e, mut r) = (0.0, 0.0);
            for (x, y) in a.iter().zip(&b) {
                e += (x - y) * (x - y);
                r += y * y;
            }
            println!(
                "relative L2 {:.4} over {} points",
                (e / r).sqrt(),
                a.len() / 3
            );
        }
        other => return Err(format!("unknown command `{other}`").into()),
    }
    Ok(())
}

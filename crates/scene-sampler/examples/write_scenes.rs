//! Writes every built-in scene to a directory (default `scenes/`): 3-D scenes as OBJ + MTL and glTF,
//! Flatland scenes as JSON, plus a probe file per scene (`<name>.probes.txt`) with points at face centroids.
//!
//! `cargo run -p scene-sampler --example write_scenes -- scenes`

use scene_sampler::{AnyScene, BUILTIN_NAMES, FlatProbe, Probe, builtin, probe};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let dir = std::env::args().nth(1).unwrap_or_else(|| "scenes".into());
    std::fs::create_dir_all(&dir)?;
    for name in BUILTIN_NAMES {
        match builtin(name)? {
            AnyScene::ThreeD(s) => {
                let p = scene_sampler::write_obj(&s, &dir)?;
                let g = scene_sampler::write_gltf(&s, &dir)?;
                // One probe per input surface: the first triangle centroid of that surface, or
                // else the first point of a barycentric grid over its triangles, that is not
                // buried inside a solid (e.g. floor under a block). A point is buried when every
                // ray over its hemisphere hits the back of a face.
                let bvh = scene_sampler::SceneBvh::new(&s);
                let buried = |point: glam::DVec3, normal: glam::DVec3, face: u32| {
                    let from = scene_sampler::SurfacePoint {
                        point,
                        normal,
                        face,
                    };
                    (0..16).all(|k| {
                        let u = [(k as f64 + 0.5) / 16.0, (k as f64 * 0.618_034).fract()];
                        let dir = scene_sampler::cosine_hemisphere(normal, u);
                        bvh.trace_from(&from, dir)
                            .is_some_and(|h| s.faces[h.face as usize].normal.dot(dir) > 0.0)
                    })
                };
                let mut seen = std::collections::HashSet::new();
                let surfaces: Vec<u32> = s
                    .faces
                    .iter()
                    .map(|f| f.surface)
                    .filter(|x| seen.insert(*x))
                    .collect();
                let probes: Vec<Probe> = surfaces
                    .iter()
                    .map(|&surface| {
                        let faces: Vec<(usize, &scene_sampler::Face)> = s
                            .faces
                            .iter()
                            .enumerate()
                            .filter(|(_, f)| f.surface == surface)
                            .collect();
                        let grid = (1..8).flat_map(|i| (1..8 - i).map(move |j| (i, j)));
                        let candidates = faces
                            .iter()
                            .map(|(i, f)| (*i, f.centroid(), f.normal))
                            .chain(faces.iter().flat_map(|(i, f)| {
                                grid.clone().map(move |(a, b)| {
                                    let (a, b) = (a as f64 / 8.0, b as f64 / 8.0);
                                    let p = f.v[0] * (1.0 - a - b) + f.v[1] * a + f.v[2] * b;
                                    (*i, p, f.normal)
                                })
                            }));
                        let (_, point, normal) = candidates
                            .clone()
                            .find(|(i, p, n)| !buried(*p, *n, *i as u32))
                            .unwrap_or_else(|| {
                                (faces[0].0, faces[0].1.centroid(), faces[0].1.normal)
                            });
                        Probe {
                            point,
                            normal,
                            line: 0,
                        }
                    })
                    .collect();
                std::fs::write(
                    format!("{dir}/{name}.probes.txt"),
                    probe::format_probes(&probes),
                )?;
                println!(
                    "{name}: {} triangles -> {} and {}",
                    s.faces.len(),
                    p.display(),
                    g.display()
                );
            }
            AnyScene::Flatland(s) => {
                let p = scene_sampler::write_flatland(&s, &dir)?;
                let probes: Vec<FlatProbe> = s
                    .segments
                    .iter()
                    .map(|g| FlatProbe {
                        point: g.point(0.5),
                        normal: g.normal,
                        line: 0,
                    })
                    .collect();
                std::fs::write(
                    format!("{dir}/{name}.probes.txt"),
                    probe::format_flat_probes(&probes),
                )?;
                println!("{name}: {} segments -> {}", s.segments.len(), p.display());
            }
        }
    }
    Ok(())
}

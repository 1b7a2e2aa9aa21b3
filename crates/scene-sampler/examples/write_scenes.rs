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
                // one probe per input surface (the centroid of its first triangle), on the front side
                let mut seen = std::collections::HashSet::new();
                let probes: Vec<Probe> = s
                    .faces
                    .iter()
                    .filter(|f| seen.insert(f.surface))
                    .map(|f| Probe {
                        point: f.centroid(),
                        normal: f.normal,
                        line: 0,
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

//! B at the probes of a probe file by the NEE path tracer, fixed paths per probe: one line
//! `B_r B_g B_b se_r se_g se_b` per probe (for checking other renderers against it, e.g. Mitsuba 3 in
//! docs/results/benchmarks-field.md).
//!
//! `cargo run --release -p baselines --example probe_reference -- cornell-box scenes/cornell-box.probes.txt 200000`

use scene_sampler::{SceneBvh, read_probes};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let name = args.get(1).map_or("cornell-box", |s| s.as_str());
    let file = args
        .get(2)
        .map_or("scenes/cornell-box.probes.txt", |s| s.as_str());
    let paths: usize = args.get(3).map_or(Ok(200_000), |s| s.parse())?;
    let scene = scene_sampler::builtin(name)?.into_3d()?;
    let bvh = SceneBvh::new(&scene);
    let points = scene.snap_probes(&read_probes(file)?, file)?;
    for e in baselines::pointwise::radiosity_at(&scene, &bvh, &points, paths, 0x5EED) {
        let (m, s) = (e.mean, e.std_error);
        println!("{} {} {} {} {} {}", m[0], m[1], m[2], s[0], s[1], s[2]);
    }
    Ok(())
}

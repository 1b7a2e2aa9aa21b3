//! The smallest complete use of the library: solve the built-in Cornell box, then read the
//! radiosity at the centre of every wall face and write the re-triangulated scene as a glTF
//! binary with vertex colours.
//!
//! ```sh
//! cargo run --release -p gcr --example solve -- [cells] [out.glb]
//! ```

use gcr::output::Exposure;
use gcr::output::write_glb;
use gcr::{Domain, Emitters, RetriangulateLimits, SolveConfig, output_mesh, radiosity_at_points};
use scene_sampler::{KernelSampler, SceneBvh};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let cells: usize = args.next().map_or(Ok(300), |s| s.parse())?;
    let out = args.next().unwrap_or_else(|| "cornell.glb".into());

    // A scene (built-in, or `scene_sampler::load("room.obj")`), its BVH, and the kernel domain
    // over it: the rays (x, y) the kernel network learns from.
    let scene = scene_sampler::builtin("cornell-box")?.into_3d()?;
    let bvh = SceneBvh::new(&scene);
    let domain = Domain::ThreeD(KernelSampler::new(&scene, &bvh));

    // The solve: networks grown to `cells` kernel cells with FEM steps in between.
    let config = SolveConfig {
        kernel_cells: cells,
        ..SolveConfig::default()
    };
    let trained = gcr::solve(&domain, &config, &mut |_| {})?;
    println!(
        "{} kernel cells, {} FEM steps, {:.1} s",
        trained.metrics.kernel_cells, trained.metrics.fem_steps, trained.metrics.seconds.total
    );

    // Radiosity B (exitance, per band) at any surface points: here each face's centroid.
    let points: Vec<_> = (scene.faces.iter().enumerate())
        .map(|(i, f)| ((f.v[0] + f.v[1] + f.v[2]) / 3.0, f.normal, i as u32))
        .collect();
    let b = radiosity_at_points(&domain, &trained, &Emitters::new(&domain), &config, &points)?;
    for (i, g) in b.iter().enumerate().step_by(4) {
        println!("face {i:>3}: B = {:.3?}", g.radiosity);
    }

    // The scene re-triangulated to the shading network's resolution, B at every vertex.
    let (mesh, _) = output_mesh(&domain, &trained, &config, RetriangulateLimits::default())?;
    let file = std::io::BufWriter::new(std::fs::File::create(&out)?);
    let lit = mesh.radiosity.clone();
    write_glb(&mesh, &scene, &Exposure::auto(lit), file)?;
    println!("{} vertices written to {out}", mesh.vertex_count());
    Ok(())
}

//! The breaking operator (sec. 4.4.2, fig. 4.18; `gcr::Breaking`): error of the base
//! gather with and without it, on `wall-floor` and `cornell-box`, for both base domains (the
//! dissertation's shading triangles Ŝ, where the operator decides what the base integrates over,
//! and the scene S, where it only removes the triangles that bridge geometric edges). The kernel
//! and ray gathers never read the base, so only the base gather is measured. Writes
//! `benchmarks-breaking.md`.

use super::gcr::{reference, relative_l2, scene_and_probes};
use crate::ctx::Ctx;
use anyhow::Result;
use gcr::{BaseDomain, Breaking, Domain, Emitters, GatherMode, SolveConfig, radiosity_at_points};
use scene_sampler::{KernelSampler, SceneBvh};
use std::fmt::Write;
use std::time::Instant;

/// Runs this group's benchmarks and writes its report into `ctx.out`.
pub fn run(ctx: &Ctx) -> Result<()> {
    let (cells, probes, paths) = if ctx.quick {
        (40, 40, 500)
    } else {
        (300, 500, 20_000)
    };
    let mut md = format!(
        "# The breaking operator (sec. 4.4.2, fig. 4.18)\n\n\
         Command: `cargo xtask bench --only breaking`{}. Relative L2 error of B from the **base \
         gather** at {probes} probe points spread area-uniformly over the non-emitting faces, \
         against the path tracer with {paths} paths per point; {cells} kernel cells, {} shading \
         cells, seed 1, everything else default. *Ŝ* = the base integrated over the shading \
         network's own triangles (the dissertation), *S* = over the scene's faces (our default). \
         The operator drops shading triangles whose corner normals disagree by more than 50° or \
         whose edges span empty space.\n\n\
         | scene | base domain | breaking | shading triangles kept | base gather error | solve s |\n\
         |---|---|---|---:|---:|---:|\n",
        if ctx.quick { " --quick" } else { "" },
        cells / 2
    );
    for name in ["wall-floor", "cornell-box"] {
        let (scene, points) = scene_and_probes(name, probes)?;
        let bvh = SceneBvh::new(&scene);
        let truth = reference(&scene, &bvh, &points, paths);
        let domain = Domain::ThreeD(KernelSampler::new(&scene, &bvh));
        let emitters = Emitters::new(&domain);
        for (label, base_domain) in [("Ŝ", BaseDomain::Shading), ("S", BaseDomain::Scene)] {
            for enabled in [false, true] {
                let config = SolveConfig {
                    kernel_cells: cells,
                    shading_cells: cells / 2,
                    base_domain,
                    breaking: Breaking {
                        enabled,
                        ..Breaking::default()
                    },
                    gather: GatherMode::Base,
                    ..SolveConfig::default()
                };
                let t = Instant::now();
                let trained = gcr::solve(&domain, &config, &mut |_| {})?;
                let seconds = t.elapsed().as_secs_f64();
                let at: Vec<_> = points.iter().map(|p| (p.point, p.normal, p.face)).collect();
                let values: Vec<[f64; 3]> =
                    radiosity_at_points(&domain, &trained, &emitters, &config, &at)?
                        .into_iter()
                        .map(|g| g.radiosity)
                        .collect();
                let error = relative_l2(&scene, &points, &values, &truth);
                let line = format!(
                    "| {name} | {label} | {} | {} | {error:.3} | {seconds:.1} |",
                    if enabled { "on" } else { "off" },
                    trained.metrics.shading_triangles,
                );
                println!("breaking: {line}");
                writeln!(md, "{line}")?;
            }
        }
    }
    std::fs::write(ctx.out.join("benchmarks-breaking.md"), md)?;
    Ok(())
}

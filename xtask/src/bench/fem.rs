//! How one FEM step's cost grows with the kernel network (issue: "the FEM step scales linearly in
//! kernel cells at fixed base size"). On `cornell-box`, networks trained to each budget are frozen
//! and the parts of a step timed separately: the sender integrals c_o (one surface integral per
//! cell: linear), and the projection's Gram matrix with its Cholesky factor (pairs of cells within
//! the support cut-off: quadratic while the supports overlap most of the network, as they do in
//! 6-D with eq. 2.10's widths). Writes `benchmarks-fem.md`.

use crate::Ctx;
use anyhow::Result;
use gcr::config::SolveConfig;
use gcr::domain::Domain;
use gcr::fem::sender_integrals;
use gcr::projection::KernelProjection;
use scene_sampler::{KernelSampler, SceneBvh};
use std::fmt::Write;
use std::time::Instant;

/// Runs this group's benchmarks and writes its report into `ctx.out`.
pub fn run(ctx: &Ctx) -> Result<()> {
    let budgets: &[usize] = if ctx.quick {
        &[40, 80]
    } else {
        &[100, 200, 400, 800, 1400]
    };
    let scene = scene_sampler::builtin("cornell-box")?.into_3d()?;
    let bvh = SceneBvh::new(&scene);
    let domain = Domain::ThreeD(KernelSampler::new(&scene, &bvh));
    let surface = domain.scene_surface();
    let defaults = SolveConfig::default();
    let mut md = format!(
        "# FEM step against kernel cells\n\n\
         Command: `cargo xtask bench --only fem`{}. `cornell-box`, default settings, the network trained to \
         each budget, then frozen; best of 3 timings of each part on {} threads. Gram = \
         `KernelProjection::new` (every cell pair within the support cut-off {:.0e}: two sums of exact \
         triangle integrals each, then the Cholesky factor).\n\n\
         | kernel cells | sender integrals (ms) | per cell (µs) | Gram + Cholesky (ms) | non-zero Gram entries | entries / cells² | per entry (µs) |\n\
         |---:|---:|---:|---:|---:|---:|---:|\n",
        if ctx.quick { " --quick" } else { "" },
        rayon::current_num_threads(),
        defaults.projection_tolerance,
    );
    for &cells in budgets {
        let config = SolveConfig {
            kernel_cells: cells,
            shading_cells: cells / 2,
            ..SolveConfig::default()
        };
        let trained = gcr::solve::solve(&domain, &config, &mut |_| {})?;
        let kernel = &trained.kernel;
        let best = |f: &mut dyn FnMut()| {
            (0..3)
                .map(|_| {
                    let t = Instant::now();
                    f();
                    t.elapsed().as_secs_f64()
                })
                .fold(f64::INFINITY, f64::min)
        };
        let sender = best(&mut || {
            std::hint::black_box(sender_integrals(
                kernel,
                &surface,
                config.projection_tolerance,
            ));
        });
        let mut entries = 0;
        let gram = best(&mut || {
            let p = KernelProjection::new(
                kernel,
                &surface,
                config.projection_tolerance,
                config.projection_rejection,
            );
            entries = p.report().gram_entries;
        });
        let z = kernel.len() as f64;
        let line = format!(
            "| {} | {:.2} | {:.1} | {:.1} | {entries} | {:.2} | {:.2} |",
            kernel.len(),
            1e3 * sender,
            1e6 * sender / z,
            1e3 * gram,
            entries as f64 / (z * z),
            1e6 * gram / entries.max(1) as f64,
        );
        println!("fem: {line}");
        writeln!(md, "{line}")?;
    }
    std::fs::write(ctx.out.join("benchmarks-fem.md"), md)?;
    Ok(())
}

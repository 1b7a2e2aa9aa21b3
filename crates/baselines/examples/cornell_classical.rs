//! Classical radiosity (Gauss–Seidel) on the Cornell box against the adaptive path tracer at five probes.
//!
//! `cargo run --release -p baselines --example cornell_classical -- [element_size] [rel_error]`
//! (defaults 0.05 and 0.005). Prints timings, per-probe B of both, and the relative differences.

use baselines::{Adaptive, classical, pointwise};
use glam::DVec3;
use scene_sampler::{AnyScene, Probe, SceneBvh, builtin};
use std::time::Instant;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let size: f64 = args.get(1).map_or(Ok(0.05), |s| s.parse())?;
    let rel: f64 = args.get(2).map_or(Ok(0.005), |s| s.parse())?;
    let AnyScene::ThreeD(scene) = builtin("cornell-box")? else {
        unreachable!()
    };
    let bvh = SceneBvh::new(&scene);
    let want = [
        (DVec3::new(0.45, 0.0, 0.1), DVec3::Y),
        (DVec3::new(0.28, 0.3, 0.559), -DVec3::Z),
        (DVec3::new(0.55, 0.3, 0.3), -DVec3::X),
        (DVec3::new(0.0, 0.2, 0.2), DVec3::X),
        (DVec3::new(0.1, 0.5488, 0.1), -DVec3::Y),
    ];
    let probes = want
        .iter()
        .map(|&(point, normal)| {
            scene.snap_probe(
                &Probe {
                    point,
                    normal,
                    line: 0,
                },
                0.01,
                "example",
            )
        })
        .collect::<Result<Vec<_>, _>>()?;
    let t = Instant::now();
    let opts = classical::ClassicalOptions {
        element_size: size,
        ..Default::default()
    };
    let sol = classical::solve(&scene, &bvh, &opts)?;
    let t_solve = t.elapsed().as_secs_f64();
    let t = Instant::now();
    let g = sol.gather(&scene, &bvh, &probes, 16, 7)?;
    let t_gather = t.elapsed().as_secs_f64();
    let el = sol.at_points(&probes)?;
    let t = Instant::now();
    let pt = pointwise::radiosity_adaptive(
        &scene,
        &bvh,
        &probes,
        &Adaptive {
            rel_error: rel,
            batch: 4096,
            min_paths: 4096,
            max_paths: 50_000_000,
            seed: 11,
        },
    )?;
    let t_pt = t.elapsed().as_secs_f64();
    println!(
        "element size {size}: {} elements, {} sweeps, solve {t_solve:.2} s, gather {t_gather:.2} s; path tracer {t_pt:.2} s",
        sol.mesh.elements.len(),
        sol.iterations
    );
    let mut worst_g: f64 = 0.0;
    let mut worst_e: f64 = 0.0;
    for (((p, g), e), pt) in probes.iter().zip(&g).zip(&el).zip(&pt) {
        let dg = [0, 1, 2].map(|k| g[k] / pt.mean[k] - 1.0);
        let de = [0, 1, 2].map(|k| e[k] / pt.mean[k] - 1.0);
        worst_g = dg.iter().fold(worst_g, |m, v| m.max(v.abs()));
        worst_e = de.iter().fold(worst_e, |m, v| m.max(v.abs()));
        println!(
            "probe {:.3?}: path {:.4?} (rel. se {:.4}, {} paths) | gather {:.4?} ({:+.2?} %) | element {:.4?} ({:+.2?} %)",
            p.point.to_array(),
            pt.mean,
            pt.rel_error(),
            pt.paths,
            g,
            dg.map(|v| 100.0 * v),
            e,
            de.map(|v| 100.0 * v)
        );
    }
    println!(
        "worst |relative difference|: gather {:.2} %, element value {:.2} %",
        100.0 * worst_g,
        100.0 * worst_e
    );
    Ok(())
}

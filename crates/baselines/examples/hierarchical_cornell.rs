//! 3-D hierarchical radiosity against the pointwise path tracer (docs/design/math.md §8) at the probes of cornell-box:
//! relative L2 error of B over the probes and the three bands at several link budgets, both for HR's
//! constant leaf value and for a final gather from HR's solution, for `docs/design/hierarchical.md`.
//!
//! `cargo run --release -p baselines --example hierarchical_cornell [probes-file] [paths-per-probe]`
//! (defaults: `scenes/cornell-box.probes.txt`, 500000 paths).

use baselines::hierarchical::*;
use baselines::pointwise;
use scene_sampler::{SceneBvh, builtin, read_probes};
use std::time::Instant;

/// `‖a − b‖₂ / ‖b‖₂` over the probes in `keep` and the three bands, and the worst per-probe relative error.
fn errors(a: &[[f64; 3]], b: &[[f64; 3]], keep: &[bool]) -> (f64, f64) {
    let (mut d2, mut n2, mut worst) = (0.0, 0.0, 0.0f64);
    for ((x, y), &k) in a.iter().zip(b).zip(keep) {
        if !k {
            continue;
        }
        let (mut pd, mut pn) = (0.0, 0.0);
        for j in 0..3 {
            pd += (x[j] - y[j]).powi(2);
            pn += y[j] * y[j];
        }
        d2 += pd;
        n2 += pn;
        worst = worst.max((pd / pn).sqrt());
    }
    ((d2 / n2).sqrt(), worst)
}

fn main() -> std::result::Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let probes_path = args
        .next()
        .unwrap_or_else(|| "scenes/cornell-box.probes.txt".into());
    let paths: usize = match args.next() {
        Some(a) => a.parse()?,
        None => 500_000,
    };
    let scene = builtin("cornell-box")?.into_3d()?;
    let probes = read_probes(&probes_path)?;
    let points = scene.snap_probes(&probes, &probes_path)?;
    let bvh = SceneBvh::new(&scene);
    let t0 = Instant::now();
    let reference = pointwise::radiosity_at(&scene, &bvh, &points, paths, 7);
    let t_ref = t0.elapsed().as_secs_f64();
    let refs: Vec<[f64; 3]> = reference.iter().map(|e| e.mean).collect();
    let all = vec![true; points.len()];
    let lit: Vec<bool> = points
        .iter()
        .map(|p| scene.faces[p.face as usize].emission.is_zero())
        .collect();
    let worst_se = reference
        .iter()
        .map(|e| {
            (0..3)
                .map(|b| e.std_error[b] / e.mean[b].max(1e-300))
                .fold(0.0, f64::max)
        })
        .fold(0.0, f64::max);
    let (ref_se, _) = errors(
        &reference
            .iter()
            .map(|e| [0, 1, 2].map(|b| e.mean[b] + e.std_error[b]))
            .collect::<Vec<_>>(),
        &refs,
        &lit,
    );
    println!(
        "reference: {} probes ({probes_path}; {} not on the light), {paths} paths each, {t_ref:.1} s; \
         largest relative standard error {:.2} % (one band of one probe); standard error as a relative L2 \
         over the non-emitting probes {:.2} %\n",
        points.len(),
        lit.iter().filter(|&&k| k).count(),
        100.0 * worst_se,
        100.0 * ref_se
    );
    println!(
        "| budget | visibility rays | links | leaves | ε | one solve | leaf B: rel. L2 (non-emitting) | worst probe | rel. L2 (all) | final gather: rel. L2 (non-emitting) | worst probe | gather time |"
    );
    println!("|---|---|---|---|---|---|---|---|---|---|---|---|");
    for (target, rays) in [
        (2000usize, 16usize),
        (5000, 16),
        (20_000, 16),
        (50_000, 16),
        (20_000, 64),
    ] {
        let base = TriHrConfig {
            min_area: budget::min_area_for(&scene, target),
            visibility_rays: rays,
            ..TriHrConfig::default()
        };
        let r = match solve_tri_for_links(&scene, target, base, 0.05) {
            Ok(r) => r,
            Err(e) => {
                println!("| {target} | {rays} | — | | {e} | | | | | | | |");
                continue;
            }
        };
        let t1 = Instant::now();
        let hr = TriHr::solve(
            &scene,
            TriHrConfig {
                epsilon: r.epsilon,
                ..base
            },
        )?;
        let t_solve = t1.elapsed().as_secs_f64();
        let leaf: Vec<[f64; 3]> = points
            .iter()
            .map(|p| hr.radiosity_at(p).map(|b| b.0))
            .collect::<Result<_>>()?;
        let t2 = Instant::now();
        let gather: Vec<[f64; 3]> = points
            .iter()
            .enumerate()
            .map(|(i, p)| hr.gather_at(p, 16, i as u64).map(|b| b.0))
            .collect::<Result<_>>()?;
        let t_gather = t2.elapsed().as_secs_f64();
        let (l_lit, l_worst) = errors(&leaf, &refs, &lit);
        let (l_all, _) = errors(&leaf, &refs, &all);
        let (g_lit, g_worst) = errors(&gather, &refs, &lit);
        println!(
            "| {target} | {rays} | {} | {} | {:.3e} | {t_solve:.2} s | {:.1} % | {:.0} % | {:.2} % | {:.1} % | {:.0} % | {t_gather:.2} s |",
            hr.link_count(),
            hr.leaves().count(),
            r.epsilon,
            100.0 * l_lit,
            100.0 * l_worst,
            100.0 * l_all,
            100.0 * g_lit,
            100.0 * g_worst,
        );
    }
    Ok(())
}

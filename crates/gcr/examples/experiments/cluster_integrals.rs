//! Accuracy and speed of the clustered surface integrals (`gcr`'s cluster tree) against the exact
//! element sums, on a large scene.
//!
//! `cargo run --release -p gcr --example cluster_integrals -- random-boxes-100000 0.25 0.05`
//!
//! For Gaussians exp(−|x − c|²/d²) centred at random element centroids, with d from 2 % to 20 %
//! of the scene's diagonal, prints the relative error of ∫_S (max and RMS over the centres) and
//! the time per integral, exact and clustered for each θ given.

use gcr::stages::SceneSurface;
use gcr::{Domain, SurfaceClusters};
use rand::{Rng, SeedableRng};
use scene_sampler::{KernelSampler, SceneBvh};
use std::time::Instant;

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().collect();
    let name = args.get(1).map_or("random-boxes-100000", |s| s.as_str());
    let thetas: Vec<f64> = if args.len() > 2 {
        args[2..]
            .iter()
            .map(|s| s.parse())
            .collect::<Result<_, _>>()?
    } else {
        vec![1.0, 0.25, 0.05]
    };
    let scene = scene_sampler::builtin(name)?.into_3d()?;
    let bvh = SceneBvh::new(&scene);
    let domain = Domain::ThreeD(KernelSampler::new(&scene, &bvh));
    let exact = SceneSurface::of(&domain);
    let diag = domain.diagonal();
    let tol = 1e-6;
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
    let centres: Vec<glam::DVec3> = (0..100)
        .map(|_| {
            let e = &exact.elements[rng.random_range(0..exact.elements.len())];
            let (lo, hi) = e.bounds();
            0.5 * (lo + hi)
        })
        .collect();
    println!(
        "{name}: {} elements, diagonal {diag:.3}",
        exact.elements.len()
    );
    let mut scratch = Vec::new();
    for frac in [0.02, 0.05, 0.1, 0.2] {
        let d = frac * diag;
        let a = 1.0 / (d * d);
        let t = Instant::now();
        let reference: Vec<f64> = centres
            .iter()
            .map(|c| exact.gaussian_integral(*c, a, tol, &mut scratch))
            .collect();
        let t_exact = t.elapsed().as_secs_f64() / centres.len() as f64;
        let mut near = 0;
        for c in &centres {
            exact.elements_near(
                *c,
                gauss_integrals::support_radius(1.0 / (d * d), tol),
                &mut scratch,
            );
            near += scratch.len();
        }
        print!(
            "d = {frac:.2}·diag: {:6.0} elements in support, exact {:8.1} µs",
            near as f64 / centres.len() as f64,
            1e6 * t_exact
        );
        for &theta in &thetas {
            let clustered = SceneSurface::of_clustered(
                &domain,
                SurfaceClusters {
                    min_elements: 0,
                    theta,
                },
            );
            let t = Instant::now();
            let got: Vec<f64> = centres
                .iter()
                .map(|c| clustered.gaussian_integral(*c, a, tol, &mut scratch))
                .collect();
            let t_tree = t.elapsed().as_secs_f64() / centres.len() as f64;
            let (mut max, mut sq) = (0.0f64, 0.0);
            for (g, r) in got.iter().zip(&reference) {
                let e = (g - r).abs() / r.abs().max(1e-300);
                max = max.max(e);
                sq += e * e;
            }
            let rms = (sq / got.len() as f64).sqrt();
            print!(
                " | θ {theta}: {:7.1} µs, rel err max {max:.1e} rms {rms:.1e}",
                1e6 * t_tree
            );
        }
        println!();
    }
    Ok(())
}

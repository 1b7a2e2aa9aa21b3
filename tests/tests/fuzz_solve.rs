//! Mutated scene files that still load go through a small solve and the gather without a panic or
//! a hang (issue "Reliability": "thousands of random mutations … through every loader and
//! `gcr solve --cells 10`"; the loaders alone are fuzzed in
//! `crates/scene-sampler/tests/fuzz_loaders.rs`). Each mutation drops, duplicates or swaps a line
//! of a built-in OBJ, or perturbs one number in it; deterministic (fixed seed), bounded in count.

use gcr::{Domain, Emitters, SolveConfig, radiosity_at_points};
use gcr_tests::workspace_path;
use scene_sampler::{KernelSampler, SceneBvh, SurfaceSampler};
use std::panic::{AssertUnwindSafe, catch_unwind};

/// A tiny deterministic generator (SplitMix64): the test needs no RNG dependency.
struct Mix(u64);
impl Mix {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    fn below(&mut self, n: usize) -> usize {
        (self.next() % n.max(1) as u64) as usize
    }
}

/// One mutation of the OBJ text.
fn mutate(text: &str, rng: &mut Mix) -> String {
    let mut lines: Vec<String> = text.lines().map(str::to_string).collect();
    let i = rng.below(lines.len());
    match rng.below(4) {
        0 => {
            lines.remove(i);
        }
        1 => {
            let l = lines[i].clone();
            lines.insert(i, l);
        }
        2 => {
            let j = rng.below(lines.len());
            lines.swap(i, j);
        }
        _ => {
            // one number scaled, negated or blown up
            let mut words: Vec<String> = lines[i].split(' ').map(str::to_string).collect();
            let w = rng.below(words.len());
            if let Ok(x) = words[w].parse::<f64>() {
                let f = [-1.0, 0.0, 1e-9, 1e9, 1.5][rng.below(5)];
                words[w] = format!("{}", x * f);
            }
            lines[i] = words.join(" ");
        }
    }
    lines.join("\n") + "\n"
}

#[test]
fn mutated_scenes_that_load_solve_without_a_panic() {
    let dir = std::env::temp_dir().join(format!("gcr-fuzz-solve-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let mut rng = Mix(0x5017);
    let mut solved = 0;
    for name in ["cornell-box", "two-blockers"] {
        let obj = std::fs::read_to_string(workspace_path(&format!("scenes/{name}.obj"))).unwrap();
        let mtl = workspace_path(&format!("scenes/{name}.mtl"));
        std::fs::copy(&mtl, dir.join(format!("{name}.mtl"))).unwrap();
        for case in 0..150 {
            let text = (0..1 + rng.below(3)).fold(obj.clone(), |t, _| mutate(&t, &mut rng));
            let path = dir.join(format!("{name}.obj"));
            std::fs::write(&path, &text).unwrap();
            let outcome = catch_unwind(AssertUnwindSafe(|| {
                let Ok(scene) = scene_sampler::load(&path).and_then(|s| s.into_3d()) else {
                    return false;
                };
                let bvh = SceneBvh::new(&scene);
                let domain = Domain::ThreeD(KernelSampler::new(&scene, &bvh));
                let config = SolveConfig {
                    kernel_cells: 10,
                    seed: case,
                    ..SolveConfig::default()
                };
                let Ok(trained) = gcr::solve(&domain, &config, &mut |_| {}) else {
                    return false;
                };
                let points: Vec<_> = SurfaceSampler::new(&scene)
                    .spread(8, |_| true)
                    .iter()
                    .map(|p| (p.point, p.normal, p.face))
                    .collect();
                let b = radiosity_at_points(
                    &domain,
                    &trained,
                    &Emitters::new(&domain),
                    &config,
                    &points,
                )
                .unwrap();
                assert!(
                    b.iter().all(|g| g.radiosity.iter().all(|v| v.is_finite())),
                    "a non-finite radiosity"
                );
                true
            }));
            match outcome {
                Ok(true) => solved += 1,
                Ok(false) => {}
                Err(_) => {
                    let keep = dir.join(format!("{name}-panic-{case}.obj"));
                    std::fs::write(&keep, &text).unwrap();
                    panic!(
                        "{name} mutation {case} panicked; the file is kept at {}",
                        keep.display()
                    );
                }
            }
        }
    }
    assert!(
        solved > 100,
        "most mutations still load and solve: {solved}"
    );
    std::fs::remove_dir_all(&dir).ok();
}

//! The main loop (figs. 1.2, 3.1, B.1): sample rays, train the kernel network on K·s and the
//! shading network on the receivers, run a FEM step every N kernel insertions and update every
//! sample's emitting strength, resample critical regions, stop at the budget.

use crate::config::{SolveConfig, StrengthFrom};
use crate::domain::{Domain, Ray};
use crate::element::{Bands, MAX_BANDS};
use crate::fem::{
    Base, FemSettings, FemSolution, KernelCells, SceneSurface, fem_step, reflected_from_kernel,
    sender_integrals,
};
use crate::metrics::Metrics;
use crate::network::GrowingNetwork;
use crate::shading::ShadingGeometry;
use glam::DVec3;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use std::time::Instant;

/// One training sample: a ray with its current emitting strength s = E(x) + B_refl(x).
#[derive(Clone, Copy, Debug)]
pub struct Sample {
    /// The ray and its kernel value.
    pub ray: Ray,
    /// Emitting strength s at the sender (MATH.md §4).
    pub s: Bands,
    /// Cached best-matching unit in the kernel network (sec. 2.6), with the epoch it belongs to.
    pub kernel_bmu: Option<(usize, u64)>,
    /// Cached best-matching unit in the shading network.
    pub shading_bmu: Option<(usize, u64)>,
}

/// What the observer sees during a solve.
#[derive(Clone, Copy, Debug, Default)]
pub struct Progress {
    /// Phase name ("training", "fem", "final", "gather").
    pub phase: &'static str,
    /// Kernel cells.
    pub kernel_cells: usize,
    /// Kernel cell budget.
    pub kernel_budget: usize,
    /// Shading cells.
    pub shading_cells: usize,
    /// Samples held.
    pub samples: usize,
    /// FEM steps so far.
    pub fem_steps: usize,
    /// Seconds since the start.
    pub elapsed: f64,
}

/// The state after training: everything the gathers need.
pub struct Trained {
    /// The kernel network frozen.
    pub kernel: KernelCells,
    /// Sender integrals c_o of the frozen kernel.
    pub sender: Vec<f64>,
    /// The last FEM step.
    pub fem: FemSolution,
    /// The samples at the end.
    pub samples: Vec<Sample>,
    /// Metrics so far (the caller adds gather and output).
    pub metrics: Metrics,
}

impl Trained {
    /// B_refl at a point by the kernel collection (fig. 4.13c).
    pub fn reflected_kernel(&self, y: DVec3) -> Bands {
        reflected_from_kernel(&self.kernel, &self.sender, y)
    }
}

fn kernel_target(ray: &Ray, s: &Bands, bands: usize, out: &mut Vec<f64>) {
    out.clear();
    out.extend((0..bands).map(|b| ray.kernel[b] * s[b]));
}

/// One kernel training step on a sample: input (x, y), target K·s, cached BMU (sec. 2.6).
fn train_kernel_on(
    kernel: &mut impl GrowingNetwork,
    smp: &mut Sample,
    dim: usize,
    bands: usize,
    input: &mut Vec<f64>,
    target: &mut Vec<f64>,
) {
    input.clear();
    input.extend_from_slice(&smp.ray.x.to_array()[..dim]);
    input.extend_from_slice(&smp.ray.y.to_array()[..dim]);
    kernel_target(&smp.ray, &smp.s, bands, target);
    let hint = smp
        .kernel_bmu
        .filter(|(_, e)| *e == kernel.epoch())
        .map(|(b, _)| b);
    let bmu = kernel.train(input, target, hint);
    smp.kernel_bmu = Some((bmu, kernel.epoch()));
}

/// Freezes the kernel network into per-cell sender/receiver halves (MATH.md §3).
pub fn freeze_kernel(net: &impl GrowingNetwork, dim: usize, bands: usize) -> KernelCells {
    let n = net.cell_count();
    let mut k = KernelCells::default();
    for i in 0..n {
        let c = net.centre(i);
        let mut wx = DVec3::ZERO;
        let mut wy = DVec3::ZERO;
        for a in 0..dim {
            wx[a] = c[a];
            wy[a] = c[dim + a];
        }
        k.wx.push(wx);
        k.wy.push(wy);
        k.width.push(net.width(i));
        let o = net.output(i);
        let mut v = [0.0; MAX_BANDS];
        for b in 0..MAX_BANDS {
            v[b] = o[b.min(bands - 1)];
        }
        k.v.push(v);
    }
    k
}

/// Freezes the shading network (cells, widths, learned normals, simplices) into the FEM's view.
pub fn freeze_shading(
    net: &impl GrowingNetwork,
    domain: &Domain,
    config: &SolveConfig,
) -> ShadingGeometry {
    let dim = domain.dim();
    let n = net.cell_count();
    let mut centres = Vec::with_capacity(n);
    let mut widths = Vec::with_capacity(n);
    let mut normals = Vec::with_capacity(n);
    for i in 0..n {
        let (c, o) = (net.centre(i), net.output(i));
        let mut p = DVec3::ZERO;
        let mut nrm = DVec3::ZERO;
        for a in 0..dim {
            p[a] = c[a];
            nrm[a] = o[a];
        }
        centres.push(p);
        widths.push(net.width(i));
        normals.push(nrm);
    }
    let tol = 2e-3 * domain.diagonal();
    ShadingGeometry::new(
        centres,
        widths,
        normals,
        dim - 1,
        &net.simplices(),
        config.breaking,
        |a, b, nrm| domain.spans_gap(a, b, nrm, tol),
    )
}

/// Runs the training loop with FEM steps until the budget is reached.
pub fn train(
    domain: &Domain,
    kernel: &mut impl GrowingNetwork,
    shading: &mut impl GrowingNetwork,
    config: &SolveConfig,
    observer: &mut dyn FnMut(&Progress),
) -> Trained {
    let start = Instant::now();
    let mut metrics = Metrics {
        bands: domain.bands(),
        seed: config.seed,
        threads: rayon::current_num_threads(),
        ..Default::default()
    };
    let mut rng = ChaCha8Rng::seed_from_u64(config.seed);
    let dim = domain.dim();
    let bands = domain.bands();
    let pd = domain.param_dim();
    let fem_settings = FemSettings {
        surface_dim: domain.surface_dim(),
        transfer: config.transfer,
        closed_forms: config.closed_forms,
        ..FemSettings::default()
    };
    let scene_surface = SceneSurface::new(domain.elements(), 0.05 * domain.diagonal());

    // Initial sample set: uniform over the ray domain, s = E (the first shot, fig. 3.1).
    let t0 = Instant::now();
    let initial = (config.samples_per_cell * 20).max(500);
    let params: Vec<Vec<f64>> = (0..initial)
        .map(|_| (0..pd).map(|_| rng.random::<f64>()).collect())
        .collect();
    let mut samples: Vec<Sample> = params
        .par_iter()
        .map(|u| {
            let ray = domain.ray(u);
            Sample {
                s: ray.emission_x,
                ray,
                kernel_bmu: None,
                shading_bmu: None,
            }
        })
        .collect();
    metrics.rays_traced += initial as u64;
    metrics.seconds.sampling += t0.elapsed().as_secs_f64();

    let mut input = Vec::with_capacity(2 * dim);
    let mut target = Vec::with_capacity(bands);
    let mut shading_in = Vec::with_capacity(dim);
    let mut shading_target = Vec::with_capacity(dim);
    let mut last_fem_insertions = 0u64;
    let mut fem: Option<FemSolution> = None;
    let mut steps = 0u64;
    let mut progress = Progress {
        phase: "training",
        kernel_budget: config.kernel_cells,
        ..Default::default()
    };
    let mut last_report = Instant::now();
    let (mut t_kernel, mut t_shading) = (0.0, 0.0);

    loop {
        let stop_cells = kernel.cell_count() >= config.kernel_cells;
        let stop_time = config
            .time_budget
            .is_some_and(|t| start.elapsed().as_secs_f64() >= t);
        if stop_cells || stop_time {
            metrics.stopped_by = if stop_cells {
                "cells".into()
            } else {
                "time".into()
            };
            break;
        }
        // One training step on a random sample, in batches to time the phases cheaply.
        let batch = 256;
        let tk = Instant::now();
        let mut shading_batch = Vec::with_capacity(batch);
        for _ in 0..batch {
            let i = rng.random_range(0..samples.len());
            train_kernel_on(kernel, &mut samples[i], dim, bands, &mut input, &mut target);
            shading_batch.push(i);
        }
        t_kernel += tk.elapsed().as_secs_f64();
        let ts = Instant::now();
        if shading.cell_count() >= config.shading_cells {
            shading.set_growing(false);
        }
        {
            for &i in &shading_batch {
                let smp = &mut samples[i];
                shading_in.clear();
                shading_in.extend_from_slice(&smp.ray.y.to_array()[..dim]);
                shading_target.clear();
                shading_target.extend_from_slice(&smp.ray.ny.to_array()[..dim]);
                let hint = smp
                    .shading_bmu
                    .filter(|(_, e)| *e == shading.epoch())
                    .map(|(b, _)| b);
                let bmu = shading.train(&shading_in, &shading_target, hint);
                smp.shading_bmu = Some((bmu, shading.epoch()));
            }
        }
        t_shading += ts.elapsed().as_secs_f64();
        steps += batch as u64;

        // Grow the sample set with the network: resample critical regions (sec. 2.5).
        let wanted = config.samples_per_cell * kernel.cell_count().max(1);
        if samples.len() < wanted.max(initial) {
            let tr = Instant::now();
            let add = (wanted.max(initial) - samples.len()).min(512);
            let mut accepted: Vec<Vec<f64>> = Vec::with_capacity(add);
            let mut tries = 0;
            let critical_wanted = (add as f64 * config.resample_critical_fraction) as usize;
            while accepted.len() < critical_wanted && tries < 20 * add {
                tries += 1;
                let u: Vec<f64> = (0..pd).map(|_| rng.random::<f64>()).collect();
                domain.endpoints(&u).input(&mut input);
                input.truncate(2 * dim);
                if kernel.is_critical(&input[..]) {
                    accepted.push(u);
                }
            }
            while accepted.len() < add {
                accepted.push((0..pd).map(|_| rng.random::<f64>()).collect());
            }
            metrics.seconds.resampling += tr.elapsed().as_secs_f64();
            let t0 = Instant::now();
            let current = fem.as_ref();
            let new: Vec<Sample> = accepted
                .par_iter()
                .map_init(Vec::new, |scratch, u| {
                    let ray = domain.ray(u);
                    let s = match (config.strength_from, current) {
                        (StrengthFrom::Kernel, Some(f)) => {
                            kernel_strength(&ray, &f.kernel, &f.sender)
                        }
                        _ => strength(&ray, current, scratch),
                    };
                    Sample {
                        ray,
                        s,
                        kernel_bmu: None,
                        shading_bmu: None,
                    }
                })
                .collect();
            metrics.rays_traced += new.len() as u64;
            samples.extend(new);
            metrics.seconds.sampling += t0.elapsed().as_secs_f64();
        }

        // FEM step every `fem_every` kernel insertions (sec. 4.4.1).
        if kernel.insertions() - last_fem_insertions >= config.fem_every as u64
            && shading.cell_count() >= 3
        {
            last_fem_insertions = kernel.insertions();
            let tf = Instant::now();
            let frozen = freeze_kernel(kernel, dim, bands);
            let base = Base::new(freeze_shading(shading, domain, config), fem_settings);
            let sol = fem_step(base, &frozen, &scene_surface);
            update_strengths(&mut samples, &sol, &frozen, config.strength_from);
            fem = Some(sol);
            metrics.fem_steps += 1;
            metrics.seconds.fem += tf.elapsed().as_secs_f64();
        }

        if last_report.elapsed().as_secs_f64() > 0.1 {
            last_report = Instant::now();
            progress.kernel_cells = kernel.cell_count();
            progress.shading_cells = shading.cell_count();
            progress.samples = samples.len();
            progress.fem_steps = metrics.fem_steps;
            progress.elapsed = start.elapsed().as_secs_f64();
            observer(&progress);
        }
    }

    // Final FEM steps: let the last kernel propagate a few more bounces, retraining in between
    // (the networks keep their size from here on).
    kernel.set_growing(false);
    shading.set_growing(false);
    let tf = Instant::now();
    for _ in 0..config.final_fem_steps.max(1) {
        let frozen = freeze_kernel(kernel, dim, bands);
        let base = Base::new(freeze_shading(shading, domain, config), fem_settings);
        let sol = fem_step(base, &frozen, &scene_surface);
        update_strengths(&mut samples, &sol, &frozen, config.strength_from);
        fem = Some(sol);
        metrics.fem_steps += 1;
        // Re-learn the new targets without growing: a sweep over the samples.
        for _ in 0..samples.len() {
            let i = rng.random_range(0..samples.len());
            train_kernel_on(kernel, &mut samples[i], dim, bands, &mut input, &mut target);
        }
    }
    let frozen = freeze_kernel(kernel, dim, bands);
    let sender = sender_integrals(&frozen, &scene_surface, fem_settings.support_tolerance);
    metrics.seconds.fem += tf.elapsed().as_secs_f64();
    metrics.seconds.kernel_training = t_kernel;
    metrics.seconds.shading_training = t_shading;
    metrics.training_steps = steps;
    metrics.kernel_cells = kernel.cell_count();
    metrics.shading_cells = shading.cell_count();
    metrics.samples = samples.len();
    let fem = fem.expect("at least one FEM step ran");
    metrics.shading_triangles = fem.base.geo.simplices.len();
    metrics.rejected_base_components = fem.rejected;
    Trained {
        kernel: frozen,
        sender,
        fem,
        samples,
        metrics,
    }
}

/// s = E(x) + B_refl(x) from the current FEM solution (E alone before the first step).
fn strength(ray: &Ray, fem: Option<&FemSolution>, scratch: &mut Vec<u32>) -> Bands {
    let mut s = ray.emission_x;
    if let Some(f) = fem {
        let b = f.reflected_from_base(ray.x, scratch);
        for k in 0..MAX_BANDS {
            s[k] += b[k].max(0.0);
        }
    }
    s
}

/// s = E(x) + B_refl(x) with B_refl from the kernel collection (fig. 4.13c) at the sender.
fn kernel_strength(ray: &Ray, kernel: &KernelCells, sender: &[f64]) -> Bands {
    let b = reflected_from_kernel(kernel, sender, ray.x);
    let mut s = ray.emission_x;
    for k in 0..MAX_BANDS {
        s[k] += b[k].max(0.0);
    }
    s
}

fn update_strengths(
    samples: &mut [Sample],
    fem: &FemSolution,
    kernel: &KernelCells,
    from: StrengthFrom,
) {
    samples
        .par_iter_mut()
        .for_each_init(Vec::new, |scratch, smp| {
            smp.s = match from {
                StrengthFrom::Base => strength(&smp.ray, Some(fem), scratch),
                StrengthFrom::Kernel => kernel_strength(&smp.ray, kernel, &fem.sender),
            };
        });
}

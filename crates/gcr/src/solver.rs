//! The main loop (figs. 1.2, 3.1, B.1): sample rays, train the kernel network on K·s and the
//! shading network on the receivers, run a FEM step every N kernel insertions and update every
//! sample's emitting strength, resample critical regions, stop at the budget.

use crate::config::{NetworkTarget, OutputFit, SolveConfig, StrengthFrom};
use crate::domain::{Domain, Ray};
use crate::element::{Bands, MAX_BANDS};
use crate::fem::{
    Base, FemSettings, FemSolution, KernelCells, SceneSurface, fem_step, receiver_integrals,
    reflected_from_kernel, sender_integrals,
};
use crate::metrics::Metrics;
use crate::network::GrowingNetwork;
use crate::projection::{
    KernelProjection, kernel_gram_excluding, kernel_reflected_power, kernel_support,
    sampled_reflected_power,
};
use crate::shading::ShadingGeometry;
use crate::shooting::SenderDensity;
use crate::solve::SolveError;
use glam::DVec3;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use std::sync::Arc;
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
    /// `1/p_x(x)` of a shot ray ([`crate::shooting`]); 0 for area-uniform samples.
    pub inv_px: f64,
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
    pub fn reflected_kernel(&self, y: DVec3, n: DVec3) -> Bands {
        reflected_from_kernel(&self.kernel, &self.sender, y, n)
    }
}

/// The kernel network's training target for a sample ([`NetworkTarget`]).
fn kernel_target(smp: &Sample, config: &SolveConfig, domain: &Domain, out: &mut Vec<f64>) {
    let (ray, s) = (&smp.ray, &smp.s);
    let bands = domain.bands();
    out.clear();
    match config.network_target {
        NetworkTarget::SampleWeight if smp.inv_px != 0.0 => {
            let rho = domain.reflectance(ray.face_y);
            out.extend((0..bands).map(|b| {
                if ray.kernel[b] > 0.0 {
                    rho[b] * s[b] * smp.inv_px
                } else {
                    0.0
                }
            }));
        }
        NetworkTarget::ClampedKernel => {
            // G·r² / max(r², r_c²): G with 1/r² clamped at r_c.
            let rc = config.network_clamp_radius * domain.diagonal();
            let f = (ray.x.distance_squared(ray.y) / (rc * rc)).min(1.0);
            out.extend((0..bands).map(|b| ray.kernel[b] * s[b] * f));
        }
        _ => out.extend((0..bands).map(|b| ray.kernel[b] * s[b])),
    }
}

/// One kernel training step on a sample: input (x, y), target ([`kernel_target`]), cached BMU
/// (sec. 2.6).
fn train_kernel_on(
    kernel: &mut impl GrowingNetwork,
    smp: &mut Sample,
    (domain, config): (&Domain, &SolveConfig),
    input: &mut Vec<f64>,
    target: &mut Vec<f64>,
) {
    let dim = domain.dim();
    input.clear();
    input.extend_from_slice(&smp.ray.x.to_array()[..dim]);
    input.extend_from_slice(&smp.ray.y.to_array()[..dim]);
    kernel_target(smp, config, domain, target);
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

/// The shading network frozen for a FEM step, or an empty geometry when nothing downstream
/// reads the base ([`SolveConfig::needs_base`]): the FEM step then costs nothing.
fn freeze_base_geometry(
    net: &impl GrowingNetwork,
    domain: &Domain,
    config: &SolveConfig,
    base_used: bool,
) -> ShadingGeometry {
    if base_used {
        freeze_shading(net, domain, config)
    } else {
        ShadingGeometry::new(
            Vec::new(),
            Vec::new(),
            Vec::new(),
            domain.dim() - 1,
            &[],
            config.breaking,
            |_, _, _| false,
        )
    }
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
    let mut out = vec![0.0; dim];
    for i in 0..n {
        // The learned normal at a cell is the network's output Ψ(ŵ_i) there, not the cell's
        // weight v_i: the Gaussians overlap, so the weights of a smooth field oscillate.
        let c = net.centre(i);
        net.predict(c, &mut out);
        let mut p = DVec3::ZERO;
        let mut nrm = DVec3::ZERO;
        for a in 0..dim {
            p[a] = c[a];
            nrm[a] = out[a];
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
) -> Result<Trained, SolveError> {
    let start = Instant::now();
    let mut metrics = Metrics {
        bands: domain.bands(),
        seed: config.seed,
        threads: rayon::current_num_threads(),
        output_fit: config.output_fit.name().into(),
        network_target: config.network_target.name().into(),
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
        base_domain: config.base_domain,
        ..FemSettings::default()
    };
    let scene_surface = Arc::new(domain.scene_surface_clustered(config.surface_clusters));

    // Initial sample set, s = E (the first shot, fig. 3.1): area-uniform over the ray domain
    // (fig. B.2) for the delta rule, shot rays for the projection.
    let t0 = Instant::now();
    let initial = (config.samples_per_cell * 20).max(500);
    let density = SenderDensity::new(domain);
    let mut shots = 0u64;
    let mut samples: Vec<Sample> = Vec::new();
    add_samples(
        domain,
        config,
        &density,
        &mut rng,
        initial,
        None,
        &mut samples,
        &mut shots,
    );
    metrics.rays_traced += shots.max(initial as u64);
    metrics.seconds.sampling += t0.elapsed().as_secs_f64();

    let mut input = Vec::with_capacity(2 * dim);
    let mut target = Vec::with_capacity(bands);
    let mut shading_in = Vec::with_capacity(dim);
    let mut shading_target = Vec::with_capacity(dim);
    let mut last_fem_insertions = 0u64;
    let mut last_projected_cells = 0usize;
    let mut fem: Option<FemSolution> = None;
    let mut steps = 0u64;
    let mut progress = Progress {
        phase: "training",
        kernel_budget: config.kernel_cells,
        ..Default::default()
    };
    let mut last_report = Instant::now();
    let (mut t_kernel, mut t_shading) = (0.0, 0.0);
    let base_used = config.needs_base();
    let to_target = (domain, config);

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
            train_kernel_on(kernel, &mut samples[i], to_target, &mut input, &mut target);
            shading_batch.push(i);
        }
        t_kernel += tk.elapsed().as_secs_f64();
        let ts = Instant::now();
        if shading.cell_count() >= config.shading_cells {
            shading.set_growing(false);
        }
        if base_used {
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

        // Grow the sample set with the network: resample critical regions (sec. 2.5) or shoot.
        let wanted = config.samples_per_cell * kernel.cell_count().max(1);
        if samples.len() < wanted.max(initial) {
            let add = (wanted.max(initial) - samples.len()).min(512);
            let current = fem.as_ref();
            if config.output_fit == OutputFit::Projection {
                let t0 = Instant::now();
                let before = shots;
                add_samples(
                    domain,
                    config,
                    &density,
                    &mut rng,
                    add,
                    current,
                    &mut samples,
                    &mut shots,
                );
                metrics.rays_traced += shots - before;
                metrics.seconds.sampling += t0.elapsed().as_secs_f64();
            } else {
                let tr = Instant::now();
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
                // in chunks: `Domain::rays` prefetches ahead within a chunk
                let new: Vec<Sample> = accepted
                    .par_chunks(64)
                    .flat_map_iter(|chunk| {
                        let mut scratch = Vec::new();
                        domain.rays(chunk).into_iter().map(move |ray| Sample {
                            s: initial_strength(&ray, config, current, &mut scratch),
                            ray,
                            kernel_bmu: None,
                            shading_bmu: None,
                            inv_px: 0.0,
                        })
                    })
                    .collect();
                metrics.rays_traced += new.len() as u64;
                samples.extend(new);
                metrics.seconds.sampling += t0.elapsed().as_secs_f64();
            }
        }

        // FEM step every `fem_every` kernel insertions (sec. 4.4.1). With the projected output
        // layer a step also needs the kernel to have grown by a quarter since the last one: its
        // Gram matrix costs O(cells²), so the steps thin out geometrically and their total cost
        // stays a small multiple of the last one.
        let projection = config.output_fit == OutputFit::Projection;
        if kernel.insertions() - last_fem_insertions >= config.fem_every as u64
            && (shading.cell_count() >= 3 || !base_used)
            && (!projection || kernel.cell_count() * 4 >= last_projected_cells * 5)
        {
            last_fem_insertions = kernel.insertions();
            last_projected_cells = kernel.cell_count();
            let tf = Instant::now();
            let frozen = if projection {
                let p = propagate(
                    kernel,
                    domain,
                    config,
                    &mut samples,
                    shots,
                    &scene_surface,
                    TRAINING_BOUNCES,
                )?;
                metrics.bounces += p.bounces;
                metrics.diverging_bounces_stopped += usize::from(p.diverged);
                metrics.stabilized_projections += p.stabilized;
                metrics.unsupported_cells = p.unsupported;
                p.kernel
            } else {
                freeze_kernel(kernel, dim, bands)
            };
            let base = Base::new(
                freeze_base_geometry(shading, domain, config, base_used),
                fem_settings,
                scene_surface.clone(),
            );
            let sol = fem_step(base, &frozen, &scene_surface);
            if !projection || config.strength_from == StrengthFrom::Base {
                update_strengths(&mut samples, &sol, &frozen, config.strength_from);
            }
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
    let (frozen, sender) = if config.output_fit == OutputFit::Projection {
        // One Gram matrix, then bounces until the strengths settle (each bounce is cheap).
        let p = propagate(
            kernel,
            domain,
            config,
            &mut samples,
            shots,
            &scene_surface,
            FINAL_BOUNCES,
        )?;
        metrics.bounces += p.bounces;
        metrics.diverging_bounces_stopped += usize::from(p.diverged);
        metrics.stabilized_projections += p.stabilized;
        metrics.unsupported_cells = p.unsupported;
        metrics.energy_balance = config.energy_correction.then_some(p.energy_balance);
        let (frozen, sender) = (p.kernel, p.sender);
        let base = Base::new(
            freeze_base_geometry(shading, domain, config, base_used),
            fem_settings,
            scene_surface.clone(),
        );
        fem = Some(fem_step(base, &frozen, &scene_surface));
        metrics.fem_steps += 1;
        (frozen, sender)
    } else {
        for _ in 0..config.final_fem_steps.max(1) {
            let frozen = freeze_kernel(kernel, dim, bands);
            let base = Base::new(
                freeze_base_geometry(shading, domain, config, base_used),
                fem_settings,
                scene_surface.clone(),
            );
            let sol = fem_step(base, &frozen, &scene_surface);
            update_strengths(&mut samples, &sol, &frozen, config.strength_from);
            fem = Some(sol);
            metrics.fem_steps += 1;
            // Re-learn the new targets without growing: a sweep over the samples.
            for _ in 0..samples.len() {
                let i = rng.random_range(0..samples.len());
                train_kernel_on(kernel, &mut samples[i], to_target, &mut input, &mut target);
            }
        }
        let frozen = freeze_kernel(kernel, dim, bands);
        let sender = sender_integrals(&frozen, &scene_surface, fem_settings.support_tolerance);
        (frozen, sender)
    };
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
    Ok(Trained {
        kernel: frozen,
        sender,
        fem,
        samples,
        metrics,
    })
}

/// Bounces per projection during training.
const TRAINING_BOUNCES: usize = 4;
/// Bounce cap after training (reached only when ρ is close to 1).
const FINAL_BOUNCES: usize = 200;
/// Relative change of the total strength below which the bounces stop.
const BOUNCE_TOLERANCE: f64 = 1e-5;

/// The frozen kernel network with everything a projection needs that does not depend on the
/// rejection threshold: computed once per network state, reused when [`propagate`] redoes the
/// projection at a higher rejection.
struct Frozen {
    /// The cells (their weights are overwritten by every fit).
    kernel: KernelCells,
    /// Sender integrals c_o.
    sender: Vec<f64>,
    /// Receiver integrals (empty without the energy correction).
    receiver: Vec<f64>,
    /// Cells left out for want of samples in their support.
    excluded: Vec<bool>,
    /// Their Gram matrix ([`crate::projection::kernel_gram_excluding`]).
    gram: nalgebra::DMatrix<f64>,
}

impl Frozen {
    fn new(
        kernel: &impl GrowingNetwork,
        domain: &Domain,
        config: &SolveConfig,
        samples: &[Sample],
        scene: &SceneSurface,
    ) -> Self {
        let tol = config.projection_tolerance;
        let mut frozen = freeze_kernel(kernel, domain.dim(), domain.bands());
        if config.kernel_facing {
            let ends: Vec<_> = samples
                .iter()
                .map(|s| (s.ray.x, s.ray.nx, s.ray.y, s.ray.ny))
                .collect();
            frozen.assign_facing(&ends, config.breaking.max_normal_angle.cos());
        }
        let sender = sender_integrals(&frozen, scene, tol);
        // Cells without data (the tiny ones the network grows along edges) are left out: their
        // moment would be one sample's noise ([`SolveConfig::projection_min_support`]).
        let min_support = config.projection_min_support;
        let excluded: Vec<bool> = if min_support > 0.0 {
            kernel_support(&frozen, samples, tol)
                .iter()
                .map(|&c| c < min_support)
                .collect()
        } else {
            Vec::new()
        };
        let receiver = if config.energy_correction {
            receiver_integrals(&frozen, scene, tol)
        } else {
            Vec::new()
        };
        let gram = kernel_gram_excluding(&frozen, scene, tol, &excluded);
        Self {
            kernel: frozen,
            sender,
            receiver,
            excluded,
            gram,
        }
    }
}

/// Projects K·s onto the frozen kernel's Gaussians ([`crate::projection`]) at the relative pivot
/// threshold `rejection` and iterates `s ← E + B_refl(s)` with the kernel collection (one light
/// bounce per iteration) until the total strength changes by less than [`BOUNCE_TOLERANCE`] or
/// `max_bounces` is reached. Returns the projected kernel, its sender integrals and the bounces
/// run.
fn propagate_at(
    prepared: &Frozen,
    domain: &Domain,
    config: &SolveConfig,
    (samples, shots): (&mut [Sample], u64),
    max_bounces: usize,
    rejection: f64,
) -> Propagated {
    let Frozen {
        kernel,
        sender,
        receiver,
        excluded,
        gram,
    } = prepared;
    let mut frozen = kernel.clone();
    let unsupported = excluded.iter().filter(|e| **e).count();
    let projection =
        KernelProjection::from_gram(gram, config.projection_tolerance, rejection, excluded);
    let reflectance = |f| domain.reflectance(f);
    let total =
        |samples: &[Sample]| -> f64 { samples.iter().map(|s| s.s.iter().sum::<f64>()).sum() };
    let mut balance = 1.0;
    // The projection conserves energy only up to its fit error and the cells it rejects; with ρ
    // near 1 the bounce iteration amplifies any excess (a ρ = 0.95 furnace ran away to 15× the
    // exact B). Rescaling the weights so that the kernel reflects exactly the power the samples
    // carry makes the iteration's gain that of the scene. Returns the balance before the
    // rescaling (None when not measured).
    let fit = |frozen: &mut KernelCells, samples: &[Sample]| -> Option<f64> {
        projection.fit(frozen, samples, shots, &reflectance);
        if !config.energy_correction {
            return None;
        }
        let sampled = sampled_reflected_power(samples, shots, &reflectance);
        let model = kernel_reflected_power(frozen, sender, receiver);
        let (mut num, mut den) = (0.0, 0.0);
        for k in 0..MAX_BANDS {
            num += model[k];
            den += sampled[k];
            let ratio = sampled[k] / model[k];
            if sampled[k] > 0.0 && model[k] > 0.0 && ratio.is_finite() {
                for v in frozen.v.iter_mut() {
                    v[k] *= ratio;
                }
            }
        }
        (den > 0.0 && num.is_finite()).then_some(num / den)
    };
    let bound = domain.radiosity_bound();
    let mut before = total(samples);
    let mut bounces = 0;
    // The physical iteration contracts (gain ≤ ρ_max < 1), so its changes shrink. A projected
    // kernel can still carry a mode with gain above 1 (seen on wall-floor at 350–450 cells: B
    // grew to 1e51 over 200 bounces while the first 30 converged): when the change grows on
    // two bounces in a row, the strengths go back to those after the smallest change and the
    // iteration stops ([`propagate`] then redoes the projection with a higher rejection). So it
    // does at once when the projection reflects far more or less power than the samples carry
    // ([`BALANCE_LIMIT`]), or a strength breaks the maximum-principle bound tenfold.
    let mut changes = (f64::INFINITY, f64::INFINITY);
    let mut best: Option<(f64, Vec<Bands>)> = None;
    let mut diverged = false;
    let restore = |samples: &mut [Sample], best: &Option<(f64, Vec<Bands>)>| {
        if let Some((_, s)) = best {
            for (smp, v) in samples.iter_mut().zip(s) {
                smp.s = *v;
            }
        }
    };
    while bounces < max_bounces {
        let measured = fit(&mut frozen, samples);
        balance = measured.unwrap_or(balance);
        if measured.is_some_and(|b| !(1.0 / BALANCE_LIMIT..=BALANCE_LIMIT).contains(&b)) {
            diverged = true;
            restore(samples, &best);
            break;
        }
        samples.par_iter_mut().for_each(|smp| {
            smp.s = kernel_strength(&smp.ray, &frozen, sender);
        });
        bounces += 1;
        let after = total(samples);
        let change = (after - before).abs() / after.abs().max(1e-300);
        before = after;
        if change < BOUNCE_TOLERANCE {
            break;
        }
        if (change > changes.1 && changes.1 > changes.0)
            || bound_excess(samples, &bound) > UNSTABLE_FACTOR
        {
            diverged = true;
            restore(samples, &best);
            break;
        }
        changes = (changes.1, change);
        if best.as_ref().is_none_or(|(c, _)| change < *c) {
            best = Some((change, samples.iter().map(|smp| smp.s).collect()));
        }
    }
    // The weights that go with the final strengths.
    if let Some(b) = fit(&mut frozen, samples) {
        balance = b;
    }
    Propagated {
        kernel: frozen,
        sender: sender.clone(),
        bounces,
        energy_balance: balance,
        diverged,
        settled: best.is_some_and(|(c, _)| c < SETTLED_CHANGE),
        stabilized: 0,
        unsupported,
    }
}

/// [`propagate_at`], guarded by the maximum principle: with `∫_S G(x, y) dy ≤ 1`, every
/// radiosity obeys `B ≤ E_max / (1 − ρ_max)` per band ([`Domain::radiosity_bound`]), and so does
/// every sample strength of a sound solve. A projected kernel whose bounce iteration breaks the
/// bound tenfold has gone unstable: measured with 1400 cornell-box cells at a support cut-off of
/// 1e−4 (B ≈ 1e15, and still ≈ 1e69 after redoing the projection with the cut-off 1000× tighter
/// and the rejection threshold raised to 0.1, so the damage is in the network the loose cut-off
/// trained, not in one Gram matrix). The solve then stops with an error instead of a wrong
/// picture.
#[allow(clippy::too_many_arguments)]
fn propagate(
    kernel: &impl GrowingNetwork,
    domain: &Domain,
    config: &SolveConfig,
    samples: &mut [Sample],
    shots: u64,
    scene: &SceneSurface,
    max_bounces: usize,
) -> Result<Propagated, SolveError> {
    let tol = config.projection_tolerance;
    let mut rejection = config.projection_rejection;
    let prepared = Frozen::new(kernel, domain, config, samples, scene);
    let run = |samples: &mut [Sample], rejection: f64| {
        propagate_at(
            &prepared,
            domain,
            config,
            (samples, shots),
            max_bounces,
            rejection,
        )
    };
    let start: Vec<Bands> = samples.iter().map(|s| s.s).collect();
    let bound = domain.radiosity_bound();
    let mut p = run(samples, rejection);
    let mut stabilized = 0;
    for higher in STABILIZING_REJECTIONS {
        // A few training bounces are too few to see a slow divergence grow; a strength beyond
        // twice the physical bound shows it anyway.
        let runaway =
            (p.diverged && !p.settled) || bound_excess(samples, &bound) > RESTABILIZE_FACTOR;
        if !runaway || higher <= rejection {
            break;
        }
        for (smp, s) in samples.iter_mut().zip(&start) {
            smp.s = *s;
        }
        rejection = higher;
        stabilized += 1;
        p = run(samples, rejection);
    }
    p.stabilized = stabilized;
    let worst = bound_excess(samples, &bound);
    if worst > UNSTABLE_FACTOR {
        return Err(SolveError::Unstable(format!(
            "the projected kernel's bounces give radiosities {worst:.1e} times the bound \
             E_max/(1 − ρ_max) of the scene (projection cut-off {:.0e}, rejection {:.0e}; the \
             defaults of both, 1e-6, are the measured-safe ones)",
            tol, rejection
        )));
    }
    Ok(p)
}

/// The largest `|s_k| / bound_k` over the samples and bands (∞ for a non-finite strength; a zero
/// bound counts as the smallest positive number, so any strength in a dark band is an excess).
fn bound_excess(samples: &[Sample], bound: &Bands) -> f64 {
    samples
        .iter()
        .flat_map(|s| (0..MAX_BANDS).map(move |k| (s.s[k].abs(), k)))
        .map(|(v, k)| {
            if v.is_finite() {
                v / bound[k].max(f64::MIN_POSITIVE)
            } else {
                f64::INFINITY
            }
        })
        .fold(0.0, f64::max)
}

/// Relative pivot thresholds a diverging projection is redone with, in turn
/// ([`propagate`]), the gentlest first. Measured on wall-floor at 400 cells, seed 2: 1e−4, 1e−2
/// and 0.1 still diverged (the unstable mode is not carried by nearly dependent cells), 0.5 and
/// 0.9 converged to B within 8 % of the 300-cell solution at the scene's probes. On cornell-box
/// at 1850 and 2000 cells (seed 2) the projection at 1e−6 reflected −195× the sampled power and
/// 1e−3 was enough: going straight to 0.5 dropped 1568 of 1850 cells, and the ray gather error
/// went from 5.8 % to 3.4 % with the gentler step. Each step refactors the same Gram matrix
/// ([`Frozen`]).
const STABILIZING_REJECTIONS: [f64; 4] = [1e-3, 1e-1, 0.5, 0.9];

/// A projection whose kernel reflects more than this many times the power the samples carry, or
/// less than its inverse, is broken ([`propagate_at`] stops its bounces at once). Sound ones measured
/// 0.98–1.06; on cornell-box at 1850 cells (seed 2, network trained on the clamped kernel) one
/// reflected −195× the sampled power, and its bounces grew by 1e4 per bounce.
const BALANCE_LIMIT: f64 = 4.0;

/// A bounce iteration whose relative change of the total strength fell below this before it
/// started to grow again counts as settled: [`propagate`] keeps the strengths at the smallest
/// change instead of redoing the projection with fewer cells. Measured on cornell-box at 2000
/// cells, seed 4: the final iteration's change fell to 1.2e−5 and then grew by 1–5 % per bounce (a
/// mode of gain just above 1); redoing it at rejection 0.5 dropped 1671 of the 2000 cells and
/// took the ray gather to 10.4 % (6.6 % with the strengths kept). A real runaway (seed 5 at 947 cells, before the
/// minimum support) grew by 3× per bounce from changes of 1e−2 and is still redone.
const SETTLED_CHANGE: f64 = 1e-4;

/// A strength this far beyond the maximum-principle bound makes [`propagate`] redo the projection
/// with a higher rejection even when its bounces did not visibly diverge. The true solution stays
/// within the bound (a furnace reaches it exactly, so 1 would be too tight); measured on
/// cornell-box seed 2: the projection at 947 cells ran 4 bounces without a growing change but left
/// strengths at 6.2× the bound, and the next one could no longer recover (guard error at 1000,
/// 1400 and 2000 cells). With this check seed 2 completes (14.7 % ray-gather error at 1400 cells,
/// 10.4 % at 2000, against 5.6–7.7 % for seeds 1, 3, 4); seed 5 still stops with the guard. A
/// run that never exceeds the factor (every default solve measured) is unchanged.
const RESTABILIZE_FACTOR: f64 = 2.0;

/// How far beyond the maximum-principle bound a strength may go (Monte-Carlo noise and the
/// projection's ringing stay far below this) before the solve counts as unstable.
const UNSTABLE_FACTOR: f64 = 10.0;

/// What [`propagate`] returns.
struct Propagated {
    /// The projected kernel.
    kernel: KernelCells,
    /// Its sender integrals.
    sender: Vec<f64>,
    /// Bounces run.
    bounces: usize,
    /// Reflected power of the projected kernel over the power the samples carry, before the
    /// energy correction, in the last fit (1 when the projection conserves energy; 1 when the
    /// correction is off and nothing was measured).
    energy_balance: f64,
    /// The bounces started to diverge and were stopped at the smallest change.
    diverged: bool,
    /// The smallest change was below [`SETTLED_CHANGE`]: a divergence from there is too slow to
    /// matter.
    settled: bool,
    /// Times the projection was redone with a higher rejection threshold because it diverged.
    stabilized: usize,
    /// Cells left out of the projection for want of samples in their support.
    unsupported: usize,
}

/// A new sample's strength s = E + B_refl from the current solution.
fn initial_strength(
    ray: &Ray,
    config: &SolveConfig,
    current: Option<&FemSolution>,
    scratch: &mut Vec<u32>,
) -> Bands {
    match (config.strength_from, current) {
        (StrengthFrom::Kernel, Some(f)) => kernel_strength(ray, &f.kernel, &f.sender),
        _ => strength(ray, current, scratch),
    }
}

/// Appends `count` samples: shot rays for the projection (every shot counted in `shots`, also
/// those that leave the scene), area-uniform rays for the delta rule.
fn add_samples(
    domain: &Domain,
    config: &SolveConfig,
    density: &SenderDensity,
    rng: &mut ChaCha8Rng,
    count: usize,
    current: Option<&FemSolution>,
    samples: &mut Vec<Sample>,
    shots: &mut u64,
) {
    let seeds: Vec<u64> = (0..count).map(|_| rng.random()).collect();
    let new: Vec<(u64, Option<Sample>)> = match config.output_fit {
        OutputFit::Projection => seeds
            .par_iter()
            .map_init(Vec::new, |scratch, &seed| {
                let mut r = ChaCha8Rng::seed_from_u64(seed);
                // Shoot until a ray lands (open scenes lose some).
                for tries in 1..=64u64 {
                    if let Some(shot) = density.shoot(domain, &mut r) {
                        let smp = Sample {
                            s: initial_strength(&shot.ray, config, current, scratch),
                            ray: shot.ray,
                            kernel_bmu: None,
                            shading_bmu: None,
                            inv_px: shot.inv_px,
                        };
                        return (tries, Some(smp));
                    }
                }
                (64, None)
            })
            .collect(),
        // each sample's parameters from its own seed, as one at a time; in chunks because `Domain::rays`
        // prefetches ahead within a chunk
        OutputFit::DeltaRule => seeds
            .par_chunks(64)
            .flat_map_iter(|chunk| {
                let us: Vec<Vec<f64>> = chunk
                    .iter()
                    .map(|&seed| {
                        let mut r = ChaCha8Rng::seed_from_u64(seed);
                        (0..domain.param_dim()).map(|_| r.random()).collect()
                    })
                    .collect();
                let mut scratch = Vec::new();
                domain.rays(&us).into_iter().map(move |ray| {
                    let smp = Sample {
                        s: initial_strength(&ray, config, current, &mut scratch),
                        ray,
                        kernel_bmu: None,
                        shading_bmu: None,
                        inv_px: 0.0,
                    };
                    (1, Some(smp))
                })
            })
            .collect(),
    };
    for (tries, smp) in new {
        *shots += tries;
        samples.extend(smp);
    }
}

/// s = E(x) + B_refl(x) from the current FEM solution (E alone before the first step).
fn strength(ray: &Ray, fem: Option<&FemSolution>, scratch: &mut Vec<u32>) -> Bands {
    let mut s = ray.emission_x;
    if let Some(f) = fem {
        let b = f.reflected_from_base(ray.x, ray.nx, scratch);
        for k in 0..MAX_BANDS {
            s[k] += b[k].max(0.0);
        }
    }
    s
}

/// s = E(x) + B_refl(x) with B_refl from the kernel collection (fig. 4.13c) at the sender.
fn kernel_strength(ray: &Ray, kernel: &KernelCells, sender: &[f64]) -> Bands {
    let b = reflected_from_kernel(kernel, sender, ray.x, ray.nx);
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

#[cfg(test)]
mod tests {
    use super::*;

    fn sample(s: Bands) -> Sample {
        Sample {
            ray: Ray {
                x: DVec3::ZERO,
                nx: DVec3::Y,
                y: DVec3::ONE,
                ny: DVec3::NEG_Y,
                face_x: 0,
                face_y: 1,
                kernel: [0.0; MAX_BANDS],
                emission_x: [0.0; MAX_BANDS],
            },
            s,
            kernel_bmu: None,
            shading_bmu: None,
            inv_px: 0.0,
        }
    }

    /// The unstable-solve test reads the worst ratio to the bound over every sample and band,
    /// takes magnitudes (a projection can ring negative), and flags non-finite strengths.
    #[test]
    fn bound_excess_finds_the_worst_strength() {
        let bound = [2.0, 4.0, 8.0];
        let (a, mut b) = ([1.0, 1.0, 1.0], [0.5, -12.0, 4.0]);
        assert_eq!(bound_excess(&[sample(a), sample(b)], &bound), 3.0);
        assert_eq!(bound_excess(&[], &bound), 0.0);
        b[2] = f64::NAN;
        assert_eq!(bound_excess(&[sample(a), sample(b)], &bound), f64::INFINITY);
        // A strength in a band the scene does not emit in is an excess of its own.
        let dark_bound = [2.0, 4.0, 0.0];
        assert!(bound_excess(&[sample([0.0, 0.0, 1e-3])], &dark_bound) > UNSTABLE_FACTOR);
    }
}

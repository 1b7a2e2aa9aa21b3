//! The sample set: rays (x, y) with their emitting strength s = E(x) + B_refl(x) (docs/design/math.md §4),
//! drawn area-uniformly (fig. B.2; the delta rule), shot from the sender density
//! ([`crate::shooting`]; the projection), or resampled in critical regions (sec. 2.5).

use super::error::SolveError;
use super::run::{Current, Run};
use crate::cell_lanes::Collection;
use crate::config::{OutputFit, SolveConfig, StrengthFrom};
use crate::domain::Ray;
use crate::element::{BANDS, Bands};
use crate::fem::FemSolution;
use crate::network::GrowingNetwork;
use crate::sample::Sample;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use std::time::Instant;

impl Sample {
    /// A sample of `ray` with its strength from the current solution.
    fn new(ray: Ray, inv_px: f64, config: &SolveConfig, current: Option<&Current>) -> Self {
        let mut scratch = Vec::new();
        Self {
            s: initial_strength(&ray, config, current, &mut scratch),
            ray,
            inv_px,
        }
    }
}

impl Run<'_> {
    /// The size of the first sample set: 20 cells' worth, at least 500.
    pub(super) fn initial_sample_count(&self) -> usize {
        (self.config.samples_per_cell * 20).max(500)
    }

    /// Appends `count` samples: shot rays for the projection (every shot counted in `shots`,
    /// also those that leave the scene), area-uniform rays for the delta rule.
    pub(super) fn add_samples(&mut self, count: usize) {
        let t0 = Instant::now();
        let (domain, config, current) = (self.domain, self.config, self.current.as_ref());
        let density = &self.density;
        let seeds: Vec<u64> = (0..count).map(|_| self.rng.random()).collect();
        let new: Vec<(u64, Option<Sample>)> = match config.output_fit {
            OutputFit::Projection => seeds
                .par_iter()
                .map(|&seed| {
                    let mut r = ChaCha8Rng::seed_from_u64(seed);
                    // Shoot until a ray lands (open scenes lose some).
                    for tries in 1..=64u64 {
                        if let Some(shot) = density.shoot(domain, &mut r) {
                            return (
                                tries,
                                Some(Sample::new(shot.ray, shot.inv_px, config, current)),
                            );
                        }
                    }
                    (64, None)
                })
                .collect(),
            // each sample's parameters from its own seed, as one at a time; in chunks because
            // `Domain::rays` prefetches ahead within a chunk
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
                    domain
                        .rays(&us)
                        .into_iter()
                        .map(move |ray| (1, Some(Sample::new(ray, 0.0, config, current))))
                })
                .collect(),
        };
        let before = self.shots;
        for (tries, smp) in new {
            self.shots += tries;
            self.samples.extend(smp);
        }
        self.metrics.rays_traced += self.shots - before;
        self.metrics.seconds.sampling += t0.elapsed().as_secs_f64();
    }

    /// Errs when no sample connects two surfaces; warns (in the metrics) when no emitter's light
    /// reaches a surface (every B would be E): a scene lit by lights facing away from it.
    pub(super) fn check_flow(&mut self) -> Result<(), SolveError> {
        if self.samples.is_empty() {
            return Err(SolveError::NoRays { shots: self.shots });
        }
        let lit = self
            .samples
            .iter()
            .any(|smp| (0..BANDS).any(|k| smp.ray.emission_x[k] > 0.0 && smp.ray.kernel[k] > 0.0));
        if !lit {
            self.metrics.warnings.push(format!(
                "none of {} sampled rays carries light from an emitter to a surface: do the lights \
                 face away from the scene? Every radiosity will be its emission",
                self.samples.len()
            ));
        }
        Ok(())
    }

    /// Appends `count` area-uniform rays of which a share
    /// ([`SolveConfig::resample_critical_fraction`]) lies in the kernel network's critical
    /// regions (definition 7, eq. 2.23; sec. 2.5), the rest anywhere: the delta rule's resampling.
    pub(super) fn resample_critical(&mut self, kernel: &impl GrowingNetwork, count: usize) {
        let (domain, config) = (self.domain, self.config);
        let (dim, pd) = (domain.dim(), domain.param_dim());
        let tr = Instant::now();
        let mut accepted: Vec<Vec<f64>> = Vec::with_capacity(count);
        let mut input = Vec::with_capacity(2 * dim);
        let mut tries = 0;
        let critical_wanted = (count as f64 * config.resample_critical_fraction) as usize;
        while accepted.len() < critical_wanted && tries < 20 * count {
            tries += 1;
            let u: Vec<f64> = (0..pd).map(|_| self.rng.random::<f64>()).collect();
            domain.endpoints(&u).input(&mut input);
            input.truncate(2 * dim);
            if kernel.is_critical(&input[..]) {
                accepted.push(u);
            }
        }
        while accepted.len() < count {
            accepted.push((0..pd).map(|_| self.rng.random::<f64>()).collect());
        }
        self.metrics.seconds.resampling += tr.elapsed().as_secs_f64();
        let t0 = Instant::now();
        let current = self.current.as_ref();
        // in chunks: `Domain::rays` prefetches ahead within a chunk
        let new: Vec<Sample> = accepted
            .par_chunks(64)
            .flat_map_iter(|chunk| {
                domain
                    .rays(chunk)
                    .into_iter()
                    .map(move |ray| Sample::new(ray, 0.0, config, current))
            })
            .collect();
        self.metrics.rays_traced += new.len() as u64;
        self.samples.extend(new);
        self.metrics.seconds.sampling += t0.elapsed().as_secs_f64();
    }

    /// s ← E + B_refl for every sample, from the last FEM step's base or kernel collection.
    pub(super) fn update_strengths(&mut self) {
        let (current, config) = (self.current.as_ref(), self.config);
        self.samples
            .par_iter_mut()
            .for_each_init(Vec::new, |scratch, smp| {
                smp.s = initial_strength(&smp.ray, config, current, scratch);
            });
    }
}

/// A sample's strength s = E + B_refl from the current solution ([`SolveConfig::strength_from`]).
fn initial_strength(
    ray: &Ray,
    config: &SolveConfig,
    current: Option<&Current>,
    scratch: &mut Vec<u32>,
) -> Bands {
    match (config.strength_from, current) {
        (StrengthFrom::Kernel, Some(c)) => kernel_strength(ray, &c.collection),
        _ => strength(ray, current.map(|c| &c.fem), scratch),
    }
}

/// s = E(x) + B_refl(x) from the current FEM solution's base (E alone before the first step).
fn strength(ray: &Ray, fem: Option<&FemSolution>, scratch: &mut Vec<u32>) -> Bands {
    let mut s = ray.emission_x;
    if let Some(f) = fem {
        let b = f.reflected_from_base(ray.x, ray.nx, scratch);
        for k in 0..BANDS {
            s[k] += b[k].max(0.0);
        }
    }
    s
}

/// s = E(x) + B_refl(x) with B_refl from the kernel collection (fig. 4.13c) at the sender.
pub(super) fn kernel_strength(ray: &Ray, collection: &Collection) -> Bands {
    let b = collection.at(ray.x, ray.nx);
    let mut s = ray.emission_x;
    for k in 0..BANDS {
        s[k] += b[k].max(0.0);
    }
    s
}

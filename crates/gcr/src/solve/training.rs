//! Training steps (fig. 2.9 through [`GrowingNetwork::train`]): the kernel network on (x, y) with
//! the target of [`NetworkTarget`], the shading network on the receivers y with their normals
//! (sec. 3.2; docs/design/math.md §6: the ray *end* points).

use crate::config::{NetworkTarget, SolveConfig};
use crate::domain::Domain;
use crate::network::GrowingNetwork;
use crate::sample::Sample;
use rand::Rng;
use rand_chacha::ChaCha8Rng;
use std::time::Instant;

/// Training steps per batch: the phases are timed per batch, not per step.
const BATCH: usize = 256;

/// Scratch buffers and phase timers of the training steps on one domain and configuration.
pub(super) struct Trainer<'a> {
    domain: &'a Domain<'a>,
    config: &'a SolveConfig,
    input: Vec<f64>,
    target: Vec<f64>,
    picked: Vec<usize>,
    /// Training steps run.
    pub steps: u64,
    /// Seconds in kernel training steps.
    pub kernel_seconds: f64,
    /// Seconds in shading training steps.
    pub shading_seconds: f64,
}

impl<'a> Trainer<'a> {
    /// A trainer with no step run yet.
    pub(super) fn new(domain: &'a Domain<'a>, config: &'a SolveConfig) -> Self {
        Self {
            domain,
            config,
            input: Vec::new(),
            target: Vec::new(),
            picked: Vec::new(),
            steps: 0,
            kernel_seconds: 0.0,
            shading_seconds: 0.0,
        }
    }

    /// One batch: the kernel network on [`BATCH`] random samples, then (when the base is read)
    /// the shading network on the same samples' receivers. The samples are drawn by `rng`. The
    /// shading network stops growing at its budget.
    pub(super) fn batch(
        &mut self,
        kernel: &mut impl GrowingNetwork,
        shading: &mut impl GrowingNetwork,
        samples: &[Sample],
        rng: &mut ChaCha8Rng,
    ) {
        let tk = Instant::now();
        self.picked.clear();
        for _ in 0..BATCH {
            let i = rng.random_range(0..samples.len());
            self.kernel_step(kernel, &samples[i]);
            self.picked.push(i);
        }
        self.kernel_seconds += tk.elapsed().as_secs_f64();
        let ts = Instant::now();
        if shading.cell_count() >= self.config.shading_cells {
            shading.set_growing(false);
        }
        if self.config.needs_base() {
            let dim = self.domain.dim();
            for &i in &self.picked {
                let ray = &samples[i].ray;
                self.input.clear();
                self.input.extend_from_slice(&ray.y.to_array()[..dim]);
                self.target.clear();
                self.target.extend_from_slice(&ray.ny.to_array()[..dim]);
                shading.train(&self.input, &self.target);
            }
        }
        self.shading_seconds += ts.elapsed().as_secs_f64();
        self.steps += BATCH as u64;
    }

    /// A sweep of `samples.len()` kernel steps on random samples without growing: the delta rule
    /// re-learns its targets after a final FEM step changed the strengths.
    pub(super) fn sweep(
        &mut self,
        kernel: &mut impl GrowingNetwork,
        samples: &[Sample],
        rng: &mut ChaCha8Rng,
    ) {
        for _ in 0..samples.len() {
            let i = rng.random_range(0..samples.len());
            self.kernel_step(kernel, &samples[i]);
        }
    }

    /// One kernel training step on a sample: input (x, y), target [`kernel_target`].
    fn kernel_step(&mut self, kernel: &mut impl GrowingNetwork, smp: &Sample) {
        let (domain, config) = (self.domain, self.config);
        let dim = domain.dim();
        self.input.clear();
        self.input.extend_from_slice(&smp.ray.x.to_array()[..dim]);
        self.input.extend_from_slice(&smp.ray.y.to_array()[..dim]);
        kernel_target(smp, config, domain, &mut self.target);
        kernel.train(&self.input, &self.target);
    }
}

/// The kernel network's training target for a sample ([`NetworkTarget`]).
fn kernel_target(smp: &Sample, config: &SolveConfig, domain: &Domain, out: &mut Vec<f64>) {
    let (ray, s) = (&smp.ray, &smp.s);
    let bands = domain.bands();
    out.clear();
    match config.network_target {
        NetworkTarget::SampleWeight if smp.inv_px != 0.0 => {
            let rho = domain.reflectance_at(ray.face_y, ray.y);
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

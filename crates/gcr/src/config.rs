//! Settings of a solve and their validation: [`SolveConfig::preset`] is what `gcr solve` runs
//! (the paths gather to a target error); [`SolveConfig::default`] the dissertation's settings
//! (fig. 4.17, sec. 4.4.1).

use thiserror::Error;

/// How the output radiosity at the vertices is computed (sec. 4.3.2).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum GatherMode {
    /// From the shading network's base (fig. 4.13a/b).
    Base,
    /// A final collection through the kernel network (fig. 4.13c, the dissertation's choice).
    Kernel,
    /// Ray-traced: exact direct light with shadow rays plus one-bounce indirect light from the
    /// networks (beyond the dissertation).
    #[default]
    Rays,
    /// Consistent: paths continued from the output point with the kernel network as a control
    /// variate at every vertex (docs/design/math.md §9); unbiased whatever the networks' error, with a
    /// standard error per point (beyond the dissertation).
    Paths,
}

impl GatherMode {
    /// The name used on the command line and in metrics.
    pub fn name(self) -> &'static str {
        match self {
            GatherMode::Base => "base",
            GatherMode::Kernel => "kernel",
            GatherMode::Rays => "rays",
            GatherMode::Paths => "paths",
        }
    }
}

impl std::str::FromStr for GatherMode {
    type Err = ConfigError;
    fn from_str(s: &str) -> Result<Self, ConfigError> {
        match s {
            "base" => Ok(GatherMode::Base),
            "kernel" => Ok(GatherMode::Kernel),
            "rays" => Ok(GatherMode::Rays),
            "paths" => Ok(GatherMode::Paths),
            other => Err(ConfigError::Invalid(format!(
                "unknown gather mode `{other}` (expected base, kernel, rays or paths)"
            ))),
        }
    }
}

/// How close the default gather runs to the answer (`gcr solve --quality`): a target for its
/// estimated relative error ([`SolveConfig::preset`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Quality {
    /// 5 %: a first look.
    Draft,
    /// 2 %: the program's default.
    #[default]
    Good,
    /// 1 %: for comparisons against a reference.
    Final,
}

impl Quality {
    /// The estimated relative error (standard error, relative L2 over the output points) the
    /// paths gather stops at.
    pub fn target_error(self) -> f64 {
        match self {
            Quality::Draft => 0.05,
            Quality::Good => 0.02,
            Quality::Final => 0.01,
        }
    }
}

impl std::str::FromStr for Quality {
    type Err = ConfigError;
    fn from_str(s: &str) -> Result<Self, ConfigError> {
        match s {
            "draft" => Ok(Quality::Draft),
            "good" => Ok(Quality::Good),
            "final" => Ok(Quality::Final),
            other => Err(ConfigError::Invalid(format!(
                "unknown quality `{other}` (expected draft, good or final)"
            ))),
        }
    }
}

/// Whether the paths gather guides its rays (`gcr solve --guiding`; docs/design/estimator.md,
/// "Guiding" and "Secondary sources"): by the table of the scene's direct radiosity, drawn at
/// every path vertex (`estimator/secondary.rs`), and by directional guides that earlier rounds
/// learned (`estimator/guide.rs`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Guiding {
    /// Never: plain paths, every round continues one Sobol sequence of cosine rays.
    Off,
    /// Both from the first round on (a per-pixel image: the table only).
    On,
    /// The table where a trial round before the rounds to a target finds hard light and the
    /// table halving its variance per ray (points, probes, texels, pixels); the directional guides when the pilot round finds hard
    /// light ([`Guiding::pays`]: at least [`GUIDING_FROM`] rays per point predicted to the
    /// target, at a relative variance per ray of at least [`GUIDING_VARIANCE`]). Otherwise
    /// exactly `Off`.
    #[default]
    Auto,
}

/// Rays per point to the target, predicted by the pilot round, from which `Guiding::Auto`
/// guides: guides learn over rounds, and a guided ray costs up to twice an unguided one. Under
/// the sun patch room's ceiling, predicted 15 574 rays to 2 %, guiding took 0.80× the time
/// (docs/design/estimator.md, "Guiding"); scenes predicted below a few thousand rays lost
/// 1.3–1.8× (uplight room to 2 %: 3 775 predicted, 1.32×).
pub const GUIDING_FROM: usize = 8_192;

/// The relative variance of one ray's estimate (the pilot's squared relative error × its rays,
/// Σσ²/ΣB² per ray) from which `Guiding::Auto` guides: below it cosine sampling finds the light
/// well enough that guides, at up to twice the cost of a ray and with rounds spent learning,
/// do not win it back against unguided rounds that stop at the part that meets the target
/// (`estimator::rounds`; guided rounds run whole). The Cornell box (0.026 per ray) to 0.12 %
/// took 1.95× as long guided although it needs 8 192 rays; the many-rooms work planes (0.15) to
/// 1 % 1.71×; the uplight room (1.5) to 1 % 1.45× (3.4 s against 2.3 s); the sun patch room's
/// ceiling (6.2) gains, 0.80× to 2 % and 0.83× to 1 %, and the door gap, far above, 0.47× to 2 %.
pub const GUIDING_VARIANCE: f64 = 3.0;

impl Guiding {
    /// Whether `Auto` guides after a pilot round of `rays` rays per point whose error's upper
    /// bound is `bound` and that predicts `needed` rays per point to the target.
    pub fn pays(rays: usize, bound: f64, needed: usize) -> bool {
        needed >= GUIDING_FROM && rays as f64 * bound * bound >= GUIDING_VARIANCE
    }
}

impl std::str::FromStr for Guiding {
    type Err = ConfigError;
    fn from_str(s: &str) -> Result<Self, ConfigError> {
        match s {
            "off" => Ok(Guiding::Off),
            "on" => Ok(Guiding::On),
            "auto" => Ok(Guiding::Auto),
            other => Err(ConfigError::Invalid(format!(
                "unknown guiding `{other}` (expected auto, on or off)"
            ))),
        }
    }
}

/// One of `count` shards of a run's output points (`gcr solve --shard index/count`, 0 ≤ index <
/// count): the points of the blocks [`PathSettings::block_points`] assigns to it
/// ([`crate::shard_points`]). Each shard's values are bit-identical to the same points' in a
/// single run; `gcr merge` joins the shards' partial outputs.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Shard {
    /// This shard, from 0.
    pub index: usize,
    /// How many shards the points are split into.
    pub count: usize,
}

impl std::str::FromStr for Shard {
    type Err = ConfigError;
    fn from_str(s: &str) -> Result<Self, ConfigError> {
        let bad = || {
            ConfigError::Invalid(format!(
                "shard `{s}`: expected INDEX/COUNT with 0 <= INDEX < COUNT, e.g. 0/4"
            ))
        };
        let (i, n) = s.split_once('/').ok_or_else(bad)?;
        let (index, count) = (
            i.trim().parse().map_err(|_| bad())?,
            n.trim().parse().map_err(|_| bad())?,
        );
        if index >= count {
            return Err(bad());
        }
        Ok(Shard { index, count })
    }
}

impl std::fmt::Display for Shard {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}/{}", self.index, self.count)
    }
}

/// The paths gather's first round with a target error, in rays per point (each of shadow and
/// cosine rays): enough points for a first estimate of the error, few enough that an easy target
/// is not overshot.
pub const PILOT_RAYS: usize = 16;

/// Where a sample's new emitting strength s = E + B_refl comes from after a FEM step.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum StrengthFrom {
    /// The shading network's Gaussian base (the dissertation, fig. 3.1).
    Base,
    /// The kernel collection B_refl(x) = Σ v_o c_o exp(−|x − w_o^y|²/d_o²). Default: the base is
    /// the projection of this same function onto fewer, surface-bound Gaussians, so it can only
    /// add error (docs/design/gcr-algorithm.md).
    #[default]
    Kernel,
}

/// How the kernel network's output weights are obtained.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum OutputFit {
    /// The dissertation: the delta rule (eq. 2.8) on area-uniform ray samples (fig. B.2), with
    /// resampling of critical regions (sec. 2.5).
    DeltaRule,
    /// Shot rays (`shooting.rs`) and, at every FEM step, the output weights replaced by the
    /// L2 projection of K·s onto the cells' Gaussians (`projection.rs`). Default: measured
    /// far more accurate (docs/design/gcr-algorithm.md).
    #[default]
    Projection,
}

/// What the kernel network is trained on. With the projected output layer
/// ([`OutputFit::Projection`]) the network only places the cells (centres and widths): its own
/// output weights are replaced at every projection, so the target decides where the cells go.
/// Measured on cornell-box, ray gather at 1024 rays, 200 points (docs/design/gcr-algorithm.md).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum NetworkTarget {
    /// The dissertation's target K(x,y)·s(x) (eq. 2.8). G = cos θ_x cos θ_y/(π r²) is unbounded
    /// where surfaces meet, so the network spends its insertions there, on cells a few
    /// millimetres wide that hold a fraction of a sample each. 1400 cells, seeds 1–5: 6.5 % on
    /// average.
    KernelValue,
    /// Each shot sample's importance weight ρ(y)·s(x)/p_x(x), the value it adds to the
    /// projection's moments (bounded: the pair density carries G). The cells follow the light,
    /// not the geometry: 4.9 % at 1400 cells, but a furnace, whose weights are constant, gets
    /// cells that ignore G (ρ = 0.95 at 80 cells: 13 % against 4 %).
    SampleWeight,
    /// K·s with the 1/r² of G clamped at `SolveConfig::network_clamp_radius`: the structure of
    /// K down to the scale the cells can resolve, without the singularity below it. 1400 cells,
    /// seeds 1–3: 3.6 / 4.2 / 4.3 %.
    #[default]
    ClampedKernel,
}

impl OutputFit {
    /// The name used on the command line and in metrics.
    pub fn name(self) -> &'static str {
        match self {
            OutputFit::DeltaRule => "delta-rule",
            OutputFit::Projection => "projection",
        }
    }
}

impl std::str::FromStr for OutputFit {
    type Err = ConfigError;
    fn from_str(s: &str) -> Result<Self, ConfigError> {
        match s {
            "delta-rule" => Ok(OutputFit::DeltaRule),
            "projection" => Ok(OutputFit::Projection),
            other => Err(ConfigError::Invalid(format!(
                "unknown output fit `{other}` (expected delta-rule or projection)"
            ))),
        }
    }
}

impl NetworkTarget {
    /// The name used on the command line and in metrics.
    pub fn name(self) -> &'static str {
        match self {
            NetworkTarget::KernelValue => "kernel-value",
            NetworkTarget::SampleWeight => "sample-weight",
            NetworkTarget::ClampedKernel => "clamped-kernel",
        }
    }
}

impl std::str::FromStr for NetworkTarget {
    type Err = ConfigError;
    fn from_str(s: &str) -> Result<Self, ConfigError> {
        match s {
            "kernel-value" => Ok(NetworkTarget::KernelValue),
            "sample-weight" => Ok(NetworkTarget::SampleWeight),
            "clamped-kernel" => Ok(NetworkTarget::ClampedKernel),
            other => Err(ConfigError::Invalid(format!(
                "unknown network target `{other}` (expected kernel-value, sample-weight or \
                 clamped-kernel)"
            ))),
        }
    }
}

/// A setting outside its valid range.
#[derive(Debug, Error, PartialEq)]
pub enum ConfigError {
    /// The message names the setting, its value and the valid range.
    #[error("invalid setting: {0}")]
    Invalid(String),
}

/// Everything that steers a solve.
#[derive(Clone, Debug)]
pub struct SolveConfig {
    /// Kernel network cell budget ("links"): the main termination condition (sec. 4.4.1).
    pub kernel_cells: usize,
    /// Shading network cell budget.
    pub shading_cells: usize,
    /// Optional wall-time budget of the solve in seconds, the final FEM step included
    /// (training stops when the time left is what that step is expected to take).
    pub time_budget: Option<f64>,
    /// Seed of every random choice.
    pub seed: u64,
    /// Training samples (rays) kept per kernel cell (sec. 4.1: "a ratio of 10 ... is sufficient").
    pub samples_per_cell: usize,
    /// A FEM step after every this many kernel insertions (sec. 4.4.1: 20 to 50; default 30).
    pub fem_every: usize,
    /// FEM steps run after training stops, to let the last kernel propagate (each one bounce).
    pub final_fem_steps: usize,
    /// Insertion period λ of both networks (fig. 4.17: 300–600).
    pub lambda: usize,
    /// Sender integral variant of the FEM step.
    pub transfer: Transfer,
    /// Flat closed forms where the criterion allows (off: exact element sums everywhere).
    pub closed_forms: bool,
    /// Skip the shading network and the base when nothing reads them (gather ≠ base and strengths
    /// from the kernel): the kernel's solution is bit-identical, only faster. Off: always train
    /// them (for figures of the base, or to time the dissertation's full loop).
    pub skip_unused_base: bool,
    /// Where the base Gaussians are integrated: the scene S (default) or the shading
    /// network's triangles Ŝ (the dissertation).
    pub base_domain: BaseDomain,
    /// The breaking operator of the shading network.
    pub breaking: Breaking,
    /// Source of the sample strengths after each FEM step.
    pub strength_from: StrengthFrom,
    /// Output gather.
    pub gather: GatherMode,
    /// Sample counts of the ray-traced gather.
    pub gather_samples: GatherSamples,
    /// The `paths` gather's corrections and Russian roulette.
    pub paths: PathSettings,
    /// Fraction of new samples drawn in critical regions (the rest uniformly), sec. 2.5.
    pub resample_critical_fraction: f64,
    /// How the kernel network's output weights are obtained.
    pub output_fit: OutputFit,
    /// Target of the kernel network's training.
    pub network_target: NetworkTarget,
    /// [`NetworkTarget::ClampedKernel`]: the distance below which G's 1/r² is held constant, as
    /// a fraction of the scene's diagonal. Measured on cornell-box at 1400 cells: 0.05 and 0.15
    /// give the same ray-gather error (3.4–4.3 %); on a ρ = 0.95 furnace at 200 cells 0.05 gives
    /// 5.9 %, 0.15 13 %.
    pub network_clamp_radius: f64,
    /// Relative pivot below which the projection rejects a kernel cell as nearly dependent.
    pub projection_rejection: f64,
    /// Support cut-off of the projection's Gaussians: Gram entries, sender integrals and moments
    /// drop where the Gaussian (product) is below this fraction of its peak. Smaller is more
    /// exact and slower (the pairs kept grow like the 6-D ball of radius d·√ln(1/tol)); default
    /// and maximum 1e-6. Measured: on cornell-box (examples/tolerance_sweep.rs) 1e-6 gives the
    /// same errors as 1e-9 at 400 and 1400 cells with 21–28 % less FEM time at 1400 (18.4 s
    /// instead of 23.2 s alone on 2 cores); `cargo xtask bench --only compare` gives the same
    /// errors to 4 digits on the three 3-D scenes at 50–400 cells and within 0.005 in Flatland.
    /// 1e-4 was fine at 400 cells and unstable at 1400 (B ≈ 1e15, now stopped by the solver's
    /// maximum-principle guard); 1e-3 gave B ≈ 1e123 at 400.
    pub projection_tolerance: f64,
    /// Kernel cells whose sample support `n_o = Σ_i g_o(ξ_i)` over the shot samples is below this
    /// get no output weight (`projection.rs`, `kernel_support`). The network grows tiny cells
    /// where K is singular (surfaces meeting at an edge) that hold a fraction of a sample on
    /// average: their moment is one sample's noise over a tiny Gram diagonal, and when that
    /// sample's sender lies in both halves of the cell (at the edge, x ≈ y) it feeds its own
    /// strength back with a gain far above 1. Measured on cornell-box, seeds 1–5 at 1400 cells
    /// (docs/design/gcr-algorithm.md): 0 (every cell projected) lets seed 5 run away and costs seed 2
    /// twice the error; 1, 2 and 4 are stable for all five seeds. 0 turns it off.
    pub projection_min_support: f64,
    /// Rescale the projected kernel's weights per band so that it reflects exactly the power the
    /// shot samples carry (`Metrics::energy_balance` reports the factor it corrected). Off: the
    /// plain Galerkin projection, whose bounce iteration can run away when ρ is close to 1.
    pub energy_correction: bool,
    /// Cluster large surfaces for the FEM integrals (`cluster.rs`; docs/design/hierarchical.md): from
    /// `min_elements` elements on, nodes of the cluster tree replace their elements wherever a
    /// Gaussian is too wide to resolve them, so that an integral costs the same on a million
    /// triangles as on a few thousand. Below it (every built-in scene) the integrals are exact.
    pub surface_clusters: SurfaceClusters,
    /// Facing masks on the projected kernel's Gaussians (`KernelCells::assign_facing`):
    /// each half lives only on surfaces that face like the samples it was fitted to (within the
    /// breaking angle), so that light does not blur across the edges where surfaces meet. Off by
    /// default: measured (docs/design/gcr-algorithm.md) it cuts the kernel collection's error on
    /// `cornell-box` and `two-blockers` by a quarter to a half, but a masked Gaussian stops at
    /// the edge, so a field that is smooth across edges loses mass there (the furnace's kernel
    /// gather goes from 6.5 % to 17 % at 100 cells) and the ray gather gains little.
    pub kernel_facing: bool,
    /// The final propagation of the projected kernel solves the linearized bounce directly (LU
    /// in the m-dimensional weight space, `crate::solve` propagate) when the kernel has at most
    /// this many cells, then polishes with ordinary bounces; above it, or at 0, it only bounces
    /// (up to 200 times: far from converged when ρ is near 1, 0.99^200 = 0.13). The LU costs
    /// O(m³) per correction step.
    pub direct_solve_cells: usize,
}

impl Default for SolveConfig {
    fn default() -> Self {
        Self {
            kernel_cells: 300,
            shading_cells: 150,
            time_budget: None,
            seed: 1,
            samples_per_cell: 10,
            fem_every: 30,
            final_fem_steps: 3,
            lambda: 300,
            transfer: Transfer::Direct,
            closed_forms: true,
            base_domain: BaseDomain::Scene,
            skip_unused_base: true,
            breaking: Breaking::default(),
            strength_from: StrengthFrom::Kernel,
            gather: GatherMode::Rays,
            gather_samples: GatherSamples::default(),
            paths: PathSettings::default(),
            resample_critical_fraction: 0.5,
            output_fit: OutputFit::default(),
            network_target: NetworkTarget::default(),
            network_clamp_radius: 0.05,
            projection_rejection: 1e-6,
            projection_tolerance: 1e-6,
            projection_min_support: 2.0,
            energy_correction: true,
            surface_clusters: SurfaceClusters::default(),
            kernel_facing: false,
            direct_solve_cells: 3000,
        }
    }
}

impl SolveConfig {
    /// What `gcr solve` runs unless told otherwise: the paths gather (an unbiased path tracer,
    /// every ray corrected, so no network is read or trained), neighbouring points sharing paths,
    /// in rounds from a pilot of [`PILOT_RAYS`] rays until the estimated error meets `quality`'s
    /// target. The rest is [`SolveConfig::default`], which is the dissertation's setting (the ray
    /// gather reading the networks, fig. 4.17).
    pub fn preset(quality: Quality) -> Self {
        Self {
            gather: GatherMode::Paths,
            gather_samples: GatherSamples {
                direct: PILOT_RAYS,
                indirect: PILOT_RAYS,
            },
            paths: PathSettings {
                target_error: Some(quality.target_error()),
                ..PathSettings::default()
            },
            ..Self::default()
        }
    }

    /// Whether the output gather reads the networks: every gather but `paths` with every ray
    /// corrected (its default), whose networks' value cancels. Output meshes read the networks
    /// anyway (their resolution is the shading network's).
    pub fn reads_networks(&self) -> bool {
        self.gather != GatherMode::Paths || self.paths.corrections != usize::MAX
    }

    /// Whether anything reads the shading network's base: the base gather, or strengths taken
    /// from the base; always when [`SolveConfig::skip_unused_base`] is off.
    pub fn needs_base(&self) -> bool {
        !self.skip_unused_base
            || self.gather == GatherMode::Base
            || self.strength_from == StrengthFrom::Base
    }

    /// Checks every setting; the error names the first one out of range.
    pub fn validate(&self) -> Result<(), ConfigError> {
        self.validate_budgets()?;
        self.validate_projection()?;
        self.validate_gather()?;
        self.validate_surfaces()
    }

    /// The budgets: network sizes, time, samples, the insertion and FEM periods.
    fn validate_budgets(&self) -> Result<(), ConfigError> {
        let bad = |m: String| Err(ConfigError::Invalid(m));
        if !(10..=200_000).contains(&self.kernel_cells) {
            return bad(format!(
                "kernel cells {} (expected 10 to 200000)",
                self.kernel_cells
            ));
        }
        if !(3..=100_000).contains(&self.shading_cells) {
            return bad(format!(
                "shading cells {} (expected 3 to 100000)",
                self.shading_cells
            ));
        }
        if let Some(t) = self.time_budget {
            if !(t.is_finite() && t > 0.0) {
                return bad(format!(
                    "time budget {t} s (expected a positive number of seconds)"
                ));
            }
        }
        if !(1..=10_000).contains(&self.samples_per_cell) {
            return bad(format!(
                "samples per cell {} (expected 1 to 10000)",
                self.samples_per_cell
            ));
        }
        if self.fem_every == 0 {
            return bad("FEM period 0 (expected at least 1 insertion)".into());
        }
        if !(10..=100_000).contains(&self.lambda) {
            return bad(format!(
                "insertion period λ = {} (expected 10 to 100000)",
                self.lambda
            ));
        }
        Ok(())
    }

    /// The projected kernel's settings (resampling, rejection, tolerance, clamps).
    fn validate_projection(&self) -> Result<(), ConfigError> {
        let bad = |m: String| Err(ConfigError::Invalid(m));
        if !(0.0..=1.0).contains(&self.resample_critical_fraction) {
            return bad(format!(
                "critical resampling fraction {} (expected 0 to 1)",
                self.resample_critical_fraction
            ));
        }
        if !(self.projection_rejection > 0.0 && self.projection_rejection < 1.0) {
            return bad(format!(
                "projection rejection {} (expected in (0, 1))",
                self.projection_rejection
            ));
        }
        // Looser cut-offs drop enough of the Gram matrix to make the solve unstable: on
        // cornell-box 1e-3 gave B ≈ 1e123 at 400 cells, 1e-4 B ≈ 1e15 at 1400
        // (examples/tolerance_sweep.rs).
        if !(self.projection_tolerance > 0.0 && self.projection_tolerance <= 1e-6) {
            return bad(format!(
                "projection tolerance {} (expected in (0, 1e-6])",
                self.projection_tolerance
            ));
        }
        if !(self.network_clamp_radius > 0.0 && self.network_clamp_radius <= 1.0) {
            return bad(format!(
                "network clamp radius {} (expected in (0, 1], a fraction of the scene's diagonal)",
                self.network_clamp_radius
            ));
        }
        if !(self.projection_min_support >= 0.0 && self.projection_min_support <= 1e6) {
            return bad(format!(
                "projection minimum support {} (expected 0 to 1e6 samples)",
                self.projection_min_support
            ));
        }
        Ok(())
    }

    /// The output gather's rays and target error.
    fn validate_gather(&self) -> Result<(), ConfigError> {
        let bad = |m: String| Err(ConfigError::Invalid(m));
        if self.gather_samples.direct + self.gather_samples.indirect > 1_000_000 {
            return bad("gather samples per point above 1000000".into());
        }
        if let Some(t) = self.paths.target_error {
            if self.gather != GatherMode::Paths {
                return bad(format!(
                    "a target error needs the paths gather (the {} gather estimates no error)",
                    self.gather.name()
                ));
            }
            if !(t > 0.0 && t < 1.0) {
                return bad(format!(
                    "target error {t} (expected a relative error in (0, 1), e.g. 0.02 for 2 %)"
                ));
            }
            if !(1..=1_000_000).contains(&self.paths.max_rays) {
                return bad(format!(
                    "at most {} rays per point (expected 1 to 1000000)",
                    self.paths.max_rays
                ));
            }
        }
        if self.gather == GatherMode::Paths
            && self.gather_samples.direct.max(self.gather_samples.indirect) == 0
        {
            return bad("the paths gather needs at least 1 ray per point".into());
        }
        if self.paths.block_points == 0 {
            return bad("block points 0 (expected at least 1)".into());
        }
        if let Some(shard) = self.paths.shard {
            if shard.index >= shard.count {
                return bad(format!("shard {shard}: the index must be below the count"));
            }
        }
        if self.gather == GatherMode::Rays && self.gather_samples.indirect == 0 {
            // Without cosine rays there is no indirect light, and no direct light either when
            // there are no shadow rays: B would silently be E (or E + direct).
            return bad("the ray gather needs at least 1 cosine ray per point".into());
        }
        Ok(())
    }

    /// The surface clusters and the breaking of the output mesh.
    fn validate_surfaces(&self) -> Result<(), ConfigError> {
        let bad = |m: String| Err(ConfigError::Invalid(m));
        let theta = self.surface_clusters.theta;
        if !(0.0..=4.0).contains(&theta) {
            return bad(format!(
                "surface cluster criterion θ = {theta} (expected 0 to 4; 0 is exact)"
            ));
        }
        if !(self.breaking.max_normal_angle > 0.0
            && self.breaking.max_normal_angle <= std::f64::consts::PI)
        {
            return bad(format!(
                "breaking angle {} rad (expected in (0, π])",
                self.breaking.max_normal_angle
            ));
        }

        Ok(())
    }
}

/// When and how finely a large surface is clustered (`cluster.rs`; docs/design/hierarchical.md).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SurfaceClusters {
    /// Surfaces with at least this many elements are clustered (`usize::MAX`: never).
    pub min_elements: usize,
    /// A node replaces its elements in an integral of exp(−a|x − c|²) when a·R² ≤ θ (R: the
    /// node's radius). The relative error of one node's contribution is O(θ²).
    pub theta: f64,
}

impl Default for SurfaceClusters {
    fn default() -> Self {
        Self {
            min_elements: 4096,
            theta: 0.05,
        }
    }
}

/// Where the base Gaussians Λ_k are integrated (and where they live).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum BaseDomain {
    /// On the scene's own elements S, each Λ_k restricted to the elements that face like its
    /// cell's learned normal (within the breaking angle). Beyond the dissertation: a single
    /// shading sheet cannot follow a closed scene (sec. 4.4.2, fig. 4.18), but the scene is
    /// there to integrate over, exactly.
    #[default]
    Scene,
    /// On the shading network's own triangles Ŝ (the dissertation, sec. 3.2).
    Shading,
}

/// Which sender integral multiplies each kernel cell (`fem.rs`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Transfer {
    /// c_o = ∫_S exp(−|x − w_o^x|²/d_o²) dx, exact on the scene: docs/design/math.md §3.
    #[default]
    Direct,
    /// The dissertation's B̄ (eq. 3.9–3.12): the constant 1 projected onto the base first.
    Projected,
}

/// Sample counts of the gather.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct GatherSamples {
    /// Shadow rays to the emitters per point.
    pub direct: usize,
    /// Cosine-weighted rays for indirect light per point.
    pub indirect: usize,
}

impl Default for GatherSamples {
    fn default() -> Self {
        Self {
            direct: 64,
            indirect: 64,
        }
    }
}

/// Settings of the consistent gather (`GatherMode::Paths`) beyond its ray counts.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PathSettings {
    /// Cosine rays per point whose hit gets the path-traced correction L̂ − C (the first ones of
    /// the gather's `indirect` rays; with a target error, of each round's). Default: all of them (`usize::MAX`), which makes the
    /// networks' C cancel, so that it is not evaluated: on cornell-box every fraction that reads the
    /// networks measured less accurate per second (docs/design/estimator.md).
    pub corrections: usize,
    /// Path vertices (the corrected hit is 1) before Russian roulette starts.
    pub roulette_depth: usize,
    /// Stop when the output's estimated relative error is at most this (`--target-error`,
    /// `--quality`): the gather's `GatherSamples` are then a pilot round, and further rounds add
    /// the rays its standard errors say are missing ([`crate::radiosity_at_points`]). `None`: one
    /// round with the gather's rays.
    pub target_error: Option<f64>,
    /// With a target error, the most shadow and cosine rays (each) per point over all rounds.
    pub max_rays: usize,
    /// With a target error and every ray corrected: at most this many neighbouring output points
    /// share each other's cosine rays and paths (`--share-paths`; 1 = every point alone; the
    /// estimator and the grouping in `estimator/neighbours.rs`).
    pub neighbours: usize,
    /// With a target error: each group's cosine rays, and its paths' bounces, drawn from guides
    /// learned from its earlier rounds (`--guiding`; `estimator/guide.rs`), a defensive mixture
    /// with the cosine density.
    pub guiding: Guiding,
    /// The points run their rounds in blocks (`--block-points`): whole groups in the grouping's
    /// order, a block closed once it holds at least this many points, each block to the target
    /// on its own. A point's value depends only on its block (formed from the whole point set),
    /// which makes shards bit-identical to a single run (`estimator/blocks.rs`). Default
    /// `usize::MAX`: one block, the whole set to the target together.
    pub block_points: usize,
    /// Only the points of this shard are estimated (`--shard`); the others are left at
    /// `Gathered::default()`.
    pub shard: Option<Shard>,
}

impl Default for PathSettings {
    fn default() -> Self {
        Self {
            corrections: usize::MAX,
            roulette_depth: 3,
            target_error: None,
            max_rays: 1 << 16,
            neighbours: 16,
            guiding: Guiding::Auto,
            block_points: usize::MAX,
            shard: None,
        }
    }
}

/// Settings of the breaking operator (sec. 4.4.2, fig. 4.18): the dissertation notes the
/// shading network spans gaps and folds around edges of the geometry, and that "some sort of
/// breaking operator which splits the network into several independent pieces at these edges
/// would be necessary". We drop a triangle when the learned normals at two of its corners
/// disagree by more than `max_normal_angle`, or when one of its edges spans empty space
/// (the caller's `spans_gap` test, e.g. the midpoint is farther than a tolerance from every
/// scene surface).
#[derive(Clone, Copy, Debug)]
pub struct Breaking {
    /// Whether the operator runs at all (off reproduces the dissertation).
    pub enabled: bool,
    /// Largest allowed angle (radians) between corner normals of one triangle.
    pub max_normal_angle: f64,
}

impl Default for Breaking {
    fn default() -> Self {
        Self {
            enabled: true,
            max_normal_angle: 50f64.to_radians(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn defaults_are_valid_and_absurd_values_are_named() {
        SolveConfig::default().validate().unwrap();
        let e = SolveConfig {
            kernel_cells: 0,
            ..Default::default()
        }
        .validate()
        .unwrap_err();
        assert!(e.to_string().contains("kernel cells 0"));
        let e = SolveConfig {
            time_budget: Some(f64::NAN),
            ..Default::default()
        }
        .validate()
        .unwrap_err();
        assert!(e.to_string().contains("time budget"));
        assert_eq!("rays".parse::<GatherMode>().unwrap(), GatherMode::Rays);
        assert!("photons".parse::<GatherMode>().is_err());
    }
}

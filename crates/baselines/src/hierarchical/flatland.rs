//! Flatland hierarchical radiosity with a constant base (Hanrahan, Salzman and Aupperle 1991; thesis sec. 1.3
//! and 4.1).
//!
//! * **Patches.** Every input segment is a root patch; a patch is split into two halves on demand (binary
//!   subdivision), never below [`FlatHrConfig::min_length`].
//! * **Links.** A link carries light from a sender patch `s` to a receiver patch `r`. Its transfer is the
//!   form factor `F_rs = F_u · V̄`: the unoccluded crossed-strings factor `F_u` (docs/design/math.md §7) times a visible
//!   fraction `V̄` estimated with [`FlatHrConfig::visibility_rays`] rays. Initially every ordered pair of root
//!   patches that face each other is linked (the "initial linking" of sec. 1.4); refinement replaces a link by
//!   two links to the halves of one of its patches, so the links always partition the kernel domain.
//! * **Oracle (BF refinement).** A link is refined when `max_band ρ_r · F · B_s > ε` (the energy it transfers
//!   per unit receiver length), where for a partially visible link (some rays blocked, some not) the
//!   unoccluded `F_u` is used instead of `F_u·V̄`: the transfer is uncertain by up to the whole unoccluded
//!   amount there, so partial visibility is a reason to refine (the "coherence" estimate of sec. 4.1). The
//!   larger of the two patches is split; a patch shorter than `2 · min_length` is not split.
//! * **Solution.** Jacobi iteration of eq. 1.17 over the link hierarchy: every link gathers
//!   `ρ_r · F_rs · B_s` into its receiver, then push-pull moves gathered radiosity down to the leaves
//!   (a child inherits everything its ancestors gathered) and averages it back up by length. Refinement
//!   passes (with the current B) and solutions alternate until a pass refines nothing.
//!
//! Units: B is radiosity (exitance), as in [`scene_sampler`]; a patch reports the average over its length.

use super::error::{HrError, Result};
use super::strings::{Piece, form_factor, visibility};
use glam::DVec2;
use scene_sampler::{FlatPoint, FlatVisibility, FlatlandScene, Spectrum};

/// Parameters of a Flatland hierarchical radiosity run.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FlatHrConfig {
    /// BF refinement threshold ε (radiosity units): links with `ρ·F·B ≤ ε` are kept.
    pub epsilon: f64,
    /// Minimum patch length (world units): patches shorter than twice this are not subdivided.
    pub min_length: f64,
    /// Rays per link for the visible fraction (the thesis quotes 10 to 200 per link).
    pub visibility_rays: usize,
    /// Safety limit on the number of links; exceeding it is an error ([`HrError::LinkLimit`]).
    pub max_links: usize,
    /// Maximum number of refine-then-solve passes.
    pub max_passes: usize,
    /// Convergence threshold of the Jacobi solution: largest change of any patch's B over the largest B.
    pub tolerance: f64,
    /// Maximum Jacobi iterations per solution.
    pub max_iterations: usize,
    /// Seed of the visibility rays (results are deterministic per seed).
    pub seed: u64,
    /// How partial visibility enters the oracle ([`PartialVisibility`]).
    pub partial: PartialVisibility,
}

/// How the oracle treats a partially visible link (some of its rays blocked, some not).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum PartialVisibility {
    /// Judge it by the unoccluded transfer `ρ_r · F_u · B_s` (an upper bound of what the visibility estimate
    /// can get wrong) instead of `ρ_r · F_u · V̄ · B_s`.
    #[default]
    UnoccludedBound,
    /// Always refine it (down to the minimum patch length), whatever ε says.
    Refine,
}

impl Default for FlatHrConfig {
    fn default() -> Self {
        FlatHrConfig {
            epsilon: 1e-2,
            min_length: 1e-3,
            visibility_rays: 32,
            max_links: 200_000,
            max_passes: 16,
            tolerance: 1e-10,
            max_iterations: 10_000,
            seed: 1,
            partial: PartialVisibility::UnoccludedBound,
        }
    }
}

impl FlatHrConfig {
    /// Checks every field; the first bad one is reported.
    pub fn validate(&self) -> Result<()> {
        let bad = |name, value: f64, reason| {
            Err(HrError::InvalidParameter {
                name,
                value,
                reason,
            })
        };
        if !(self.epsilon.is_finite() && self.epsilon >= 0.0) {
            return bad("epsilon", self.epsilon, "must be finite and ≥ 0");
        }
        if !(self.min_length.is_finite() && self.min_length > 0.0) {
            return bad("min_length", self.min_length, "must be finite and > 0");
        }
        if self.visibility_rays == 0 {
            return bad("visibility_rays", 0.0, "must be ≥ 1");
        }
        if self.max_links == 0 {
            return bad("max_links", 0.0, "must be ≥ 1");
        }
        if self.max_passes == 0 {
            return bad("max_passes", 0.0, "must be ≥ 1");
        }
        if !(self.tolerance.is_finite() && self.tolerance > 0.0) {
            return bad("tolerance", self.tolerance, "must be finite and > 0");
        }
        if self.max_iterations == 0 {
            return bad("max_iterations", 0.0, "must be ≥ 1");
        }
        Ok(())
    }
}

/// A node of a segment's binary patch tree.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Patch {
    /// The input segment it lies on.
    pub segment: u32,
    /// Start, as a fraction of the segment (from its `a` end).
    pub t0: f64,
    /// End, as a fraction of the segment.
    pub t1: f64,
    /// Length.
    pub length: f64,
    /// Parent patch (None for a root = a whole input segment).
    pub parent: Option<u32>,
    /// The two halves, once subdivided.
    pub children: Option<[u32; 2]>,
    /// Current radiosity B (average over the patch, emission included).
    pub radiosity: Spectrum,
    /// Reflected radiosity gathered by this patch's own links in the last iteration (before push-pull).
    pub gathered: Spectrum,
}

/// A link: light from `sender` arriving at `receiver`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Link {
    /// Receiving patch.
    pub receiver: u32,
    /// Sending patch.
    pub sender: u32,
    /// Unoccluded form factor `F_u` from receiver to sender (crossed strings, docs/design/math.md §7).
    pub unoccluded: f64,
    /// Estimated G-weighted visible fraction `V̄`.
    pub visibility: f64,
    /// True if the visibility rays disagreed.
    pub partial: bool,
}

impl Link {
    /// The occluded form factor `F_rs = F_u · V̄`: the fraction of the energy leaving the receiver's area that
    /// reaches the sender, which by reciprocity weights the sender's radiosity in the receiver's gather.
    pub fn form_factor(&self) -> f64 {
        self.unoccluded * self.visibility
    }
}

/// Counters of a run.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct FlatHrStats {
    /// Refine-then-solve passes made.
    pub passes: usize,
    /// Jacobi iterations, summed over passes.
    pub iterations: usize,
    /// Visibility rays traced.
    pub rays: usize,
    /// True if the last pass refined nothing (the hierarchy converged for this ε).
    pub converged: bool,
}

/// A Flatland hierarchical radiosity solution: the patch trees, the links and the radiosity.
#[derive(Clone, Debug)]
pub struct FlatHr {
    scene: FlatlandScene,
    vis: FlatVisibility,
    config: FlatHrConfig,
    patches: Vec<Patch>,
    links: Vec<Link>,
    stats: FlatHrStats,
}

impl FlatHr {
    /// Sets up the root patches (one per segment, B = E) and the initial links between every ordered pair of
    /// segments that face each other, without refining or solving.
    pub fn new(scene: &FlatlandScene, config: FlatHrConfig) -> Result<FlatHr> {
        config.validate()?;
        let patches = scene
            .segments
            .iter()
            .enumerate()
            .map(|(i, s)| Patch {
                segment: i as u32,
                t0: 0.0,
                t1: 1.0,
                length: s.length,
                parent: None,
                children: None,
                radiosity: s.emission,
                gathered: Spectrum::ZERO,
            })
            .collect();
        let mut hr = FlatHr {
            scene: scene.clone(),
            vis: FlatVisibility::new(scene),
            config,
            patches,
            links: Vec::new(),
            stats: FlatHrStats::default(),
        };
        let n = scene.segments.len() as u32;
        for r in 0..n {
            for s in 0..n {
                if r != s {
                    if let Some(l) = hr.make_link(r, s) {
                        hr.links.push(l);
                    }
                }
            }
        }
        Ok(hr)
    }

    /// Runs hierarchical radiosity to convergence: alternately refine every link with the oracle (using the
    /// current B) and solve, until a pass refines nothing or [`FlatHrConfig::max_passes`] is reached.
    pub fn solve(scene: &FlatlandScene, config: FlatHrConfig) -> Result<FlatHr> {
        let mut hr = FlatHr::new(scene, config)?;
        hr.run()?;
        Ok(hr)
    }

    /// The refine/solve loop of [`FlatHr::solve`] on an already set-up hierarchy.
    pub fn run(&mut self) -> Result<()> {
        self.gather_solve();
        for _ in 0..self.config.max_passes {
            self.stats.passes += 1;
            let changed = self.refine_pass()?;
            if !changed {
                self.stats.converged = true;
                break;
            }
            self.gather_solve();
        }
        Ok(())
    }

    /// The scene.
    pub fn scene(&self) -> &FlatlandScene {
        &self.scene
    }
    /// The configuration used.
    pub fn config(&self) -> &FlatHrConfig {
        &self.config
    }
    /// All patches (roots first, one per segment, in segment order; then subdivisions in creation order).
    pub fn patches(&self) -> &[Patch] {
        &self.patches
    }
    /// All links.
    pub fn links(&self) -> &[Link] {
        &self.links
    }
    /// Number of links (the budget measure of sec. 4.1).
    pub fn link_count(&self) -> usize {
        self.links.len()
    }
    /// Counters of the run.
    pub fn stats(&self) -> FlatHrStats {
        self.stats
    }
    /// The leaves (the finest patches), in patch order.
    pub fn leaves(&self) -> impl Iterator<Item = &Patch> {
        self.patches.iter().filter(|p| p.children.is_none())
    }

    /// The leaf of segment `segment` containing fraction `t ∈ [0,1]` along it.
    pub fn leaf_at(&self, segment: u32, t: f64) -> Result<&Patch> {
        if segment as usize >= self.scene.segments.len() {
            return Err(HrError::NotOnSurface {
                segment,
                reason: format!("the scene has {} segments", self.scene.segments.len()),
            });
        }
        if !(0.0..=1.0).contains(&t) {
            return Err(HrError::NotOnSurface {
                segment,
                reason: format!("fraction {t} is outside [0, 1]"),
            });
        }
        let mut p = segment as usize;
        while let Some([c0, c1]) = self.patches[p].children {
            p = if t < self.patches[c0 as usize].t1 {
                c0 as usize
            } else {
                c1 as usize
            };
        }
        Ok(&self.patches[p])
    }

    /// Radiosity at a surface point (e.g. a snapped probe, [`FlatlandScene::snap_probes`]): the B of the leaf
    /// containing the point's projection onto its segment.
    pub fn radiosity_at(&self, point: &FlatPoint) -> Result<Spectrum> {
        let Some(seg) = self.scene.segments.get(point.segment as usize) else {
            return Err(HrError::NotOnSurface {
                segment: point.segment,
                reason: format!("the scene has {} segments", self.scene.segments.len()),
            });
        };
        let dist = (seg.point(seg.closest_t(point.point)) - point.point).length();
        if dist.is_nan() || dist > 1e-6 * self.scene.diagonal() {
            return Err(HrError::NotOnSurface {
                segment: point.segment,
                reason: format!("the point is {dist:e} away from it"),
            });
        }
        Ok(self
            .leaf_at(point.segment, seg.closest_t(point.point))?
            .radiosity)
    }

    /// The geometric piece of a patch.
    pub fn piece(&self, patch: u32) -> Piece {
        let p = &self.patches[patch as usize];
        let s = &self.scene.segments[p.segment as usize];
        Piece::new(s.point(p.t0), s.point(p.t1), p.segment)
    }

    /// A link from `sender` to `receiver` with its form factor and visibility, or `None` if they do not
    /// face each other.
    fn make_link(&mut self, receiver: u32, sender: u32) -> Option<Link> {
        let (pr, ps) = (self.piece(receiver), self.piece(sender));
        let fu = form_factor(&pr, &ps);
        if fu <= 0.0 {
            return None;
        }
        let seed = self
            .config
            .seed
            .wrapping_mul(0x9E37_79B9_7F4A_7C15)
            .wrapping_add(((receiver as u64) << 32) | sender as u64);
        let v = visibility(&self.vis, &pr, &ps, self.config.visibility_rays, seed);
        self.stats.rays += self.config.visibility_rays;
        if v.fraction <= 0.0 {
            return None;
        }
        Some(Link {
            receiver,
            sender,
            unoccluded: fu,
            visibility: v.fraction,
            partial: v.partial,
        })
    }

    /// The oracle's estimate of the error a link commits: `max_band ρ_r · F · B_s` with `F = F_u` for a
    /// partially visible link and `F_u·V̄` otherwise (module docs).
    ///
    /// With [`PartialVisibility::Refine`] a partially visible link reports `+∞`.
    pub fn oracle(&self, link: &Link) -> f64 {
        if link.partial && self.config.partial == PartialVisibility::Refine {
            return f64::INFINITY;
        }
        let rho = self.scene.segments[self.patches[link.receiver as usize].segment as usize].rho;
        let b = self.patches[link.sender as usize].radiosity;
        let f = if link.partial {
            link.unoccluded
        } else {
            link.form_factor()
        };
        (0..3).map(|k| rho.0[k] * f * b.0[k]).fold(0.0, f64::max)
    }

    /// Splits a patch into halves (once; later calls return the existing halves). Halves start with the
    /// parent's radiosity.
    fn subdivide(&mut self, p: u32) -> [u32; 2] {
        if let Some(c) = self.patches[p as usize].children {
            return c;
        }
        let par = self.patches[p as usize];
        let tm = 0.5 * (par.t0 + par.t1);
        let first = self.patches.len() as u32;
        for (t0, t1) in [(par.t0, tm), (tm, par.t1)] {
            self.patches.push(Patch {
                segment: par.segment,
                t0,
                t1,
                length: 0.5 * par.length,
                parent: Some(p),
                children: None,
                radiosity: par.radiosity,
                gathered: Spectrum::ZERO,
            });
        }
        self.patches[p as usize].children = Some([first, first + 1]);
        [first, first + 1]
    }

    /// One refinement pass over all links; true if any link was refined.
    fn refine_pass(&mut self) -> Result<bool> {
        let old = std::mem::take(&mut self.links);
        let mut out = Vec::with_capacity(old.len());
        let mut changed = false;
        for l in old {
            changed |= self.refine_link(l, &mut out)?;
        }
        self.links = out;
        Ok(changed)
    }

    /// Refines one link recursively into `out`; true if it was split.
    fn refine_link(&mut self, l: Link, out: &mut Vec<Link>) -> Result<bool> {
        if out.len() >= self.config.max_links {
            return Err(HrError::LinkLimit {
                limit: self.config.max_links,
                epsilon: self.config.epsilon,
            });
        }
        if self.oracle(&l) <= self.config.epsilon {
            out.push(l);
            return Ok(false);
        }
        let lr = self.patches[l.receiver as usize].length;
        let ls = self.patches[l.sender as usize].length;
        let can = |len: f64| 0.5 * len >= self.config.min_length;
        let split_sender = match (can(lr), can(ls)) {
            (false, false) => {
                out.push(l);
                return Ok(false);
            }
            (true, false) => false,
            (false, true) => true,
            (true, true) => ls > lr,
        };
        if split_sender {
            for c in self.subdivide(l.sender) {
                if let Some(nl) = self.make_link(l.receiver, c) {
                    self.refine_link(nl, out)?;
                }
            }
        } else {
            for c in self.subdivide(l.receiver) {
                if let Some(nl) = self.make_link(c, l.sender) {
                    self.refine_link(nl, out)?;
                }
            }
        }
        Ok(true)
    }

    /// Jacobi iteration (eq. 1.17) with gather over links and push-pull, until the largest change of any
    /// patch's B is below `tolerance` times the largest B, or `max_iterations`.
    fn gather_solve(&mut self) {
        let roots = self.scene.segments.len();
        let mut old: Vec<Spectrum> = Vec::with_capacity(self.patches.len());
        for _ in 0..self.config.max_iterations {
            self.stats.iterations += 1;
            for p in &mut self.patches {
                p.gathered = Spectrum::ZERO;
            }
            for l in &self.links {
                let r = &self.patches[l.receiver as usize];
                let rho = self.scene.segments[r.segment as usize].rho;
                let add = rho * self.patches[l.sender as usize].radiosity * l.form_factor();
                self.patches[l.receiver as usize].gathered += add;
            }
            old.clear();
            old.extend(self.patches.iter().map(|p| p.radiosity));
            for r in 0..roots {
                self.push_pull(r as u32, Spectrum::ZERO);
            }
            let mut change: f64 = 0.0;
            let mut top: f64 = 0.0;
            for (p, o) in self.patches.iter().zip(&old) {
                change = change.max((p.radiosity - *o).map(f64::abs).max());
                top = top.max(p.radiosity.max());
            }
            if change <= self.config.tolerance * top {
                break;
            }
        }
    }

    /// Push-pull (HSA 1991): `down` is the radiosity gathered by the ancestors; returns the patch's new B.
    fn push_pull(&mut self, p: u32, down: Spectrum) -> Spectrum {
        let patch = self.patches[p as usize];
        let g = down + patch.gathered;
        let b = match patch.children {
            None => self.scene.segments[patch.segment as usize].emission + g,
            Some([c0, c1]) => {
                let (l0, l1) = (
                    self.patches[c0 as usize].length,
                    self.patches[c1 as usize].length,
                );
                let b0 = self.push_pull(c0, g);
                let b1 = self.push_pull(c1, g);
                (b0 * l0 + b1 * l1) / (l0 + l1)
            }
        };
        self.patches[p as usize].radiosity = b;
        b
    }

    /// The midpoint of a patch in the plane (convenience for plots).
    pub fn leaf_midpoint(&self, patch: &Patch) -> DVec2 {
        self.scene.segments[patch.segment as usize].point(0.5 * (patch.t0 + patch.t1))
    }
}

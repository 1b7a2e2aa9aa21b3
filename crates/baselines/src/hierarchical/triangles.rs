//! 3-D hierarchical radiosity on triangles with a constant base (Hanrahan, Salzman and Aupperle 1991; thesis
//! sec. 1.3), the 3-D counterpart of [`super::flatland`].
//!
//! * **Patches.** Every scene triangle is a root patch; a patch is split at its edge midpoints into four
//!   similar triangles (the triangle analogue of HSA's quadtree), never below [`TriHrConfig::min_area`].
//! * **Links.** A link carries light from a sender patch `s` to a receiver patch `r` with the form factor
//!   `F_rs = F_u · V̄`. `F_u = (1/A_r) ∫_r F(x → s) dx` (eq. 1.5 with a constant base) is the point-to-polygon
//!   factor averaged over the part of the receiver in front of the sender by a degree-2 rule
//!   ([`super::polygon::triangle_to_polygon`]) — where HSA used one point, which misses links whenever that
//!   point is behind the sender's plane but part of the receiver is not. `V̄` is the `G`-weighted visible
//!   fraction `Σ G V / Σ G`, `G = cos θx cos θy / r²`, of [`TriHrConfig::visibility_rays`] rays between random
//!   point pairs of the two patches (pairs whose cosines are not both positive are not counted), traced with
//!   [`scene_sampler::SceneBvh`]; the unweighted fraction of HSA underestimates the transfer of patches
//!   meeting at an edge, where the near, always visible pairs carry most of it. Initially every ordered pair of facing root triangles is linked; refinement
//!   replaces a link by the four links to the quarters of its larger patch, so the links always partition
//!   the kernel domain.
//! * **Oracle (BF refinement)** as in Flatland: refine when `max_band ρ_r · F · B_s > ε`, with the
//!   unoccluded `F_u` for a partially visible link ([`PartialVisibility`]).
//! * **Solution.** Jacobi iteration of eq. 1.17 over the links with push-pull (children inherit what their
//!   ancestors gathered, parents are area-weighted means), alternating with refinement passes until a pass
//!   refines nothing.
//!
//! Units: B is radiosity (exitance), as in [`scene_sampler`]; a patch reports the average over its area. The
//! initial linking is `O(n²)` in the number of scene triangles: this is a reference for small scenes.

use super::error::{HrError, Result};
use super::flatland::PartialVisibility;
use super::polygon::{point_to_polygon, triangle_point, triangle_to_polygon};
use glam::DVec3;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use scene_sampler::sample::barycentric;
use scene_sampler::{Scene, SceneBvh, Spectrum, SurfacePoint};

/// Parameters of a 3-D hierarchical radiosity run.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TriHrConfig {
    /// BF refinement threshold ε (radiosity units): links with `ρ·F·B ≤ ε` are kept.
    pub epsilon: f64,
    /// Minimum patch area (world units²): a patch is split only if its quarters are at least this large.
    pub min_area: f64,
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
    /// How partial visibility enters the oracle.
    pub partial: PartialVisibility,
}

impl Default for TriHrConfig {
    fn default() -> Self {
        TriHrConfig {
            epsilon: 1e-1,
            min_area: 1e-4,
            visibility_rays: 16,
            max_links: 2_000_000,
            max_passes: 16,
            tolerance: 1e-8,
            max_iterations: 10_000,
            seed: 1,
            partial: PartialVisibility::UnoccludedBound,
        }
    }
}

impl TriHrConfig {
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
        if !(self.min_area.is_finite() && self.min_area > 0.0) {
            return bad("min_area", self.min_area, "must be finite and > 0");
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

/// A node of a triangle's patch tree.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TriPatch {
    /// The scene face it lies on.
    pub face: u32,
    /// Vertices, wound like the face.
    pub v: [DVec3; 3],
    /// Area.
    pub area: f64,
    /// Parent patch (None for a root = a whole scene triangle).
    pub parent: Option<u32>,
    /// The four quarters once subdivided: corners at `v0`, `v1`, `v2`, then the middle one.
    pub children: Option<[u32; 4]>,
    /// Current radiosity B (average over the patch, emission included).
    pub radiosity: Spectrum,
    /// Reflected radiosity gathered by this patch's own links in the last iteration (before push-pull).
    pub gathered: Spectrum,
}

/// A link: light from `sender` arriving at `receiver`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TriLink {
    /// Receiving patch.
    pub receiver: u32,
    /// Sending patch.
    pub sender: u32,
    /// Unoccluded form factor `F_u` from receiver to sender (point-to-polygon, averaged over the receiver).
    pub unoccluded: f64,
    /// Estimated visible fraction `V̄`.
    pub visibility: f64,
    /// True if the visibility rays disagreed (or none could be cast).
    pub partial: bool,
}

impl TriLink {
    /// The occluded form factor `F_rs = F_u · V̄`, the weight of the sender's radiosity in the receiver's
    /// gather.
    pub fn form_factor(&self) -> f64 {
        self.unoccluded * self.visibility
    }
}

/// Counters of a run.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct TriHrStats {
    /// Refine-then-solve passes made.
    pub passes: usize,
    /// Jacobi iterations, summed over passes.
    pub iterations: usize,
    /// Visibility rays traced.
    pub rays: usize,
    /// True if the last pass refined nothing (the hierarchy converged for this ε).
    pub converged: bool,
}

/// A 3-D hierarchical radiosity solution: the patch trees, the links and the radiosity.
pub struct TriHr {
    scene: Scene,
    bvh: SceneBvh,
    config: TriHrConfig,
    patches: Vec<TriPatch>,
    links: Vec<TriLink>,
    stats: TriHrStats,
}

impl std::fmt::Debug for TriHr {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("TriHr")
            .field("scene", &self.scene.name)
            .field("config", &self.config)
            .field("patches", &self.patches.len())
            .field("links", &self.links.len())
            .field("stats", &self.stats)
            .finish()
    }
}

impl TriHr {
    /// Sets up the root patches (one per triangle, B = E) and the initial links between every ordered pair of
    /// triangles that face each other, without refining or solving.
    pub fn new(scene: &Scene, config: TriHrConfig) -> Result<TriHr> {
        config.validate()?;
        let patches = scene
            .faces
            .iter()
            .enumerate()
            .map(|(i, f)| TriPatch {
                face: i as u32,
                v: f.v,
                area: f.area,
                parent: None,
                children: None,
                radiosity: f.emission,
                gathered: Spectrum::ZERO,
            })
            .collect();
        let mut hr = TriHr {
            scene: scene.clone(),
            bvh: SceneBvh::new(scene),
            config,
            patches,
            links: Vec::new(),
            stats: TriHrStats::default(),
        };
        let n = scene.faces.len() as u32;
        for r in 0..n {
            for s in 0..n {
                if r != s {
                    if let Some(l) = hr.make_link(r, s) {
                        if hr.links.len() >= config.max_links {
                            return Err(HrError::LinkLimit {
                                limit: config.max_links,
                                epsilon: config.epsilon,
                            });
                        }
                        hr.links.push(l);
                    }
                }
            }
        }
        Ok(hr)
    }

    /// Runs hierarchical radiosity to convergence: alternately refine every link with the oracle (using the
    /// current B) and solve, until a pass refines nothing or [`TriHrConfig::max_passes`] is reached.
    pub fn solve(scene: &Scene, config: TriHrConfig) -> Result<TriHr> {
        let mut hr = TriHr::new(scene, config)?;
        hr.run()?;
        Ok(hr)
    }

    /// The refine/solve loop of [`TriHr::solve`] on an already set-up hierarchy.
    pub fn run(&mut self) -> Result<()> {
        self.gather_solve();
        for _ in 0..self.config.max_passes {
            self.stats.passes += 1;
            if !self.refine_pass()? {
                self.stats.converged = true;
                break;
            }
            self.gather_solve();
        }
        Ok(())
    }

    /// The scene.
    pub fn scene(&self) -> &Scene {
        &self.scene
    }
    /// The configuration used.
    pub fn config(&self) -> &TriHrConfig {
        &self.config
    }
    /// All patches (roots first, one per scene face, in face order; then subdivisions in creation order).
    pub fn patches(&self) -> &[TriPatch] {
        &self.patches
    }
    /// All links.
    pub fn links(&self) -> &[TriLink] {
        &self.links
    }
    /// Number of links (the budget measure of sec. 4.1).
    pub fn link_count(&self) -> usize {
        self.links.len()
    }
    /// Counters of the run.
    pub fn stats(&self) -> TriHrStats {
        self.stats
    }
    /// The leaves (the finest patches), in patch order.
    pub fn leaves(&self) -> impl Iterator<Item = &TriPatch> {
        self.patches.iter().filter(|p| p.children.is_none())
    }

    /// The leaf of face `face` containing `point` (projected onto the face's plane; points outside the
    /// triangle go to the nearest quarter at each level).
    pub fn leaf_at(&self, face: u32, point: DVec3) -> Result<&TriPatch> {
        if face as usize >= self.scene.faces.len() {
            return Err(HrError::NotOnSurface {
                segment: face,
                reason: format!("the scene has {} triangles", self.scene.faces.len()),
            });
        }
        if !point.is_finite() {
            return Err(HrError::NotOnSurface {
                segment: face,
                reason: format!("the point {point} is not finite"),
            });
        }
        let mut p = face as usize;
        while let Some(c) = self.patches[p].children {
            let (b1, b2) = barycentric(self.patches[p].v, point);
            let b0 = 1.0 - b1 - b2;
            p = c[if b0 >= 0.5 {
                0
            } else if b1 >= 0.5 {
                1
            } else if b2 >= 0.5 {
                2
            } else {
                3
            }] as usize;
        }
        Ok(&self.patches[p])
    }

    /// Radiosity at a surface point (e.g. a snapped probe, [`Scene::snap_probes`]): the B of the leaf
    /// containing it. Error if the point is farther than `10⁻⁶ · diagonal` from its face.
    pub fn radiosity_at(&self, point: &SurfacePoint) -> Result<Spectrum> {
        let Some(f) = self.scene.faces.get(point.face as usize) else {
            return Err(HrError::NotOnSurface {
                segment: point.face,
                reason: format!("the scene has {} triangles", self.scene.faces.len()),
            });
        };
        let dist = (f.closest_point(point.point) - point.point).length();
        if dist.is_nan() || dist > 1e-6 * self.scene.diagonal() {
            return Err(HrError::NotOnSurface {
                segment: point.face,
                reason: format!("the point is {dist:e} away from it"),
            });
        }
        Ok(self.leaf_at(point.face, point.point)?.radiosity)
    }

    /// Final gather at a surface point: `B(x) = E(x) + ρ(x) Σ_leaves F(x → leaf) · V̄ · B_leaf` with the exact
    /// point-to-polygon factor and a `G`-weighted visible fraction from `rays` rays to random points of each
    /// leaf (deterministic per `seed`). Removes the constant-leaf error at `x` (the classical "final gather");
    /// costs one pass over all leaves per point.
    pub fn gather_at(&self, point: &SurfacePoint, rays: usize, seed: u64) -> Result<Spectrum> {
        // validates the point
        self.radiosity_at(point)?;
        if rays == 0 {
            return Err(HrError::InvalidParameter {
                name: "rays",
                value: 0.0,
                reason: "must be ≥ 1",
            });
        }
        let f = &self.scene.faces[point.face as usize];
        let (x, nx) = (point.point, f.normal);
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let mut sum = Spectrum::ZERO;
        for leaf in self.leaves() {
            if leaf.face == point.face {
                continue;
            }
            let ns = self.scene.faces[leaf.face as usize].normal;
            let fu = point_to_polygon(x, nx, &leaf.v, ns);
            if fu <= 0.0 {
                continue;
            }
            let (mut w_all, mut w_vis) = (0.0, 0.0);
            for _ in 0..rays {
                let y = triangle_point(&leaf.v, [rng.random(), rng.random()]);
                let d = y - x;
                let r2 = d.length_squared();
                let (cx, cy) = (nx.dot(d), -ns.dot(d));
                if cx <= 0.0 || cy <= 0.0 || r2 <= 0.0 {
                    continue;
                }
                let w = cx * cy / (r2 * r2);
                w_all += w;
                let py = SurfacePoint {
                    point: y,
                    normal: ns,
                    face: leaf.face,
                };
                let px = SurfacePoint {
                    point: x,
                    normal: nx,
                    face: point.face,
                };
                if self.bvh.visible(&px, &py) {
                    w_vis += w;
                }
            }
            let v = if w_all > 0.0 { w_vis / w_all } else { 1.0 };
            sum += leaf.radiosity * (fu * v);
        }
        Ok(f.emission + f.rho * sum)
    }

    /// A link from `sender` to `receiver` with its form factor and visibility, or `None` if no part of the
    /// receiver sees the front of the sender, or every ray was blocked.
    fn make_link(&mut self, receiver: u32, sender: u32) -> Option<TriLink> {
        let (r, s) = (
            &self.patches[receiver as usize],
            &self.patches[sender as usize],
        );
        if r.face == s.face {
            return None;
        }
        let (nr, ns) = (
            self.scene.faces[r.face as usize].normal,
            self.scene.faces[s.face as usize].normal,
        );
        let fu = triangle_to_polygon(&r.v, nr, &s.v, ns);
        if fu <= 0.0 {
            return None;
        }
        let seed = self
            .config
            .seed
            .wrapping_mul(0x9E37_79B9_7F4A_7C15)
            .wrapping_add(((receiver as u64) << 32) | sender as u64);
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let (mut counted, mut blocked) = (0usize, 0usize);
        let (mut w_all, mut w_vis) = (0.0, 0.0);
        for _ in 0..self.config.visibility_rays {
            let x = triangle_point(&r.v, [rng.random(), rng.random()]);
            let y = triangle_point(&s.v, [rng.random(), rng.random()]);
            let d = y - x;
            let r2 = d.length_squared();
            let (cx, cy) = (nr.dot(d), -ns.dot(d));
            if cx <= 0.0 || cy <= 0.0 || r2 <= 0.0 {
                continue;
            }
            counted += 1;
            let w = cx * cy / (r2 * r2);
            w_all += w;
            let (px, py) = (
                SurfacePoint {
                    point: x,
                    normal: nr,
                    face: r.face,
                },
                SurfacePoint {
                    point: y,
                    normal: ns,
                    face: s.face,
                },
            );
            if self.bvh.visible(&px, &py) {
                w_vis += w;
            } else {
                blocked += 1;
            }
        }
        self.stats.rays += counted;
        let (v, partial) = if counted == 0 || w_all <= 0.0 {
            // the facing parts are too small to hit with these rays: unknown, so refine if it matters
            (1.0, true)
        } else {
            (w_vis / w_all, blocked > 0 && blocked < counted)
        };
        if v <= 0.0 {
            return None;
        }
        Some(TriLink {
            receiver,
            sender,
            unoccluded: fu,
            visibility: v,
            partial,
        })
    }

    /// The oracle's estimate of the error a link commits: `max_band ρ_r · F · B_s` with `F = F_u` for a
    /// partially visible link and `F_u·V̄` otherwise; `+∞` for a partially visible link under
    /// [`PartialVisibility::Refine`].
    pub fn oracle(&self, link: &TriLink) -> f64 {
        if link.partial && self.config.partial == PartialVisibility::Refine {
            return f64::INFINITY;
        }
        let rho = self.scene.faces[self.patches[link.receiver as usize].face as usize].rho;
        let b = self.patches[link.sender as usize].radiosity;
        let f = if link.partial {
            link.unoccluded
        } else {
            link.form_factor()
        };
        (0..3).map(|k| rho.0[k] * f * b.0[k]).fold(0.0, f64::max)
    }

    /// Splits a patch into its four quarters (once). Quarters start with the parent's radiosity.
    fn subdivide(&mut self, p: u32) -> [u32; 4] {
        if let Some(c) = self.patches[p as usize].children {
            return c;
        }
        let par = self.patches[p as usize];
        let [a, b, c] = par.v;
        let (ab, bc, ca) = ((a + b) * 0.5, (b + c) * 0.5, (c + a) * 0.5);
        let first = self.patches.len() as u32;
        for v in [[a, ab, ca], [ab, b, bc], [ca, bc, c], [ab, bc, ca]] {
            self.patches.push(TriPatch {
                face: par.face,
                v,
                area: 0.25 * par.area,
                parent: Some(p),
                children: None,
                radiosity: par.radiosity,
                gathered: Spectrum::ZERO,
            });
        }
        self.patches[p as usize].children = Some([first, first + 1, first + 2, first + 3]);
        [first, first + 1, first + 2, first + 3]
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
    fn refine_link(&mut self, l: TriLink, out: &mut Vec<TriLink>) -> Result<bool> {
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
        let ar = self.patches[l.receiver as usize].area;
        let asn = self.patches[l.sender as usize].area;
        let can = |a: f64| 0.25 * a >= self.config.min_area;
        let split_sender = match (can(ar), can(asn)) {
            (false, false) => {
                out.push(l);
                return Ok(false);
            }
            (true, false) => false,
            (false, true) => true,
            (true, true) => asn > ar,
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
        let roots = self.scene.faces.len();
        let mut old: Vec<Spectrum> = Vec::with_capacity(self.patches.len());
        for _ in 0..self.config.max_iterations {
            self.stats.iterations += 1;
            for p in &mut self.patches {
                p.gathered = Spectrum::ZERO;
            }
            for l in &self.links {
                let r = &self.patches[l.receiver as usize];
                let rho = self.scene.faces[r.face as usize].rho;
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
            None => self.scene.faces[patch.face as usize].emission + g,
            Some(c) => {
                let mut sum = Spectrum::ZERO;
                let mut area = 0.0;
                for k in c {
                    let a = self.patches[k as usize].area;
                    sum += self.push_pull(k, g) * a;
                    area += a;
                }
                sum / area
            }
        };
        self.patches[p as usize].radiosity = b;
        b
    }
}

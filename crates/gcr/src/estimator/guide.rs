//! Guided bounces (`--guiding`; issue "The networks earn their place"): the cosine rays of a group
//! of neighbouring points, and of their paths' later bounces, drawn from learned distributions
//! instead of cos θ/π alone (docs/design/estimator.md, "Guiding").
//!
//! The cosine warp ([`scene_sampler::cosine_hemisphere`]) maps the unit square to the hemisphere,
//! (u₀, u₁) ↦ (sin²θ = u₀, φ = 2πu₁), with density cos θ/π: the reflected-light integral
//! ∫ L(ω) cos θ/π dω is ∫_□ L(ω(u)) du over the square. Guiding warps the square first by a
//! piecewise-constant density q on an `RES` × `RES` grid (mean 1), so a ray's solid-angle density
//! is q(u)·cos θ/π and its weight L/q:
//!
//! ```text
//! q(u) = (1 − λ) + λ·RES²·h(bin(u)),   λ = (1 − α)·n/(n + CONFIDENCE),
//! ```
//!
//! h the learned share of ∫ L over each bin from n rays: a defensive mixture (α = [`DEFENSIVE`]):
//! no ray's weight exceeds 1/α of the cosine ray's, so a poor guide costs at most a bounded factor
//! per bounce, and q > 0 wherever cos θ is, so the estimate stays unbiased whatever was learned. q
//! is sampled by inversion (the bin's row from the marginal, its column from the row, the point
//! within the bin linearly), so the Sobol points' stratification carries through the warp.
//!
//! What is learned: each ray adds the luminance of the light it brought divided by its density q
//! to its bin, an unbiased estimate of ∫_bin L du; h is those sums normalized. A group's first
//! bounces learn in a [`Learner`] of their own ([`GroupGuide`]); the paths' later bounces in
//! spatial cells shared by all groups ([`SpatialLearner`], [`SpatialGuides`]), which also learn
//! the mean light that rays brought from each cell (its outgoing radiance, as the paths saw it:
//! what splits a path where it meets more light than it started from, `PathGather::reflected`).
//! A round's guides are fixed before it starts and built from earlier rounds only, so each
//! replicate of the round is unbiased given them and the replicates stay uncorrelated (the
//! standard error remains honest).

use glam::DVec3;
use scene_sampler::orthonormal_basis;

/// Bins per side of the guide's grid on the cosine square (8: 16 measured noisier for the rays a
/// cell sees; the diagnostic in `paths.rs`, `guided_paths_vary_less_at_a_wall…`).
pub(crate) const RES: usize = 8;
/// The cosine density's least share α of the guided density (module docs).
pub(crate) const DEFENSIVE: f64 = 0.3;
/// Rays learned from at which the learned part gets half of its share 1 − α (32 per bin): a guide
/// from a handful of rays is noise, and a confident guide from noise makes the weights of the
/// directions it neglects 1/α at every bounce (with none, fireflies of 20× the brightest point on
/// the door-gap room; with 256 rays, paths from a wall of the sun patch room varied more guided
/// than unguided, 7.9 against 4.45 relative standard deviation; with 2048, 2.6).
const CONFIDENCE: f64 = 2048.0;

/// The square coordinates (sin²θ, φ/2π) of the unit direction `dir` about the unit normal `n`:
/// the inverse of [`scene_sampler::cosine_hemisphere`] (same tangent frame).
#[cfg(test)]
pub(crate) fn to_square(n: DVec3, dir: DVec3) -> [f64; 2] {
    let (t, b) = orthonormal_basis(n);
    let (x, y) = (dir.dot(t), dir.dot(b));
    let s = (x * x + y * y).clamp(0.0, 1.0);
    let phi = y.atan2(x) / std::f64::consts::TAU;
    [
        s,
        if phi < 0.0 { phi + 1.0 } else { phi }.min(1.0 - f64::EPSILON),
    ]
}

fn bin(u: f64) -> usize {
    ((u * RES as f64) as usize).min(RES - 1)
}

/// A piecewise-constant density q on the unit square (module docs), mean 1; inline (one
/// look-up per bounce reads it: no pointers to chase).
#[derive(Clone, Debug)]
pub(crate) struct Guide {
    /// q per bin, row-major: row = bin of u₀, column = bin of u₁.
    density: [f64; RES * RES],
    /// Cumulative row masses (RES + 1 entries, 0 … 1).
    rows: [f64; RES + 1],
    /// Per row, the cumulative masses of its columns (RES + 1 entries each, 0 … 1).
    columns: [f64; RES * (RES + 1)],
}

impl Guide {
    /// The guide from per-bin sums of ∫ L (row-major, RES² entries, non-negative) over `rays`
    /// rays: the learned part's share is (1 − α)·rays/(rays + [`CONFIDENCE`]). `None` when nothing
    /// was learned (every sum 0 or not finite).
    pub(crate) fn from_sums(sums: &[f64], rays: f64) -> Option<Self> {
        let total: f64 = sums.iter().sum();
        if !(total > 0.0 && total.is_finite()) {
            return None;
        }
        let cells = (RES * RES) as f64;
        let learned = (1.0 - DEFENSIVE) * rays / (rays + CONFIDENCE);
        let density: [f64; RES * RES] =
            std::array::from_fn(|b| (1.0 - learned) + learned * cells * sums[b].max(0.0) / total);
        let mut rows = [0.0; RES + 1];
        let mut columns = [0.0; RES * (RES + 1)];
        for r in 0..RES {
            let row = &density[r * RES..(r + 1) * RES];
            let col = &mut columns[r * (RES + 1)..(r + 1) * (RES + 1)];
            for c in 0..RES {
                col[c + 1] = col[c] + row[c];
            }
            let mass = col[RES];
            col.iter_mut().for_each(|v| *v /= mass);
            rows[r + 1] = rows[r] + mass;
        }
        let mass = rows[RES];
        rows.iter_mut().for_each(|v| *v /= mass);
        Some(Self {
            density,
            rows,
            columns,
        })
    }

    /// q at the square point `u`.
    #[cfg(test)]
    pub(crate) fn density(&self, u: [f64; 2]) -> f64 {
        self.density[bin(u[0]) * RES + bin(u[1])]
    }

    /// q toward the direction `d` (not necessarily unit) about the unit normal `n`: `density` at
    /// [`to_square`]`(n, d)`, its bin of φ found by the octant of (x, y) instead of an arctangent
    /// (5 % of a guided run's time, for the next-event rays' MIS weights).
    pub(crate) fn density_toward(&self, n: DVec3, d: DVec3) -> f64 {
        const _: () = assert!(RES == 8, "the bins of φ are the octants");
        let (t, b) = orthonormal_basis(n);
        let (x, y) = (d.dot(t), d.dot(b));
        let s = ((x * x + y * y) / d.length_squared()).clamp(0.0, 1.0);
        // the quadrant of φ = atan2(y, x) in [0, 2π), then (x, y) turned into the first one
        let (quadrant, x, y) = if y >= 0.0 {
            if x > 0.0 { (0, x, y) } else { (1, y, -x) }
        } else if x < 0.0 {
            (2, -x, -y)
        } else {
            (3, -y, x)
        };
        let octant = 2 * quadrant + usize::from(y >= x);
        self.density[bin(s) * RES + octant]
    }

    /// The point of the square that `u` maps to under q's inversion, and q there.
    pub(crate) fn sample(&self, u: [f64; 2]) -> ([f64; 2], f64) {
        let (r, a) = invert(&self.rows, u[0]);
        let (c, b) = invert(&self.columns[r * (RES + 1)..(r + 1) * (RES + 1)], u[1]);
        let to = |i: usize, f: f64| ((i as f64 + f) / RES as f64).min(1.0 - f64::EPSILON);
        ([to(r, a), to(c, b)], self.density[r * RES + c])
    }
}

/// The bin of the cumulative table `cdf` (RES + 1 entries from 0 to 1) holding `u`, and u's
/// fraction within it.
fn invert(cdf: &[f64], u: f64) -> (usize, f64) {
    let i = cdf[1..RES].partition_point(|&c| c <= u);
    let width = cdf[i + 1] - cdf[i];
    let f = if width > 0.0 {
        ((u - cdf[i]) / width).clamp(0.0, 1.0)
    } else {
        0.5
    };
    (i, f)
}

/// What a group has learned so far: per bin, Σ luminance(L)/q of the rays that fell in it (empty
/// until a ray brought light: a group that is never guided holds no bins), and how many rays
/// (those that brought nothing too).
#[derive(Clone, Debug, Default)]
pub(crate) struct Learner {
    sums: Vec<f64>,
    rays: f64,
}

impl Learner {
    /// Records one ray at square point `u`, drawn with density `q`, that brought `value`.
    pub(crate) fn add(&mut self, u: [f64; 2], q: f64, value: f64) {
        self.rays += 1.0;
        if value > 0.0 && value.is_finite() && q > 0.0 {
            if self.sums.is_empty() {
                self.sums = vec![0.0; RES * RES];
            }
            self.sums[bin(u[0]) * RES + bin(u[1])] += value / q;
        }
    }

    /// The guide for the next round (`None` while nothing was found).
    pub(crate) fn guide(&self) -> Option<Guide> {
        if self.sums.is_empty() {
            return None;
        }
        Guide::from_sums(&self.sums, self.rays)
    }
}

/// A group's guiding state across its rounds: the guide of the current round and what the
/// rounds so far have learned. About 80 bytes until the group learns (every group of a
/// `--guiding auto` run has one before the pilot decides); [`GUIDED_GROUP_BYTES`] at most after.
#[derive(Clone, Debug, Default)]
pub(crate) struct GroupGuide {
    /// This round's guide (`None`: cosine rays, as in a pilot round), boxed: 1.2 KB that only a
    /// guided group needs.
    pub(crate) guide: Option<Box<Guide>>,
    /// Every earlier round's rays.
    pub(crate) learner: Learner,
    /// This round's path vertices for the spatial guides (at most [`SpatialGuides::cap`]).
    pub(crate) records: Vec<Record>,
}

/// Path vertices a group records per round for the spatial guides, at most: all groups' records
/// are held until the round ends (16 bytes each), so the groups share [`RECORDS_PER_ROUND`].
/// 32 768: the door gap's work plane (125 groups) met 2 % in 0.91× the time it took with 8 192
/// on the mean of seeds 1–3 (15.8 / 17.5 / 19.4 s against 19.8 / 20.0 / 18.5 s): the guides of
/// a round learn from the records of the rounds before it, and the early rounds are where they
/// are poor. The merge of the records is a pass over a dense array ([`CELL_COUNT`]); with a
/// hash map it cost more than the extra records gained.
const RECORDS_PER_GROUP: usize = 32_768;
/// Path vertices all groups record per round, at most (128 MB): a group records at most its
/// share of them (at least one), so that 50 000 lone probes do not hold 256 each (205 MB, as they
/// did).
const RECORDS_PER_ROUND: usize = 1 << 23;

/// Bytes one record takes.
const RECORD_BYTES: usize = std::mem::size_of::<Record>();

/// Bytes a guided group's [`GroupGuide`] takes at most besides its records: its boxed guide
/// (1 160), its learner's bins (512) and the struct, with room for the allocator.
const GUIDED_GROUP_BYTES: usize = 1_900;

/// Bytes the spatial guides take at most besides the records: per cell of the grid its learned
/// sums and its guide ([`CELL_COUNT`] × (536 + 1 160)), and the dense index of the cells.
const SPATIAL_BYTES: usize = CELL_COUNT * (536 + 1_160 + 16);

/// Bytes guiding adds at most to a gather of `groups` groups: their guides
/// ([`GUIDED_GROUP_BYTES`]), the records of a round ([`RECORDS_PER_ROUND`]) and the spatial
/// guides. 50 000 lone probes on the door gap: 231 MB measured over the unguided run's peak,
/// 279 MB by this.
pub(crate) fn guiding_bytes(groups: usize) -> u64 {
    (groups as u64)
        .saturating_mul(GUIDED_GROUP_BYTES as u64)
        .saturating_add((RECORDS_PER_ROUND * RECORD_BYTES + SPATIAL_BYTES) as u64)
}
/// Spatial cells per diagonal of the scene (16; 32 left too few rays per cell).
const CELLS: f64 = 16.0;

/// One bounce of a path for the spatial guides: its cell and the bin of its square point, the
/// light it brought divided by its density (an unbiased estimate of ∫_bin L du), the cell of its
/// hit and the light it brought (for the cells' mean light, [`Cell::light`]). 16 bytes.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Record {
    /// The cell ([`cell_index`], below 2¹⁶) and, from bit 16, the bin.
    key_bin: u32,
    value: f32,
    light: f32,
    hit: u16,
}

impl Record {
    /// The cell of the bounce's vertex.
    fn cell(&self) -> u32 {
        self.key_bin & 0xffff
    }

    /// The bin of the bounce's square point.
    fn bin(&self) -> usize {
        (self.key_bin >> 16) as usize
    }
}

/// Cells per axis of the grid: [`CELLS`] per diagonal of the scene's frame cover at most
/// `CELLS + 1` along any axis.
const AXIS: usize = CELLS as usize + 1;
/// Cells in all: the grid times the six dominant directions of a normal (29 478; a dense index,
/// 118 KB, instead of a hash map: a look-up per bounce and per record).
const CELL_COUNT: usize = AXIS * AXIS * AXIS * 6;
const _: () = assert!(CELL_COUNT <= 1 << 16, "a record holds a cell in 16 bits");
/// No slot.
const NONE: u32 = u32::MAX;

/// The index of a path vertex's cell: its position on a grid of [`CELLS`] per diagonal of the
/// scene's frame and the dominant axis of its normal (6 directions), so that a floor and the
/// ceiling above it, or the two sides of a thin wall, learn apart.
fn cell_index((origin, diagonal): (DVec3, f64), p: DVec3, n: DVec3) -> u32 {
    let q = ((p - origin) / diagonal.max(f64::MIN_POSITIVE) * CELLS)
        .clamp(DVec3::ZERO, DVec3::splat(CELLS));
    let a = n.abs();
    let axis = if a.x >= a.y && a.x >= a.z {
        0
    } else if a.y >= a.z {
        1
    } else {
        2
    };
    let side = usize::from(n[axis] < 0.0);
    let (x, y, z) = (q.x as usize, q.y as usize, q.z as usize);
    (((z * AXIS + y) * AXIS + x) * 6 + 2 * axis + side) as u32
}

/// What a spatial cell holds for a round: its guide (if it learned one) and the mean light that
/// rays brought from it (the paths' estimate of the radiance leaving it, for splitting).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Cell<'a> {
    /// The guide of the bounces from the cell's vertices.
    pub(crate) guide: Option<&'a Guide>,
    /// The mean luminance of the light that rays brought from the cell.
    pub(crate) light: f64,
}

/// The guides of the continuation bounces (path vertices beyond the output points): one per
/// spatial cell ([`cell_index`]) that earlier rounds learned in, frozen during a round.
#[derive(Debug, Default)]
pub(crate) struct SpatialGuides {
    frame: (DVec3, f64),
    cap: usize,
    /// Per cell of the grid ([`CELL_COUNT`], empty while nothing was learned): its guide's index
    /// in `guides` ([`NONE`]: none) and its mean light (negative: the cell learned nothing).
    cells: Vec<(u32, f32)>,
    guides: Vec<Guide>,
}

impl SpatialGuides {
    /// The most bounces a group records per round.
    pub(crate) fn cap(&self) -> usize {
        self.cap
    }

    /// Keeps `record` in a group's `records` while they hold fewer than [`SpatialGuides::cap`]:
    /// room for the cap at the first (growing by doubling, 50 000 lone probes' 167 records each
    /// took room for 256).
    pub(crate) fn keep(&self, records: &mut Vec<Record>, record: Record) {
        if records.len() < self.cap {
            if records.capacity() == 0 {
                records.reserve_exact(self.cap);
            }
            records.push(record);
        }
    }

    /// The cell of a path vertex (p, n), if earlier rounds learned there.
    pub(crate) fn at(&self, p: DVec3, n: DVec3) -> Option<Cell<'_>> {
        let &(guide, light) = self.cells.get(cell_index(self.frame, p, n) as usize)?;
        if light < 0.0 {
            return None;
        }
        Some(Cell {
            guide: self.guides.get(guide as usize),
            light: f64::from(light),
        })
    }

    /// The record of a bounce at (p, n) through square point `u` with density `q` that brought
    /// `light` from its hit at (hp, hn).
    pub(crate) fn record(
        &self,
        (p, n): (DVec3, DVec3),
        u: [f64; 2],
        q: f64,
        light: f64,
        (hp, hn): (DVec3, DVec3),
    ) -> Record {
        Record {
            key_bin: cell_index(self.frame, p, n) | ((bin(u[0]) * RES + bin(u[1])) as u32) << 16,
            value: (light / q) as f32,
            light: light as f32,
            hit: cell_index(self.frame, hp, hn) as u16,
        }
    }
}

/// What the rounds so far learned in one spatial cell.
#[derive(Clone, Debug)]
struct CellSums {
    /// Per bin Σ L/q of the bounces from the cell.
    bins: [f64; RES * RES],
    /// The bounces from the cell.
    count: f64,
    /// Σ of the light that rays brought from the cell, and their count.
    light: (f64, f64),
}

/// Everything the rounds so far have learned for the spatial guides: per cell, per bin, Σ L/q,
/// and the light that rays brought from it.
#[derive(Debug)]
pub(crate) struct SpatialLearner {
    frame: (DVec3, f64),
    cap: usize,
    /// Per cell of the grid ([`CELL_COUNT`]): its slot in `sums` ([`NONE`]: nothing learned).
    slots: Vec<u32>,
    /// The cells that learned something, in the order they first did.
    sums: Vec<CellSums>,
}

impl SpatialLearner {
    /// Nothing learned yet, in the scene's frame (`Domain::frame`), for `groups` groups.
    pub(crate) fn new(frame: (DVec3, f64), groups: usize) -> Self {
        Self {
            frame,
            cap: (RECORDS_PER_ROUND / groups.max(1)).clamp(1, RECORDS_PER_GROUP),
            slots: Vec::new(),
            sums: Vec::new(),
        }
    }

    /// The sums of cell `index`, new when it had none.
    fn cell(&mut self, index: u32) -> &mut CellSums {
        if self.slots.is_empty() {
            self.slots = vec![NONE; CELL_COUNT];
        }
        let slot = &mut self.slots[index as usize];
        if *slot == NONE {
            *slot = self.sums.len() as u32;
            self.sums.push(CellSums {
                bins: [0.0; RES * RES],
                count: 0.0,
                light: (0.0, 0.0),
            });
        }
        &mut self.sums[*slot as usize]
    }

    /// Adds a group's records (call in a fixed order of the groups: the sums, and so the guides,
    /// do not depend on the thread count).
    pub(crate) fn learn(&mut self, records: &[Record]) {
        for r in records {
            let cell = self.cell(r.cell());
            cell.count += 1.0;
            if r.value > 0.0 && r.value.is_finite() {
                cell.bins[r.bin()] += f64::from(r.value);
            }
            let light = &mut self.cell(u32::from(r.hit)).light;
            light.1 += 1.0;
            if r.light > 0.0 && r.light.is_finite() {
                light.0 += f64::from(r.light);
            }
        }
    }

    /// The guides of everything learned so far.
    pub(crate) fn guides(&self) -> SpatialGuides {
        let mut cells = Vec::new();
        let mut guides = Vec::new();
        if !self.sums.is_empty() {
            cells = vec![(NONE, -1.0f32); CELL_COUNT];
            for (cell, &slot) in cells.iter_mut().zip(&self.slots) {
                let Some(s) = self.sums.get(slot as usize) else {
                    continue;
                };
                let (sum, count) = s.light;
                let light = if count > 0.0 {
                    (sum / count) as f32
                } else {
                    0.0
                };
                let guide = Guide::from_sums(&s.bins, s.count).map_or(NONE, |g| {
                    guides.push(g);
                    (guides.len() - 1) as u32
                });
                *cell = (guide, light);
            }
        }
        SpatialGuides {
            frame: self.frame,
            cap: self.cap,
            cells,
            guides,
        }
    }
}

impl GroupGuide {
    /// Ends a round: the next one is guided by everything learned so far.
    pub(crate) fn next_round(&mut self) {
        self.guide = self.learner.guide().map(Box::new);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use scene_sampler::cosine_hemisphere;

    /// `to_square` inverts the cosine warp.
    #[test]
    fn the_square_inverts_the_cosine_warp() {
        for n in [DVec3::Y, DVec3::new(0.3, -0.5, 0.8).normalize(), -DVec3::Z] {
            // (from 1: at sin²θ = 0, the pole, every φ is the same direction)
            for i in 1..50 {
                let u = [(i as f64 * 0.618_034) % 1.0, (i as f64 * 0.754_878) % 1.0];
                let v = to_square(n, cosine_hemisphere(n, u));
                assert!(
                    (u[0] - v[0]).abs() < 1e-9 && (u[1] - v[1]).abs() < 1e-9,
                    "{u:?} {v:?}"
                );
            }
        }
    }

    /// `density_toward` is `density` at `to_square` (its octants are atan2's bins of φ).
    #[test]
    fn the_density_toward_a_direction_is_the_densitys_at_its_square_point() {
        let sums: Vec<f64> = (0..RES * RES).map(|b| (b * 7 % 13) as f64).collect();
        let g = Guide::from_sums(&sums, 1e6).unwrap();
        for n in [DVec3::Y, DVec3::new(0.3, -0.5, 0.8).normalize(), -DVec3::Z] {
            // (from 1: the pole, where every φ is the same direction, and the octants' edges
            // have measure zero)
            for i in 1..4000 {
                let u = [(i as f64 * 0.618_034) % 1.0, (i as f64 * 0.754_878) % 1.0];
                let d = scene_sampler::cosine_hemisphere(n, u) * (1.0 + i as f64 % 3.0);
                assert_eq!(
                    g.density_toward(n, d),
                    g.density(to_square(n, d.normalize())),
                    "{n} {d}"
                );
            }
        }
    }

    /// A guide's density integrates to 1 over the square, is at least α everywhere, and its
    /// sampling draws each bin with its mass (a histogram of 2²⁰ points).
    #[test]
    fn the_guide_samples_its_density() {
        let mut sums = vec![0.0; RES * RES];
        sums[3 * RES + 5] = 10.0;
        sums[7 * RES + RES - 1] = 1.0;
        sums[0] = 0.5;
        let g = Guide::from_sums(&sums, 1e300).unwrap();
        let mean: f64 = g.density.iter().sum::<f64>() / (RES * RES) as f64;
        assert!((mean - 1.0).abs() < 1e-12, "{mean}");
        assert!(g.density.iter().all(|&q| q >= DEFENSIVE - 1e-12));
        // the R2 sequence (well spread in every projection, unlike a grid, whose lines would
        // quantize a light column of a heavy row)
        let n = 1usize << 20;
        let mut counts = vec![0usize; RES * RES];
        for i in 0..n {
            let t = i as f64;
            let u = [
                (0.5 + t * 0.754_877_666_246_692_7).fract(),
                (0.5 + t * 0.569_840_290_998_053_3).fract(),
            ];
            let (v, q) = g.sample(u);
            assert_eq!(q, g.density(v));
            counts[bin(v[0]) * RES + bin(v[1])] += 1;
        }
        for (b, &c) in counts.iter().enumerate() {
            let expected = g.density[b] / (RES * RES) as f64 * n as f64;
            assert!(
                (c as f64 - expected).abs() <= 2.0 + 0.02 * expected,
                "bin {b}: {c} vs {expected}"
            );
        }
        assert!(Guide::from_sums(&[0.0; RES * RES], 1e3).is_none());
    }
}

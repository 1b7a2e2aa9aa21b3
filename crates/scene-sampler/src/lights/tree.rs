//! A light tree: light selection that depends on the receiver (Conty Estevez & Kulla 2018,
//! "Importance sampling of many lights with adaptive tree splitting"; pbrt-v4's
//! `BVHLightSampler`). With many lamps in many rooms, drawing a light in proportion to its power
//! sends most shadow rays to lamps that are far away or behind a wall; the tree draws lights in
//! proportion to a bound of what they can send to the receiver instead.
//!
//! Every light with a position (an emitting face, a point or spot light) is a leaf with its
//! [`LightBounds`]: a box, its power Φ, and a cone of emission directions (axis w, spread θ_o
//! of the normals or axes about w, and falloff θ_e beyond them to where nothing is emitted). An
//! interior node bounds its two children. At a receiver (y, n) a node's **importance** is
//!
//! ```text
//! I(y, n) = Φ · cos θ' · cos θ'_i / max(d², (|diag|/2)²)
//! θ'   = max(0, θ_w − θ_o − θ_b)   (0 when θ' ≥ θ_e: the receiver is outside every emission cone)
//! θ'_i = max(0, θ_i − θ_b)         (0 when θ'_i ≥ π/2: the box is below the receiver's horizon)
//! ```
//!
//! with d the distance from the box's centre to y, θ_w the angle between w and the direction from
//! the centre to y, θ_i the angle between n and the direction from y to the centre, and θ_b the
//! half-angle of the cone from y that holds the box's bounding sphere (π when y is inside it).
//! The angles shrink by θ_b, so a node's importance is 0 only when no point of any of its lights
//! can send light to the receiver's side: a light the tree never draws gives the receiver nothing
//! (point and spot lights, which no cosine ray reaches, rely on this), and an emitting face the
//! tree draws with too small a probability only shifts MIS weight to the cosine rays.
//!
//! A light is drawn by walking from the root, choosing a child with probability proportional to
//! its importance (one random number, remapped at each level); its probability is the product of
//! those choices, which [`LightTree::probability`] recomputes by walking from the leaf up with the
//! same arithmetic. Nodes are split by the binned surface-area-orientation heuristic of Conty
//! Estevez & Kulla (Φ · M_Ω · surface area, 12 buckets per axis).

use super::Receiver;
use glam::DVec3;
use std::f64::consts::PI;

/// What a light, or a node of lights, can send where (module docs).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LightBounds {
    /// The box's lower corner.
    pub lo: DVec3,
    /// The box's upper corner.
    pub hi: DVec3,
    /// Power Φ (any positive measure proportional to the flux; the tree's choices are relative).
    pub power: f64,
    /// Unit axis w of the emission cone.
    pub axis: DVec3,
    /// cos θ_o: every emitting normal (a spot's full-intensity cone) within θ_o of the axis.
    pub cos_spread: f64,
    /// cos θ_e: emission stops θ_e beyond the spread (π/2 for a Lambertian face).
    pub cos_falloff: f64,
}

impl LightBounds {
    /// An emitting triangle with unit normal `normal` and power `power` (one-sided, Lambertian).
    pub fn face(corners: [DVec3; 3], normal: DVec3, power: f64) -> Self {
        let lo = corners[0].min(corners[1]).min(corners[2]);
        let hi = corners[0].max(corners[1]).max(corners[2]);
        Self {
            lo,
            hi,
            power,
            axis: normal,
            cos_spread: 1.0,
            cos_falloff: 0.0,
        }
    }

    /// A point light at `p` that sends light in every direction.
    pub fn point(p: DVec3, power: f64) -> Self {
        Self {
            lo: p,
            hi: p,
            power,
            axis: DVec3::Z,
            cos_spread: -1.0,
            cos_falloff: 0.0,
        }
    }

    /// A spot light at `p` along the unit `axis`, at full intensity within the cone of cosine
    /// `cos_inner` and nothing beyond `cos_outer`.
    pub fn spot(p: DVec3, power: f64, axis: DVec3, cos_inner: f64, cos_outer: f64) -> Self {
        let (inner, outer) = (
            cos_inner.clamp(-1.0, 1.0).acos(),
            cos_outer.clamp(-1.0, 1.0).acos(),
        );
        Self {
            cos_spread: cos_inner,
            cos_falloff: (outer - inner).max(0.0).cos(),
            ..Self::point(p, power).with_axis(axis)
        }
    }

    fn with_axis(self, axis: DVec3) -> Self {
        Self { axis, ..self }
    }

    fn centre(&self) -> DVec3 {
        0.5 * (self.lo + self.hi)
    }

    /// The smallest bounds that hold both (the cones merged as in Conty Estevez & Kulla, §4.2).
    fn union(&self, o: &Self) -> Self {
        let (axis, cos_spread) = union_cone((self.axis, self.cos_spread), (o.axis, o.cos_spread));
        Self {
            lo: self.lo.min(o.lo),
            hi: self.hi.max(o.hi),
            power: self.power + o.power,
            axis,
            cos_spread,
            cos_falloff: self.cos_falloff.min(o.cos_falloff),
        }
    }

    /// The importance I(y, n) of the module docs at the receiver `at`.
    pub fn importance(&self, at: &Receiver) -> f64 {
        let c = self.centre();
        let half_diag2 = 0.25 * (self.hi - self.lo).length_squared();
        let to_y = at.p - c;
        let d2 = to_y.length_squared();
        // θ_b: the half-angle from y of the box's bounding sphere (π inside it)
        let (sin_b, cos_b) = if d2 <= half_diag2 {
            (0.0, -1.0)
        } else {
            let s2 = half_diag2 / d2;
            (s2.sqrt(), (1.0 - s2).sqrt())
        };
        let Some(wi) = to_y.try_normalize() else {
            return self.power / half_diag2.max(f64::MIN_POSITIVE);
        };
        // θ' = θ_w − θ_o − θ_b, clamped at 0
        let cos_w = self.axis.dot(wi).clamp(-1.0, 1.0);
        let sin_w = (1.0 - cos_w * cos_w).max(0.0).sqrt();
        let sin_o = (1.0 - self.cos_spread * self.cos_spread).max(0.0).sqrt();
        let (sin_x, cos_x) = minus_clamped((sin_w, cos_w), (sin_o, self.cos_spread));
        let (_, cos_p) = minus_clamped((sin_x, cos_x), (sin_b, cos_b));
        if cos_p <= self.cos_falloff {
            return 0.0;
        }
        // θ'_i = θ_i − θ_b, clamped at 0
        let cos_i = (-wi).dot(at.n).clamp(-1.0, 1.0);
        let sin_i = (1.0 - cos_i * cos_i).max(0.0).sqrt();
        let (_, cos_pi) = minus_clamped((sin_i, cos_i), (sin_b, cos_b));
        if cos_pi <= 0.0 {
            return 0.0;
        }
        let v = self.power * cos_p * cos_pi / d2.max(half_diag2);
        if v.is_finite() { v.max(0.0) } else { 0.0 }
    }

    /// Conty Estevez & Kulla's orientation measure M_Ω of the cone (θ_o, θ_e), eq. 1.
    fn orientation_measure(&self) -> f64 {
        let o = self.cos_spread.clamp(-1.0, 1.0).acos();
        let e = self.cos_falloff.clamp(-1.0, 1.0).acos();
        let w = (o + e).min(PI);
        2.0 * PI * (1.0 - o.cos())
            + PI / 2.0 * (2.0 * w * o.sin() - (o - 2.0 * w).cos() - 2.0 * o * o.sin() + o.cos())
    }

    fn surface_area(&self) -> f64 {
        let d = self.hi - self.lo;
        2.0 * (d.x * d.y + d.y * d.z + d.z * d.x)
    }
}

/// (sin, cos) of max(0, a − b) for angles a, b ∈ [0, π] given by their sines and cosines.
fn minus_clamped((sin_a, cos_a): (f64, f64), (sin_b, cos_b): (f64, f64)) -> (f64, f64) {
    if cos_a >= cos_b {
        return (0.0, 1.0);
    }
    (sin_a * cos_b - cos_a * sin_b, cos_a * cos_b + sin_a * sin_b)
}

/// The smallest cone (axis, cos θ) that holds the cones `a` and `b`.
fn union_cone(a: (DVec3, f64), b: (DVec3, f64)) -> (DVec3, f64) {
    let (a, b) = if b.1 < a.1 { (b, a) } else { (a, b) }; // a the wider
    let (ta, tb) = (a.1.clamp(-1.0, 1.0).acos(), b.1.clamp(-1.0, 1.0).acos());
    let td = a.0.dot(b.0).clamp(-1.0, 1.0).acos();
    if (td + tb).min(PI) <= ta {
        return a;
    }
    let to = 0.5 * (ta + td + tb);
    if to >= PI {
        return (a.0, -1.0);
    }
    // turn a's axis toward b's by θ_o − θ_a
    let Some(k) = a.0.cross(b.0).try_normalize() else {
        return (a.0, -1.0);
    };
    let r = to - ta;
    let axis = a.0 * r.cos() + k.cross(a.0) * r.sin() + k * k.dot(a.0) * (1.0 - r.cos());
    (axis.normalize(), to.cos())
}

/// A node: its bounds, and either a leaf (a run of `members`) or the index of its second child
/// (the first follows it).
#[derive(Clone, Debug)]
struct Node {
    bounds: LightBounds,
    /// A leaf's lights: `members[start..start + count]`.
    leaf: Option<(u32, u32)>,
    second: u32,
    parent: u32,
}

/// A binary tree over lights with [`LightBounds`] (module docs).
#[derive(Clone, Debug)]
pub struct LightTree {
    nodes: Vec<Node>,
    /// The leaves' lights, leaf by leaf.
    members: Vec<u32>,
    /// Each light's leaf node (`u32::MAX`: never drawn).
    node_of: Vec<u32>,
    /// Each light's power.
    power: Vec<f64>,
}

const BUCKETS: usize = 12;

impl LightTree {
    /// The tree over `lights` (light i is `lights[i]`); `None` when no light has positive finite
    /// power and finite bounds. Lights without them are never drawn.
    ///
    /// Lights whose bounds are the same but for their power (the two triangles of a rectangular
    /// lamp) share a leaf and are drawn within it by power: the importance of each is its power
    /// times the same factor, so this is the distribution the full tree would give, for less work.
    /// A tree that is one leaf draws by power alone and evaluates no importance.
    pub fn new(lights: &[LightBounds]) -> Option<Self> {
        let mut items: Vec<(LightBounds, u32)> = (lights.iter().enumerate())
            .filter(|(_, b)| {
                b.power > 0.0
                    && b.power.is_finite()
                    && b.lo.is_finite()
                    && b.hi.is_finite()
                    && b.axis.is_finite()
            })
            .map(|(i, b)| (*b, i as u32))
            .collect();
        if items.is_empty() {
            return None;
        }
        let mut tree = Self {
            nodes: Vec::with_capacity(2 * items.len()),
            members: Vec::with_capacity(items.len()),
            node_of: vec![u32::MAX; lights.len()],
            power: lights.iter().map(|b| b.power).collect(),
        };
        tree.build(&mut items, u32::MAX);
        Some(tree)
    }

    /// Builds the subtree of `items` under `parent`; returns its node's index.
    fn build(&mut self, items: &mut [(LightBounds, u32)], parent: u32) -> u32 {
        let at = self.nodes.len() as u32;
        let bounds = (items[1..].iter()).fold(items[0].0, |b, (o, _)| b.union(o));
        let same = |b: &LightBounds| {
            LightBounds {
                power: items[0].0.power,
                ..*b
            } == items[0].0
        };
        if items.iter().all(|(b, _)| same(b)) {
            let start = self.members.len() as u32;
            for (_, light) in items.iter() {
                self.node_of[*light as usize] = at;
                self.members.push(*light);
            }
            self.nodes.push(Node {
                bounds,
                leaf: Some((start, items.len() as u32)),
                second: 0,
                parent,
            });
            return at;
        }
        self.nodes.push(Node {
            bounds,
            leaf: None,
            second: 0,
            parent,
        });
        let mid = split(items, &bounds);
        let (first, second) = items.split_at_mut(mid);
        self.build(first, at);
        let s = self.build(second, at);
        self.nodes[at as usize].second = s;
        at
    }

    /// The probability of the first child of the interior node `node` at the receiver; `None`
    /// when neither child can send it light.
    fn first_share(&self, node: u32, at: &Receiver) -> Option<f64> {
        let n = &self.nodes[node as usize];
        let a = self.nodes[node as usize + 1].bounds.importance(at);
        let b = self.nodes[n.second as usize].bounds.importance(at);
        let total = a + b;
        (total > 0.0).then(|| a / total)
    }

    /// Whether the tree is one leaf: it draws by power alone.
    pub fn is_leaf(&self) -> bool {
        self.nodes.len() == 1
    }

    /// The share of `light` within its leaf `node`: its power over the leaf's.
    fn within(&self, node: u32, light: u32) -> f64 {
        self.power[light as usize] / self.nodes[node as usize].bounds.power
    }

    /// A light drawn for the receiver `at` from `u ∈ [0, 1)`, with its probability; `None` when
    /// no light can send the receiver anything (or none along the way `u` leads).
    pub fn sample(&self, at: &Receiver, mut u: f64) -> Option<(u32, f64)> {
        let mut node = 0u32;
        let mut p = 1.0;
        loop {
            let n = &self.nodes[node as usize];
            if let Some((start, count)) = n.leaf {
                let lights = &self.members[start as usize..(start + count) as usize];
                let mut acc = 0.0;
                for &light in lights {
                    let share = self.within(node, light);
                    acc += share;
                    if u < acc || light == lights[lights.len() - 1] {
                        return Some((light, p * share));
                    }
                }
            }
            let share = self.first_share(node, at)?;
            if u < share {
                u = (u / share).min(1.0 - f64::EPSILON);
                p *= share;
                node += 1;
            } else {
                u = ((u - share) / (1.0 - share)).clamp(0.0, 1.0 - f64::EPSILON);
                p *= 1.0 - share;
                node = n.second;
            }
        }
    }

    /// The probability with which [`LightTree::sample`] draws `light` for the receiver `at`.
    pub fn probability(&self, at: &Receiver, light: u32) -> f64 {
        let Some(&leaf) = self.node_of.get(light as usize) else {
            return 0.0;
        };
        if leaf == u32::MAX {
            return 0.0;
        }
        let mut p = self.within(leaf, light);
        let mut node = leaf;
        while node != 0 {
            let parent = self.nodes[node as usize].parent;
            let Some(share) = self.first_share(parent, at) else {
                return 0.0;
            };
            p *= if node == parent + 1 {
                share
            } else {
                1.0 - share
            };
            node = parent;
        }
        p
    }
}

/// Orders `items` so that `[..mid]` and `[mid..]` are the two children of the node with `bounds`
/// (binned surface-area-orientation heuristic; the middle by count when the centroids coincide).
fn split(items: &mut [(LightBounds, u32)], bounds: &LightBounds) -> usize {
    let (clo, chi) = (items.iter()).fold(
        (DVec3::INFINITY, DVec3::NEG_INFINITY),
        |(lo, hi), (b, _)| (lo.min(b.centre()), hi.max(b.centre())),
    );
    let extent = bounds.hi - bounds.lo;
    let max_extent = extent.max_element();
    let bucket = |b: &LightBounds, axis: usize| {
        let (lo, hi) = (clo[axis], chi[axis]);
        (((b.centre()[axis] - lo) / (hi - lo) * BUCKETS as f64) as usize).min(BUCKETS - 1)
    };
    let mut best: Option<(f64, usize, usize)> = None; // (cost, axis, first bucket of the second)
    for axis in 0..3 {
        if chi[axis] <= clo[axis] {
            continue;
        }
        let mut buckets: [Option<LightBounds>; BUCKETS] = [None; BUCKETS];
        for (b, _) in items.iter() {
            let k = bucket(b, axis);
            buckets[k] = Some(buckets[k].map_or(*b, |x| x.union(b)));
        }
        let merge = |r: &[Option<LightBounds>]| {
            (r.iter().flatten()).fold(None, |acc: Option<LightBounds>, b| {
                Some(acc.map_or(*b, |a| a.union(b)))
            })
        };
        let cost = |b: LightBounds| b.power * b.orientation_measure() * b.surface_area();
        let regular = if extent[axis] > 0.0 {
            max_extent / extent[axis]
        } else {
            1.0
        };
        for cut in 1..BUCKETS {
            let (Some(l), Some(r)) = (merge(&buckets[..cut]), merge(&buckets[cut..])) else {
                continue;
            };
            let c = regular * (cost(l) + cost(r));
            if best.is_none_or(|(b, _, _)| c < b) {
                best = Some((c, axis, cut));
            }
        }
    }
    let mut mid = 0;
    if let Some((_, axis, cut)) = best {
        for j in 0..items.len() {
            if bucket(&items[j].0, axis) < cut {
                items.swap(mid, j);
                mid += 1;
            }
        }
    }
    if mid == 0 || mid == items.len() {
        // coincident centroids (or a degenerate cut): halve by count, deterministically
        items.sort_by_key(|(_, i)| *i);
        return items.len() / 2;
    }
    mid
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    fn receiver(rng: &mut ChaCha8Rng) -> Receiver {
        let p = DVec3::new(rng.random(), rng.random(), rng.random()) * 10.0 - 1.0;
        let n = DVec3::new(rng.random(), rng.random(), rng.random()) * 2.0 - DVec3::ONE;
        Receiver {
            p,
            n: n.normalize(),
        }
    }

    /// Lamps under the ceilings of a row of rooms (faces facing down), points and spots.
    fn lights(rng: &mut ChaCha8Rng) -> Vec<LightBounds> {
        let mut out = Vec::new();
        for k in 0..40 {
            let c = DVec3::new(rng.random::<f64>() * 8.0, 2.5, rng.random::<f64>() * 8.0);
            let corners = [c, c + DVec3::X * 0.3, c + DVec3::Z * 0.3];
            out.push(LightBounds::face(corners, -DVec3::Y, 1.0 + k as f64 % 3.0));
        }
        out.push(LightBounds::point(DVec3::new(2.0, 1.0, 2.0), 5.0));
        let s = LightBounds::spot(DVec3::new(6.0, 0.2, 6.0), 5.0, DVec3::Y, 0.9, 0.8);
        out.push(s);
        out.push(LightBounds { power: 0.0, ..s });
        out
    }

    /// Over every light, the probabilities at a receiver sum to at most 1, and `sample` returns
    /// the light's `probability`.
    #[test]
    fn probabilities_sum_to_one_and_match_the_draws() {
        let mut rng = ChaCha8Rng::seed_from_u64(7);
        let lights = lights(&mut rng);
        let tree = LightTree::new(&lights).unwrap();
        assert_eq!(tree.probability(&receiver(&mut rng), 42), 0.0, "no power");
        for _ in 0..200 {
            let at = receiver(&mut rng);
            let total: f64 = (0..lights.len() as u32)
                .map(|i| tree.probability(&at, i))
                .sum();
            // below 1 where a node whose bound reaches the receiver has children that both do
            // not (a draw that ends there is lost: a wasted sample, not a bias)
            assert!((0.0..=1.0 + 1e-12).contains(&total), "{total}");
            for _ in 0..20 {
                if let Some((i, p)) = tree.sample(&at, rng.random()) {
                    assert!(p > 0.0 && (p - tree.probability(&at, i)).abs() < 1e-14 * p);
                }
            }
        }
    }

    /// The draws follow the probabilities: frequencies over 40 000 draws at one receiver within
    /// 5 standard deviations.
    #[test]
    fn draws_follow_the_probabilities() {
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        let lights = lights(&mut rng);
        let tree = LightTree::new(&lights).unwrap();
        let at = Receiver {
            p: DVec3::new(3.0, 0.8, 4.0),
            n: DVec3::Y,
        };
        let n = 40_000;
        let mut count = vec![0usize; lights.len()];
        for k in 0..n {
            let (i, _) = tree.sample(&at, (k as f64 + 0.5) / n as f64).unwrap();
            count[i as usize] += 1;
        }
        for (i, c) in count.iter().enumerate() {
            let p = tree.probability(&at, i as u32);
            let sd = (n as f64 * p * (1.0 - p)).sqrt().max(1.0);
            assert!(
                (*c as f64 - n as f64 * p).abs() < 5.0 * sd,
                "{i}: {c} vs {p}"
            );
        }
    }

    /// A light that can send the receiver something is never given probability 0 (checked at
    /// the corners of lamps facing down, at point lights, at a spot's cone), and a ceiling lamp
    /// seen from above the ceiling gets 0.
    #[test]
    fn zero_only_where_nothing_arrives() {
        let mut rng = ChaCha8Rng::seed_from_u64(11);
        let mut lights = Vec::new();
        type Reaches = Box<dyn Fn(&Receiver) -> bool>;
        let mut reaches: Vec<Reaches> = Vec::new();
        let sees = |at: &Receiver, x: DVec3| at.n.dot(x - at.p) > 1e-9;
        for _ in 0..30 {
            let c = DVec3::new(rng.random(), rng.random(), rng.random()) * 8.0;
            let n = (DVec3::new(rng.random(), rng.random(), rng.random()) - 0.5).normalize();
            let (t, b) = (
                n.any_orthonormal_vector(),
                n.any_orthonormal_vector().cross(n),
            );
            let corners = [c, c + 0.4 * t, c + 0.4 * b];
            lights.push(LightBounds::face(corners, n, 1.0));
            reaches.push(Box::new(move |at| {
                corners
                    .iter()
                    .any(|x| n.dot(at.p - *x) > 1e-9 && sees(at, *x))
            }));
        }
        for _ in 0..5 {
            let p = DVec3::new(rng.random(), rng.random(), rng.random()) * 8.0;
            lights.push(LightBounds::point(p, 3.0));
            reaches.push(Box::new(move |at| sees(at, p)));
            let axis = (DVec3::new(rng.random(), rng.random(), rng.random()) - 0.5).normalize();
            lights.push(LightBounds::spot(p, 3.0, axis, 0.95, 0.9));
            reaches.push(Box::new(move |at| {
                sees(at, p) && axis.dot((at.p - p).normalize()) > 0.9 + 1e-9
            }));
        }
        let tree = LightTree::new(&lights).unwrap();
        for _ in 0..3000 {
            let at = receiver(&mut rng);
            for (i, reach) in reaches.iter().enumerate() {
                if reach(&at) {
                    assert!(tree.probability(&at, i as u32) > 0.0, "light {i} at {at:?}");
                }
            }
        }
        // of two lamps, one seen from above its ceiling: only the other is drawn
        let lamps = [
            LightBounds::face([DVec3::ZERO, DVec3::X, DVec3::Z], -DVec3::Y, 1.0),
            LightBounds::face([DVec3::Y * 5.0, DVec3::X, DVec3::Z], DVec3::X, 1.0),
        ];
        let two = LightTree::new(&lamps).unwrap();
        let above = Receiver {
            p: DVec3::new(0.3, 1.0, 0.3),
            n: -DVec3::Y,
        };
        assert_eq!(two.probability(&above, 0), 0.0);
        assert_eq!(two.probability(&above, 1), 1.0);
        assert_eq!(two.sample(&above, 0.01).map(|s| s.0), Some(1));
    }

    /// The two triangles of a rectangular lamp share a leaf and are drawn by power: a tree of
    /// one leaf is selection by power.
    #[test]
    fn a_leaf_of_equal_bounds_draws_by_power() {
        let (a, b, c, d) = (DVec3::ZERO, DVec3::X, DVec3::new(1.0, 0.0, 1.0), DVec3::Z);
        let lamp = [
            LightBounds::face([a, b, c], -DVec3::Y, 1.0),
            LightBounds::face([a, c, d], -DVec3::Y, 3.0),
        ];
        let tree = LightTree::new(&lamp).unwrap();
        assert_eq!(tree.nodes.len(), 1);
        let anywhere = Receiver {
            p: DVec3::new(9.0, 9.0, 9.0),
            n: DVec3::X,
        };
        assert_eq!(tree.probability(&anywhere, 0), 0.25);
        assert_eq!(tree.sample(&anywhere, 0.2), Some((0, 0.25)));
        assert_eq!(tree.sample(&anywhere, 0.3), Some((1, 0.75)));
    }

    /// Near one lamp of many far apart, that lamp gets most of the probability (the point of the
    /// tree: power alone gives it 1/20).
    #[test]
    fn the_near_lamp_wins() {
        let lamps: Vec<LightBounds> = (0..20)
            .map(|k| {
                let c = DVec3::new(4.0 * k as f64 + 2.0, 2.8, 2.0);
                LightBounds::face([c, c + DVec3::X * 0.5, c + DVec3::Z * 0.5], -DVec3::Y, 1.0)
            })
            .collect();
        let tree = LightTree::new(&lamps).unwrap();
        let at = Receiver {
            p: DVec3::new(4.0 * 7.0 + 2.0, 0.8, 2.0),
            n: DVec3::Y,
        };
        let p = tree.probability(&at, 7);
        assert!(p > 0.5, "{p}");
    }

    #[test]
    fn cones_merge_to_hold_both() {
        let (axis, c) = union_cone((DVec3::Y, 1.0), (DVec3::X, 1.0));
        assert!((c - (PI / 4.0).cos()).abs() < 1e-12);
        assert!((axis - DVec3::new(1.0, 1.0, 0.0).normalize()).length() < 1e-12);
        assert_eq!(union_cone((DVec3::Y, 1.0), (-DVec3::Y, 1.0)).1, -1.0);
        let wide = (DVec3::Y, 0.0);
        assert_eq!(union_cone(wide, (DVec3::X, 1.0)), wide);
    }
}

//! Flatland form factors between segments: Hottel's crossed strings (docs/design/math.md §7) and a ray estimate of the
//! visible fraction.
//!
//! For two segments `i = (a, b)` and `j = (c, d)`, both with their front (left of `a → b`) side facing the
//! other and each lying entirely in front of the other's line, the unoccluded form factor is
//!
//! `F_ij = ((|ac| + |bd|) − (|ad| + |bc|)) / (2 L_i)`              (docs/design/math.md §7)
//!
//! — the fraction of the energy leaving i (uniform radiosity) that arrives at j, i.e.
//! `F_ij = (1/L_i) ∫_i ∫_j cos θx cos θy / (2r) dy dx` with the Flatland kernel of sec. 4.1.
//! Segments that are partly behind each other are first clipped to the other's front half-plane (only the
//! clipped parts exchange light; `L_i` stays the full length). Reciprocity `L_i F_ij = L_j F_ji` holds exactly.

use glam::DVec2;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use scene_sampler::{FlatPoint, FlatVisibility};

/// A piece of a Flatland segment: the straight part from `a` to `b` of input segment `segment`, front side to
/// the left of `a → b` (the convention of [`scene_sampler::Segment`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Piece {
    /// Start point.
    pub a: DVec2,
    /// End point.
    pub b: DVec2,
    /// Unit front normal (`b − a` rotated by +90°).
    pub normal: DVec2,
    /// Index of the input segment the piece lies on (visibility rays skip it).
    pub segment: u32,
}

impl Piece {
    /// A piece from `a` to `b` of segment `segment`; the normal is computed.
    pub fn new(a: DVec2, b: DVec2, segment: u32) -> Self {
        let d = b - a;
        let l = d.length();
        let normal = if l > 0.0 {
            DVec2::new(-d.y, d.x) / l
        } else {
            DVec2::ZERO
        };
        Piece {
            a,
            b,
            normal,
            segment,
        }
    }
    /// Length `|b − a|`.
    pub fn length(&self) -> f64 {
        (self.b - self.a).length()
    }
}

/// Clips `(p, q)` to the closed half-plane `n · (x − o) ≥ 0`; `None` if nothing of positive length remains.
fn clip(p: DVec2, q: DVec2, o: DVec2, n: DVec2) -> Option<(DVec2, DVec2)> {
    let scale = (q - p).length().max((p - o).length()).max(1e-300);
    let tol = 1e-12 * scale;
    let mut dp = n.dot(p - o);
    let mut dq = n.dot(q - o);
    if dp.abs() <= tol {
        dp = 0.0;
    }
    if dq.abs() <= tol {
        dq = 0.0;
    }
    if dp < 0.0 && dq <= 0.0 || dp <= 0.0 && dq < 0.0 || dp == 0.0 && dq == 0.0 {
        return None;
    }
    if dp >= 0.0 && dq >= 0.0 {
        return Some((p, q));
    }
    let x = p + (q - p) * (dp / (dp - dq));
    if dp < 0.0 { Some((x, q)) } else { Some((p, x)) }
}

/// The parts of `i` and `j` that lie in front of each other (each clipped to the other's front half-plane),
/// or `None` if they cannot exchange light.
pub fn mutually_visible_parts(i: &Piece, j: &Piece) -> Option<(Piece, Piece)> {
    let (c, d) = clip(j.a, j.b, i.a, i.normal)?;
    let (a, b) = clip(i.a, i.b, j.a, j.normal)?;
    // clipping i may not change what of j is in front of i (i's line is unchanged), and vice versa
    Some((
        Piece {
            a,
            b,
            normal: i.normal,
            segment: i.segment,
        },
        Piece {
            a: c,
            b: d,
            normal: j.normal,
            segment: j.segment,
        },
    ))
}

/// Unoccluded Flatland form factor `F_ij` from piece `i` to piece `j` by crossed strings (docs/design/math.md §7), after
/// clipping both to each other's front half-plane. Exact; 0 if they do not face each other.
pub fn form_factor(i: &Piece, j: &Piece) -> f64 {
    let li = i.length();
    if li == 0.0 || j.length() == 0.0 {
        return 0.0;
    }
    let Some((ci, cj)) = mutually_visible_parts(i, j) else {
        return 0.0;
    };
    let (a, b, c, d) = (ci.a, ci.b, cj.a, cj.b);
    let crossed = (c - a).length() + (d - b).length();
    let uncrossed = (d - a).length() + (c - b).length();
    ((crossed - uncrossed) / (2.0 * li)).max(0.0)
}

/// The Flatland geometry term `G(x, y) = cos θx cos θy / (2r)` (sec. 4.1, docs/design/math.md §7), 0 if either side
/// faces away.
pub fn geometry_term(x: DVec2, nx: DVec2, y: DVec2, ny: DVec2) -> f64 {
    let d = y - x;
    let r = d.length();
    if r == 0.0 {
        return 0.0;
    }
    let cx = nx.dot(d) / r;
    let cy = -ny.dot(d) / r;
    if cx <= 0.0 || cy <= 0.0 {
        0.0
    } else {
        0.5 * cx * cy / r
    }
}

/// The result of [`visibility`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct VisibilityEstimate {
    /// G-weighted visible fraction in `[0, 1]`.
    pub fraction: f64,
    /// True if some rays were blocked and some were not.
    pub partial: bool,
}

/// Estimate of the visible fraction `∫∫ G V / ∫∫ G` between two pieces with `rays` rays (the "coherence"
/// estimate of sec. 4.1), and whether the rays disagreed (partial visibility).
///
/// Ray ends are stratified on the mutually visible parts: the k-th ray starts in stratum k of `i` and ends in
/// stratum `π(k)` of `j` (a random permutation, i.e. a Latin-hypercube pairing), jittered; each ray is
/// weighted by `G`, so the estimate converges to the G-weighted visibility that makes `F · V̄` the occluded
/// form factor. Deterministic per `seed`.
pub fn visibility(
    vis: &FlatVisibility,
    i: &Piece,
    j: &Piece,
    rays: usize,
    seed: u64,
) -> VisibilityEstimate {
    let Some((ci, cj)) = mutually_visible_parts(i, j) else {
        return VisibilityEstimate {
            fraction: 0.0,
            partial: false,
        };
    };
    let n = rays.max(1);
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut perm: Vec<usize> = (0..n).collect();
    for k in (1..n).rev() {
        let m = rng.random_range(0..=k);
        perm.swap(k, m);
    }
    let (mut w_all, mut w_vis) = (0.0, 0.0);
    let (mut seen, mut blocked) = (0usize, 0usize);
    for k in 0..n {
        let u = (k as f64 + rng.random::<f64>()) / n as f64;
        let v = (perm[k] as f64 + rng.random::<f64>()) / n as f64;
        let x = ci.a + (ci.b - ci.a) * u;
        let y = cj.a + (cj.b - cj.a) * v;
        // tiny G floor so that a ray along a shared line still counts
        let g = geometry_term(x, ci.normal, y, cj.normal).max(1e-300);
        let px = FlatPoint {
            point: x,
            normal: ci.normal,
            segment: ci.segment,
        };
        let py = FlatPoint {
            point: y,
            normal: cj.normal,
            segment: cj.segment,
        };
        w_all += g;
        if vis.visible(&px, &py) {
            w_vis += g;
            seen += 1;
        } else {
            blocked += 1;
        }
    }
    VisibilityEstimate {
        fraction: if w_all > 0.0 { w_vis / w_all } else { 0.0 },
        partial: seen > 0 && blocked > 0,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parallel_unit_plates() {
        let i = Piece::new(DVec2::new(0.0, 0.0), DVec2::new(1.0, 0.0), 0);
        let j = Piece::new(DVec2::new(1.0, 1.0), DVec2::new(0.0, 1.0), 1);
        assert!((form_factor(&i, &j) - (2f64.sqrt() - 1.0)).abs() < 1e-15);
    }

    #[test]
    fn right_angle_corner() {
        let wall = Piece::new(DVec2::new(0.0, 1.0), DVec2::new(0.0, 0.0), 0);
        let floor = Piece::new(DVec2::new(0.0, 0.0), DVec2::new(1.0, 0.0), 1);
        let want = (2.0 - 2f64.sqrt()) / 2.0;
        assert!((form_factor(&wall, &floor) - want).abs() < 1e-15);
        assert!((form_factor(&floor, &wall) - want).abs() < 1e-15);
    }

    #[test]
    fn back_to_back_and_collinear_give_zero() {
        let i = Piece::new(DVec2::new(0.0, 0.0), DVec2::new(1.0, 0.0), 0);
        let below = Piece::new(DVec2::new(0.0, -1.0), DVec2::new(1.0, -1.0), 1);
        assert_eq!(form_factor(&i, &below), 0.0);
        let along = Piece::new(DVec2::new(2.0, 0.0), DVec2::new(3.0, 0.0), 1);
        assert_eq!(form_factor(&i, &along), 0.0);
    }
}

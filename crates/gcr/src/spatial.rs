//! A uniform hash grid over axis-aligned boxes, for "which elements can a Gaussian reach" queries.
//!
//! Gaussians are cut off where exp(−|x − w|²/d²) falls below a relative tolerance, so every
//! integral or evaluation only touches the elements inside a ball of radius ρ = d·√(ln 1/tol)
//! (ARCHITECTURE.md: "Gaussian support cut-off: index cells spatially"). A uniform grid is the
//! simplest structure that makes those ball queries output-sensitive; its cell size is chosen
//! from the typical query radius.

use glam::DVec3;
use std::collections::HashMap;

/// The exponent factor a = 1/d² of a Gaussian exp(−|x − w|²/d²) of width d, as
/// [`gauss_integrals::support_radius`] and the closed forms take it.
pub fn width_a(d: f64) -> f64 {
    1.0 / (d * d)
}

/// A uniform grid of buckets holding item ids whose bounding boxes overlap each bucket.
#[derive(Clone, Debug)]
pub struct BoxGrid {
    cell: f64,
    buckets: HashMap<[i64; 3], Vec<u32>>,
    boxes: Vec<(DVec3, DVec3)>,
}

impl BoxGrid {
    /// Indexes `boxes` (min, max) with bucket size `cell` (> 0). Items larger than
    /// `max_cells_per_item` buckets per axis are still indexed (in every bucket they overlap),
    /// so a few huge items cost memory proportional to their size in buckets; pick `cell` about
    /// the typical query radius.
    pub fn new(boxes: Vec<(DVec3, DVec3)>, cell: f64) -> Self {
        let cell = if cell.is_finite() && cell > 0.0 {
            cell
        } else {
            1.0
        };
        let mut buckets: HashMap<[i64; 3], Vec<u32>> = HashMap::new();
        for (i, (lo, hi)) in boxes.iter().enumerate() {
            let (a, b) = (key(*lo, cell), key(*hi, cell));
            for x in a[0]..=b[0] {
                for y in a[1]..=b[1] {
                    for z in a[2]..=b[2] {
                        buckets.entry([x, y, z]).or_default().push(i as u32);
                    }
                }
            }
        }
        Self {
            cell,
            buckets,
            boxes,
        }
    }

    /// Ids of the items whose boxes intersect the ball (centre, radius), each once, ascending.
    pub fn query_ball(&self, centre: DVec3, radius: f64, out: &mut Vec<u32>) {
        out.clear();
        if self.boxes.is_empty() || radius.is_nan() || radius < 0.0 || !centre.is_finite() {
            return;
        }
        let r = DVec3::splat(radius);
        let (a, b) = (key(centre - r, self.cell), key(centre + r, self.cell));
        // Bucket count of the ball in f64: keys saturate at ±i64::MAX for huge balls or tiny
        // buckets, where integer spans would overflow.
        let span: f64 = (0..3).map(|i| (b[i] as f64 - a[i] as f64) + 1.0).product();
        if span > self.buckets.len() as f64 {
            // The ball covers more buckets than exist: test every item instead.
            out.extend((0..self.boxes.len() as u32).filter(|&i| self.box_hits(i, centre, radius)));
            return;
        }
        for x in a[0]..=b[0] {
            for y in a[1]..=b[1] {
                for z in a[2]..=b[2] {
                    if let Some(items) = self.buckets.get(&[x, y, z]) {
                        out.extend(
                            items
                                .iter()
                                .copied()
                                .filter(|&i| self.box_hits(i, centre, radius)),
                        );
                    }
                }
            }
        }
        out.sort_unstable();
        out.dedup();
    }

    /// Whether item `i`'s box intersects the ball (c, r): the test [`BoxGrid::query_ball`]
    /// applies, for callers that filter a candidate list of their own.
    pub fn box_hits(&self, i: u32, c: DVec3, r: f64) -> bool {
        let (lo, hi) = self.boxes[i as usize];
        c.clamp(lo, hi).distance_squared(c) <= r * r
    }
}

fn key(p: DVec3, cell: f64) -> [i64; 3] {
    let k = (p / cell).floor();
    [k.x as i64, k.y as i64, k.z as i64]
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(48))]
        #[test]
        fn ball_query_equals_brute_force(
            pts in prop::collection::vec((-5.0f64..5.0, -5.0f64..5.0, -5.0f64..5.0, 0.0f64..1.0), 1..80),
            c in (-6.0f64..6.0, -6.0f64..6.0, -6.0f64..6.0),
            r in 0.0f64..4.0,
            cell in 0.1f64..3.0,
        ) {
            let boxes: Vec<(DVec3, DVec3)> = pts.iter().map(|&(x, y, z, s)| {
                let p = DVec3::new(x, y, z);
                (p, p + DVec3::splat(s))
            }).collect();
            let grid = BoxGrid::new(boxes.clone(), cell);
            let centre = DVec3::new(c.0, c.1, c.2);
            let mut got = Vec::new();
            grid.query_ball(centre, r, &mut got);
            let want: Vec<u32> = (0..boxes.len() as u32)
                .filter(|&i| { let (lo, hi) = boxes[i as usize]; centre.clamp(lo, hi).distance(centre) <= r })
                .collect();
            prop_assert_eq!(got, want);
        }
    }

    #[test]
    fn support_radius_matches_the_gaussian() {
        let r = gauss_integrals::support_radius(width_a(2.0), 1e-12);
        assert!(((-(r / 2.0).powi(2)).exp() - 1e-12).abs() < 1e-20);
        let mut out = vec![7];
        BoxGrid::new(vec![], 1.0).query_ball(DVec3::ZERO, f64::NAN, &mut out);
        assert!(out.is_empty());
    }

    /// Buckets far smaller than the ball (keys saturate) must neither hang nor overflow.
    #[test]
    fn huge_balls_in_tiny_buckets_fall_back_to_a_scan() {
        let mut out = Vec::new();
        BoxGrid::new(vec![], 1e-300).query_ball(DVec3::ONE, 1.0, &mut out);
        assert!(out.is_empty());
        let grid = BoxGrid::new(vec![(DVec3::ZERO, DVec3::ZERO)], 1e-300);
        grid.query_ball(DVec3::ONE, 2.0, &mut out);
        assert_eq!(out, vec![0]);
        grid.query_ball(DVec3::ONE, f64::INFINITY, &mut out);
        assert_eq!(out, vec![0]);
    }
}

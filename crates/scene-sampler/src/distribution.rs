//! Sampling building blocks shared by every sampler of the workspace: a discrete distribution
//! over weighted items (pbrt-v4's `PiecewiseConstant1D`, discrete) and the uniform warp onto a
//! triangle. The surface parameterization ([`crate::SurfaceSampler`]), the emitter table
//! ([`crate::EmitterTable`]), gcr's gathers and shot rays, and the reference path tracers of
//! `baselines` draw through these, so that one table and one warp serve all.

/// A discrete distribution: item i is drawn with probability w_i / Σ w.
///
/// `cdf[i]` = (w_0 + … + w_{i−1}) / Σ w, with `cdf[n] = 1` exactly; [`Discrete::sample`] returns the
/// i with `cdf[i] ≤ u < cdf[i+1]` (items of weight 0 are never drawn).
#[derive(Clone, Debug, PartialEq)]
pub struct Discrete {
    cdf: Vec<f64>,
    total: f64,
}

impl Discrete {
    /// The distribution of non-negative finite `weights`; `None` when they are empty, not all
    /// finite and non-negative, or sum to 0.
    pub fn new(weights: &[f64]) -> Option<Self> {
        if weights.iter().any(|w| !w.is_finite() || *w < 0.0) {
            return None;
        }
        let total: f64 = weights.iter().sum();
        if !(total > 0.0 && total.is_finite()) {
            return None;
        }
        let mut cdf = Vec::with_capacity(weights.len() + 1);
        let mut acc = 0.0;
        cdf.push(0.0);
        for w in weights {
            acc += w;
            cdf.push(acc / total);
        }
        *cdf.last_mut().expect("non-empty") = 1.0;
        Some(Self { cdf, total })
    }

    /// Number of items.
    pub fn len(&self) -> usize {
        self.cdf.len() - 1
    }

    /// Always false: a distribution has at least one item of positive weight.
    pub fn is_empty(&self) -> bool {
        false
    }

    /// The sum of the weights.
    pub fn total(&self) -> f64 {
        self.total
    }

    /// The probability of item `i`.
    pub fn probability(&self, i: usize) -> f64 {
        self.cdf[i + 1] - self.cdf[i]
    }

    /// The cumulative table (`len() + 1` entries, from 0 to 1).
    pub fn cdf(&self) -> &[f64] {
        &self.cdf
    }

    /// The item of `u ∈ [0, 1)` (`u` ≥ 1 gives the last item).
    pub fn sample(&self, u: f64) -> usize {
        (self.cdf.partition_point(|&c| c <= u).saturating_sub(1)).min(self.len() - 1)
    }

    /// [`Discrete::sample`] and `u` remapped to [0, 1] within the item's interval, so that one
    /// random number picks the item and a position in it.
    pub fn sample_remapped(&self, u: f64) -> (usize, f64) {
        let i = self.sample(u);
        let (lo, hi) = (self.cdf[i], self.cdf[i + 1]);
        (i, ((u - lo) / (hi - lo)).clamp(0.0, 1.0))
    }
}

/// Barycentric coordinates (b1, b2) of a point uniform on a triangle from `u ∈ [0,1)²`, by the
/// square-root warp: with s = √u0, (b1, b2) = (s·(1 − u1), s·u1), the point p0 + b1·(p1 − p0) +
/// b2·(p2 − p0) (pbrt-v4's `SampleUniformTriangle` up to the order of the corners).
pub fn uniform_triangle(u: [f64; 2]) -> [f64; 2] {
    let s = u[0].sqrt();
    [s * (1.0 - u[1]), s * u[1]]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn items_are_drawn_in_proportion_to_their_weights() {
        let d = Discrete::new(&[1.0, 0.0, 3.0]).unwrap();
        assert_eq!(d.len(), 3);
        assert_eq!(d.total(), 4.0);
        assert_eq!(d.probability(0), 0.25);
        assert_eq!(d.probability(1), 0.0);
        assert_eq!(d.probability(2), 0.75);
        assert_eq!(d.sample(0.0), 0);
        assert_eq!(d.sample(0.2499), 0);
        assert_eq!(d.sample(0.25), 2, "the empty item is skipped");
        assert_eq!(d.sample(0.9999), 2);
        assert_eq!(d.sample(1.0), 2);
        let (i, r) = d.sample_remapped(0.625);
        assert_eq!(i, 2);
        assert!((r - 0.5).abs() < 1e-15);
        let n = 100_000;
        let hits = (0..n)
            .filter(|k| d.sample((*k as f64 + 0.5) / n as f64) == 0)
            .count();
        assert!((hits as f64 / n as f64 - 0.25).abs() < 1e-4);
    }

    #[test]
    fn bad_weights_give_no_distribution() {
        assert!(Discrete::new(&[]).is_none());
        assert!(Discrete::new(&[0.0, 0.0]).is_none());
        assert!(Discrete::new(&[1.0, -1.0]).is_none());
        assert!(Discrete::new(&[1.0, f64::NAN]).is_none());
        assert!(Discrete::new(&[f64::INFINITY]).is_none());
    }

    /// The warp is uniform: the mean of the barycentrics is (1/3, 1/3), and every point is inside.
    #[test]
    fn the_triangle_warp_is_uniform_and_inside() {
        let n = 200;
        let (mut m1, mut m2) = (0.0, 0.0);
        for i in 0..n {
            for j in 0..n {
                let [b1, b2] =
                    uniform_triangle([(i as f64 + 0.5) / n as f64, (j as f64 + 0.5) / n as f64]);
                assert!(b1 >= 0.0 && b2 >= 0.0 && b1 + b2 <= 1.0);
                m1 += b1;
                m2 += b2;
            }
        }
        let k = (n * n) as f64;
        assert!((m1 / k - 1.0 / 3.0).abs() < 1e-3 && (m2 / k - 1.0 / 3.0).abs() < 1e-3);
    }
}

//! Multiple importance sampling of direct light (Veach & Guibas 1995, the power heuristic β = 2).
//!
//! A receiver's direct light E·G is sampled two ways: by **emitter sampling** (a point x on an
//! emitter with area density p_e(x), estimator E·G/p_e) and by **cosine sampling** (a cosine-
//! weighted ray that happens to hit an emitter, estimator E: the density G per unit area cancels
//! the geometry term). With n_e emitter and n_c cosine samples per receiver, a = n_e·p_e and
//! b = n_c·G, the power heuristic weights the two by a²/(a² + b²) and b²/(a² + b²). Both weights
//! below are written with ratios so that G → ∞ (a receiver at the edge where an emitter meets it)
//! gives the limits 0 and 1/n_c, not ∞/∞.
//!
//! ```
//! use scene_sampler::PowerHeuristic;
//! let mis = PowerHeuristic::ONE_EACH;
//! // Where the two densities agree, each technique gets half: E·G/p_e · ½ and E · ½.
//! assert_eq!(mis.light(2.0, 2.0), 0.5);
//! assert_eq!(mis.cosine(2.0, 2.0), 0.5);
//! ```

/// The power heuristic for n_e emitter samples and n_c cosine samples per receiver (module docs).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PowerHeuristic {
    /// n_e: emitter samples per receiver.
    pub light_samples: f64,
    /// n_c: cosine samples per receiver.
    pub cosine_samples: f64,
}

impl PowerHeuristic {
    /// One sample of each technique (the path tracers' next-event estimation at every vertex).
    pub const ONE_EACH: Self = Self {
        light_samples: 1.0,
        cosine_samples: 1.0,
    };

    /// Contribution per unit emission of one emitter-sampled point with geometry term `g` and area
    /// density `p_e`, the 1/n_e of the average included: G·a/(a² + b²) = (G/a)/(1 + (b/a)²). 0 when
    /// either is 0, NaN or the result overflows.
    pub fn light(&self, g: f64, p_e: f64) -> f64 {
        let a = self.light_samples * p_e;
        if !(g > 0.0 && a > 0.0) {
            return 0.0;
        }
        let r = self.cosine_samples * g / a;
        let w = g / a / (1.0 + r * r);
        if w.is_finite() { w } else { 0.0 }
    }

    /// Contribution per unit emission of one cosine ray that hits an emitter point with geometry
    /// term `g` (the density per unit area the ray had) and emitter density `p_e` there, the 1/n_c
    /// of the average included: b²/(n_c·(a² + b²)) = 1/(n_c·(1 + (a/b)²)). 1/n_c where `g` is
    /// infinite or nothing samples the face (p_e ≤ 0); 0 where `g` ≤ 0.
    pub fn cosine(&self, g: f64, p_e: f64) -> f64 {
        let a = self.light_samples * p_e;
        if g == f64::INFINITY || a.is_nan() || a <= 0.0 {
            return 1.0 / self.cosine_samples;
        }
        if g.is_nan() || g <= 0.0 {
            return 0.0;
        }
        let r = a / (self.cosine_samples * g);
        1.0 / (self.cosine_samples * (1.0 + r * r))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The two weights of one point sum to its full estimate: light·(n_e·p_e/G) + cosine·n_c = 1.
    #[test]
    fn the_weights_partition_unity() {
        for (ne, nc) in [(1.0, 1.0), (4.0, 16.0), (64.0, 1.0)] {
            let mis = PowerHeuristic {
                light_samples: ne,
                cosine_samples: nc,
            };
            for (g, p) in [(1e-6, 3.0), (0.5, 0.5), (7.0, 1e-3), (1e12, 2.0)] {
                let sum = mis.light(g, p) * ne * p / g + mis.cosine(g, p) * nc;
                assert!(
                    (sum - 1.0).abs() < 1e-12,
                    "n = ({ne}, {nc}), g = {g}, p = {p}: {sum}"
                );
            }
        }
    }

    /// The edge limits: G infinite, G zero, nothing sampling the face, NaN.
    #[test]
    fn the_limits_are_finite() {
        let mis = PowerHeuristic {
            light_samples: 2.0,
            cosine_samples: 8.0,
        };
        assert_eq!(mis.light(f64::INFINITY, 1.0), 0.0);
        assert_eq!(mis.cosine(f64::INFINITY, 1.0), 1.0 / 8.0);
        assert_eq!(mis.light(0.0, 1.0), 0.0);
        assert_eq!(mis.cosine(0.0, 1.0), 0.0);
        assert_eq!(mis.light(1.0, 0.0), 0.0);
        assert_eq!(mis.cosine(1.0, 0.0), 1.0 / 8.0);
        assert_eq!(mis.light(f64::NAN, 1.0), 0.0);
        assert_eq!(mis.light(1.0, f64::NAN), 0.0);
        assert_eq!(mis.cosine(1.0, f64::NAN), 1.0 / 8.0);
    }
}

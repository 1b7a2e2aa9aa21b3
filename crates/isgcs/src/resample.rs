//! Resampling (sec. 2.5, definitions 4–7): finding critical regions of the input domain, where
//! the caller should evaluate the goal function on new samples.

use crate::network::{Isgcs, IsgcsError};

impl Isgcs {
    /// σ (definition 6) for every cell: τ_i ≥ ω · mean τ. All false when every resource is 0.
    pub fn critical_cells(&self) -> Vec<bool> {
        let z = self.len();
        let mean = (0..z).map(|i| self.resource(i)).sum::<f64>() / z.max(1) as f64;
        (0..z)
            .map(|i| mean > 0.0 && self.resource(i) >= self.params().omega * mean)
            .collect()
    }

    /// φ_A (definition 7, eq. 2.23): `x` lies in a critical region if the critical sub-network's
    /// activation Υ_{A_CR}(x) (eq. 2.22 over the critical cells) reaches φ, or if the whole
    /// network's Υ_A(x) stays below φ (x outside the network). `critical` is
    /// [`Isgcs::critical_cells`].
    ///
    /// (`is_critical`, which `gcr` uses, tests the BMU's criticality instead of Υ_{A_CR}; it
    /// is kept as it is.)
    pub fn in_critical_region(&self, x: &[f64], critical: &[bool]) -> bool {
        let mut cells = Vec::new();
        self.support(x, &mut cells);
        let all: f64 = cells.iter().map(|&(_, a)| a).sum();
        let crit: f64 = cells
            .iter()
            .filter(|&&(i, _)| critical.get(i).copied().unwrap_or(false))
            .map(|&(_, a)| a)
            .sum();
        let phi = self.params().phi;
        crit >= phi || all < phi
    }

    /// The resampling scan of sec. 2.5: the box [lo, hi] is scanned on a grid of
    /// `steps_per_axis` points per axis (the centres of the grid's boxes); where a grid point
    /// lies in a critical region (eq. 2.23) the step is decreased, and the `refine` points per
    /// axis of a sub-grid of that grid box are returned as positions for new samples (the caller
    /// evaluates the goal there and adds them to its training set). Errors for an invalid box or
    /// more than 10⁷ grid or output points.
    pub fn resample_positions(
        &self,
        lo: &[f64],
        hi: &[f64],
        steps_per_axis: usize,
        refine: usize,
    ) -> Result<Vec<Vec<f64>>, IsgcsError> {
        let n = self.input_dim();
        let ok_box = lo.len() == n
            && hi.len() == n
            && lo
                .iter()
                .zip(hi)
                .all(|(a, b)| a.is_finite() && b.is_finite() && a < b);
        let count = |per: usize| (per as f64).powi(n as i32);
        if !ok_box || steps_per_axis == 0 || refine == 0 || count(steps_per_axis) > 1e7 {
            return Err(IsgcsError::Invalid(format!(
                "resample: box {lo:?}..{hi:?} must be n = {n} finite increasing bounds, \
                 with 1 ≤ steps_per_axis^n ≤ 1e7 (steps {steps_per_axis}) and refine ≥ 1"
            )));
        }
        let critical = self.critical_cells();
        let step: Vec<f64> = lo
            .iter()
            .zip(hi)
            .map(|(a, b)| (b - a) / steps_per_axis as f64)
            .collect();
        let mut out = Vec::new();
        let mut idx = vec![0usize; n];
        let mut x = vec![0.0; n];
        loop {
            for a in 0..n {
                x[a] = lo[a] + (idx[a] as f64 + 0.5) * step[a];
            }
            if self.in_critical_region(&x, &critical) {
                if count(refine) * (out.len() as f64 + 1.0) > 1e7 {
                    return Err(IsgcsError::Invalid(
                        "resample: more than 1e7 positions; use coarser steps".into(),
                    ));
                }
                let mut sub = vec![0usize; n];
                loop {
                    out.push(
                        (0..n)
                            .map(|a| {
                                lo[a]
                                    + (idx[a] as f64 + (sub[a] as f64 + 0.5) / refine as f64)
                                        * step[a]
                            })
                            .collect(),
                    );
                    if !next(&mut sub, refine) {
                        break;
                    }
                }
            }
            if !next(&mut idx, steps_per_axis) {
                break;
            }
        }
        Ok(out)
    }
}

/// Advances a multi-index with `per` values per digit; false after the last one.
fn next(idx: &mut [usize], per: usize) -> bool {
    for d in idx.iter_mut() {
        *d += 1;
        if *d < per {
            return true;
        }
        *d = 0;
    }
    false
}

#[cfg(test)]
mod tests {
    use crate::{Isgcs, Params};

    #[test]
    fn outside_regions_and_high_error_regions_are_critical() {
        // Trained only on x < 0.5 (a smooth target), the right half lies outside the network.
        let init = vec![vec![0.1, 0.2], vec![0.4, 0.2], vec![0.25, 0.8]];
        let mut net = Isgcs::new(Params::thesis(), 2, 1, 2, init).unwrap();
        for i in 0..30_000u64 {
            let x = 0.5 * ((i as f64) * 0.754_877_666).fract();
            let y = ((i as f64) * 0.569_840_291).fract();
            net.train(&[x, y], &[x + y], None);
        }
        let pos = net
            .resample_positions(&[0.0, 0.0], &[1.0, 1.0], 10, 2)
            .unwrap();
        assert!(!pos.is_empty());
        let right = pos.iter().filter(|p| p[0] > 0.6).count();
        // Every grid point with x > 0.6 (40 of them, 4 sub-points each) is outside.
        assert_eq!(right, 160, "{pos:?}");
        assert!(
            pos.iter()
                .all(|p| p.iter().all(|v| (0.0..=1.0).contains(v)))
        );
        // Inside the trained half, only regions dominated by critical cells are returned: far
        // fewer than the whole half (measured: 36 of 120).
        let left = pos.iter().filter(|p| p[0] > 0.1 && p[0] < 0.4).count();
        assert!(left < 60, "{left} of 120 inner positions flagged");
        // A critical cell's own centre lies in a critical region when it dominates there.
        let critical = net.critical_cells();
        assert!(critical.iter().any(|&c| c));
        assert!(critical.iter().any(|&c| !c));
        assert!(net.resample_positions(&[0.0, 0.0], &[1.0], 10, 2).is_err());
        assert!(
            net.resample_positions(&[0.0, 0.0], &[1.0, 0.0], 10, 2)
                .is_err()
        );
        assert!(
            net.resample_positions(&[0.0, 0.0], &[1.0, 1.0], 10_000, 2)
                .is_err()
        );
    }
}

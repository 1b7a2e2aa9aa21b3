//! Smooth test functions for measuring approximation error (the example and the benchmarks).

/// Franke's 2-D test function on [0, 1]² (Franke 1979), the usual scattered-data benchmark.
pub fn franke(x: f64, y: f64) -> f64 {
    0.75 * (-((9.0 * x - 2.0).powi(2) + (9.0 * y - 2.0).powi(2)) / 4.0).exp()
        + 0.75 * (-(9.0 * x + 1.0).powi(2) / 49.0 - (9.0 * y + 1.0) / 10.0).exp()
        + 0.5 * (-((9.0 * x - 7.0).powi(2) + (9.0 * y - 3.0).powi(2)) / 4.0).exp()
        - 0.2 * (-(9.0 * x - 4.0).powi(2) - (9.0 * y - 7.0).powi(2)).exp()
}

/// A smooth function on [0, 1]⁶: a broad bump modulated by a plane wave, plus a product term
/// and a cosine. Reads the first six coordinates of `x` (shorter inputs count as zero-padded).
pub fn smooth6(x: &[f64]) -> f64 {
    let c = |i: usize| x.get(i).copied().unwrap_or(0.0);
    let r2: f64 = (0..6).map(|i| (c(i) - 0.5) * (c(i) - 0.5)).sum();
    (-r2).exp() * (1.0 + 0.5 * (2.0 * c(0) + c(1) - c(2)).sin()) + 0.3 * c(3) * c(4)
        - 0.2 * (2.0 * c(5)).cos()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn known_values() {
        // Franke's function peaks near (0.2, 0.2); reference value computed from the formula.
        let f = franke(2.0 / 9.0, 2.0 / 9.0);
        let expect = 0.75
            + 0.75 * (-(3.0f64).powi(2) / 49.0 - 0.3).exp()
            + 0.5 * (-(25.0 + 1.0) / 4.0f64).exp()
            - 0.2 * (-4.0 - 25.0f64).exp();
        assert!((f - expect).abs() < 1e-14, "{f} vs {expect}");
        let centre = smooth6(&[0.5; 6]);
        let expect = 1.0 + 0.5 * (1.0f64).sin() + 0.3 * 0.25 - 0.2 * (1.0f64).cos();
        assert!((centre - expect).abs() < 1e-14);
    }
}

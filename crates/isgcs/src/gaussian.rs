//! The Gaussian factor e^(−e), e ≥ 0, of every cell's activation (eq. 2.1), in straight-line
//! arithmetic that the compiler vectorizes across a loop.
//!
//! A network's training step and its evaluations take one such factor per cell in reach, and at
//! a thousand cells in 6-D (half of them in reach) the library call `f64::exp` was the larger
//! part of a step. This form trades its correct rounding for at most a few units in the last
//! place (the test measures the error against `f64::exp`) and no call, no branch and no table:
//!
//! 1. Range reduction (Cody–Waite): −e = k·ln 2 + r with k = round(−e / ln 2) and |r| ≤ ln 2 / 2,
//!    ln 2 split into a high part exact in 32 bits and a low part, so k·ln2_hi is exact.
//! 2. e^r by its Taylor series to degree 13 (remainder |r|¹⁴/14! < 5·10⁻¹⁸ relative) in Estrin's
//!    form, so that the terms of one factor and of neighbouring ones overlap in the pipeline.
//! 3. 2^k from the exponent bits; k is read from the same sum that rounded it (the "magic
//!    number" 1.5·2⁵² rounds to an integer in the last bits without a rounding instruction,
//!    which SSE2 lacks).
//!
//! Beyond e = 708 (2^k no longer normal) the factor is 0; the true value is below 3·10⁻³⁰⁸.

/// 1.5·2⁵²: adding it rounds any |t| < 2⁵¹ to an integer held in the low mantissa bits.
const ROUND: f64 = 6_755_399_441_055_744.0;
/// ln 2, high part (its last 32 mantissa bits zero, so k·LN2_HI is exact for |k| < 2²¹).
const LN2_HI: f64 = f64::from_bits(0x3FE6_2E42_FEE0_0000);
/// ln 2 − LN2_HI.
const LN2_LO: f64 = 1.908_214_929_270_587_7e-10;
/// Largest exponent e for which e^(−e) is a normal number.
const LAST: f64 = 708.0;

/// e^(−e) for e ≥ 0 (a Gaussian's factor at squared scaled distance e), within a few units in
/// the last place of `(-e).exp()`; 0 for e > 708 and for e = +∞, NaN for NaN.
#[inline(always)]
pub fn gaussian(e: f64) -> f64 {
    debug_assert!(e >= 0.0 || e.is_nan(), "gaussian({e}) takes e ≥ 0");
    let x = -e.min(LAST);
    // ⟨k = round(x / ln 2), r = x − k ln 2⟩
    let t = x * std::f64::consts::LOG2_E + ROUND;
    let k = t - ROUND;
    let r = (x - k * LN2_HI) - k * LN2_LO;
    // ⟨e^r, Taylor to degree 13, in Estrin's form (a dependency chain of 8 operations, not 26)⟩
    let r2 = r * r;
    let r4 = r2 * r2;
    let r8 = r4 * r4;
    let p01 = 1.0 + r;
    let p23 = 1.0 / 2.0 + r * (1.0 / 6.0);
    let p45 = 1.0 / 24.0 + r * (1.0 / 120.0);
    let p67 = 1.0 / 720.0 + r * (1.0 / 5_040.0);
    let p89 = 1.0 / 40_320.0 + r * (1.0 / 362_880.0);
    let p1011 = 1.0 / 3_628_800.0 + r * (1.0 / 39_916_800.0);
    let p1213 = 1.0 / 479_001_600.0 + r * (1.0 / 6_227_020_800.0);
    let q0 = p01 + r2 * p23;
    let q1 = p45 + r2 * p67;
    let q2 = p89 + r2 * p1011;
    let p = (q0 + r4 * q1) + r8 * (q2 + r4 * p1213);
    // ⟨2^k from k's bits in t⟩
    let k_int = t.to_bits().wrapping_sub(ROUND.to_bits()) as i64;
    let scale = f64::from_bits(((k_int + 1023) << 52) as u64);
    // (`min` above would have swallowed a NaN: pass it on.)
    if e > LAST {
        0.0
    } else if e.is_nan() {
        e
    } else {
        p * scale
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Units in the last place between `a` and the reference `b`.
    fn ulps(a: f64, b: f64) -> f64 {
        (a - b).abs() / (b * f64::EPSILON)
    }

    #[test]
    fn matches_the_library_exponential_to_a_few_ulps() {
        let mut worst = 0.0f64;
        // Dense over the Gaussians' working range, then out to the last normal value.
        for i in 0..=2_000_000 {
            let e = i as f64 * 1e-5;
            worst = worst.max(ulps(gaussian(e), (-e).exp()));
        }
        for i in 0..=688_000 {
            let e = 20.0 + i as f64 * 1e-3;
            worst = worst.max(ulps(gaussian(e), (-e).exp()));
        }
        assert!(worst <= 2.0, "worst error {worst} ulps");
        assert_eq!(gaussian(0.0), 1.0);
    }

    #[test]
    fn is_zero_beyond_the_normal_range_and_at_infinity() {
        assert_eq!(gaussian(708.5), 0.0);
        assert_eq!(gaussian(1e300), 0.0);
        assert_eq!(gaussian(f64::INFINITY), 0.0);
        assert!(gaussian(707.9) > 0.0);
        assert!(gaussian(f64::NAN).is_nan());
    }
}

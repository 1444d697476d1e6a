//! Scalar math shared by host and target.
//!
//! Every transcendental function used by this crate is called through here, backed by the
//! `libm` crate, so the simulator on a laptop computes with the same code as the Cortex-M7
//! (std's `f32::sqrt` would otherwise shadow it on the host).

/// Square root.
#[inline]
pub fn sqrt(x: f32) -> f32 {
    libm::sqrtf(x)
}

/// Absolute value.
#[inline]
pub fn abs(x: f32) -> f32 {
    libm::fabsf(x)
}

/// Natural exponential.
#[inline]
pub fn exp(x: f32) -> f32 {
    libm::expf(x)
}

/// Natural logarithm.
#[inline]
pub fn ln(x: f32) -> f32 {
    libm::logf(x)
}

/// The smaller of `a` and `b` by a plain comparison (`b` if either is NaN). On the Cortex-M7
/// (ARMv7E-M, no `vminnm`) `f32::min` is a library call; this is two instructions.
#[inline]
pub fn min(a: f32, b: f32) -> f32 {
    if a < b { a } else { b }
}

/// The larger of `a` and `b` by a plain comparison (`b` if either is NaN); see [`min`].
#[inline]
pub fn max(a: f32, b: f32) -> f32 {
    if a > b { a } else { b }
}

/// Largest integer not above `x`.
#[inline]
pub fn floor(x: f32) -> f32 {
    libm::floorf(x)
}

/// Smallest integer not below `x`.
#[inline]
pub fn ceil(x: f32) -> f32 {
    libm::ceilf(x)
}

/// Nearest integer, halves away from zero.
#[inline]
pub fn round(x: f32) -> f32 {
    libm::roundf(x)
}

/// Sine (radians).
#[inline]
pub fn sin(x: f32) -> f32 {
    libm::sinf(x)
}

/// Cosine (radians).
#[inline]
pub fn cos(x: f32) -> f32 {
    libm::cosf(x)
}

/// Arc sine (radians), argument clamped to `[-1, 1]`.
#[inline]
pub fn asin(x: f32) -> f32 {
    libm::asinf(x.clamp(-1.0, 1.0))
}

/// Arc cosine (radians), argument clamped to `[-1, 1]`.
#[inline]
pub fn acos(x: f32) -> f32 {
    libm::acosf(x.clamp(-1.0, 1.0))
}

/// Four-quadrant arc tangent of `y / x` (radians).
#[inline]
pub fn atan2(y: f32, x: f32) -> f32 {
    libm::atan2f(y, x)
}

/// Error function.
#[inline]
pub fn erf(x: f32) -> f32 {
    libm::erff(x)
}

/// Complementary error function `1 - erf(x)`, accurate in the tail.
#[inline]
pub fn erfc(x: f32) -> f32 {
    libm::erfcf(x)
}

/// `ln(sqrt(2 pi))`.
pub const LN_SQRT_2PI: f32 = 0.918_938_5;

/// Standard normal density.
#[inline]
pub fn normal_pdf(x: f32) -> f32 {
    exp(-0.5 * x * x - LN_SQRT_2PI)
}

/// Standard normal distribution function `P(X <= x)`.
#[inline]
pub fn normal_cdf(x: f32) -> f32 {
    0.5 * erfc(-x * core::f32::consts::FRAC_1_SQRT_2)
}

/// `ln P(X >= a)` for a standard normal `X`, finite for every finite `a` (asymptotic
/// expansion where `erfc` would underflow).
pub fn ln_normal_sf(a: f32) -> f32 {
    if a < 9.0 {
        ln(0.5 * erfc(a * core::f32::consts::FRAC_1_SQRT_2))
    } else {
        // Mills ratio: P(X >= a) ~ phi(a) / a * (1 - 1/a^2 + 3/a^4); relative error < 3e-5 here.
        let inv2 = 1.0 / (a * a);
        -0.5 * a * a - LN_SQRT_2PI - ln(a) + ln(1.0 - inv2 + 3.0 * inv2 * inv2)
    }
}

/// `ln(sum(exp(terms)))` without overflow or underflow (`-inf` for no terms, or all `-inf`).
pub fn ln_sum_exp(terms: &[f32]) -> f32 {
    let top = terms.iter().copied().fold(f32::NEG_INFINITY, max);
    if !top.is_finite() {
        return top;
    }
    let sum: f32 = terms.iter().map(|&t| exp(t - top)).sum();
    top + ln(sum)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn normal_tail_is_continuous_across_the_switch_and_exact_below_it() {
        assert!((ln_normal_sf(0.0) - ln(0.5)).abs() < 1e-6);
        let below = ln_normal_sf(8.9999);
        let above = ln_normal_sf(9.0);
        assert!((below - above).abs() < 1e-3, "{below} vs {above}");
        // Exact value of ln P(X >= 6) = ln(9.8659e-10).
        assert!(
            (ln_normal_sf(6.0) - (-20.7367)).abs() < 1e-3,
            "{}",
            ln_normal_sf(6.0)
        );
        assert!(ln_normal_sf(40.0).is_finite());
        assert!(ln_normal_sf(-10.0).abs() < 1e-6);
    }
}

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

/// Tangent (radians).
#[inline]
pub fn tan(x: f32) -> f32 {
    libm::tanf(x)
}

/// `x` limited to `[lo, hi]` (NaN stays NaN). Unlike `f32::clamp` it never panics: a limit
/// that came out NaN or inverted (`lo > hi`, then `lo` wins) must not stop a flight
/// controller, and the panic's message would pull `core`'s float formatting into the image.
#[inline]
pub fn clamp(x: f32, lo: f32, hi: f32) -> f32 {
    if x < lo {
        lo
    } else if x > hi {
        hi
    } else {
        x
    }
}

/// `magnitude`'s absolute value with `sign`'s sign.
#[inline]
pub fn copysign(magnitude: f32, sign: f32) -> f32 {
    libm::copysignf(magnitude, sign)
}

/// An angle brought into `(-pi, pi]`, rad.
#[inline]
pub fn wrap_pi(angle: f32) -> f32 {
    use core::f32::consts::{PI, TAU};
    let wrapped = angle - TAU * floor((angle + PI) / TAU);
    if wrapped <= -PI {
        wrapped + TAU
    } else {
        wrapped
    }
}

/// Arc sine (radians), argument clamped to `[-1, 1]`.
#[inline]
pub fn asin(x: f32) -> f32 {
    libm::asinf(clamp(x, -1.0, 1.0))
}

/// Arc cosine (radians), argument clamped to `[-1, 1]`.
#[inline]
pub fn acos(x: f32) -> f32 {
    libm::acosf(clamp(x, -1.0, 1.0))
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
    ln_sum_exp_from(terms, top)
}

/// [`ln_sum_exp`] when the largest term, `top`, is known already.
pub fn ln_sum_exp_from(terms: &[f32], top: f32) -> f32 {
    if !top.is_finite() {
        return top;
    }
    let sum: f32 = terms.iter().map(|&t| exp_nonpositive(t - top)).sum();
    top + ln(sum)
}

/// `e^x` for `x <= 0` (what [`ln_sum_exp`] takes), within about two units in the last place
/// of `libm::expf`, in about half its instructions: `x = k ln 2 + r` with `|r| <= ln 2 / 2`
/// (Cody and Waite's two-part `ln 2`), `e^r` by its Taylor polynomial of degree 7 (truncation
/// under 5e-9 relative), and `2^k` put in the exponent bits. Below `-87` (where `2^k` would
/// leave the normal range) and for NaN it is `libm::expf` itself.
#[inline]
pub fn exp_nonpositive(x: f32) -> f32 {
    const LN2_HI: f32 = 0.693_145_75;
    const LN2_LO: f32 = 1.428_606_8e-6;
    // One comparison for both exceptions: NaN fails it as anything below -87 does.
    if x >= -87.0 {
        let t = x * core::f32::consts::LOG2_E;
        // The nearest whole number: `-t >= 0`, and truncating `-t + 1/2` rounds it.
        let k = -((0.5 - t) as i32);
        let kf = k as f32;
        let r = (x - kf * LN2_HI) - kf * LN2_LO;
        let p = 1.0
            + r * (1.0
                + r * (0.5
                    + r * (1.0 / 6.0
                        + r * (1.0 / 24.0
                            + r * (1.0 / 120.0 + r * (1.0 / 720.0 + r * (1.0 / 5040.0)))))));
        return p * f32::from_bits(((k + 127) as u32) << 23);
    }
    exp(x)
}

/// Sorts a short slice by `less` (insertion sort, stable). The hull's points and a face's
/// cuts are a few dozen values at most; `core`'s pattern-defeating quicksort would cost the
/// firmware about 9 KB of flash for them.
pub fn sort_small_by<T: Copy>(items: &mut [T], less: impl Fn(&T, &T) -> bool) {
    for i in 1..items.len() {
        let item = items[i];
        let mut j = i;
        while j > 0 && less(&item, &items[j - 1]) {
            items[j] = items[j - 1];
            j -= 1;
        }
        items[j] = item;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn exp_nonpositive_is_libm_to_two_units_in_the_last_place() {
        let mut worst = 0.0f32;
        let mut x = 0.0f32;
        while x > -90.0 {
            let (fast, reference) = (exp_nonpositive(x), exp(x));
            if reference > 0.0 {
                let ulp = f32::from_bits(reference.to_bits() + 1) - reference;
                worst = max(worst, (fast - reference).abs() / ulp);
            } else {
                assert_eq!(fast, reference, "at {x}");
            }
            x -= 0.000_731;
        }
        assert!(worst <= 2.0, "{worst} units in the last place");
        assert_eq!(exp_nonpositive(0.0), 1.0);
        assert_eq!(exp_nonpositive(f32::NEG_INFINITY), 0.0);
        assert!(exp_nonpositive(f32::NAN).is_nan());
    }

    #[test]
    fn clamp_limits_keeps_nan_and_survives_bad_limits() {
        assert_eq!(clamp(2.0, -1.0, 1.0), 1.0);
        assert_eq!(clamp(-3.0, -1.0, 1.0), -1.0);
        assert_eq!(clamp(0.25, -1.0, 1.0), 0.25);
        assert!(clamp(f32::NAN, -1.0, 1.0).is_nan());
        assert_eq!(clamp(0.0, 1.0, -1.0), 1.0);
        assert_eq!(clamp(0.5, f32::NAN, 1.0), 0.5);
    }

    #[test]
    fn short_slices_sort_in_order_and_keep_equal_items_in_place() {
        let mut v = [3.0_f32, -1.0, 2.5, -1.0, 0.0, 7.0, 2.5];
        sort_small_by(&mut v, |a, b| a < b);
        assert_eq!(v, [-1.0, -1.0, 0.0, 2.5, 2.5, 3.0, 7.0]);
        let mut pairs = [(1, 'a'), (0, 'b'), (1, 'c'), (0, 'd')];
        sort_small_by(&mut pairs, |a, b| a.0 < b.0);
        assert_eq!(pairs, [(0, 'b'), (0, 'd'), (1, 'a'), (1, 'c')]);
        let mut empty: [f32; 0] = [];
        sort_small_by(&mut empty, |a, b| a < b);
    }

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

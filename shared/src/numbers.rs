//! Numbers written for people, without `core`'s float formatting.
//!
//! The firmware writes its state as text (`STATUSTEXT`, the mission's reasons). `core`'s `{}`
//! and `{:.N}` on an `f32` pull in its exact decimal conversion (Grisu with a Dragon4
//! fallback, about 14 KB of flash on the Cortex-M7: measured on the Pixhawk image). Text for
//! people needs a few digits, not the shortest round-trip form, so these wrappers round with
//! integer arithmetic: [`Fixed`] for `{:.N}`, [`Sci`] for `{:.Ne}`, [`Num`] for `{}`.

use core::fmt::{self, Display, Formatter, Write};

use crate::math;

/// Most decimals [`Fixed`] writes (beyond this an `f32` has no more digits to give).
const MAX_PLACES: u8 = 9;

/// `value` with `places` decimals, as `{:.N}` writes it (`-1.50`, `12.000`); `NaN`, `inf`
/// and `-inf` for the non-finite; values whose digits do not fit 19 are written as [`Sci`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Fixed(pub f32, pub u8);

/// `value` in scientific notation with `places` decimals of mantissa, as `{:.Ne}` writes it
/// (`1.234e5`, `-2.0e-3`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sci(pub f32, pub u8);

/// `value` with at most six significant digits and no trailing zeros (`0.002`, `200`,
/// `1.5e-7`): what `{}` is used for in text for people.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Num(pub f32);

fn non_finite(value: f32, f: &mut Formatter<'_>) -> Option<fmt::Result> {
    if value.is_nan() {
        Some(f.write_str("NaN"))
    } else if value.is_infinite() {
        Some(f.write_str(if value > 0.0 { "inf" } else { "-inf" }))
    } else {
        None
    }
}

fn pow10(places: u8) -> u64 {
    10u64.pow(u32::from(places))
}

/// `10^exponent` in f64 (exact up to 10^22, within an ulp or two beyond: text, not math).
fn pow10_f64(exponent: i32) -> f64 {
    let mut p = 1.0_f64;
    for _ in 0..exponent.unsigned_abs() {
        p *= 10.0;
    }
    if exponent < 0 { 1.0 / p } else { p }
}

/// Rounds a non-negative value half away from zero (saturating at `u64::MAX`).
fn round_to_u64(x: f64) -> u64 {
    (x + 0.5) as u64
}

/// `floor(log10(x))` for a finite `x > 0`.
fn decimal_exponent(x: f64) -> i32 {
    let mut e = 0;
    let mut p = 1.0_f64;
    while x >= p * 10.0 {
        p *= 10.0;
        e += 1;
    }
    while x < p {
        p /= 10.0;
        e -= 1;
    }
    e
}

/// Writes `digits / 10^places` with exactly `places` decimals.
fn write_scaled(
    negative: bool,
    digits: u64,
    places: u8,
    f: &mut (impl Write + ?Sized),
) -> fmt::Result {
    if let Ok(small) = u32::try_from(digits) {
        return write_scaled_u32(negative, small, places, f);
    }
    let scale = pow10(places);
    if negative && digits != 0 {
        f.write_char('-')?;
    }
    write!(f, "{}", digits / scale)?;
    if places > 0 {
        write!(
            f,
            ".{:0width$}",
            digits % scale,
            width = usize::from(places)
        )?;
    }
    Ok(())
}

/// [`write_scaled`] for digits that fit 32 bits (every value a text for people carries): the
/// digits by hand into a buffer and written once. `core::fmt`'s 64-bit integers and padding
/// cost the control step about 1,000 instructions a number on the Cortex-M7.
fn write_scaled_u32(
    negative: bool,
    digits: u32,
    places: u8,
    f: &mut (impl Write + ?Sized),
) -> fmt::Result {
    // Ten digits, up to MAX_PLACES leading zeros, the point and the sign.
    let places = places.min(MAX_PLACES);
    let mut text = [0u8; 24];
    let mut at = text.len();
    let mut left = digits;
    let mut written = 0u8;
    // The decimals, the point, then the integer's digits (at least one).
    loop {
        if written == places && places > 0 {
            at -= 1;
            text[at] = b'.';
        }
        at -= 1;
        text[at] = b'0' + (left % 10) as u8;
        left /= 10;
        written += 1;
        if left == 0 && written > places {
            break;
        }
    }
    if negative && digits != 0 {
        at -= 1;
        text[at] = b'-';
    }
    // Only ASCII digits, a point and a sign were written.
    f.write_str(core::str::from_utf8(&text[at..]).unwrap_or("?"))
}

impl Display for Fixed {
    fn fmt(&self, f: &mut Formatter<'_>) -> fmt::Result {
        let Self(value, places) = *self;
        if let Some(r) = non_finite(value, f) {
            return r;
        }
        let places = places.min(MAX_PLACES);
        // In f64 so that the scaling adds no error of its own to the f32's value.
        let scaled = f64::from(value).abs() * pow10(places) as f64;
        if scaled >= 1e18 {
            return Sci(value, places).fmt(f);
        }
        write_scaled(value < 0.0, round_to_u64(scaled), places, f)
    }
}

impl Display for Sci {
    fn fmt(&self, f: &mut Formatter<'_>) -> fmt::Result {
        let Self(value, places) = *self;
        if let Some(r) = non_finite(value, f) {
            return r;
        }
        let places = places.min(MAX_PLACES);
        let magnitude = f64::from(value).abs();
        let (mut mantissa, mut exponent) = if magnitude == 0.0 {
            (0u64, 0i32)
        } else {
            let exponent = decimal_exponent(magnitude);
            let m = magnitude / pow10_f64(exponent);
            (round_to_u64(m * pow10(places) as f64), exponent)
        };
        // Rounding (or log10's last bit) may leave the mantissa at 10 or just under 1.
        if mantissa >= 10 * pow10(places) {
            mantissa /= 10;
            exponent += 1;
        } else if mantissa != 0 && mantissa < pow10(places) {
            mantissa *= 10;
            exponent -= 1;
        }
        write_scaled(value < 0.0, mantissa, places, f)?;
        write!(f, "e{exponent}")
    }
}

impl Display for Num {
    fn fmt(&self, f: &mut Formatter<'_>) -> fmt::Result {
        let Self(value) = *self;
        if let Some(r) = non_finite(value, f) {
            return r;
        }
        let magnitude = math::abs(value);
        if magnitude != 0.0 && !(1e-4..1e9).contains(&magnitude) {
            // Six significant digits, trailing zeros of the mantissa dropped.
            let mut text: heapless::String<32> = heapless::String::new();
            write!(text, "{}", Sci(value, 5))?;
            let (mantissa, exponent) = text.split_once('e').unwrap_or((&text, "0"));
            return write!(f, "{}e{exponent}", trim_zeros(mantissa));
        }
        let integer_digits = if magnitude == 0.0 {
            1
        } else {
            decimal_exponent(f64::from(magnitude)) + 1
        };
        let places = (6 - integer_digits).clamp(0, i32::from(MAX_PLACES)) as u8;
        let mut text: heapless::String<32> = heapless::String::new();
        write!(text, "{}", Fixed(value, places))?;
        f.write_str(trim_zeros(&text))
    }
}

/// `12.500` -> `12.5`, `3.000` -> `3`, `-0.000` -> `0`; text without a point is kept.
fn trim_zeros(text: &str) -> &str {
    if !text.contains('.') {
        return text;
    }
    let trimmed = text.trim_end_matches('0').trim_end_matches('.');
    if trimmed == "-0" { "0" } else { trimmed }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::borrow::ToOwned;
    use std::format;

    #[test]
    fn fixed_writes_what_core_writes_for_ordinary_values() {
        for &v in &[
            0.0_f32,
            1.0,
            -1.5,
            12.345,
            -0.0004,
            999.9996,
            3.25e6,
            0.1,
            2.0 / 3.0,
            1e13,
        ] {
            for places in 0..=4u8 {
                let core = format!("{:.*}", usize::from(places), v);
                // core writes `-0.00` for a negative value that rounds to zero; we write `0.00`.
                let core = match core.strip_prefix('-') {
                    Some(rest) if rest.chars().all(|c| c == '0' || c == '.') => rest.to_owned(),
                    _ => core,
                };
                assert_eq!(format!("{}", Fixed(v, places)), core, "{v} {places}");
            }
        }
        // An exact tie rounds away from zero (core rounds it to even).
        assert_eq!(format!("{}", Fixed(0.125, 2)), "0.13");
        assert_eq!(format!("{}", Fixed(f32::NAN, 2)), "NaN");
        assert_eq!(format!("{}", Fixed(f32::NEG_INFINITY, 1)), "-inf");
        assert_eq!(format!("{}", Fixed(3e30, 1)), "3.0e30");
    }

    #[test]
    fn digits_by_hand_are_what_core_writes() {
        let mut digits = 0u32;
        for k in 0..3000u32 {
            // From one digit to ten, crossing every power of ten.
            digits = digits.wrapping_mul(7).wrapping_add(k) % (u32::MAX / 2) + k % 11;
            for places in 0..=MAX_PLACES {
                let scale = 10u64.pow(u32::from(places));
                let d = u64::from(digits);
                let core = if places == 0 {
                    format!("{d}")
                } else {
                    format!("{}.{:0w$}", d / scale, d % scale, w = usize::from(places))
                };
                for negative in [false, true] {
                    let mut text = std::string::String::new();
                    write_scaled_u32(negative, digits, places, &mut text).unwrap();
                    let sign = if negative && digits != 0 { "-" } else { "" };
                    assert_eq!(text, format!("{sign}{core}"), "{digits} {places}");
                }
            }
        }
    }

    #[test]
    fn sci_writes_what_core_writes() {
        for &(v, places) in &[
            (1234.56_f32, 3u8),
            (-0.00213, 1),
            (1.0, 0),
            (9.9996, 3),
            (6.02e23, 2),
            (1.5e-30, 4),
            (0.0, 2),
        ] {
            assert_eq!(
                format!("{}", Sci(v, places)),
                format!("{:.*e}", usize::from(places), v),
                "{v} {places}"
            );
        }
    }

    #[test]
    fn num_writes_six_significant_digits_without_trailing_zeros() {
        let cases = [
            (0.0_f32, "0"),
            (200.0, "200"),
            (0.002, "0.002"),
            (-1.5, "-1.5"),
            (0.1, "0.1"),
            (123456.7, "123457"),
            (2.0 / 3.0, "0.666667"),
            (1.5e-7, "1.5e-7"),
            (1e30, "1e30"),
            (-2.5e12, "-2.5e12"),
            (f32::INFINITY, "inf"),
        ];
        for (v, text) in cases {
            assert_eq!(format!("{}", Num(v)), text, "{v}");
        }
    }
}

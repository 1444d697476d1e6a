//! Second-order IIR filters (biquads) for the IMU's sample-rate stream: the anti-alias
//! low-pass and the rotors' notches ([`crate::imu`], docs/models.md#imu-front-end). The coefficients
//! follow R. Bristow-Johnson's "Audio EQ Cookbook" (bilinear transform, prewarped), the same
//! forms PX4's `LowPassFilter2p` and `NotchFilter` use. A filter's coefficients are kept apart
//! from its state so that one set serves several axes.

/// A biquad's coefficients, normalised so that `a0` is 1.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BiquadCoefficients {
    b: [f32; 3],
    a: [f32; 2],
}

impl BiquadCoefficients {
    /// Output equals input.
    pub const PASS_THROUGH: Self = Self {
        b: [1.0, 0.0, 0.0],
        a: [0.0, 0.0],
    };

    /// A second-order Butterworth low-pass cutting at `cutoff_hz` for samples at `sample_hz`; a
    /// pass-through if the cutoff is not positive or not below the Nyquist frequency.
    pub fn low_pass(cutoff_hz: f32, sample_hz: f32) -> Self {
        if !(cutoff_hz > 0.0 && cutoff_hz < 0.5 * sample_hz) {
            return Self::PASS_THROUGH;
        }
        let k = shared::math::tan(core::f32::consts::PI * cutoff_hz / sample_hz);
        let q = core::f32::consts::FRAC_1_SQRT_2;
        let norm = 1.0 / (1.0 + k / q + k * k);
        let b0 = k * k * norm;
        Self {
            b: [b0, 2.0 * b0, b0],
            a: [2.0 * (k * k - 1.0) * norm, (1.0 - k / q + k * k) * norm],
        }
    }

    /// A notch at `centre_hz`, `bandwidth_hz` wide between its -3 dB points, for samples at
    /// `sample_hz`: unity gain away from the centre, none at it. A pass-through if the centre is
    /// not positive or not below the Nyquist frequency, or the bandwidth is not positive.
    pub fn notch(centre_hz: f32, bandwidth_hz: f32, sample_hz: f32) -> Self {
        if !(centre_hz > 0.0 && centre_hz < 0.5 * sample_hz && bandwidth_hz > 0.0) {
            return Self::PASS_THROUGH;
        }
        let w0 = 2.0 * core::f32::consts::PI * centre_hz / sample_hz;
        let q = centre_hz / bandwidth_hz;
        let alpha = shared::math::sin(w0) / (2.0 * q);
        let cos = shared::math::cos(w0);
        let norm = 1.0 / (1.0 + alpha);
        Self {
            b: [norm, -2.0 * cos * norm, norm],
            a: [-2.0 * cos * norm, (1.0 - alpha) * norm],
        }
    }
}

/// One channel's memory of a biquad (transposed direct form II).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct BiquadState([f32; 2]);

impl BiquadState {
    /// A filter at rest at zero.
    pub const AT_REST: Self = Self([0.0; 2]);

    /// The state of a filter `c` that has long seen the constant `value` (no start-up
    /// transient): its input and output are both `value` (every filter here passes DC).
    pub fn settle(&mut self, c: &BiquadCoefficients, value: f32) {
        self.0[1] = value * (c.b[2] - c.a[1]);
        self.0[0] = value * (c.b[1] - c.a[0]) + self.0[1];
    }

    /// One sample through the filter `c`.
    pub fn apply(&mut self, c: &BiquadCoefficients, x: f32) -> f32 {
        let y = c.b[0] * x + self.0[0];
        self.0[0] = c.b[1] * x - c.a[0] * y + self.0[1];
        self.0[1] = c.b[2] * x - c.a[1] * y;
        y
    }
}

/// One channel's memory of a biquad whose coefficients change while it runs (direct form I:
/// the last two inputs and outputs). Unlike the transposed form its memory is the signal
/// itself, so retuning a notch on a signal with a steady part (gravity on the accelerometer)
/// leaves that part untouched instead of ringing.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct RetunableState {
    x: [f32; 2],
    y: [f32; 2],
}

impl RetunableState {
    /// A filter at rest at zero.
    pub const AT_REST: Self = Self {
        x: [0.0; 2],
        y: [0.0; 2],
    };

    /// The state of a filter that has long seen the constant `value` and passes DC.
    pub fn settle(&mut self, value: f32) {
        self.x = [value; 2];
        self.y = [value; 2];
    }

    /// One sample through the filter `c`.
    pub fn apply(&mut self, c: &BiquadCoefficients, x: f32) -> f32 {
        let y = c.b[0] * x + c.b[1] * self.x[0] + c.b[2] * self.x[1]
            - c.a[0] * self.y[0]
            - c.a[1] * self.y[1];
        self.x = [x, self.x[0]];
        self.y = [y, self.y[0]];
        y
    }
}

/// A single-channel biquad: its coefficients and its state.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Biquad {
    coefficients: BiquadCoefficients,
    state: BiquadState,
}

impl Biquad {
    /// A filter with `coefficients`, at rest at zero.
    pub fn new(coefficients: BiquadCoefficients) -> Self {
        Self {
            coefficients,
            state: BiquadState::default(),
        }
    }

    /// Starts the filter settled at `value` (no start-up transient).
    pub fn reset(&mut self, value: f32) {
        self.state.settle(&self.coefficients, value);
    }

    /// One sample in, one out.
    pub fn apply(&mut self, x: f32) -> f32 {
        self.state.apply(&self.coefficients, x)
    }
}

/// The steady peak output of a filter for a unit sine at `freq` Hz, sampled at 2 kHz (for
/// the filters' tests).
#[cfg(test)]
pub(crate) fn gain(c: BiquadCoefficients, freq: f32) -> f32 {
    let mut f = Biquad::new(c);
    let mut peak = 0.0f32;
    for n in 0..8000 {
        let y = f.apply(shared::math::sin(
            2.0 * core::f32::consts::PI * freq * n as f32 / 2000.0,
        ));
        if n > 6000 {
            peak = peak.max(y.abs());
        }
    }
    peak
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_notch_removes_its_centre_and_passes_what_is_a_bandwidth_away() {
        let c = BiquadCoefficients::notch(130.0, 30.0, 2000.0);
        assert!(gain(c, 130.0) < 0.01, "{}", gain(c, 130.0));
        // The -3 dB points are half a bandwidth either side.
        let edge = gain(c, 130.0 + 15.5);
        assert!(
            (edge - core::f32::consts::FRAC_1_SQRT_2).abs() < 0.05,
            "{edge}"
        );
        assert!(gain(c, 10.0) > 0.99 && gain(c, 400.0) > 0.95);
        let mut settled = Biquad::new(c);
        settled.reset(9.8);
        assert!(
            (settled.apply(9.8) - 9.8).abs() < 1e-4,
            "DC passes from the first sample"
        );
    }

    #[test]
    fn a_centre_past_nyquist_or_no_bandwidth_passes_everything() {
        for c in [
            BiquadCoefficients::notch(1200.0, 30.0, 2000.0),
            BiquadCoefficients::notch(100.0, 0.0, 2000.0),
            BiquadCoefficients::low_pass(0.0, 2000.0),
        ] {
            assert_eq!(c, BiquadCoefficients::PASS_THROUGH);
        }
    }
}

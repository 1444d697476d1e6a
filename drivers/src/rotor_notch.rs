//! Notches that follow the rotors (docs/models.md#imu-front-end): each rotor's rotation frequency and
//! its blade-pass frequency (two blades: twice the rotation) are taken out of the IMU's
//! sample-rate stream, each rotor's from its own ESC's RPM. A frame's vibration sits at exactly
//! those frequencies; a low-pass alone either leaves it (a 130 Hz rotor through the board's
//! 80 Hz anti-alias filter keeps a third of its amplitude) or, cut low enough, lags the control
//! loop. This is PX4's dynamic notch from ESC RPM (`IMU_GYRO_DNF_EN`) and ArduPilot's harmonic
//! notch with one notch per motor; here both gyro and accelerometer are notched, because the
//! mission's IMU monitor ([`shared::control::imu_monitor`]) reads both.
//!
//! A notch is on while its frequency is at least [`MIN_NOTCH_HZ`] (PX4's
//! `IMU_GYRO_DNF_MIN` is 25 Hz) and below 0.45 of the sample rate; its width is a quarter of
//! its frequency for up to [`FULL_WIDTH_ROTORS`] rotors, at least [`MIN_BANDWIDTH_HZ`]
//! (between ArduPilot's default of half the frequency and PX4's fixed 15 Hz,
//! `IMU_GYRO_DNF_BW`). The notches lie in series in the rate loop, and below its centre each
//! lags the signal by about (f / f0) / Q. Half-frequency notches on twelve to sixteen robots
//! lagged the loop by some 30 degrees at its crossover, and a payload whose true inertia was
//! 13 % below the model's (the campaign's `inertia_scale`) oscillated at 8 Hz until the rotor
//! monitor named healthy rotors and the payload fell (seed 7, trials 384 and 511); with a
//! quarter they fly. PX4's 15 Hz everywhere was tried too: it leaves a line whose rotor
//! changes speed fast (a touchdown at the paper's strongest vibration) and the IMU monitor
//! called the IMU noisy. With more rotors each notch is narrower still, by
//! `FULL_WIDTH_ROTORS / n`, so the bank lags the loop as eight rotors' does. A narrower notch
//! rings longer after a knock; the IMU monitor tells a ring-down from a noisy sensor
//! ([`shared::control::imu_monitor`]). Rotors turning at the same speed share one notch per
//! harmonic. A notch that comes on starts settled at the latest sample (or the first, if it comes on before any), so
//! switching it adds no transient; the front end notches after its low-pass, so that sample is
//! a smooth one.

use crate::biquad::{BiquadCoefficients, RetunableState};

/// Harmonics notched per rotor: its rotation and its two-bladed propeller's blade pass.
pub const HARMONICS: usize = 2;
/// Lowest frequency notched, Hz: below it a rotor is idle or stopped.
pub const MIN_NOTCH_HZ: f32 = 25.0;
/// A notch's width over its frequency (up to [`FULL_WIDTH_ROTORS`] rotors).
pub const QUARTER: f32 = 0.25;
/// Narrowest notch, Hz.
pub const MIN_BANDWIDTH_HZ: f32 = 10.0;
/// Rotors up to which a notch is a quarter of its frequency wide; beyond, narrower in
/// proportion.
pub const FULL_WIDTH_ROTORS: usize = 8;
/// Change of a rotor's frequency, Hz, below which its notches keep their coefficients (RPM
/// telemetry jitters; recomputing costs a sine and a cosine).
const RETUNE_HZ: f32 = 0.5;

/// Each notch's width as a share of the full (a quarter of its frequency) with `rotors` notched:
/// one up to [`FULL_WIDTH_ROTORS`], then in proportion, so the bank's lag at the rate loop's
/// crossover stays that of eight rotors.
pub fn width_share(rotors: usize) -> f32 {
    if rotors <= FULL_WIDTH_ROTORS {
        1.0
    } else {
        FULL_WIDTH_ROTORS as f32 / rotors as f32
    }
}

/// One notch over the six channels (gyro x y z, accelerometer x y z).
#[derive(Clone, Copy, Debug, PartialEq)]
struct Notch {
    /// Its frequency, Hz; 0 when off.
    centre_hz: f32,
    coefficients: BiquadCoefficients,
    state: [RetunableState; 6],
}

impl Notch {
    const OFF: Self = Self {
        centre_hz: 0.0,
        coefficients: BiquadCoefficients::PASS_THROUGH,
        state: [RetunableState::AT_REST; 6],
    };
}

/// The notches of up to `ROTORS` rotors, each at [`HARMONICS`] frequencies.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RotorNotches<const ROTORS: usize> {
    sample_hz: f32,
    notches: [[Notch; HARMONICS]; ROTORS],
    /// The latest sample, once there is one.
    latest: Option<[f32; 6]>,
    /// The most rotors whose speed was heard at once (the notches' width follows it; a
    /// rotor stopped reports 0 and still counts, a slot with no ESC is NaN and does not).
    rotors_heard: usize,
}

impl<const ROTORS: usize> RotorNotches<ROTORS> {
    /// Notches for samples at `sample_hz`, all off.
    pub fn new(sample_hz: f32) -> Self {
        Self {
            sample_hz,
            notches: [[Notch::OFF; HARMONICS]; ROTORS],
            latest: None,
            rotors_heard: 0,
        }
    }

    /// Follows the rotors' speeds (RPM, one per rotor, in the ESCs' order; rotors past
    /// `ROTORS` are not notched, a missing or non-finite speed turns its rotor's notches off).
    /// The notches' width follows the most rotors heard at once ([`width_share`]).
    pub fn follow(&mut self, rpm: &[f32]) {
        let nyquist_margin = 0.45 * self.sample_hz;
        let heard = rpm.iter().take(ROTORS).filter(|r| r.is_finite()).count();
        self.rotors_heard = self.rotors_heard.max(heard);
        let share = width_share(self.rotors_heard);
        for k in 0..ROTORS {
            let turns_hz = rpm.get(k).copied().filter(|r| r.is_finite()).unwrap_or(0.0) / 60.0;
            for h in 0..HARMONICS {
                let f = turns_hz * (h + 1) as f32;
                // Off below the lowest frequency and near Nyquist, and where an earlier
                // rotor's notch sits at the very same frequency (rotors given one command
                // would otherwise stack notches: deeper, but ringing far longer after a knock).
                // Only the same: sharing nearby notches switches them on and off as speeds
                // cross, and each switch is a transient the IMU monitor sees as noise.
                let covered = rpm.iter().take(k).any(|&r| r / 60.0 == turns_hz);
                let notch = &mut self.notches[k][h];
                if covered || !(MIN_NOTCH_HZ..nyquist_margin).contains(&f) {
                    *notch = Notch::OFF;
                    continue;
                }
                if notch.centre_hz > 0.0 && (f - notch.centre_hz).abs() < RETUNE_HZ {
                    continue;
                }
                let was_off = notch.centre_hz == 0.0;
                let width = (QUARTER * f * share).max(MIN_BANDWIDTH_HZ);
                notch.coefficients = BiquadCoefficients::notch(f, width, self.sample_hz);
                notch.centre_hz = f;
                if let (true, Some(latest)) = (was_off, &self.latest) {
                    for (s, &x) in notch.state.iter_mut().zip(latest) {
                        s.settle(x);
                    }
                }
            }
        }
    }

    /// Notches in use.
    pub fn active(&self) -> usize {
        self.notches
            .iter()
            .flatten()
            .filter(|n| n.centre_hz > 0.0)
            .count()
    }

    /// One sample of the six channels through every notch that is on.
    pub fn apply(&mut self, mut x: [f32; 6]) -> [f32; 6] {
        let first = self.latest.replace(x).is_none();
        for notch in self.notches.iter_mut().flatten() {
            if notch.centre_hz == 0.0 {
                continue;
            }
            if first {
                for (s, &v) in notch.state.iter_mut().zip(&x) {
                    s.settle(v);
                }
            }
            for (v, s) in x.iter_mut().zip(notch.state.iter_mut()) {
                *v = s.apply(&notch.coefficients, *v);
            }
        }
        x
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use core::f32::consts::PI;

    /// RMS of the last half of `n` samples of two rotors' vibration (rotation and blade pass)
    /// through the notches, with 9.8 of gravity on the accelerometer's z.
    fn residual(notched: bool, rpm: [f32; 2], n: usize) -> f32 {
        let mut notches = RotorNotches::<4>::new(2000.0);
        if notched {
            notches.follow(&rpm);
        }
        let mut sum = 0.0;
        for k in 0..n {
            let t = k as f32 / 2000.0;
            let mut v = 0.0;
            for r in rpm {
                let f = r / 60.0;
                v += shared::math::sin(2.0 * PI * f * t) + shared::math::sin(4.0 * PI * f * t);
            }
            let y = notches.apply([v, v, v, v, v, 9.8 + v]);
            if k >= n / 2 {
                sum += (y[5] - 9.8) * (y[5] - 9.8);
            }
        }
        shared::math::sqrt(sum / (n / 2) as f32)
    }

    #[test]
    fn each_rotor_s_rotation_and_blade_pass_are_taken_out() {
        let rpm = [7_800.0, 9_100.0];
        let raw = residual(false, rpm, 4000);
        let notched = residual(true, rpm, 4000);
        assert!(raw > 1.3, "four unit sines: RMS {raw}");
        assert!(notched < 0.02 * raw, "{notched} of {raw}");
    }

    /// Phase lag, degrees, of a 5.5 Hz signal (where the rate loop crosses over) through the
    /// notches of `rotors` rotors near `rpm`, each 0.5 % faster than the one before.
    fn lag_at_crossover<const N: usize>(rotors: usize, rpm: f32) -> f32 {
        // As the flight controller passes them: every slot, NaN where no ESC is.
        let mut speeds = [f32::NAN; N];
        for (k, s) in speeds.iter_mut().take(rotors).enumerate() {
            *s = rpm * (1.0 + 0.005 * k as f32);
        }
        let mut notches = RotorNotches::<N>::new(2000.0);
        notches.follow(&speeds);
        assert_eq!(notches.active(), 2 * rotors);
        let (f, n) = (5.5, 8000);
        let (mut in_phase, mut quadrature) = (0.0, 0.0);
        for k in 0..n {
            let w = 2.0 * PI * f * k as f32 / 2000.0;
            let y = notches.apply([shared::math::sin(w), 0.0, 0.0, 0.0, 0.0, 0.0])[0];
            if k >= n / 2 {
                in_phase += y * shared::math::sin(w);
                quadrature += y * shared::math::cos(w);
            }
        }
        -shared::math::atan2(quadrature, in_phase).to_degrees()
    }

    #[test]
    fn sixteen_rotors_notches_lag_the_rate_loop_no_more_than_eight_rotors_do() {
        // Eight rotors carrying a paper payload (about 6.5 N each, 7,400 RPM) and sixteen
        // carrying a long one (about 4 N each, 5,800 RPM).
        let eight = lag_at_crossover::<16>(8, 7_400.0);
        let sixteen = lag_at_crossover::<16>(16, 5_800.0);
        // A quarter of their frequency wide: half the 15 to 20 deg of half-frequency notches.
        assert!(eight > 5.0 && eight < 10.0, "eight rotors lag {eight} deg");
        // Half their frequency wide and not narrowed, sixteen rotors' notches would lag it by
        // about 37 deg.
        assert!(
            sixteen < 1.3 * eight,
            "sixteen {sixteen} deg, eight {eight} deg"
        );
        assert_eq!(width_share(4), 1.0);
        assert_eq!(width_share(16), 0.5);
    }

    #[test]
    fn idle_rotors_and_missing_telemetry_turn_notches_off() {
        let mut notches = RotorNotches::<4>::new(2000.0);
        notches.follow(&[7_800.0, 600.0, f32::NAN]);
        assert_eq!(
            notches.active(),
            2,
            "only the first rotor turns fast enough"
        );
        notches.follow(&[]);
        assert_eq!(notches.active(), 0);
        // Past the capacity: not notched, not a fault.
        notches.follow(&[6_000.0, 7_000.0, 8_000.0, 9_000.0, 10_000.0, 11_000.0]);
        assert_eq!(notches.active(), 8);
        // Rotors at one speed share their notches.
        notches.follow(&[7_800.0, 7_800.0, 7_810.0]);
        assert_eq!(notches.active(), 4);
    }

    #[test]
    fn a_notch_coming_on_adds_no_step_to_a_steady_signal() {
        let mut notches = RotorNotches::<1>::new(2000.0);
        for _ in 0..10 {
            notches.apply([0.1, 0.0, 0.0, 0.0, 0.0, -9.8]);
        }
        notches.follow(&[7_800.0]);
        for _ in 0..200 {
            let y = notches.apply([0.1, 0.0, 0.0, 0.0, 0.0, -9.8]);
            assert!(
                (y[5] + 9.8).abs() < 1e-3 && (y[0] - 0.1).abs() < 1e-4,
                "{y:?}"
            );
        }
    }
}

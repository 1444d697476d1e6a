//! The IMU's own plausibility, checked every control tick (`imu-stuck` and
//! `imu-noise`): a sensor that repeats its last sample (frozen) or whose samples jump far more
//! from tick to tick than sensor noise and the vehicle's motion can make (wildly noisy). The
//! board's driver catches a sensor that stops answering or reads at full scale
//! ([`crate::mission::HardwareFaults::imu`]); this catches one that answers with data that
//! cannot be true. Both are decided within 100 ms (40 ticks at 400 Hz); the mission stops on
//! the ground and lands on motion capture in flight.
//!
//! **Frozen.** A MEMS IMU never repeats itself: the ICM-42688-P's noise (gyro 2.8 mdeg/s/sqrt(Hz),
//! accelerometer 70 ug/sqrt(Hz)), filtered at 80 Hz from 2 kHz as the board does, leaves about
//! 0.5 mrad/s and 7 mm/s^2 per axis in each tick's sample, and the simulated sensor has ten
//! times that (0.005 rad/s, 0.05 m/s^2). A tick whose six readings all moved by less than
//! [`STILL_GYRO`] and [`STILL_ACCEL`] (about 1/50 of the real sensor's tick-to-tick noise:
//! each axis does that one tick in some 50, all six about one in 10^10) is *still*;
//! [`STUCK_TICKS`] still ticks in a row (50 ms) are a frozen IMU. The tolerance, rather than
//! bit equality, also catches a frozen sensor behind the driver's low-pass filter, whose
//! output creeps towards the last value before it stops changing.
//!
//! **Wildly noisy.** A tick is a *jump* when the gyro moved by more than [`JUMP_GYRO`] or the
//! accelerometer by more than [`JUMP_ACCEL`] (norms of the change of the 3-vectors) since the
//! previous tick; [`NOISY_JUMPS`] jumps among the last [`NOISY_WINDOW`] ticks are a noisy IMU.
//! In every scenario's whole mission in the plant, with and without a load shift, the largest
//! changes outside ground contact were 0.037 rad/s and 0.38 m/s^2 (sensor noise, whose
//! tick-to-tick change has a norm of about 0.012 rad/s and 0.12 m/s^2, plus the vehicle's
//! motion): the thresholds are four times that, 21 standard deviations of one axis's change.
//! The payload settling back on the ground after a lift, and touchdown, do jump (up to
//! 190 m/s^2 and 0.7 rad/s), but in bursts: at most 10 jumps in any 32 ticks on the tick-rate
//! sensor model, and up to 20 once the knock has rung through the board's anti-alias filter
//! and the rotors' notches (the raw 2 kHz path, `[plant]` `imu_vibration`; a notch at a slowly
//! turning rotor's 30 Hz rings for some 15 ms), hence [`NOISY_JUMPS`] 24 of 32. Counting jumps
//! rather than summing squares keeps such bursts from adding up. Noise of `k` times the
//! simulated sensor's makes a jump in almost every tick from `k` about 20 (gyro 0.1 rad/s per
//! sample: 200 times the real sensor's) and is flagged 24 to 30 ticks after it starts, within
//! the 100 ms; noise below about 7 times is not flagged, and the vehicle flies with it. A real
//! frame's propeller vibration is taken out before this check by the notches that follow each
//! rotor's RPM (`drivers::rotor_notch`): with them, 10 m/s^2 and 0.3 rad/s RMS of vibration
//! leave tick-to-tick changes under half the thresholds. Without ESC RPM telemetry nothing is
//! notched: check the tick-to-tick change in flight logs before flying a new airframe so.
//!
//! **A knock rings down; a broken sensor does not.** A knock (a payload set down after a lift,
//! a hard touchdown) rings through the anti-alias filter and the notches for tens of
//! milliseconds, long enough at a narrow notch to fill the window with jumps. So the jumps'
//! size (the larger of the gyro's and the accelerometer's change over its threshold) is
//! averaged twice, over about 4 ticks and about 16: a ringing knock decays (the recent average
//! falls below [`RING_DOWN_RATIO`] of the longer one within the 24 ticks the window needs),
//! a noisy sensor does not, and only jumps that do not decay make a noisy IMU. A noise fault
//! that starts is no slower to flag: its recent average is the larger.
//!
//! **On the ground a noisy IMU must stay noisy.** Setting a heavy payload down after a lift
//! rattles it on its feet for a tenth of a second or more, jumps that neither decay smoothly
//! nor last, and so do the rotors spinning down after a touchdown. On the ground nothing is at
//! stake in waiting, so there a noisy verdict counts only once it has held for
//! [`GROUND_NOISY_TICKS`] (0.5 s); in flight it counts at once. A frozen IMU counts at once
//! everywhere.
//!
//! Non-finite samples count as jumps (of size [`NON_FINITE_JUMP`]). The state is a previous
//! sample, two counters and two averages (48 bytes): the flight controller's RAM is tight.

use crate::control::navigator::ImuSample;
use crate::control::vector::Vec3;

/// Largest change of a gyro axis between two ticks that still counts as not moving, rad/s.
pub const STILL_GYRO: f32 = 1.0e-5;
/// Largest change of an accelerometer axis between two ticks that still counts as not
/// moving, m/s^2.
pub const STILL_ACCEL: f32 = 1.0e-4;
/// Still ticks in a row that make a frozen IMU (50 ms at 400 Hz).
pub const STUCK_TICKS: u8 = 20;
/// Change of the gyro's 3-vector between two ticks that makes a jump, rad/s.
pub const JUMP_GYRO: f32 = 0.15;
/// Change of the accelerometer's 3-vector between two ticks that makes a jump, m/s^2.
pub const JUMP_ACCEL: f32 = 1.5;
/// Ticks over which jumps are counted (80 ms at 400 Hz; at most 32, the width of the record).
pub const NOISY_WINDOW: u32 = 32;
/// Jumps among the last [`NOISY_WINDOW`] ticks that make a noisy IMU.
pub const NOISY_JUMPS: u32 = 24;
/// Share of the long average of the jumps' size below which the short one says they are
/// dying away (a ring-down, not a noisy sensor).
pub const RING_DOWN_RATIO: f32 = 0.5;
/// Weight of a tick in the short average of the jumps' size (about 4 ticks).
const SHORT_WEIGHT: f32 = 0.25;
/// Weight of a tick in the long average (about 16 ticks).
const LONG_WEIGHT: f32 = 1.0 / 16.0;
/// Size of a non-finite sample's jump, in thresholds.
pub const NON_FINITE_JUMP: f32 = 10.0;
/// Ticks a noisy verdict must hold on the ground before it counts (0.5 s at 400 Hz).
pub const GROUND_NOISY_TICKS: u16 = 200;
/// Largest size a jump counts with, in thresholds (one absurd sample does not hold the long
/// average up for long).
const LARGEST_JUMP: f32 = 100.0;

/// What is wrong with the IMU's samples.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ImuFailure {
    /// The same sample, tick after tick.
    Stuck,
    /// Tick-to-tick changes far beyond sensor noise and the vehicle's motion.
    Noisy,
}

impl core::fmt::Display for ImuFailure {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::Stuck => write!(
                f,
                "IMU frozen: the same gyro and accelerometer sample for {} ms",
                u32::from(STUCK_TICKS) * 1000 / crate::timing::CONTROL_RATE_HZ
            ),
            Self::Noisy => write!(
                f,
                "IMU noisy: its samples jump far beyond sensor noise and the vehicle's motion"
            ),
        }
    }
}

/// The monitor: feed it every tick's sample.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ImuMonitor {
    previous: Option<ImuSample>,
    still: u8,
    /// Bit `k` set: the tick `k` ticks ago was a jump.
    jumps: u32,
    /// The jumps' size (change over threshold) averaged over about 4 ticks and about 16.
    short_size: f32,
    long_size: f32,
    /// Ticks in a row the samples have been noisy.
    noisy_ticks: u16,
}

impl Default for ImuMonitor {
    fn default() -> Self {
        Self::new()
    }
}

impl ImuMonitor {
    /// A monitor that has seen no sample.
    pub const fn new() -> Self {
        Self {
            previous: None,
            still: 0,
            jumps: 0,
            short_size: 0.0,
            long_size: 0.0,
            noisy_ticks: 0,
        }
    }

    /// Takes this tick's sample, `flying` or on the ground; what is wrong with the IMU now,
    /// if anything (the verdict clears once the samples are plausible again: the caller
    /// latches what it acts on).
    pub fn check(&mut self, sample: &ImuSample, flying: bool) -> Option<ImuFailure> {
        let finite = sample.gyro.is_finite() && sample.accel.is_finite();
        let (size, still) = match (&self.previous, finite) {
            (_, false) => (NON_FINITE_JUMP, false),
            (None, true) => (0.0, false),
            (Some(p), true) => {
                let dg = sample.gyro - p.gyro;
                let da = sample.accel - p.accel;
                let still = max_abs(dg) <= STILL_GYRO && max_abs(da) <= STILL_ACCEL;
                let size = crate::math::max(dg.norm() / JUMP_GYRO, da.norm() / JUMP_ACCEL);
                (crate::math::min(size, LARGEST_JUMP), still)
            }
        };
        let jump = size > 1.0;
        self.short_size += SHORT_WEIGHT * (size - self.short_size);
        self.long_size += LONG_WEIGHT * (size - self.long_size);
        if finite {
            self.previous = Some(*sample);
        }
        self.still = if still {
            self.still.saturating_add(1)
        } else {
            0
        };
        let mask = if NOISY_WINDOW >= 32 {
            u32::MAX
        } else {
            (1u32 << NOISY_WINDOW) - 1
        };
        self.jumps = ((self.jumps << 1) | u32::from(jump)) & mask;
        let noisy = self.jumps.count_ones() >= NOISY_JUMPS
            && self.short_size >= RING_DOWN_RATIO * self.long_size;
        self.noisy_ticks = if noisy {
            self.noisy_ticks.saturating_add(1)
        } else {
            0
        };
        if self.still >= STUCK_TICKS {
            Some(ImuFailure::Stuck)
        } else if noisy && (flying || self.noisy_ticks >= GROUND_NOISY_TICKS) {
            Some(ImuFailure::Noisy)
        } else {
            None
        }
    }
}

fn max_abs(v: Vec3) -> f32 {
    crate::math::max(
        crate::math::max(crate::math::abs(v.x), crate::math::abs(v.y)),
        crate::math::abs(v.z),
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scenario::GRAVITY;

    /// A small deterministic noise source (xorshift), uniform in [-1, 1].
    struct Noise(u32);

    impl Noise {
        fn next(&mut self) -> f32 {
            self.0 ^= self.0 << 13;
            self.0 ^= self.0 >> 17;
            self.0 ^= self.0 << 5;
            (self.0 as f32 / u32::MAX as f32) * 2.0 - 1.0
        }

        fn vec(&mut self, scale: f32) -> Vec3 {
            Vec3::new(self.next(), self.next(), self.next()) * scale
        }
    }

    /// A resting IMU with noise of `scale` times the simulated sensor's (uniform with the
    /// same standard deviation: `sqrt(3)` sigma wide).
    fn sample(noise: &mut Noise, scale: f32) -> ImuSample {
        let w = 3.0f32.sqrt() * scale;
        ImuSample {
            gyro: Vec3::new(0.01, -0.005, 0.002) + noise.vec(0.005 * w),
            accel: Vec3::new(0.0, 0.0, -GRAVITY) + noise.vec(0.05 * w),
        }
    }

    /// Ticks until the first verdict, feeding `make` (None within `limit`).
    fn ticks_to_verdict(
        monitor: &mut ImuMonitor,
        limit: u32,
        mut make: impl FnMut(u32) -> ImuSample,
    ) -> Option<(u32, ImuFailure)> {
        (1..=limit).find_map(|k| monitor.check(&make(k), true).map(|f| (k, f)))
    }

    #[test]
    fn a_healthy_imu_is_never_flagged_even_at_the_real_sensors_noise() {
        let mut noise = Noise(7);
        let mut monitor = ImuMonitor::new();
        // The simulated sensor's noise, and a tenth of it (the real ICM-42688-P's), a minute
        // each.
        for scale in [1.0, 0.1] {
            let verdict = ticks_to_verdict(&mut monitor, 24_000, |_| sample(&mut noise, scale));
            assert_eq!(verdict, None, "scale {scale}");
        }
    }

    #[test]
    fn a_frozen_imu_is_flagged_after_stuck_ticks() {
        let mut noise = Noise(11);
        let mut monitor = ImuMonitor::new();
        assert_eq!(
            ticks_to_verdict(&mut monitor, 400, |_| sample(&mut noise, 1.0)),
            None
        );
        let frozen = sample(&mut noise, 1.0);
        let verdict = ticks_to_verdict(&mut monitor, 40, |_| frozen);
        assert_eq!(
            verdict,
            Some((u32::from(STUCK_TICKS) + 1, ImuFailure::Stuck)),
            "the first frozen sample is new: still from the second on"
        );
        // Once it moves again the verdict clears.
        assert_eq!(monitor.check(&sample(&mut noise, 1.0), true), None);
    }

    #[test]
    fn a_frozen_imu_behind_a_low_pass_filter_is_flagged() {
        // The driver's filter creeps towards the frozen value: its changes shrink below the
        // tolerance long before they reach zero.
        let mut noise = Noise(3);
        let mut monitor = ImuMonitor::new();
        let frozen = sample(&mut noise, 1.0);
        let mut out = sample(&mut noise, 1.0);
        let verdict = ticks_to_verdict(&mut monitor, 40, |_| {
            out.gyro = out.gyro + (frozen.gyro - out.gyro) * 0.5;
            out.accel = out.accel + (frozen.accel - out.accel) * 0.5;
            out
        });
        assert!(
            matches!(verdict, Some((k, ImuFailure::Stuck)) if k <= 40),
            "{verdict:?}"
        );
    }

    #[test]
    fn wild_noise_is_flagged_within_100_ms_and_mild_noise_is_not() {
        for (scale, flagged) in [(20.0, true), (100.0, true), (1000.0, true), (5.0, false)] {
            let mut noise = Noise(5);
            let mut monitor = ImuMonitor::new();
            let verdict = ticks_to_verdict(&mut monitor, 4000, |_| sample(&mut noise, scale));
            if flagged {
                assert!(
                    matches!(verdict, Some((k, ImuFailure::Noisy)) if k <= 40),
                    "x{scale}: {verdict:?}"
                );
            } else {
                assert_eq!(verdict, None, "x{scale}");
            }
        }
    }

    #[test]
    fn bursts_of_ground_contact_are_no_noise() {
        // A touchdown as the plant makes it: the accelerometer rattles by 100 m/s^2 from tick
        // to tick for 10 ticks (11 jumps), then rests.
        let mut noise = Noise(9);
        let mut monitor = ImuMonitor::new();
        let verdict = ticks_to_verdict(&mut monitor, 400, |k| {
            let mut s = sample(&mut noise, 1.0);
            if (100..110).contains(&k) && k % 2 == 0 {
                s.accel.z += 100.0;
            }
            s
        });
        assert_eq!(verdict, None);
    }

    /// A knock as a narrow notch rings it down: the accelerometer swings at 30 Hz from
    /// 190 m/s^2, decaying with a 21 ms time constant (a 15 Hz wide notch), so its tick-to-tick
    /// change stays above the threshold for some 35 ticks in a row. A ring-down, not noise;
    /// the same swing held at its size is noise.
    #[test]
    fn a_ringing_knock_is_no_noise_but_a_swing_that_holds_is() {
        for (decays, flagged) in [(true, false), (false, true)] {
            let mut noise = Noise(21);
            let mut monitor = ImuMonitor::new();
            let verdict = ticks_to_verdict(&mut monitor, 800, |k| {
                let mut s = sample(&mut noise, 1.0);
                if k >= 400 {
                    let t = (k - 400) as f32 * 0.0025;
                    let size = if decays { libm::expf(-t / 0.021) } else { 0.2 };
                    s.accel.z += 190.0 * size * libm::sinf(core::f32::consts::TAU * 30.0 * t);
                }
                s
            });
            if flagged {
                assert!(
                    matches!(verdict, Some((k, ImuFailure::Noisy)) if k <= 440),
                    "{verdict:?}"
                );
            } else {
                assert_eq!(verdict, None);
            }
        }
    }

    /// On the ground a noisy IMU counts after half a second of noise; in flight at once.
    #[test]
    fn on_the_ground_noise_must_last_half_a_second() {
        let mut noise = Noise(17);
        let mut monitor = ImuMonitor::new();
        let on_ground = (1..=400)
            .find(|_| monitor.check(&sample(&mut noise, 100.0), false).is_some())
            .map(|k| k as u16);
        assert!(
            on_ground.is_some_and(|k| (GROUND_NOISY_TICKS..GROUND_NOISY_TICKS + 40).contains(&k)),
            "flagged on the ground after {on_ground:?} ticks"
        );
    }

    #[test]
    fn the_state_stays_small() {
        assert!(core::mem::size_of::<ImuMonitor>() <= 48);
    }

    #[test]
    fn non_finite_samples_count_as_noise() {
        let mut noise = Noise(13);
        let mut monitor = ImuMonitor::new();
        assert_eq!(
            ticks_to_verdict(&mut monitor, 100, |_| sample(&mut noise, 1.0)),
            None
        );
        let mut bad = sample(&mut noise, 1.0);
        bad.gyro.x = f32::NAN;
        let verdict = ticks_to_verdict(&mut monitor, 40, |_| bad);
        assert_eq!(verdict, Some((NOISY_JUMPS, ImuFailure::Noisy)));
    }
}

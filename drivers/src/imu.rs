//! From IMU samples to the control tick: the board's mounting rotation into the
//! body frame the controller uses (x forward, y right, z down: docs/models.md#conventions), a
//! second-order Butterworth anti-alias filter and the rotors' notches ([`crate::rotor_notch`])
//! at the sample rate, decimation to the 400 Hz tick, and the IMU's health: a stalled, saturated
//! or implausible IMU is a fault with a name.

use shared::control::vector::Vec3;
use shared::scenario::GRAVITY;

use crate::biquad::{Biquad, BiquadCoefficients};
use crate::rotor_notch::RotorNotches;

/// How the IMU sits on the board: a yaw about the body's z axis (PX4's `ROTATION_YAW_*`,
/// applied as PX4 does: body = R * sensor). The Pixhawk 6C's ICM-42688-P is yaw 270 deg
/// (`rc.board_sensors`: `icm42688p -R 6`), its BMI088 yaw 180 deg (`-R 4`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Mounting {
    /// Sensor axes are body axes.
    Identity,
    /// Yaw 90 deg.
    Yaw90,
    /// Yaw 180 deg.
    Yaw180,
    /// Yaw 270 deg.
    Yaw270,
}

impl Mounting {
    /// `v` (sensor axes) in body axes.
    pub fn to_body(self, [x, y, z]: [f32; 3]) -> [f32; 3] {
        match self {
            Self::Identity => [x, y, z],
            Self::Yaw90 => [-y, x, z],
            Self::Yaw180 => [-x, -y, z],
            Self::Yaw270 => [y, -x, z],
        }
    }
}

/// The IMU's readings for one control tick, body frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TickSample {
    /// Angular rate, rad/s.
    pub gyro: [f32; 3],
    /// Specific force, m/s^2.
    pub accel: [f32; 3],
    /// Samples filtered since the last tick.
    pub samples: u16,
}

/// Why the IMU cannot be trusted.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ImuFault {
    /// `WHO_AM_I` answered something else: no IMU, or another part.
    WrongDevice(u8),
    /// No sample for this many ticks in a row.
    Stalled(u16),
    /// A reading at full scale.
    Saturated,
    /// At rest the readings are not those of a resting IMU (pre-flight check).
    Implausible,
}

impl core::fmt::Display for ImuFault {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match *self {
            Self::WrongDevice(id) => write!(f, "IMU: WHO_AM_I {id:#04x}, not an ICM-42688-P"),
            Self::Stalled(ticks) => write!(f, "IMU: no samples for {ticks} control steps"),
            Self::Saturated => f.write_str("IMU: reading at full scale"),
            Self::Implausible => {
                f.write_str("IMU: at rest it does not read 1 g and no rotation (pre-flight)")
            }
        }
    }
}

/// Ticks without a sample that make a stall: 5 ticks, 12.5 ms at 400 Hz.
pub const STALL_TICKS: u16 = 5;

/// Ticks in a row with a reading at full scale that make a saturated IMU: 4 ticks, 10 ms at
/// 400 Hz. A hard touchdown clips the accelerometer for a few milliseconds (the plant's
/// payload settling back after a lift reaches 19 g for about 2 ms), as PX4 counts clipping
/// without failing the sensor; a sensor pinned at full scale stays there.
pub const SATURATED_TICKS: u16 = 4;

/// Filters every sample, hands the latest filtered one to each tick, and watches the IMU;
/// notches follow up to `ROTORS` rotors (the board's ESC outputs).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ImuFrontEnd<const ROTORS: usize = 8> {
    mounting: Mounting,
    notches: RotorNotches<ROTORS>,
    gyro: [Biquad; 3],
    accel: [Biquad; 3],
    latest: Option<TickSample>,
    started: bool,
    samples: u16,
    empty_ticks: u16,
    saturated: bool,
    saturated_ticks: u16,
}

impl<const ROTORS: usize> ImuFrontEnd<ROTORS> {
    /// A front end for an IMU mounted `mounting`, sampling at `sample_hz`, filtered at
    /// `cutoff_hz` (below half the tick rate, so the decimation does not alias).
    pub fn new(mounting: Mounting, sample_hz: f32, cutoff_hz: f32) -> Self {
        let lp = Biquad::new(BiquadCoefficients::low_pass(cutoff_hz, sample_hz));
        Self {
            mounting,
            notches: RotorNotches::new(sample_hz),
            gyro: [lp; 3],
            accel: [lp; 3],
            latest: None,
            started: false,
            samples: 0,
            empty_ticks: 0,
            saturated: false,
            saturated_ticks: 0,
        }
    }

    /// Follows the rotors' speeds, RPM in the ESCs' order (from their telemetry; an empty
    /// slice when there is none, and then nothing is notched).
    pub fn follow_rotors(&mut self, rpm: &[f32]) {
        self.notches.follow(rpm);
    }

    /// One sample (sensor axes, SI units; `saturated` if the sensor read at full scale).
    pub fn push(&mut self, gyro: [f32; 3], accel: [f32; 3], saturated: bool) {
        let gyro = self.mounting.to_body(gyro);
        let accel = self.mounting.to_body(accel);
        if !self.started {
            for axis in 0..3 {
                self.gyro[axis].reset(gyro[axis]);
                self.accel[axis].reset(accel[axis]);
            }
            self.started = true;
        }
        // The anti-alias filter, then the notches: a notch that comes on settles at the
        // filtered signal, not at one noisy sample.
        let mut smooth = [0.0f32; 6];
        for axis in 0..3 {
            smooth[axis] = self.gyro[axis].apply(gyro[axis]);
            smooth[3 + axis] = self.accel[axis].apply(accel[axis]);
        }
        let [gx, gy, gz, ax, ay, az] = self.notches.apply(smooth);
        let out = TickSample {
            gyro: [gx, gy, gz],
            accel: [ax, ay, az],
            samples: 0,
        };
        self.samples = self.samples.saturating_add(1);
        self.saturated |= saturated;
        self.latest = Some(out);
    }

    /// The latest filtered sample, faulty or not (what a control step runs on while the
    /// mission lands on a failed IMU).
    pub fn latest(&self) -> Option<TickSample> {
        self.latest
    }

    /// The tick's reading: the latest filtered sample, or the fault that makes it unusable.
    pub fn tick(&mut self) -> Result<TickSample, ImuFault> {
        let samples = core::mem::take(&mut self.samples);
        let saturated = core::mem::take(&mut self.saturated);
        if samples == 0 {
            self.empty_ticks = self.empty_ticks.saturating_add(1);
        } else {
            self.empty_ticks = 0;
        }
        if self.empty_ticks >= STALL_TICKS || self.latest.is_none() {
            return Err(ImuFault::Stalled(self.empty_ticks));
        }
        self.saturated_ticks = if saturated {
            self.saturated_ticks.saturating_add(1)
        } else {
            0
        };
        if self.saturated_ticks >= SATURATED_TICKS {
            return Err(ImuFault::Saturated);
        }
        let mut out = self.latest.ok_or(ImuFault::Stalled(self.empty_ticks))?;
        out.samples = samples;
        Ok(out)
    }
}

/// The pre-flight check of a resting vehicle: the specific force within 10 % of 1 g and no
/// rotation above 0.1 rad/s (3 x the ICM-42688-P's worst zero-rate offset at 2000 deg/s).
pub fn plausible_at_rest(sample: &TickSample) -> Result<(), ImuFault> {
    let norm = |[x, y, z]: [f32; 3]| Vec3::new(x, y, z).norm();
    let a = norm(sample.accel);
    if (a - GRAVITY).abs() <= 0.1 * GRAVITY && norm(sample.gyro) <= 0.1 {
        Ok(())
    } else {
        Err(ImuFault::Implausible)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// PX4's rotations: yaw 270 maps sensor x to body -y and sensor y to body x.
    #[test]
    fn mountings_by_hand() {
        let v = [1.0, 2.0, 3.0];
        assert_eq!(Mounting::Identity.to_body(v), [1.0, 2.0, 3.0]);
        assert_eq!(Mounting::Yaw90.to_body(v), [-2.0, 1.0, 3.0]);
        assert_eq!(Mounting::Yaw180.to_body(v), [-1.0, -2.0, 3.0]);
        assert_eq!(Mounting::Yaw270.to_body(v), [2.0, -1.0, 3.0]);
        // Yaw 90 then yaw 270 is no rotation.
        assert_eq!(Mounting::Yaw270.to_body(Mounting::Yaw90.to_body(v)), v);
    }

    fn gain_at(freq: f32) -> f32 {
        crate::biquad::gain(BiquadCoefficients::low_pass(80.0, 2000.0), freq)
    }

    /// A Butterworth passes DC, is -3 dB at its cutoff, and at 400 Hz (aliasing onto 0 Hz
    /// after decimation to 400 Hz) is down by 2 x 12 dB per octave over 2.3 octaves.
    #[test]
    fn the_anti_alias_filter_responds_as_a_butterworth() {
        let mut lp = Biquad::new(BiquadCoefficients::low_pass(80.0, 2000.0));
        let mut y = 0.0;
        for _ in 0..500 {
            y = lp.apply(1.0);
        }
        assert!((y - 1.0).abs() < 1e-4);
        assert!((gain_at(80.0) - core::f32::consts::FRAC_1_SQRT_2).abs() < 0.02);
        assert!(gain_at(400.0) < 0.05, "{}", gain_at(400.0));
        assert!(gain_at(10.0) > 0.99);
        // Settled start: the first output equals a constant input.
        let mut lp = Biquad::new(BiquadCoefficients::low_pass(80.0, 2000.0));
        lp.reset(9.8);
        assert!((lp.apply(9.8) - 9.8).abs() < 1e-4);
        assert!((lp.apply(9.8) - 9.8).abs() < 1e-4);
    }

    #[test]
    fn ticks_take_the_latest_filtered_sample_in_body_axes() {
        let mut imu = ImuFrontEnd::<8>::new(Mounting::Yaw270, 2000.0, 80.0);
        assert_eq!(imu.tick(), Err(ImuFault::Stalled(1)), "nothing yet");
        for _ in 0..5 {
            imu.push([0.0, 0.5, 0.0], [0.0, 0.0, -9.8], false);
        }
        let s = imu.tick().unwrap();
        assert_eq!(s.samples, 5);
        assert!(
            (s.gyro[0] - 0.5).abs() < 1e-4,
            "sensor y is body x: {:?}",
            s.gyro
        );
        assert!((s.accel[2] + 9.8).abs() < 1e-4);
        assert_eq!(
            plausible_at_rest(&TickSample {
                gyro: [0.0; 3],
                ..s
            }),
            Ok(())
        );
        assert_eq!(
            plausible_at_rest(&s),
            Err(ImuFault::Implausible),
            "0.5 rad/s is no rest"
        );
    }

    #[test]
    fn a_silent_imu_stalls_and_a_saturated_one_is_reported() {
        let mut imu = ImuFrontEnd::<8>::new(Mounting::Identity, 2000.0, 80.0);
        imu.push([0.0; 3], [0.0, 0.0, -9.8], false);
        assert!(imu.tick().is_ok());
        for tick in 1..STALL_TICKS {
            assert!(
                imu.tick().is_ok(),
                "tick {tick}: the last sample still stands"
            );
        }
        assert_eq!(imu.tick(), Err(ImuFault::Stalled(STALL_TICKS)));
        assert!(
            imu.latest().is_some(),
            "the last sample stays for the landing"
        );
        imu.push([0.0; 3], [0.0, 0.0, -9.8], true);
        assert!(
            imu.tick().is_ok(),
            "one clipped tick is a bump, not a fault"
        );
        for _ in 2..SATURATED_TICKS {
            imu.push([0.0; 3], [0.0, 0.0, -9.8], true);
            assert!(imu.tick().is_ok());
        }
        imu.push([0.0; 3], [0.0, 0.0, -9.8], true);
        assert_eq!(imu.tick(), Err(ImuFault::Saturated), "pinned at full scale");
        imu.push([0.0; 3], [0.0, 0.0, -9.8], false);
        assert!(imu.tick().is_ok(), "a clean sample clears it");
    }
}

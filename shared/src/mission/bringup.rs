//! Bring-up of a real vehicle on the bench (docs/ground-link.md#bring-up-commands): the IMU's
//! calibrations at rest and the motor test, as plain state the mission steps while idle.
//!
//! - [`SensorOffsets`]: the gyro's and the accelerometer's offsets (`CAL_GYRO0_*OFF`,
//!   `CAL_ACC0_*OFF`), taken off every sample before anything reads it.
//! - [`ImuCalibration`]: [`CALIBRATION_SAMPLES`] samples at rest averaged (Welford's running
//!   mean and variance per axis); a vehicle that moves meanwhile fails it, as does an offset
//!   no sensor bias explains.
//! - [`MotorTest`]: some rotors at an ESC command for a while (`MAV_CMD_DO_MOTOR_TEST`).

use crate::control::navigator::ImuSample;
use crate::control::vector::Vec3;
use crate::math;
use crate::numbers::Fixed;
use crate::scenario::GRAVITY;

/// Samples a calibration averages: 2 s at the control rate.
pub const CALIBRATION_SAMPLES: u32 = 800;
/// Largest standard deviation of a gyro axis at rest, rad/s: above it the vehicle moved (an
/// ICM-42688-P reads about 0.003 at 400 Hz; the simulated gyro 0.005).
pub const MAX_GYRO_SPREAD: f32 = 0.03;
/// Largest standard deviation of an accelerometer axis at rest, m/s^2.
pub const MAX_ACCEL_SPREAD: f32 = 0.3;
/// Largest gyro offset taken as a bias, rad/s (about 20 deg/s: far above any MEMS gyro's).
pub const MAX_GYRO_OFFSET: f32 = 0.35;
/// Largest accelerometer offset of a level calibration on an axis, m/s^2 (about 12 degrees of
/// tilt on x or y): beyond it the vehicle is not level.
pub const MAX_ACCEL_OFFSET: f32 = 2.0;
/// Largest difference of the accelerometer's magnitude from gravity at rest, m/s^2.
pub const MAX_REST_ERROR: f32 = 1.0;
/// Longest motor test, s (`MAV_CMD_DO_MOTOR_TEST`'s timeout is cut to it).
pub const MAX_MOTOR_TEST_TIME: f32 = 3.0;

/// Offsets taken off each IMU sample.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SensorOffsets {
    /// Gyro offsets, rad/s (`CAL_GYRO0_XOFF`, `_YOFF`, `_ZOFF`).
    pub gyro: [f32; 3],
    /// Accelerometer offsets, m/s^2 (`CAL_ACC0_XOFF`, `_YOFF`, `_ZOFF`).
    pub accel: [f32; 3],
}

impl SensorOffsets {
    /// None.
    pub const ZERO: Self = Self {
        gyro: [0.0; 3],
        accel: [0.0; 3],
    };

    /// `sample` with the offsets taken off.
    pub fn correct(&self, sample: &ImuSample) -> ImuSample {
        let [gx, gy, gz] = self.gyro;
        let [ax, ay, az] = self.accel;
        ImuSample {
            gyro: sample.gyro - Vec3::new(gx, gy, gz),
            accel: sample.accel - Vec3::new(ax, ay, az),
        }
    }
}

impl Default for SensorOffsets {
    fn default() -> Self {
        Self::ZERO
    }
}

/// The parameters the bench needs with or without a payload description: the IMU's offsets
/// and the hardware settings (the motor test's thrust map and switch).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BenchConfig {
    /// The IMU's offsets.
    pub sensors: SensorOffsets,
    /// The drivers' settings.
    pub hardware: crate::mission::HardwareConfig,
}

impl From<&crate::mission::MissionConfig> for BenchConfig {
    fn from(c: &crate::mission::MissionConfig) -> Self {
        Self {
            sensors: c.sensors,
            hardware: c.hardware,
        }
    }
}

/// Which calibration (`MAV_CMD_PREFLIGHT_CALIBRATION`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CalibrationKind {
    /// The gyro's offsets at rest (param1 = 1).
    Gyro,
    /// The accelerometer's offsets at rest on a level surface (param5 = 2).
    Level,
}

impl CalibrationKind {
    /// Its name for people.
    pub fn name(self) -> &'static str {
        match self {
            Self::Gyro => "gyro",
            Self::Level => "level",
        }
    }
}

/// Why a calibration failed.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum CalibrationFailure {
    /// The vehicle moved: an axis spread more than a sensor at rest does.
    Moving {
        /// The axis (0 x, 1 y, 2 z) that spread most past its limit.
        axis: u8,
        /// Its standard deviation (rad/s for the gyro, m/s^2 for the accelerometer).
        spread: f32,
        /// The gyro (true) or the accelerometer.
        gyro: bool,
    },
    /// The accelerometer's magnitude is not gravity: the vehicle is not at rest.
    NotAtRest {
        /// The magnitude read, m/s^2.
        magnitude: f32,
    },
    /// An offset larger than a sensor's bias can be.
    OffsetTooLarge {
        /// The axis.
        axis: u8,
        /// The offset (rad/s or m/s^2).
        offset: f32,
    },
    /// A sample was not a number.
    NotANumber,
}

/// The axis' letter.
fn axis_name(axis: u8) -> char {
    match axis {
        0 => 'x',
        1 => 'y',
        _ => 'z',
    }
}

impl core::fmt::Display for CalibrationFailure {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match *self {
            Self::Moving { axis, spread, gyro } => write!(
                f,
                "the vehicle moved: the {} {} axis spread {} {} (at rest at most {}); keep it still",
                if gyro { "gyro's" } else { "accelerometer's" },
                axis_name(axis),
                Fixed(spread, 3),
                if gyro { "rad/s" } else { "m/s^2" },
                Fixed(
                    if gyro {
                        MAX_GYRO_SPREAD
                    } else {
                        MAX_ACCEL_SPREAD
                    },
                    3
                ),
            ),
            Self::NotAtRest { magnitude } => write!(
                f,
                "not at rest: the accelerometer reads {} m/s^2, gravity is {}",
                Fixed(magnitude, 2),
                Fixed(GRAVITY, 2)
            ),
            Self::OffsetTooLarge { axis, offset } => write!(
                f,
                "the {} offset {} is too large for a sensor's bias (the vehicle turned or is not level, or the sensor is faulty)",
                axis_name(axis),
                Fixed(offset, 3)
            ),
            Self::NotANumber => write!(f, "a sample was not a number (a faulty sensor)"),
        }
    }
}

/// A calibration at rest under way: each axis' running mean and sum of squared deviations.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ImuCalibration {
    kind: CalibrationKind,
    count: u32,
    /// Gyro x, y, z then accelerometer x, y, z.
    mean: [f32; 6],
    m2: [f32; 6],
}

impl ImuCalibration {
    /// A calibration of `kind`, no sample yet.
    pub fn new(kind: CalibrationKind) -> Self {
        Self {
            kind,
            count: 0,
            mean: [0.0; 6],
            m2: [0.0; 6],
        }
    }

    /// Which calibration.
    pub fn kind(&self) -> CalibrationKind {
        self.kind
    }

    /// Takes one raw sample (before any offset); the offsets found (gyro or accelerometer,
    /// by [`Self::kind`]) or why not, once [`CALIBRATION_SAMPLES`] are in.
    pub fn add(&mut self, sample: &ImuSample) -> Option<Result<[f32; 3], CalibrationFailure>> {
        let g = sample.gyro;
        let a = sample.accel;
        let values = [g.x, g.y, g.z, a.x, a.y, a.z];
        if values.iter().any(|v| !v.is_finite()) {
            return Some(Err(CalibrationFailure::NotANumber));
        }
        self.count += 1;
        let n = self.count as f32;
        for (i, &v) in values.iter().enumerate() {
            let delta = v - self.mean[i];
            self.mean[i] += delta / n;
            self.m2[i] += delta * (v - self.mean[i]);
        }
        (self.count >= CALIBRATION_SAMPLES).then(|| self.result())
    }

    /// The standard deviation of axis `i` so far.
    fn spread(&self, i: usize) -> f32 {
        if self.count < 2 {
            return 0.0;
        }
        math::sqrt(self.m2[i] / (self.count - 1) as f32)
    }

    /// The offsets from the samples in, or why they are not to be trusted.
    fn result(&self) -> Result<[f32; 3], CalibrationFailure> {
        for gyro in [true, false] {
            let (base, limit) = if gyro {
                (0, MAX_GYRO_SPREAD)
            } else {
                (3, MAX_ACCEL_SPREAD)
            };
            let worst = (0..3u8)
                .map(|axis| (axis, self.spread(base + axis as usize)))
                .fold((0u8, 0.0f32), |w, s| if s.1 > w.1 { s } else { w });
            if worst.1 > limit {
                return Err(CalibrationFailure::Moving {
                    axis: worst.0,
                    spread: worst.1,
                    gyro,
                });
            }
        }
        let [_, _, _, ax, ay, az] = self.mean;
        let magnitude = math::sqrt(ax * ax + ay * ay + az * az);
        if (magnitude - GRAVITY).abs() > MAX_REST_ERROR {
            return Err(CalibrationFailure::NotAtRest { magnitude });
        }
        let (offsets, limit) = match self.kind {
            CalibrationKind::Gyro => ([self.mean[0], self.mean[1], self.mean[2]], MAX_GYRO_OFFSET),
            // Level and at rest the accelerometer reads (0, 0, -g) (FRD): the rest is offset.
            CalibrationKind::Level => ([ax, ay, az + GRAVITY], MAX_ACCEL_OFFSET),
        };
        if let Some(axis) = (0..3).find(|&i| offsets[i].abs() > limit) {
            return Err(CalibrationFailure::OffsetTooLarge {
                axis: axis as u8,
                offset: offsets[axis],
            });
        }
        Ok(offsets)
    }
}

/// A motor test as the operator asks for it (`MAV_CMD_DO_MOTOR_TEST`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct MotorTestRequest {
    /// The first robot, from 1.
    pub first: u8,
    /// How many robots from the first.
    pub count: u8,
    /// The ESC command, thousandths of full.
    pub permille: u16,
    /// How long, ms (cut to 3 s).
    pub millis: u16,
}

/// A motor test under way: robots `first .. first + count` (from 0) at an ESC command.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MotorTest {
    first: u8,
    count: u8,
    command: f32,
    left: f32,
}

impl MotorTest {
    /// `count` rotors from robot `first` (from 0) at `command` (fraction of full ESC command,
    /// clamped to `[0, 1]`) for `seconds` (cut to [`MAX_MOTOR_TEST_TIME`]; a non-positive or
    /// non-finite time is the longest).
    pub fn new(first: u8, count: u8, command: f32, seconds: f32) -> Self {
        let left = if seconds.is_finite() && seconds > 0.0 {
            seconds.min(MAX_MOTOR_TEST_TIME)
        } else {
            MAX_MOTOR_TEST_TIME
        };
        Self {
            first,
            count,
            command: if command.is_finite() {
                command.clamp(0.0, 1.0)
            } else {
                0.0
            },
            left,
        }
    }

    /// The time gone by; false once the test is over.
    pub fn step(&mut self, dt: f32) -> bool {
        self.left -= dt;
        self.left > 0.0
    }

    /// The ESC command of robot `j`'s rotor (zero for the rotors not tested).
    pub fn command(&self, j: usize) -> f32 {
        let first = usize::from(self.first);
        if (first..first + usize::from(self.count)).contains(&j) {
            self.command
        } else {
            0.0
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample(gyro: [f32; 3], accel: [f32; 3]) -> ImuSample {
        ImuSample {
            gyro: Vec3::new(gyro[0], gyro[1], gyro[2]),
            accel: Vec3::new(accel[0], accel[1], accel[2]),
        }
    }

    /// A small deterministic noise in [-1, 1] (a linear congruential sequence).
    fn noise(state: &mut u32) -> f32 {
        *state = state.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
        (*state >> 8) as f32 / (1u32 << 23) as f32 - 1.0
    }

    fn run(
        kind: CalibrationKind,
        gyro: [f32; 3],
        accel: [f32; 3],
        gyro_noise: f32,
        accel_noise: f32,
    ) -> Result<[f32; 3], CalibrationFailure> {
        let mut cal = ImuCalibration::new(kind);
        let mut state = 7;
        for i in 0..CALIBRATION_SAMPLES {
            let mut n = |s: f32| s * noise(&mut state);
            let s = sample(
                [
                    gyro[0] + n(gyro_noise),
                    gyro[1] + n(gyro_noise),
                    gyro[2] + n(gyro_noise),
                ],
                [
                    accel[0] + n(accel_noise),
                    accel[1] + n(accel_noise),
                    accel[2] + n(accel_noise),
                ],
            );
            if let Some(result) = cal.add(&s) {
                assert_eq!(i + 1, CALIBRATION_SAMPLES);
                return result;
            }
        }
        panic!("the calibration never ended");
    }

    #[test]
    fn the_gyro_bias_at_rest_is_found_through_the_noise() {
        let bias = [0.05, -0.02, 0.013];
        let found = run(CalibrationKind::Gyro, bias, [0.0, 0.0, -GRAVITY], 0.01, 0.1).unwrap();
        for i in 0..3 {
            assert!((found[i] - bias[i]).abs() < 0.002, "{found:?}");
        }
        // Taken off, the sample reads zero rate.
        let offsets = SensorOffsets {
            gyro: found,
            accel: [0.0; 3],
        };
        let corrected = offsets.correct(&sample(bias, [0.0, 0.0, -GRAVITY]));
        assert!(corrected.gyro.norm() < 0.003);
    }

    #[test]
    fn a_level_calibration_finds_the_accelerometer_offsets_from_gravity() {
        let found = run(
            CalibrationKind::Level,
            [0.0; 3],
            [0.3, -0.2, -GRAVITY + 0.15],
            0.005,
            0.05,
        )
        .unwrap();
        let expected = [0.3, -0.2, 0.15];
        for i in 0..3 {
            assert!((found[i] - expected[i]).abs() < 0.01, "{found:?}");
        }
    }

    #[test]
    fn a_vehicle_that_moves_fails_the_calibration() {
        // Turned back and forth by hand: the gyro's y axis swings by 0.2 rad/s.
        let err = run(
            CalibrationKind::Gyro,
            [0.0; 3],
            [0.0, 0.0, -GRAVITY],
            0.0,
            0.0,
        );
        assert!(err.is_ok());
        let mut cal = ImuCalibration::new(CalibrationKind::Gyro);
        let mut result = None;
        for i in 0..CALIBRATION_SAMPLES {
            let swing = if (i / 40) % 2 == 0 { 0.2 } else { -0.2 };
            result = cal.add(&sample([0.0, swing, 0.0], [0.0, 0.0, -GRAVITY]));
        }
        match result {
            Some(Err(CalibrationFailure::Moving { axis, gyro, spread })) => {
                assert_eq!(axis, 1);
                assert!(gyro);
                assert!((spread - 0.2).abs() < 0.01, "{spread}");
            }
            other => panic!("{other:?}"),
        }
        // Carried: the accelerometer shakes.
        let shaken = run(
            CalibrationKind::Gyro,
            [0.0; 3],
            [0.0, 0.0, -GRAVITY],
            0.0,
            2.0,
        );
        assert!(
            matches!(shaken, Err(CalibrationFailure::Moving { gyro: false, .. })),
            "{shaken:?}"
        );
    }

    #[test]
    fn offsets_no_bias_explains_fail() {
        // A steady turn at 1 rad/s is not a bias.
        let turning = run(
            CalibrationKind::Gyro,
            [0.0, 0.0, 1.0],
            [0.0, 0.0, -GRAVITY],
            0.0,
            0.0,
        );
        assert_eq!(
            turning,
            Err(CalibrationFailure::OffsetTooLarge {
                axis: 2,
                offset: 1.0
            })
        );
        // Tilted by 20 degrees: not level.
        let (s, c) = (math::sin(0.35), math::cos(0.35));
        let tilted = run(
            CalibrationKind::Level,
            [0.0; 3],
            [GRAVITY * s, 0.0, -GRAVITY * c],
            0.0,
            0.0,
        );
        assert!(
            matches!(
                tilted,
                Err(CalibrationFailure::OffsetTooLarge { axis: 0, .. })
            ),
            "{tilted:?}"
        );
        // In free fall (or accelerating): not at rest.
        let falling = run(CalibrationKind::Gyro, [0.0; 3], [0.0, 0.0, -3.0], 0.0, 0.0);
        assert!(matches!(falling, Err(CalibrationFailure::NotAtRest { .. })));
        let mut cal = ImuCalibration::new(CalibrationKind::Gyro);
        assert_eq!(
            cal.add(&sample([f32::NAN, 0.0, 0.0], [0.0; 3])),
            Some(Err(CalibrationFailure::NotANumber))
        );
    }

    #[test]
    fn a_motor_test_spins_only_its_rotors_and_stops_at_its_time() {
        let mut test = MotorTest::new(2, 2, 0.15, 0.5);
        assert_eq!(test.command(1), 0.0);
        assert_eq!(test.command(2), 0.15);
        assert_eq!(test.command(3), 0.15);
        assert_eq!(test.command(4), 0.0);
        let mut steps = 0;
        while test.step(0.0025) {
            steps += 1;
        }
        // 0.5 s of 2.5 ms steps, give or take the sum's rounding.
        assert!((199..=200).contains(&steps), "{steps}");
        // The longest test is 3 s, whatever is asked.
        let mut long = MotorTest::new(0, 1, 2.0, 60.0);
        assert_eq!(long.command(0), 1.0);
        let mut steps = 0;
        while long.step(0.0025) {
            steps += 1;
        }
        assert!((1199..=1200).contains(&steps), "{steps}");
        assert_eq!(MotorTest::new(0, 1, f32::NAN, f32::NAN).command(0), 0.0);
    }
}

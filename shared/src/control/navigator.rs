//! The vehicle's state estimate as every phase uses it (docs/models.md#state-estimation: the lift-off
//! detector reads the attitude on the ground, the cascade reads attitude, position and
//! velocity in flight): the attitude filter and the position observer fed by the IMU every
//! tick and by motion-capture fixes when they come.
//!
//! Once the IMU is dropped ([`Navigator::drop_imu`], it failed in flight) both run on motion
//! capture and on what the rotors were told ([`Navigator::rotor_command`]): the angular
//! acceleration and specific force the allocated thrusts make on the vehicle model stand in for
//! the gyro and the accelerometer in the prediction, and the fixes correct it. Without that
//! model, a rate differentiated from 100 Hz fixes lags too far for the rate loop: in the plant
//! the cascade oscillated and the payload dropped within a second.

use crate::control::attitude_estimator::{
    AttitudeEstimator, AttitudeEstimatorGains, AttitudeState,
};
use crate::control::position_estimator::{
    PositionEstimator, PositionEstimatorGains, PositionState,
};
use crate::control::vector::{Quat, Vec3};
use crate::math;
use crate::scenario::GRAVITY;

/// One IMU sample in the body frame (FRD).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ImuSample {
    /// Body rate, rad/s.
    pub gyro: Vec3,
    /// Specific force, m/s^2 (`z = -9.81` at rest, level).
    pub accel: Vec3,
}

/// One motion-capture fix of the payload frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MocapFix {
    /// Position, world NED from the take-off point, m.
    pub position: Vec3,
    /// Attitude, body to world.
    pub attitude: Quat,
    /// When the fix was taken, on the flight controller's clock, us.
    pub stamp_us: u64,
}

/// What the vehicle believes about itself.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NavState {
    /// Attitude and body rate.
    pub attitude: AttitudeState,
    /// Position and velocity.
    pub position: PositionState,
}

impl NavState {
    /// Height above a ground at NED z `ground_z`, m.
    pub fn height_above(&self, ground_z: f32) -> f32 {
        ground_z - self.position.position.z
    }

    /// Sine squared of the tilt from level (0 when level), from the attitude quaternion's
    /// body z axis: a few multiplications, no trigonometry.
    pub fn sin2_tilt(&self) -> f32 {
        let q = self.attitude.attitude;
        let cos = 1.0 - 2.0 * (q.x * q.x + q.y * q.y);
        math::max(1.0 - cos * cos, 0.0)
    }

    /// Cosine of the tilt from level (1 when level).
    pub fn level_cosine(&self) -> f32 {
        self.attitude.attitude.rotate(Vec3::DOWN).z
    }
}

/// The attitude filter and the position observer together.
#[derive(Clone, Debug)]
pub struct Navigator {
    attitude: AttitudeEstimator,
    position: PositionEstimator,
    imu_dropped: bool,
    /// Without the IMU: body angular acceleration (rad/s^2) and specific force (m/s^2) of the
    /// last rotor command.
    commanded: (Vec3, Vec3),
    delivered: (Vec3, Vec3),
}

/// Time constant of the rotors' thrust response to a command, s (the plant's motors; a real
/// propulsion set's is 20 to 50 ms).
pub const ROTOR_TIME_CONSTANT: f32 = 0.02;

impl Default for Navigator {
    fn default() -> Self {
        Self::new()
    }
}

impl Navigator {
    /// Both estimators with their default gains, before any sample.
    pub const fn new() -> Self {
        Self {
            attitude: AttitudeEstimator::new(AttitudeEstimatorGains::DEFAULT),
            position: PositionEstimator::new(PositionEstimatorGains::DEFAULT),
            imu_dropped: false,
            commanded: (Vec3::ZERO, Vec3::ZERO),
            delivered: (Vec3::ZERO, Vec3::ZERO),
        }
    }

    /// What the rotors were last commanded, as the vehicle model turns it into motion: body
    /// angular acceleration (rad/s^2) and specific force (m/s^2, body): the prediction once
    /// the IMU is dropped (ignored while it is used). Non-finite values are ignored.
    pub fn rotor_command(&mut self, angular_acceleration: Vec3, specific_force: Vec3) {
        if angular_acceleration.is_finite() && specific_force.is_finite() {
            self.commanded = (angular_acceleration, specific_force);
        }
    }

    /// The rotor command as the rotors deliver it: a first-order lag of
    /// [`ROTOR_TIME_CONSTANT`] behind what they were told.
    fn delivered(&mut self, dt: f32) -> (Vec3, Vec3) {
        let k = crate::math::clamp(dt / ROTOR_TIME_CONSTANT, 0.0, 1.0);
        let (alpha, force) = self.commanded;
        let (a, f) = &mut self.delivered;
        *a += (alpha - *a) * k;
        *f += (force - *f) * k;
        (*a, *f)
    }

    /// Stops using the IMU (it failed): from the next update on, its samples are ignored.
    pub fn drop_imu(&mut self) {
        if !self.imu_dropped {
            self.imu_dropped = true;
            self.delivered = self.commanded;
            self.position.learn_bias(true);
            self.attitude.forget_rate();
        }
    }

    /// Uses the IMU again (a new mission on a sensor that passes the checks again).
    pub fn restore_imu(&mut self) {
        self.imu_dropped = false;
        self.position.learn_bias(false);
    }

    /// Whether the IMU is dropped.
    pub fn imu_dropped(&self) -> bool {
        self.imu_dropped
    }

    /// Takes a motion-capture fix (it may arrive late: each estimator meets it at its stamp).
    pub fn motion_capture(&mut self, fix: &MocapFix) {
        self.attitude.set_reference(fix.attitude, fix.stamp_us);
        self.position.correct(fix.position, fix.stamp_us);
    }

    /// One IMU sample at `now_us`, `dt` seconds after the previous one (ignored once the IMU
    /// is dropped: the rotor command predicts instead).
    pub fn update(&mut self, imu: &ImuSample, dt: f32, now_us: u64) -> NavState {
        if self.imu_dropped {
            let (alpha, force) = self.delivered(dt);
            let attitude = self.attitude.update_from_reference(alpha, dt, now_us);
            let world = attitude.attitude.rotate(force) + Vec3::DOWN * GRAVITY;
            self.position.predict(world, dt, now_us);
            return NavState {
                attitude,
                position: self.position.state(),
            };
        }
        let attitude = self.attitude.update(imu.gyro, imu.accel, dt, now_us);
        let world = attitude.attitude.rotate(imu.accel) + Vec3::DOWN * GRAVITY;
        self.position.predict(world, dt, now_us);
        NavState {
            attitude,
            position: self.position.state(),
        }
    }

    /// The estimate after the last update.
    pub fn state(&self) -> NavState {
        NavState {
            attitude: self.attitude.state(),
            position: self.position.state(),
        }
    }
}

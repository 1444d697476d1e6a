//! Attitude and body-rate estimation from the IMU (docs/models.md#state-estimation): a Mahony
//! complementary filter on the unit quaternion, with gyro bias estimation.
//!
//! The gyro is integrated at the IMU rate. The motion-capture attitude, when it comes,
//! corrects all three axes; it is compared with the estimate the filter had when the fix was
//! taken (a short history of estimates), so its latency does not pull the estimate during
//! fast motion. The accelerometer's direction corrects roll and pitch only while
//! no motion-capture attitude has arrived for [`AttitudeEstimatorGains::reference_timeout`]
//! (on the bench, or during a dropout): on a multirotor in flight the accelerometer measures
//! the thrust direction, not gravity, and would pull a tilted estimate towards level during
//! every manoeuvre. The integral of the correction is the gyro bias estimate, learnt as PX4's
//! attitude estimator learns it: quickly for the first seconds at rest, then slowly (0.1/s,
//! PX4's `ATT_W_GYRO_BIAS`), and only while the body turns slower than 0.175 rad/s. A knock
//! or a set-down, whose fast motion the filtered gyro and the late fixes disagree on, would
//! otherwise wind a false bias that takes seconds to unwind, and a lift starting meanwhile
//! reads the estimate's drift as the payload's tilt (docs/models.md#state-estimation).
//!
//! Without the IMU (it failed in flight, [`AttitudeEstimator::update_from_reference`]) the
//! same filter runs on motion capture and the commanded angular acceleration: the rate is a
//! state of its own, driven by the command and corrected by the fixes' error as the bias was,
//! with a third state for the angular acceleration the command does not explain
//! ([`REFERENCE_ONLY_BANDWIDTH`], [`REFERENCE_ONLY_DISTURBANCE_BANDWIDTH`]).

use crate::control::vector::{Quat, Vec3};
use crate::math;
use crate::scenario::GRAVITY;

/// Filter gains.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AttitudeEstimatorGains {
    /// Proportional correction from the accelerometer, rad/s per unit error.
    pub accel_p: f32,
    /// Proportional correction from the motion-capture attitude, rad/s per rad.
    pub reference_p: f32,
    /// Without a motion-capture attitude for this long, the accelerometer corrects tilt, s.
    pub reference_timeout: f32,
    /// Integral gain of the correction (gyro bias), 1/s.
    pub bias_i: f32,
    /// The integral gain for the first [`Self::initial_bias_time`] after the filter starts
    /// (a resting vehicle learns its gyro's offset quickly, as PX4's calibration at rest
    /// does), 1/s.
    pub initial_bias_i: f32,
    /// How long the initial gain lasts, s.
    pub initial_bias_time: f32,
    /// Largest gyro bias estimate, rad/s.
    pub bias_limit: f32,
    /// The accelerometer corrects only while `| |f| - g |` is below this fraction of `g`.
    pub accel_trust_band: f32,
    /// After the initial seconds, the gyro bias is learnt only while the body turns slower
    /// than this, rad/s.
    pub bias_spin_limit: f32,
}

impl AttitudeEstimatorGains {
    /// The defaults.
    pub const DEFAULT: Self = Self {
        accel_p: 1.0,
        reference_p: 2.0,
        reference_timeout: 0.1,
        bias_i: 0.1,
        initial_bias_i: 1.0,
        initial_bias_time: 5.0,
        bias_limit: 0.1,
        accel_trust_band: 0.15,
        bias_spin_limit: 0.175,
    };
}

impl Default for AttitudeEstimatorGains {
    fn default() -> Self {
        Self::DEFAULT
    }
}

/// What the estimator believes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AttitudeState {
    /// Attitude (body to world).
    pub attitude: Quat,
    /// Body rate with the bias removed, rad/s.
    pub rate: Vec3,
    /// Estimated gyro bias, rad/s.
    pub gyro_bias: Vec3,
}

/// Mahony attitude filter.
#[derive(Clone, Debug, PartialEq)]
pub struct AttitudeEstimator {
    gains: AttitudeEstimatorGains,
    state: AttitudeState,
    initialised: bool,
    /// Body-frame rotation vector from the estimate (at the fix's time) to the latest fix.
    reference_error: Option<Vec3>,
    initial_yaw: Option<f32>,
    since_reference: f32,
    history: heapless::Deque<(u64, Quat), ATTITUDE_HISTORY>,
    /// Without the IMU: the angular acceleration the command does not explain, rad/s^2.
    disturbance: Vec3,
    /// Time since the filter started, s (up to the initial gain's time).
    running: f32,
}

/// Estimates kept to meet late motion-capture fixes (0.16 s at 400 Hz).
pub const ATTITUDE_HISTORY: usize = 64;

/// Bandwidth of the attitude and rate observer without the IMU, rad/s: the commanded angular
/// acceleration carries the fast motion; the fixes (5 mrad noise at 100 Hz, 5 to 30 ms late)
/// correct the rest. First tuned on rect-ex1 alone (20 rad/s kept it within 6 deg, 40 dropped
/// it); over the campaign's plants (inertia 0.7 to 1.5 times the model's, the fixes up to 30 ms
/// late) 20 rad/s dropped 25 of 44 payloads whose IMU froze or went noisy in flight, 12 rad/s
/// 4, 10 rad/s 3, 8 rad/s 2; the paper's payloads tilt at most 10 deg at 10 rad/s, 16.5 at 8.
pub const REFERENCE_ONLY_BANDWIDTH: f32 = 10.0;
/// Bandwidth of the disturbance estimate without the IMU, rad/s: the angular acceleration the
/// command does not explain (the hover torque of a COM the model misplaces, the disturbance
/// torque, the ground's reaction), learnt so the rate estimate carries no steady error.
pub const REFERENCE_ONLY_DISTURBANCE_BANDWIDTH: f32 = 8.0;

impl AttitudeEstimator {
    /// A filter that initialises its tilt from the first accelerometer sample.
    pub const fn new(gains: AttitudeEstimatorGains) -> Self {
        Self {
            gains,
            state: AttitudeState {
                attitude: Quat::IDENTITY,
                rate: Vec3::ZERO,
                gyro_bias: Vec3::ZERO,
            },
            initialised: false,
            reference_error: None,
            initial_yaw: None,
            since_reference: f32::INFINITY,
            history: heapless::Deque::new(),
            disturbance: Vec3::ZERO,
            running: 0.0,
        }
    }

    /// The current estimate.
    pub fn state(&self) -> AttitudeState {
        self.state
    }

    /// An attitude from motion capture taken at `stamp_us` (the clock `update` is given): it
    /// is compared with the estimate of that instant and the difference corrects every IMU
    /// step until a newer fix comes or it grows older than `reference_timeout`.
    pub fn set_reference(&mut self, attitude: Quat, stamp_us: u64) {
        if !attitude.is_finite() {
            return;
        }
        let then = self
            .history
            .iter()
            .rev()
            .find(|&&(t, _)| t <= stamp_us)
            .map(|&(_, q)| q)
            .unwrap_or(self.state.attitude);
        if !self.initialised {
            self.reference_error = None;
            self.initial_yaw = Some(attitude.to_euler().z);
            return;
        }
        let error = then.conjugate() * attitude.normalized();
        let sign = if error.w < 0.0 { -1.0 } else { 1.0 };
        self.reference_error = Some(error.vector() * (2.0 * sign));
        self.since_reference = 0.0;
    }

    /// One IMU sample at `now_us`: gyro (rad/s, body) and accelerometer specific force
    /// (m/s^2, body), `dt` seconds after the previous one. Non-finite samples are skipped.
    pub fn update(&mut self, gyro: Vec3, accel: Vec3, dt: f32, now_us: u64) -> AttitudeState {
        if !(gyro.is_finite() && accel.is_finite() && dt > 0.0 && dt < 0.1) {
            return self.state;
        }
        // At rest an accelerometer reads the reaction to gravity, f = R^T (0, 0, -g): world
        // down seen from the body is -f / |f| = (-sin(pitch), sin(roll) cos(pitch),
        // cos(roll) cos(pitch)).
        let f_norm = accel.norm();
        if !self.initialised {
            if f_norm > 0.5 * GRAVITY {
                let down = -accel * (1.0 / f_norm);
                let roll = math::atan2(down.y, down.z);
                let pitch = math::asin(-down.x);
                let yaw = self.initial_yaw.unwrap_or(0.0);
                self.state.attitude = Quat::from_euler(roll, pitch, yaw);
                self.initialised = true;
            }
            self.state.rate = gyro;
            return self.state;
        }
        let q = self.state.attitude;
        let mut correction = Vec3::ZERO;
        // The latest fix corrects every step while it is fresh (fixes come slower than IMU
        // samples; correcting only on arrival would cut the gain by the rate ratio).
        if let Some(error) = self.reference_error {
            if self.since_reference <= self.gains.reference_timeout {
                correction += error * self.gains.reference_p;
            }
        }
        let accel_trusted = (f_norm - GRAVITY).abs() < self.gains.accel_trust_band * GRAVITY;
        if self.since_reference > self.gains.reference_timeout && accel_trusted {
            let measured_down = -accel * (1.0 / f_norm);
            let estimated_down = q.inverse_rotate(Vec3::DOWN);
            correction += measured_down.cross(estimated_down) * self.gains.accel_p;
        }
        let rate = gyro - self.state.gyro_bias;
        // The first seconds learn whatever the gyro reads (its offset may exceed the spin
        // limit before it is learnt); after them, slowly and only while turning slowly.
        let initial = self.running < self.gains.initial_bias_time;
        let bias_i = if initial {
            self.running += dt;
            self.gains.initial_bias_i
        } else {
            self.gains.bias_i
        };
        if initial || rate.norm() < self.gains.bias_spin_limit {
            let bias_step = -correction * (bias_i * dt);
            let limit = Vec3::splat(self.gains.bias_limit);
            self.state.gyro_bias = (self.state.gyro_bias + bias_step).clamp_each(limit);
        }
        let rate = gyro - self.state.gyro_bias;
        let omega = rate + correction;
        self.state.attitude = (q * Quat::from_rotation_vector(omega * dt)).normalized();
        self.state.rate = rate;
        self.since_reference += dt;
        if self.history.is_full() {
            self.history.pop_front();
        }
        let _ = self.history.push_back((now_us, self.state.attitude));
        self.state
    }
}

impl AttitudeEstimator {
    /// Forgets the body rate (the IMU it came from failed): [`Self::update_from_reference`]
    /// starts from rest and learns the rate from the fixes.
    pub fn forget_rate(&mut self) {
        self.state.rate = Vec3::ZERO;
        self.disturbance = Vec3::ZERO;
    }

    /// One step without the IMU, `dt` seconds after the previous one, at `now_us`: the body
    /// rate driven by `angular_acceleration` (rad/s^2, what the rotors were commanded) and
    /// both it and the attitude corrected by the motion-capture fixes (a third-order
    /// observer with the unexplained angular acceleration; the fixes' latency is met as in
    /// [`Self::update`]). Without a fresh fix it
    /// predicts on the command and the disturbance learnt so far.
    pub fn update_from_reference(
        &mut self,
        angular_acceleration: Vec3,
        dt: f32,
        now_us: u64,
    ) -> AttitudeState {
        if !(dt > 0.0 && dt < 0.1 && angular_acceleration.is_finite()) {
            return self.state;
        }
        let error = match self.reference_error {
            Some(e) if self.since_reference <= self.gains.reference_timeout => e,
            _ => Vec3::ZERO,
        };
        // Poles at -w (twice) and -wd: (s + w)^2 (s + wd).
        let (w, wd) = (
            REFERENCE_ONLY_BANDWIDTH,
            REFERENCE_ONLY_DISTURBANCE_BANDWIDTH,
        );
        self.disturbance += error * (w * w * wd * dt);
        self.state.rate +=
            (angular_acceleration + self.disturbance + error * (w * w + 2.0 * w * wd)) * dt;
        let omega = self.state.rate + error * (2.0 * w + wd);
        self.state.attitude =
            (self.state.attitude * Quat::from_rotation_vector(omega * dt)).normalized();
        self.since_reference += dt;
        if self.history.is_full() {
            self.history.pop_front();
        }
        let _ = self.history.push_back((now_us, self.state.attitude));
        self.state
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Specific force of a vehicle at rest with attitude `q` (body frame).
    fn at_rest(q: Quat) -> Vec3 {
        q.inverse_rotate(Vec3::new(0.0, 0.0, -GRAVITY))
    }

    #[test]
    fn converges_to_a_tilt_and_learns_the_gyro_bias() {
        let truth = Quat::from_euler(0.2, -0.1, 0.7);
        let bias = Vec3::new(0.02, -0.015, 0.01);
        let mut est = AttitudeEstimator::new(AttitudeEstimatorGains::default());
        // Starts from the first sample with a wrong yaw; the accelerometer levels it, then
        // motion capture brings the yaw.
        for k in 0..400 * 120 {
            let now = k * 2500;
            if k % 4 == 0 && k > 400 * 60 {
                est.set_reference(truth, now); // motion capture for the second minute
            }
            est.update(bias, at_rest(truth), 0.0025, now);
        }
        let s = est.state();
        let e = s.attitude.to_euler();
        assert!((e - Vec3::new(0.2, -0.1, 0.7)).norm() < 0.01, "{e:?}");
        assert!((s.gyro_bias - bias).norm() < 3e-3, "{:?}", s.gyro_bias);
        assert!(
            s.rate.norm() < 3e-3,
            "bias removed from the rate: {:?}",
            s.rate
        );
    }

    /// Motion capture at 100 Hz, IMU at 400 Hz, a gyro bias: the estimate of a resting payload
    /// must settle within 2 mrad and stop drifting (a lift-off detector watches for 10 mrad).
    #[test]
    fn slower_reference_still_holds_a_resting_payload_steady() {
        let truth = Quat::from_euler(0.01, -0.02, 0.4);
        let bias = Vec3::new(0.01, -0.012, 0.008);
        let mut est = AttitudeEstimator::new(AttitudeEstimatorGains::default());
        let tilt_error = |e: &AttitudeEstimator| {
            let a = e.state().attitude.rotate(Vec3::DOWN);
            let b = truth.rotate(Vec3::DOWN);
            math::acos(a.dot(b).clamp(-1.0, 1.0))
        };
        let mut at_15 = 0.0;
        for k in 0..400 * 25 {
            if k % 4 == 0 {
                est.set_reference(truth, k * 2500);
            }
            est.update(bias, at_rest(truth), 0.0025, k * 2500);
            if k == 400 * 15 {
                at_15 = tilt_error(&est);
            }
        }
        let at_25 = tilt_error(&est);
        assert!(at_25 < 2e-3, "{at_25}");
        assert!((at_25 - at_15).abs() < 1e-3, "drift {at_15} -> {at_25}");
    }

    /// A set-down after a lift: the payload tips 6 degrees back to rest in 0.15 s, seen by a
    /// gyro 20 ms late (the IMU's filters) and by fixes stamped when taken. The gyro bias must
    /// not learn the disagreement: from a second after the knock, over the two seconds a lift's
    /// settling and ramp take, the estimate moves by less than 1 mrad (a lift reads 10 mrad as
    /// lift-off; with the bias learnt at 1/s at any rate it moves 1.3 mrad).
    #[test]
    fn a_knock_does_not_wind_the_gyro_bias() {
        let dt = 0.0025;
        let mut est = AttitudeEstimator::new(AttitudeEstimatorGains::default());
        let tipped = 6.0f32.to_radians();
        let fall = 0.15;
        // Roll at time t: tipped until 10 s, back to level over `fall` (a half cosine).
        let roll = |t: f32| {
            if t < 10.0 {
                tipped
            } else if t < 10.0 + fall {
                0.5 * tipped * (1.0 + (core::f32::consts::PI * (t - 10.0) / fall).cos())
            } else {
                0.0
            }
        };
        let rate = |t: f32| (roll(t + dt) - roll(t)) / dt;
        let lag = 0.02;
        let (mut low, mut high) = (f32::INFINITY, f32::NEG_INFINITY);
        for k in 0..(400 * 13 + 40) {
            let t = k as f32 * dt;
            let now = k * 2500;
            if k % 4 == 0 {
                est.set_reference(Quat::from_euler(roll(t), 0.0, 0.0), now);
            }
            let gyro = Vec3::new(rate(t - lag), 0.0, 0.0);
            let accel = at_rest(Quat::from_euler(roll(t - lag), 0.0, 0.0));
            est.update(gyro, accel, dt, now);
            if (11.0..=13.0).contains(&t) {
                let x = est.state().attitude.rotate(Vec3::DOWN).y;
                low = low.min(x);
                high = high.max(x);
            }
        }
        assert!(high - low < 1e-3, "moved {} rad", high - low);
    }

    /// A vehicle turning faster than the spin limit from its start (a restart while the payload
    /// still swings): the first seconds learn the gyro's offset anyway.
    #[test]
    fn the_first_seconds_learn_the_offset_while_turning() {
        let bias = Vec3::new(0.05, -0.04, 0.03);
        let spin = Vec3::new(0.0, 0.0, 0.5);
        let mut est = AttitudeEstimator::new(AttitudeEstimatorGains::default());
        let mut truth = Quat::IDENTITY;
        for k in 0..400 * 5 {
            truth = (truth * Quat::from_rotation_vector(spin * 0.0025)).normalized();
            if k % 4 == 0 {
                est.set_reference(truth, k * 2500);
            }
            est.update(spin + bias, at_rest(truth), 0.0025, k * 2500);
        }
        let learnt = est.state().gyro_bias;
        assert!((learnt - bias).norm() < 0.01, "{learnt:?}");
    }

    #[test]
    fn tracks_a_rotation_from_the_gyro() {
        let mut est = AttitudeEstimator::new(AttitudeEstimatorGains::default());
        let mut truth = Quat::IDENTITY;
        let rate = Vec3::new(0.0, 0.0, 0.5); // pure yaw keeps the accelerometer reading fixed
        for k in 0..800u64 {
            truth = (truth * Quat::from_rotation_vector(rate * 0.0025)).normalized();
            est.update(rate, at_rest(truth), 0.0025, k * 2500);
        }
        let yaw = est.state().attitude.to_euler().z;
        assert!((yaw - truth.to_euler().z).abs() < 0.01, "{yaw}");
    }
}

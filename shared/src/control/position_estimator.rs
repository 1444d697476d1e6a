//! Position and velocity in the world frame (NED, from the take-off point) from the
//! accelerometer at the control rate and motion-capture fixes at 30 to 120 Hz that arrive late
//! or not at all (docs/models.md#state-estimation).
//!
//! A second-order complementary observer: the state is propagated with the world-frame
//! acceleration every tick; a fix stamped at `t` is compared with the state the observer had
//! at `t` (kept in a short history), and the innovation corrects position and velocity with
//! gains `2 zeta w` and `w^2`. A fix older than the history, or none for `fix_timeout`, marks
//! the estimate invalid so the caller can hold or land.

use crate::control::vector::Vec3;
use crate::math;

/// Gain of the acceleration bias learnt from the fixes while [`PositionEstimator::learn_bias`]
/// is on, rad/s: the third coefficient is `bandwidth^2` times it (stable below
/// `2 damping bandwidth`, 7.2 rad/s). At 3 rad/s a landing without the IMU comes to rest in
/// the estimate (below the land detector's 0.1 m/s) about 1.5 s after touchdown; at 1 rad/s
/// the velocity error stayed above it for the 5 s the flight waits.
pub const BIAS_BANDWIDTH: f32 = 3.0;

/// Ticks of history kept for late fixes (0.32 s at 400 Hz).
pub const HISTORY: usize = 128;

/// Observer tuning.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PositionEstimatorGains {
    /// Observer bandwidth, rad/s.
    pub bandwidth: f32,
    /// Observer damping ratio.
    pub damping: f32,
    /// Without a fix for this long the estimate is invalid, s. One second, PX4's
    /// `COM_POS_FS_DELAY`: motion capture loses fixes in bursts (occlusions). At 0.25 s a
    /// campaign of healthy vehicles (`host-sim campaign`, 5 % of fixes lost in bursts of 50 ms
    /// on average) aborted one mission in twelve for a position lost that the IMU carried
    /// through; at 0.5 s one in a thousand (a burst of 0.53 s, seed 1, trial 440). Dead
    /// reckoning on the IMU with 0.05 m/s^2 of bias left drifts 2.5 cm in that second.
    pub fix_timeout: f32,
}

impl PositionEstimatorGains {
    /// The defaults.
    pub const DEFAULT: Self = Self {
        bandwidth: 4.0,
        damping: 0.9,
        fix_timeout: 1.0,
    };
}

impl Default for PositionEstimatorGains {
    fn default() -> Self {
        Self::DEFAULT
    }
}

/// The observer's output.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PositionState {
    /// Position, m (NED from the take-off point).
    pub position: Vec3,
    /// Velocity, m/s.
    pub velocity: Vec3,
    /// False before the first fix or after `fix_timeout` without one.
    pub valid: bool,
}

/// The position and velocity observer.
#[derive(Clone, Debug)]
pub struct PositionEstimator {
    gains: PositionEstimatorGains,
    position: Vec3,
    velocity: Vec3,
    history: [(u64, Vec3); HISTORY],
    head: usize,
    filled: usize,
    last_fix_us: Option<u64>,
    now_us: u64,
    /// Acceleration bias learnt from the fixes, m/s^2 (world), while `learn_bias`.
    bias: Vec3,
    learn_bias: bool,
}

impl PositionEstimator {
    /// An observer with no fix yet.
    pub const fn new(gains: PositionEstimatorGains) -> Self {
        Self {
            gains,
            position: Vec3::ZERO,
            velocity: Vec3::ZERO,
            history: [(0, Vec3::ZERO); HISTORY],
            head: 0,
            filled: 0,
            last_fix_us: None,
            now_us: 0,
            bias: Vec3::ZERO,
            learn_bias: false,
        }
    }

    /// Learns (from now on, starting from zero) or stops learning a constant bias of the
    /// acceleration `predict` is given: a third-order observer, for a prediction that is a
    /// model's rather than an accelerometer's (the IMU failed; the vehicle model's thrust is
    /// off by the mass error, and on the ground the ground carries what the rotors do not).
    pub fn learn_bias(&mut self, on: bool) {
        self.learn_bias = on;
        self.bias = Vec3::ZERO;
    }

    /// Propagates with world acceleration `acceleration` (m/s^2, gravity removed) over `dt`,
    /// ending at time `now_us`.
    pub fn predict(&mut self, acceleration: Vec3, dt: f32, now_us: u64) {
        if acceleration.is_finite() && dt > 0.0 && dt < 0.1 {
            let acceleration = acceleration + self.bias;
            self.position += self.velocity * dt + acceleration * (0.5 * dt * dt);
            self.velocity += acceleration * dt;
        }
        self.now_us = now_us;
        self.history[self.head] = (now_us, self.position);
        self.head = (self.head + 1) % HISTORY;
        self.filled = (self.filled + 1).min(HISTORY);
    }

    /// Position the observer had at `t_us` (the newest entry not after it).
    fn position_at(&self, t_us: u64) -> Option<Vec3> {
        (1..=self.filled)
            .map(|k| self.history[(self.head + HISTORY - k) % HISTORY])
            .find(|&(t, _)| t <= t_us)
            .map(|(_, p)| p)
    }

    /// A motion-capture position fix stamped `stamp_us`. Returns false (fix ignored) when it
    /// is not finite, from the future, or older than the history.
    pub fn correct(&mut self, position: Vec3, stamp_us: u64) -> bool {
        if !position.is_finite() || stamp_us > self.now_us {
            return false;
        }
        let Some(first) = self.last_fix_us else {
            // First fix: take it as it is.
            self.position = position;
            self.velocity = Vec3::ZERO;
            self.last_fix_us = Some(stamp_us);
            return true;
        };
        let Some(then) = self.position_at(stamp_us) else {
            return false;
        };
        let interval = math::clamp(stamp_us.saturating_sub(first) as f32 * 1e-6, 1e-3, 0.1);
        let innovation = position - then;
        let w = self.gains.bandwidth;
        let k_position = (2.0 * self.gains.damping * w * interval).min(1.0);
        let k_velocity = w * w * interval;
        self.position += innovation * k_position;
        self.velocity += innovation * k_velocity;
        if self.learn_bias {
            self.bias += innovation * (w * w * BIAS_BANDWIDTH * interval);
        }
        self.last_fix_us = Some(stamp_us);
        true
    }

    /// The current estimate.
    pub fn state(&self) -> PositionState {
        let valid = self.last_fix_us.is_some_and(|t| {
            (self.now_us.saturating_sub(t) as f32) * 1e-6 <= self.gains.fix_timeout
        });
        PositionState {
            position: self.position,
            velocity: self.velocity,
            valid,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn late_fixes_at_60_hz_track_a_constant_acceleration() {
        let mut est = PositionEstimator::new(PositionEstimatorGains::default());
        let accel = Vec3::new(0.5, -0.2, 0.0);
        let latency_us = 30_000; // fixes arrive 30 ms after they were taken
        let truth = |t: f32| accel * (0.5 * t * t);
        let mut pending: heapless::Deque<(u64, Vec3), 16> = heapless::Deque::new();
        for k in 1..=1600u64 {
            let now = k * 2500;
            est.predict(accel + Vec3::new(0.05, 0.0, 0.0), 0.0025, now); // biased accelerometer
            if k % 7 == 0 {
                let _ = pending.push_back((now, truth(now as f32 * 1e-6)));
            }
            while let Some(&(stamp, p)) = pending.front() {
                if stamp + latency_us > now {
                    break;
                }
                est.correct(p, stamp);
                pending.pop_front();
            }
        }
        let s = est.state();
        let t = 1600.0 * 0.0025;
        assert!(s.valid);
        assert!(
            (s.position - truth(t)).norm() < 0.02,
            "{:?} vs {:?}",
            s.position,
            truth(t)
        );
        assert!((s.velocity - accel * t).norm() < 0.05, "{:?}", s.velocity);
    }

    #[test]
    fn invalid_without_fixes_and_ignores_bad_ones() {
        let mut est = PositionEstimator::new(PositionEstimatorGains::default());
        est.predict(Vec3::ZERO, 0.0025, 2500);
        assert!(!est.state().valid, "no fix yet");
        assert!(est.correct(Vec3::new(1.0, 0.0, 0.0), 2500));
        assert!(!est.correct(Vec3::new(f32::NAN, 0.0, 0.0), 2500));
        assert!(!est.correct(Vec3::ZERO, 10_000), "from the future");
        for k in 2..400u64 {
            est.predict(Vec3::ZERO, 0.0025, k * 2500);
        }
        assert!(
            est.state().valid,
            "almost 1 s without a fix: still carried by the IMU"
        );
        for k in 400..500u64 {
            est.predict(Vec3::ZERO, 0.0025, k * 2500);
        }
        assert!(!est.state().valid, "1.25 s without a fix");
        assert!((est.state().position.x - 1.0).abs() < 1e-6);
    }
}

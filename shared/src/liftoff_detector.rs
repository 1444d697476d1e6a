//! Lift-off detection during an estimation lift (docs/models.md#lift-off-detector): the pair's
//! thrust ramps slowly while the other robots hold their own weight; the IMU's attitude shows
//! when the payload starts to tilt, and the thrust at that moment is the measurement.
//!
//! The detector first holds the pair at its own weight while the attitude settles and takes
//! the resting attitude as reference. It then ramps at `ramp_rate` and watches the angle
//! between the body's z axis and the reference's. Crossing `tilt_threshold` is the lift-off.
//! Tilt shows up late: after equilibrium is lost the payload must turn far enough to cross the
//! threshold, slowly for a heavy axis, while the thrust ramps on. Past lift-off the unbalanced
//! torque grows with the ramp, `(T - lambda) ~ ramp_rate (t - t0)`, so the tilt grows as
//! `k (t - t0)^3`. The detector keeps the last second of (time, thrust, tilt vector); on
//! crossing the threshold at `t2` it projects that history onto the direction the payload tipped
//! (so the estimate's noise averages out instead of adding to a magnitude), smooths it over a
//! few samples, finds where it first rose above `onset_fraction` of the threshold, `t1`, and
//! solves the cubic through both for the onset `t0 = (t2 - r t1) / (1 - r)`,
//! `r = (tilt2 / tilt1)^(1/3)`. The reading is the ramp's thrust at `t0`, minus
//! `ramp_rate * detection_delay` for the sensor's own latency.
//! If the ramp reaches the robots' maximum and holds it for `settle_time` without a tilt, the
//! reading is "could not lift" (a censored measurement).

use crate::control::vector::{Quat, Vec3};
use crate::estimation::Measurement;
use crate::math;

/// Tuning of the detector.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LiftoffConfig {
    /// Thrust ramp of each robot of the pair, N/s.
    pub ramp_rate: f32,
    /// Tilt from the resting attitude that counts as lift-off, rad.
    pub tilt_threshold: f32,
    /// Latency of the attitude estimate behind the payload (the IMU's), compensated, s.
    pub detection_delay: f32,
    /// Share of the threshold below which the tilt counts as not yet started.
    pub onset_fraction: f32,
    /// Time held at the start (reference) and at maximum thrust (before giving up), s.
    pub settle_time: f32,
}

impl LiftoffConfig {
    /// The defaults (the simulated vehicle's characterised detector).
    pub const DEFAULT: Self = Self {
        ramp_rate: 1.0,
        tilt_threshold: 0.01,
        detection_delay: 0.005,
        onset_fraction: 0.3,
        settle_time: 0.5,
    };
}

impl Default for LiftoffConfig {
    fn default() -> Self {
        Self::DEFAULT
    }
}

/// Where a lift stands.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum LiftState {
    /// Holding the pair at its own weight while the resting attitude is taken.
    Settling,
    /// Ramping the pair's thrust.
    Ramping,
    /// Holding maximum thrust, waiting for a tilt that has not come.
    HoldingMaximum,
    /// Done: the measurement for the estimator.
    Measured(Measurement),
}

/// Samples of (thrust, tilt) kept to find the tilt's onset (one second at 400 Hz).
pub const HISTORY: usize = 400;
/// Samples averaged when the history is projected (20 ms at 400 Hz).
const SMOOTHING: usize = 8;

/// Thrust of a linear ramp `back` seconds before it reached `thrust`.
fn ramp_back(thrust: f32, rate: f32, back: f32) -> f32 {
    thrust - rate * back
}

/// One lift.
#[derive(Clone, Debug, PartialEq)]
pub struct LiftoffDetector {
    config: LiftoffConfig,
    start_thrust: f32,
    max_thrust: f32,
    thrust: f32,
    timer: f32,
    reference_axis: Vec3,
    state: LiftState,
    history: heapless::Deque<(f32, f32, Vec3), HISTORY>,
    clock: f32,
}

impl LiftoffDetector {
    /// A lift whose pair starts at `start_thrust` (the robots' own weight, N) and may go up
    /// to `max_thrust` (N, per robot).
    pub fn new(config: LiftoffConfig, start_thrust: f32, max_thrust: f32) -> Self {
        Self {
            config,
            start_thrust,
            max_thrust,
            thrust: start_thrust,
            timer: 0.0,
            reference_axis: Vec3::ZERO,
            state: LiftState::Settling,
            history: heapless::Deque::new(),
            clock: 0.0,
        }
    }

    /// Where the lift stands.
    pub fn state(&self) -> LiftState {
        self.state
    }

    /// The body's down axis (world frame) at rest before the ramp, the reference of the tilt;
    /// zero while settling.
    pub fn resting_axis(&self) -> Vec3 {
        self.reference_axis
    }

    /// Thrust to command on each robot of the pair now, N.
    pub fn pair_thrust(&self) -> f32 {
        self.thrust
    }

    /// The onset of the tilt (detector clock, s) from the history, the tilt now being
    /// `tilt_vector` (change of the body z axis since the reference).
    fn onset(&self, tilt_vector: Vec3) -> f32 {
        let direction = tilt_vector.normalized();
        // Walk back from the newest sample, projecting as it goes and smoothing with a
        // trailing moving average kept as a running sum over the window: only the samples
        // since the tilt rose are touched (this runs inside a control tick).
        let mut older = self
            .history
            .iter()
            .rev()
            .map(|&(t, _, v)| (t, v.dot(direction)));
        // Samples i, i - 1, ..., i - SMOOTHING + 1: the window of the smoothed value at i.
        let mut window: heapless::Deque<(f32, f32), SMOOTHING> = heapless::Deque::new();
        let mut sum = 0.0f32;
        for sample in older.by_ref().take(SMOOTHING) {
            sum += sample.1;
            // At most SMOOTHING samples were taken.
            let _ = window.push_back(sample);
        }
        let floor = self.config.onset_fraction * self.config.tilt_threshold;
        let t2 = self.clock;
        let tilt2 = sum / math::max(window.len() as f32, 1.0);
        let mut first = (t2, tilt2);
        while let Some(&(t_i, raw_i)) = window.front() {
            let smoothed = sum / window.len() as f32;
            if smoothed <= floor {
                break;
            }
            first = (t_i, smoothed);
            let _ = window.pop_front();
            sum -= raw_i;
            if let Some(sample) = older.next() {
                sum += sample.1;
                let _ = window.push_back(sample);
            }
        }
        // Cubic growth through (t1, tilt1) and (t2, tilt2): the onset t0.
        let (t1, tilt1) = first;
        let r = libm::cbrtf(tilt2 / math::max(tilt1, 1e-9));
        if r > 1.0 + 1e-3 && t2 > t1 {
            math::min((t2 - r * t1) / (1.0 - r), t1)
        } else {
            t1
        }
    }

    /// One step with the current attitude estimate, `dt` seconds after the previous one.
    /// Returns the state after the step.
    pub fn step(&mut self, attitude: Quat, dt: f32) -> LiftState {
        let axis = attitude.rotate(Vec3::DOWN);
        match self.state {
            LiftState::Settling => {
                self.reference_axis += axis;
                self.timer += dt;
                if self.timer >= self.config.settle_time {
                    self.reference_axis = self.reference_axis.normalized();
                    self.timer = 0.0;
                    self.state = LiftState::Ramping;
                }
            }
            LiftState::Ramping | LiftState::HoldingMaximum => {
                let cos = math::clamp(axis.normalized().dot(self.reference_axis), -1.0, 1.0);
                let tilt = crate::math::acos(cos);
                self.clock += dt;
                if self.history.is_full() {
                    self.history.pop_front();
                }
                let tilt_vector = axis.normalized() - self.reference_axis;
                let _ = self
                    .history
                    .push_back((self.clock, self.thrust, tilt_vector));
                if tilt > self.config.tilt_threshold {
                    let onset = self.onset(tilt_vector);
                    let at_onset =
                        ramp_back(self.thrust, self.config.ramp_rate, self.clock - onset);
                    let compensated =
                        at_onset - self.config.ramp_rate * self.config.detection_delay;
                    let thrust = crate::math::max(compensated, self.start_thrust);
                    self.state = LiftState::Measured(Measurement::Lifted { thrust });
                } else if self.state == LiftState::Ramping {
                    self.thrust =
                        crate::math::min(self.thrust + self.config.ramp_rate * dt, self.max_thrust);
                    if self.thrust >= self.max_thrust {
                        self.state = LiftState::HoldingMaximum;
                    }
                } else {
                    self.timer += dt;
                    if self.timer >= self.config.settle_time {
                        self.state = LiftState::Measured(Measurement::CouldNotLift);
                    }
                }
            }
            LiftState::Measured(_) => {}
        }
        self.state
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A payload that starts tilting `lag` seconds after the pair passes `lift_at`.
    fn run(lift_at: f32, lag: f32, max: f32) -> (Measurement, f32) {
        let config = LiftoffConfig {
            detection_delay: lag,
            ..LiftoffConfig::default()
        };
        let mut d = LiftoffDetector::new(config, 0.98, max);
        let dt = 0.0025;
        let mut tilt_start: Option<f32> = None;
        let mut t = 0.0;
        loop {
            let thrust = d.pair_thrust();
            if thrust >= lift_at && tilt_start.is_none() {
                tilt_start = Some(t + lag);
            }
            // Once it goes the tilt grows as the cube of time (the torque grows with the ramp).
            let tilt = tilt_start.map_or(0.0, |s| 0.2 * (t - s).max(0.0).powi(3));
            let q = Quat::from_euler(0.02 + tilt, -0.01, 0.3); // resting slightly off level
            if let LiftState::Measured(m) = d.step(q, dt) {
                return (m, t);
            }
            t += dt;
            assert!(t < 60.0, "the lift must end");
        }
    }

    #[test]
    fn reads_the_lift_off_thrust_with_the_delay_compensated() {
        let (m, _) = run(6.0, 0.005, 14.2);
        let Measurement::Lifted { thrust } = m else {
            panic!("{m:?}");
        };
        // The threshold is crossed at 6 + (0.01 / 0.2)^(1/3) = 6.37 N; the cubic fit through
        // the onset floor finds the lift-off itself.
        assert!((thrust - 6.0).abs() < 0.03, "{thrust}");
    }

    #[test]
    fn a_pair_that_cannot_lift_is_a_censored_reading() {
        let (m, t) = run(20.0, 0.005, 14.2);
        assert_eq!(m, Measurement::CouldNotLift);
        assert!(t > (14.2 - 0.98) / 1.0, "ramped all the way first: {t}");
    }
}

//! The payload's COM and mass estimated in flight from what the controller needs to hold it
//! (beyond the paper, which names a load that shifts in flight as future work).
//!
//! In a steady hover the rotors' torque about the believed COM cancels the weight's: with
//! the true COM at `delta` from the believed one (body FRD, z down) the payload's weight
//! `M g` pulls with torque `(delta_y M g, -delta_x M g)` in roll and pitch, so the rotors
//! deliver `tau = (-delta_y M g, delta_x M g)`:
//!
//! ```text
//! delta_x = tau_pitch / (M g)        delta_y = -tau_roll / (M g)
//! ```
//!
//! and the collective holds the weight: `M = T / g - n m_r`. The delivered wrench is
//! averaged over [`TrimConfig::window`] seconds (the paper's torque disturbance, sinusoids
//! at 0.37 and 0.53 Hz, averages out), only while the vehicle hovers: level, slow, not
//! saturated. The estimate is confident when the two halves of the window agree within
//! [`TrimConfig::steadiness`]: a manoeuvre or a transient leaves the halves apart.

use crate::control::allocation::Wrench;
use crate::control::navigator::NavState;
use crate::geometry::Vec2;
use crate::math;
use crate::scenario::GRAVITY;

/// Tuning of the estimator.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TrimConfig {
    /// Averaging window, s.
    pub window: f32,
    /// Largest speed counted as hovering, m/s.
    pub max_speed: f32,
    /// Largest tilt counted as hovering, rad.
    pub max_tilt: f32,
    /// Largest body rate counted as hovering, rad/s.
    pub max_rate: f32,
    /// Largest difference between the window's two halves, as a COM offset, for the
    /// estimate to count as steady, m.
    pub steadiness: f32,
}

impl TrimConfig {
    /// The defaults.
    pub const DEFAULT: Self = Self {
        window: 6.0,
        max_speed: 0.15,
        max_tilt: 0.1,
        max_rate: 0.3,
        steadiness: 0.01,
    };
}

impl Default for TrimConfig {
    fn default() -> Self {
        Self::DEFAULT
    }
}

/// What the trim says about the payload.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TrimEstimate {
    /// The COM's offset from the believed one, body frame, m.
    pub com_offset: Vec2,
    /// The payload's mass, kg.
    pub mass: f32,
    /// The window is full of hover and its halves agree.
    pub confident: bool,
}

/// Sums over one half window.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
struct Half {
    roll: f32,
    pitch: f32,
    thrust: f32,
    time: f32,
}

impl Half {
    fn add(&mut self, wrench: &Wrench, dt: f32) {
        self.roll += wrench.torque.x * dt;
        self.pitch += wrench.torque.y * dt;
        self.thrust += wrench.thrust * dt;
        self.time += dt;
    }
}

/// The estimator: the last two complete half windows and the one filling.
#[derive(Clone, Debug, PartialEq)]
pub struct TrimEstimator {
    config: TrimConfig,
    /// Weight of the believed payload, N.
    payload_weight: f32,
    /// Robots' mass, all of them, kg.
    robots_mass: f32,
    previous: Half,
    last: Half,
    filling: Half,
}

impl TrimEstimator {
    /// An estimator for a payload believed to weigh `payload_mass` carried by robots of
    /// `robots_mass` in all.
    pub fn new(config: TrimConfig, payload_mass: f32, robots_mass: f32) -> Self {
        Self {
            config,
            payload_weight: payload_mass * GRAVITY,
            robots_mass,
            previous: Half::default(),
            last: Half::default(),
            filling: Half::default(),
        }
    }

    /// Forgets the window (after the COM it is measured from has changed).
    pub fn restart(&mut self, payload_mass: f32) {
        self.payload_weight = payload_mass * GRAVITY;
        self.previous = Half::default();
        self.last = Half::default();
        self.filling = Half::default();
    }

    /// One tick: the wrench the rotors delivered, the state, whether the allocation cut
    /// anything; `dt` seconds since the previous tick.
    pub fn update(&mut self, delivered: &Wrench, nav: &NavState, saturated: bool, dt: f32) {
        let hovering = nav.position.valid
            && !saturated
            && nav.position.velocity.norm() < self.config.max_speed
            && nav.level_cosine() > math::cos(self.config.max_tilt)
            && nav.attitude.rate.norm() < self.config.max_rate;
        if !hovering {
            self.restart(self.payload_weight / GRAVITY);
            return;
        }
        self.filling.add(delivered, dt);
        if self.filling.time >= 0.5 * self.config.window {
            self.previous = self.last;
            self.last = self.filling;
            self.filling = Half::default();
        }
    }

    fn offset_of(&self, half: &Half) -> Vec2 {
        let w = self.payload_weight.max(1e-3) * half.time.max(1e-6);
        Vec2::new(half.pitch / w, -half.roll / w)
    }

    /// The estimate from the last two complete half windows; `None` before a window of
    /// hover.
    pub fn estimate(&self) -> Option<TrimEstimate> {
        let half = 0.5 * self.config.window;
        if self.previous.time < half || self.last.time < half {
            return None;
        }
        let both = Half {
            roll: self.previous.roll + self.last.roll,
            pitch: self.previous.pitch + self.last.pitch,
            thrust: self.previous.thrust + self.last.thrust,
            time: self.previous.time + self.last.time,
        };
        let apart = (self.offset_of(&self.previous) - self.offset_of(&self.last)).norm();
        Some(TrimEstimate {
            com_offset: self.offset_of(&both),
            mass: both.thrust / both.time / GRAVITY - self.robots_mass,
            confident: apart < self.config.steadiness,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::control::attitude_estimator::AttitudeState;
    use crate::control::position_estimator::PositionState;
    use crate::control::vector::{Quat, Vec3};

    fn hover(velocity: Vec3) -> NavState {
        NavState {
            attitude: AttitudeState {
                attitude: Quat::IDENTITY,
                rate: Vec3::ZERO,
                gyro_bias: Vec3::ZERO,
            },
            position: PositionState {
                position: Vec3::new(0.0, 0.0, -0.5),
                velocity,
                valid: true,
            },
        }
    }

    /// The wrench holding a payload of `mass` whose COM lies `delta` from the believed one,
    /// with the paper's disturbance (0.3 N m at 0.37 and 0.53 Hz) on top.
    fn held(mass: f32, delta: Vec2, t: f32) -> Wrench {
        let w = mass * GRAVITY;
        let d = 0.3 * libm::sinf(2.0 * core::f32::consts::PI * 0.37 * t)
            + 0.2 * libm::sinf(2.0 * core::f32::consts::PI * 0.53 * t + 1.0);
        Wrench {
            thrust: (mass + 0.8) * GRAVITY,
            torque: Vec3::new(-delta.y * w + d, delta.x * w - d, 0.0),
        }
    }

    #[test]
    fn finds_a_shifted_com_and_the_mass_through_the_disturbance() {
        let delta = Vec2::new(0.15, -0.04);
        let mut e = TrimEstimator::new(TrimConfig::DEFAULT, 3.23, 0.8);
        let dt = 0.0025;
        let mut t = 0.0;
        assert_eq!(e.estimate(), None);
        while t < 7.0 {
            e.update(&held(3.23, delta, t), &hover(Vec3::ZERO), false, dt);
            t += dt;
        }
        let est = e.estimate().expect("a window of hover");
        assert!(est.confident, "{est:?}");
        assert!((est.com_offset - delta).norm() < 0.005, "{est:?}");
        assert!((est.mass - 3.23).abs() < 0.01, "{est:?}");
    }

    #[test]
    fn a_manoeuvre_or_a_change_is_not_confident() {
        let dt = 0.0025;
        // Moving: no hover, no estimate.
        let mut e = TrimEstimator::new(TrimConfig::DEFAULT, 3.0, 0.8);
        for k in 0..4000 {
            let t = k as f32 * dt;
            e.update(
                &held(3.0, Vec2::default(), t),
                &hover(Vec3::new(0.4, 0.0, 0.0)),
                false,
                dt,
            );
        }
        assert_eq!(e.estimate(), None);
        // The COM jumps in the middle of the window: the halves disagree.
        let mut e = TrimEstimator::new(TrimConfig::DEFAULT, 3.0, 0.8);
        let mut t = 0.0;
        while t < 6.1 {
            let delta = if t < 4.5 {
                Vec2::default()
            } else {
                Vec2::new(0.1, 0.0)
            };
            e.update(&held(3.0, delta, t), &hover(Vec3::ZERO), false, dt);
            t += dt;
        }
        let est = e.estimate().expect("an estimate");
        assert!(!est.confident, "{est:?}");
        // Saturated ticks restart the window.
        e.update(&held(3.0, Vec2::default(), t), &hover(Vec3::ZERO), true, dt);
        assert_eq!(e.estimate(), None);
    }
}

//! The robots' rail drive: arc length to stepper steps through the pinion on the rack, and
//! trapezoidal motion profiles with speed and acceleration limits, turned into the step times
//! the firmware loads into a timer (docs/models.md#rail-moves: rack and pinion, one stepper each).

use crate::math;

/// The drive train of one robot.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DriveConfig {
    /// Full steps per motor revolution (200 for a 1.8 degree stepper).
    pub steps_per_rev: u32,
    /// Microsteps per full step set in the driver.
    pub microsteps: u32,
    /// Pitch diameter of the pinion, m (the rack advances pi d per revolution).
    pub pinion_pitch_diameter: f32,
}

impl DriveConfig {
    /// The defaults (200-step motors, 16 microsteps, 20 mm pinion).
    pub const DEFAULT: Self = Self {
        steps_per_rev: 200,
        microsteps: 16,
        pinion_pitch_diameter: 0.02,
    };
}

impl Default for DriveConfig {
    fn default() -> Self {
        Self::DEFAULT
    }
}

impl DriveConfig {
    /// Microsteps per metre of rail.
    pub fn steps_per_metre(&self) -> f32 {
        (self.steps_per_rev * self.microsteps) as f32
            / (core::f32::consts::PI * self.pinion_pitch_diameter)
    }

    /// The nearest whole step to arc length `s`, m.
    pub fn to_steps(&self, s: f32) -> i32 {
        math::round(s * self.steps_per_metre()) as i32
    }

    /// Arc length of `steps`, m.
    pub fn to_metres(&self, steps: i32) -> f32 {
        steps as f32 / self.steps_per_metre()
    }
}

/// Speed and acceleration limits of a move.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MotionLimits {
    /// Largest speed, m/s.
    pub max_speed: f32,
    /// Largest acceleration, m/s^2.
    pub max_acceleration: f32,
}

impl MotionLimits {
    /// The defaults.
    pub const DEFAULT: Self = Self {
        max_speed: 0.2,
        max_acceleration: 0.5,
    };
}

impl Default for MotionLimits {
    fn default() -> Self {
        Self::DEFAULT
    }
}

/// A trapezoidal (or, for short moves, triangular) velocity profile over a signed distance.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TrapezoidProfile {
    distance: f32,
    peak_speed: f32,
    acceleration: f32,
    ramp_time: f32,
    cruise_time: f32,
}

impl TrapezoidProfile {
    /// The fastest profile over `distance` (m, signed) within `limits`.
    pub fn new(distance: f32, limits: MotionLimits) -> Self {
        let d = math::abs(distance);
        let a = limits.max_acceleration.max(1e-6);
        let v = limits.max_speed.max(1e-6);
        // Triangular when the speed limit is never reached.
        let peak = math::min(v, math::sqrt(a * d));
        let ramp_time = peak / a;
        let ramp_distance = peak * ramp_time; // both ramps together
        let cruise_time = if peak > 0.0 {
            (d - ramp_distance) / peak
        } else {
            0.0
        };
        Self {
            distance,
            peak_speed: peak,
            acceleration: a,
            ramp_time,
            cruise_time: math::max(cruise_time, 0.0),
        }
    }

    /// Duration, s.
    pub fn duration(&self) -> f32 {
        2.0 * self.ramp_time + self.cruise_time
    }

    /// Signed displacement at time `t` (clamped to the profile), m.
    pub fn position(&self, t: f32) -> f32 {
        let sign = if self.distance < 0.0 { -1.0 } else { 1.0 };
        let t = math::clamp(t, 0.0, self.duration());
        let (a, v, r) = (self.acceleration, self.peak_speed, self.ramp_time);
        let travelled = if t < r {
            0.5 * a * t * t
        } else if t < r + self.cruise_time {
            0.5 * a * r * r + v * (t - r)
        } else {
            let left = self.duration() - t;
            math::abs(self.distance) - 0.5 * a * left * left
        };
        sign * travelled
    }

    /// Time at which the displacement first reaches `|travel|` of the distance, s.
    pub fn time_at(&self, travel: f32) -> f32 {
        let d = math::abs(self.distance);
        let x = math::clamp(math::abs(travel), 0.0, d);
        let (a, v, r) = (self.acceleration, self.peak_speed, self.ramp_time);
        let ramp_distance = 0.5 * a * r * r;
        if x <= ramp_distance {
            math::sqrt(2.0 * x / a)
        } else if x <= d - ramp_distance {
            r + (x - ramp_distance) / v.max(1e-9)
        } else {
            self.duration() - math::sqrt(math::max(2.0 * (d - x) / a, 0.0))
        }
    }
}

/// The instants of each step of one robot's move, for the firmware's step timer.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StepSchedule {
    profile: TrapezoidProfile,
    steps_per_metre: f32,
    total: u32,
    next: u32,
}

impl StepSchedule {
    /// The steps of `profile` on a drive with `config`.
    pub fn new(profile: TrapezoidProfile, config: &DriveConfig) -> Self {
        let steps_per_metre = config.steps_per_metre();
        let total = math::round(math::abs(profile.distance) * steps_per_metre) as u32;
        Self {
            profile,
            steps_per_metre,
            total,
            next: 0,
        }
    }

    /// Direction of every step: +1 forward along the rail, -1 backward.
    pub fn direction(&self) -> i8 {
        if self.profile.distance < 0.0 { -1 } else { 1 }
    }

    /// Steps in the move.
    pub fn total_steps(&self) -> u32 {
        self.total
    }
}

impl Iterator for StepSchedule {
    /// Time of the next step from the start of the move, s.
    type Item = f32;

    fn next(&mut self) -> Option<f32> {
        if self.next >= self.total {
            return None;
        }
        self.next += 1;
        Some(
            self.profile
                .time_at(self.next as f32 / self.steps_per_metre),
        )
    }
}

/// Where a robot is, counted in the steps the firmware has sent its driver.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct StepCounter {
    steps: i32,
}

impl StepCounter {
    /// A counter at `arc_length` (m) on a drive with `config`.
    pub fn at(arc_length: f32, config: &DriveConfig) -> Self {
        Self {
            steps: config.to_steps(arc_length),
        }
    }

    /// One step sent in `direction` (+1 forward, -1 backward).
    pub fn step(&mut self, direction: i8) {
        self.steps = self.steps.saturating_add(i32::from(direction.signum()));
    }

    /// Steps from the rail's origin.
    pub fn steps(&self) -> i32 {
        self.steps
    }

    /// Arc length along a closed rail of `perimeter`, m, in `[0, perimeter)`.
    pub fn arc_length(&self, config: &DriveConfig, perimeter: f32) -> f32 {
        let s = config.to_metres(self.steps);
        let w = s - perimeter * math::floor(s / perimeter);
        if w >= perimeter { 0.0 } else { w }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn steps_round_trip_and_scale_with_the_pinion() {
        let drive = DriveConfig::default();
        // 3200 microsteps per revolution over pi * 20 mm.
        assert!((drive.steps_per_metre() - 3200.0 / (core::f32::consts::PI * 0.02)).abs() < 1e-2);
        let s = 1.2345;
        assert!((drive.to_metres(drive.to_steps(s)) - s).abs() <= 0.5 / drive.steps_per_metre());
    }

    #[test]
    fn profile_respects_its_limits_and_ends_on_target() {
        let limits = MotionLimits::default();
        for distance in [-1.3f32, -0.01, 0.0, 0.05, 0.7, 2.4] {
            let p = TrapezoidProfile::new(distance, limits);
            assert!(
                (p.position(p.duration()) - distance).abs() < 1e-5,
                "{distance}"
            );
            let dt = 1e-3;
            let mut last = 0.0;
            let mut last_v = 0.0;
            let mut t = dt;
            while t <= p.duration() + dt {
                let x = p.position(t);
                let v = (x - last) / dt;
                assert!(v.abs() <= limits.max_speed + 1e-3, "{distance}: speed {v}");
                assert!(
                    ((v - last_v) / dt).abs() <= limits.max_acceleration * 1.05 + 1.0,
                    "{distance}"
                );
                last = x;
                last_v = v;
                t += dt;
            }
            // time_at inverts position.
            let half = 0.5 * distance;
            assert!(
                (p.position(p.time_at(half)) - half).abs() < 1e-4,
                "{distance}"
            );
        }
    }

    #[test]
    fn counting_a_schedule_s_steps_tracks_the_robot_to_its_target() {
        let drive = DriveConfig::default();
        let perimeter = 4.88;
        let mut robot = StepCounter::at(0.1, &drive);
        // Backward across the rail's origin: 0.1 -> 4.68 (wrapped).
        let schedule =
            StepSchedule::new(TrapezoidProfile::new(-0.3, MotionLimits::default()), &drive);
        let direction = schedule.direction();
        for _ in schedule {
            robot.step(direction);
        }
        let s = robot.arc_length(&drive, perimeter);
        assert!(
            (s - 4.68).abs() <= 1.0 / drive.steps_per_metre() + 1e-4,
            "{s}"
        );
    }

    #[test]
    fn step_times_increase_and_cover_the_move() {
        let drive = DriveConfig::default();
        let p = TrapezoidProfile::new(-0.3, MotionLimits::default());
        let schedule = StepSchedule::new(p, &drive);
        assert_eq!(schedule.direction(), -1);
        let total = schedule.total_steps();
        assert_eq!(total, drive.to_steps(0.3) as u32);
        let times: heapless::Vec<f32, 20000> = schedule.collect();
        assert_eq!(times.len() as u32, total);
        assert!(times.windows(2).all(|w| w[1] >= w[0]));
        assert!((times[times.len() - 1] - p.duration()).abs() < 1e-3);
    }
}

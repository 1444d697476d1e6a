//! Position mode's setpoint (docs/manual-control.md#position-mode, PX4's `POSCTL`): a person's
//! sticks command the payload's horizontal velocity, its climb rate and its yaw rate, flown
//! through the formation's own cascade. The setpoint moves at the commanded velocity and is
//! held where it is when the sticks are centred (inside the dead zone, PX4's `MPC_HOLD_DZ`), so
//! centred sticks hold position; it never runs more than [`LEASH`] ahead of the vehicle (a
//! payload pushed against something does not wind up a jump), and never deeper than the
//! landing's own [`SETTLE_DEPTH`] below the ground (throttle down lands: the land detector then
//! stops the rotors).

use crate::control::trajectory::{SETTLE_DEPTH, Setpoint};
use crate::control::vector::Vec3;
use crate::manual::Sticks;
use crate::math;

/// How far the setpoint may run ahead of the vehicle, m.
pub const LEASH: f32 = 0.5;

/// Position mode's limits (PX4's names).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ManualLimits {
    /// Horizontal speed at full stick, m/s (`MPC_VEL_MANUAL`).
    pub horizontal_speed: f32,
    /// Climb rate at full throttle, m/s (`MPC_Z_VEL_MAX_UP`).
    pub climb_speed: f32,
    /// Descent rate at zero throttle, m/s (`MPC_Z_VEL_MAX_DN`).
    pub descent_speed: f32,
    /// Yaw rate at full stick, deg/s (`MPC_MAN_Y_MAX`).
    pub yaw_rate: f32,
    /// Stick travel around the centre that counts as centred, of full travel (`MPC_HOLD_DZ`).
    pub dead_zone: f32,
}

impl ManualLimits {
    /// The defaults: PX4's `MPC_VEL_MANUAL` is 10 m/s for a multicopter; a payload carried by
    /// robots is flown at the plan's own cruise speed, 0.5 m/s.
    pub const DEFAULT: Self = Self {
        horizontal_speed: 0.5,
        climb_speed: 0.3,
        descent_speed: 0.25,
        yaw_rate: 20.0,
        dead_zone: 0.1,
    };
}

impl Default for ManualLimits {
    fn default() -> Self {
        Self::DEFAULT
    }
}

/// What the sticks ask of the payload: a velocity (NED, m/s) and a yaw rate (rad/s).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ManualVelocity {
    /// Velocity, NED, m/s (down positive).
    pub velocity: Vec3,
    /// Yaw rate, rad/s (clockwise seen from above positive).
    pub yaw_rate: f32,
}

/// A stick's deflection past the dead zone, rescaled to the full range.
fn past_dead_zone(value: f32, dead_zone: f32) -> f32 {
    let dz = math::clamp(dead_zone, 0.0, 0.9);
    let magnitude = math::abs(value) - dz;
    if magnitude <= 0.0 {
        return 0.0;
    }
    math::copysign(math::min(magnitude / (1.0 - dz), 1.0), value)
}

impl ManualVelocity {
    /// The velocity `sticks` ask for with the payload heading `yaw` (rad): pitch forward and roll
    /// right in the payload's heading frame, as PX4 flies Position mode; throttle above its
    /// centre climbs and below it descends.
    pub fn from_sticks(sticks: &Sticks, yaw: f32, limits: &ManualLimits) -> Self {
        let dz = limits.dead_zone;
        let forward = past_dead_zone(sticks.pitch, dz) * limits.horizontal_speed;
        let right = past_dead_zone(sticks.roll, dz) * limits.horizontal_speed;
        let (s, c) = (math::sin(yaw), math::cos(yaw));
        let climb = past_dead_zone(2.0 * (sticks.throttle - 0.5), dz);
        let down = if climb >= 0.0 {
            -climb * limits.climb_speed
        } else {
            -climb * limits.descent_speed
        };
        Self {
            velocity: Vec3::new(forward * c - right * s, forward * s + right * c, down),
            yaw_rate: past_dead_zone(sticks.yaw, dz) * limits.yaw_rate.to_radians(),
        }
    }
}

/// The setpoint Position mode flies.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ManualSetpoint {
    setpoint: Setpoint,
}

impl ManualSetpoint {
    /// Position mode taken over from `from` (the setpoint flown until now): held there, still.
    pub fn new(from: Setpoint) -> Self {
        Self {
            setpoint: Setpoint {
                velocity: Vec3::ZERO,
                acceleration: Vec3::ZERO,
                ..from
            },
        }
    }

    /// One tick of `command` for `dt` seconds, the vehicle at `here` (NED) over the ground at
    /// NED height `ground_z`: the setpoint moved and kept on its leash.
    pub fn step(&mut self, command: &ManualVelocity, here: Vec3, ground_z: f32, dt: f32) {
        let sp = &mut self.setpoint;
        let mut next = sp.position + command.velocity * dt;
        // On the leash: the offset from the vehicle at most LEASH, axis by axis, but a setpoint
        // already further out (the take-over's) is only ever brought closer.
        let pull = |next: f32, before: f32, at: f32| {
            let limit = math::max(LEASH, math::abs(before - at));
            at + math::clamp(next - at, -limit, limit)
        };
        next.x = pull(next.x, sp.position.x, here.x);
        next.y = pull(next.y, sp.position.y, here.y);
        next.z = pull(next.z, sp.position.z, here.z);
        next.z = math::min(next.z, ground_z + SETTLE_DEPTH);
        let moved = next - sp.position;
        sp.velocity = if dt > 0.0 {
            moved * (1.0 / dt)
        } else {
            Vec3::ZERO
        };
        sp.position = next;
        sp.acceleration = Vec3::ZERO;
        sp.yaw = math::wrap_pi(sp.yaw + command.yaw_rate * dt);
    }

    /// The setpoint now.
    pub fn setpoint(&self) -> Setpoint {
        self.setpoint
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn hover() -> Setpoint {
        Setpoint {
            position: Vec3::new(0.0, 0.0, -1.0),
            velocity: Vec3::new(0.2, 0.0, 0.0),
            acceleration: Vec3::new(0.1, 0.0, 0.0),
            yaw: 0.0,
        }
    }

    #[test]
    fn centred_sticks_hold_where_the_setpoint_was() {
        let mut m = ManualSetpoint::new(hover());
        let still = ManualVelocity::from_sticks(&Sticks::CENTRED, 0.0, &ManualLimits::DEFAULT);
        assert_eq!(still, ManualVelocity::default());
        for _ in 0..400 {
            m.step(&still, Vec3::new(0.05, 0.0, -1.0), 0.0, 0.0025);
        }
        let sp = m.setpoint();
        assert_eq!(sp.position, Vec3::new(0.0, 0.0, -1.0));
        assert_eq!(sp.velocity, Vec3::ZERO);
        assert_eq!(sp.acceleration, Vec3::ZERO);
    }

    #[test]
    fn full_forward_pitch_moves_north_at_the_manual_speed_and_turns_with_the_heading() {
        let mut sticks = Sticks::CENTRED;
        sticks.pitch = 1.0;
        let l = ManualLimits::DEFAULT;
        let north = ManualVelocity::from_sticks(&sticks, 0.0, &l);
        assert!((north.velocity.x - l.horizontal_speed).abs() < 1e-6);
        assert!(north.velocity.y.abs() < 1e-6);
        let east = ManualVelocity::from_sticks(&sticks, core::f32::consts::FRAC_PI_2, &l);
        assert!((east.velocity.y - l.horizontal_speed).abs() < 1e-6);
        assert!(east.velocity.x.abs() < 1e-6);
    }

    #[test]
    fn the_throttle_climbs_above_its_centre_and_descends_below_it() {
        let l = ManualLimits::DEFAULT;
        let mut sticks = Sticks::CENTRED;
        sticks.throttle = 1.0;
        let up = ManualVelocity::from_sticks(&sticks, 0.0, &l);
        assert!((up.velocity.z + l.climb_speed).abs() < 1e-6);
        sticks.throttle = 0.0;
        let down = ManualVelocity::from_sticks(&sticks, 0.0, &l);
        assert!((down.velocity.z - l.descent_speed).abs() < 1e-6);
        // Inside the dead zone: nothing.
        sticks.throttle = 0.53;
        assert_eq!(
            ManualVelocity::from_sticks(&sticks, 0.0, &l).velocity.z,
            0.0
        );
    }

    #[test]
    fn the_setpoint_stays_on_its_leash_and_above_the_settle_depth() {
        let mut m = ManualSetpoint::new(hover());
        let push = ManualVelocity {
            velocity: Vec3::new(1.0, 0.0, 1.0),
            yaw_rate: 0.0,
        };
        // The vehicle does not move (held against something): the setpoint stops LEASH ahead.
        for _ in 0..4000 {
            m.step(&push, Vec3::new(0.0, 0.0, -1.0), 0.0, 0.0025);
        }
        let sp = m.setpoint();
        assert!((sp.position.x - LEASH).abs() < 1e-5, "{sp:?}");
        // Down: at most the settle depth below the ground, even with the vehicle on it.
        for _ in 0..4000 {
            m.step(&push, Vec3::new(0.0, 0.0, 0.0), 0.0, 0.0025);
        }
        assert!(m.setpoint().position.z <= SETTLE_DEPTH + 1e-6);
        assert!(m.setpoint().position.z > SETTLE_DEPTH - 1e-3);
    }
}

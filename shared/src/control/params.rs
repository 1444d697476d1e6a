//! Every gain and limit of the flight controller in one place, with units
//! (docs/models.md#flight-cascade).
//!
//! The loops command physical quantities: the position loop a velocity, the velocity loop an
//! acceleration (m/s^2), the attitude loop a body rate, and the rate loop an angular
//! acceleration that the estimated inertia turns into a torque. So the gains below carry
//! over between payloads of different mass and inertia; the defaults fly the paper's payloads
//! (2.4 to 4 kg on eight 14.2 N rotors, 1.76 m x 0.2 m plate or the 0.62 m L). Tuned in the
//! physics plant (`host-sim fly`, 20 ms rotor lag, 10 ms motion-capture latency, the paper's
//! 0.3 N m disturbance): the roll axis of the narrow plate (inertia ~0.04 kg m^2) sets the
//! rate-loop gains.

use crate::control::vector::Vec3;

/// Gains and limits of the cascade.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ControlParams {
    /// Position error to velocity setpoint, 1/s (x, y, z).
    pub position_p: Vec3,
    /// Largest horizontal velocity setpoint, m/s.
    pub max_speed_xy: f32,
    /// Largest vertical velocity setpoint, m/s.
    pub max_speed_z: f32,
    /// Velocity error to acceleration, 1/s.
    pub velocity_p: Vec3,
    /// Integral of velocity error to acceleration, 1/s^2.
    pub velocity_i: Vec3,
    /// Velocity derivative (of the measurement) to acceleration, dimensionless.
    pub velocity_d: Vec3,
    /// Largest integral contribution of the velocity loop, m/s^2.
    pub velocity_integral_limit: Vec3,
    /// Cut-off of the derivative low-pass of the velocity loop, Hz.
    pub velocity_d_cutoff_hz: f32,
    /// Largest tilt of the thrust vector from vertical, rad.
    pub max_tilt: f32,
    /// Attitude error to body-rate setpoint, 1/s (roll, pitch, yaw).
    pub attitude_p: Vec3,
    /// Largest body-rate setpoint, rad/s.
    pub max_rate: Vec3,
    /// Rate error to angular acceleration, 1/s.
    pub rate_p: Vec3,
    /// Integral of rate error to angular acceleration, 1/s^2.
    pub rate_i: Vec3,
    /// Rate derivative (of the measurement) to angular acceleration, dimensionless.
    pub rate_d: Vec3,
    /// Largest integral contribution of the rate loop, rad/s^2.
    pub rate_integral_limit: Vec3,
    /// Largest angular acceleration command, rad/s^2.
    pub max_angular_acceleration: Vec3,
    /// Cut-off of the derivative low-pass of the rate loop, Hz.
    pub rate_d_cutoff_hz: f32,
    /// Collective thrust never commanded above this fraction of the rotors' total, so roll,
    /// pitch and yaw keep some margin.
    pub max_collective_fraction: f32,
}

impl ControlParams {
    /// The defaults, tuned in the physics plant for the paper's payloads.
    pub const DEFAULT: Self = Self {
        position_p: Vec3::new(1.0, 1.0, 1.2),
        max_speed_xy: 1.0,
        max_speed_z: 0.6,
        velocity_p: Vec3::new(2.0, 2.0, 3.0),
        velocity_i: Vec3::new(0.5, 0.5, 1.0),
        velocity_d: Vec3::new(0.0, 0.0, 0.0),
        velocity_integral_limit: Vec3::new(1.5, 1.5, 3.0),
        velocity_d_cutoff_hz: 5.0,
        max_tilt: 0.35,
        attitude_p: Vec3::new(10.0, 10.0, 2.5),
        max_rate: Vec3::new(2.5, 2.5, 1.0),
        rate_p: Vec3::new(30.0, 30.0, 6.0),
        rate_i: Vec3::new(40.0, 40.0, 3.0),
        rate_d: Vec3::new(0.25, 0.25, 0.0),
        rate_integral_limit: Vec3::new(8.0, 8.0, 3.0),
        max_angular_acceleration: Vec3::new(40.0, 40.0, 10.0),
        rate_d_cutoff_hz: 30.0,
        max_collective_fraction: 0.85,
    };
}

impl Default for ControlParams {
    fn default() -> Self {
        Self::DEFAULT
    }
}

//! The flying vehicle as the controller sees it: total mass, inertia about the estimated COM,
//! thrust available (docs/models.md#flight-cascade: gravity compensation from the estimated mass).
//!
//! The inertia is estimated from what the robots know: the payload as a uniform plate of its
//! footprint moved to the estimated COM (parallel axis), plus each robot as a point mass at its
//! rotor. It sets the scale of the rate loop's torque, so its error shows up as a loop gain
//! error, not as a bias.

use crate::control::vector::Vec3;
use crate::geometry::{Vec2, area_moments};
use crate::scenario::GRAVITY;

/// Mass properties and thrust of the vehicle.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct VehicleModel {
    /// Payload plus robots, kg.
    pub mass: f32,
    /// Principal moments about the COM (roll, pitch, yaw), kg m^2.
    pub inertia: Vec3,
    /// Sum of the rotors' maximum thrusts, N.
    pub max_total_thrust: f32,
}

impl VehicleModel {
    /// The model of a payload of `payload_mass` with footprint `footprint` and COM `com`,
    /// carried by robots of `robot_mass` at `rotor_points`, each up to `max_thrust`.
    pub fn from_payload(
        footprint: &[Vec2],
        com: Vec2,
        payload_mass: f32,
        rotor_points: &[Vec2],
        robot_mass: f32,
        max_thrust: f32,
    ) -> Self {
        let plate = area_moments(footprint);
        let (mut ixx, mut iyy) = (0.0f32, 0.0f32);
        if plate.area > 0.0 {
            let density = payload_mass / plate.area;
            let offset = plate.centroid - com;
            // A flat plate: I_xx = integral of y^2 dm, I_yy = integral of x^2 dm.
            ixx = density * plate.yy + payload_mass * offset.y * offset.y;
            iyy = density * plate.xx + payload_mass * offset.x * offset.x;
        }
        for &p in rotor_points {
            let r = p - com;
            ixx += robot_mass * r.y * r.y;
            iyy += robot_mass * r.x * r.x;
        }
        Self {
            mass: payload_mass + robot_mass * rotor_points.len() as f32,
            inertia: Vec3::new(ixx, iyy, ixx + iyy),
            max_total_thrust: max_thrust * rotor_points.len() as f32,
        }
    }

    /// Thrust that holds the vehicle's weight, N.
    pub fn hover_thrust(&self) -> f32 {
        self.mass * GRAVITY
    }
}

//! Whether the payload has left the ground or is back on it (docs/models.md#flight-cascade: the
//! integrators must not run while the payload still rests on the ground).
//!
//! Airborne once the estimated height above the take-off point exceeds
//! [`LandDetector::LIFT_HEIGHT`]; landed again once, descending, its lowest point stays within
//! [`LandDetector::LAND_HEIGHT`] of the ground and it is nearly still for
//! [`LandDetector::LAND_TIME`].
//!
//! The lowest point, not the payload frame's origin: in wind the vehicle leans into it and
//! comes down on one edge, its origin `reach * sin(tilt)` above the ground at most (`reach`,
//! the farthest any part of the vehicle is from the origin: [`clear_by`]). Judged by the
//! origin, a payload resting on its edge was never down, and hovered on it until the plan's
//! touchdown timeout (docs/formats.md#the-plant-section).

use crate::control::vector::Vec3;

/// Ground contact state.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Contact {
    /// Resting on the ground (before take-off).
    OnGround,
    /// Flying.
    Airborne,
    /// Back on the ground after a flight.
    Landed,
}

/// The detector.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LandDetector {
    contact: Contact,
    ground_z: f32,
    still_for: f32,
    /// The farthest any part of the vehicle is from the payload frame's origin, m.
    reach: f32,
}

/// Whether every point within `reach` of the payload frame's origin is more than `margin`
/// above the ground, the origin `height` above it and the payload tilted by an angle whose
/// sine squared is `sin2_tilt`: the lowest point is at most `reach * sin(tilt)` below the
/// origin. Compared squared (no square root on the target: a few multiplications).
pub fn clear_by(height: f32, reach: f32, sin2_tilt: f32, margin: f32) -> bool {
    let above = height - margin;
    above > 0.0 && above * above > reach * reach * sin2_tilt
}

impl LandDetector {
    /// Height above the take-off point that counts as airborne, m.
    pub const LIFT_HEIGHT: f32 = 0.05;
    /// Height within which a descending vehicle counts as down, m.
    pub const LAND_HEIGHT: f32 = 0.03;
    /// Speed below which a vehicle counts as still, m/s.
    pub const STILL_SPEED: f32 = 0.1;
    /// Time on the ground and still before it counts as landed, s.
    pub const LAND_TIME: f32 = 0.5;

    /// A detector for a vehicle resting on the ground at height `ground_z` (NED z), no part of
    /// it farther than `reach` (m) from the payload frame's origin.
    pub fn new(ground_z: f32, reach: f32) -> Self {
        Self {
            contact: Contact::OnGround,
            ground_z,
            still_for: 0.0,
            reach,
        }
    }

    /// Whether the vehicle's lowest point is more than `margin` (m) above the ground, at NED
    /// position `position` and tilted by an angle whose sine squared is `sin2_tilt`.
    pub fn clear_of_ground(&self, position: Vec3, sin2_tilt: f32, margin: f32) -> bool {
        clear_by(self.ground_z - position.z, self.reach, sin2_tilt, margin)
    }

    /// The state.
    pub fn contact(&self) -> Contact {
        self.contact
    }

    /// True while flying.
    pub fn airborne(&self) -> bool {
        self.contact == Contact::Airborne
    }

    /// True while, landing, the vehicle's lowest point rests within [`Self::LAND_HEIGHT`] of
    /// the ground and it is nearly still (the time that makes it landed is running): the
    /// ground carries part of it.
    pub fn settling(&self) -> bool {
        self.contact == Contact::Airborne && self.still_for > 0.0
    }

    /// One step with the estimated position and velocity (NED) and the tilt (its sine
    /// squared); `descending` when the plan is landing.
    pub fn update(
        &mut self,
        position: Vec3,
        velocity: Vec3,
        sin2_tilt: f32,
        descending: bool,
        dt: f32,
    ) -> Contact {
        let height = self.ground_z - position.z;
        match self.contact {
            Contact::OnGround => {
                if height > Self::LIFT_HEIGHT {
                    self.contact = Contact::Airborne;
                }
            }
            Contact::Airborne => {
                let low = !self.clear_of_ground(position, sin2_tilt, Self::LAND_HEIGHT);
                let down = low && velocity.norm() < Self::STILL_SPEED;
                self.still_for = if descending && down {
                    self.still_for + dt
                } else {
                    0.0
                };
                if self.still_for >= Self::LAND_TIME {
                    self.contact = Contact::Landed;
                }
            }
            Contact::Landed => {}
        }
        self.contact
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lifts_off_then_lands_only_when_descending_and_still() {
        let mut d = LandDetector::new(0.0, 1.0);
        assert_eq!(
            d.update(Vec3::new(0.0, 0.0, -0.02), Vec3::ZERO, 0.0, false, 0.01),
            Contact::OnGround
        );
        assert_eq!(
            d.update(Vec3::new(0.0, 0.0, -0.06), Vec3::ZERO, 0.0, false, 0.01),
            Contact::Airborne
        );
        for _ in 0..100 {
            d.update(Vec3::new(0.0, 0.0, -0.01), Vec3::ZERO, 0.0, false, 0.01);
        }
        assert!(d.airborne(), "low but not landing: still airborne");
        for _ in 0..49 {
            d.update(Vec3::new(0.0, 0.0, -0.01), Vec3::ZERO, 0.0, true, 0.01);
        }
        assert!(d.airborne());
        d.update(Vec3::new(0.0, 0.0, -0.01), Vec3::ZERO, 0.0, true, 0.011);
        assert_eq!(d.contact(), Contact::Landed);
    }

    #[test]
    fn a_payload_resting_tilted_on_its_edge_is_down_and_one_clear_of_the_ground_is_not() {
        // Origin 6 cm up, tilted 4 degrees (sine squared 0.0049), 0.9 m reach: the low edge
        // is on the ground.
        let mut d = LandDetector::new(0.0, 0.9);
        d.update(Vec3::new(0.0, 0.0, -0.2), Vec3::ZERO, 0.0, false, 0.01);
        assert!(d.airborne());
        let on_edge = Vec3::new(0.0, 0.0, -0.06);
        d.update(on_edge, Vec3::ZERO, 0.0049, true, 0.01);
        assert!(d.settling());
        for _ in 0..50 {
            d.update(on_edge, Vec3::ZERO, 0.0049, true, 0.01);
        }
        assert_eq!(d.contact(), Contact::Landed);
        assert!(!d.settling(), "landed, no longer settling");
        // Level at the same height, it is 6 cm clear: not down.
        let mut level = LandDetector::new(0.0, 0.9);
        level.update(Vec3::new(0.0, 0.0, -0.2), Vec3::ZERO, 0.0, false, 0.01);
        for _ in 0..100 {
            level.update(on_edge, Vec3::ZERO, 0.0, true, 0.01);
        }
        assert!(level.airborne());
        assert!(!level.settling());
        assert!(level.clear_of_ground(on_edge, 0.0, 0.05));
        assert!(!level.clear_of_ground(on_edge, 0.0049, 0.0));
    }
}

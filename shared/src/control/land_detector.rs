//! Whether the payload has left the ground or is back on it (docs/models.md#flight-cascade: the
//! integrators must not run while the payload still rests on the ground).
//!
//! Airborne once the estimated height above the take-off point exceeds
//! [`LandDetector::LIFT_HEIGHT`]; landed again once, descending, it stays within
//! [`LandDetector::LAND_HEIGHT`] of the ground and nearly still for
//! [`LandDetector::LAND_TIME`].

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

    /// A detector for a vehicle resting on the ground at height `ground_z` (NED z).
    pub fn new(ground_z: f32) -> Self {
        Self {
            contact: Contact::OnGround,
            ground_z,
            still_for: 0.0,
        }
    }

    /// The state.
    pub fn contact(&self) -> Contact {
        self.contact
    }

    /// True while flying.
    pub fn airborne(&self) -> bool {
        self.contact == Contact::Airborne
    }

    /// One step with the estimated position and velocity (NED); `descending` when the plan is
    /// landing.
    pub fn update(&mut self, position: Vec3, velocity: Vec3, descending: bool, dt: f32) -> Contact {
        let height = self.ground_z - position.z;
        match self.contact {
            Contact::OnGround => {
                if height > Self::LIFT_HEIGHT {
                    self.contact = Contact::Airborne;
                }
            }
            Contact::Airborne => {
                let down = height < Self::LAND_HEIGHT && velocity.norm() < Self::STILL_SPEED;
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
        let mut d = LandDetector::new(0.0);
        assert_eq!(
            d.update(Vec3::new(0.0, 0.0, -0.02), Vec3::ZERO, false, 0.01),
            Contact::OnGround
        );
        assert_eq!(
            d.update(Vec3::new(0.0, 0.0, -0.06), Vec3::ZERO, false, 0.01),
            Contact::Airborne
        );
        for _ in 0..100 {
            d.update(Vec3::new(0.0, 0.0, -0.01), Vec3::ZERO, false, 0.01);
        }
        assert!(d.airborne(), "low but not landing: still airborne");
        for _ in 0..49 {
            d.update(Vec3::new(0.0, 0.0, -0.01), Vec3::ZERO, true, 0.01);
        }
        assert!(d.airborne());
        d.update(Vec3::new(0.0, 0.0, -0.01), Vec3::ZERO, true, 0.011);
        assert_eq!(d.contact(), Contact::Landed);
    }
}

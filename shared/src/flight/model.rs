//! The flight's model of the vehicle and its mixer, built from the robots' positions and the
//! estimate (docs/models.md#allocation-and-mixer: the mixing matrix is rebuilt from the new
//! positions; docs/models.md#flight-cascade: gravity compensation from the estimated mass).

use heapless::Vec;

use crate::control::allocation::{AllocationError, Mixer, MixerKind, RotorLayout};
use crate::control::vehicle::VehicleModel;
use crate::geometry::Vec2;
use crate::scenario::{MAX_ROBOTS, Scenario};

/// What the flight stack flies with.
#[derive(Clone, Debug, PartialEq)]
pub struct FlightModel {
    /// The mixer of the formation about the estimated COM.
    pub mixer: Mixer,
    /// Mass, inertia and thrust as the controller believes them.
    pub vehicle: VehicleModel,
    /// The COM the mixer's torques are about (body frame, from the payload frame's origin,
    /// where the IMU sits), m.
    pub com: Vec2,
    /// The farthest any part of the vehicle (the footprint's corners, the rail the robots
    /// ride) is from the payload frame's origin, m: how far below the origin a tilted
    /// vehicle's lowest point can be (the land detector's and the rotor monitor's "clear of
    /// the ground").
    pub reach: f32,
}

/// The farthest of `points` from the payload frame's origin, m (0 for none).
pub fn reach_of(points: &[Vec2]) -> f32 {
    points
        .iter()
        .fold(0.0, |m, p| crate::math::max(m, p.norm()))
}

impl FlightModel {
    /// The model of `scenario`'s payload with the robots at arc lengths `positions`, the
    /// payload believed to have its COM at `com` and mass `mass`; the mixer of `kind`.
    pub fn build(
        scenario: &Scenario,
        positions: &[f32],
        com: Vec2,
        mass: f32,
        kind: MixerKind,
    ) -> Result<Self, AllocationError> {
        let robots = &scenario.robots;
        let rail = &scenario.payload.rail;
        if positions.len() != robots.count() {
            return Err(AllocationError::BadLayout);
        }
        let points: Vec<Vec2, MAX_ROBOTS> = positions.iter().map(|&s| rail.point_at(s)).collect();
        let mixer = mixer_at(scenario, &points, com, kind)?;
        let vehicle = VehicleModel::from_payload(
            &scenario.payload.footprint,
            com,
            mass,
            &points,
            robots.mass,
            robots.max_thrust,
        );
        let reach = crate::math::max(
            reach_of(&scenario.payload.footprint),
            reach_of(rail.vertices()),
        );
        Ok(Self {
            mixer,
            vehicle,
            com,
            reach,
        })
    }
}

/// The mixer of `kind` for the robots of `scenario` at rail positions `positions`, about `com`
/// (the mixer [`FlightModel::build`] builds, without the vehicle model).
pub fn mixer_for(
    scenario: &Scenario,
    positions: &[f32],
    com: Vec2,
    kind: MixerKind,
) -> Result<Mixer, AllocationError> {
    if positions.len() != scenario.robots.count() {
        return Err(AllocationError::BadLayout);
    }
    let rail = &scenario.payload.rail;
    let points: Vec<Vec2, MAX_ROBOTS> = positions.iter().map(|&s| rail.point_at(s)).collect();
    mixer_at(scenario, &points, com, kind)
}

fn mixer_at(
    scenario: &Scenario,
    points: &[Vec2],
    com: Vec2,
    kind: MixerKind,
) -> Result<Mixer, AllocationError> {
    let robots = &scenario.robots;
    let layout = RotorLayout {
        points,
        spin: &robots.spin,
        com,
        torque_per_thrust: robots.torque_per_thrust,
        max_thrust: robots.max_thrust,
    };
    Mixer::build(kind, &layout)
}

//! The paper's simulation cases built in (docs/system.md#paper-cases): `rect-sim1` and `L-sim1` as
//! [`ScenarioInput`]s, the same values as the files in `tests/scenarios/` (a test checks they
//! agree). For unit tests and for target-side benchmarks that cannot read files, with a
//! hovering flight of the rectangle for the 400 Hz benchmarks.

use crate::control::allocation::{Mixer, MixerKind, RotorLayout};
use crate::control::navigator::{ImuSample, MocapFix, Navigator};
use crate::control::vector::{Quat, Vec3};
use crate::control::vehicle::VehicleModel;
use crate::flight::model::reach_of;
use crate::flight::{FlightConfig, FlightModel, FlightStack};
use crate::geometry::Vec2;
use crate::scenario::{
    EstimationSetup, FormationSetup, GRAVITY, RobotsInput, Scenario, ScenarioInput, Truth,
};

/// The rectangular payload's footprint, m (its long side along x).
pub const RECT: [Vec2; 4] = [
    Vec2::new(-0.88, -0.1),
    Vec2::new(0.88, -0.1),
    Vec2::new(0.88, 0.1),
    Vec2::new(-0.88, 0.1),
];
const RECT_RAIL: [Vec2; 4] = [
    Vec2::new(-1.0, -0.22),
    Vec2::new(1.0, -0.22),
    Vec2::new(1.0, 0.22),
    Vec2::new(-1.0, 0.22),
];
const RECT_CANDIDATES: [f32; 12] = [
    0.12, 0.56, 1.0, 1.44, 1.88, 2.22, 2.56, 3.0, 3.44, 3.88, 4.32, 4.66,
];
const L_SHAPE: [Vec2; 6] = [
    Vec2::new(0.0, 0.0),
    Vec2::new(0.62, 0.0),
    Vec2::new(0.62, 0.2),
    Vec2::new(0.2, 0.2),
    Vec2::new(0.2, 0.62),
    Vec2::new(0.0, 0.62),
];
const L_RAIL: [Vec2; 6] = [
    Vec2::new(-0.12, -0.12),
    Vec2::new(0.74, -0.12),
    Vec2::new(0.74, 0.32),
    Vec2::new(0.32, 0.32),
    Vec2::new(0.32, 0.74),
    Vec2::new(-0.12, 0.74),
];
const L_CANDIDATES: [f32; 11] = [0.1, 0.45, 0.8, 1.08, 1.5, 1.72, 1.94, 2.36, 2.64, 2.99, 3.3];
const SPIN: [i64; 8] = [1, -1, 1, -1, 1, -1, 1, -1];

fn robots() -> RobotsInput<'static> {
    RobotsInput {
        count: 8,
        mass: 0.1,
        max_thrust: 14.2,
        torque_per_thrust: 0.016,
        spin: &SPIN,
        min_spacing: 0.25,
        pair_size: 2,
        initial: None,
    }
}

/// Eight rotor points on the rectangle's rail (m), roughly balanced about a COM near
/// (0.1, 0.0): the layout the mixer and cascade tests and benchmarks fly.
pub const RECT_ROTORS: [Vec2; 8] = [
    Vec2::new(-0.6, -0.22),
    Vec2::new(0.1, -0.22),
    Vec2::new(0.7, -0.22),
    Vec2::new(1.0, 0.05),
    Vec2::new(0.8, 0.22),
    Vec2::new(0.3, 0.22),
    Vec2::new(-0.4, 0.22),
    Vec2::new(-1.0, 0.0),
];

/// Alternating spin signs of eight robots.
pub const ALTERNATING_SPIN: [i8; 8] = [1, -1, 1, -1, 1, -1, 1, -1];

/// Not a paper case: a 3.2 m x 0.3 m rectangle, the longest payload sixteen robots carry
/// (tests/scenarios/rect-16.toml's outline), for the benchmarks of a control step with every
/// robot the software takes.
pub const LONG_RECT: [Vec2; 4] = [
    Vec2::new(-1.6, -0.15),
    Vec2::new(1.6, -0.15),
    Vec2::new(1.6, 0.15),
    Vec2::new(-1.6, 0.15),
];

/// Sixteen rotor points on [`LONG_RECT`]'s rail (m), eight along each long side, balanced
/// about a COM near (0.1, 0.0).
pub const LONG_RECT_ROTORS: [Vec2; 16] = [
    Vec2::new(-1.6, -0.27),
    Vec2::new(-1.1, -0.27),
    Vec2::new(-0.6, -0.27),
    Vec2::new(-0.1, -0.27),
    Vec2::new(0.4, -0.27),
    Vec2::new(0.9, -0.27),
    Vec2::new(1.4, -0.27),
    Vec2::new(1.72, -0.05),
    Vec2::new(1.5, 0.27),
    Vec2::new(1.0, 0.27),
    Vec2::new(0.5, 0.27),
    Vec2::new(0.0, 0.27),
    Vec2::new(-0.5, 0.27),
    Vec2::new(-1.0, 0.27),
    Vec2::new(-1.5, 0.27),
    Vec2::new(-1.72, 0.05),
];

/// Alternating spin signs of sixteen robots.
pub const ALTERNATING_SPIN_16: [i8; 16] = [1, -1, 1, -1, 1, -1, 1, -1, 1, -1, 1, -1, 1, -1, 1, -1];

/// `rect-sim1` as input.
pub fn rect_sim1() -> ScenarioInput<'static> {
    ScenarioInput {
        footprint: &RECT,
        rail: &RECT_RAIL,
        candidates: &RECT_CANDIDATES,
        robots: robots(),
        estimation: EstimationSetup {
            grid_min: [-0.5, -0.05, 2.5],
            grid_max: [0.5, 0.05, 4.0],
            resolution: [0.1, 0.03, 0.5],
            threshold: 0.8,
            noise_sigma: 1.0,
            max_measurements: 20,
        },
        formation: FormationSetup { balance_eps: 1e-5 },
        truth: Some(Truth {
            com: Vec2::new(0.33, 0.01),
            mass: 3.5,
        }),
        flight: None,
    }
}

/// `L-sim1` as input.
pub fn l_sim1() -> ScenarioInput<'static> {
    ScenarioInput {
        footprint: &L_SHAPE,
        rail: &L_RAIL,
        candidates: &L_CANDIDATES,
        robots: robots(),
        estimation: EstimationSetup {
            grid_min: [0.05, 0.02, 2.2],
            grid_max: [0.57, 0.57, 4.0],
            resolution: [0.065, 0.065, 0.45],
            threshold: 0.8,
            noise_sigma: 1.0,
            max_measurements: 20,
        },
        formation: FormationSetup { balance_eps: 1e-4 },
        truth: Some(Truth {
            com: Vec2::new(0.31, 0.1),
            mass: 3.5,
        }),
        flight: None,
    }
}

/// A flight of the rectangle (COM (0.12, 0.01), 3.5 kg) on [`RECT_ROTORS`] with `mixer`,
/// its navigator primed by a motion-capture fix 0.5 m above the take-off point, so the flight
/// stack is airborne from its first step: the state the 400 Hz benchmarks step from. `None`
/// if the mixer cannot be built (never, for these rotors).
pub fn hovering_flight(mixer: MixerKind) -> Option<(Navigator, FlightStack)> {
    hovering_flight_on(mixer, &RECT, &RECT_ROTORS, &ALTERNATING_SPIN, 3.5)
}

/// [`hovering_flight`] of any payload `outline` of `mass` kg (COM (0.12, 0.01)) on rotors at
/// `points` spinning `spin`: [`LONG_RECT`] on [`LONG_RECT_ROTORS`] is the sixteen-robot case.
pub fn hovering_flight_on(
    mixer: MixerKind,
    outline: &[Vec2],
    points: &[Vec2],
    spin: &[i8],
    mass: f32,
) -> Option<(Navigator, FlightStack)> {
    let com = Vec2::new(0.12, 0.01);
    let layout = RotorLayout {
        points,
        spin,
        com,
        torque_per_thrust: 0.016,
        max_thrust: 14.2,
    };
    let model = FlightModel {
        mixer: Mixer::build(mixer, &layout).ok()?,
        vehicle: VehicleModel::from_payload(outline, com, mass, points, 0.1, 14.2),
        com,
        reach: reach_of(points),
    };
    let above = Vec3::new(0.0, 0.0, -0.5);
    let mut navigator = Navigator::new();
    let level = ImuSample {
        gyro: Vec3::ZERO,
        accel: Vec3::new(0.0, 0.0, -GRAVITY),
    };
    navigator.motion_capture(&MocapFix {
        position: above,
        attitude: Quat::IDENTITY,
        stamp_us: 0,
    });
    navigator.update(&level, 0.0025, 0);
    let stack = FlightStack::new(FlightConfig::default(), model, Vec3::ZERO, [0.3, 1.98, 0.5]);
    Some((navigator, stack))
}

/// A built-in case, checked (the built-in values are valid; a failure here is a bug in this
/// file, caught by its test).
pub fn checked(input: ScenarioInput<'_>) -> Scenario {
    match Scenario::from_input(&input) {
        Ok(s) => s,
        Err(e) => panic!("built-in paper case is invalid: {e}"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn built_in_cases_are_valid() {
        assert_eq!(checked(rect_sim1()).robots.count(), 8);
        assert_eq!(checked(l_sim1()).payload.candidates.len(), 11);
    }
}

//! Wind over the vehicle (docs/formats.md#the-plant-section): a mean wind and gusts about it
//! in Dryden's first-order form (MIL-F-8785C's low-altitude model: each horizontal axis a
//! Gauss-Markov process of the given RMS with correlation time L / V, the length scale L taken
//! as [`GUST_LENGTH`] near the ground), and the drag the air moving past the vehicle makes:
//!
//! - on the payload's edge, the plate's thickness times its width across the wind, as a bluff
//!   body's ([`DRAG_COEFFICIENT`], air at [`AIR_DENSITY`]), at the footprint's centroid (a
//!   horizontal wind meets a flat payload edge-on: its plan area takes no dynamic pressure);
//! - on each robot's body, [`ROBOT_FRONTAL_AREA`], at its rotor;
//! - on each rotor, the rotor drag of a propeller moving edgewise through the air (blade
//!   flapping and induced drag: P. Martin and E. Salaün, "The true role of accelerometer
//!   feedback in quadrotor control", ICRA 2010), linear in the airspeed in the rotor's plane
//!   and in the rotor's speed ([`ROTOR_DRAG_COEFFICIENT`]), at its rotor. In a hover the
//!   rotors' speeds are spread about the COM much as their thrusts are, so this drag, by far
//!   the largest, makes almost no yaw torque.
//!
//! The drag is the wind's: in calm air (the model) nothing is applied, as before the plant
//! had wind.

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};
use shared::control::vector::Vec3;
use shared::geometry::{Vec2, area_moments};

/// Air density, kg/m^3 (sea level, 15 C).
pub const AIR_DENSITY: f32 = 1.225;
/// Drag coefficient of the payload's edge and of a robot's body on their frontal areas: a
/// bluff body's (a flat plate broadside has 1.17: S. F. Hoerner, "Fluid-Dynamic Drag", 1965).
pub const DRAG_COEFFICIENT: f32 = 1.0;
/// Frontal area of one robot (its carriage, motor and arm), m^2: 10 by 10 cm.
pub const ROBOT_FRONTAL_AREA: f32 = 0.01;
/// Rotor drag, N per rad/s of the rotor's speed per m/s of airspeed in its plane: PX4's
/// simulated Iris (`rotorDragCoefficient` 8.06428e-05 in its Gazebo motor model), whose
/// rotors make about 8.5 N at 1,000 rad/s as these make 14.2 N at 1,150.
pub const ROTOR_DRAG_COEFFICIENT: f32 = 8.064_28e-5;
/// The gusts' length scale near the ground, m (Dryden's L_u at a few metres up).
pub const GUST_LENGTH: f32 = 5.0;

/// The wind a plant has.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WindConfig {
    /// Mean wind, north and east, m/s.
    pub mean: [f32; 2],
    /// Gusts, m/s RMS per horizontal axis.
    pub gust: f32,
    /// Seed of the gusts.
    pub seed: u64,
}

impl WindConfig {
    /// No wind.
    pub const CALM: Self = Self {
        mean: [0.0; 2],
        gust: 0.0,
        seed: 0,
    };
}

/// A drag force and where it acts.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Drag {
    /// Force, world frame (NED), N.
    pub force: Vec3,
    /// Where it acts, body frame, m.
    pub at: Vec2,
}

/// The wind's state: its gusts now.
#[derive(Clone, Debug)]
pub struct Wind {
    config: WindConfig,
    gust: [f32; 2],
    rng: ChaCha8Rng,
}

impl Wind {
    /// The wind of `config`, its gusts starting from a draw of their own distribution.
    pub fn new(config: &WindConfig) -> Self {
        let mut rng = ChaCha8Rng::seed_from_u64(config.seed ^ 0x6057_5EED);
        let mut draw = || {
            let n: f32 = StandardNormal.sample(&mut rng);
            n * config.gust
        };
        let gust = [draw(), draw()];
        Self {
            config: *config,
            gust,
            rng,
        }
    }

    /// The air's velocity over the ground now, NED (horizontal), m/s.
    pub fn air(&self) -> Vec3 {
        let [n, e] = self.config.mean;
        Vec3::new(n + self.gust[0], e + self.gust[1], 0.0)
    }

    /// The gusts moved on by `dt` s; false in calm air (no drag is applied then).
    pub fn advance(&mut self, dt: f32) -> bool {
        let c = self.config;
        if c.mean == [0.0; 2] && c.gust == 0.0 {
            return false;
        }
        if c.gust > 0.0 {
            let speed = (c.mean[0].hypot(c.mean[1])).max(1.0);
            let tau = GUST_LENGTH / speed;
            let a = (-dt / tau).exp();
            let b = c.gust * (1.0 - a * a).sqrt();
            for g in &mut self.gust {
                let n: f32 = StandardNormal.sample(&mut self.rng);
                *g = a * *g + b * n;
            }
        }
        true
    }
}

/// The dynamic pressure's drag on a bluff body of frontal `area` (m^2) in the air moving past
/// it at `relative` (air minus body, world frame, m/s): along `relative`, N.
pub fn bluff_drag(relative: Vec3, area: f32) -> Vec3 {
    relative * (0.5 * AIR_DENSITY * DRAG_COEFFICIENT * area * relative.norm())
}

/// The drag on a rotor turning at `omega` rad/s about `axis` (a unit vector, world frame) in
/// the air moving past it at `relative` (world frame, m/s): along the airspeed in its plane, N.
pub fn rotor_drag(relative: Vec3, axis: Vec3, omega: f32) -> Vec3 {
    let along = axis * relative.dot(axis);
    (relative - along) * (ROTOR_DRAG_COEFFICIENT * omega.abs())
}

/// The payload's edge facing air that moves past it along `direction` (body frame,
/// horizontal; any length): the plate's `thickness` times the footprint's width across that
/// direction, m^2 (0 for still air).
pub fn edge_area(footprint: &[Vec2], direction: Vec2, thickness: f32) -> f32 {
    let length = direction.x.hypot(direction.y);
    if length <= 0.0 {
        return 0.0;
    }
    // The unit vector across the air's direction, and the footprint's extent along it.
    let (ux, uy) = (-direction.y / length, direction.x / length);
    let (mut low, mut high) = (f32::INFINITY, f32::NEG_INFINITY);
    for p in footprint {
        let s = p.x * ux + p.y * uy;
        low = low.min(s);
        high = high.max(s);
    }
    if high >= low {
        thickness * (high - low)
    } else {
        0.0
    }
}

/// The drag on the payload's edge, at the footprint's centroid: `relative` the air's velocity
/// past it in the world frame, `relative_body` the same in the body frame (for the width the
/// air meets).
pub fn plate_drag(relative: Vec3, relative_body: Vec3, footprint: &[Vec2], thickness: f32) -> Drag {
    let area = edge_area(
        footprint,
        Vec2::new(relative_body.x, relative_body.y),
        thickness,
    );
    Drag {
        force: bluff_drag(relative, area),
        at: area_moments(footprint).centroid,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn square() -> Vec<Vec2> {
        vec![
            Vec2::new(-0.5, -0.5),
            Vec2::new(0.5, -0.5),
            Vec2::new(0.5, 0.5),
            Vec2::new(-0.5, 0.5),
        ]
    }

    #[test]
    fn a_steady_wind_pushes_downwind_on_the_plate_s_edge_and_the_robots() {
        // 0.5 * 1.225 * 1.0 * (0.03 m * 1 m) * (2 m/s)^2 = 0.0735 N north, at the centroid.
        let relative = Vec3::new(2.0, 0.0, 0.0);
        let d = plate_drag(relative, relative, &square(), 0.03);
        assert!((d.force.x - 0.0735).abs() < 1e-5, "{d:?}");
        assert_eq!((d.force.y, d.force.z), (0.0, 0.0));
        assert!(d.at.x.abs() < 1e-6 && d.at.y.abs() < 1e-6);
        // Across the diagonal the square is wider by the square root of two.
        let diagonal = edge_area(&square(), Vec2::new(1.0, 1.0), 0.03);
        assert!((diagonal - 0.03 * 2f32.sqrt()).abs() < 1e-5, "{diagonal}");
        // Moving with the air: no drag.
        assert!(bluff_drag(Vec3::ZERO, 1.0).norm() < 1e-9);
        assert_eq!(edge_area(&square(), Vec2::new(0.0, 0.0), 0.03), 0.0);
        // A robot: 0.5 * 1.225 * 0.01 * 4 = 0.0245 N.
        let robot = bluff_drag(relative, ROBOT_FRONTAL_AREA);
        assert!((robot.x - 0.0245).abs() < 1e-5, "{robot:?}");
    }

    #[test]
    fn a_rotor_drags_along_the_airspeed_in_its_plane_in_proportion_to_its_speed() {
        let down = Vec3::new(0.0, 0.0, 1.0);
        // 650 rad/s, 2 m/s edgewise: 8.06e-5 * 650 * 2 = 0.105 N.
        let d = rotor_drag(Vec3::new(2.0, 0.0, 0.0), down, 650.0);
        assert!((d.x - 0.1048).abs() < 1e-3, "{d:?}");
        // Air along its axis makes none; twice the speed, twice the drag.
        assert!(rotor_drag(Vec3::new(0.0, 0.0, 3.0), down, 650.0).norm() < 1e-9);
        let twice = rotor_drag(Vec3::new(2.0, 0.0, 0.0), down, 1300.0);
        assert!((twice.x - 2.0 * d.x).abs() < 1e-6);
        // Calm air: the plant applies nothing.
        assert!(!Wind::new(&WindConfig::CALM).advance(0.0005));
    }

    #[test]
    fn gusts_have_their_rms_and_their_correlation_time() {
        let mut w = Wind::new(&WindConfig {
            mean: [5.0, 0.0],
            gust: 1.0,
            seed: 3,
        });
        let dt = 0.0005;
        let n = 400_000;
        let (mut sum, mut sq) = (0.0f64, 0.0f64);
        for _ in 0..n {
            w.advance(dt);
            let g = f64::from(w.air().x - 5.0);
            sum += g;
            sq += g * g;
        }
        let mean = sum / f64::from(n);
        let rms = (sq / f64::from(n) - mean * mean).sqrt();
        // 200 s over a 1 s correlation time: within about a tenth.
        assert!((0.8..1.2).contains(&rms), "rms {rms}");
        assert!(mean.abs() < 0.3, "mean {mean}");
    }
}

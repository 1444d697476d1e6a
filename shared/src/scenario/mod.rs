//! Plain data the rest of the crate takes: one payload, its rail, the robots, the estimation
//! set-up and (for simulation) the truth, with the checks that make them safe to use.
//!
//! This is the data of a scenario file (docs/formats.md#scenario-files); the TOML parsing
//! lives on the host, which hands the values over as a [`ScenarioInput`]. Every rule that a
//! value must follow is checked here, once, so that the firmware (which may receive the same
//! values over telemetry) and the simulator reject exactly the same inputs. Each error names
//! the scenario key it is about.
//!
//! Beyond the rules the models need (a simple footprint, a resolution above zero, ...), a
//! scenario must describe a vehicle that can exist and be flown: the `MAX_*` bounds below are
//! generous for a payload carried by rail-riding single-rotor robots (the paper's prototype:
//! a 1.76 m x 0.2 m payload of 2.4 to 3.2 kg, 0.1 kg robots of 14.2 N, rotors 0.12 m outside
//! the outline), and each says why it sits where it does.

use heapless::Vec;

use crate::estimation::groups::{group_count, lift_group};
use crate::geometry::{
    ConvexHull, MAX_VERTICES, PolygonError, Rail, Vec2, check_simple_polygon, farthest_beyond,
    first_touching_edges, polygon_contains,
};
use crate::liftoff_thrust::{lift_fraction, thrust_from_fraction};
use crate::numbers::Num;

/// Most robots on one rail.
pub const MAX_ROBOTS: usize = 16;
/// Most candidate attachment points on one rail.
pub const MAX_CANDIDATES: usize = 64;
/// Most points of the estimation grid (all axes multiplied).
pub const MAX_GRID_POINTS: usize = 4096;
/// Standard gravity, m/s^2.
pub const GRAVITY: f32 = 9.80665;

/// Largest `|x|` or `|y|` of a footprint vertex or rail point, m. A payload that rotor robots
/// carry together fits well inside 100 m x 100 m; the bound keeps lengths finite and `f32`
/// arc lengths precise to a fraction of a millimetre.
pub const MAX_COORDINATE: f32 = 50.0;
/// Farthest a point of the rail (a rotor centre) may lie from the footprint's outline, m. The
/// rotor sits a rotor radius plus a margin outside the outline (0.12 m on the prototype; a
/// 30-inch heavy-lift propeller needs about 0.45 m); the lift model treats the rotor as
/// attached at the outline through a short arm.
pub const MAX_RAIL_CLEARANCE: f32 = 1.0;
/// How closely [`MAX_RAIL_CLEARANCE`] is checked along the rail (not only at its vertices), m.
pub const RAIL_CLEARANCE_TOLERANCE: f32 = 0.01;
/// Heaviest robot, kg: a single heavy-lift rotor with its motor, ESC, arm and stepper
/// (the prototype's robot is 0.1 kg).
pub const MAX_ROBOT_MASS: f32 = 10.0;
/// Largest maximum thrust of one rotor, N: the biggest single heavy-lift motor and propeller
/// sets make about 40 kgf (the prototype's make 14.2 N).
pub const MAX_ROTOR_THRUST: f32 = 500.0;
/// Largest rotor torque per thrust `c_q / c_t`, m. Real propellers have 0.005 to 0.05 m (the
/// prototype 0.016 m); zero would leave yaw uncontrollable.
pub const MAX_TORQUE_PER_THRUST: f32 = 0.2;
/// Heaviest payload, kg (truth and the grid's mass axis): sixteen robots of
/// [`MAX_ROTOR_THRUST`] lift about 800 kg.
pub const MAX_PAYLOAD_MASS: f32 = 1000.0;
/// Most lifts of one estimation: the paper converges by the 4th and allows 20; each real lift
/// takes some 15 s of settling, ramping and relaxing.
pub const MAX_MEASUREMENTS: u32 = 50;
/// Largest `formation.balance_eps`, m: the balance sums are lever arms of a payload a few
/// metres long (the paper uses 1e-5 and 0.1); a larger bound balances nothing.
pub const MAX_BALANCE_EPS: f32 = 1.0;
/// Farthest flight target from the take-off point, horizontally, m: flights are simulated
/// inside a motion-capture volume (the paper's target is 2 m away).
pub const MAX_TARGET_DISTANCE: f32 = 20.0;
/// Highest flight target above the ground, m (the paper's is 0.5 m).
pub const MAX_TARGET_HEIGHT: f32 = 10.0;
/// Largest peak of the simulated body-torque disturbance, N m (the paper's is 0.3 N m; a
/// 10 m/s gust on a 2 m^2 payload, acting 0.2 m off its centre, makes about 25 N m: more is
/// weather no vehicle of this kind flies in).
pub const MAX_DISTURBANCE_TORQUE: f32 = 50.0;
/// Tolerance of "inside the footprint's hull" for COMs, m (as the estimator's prior uses).
const HULL_TOLERANCE: f32 = 1e-6;

/// Guard added before flooring `(max - min) / resolution` to count grid points.
/// The SPEC wrote `1e-9` for double precision; the values here are `f32`, whose rounding of a
/// ratio such as `0.52 / 0.065` is about `1e-6`, so the guard is widened accordingly.
const AXIS_COUNT_GUARD: f32 = 1e-4;

/// The values of one scenario as read from a file, before checking.
#[derive(Clone, Copy, Debug)]
pub struct ScenarioInput<'a> {
    /// `payload.footprint`: outline polygon, in order.
    pub footprint: &'a [Vec2],
    /// `payload.rail`: closed path of the rotor centres, in order.
    pub rail: &'a [Vec2],
    /// `payload.candidates`: candidate attachment points as arc lengths along the rail.
    pub candidates: &'a [f32],
    /// `robots.*`.
    pub robots: RobotsInput<'a>,
    /// `estimation.*`.
    pub estimation: EstimationSetup,
    /// `formation.*`.
    pub formation: FormationSetup,
    /// `truth.*` (simulation only).
    pub truth: Option<Truth>,
    /// `flight.*` (simulation only).
    pub flight: Option<FlightSetup>,
}

/// `robots.*` as read, before checking.
#[derive(Clone, Copy, Debug)]
pub struct RobotsInput<'a> {
    /// `robots.count`.
    pub count: usize,
    /// `robots.mass`: one robot, kg.
    pub mass: f32,
    /// `robots.max_thrust`: one rotor, N.
    pub max_thrust: f32,
    /// `robots.torque_per_thrust`: `c_q / c_t`, metres.
    pub torque_per_thrust: f32,
    /// `robots.spin`: +1 or -1 per robot.
    pub spin: &'a [i64],
    /// `robots.min_spacing`: along the rail, metres.
    pub min_spacing: f32,
    /// `robots.pair_size`: robots that lift together during estimation.
    pub pair_size: usize,
    /// `robots.initial`: arc lengths at start; `None` for the even formation.
    pub initial: Option<&'a [f32]>,
}

/// `estimation.*`: the grid of theta = [COM x, COM y, mass] and the stopping rule.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EstimationSetup {
    /// `grid_min`: lowest value of each axis (m, m, kg).
    pub grid_min: [f32; 3],
    /// `grid_max`: highest value of each axis.
    pub grid_max: [f32; 3],
    /// `resolution`: spacing of each axis.
    pub resolution: [f32; 3],
    /// `threshold`: posterior mass near the MAP at which estimation stops (`eps_th`).
    pub threshold: f32,
    /// `noise_sigma`: standard deviation of a thrust measurement, N.
    pub noise_sigma: f32,
    /// `max_measurements`: lifts before giving up as not converged.
    pub max_measurements: u32,
}

impl EstimationSetup {
    /// Number of grid points along `axis`: `floor((max - min) / res + guard) + 1`
    /// (docs/formats.md#scenario-keys).
    pub fn axis_len(&self, axis: usize) -> usize {
        let span = (self.grid_max[axis] - self.grid_min[axis]) / self.resolution[axis];
        crate::math::floor(span + AXIS_COUNT_GUARD) as usize + 1
    }

    /// Value of grid point `index` along `axis`: `min + index * res`.
    pub fn axis_value(&self, axis: usize, index: usize) -> f32 {
        self.grid_min[axis] + index as f32 * self.resolution[axis]
    }

    /// Total number of grid points.
    pub fn grid_points(&self) -> usize {
        (0..3).map(|a| self.axis_len(a)).product()
    }
}

/// `formation.*`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FormationSetup {
    /// `balance_eps`: bound on `|sum b1|` and `|sum b2|`, metres.
    pub balance_eps: f32,
}

/// `truth.*`: the payload as it really is (simulation only).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Truth {
    /// Centre of mass in the body frame, m.
    pub com: Vec2,
    /// Payload mass without robots, kg.
    pub mass: f32,
}

/// `flight.*` (simulation only).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FlightSetup {
    /// World x, y from the take-off point and height above ground, m.
    pub target: [f32; 3],
    /// Peak of the body-torque disturbance, N m.
    pub disturbance_torque: f32,
}

/// The robots, checked.
#[derive(Clone, Debug, PartialEq)]
pub struct Robots {
    /// Robot mass, kg.
    pub mass: f32,
    /// Maximum thrust of one rotor, N.
    pub max_thrust: f32,
    /// `c_q / c_t`, metres.
    pub torque_per_thrust: f32,
    /// Spin sign of each robot (+1 or -1); its length is the robot count.
    pub spin: Vec<i8, MAX_ROBOTS>,
    /// Smallest allowed arc length between neighbours, m.
    pub min_spacing: f32,
    /// Robots that lift together during estimation.
    pub pair_size: usize,
    /// Arc length of each robot at start, in rail order.
    pub initial: Vec<f32, MAX_ROBOTS>,
}

impl Robots {
    /// Number of robots.
    pub fn count(&self) -> usize {
        self.spin.len()
    }
}

/// A payload with its rail and candidate points, checked.
#[derive(Clone, Debug, PartialEq)]
pub struct Payload {
    /// Outline polygon.
    pub footprint: Vec<Vec2, MAX_VERTICES>,
    /// Convex hull of the outline: the support on flat ground.
    pub hull: ConvexHull,
    /// The rail of rotor centres.
    pub rail: Rail,
    /// Candidate attachment points, arc lengths, strictly increasing in `[0, perimeter)`.
    pub candidates: Vec<f32, MAX_CANDIDATES>,
}

/// One whole scenario, checked.
#[derive(Debug, PartialEq)]
pub struct Scenario {
    /// Payload, rail, candidates.
    pub payload: Payload,
    /// The robots.
    pub robots: Robots,
    /// Estimation grid and stopping rule.
    pub estimation: EstimationSetup,
    /// Formation decision set-up.
    pub formation: FormationSetup,
    /// The truth, when simulated.
    pub truth: Option<Truth>,
    /// Flight set-up, when simulated.
    pub flight: Option<FlightSetup>,
}

impl Clone for Scenario {
    /// A copy, out of line: its callers (the planner's load, the mission's, the payload
    /// handed from one to the other) share one body, which the flight controller's flash
    /// budget counts (inlined into one it costs some 1.2 KB more).
    #[inline(never)]
    fn clone(&self) -> Self {
        Self {
            payload: self.payload.clone(),
            robots: self.robots.clone(),
            estimation: self.estimation,
            formation: self.formation,
            truth: self.truth,
            flight: self.flight,
        }
    }
}

mod checks;
mod problem;
#[cfg(test)]
mod tests;

pub use problem::{Problem, ScenarioError};

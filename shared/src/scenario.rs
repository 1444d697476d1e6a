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
#[derive(Clone, Debug, PartialEq)]
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

/// What is wrong with a value.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Problem {
    /// The polygon is unusable.
    Polygon(PolygonError),
    /// A number is NaN or infinite.
    NotFinite,
    /// Must be greater than zero.
    NotPositive(f32),
    /// Must not be negative.
    Negative(f32),
    /// A fraction must lie in (0, 1].
    NotAFraction(f32),
    /// A list has the wrong length.
    Length {
        /// Length required.
        expected: usize,
        /// Length found.
        found: usize,
    },
    /// A list or count is over the capacity this build supports.
    TooMany {
        /// Number found.
        found: usize,
        /// Most allowed.
        max: usize,
    },
    /// Fewer than allowed.
    TooFew {
        /// Number found.
        found: usize,
        /// Least allowed.
        min: usize,
    },
    /// An arc length that is not on the rail.
    OffRail {
        /// Index in the list.
        index: usize,
        /// The value, m.
        arc_length: f32,
        /// The rail's length, m.
        perimeter: f32,
    },
    /// Arc lengths must increase strictly.
    NotIncreasing {
        /// Index of the first value that does not increase.
        index: usize,
    },
    /// A spin sign other than +1 or -1.
    BadSpin {
        /// Robot index.
        index: usize,
        /// The value found.
        value: i64,
    },
    /// Two neighbouring robots closer than `min_spacing`.
    TooClose {
        /// Index of the first robot of the pair.
        index: usize,
        /// Arc length between them, m.
        gap: f32,
        /// Smallest allowed, m.
        min_spacing: f32,
    },
    /// The rail is too short for the robots at `min_spacing`.
    RailTooShort {
        /// Robots.
        count: usize,
        /// Needed rail length, m.
        needed: f32,
        /// Rail length, m.
        perimeter: f32,
    },
    /// More robots in a lifting group than robots.
    FewerRobotsThanPair {
        /// Robots.
        count: usize,
        /// Robots per lifting group.
        pair_size: usize,
    },
    /// `grid_max` below `grid_min` on an axis.
    EmptyAxis {
        /// Axis index (0: COM x, 1: COM y, 2: mass).
        axis: usize,
    },
    /// The mass axis must stay above zero.
    NonPositiveMass {
        /// Lowest mass on the grid, kg.
        lowest: f32,
    },
    /// A point outside the footprint's convex hull.
    OutsideHull,
    /// A robot whose rotor cannot even lift its own weight.
    CannotHoldOwnWeight {
        /// Rotor maximum, N.
        max_thrust: f32,
        /// Robot weight, N.
        weight: f32,
    },
    /// A value above the largest a vehicle of this kind can have.
    TooLarge {
        /// The value.
        value: f32,
        /// Largest allowed.
        max: f32,
        /// Its unit, for the message.
        unit: &'static str,
    },
    /// A value outside the range a vehicle of this kind can have.
    OutOfRange {
        /// The value.
        value: f32,
        /// Smallest allowed.
        min: f32,
        /// Largest allowed.
        max: f32,
        /// Its unit, for the message.
        unit: &'static str,
    },
    /// A point (footprint vertex or rail point) with other than two coordinates.
    Coordinates {
        /// Index of the point in the list.
        index: usize,
        /// Numbers found.
        found: usize,
    },
    /// A coordinate of a point beyond [`MAX_COORDINATE`].
    FarCoordinate {
        /// Index of the point in the list.
        index: usize,
        /// The coordinate, m.
        value: f32,
    },
    /// A rail edge touches or crosses a footprint edge.
    RailCrossesFootprint {
        /// Index of the rail edge (from rail point `rail_edge` to the next).
        rail_edge: usize,
        /// Index of the footprint edge.
        footprint_edge: usize,
    },
    /// A footprint vertex outside the rail: the rail does not run around the payload.
    RailDoesNotEnclose {
        /// Index of the footprint vertex.
        vertex: usize,
    },
    /// A point of the rail farther from the footprint than [`MAX_RAIL_CLEARANCE`].
    RailTooFar {
        /// The point, m.
        at: Vec2,
        /// Its distance from the footprint's outline, m.
        distance: f32,
    },
    /// A lifting group needs more candidates than there are.
    GroupLargerThanCandidates {
        /// Robots per lifting group.
        pair_size: usize,
        /// Candidate points.
        candidates: usize,
    },
    /// No lifting group can stand at its candidates.
    NoReachableGroup {
        /// Robots per lifting group.
        pair_size: usize,
        /// `robots.min_spacing`, m.
        min_spacing: f32,
    },
    /// Every robot spins the same way: yaw cannot be balanced.
    OneSpinDirection {
        /// The one sign present.
        sign: i8,
    },
    /// The estimation grid is larger than supported.
    TooManyGridPoints {
        /// Points, when the count is meaningful (each axis at most [`MAX_GRID_POINTS`]).
        found: Option<u64>,
    },
    /// No COM of the grid lies inside the footprint's convex hull.
    GridOutsideHull,
}

/// A number for a message: plain when ordinary, in exponent form when huge or tiny, and
/// `f32::MAX` (what the host makes of a value beyond `f32`) as "over 3.40282e38" (six
/// significant digits, see [`Num`]).
struct Number(f32);

impl core::fmt::Display for Number {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        let v = self.0;
        if crate::math::abs(v) == f32::MAX {
            let beyond = if v > 0.0 { "over" } else { "under" };
            write!(f, "{beyond} {}", Num(v))
        } else {
            write!(f, "{}", Num(v))
        }
    }
}

impl core::fmt::Display for Problem {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match *self {
            Self::Polygon(e) => write!(f, "polygon {e}"),
            Self::NotFinite => write!(f, "must be a finite number"),
            Self::NotPositive(v) => write!(f, "must be greater than zero (got {v})", v = Num(v)),
            Self::Negative(v) => write!(f, "must not be negative (got {v})", v = Num(v)),
            Self::NotAFraction(v) => write!(f, "must lie in (0, 1] (got {v})", v = Num(v)),
            Self::Length { expected, found } => {
                write!(f, "needs {expected} entries (got {found})")
            }
            Self::TooMany { found, max } => write!(f, "has {found}, at most {max} supported"),
            Self::TooFew { found, min } => write!(f, "has {found}, needs at least {min}"),
            Self::OffRail {
                index,
                arc_length,
                perimeter,
            } => write!(
                f,
                "entry {index} = {arc_length} m is unreachable: the rail runs from 0 to {perimeter} m",
                arc_length = Num(arc_length),
                perimeter = Num(perimeter)
            ),
            Self::NotIncreasing { index } => {
                write!(f, "entry {index} does not increase along the rail")
            }
            Self::BadSpin { index, value } => {
                write!(f, "entry {index} is {value}; spin must be 1 or -1")
            }
            Self::TooClose {
                index,
                gap,
                min_spacing,
            } => write!(
                f,
                "robots {index} and the next are {gap} m apart, closer than min_spacing {min_spacing} m",
                gap = Num(gap),
                min_spacing = Num(min_spacing)
            ),
            Self::RailTooShort {
                count,
                needed,
                perimeter,
            } => write!(
                f,
                "{count} robots at min_spacing need {needed} m of rail, the rail is {perimeter} m",
                needed = Num(needed),
                perimeter = Num(perimeter)
            ),
            Self::FewerRobotsThanPair { count, pair_size } => {
                write!(
                    f,
                    "{count} robots are fewer than a lifting group of {pair_size}"
                )
            }
            Self::EmptyAxis { axis } => write!(f, "axis {axis} has grid_max below grid_min"),
            Self::NonPositiveMass { lowest } => {
                write!(
                    f,
                    "mass axis must stay above zero (lowest {} kg)",
                    Num(lowest)
                )
            }
            Self::OutsideHull => write!(f, "lies outside the footprint's convex hull"),
            Self::CannotHoldOwnWeight { max_thrust, weight } => write!(
                f,
                "{max_thrust} N cannot hold the robot's own weight of {weight} N",
                max_thrust = Num(max_thrust),
                weight = Num(weight)
            ),
            Self::TooLarge { value, max, unit } => {
                write!(
                    f,
                    "must be at most {max} {unit} (got {} {unit})",
                    Number(value),
                    max = Num(max)
                )
            }
            Self::OutOfRange {
                value,
                min,
                max,
                unit,
            } => write!(
                f,
                "must lie between {min} and {max} {unit} (got {} {unit})",
                Number(value),
                max = Num(max),
                min = Num(min)
            ),
            Self::Coordinates { index, found } => write!(
                f,
                "point {index} has {found} numbers; each point is [x, y], two numbers"
            ),
            Self::FarCoordinate { index, value } => write!(
                f,
                "point {index} has coordinate {} m, beyond the {MAX_COORDINATE} m a payload of this kind spans",
                Number(value),
                MAX_COORDINATE = Num(MAX_COORDINATE)
            ),
            Self::RailCrossesFootprint {
                rail_edge,
                footprint_edge,
            } => write!(
                f,
                "rail edge {rail_edge} touches or crosses footprint edge {footprint_edge}; every rotor must sit outside the outline"
            ),
            Self::RailDoesNotEnclose { vertex } => write!(
                f,
                "footprint vertex {vertex} lies outside the rail; the rail must run around the footprint"
            ),
            Self::RailTooFar { at, distance } => write!(
                f,
                "rail point ({}, {}) is {} m from the footprint, more than the {MAX_RAIL_CLEARANCE} m a rotor arm reaches",
                Number(at.x),
                Number(at.y),
                Number(distance),
                MAX_RAIL_CLEARANCE = Num(MAX_RAIL_CLEARANCE)
            ),
            Self::GroupLargerThanCandidates {
                pair_size,
                candidates,
            } => write!(
                f,
                "a lifting group of {pair_size} robots needs {pair_size} candidates, payload.candidates has {candidates}"
            ),
            Self::NoReachableGroup {
                pair_size,
                min_spacing,
            } => write!(
                f,
                "no {pair_size} adjacent candidates can hold robots: they are closer than robots.min_spacing {min_spacing} m or leave no room for the other robots",
                min_spacing = Num(min_spacing)
            ),
            Self::OneSpinDirection { sign } => write!(
                f,
                "every robot spins {sign:+}; balancing yaw needs rotors of both directions (1 and -1)"
            ),
            Self::TooManyGridPoints { found: Some(found) } => write!(
                f,
                "the grid has {found} points, at most {MAX_GRID_POINTS} supported"
            ),
            Self::TooManyGridPoints { found: None } => write!(
                f,
                "the grid has more than {MAX_GRID_POINTS} points on one axis alone, at most {MAX_GRID_POINTS} supported"
            ),
            Self::GridOutsideHull => write!(
                f,
                "no COM of the grid (grid_min to grid_max) lies inside the footprint's convex hull"
            ),
        }
    }
}

/// A scenario value that breaks a rule: which key, and what is wrong.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ScenarioError {
    /// The scenario key, as in the file (`section.key`).
    pub key: &'static str,
    /// What is wrong with it.
    pub problem: Problem,
}

impl core::fmt::Display for ScenarioError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        write!(f, "{}: {}", self.key, self.problem)
    }
}

impl core::error::Error for ScenarioError {}

fn fail<T>(key: &'static str, problem: Problem) -> Result<T, ScenarioError> {
    Err(ScenarioError { key, problem })
}

fn positive(key: &'static str, v: f32) -> Result<f32, ScenarioError> {
    if !v.is_finite() {
        fail(key, Problem::NotFinite)
    } else if v <= 0.0 {
        fail(key, Problem::NotPositive(v))
    } else {
        Ok(v)
    }
}

fn non_negative(key: &'static str, v: f32) -> Result<f32, ScenarioError> {
    if !v.is_finite() {
        fail(key, Problem::NotFinite)
    } else if v < 0.0 {
        fail(key, Problem::Negative(v))
    } else {
        Ok(v)
    }
}

fn at_most(key: &'static str, v: f32, max: f32, unit: &'static str) -> Result<f32, ScenarioError> {
    if v > max {
        fail(
            key,
            Problem::TooLarge {
                value: v,
                max,
                unit,
            },
        )
    } else {
        Ok(v)
    }
}

/// Checks a payload mass, kg: finite, above zero, at most [`MAX_PAYLOAD_MASS`].
fn check_payload_mass(key: &'static str, mass: f32) -> Result<f32, ScenarioError> {
    at_most(key, positive(key, mass)?, MAX_PAYLOAD_MASS, "kg")
}

/// Checks the points of a footprint or rail: finite, each coordinate within
/// [`MAX_COORDINATE`].
fn coordinates(key: &'static str, points: &[Vec2]) -> Result<(), ScenarioError> {
    for (index, p) in points.iter().enumerate() {
        for value in [p.x, p.y] {
            if !value.is_finite() {
                return fail(
                    key,
                    Problem::Polygon(PolygonError::NotFinite { vertex: index }),
                );
            }
            if crate::math::abs(value) > MAX_COORDINATE {
                return fail(key, Problem::FarCoordinate { index, value });
            }
        }
    }
    Ok(())
}

/// Checks arc lengths on `rail`: each in `[0, perimeter)`, strictly increasing.
fn arc_lengths_on_rail(
    key: &'static str,
    values: &[f32],
    rail: &Rail,
) -> Result<(), ScenarioError> {
    let perimeter = rail.perimeter();
    for (index, &s) in values.iter().enumerate() {
        if !s.is_finite() {
            return fail(key, Problem::NotFinite);
        }
        if !(0.0..perimeter).contains(&s) {
            return fail(
                key,
                Problem::OffRail {
                    index,
                    arc_length: s,
                    perimeter,
                },
            );
        }
        if index > 0 && s <= values[index - 1] {
            return fail(key, Problem::NotIncreasing { index });
        }
    }
    Ok(())
}

/// Checks that the rail runs around the footprint with every rotor outside the outline and
/// within [`MAX_RAIL_CLEARANCE`] of it: no rail edge touches a footprint edge, every footprint
/// vertex lies inside the rail (together: the outline lies wholly inside the rail and the rail
/// wholly outside the outline), and no point of the rail is farther than the bound.
fn rail_around_footprint(rail: &[Vec2], footprint: &[Vec2]) -> Result<(), ScenarioError> {
    const KEY: &str = "payload.rail";
    if let Some((rail_edge, footprint_edge)) = first_touching_edges(rail, footprint) {
        return fail(
            KEY,
            Problem::RailCrossesFootprint {
                rail_edge,
                footprint_edge,
            },
        );
    }
    if let Some(vertex) = footprint.iter().position(|&v| !polygon_contains(rail, v)) {
        return fail(KEY, Problem::RailDoesNotEnclose { vertex });
    }
    if let Some((at, distance)) = farthest_beyond(
        rail,
        footprint,
        MAX_RAIL_CLEARANCE,
        RAIL_CLEARANCE_TOLERANCE,
    ) {
        return fail(KEY, Problem::RailTooFar { at, distance });
    }
    Ok(())
}

impl Scenario {
    /// Checks every value of `input` and builds the scenario, or names the first key that
    /// breaks a rule.
    pub fn from_input(input: &ScenarioInput<'_>) -> Result<Self, ScenarioError> {
        let payload = Self::payload(input)?;
        let robots = Self::robots(&input.robots, &payload)?;
        let estimation = Self::estimation(&input.estimation, robots.max_thrust)?;
        let eps = positive("formation.balance_eps", input.formation.balance_eps)?;
        let formation = FormationSetup {
            balance_eps: at_most("formation.balance_eps", eps, MAX_BALANCE_EPS, "m")?,
        };
        if let Some(truth) = input.truth {
            if !truth.com.is_finite() {
                return fail("truth.com", Problem::NotFinite);
            }
            if !payload.hull.contains(truth.com, HULL_TOLERANCE) {
                return fail("truth.com", Problem::OutsideHull);
            }
            check_payload_mass("truth.mass", truth.mass)?;
        }
        if let Some(flight) = input.flight {
            Self::flight(&flight)?;
        }
        let scenario = Self {
            payload,
            robots,
            estimation,
            formation,
            truth: input.truth,
            flight: input.flight,
        };
        scenario.lifting_groups()?;
        scenario.grid_support()?;
        Ok(scenario)
    }

    fn payload(input: &ScenarioInput<'_>) -> Result<Payload, ScenarioError> {
        coordinates("payload.footprint", input.footprint)?;
        check_simple_polygon(input.footprint)
            .or_else(|e| fail("payload.footprint", Problem::Polygon(e)))?;
        let footprint = Vec::from_slice(input.footprint).or_else(|_| {
            fail(
                "payload.footprint",
                Problem::Polygon(PolygonError::TooManyVertices),
            )
        })?;
        let hull = match ConvexHull::of(input.footprint) {
            Some(h) => h,
            None => {
                return fail(
                    "payload.footprint",
                    Problem::Polygon(PolygonError::ZeroArea),
                );
            }
        };
        coordinates("payload.rail", input.rail)?;
        let rail = Rail::new(input.rail).or_else(|e| fail("payload.rail", Problem::Polygon(e)))?;
        rail_around_footprint(input.rail, input.footprint)?;
        let found = input.candidates.len();
        if found < 2 {
            return fail("payload.candidates", Problem::TooFew { found, min: 2 });
        }
        let candidates = Vec::from_slice(input.candidates).or_else(|_| {
            fail(
                "payload.candidates",
                Problem::TooMany {
                    found,
                    max: MAX_CANDIDATES,
                },
            )
        })?;
        arc_lengths_on_rail("payload.candidates", input.candidates, &rail)?;
        Ok(Payload {
            footprint,
            hull,
            rail,
            candidates,
        })
    }

    fn robots(input: &RobotsInput<'_>, payload: &Payload) -> Result<Robots, ScenarioError> {
        let rail = &payload.rail;
        let count = input.count;
        if count == 0 {
            return fail("robots.count", Problem::TooFew { found: 0, min: 1 });
        }
        if count > MAX_ROBOTS {
            return fail(
                "robots.count",
                Problem::TooMany {
                    found: count,
                    max: MAX_ROBOTS,
                },
            );
        }
        let mass = positive("robots.mass", input.mass)?;
        let mass = at_most("robots.mass", mass, MAX_ROBOT_MASS, "kg")?;
        let max_thrust = positive("robots.max_thrust", input.max_thrust)?;
        let max_thrust = at_most("robots.max_thrust", max_thrust, MAX_ROTOR_THRUST, "N")?;
        if max_thrust <= mass * GRAVITY {
            return fail(
                "robots.max_thrust",
                Problem::CannotHoldOwnWeight {
                    max_thrust,
                    weight: mass * GRAVITY,
                },
            );
        }
        let torque_per_thrust = positive("robots.torque_per_thrust", input.torque_per_thrust)?;
        let torque_per_thrust = at_most(
            "robots.torque_per_thrust",
            torque_per_thrust,
            MAX_TORQUE_PER_THRUST,
            "m",
        )?;
        if input.spin.len() != count {
            return fail(
                "robots.spin",
                Problem::Length {
                    expected: count,
                    found: input.spin.len(),
                },
            );
        }
        let mut spin: Vec<i8, MAX_ROBOTS> = Vec::new();
        for (index, &value) in input.spin.iter().enumerate() {
            let sign = match value {
                1 => 1,
                -1 => -1,
                _ => return fail("robots.spin", Problem::BadSpin { index, value }),
            };
            // count <= MAX_ROBOTS was checked above.
            let _ = spin.push(sign);
        }
        let min_spacing = positive("robots.min_spacing", input.min_spacing)?;
        let perimeter = rail.perimeter();
        let needed = count as f32 * min_spacing;
        if needed > perimeter {
            return fail(
                "robots.min_spacing",
                Problem::RailTooShort {
                    count,
                    needed,
                    perimeter,
                },
            );
        }
        let pair_size = input.pair_size;
        if pair_size == 0 {
            return fail("robots.pair_size", Problem::TooFew { found: 0, min: 1 });
        }
        if pair_size > count {
            return fail(
                "robots.pair_size",
                Problem::FewerRobotsThanPair { count, pair_size },
            );
        }
        if pair_size > payload.candidates.len() {
            return fail(
                "robots.pair_size",
                Problem::GroupLargerThanCandidates {
                    pair_size,
                    candidates: payload.candidates.len(),
                },
            );
        }
        // Yaw comes only from the rotors' drag torques: with every rotor turning one way, no
        // positive thrusts sum to zero yaw torque, in hover or ever (one robot included).
        // Both directions are enough here: where the robots stand is the formation's choice.
        let first = spin[0];
        if spin.iter().all(|&s| s == first) {
            return fail("robots.spin", Problem::OneSpinDirection { sign: first });
        }
        let initial = match input.initial {
            None => (0..count)
                .map(|j| j as f32 * perimeter / count as f32)
                .collect(),
            Some(given) => {
                if given.len() != count {
                    return fail(
                        "robots.initial",
                        Problem::Length {
                            expected: count,
                            found: given.len(),
                        },
                    );
                }
                arc_lengths_on_rail("robots.initial", given, rail)?;
                for index in 0..count {
                    let next = (index + 1) % count;
                    let gap = rail.forward_gap(given[index], given[next]);
                    let gap = if count == 1 { perimeter } else { gap };
                    if gap < min_spacing - 1e-6 {
                        return fail(
                            "robots.initial",
                            Problem::TooClose {
                                index,
                                gap,
                                min_spacing,
                            },
                        );
                    }
                }
                // Length checked equal to count <= MAX_ROBOTS.
                Vec::from_slice(given).unwrap_or_default()
            }
        };
        Ok(Robots {
            mass,
            max_thrust,
            torque_per_thrust,
            spin,
            min_spacing,
            pair_size,
            initial,
        })
    }

    fn estimation(
        input: &EstimationSetup,
        max_thrust: f32,
    ) -> Result<EstimationSetup, ScenarioError> {
        for axis in 0..3 {
            for (key, value) in [
                ("estimation.grid_min", input.grid_min[axis]),
                ("estimation.grid_max", input.grid_max[axis]),
            ] {
                if !value.is_finite() {
                    return fail(key, Problem::NotFinite);
                }
                if axis < 2 && crate::math::abs(value) > MAX_COORDINATE {
                    return fail(
                        key,
                        Problem::OutOfRange {
                            value,
                            min: -MAX_COORDINATE,
                            max: MAX_COORDINATE,
                            unit: "m",
                        },
                    );
                }
                if axis == 2 {
                    at_most(key, value, MAX_PAYLOAD_MASS, "kg")?;
                }
            }
            positive("estimation.resolution", input.resolution[axis])?;
            if input.grid_max[axis] < input.grid_min[axis] {
                return fail("estimation.grid_max", Problem::EmptyAxis { axis });
            }
        }
        if input.grid_min[2] <= 0.0 {
            return fail(
                "estimation.grid_min",
                Problem::NonPositiveMass {
                    lowest: input.grid_min[2],
                },
            );
        }
        // Count in f32 only after the per-axis sizes are known to be sane; u64 holds the
        // product of three axes of at most MAX_GRID_POINTS + 1 points each.
        let mut points: Option<u64> = Some(1);
        for axis in 0..3 {
            let span = (input.grid_max[axis] - input.grid_min[axis]) / input.resolution[axis];
            points = if span.is_finite() && span <= MAX_GRID_POINTS as f32 {
                points.map(|p| p * input.axis_len(axis) as u64)
            } else {
                None
            };
        }
        if points.is_none_or(|p| p > MAX_GRID_POINTS as u64) {
            return fail(
                "estimation.resolution",
                Problem::TooManyGridPoints { found: points },
            );
        }
        let t = input.threshold;
        if !t.is_finite() {
            return fail("estimation.threshold", Problem::NotFinite);
        }
        if t <= 0.0 || t > 1.0 {
            return fail("estimation.threshold", Problem::NotAFraction(t));
        }
        let sigma = positive("estimation.noise_sigma", input.noise_sigma)?;
        // A reading's noise larger than the rotor's whole range carries no information.
        at_most("estimation.noise_sigma", sigma, max_thrust, "N")?;
        if input.max_measurements == 0 {
            return fail(
                "estimation.max_measurements",
                Problem::TooFew { found: 0, min: 1 },
            );
        }
        if input.max_measurements > MAX_MEASUREMENTS {
            return fail(
                "estimation.max_measurements",
                Problem::TooMany {
                    found: input.max_measurements as usize,
                    max: MAX_MEASUREMENTS as usize,
                },
            );
        }
        Ok(*input)
    }

    fn flight(flight: &FlightSetup) -> Result<(), ScenarioError> {
        const KEY: &str = "flight.target";
        if flight.target.iter().any(|v| !v.is_finite()) {
            return fail(KEY, Problem::NotFinite);
        }
        let [x, y, height] = flight.target;
        let distance = crate::math::sqrt(x * x + y * y);
        at_most(KEY, distance, MAX_TARGET_DISTANCE, "m away")?;
        positive(KEY, height)?;
        at_most(KEY, height, MAX_TARGET_HEIGHT, "m high")?;
        let torque = non_negative("flight.disturbance_torque", flight.disturbance_torque)?;
        at_most(
            "flight.disturbance_torque",
            torque,
            MAX_DISTURBANCE_TORQUE,
            "N m",
        )?;
        Ok(())
    }

    /// Refuses lifting groups that cannot be formed: at least one group of `pair_size`
    /// adjacent candidates must hold robots at `min_spacing` with room for the others, or
    /// estimation could never take a reading.
    fn lifting_groups(&self) -> Result<(), ScenarioError> {
        let reachable = (0..group_count(self))
            .filter_map(|i| lift_group(self, i))
            .any(|g| g.reachable);
        if reachable {
            Ok(())
        } else {
            fail(
                "payload.candidates",
                Problem::NoReachableGroup {
                    pair_size: self.robots.pair_size,
                    min_spacing: self.robots.min_spacing,
                },
            )
        }
    }

    /// Refuses a grid with no COM inside the footprint's hull: its prior would be empty.
    fn grid_support(&self) -> Result<(), ScenarioError> {
        let e = &self.estimation;
        let hull = &self.payload.hull;
        let inside = (0..e.axis_len(0)).any(|i| {
            (0..e.axis_len(1)).any(|j| {
                hull.contains(
                    Vec2::new(e.axis_value(0, i), e.axis_value(1, j)),
                    HULL_TOLERANCE,
                )
            })
        });
        if inside {
            Ok(())
        } else {
            fail("estimation.grid_min/grid_max", Problem::GridOutsideHull)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::paper::rect_sim1;

    #[test]
    fn paper_rectangle_is_accepted_with_even_start() {
        let s = Scenario::from_input(&rect_sim1()).expect("valid");
        assert_eq!(s.robots.count(), 8);
        assert!((s.robots.initial[1] - 4.88 / 8.0).abs() < 1e-6);
        // floor(1/0.1)+1, floor(0.1/0.03)+1, floor(1.5/0.5)+1
        assert_eq!(
            [0, 1, 2].map(|a| s.estimation.axis_len(a)),
            [11, 4, 4],
            "the grid axis rule"
        );
    }

    #[test]
    fn experiment_grid_counts_despite_f32_rounding() {
        let e = EstimationSetup {
            grid_min: [-0.26, -0.06, 2.2],
            grid_max: [0.26, 0.06, 4.0],
            resolution: [0.065, 0.04, 0.45],
            threshold: 0.53,
            noise_sigma: 1.0,
            max_measurements: 20,
        };
        assert_eq!([0, 1, 2].map(|a| e.axis_len(a)), [9, 4, 5]);
    }

    #[test]
    fn each_bad_value_names_its_key() {
        let mut bad = rect_sim1();
        bad.estimation.resolution[1] = 0.0;
        assert_eq!(
            Scenario::from_input(&bad).unwrap_err().key,
            "estimation.resolution"
        );

        let mut bad = rect_sim1();
        bad.robots.count = 1;
        bad.robots.spin = &[1];
        assert_eq!(
            Scenario::from_input(&bad).unwrap_err().problem,
            Problem::FewerRobotsThanPair {
                count: 1,
                pair_size: 2
            }
        );

        let far = [0.12, 0.56, 5.0];
        let mut bad = rect_sim1();
        bad.candidates = &far;
        let err = Scenario::from_input(&bad).unwrap_err();
        assert_eq!(err.key, "payload.candidates");
        assert!(matches!(err.problem, Problem::OffRail { index: 2, .. }));

        let bow = [
            Vec2::new(0.0, 0.0),
            Vec2::new(1.0, 1.0),
            Vec2::new(1.0, 0.0),
            Vec2::new(0.0, 1.0),
        ];
        let mut bad = rect_sim1();
        bad.footprint = &bow;
        assert_eq!(
            Scenario::from_input(&bad).unwrap_err().key,
            "payload.footprint"
        );

        let mut bad = rect_sim1();
        bad.truth = Some(Truth {
            com: Vec2::new(0.95, 0.0),
            mass: 3.0,
        });
        assert_eq!(
            Scenario::from_input(&bad).unwrap_err().problem,
            Problem::OutsideHull
        );
    }

    #[test]
    fn initial_positions_must_keep_spacing_across_the_wrap() {
        let crowded = [0.0, 0.5, 1.0, 1.5, 2.0, 2.5, 3.0, 4.7];
        let mut bad = rect_sim1();
        bad.robots.initial = Some(&crowded);
        let err = Scenario::from_input(&bad).unwrap_err();
        assert_eq!(err.key, "robots.initial");
        assert!(matches!(err.problem, Problem::TooClose { index: 7, .. }));
    }

    use std::string::ToString;

    /// The key and problem of the error `edit` makes of rect-sim1.
    fn refusal(edit: impl FnOnce(&mut ScenarioInput<'static>)) -> ScenarioError {
        let mut input = rect_sim1();
        edit(&mut input);
        Scenario::from_input(&input).expect_err("must be refused")
    }

    #[test]
    fn coordinates_beyond_the_bound_are_refused_before_lengths_overflow() {
        static FAR: [Vec2; 4] = [
            Vec2::new(-0.88, -0.1),
            Vec2::new(1e20, -0.1),
            Vec2::new(0.88, 0.1),
            Vec2::new(-0.88, 0.1),
        ];
        let err = refusal(|s| s.footprint = &FAR);
        assert_eq!(err.key, "payload.footprint");
        assert_eq!(
            err.problem,
            Problem::FarCoordinate {
                index: 1,
                value: 1e20
            }
        );
        let err = refusal(|s| s.rail = &FAR);
        assert_eq!(err.key, "payload.rail");
        assert!(err.to_string().contains("1e20"), "{err}");
    }

    #[test]
    fn the_rail_must_run_close_around_the_footprint() {
        static FAR_AWAY: [Vec2; 4] = [
            Vec2::new(-5.88, -5.1),
            Vec2::new(5.88, -5.1),
            Vec2::new(5.88, 5.1),
            Vec2::new(-5.88, 5.1),
        ];
        static INSIDE: [Vec2; 4] = [
            Vec2::new(-0.8, -0.05),
            Vec2::new(0.8, -0.05),
            Vec2::new(0.8, 0.05),
            Vec2::new(-0.8, 0.05),
        ];
        static CROSSING: [Vec2; 4] = [
            Vec2::new(-0.5, -0.22),
            Vec2::new(0.5, -0.22),
            Vec2::new(0.5, 0.22),
            Vec2::new(-0.5, 0.22),
        ];
        static BESIDE: [Vec2; 4] = [
            Vec2::new(1.0, -0.22),
            Vec2::new(1.5, -0.22),
            Vec2::new(1.5, 0.22),
            Vec2::new(1.0, 0.22),
        ];
        let err = refusal(|s| s.rail = &FAR_AWAY);
        assert_eq!(err.key, "payload.rail");
        assert!(matches!(err.problem, Problem::RailTooFar { distance, .. } if distance > 4.9));
        let err = refusal(|s| s.rail = &INSIDE);
        assert_eq!(err.problem, Problem::RailDoesNotEnclose { vertex: 0 });
        let err = refusal(|s| s.rail = &CROSSING);
        assert!(matches!(err.problem, Problem::RailCrossesFootprint { .. }));
        let err = refusal(|s| s.rail = &BESIDE);
        assert_eq!(err.problem, Problem::RailDoesNotEnclose { vertex: 0 });
        // Just inside the bound is fine: the rail's corners are sqrt(2) * 0.7 = 0.99 m out.
        static WIDE: [Vec2; 4] = [
            Vec2::new(-1.58, -0.8),
            Vec2::new(1.58, -0.8),
            Vec2::new(1.58, 0.8),
            Vec2::new(-1.58, 0.8),
        ];
        let mut wide = rect_sim1();
        wide.rail = &WIDE;
        wide.candidates = &[0.12, 0.56, 1.0];
        Scenario::from_input(&wide).expect("0.99 m of clearance is within the bound");
    }

    #[test]
    fn lifting_groups_that_cannot_be_formed_are_refused() {
        let err = refusal(|s| {
            s.candidates = &[0.12, 0.56];
            s.robots.pair_size = 3;
        });
        assert_eq!(err.key, "robots.pair_size");
        assert_eq!(
            err.problem,
            Problem::GroupLargerThanCandidates {
                pair_size: 3,
                candidates: 2
            }
        );
        // rect-sim1's candidates are 0.34 to 0.44 m apart.
        let err = refusal(|s| s.robots.min_spacing = 0.5);
        assert_eq!(err.key, "payload.candidates");
        assert!(err.to_string().contains("robots.min_spacing 0.5"), "{err}");
    }

    #[test]
    fn a_grid_wholly_outside_the_hull_is_refused() {
        let err = refusal(|s| {
            s.estimation.grid_min[0] = 0.9;
            s.estimation.grid_max[0] = 1.2;
        });
        assert_eq!(err.key, "estimation.grid_min/grid_max");
        assert_eq!(err.problem, Problem::GridOutsideHull);
        // One column on the hull's edge is enough.
        let mut edge = rect_sim1();
        edge.estimation.grid_min[0] = 0.88;
        edge.estimation.grid_max[0] = 1.2;
        Scenario::from_input(&edge).expect("x = 0.88 lies on the hull");
    }

    #[test]
    fn yaw_needs_both_spin_directions() {
        let err = refusal(|s| s.robots.spin = &[1; 8]);
        assert_eq!(err.key, "robots.spin");
        assert_eq!(err.problem, Problem::OneSpinDirection { sign: 1 });
        let err = refusal(|s| s.robots.spin = &[-1; 8]);
        assert_eq!(err.problem, Problem::OneSpinDirection { sign: -1 });
        // Unequal counts can still balance yaw with unequal thrusts.
        let mut uneven = rect_sim1();
        uneven.robots.spin = &[1, 1, 1, -1, 1, 1, 1, 1];
        Scenario::from_input(&uneven).expect("both directions present");
    }

    #[test]
    fn absurd_magnitudes_name_their_key() {
        type Edit = fn(&mut ScenarioInput<'static>);
        let cases: [(Edit, &str); 10] = [
            (
                |s| s.robots.torque_per_thrust = 1e6,
                "robots.torque_per_thrust",
            ),
            (
                |s| s.robots.torque_per_thrust = 0.0,
                "robots.torque_per_thrust",
            ),
            (|s| s.robots.mass = 50.0, "robots.mass"),
            (|s| s.robots.max_thrust = 1e4, "robots.max_thrust"),
            (|s| s.estimation.grid_max[2] = 1e5, "estimation.grid_max"),
            (
                |s| s.estimation.noise_sigma = 100.0,
                "estimation.noise_sigma",
            ),
            (
                |s| s.estimation.max_measurements = 1000,
                "estimation.max_measurements",
            ),
            (|s| s.formation.balance_eps = 5.0, "formation.balance_eps"),
            (
                |s| {
                    s.truth = Some(Truth {
                        com: Vec2::new(0.3, 0.0),
                        mass: 1e6,
                    })
                },
                "truth.mass",
            ),
            (
                |s| {
                    s.flight = Some(FlightSetup {
                        target: [0.3, 1.98, 0.5],
                        disturbance_torque: 1e6,
                    })
                },
                "flight.disturbance_torque",
            ),
        ];
        for (edit, key) in cases {
            let err = refusal(edit);
            assert_eq!(err.key, key, "{err}");
        }
        for target in [[1e6, 0.0, 0.5], [0.3, 1.98, 1e6], [0.3, 1.98, 0.0]] {
            let err = refusal(|s| {
                s.flight = Some(FlightSetup {
                    target,
                    disturbance_torque: 0.3,
                })
            });
            assert_eq!(err.key, "flight.target", "{target:?}");
        }
        // A payload too heavy for the robots is a vehicle that exists: the mission must find
        // out and refuse to fly, so the scenario stays valid.
        let mut heavy = rect_sim1();
        heavy.truth = Some(Truth {
            com: Vec2::new(0.33, 0.01),
            mass: 20.0,
        });
        Scenario::from_input(&heavy).expect("20 kg is a payload that exists");
    }

    #[test]
    fn a_grid_too_fine_to_count_says_so_in_words() {
        let err = refusal(|s| s.estimation.resolution[0] = 1e-6);
        assert_eq!(err.key, "estimation.resolution");
        assert_eq!(err.problem, Problem::TooManyGridPoints { found: None });
        let text = err.to_string();
        assert!(text.contains("more than 4096"), "{text}");
        assert!(!text.contains("18446744073709551615"), "{text}");
        // 1001 x 4 x 4 points: counted exactly.
        let err = refusal(|s| s.estimation.resolution[0] = 0.001);
        assert_eq!(
            err.problem,
            Problem::TooManyGridPoints {
                found: Some(1001 * 16)
            }
        );
    }

    #[test]
    fn numbers_in_messages_stay_readable() {
        assert_eq!(Number(0.2).to_string(), "0.2");
        assert_eq!(Number(1e20).to_string(), "1e20");
        assert_eq!(Number(f32::MAX).to_string(), "over 3.40282e38");
        assert_eq!(Number(-f32::MAX).to_string(), "under -3.40282e38");
    }
}

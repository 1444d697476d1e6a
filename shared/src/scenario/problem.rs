//! What is wrong with a scenario value, said for people: [`Problem`] and [`ScenarioError`]
//! (the key and the problem), with the numbers written plainly.

use super::*;

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
    /// No reachable lifting group can tip the grid's heaviest payload at some grid COM: its
    /// every lift would read "could not lift".
    NoGroupTips {
        /// Robots per lifting group.
        pair_size: usize,
        /// The grid's heaviest mass, kg.
        mass: f32,
        /// The grid's COM no group tips, m.
        com: Vec2,
        /// Thrust per robot the best group needs there, N (infinite: none can tip it at all).
        needed: f32,
        /// `robots.max_thrust`, N.
        max_thrust: f32,
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
pub(super) struct Number(pub(super) f32);

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
            Self::NoGroupTips {
                pair_size,
                mass,
                com,
                needed,
                max_thrust,
            } => write!(
                f,
                "no group of {pair_size} adjacent robots can tip the grid's heaviest payload: {} kg with its COM at ({}, {}) m needs {} N per robot of the best group, above robots.max_thrust {} N; lift in larger groups or narrow the grid's mass",
                Num(mass),
                Num(com.x),
                Num(com.y),
                crate::numbers::Fixed(needed, 2),
                Num(max_thrust)
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

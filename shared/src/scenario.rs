//! Plain data the rest of the crate takes: one payload, its rail, the robots, the estimation
//! set-up and (for simulation) the truth, with the checks that make them safe to use.
//!
//! This is the data of a scenario file (SPEC.md section 5, "Scenario files"); the TOML parsing
//! lives on the host, which hands the values over as a [`ScenarioInput`]. Every rule that a
//! value must follow is checked here, once, so that the firmware (which may receive the same
//! values over telemetry) and the simulator reject exactly the same inputs. Each error names
//! the scenario key it is about.

use heapless::Vec;

use crate::geometry::{ConvexHull, MAX_VERTICES, PolygonError, Rail, Vec2, check_simple_polygon};

/// Most robots on one rail.
pub const MAX_ROBOTS: usize = 16;
/// Most candidate attachment points on one rail.
pub const MAX_CANDIDATES: usize = 64;
/// Most points of the estimation grid (all axes multiplied).
pub const MAX_GRID_POINTS: usize = 4096;
/// Standard gravity, m/s^2.
pub const GRAVITY: f32 = 9.80665;

/// Guard added before flooring `(max - min) / resolution` to count grid points.
/// SPEC.md writes `1e-9` for double precision; the values here are `f32`, whose rounding of a
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
    /// Number of grid points along `axis`: `floor((max - min) / res) + 1` (SPEC.md section 5).
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
}

impl core::fmt::Display for Problem {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match *self {
            Self::Polygon(e) => write!(f, "polygon {e}"),
            Self::NotFinite => write!(f, "must be a finite number"),
            Self::NotPositive(v) => write!(f, "must be greater than zero (got {v})"),
            Self::Negative(v) => write!(f, "must not be negative (got {v})"),
            Self::NotAFraction(v) => write!(f, "must lie in (0, 1] (got {v})"),
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
                "entry {index} = {arc_length} m is unreachable: the rail runs from 0 to {perimeter} m"
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
                "robots {index} and the next are {gap} m apart, closer than min_spacing {min_spacing} m"
            ),
            Self::RailTooShort {
                count,
                needed,
                perimeter,
            } => write!(
                f,
                "{count} robots at min_spacing need {needed} m of rail, the rail is {perimeter} m"
            ),
            Self::FewerRobotsThanPair { count, pair_size } => {
                write!(
                    f,
                    "{count} robots are fewer than a lifting group of {pair_size}"
                )
            }
            Self::EmptyAxis { axis } => write!(f, "axis {axis} has grid_max below grid_min"),
            Self::NonPositiveMass { lowest } => {
                write!(f, "mass axis must stay above zero (lowest {lowest} kg)")
            }
            Self::OutsideHull => write!(f, "lies outside the footprint's convex hull"),
            Self::CannotHoldOwnWeight { max_thrust, weight } => write!(
                f,
                "{max_thrust} N cannot hold the robot's own weight of {weight} N"
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

impl Scenario {
    /// Checks every value of `input` and builds the scenario, or names the first key that
    /// breaks a rule.
    pub fn from_input(input: &ScenarioInput<'_>) -> Result<Self, ScenarioError> {
        let payload = Self::payload(input)?;
        let robots = Self::robots(&input.robots, &payload.rail)?;
        let estimation = Self::estimation(&input.estimation)?;
        let formation = FormationSetup {
            balance_eps: positive("formation.balance_eps", input.formation.balance_eps)?,
        };
        if let Some(truth) = input.truth {
            if !truth.com.is_finite() {
                return fail("truth.com", Problem::NotFinite);
            }
            if !payload.hull.contains(truth.com, 1e-6) {
                return fail("truth.com", Problem::OutsideHull);
            }
            positive("truth.mass", truth.mass)?;
        }
        if let Some(flight) = input.flight {
            if flight.target.iter().any(|v| !v.is_finite()) {
                return fail("flight.target", Problem::NotFinite);
            }
            positive("flight.target", flight.target[2])?;
            non_negative("flight.disturbance_torque", flight.disturbance_torque)?;
        }
        Ok(Self {
            payload,
            robots,
            estimation,
            formation,
            truth: input.truth,
            flight: input.flight,
        })
    }

    fn payload(input: &ScenarioInput<'_>) -> Result<Payload, ScenarioError> {
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
        let rail = Rail::new(input.rail).or_else(|e| fail("payload.rail", Problem::Polygon(e)))?;
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

    fn robots(input: &RobotsInput<'_>, rail: &Rail) -> Result<Robots, ScenarioError> {
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
        let max_thrust = positive("robots.max_thrust", input.max_thrust)?;
        if max_thrust <= mass * GRAVITY {
            return fail(
                "robots.max_thrust",
                Problem::CannotHoldOwnWeight {
                    max_thrust,
                    weight: mass * GRAVITY,
                },
            );
        }
        let torque_per_thrust = non_negative("robots.torque_per_thrust", input.torque_per_thrust)?;
        if input.spin.len() != count {
            return fail(
                "robots.spin",
                Problem::Length {
                    expected: count,
                    found: input.spin.len(),
                },
            );
        }
        let mut spin = Vec::new();
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

    fn estimation(input: &EstimationSetup) -> Result<EstimationSetup, ScenarioError> {
        for axis in 0..3 {
            if !input.grid_min[axis].is_finite() {
                return fail("estimation.grid_min", Problem::NotFinite);
            }
            if !input.grid_max[axis].is_finite() {
                return fail("estimation.grid_max", Problem::NotFinite);
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
        // Count in f32 only after the per-axis sizes are known to be sane.
        let mut points: usize = 1;
        for axis in 0..3 {
            let span = (input.grid_max[axis] - input.grid_min[axis]) / input.resolution[axis];
            if span > MAX_GRID_POINTS as f32 {
                points = usize::MAX;
                break;
            }
            points = points.saturating_mul(input.axis_len(axis));
        }
        if points > MAX_GRID_POINTS {
            return fail(
                "estimation.resolution",
                Problem::TooMany {
                    found: points,
                    max: MAX_GRID_POINTS,
                },
            );
        }
        let t = input.threshold;
        if !t.is_finite() {
            return fail("estimation.threshold", Problem::NotFinite);
        }
        if t <= 0.0 || t > 1.0 {
            return fail("estimation.threshold", Problem::NotAFraction(t));
        }
        positive("estimation.noise_sigma", input.noise_sigma)?;
        if input.max_measurements == 0 {
            return fail(
                "estimation.max_measurements",
                Problem::TooFew { found: 0, min: 1 },
            );
        }
        Ok(*input)
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
            "SPEC grid axis rule"
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
}

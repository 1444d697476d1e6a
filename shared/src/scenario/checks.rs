//! The checks that make a scenario safe to use, and the geometry derived from it: each rule
//! once, each failure naming its key ([`Scenario::from_input`]).

use super::*;

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
        scenario.groups_tip_the_heaviest()?;
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

    /// Refuses a payload that some grid point would make unreadable: at the grid's heaviest
    /// mass, every COM of the grid inside the hull must be tipped by at least one reachable
    /// lifting group within `robots.max_thrust` (docs/models.md#lift-off-thrust). Where none
    /// can, every lift of such a payload reads "could not lift", and the estimate can only
    /// run out of lifts: the vehicle says so before the first one.
    fn groups_tip_the_heaviest(&self) -> Result<(), ScenarioError> {
        let e = &self.estimation;
        let hull = &self.payload.hull;
        let heaviest = e.axis_value(2, e.axis_len(2) - 1);
        let groups: Vec<Vec2, MAX_CANDIDATES> = (0..group_count(self))
            .filter_map(|i| lift_group(self, i))
            .filter(|g| g.reachable)
            .map(|g| g.centroid)
            .collect();
        let k = self.robots.pair_size;
        for i in 0..e.axis_len(0) {
            for j in 0..e.axis_len(1) {
                let com = Vec2::new(e.axis_value(0, i), e.axis_value(1, j));
                if !hull.contains(com, HULL_TOLERANCE) {
                    continue;
                }
                let needed = groups
                    .iter()
                    .filter_map(|&m| lift_fraction(hull, com, m, k))
                    .map(|f| thrust_from_fraction(f, heaviest, self.robots.mass))
                    .fold(f32::INFINITY, crate::math::min);
                if needed > self.robots.max_thrust {
                    return fail(
                        "robots.pair_size",
                        Problem::NoGroupTips {
                            pair_size: k,
                            mass: heaviest,
                            com,
                            needed,
                            max_thrust: self.robots.max_thrust,
                        },
                    );
                }
            }
        }
        Ok(())
    }
}

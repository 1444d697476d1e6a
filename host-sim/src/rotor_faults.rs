//! Rotor faults beyond one, measured (docs/failures.md#rotors-that-stop-in-flight): every
//! pair of rotors stopped at once and every rotor fading, flown in the plant with `shared`'s
//! mission, and whether a static hover exists on the rotors left.
//!
//! A static hover exists when thrusts `0 <= t_i <= 0.85 T_max` on the rotors left hold the
//! weight with no roll or pitch torque about the true COM (the formation's rail positions,
//! the payload's and the robots' masses): a linear feasibility problem in as many unknowns as
//! rotors and three equations, decided exactly by its vertices (a feasible bounded polytope
//! has one, with all but three thrusts at a bound).

use anyhow::{Result, anyhow};
use shared::geometry::Vec2;
use shared::scenario::{GRAVITY, Scenario};

use crate::mission_run::{self, EscLink, MissionOutcome, MissionSetup, RotorStop};

/// Largest share of a rotor's maximum thrust a static hover may use.
pub const HOVER_CEILING: f32 = 0.85;

/// When the pairs stop, s after take-off began (in the hover of the paper's missions).
pub const PAIR_STOP_AFTER: f32 = 11.0;

/// When a fade begins, s after take-off began.
pub const FADE_AFTER: f32 = 11.0;

/// The fade's length, s: slower than any rotor's response, so the vehicle's response shows it
/// only as a drift.
pub const FADE_SECONDS: f32 = 4.0;

/// Whether thrusts within `[0, ceiling]` on rotors at `points` hold `weight` (N) with no roll
/// or pitch torque about `com`.
pub fn static_hover_exists(points: &[Vec2], com: Vec2, weight: f32, ceiling: f32) -> bool {
    let columns: Vec<[f64; 3]> = points
        .iter()
        .map(|p| [1.0, f64::from(p.y - com.y), f64::from(p.x - com.x)])
        .collect();
    let (weight, ceiling) = (f64::from(weight), f64::from(ceiling));
    let n = columns.len();
    let det = |m: &[[f64; 3]; 3]| {
        m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1])
            - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
            + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0])
    };
    for a in 0..n {
        for b in a + 1..n {
            for c in b + 1..n {
                let free = [a, b, c];
                let bound: Vec<usize> = (0..n).filter(|i| !free.contains(i)).collect();
                let m: [[f64; 3]; 3] =
                    std::array::from_fn(|r| std::array::from_fn(|k| columns[free[k]][r]));
                let d = det(&m);
                if d.abs() < 1e-9 {
                    continue;
                }
                // Every way of putting the other rotors at 0 or at the ceiling.
                for at_ceiling in 0u32..(1 << bound.len()) {
                    let mut rhs = [weight, 0.0, 0.0];
                    for (k, &i) in bound.iter().enumerate() {
                        if at_ceiling & (1 << k) != 0 {
                            for (r, v) in rhs.iter_mut().enumerate() {
                                *v -= columns[i][r] * ceiling;
                            }
                        }
                    }
                    let fits = (0..3).all(|k| {
                        let mut mk = m;
                        for (r, row) in mk.iter_mut().enumerate() {
                            row[k] = rhs[r];
                        }
                        let t = det(&mk) / d;
                        (-1e-6..=ceiling + 1e-6).contains(&t)
                    });
                    if fits {
                        return true;
                    }
                }
            }
        }
    }
    false
}

/// One pair of rotors stopped at once: what the vehicle could do and what it did.
#[derive(Clone, Debug)]
pub struct PairCase {
    /// The robots, from 1.
    pub robots: (usize, usize),
    /// A static hover exists on the six left.
    pub holdable: bool,
    /// The flight's outcome.
    pub outcome: MissionOutcome,
}

impl PairCase {
    /// Time from the stop to the later of the two rotors named, s (`None` unless both were).
    pub fn detection_s(&self) -> Option<f32> {
        let stopped = self.outcome.rotors_stopped.first()?.1;
        let (a, b) = self.robots;
        let named = |robot: usize| self.outcome.named_at(robot - 1);
        Some(named(a)?.max(named(b)?) - stopped)
    }

    /// The robots named (from 1), in order.
    pub fn named(&self) -> Vec<usize> {
        self.outcome
            .rotors_found
            .iter()
            .map(|(r, _)| r + 1)
            .collect()
    }
}

/// The rotor points and the true COM (payload and robots) of `scenario`'s formation
/// `positions` (arc lengths).
fn formation(scenario: &Scenario, positions: &[f32]) -> Result<(Vec<Vec2>, Vec2, f32)> {
    let truth = scenario
        .truth
        .ok_or_else(|| anyhow!("the scenario has no truth to fly"))?;
    let points: Vec<Vec2> = positions
        .iter()
        .map(|&s| scenario.payload.rail.point_at(s))
        .collect();
    let robot_mass = scenario.robots.mass;
    let total = truth.mass + robot_mass * points.len() as f32;
    let mut moment = truth.com * truth.mass;
    for &p in &points {
        moment = moment + p * robot_mass;
    }
    Ok((points, moment * (1.0 / total), total))
}

/// Whether a static hover exists ([`static_hover_exists`], thrusts up to [`HOVER_CEILING`])
/// on the rotors of `scenario`'s robots at rail `positions` but those of robots `out` (from
/// 0), about the true COM with the true mass.
pub fn holdable_without(scenario: &Scenario, positions: &[f32], out: &[usize]) -> Result<bool> {
    let (points, com, mass) = formation(scenario, positions)?;
    let left: Vec<Vec2> = points
        .iter()
        .enumerate()
        .filter(|(i, _)| !out.contains(i))
        .map(|(_, &p)| p)
        .collect();
    Ok(static_hover_exists(
        &left,
        com,
        mass * GRAVITY,
        HOVER_CEILING * scenario.robots.max_thrust,
    ))
}

/// Where the rotor monitor reads each rotor's RPM from, if anywhere.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RpmSource {
    /// Nowhere: the vehicle's response alone.
    None,
    /// Bidirectional DShot, every control step.
    Dshot,
    /// DroneCAN ESCs' Status, 50 Hz each.
    DroneCan,
}

impl From<bool> for RpmSource {
    /// `true`: bidirectional DShot's RPM; `false`: none.
    fn from(esc_telemetry: bool) -> Self {
        if esc_telemetry {
            Self::Dshot
        } else {
            Self::None
        }
    }
}

/// Flies `scenario` (seed 1) with `stops`, the ESCs' RPM from `rpm`.
pub fn fly(
    scenario: &Scenario,
    stops: &[RotorStop],
    rpm: impl Into<RpmSource>,
) -> Result<MissionOutcome> {
    let rpm = rpm.into();
    let setup = MissionSetup {
        seed: 1,
        rotors_out: stops.to_vec(),
        esc_telemetry: rpm == RpmSource::Dshot,
        esc: if rpm == RpmSource::DroneCan {
            EscLink::Dronecan
        } else {
            EscLink::Dshot
        },
        ..MissionSetup::default()
    };
    Ok(mission_run::run(scenario, &setup, &mut |_, _, _| {})?.0)
}

/// Rotors `a` and `b` (from 1) of `scenario` stopped at once [`PAIR_STOP_AFTER`] s after
/// take-off began.
pub fn pair(
    scenario: &Scenario,
    a: usize,
    b: usize,
    rpm: impl Into<RpmSource>,
) -> Result<PairCase> {
    let stop = |robot: usize| RotorStop {
        robot: robot - 1,
        after: PAIR_STOP_AFTER,
        fade: 0.0,
    };
    let outcome = fly(scenario, &[stop(a), stop(b)], rpm)?;
    let positions = outcome
        .positions
        .clone()
        .ok_or_else(|| anyhow!("the mission chose no formation"))?;
    let holdable = holdable_without(scenario, &positions, &[a - 1, b - 1])?;
    Ok(PairCase {
        robots: (a, b),
        holdable,
        outcome,
    })
}

/// One rotor fading: when it was named and how far the payload had tilted by then.
#[derive(Clone, Debug)]
pub struct FadeCase {
    /// The robot, from 1.
    pub robot: usize,
    /// The flight's outcome.
    pub outcome: MissionOutcome,
}

impl FadeCase {
    /// Time from the fade's start to the rotor named, s.
    pub fn detection_s(&self) -> Option<f32> {
        let began = self.outcome.rotors_stopped.first()?.1;
        Some(self.outcome.named_at(self.robot - 1)? - began)
    }

    /// The robots named that were not fading (from 1): a neighbour whose column reads the
    /// same drift, named in its place.
    pub fn others_named(&self) -> Vec<usize> {
        self.outcome
            .rotors_found
            .iter()
            .map(|(r, _)| r + 1)
            .filter(|&r| r != self.robot)
            .collect()
    }

    /// The largest tilt from the fade's start until the rotor was named, degrees (`None`
    /// if it never was).
    pub fn tilt_when_named_deg(&self) -> Option<f32> {
        let named = self.outcome.named_at(self.robot - 1)?;
        Some(self.outcome.tilt_until(named))
    }
}

/// Robot `robot`'s rotor (from 1) fading to nothing over `seconds`, from [`FADE_AFTER`] s
/// after take-off began.
pub fn fade(
    scenario: &Scenario,
    robot: usize,
    seconds: f32,
    rpm: impl Into<RpmSource>,
) -> Result<FadeCase> {
    let stop = RotorStop {
        robot: robot - 1,
        after: FADE_AFTER,
        fade: seconds,
    };
    Ok(FadeCase {
        robot,
        outcome: fly(scenario, &[stop], rpm)?,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn square() -> Vec<Vec2> {
        vec![
            Vec2::new(-1.0, -1.0),
            Vec2::new(1.0, -1.0),
            Vec2::new(1.0, 1.0),
            Vec2::new(-1.0, 1.0),
        ]
    }

    #[test]
    fn a_hover_exists_inside_the_rotors_and_not_outside() {
        // Four rotors of 10 N at most around the COM: 30 N is held, 41 N is not.
        assert!(static_hover_exists(
            &square(),
            Vec2::new(0.0, 0.0),
            30.0,
            10.0
        ));
        assert!(!static_hover_exists(
            &square(),
            Vec2::new(0.0, 0.0),
            41.0,
            10.0
        ));
        // The COM near one corner: that rotor would carry most of it.
        assert!(!static_hover_exists(
            &square(),
            Vec2::new(0.9, 0.9),
            30.0,
            10.0
        ));
        assert!(static_hover_exists(
            &square(),
            Vec2::new(0.9, 0.9),
            10.0,
            10.0
        ));
        // Outside the rotors' hull: never.
        assert!(!static_hover_exists(
            &square(),
            Vec2::new(1.5, 0.0),
            1.0,
            10.0
        ));
        // Three rotors on a line cannot hold a COM off it.
        let line = [
            Vec2::new(-1.0, 0.0),
            Vec2::new(0.0, 0.0),
            Vec2::new(1.0, 0.0),
        ];
        assert!(!static_hover_exists(&line, Vec2::new(0.0, 0.1), 5.0, 10.0));
    }
}

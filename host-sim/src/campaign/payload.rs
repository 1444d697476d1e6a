//! Random payloads for `campaign` (docs/commands.md#campaign): from a trial's random stream, a
//! payload the paper's robots could carry, written as a scenario file
//! (docs/formats.md#scenario-files) and read back through the same checks every scenario
//! passes (`shared::scenario`), so a drawn payload is exactly a file `mission --scenario` flies.
//!
//! What is drawn, in this order:
//! - the robots' count, uniformly in [`ROBOTS`] (the flight controller's buffers hold 16);
//! - a star-shaped footprint of [`VERTICES`] vertices: angles spread round the origin with a
//!   jitter (each gap under half a turn), radii in [`RADIUS_BAND`] of the largest, squeezed
//!   along y by [`ASPECT`], then scaled so that the rail's length is [`RAIL_PER_ROBOT`] per
//!   robot (the paper's rectangle has 0.61 m, its L-shape 0.43 m). A polygon whose vertices
//!   are in angular order round a point it encloses is simple by construction;
//! - the rail: each footprint vertex pushed [`RAIL_OFFSET`] further out along its ray from the
//!   origin (with every gap under half a turn, that polygon encloses the footprint and touches
//!   it nowhere), refused below [`MIN_RAIL_CLEARANCE`];
//! - the candidates, evenly spaced along the rail [`CANDIDATE_SPACING`] apart from a random
//!   start;
//! - the estimation grid: a box round the footprint's centroid, a fraction [`GRID_FRACTION`]
//!   of the footprint's half-extent each side, 9 points an axis; the mass axis
//!   [`PAYLOAD_MASS_PER_ROBOT`] times the robot count, 5 points (the paper's 2.2 to 4.0 kg for
//!   eight robots);
//! - the truth: a mass uniformly along the grid's mass axis, a COM uniformly in the grid's box
//!   and inside the footprint.
//!
//! The robots, the stopping rule and the flight are the paper's (rect-sim1: 0.1 kg robots of
//! 14.2 N, 0.25 m apart; `eps_th` 0.8; the target 2 m away, 0.5 m high). They lift in
//! groups of [`lifting_group`]: pairs up to ten robots, as in the paper, and threes
//! beyond, so a group's spare thrust lifts half the heaviest payload of the grid, as a team
//! would choose for a long payload (two robots could not lift any edge of an 8 kg payload
//! carried by sixteen: every lift read "could not lift" until the estimate gave up).
//! A draw that a check refuses (or that the mission's planner cannot load) is drawn again from
//! the same stream, at most [`MAX_ATTEMPTS`] times: the campaign never counts a payload that
//! could not exist as a vehicle's failure. The vehicle's own pre-flight checks are among them
//! (a payload some grid point of which no lifting group could tip is refused before the first
//! lift), so the campaign flies only payloads the vehicle accepts; each redraw keeps its
//! reason, and the report counts them.

use std::fmt::Write as _;
use std::ops::RangeInclusive;

use anyhow::{Result, bail};
use rand::RngExt;
use rand_chacha::ChaCha8Rng;
use shared::geometry::{Rail, Vec2, area_moments, distance_to_outline, polygon_contains};
use shared::mission::{MissionConfig, MissionPlanner};

use crate::scenario_file::{self, LoadedScenario};

/// The robots' count.
pub const ROBOTS: RangeInclusive<usize> = 4..=16;
/// The footprint's vertex count.
pub const VERTICES: RangeInclusive<usize> = 4..=9;
/// Each vertex's distance from the origin, as a fraction of the largest.
pub const RADIUS_BAND: [f32; 2] = [0.55, 1.0];
/// The footprint's extent along y over its extent along x, before scaling (the paper's
/// rectangle is 0.11, its L-shape 1).
pub const ASPECT: [f32; 2] = [0.2, 1.0];
/// The rail's length per robot, m.
pub const RAIL_PER_ROBOT: [f32; 2] = [0.45, 0.62];
/// How far out along its ray from the origin a rail vertex sits from its footprint vertex, m
/// (the prototype's rotors sit 0.12 m outside the outline).
pub const RAIL_OFFSET: f32 = 0.14;
/// Least distance between a rail vertex and the outline, or a footprint vertex and the rail, m.
pub const MIN_RAIL_CLEARANCE: f32 = 0.08;
/// The candidates' spacing along the rail, m (the paper's rectangle: 0.34 to 0.44 m).
pub const CANDIDATE_SPACING: [f32; 2] = [0.3, 0.45];
/// The estimation grid's half-width about the centroid, as a fraction of the footprint's
/// half-extent, per axis.
pub const GRID_FRACTION: [f32; 2] = [0.25, 0.5];
/// The grid's mass axis, kg per robot (the paper: 2.2 to 4.0 kg for eight robots).
pub const PAYLOAD_MASS_PER_ROBOT: [f32; 2] = [0.275, 0.5];
/// Grid points along each COM axis.
const COM_POINTS: usize = 9;
/// Grid points along the mass axis.
const MASS_POINTS: usize = 5;
/// Draws before giving up on a payload.
pub const MAX_ATTEMPTS: usize = 100;
/// Tries at a COM inside the footprint before drawing the whole payload again.
const COM_TRIES: usize = 50;

/// A payload drawn, checked and loaded.
#[derive(Clone, Debug)]
pub struct RandomPayload {
    /// The scenario file it is (without a `[plant]` section).
    pub toml: String,
    /// The scenario, checked.
    pub loaded: LoadedScenario,
    /// Footprint vertices.
    pub vertices: usize,
    /// Why each draw before it was refused, in order (empty: the first passed every check).
    pub redrawn: Vec<String>,
}

/// A payload named `name` drawn from `rng`; an error only if [`MAX_ATTEMPTS`] draws in a row
/// fail the checks (never, for these ranges: a test draws hundreds).
pub fn draw(name: &str, rng: &mut ChaCha8Rng) -> Result<RandomPayload> {
    let robots = rng.random_range(ROBOTS);
    let mut redrawn = Vec::new();
    for _ in 0..MAX_ATTEMPTS {
        let (toml, vertices) = match candidate(name, robots, rng) {
            Ok(drawn) => drawn,
            Err(why) => {
                redrawn.push(why.to_string());
                continue;
            }
        };
        let loaded = match scenario_file::parse(&toml, std::path::Path::new(name)) {
            Ok(l) => l,
            Err(e) => {
                redrawn.push(refusal(&e));
                continue;
            }
        };
        if let Err(e) = MissionPlanner::new(&loaded.scenario, MissionConfig::default()) {
            redrawn.push(format!("the mission cannot load it: {e}"));
            continue;
        }
        return Ok(RandomPayload {
            toml,
            loaded,
            vertices,
            redrawn,
        });
    }
    let last = redrawn.last().map_or("none", String::as_str);
    bail!("no valid payload for {robots} robots in {MAX_ATTEMPTS} draws (the last: {last})")
}

/// A scenario file's refusal without the file's name in front (every draw has its own name,
/// and the report counts refusals by kind): the innermost cause, which names the key.
fn refusal(e: &anyhow::Error) -> String {
    e.root_cause().to_string()
}

/// Uniformly in `[lo, hi]`.
fn uniform(rng: &mut ChaCha8Rng, [lo, hi]: [f32; 2]) -> f32 {
    rng.random_range(lo..=hi)
}

/// To the millimetre, as a scenario file is written by hand.
fn mm(v: f32) -> f32 {
    (v * 1000.0).round() / 1000.0
}

/// The star polygon of `angles` and `radii`, squeezed along y by `aspect` and scaled by `s`.
fn star(angles: &[f32], radii: &[f32], aspect: f32, s: f32) -> Vec<Vec2> {
    angles
        .iter()
        .zip(radii)
        .map(|(&a, &r)| Vec2::new(s * r * a.cos(), s * aspect * r * a.sin()))
        .collect()
}

/// Each vertex pushed `offset` further out along its ray from the origin.
fn pushed_out(footprint: &[Vec2], offset: f32) -> Vec<Vec2> {
    footprint
        .iter()
        .map(|&v| v + v * (offset / v.norm()))
        .collect()
}

fn perimeter(points: &[Vec2]) -> f32 {
    let n = points.len();
    (0..n)
        .map(|i| (points[(i + 1) % n] - points[i]).norm())
        .sum()
}

fn points_toml(points: &[Vec2]) -> String {
    let each: Vec<String> = points
        .iter()
        .map(|p| format!("[{}, {}]", p.x, p.y))
        .collect();
    format!("[{}]", each.join(", "))
}

fn numbers_toml(values: &[f32]) -> String {
    let each: Vec<String> = values.iter().map(|v| v.to_string()).collect();
    format!("[{}]", each.join(", "))
}

/// Each robot's mass, kg (the paper's).
const ROBOT_MASS: f32 = 0.1;
/// Each robot's largest thrust, N (the paper's).
const ROBOT_MAX_THRUST: f32 = 14.2;

/// Robots lifting together for a payload of the grid's heaviest mass for `robots` robots:
/// the fewest, at least two, whose thrust beyond their own weight lifts half its weight (the
/// paper's pairs lift two thirds of its heaviest, 4 kg for eight).
pub fn lifting_group(robots: usize) -> usize {
    let spare = ROBOT_MAX_THRUST - ROBOT_MASS * shared::scenario::GRAVITY;
    let half = 0.5 * robots as f32 * PAYLOAD_MASS_PER_ROBOT[1] * shared::scenario::GRAVITY;
    ((half / spare).ceil() as usize).max(2)
}

/// One draw for `robots` robots: the scenario file and its vertex count, or why there is none.
fn candidate(
    name: &str,
    robots: usize,
    rng: &mut ChaCha8Rng,
) -> Result<(String, usize), &'static str> {
    let n = rng.random_range(VERTICES);
    let step = std::f32::consts::TAU / n as f32;
    let turn: f32 = rng.random_range(0.0..std::f32::consts::TAU);
    // A jitter of at most 0.35 of a step either way keeps every gap under 1.7 steps, below
    // half a turn for four vertices or more.
    let angles: Vec<f32> = (0..n)
        .map(|i| turn + step * (i as f32 + rng.random_range(-0.35f32..=0.35)))
        .collect();
    let radii: Vec<f32> = (0..n).map(|_| uniform(rng, RADIUS_BAND)).collect();
    let aspect = uniform(rng, ASPECT);
    let rail_length = robots as f32 * uniform(rng, RAIL_PER_ROBOT);
    // The rail's length grows with the scale: bisect for the one that gives `rail_length`.
    let rail_at = |s: f32| pushed_out(&star(&angles, &radii, aspect, s), RAIL_OFFSET);
    let (mut lo, mut hi) = (0.01f32, 20.0f32);
    for _ in 0..40 {
        let mid = 0.5 * (lo + hi);
        if perimeter(&rail_at(mid)) < rail_length {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    let footprint: Vec<Vec2> = star(&angles, &radii, aspect, hi)
        .into_iter()
        .map(|p| Vec2::new(mm(p.x), mm(p.y)))
        .collect();
    let rail: Vec<Vec2> = pushed_out(&footprint, RAIL_OFFSET)
        .into_iter()
        .map(|p| Vec2::new(mm(p.x), mm(p.y)))
        .collect();
    let clear = rail
        .iter()
        .all(|&p| distance_to_outline(&footprint, p) >= MIN_RAIL_CLEARANCE)
        && footprint
            .iter()
            .all(|&p| distance_to_outline(&rail, p) >= MIN_RAIL_CLEARANCE);
    if !clear {
        return Err("the rail runs too close to the footprint");
    }
    let length = Rail::new(&rail)
        .map_err(|_| "the rail is not a simple polygon")?
        .perimeter();
    let spacing = uniform(rng, CANDIDATE_SPACING);
    let count = ((length / spacing).floor() as usize).clamp(2, shared::scenario::MAX_CANDIDATES);
    let gap = length / count as f32;
    let start: f32 = rng.random_range(0.0..gap);
    let candidates: Vec<f32> = (0..count)
        .map(|j| mm(start + j as f32 * gap))
        .filter(|&s| s < length)
        .collect();
    // The grid: a box round the centroid.
    let centroid = area_moments(&footprint).centroid;
    let (mut x0, mut x1, mut y0, mut y1) = (f32::MAX, f32::MIN, f32::MAX, f32::MIN);
    for p in &footprint {
        (x0, x1, y0, y1) = (x0.min(p.x), x1.max(p.x), y0.min(p.y), y1.max(p.y));
    }
    let half = [
        mm(0.5 * (x1 - x0) * uniform(rng, GRID_FRACTION)),
        mm(0.5 * (y1 - y0) * uniform(rng, GRID_FRACTION)),
    ];
    let centre = [mm(centroid.x), mm(centroid.y)];
    let mass = [
        mm(robots as f32 * PAYLOAD_MASS_PER_ROBOT[0]),
        mm(robots as f32 * PAYLOAD_MASS_PER_ROBOT[1]),
    ];
    let grid_min = [mm(centre[0] - half[0]), mm(centre[1] - half[1]), mass[0]];
    let grid_max = [mm(centre[0] + half[0]), mm(centre[1] + half[1]), mass[1]];
    let resolution: [f32; 3] = std::array::from_fn(|axis| {
        let points = if axis == 2 { MASS_POINTS } else { COM_POINTS };
        (grid_max[axis] - grid_min[axis]) / (points - 1) as f32
    });
    let com = (0..COM_TRIES)
        .map(|_| {
            Vec2::new(
                mm(rng.random_range(grid_min[0]..=grid_max[0])),
                mm(rng.random_range(grid_min[1]..=grid_max[1])),
            )
        })
        .find(|&c| polygon_contains(&footprint, c))
        .ok_or("no COM of the grid's box inside the footprint")?;
    let truth_mass = mm(rng.random_range(mass[0]..=mass[1]));
    let spin: Vec<&str> = (0..robots)
        .map(|j| if j % 2 == 0 { "1" } else { "-1" })
        .collect();
    let spin = format!("[{}]", spin.join(", "));
    let mut toml = String::new();
    // Writing to a String cannot fail.
    let _ = write!(
        toml,
        "# A random payload (host-sim campaign): {n} vertices, {robots} robots.\n\
         name = \"{name}\"\n\n\
         [payload]\nfootprint = {}\nrail = {}\ncandidates = {}\n\n\
         [robots]\ncount = {robots}\nmass = {ROBOT_MASS}\nmax_thrust = {ROBOT_MAX_THRUST}\ntorque_per_thrust = 0.016\n\
         spin = {}\nmin_spacing = 0.25\npair_size = {}\n\n\
         [estimation]\ngrid_min = {}\ngrid_max = {}\nresolution = {}\nthreshold = 0.8\n\
         noise_sigma = 1.0\nmax_measurements = 20\n\n\
         [formation]\nbalance_eps = 0.0001\n\n\
         [truth]\ncom = [{}, {}]\nmass = {truth_mass}\n\n\
         [flight]\ntarget = [0.3, 1.98, 0.5]\ndisturbance_torque = 0.3\n",
        points_toml(&footprint),
        points_toml(&rail),
        numbers_toml(&candidates),
        spin,
        lifting_group(robots),
        numbers_toml(&grid_min),
        numbers_toml(&grid_max),
        numbers_toml(&resolution),
        com.x,
        com.y,
    );
    Ok((toml, n))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_lifting_group_lifts_half_the_heaviest_payload_and_the_paper_lifts_in_pairs() {
        assert_eq!(
            lifting_group(8),
            2,
            "the paper's eight robots lift in pairs"
        );
        assert_eq!(lifting_group(4), 2);
        for robots in ROBOTS {
            let k = lifting_group(robots);
            let spare = k as f32 * (ROBOT_MAX_THRUST - ROBOT_MASS * shared::scenario::GRAVITY);
            let heaviest = robots as f32 * PAYLOAD_MASS_PER_ROBOT[1] * shared::scenario::GRAVITY;
            assert!(spare >= 0.5 * heaviest, "{robots} robots, groups of {k}");
            // The fewest: one robot fewer would not (or the group is the pair).
            let fewer =
                (k - 1) as f32 * (ROBOT_MAX_THRUST - ROBOT_MASS * shared::scenario::GRAVITY);
            assert!(
                k == 2 || fewer < 0.5 * heaviest,
                "{robots} robots, groups of {k}"
            );
        }
        assert_eq!(lifting_group(16), 3);
    }
}

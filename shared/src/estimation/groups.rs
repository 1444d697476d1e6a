//! Lifting groups: `pair_size` robots at adjacent candidate attachment points, group `i` at
//! candidates `i, i+1, ...` (wrapping) (docs/system.md#estimation-loop: only adjacent pairs are
//! scored, so the cost does not grow with the number of robots).
//!
//! A group is reachable when its robots can stand there at all: neighbouring candidates of the
//! group at least `min_spacing` apart along the rail, and room on the rest of the rail for the
//! other robots at `min_spacing`.

use heapless::Vec;

use crate::geometry::Vec2;
use crate::liftoff_thrust::group_centroid;
use crate::scenario::{MAX_ROBOTS, Scenario};

/// One lifting group of adjacent candidates.
#[derive(Clone, Debug, PartialEq)]
pub struct LiftGroup {
    /// Index of the group (its first candidate).
    pub index: usize,
    /// Candidate indices, in rail order.
    pub candidates: Vec<usize, MAX_ROBOTS>,
    /// Rotor points of the group's robots, m.
    pub rotor_points: Vec<Vec2, MAX_ROBOTS>,
    /// Mean of the rotor points.
    pub centroid: Vec2,
    /// Whether the robots can stand at these candidates (spacing and room for the others).
    pub reachable: bool,
}

/// Number of lifting groups of a scenario (one per candidate: groups wrap around the rail).
pub fn group_count(scenario: &Scenario) -> usize {
    scenario.payload.candidates.len()
}

/// Lifting group `index` of `scenario`; `None` when `index` is not below [`group_count`].
pub fn lift_group(scenario: &Scenario, index: usize) -> Option<LiftGroup> {
    let candidates = &scenario.payload.candidates;
    let rail = &scenario.payload.rail;
    let n = candidates.len();
    let k = scenario.robots.pair_size;
    if index >= n || k == 0 || k > n || k > MAX_ROBOTS {
        return None;
    }
    let members: Vec<usize, MAX_ROBOTS> = (0..k).map(|j| (index + j) % n).collect();
    let rotor_points: Vec<Vec2, MAX_ROBOTS> = members
        .iter()
        .map(|&c| rail.point_at(candidates[c]))
        .collect();
    let centroid = group_centroid(&rotor_points)?;
    let spacing = scenario.robots.min_spacing;
    let gaps_ok = members
        .windows(2)
        .all(|w| rail.forward_gap(candidates[w[0]], candidates[w[1]]) >= spacing - 1e-6);
    let span = rail.forward_gap(candidates[members[0]], candidates[members[k - 1]]);
    let others = scenario.robots.count() - k;
    let room_ok = others == 0 || rail.perimeter() - span >= (others + 1) as f32 * spacing - 1e-6;
    Some(LiftGroup {
        index,
        candidates: members,
        rotor_points,
        centroid,
        reachable: gaps_ok && room_ok,
    })
}

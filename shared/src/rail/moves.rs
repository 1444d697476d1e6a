//! Moves of all robots along the shared rail that keep their cyclic order and `min_spacing`
//! at every instant (docs/models.md#rail-moves: the robots cannot pass each other).
//!
//! All robots move together on one time profile: robot `j` travels `lambda(t) d_j` with the
//! same `lambda` from 0 to 1. The displacements are chosen so that each forward gap changes
//! linearly from its start value to its end value (`d_{j+1} - d_j` = end gap - start gap), so
//! every gap stays between two values that are both at least `min_spacing`: the constraints
//! hold throughout, not only at the ends. What is left free is a common lap offset `d_0`; the one
//! with the least total travel is taken. The robot that travels farthest sets the profile
//! within the speed and acceleration limits.
//!
//! [`lift_targets`] places the robots for one lift: a group of consecutive robots on the
//! group's candidates, the others spread evenly over the rest of the rail, choosing the robots
//! that move least.

use heapless::Vec;

use crate::geometry::Rail;
use crate::math;
use crate::rail::stepper::{MotionLimits, TrapezoidProfile};
use crate::scenario::MAX_ROBOTS;

/// Arc lengths of the robots in rail order.
pub type Positions = Vec<f32, MAX_ROBOTS>;

/// Why a move cannot be made.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum MoveError {
    /// Start and end do not have the same number of robots, or there are none.
    CountMismatch,
    /// The start or the end breaks the order or the spacing.
    Infeasible,
}

impl core::fmt::Display for MoveError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::CountMismatch => write!(f, "start and end must have the same robots"),
            Self::Infeasible => write!(
                f,
                "start or end positions break the robots' order or min_spacing"
            ),
        }
    }
}

impl core::error::Error for MoveError {}

/// A planned move of every robot.
#[derive(Clone, Debug, PartialEq)]
pub struct RailMove {
    start: Positions,
    displacement: Positions,
    profile: TrapezoidProfile,
    lead: f32,
}

fn gaps_hold(rail: &Rail, positions: &[f32], spacing: f32) -> bool {
    crate::formation::search::order_and_spacing_hold(rail, positions, spacing)
}

impl RailMove {
    /// Plans the move from `from` to `to` (robot `j` from `from[j]` to `to[j]`).
    pub fn plan(
        rail: &Rail,
        from: &[f32],
        to: &[f32],
        min_spacing: f32,
        limits: MotionLimits,
    ) -> Result<Self, MoveError> {
        let n = from.len();
        if n == 0 || n != to.len() || n > MAX_ROBOTS {
            return Err(MoveError::CountMismatch);
        }
        let tolerance = min_spacing - 1e-5;
        if !gaps_hold(rail, from, tolerance) || !gaps_hold(rail, to, tolerance) {
            return Err(MoveError::Infeasible);
        }
        let p = rail.perimeter();
        // Offsets of each robot's displacement from robot 0's.
        let mut offset = [0.0f32; MAX_ROBOTS];
        for j in 1..n {
            let start_gap = rail.forward_gap(from[j - 1], from[j]);
            let end_gap = rail.forward_gap(to[j - 1], to[j]);
            offset[j] = offset[j - 1] + (end_gap - start_gap);
        }
        // d_0 is fixed up to whole laps; take the lap with the least total travel.
        let base = rail.forward_gap(from[0], to[0]);
        let travel = |d0: f32| (0..n).map(|j| math::abs(d0 + offset[j])).sum::<f32>();
        let mut best = (f32::INFINITY, 0.0);
        for lap in -2..=1 {
            let d0 = base + lap as f32 * p;
            let t = travel(d0);
            if t < best.0 {
                best = (t, d0);
            }
        }
        let d0 = best.1;
        let displacement: Positions = (0..n).map(|j| d0 + offset[j]).collect();
        let lead = displacement
            .iter()
            .fold(0.0f32, |m, &d| math::max(m, math::abs(d)));
        Ok(Self {
            start: Vec::from_slice(from).unwrap_or_default(),
            displacement,
            profile: TrapezoidProfile::new(lead, limits),
            lead,
        })
    }

    /// Duration, s.
    pub fn duration(&self) -> f32 {
        self.profile.duration()
    }

    /// Total arc length travelled by all robots, m.
    pub fn total_travel(&self) -> f32 {
        self.displacement.iter().map(|&d| math::abs(d)).sum()
    }

    /// Signed travel of each robot (positive: forward along the rail), m.
    pub fn displacements(&self) -> &[f32] {
        &self.displacement
    }

    /// Where every robot is at time `t` into the move.
    pub fn positions_at(&self, rail: &Rail, t: f32) -> Positions {
        let lambda = if self.lead > 0.0 {
            self.profile.position(t) / self.lead
        } else {
            1.0
        };
        self.start
            .iter()
            .zip(self.displacement.iter())
            .map(|(&s, &d)| rail.wrap(s + lambda * d))
            .collect()
    }
}

/// Targets for a lift: consecutive robots on `group` (arc lengths in rail order, e.g. the two
/// candidates of a pair), the rest evenly spread over the remaining arc, choosing the robots
/// that make the least total travel from `current`. `None` when the group does not fit.
pub fn lift_targets(
    rail: &Rail,
    current: &[f32],
    group: &[f32],
    min_spacing: f32,
) -> Option<Positions> {
    let n = current.len();
    let k = group.len();
    if k == 0 || k > n || n > MAX_ROBOTS {
        return None;
    }
    let p = rail.perimeter();
    let span = rail.forward_gap(group[0], group[k - 1]);
    let others = n - k;
    let rest = p - span;
    let gap = rest / (others + 1) as f32;
    if gap < min_spacing {
        return None;
    }
    let mut best: Option<(f32, Positions)> = None;
    for first in 0..n {
        // Robots first, first+1, ... take the group; the following ones fill the rest.
        let mut target = [0.0f32; MAX_ROBOTS];
        for m in 0..k {
            target[(first + m) % n] = group[m];
        }
        for m in 0..others {
            target[(first + k + m) % n] = rail.wrap(group[k - 1] + gap * (m + 1) as f32);
        }
        let target = &target[..n];
        let Ok(mv) = RailMove::plan(rail, current, target, min_spacing, MotionLimits::default())
        else {
            continue;
        };
        let travel = mv.total_travel();
        if best.as_ref().is_none_or(|(b, _)| travel < *b) {
            best = Some((travel, Vec::from_slice(target).unwrap_or_default()));
        }
    }
    best.map(|(_, t)| t)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::paper::{checked, rect_sim1};
    use proptest::prelude::*;

    fn min_gap(rail: &Rail, positions: &[f32]) -> f32 {
        crate::formation::objective::min_gap(rail, positions)
    }

    #[test]
    fn a_rotation_of_the_whole_formation_moves_everyone_the_short_way() {
        let s = checked(rect_sim1());
        let rail = &s.payload.rail;
        let from = &s.robots.initial;
        let to: Positions = from.iter().map(|&x| rail.wrap(x - 0.3)).collect();
        let mv = RailMove::plan(rail, from, &to, 0.25, MotionLimits::default()).unwrap();
        assert!(
            mv.displacements().iter().all(|&d| (d + 0.3).abs() < 1e-4),
            "{mv:?}"
        );
        assert!((mv.total_travel() - 8.0 * 0.3).abs() < 1e-3);
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(64))]
        #[test]
        fn spacing_and_order_hold_at_every_instant(
            shift in -3.0f32..3.0,
            first in 0usize..12,
        ) {
            let s = checked(rect_sim1());
            let rail = &s.payload.rail;
            let from: Positions = s.robots.initial.iter().map(|&x| rail.wrap(x + shift)).collect();
            let c = &s.payload.candidates;
            let group = [c[first], c[(first + 1) % c.len()]];
            let to = lift_targets(rail, &from, &group, 0.25).expect("a pair fits on the rectangle");
            let mv = RailMove::plan(rail, &from, &to, 0.25, MotionLimits::default()).unwrap();
            let steps = 200;
            for i in 0..=steps {
                let t = mv.duration() * i as f32 / steps as f32;
                let at = mv.positions_at(rail, t);
                prop_assert!(gaps_hold(rail, &at, 0.25 - 1e-4), "t = {}: {:?}", t, at);
            }
            let end = mv.positions_at(rail, mv.duration() + 1.0);
            for (a, b) in end.iter().zip(to.iter()) {
                prop_assert!(rail.forward_gap(*a, *b).min(rail.forward_gap(*b, *a)) < 1e-3);
            }
            // The group's robots stand on the candidates.
            prop_assert!(to.iter().any(|&x| (x - group[0]).abs() < 1e-5));
            prop_assert!(to.iter().any(|&x| (x - group[1]).abs() < 1e-5));
            prop_assert!(min_gap(rail, &to) >= 0.25 - 1e-5);
        }
    }

    #[test]
    fn a_group_too_long_for_the_rail_has_no_targets() {
        let s = checked(rect_sim1());
        let rail = &s.payload.rail;
        // Span 4.5 m of a 4.88 m rail leaves no room for six more robots.
        assert_eq!(
            lift_targets(rail, &s.robots.initial, &[0.0, 4.5], 0.25),
            None
        );
        let crowded = [0.0, 0.1];
        assert_eq!(
            RailMove::plan(rail, &crowded, &crowded, 0.25, MotionLimits::default()),
            Err(MoveError::Infeasible)
        );
    }
}

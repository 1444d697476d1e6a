//! Where a robot can move from a rail point, and the order and spacing check
//! (docs/models.md#formation-search): robots keep their cyclic order and `min_spacing` on the
//! closed rail.

use crate::geometry::{Rail, Vec2};

/// A robot this close to a rail vertex (m) is taken to stand on it.
const VERTEX_TOLERANCE: f32 = 1e-5;
/// Extra spacing kept beyond `min_spacing` (m), so rounding never breaks the constraint.
pub const SPACING_MARGIN: f32 = 2e-5;

/// How a robot can move from where it stands in one direction along the rail.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Side {
    /// Unit direction of motion in the plane when the arc length grows (forward side) or the
    /// rail's direction of the segment behind (backward side).
    pub tangent: Vec2,
    /// Arc length it can travel on that segment before the next vertex, m.
    pub reach: f32,
}

/// The forward and backward sides of arc length `s`.
pub fn sides(rail: &Rail, s: f32) -> (Side, Side) {
    let n = rail.segment_count();
    let s = rail.wrap(s);
    let k = rail.segment_at(s);
    let (start, end) = rail.segment_span(k);
    let length = |i: usize| {
        let (a, b) = rail.segment_span(i);
        b - a
    };
    let (prev, next) = ((k + n - 1) % n, (k + 1) % n);
    let here = rail.segment_direction(k);
    if end - s < VERTEX_TOLERANCE {
        (
            Side {
                tangent: rail.segment_direction(next),
                reach: length(next) + (end - s),
            },
            Side {
                tangent: here,
                reach: s - start,
            },
        )
    } else if s - start < VERTEX_TOLERANCE {
        (
            Side {
                tangent: here,
                reach: end - s,
            },
            Side {
                tangent: rail.segment_direction(prev),
                reach: length(prev) + (s - start),
            },
        )
    } else {
        (
            Side {
                tangent: here,
                reach: end - s,
            },
            Side {
                tangent: here,
                reach: s - start,
            },
        )
    }
}

/// True when robots at `positions` keep their cyclic order (forward gaps add up to one lap)
/// and every forward gap is at least `spacing`.
pub fn order_and_spacing_hold(rail: &Rail, positions: &[f32], spacing: f32) -> bool {
    let n = positions.len();
    if n < 2 {
        return true;
    }
    let mut total = 0.0;
    for j in 0..n {
        let gap = rail.forward_gap(positions[j], positions[(j + 1) % n]);
        if gap < spacing {
            return false;
        }
        total += gap;
    }
    (total - rail.perimeter()).abs() < 1e-3
}

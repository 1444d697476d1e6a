//! Segment assignments: which straight rail segment each robot stands on
//! (docs/models.md#formation-search).
//!
//! Robots keep their cyclic order, so an assignment is a count of robots per segment (in rail
//! order, each at most what the segment holds at `min_spacing`) and the robot that comes first.
//! Two first robots whose spin sequences agree, or are each other's negative (alternating
//! spins: every shift), give the same problem, so only the first `period` are tried. On a fixed assignment every robot
//! moves along one straight segment: its point is affine in its arc length, the balance sums
//! are linear and `det(S)` is a quartic polynomial (see [`crate::formation::face`]).

use crate::geometry::{MAX_VERTICES, Rail, Vec2};
use crate::scenario::MAX_ROBOTS;

/// One assignment: robots per segment and the robot placed first.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Assignment {
    /// Robots on each segment, in rail order.
    pub counts: [u8; MAX_VERTICES],
    /// The robot (index in the caller's order) that is first on the first occupied segment.
    pub first: u8,
}

/// Enumerates the assignments of `n` robots to a rail's segments, in a fixed order, with no
/// storage beyond the current one.
#[derive(Clone, Debug)]
pub struct Assignments {
    segments: usize,
    robots: usize,
    capacity: [u8; MAX_VERTICES],
    /// Robots the segments from index `i` on can hold together.
    room_from: [u16; MAX_VERTICES + 1],
    period: u8,
    current: Option<Assignment>,
    started: bool,
}

/// Robots a segment of `length` holds at `spacing` (both ends included).
pub fn segment_capacity(length: f32, spacing: f32) -> u8 {
    let fit = crate::math::floor(length / spacing + 1e-4) as i32 + 1;
    fit.clamp(0, MAX_ROBOTS as i32) as u8
}

/// The smallest shift `p` (dividing the count) that maps the spin sequence onto itself or onto
/// its negative (`spin[j + p] == spin[j]` for every robot, or `== -spin[j]` for every robot).
/// `det(B B^T)` does not change when every spin flips (the third row of `B` changes sign), so
/// formations that differ by such a shift are equally good.
pub fn spin_period(spin: &[i8]) -> usize {
    let n = spin.len();
    let maps = |p: usize, sign: i8| (0..n).all(|j| spin[(j + p) % n] == sign * spin[j]);
    (1..=n)
        .find(|&p| n % p == 0 && (maps(p, 1) || maps(p, -1)))
        .unwrap_or(n)
}

impl Assignments {
    /// All assignments of the robots with spins `spin` to `rail` at `spacing`.
    pub fn new(rail: &Rail, spin: &[i8], spacing: f32) -> Self {
        let segments = rail.segment_count().min(MAX_VERTICES);
        let mut capacity = [0u8; MAX_VERTICES];
        for (s, c) in capacity.iter_mut().enumerate().take(segments) {
            let (a, b) = rail.segment_span(s);
            *c = segment_capacity(b - a, spacing);
        }
        let mut room_from = [0u16; MAX_VERTICES + 1];
        for s in (0..segments).rev() {
            room_from[s] = room_from[s + 1] + u16::from(capacity[s]);
        }
        Self {
            segments,
            robots: spin.len().min(MAX_ROBOTS),
            capacity,
            room_from,
            period: spin_period(spin) as u8,
            current: None,
            started: false,
        }
    }

    /// Fills segments `from..` with `remaining` robots, as few as possible on early segments.
    /// Returns false when they do not fit.
    fn fill_from(&self, counts: &mut [u8; MAX_VERTICES], from: usize, remaining: u16) -> bool {
        if remaining > self.room_from[from] {
            return false;
        }
        let mut left = remaining;
        for (count, &later) in counts[from..self.segments]
            .iter_mut()
            .zip(&self.room_from[from + 1..])
        {
            let here = left.saturating_sub(later);
            *count = here as u8;
            left -= here;
        }
        left == 0
    }

    /// The next count vector after `counts` in lexicographic order, if any.
    fn next_counts(&self, counts: &mut [u8; MAX_VERTICES]) -> bool {
        let mut prefix = [0u16; MAX_VERTICES + 1];
        for s in 0..self.segments {
            prefix[s + 1] = prefix[s] + u16::from(counts[s]);
        }
        for s in (0..self.segments.saturating_sub(1)).rev() {
            let placed = prefix[s] + u16::from(counts[s]) + 1;
            if counts[s] < self.capacity[s] && placed <= self.robots as u16 {
                let remaining = self.robots as u16 - placed;
                if remaining <= self.room_from[s + 1] {
                    counts[s] += 1;
                    return self.fill_from(counts, s + 1, remaining);
                }
            }
        }
        false
    }
}

impl Iterator for Assignments {
    type Item = Assignment;

    fn next(&mut self) -> Option<Assignment> {
        if !self.started {
            self.started = true;
            let mut counts = [0u8; MAX_VERTICES];
            if self.segments == 0 || !self.fill_from(&mut counts, 0, self.robots as u16) {
                return None;
            }
            self.current = Some(Assignment { counts, first: 0 });
            return self.current;
        }
        let mut a = self.current?;
        if a.first + 1 < self.period {
            a.first += 1;
        } else if self.next_counts(&mut a.counts) {
            a.first = 0;
        } else {
            self.current = None;
            return None;
        }
        self.current = Some(a);
        self.current
    }
}

/// One assignment's smooth problem, unrolled along the rail: sequence index `i` is robot
/// `robot[i]`, at arc length `x_i` (from the rail's first vertex, increasing with `i`, within
/// `[lo_i, hi_i]`, the ends of its segment), at point `base_i + tangent_i * x_i` relative to
/// the COM. Neighbours keep `x_{i+1} - x_i >= spacing`, and the last and first robots
/// `x_0 + perimeter - x_{n-1} >= spacing`.
#[derive(Clone, Debug)]
pub struct Layout {
    /// Robots.
    pub n: usize,
    /// Robot (caller's index) at each sequence index.
    pub robot: [u8; MAX_ROBOTS],
    /// Spin of each sequence index, as +-1.0.
    pub spin: [f32; MAX_ROBOTS],
    /// Unit direction of its segment.
    pub tangent: [Vec2; MAX_ROBOTS],
    /// Point (relative to the COM) the affine map starts from.
    pub base: [Vec2; MAX_ROBOTS],
    /// Start of its segment (arc length).
    pub lo: [f32; MAX_ROBOTS],
    /// End of its segment (arc length).
    pub hi: [f32; MAX_ROBOTS],
    /// Tightest range each robot can reach with the spacing of its neighbours.
    pub reach: [(f32, f32); MAX_ROBOTS],
    /// Smallest gap kept, m.
    pub spacing: f32,
    /// Rail length, m.
    pub perimeter: f32,
}

impl Layout {
    /// The problem of `assignment` on `rail` about `com`, or `None` when the robots cannot
    /// stand on those segments at `spacing`.
    pub fn new(
        rail: &Rail,
        spin: &[i8],
        com: Vec2,
        spacing: f32,
        assignment: &Assignment,
    ) -> Option<Self> {
        let n = spin.len().min(MAX_ROBOTS);
        let mut layout = Self {
            n,
            robot: [0; MAX_ROBOTS],
            spin: [0.0; MAX_ROBOTS],
            tangent: [Vec2::default(); MAX_ROBOTS],
            base: [Vec2::default(); MAX_ROBOTS],
            lo: [0.0; MAX_ROBOTS],
            hi: [0.0; MAX_ROBOTS],
            reach: [(0.0, 0.0); MAX_ROBOTS],
            spacing,
            perimeter: rail.perimeter(),
        };
        let mut i = 0;
        for s in 0..rail.segment_count().min(MAX_VERTICES) {
            let (start, end) = rail.segment_span(s);
            let t = rail.segment_direction(s);
            let origin = rail.vertices()[s] - com - t * start;
            for _ in 0..assignment.counts[s] {
                if i >= n {
                    return None;
                }
                let robot = (usize::from(assignment.first) + i) % n;
                layout.robot[i] = robot as u8;
                layout.spin[i] = f32::from(spin[robot]);
                layout.tangent[i] = t;
                layout.base[i] = origin;
                layout.lo[i] = start;
                layout.hi[i] = end;
                i += 1;
            }
        }
        if i != n {
            return None;
        }
        // Reachable ranges: forward passes of the spacing for the lower ends, backward passes
        // for the upper ends. The closed rail also ties the last robot to the first
        // (`x_0 + perimeter - x_{n-1} >= spacing`): a second lap carries that gap round, after
        // which the ranges are exact (a lap adds `n spacing - perimeter <= 0`, so a third
        // changes nothing). Then the robots all at the lower ends (or all at the upper ends,
        // or any mix of the two) stand apart, and every start of the face solver is feasible.
        for i in 0..n {
            layout.reach[i].0 = if i == 0 {
                layout.lo[0]
            } else {
                layout.lo[i].max(layout.reach[i - 1].0 + spacing)
            };
        }
        for i in (0..n).rev() {
            layout.reach[i].1 = if i + 1 == n {
                layout.hi[i]
            } else {
                layout.hi[i].min(layout.reach[i + 1].1 - spacing)
            };
        }
        if n >= 2 {
            let wrap = layout.perimeter - spacing;
            layout.reach[0].0 = layout.reach[0].0.max(layout.reach[n - 1].0 - wrap);
            for i in 1..n {
                layout.reach[i].0 = layout.reach[i].0.max(layout.reach[i - 1].0 + spacing);
            }
            layout.reach[n - 1].1 = layout.reach[n - 1].1.min(layout.reach[0].1 + wrap);
            for i in (0..n - 1).rev() {
                layout.reach[i].1 = layout.reach[i].1.min(layout.reach[i + 1].1 - spacing);
            }
        }
        let wraps =
            n < 2 || layout.reach[n - 1].0 - layout.reach[0].1 <= layout.perimeter - spacing;
        let fits = (0..n).all(|i| layout.reach[i].0 <= layout.reach[i].1);
        (fits && wraps).then_some(layout)
    }

    /// The point of sequence index `i` at arc length `x`, relative to the COM.
    pub fn point(&self, i: usize, x: f32) -> Vec2 {
        self.base[i] + self.tangent[i] * x
    }
}

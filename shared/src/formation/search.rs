//! Local search of the formation: moves of two or three robots along the rail that keep both
//! balance sums fixed, each with an exact line search (SPEC.md section 2, step 2).
//!
//! Along a straight rail segment a robot's position is linear in its arc length, so for a move
//! `ds = alpha * d` that keeps every moving robot on its segments, each entry of the Schur
//! matrix `S` (see [`crate::formation::objective`]) is a quadratic in `alpha` and `det(S)` a
//! quartic: its maximum on the allowed interval is found exactly from the roots of the cubic
//! derivative. The interval ends where a robot reaches a rail vertex or two neighbours reach
//! `min_spacing`; the next move then starts from the vertex with the next segment's direction.
//!
//! Directions that keep `sum b1` and `sum b2` fixed: for three robots with rail directions
//! `t_i, t_j, t_k`, `d = (t_j x t_k, t_k x t_i, t_i x t_j)` (the null space of `[t_i t_j t_k]`);
//! for two robots on parallel segments, `d = (1, -t_i . t_j)`. At a vertex a robot has two
//! directions (forward and backward); every consistent combination is tried.

use crate::formation::objective::Moments;
use crate::geometry::{Rail, Vec2};
use crate::scenario::MAX_ROBOTS;

/// A robot this close to a rail vertex (m) is taken to stand on it.
const VERTEX_TOLERANCE: f32 = 1e-5;
/// Extra spacing kept beyond `min_spacing` (m), so rounding never breaks the constraint.
pub const SPACING_MARGIN: f32 = 2e-5;
/// Relative gain below which a move is not worth making.
const MIN_RELATIVE_GAIN: f32 = 1e-6;
/// Sign changes of the derivative are looked for on this many sub-intervals.
const ROOT_SAMPLES: usize = 24;

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

/// Robots, rail and spins of one search.
#[derive(Clone, Copy, Debug)]
pub struct SearchSpace<'a> {
    /// The rail.
    pub rail: &'a Rail,
    /// Spin of each robot.
    pub spin: &'a [i8],
    /// The COM (origin of `B`).
    pub com: Vec2,
    /// Smallest arc length between neighbours, m.
    pub min_spacing: f32,
}

/// A move under consideration: up to three robots and their rates.
#[derive(Clone, Copy, Debug)]
struct Move {
    robots: [usize; 3],
    rates: [f32; 3],
    tangents: [Vec2; 3],
    reach: [f32; 3],
    count: usize,
}

impl SearchSpace<'_> {
    fn points(&self, positions: &[f32], out: &mut [Vec2; MAX_ROBOTS]) {
        for (p, &s) in out.iter_mut().zip(positions) {
            *p = self.rail.point_at(s);
        }
    }

    /// Largest `alpha >= 0` the move may take.
    fn step_limit(&self, positions: &[f32], mv: &Move) -> f32 {
        let n = positions.len();
        let mut rate = [0.0f32; MAX_ROBOTS];
        let mut limit = f32::INFINITY;
        for m in 0..mv.count {
            rate[mv.robots[m]] = mv.rates[m];
            if mv.rates[m] != 0.0 {
                limit = limit.min(mv.reach[m] / mv.rates[m].abs());
            }
        }
        for j in 0..n {
            let next = (j + 1) % n;
            let closing = rate[j] - rate[next];
            if closing > 0.0 {
                let gap = self.rail.forward_gap(positions[j], positions[next]);
                let room = gap - self.min_spacing - SPACING_MARGIN;
                limit = limit.min((room / closing).max(0.0));
            }
        }
        limit
    }

    /// Best `alpha` in `[0, limit]` for the move and the predicted `det(S)` there.
    fn line_search(&self, points: &[Vec2], moments: &Moments, mv: &Move, limit: f32) -> (f32, f32) {
        let n = moments.n;
        let (mut sa, mut sb) = (0.0f32, 0.0f32); // sum spin * a, sum spin * b
        let (mut xa, mut yb, mut cross) = (0.0f32, 0.0f32, 0.0f32);
        let (mut aa, mut bb, mut ab) = (0.0f32, 0.0f32, 0.0f32);
        for m in 0..mv.count {
            let j = mv.robots[m];
            let r = points[j] - self.com;
            let a = mv.rates[m] * mv.tangents[m].x;
            let b = mv.rates[m] * mv.tangents[m].y;
            let spin = f32::from(self.spin[j]);
            sa += spin * a;
            sb += spin * b;
            xa += r.x * a;
            yb += r.y * b;
            cross += r.x * b + r.y * a;
            aa += a * a;
            bb += b * b;
            ab += a * b;
        }
        let c = [
            moments.sxx - moments.vx * moments.vx / n,
            2.0 * xa - 2.0 * moments.vx * sa / n,
            aa - sa * sa / n,
        ];
        let d = [
            moments.syy - moments.vy * moments.vy / n,
            2.0 * yb - 2.0 * moments.vy * sb / n,
            bb - sb * sb / n,
        ];
        let e = [
            moments.sxy - moments.vx * moments.vy / n,
            cross - (moments.vx * sb + moments.vy * sa) / n,
            ab - sa * sb / n,
        ];
        let p = [
            c[0] * d[0] - e[0] * e[0],
            c[0] * d[1] + c[1] * d[0] - 2.0 * e[0] * e[1],
            c[0] * d[2] + c[1] * d[1] + c[2] * d[0] - e[1] * e[1] - 2.0 * e[0] * e[2],
            c[1] * d[2] + c[2] * d[1] - 2.0 * e[1] * e[2],
            c[2] * d[2] - e[2] * e[2],
        ];
        let value = |x: f32| p[0] + x * (p[1] + x * (p[2] + x * (p[3] + x * p[4])));
        let slope = |x: f32| p[1] + x * (2.0 * p[2] + x * (3.0 * p[3] + x * 4.0 * p[4]));
        let mut best = (0.0, value(0.0));
        let mut consider = |x: f32| {
            let v = value(x);
            if v > best.1 {
                best = (x, v);
            }
        };
        consider(limit);
        let mut lo = 0.0f32;
        let mut slope_lo = slope(lo);
        for i in 1..=ROOT_SAMPLES {
            let hi = limit * i as f32 / ROOT_SAMPLES as f32;
            let slope_hi = slope(hi);
            if slope_lo > 0.0 && slope_hi <= 0.0 {
                // A maximum of the quartic lies in [lo, hi]: bisect the derivative.
                let (mut a, mut b) = (lo, hi);
                for _ in 0..40 {
                    let mid = 0.5 * (a + b);
                    if slope(mid) > 0.0 { a = mid } else { b = mid }
                }
                consider(0.5 * (a + b));
            }
            lo = hi;
            slope_lo = slope_hi;
        }
        best
    }

    /// Tries `mv`; applies it when it gains. Returns whether it did.
    fn try_move(
        &self,
        positions: &mut [f32],
        points: &mut [Vec2; MAX_ROBOTS],
        moments: &mut Moments,
        mv: &Move,
    ) -> bool {
        let limit = self.step_limit(positions, mv);
        if limit.is_nan() || limit <= 0.0 {
            return false;
        }
        let current = moments.schur_det();
        let (alpha, predicted) = self.line_search(&points[..positions.len()], moments, mv, limit);
        if alpha <= 0.0 || predicted <= current + MIN_RELATIVE_GAIN * current.abs().max(1e-9) {
            return false;
        }
        for m in 0..mv.count {
            let j = mv.robots[m];
            positions[j] = self.rail.wrap(positions[j] + alpha * mv.rates[m]);
        }
        self.points(positions, points);
        *moments = Moments::of(&points[..positions.len()], self.com, self.spin);
        true
    }

    /// Sweeps over all pairs and triples of robots, applying every improving move, until a
    /// sweep gains nothing or `max_sweeps` sweeps are done. Returns the sweeps made.
    pub fn climb(&self, positions: &mut [f32], max_sweeps: u32) -> u32 {
        let n = positions.len().min(MAX_ROBOTS);
        let positions = &mut positions[..n];
        let mut points = [Vec2::default(); MAX_ROBOTS];
        self.points(positions, &mut points);
        let mut moments = Moments::of(&points[..n], self.com, self.spin);
        for sweep in 0..max_sweeps {
            let mut improved = false;
            for i in 0..n {
                for j in (i + 1)..n {
                    for mv in self.pair_moves(positions, i, j) {
                        improved |= self.try_move(positions, &mut points, &mut moments, &mv);
                    }
                    for k in (j + 1)..n {
                        for combo in 0..8u8 {
                            for sign in [1.0f32, -1.0] {
                                if let Some(mv) =
                                    self.triple_move(positions, [i, j, k], combo, sign)
                                {
                                    improved |=
                                        self.try_move(positions, &mut points, &mut moments, &mv);
                                }
                            }
                        }
                    }
                }
            }
            if !improved {
                return sweep + 1;
            }
        }
        max_sweeps
    }

    fn side(&self, s: f32, backward: bool) -> Side {
        let (forward, back) = sides(self.rail, s);
        if backward { back } else { forward }
    }

    /// A move's rates are consistent with the sides chosen: forward sides move forward.
    fn consistent(rates: &[f32], backward: &[bool]) -> bool {
        rates
            .iter()
            .zip(backward)
            .all(|(&r, &b)| if b { r <= 0.0 } else { r >= 0.0 })
    }

    fn triple_move(
        &self,
        positions: &[f32],
        robots: [usize; 3],
        combo: u8,
        sign: f32,
    ) -> Option<Move> {
        let backward = [combo & 1 != 0, combo & 2 != 0, combo & 4 != 0];
        let sides = [0, 1, 2].map(|m| self.side(positions[robots[m]], backward[m]));
        let t = sides.map(|s| s.tangent);
        let d = [t[1].cross(t[2]), t[2].cross(t[0]), t[0].cross(t[1])];
        let scale = d.iter().fold(0.0f32, |a, v| a.max(v.abs()));
        if scale < 1e-6 {
            return None;
        }
        let rates = d.map(|v| sign * v / scale);
        Self::consistent(&rates, &backward).then_some(Move {
            robots,
            rates,
            tangents: t,
            reach: sides.map(|s| s.reach),
            count: 3,
        })
    }

    fn pair_moves(&self, positions: &[f32], i: usize, j: usize) -> heapless::Vec<Move, 8> {
        let mut out = heapless::Vec::new();
        for combo in 0..4u8 {
            let backward = [combo & 1 != 0, combo & 2 != 0];
            let si = self.side(positions[i], backward[0]);
            let sj = self.side(positions[j], backward[1]);
            if si.tangent.cross(sj.tangent).abs() > 1e-6 {
                continue; // not parallel: two robots alone cannot keep the centroid
            }
            for sign in [1.0f32, -1.0] {
                let rates = [sign, -sign * si.tangent.dot(sj.tangent), 0.0];
                if Self::consistent(&rates[..2], &backward) {
                    let _ = out.push(Move {
                        robots: [i, j, j],
                        rates,
                        tangents: [si.tangent, sj.tangent, Vec2::default()],
                        reach: [si.reach, sj.reach, 0.0],
                        count: 2,
                    });
                }
            }
        }
        out
    }
}

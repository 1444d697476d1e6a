//! Climbing from one vertex of an assignment's polytope to a better neighbour
//! (docs/models.md#formation-search): from a local maximum of `det(S)`, each active
//! constraint released opens an edge along which both balance sums hold; the edge is probed
//! with the face's exact line search of `det(S)` up to the next constraint it meets, and the
//! best one that ends higher is followed ([`Face::climb_edge`]). The solver climbs so from the
//! best start of each assignment.

use super::{Blocks, Constraint, Face, N, Pin, Sym, quartic_argmax};
use crate::geometry::Vec2;

/// Relative gain in `det(S)` an edge probe must reach to be followed (above rounding).
const EDGE_GAIN: f32 = 1e-5;

/// An edge a probe found worth following.
#[derive(Clone, Copy, Debug)]
struct Edge {
    /// The active constraint released.
    released: Constraint,
    /// Robot velocities along the edge.
    dx: [f32; N],
    /// How far along it the line search goes.
    alpha: f32,
    /// Where it meets the next constraint, `hit`.
    limit: f32,
    hit: Option<Constraint>,
}

impl Face<'_> {
    /// From a local maximum of `det(S)` (the end of a [`Goal::Det`](super::Goal::Det) solve):
    /// probes the edge that releasing each active constraint opens, by the exact line search of
    /// `det(S)` up to the first constraint the edge meets, and moves along the best one if it
    /// ends at least [`EDGE_GAIN`] above the current value (then solve for
    /// [`Goal::Det`](super::Goal::Det) again). Returns whether it moved. `O(n)` per active
    /// constraint, no Newton step.
    pub fn climb_edge(&mut self) -> bool {
        let l = self.layout;
        let n = l.n;
        if n < 2 || self.tight[..n].iter().all(|&t| t) {
            // One rigid ring: no edge to open.
            return false;
        }
        let st = self.state();
        let value = st.s.det();
        let blocks = self.blocks();
        // Per block: the sum of its tangents and its pinned members; per robot: its place in
        // its block; `gram`: `T T^T` over the free blocks.
        let mut t_blk = [Vec2::default(); N];
        let mut pins = [0u8; N];
        let mut place = [0u8; N];
        let mut gram = Sym::default();
        for blk in 0..blocks.count {
            let from = usize::from(blocks.start[blk]);
            let to = usize::from(blocks.start[blk + 1]);
            for (p, &i) in blocks.order[from..to].iter().enumerate() {
                let i = usize::from(i);
                t_blk[blk] = t_blk[blk] + l.tangent[i];
                pins[blk] += u8::from(self.pin[i] != Pin::Free);
                place[i] = p as u8;
            }
            if blocks.free_index[blk] != u8::MAX {
                gram = gram.add(Sym::square(t_blk[blk]));
            }
        }
        let mut target = value + EDGE_GAIN * value.abs().max(1e-12);
        let mut best: Option<Edge> = None;
        for slot in 0..2 * n {
            let Some((c, blk, moving, sign)) = self.edge_of(slot, &blocks, &pins, &place) else {
                continue;
            };
            let Some(dx) = self.edge_velocities(&blocks, &t_blk, gram, blk, moving, sign) else {
                continue;
            };
            self.remove(c);
            let (limit, hit) = self.step_limit(&dx);
            self.add(c);
            if limit.is_nan() || limit <= 0.0 {
                continue;
            }
            let alpha = quartic_argmax(&st, l, &dx, limit);
            if alpha.is_nan() || alpha <= 0.0 {
                continue;
            }
            let reached = self.det_along(&dx, alpha);
            if reached > target {
                target = reached;
                best = Some(Edge {
                    released: c,
                    dx,
                    alpha,
                    limit,
                    hit,
                });
            }
        }
        let Some(Edge {
            released: c,
            dx,
            alpha,
            limit,
            hit,
        }) = best
        else {
            return false;
        };
        self.remove(c);
        for (x, &d) in self.x.iter_mut().zip(&dx).take(n) {
            *x += alpha * d;
        }
        if alpha >= limit {
            if let Some(h) = hit {
                self.add(h);
            }
        }
        true
    }

    /// The edge that releasing the constraint of `slot` (gap `slot`, or robot `slot - n`'s
    /// bound) opens, if it is active and releasing it lets robots move: the constraint, its
    /// block, the places in that block of the members that start to move, and their velocity
    /// relative to the rest of the block. `pins` counts each block's pinned members, `place`
    /// is each robot's place in its block.
    fn edge_of(
        &self,
        slot: usize,
        blocks: &Blocks,
        pins: &[u8; N],
        place: &[u8; N],
    ) -> Option<(Constraint, usize, core::ops::Range<usize>, f32)> {
        let n = self.layout.n;
        if slot < n {
            if !self.tight[slot] {
                return None;
            }
            let blk = usize::from(blocks.block_of[slot]);
            let from = usize::from(blocks.start[blk]);
            let len = usize::from(blocks.start[blk + 1]) - from;
            let cut = usize::from(place[slot]) + 1;
            let before = blocks.order[from..from + cut]
                .iter()
                .filter(|&&i| self.pin[usize::from(i)] != Pin::Free)
                .count() as u8;
            // The part after the gap moves forward, unless it holds the pin (then the part
            // before moves back); of a free block, both parts move.
            let (moving, sign) = match (before > 0, pins[blk] > before) {
                (true, true) => return None,
                (false, true) => (0..cut, -1.0),
                _ => (cut..len, 1.0),
            };
            Some((Constraint::Gap(slot), blk, moving, sign))
        } else {
            let i = slot - n;
            let blk = usize::from(blocks.block_of[i]);
            if self.pin[i] == Pin::Free || pins[blk] != 1 {
                return None;
            }
            let sign = if self.pin[i] == Pin::Low { 1.0 } else { -1.0 };
            let len = usize::from(blocks.start[blk + 1] - blocks.start[blk]);
            Some((Constraint::Bound(i, self.pin[i]), blk, 0..len, sign))
        }
    }

    /// Robot velocities along an edge: the members of block `blk` at places `moving` start to
    /// move at `sign` relative to the rest of the block (which, in a free block, moves at
    /// `-sign`), and every free block moves by least squares so that both balance sums hold
    /// (`d = g - T^T (T T^T)^-1 T g` on the block shifts). `None` when the balance leaves the
    /// edge no room.
    fn edge_velocities(
        &self,
        blocks: &Blocks,
        t_blk: &[Vec2; N],
        gram: Sym,
        blk: usize,
        moving: core::ops::Range<usize>,
        sign: f32,
    ) -> Option<[f32; N]> {
        let l = self.layout;
        let from = usize::from(blocks.start[blk]);
        let to = usize::from(blocks.start[blk + 1]);
        let moving = |p: usize| moving.contains(&p);
        let mut t_move = Vec2::default();
        for (p, &i) in blocks.order[from..to].iter().enumerate() {
            if moving(p) {
                t_move = t_move + l.tangent[usize::from(i)];
            }
        }
        // The rest of a free block stays a variable of its own, moving at `-sign`.
        let was_free = blocks.free_index[blk] != u8::MAX;
        let t_rest = if was_free {
            t_blk[blk] - t_move
        } else {
            Vec2::default()
        };
        let mut m = gram.add(Sym::square(t_move)).add(Sym::square(t_rest));
        if was_free {
            m = m.add(Sym::square(t_blk[blk]).scale(-1.0));
        }
        let w = (t_move - t_rest) * sign;
        let damping = 1e-6 * (m.a + m.c) + 1e-20;
        let (a, c) = (m.a + damping, m.c + damping);
        let det = a * c - m.b * m.b;
        if det.is_nan() || det <= 0.0 {
            return None;
        }
        let lambda = Vec2::new((c * w.x - m.b * w.y) / det, (a * w.y - m.b * w.x) / det);
        let (v_move, v_rest) = (sign - t_move.dot(lambda), -sign - t_rest.dot(lambda));
        let mut room = v_move * v_move;
        if was_free {
            room += v_rest * v_rest;
        }
        let mut dx = [0.0f32; N];
        for (b, &t) in t_blk.iter().enumerate().take(blocks.count) {
            let members =
                &blocks.order[usize::from(blocks.start[b])..usize::from(blocks.start[b + 1])];
            if b == blk {
                for (p, &i) in members.iter().enumerate() {
                    dx[usize::from(i)] = if moving(p) {
                        v_move
                    } else if was_free {
                        v_rest
                    } else {
                        0.0
                    };
                }
            } else if blocks.free_index[b] != u8::MAX {
                let v = -t.dot(lambda);
                room += v * v;
                for &i in members {
                    dx[usize::from(i)] = v;
                }
            }
        }
        let size = if was_free { 2.0 } else { 1.0 };
        (room > 1e-6 * size).then_some(dx)
    }

    /// `det(S)` at `x + alpha dx`.
    fn det_along(&self, dx: &[f32; N], alpha: f32) -> f32 {
        let l = self.layout;
        let mut m = Sym::default();
        let mut v = Vec2::default();
        for (i, (&x, &d)) in self.x.iter().zip(dx).enumerate().take(l.n) {
            let r = l.point(i, x + alpha * d);
            m = m.add(Sym::square(r));
            v = v + r * l.spin[i];
        }
        m.add(Sym::square(v).scale(-1.0 / l.n as f32)).det()
    }
}

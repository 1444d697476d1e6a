//! The smooth problem of one segment assignment, solved by an active-set Newton method
//! (docs/models.md#formation-search).
//!
//! On a fixed assignment ([`crate::formation::assignment::Layout`]) robot `i` stands at
//! `r_i = base_i + t_i x_i` from the COM, so the balance sums `h = sum r_i` are linear in the
//! arc lengths `x` and `det(S)`, `S = sum r r^T - v v^T / n`, `v = sum s_i r_i`, is a quartic
//! ([`crate::formation::objective`]). The constraints are linear: each robot within its
//! segment, neighbours at least `spacing` apart. The active set groups robots into blocks
//! (neighbours at exactly `spacing` move together) and pins blocks whose robot sits on a
//! segment end; the free blocks' shifts `u` are the variables.
//!
//! - [`Goal::Balance`] minimises `|h|^2` (a convex quadratic: the active set method ends at
//!   its global minimum, which tells whether and how closely the assignment can balance).
//! - [`Goal::Det`] maximises `det(S)` from a balanced start, keeping `T u = 0` (`T_b` the sum
//!   of a block's tangents) so both balance sums stay fixed.
//!
//! Each iteration takes a Newton step on the current face (Levenberg-damped until the reduced
//! Hessian is negative definite), then an exact line search: along the step the objective is a
//! polynomial of degree 4 (2 for the balance), maximised on the interval up to the first
//! constraint it would break, which then joins the active set. On a stationary face, a
//! constraint whose Lagrange multiplier has the wrong sign is released. The iteration count is
//! capped, and every step is `O(n^2 + k^3)` with fixed-size arrays: bounded time, no
//! allocation.
//!
//! A point where every multiplier has the right sign is only a local maximum of `det(S)`, and
//! the problem of one assignment can have several, often at vertices of its polytope (as many
//! free blocks as balance sums). Neighbouring vertices are one edge apart: releasing one
//! active constraint leaves a line along which `det(S)` may first fall and then rise above the
//! current value further on. [`Face::climb_edge`] probes the edge each active constraint
//! opens (the move that relaxes it, projected onto `T u = 0`) with the same exact line search,
//! and follows the best one that ends higher; the solver climbs so from the best start of each
//! assignment.

use crate::formation::assignment::Layout;
use crate::formation::newton::newton_step;
use crate::geometry::Vec2;
use crate::math;
use crate::scenario::MAX_ROBOTS;

mod edge;

const N: usize = MAX_ROBOTS;
/// A constraint closer than this (m) counts as active when a face is first read.
const ACTIVE_TOLERANCE: f32 = 1e-6;

/// What the face solver optimises.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Goal {
    /// Minimise `|sum r|^2` (bring the centroid onto the COM).
    Balance,
    /// Maximise `det(S)` with both balance sums held.
    Det,
}

/// A symmetric 2 x 2 matrix `[[a, b], [b, c]]`.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
struct Sym {
    a: f32,
    b: f32,
    c: f32,
}

impl Sym {
    fn outer(p: Vec2, q: Vec2) -> Self {
        // p q^T + q p^T
        Self {
            a: 2.0 * p.x * q.x,
            b: p.x * q.y + p.y * q.x,
            c: 2.0 * p.y * q.y,
        }
    }
    fn square(p: Vec2) -> Self {
        Self {
            a: p.x * p.x,
            b: p.x * p.y,
            c: p.y * p.y,
        }
    }
    fn add(self, o: Self) -> Self {
        Self {
            a: self.a + o.a,
            b: self.b + o.b,
            c: self.c + o.c,
        }
    }
    fn scale(self, k: f32) -> Self {
        Self {
            a: self.a * k,
            b: self.b * k,
            c: self.c * k,
        }
    }
    fn det(self) -> f32 {
        self.a * self.c - self.b * self.b
    }
    /// `tr(adj(self) o)`: the polarisation of the determinant.
    fn mixed(self, o: Self) -> f32 {
        self.a * o.c + self.c * o.a - 2.0 * self.b * o.b
    }
    /// `p^T self q`.
    fn form(self, p: Vec2, q: Vec2) -> f32 {
        p.x * (self.a * q.x + self.b * q.y) + p.y * (self.b * q.x + self.c * q.y)
    }
    fn adj(self) -> Self {
        Self {
            a: self.c,
            b: -self.b,
            c: self.a,
        }
    }
}

/// Whether a robot sits on an end of its segment (an active bound).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
enum Pin {
    #[default]
    Free,
    Low,
    High,
}

/// A constraint of the face: the gap after a sequence index, or a robot's bound.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Constraint {
    Gap(usize),
    Bound(usize, Pin),
}

/// How a face solve ended.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Outcome {
    /// The objective: `det(S)` for [`Goal::Det`], `-|h|^2` for [`Goal::Balance`].
    pub value: f32,
    /// The balance sums `h` at the end.
    pub balance: Vec2,
    /// Newton iterations made.
    pub iterations: u32,
}

/// Sums of the current point.
#[derive(Clone, Copy, Debug, Default)]
struct State {
    r: [Vec2; N],
    s: Sym,
    v: Vec2,
    h: Vec2,
}

/// Blocks of the current face.
#[derive(Clone, Copy, Debug)]
struct Blocks {
    /// Sequence indices in walking order (starting after a free gap).
    order: [u8; N],
    /// Start (in `order`) of each block; `start[count]` is `n`.
    start: [u8; N + 1],
    count: usize,
    /// Free-block index of each block, or `u8::MAX` for a pinned block.
    free_index: [u8; N],
    /// Block of each sequence index.
    block_of: [u8; N],
    /// Free blocks.
    free: usize,
}

/// The active-set solver on one assignment.
#[derive(Clone, Debug)]
pub struct Face<'a> {
    layout: &'a Layout,
    /// Arc lengths, sequence order.
    pub x: [f32; N],
    tight: [bool; N],
    pin: [Pin; N],
}

impl<'a> Face<'a> {
    /// A feasible start on `layout`: each robot at fraction `lean` (0: earliest packing, 1:
    /// latest) of the range it can reach, with the constraints it touches active; `None` if
    /// that point breaks the wrap-around gap (the ranges account for it: only by rounding).
    pub fn start(layout: &'a Layout, lean: f32) -> Option<Self> {
        let n = layout.n;
        let mut x = [0.0f32; N];
        for (i, xi) in x.iter_mut().enumerate().take(n) {
            let (a, b) = layout.reach[i];
            *xi = a + lean * (b - a);
        }
        let mut face = Self {
            layout,
            x,
            tight: [false; N],
            pin: [Pin::Free; N],
        };
        if n >= 2 && face.slack(n - 1) < -ACTIVE_TOLERANCE {
            return None;
        }
        face.detect_active();
        Some(face)
    }

    /// Slack of the gap after sequence index `i` beyond `spacing`.
    fn slack(&self, i: usize) -> f32 {
        let n = self.layout.n;
        let (a, b) = (self.x[i], self.x[(i + 1) % n]);
        let gap = if i + 1 == n {
            b + self.layout.perimeter - a
        } else {
            b - a
        };
        gap - self.layout.spacing
    }

    fn detect_active(&mut self) {
        let n = self.layout.n;
        for i in 0..n {
            self.tight[i] = n >= 2 && self.slack(i) <= ACTIVE_TOLERANCE;
            self.pin[i] = if self.x[i] - self.layout.lo[i] <= ACTIVE_TOLERANCE {
                Pin::Low
            } else if self.layout.hi[i] - self.x[i] <= ACTIVE_TOLERANCE {
                Pin::High
            } else {
                Pin::Free
            };
        }
    }

    fn state(&self) -> State {
        let l = self.layout;
        let mut st = State::default();
        let mut m = Sym::default();
        for i in 0..l.n {
            let r = l.point(i, self.x[i]);
            st.r[i] = r;
            m = m.add(Sym::square(r));
            st.v = st.v + r * l.spin[i];
            st.h = st.h + r;
        }
        st.s = m.add(Sym::square(st.v).scale(-1.0 / l.n as f32));
        st
    }

    fn blocks(&self) -> Blocks {
        let n = self.layout.n;
        let mut b = Blocks {
            order: [0; N],
            start: [0; N + 1],
            count: 0,
            free_index: [u8::MAX; N],
            block_of: [0; N],
            free: 0,
        };
        let first = (0..n).find(|&i| !self.tight[(i + n - 1) % n]);
        let Some(first) = first else {
            // Every gap tight: one rigid ring that cannot move.
            for j in 0..n {
                b.order[j] = j as u8;
            }
            b.count = 1;
            b.start[1] = n as u8;
            return b;
        };
        let mut pinned = [false; N];
        for j in 0..n {
            let i = (first + j) % n;
            b.order[j] = i as u8;
            if j == 0 || !self.tight[(i + n - 1) % n] {
                b.start[b.count] = j as u8;
                b.count += 1;
            }
            let blk = b.count - 1;
            b.block_of[i] = blk as u8;
            pinned[blk] |= self.pin[i] != Pin::Free;
        }
        b.start[b.count] = n as u8;
        for (index, &pinned) in b.free_index.iter_mut().zip(&pinned).take(b.count) {
            if !pinned {
                *index = b.free as u8;
                b.free += 1;
            }
        }
        b
    }

    /// Runs the solver for `goal` until stationary with the right multipliers, until the
    /// balance is within `tolerance` ([`Goal::Balance`]), or for `max_iterations`.
    pub fn solve(&mut self, goal: Goal, tolerance: f32, max_iterations: u32) -> Outcome {
        let l = self.layout;
        let n = l.n;
        let inv_n = 1.0 / n as f32;
        let mut iterations = 0;
        // Constraints released without progress since the last step (no second try).
        let mut futile = [false; 2 * N];
        let mut last_released: Option<Constraint> = None;
        while iterations < max_iterations {
            iterations += 1;
            let st = self.state();
            let value = objective(goal, &st);
            if goal == Goal::Balance && st.h.x.abs() <= tolerance && st.h.y.abs() <= tolerance {
                break;
            }
            let blocks = self.blocks();
            let k = blocks.free;
            // Robot-level gradient pieces.
            let adj = st.s.adj();
            let mut grad_i = [0.0f32; N];
            let mut g_b = [Sym::default(); N];
            let mut t_b = [Vec2::default(); N];
            let mut ts_b = [Vec2::default(); N];
            let mut d_b = [0.0f32; N];
            for (i, grad_of) in grad_i.iter_mut().enumerate().take(n) {
                let t = l.tangent[i];
                match goal {
                    Goal::Det => {
                        let w = st.r[i] - st.v * (l.spin[i] * inv_n);
                        let g = Sym::outer(t, w);
                        *grad_of = st.s.mixed(g);
                        let f = blocks.free_index[usize::from(blocks.block_of[i])];
                        if f != u8::MAX {
                            let f = usize::from(f);
                            g_b[f] = g_b[f].add(g);
                            t_b[f] = t_b[f] + t;
                            ts_b[f] = ts_b[f] + t * l.spin[i];
                            d_b[f] += 2.0 * adj.form(t, t);
                        }
                    }
                    Goal::Balance => {
                        *grad_of = -2.0 * st.h.dot(t);
                        let f = blocks.free_index[usize::from(blocks.block_of[i])];
                        if f != u8::MAX {
                            t_b[usize::from(f)] = t_b[usize::from(f)] + t;
                        }
                    }
                }
            }
            let mut grad = [0.0f32; N];
            let mut hess = [[0.0f32; N]; N];
            for b in 0..k {
                for c in 0..k {
                    hess[b][c] = match goal {
                        Goal::Det => {
                            let mut h =
                                g_b[b].mixed(g_b[c]) - 2.0 * inv_n * adj.form(ts_b[b], ts_b[c]);
                            if b == c {
                                h += d_b[b];
                            }
                            h
                        }
                        Goal::Balance => -2.0 * t_b[b].dot(t_b[c]),
                    };
                }
                grad[b] = match goal {
                    Goal::Det => st.s.mixed(g_b[b]),
                    Goal::Balance => -2.0 * st.h.dot(t_b[b]),
                };
            }
            let step = newton_step(goal, k, &grad, &hess, &t_b);
            let gain: f32 = (0..k).map(|b| grad[b] * step[b]).sum();
            let scale = match goal {
                Goal::Det => value.abs().max(1e-12),
                Goal::Balance => value.abs().max(tolerance * tolerance),
            };
            if k == 0 || gain.is_nan() || gain <= 1e-6 * scale {
                // Stationary on this face: release the constraint with the most negative
                // multiplier, or stop.
                if let Some(c) = last_released.take() {
                    // Released without a step: put it back and do not try it again here.
                    futile[self.constraint_slot(c)] = true;
                    self.add(c);
                    continue;
                }
                let mu = match goal {
                    Goal::Det => balance_multiplier(k, &grad, &t_b),
                    Goal::Balance => Vec2::default(),
                };
                let mut e = [0.0f32; N];
                for i in 0..n {
                    e[i] = grad_i[i] + l.tangent[i].dot(mu);
                }
                match self.most_negative_multiplier(&blocks, &e, &futile) {
                    Some(c) => {
                        self.remove(c);
                        last_released = Some(c);
                        continue;
                    }
                    None => break,
                }
            }
            // Robot velocities along the step.
            let mut dx = [0.0f32; N];
            for (d, &blk) in dx.iter_mut().zip(&blocks.block_of).take(n) {
                let f = blocks.free_index[usize::from(blk)];
                if f != u8::MAX {
                    *d = step[usize::from(f)];
                }
            }
            let (limit, hit) = self.step_limit(&dx);
            let alpha = match goal {
                Goal::Det => quartic_argmax(&st, l, &dx, limit),
                Goal::Balance => {
                    let mut ha = Vec2::default();
                    for (&t, &d) in l.tangent.iter().zip(&dx).take(n) {
                        ha = ha + t * d;
                    }
                    let den = ha.dot(ha);
                    if den > 0.0 {
                        math::clamp(-st.h.dot(ha) / den, 0.0, limit)
                    } else {
                        0.0
                    }
                }
            };
            if alpha > 0.0 {
                for (x, &d) in self.x.iter_mut().zip(&dx).take(n) {
                    *x += alpha * d;
                }
                futile = [false; 2 * N];
                last_released = None;
            }
            if alpha >= limit {
                match hit {
                    Some(c) => self.add(c),
                    None => break,
                }
            } else if alpha <= 0.0 {
                // No progress along a step that predicted a gain: rounding; stop here.
                break;
            }
        }
        let st = self.state();
        Outcome {
            value: objective(goal, &st),
            balance: st.h,
            iterations,
        }
    }

    fn constraint_slot(&self, c: Constraint) -> usize {
        match c {
            Constraint::Gap(i) => i,
            Constraint::Bound(i, _) => N + i,
        }
    }

    fn add(&mut self, c: Constraint) {
        match c {
            Constraint::Gap(i) => self.tight[i] = true,
            Constraint::Bound(i, p) => self.pin[i] = p,
        }
    }

    fn remove(&mut self, c: Constraint) {
        match c {
            Constraint::Gap(i) => self.tight[i] = false,
            Constraint::Bound(i, _) => self.pin[i] = Pin::Free,
        }
    }

    /// The largest step along `dx` before a free gap closes to `spacing` or a robot reaches a
    /// segment end, and the constraint that stops it.
    fn step_limit(&self, dx: &[f32; N]) -> (f32, Option<Constraint>) {
        let l = self.layout;
        let n = l.n;
        let mut limit = f32::INFINITY;
        let mut hit = None;
        for i in 0..n {
            if n >= 2 && !self.tight[i] {
                let closing = dx[i] - dx[(i + 1) % n];
                if closing > 0.0 {
                    let a = self.slack(i).max(0.0) / closing;
                    if a < limit {
                        limit = a;
                        hit = Some(Constraint::Gap(i));
                    }
                }
            }
            if self.pin[i] == Pin::Free {
                if dx[i] > 0.0 {
                    let a = (l.hi[i] - self.x[i]).max(0.0) / dx[i];
                    if a < limit {
                        limit = a;
                        hit = Some(Constraint::Bound(i, Pin::High));
                    }
                } else if dx[i] < 0.0 {
                    let a = (self.x[i] - l.lo[i]).max(0.0) / -dx[i];
                    if a < limit {
                        limit = a;
                        hit = Some(Constraint::Bound(i, Pin::Low));
                    }
                }
            }
        }
        (limit, hit)
    }

    /// The active constraint whose Lagrange multiplier is most negative (releasing it lets
    /// the objective grow), skipping `futile` ones. `e` is the gradient per robot with the
    /// balance multipliers' share taken off.
    fn most_negative_multiplier(
        &self,
        blocks: &Blocks,
        e: &[f32; N],
        futile: &[bool; 2 * N],
    ) -> Option<Constraint> {
        let n = self.layout.n;
        let size = e[..n].iter().fold(0.0f32, |a, v| a.max(v.abs()));
        let mut worst = -1e-4 * size;
        let mut found = None;
        let mut consider = |c: Constraint, lambda: f32, slot: usize| {
            if !futile[slot] && lambda < worst {
                worst = lambda;
                found = Some(c);
            }
        };
        for blk in 0..blocks.count {
            let from = usize::from(blocks.start[blk]);
            let to = usize::from(blocks.start[blk + 1]);
            let members = &blocks.order[from..to];
            let len = members.len();
            let pinned = members
                .iter()
                .position(|&i| self.pin[usize::from(i)] != Pin::Free);
            // Gap multipliers, indexed by position in the block (gap after member j).
            let mut lambda = [0.0f32; N];
            let left_end = pinned.unwrap_or(len - 1);
            let mut sum = 0.0;
            for j in 0..left_end {
                sum += e[usize::from(members[j])];
                lambda[j] = sum;
            }
            if let Some(p) = pinned {
                let mut sum = 0.0;
                for j in (p + 1..len).rev() {
                    sum += e[usize::from(members[j])];
                    lambda[j - 1] = -sum;
                }
                let i = usize::from(members[p]);
                let before = if p > 0 { lambda[p - 1] } else { 0.0 };
                let after = if p + 1 < len { lambda[p] } else { 0.0 };
                let net = e[i] + before - after;
                let pin = self.pin[i];
                let lam = if pin == Pin::Low { -net } else { net };
                consider(Constraint::Bound(i, pin), lam, N + i);
            }
            for j in 0..len.saturating_sub(1) {
                let i = usize::from(members[j]);
                consider(Constraint::Gap(i), lambda[j], i);
            }
        }
        found
    }
}

fn objective(goal: Goal, st: &State) -> f32 {
    match goal {
        Goal::Det => st.s.det(),
        Goal::Balance => -st.h.dot(st.h),
    }
}

/// Least-squares balance multipliers `mu` with `grad_b + T_b . mu = 0` on the free blocks.
fn balance_multiplier(k: usize, grad: &[f32; N], t_b: &[Vec2; N]) -> Vec2 {
    let (mut a, mut b, mut c, mut rx, mut ry) = (0.0f32, 0.0f32, 0.0f32, 0.0f32, 0.0f32);
    for f in 0..k {
        let t = t_b[f];
        a += t.x * t.x;
        b += t.x * t.y;
        c += t.y * t.y;
        rx -= t.x * grad[f];
        ry -= t.y * grad[f];
    }
    let damping = 1e-6 * (a + c) + 1e-20;
    let (a, c) = (a + damping, c + damping);
    let det = a * c - b * b;
    if det.is_nan() || det <= 0.0 {
        return Vec2::default();
    }
    Vec2::new((c * rx - b * ry) / det, (a * ry - b * rx) / det)
}

/// The `alpha` in `[0, limit]` maximising `det(S)` along robot velocities `dx`: the quartic
/// `det(S0 + alpha S1 + alpha^2 S2)` at the end or at a root of its derivative.
fn quartic_argmax(st: &State, l: &Layout, dx: &[f32; N], limit: f32) -> f32 {
    let n = l.n;
    let inv_n = 1.0 / n as f32;
    let mut va = Vec2::default();
    let mut s1 = Sym::default();
    let mut s2 = Sym::default();
    for (i, &d) in dx.iter().enumerate().take(n) {
        if d == 0.0 {
            continue;
        }
        let a = l.tangent[i] * d;
        va = va + a * l.spin[i];
        s1 = s1.add(Sym::outer(st.r[i], a));
        s2 = s2.add(Sym::square(a));
    }
    let s1 = s1.add(Sym::outer(st.v, va).scale(-inv_n));
    let s2 = s2.add(Sym::square(va).scale(-inv_n));
    let s0 = st.s;
    let p = [
        s0.det(),
        s0.mixed(s1),
        s1.det() + s0.mixed(s2),
        s1.mixed(s2),
        s2.det(),
    ];
    let value = |x: f32| p[0] + x * (p[1] + x * (p[2] + x * (p[3] + x * p[4])));
    let slope = |x: f32| p[1] + x * (2.0 * p[2] + x * (3.0 * p[3] + x * 4.0 * p[4]));
    let limit = if limit.is_finite() { limit } else { 1e3 };
    // Split [0, limit] where the slope's own derivative (a quadratic) vanishes.
    let mut cuts = [0.0f32, limit, limit, limit];
    let (qa, qb, qc) = (12.0 * p[4], 6.0 * p[3], 2.0 * p[2]);
    let mut count = 2;
    let mut push = |r: f32| {
        if r > 0.0 && r < limit {
            cuts[count] = r;
            count += 1;
        }
    };
    if qa.abs() > 1e-30 {
        let disc = qb * qb - 4.0 * qa * qc;
        if disc > 0.0 {
            let sq = math::sqrt(disc);
            push((-qb - sq) / (2.0 * qa));
            push((-qb + sq) / (2.0 * qa));
        }
    } else if qb.abs() > 1e-30 {
        push(-qc / qb);
    }
    let cuts = &mut cuts[..count];
    math::sort_small_by(cuts, |a, b| a < b);
    let mut best = (limit, value(limit));
    let v0 = value(0.0);
    if v0 >= best.1 {
        best = (0.0, v0);
    }
    for w in cuts.windows(2) {
        let (mut a, mut b) = (w[0], w[1]);
        if slope(a) > 0.0 && slope(b) <= 0.0 {
            for _ in 0..30 {
                let mid = 0.5 * (a + b);
                if slope(mid) > 0.0 {
                    a = mid;
                } else {
                    b = mid;
                }
            }
            let x = 0.5 * (a + b);
            let vx = value(x);
            if vx > best.1 {
                best = (x, vx);
            }
        }
    }
    best.0
}
